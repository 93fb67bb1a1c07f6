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
