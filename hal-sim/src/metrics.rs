//! SPEC §9 metrics computed from a run trace.

use imu_fdi::math::wrap_pi_f64;
use imu_fdi::model::CHANNEL_NAMES;
use imu_fdi::monitor::Phase;

use crate::runner::Trace;

/// Time after a fault ends during which flags are neither false alarms nor
/// wrong-channel flags: 2·L. A window still holds in-fault innovations for one
/// window length after the fault ends, and a large fault (S2's a_x ramp ends at
/// 0.9 m/s², ≈ 25 σ per innovation) keeps the statistic above threshold until
/// the last of them has left; the filter's own recovery adds a few epochs.
pub fn grace_s(trace: &Trace) -> f64 {
    2.0 * trace.latency_s
}

/// Per-channel figures of one or more runs.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct ChannelMetrics {
    /// Fault rows injected on this channel.
    pub faults: usize,
    /// Of those, detected at least once on this channel with the right sign.
    pub detected: usize,
    /// Samples counted for the detection rate (from detectable onset + L,
    /// |fault| ≥ minimum).
    pub counted: usize,
    /// Of those, flagged on this channel with the right sign.
    pub hits: usize,
    /// Samples inside this channel's fault windows.
    pub fault_samples: usize,
    /// Of those, samples where some channel without a fault was flagged.
    pub wrong_channel: usize,
    /// Fault-free samples (outside every fault window and grace period).
    pub free_samples: usize,
    /// Of those, samples with this channel flagged.
    pub false_alarms: usize,
    /// Sum and count of detection delays, and the largest, s.
    pub delay_sum: f64,
    /// Number of delays summed.
    pub delay_n: usize,
    /// Largest delay, s.
    pub delay_max: f64,
    /// Σ squared error of the corrected estimate over fault samples.
    pub se_sum: f64,
    /// Σ squared error of the as-written estimate.
    pub se_as_written_sum: f64,
    /// Samples in the RMSE sums.
    pub se_n: usize,
}

impl ChannelMetrics {
    /// Detection rate (None when nothing was counted).
    pub fn detection_rate(&self) -> Option<f64> {
        (self.counted > 0).then(|| self.hits as f64 / self.counted as f64)
    }
    /// False-alarm rate over fault-free samples.
    pub fn false_alarm_rate(&self) -> f64 {
        if self.free_samples == 0 {
            0.0
        } else {
            self.false_alarms as f64 / self.free_samples as f64
        }
    }
    /// Wrong-channel rate over this channel's fault samples.
    pub fn wrong_channel_rate(&self) -> Option<f64> {
        (self.fault_samples > 0).then(|| self.wrong_channel as f64 / self.fault_samples as f64)
    }
    /// Mean detection delay, s.
    pub fn delay_mean(&self) -> Option<f64> {
        (self.delay_n > 0).then(|| self.delay_sum / self.delay_n as f64)
    }
    /// RMSE of the corrected fault estimate.
    pub fn rmse(&self) -> Option<f64> {
        (self.se_n > 0).then(|| (self.se_sum / self.se_n as f64).sqrt())
    }
    /// RMSE of the as-written estimate.
    pub fn rmse_as_written(&self) -> Option<f64> {
        (self.se_n > 0).then(|| (self.se_as_written_sum / self.se_n as f64).sqrt())
    }
    fn add(&mut self, o: &Self) {
        self.faults += o.faults;
        self.detected += o.detected;
        self.counted += o.counted;
        self.hits += o.hits;
        self.fault_samples += o.fault_samples;
        self.wrong_channel += o.wrong_channel;
        self.free_samples += o.free_samples;
        self.false_alarms += o.false_alarms;
        self.delay_sum += o.delay_sum;
        self.delay_n += o.delay_n;
        self.delay_max = self.delay_max.max(o.delay_max);
        self.se_sum += o.se_sum;
        self.se_as_written_sum += o.se_as_written_sum;
        self.se_n += o.se_n;
    }
}

/// Figures of one or more runs.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct RunMetrics {
    /// Per IMU channel.
    pub channels: [ChannelMetrics; 6],
    /// Rising edges of "any channel flagged" in fault-free time.
    pub false_alarm_events: usize,
    /// Fault-free monitored time, s.
    pub free_time_s: f64,
    /// Runs merged.
    pub runs: usize,
    /// Latency allowance L, s.
    pub latency_s: f64,
    /// Covariance resets summed over runs.
    pub covariance_resets: u64,
    /// State RMSE `[u, v, w, φ, θ, ψ]` over fault-free monitored time (yaw wrapped).
    pub state_rmse: [f64; 6],
    /// RMS of the fault estimate over fault-free monitored time: the bias
    /// the learning phase and drift tracking leave unexplained.
    pub residual_rms: [f64; 6],
    state_se: [f64; 6],
    residual_se: [f64; 6],
    state_n: usize,
}

