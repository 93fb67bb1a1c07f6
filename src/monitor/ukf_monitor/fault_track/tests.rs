//! The tracker against the 12-state augmented Kalman filter on linear
//! systems, and its numerical guards.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
use super::*;
use nalgebra::{SMatrix, SVector};

type M12 = SMatrix<f64, 12, 12>;
type V12 = SVector<f64, 12>;

/// Deterministic N(0, 1)-ish samples (sum of 12 uniforms − 6).
struct Noise(u64);
impl Noise {
    fn next(&mut self) -> f64 {
        let mut s = 0.0;
        for _ in 0..12 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            s += (self.0 >> 11) as f64 / (1u64 << 53) as f64;
        }
        s - 6.0
    }
}

/// On a linear system with one scalar measurement per epoch the tracker
/// run beside a filter that ignores the fault gives exactly the fault
/// estimate and covariance of the 12-state augmented Kalman filter: the
/// fault-free filter's innovations are white and independent of the
/// fault, and the innovations actually seen are those plus `−H e⁻`,
/// with `e` the state deviation the fault history has caused. The fault
/// is a random walk with the tracker's spectral density plus a step and
/// a ramp, whatever its shape.
#[test]
fn equals_the_augmented_kalman_filter_on_a_linear_system() {
    let dt = 0.1;
    // Coupled dynamics (a rotation-like block and a gravity-like one).
    let a = Mat6::<f64>::from_fn(|i, j| match (i, j) {
        (0, 1) => 0.3,
        (1, 0) => -0.3,
        (0, 4) => -9.8,
        (1, 3) => 9.8,
        (2, 2) => -0.05,
        (3, 4) => 0.1,
        (4, 3) => -0.1,
        (5, 5) => -0.02,
        _ => 0.0,
    });
    let phi = Mat6::identity() + a * dt + a * a * (dt * dt * 0.5);
    let gamma = Mat6::<f64>::identity() * dt;
    let q = Mat6::from_diagonal(&ImuVec::new(1e-4, 1e-4, 1e-4, 1e-7, 1e-7, 1e-7));
    let r = [
        0.05f64.powi(2),
        0.05f64.powi(2),
        0.05f64.powi(2),
        3e-6,
        3e-6,
        5e-6,
    ];
    let psd = ImuVec::new(0.05, 0.05, 0.05, 8e-5, 8e-5, 8e-5);
    let sigma0 = ImuVec::new(0.2, 0.2, 0.2, 0.02, 0.02, 0.02);
    let p0 = Mat6::from_diagonal(&ImuVec::new(0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3));

    // The augmented filter on (x, f): x' = Φx + Γ(u − f) + w, f' = f + η.
    let mut fa = M12::identity();
    fa.fixed_view_mut::<6, 6>(0, 0).copy_from(&phi);
    fa.fixed_view_mut::<6, 6>(0, 6).copy_from(&(-gamma));
    let mut qa = M12::zeros();
    qa.fixed_view_mut::<6, 6>(0, 0).copy_from(&q);
    for i in 0..6 {
        qa[(6 + i, 6 + i)] = psd[i] * dt;
    }
    let mut xa = V12::zeros();
    let mut pa = M12::zeros();
    pa.fixed_view_mut::<6, 6>(0, 0).copy_from(&p0);
    for i in 0..6 {
        pa[(6 + i, 6 + i)] = sigma0[i] * sigma0[i];
    }
    // The fault-free filter, its sensitivity X, and the tracker.
    let (mut xb, mut pb, mut xs) = (StateVec::<f64>::zeros(), p0, Mat6::<f64>::zeros());
    let mut tr = FaultTracker::<f64>::new();
    tr.start(&sigma0, &xs);

    let mut noise = Noise(7);
    let mut x = StateVec::<f64>::zeros();
    let mut worst_f = 0.0f64;
    let mut worst_p = 0.0f64;
    for k in 0..600 {
        let t = k as f64 * dt;
        let u = ImuVec::new(0.3 * (0.2 * t).sin(), 0.1, 0.0, 0.01, -0.02, 0.0);
        let mut f = ImuVec::zeros();
        if t > 10.0 {
            f[0] = 0.5;
            f[4] = 0.03;
        }
        if t > 20.0 {
            f[2] = 0.05 * (t - 20.0);
            f[3] = -0.002 * (t - 20.0);
        }
        let w = ImuVec::from_fn(|i, _| q[(i, i)].sqrt() * noise.next());
        x = phi * x + gamma * u + w;
        let um = u + f;
        // Predict both filters.
        let mut ua = V12::zeros();
        ua.fixed_rows_mut::<6>(0).copy_from(&(gamma * um));
        xa = fa * xa + ua;
        pa = fa * pa * fa.transpose() + qa;
        xb = phi * xb + gamma * um;
        pb = phi * pb * phi.transpose() + q;
        xs = phi * xs + gamma;
        tr.phi = phi;
        tr.elapsed = dt;
        tr.propagate(&xs, &psd);
        // One scalar measurement, cycling through the channels.
        let i = k % 6;
        let h = nalgebra::RowSVector::<f64, 6>::from_fn(|_, j| if j == i { 1.0 } else { 0.0 });
        let hc = h.transpose();
        let z = x[i] + r[i].sqrt() * noise.next();
        // Augmented update.
        let mut ha = nalgebra::RowSVector::<f64, 12>::zeros();
        ha[i] = 1.0;
        let sa = (ha * pa * ha.transpose())[(0, 0)] + r[i];
        let ka = pa * ha.transpose() / sa;
        xa += ka * (z - (ha * xa)[(0, 0)]);
        pa -= ka * ha * pa;
        // Fault-free filter's update; the tracker sees its innovation.
        let s = (h * pb * h.transpose())[(0, 0)] + r[i];
        let kb = pb * h.transpose() / s;
        let innov = z - (h * xb)[(0, 0)];
        tr.observe(&hc, innov, s, 8.0);
        xb += kb * innov;
        let tm = Mat6::identity() - kb * h;
        pb = tm * pb;
        xs = tm * xs;
        tr.filter_update(&tm, &xs);
        let (fh, sd) = tr.estimate();
        for c in 0..6 {
            let scale = sigma0[c];
            worst_f = worst_f.max((fh[c] - xa[6 + c]).abs() / scale);
            let sa = pa[(6 + c, 6 + c)].sqrt();
            worst_p = worst_p.max((sd[c] - sa).abs() / sa);
        }
    }
    // Equal to rounding (relative to the fault scale / the σ).
    assert!(worst_f < 1e-8, "estimate differs by {worst_f} σ0");
    assert!(worst_p < 1e-8, "σ differs by {worst_p} relative");
    // And it found the faults.
    let (fh, _) = tr.estimate();
    assert!((fh[0] - 0.5).abs() < 0.1, "{fh}");
    // An aiding outlier (100 m/s off) moves nothing.
    let before = tr.clone();
    tr.observe(
        &StateVec::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        100.0,
        r[0],
        8.0,
    );
    assert_eq!(tr.estimate(), before.estimate());
    // A non-finite input restarts the estimate instead of poisoning it.
    tr.observe(
        &StateVec::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        0.0,
        f64::NAN,
        8.0,
    );
    tr.filter_update(&Mat6::identity(), &Mat6::from_element(f64::NAN));
    tr.filter_update(&Mat6::identity(), &Mat6::zeros());
    assert!(tr.estimate().0.iter().all(|v| v.is_finite()));
}
