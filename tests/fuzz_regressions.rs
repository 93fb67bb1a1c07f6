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

/// `fuzz/…/parity_monitor/crash-e41ed475`: two sensors of the cone out
/// (parity dimension 1: detect-only), then a gross transient on a third
/// pushed the CUSUM to hundreds of times its threshold; once the input was
/// valid again the alarm stayed for minutes while the CUSUM decayed by κ
/// per block. The CUSUM is now held below `h + 50 κ`: the alarm clears
/// within 5 s of valid input.
#[test]
fn parity_cusum_alarm_clears_after_a_gross_transient() {
    use hal_sim::array::{cone6_directions, ArrayKind, ArraySim, ArraySpec, Layout};
    use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading};

    let spec = ArraySpec::fault_free(
        "cone6",
        cone6_directions(),
        ArrayKind::Gyro,
        Layout::Single,
        40.0,
    );
    let sim = ArraySim::new(&spec, 1);
    let fs = spec.errors.full_scale as f32;
    let dirs = spec.directions.map(|d| d.map(|v| v as f32));
    let mut cfg = ParityConfig::<f32>::gyro(100.0, fs);
    cfg.set_lead_in(sim.lead_in_samples());
    let mut m = ParityMonitor::<f32, 6, 16>::new(&Geometry::new(&dirs).unwrap(), cfg).unwrap();
    let mut last_alarm = f64::NAN;
    let mut peak = 0.0f32;
    for s in sim {
        let mut r = s.readings.map(|r| r.map(|v| v as f32));
        // Sensors 2 and 5 time out at 1 s (latched): dimension 1 remains.
        if s.t >= 1.0 {
            r[2] = Reading::Missing;
            r[5] = Reading::Missing;
        }
        // 3 s of +30 °/s on sensor 0 (not isolable in dimension 1).
        if (5.0..8.0).contains(&s.t) {
            if let Reading::Sample(x) = &mut r[0] {
                *x += 30f32.to_radians();
            }
        }
        let rep = m.step(&r);
        if s.t >= 0.0 && rep.fault {
            last_alarm = s.t;
        }
        peak = peak.max(rep.cusum_ratio);
    }
    assert_eq!(m.phase(), ParityPhase::Monitoring);
    assert!(
        peak > 1.0,
        "the transient must raise the CUSUM alarm: {peak}"
    );
    assert!(
        last_alarm < 8.0 + 5.5,
        "alarm at {last_alarm:.2} s, more than 5.5 s after the transient ended at 8 s"
    );
}
