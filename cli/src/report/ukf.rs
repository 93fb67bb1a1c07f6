//! The single-IMU side of the report: every IMU of the log through its own
//! UKF innovation monitor (`eval::replay`, flight profile), recorded per
//! step: fault estimates with flag bands, innovations with ±3σ, phases and
//! input health.
//!
//! Only the report fields every single-IMU monitor shares (phase, status,
//! fault estimate, health, updated) are read, plus the innovations of the
//! UKF monitor's diagnostics in `innovations` (one place to adapt when the
//! monitors' report types are unified).

use std::path::Path;

use crate::eval::replay_monitor::ReplayDetail;
use anyhow::Result;
use imu_fdi::model::AidingKind;
use imu_fdi::monitor::{ChannelState, Phase, Report};

use super::verdict::{State, Verdict, CHANNELS};
use super::{FlightReport, Marker, Plot, Runs, Series, Strip, Stroke, AXIS_COLORS};

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Per IMU, what the run recorded.
struct Track {
    fhat: [Series; 6],
    innov: [Series; 6],
    plus: [Series; 6],
    minus: [Series; 6],
    flags: [Runs; 6],
    phase: Runs,
    health: Runs,
    first_flag: [Option<(f64, f64, i8)>; 6],
    flagged_s: [f64; 6],
    last_state: [ChannelState; 6],
    observed: [bool; 6],
    monitoring_from: Option<f64>,
    last_t: Option<f64>,
}

impl Track {
    fn new(k: usize) -> Self {
        let names = ["v_n", "v_e", "v_d", "roll", "pitch", "yaw"];
        let ch = |i: usize| AXIS_COLORS.get(i % 3).copied().unwrap_or("#000");
        Self {
            fhat: core::array::from_fn(|i| {
                Series::new(
                    format!("IMU {k} {}", CHANNELS.get(i).unwrap_or(&"")),
                    ch(i),
                    Stroke::Solid,
                )
            }),
            innov: core::array::from_fn(|i| {
                Series::new(names.get(i).copied().unwrap_or(""), ch(i), Stroke::Solid)
            }),
            plus: core::array::from_fn(|i| {
                Series::new(
                    format!("+3σ {}", names.get(i).unwrap_or(&"")),
                    ch(i),
                    Stroke::Dashed,
                )
            }),
            minus: core::array::from_fn(|i| {
                Series::new(
                    format!("−3σ {}", names.get(i).unwrap_or(&"")),
                    ch(i),
                    Stroke::Dashed,
                )
            }),
            flags: Default::default(),
            phase: Runs::default(),
            health: Runs::default(),
            first_flag: [None; 6],
            flagged_s: [0.0; 6],
            last_state: [ChannelState::NotMonitored; 6],
            observed: [false; 6],
            monitoring_from: None,
            last_t: None,
        }
    }

    fn see(&mut self, t: f64, r: &Report<f64, ReplayDetail>) {
        let dt = self.last_t.map_or(0.0, |p| t - p);
        self.last_t = Some(t);
        let monitoring = r.phase == Phase::Monitoring;
        if monitoring {
            self.monitoring_from.get_or_insert(t);
        }
        self.phase.see(
            t,
            Some(match r.phase {
                Phase::Aligning => ("aligning", "#bbbbbb"),
                Phase::Converging => ("converging", "#dddd88"),
                Phase::Learning => ("learning biases", "#88bbdd"),
                Phase::Monitoring => ("monitoring", "#9fd89f"),
            }),
        );
        self.health
            .see(t, health_label(&r.health).map(|l| (l, "#e6a23c")));
        for i in 0..6 {
            let unit = if i >= 3 { DEG } else { 1.0 };
            let fe = r.fault_estimate.get(i).copied().unwrap_or(f64::NAN);
            if let Some(s) = self.fhat.get_mut(i) {
                s.push(t, if monitoring { fe * unit } else { f64::NAN });
            }
            let st = r.status.get(i).copied().unwrap_or_default();
            let sign = if monitoring { st.sign() } else { None };
            if let Some(f) = self.flags.get_mut(i) {
                f.see(
                    t,
                    match sign {
                        Some(1) => Some(("+ fault", "#d62728")),
                        Some(-1) => Some(("− fault", "#1f77b4")),
                        _ => None,
                    },
                );
            }
            if sign.is_some() {
                if let Some(o) = self.observed.get_mut(i) {
                    *o = true;
                }
            }
            if let Some(s @ (1 | -1)) = sign {
                if let Some(ff) = self.first_flag.get_mut(i) {
                    ff.get_or_insert((t, fe * unit, s));
                }
                if let Some(d) = self.flagged_s.get_mut(i) {
                    *d += dt;
                }
            }
            if let Some(l) = self.last_state.get_mut(i) {
                *l = if monitoring {
                    st
                } else {
                    ChannelState::NotMonitored
                };
            }
        }
        if r.updated {
            for (i, (r_i, s_i)) in innovations(r).into_iter().enumerate() {
                let unit = if i >= 3 { DEG } else { 1.0 };
                let three = 3.0 * s_i.sqrt() * unit;
                if let (Some(a), Some(p), Some(m)) = (
                    self.innov.get_mut(i),
                    self.plus.get_mut(i),
                    self.minus.get_mut(i),
                ) {
                    a.push(t, r_i * unit);
                    p.push(t, three);
                    m.push(t, -three);
                }
            }
        }
    }
}

