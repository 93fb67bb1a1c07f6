//! SPEC §6 acceptance test of the optimal two-stage UKF: on a linear
//! time-varying system with a random-walk input bias it equals the 12-state
//! augmented Kalman filter (state `[x; f]`) to round-off.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use imu_fdi::filter::{Gate, Otsukf, SigmaParams};
use nalgebra::{SMatrix, SVector};
use rand::{Rng, SeedableRng};

type M6 = SMatrix<f64, 6, 6>;
type V6 = SVector<f64, 6>;
type M12 = SMatrix<f64, 12, 12>;
type V12 = SVector<f64, 12>;

fn rel(a: f64, scale: f64) -> f64 {
    a / scale.max(1e-300)
}

#[test]
fn two_stage_equals_the_augmented_kalman_filter() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(27);
    let mut uniform = |a: f64| rng.random_range(-a..a);
    let dt = 0.01;
    let qx = M6::from_diagonal(&V6::new(1e-4, 1e-4, 1e-4, 3e-8, 3e-8, 3e-8)) * dt;
    let qf = M6::from_diagonal(&V6::new(1e-4, 1e-4, 1e-4, 3e-8, 3e-8, 3e-8)) * dt;
    let r = V6::new(1e-4, 1e-4, 1e-4, 3e-8, 3e-8, 3e-8);
    let x0 = V6::new(20.0, 1.0, -0.5, 0.1, 0.05, 1.0);
    // A prior not orders of magnitude wider than R: the first update must
    // not cancel away the digits both filters are compared on.
    let px0 = M6::from_diagonal(&V6::new(1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 1e-6));
    let pf0 = M6::identity();
    let mut ts = Otsukf::<f64, 6, 13, 6>::new(
        x0,
        px0,
        V6::zeros(),
        pf0,
        qf,
        &SigmaParams::default(),
        [false; 6],
    )
    .unwrap();
    ts.set_min_variance(V6::zeros());
    let mut xa = V12::zeros();
    xa.fixed_rows_mut::<6>(0).copy_from(&x0);
    let mut pa = M12::zeros();
    pa.fixed_view_mut::<6, 6>(0, 0).copy_from(&px0);
    pa.fixed_view_mut::<6, 6>(6, 6).copy_from(&pf0);
    let mut qa = M12::zeros();
    qa.fixed_view_mut::<6, 6>(0, 0).copy_from(&qx);
    qa.fixed_view_mut::<6, 6>(6, 6).copy_from(&qf);
    // A 1σ gate that never rejects (no rejections allowed): every channel
    // is fused and its test ratio ν²/σ² is reported, to compare with the
    // augmented filter's normalised innovation.
    let mut gate = Gate::<f64, 6>::new(1.0, 0);
    let mut worst_gate = 0.0f64;
    let (mut worst_x, mut worst_f, mut worst_px, mut worst_pf) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let truth_f = V6::new(0.3, -0.1, 0.2, 0.01, -0.02, 0.005);
    let mut truth = x0;
    for k in 0..10_000 {
        // Time-varying, vehicle-like matrices: Φ near identity, F ≈ −B dt.
        let t = k as f64 * dt;
        // Vehicle structure: velocity rotated by a body rate (skew block),
        // tilted gravity into velocity, attitude driven only by attitude.
        let w = [
            0.2 * (0.1 * t).sin(),
            0.1 * (0.07 * t).cos(),
            0.3 * (0.05 * t).sin(),
        ];
        let a = M6::from_fn(|i, j| match (i < 3, j < 3) {
            (true, true) => {
                let skew = [[0.0, w[2], -w[1]], [-w[2], 0.0, w[0]], [w[1], -w[0], 0.0]];
                skew[i][j]
            }
            (true, false) => 9.8 * (0.3 * (t + (i + j) as f64)).sin(),
            (false, true) => 0.0,
            (false, false) => 0.05 * (0.1 * t + (i * 6 + j) as f64).cos(),
        });
        let phi = M6::identity() + a * dt;
        let b = M6::from_fn(|i, j| {
            if i == j {
                1.0
            } else {
                0.1 * ((i + 2 * j) as f64 + t).sin()
            }
        });
        let fmat = -b * dt;
        let input = V6::from_fn(|i, _| (0.5 * t + i as f64).sin()) * dt;
        truth = phi * truth + fmat * truth_f + input;
        // Two-stage.
        let f_hat = *ts.fault();
        ts.predict(
            |s| Ok::<_, ()>(phi * s + fmat * f_hat + input),
            &phi,
            &fmat,
            &qx,
        )
        .unwrap();
        // Augmented KF.
        let mut phia = M12::identity();
        phia.fixed_view_mut::<6, 6>(0, 0).copy_from(&phi);
        phia.fixed_view_mut::<6, 6>(0, 6).copy_from(&fmat);
        let mut ina = V12::zeros();
        ina.fixed_rows_mut::<6>(0).copy_from(&input);
        xa = phia * xa + ina;
        pa = phia * pa * phia.transpose() + qa;
        if k % 10 == 9 {
            let h = M6::from_fn(|i, j| {
                if i == j {
                    1.0
                } else {
                    0.05 * ((i * j) as f64 + t).cos()
                }
            });
            let z = h * truth + V6::from_fn(|i, _| uniform(1.0) * r[i].sqrt());
            let avail = [true, true, k % 30 != 9, true, true, true];
            let out = ts
                .update(
                    &z,
                    &avail,
                    |s| Ok::<_, ()>(h * s),
                    &h,
                    &r,
                    &[false; 6],
                    &mut gate,
                )
                .unwrap();
            // Augmented update; a missing channel is a zero row of H with
            // unit noise and zero measurement (no information).
            let mut ha = SMatrix::<f64, 6, 12>::zeros();
            let mut zz = V6::zeros();
            let mut rr = M6::identity();
            for i in 0..6 {
                if avail[i] {
                    for j in 0..6 {
                        ha[(i, j)] = h[(i, j)];
                    }
                    zz[i] = z[i];
                    rr[(i, i)] = r[i];
                }
            }
            let s = ha * pa * ha.transpose() + rr;
            let kgain = pa * ha.transpose() * s.try_inverse().unwrap();
            let innovation = zz - ha * xa;
            // The gate tests what the augmented filter would: its innovation
            // against its innovation variance.
            for i in 0..6 {
                if avail[i] {
                    let want = innovation[i] * innovation[i] / s[(i, i)];
                    let got = out.bias_free.diag[i].test_ratio;
                    worst_gate = worst_gate.max(rel((got - want).abs(), want.max(1e-3)));
                }
            }
            xa += kgain * innovation;
            pa -= kgain * s * kgain.transpose();
            pa = (pa + pa.transpose()) * 0.5;
        }
        let x = ts.state();
        let px = ts.state_covariance();
        let pf = ts.fault_covariance();
        worst_x = worst_x.max(rel(
            (x - xa.fixed_rows::<6>(0)).amax(),
            xa.fixed_rows::<6>(0).amax(),
        ));
        worst_f = worst_f.max(rel(
            (ts.fault() - xa.fixed_rows::<6>(6)).amax(),
            xa.fixed_rows::<6>(6)
                .amax()
                .max(pf.diagonal().amax().sqrt()),
        ));
        let pxa = pa.fixed_view::<6, 6>(0, 0);
        let pfa = pa.fixed_view::<6, 6>(6, 6);
        worst_px = worst_px.max(rel((px - pxa).amax(), pxa.amax()));
        worst_pf = worst_pf.max(rel((pf - pfa).amax(), pfa.amax()));
    }
    println!(
        "two-stage vs augmented KF over 10^4 steps: state {worst_x:.2e}, fault {worst_f:.2e}, P^x {worst_px:.2e}, P^f {worst_pf:.2e}, gate ratio {worst_gate:.2e} (relative)"
    );
    assert!(worst_x < 1e-9 && worst_f < 1e-9 && worst_px < 1e-9 && worst_pf < 1e-9);
    assert!(worst_gate < 1e-6, "{worst_gate}");
    // And the fault is actually estimated.
    assert!((ts.fault() - truth_f).amax() < 0.05, "{:?}", ts.fault());
}
