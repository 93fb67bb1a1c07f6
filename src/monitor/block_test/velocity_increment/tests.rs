//! Unit tests of the accelerometer/GNSS-velocity test: the closed-form bias
//! at a constant attitude, the GNSS lag learnt from the data, a step
//! detected with its size and sign, and the flag back to nominal after it.

// Test code: a panic is a failed assertion.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
use super::super::test_noise::Noise;
use super::*;
use crate::model::G0;

const DEG: f64 = core::f64::consts::PI / 180.0;
const DT: f64 = 0.01;

/// The fixed attitude of these tests (roll 10°, pitch −5°, yaw 30°).
const EULER: [f64; 3] = [10.0 * DEG, -5.0 * DEG, 30.0 * DEG];

/// A vehicle at the fixed attitude with NED acceleration `accel(t)` (and
/// velocity `vel(t)`, its integral); a 100-Hz accelerometer reading
/// `Cᵀ(a − g) + bias(t) + white noise imu_sd`, 10-Hz attitude aiding and
/// 5-Hz GNSS velocity `vel(t − lag)` with white errors `gnss_sd`, fed to
/// `vi` for `secs` from `t0`; deviations below `relevant` (m/s², every
/// axis) are not reported.
#[allow(clippy::too_many_arguments)]
fn fly(
    vi: &mut VelocityIncrement<f64>,
    cfg: &VelocityIncrementConfig<f64>,
    t0: f64,
    secs: f64,
    accel: impl Fn(f64) -> Vector3<f64>,
    vel: impl Fn(f64) -> Vector3<f64>,
    bias: impl Fn(f64) -> Vector3<f64>,
    lag: f64,
    noise: &mut Noise,
    imu_sd: f64,
    gnss_sd: f64,
    relevant: f64,
) {
    let c = from_euler(EULER[0], EULER[1], EULER[2]).to_rotation_matrix();
    let g = Vector3::new(0.0, 0.0, G0);
    let limits = ChannelLimits {
        nominal: Vector3::from_element(2.0),
        relevant: Vector3::from_element(relevant),
    };
    let steps = libm::round(secs / DT) as usize;
    for i in 0..steps {
        let t = t0 + i as f64 * DT;
        // The specific force at mid-sample (the integration's point).
        let f = c.inverse() * (accel(t + 0.5 * DT) - g) + bias(t) + noise.vec(imu_sd);
        vi.integrate(&f, &Vector3::zeros(), DT);
        let k = i + 1;
        if k % 10 == 0 {
            vi.attitude_epoch(EULER);
        }
        if k % 20 == 0 {
            let v = vel(t + DT - lag) + noise.vec(gnss_sd);
            vi.velocity_epoch(cfg, v, &limits, 1.0, false);
        }
    }
}

fn new_test(cfg: &VelocityIncrementConfig<f64>) -> VelocityIncrement<f64> {
    let mut vi = VelocityIncrement::new(cfg.alpha(), DT, G0);
    vi.attitude_epoch(EULER);
    vi
}

/// A manoeuvring vehicle: NED acceleration and its velocity.
fn weave_a(t: f64) -> Vector3<f64> {
    Vector3::new(
        3.0 * libm::sin(0.9 * t),
        2.0 * libm::cos(0.6 * t),
        0.8 * libm::sin(1.3 * t),
    )
}
fn weave_v(t: f64) -> Vector3<f64> {
    Vector3::new(
        -3.0 / 0.9 * libm::cos(0.9 * t),
        2.0 / 0.6 * libm::sin(0.6 * t),
        -0.8 / 1.3 * libm::cos(1.3 * t),
    )
}

#[test]
fn a_constant_attitude_and_acceleration_give_the_body_bias_in_closed_form() {
    // r = Δv_G − ∫(C f + g) = −C b Δt and M = C Δt, so −M⁻¹ r = b exactly:
    // every block mean is the bias, at every lag (constant acceleration).
    let cfg = VelocityIncrementConfig::velocity();
    let mut vi = new_test(&cfg);
    let a = Vector3::new(0.4, -0.3, 0.1);
    let b = Vector3::new(0.5, -0.25, 0.1);
    let mut n = Noise(7);
    fly(
        &mut vi,
        &cfg,
        0.0,
        30.0,
        |_| a,
        |t| a * t,
        |_| b,
        0.0,
        &mut n,
        0.0,
        0.0,
        0.0,
    );
    assert!(vi.test.filled >= 25, "{} blocks", vi.test.filled);
    for age in 0..vi.test.filled {
        let m = vi.test.blocks[vi.test.slot(age).unwrap()];
        assert!((m - b).norm() < 1e-9, "block {age}: {m:?}");
    }
}

/// The weaving flight with GNSS velocity 0.3 s late, a constant bias,
/// 0.3 m/s² accelerometer and 0.02 m/s GNSS noise, from `t0` for `secs`.
fn weave_late(
    vi: &mut VelocityIncrement<f64>,
    cfg: &VelocityIncrementConfig<f64>,
    t0: f64,
    secs: f64,
    n: &mut Noise,
) {
    let bias = |_| Vector3::new(0.1, 0.0, -0.2);
    fly(
        vi, cfg, t0, secs, weave_a, weave_v, bias, 0.3, n, 0.3, 0.02, 0.0,
    );
}

