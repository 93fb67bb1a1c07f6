//! The injection sweep of a multi-IMU log: the smallest bias each method
//! (parity monitor, PX4-like, ArduPilot-like) detects on every channel.

use anyhow::Result;
use hal_sim::array::ArrayKind;

use super::parity_replay::{replay_parity_with, ImuLog, Injection, ParityMethod};

/// Seconds after onset within which an injected bias counts as detected.
pub const DETECT_WITHIN_S: f64 = 15.0;

/// Smallest injected bias detected on one channel, per method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InjectionResult {
    /// IMU index.
    pub imu: usize,
    /// Axis 0–2 of the swept kind.
    pub axis: usize,
    /// Onset, s.
    pub onset: f64,
    /// Parity monitor: (size, delay s, isolated to the right sensor).
    pub parity: Option<(f64, f64, bool)>,
    /// PX4-like: (size, delay s).
    pub px4: Option<(f64, f64)>,
    /// ArduPilot-like: (size, delay s).
    pub ardupilot: Option<(f64, f64)>,
}

/// For every IMU channel of `kind` and each onset, the smallest of `sizes`
/// (ascending) that each method flags within [`DETECT_WITHIN_S`] with no
/// alarm between monitoring start and onset.
pub fn injection_sweep(
    log: &ImuLog,
    kind: ArrayKind,
    train_start: f64,
    train_s: f64,
    onsets: &[f64],
    sizes: &[f64],
    method: ParityMethod,
) -> Result<Vec<InjectionResult>> {
    let channel0 = match kind {
        ArrayKind::Gyro => 3,
        ArrayKind::Accel => 0,
    };
    let mut out = Vec::new();
    for imu in 0..3 {
        for axis in 0..3 {
            for &onset in onsets {
                let mut res = InjectionResult {
                    imu,
                    axis,
                    onset,
                    parity: None,
                    px4: None,
                    ardupilot: None,
                };
                for &size in sizes {
                    let inj = Injection {
                        imu,
                        channel: channel0 + axis,
                        size,
                        start: onset,
                        end: f64::INFINITY,
                    };
                    let r = replay_parity_with(log, kind, train_start, train_s, Some(inj), method)?;
                    let first = |list: &[(f64, f64, Option<usize>)]| {
                        if list.iter().any(|a| a.0 < onset) {
                            return None;
                        }
                        list.iter()
                            .find(|a| a.0 < onset + DETECT_WITHIN_S)
                            .map(|a| a.0 - onset)
                    };
                    if res.parity.is_none() {
                        if let Some(d) = first(&r.alarms) {
                            let ok = r.isolations.first().is_some_and(|(k, t)| {
                                *k == 3 * imu + axis && *t < onset + DETECT_WITHIN_S
                            });
                            res.parity = Some((size, d, ok));
                        }
                    }
                    if res.px4.is_none() {
                        res.px4 = first(&r.px4).map(|d| (size, d));
                    }
                    if res.ardupilot.is_none() {
                        res.ardupilot = first(&r.ardupilot).map(|d| (size, d));
                    }
                    if res.parity.is_some() && res.px4.is_some() && res.ardupilot.is_some() {
                        break;
                    }
                }
                out.push(res);
            }
        }
    }
    Ok(out)
}

/// Bias grid for [`injection_sweep`]: gyro 0.5–30 °/s (rad/s), accel
/// 0.05–5 m/s².
pub fn injection_sizes(kind: ArrayKind) -> Vec<f64> {
    match kind {
        ArrayKind::Gyro => [0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 7.0, 10.0, 15.0, 20.0, 30.0]
            .iter()
            .map(|d: &f64| d.to_radians())
            .collect(),
        ArrayKind::Accel => vec![0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0],
    }
}
