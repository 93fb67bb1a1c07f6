//! Unit tests of the gyro/attitude-aiding consistency test: closed-form
//! residuals, `f32` against `f64`, detection, recovery, no learning during
//! a fault, no judging of flight against a spread learnt at rest.

// Test code: a panic is a failed assertion.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
use super::super::test_noise::Noise;
use super::*;

const DEG: f64 = core::f64::consts::PI / 180.0;

/// A body turning at `rate(t)` (rad/s, piecewise constant over each
/// 100-Hz IMU sample, so the truth is exact), its gyro reading
/// `rate + bias(t) + white noise`, and 10-Hz attitude aiding with white
/// errors of `aid_sd` per axis, fed to `ar` for `secs` from `t0`.
/// Returns the truth attitude at the end.
#[allow(clippy::too_many_arguments)]
fn fly<T: Real>(
    ar: &mut AttitudeRate<T>,
    cfg: &AttitudeRateConfig<T>,
    truth: UnitQuaternion<f64>,
    t0: f64,
    secs: f64,
    rate: impl Fn(f64) -> Vector3<f64>,
    bias: impl Fn(f64) -> Vector3<f64>,
    noise: &mut Noise,
    gyro_sd: f64,
    aid_sd: f64,
) -> UnitQuaternion<f64> {
    let dt = 0.01;
    let mut q = truth;
    let limits = ChannelLimits {
        nominal: Vector3::from_element(T::lit(1.0)),
        relevant: Vector3::zeros(),
    };
    let steps = libm::round(secs / dt) as usize;
    for i in 0..steps {
        let t = t0 + i as f64 * dt;
        let w = rate(t);
        q *= rotation_exp(&(w * dt));
        let g = w + bias(t) + noise.vec(gyro_sd);
        ar.integrate(&g.map(T::lit), T::lit(dt));
        if (i + 1) % 10 == 0 {
            let aid = q * rotation_exp(&noise.vec(aid_sd));
            let (r, p, y) = aid.euler_angles();
            ar.epoch(
                cfg,
                [T::lit(r), T::lit(p), T::lit(y)],
                &limits,
                T::lit(1.0),
                false,
            );
        }
    }
    q
}

fn turning(t: f64) -> Vector3<f64> {
    Vector3::new(
        60.0 * libm::sin(0.7 * t),
        45.0 * libm::cos(1.1 * t),
        20.0 * libm::sin(0.3 * t + 1.0),
    ) * DEG
}

#[test]
fn log_and_exp_are_inverse_and_small_angles_keep_their_digits_in_f32() {
    for v in [
        Vector3::new(0.3, -1.2, 2.0),
        Vector3::new(1e-3, 2e-3, -3e-3),
        Vector3::new(0.0, 3.0, 0.1),
    ] {
        let back = rotation_log(&rotation_exp(&v));
        assert!((back - v).norm() < 1e-12 * (1.0 + v.norm()), "{v} {back}");
    }
    // 2 °/s over 0.1 s in f32: within 1e-4 relative (acos would lose
    // ≈ 10 %).
    let v = Vector3::new(2.0 * DEG * 0.1, 0.0, 0.0).map(|x| x as f32);
    let back = rotation_log(&rotation_exp(&v));
    assert!((back - v).norm() / v.norm() < 1e-4, "{back}");
}

