//! The split unscented transforms (issue 17) against the plain ones, in
//! `f64`: `Ukf::predict_split` with the vehicle model and `Ukf::update_split`
//! with M2 aiding (GNSS velocity + attitude, affine in the body velocity)
//! agree with `predict` / `update` in the mean and covariance to far below
//! the filter's own spread. They differ only in the fourth moments of the
//! nonlinear states (another square root of `P`), so the bound is relative
//! to `σ`, not to rounding.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code: a panic is a failed assertion

use imu_fdi::filter::{Gate, SigmaParams, Ukf};
use imu_fdi::model::{
    AidingKind, ImuVec, Mat6, MeasVec, MeasurementModel, StateVec, VehicleModel, STATE_ANGLES,
};
use nalgebra::Vector3;

const MEAS_ANGLES: [bool; 6] = [false, false, false, true, true, true];

fn start() -> (StateVec<f64>, Mat6<f64>) {
    let x = StateVec::new(18.0, 0.4, -0.3, 0.2, -0.1, 2.9);
    // A correlated covariance: σ 0.3 m/s, 0.02 rad, cross terms 0.3.
    let s = StateVec::new(0.3, 0.3, 0.3, 0.02, 0.02, 0.02);
    let p = Mat6::from_fn(|i, j| s[i] * s[j] * if i == j { 1.0 } else { 0.3 });
    (x, p)
}

/// Largest state difference in units of the filter's σ, and the largest
/// covariance difference relative to the largest variance.
fn gaps(a: &Ukf<f64, 6, 13>, b: &Ukf<f64, 6, 13>) -> (f64, f64) {
    let p = a.covariance();
    let dx = (0..6)
        .map(|i| (a.state()[i] - b.state()[i]).abs() / p[(i, i)].sqrt())
        .fold(0.0, f64::max);
    let dp = (p - b.covariance()).amax() / p.diagonal().amax();
    (dx, dp)
}

#[test]
fn split_update_matches_the_plain_update_for_m2() {
    let meas = MeasurementModel::<f64>::new(AidingKind::GnssAttitude);
    let omega = Vector3::new(0.1, -0.05, 0.3);
    let (x, p) = start();
    let z = meas.predict(
        &(x + StateVec::new(0.2, -0.1, 0.05, 0.01, -0.01, 0.02)),
        &omega,
    );
    let r = MeasVec::new(0.04, 0.04, 0.04, 1e-4, 1e-4, 1e-4);
    let params = SigmaParams::default();
    let mut plain = Ukf::<f64, 6, 13>::new(x, p, &params, STATE_ANGLES).unwrap();
    let mut split = plain.clone();
    let (mut g1, mut g2) = (Gate::new(0.0, 0), Gate::new(0.0, 0));
    let h = |s: &StateVec<f64>| Ok::<_, ()>(meas.predict(s, &omega));
    let a = plain
        .update(&z, &[true; 6], h, &r, &MEAS_ANGLES, &mut g1)
        .unwrap();
    let (order, nonlinear) = meas.split();
    let b = split
        .update_split(
            &x,
            &order,
            nonlinear,
            &z,
            &[true; 6],
            h,
            &meas.jacobian(&x, &omega),
            &r,
            &MEAS_ANGLES,
            &mut g2,
        )
        .unwrap();
    let (dx, dp) = gaps(&plain, &split);
    assert!(dx < 1e-3 && dp < 1e-3, "state {dx:e} σ, covariance {dp:e}");
    // It moved the state: the comparison is not of two untouched filters.
    assert!((plain.state() - x).amax() > 0.05);
    for (da, db) in a.diag.iter().zip(b.diag.iter()) {
        assert!((da.innovation - db.innovation).abs() < 1e-3 * da.variance.sqrt());
        assert!((da.variance - db.variance).abs() < 1e-3 * da.variance);
    }
}

#[test]
fn split_predict_matches_the_plain_predict() {
    let m = VehicleModel::<f64>::default();
    let u = ImuVec::new(0.5, -0.2, -9.5, 0.6, -0.8, 1.1);
    let (x, p) = start();
    let q = Mat6::from_diagonal_element(1e-6);
    let params = SigmaParams::default();
    let mut plain = Ukf::<f64, 6, 13>::new(x, p, &params, STATE_ANGLES).unwrap();
    let mut split = plain.clone();
    let mut near = plain.clone();
    plain.predict(|s| m.step(s, &u, 0.01), &q).unwrap();
    split
        .predict_split(
            &VehicleModel::<f64>::SPLIT_ORDER,
            VehicleModel::<f64>::NONLINEAR_STATES,
            |s| m.step(s, &u, 0.01),
            |d| m.step_deviation(d, &u, 0.01),
            &q,
        )
        .unwrap();
    // The monitor's form: sigma-point trigonometry shifted from the mean's.
    let t = m.attitude_trig(&x).unwrap();
    near.predict_split(
        &VehicleModel::<f64>::SPLIT_ORDER,
        VehicleModel::<f64>::NONLINEAR_STATES,
        |s| m.step_near(s, &x, &t, &u, 0.01),
        |d| m.step_deviation(d, &u, 0.01),
        &q,
    )
    .unwrap();
    let (dx, dp) = gaps(&plain, &split);
    assert!(dx < 1e-3 && dp < 1e-3, "state {dx:e} σ, covariance {dp:e}");
    let (dx, dp) = gaps(&split, &near);
    assert!(
        dx < 1e-9 && dp < 1e-9,
        "step_near: state {dx:e} σ, covariance {dp:e}"
    );
}
