//! SPEC §10 replay: CSV in (IMU + aiding, optional truth), CSV and JSON out.

use std::path::Path;

use anyhow::{bail, Context, Result};
use imu_fdi::model::{AidingKind, ImuVec, MeasVec, Measurement, CHANNEL_NAMES};
use imu_fdi::monitor::{Phase, UkfMonitorConfig, MAX_DELAY_STEPS};

use super::replay_monitor::{phase_name, MonitorKind, ReplayMonitor};
use super::replay_read::{read_log, Log, Row};

pub use super::replay_sim::write_simulated;
pub use super::replay_summary::{ChannelSummary, ReplaySummary};

pub(crate) const IMU_COLS: [&str; 6] = [
    "imu0_ax", "imu0_ay", "imu0_az", "imu0_gx", "imu0_gy", "imu0_gz",
];
pub(crate) const DVL_COLS: [&str; 3] = ["dvl_u", "dvl_v", "dvl_w"];
pub(crate) const GNSS_COLS: [&str; 3] = ["gnss_vn", "gnss_ve", "gnss_vd"];
pub(crate) const ATT_COLS: [&str; 3] = ["att_roll", "att_pitch", "att_yaw"];

pub use super::replay_options::{flight_config, AidingDelay, Profile, ReplayOptions};

fn channel_name(k: usize, c: &str) -> String {
    if k == 0 {
        c.to_string()
    } else {
        format!("imu{k}_{c}")
    }
}

/// Replays `input` (SPEC §10 CSV; every `imu{k}_…` triad gets its own
/// monitor) and writes `out` / `summary`. `sim_cfg` gives the `Sim` profile's
/// tuning for an aiding kind.
pub fn replay(
    input: &Path,
    out: Option<&Path>,
    summary: Option<&Path>,
    sim_cfg: impl Fn(AidingKind) -> UkfMonitorConfig<f64>,
    opts: &ReplayOptions,
) -> Result<ReplaySummary> {
    replay_observed(input, out, summary, sim_cfg, opts, &mut |_, _| {})
}

/// One row's report of one IMU's monitor, as the replay hands it on.
pub type ReplayReport = imu_fdi::monitor::Report<f64, super::replay_monitor::ReplayDetail>;