/// Constant body rate (≈ 110 °/s about a skew axis) and constant bias,
/// no noise: every residual is the bias exactly to first order, so
/// the block means equal it (to 1e-3 of it; the second-order term is
/// `|b|Δt` ≈ 5e-3 rad here). Without the Jacobian it would be turned
/// by ½·ω·Δt ≈ 5.5°, a 10 % error across axes.
#[test]
fn constant_rate_and_bias_give_the_bias() {
    let cfg = AttitudeRateConfig::<f64>::flight();
    let mut ar = AttitudeRate::<f64>::new(cfg.alpha());
    let w = Vector3::new(1.0, -0.7, 1.5);
    let b = Vector3::new(2.0, -3.0, 1.0) * DEG;
    let q0 = UnitQuaternion::from_euler_angles(0.2, -0.3, 1.0);
    let mut n = Noise(7);
    fly(&mut ar, &cfg, q0, 0.0, 30.0, |_| w, |_| b, &mut n, 0.0, 0.0);
    assert!(ar.test.filled >= 40);
    for a in 0..ar.test.filled {
        let m = ar.test.blocks[ar.test.slot(a).unwrap()];
        assert!((m - b).norm() < 1e-3 * b.norm(), "{m} vs {b}");
    }
    // The same in f32 (the MCU's type): 1 % of the bias.
    let cfg32 = AttitudeRateConfig::<f32>::flight();
    let mut ar32 = AttitudeRate::<f32>::new(cfg32.alpha());
    let mut n = Noise(7);
    fly(
        &mut ar32,
        &cfg32,
        q0,
        0.0,
        30.0,
        |_| w,
        |_| b,
        &mut n,
        0.0,
        0.0,
    );
    for a in 0..ar32.test.filled {
        let m = ar32.test.blocks[ar32.test.slot(a).unwrap()].map(f64::from);
        assert!((m - b).norm() < 1e-2 * b.norm(), "{m} vs {b}");
    }
}

/// A body turning at up to 75 °/s on all axes, a constant bias: the
/// quaternion integration across each 0.1-s interval keeps the block
/// means on the bias (within 2 % of it; 1.4 % is the residual
/// second-order term of a varying rate).
#[test]
fn a_turning_body_gives_the_bias() {
    let cfg = AttitudeRateConfig::<f64>::flight();
    let mut ar = AttitudeRate::<f64>::new(cfg.alpha());
    let b = Vector3::new(-1.0, 2.0, 0.5) * DEG;
    let mut n = Noise(3);
    fly(
        &mut ar,
        &cfg,
        UnitQuaternion::identity(),
        0.0,
        20.0,
        turning,
        |_| b,
        &mut n,
        0.0,
        0.0,
    );
    for a in 0..ar.test.filled {
        let m = ar.test.blocks[ar.test.slot(a).unwrap()];
        assert!((m - b).norm() < 0.02 * b.norm(), "{m} vs {b}");
    }
}

/// Learning `secs` of healthy turning flight (gyro 0.5 °/s/√Hz-class
/// noise, 0.3° aiding errors), then judging.
fn learnt<T: Real>(secs: f64, n: &mut Noise) -> (AttitudeRate<T>, UnitQuaternion<f64>) {
    let cfg = AttitudeRateConfig::<T>::flight();
    let mut ar = AttitudeRate::<T>::new(cfg.alpha());
    let bias = Vector3::new(0.3, -0.2, 0.1) * DEG;
    let q = fly(
        &mut ar,
        &cfg,
        UnitQuaternion::identity(),
        0.0,
        secs,
        turning,
        |_| bias,
        n,
        0.02,
        0.3 * DEG,
    );
    ar.test.start_judging();
    (ar, q)
}

