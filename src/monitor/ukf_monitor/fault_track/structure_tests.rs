//! The tracker's structured kernels (Φ on its nonzero blocks, the rolled
//! products) against the plain nalgebra computation.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code
use super::*;
use crate::model::VehicleModel;

/// A state Jacobian of the model's form `[[Ω, G, 0], [0, L, 0]]`.
fn jacobian(seed: f64) -> Mat6<f64> {
    let v = |k: f64| (seed * 1.7 + k * 0.37).sin();
    let (w0, w1, w2) = (v(1.0), v(2.0), v(3.0));
    let mut a = Mat6::zeros();
    a[(2, 1)] = w0;
    a[(1, 2)] = -w0;
    a[(0, 2)] = w1;
    a[(2, 0)] = -w1;
    a[(1, 0)] = w2;
    a[(0, 1)] = -w2;
    for r in 0..6 {
        for c in 3..5 {
            a[(r, c)] = 9.8 * v(10.0 + (r * 2 + c) as f64);
        }
    }
    a
}

/// `advance` gives bit for bit the transition of the full product
/// `Φ += A Φ dt` (`VehicleModel::mul_state_jacobian`) over many steps.
#[test]
fn advance_equals_the_full_product() {
    let mut tr = FaultTracker::<f64>::new();
    let mut phi = Mat6::<f64>::identity();
    for k in 0..500 {
        let a = jacobian(k as f64);
        phi += VehicleModel::mul_state_jacobian(&a, &phi) * 0.01;
        tr.advance(&a, 0.01);
    }
    assert_eq!(tr.phi, phi);
    assert!((tr.elapsed - 5.0).abs() < 1e-9);
    // And the transition is far from the identity (the test can fail).
    assert!((phi - Mat6::identity()).abs().max() > 0.5);
}

/// `observe_state(i)` is `observe` with the row `eᵢ`, and `mul_acc`
/// the plain products.
#[test]
fn unit_row_and_kernel_equal_the_general_forms() {
    let mut tr = FaultTracker::<f64>::new();
    tr.start(
        &ImuVec::new(0.2, 0.2, 0.2, 0.02, 0.02, 0.02),
        &Mat6::zeros(),
    );
    tr.phi = Mat6::identity() + jacobian(3.0) * 0.05;
    tr.elapsed = 0.1;
    tr.propagate(
        &Mat6::from_fn(|i, j| 0.1 * (i as f64 - j as f64 + 0.5)),
        &ImuVec::repeat(0.05),
    );
    let mut general = tr.clone();
    for i in 0..6 {
        let r = 0.3 * i as f64 - 0.7;
        tr.observe_state(i, r, 0.01, 8.0);
        let h = StateVec::from_fn(|k, _| if k == i { 1.0 } else { 0.0 });
        general.observe(&h, r, 0.01, 8.0);
    }
    let (f, sd) = tr.estimate();
    let (fg, sdg) = general.estimate();
    assert!((f - fg).abs().max() < 1e-12 && (sd - sdg).abs().max() < 1e-12);
    assert!(f.abs().max() > 1e-3, "the estimate moved: {f}");
    let a = jacobian(1.0);
    let b = jacobian(2.0) + Mat6::identity();
    let mut out = Mat6::identity();
    mul_acc(out.as_mut_slice(), &a, b.as_slice(), false, 2.0);
    assert!((out - (Mat6::identity() + a * b * 2.0)).abs().max() < 1e-12);
    let mut out = Mat6::zeros();
    mul_acc(out.as_mut_slice(), &a, b.as_slice(), true, -1.0);
    assert!((out + a * b.transpose()).abs().max() < 1e-12);
}