#[test]
fn the_gnss_lag_is_learnt_from_the_data() {
    // GNSS velocity 0.3 s late on a weaving flight: the lag whose block
    // estimates vary least is 0.3 s (at 0 s the misfit is ≈ 0.3 s × the
    // change of acceleration over a block, up to 0.8 m/s²).
    let cfg = VelocityIncrementConfig::velocity();
    let mut vi = new_test(&cfg);
    let mut n = Noise(11);
    weave_late(&mut vi, &cfg, 0.0, 90.0, &mut n);
    assert!((vi.lag_s() - 0.3).abs() < 1e-9, "lag {}", vi.lag_s());
    let d = &vi.diff2;
    assert!(d[3] < 0.5 * d[0], "variation per lag {d:?}");
}

#[test]
fn a_step_is_flagged_with_its_size_and_the_flag_clears_after_it() {
    let cfg = VelocityIncrementConfig::velocity();
    let mut vi = new_test(&cfg);
    let mut n = Noise(3);
    let turn_on = Vector3::new(0.05, -0.1, 0.3);
    let (onset, end) = (150.0, 170.0);
    let bias = move |t: f64| {
        if (onset..end).contains(&t) {
            turn_on + Vector3::new(0.5, 0.0, 0.0)
        } else {
            turn_on
        }
    };
    let run = |vi: &mut VelocityIncrement<f64>, n: &mut Noise, t0: f64, secs: f64| {
        fly(
            vi, &cfg, t0, secs, weave_a, weave_v, bias, 0.2, n, 0.5, 0.05, 0.0,
        );
    };
    // 60 s of learning, then 90 s judged fault-free.
    run(&mut vi, &mut n, 0.0, 60.0);
    vi.test.start_judging();
    let mut max_ratio: f64 = 0.0;
    let mut t = 60.0;
    while t < onset {
        run(&mut vi, &mut n, t, 1.0);
        t += 1.0;
        assert_eq!(vi.test.detail.flag, [0; 3], "false alarm at {t} s");
        max_ratio = vi
            .test
            .detail
            .ratio
            .iter()
            .fold(max_ratio, |m, r| m.max(*r));
    }
    assert!(max_ratio > 0.0, "never judged");
    assert!((vi.lag_s() - 0.2).abs() < 1e-9, "lag {}", vi.lag_s());
    // The learnt offset is the turn-on bias.
    let off = Vector3::from(vi.test.detail.offset);
    assert!((off - turn_on).norm() < 0.05, "offset {off:?}");
    let mut found = None;
    while t < end {
        run(&mut vi, &mut n, t, 1.0);
        t += 1.0;
        if found.is_none() && vi.test.detail.flag == [1, 0, 0] {
            found = Some(t - onset);
        }
        assert!(vi.test.detail.flag[1..] == [0, 0], "y/z flagged at {t} s");
    }
    // Its size once every window holds it (the first flag may come from a
    // window that straddles the onset).
    assert_eq!(vi.test.detail.flag, [1, 0, 0]);
    let e = vi.test.detail.estimate[0];
    assert!((e - 0.5).abs() < 0.1, "estimate {e}");
    let found = found.expect("step not flagged");
    assert!(found <= 5.0, "flagged after {found} s");
    let mut cleared = None;
    while t < end + 40.0 {
        run(&mut vi, &mut n, t, 1.0);
        t += 1.0;
        if cleared.is_none() && vi.test.detail.flag == [0; 3] {
            cleared = Some(t - end);
        }
        if let Some(c) = cleared {
            assert_eq!(
                vi.test.detail.flag, [0; 3],
                "back on at {t} s (cleared {c} s)"
            );
        }
    }
    let cleared = cleared.expect("flag never cleared");
    assert!(cleared <= 8.0, "cleared {cleared} s after the step");
}

/// A 0.15 m/s² x step on quiet aiding (the simulated kind): flagged on the
/// statistics alone, not once the smallest fault reported is 0.2 m/s².
#[test]
fn a_significant_deviation_below_the_smallest_fault_is_not_reported() {
    let cfg = VelocityIncrementConfig::velocity();
    let (onset, end) = (120.0, 140.0);
    let bias = move |t: f64| {
        if (onset..end).contains(&t) {
            Vector3::new(0.15, 0.0, 0.0)
        } else {
            Vector3::zeros()
        }
    };
    let flagged_s = |relevant: f64| {
        let mut vi = new_test(&cfg);
        let mut n = Noise(5);
        fly(
            &mut vi, &cfg, 0.0, 60.0, weave_a, weave_v, bias, 0.2, &mut n, 0.1, 0.01, relevant,
        );
        vi.test.start_judging();
        let mut flagged = 0;
        for s in 60..160 {
            fly(
                &mut vi,
                &cfg,
                f64::from(s),
                1.0,
                weave_a,
                weave_v,
                bias,
                0.2,
                &mut n,
                0.1,
                0.01,
                relevant,
            );
            if vi.test.detail.flag != [0; 3] {
                flagged += 1;
            }
        }
        flagged
    };
    let on_statistics = flagged_s(0.0);
    assert!(on_statistics >= 10, "flagged {on_statistics} s");
    assert_eq!(flagged_s(0.2), 0);
}
