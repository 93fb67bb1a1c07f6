//! Bad input never panics and never leaks NaN: each case gets its status and
//! the monitor recovers.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use imu_fdi::filter::{SigmaParams, Ukf, UkfError};
use imu_fdi::math::LinalgError;
use imu_fdi::model::{ImuVec, Mat6, MeasVec, Measurement, StateVec, STATE_ANGLES};
use imu_fdi::monitor::{Phase, UkfMonitor, UkfMonitorConfig};
use proptest::prelude::*;

const G: f32 = 9.806_65;

fn level() -> ImuVec<f32> {
    ImuVec::new(0.0, 0.0, -G, 0.0, 0.0, 0.0)
}

fn aiding(all: bool) -> Measurement<f32> {
    Measurement {
        z: MeasVec::zeros(),
        available: [all, all, all, true, true, true],
    }
}

fn aligned() -> UkfMonitor<f32> {
    let mut m = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
    m.step(&level(), 0.01, &aiding(true));
    assert_eq!(m.phase(), Phase::Converging);
    m
}

fn finite(r: &imu_fdi::monitor::Report<f32>) -> bool {
    r.state
        .iter()
        .chain(r.state_sigma.iter())
        .chain(r.fault_estimate.iter())
        .all(|v| v.is_finite())
}

#[test]
fn nan_and_out_of_range_imu_samples_are_rejected() {
    let mut m = aligned();
    let mut bad = level();
    bad[4] = f32::NAN;
    let r = m.step(&bad, 0.01, &aiding(false));
    assert!(r.health.input_invalid && finite(&r));
    bad[4] = 1e9;
    let r = m.step(&bad, 0.01, &aiding(false));
    assert!(r.health.input_invalid && finite(&r));
    let r = m.step(&level(), 0.01, &aiding(true));
    assert!(!r.health.input_invalid && finite(&r));
}

#[test]
fn alignment_on_a_nan_sample_does_not_leak_nan() {
    // Found by the property test below on a fresh machine.
    let mut m = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
    let r = m.step(&ImuVec::from_element(f32::NAN), 0.01, &aiding(true));
    assert!(r.health.input_invalid && finite(&r), "{:?}", r.state);
}

#[test]
fn bad_dt_is_reported_and_gaps_are_bounded() {
    let mut m = aligned();
    for dt in [0.0, -0.01, f32::NAN, f32::INFINITY] {
        let before = *m.filter().state();
        let r = m.step(&level(), dt, &aiding(false));
        assert!(r.health.dt_out_of_range);
        assert_eq!(
            *m.filter().state(),
            before,
            "state must not move for dt = {dt}"
        );
    }
    let r = m.step(&level(), 3.0, &aiding(false));
    assert!(r.health.dt_out_of_range && finite(&r));
}

#[test]
fn frozen_imu_is_flagged() {
    let mut m = aligned();
    let mut frozen = false;
    for _ in 0..30 {
        frozen |= m.step(&level(), 0.01, &aiding(false)).health.frozen;
    }
    assert!(frozen);
}

#[test]
fn saturation_is_flagged() {
    let mut m = aligned();
    let mut s = level();
    s[3] = 0.99 * m.config().full_scale[3];
    assert!(m.step(&s, 0.01, &aiding(false)).health.saturated);
}

#[test]
fn pitch_singularity_is_reported_not_nan() {
    let mut m = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
    // Align at 89°: the model refuses, the monitor keeps waiting.
    let mut z = MeasVec::zeros();
    z[4] = 89f32.to_radians();
    let r = m.step(
        &level(),
        0.01,
        &Measurement {
            z,
            available: [true; 6],
        },
    );
    assert_eq!(r.phase, Phase::Aligning);
    // Aligned level, then pitched up hard by a large q: reported, finite.
    let mut m = aligned();
    let mut pitch_up = level();
    pitch_up[4] = 30.0;
    let mut seen = false;
    for _ in 0..200 {
        let r = m.step(&pitch_up, 0.01, &Measurement::none());
        seen |= r.health.pitch_singular;
        assert!(finite(&r));
    }
    assert!(seen);
}