/// The flag: raised with its sign and size on a 2 °/s step within
/// 10 s, never raised on healthy flight, cleared within the 5 s the
/// issue allows after the fault ends (the longer windows' verdict
/// withdrawn by the shortest), and the offset and variance not learnt
/// meanwhile; then a negative step on another axis.
#[test]
fn a_step_is_flagged_learnt_never_and_the_flag_clears() {
    let cfg = AttitudeRateConfig::<f64>::flight();
    let mut n = Noise(11);
    let (mut ar, mut q) = learnt::<f64>(60.0, &mut n);
    let base = Vector3::new(0.3, -0.2, 0.1) * DEG;
    let mut t = 60.0;
    let mut max_ratio: f64 = 0.0;
    for _ in 0..120 {
        q = fly(
            &mut ar,
            &cfg,
            q,
            t,
            1.0,
            turning,
            |_| base,
            &mut n,
            0.02,
            0.3 * DEG,
        );
        t += 1.0;
        assert_eq!(
            ar.test.detail.flag, [0; 3],
            "healthy flagged at {t}: {:?}",
            ar.test.detail.ratio
        );
        max_ratio = max_ratio.max(ar.test.detail.ratio.iter().copied().fold(0.0, f64::max));
    }
    assert!(max_ratio > 0.2 && max_ratio < 1.0, "{max_ratio}");
    let (n_b, s1) = (ar.test.n_b[0], ar.test.s1[0]);
    let step = Vector3::new(2.0, 0.0, 0.0) * DEG;
    let mut found = None;
    for k in 0..40 {
        q = fly(
            &mut ar,
            &cfg,
            q,
            t,
            0.5,
            turning,
            |_| base + step,
            &mut n,
            0.02,
            0.3 * DEG,
        );
        t += 0.5;
        if found.is_none() && ar.test.detail.flag[0] == 1 {
            found = Some(0.5 * (k + 1) as f64);
        }
    }
    let found = found.expect("2 °/s step not flagged in 20 s");
    assert!(found <= 10.0, "{found}");
    assert_eq!(ar.test.detail.flag, [1, 0, 0]);
    assert!(
        (ar.test.detail.estimate[0] - 2.0 * DEG).abs() < 0.5 * DEG,
        "{}",
        ar.test.detail.estimate[0] / DEG
    );
    // Nothing of the fault was learnt (the forgetting alone moved the
    // sums by < 2 %).
    assert!(
        (ar.test.s1[0] / ar.test.n_b[0] - s1 / n_b).abs() < 0.05 * DEG,
        "offset moved"
    );
    let mut cleared = None;
    for k in 0..60 {
        q = fly(
            &mut ar,
            &cfg,
            q,
            t,
            0.5,
            turning,
            |_| base,
            &mut n,
            0.02,
            0.3 * DEG,
        );
        t += 0.5;
        if cleared.is_none() && ar.test.detail.flag == [0; 3] {
            cleared = Some(0.5 * (k + 1) as f64);
        }
        if let Some(c) = cleared {
            assert_eq!(
                ar.test.detail.flag,
                [0; 3],
                "raised again {} s after clearing",
                0.5 * (k + 1) as f64 - c
            );
        }
    }
    let cleared = cleared.expect("never cleared");
    // 2.5 s measured: the 2.5-s window withdraws the longer ones'
    // verdict (9 s without, the 10-s window flushing).
    assert!(cleared <= 5.0, "{cleared}");
    assert!(ar.test.n_b[0] > n_b, "learning did not resume");
    for _ in 0..40 {
        q = fly(
            &mut ar,
            &cfg,
            q,
            t,
            0.5,
            turning,
            |_| base - step.yzx(),
            &mut n,
            0.02,
            0.3 * DEG,
        );
        t += 0.5;
    }
    assert_eq!(ar.test.detail.flag, [0, 0, -1]);
}

/// Learnt at rest (tiny spread), then flying: no window is judged
/// until a longest window of flight has been learnt, so the rest's
/// spread raises no alarm; then judging resumes, calibrated on flight.
#[test]
fn a_spread_learnt_at_rest_does_not_judge_flight() {
    let cfg = AttitudeRateConfig::<f64>::flight();
    let mut ar = AttitudeRate::<f64>::new(cfg.alpha());
    let mut n = Noise(21);
    let still = |_: f64| Vector3::zeros();
    let b = Vector3::new(0.3, -0.2, 0.1) * DEG;
    let mut q = fly(
        &mut ar,
        &cfg,
        UnitQuaternion::identity(),
        0.0,
        40.0,
        still,
        |_| b,
        &mut n,
        0.001,
        0.01 * DEG,
    );
    ar.test.start_judging();
    q = fly(
        &mut ar,
        &cfg,
        q,
        40.0,
        5.0,
        still,
        |_| b,
        &mut n,
        0.001,
        0.01 * DEG,
    );
    assert!(
        ar.test.detail.ratio.iter().all(|r| *r > 0.0),
        "{:?}",
        ar.test.detail.ratio
    );
    // Flight: 20× the gyro noise, 30× the aiding's; its first 10 s
    // (and the 9.5 s before a block is learnt) are not judged.
    let mut judged_at = None;
    for k in 0..60 {
        q = fly(
            &mut ar,
            &cfg,
            q,
            45.0 + 0.5 * k as f64,
            0.5,
            turning,
            |_| b,
            &mut n,
            0.02,
            0.3 * DEG,
        );
        assert_eq!(
            ar.test.detail.flag, [0; 3],
            "{:?} at {k}",
            ar.test.detail.ratio
        );
        if judged_at.is_none() && ar.test.detail.ratio.iter().any(|r| *r > 0.0) {
            judged_at = Some(0.5 * (k + 1) as f64);
        }
    }
    let t = judged_at.expect("flight never judged");
    assert!((19.0..=25.0).contains(&t), "{t}");
}

