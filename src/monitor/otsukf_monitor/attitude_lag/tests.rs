#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
use super::*;

/// A vehicle rocking in roll, pitch and yaw at different frequencies
/// (rad, `t` in s): its rates change, so a lag shows in the changes.
fn attitude(t: f64) -> Vector3<f64> {
    Vector3::new(
        0.4 * (1.3 * t).sin(),
        0.2 * (0.7 * t + 0.5).sin(),
        wrap_pi(0.3 * t + 0.8 * (0.4 * t).sin()),
    )
}

/// 100 Hz IMU, 10 Hz attitude aiding `true_lag` periods late with a
/// deterministic ±`noise` rad error; the ring's changes carry a constant
/// gyro bias of 0.01 rad/s, which the spread must ignore. Returns the lag
/// estimate after `seconds`.
fn run(true_lag: usize, noise: f64, seconds: usize) -> AttitudeLag<f64> {
    let dt = 0.01;
    let sigma = Vector3::from_element(0.01);
    let mut lag = AttitudeLag::<f64>::new(0);
    let mut seed = 12345_u64;
    for k in 1..=seconds * 100 {
        let t = k as f64 * dt;
        let d = (attitude(t) - attitude(t - dt)).map(wrap_pi) + Vector3::from_element(0.01 * dt);
        lag.push(d);
        if k % 10 == 0 {
            let mut e = Vector3::zeros();
            for v in e.iter_mut() {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *v = noise * (((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0);
            }
            let late = attitude(t - true_lag as f64 * dt) + e;
            lag.observe(late.map(wrap_pi), &sigma);
        }
    }
    lag
}

#[test]
fn a_known_lag_is_recovered_from_the_changes() {
    for true_lag in [0, 7, 20, 30] {
        // Noise-free: the true lag's mismatches are the bias alone, a
        // constant with zero spread.
        assert_eq!(run(true_lag, 0.0, 20).steps, true_lag, "lag {true_lag}");
        // With ±0.3° of aiding error, within a period after a minute.
        let est = run(true_lag, 0.005, 60).steps;
        assert!(est.abs_diff(true_lag) <= 1, "lag {true_lag}: {est}");
    }
}

#[test]
fn no_estimate_before_three_blocks_and_the_late_attitude_is_brought_to_now() {
    // 5.9 s: two full blocks (the first epoch only sets the reference).
    assert_eq!(run(20, 0.0, 5).steps, 0);
    let lag = run(20, 0.0, 10);
    assert_eq!(lag.steps, 20);
    // At 10 s the aiding describes 9.8 s; the ring's last 20 changes
    // bring it to 10 s (plus the bias's 0.2 s × 0.01 rad/s).
    let now = attitude(10.0 - 0.2) + lag.over(0, 20).unwrap();
    let err = (now - attitude(10.0)).map(wrap_pi) - Vector3::from_element(0.002);
    assert!(err.norm() < 1e-9, "{err}");
    assert_eq!(lag.over(LAG_RING - 19, 20), None);
}
