//! The sensitivity sweep of SPEC §7 / issue "redundant IMUs": for each
//! method, the smallest bias detected in ≥ 99 % of runs with zero false
//! alarms over fault-free hours, and the detection delay. Runs in parallel
//! over all cores (rayon).

use core::f64::consts::PI;

use anyhow::Result;
use rayon::prelude::*;

use crate::eval::array_run::{array_config, run_array, ArrayRun, MethodOutcome};
use hal_sim::array::{ArrayFault, ArrayFaultKind, ArrayKind, ArraySpec, Layout};

/// The five methods compared.
pub const METHODS: [&str; 5] = [
    "paper PCA",
    "chi2/GLT",
    "CUSUM",
    "PX4-like",
    "ArduPilot-like",
];

/// Onset of the swept fault (scenario time), s.
pub const SWEEP_ONSET: f64 = 5.0;
/// Scenario length of a sweep run, s (20 s after onset: ArduPilot's 10 s
/// persistence fits).
pub const SWEEP_DURATION: f64 = 25.0;

fn outcome(run: &ArrayRun, method: usize) -> &MethodOutcome {
    match method {
        0 => &run.pca,
        1 => &run.glt,
        2 => &run.cusum,
        3 => &run.px4,
        _ => &run.ardupilot,
    }
}

/// Detection of one method at one bias size.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SizeResult {
    /// Bias (unit of the sensors).
    pub size: f64,
    /// Runs with an alarm while the fault was active.
    pub detected: u32,
    /// Runs.
    pub runs: u32,
    /// Mean delay onset → first alarm over detected runs, s.
    pub mean_delay: f64,
    /// Largest delay, s.
    pub max_delay: f64,
    /// Detected runs whose blamed sensor/IMU was the faulty one.
    pub correct_blame: u32,
}

/// Sweep of one method.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MethodSweep {
    /// Method name.
    pub method: &'static str,
    /// False-alarm events over the fault-free hours.
    pub false_alarms: u32,
    /// Per size, ascending.
    pub sizes: Vec<SizeResult>,
}

impl MethodSweep {
    /// Smallest size from which every larger swept size is detected in
    /// ≥ 99 % of runs, if the method also had zero false alarms.
    pub fn min_detected(&self) -> Option<&SizeResult> {
        if self.false_alarms > 0 {
            return None;
        }
        let mut best = None;
        for r in self.sizes.iter().rev() {
            if f64::from(r.detected) >= 0.99 * f64::from(r.runs) {
                best = Some(r);
            } else {
                break;
            }
        }
        best
    }
}

/// The unit the baselines blame for sensor `k`.
fn unit_of(layout: Layout, k: usize) -> usize {
    match layout {
        Layout::Single => k,
        Layout::Triads => k / 3,
    }
}

