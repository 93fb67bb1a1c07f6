//! On a linear model the unscented transform is exact, so the UKF must equal
//! the closed-form Kalman filter (for any sigma-point parameters).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use imu_fdi::filter::{Gate, SigmaParams, Ukf};
use nalgebra::{SMatrix, SVector};
use rand::{Rng, SeedableRng};

type V4 = SVector<f64, 4>;
type M4 = SMatrix<f64, 4, 4>;
type V2 = SVector<f64, 2>;

#[test]
fn ukf_equals_kalman_filter_on_a_linear_system() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let dt = 0.1;
    // Constant-velocity model in 2-D, position measured.
    let f = M4::new(
        1.0, 0.0, dt, 0.0, 0.0, 1.0, 0.0, dt, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    );
    let h = SMatrix::<f64, 2, 4>::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
    let q = M4::from_diagonal(&V4::new(1e-4, 1e-4, 1e-2, 1e-2));
    let r = V2::new(0.25, 0.09);
    let x0 = V4::new(1.0, -2.0, 0.5, 0.3);
    let p0 = M4::from_diagonal(&V4::new(4.0, 4.0, 1.0, 1.0));
    for params in [
        SigmaParams::default(),
        SigmaParams {
            alpha: 0.5,
            beta: 2.0,
            kappa: 1.0,
        },
    ] {
        let mut ukf = Ukf::<f64, 4, 9>::new(x0, p0, &params, [false; 4]).unwrap();
        ukf.set_min_variance(V4::zeros());
        let (mut x, mut p) = (x0, p0);
        let mut gate = Gate::<f64, 2>::new(0.0, 0);
        let mut worst = 0.0f64;
        for k in 0..2000 {
            ukf.predict(|s| Ok::<_, ()>(f * s), &q).unwrap();
            x = f * x;
            p = f * p * f.transpose() + q;
            if k % 3 == 0 {
                let z = V2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0));
                let avail = [true, k % 9 != 0];
                ukf.update(
                    &z,
                    &avail,
                    |s| Ok::<_, ()>(h * s),
                    &r,
                    &[false; 2],
                    &mut gate,
                )
                .unwrap();
                // Closed form on the available rows.
                if avail[1] {
                    let s = h * p * h.transpose() + SMatrix::<f64, 2, 2>::from_diagonal(&r);
                    let kg = p * h.transpose() * s.try_inverse().unwrap();
                    x += kg * (z - h * x);
                    p -= kg * h * p;
                } else {
                    let h0 = h.row(0);
                    let s = (h0 * p * h0.transpose())[(0, 0)] + r[0];
                    let kg = p * h0.transpose() / s;
                    x += kg * (z[0] - (h0 * x)[(0, 0)]);
                    p -= kg * h0 * p;
                }
            }
            worst = worst
                .max((ukf.state() - x).amax())
                .max((ukf.covariance() - p).amax());
        }
        println!("α = {}: worst |UKF − KF| = {worst:.2e}", params.alpha);
        assert!(worst < 1e-9, "UKF differs from KF by {worst:e}");
    }
}

/// The closed-form update for an affine measurement (used for M1) equals the
/// sigma-point update to rounding — with angle channels straddling ±π,
/// channels missing, the gate rejecting a spike, and a delayed centre.
#[test]
fn affine_update_equals_the_sigma_point_update() {
    use imu_fdi::model::{AidingKind, MeasVec, MeasurementModel, StateVec, STATE_ANGLES};
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let mut meas = MeasurementModel::<f64>::new(AidingKind::DvlCompass);
    meas.lever_arm = nalgebra::Vector3::new(0.4, -0.1, 0.3);
    let angles = [false, false, false, true, true, true];
    let r = MeasVec::<f64>::new(1e-4, 1e-4, 4e-4, 1e-6, 1e-6, 4e-6);
    let mut worst = 0.0f64;
    for trial in 0..200 {
        let x = StateVec::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-0.3..0.3),
            rng.random_range(-0.3..0.3),
            if trial % 2 == 0 {
                3.139
            } else {
                rng.random_range(-3.1..3.1)
            },
        );
        let a = SMatrix::<f64, 6, 6>::from_fn(|_, _| rng.random_range(-0.02..0.02));
        let p = a * a.transpose() + SMatrix::<f64, 6, 6>::from_diagonal_element(1e-5);
        let omega = nalgebra::Vector3::new(0.1, -0.2, 0.05);
        let delayed = if trial % 3 == 0 {
            x + StateVec::new(0.01, 0.0, -0.01, 0.001, 0.0, 0.002)
        } else {
            x
        };
        let mut z = meas.predict(&x, &omega)
            + MeasVec::from_fn(|i, _| rng.random_range(-1.0..1.0_f64) * r[i].sqrt() * 2.0);
        z[5] = imu_fdi::math::wrap_pi(z[5]);
        if trial % 5 == 0 {
            z[1] += 1.0; // a spike the gate must reject in both forms
        }
        let available = [true, trial % 4 != 0, true, true, trial % 7 != 0, true];
        let mut sigma =
            Ukf::<f64, 6, 13>::new(x, p, &SigmaParams::default(), STATE_ANGLES).unwrap();
        let mut affine = sigma.clone();
        let (mut g1, mut g2) = (Gate::<f64, 6>::new(8.0, 2), Gate::<f64, 6>::new(8.0, 2));
        let o1 = sigma
            .update_delayed(
                &delayed,
                &z,
                &available,
                |s| Ok::<_, ()>(meas.predict(s, &omega)),
                &r,
                &angles,
                &mut g1,
            )
            .unwrap();
        let h = meas.jacobian(&x, &omega);
        let o2 = affine
            .update_affine(
                &meas.predict(&delayed, &omega),
                &h,
                &z,
                &available,
                &r,
                &angles,
                &mut g2,
            )
            .unwrap();
        for (d1, d2) in o1.diag.iter().zip(o2.diag.iter()) {
            assert_eq!(d1.fused, d2.fused);
            assert_eq!(d1.available, d2.available);
            worst = worst.max((d1.innovation - d2.innovation).abs() / d1.variance.sqrt());
        }
        let dx = sigma.state() - affine.state();
        let dx = dx.map(imu_fdi::math::wrap_pi_f64);
        worst = worst.max(dx.amax() / p.diagonal().amax().sqrt());
        worst = worst.max((sigma.covariance() - affine.covariance()).amax() / p.amax());
    }
    println!("affine vs sigma-point update: largest relative difference {worst:e}");
    assert!(worst < 1e-9, "largest relative difference {worst:e}");
}