/// The innovations and their variances `S_ii` of the last aiding update
/// (NaN for a channel that was absent or a monitor without them).
fn innovations(r: &Report<f64, ReplayDetail>) -> [(f64, f64); 6] {
    r.detail.innovations.unwrap_or([(f64::NAN, f64::NAN); 6])
}

/// A short name of the input-health conditions of one step, if any.
fn health_label(h: &imu_fdi::monitor::Health) -> Option<&'static str> {
    if h.input_invalid {
        Some("IMU sample invalid")
    } else if h.frozen {
        Some("IMU frozen")
    } else if h.saturated {
        Some("saturated")
    } else if h.dt_out_of_range {
        Some("time gap")
    } else if h.covariance_reset {
        Some("covariance reset")
    } else if h.aiding_realigned {
        Some("aiding realigned")
    } else if h.aiding_invalid {
        Some("aiding invalid")
    } else if h.aiding_stale {
        Some("aiding repeating its last values")
    } else if h.aiding_rejected {
        Some("aiding outlier rejected")
    } else if h.pitch_singular {
        Some("pitch near ±90°")
    } else {
        None
    }
}

/// Replays the SPEC §10 CSV `csv` (converted from any log) through one UKF
/// monitor per IMU and adds its plots, lanes and verdicts to `report`.
/// `imus` is the number of IMUs in the file. When the monitor cannot run
/// (no aiding in the log) every channel is "not judged" with the reason.
pub fn add(csv: &Path, imus: usize, report: &mut FlightReport) -> Result<()> {
    let ropts = hal_sim::setup::RunOptions::default();
    let sim_cfg = |kind: AidingKind| {
        let scn = match kind {
            AidingKind::DvlCompass => hal_sim::Scenario::s2(),
            AidingKind::GnssAttitude => hal_sim::Scenario::s3(),
        };
        let mut c: imu_fdi::monitor::UkfMonitorConfig<f64> =
            hal_sim::runner::monitor_config(&scn, &ropts);
        c.detector = ropts.detector;
        c
    };
    let opts = crate::eval::replay::ReplayOptions::default();
    let mut tracks: Vec<Track> = (0..imus).map(Track::new).collect();
    // Samples where every IMU flags a channel at once: the aiding or the
    // model, not one IMU (SPEC §8b).
    let mut common = [0usize; 6];
    let run =
        crate::eval::replay::replay_observed(csv, None, None, sim_cfg, &opts, &mut |t, rs| {
            for (tr, r) in tracks.iter_mut().zip(rs) {
                tr.see(t, r);
            }
            for (i, c) in common.iter_mut().enumerate() {
                let flagged = |r: &Report<f64, ReplayDetail>| {
                    r.phase == Phase::Monitoring
                        && r.status
                            .get(i)
                            .and_then(|s| s.sign())
                            .is_some_and(|s| s != 0)
                };
                if rs.len() >= 2 && rs.iter().all(flagged) {
                    *c += 1;
                }
            }
        });
    let sum = match run {
        Ok(s) => s,
        Err(e) => {
            let why = format!("UKF monitor not run: {e:#}");
            let short = why
                .split_once(": the UKF")
                .map_or(why.as_str(), |(a, _)| a)
                .to_string();
            report.notes.push(why);
            for k in 0..imus {
                report
                    .verdicts
                    .extend(super::verdict::not_judged(k, "ukf", &short));
            }
            return Ok(());
        }
    };
    report.notes.push(format!(
        "UKF innovation monitor (run-time matrix + GLR, {} profile) on each of {} IMU(s) at {:.1} Hz; aiding {}; monitoring from {}",
        sum.profile.to_lowercase(),
        sum.imus,
        sum.imu_rate_hz,
        match sum.aiding.as_str() {
            "GnssAttitude" => "GNSS velocity and attitude",
            "DvlCompass" => "DVL velocity and compass attitude",
            other => other,
        },
        sum.monitoring_from_s
            .map_or("never".to_string(), |t| format!("{t:.2} s"))
    ));
    let dt = 1.0 / sum.imu_rate_hz.max(1e-9);
    let common_s = common.map(|n| n as f64 * dt);
    for (k, mut tr) in tracks.into_iter().enumerate() {
        if sum.aiding == "DvlCompass" {
            // DVL velocity is in the body frame, not north-east-down.
            for (s, name) in tr.innov.iter_mut().zip(["u", "v", "w"]) {
                s.name = name.into();
            }
        }
        add_imu(k, tr, &common_s, report);
    }
    Ok(())
}