/// Sweeps `sizes` with `runs` seeded runs each (fault on sensor
/// `seed % N`, random sign, from [`SWEEP_ONSET`]) and `hours` fault-free
/// hours, for all five methods.
pub fn sweep<const N: usize>(
    base: &ArraySpec<N>,
    sizes: &[f64],
    runs: u32,
    hours: u32,
    first_seed: u64,
) -> Result<Vec<MethodSweep>> {
    let mut free = base.clone();
    free.faults.clear();
    free.duration_s = 3600.0;
    free.motion_start = 0.0;
    let fa: Vec<ArrayRun> = (0..u64::from(hours))
        .into_par_iter()
        .map(|h| run_array::<f32, N>(&free, first_seed + 1_000_000 + h, array_config(&free)))
        .collect::<Result<_>>()?;
    let jobs: Vec<(usize, u64)> = (0..sizes.len())
        .flat_map(|i| (0..u64::from(runs)).map(move |s| (i, s)))
        .collect();
    let results: Vec<(usize, usize, ArrayRun)> = jobs
        .par_iter()
        .map(|&(i, s)| {
            let seed = first_seed + s;
            let sensor = (seed as usize) % N;
            let sign = if (seed / N as u64) % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            let mut spec = base.clone();
            spec.faults.clear();
            spec.duration_s = SWEEP_DURATION;
            spec.motion_start = 0.0;
            let spec = spec.with_fault(ArrayFault {
                sensor,
                start: SWEEP_ONSET,
                end: f64::INFINITY,
                kind: ArrayFaultKind::Bias(sign * sizes.get(i).copied().unwrap_or(0.0)),
            });
            run_array::<f32, N>(&spec, seed, array_config(&spec)).map(|r| (i, sensor, r))
        })
        .collect::<Result<_>>()?;
    Ok((0..METHODS.len())
        .map(|m| {
            let false_alarms = fa.iter().map(|r| outcome(r, m).false_alarm_events).sum();
            let sizes = sizes
                .iter()
                .enumerate()
                .map(|(i, &size)| {
                    let mut r = SizeResult {
                        size,
                        detected: 0,
                        runs: 0,
                        mean_delay: 0.0,
                        max_delay: 0.0,
                        correct_blame: 0,
                    };
                    for (_, sensor, run) in results.iter().filter(|(j, _, _)| *j == i) {
                        r.runs += 1;
                        let o = outcome(run, m);
                        if let Some(t) = o.first_alarm {
                            let d = t - SWEEP_ONSET;
                            r.detected += 1;
                            r.mean_delay += d;
                            r.max_delay = r.max_delay.max(d);
                            let blamed = match m {
                                0..=2 => run.isolated.map(|(k, _)| k).or(o.blamed),
                                _ => o.blamed,
                            };
                            let want = if m >= 3 {
                                unit_of(base.layout, *sensor)
                            } else {
                                *sensor
                            };
                            if blamed == Some(want) {
                                r.correct_blame += 1;
                            }
                        }
                    }
                    if r.detected > 0 {
                        r.mean_delay /= f64::from(r.detected);
                    }
                    r
                })
                .collect();
            MethodSweep {
                method: METHODS.get(m).copied().unwrap_or("?"),
                false_alarms,
                sizes,
            }
        })
        .collect())
}

/// The default bias grid: gyro in rad/s (0.01–30 °/s), accel in m/s²
/// (0.002–5 m/s²).
pub fn default_sizes(kind: ArrayKind) -> Vec<f64> {
    match kind {
        ArrayKind::Gyro => [
            0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0,
            7.0, 10.0, 15.0, 20.0, 30.0,
        ]
        .iter()
        .map(|d| d * PI / 180.0)
        .collect(),
        ArrayKind::Accel => vec![
            0.002, 0.003, 0.005, 0.007, 0.01, 0.015, 0.02, 0.03, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3,
            0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0,
        ],
    }
}

/// Display unit and scale of an array kind.
pub fn unit(kind: ArrayKind) -> (&'static str, f64) {
    match kind {
        ArrayKind::Gyro => ("°/s", 180.0 / PI),
        ArrayKind::Accel => ("m/s²", 1.0),
    }
}

/// The sweep as a text table: per method, false alarms, the smallest bias
/// detected in ≥ 99 % of runs, its mean/max delay and isolation accuracy.
pub fn format_sweep(kind: ArrayKind, sweeps: &[MethodSweep], runs: u32, hours: u32) -> String {
    use core::fmt::Write as _;
    let (u, scale) = unit(kind);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<15} {:>12} {:>14} {:>16} {:>10}",
        "method",
        format!("FA in {hours} h"),
        format!("min bias {u}"),
        "delay mean/max s",
        "blame ok"
    );
    for m in sweeps {
        match m.min_detected() {
            Some(r) => {
                // ArduPilot's consistency check names no IMU.
                let blame = if m.method == "ArduPilot-like" {
                    "n/a".to_string()
                } else {
                    format!(
                        "{:.0}%",
                        100.0 * f64::from(r.correct_blame) / f64::from(r.detected.max(1))
                    )
                };
                let _ = writeln!(
                    s,
                    "{:<15} {:>12} {:>14.3} {:>9.2}/{:<6.2} {:>10}",
                    m.method,
                    m.false_alarms,
                    r.size * scale,
                    r.mean_delay,
                    r.max_delay,
                    blame
                );
            }
            None => {
                let why = if m.false_alarms > 0 {
                    "false alarms"
                } else {
                    "none in grid"
                };
                let _ = writeln!(s, "{:<15} {:>12} {:>14}", m.method, m.false_alarms, why);
            }
        }
    }
    let _ = writeln!(
        s,
        "({runs} runs per size, fault on a random sensor from t = {SWEEP_ONSET} s, {} s after onset; \
         'min bias' = smallest size from which every larger swept size is detected in >= 99 % of runs)",
        SWEEP_DURATION - SWEEP_ONSET
    );
    s
}
