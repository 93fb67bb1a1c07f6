//! Recovery from bad input (issue 16, `docs/recovery.md`): clean runs to
//! corrupt, a pitch manoeuvre through ±90°, the fault classes, and what
//! "back to nominal" means for each monitor. Shared by the recovery matrix
//! (`hal-sim/tests/recovery_matrix.rs`) and the fuzz targets (`fuzz/`), so
//! both judge recovery by the same predicate.

use std::vec::Vec;

use imu_fdi::model::{AidingKind, ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::{
    ChannelState, Health, OtsukfMonitor, OtsukfReport, Phase, Report, UkfMonitor,
};
use imu_fdi::parity::{ParityPhase, ParityReport, SensorStatus};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::{Scenario, Simulator};

/// Standard gravity of the model, m/s².
const G: f64 = 9.806_65;

/// One monitor period as the monitor sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Time, s.
    pub t: f64,
    /// The IMU sample `[a; ω]`.
    pub imu: ImuVec<f32>,
    /// The measured period, s.
    pub dt: f32,
    /// The aiding that arrived in this period.
    pub aiding: Measurement<f32>,
}

/// A fault-free run of `scn` (its fault table cleared) for `duration_s`.
pub fn clean_run(scn: &Scenario, seed: u64, duration_s: f64) -> Vec<Step> {
    let mut scn = scn.clone();
    scn.faults.clear();
    scn.duration_s = duration_s;
    Simulator::new(&scn, seed)
        .map(|s| Step {
            t: s.t,
            imu: s.imu.map_or(ImuVec::from_element(f32::NAN), |v| {
                ImuVec::from_fn(|i, _| v[i] as f32)
            }),
            dt: s.dt as f32,
            aiding: Measurement {
                z: MeasVec::from_fn(|i, _| s.aiding[i] as f32),
                available: s.aiding_available,
            },
        })
        .collect()
}

/// A pitch manoeuvre about the body y axis at constant forward speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PitchManoeuvre {
    /// Full loops at a constant pitch rate, °/s.
    Loop {
        /// Pitch rate, °/s.
        rate_dps: f64,
    },
    /// `α(t) = A sin(2π t / T)`: through ±90° when `A` > 90°.
    Sweep {
        /// Amplitude `A`, °.
        amplitude_deg: f64,
        /// Period `T`, s.
        period_s: f64,
    },
}

/// Straight and level for `lead_s`, the manoeuvre for `manoeuvre_s`, level
/// again for `tail_s`, at 100 Hz: body velocity `(speed, 0, 0)` and a
/// rotation `α` about body y, so the specific force is exactly
/// `(g sin α, 0, −speed·α̇ − g cos α)` and the aiding is the Euler triad of
/// `R_y(α)` — (0, α, 0) while `cos α > 0`, (π, π − α, π) beyond — with the
/// velocity in body axes (DVL) or NED (GNSS). White noise on the IMU
/// (0.02 m/s², 0.05 °/s) and the aiding (0.01 m/s, 0.02°); velocity at 5 Hz,
/// attitude at 10 Hz. The manoeuvre ends at a whole number of loops or
/// sweep periods so the tail is level.
pub fn pitch_run(
    kind: AidingKind,
    speed: f64,
    manoeuvre: PitchManoeuvre,
    lead_s: f64,
    manoeuvre_s: f64,
    tail_s: f64,
    seed: u64,
) -> Vec<Step> {
    let rate = 100.0;
    let dt = 1.0 / rate;
    let n = ((lead_s + manoeuvre_s + tail_s) * rate).round() as usize;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x7069_7463);
    let mut gauss = move || -> f64 { StandardNormal.sample(&mut rng) };
    let deg = core::f64::consts::PI / 180.0;
    let angle = |t: f64| -> (f64, f64) {
        let tm = t - lead_s;
        if !(0.0..manoeuvre_s).contains(&tm) {
            return (0.0, 0.0);
        }
        match manoeuvre {
            PitchManoeuvre::Loop { rate_dps } => (rate_dps * deg * tm, rate_dps * deg),
            PitchManoeuvre::Sweep {
                amplitude_deg,
                period_s,
            } => {
                let w = 2.0 * core::f64::consts::PI / period_s;
                let a = amplitude_deg * deg;
                (a * libm::sin(w * tm), a * w * libm::cos(w * tm))
            }
        }
    };
    (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            // The sample is the mean over its period: take the mid-point rate.
            let (alpha, q) = angle(t - 0.5 * dt);
            let (sa, ca) = (libm::sin(alpha), libm::cos(alpha));
            let f = [G * sa, 0.0, -speed * q - G * ca];
            let imu = ImuVec::from_fn(|i, _| {
                let (v, s) = if i < 3 {
                    (f[i], 0.02)
                } else if i == 4 {
                    (q, 0.05 * deg)
                } else {
                    (0.0, 0.05 * deg)
                };
                (v + s * gauss()) as f32
            });
            let (alpha, _) = angle(t);
            let (sa, ca) = (libm::sin(alpha), libm::cos(alpha));
            // Euler (ZYX) of R_y(α).
            let theta = libm::asin(sa.clamp(-1.0, 1.0));
            let flip = if ca >= 0.0 {
                0.0
            } else {
                core::f64::consts::PI
            };
            let vel = match kind {
                AidingKind::DvlCompass => [speed, 0.0, 0.0],
                AidingKind::GnssAttitude => [speed * ca, 0.0, -speed * sa],
            };
            let z = [
                vel[0] + 0.01 * gauss(),
                vel[1] + 0.01 * gauss(),
                vel[2] + 0.01 * gauss(),
                flip + 0.02 * deg * gauss(),
                theta + 0.02 * deg * gauss(),
                flip + 0.02 * deg * gauss(),
            ];
            let vel_epoch = k % 20 == 0;
            let att_epoch = k % 10 == 0;
            Step {
                t,
                imu,
                dt: dt as f32,
                aiding: Measurement {
                    z: MeasVec::from_fn(|i, _| imu_fdi::math::wrap_pi(z[i]) as f32),
                    available: [
                        vel_epoch, vel_epoch, vel_epoch, att_epoch, att_epoch, att_epoch,
                    ],
                },
            }
        })
        .collect()
}