/// [`replay`], calling `observe(t, reports)` after every row with the
/// report of each IMU's monitor (the flight report plots these).
pub fn replay_observed(
    input: &Path,
    out: Option<&Path>,
    summary: Option<&Path>,
    sim_cfg: impl Fn(AidingKind) -> UkfMonitorConfig<f64>,
    opts: &ReplayOptions,
    observe: &mut dyn FnMut(f64, &[ReplayReport]),
) -> Result<ReplaySummary> {
    let mut sum = ReplaySummary {
        monitor: opts.monitor,
        ..Default::default()
    };
    let Log {
        kind,
        imus,
        file_truth,
        mut rows,
        dt,
    } = read_log(input, opts, &mut sum)?;

    // --- inject -------------------------------------------------------------
    if let Some((table, k)) = &opts.inject {
        if *k >= imus {
            bail!(
                "{}: cannot inject on IMU {k}: the file has {} IMU(s)",
                input.display(),
                imus
            );
        }
        let sigma =
            crate::eval::inject::difference_sigma(rows.iter().filter_map(|r| r.imus.get(*k)));
        let mut inj = crate::eval::inject::Injector::new(table.clone(), sigma, opts.seed);
        for r in &mut rows {
            if let Some(s) = r.imus.get_mut(*k) {
                let tr = inj.apply(r.t, s);
                if let Some(slot) = r.truth.get_mut(*k) {
                    *slot = Some(tr);
                }
            }
        }
    }

    // --- configure ------------------------------------------------------------
    let profile = match opts.profile {
        Profile::Auto if file_truth => Profile::Sim,
        Profile::Auto => Profile::Flight,
        p => p,
    };
    sum.profile = format!("{profile:?}");
    let mut monitors = Vec::new();
    // Per IMU, the velocity aiding's lag in rows (see `velocity_delay`).
    let mut vel_lag = Vec::new();
    // The GNSS velocity's lag fitted on IMU `k`'s learning span.
    let fit_lag = |k: usize| -> Result<Option<super::gnss_lag::GnssLag>> {
        // The fit compares NED velocity changes with the specific force
        // rotated by the attitude: a DVL's body-frame velocity is another
        // model.
        if kind != AidingKind::GnssAttitude {
            bail!(
                "{}: --velocity-delay/--velocity-lag auto needs GNSS velocity (NED) and \
                 attitude aiding; give a DVL's latency in seconds",
                input.display()
            );
        }
        let probe = sim_cfg(kind);
        let t0 = rows.first().map_or(0.0, |r| r.t);
        let span = probe.converge_s + opts.learn_s.unwrap_or(probe.learn_s.max(20.0));
        let head: Vec<&Row> = rows.iter().take_while(|r| r.t < t0 + span).collect();
        let avail3 = |r: &Row, o: usize| {
            let ok = r.avail.iter().skip(o).take(3).all(|a| *a);
            ok.then(|| core::array::from_fn(|i| r.z.get(o + i).copied().unwrap_or(0.0)))
        };
        let times: Vec<f64> = head.iter().map(|r| r.t).collect();
        let imu = super::gnss_lag::bridge_bad_cells(
            head.iter()
                .map(|r| r.imus.get(k).copied().unwrap_or([f64::NAN; 6])),
        );
        let mut att: Vec<Option<[f64; 3]>> = head.iter().map(|r| avail3(r, 3)).collect();
        // The OTSUKF's attitude latency (`--aiding-delay`): the attitude
        // rows moved back by it, so the velocity fit rotates the specific
        // force by the attitude of its own time (`attitude_lag.rs`).
        // The UKF monitor's likewise: with a late attitude its latency would
        // otherwise enter the velocity's fit.
        let att_rows = match opts.aiding_delay {
            AidingDelay::Fixed(d) => (d / dt).round().max(0.0) as usize,
            AidingDelay::Auto => {
                super::attitude_lag::estimate(&times, &imu, &att, MAX_DELAY_STEPS).unwrap_or(0)
            }
        };
        if att_rows > 0 {
            att = att.iter().skip(att_rows).copied().collect();
            att.resize(head.len(), None);
        }
        Ok(super::gnss_lag::estimate(
            &times,
            &imu,
            &head.iter().map(|r| avail3(r, 0)).collect::<Vec<_>>(),
            &att,
            // The UKF monitor's state history bounds the lag it compensates.
            match opts.monitor {
                MonitorKind::Otsukf => (0.5 / dt).round() as usize,
                MonitorKind::Ukf => ((0.5 / dt).round() as usize).min(MAX_DELAY_STEPS),
            },
        ))
    };
    for k in 0..imus {
        let lag = match opts.velocity_delay {
            AidingDelay::Fixed(d) => (d / dt).round().max(0.0) as usize,
            AidingDelay::Auto => {
                let fit = fit_lag(k)?;
                if let Some(l) = fit {
                    sum.velocity_fit_rms_m_s.push(l.rms_m_s);
                }
                fit.map_or(0, |l| l.rows)
            }
        };
        // The monitor's own (causal) compensation: the OTSUKF's by default,
        // the UKF monitor's when asked (`--velocity-lag`), in the flight
        // profile with GNSS aiding, unless the rows are re-timed above.
        let own_lag = match opts.monitor {
            MonitorKind::Otsukf => Some(opts.velocity_lag.unwrap_or(AidingDelay::Auto)),
            MonitorKind::Ukf => opts.velocity_lag,
        };
        let own_lag_s = match own_lag {
            Some(AidingDelay::Fixed(d)) => Some(d),
            Some(AidingDelay::Auto)
                if lag == 0 && profile == Profile::Flight && kind == AidingKind::GnssAttitude =>
            {
                Some(fit_lag(k)?.map_or(0.0, |l| l.rows as f64 * dt))
            }
            Some(AidingDelay::Auto) => Some(0.0),
            None => None,
        };
        let otsukf_lag_s = own_lag_s.filter(|_| opts.monitor == MonitorKind::Otsukf);
        if let Some(l) = own_lag_s {
            match opts.monitor {
                MonitorKind::Otsukf => sum.otsukf_velocity_lag_s.push(l),
                MonitorKind::Ukf => sum.ukf_velocity_lag_s.push(l),
            }
        }
        sum.velocity_delay_s.push(lag as f64 * dt);
        vel_lag.push(lag);
        let mut cfg = match profile {
            Profile::Flight => {
                let probe = sim_cfg(kind);
                let t0 = rows.first().map_or(0.0, |r| r.t);
                let span = probe.converge_s + opts.learn_s.unwrap_or(20.0);
                let learn: Vec<[f64; 6]> = rows
                    .iter()
                    .take_while(|r| r.t < t0 + span)
                    .filter_map(|r| r.imus.get(k).copied())
                    .collect();
                flight_config(probe, dt, &learn, opts)
            }
            _ => {
                let mut c = sim_cfg(kind);
                c.imu_period = dt;
                if let Some(l) = opts.learn_s {
                    c.learn_s = l;
                }
                if let Some(m) = opts.max_inflation {
                    c.max_innovation_inflation = m;
                }
                if let Some(m) = opts.inflation_memory {
                    c.inflation_memory_s = m;
                }
                c
            }
        };
        cfg.aiding = kind;
        match opts.aiding_delay {
            AidingDelay::Fixed(d) => cfg.aiding_delay_s = d,
            AidingDelay::Auto => cfg.estimate_aiding_delay = true,
        }
        cfg.estimate_heading_offset = opts.estimate_heading_offset;
        if opts.monitor == MonitorKind::Ukf {
            cfg.velocity_delay_s = own_lag_s;
        }
        // The OTSUKF takes `--aiding-delay` as its attitude aiding's latency
        // (its GNSS velocity's is `--velocity-lag`); it has no heading
        // offset estimate.
        if opts.monitor == MonitorKind::Otsukf && opts.estimate_heading_offset {
            bail!(
                "{}: the heading offset is the UKF monitor's (--monitor ukf)",
                input.display()
            );
        }
        if k == 0 {
            sum.process_noise_psd = cfg.process_noise.psd.iter().copied().collect();
            sum.meas_sigma = cfg.meas_sigma.iter().copied().collect();
            sum.process_noise_psd_accel_m2_s3 =
                sum.process_noise_psd.iter().take(3).copied().collect();
            sum.process_noise_psd_gyro_rad2_s =
                sum.process_noise_psd.iter().skip(3).copied().collect();
            sum.meas_sigma_velocity_m_s = sum.meas_sigma.iter().take(3).copied().collect();
            sum.meas_sigma_attitude_rad = sum.meas_sigma.iter().skip(3).copied().collect();
        }
        monitors.push(ReplayMonitor::new(
            opts.monitor,
            cfg,
            otsukf_lag_s.unwrap_or(0.0),
        )?);
    }
    let has_truth: Vec<bool> = (0..imus)
        .map(|k| {
            rows.iter()
                .any(|r| r.truth.get(k).is_some_and(Option::is_some))
        })
        .collect();
    sum.channels = (0..imus)
        .flat_map(|k| {
            let ht = has_truth.get(k).copied().unwrap_or(false);
            CHANNEL_NAMES.iter().map(move |c| ChannelSummary {
                channel: channel_name(k, c),
                fault_samples: ht.then_some(0),
                correct_samples: ht.then_some(0),
                false_alarm_samples: ht.then_some(0),
                false_alarm_events: ht.then_some(0),
                ..Default::default()
            })
        })
        .collect();

    // --- run ------------------------------------------------------------------
    let mut writer = match out {
        Some(p) => Some(
            csv::Writer::from_path(p).with_context(|| format!("cannot write {}", p.display()))?,
        ),
        None => None,
    };
    if let Some(w) = writer.as_mut() {
        let mut h = vec!["t".to_string()];
        for s in ["x_u", "x_v", "x_w", "x_roll", "x_pitch", "x_yaw"] {
            h.push(s.into());
        }
        // One layout for both monitors: `fsig_*` (the fault estimate's σ)
        // is empty where the monitor does not estimate it (UKF monitor),
        // `ratio_*` (the block tests' ratios) where it has no block test.
        for k in 0..imus {
            h.push(channel_name(k, "phase"));
            for prefix in ["flag", "fhat", "fsig", "ratio"] {
                for c in CHANNEL_NAMES {
                    h.push(channel_name(k, &format!("{prefix}_{c}")));
                }
            }
        }
        w.write_record(&h)?;
    }
    let mut last_fault_t = vec![f64::NEG_INFINITY; imus];
    let mut prev_t: Option<f64> = None;
    for (row_index, row) in rows.iter().enumerate() {
        let row_is_last = row_index + 1 == rows.len();
        let t = row.t;
        let step_dt = prev_t.map_or(dt, |p| t - p);
        prev_t = Some(t);
        // Per IMU: the attitude of this row, the velocity sample that
        // describes this row (logged `lag` rows later).
        let meas_for = |lag: usize| {
            let mut m = Measurement {
                z: MeasVec::from_iterator(row.z.iter().copied()),
                available: row.avail,
            };
            for i in 0..3 {
                let later = rows.get(row_index + lag);
                let (z, a) = later.map_or((0.0, false), |r| {
                    (
                        r.z.get(i).copied().unwrap_or(0.0),
                        r.avail.get(i).copied().unwrap_or(false),
                    )
                });
                if let (Some(mz), Some(ma)) = (m.z.get_mut(i), m.available.get_mut(i)) {
                    *mz = z;
                    *ma = a;
                }
            }
            m
        };
        let mut record = vec![format!("{t}")];
        let mut cells = Vec::new();
        let reports: Vec<_> = monitors
            .iter_mut()
            .enumerate()
            .map(|(k, m)| {
                let imu = ImuVec::from_iterator(row.imus.get(k).copied().unwrap_or([f64::NAN; 6]));
                m.step(
                    &imu,
                    step_dt,
                    &meas_for(vel_lag.get(k).copied().unwrap_or(0)),
                )
            })
            .collect();
        let raised = |r: &imu_fdi::monitor::Report<f64, _>, i: usize| {
            r.phase == Phase::Monitoring
                && r.status
                    .get(i)
                    .and_then(|s| s.sign())
                    .is_some_and(|f| f != 0)
        };
        observe(t, &reports);
        // The same channel flagged on every IMU at once is the aiding or the
        // model, not an IMU (SPEC §8b: gate and attribute).
        let common: [bool; 6] =
            core::array::from_fn(|i| reports.len() >= 2 && reports.iter().all(|r| raised(r, i)));
        for (k, (r, lf)) in reports.iter().zip(last_fault_t.iter_mut()).enumerate() {
            if k == 0 {
                if r.health.input_invalid {
                    sum.rejected_imu_rows += 1;
                }
                if r.phase == Phase::Monitoring {
                    sum.monitoring_from_s.get_or_insert(t);
                    sum.monitored_samples += 1;
                }
                record.extend(r.state.iter().map(|v| format!("{v}")));
            }
            let truth = row.truth.get(k).copied().flatten();
            let any_fault = truth.is_some_and(|tr| tr.iter().any(|v| *v != 0.0));
            if any_fault {
                *lf = t;
            }
            let in_grace = !any_fault && t - *lf < opts.grace_s;
            for (i, ch) in sum.channels.iter_mut().skip(6 * k).take(6).enumerate() {
                let flag = r.status.get(i).and_then(|s| s.sign());
                let flagged = flag.is_some_and(|f| f != 0);
                let rising = flagged && r.phase == Phase::Monitoring && !ch.was_flagged;
                ch.was_flagged = flagged && r.phase == Phase::Monitoring;
                if rising {
                    ch.flag_events += 1;
                }
                if flagged && r.phase == Phase::Monitoring {
                    ch.flagged_samples += 1;
                    ch.first_detection_s.get_or_insert(t);
                    if common.get(i).copied().unwrap_or(false) {
                        ch.common_mode_samples += 1;
                    }
                }
                if let (Some(tr), Some(f)) = (truth, flag) {
                    let fv = tr.get(i).copied().unwrap_or(0.0);
                    if fv != 0.0 {
                        *ch.fault_samples.get_or_insert(0) += 1;
                        // NaN: a hardware fault, of no sign.
                        let correct = if fv.is_nan() {
                            f != 0
                        } else {
                            f == if fv > 0.0 { 1 } else { -1 }
                        };
                        *ch.correct_samples.get_or_insert(0) += usize::from(correct);
                        if r.phase == Phase::Monitoring && fv.is_finite() {
                            let e = r.fault_estimate.get(i).copied().unwrap_or(0.0) - fv;
                            ch.fault_sq_sum += e * e;
                            ch.fault_rmse_n += 1;
                        }
                        if correct {
                            ch.first_correct_s.get_or_insert(t);
                        }
                    } else if !any_fault && !in_grace && flagged {
                        *ch.false_alarm_samples.get_or_insert(0) += 1;
                        if rising {
                            *ch.false_alarm_events.get_or_insert(0) += 1;
                        }
                    }
                }
            }
            if row_is_last {
                let b = |i: usize| r.nominal_bias.get(i).copied().unwrap_or(0.0);
                sum.nominal_bias_accel_m_s2.push(core::array::from_fn(b));
                sum.nominal_bias_gyro_rad_s
                    .push(core::array::from_fn(|i| b(i + 3)));
                if let Some(inf) = r.detail.innovation_inflation {
                    sum.innovation_inflation.push(inf);
                }
                if let Some(d) = r.detail.aiding_delay_s {
                    sum.aiding_delay_s.push(d);
                }
                if let Some(h) = r.detail.heading_offset_rad {
                    sum.heading_offset_deg.push(h.to_degrees());
                }
                if let Some((lag, off)) = r.detail.velocity_increment {
                    sum.velocity_increment_lag_s.push(lag);
                    sum.velocity_increment_offset_m_s2.push(off);
                }
            }
            cells.push((
                r.phase,
                r.status,
                r.fault_estimate,
                r.detail.fault_sigma,
                r.detail.block_ratio,
            ));
        }
        if let Some(w) = writer.as_mut() {
            for (phase, status, fhat, fsig, ratio) in &cells {
                record.push(phase_name(*phase).to_string());
                record.extend(
                    status
                        .iter()
                        .map(|s| s.sign().map_or(String::new(), |v| v.to_string())),
                );
                record.extend(fhat.iter().map(|v| format!("{v}")));
                match fsig {
                    Some(s) => record.extend(s.iter().map(|v| format!("{v}"))),
                    None => record.extend(std::iter::repeat_n(String::new(), 6)),
                }
                record.extend(
                    ratio
                        .iter()
                        .map(|v| v.map_or(String::new(), |v| format!("{v}"))),
                );
            }
            w.write_record(&record)?;
        }
    }
    if let Some(mut w) = writer {
        w.flush()?;
    }
    for (i, ch) in sum.channels.iter_mut().enumerate() {
        if ch.fault_rmse_n > 0 {
            let rmse = (ch.fault_sq_sum / ch.fault_rmse_n as f64).sqrt();
            ch.fault_rmse_si = Some(rmse);
            // Channels a_x, a_y, a_z, then p, q, r.
            if i < 3 {
                ch.fault_rmse_m_s2 = Some(rmse);
            } else {
                ch.fault_rmse_rad_s = Some(rmse);
            }
        }
    }
    sum.imus = imus;
    if opts.monitor == MonitorKind::Ukf || opts.aiding_delay != AidingDelay::Fixed(0.0) {
        sum.aiding_delay_mode = Some(match opts.aiding_delay {
            AidingDelay::Fixed(_) => "fixed".into(),
            AidingDelay::Auto => "auto".into(),
        });
    }
    sum.heading_offset_estimated = opts.estimate_heading_offset;
    sum.velocity_delay_mode = match opts.velocity_delay {
        AidingDelay::Fixed(_) => "fixed".into(),
        AidingDelay::Auto => "auto".into(),
    };
    sum.span_s = (
        rows.first().map_or(0.0, |r| r.t),
        rows.last().map_or(0.0, |r| r.t),
    );
    if let Some(p) = summary {
        std::fs::write(p, serde_json::to_string_pretty(&sum)?)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    Ok(sum)
}