#[test]
fn lost_cholesky_is_an_error_with_recovery() {
    let p0 = Mat6::<f64>::identity() * 0.01;
    let mut ukf =
        Ukf::<f64, 6, 13>::new(StateVec::zeros(), p0, &SigmaParams::default(), STATE_ANGLES)
            .unwrap();
    let mut bad = Mat6::identity();
    bad[(2, 2)] = -1.0;
    ukf.reset(StateVec::zeros(), bad);
    let r = ukf.predict(|x| Ok::<_, ()>(*x), &Mat6::zeros());
    assert_eq!(
        r,
        Err(UkfError::CovarianceReset(LinalgError::NotPositiveDefinite(
            2
        )))
    );
    assert_eq!(ukf.covariance_resets(), 1);
    assert!((ukf.covariance() - p0).amax() < 1e-15);
    assert_eq!(ukf.predict(|x| Ok::<_, ()>(*x), &Mat6::zeros()), Ok(()));
}

#[test]
fn nan_aiding_channels_are_ignored() {
    let mut m = aligned();
    let mut z = MeasVec::zeros();
    z[0] = f32::NAN;
    let r = m.step(
        &level(),
        0.01,
        &Measurement {
            z,
            available: [true; 6],
        },
    );
    assert!(finite(&r));
    assert!(!r.detail.diag[0].fused);
}

/// A channel whose aiding is absent is "not monitored", a third state
/// distinct from healthy: DVL lost → accelerometers not monitored, gyros
/// still monitored through the compass.
#[test]
fn lost_aiding_makes_channels_not_monitored() {
    use hal_sim::runner::{monitor_config, RunOptions};
    use hal_sim::{Scenario, Simulator};
    use imu_fdi::monitor::ChannelState;
    let scn = Scenario::auv_fault_free(30.0);
    let mut m = UkfMonitor::<f32>::new(monitor_config(&scn, &RunOptions::default())).unwrap();
    let mut last = None;
    for s in Simulator::new(&scn, 1) {
        let mut avail = s.aiding_available;
        if s.t > 20.0 {
            avail[0] = false;
            avail[1] = false;
            avail[2] = false;
        }
        let u = ImuVec::from_fn(|i, _| s.imu.unwrap()[i] as f32);
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let r = m.step(
            &u,
            0.01,
            &Measurement {
                z,
                available: avail,
            },
        );
        if (s.t - 19.9).abs() < 1e-9 {
            assert!(
                r.status.iter().all(|c| *c == ChannelState::Healthy),
                "{:?}",
                r.status
            );
        }
        last = Some(r);
    }
    let r = last.unwrap();
    assert_eq!(r.status[..3], [ChannelState::NotMonitored; 3]);
    assert_eq!(r.status[3..], [ChannelState::Healthy; 3]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// Arbitrary sequences of samples, dt and aiding (including NaN, huge
    /// and negative values) never panic and never produce a non-finite state.
    #[test]
    fn arbitrary_input_never_panics_or_leaks_nan(
        steps in prop::collection::vec(
            (prop::array::uniform6(prop_oneof![Just(f32::NAN), -1e3f32..1e3, Just(0.0f32)]),
             prop_oneof![Just(0.01f32), Just(f32::NAN), -1.0f32..2.0],
             prop::array::uniform6(prop_oneof![Just(f32::NAN), -10f32..10.0]),
             prop::array::uniform6(any::<bool>())),
            1..300)
    ) {
        let mut m = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
        for (imu, dt, z, avail) in steps {
            let r = m.step(&ImuVec::from(imu), dt, &Measurement { z: MeasVec::from(z), available: avail });
            prop_assert!(finite(&r), "non-finite report {:?}", r.state);
        }
    }
}