fn add_imu(k: usize, tr: Track, common_s: &[f64; 6], report: &mut FlightReport) {
    let Track {
        fhat,
        innov,
        plus,
        minus,
        flags,
        phase,
        health,
        first_flag,
        flagged_s,
        last_state,
        observed,
        monitoring_from,
        ..
    } = tr;
    let flags: Vec<Vec<super::Interval>> = flags.into_iter().map(Runs::finish).collect();
    // Verdicts.
    for i in 0..6 {
        let unit = if i >= 3 { "°/s" } else { "m/s²" };
        let (state, since_s, why) = match (monitoring_from, first_flag.get(i).copied().flatten()) {
            (None, _) => (
                State::NotJudged,
                None,
                "the monitor never left alignment, convergence or learning".to_string(),
            ),
            (Some(_), Some((t, fe, s))) => {
                let episodes = flags.get(i).map_or(0, Vec::len);
                let now = match last_state.get(i) {
                    Some(ChannelState::FaultPositive | ChannelState::FaultNegative) => {
                        "still flagged at the end of the log".to_string()
                    }
                    _ => "back to healthy at the end of the log".to_string(),
                };
                let flagged = flagged_s.get(i).copied().unwrap_or(0.0);
                let shared = common_s.get(i).copied().unwrap_or(0.0);
                let common = if shared > 0.0 {
                    format!(
                        "; every IMU flagged this channel at once for {shared:.1} s of it (the aiding or the model rather than this IMU)"
                    )
                } else {
                    String::new()
                };
                (
                    State::Faulty,
                    Some(t),
                    format!(
                        "flagged {} in {episodes} episode(s), {flagged:.1} s in all; fault estimate {fe:+.3} {unit} at the first flag; {now}{common}",
                        if s > 0 { "positive" } else { "negative" },
                    ),
                )
            }
            (Some(_), None) if !observed.get(i).copied().unwrap_or(false) => (
                State::NotJudged,
                None,
                "no aiding observes this channel (it stayed not monitored)".to_string(),
            ),
            (Some(t), None) => (
                State::Healthy,
                Some(t),
                "monitored, never flagged".to_string(),
            ),
        };
        report.verdicts.push(Verdict {
            imu: k,
            channel: CHANNELS.get(i).copied().unwrap_or("").into(),
            monitor: "ukf".into(),
            state,
            since_s,
            why,
        });
    }
    // Fault estimates with flag bands, one plot per triad.
    let mut fhat = fhat.into_iter();
    let mut flags_it = flags.into_iter();
    for (triad, unit, title) in [("accel", "m/s²", "accelerometer"), ("gyro", "°/s", "gyro")] {
        let mut p = Plot::new(
            format!("imu{k}_{triad}_fault"),
            format!("IMU {k} {title}: UKF fault estimate and flags"),
            unit,
        );
        for a in 0..3 {
            if let Some(s) = fhat.next() {
                p.series.push(s);
            }
            let name = CHANNELS.get(if triad == "gyro" { 3 + a } else { a });
            p.strips.push(Strip {
                name: name.copied().unwrap_or("").into(),
                intervals: flags_it.next().unwrap_or_default(),
            });
        }
        if let Some(t) = monitoring_from {
            p.markers.push(Marker {
                t_s: t,
                label: "monitoring".into(),
                color: "#2ca02c".into(),
            });
        }
        report.plots.push(p);
    }
    // Innovations with ±3σ.
    let mut it = innov.into_iter().zip(plus).zip(minus);
    for (what, unit) in [("velocity", "m/s"), ("attitude", "°")] {
        let mut p = Plot::new(
            format!("imu{k}_{what}_innovation"),
            format!("IMU {k}: {what} innovations with ±3σ"),
            unit,
        );
        for _ in 0..3 {
            if let Some(((a, b), c)) = it.next() {
                if a.y.iter().any(|v| v.is_finite()) {
                    p.series.extend([a, b, c]);
                }
            }
        }
        if !p.series.is_empty() {
            report.plots.push(p);
        }
    }
    report.timeline.lanes.push(Strip {
        name: format!("UKF IMU {k} phase"),
        intervals: phase.finish(),
    });
    report.timeline.lanes.push(Strip {
        name: format!("UKF IMU {k} input health"),
        intervals: health.finish(),
    });
}