impl RunMetrics {
    /// Merges another run's figures.
    pub fn merge(&mut self, o: &Self) {
        for (a, b) in self.channels.iter_mut().zip(o.channels.iter()) {
            a.add(b);
        }
        self.false_alarm_events += o.false_alarm_events;
        self.free_time_s += o.free_time_s;
        self.runs += o.runs;
        self.latency_s = o.latency_s;
        self.covariance_resets += o.covariance_resets;
        for i in 0..6 {
            self.state_se[i] += o.state_se[i];
            self.residual_se[i] += o.residual_se[i];
        }
        self.state_n += o.state_n;
        self.finish();
    }
    fn finish(&mut self) {
        let n = self.state_n.max(1) as f64;
        for i in 0..6 {
            self.state_rmse[i] = (self.state_se[i] / n).sqrt();
            self.residual_rms[i] = (self.residual_se[i] / n).sqrt();
        }
    }

    /// Total false-alarm samples over all channels.
    pub fn total_false_alarms(&self) -> usize {
        self.channels.iter().map(|c| c.false_alarms).sum()
    }

    /// A fixed-width table, one row per channel.
    pub fn table(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "{:<4} {:>6} {:>9} {:>9} {:>10} {:>10} {:>9} {:>9} {:>11} {:>11}\n",
            "ch",
            "faults",
            "detected",
            "det.rate",
            "false.al.",
            "wrong.ch.",
            "delay.mn",
            "delay.mx",
            "rmse.corr",
            "rmse.paper"
        ));
        for (c, name) in self.channels.iter().zip(CHANNEL_NAMES.iter()) {
            let pct = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{:.2}%", 100.0 * x));
            let sec = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}s"));
            let num = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
            s.push_str(&format!(
                "{:<4} {:>6} {:>9} {:>9} {:>10} {:>10} {:>9} {:>9} {:>11} {:>11}\n",
                name,
                c.faults,
                format!("{}/{}", c.detected, c.faults),
                pct(c.detection_rate()),
                format!("{:.3}%", 100.0 * c.false_alarm_rate()),
                pct(c.wrong_channel_rate()),
                sec(c.delay_mean()),
                sec((c.delay_n > 0).then_some(c.delay_max)),
                num(c.rmse()),
                num(c.rmse_as_written()),
            ));
        }
        s.push_str(&format!(
            "runs {}, latency L = {:.2} s, fault-free monitored time {:.1} s, false-alarm events {}, covariance resets {}\n",
            self.runs, self.latency_s, self.free_time_s, self.false_alarm_events, self.covariance_resets
        ));
        let r = &self.residual_rms;
        s.push_str(&format!(
            "residual bias after learning (RMS of f̂, fault-free): accel {:.4} {:.4} {:.4} m/s², gyro {:.3} {:.3} {:.3} °/s\n",
            r[0], r[1], r[2], r[3].to_degrees(), r[4].to_degrees(), r[5].to_degrees()
        ));
        s.push_str("units: accel m/s², gyro rad/s; rmse over fault-active monitored samples\n");
        s
    }
}