/// `f32` against `f64` on the same flight: block means within 1e-3
/// °/s, ratios within 1 %.
#[test]
fn f32_agrees_with_f64() {
    let (mut a64, q) = learnt::<f64>(60.0, &mut Noise(5));
    let (mut a32, _) = learnt::<f32>(60.0, &mut Noise(5));
    for a in 0..a64.test.filled {
        let d = a64.test.blocks[a64.test.slot(a).unwrap()]
            - a32.test.blocks[a32.test.slot(a).unwrap()].map(f64::from);
        assert!(d.norm() < 1e-3 * DEG, "{d}");
    }
    let b = Vector3::new(1.5, 0.0, 0.0) * DEG;
    let c64 = AttitudeRateConfig::<f64>::flight();
    let c32 = AttitudeRateConfig::<f32>::flight();
    fly(
        &mut a64,
        &c64,
        q,
        60.0,
        8.0,
        turning,
        |_| b,
        &mut Noise(9),
        0.02,
        0.3 * DEG,
    );
    fly(
        &mut a32,
        &c32,
        q,
        60.0,
        8.0,
        turning,
        |_| b,
        &mut Noise(9),
        0.02,
        0.3 * DEG,
    );
    for (r64, r32) in a64
        .test
        .detail
        .ratio
        .iter()
        .zip(a32.test.detail.ratio.iter())
    {
        assert!(
            (r64 - f64::from(*r32)).abs() < 0.01 * r64.max(0.1),
            "{r64} {r32}"
        );
    }
    assert!(
        a64.test.detail.ratio[0] > 0.5,
        "{:?}",
        a64.test.detail.ratio
    );
}

/// Attitude aiding 0.2 s late (20 periods at 100 Hz) on a turning body
/// with a gyro bias `b`: integrated at that latency the block means are
/// `b` again (within 2 %, as on time); integrated on time they are off by
/// the rate change over the lag, many times `b`.
#[test]
fn late_aiding_integrated_at_its_latency_gives_the_bias() {
    let cfg = AttitudeRateConfig::<f64>::flight();
    let b = Vector3::new(-1.0, 2.0, 0.5) * DEG;
    let limits = ChannelLimits {
        nominal: Vector3::from_element(1.0),
        relevant: Vector3::zeros(),
    };
    let lag = 20;
    let worst = |delay: usize| {
        let mut ar = AttitudeRate::<f64>::new(cfg.alpha());
        let (dt, mut q) = (0.01, UnitQuaternion::identity());
        let mut truth = std::vec::Vec::new();
        for i in 0..2000 {
            let w = turning(i as f64 * dt);
            q *= rotation_exp(&(w * dt));
            truth.push(q);
            let mut imu = ImuVec::<f64>::zeros();
            imu.fixed_rows_mut::<3>(3).copy_from(&(w + b));
            ar.sample_delayed(&imu, dt, true, delay);
            if (i + 1) % 10 == 0 && i >= lag {
                let (r, p, y) = truth[i - lag].euler_angles();
                ar.epoch(&cfg, [r, p, y], &limits, 1.0, false);
            }
        }
        (0..ar.test.filled)
            .map(|a| (ar.test.blocks[ar.test.slot(a).unwrap()] - b).norm())
            .fold(0.0, f64::max)
    };
    let (late, on_time) = (worst(lag), worst(0));
    assert!(late < 0.02 * b.norm(), "{late} vs {}", b.norm());
    assert!(on_time > 5.0 * b.norm(), "{on_time} vs {}", b.norm());
}
