//! Numerical checks run on the target (`target-tests`, QEMU) against
//! expectations computed on the host.
//!
//! Each check is one generic function: the host runs it in `f64` and writes
//! the results to `tests/data/target_expectations.txt` (a host test keeps
//! that file current); the firmware image runs the same function in `f32`
//! on the emulated Cortex-M4F and compares. What differs between the two is
//! exactly what the checks are for: the target's FPU, its `vsqrt`, the `f32`
//! trigonometry and the `f32` filter arithmetic.

use imu_fdi::math::Real;
use imu_fdi::model::{ImuVec, Mat6, MeasVec, Measurement, StateVec};
use imu_fdi::monitor::{OtsukfMonitor, Phase, UkfMonitor};

use crate::setup::{monitor_config, RunOptions};
use crate::{Scenario, Simulator};

/// Square-root inputs: the target's `vsqrt` must give the bits of the
/// host's correctly rounded `sqrtf`.
pub const SQRT_INPUTS: [f32; 10] = [
    0.0, 1e-30, 1e-12, 2.5e-7, 0.3, 1.0, 2.0, 9.806_65, 12_345.679, 3.0e30,
];

/// Angles (rad) for the `f32` sine and cosine.
pub const ANGLES: [f64; 10] = [-1.0e3, -3.1, -1.56, -0.2, 0.0, 1e-6, 0.5, 1.58, 3.13, 123.4];

/// A symmetric positive definite 6×6 matrix with all entries coupled and a
/// condition number of about 1e4 (covariance-like).
pub fn spd6<T: Real>() -> Mat6<T> {
    let scale = [1e-2, 1e-2, 4e-2, 1e-4, 1e-4, 4e-4];
    Mat6::from_fn(|i, j| {
        let (si, sj) = (scale[i], scale[j]);
        let c = if i == j {
            1.0
        } else {
            0.3 / (1.0 + (i as f64 - j as f64).abs())
        };
        T::lit(c * libm::sqrt(si * sj))
    })
}

/// Steps of each monitor run.
pub const MONITOR_STEPS: usize = 1500;

/// A simulated sample as the monitor's input, rounded to `f32` first on
/// both sides so that the host's `f64` run and the target's `f32` run
/// differ only in the filter's arithmetic.
fn rounded_to_f32<T: Real>(s: &crate::SimSample) -> (ImuVec<T>, T, Measurement<T>) {
    let u = ImuVec::from_fn(|i, _| {
        s.imu
            .map_or(T::lit(f64::NAN), |v| T::lit(f64::from(v[i] as f32)))
    });
    let z = MeasVec::from_fn(|i, _| T::lit(f64::from(s.aiding[i] as f32)));
    let m = Measurement {
        z,
        available: s.aiding_available,
    };
    (u, T::lit(f64::from(s.dt as f32)), m)
}

/// Runs the UKF monitor in `T` over the first [`MONITOR_STEPS`] IMU periods
/// of `scn` (seed 1) and returns its state and state standard deviations.
/// Returns `None` if the configuration is refused.
pub fn monitor_run<T: Real>(scn: &Scenario) -> Option<(StateVec<T>, StateVec<T>)> {
    let cfg = monitor_config::<T>(scn, &RunOptions::default());
    let mut monitor = UkfMonitor::<T>::new(cfg).ok()?;
    let mut last = None;
    for s in Simulator::new(scn, 1).take(MONITOR_STEPS) {
        let (u, dt, m) = rounded_to_f32(&s);
        let r = monitor.step(&u, dt, &m);
        last = Some((r.state, r.state_sigma));
    }
    last
}

/// Runs the OTSUKF monitor in `T` over the first [`MONITOR_STEPS`]
/// IMU periods of S3 (seed 1, the realistic configuration; monitoring from
/// about 8 s on, faults from 10 s) and returns its whole fault estimate
/// `f̂` and the estimate's standard deviations. `each` gets every report's
/// phase (the target counts the instructions of monitoring steps with it).
/// Returns `None` if the configuration is refused.
pub fn otsukf_run<T: Real>(
    mut each: impl FnMut(&mut dyn FnMut() -> Phase),
) -> Option<(ImuVec<T>, ImuVec<T>)> {
    let scn = Scenario::s3();
    let cfg = crate::ots::otsukf_config::<T>(&scn, crate::ots::Setting::Realistic);
    let mut monitor = OtsukfMonitor::<T>::new(cfg).ok()?;
    let mut last = None;
    for s in Simulator::new(&scn, 1).take(MONITOR_STEPS) {
        let (u, dt, m) = rounded_to_f32(&s);
        each(&mut || {
            let r = monitor.step(&u, dt, &m);
            last = Some((r.detail.total_bias, r.detail.fault_sigma));
            r.phase
        });
    }
    last
}

/// The two monitor runs: S2 (AUV, DVL + compass, the affine update) and
/// the aircraft profile (GNSS velocity + attitude, the sigma-point update).
pub fn monitor_scenarios() -> [(&'static str, Scenario); 2] {
    [
        ("s2", Scenario::s2()),
        ("aircraft", Scenario::aircraft_fault_free(60.0)),
    ]
}

/// Student-t quantiles checked on target: `(alpha, degrees of freedom)`.
pub const T_QUANTILES: [(f64, u32); 3] = [(1e-6, 9), (1e-3, 9), (0.05, 4)];