/// Computes the metrics of one trace.
pub fn evaluate(trace: &Trace) -> RunMetrics {
    let scn = &trace.scenario;
    let rows = &trace.rows;
    let lat = trace.latency_s;
    let grace = grace_s(trace);
    let dt = 1.0 / scn.imu_rate_hz;
    let mut m = RunMetrics {
        runs: 1,
        latency_s: lat,
        covariance_resets: rows.last().map_or(0, |r| u64::from(r.covariance_resets)),
        ..RunMetrics::default()
    };
    // Per additive fault row: detection rate, delay, RMSE. Hardware rows
    // have no size or sign to score this way: see `hardware_detections`.
    for fr in scn.faults.iter().filter(|r| !r.is_hardware()) {
        let j = fr.channel;
        let Some(c) = m.channels.get_mut(j) else {
            continue;
        };
        let mdf = scn.min_fault.get(j).copied().unwrap_or(0.0);
        c.faults += 1;
        let in_window = rows
            .iter()
            .filter(|r| fr.active(r.t) && r.phase == Phase::Monitoring);
        let t_detectable = rows
            .iter()
            .filter(|r| fr.active(r.t))
            .find(|r| r.fault[j].abs() >= mdf)
            .map(|r| r.t);
        let mut detected = false;
        for r in in_window {
            let f = r.fault[j];
            let want = if f > 0.0 { 1 } else { -1 };
            let correct = r.flag[j] == Some(want) && f != 0.0;
            if let Some(td) = t_detectable {
                // Delay from the time the fault reached its minimum size; a
                // flag raised earlier than that counts as zero delay.
                if correct && !detected {
                    let d = (r.t - td).max(0.0);
                    c.delay_sum += d;
                    c.delay_n += 1;
                    c.delay_max = c.delay_max.max(d);
                }
                if r.t >= td + lat && f.abs() >= mdf {
                    c.counted += 1;
                    c.hits += usize::from(correct);
                }
            }
            detected |= correct;
            c.fault_samples += 1;
            // A channel is "wrong" only if no fault of its own is active or
            // ended within the grace period (its flag may still be releasing).
            let wrong = (0..6).any(|k| {
                let own_recent = scn
                    .faults
                    .iter()
                    .any(|f| f.channel == k && r.t >= f.start && r.t < f.end + grace);
                !own_recent && r.flag[k].is_some_and(|v| v != 0)
            });
            c.wrong_channel += usize::from(wrong);
            if r.flag[j].is_some() {
                c.se_sum += (r.fhat[j] - f).powi(2);
                c.se_as_written_sum += (r.fhat_as_written[j] - f).powi(2);
                c.se_n += 1;
            }
        }
        c.detected += usize::from(detected);
    }
    // False alarms in fault-free monitored time.
    let mut prev_any = false;
    for r in rows.iter().filter(|r| r.phase == Phase::Monitoring) {
        let near_fault = scn
            .faults
            .iter()
            .any(|f| r.t >= f.start && r.t < f.end + grace);
        if near_fault {
            prev_any = false;
            continue;
        }
        let mut any = false;
        for (c, fl) in m.channels.iter_mut().zip(r.flag.iter()) {
            c.free_samples += 1;
            if fl.is_some_and(|v| v != 0) {
                c.false_alarms += 1;
                any = true;
            }
        }
        if any && !prev_any {
            m.false_alarm_events += 1;
        }
        prev_any = any;
        m.free_time_s += dt;
        for i in 0..6 {
            let mut e = r.state[i] - r.truth[i];
            if i >= 3 {
                e = wrap_pi_f64(e);
            }
            m.state_se[i] += e * e;
            m.residual_se[i] += r.fhat[i] * r.fhat[i];
        }
        m.state_n += 1;
    }
    m.finish();
    m
}

/// How the monitor saw one hardware-fault row (SPEC §8 S5): through a
/// health check of the sample, or through a flag on the faulty channel.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HardwareDetection {
    /// The fault row.
    pub kind: String,
    /// Its channel name.
    pub channel: String,
    /// Onset, s.
    pub start: f64,
    /// End, s.
    pub end: f64,
    /// First health flag from onset to end + L, s after onset, and which.
    pub first_health: Option<(f64, String)>,
    /// First flag (either sign) on the faulty channel, s after onset.
    pub first_flag: Option<f64>,
    /// Samples with a flag on another channel in the same interval.
    pub other_channel_samples: usize,
}

impl HardwareDetection {
    /// Seconds from onset to the first sign of the fault, health flag or
    /// channel flag, whichever came first.
    pub fn first_seen(&self) -> Option<f64> {
        let health = self.first_health.as_ref().map(|(s, _)| *s);
        match (health, self.first_flag) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

fn health_names(h: &imu_fdi::monitor::Health) -> String {
    let mut v = Vec::new();
    for (on, name) in [
        (h.input_invalid, "input_invalid"),
        (h.frozen, "frozen"),
        (h.saturated, "saturated"),
        (h.dt_out_of_range, "dt_out_of_range"),
    ] {
        if on {
            v.push(name);
        }
    }
    v.join("+")
}

/// The hardware rows of the trace's scenario, each with how it was seen
/// (from onset to end + the latency allowance L).
pub fn hardware_detections(trace: &Trace) -> Vec<HardwareDetection> {
    trace
        .scenario
        .faults
        .iter()
        .filter(|r| r.is_hardware())
        .map(|r| {
            let within = trace
                .rows
                .iter()
                .filter(|x| x.t >= r.start && x.t < r.end + trace.latency_s);
            let mut d = HardwareDetection {
                kind: format!("{:?}", r.kind),
                channel: CHANNEL_NAMES
                    .get(r.channel)
                    .map_or(String::new(), |c| (*c).to_string()),
                start: r.start,
                end: r.end,
                first_health: None,
                first_flag: None,
                other_channel_samples: 0,
            };
            for x in within {
                let names = health_names(&x.health);
                if d.first_health.is_none() && !names.is_empty() {
                    d.first_health = Some((x.t - r.start, names));
                }
                for (c, f) in x.flag.iter().enumerate() {
                    if f.is_some_and(|f| f != 0) {
                        if c == r.channel {
                            d.first_flag.get_or_insert(x.t - r.start);
                        } else {
                            d.other_channel_samples += 1;
                        }
                    }
                }
            }
            d
        })
        .collect()
}