/// True when no health flag is raised.
pub fn health_clear(h: &Health) -> bool {
    *h == Health::default()
}

/// The name of the first health flag raised, if any.
pub fn health_flag(h: &Health) -> Option<&'static str> {
    let flags = [
        (h.input_invalid, "input_invalid"),
        (h.frozen, "frozen"),
        (h.saturated, "saturated"),
        (h.dt_out_of_range, "dt_out_of_range"),
        (h.pitch_singular, "pitch_singular"),
        (h.covariance_reset, "covariance_reset"),
        (h.aiding_rejected, "aiding_rejected"),
        (h.aiding_invalid, "aiding_invalid"),
        (h.aiding_stale, "aiding_stale"),
        (h.aiding_realigned, "aiding_realigned"),
    ];
    flags.iter().find(|(set, _)| *set).map(|(_, name)| *name)
}

fn all_finite<'a>(v: impl IntoIterator<Item = &'a f32>) -> bool {
    v.into_iter().all(|x| x.is_finite())
}

fn positive_definite<const N: usize>(p: &nalgebra::SMatrix<f32, N, N>) -> bool {
    let p = p.map(f64::from);
    p.iter().all(|v| v.is_finite()) && p.cholesky().is_some()
}

/// The part of "back to nominal" both single-IMU monitors share:
/// monitoring, no health flag, every channel healthy.
fn judged_nominal(phase: Phase, health: &Health, status: &[ChannelState]) -> Option<&'static str> {
    if phase != Phase::Monitoring {
        return Some("not monitoring");
    }
    if let Some(flag) = health_flag(health) {
        return Some(flag);
    }
    if !channels_healthy(status) {
        return Some("channel not healthy");
    }
    None
}

fn channels_healthy(status: &[ChannelState]) -> bool {
    status.iter().all(|s| *s == ChannelState::Healthy)
}

/// Why the UKF monitor is not back to nominal (`None` when it is):
/// monitoring, every channel `Healthy` (no stale fault, none unmonitored),
/// no health flag, finite state and estimates, covariance positive definite.
pub fn ukf_off_nominal<const W: usize>(
    r: &Report<f32>,
    m: &UkfMonitor<f32, W>,
) -> Option<&'static str> {
    if !all_finite(
        r.state
            .iter()
            .chain(r.state_sigma.iter())
            .chain(r.fault_estimate.iter())
            .chain(r.corrected_imu.iter()),
    ) {
        return Some("non-finite output");
    }
    if !positive_definite(m.filter().covariance()) {
        return Some("covariance not positive definite");
    }
    judged_nominal(r.phase, &r.health, &r.status)
}

/// As [`ukf_off_nominal`] for the two-stage monitor (state and fault
/// covariances).
pub fn ots_off_nominal(r: &OtsukfReport<f32>, m: &OtsukfMonitor<f32>) -> Option<&'static str> {
    if !all_finite(
        r.state
            .iter()
            .chain(r.state_sigma.iter())
            .chain(r.fault_estimate.iter())
            .chain(r.detail.fault_sigma.iter())
            .chain(r.corrected_imu.iter()),
    ) {
        return Some("non-finite output");
    }
    if !positive_definite(&m.filter().state_covariance())
        || !positive_definite(m.filter().fault_covariance())
    {
        return Some("covariance not positive definite");
    }
    judged_nominal(r.phase, &r.health, &r.status)
}

/// Why the parity monitor is not back to nominal: monitoring, no alarm,
/// a finite fused output, and every sensor `Healthy` except those in
/// `latched` (a sensor that failed a hardware check for longer than its
/// limit is out of the set by design until `reset`, `docs/recovery.md`),
/// which must be reported failed — never silently back.
pub fn parity_off_nominal<const N: usize>(
    r: &ParityReport<f32, N>,
    latched: &[bool; N],
) -> Option<&'static str> {
    if r.phase != ParityPhase::Monitoring {
        return Some("not monitoring");
    }
    if !r.fused.is_some_and(|v| all_finite(v.iter())) {
        return Some("no finite fused output");
    }
    if r.fault {
        return Some("alarm");
    }
    for (s, l) in r.status.iter().zip(latched.iter()) {
        match (*l, *s) {
            (false, SensorStatus::Healthy) => {}
            (true, s) if s.is_failed() => {}
            (false, _) => return Some("sensor not healthy"),
            (true, _) => return Some("failed sensor not reported"),
        }
    }
    None
}
