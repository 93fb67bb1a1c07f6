//! Inputs the fuzz targets (`fuzz/`) found, reduced to the monitor call
//! that failed: each one must stay fixed.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code

use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::{OtsukfConfig, OtsukfMonitor, UkfMonitor, UkfMonitorConfig};

const G: f32 = 9.806_65;

fn level() -> ImuVec<f32> {
    ImuVec::new(0.01, -0.02, -G, 0.001, -0.002, 0.0)
}

fn attitude() -> Measurement<f32> {
    Measurement {
        z: MeasVec::zeros(),
        available: [true; 6],
    }
}

/// `fuzz/artifacts/…/crash-4fb71c78`, `crash-825392ab`: a NaN or ∞ IMU
/// channel made the reported corrected sample non-finite (the state stayed
/// finite). The corrected sample of an invalid input is now the stand-in
/// the filter used: the last good sample, corrected.
#[test]
fn corrected_sample_of_an_invalid_input_is_finite() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30] {
        let mut ukf = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
        let mut ots =
            OtsukfMonitor::<f32>::new(OtsukfConfig::from_base(UkfMonitorConfig::auv())).unwrap();
        let none = Measurement::<f32>::none();
        for k in 0..5 {
            let mut imu = level();
            if k >= 3 {
                imu[k % 6] = bad;
            }
            let aiding = if k == 0 { attitude() } else { none };
            let r = ukf.step(&imu, 0.01, &aiding);
            assert_eq!(r.health.input_invalid, k >= 3);
            assert!(
                r.corrected_imu.iter().all(|v| v.is_finite()),
                "UKF {bad}: {r:?}"
            );
            let r = ots.step(&imu, 0.01, &aiding);
            assert_eq!(r.health.input_invalid, k >= 3);
            assert!(
                r.corrected_imu.iter().all(|v| v.is_finite()),
                "OTSUKF {bad}: {r:?}"
            );
        }
    }
}
