//! The `f64` UKF against an independent numpy implementation
//! (`scripts/golden_ukf.py`) on the same model, inputs and measurements, for
//! both aiding models, including a yaw that wraps through ±π and subsets of
//! measurement channels.
//!
//! Acceptance: every state within 1e-9 of its scale max(|x|, σ), every
//! covariance entry within 1e-9 of σᵢσⱼ, at every one of 1200 steps.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use imu_fdi::filter::{Gate, SigmaParams, Ukf};
use imu_fdi::model::{
    discrete_process_noise, AidingKind, ImuNoisePsd, ImuVec, Mat6, MeasVec, MeasurementModel,
    StateVec, VehicleModel, STATE_ANGLES,
};
use nalgebra::Vector3;

fn check(file: &str, kind: AidingKind) {
    let text = std::fs::read_to_string(format!("{}/tests/data/{file}", env!("CARGO_MANIFEST_DIR")))
        .unwrap();
    let mut lines = text.lines();
    let meta: Vec<f64> = lines
        .next()
        .unwrap()
        .trim_start_matches("# ")
        .split(' ')
        .map(|v| v.parse().unwrap())
        .collect();
    let psd = ImuVec::from_column_slice(&meta[0..6]);
    let sig = MeasVec::from_column_slice(&meta[6..12]);
    let x0 = StateVec::from_column_slice(&meta[12..18]);
    let s0 = StateVec::from_column_slice(&meta[18..24]);
    let _header = lines.next().unwrap();
    let model = VehicleModel::<f64>::default();
    let meas = MeasurementModel::<f64>::new(kind);
    let noise = ImuNoisePsd { psd };
    let mut ukf = Ukf::<f64, 6, 13>::new(
        x0,
        Mat6::from_diagonal(&s0.component_mul(&s0)),
        &SigmaParams::default(),
        STATE_ANGLES,
    )
    .unwrap();
    let r = sig.component_mul(&sig);
    let angles = [false, false, false, true, true, true];
    let mut gate = Gate::<f64, 6>::new(0.0, 0);
    let (mut worst_x, mut worst_p) = (0.0f64, 0.0f64);
    let mut rows = 0;
    for line in lines {
        let v: Vec<f64> = line
            .split(',')
            .map(|s| {
                if s.is_empty() {
                    f64::NAN
                } else {
                    s.parse().unwrap()
                }
            })
            .collect();
        let dt = v[1];
        let u = ImuVec::from_column_slice(&v[2..8]);
        let z = MeasVec::from_fn(|i, _| if v[8 + i].is_nan() { 0.0 } else { v[8 + i] });
        let avail: [bool; 6] = core::array::from_fn(|i| v[14 + i] > 0.5);
        let x_prior = *ukf.state();
        let q = discrete_process_noise(&model, &x_prior, &u, &noise, dt).unwrap();
        ukf.predict(|s| model.step(s, &u, dt), &q).unwrap();
        if avail.iter().any(|a| *a) {
            ukf.update(
                &z,
                &avail,
                |s| Ok::<_, ()>(meas.predict(s, &Vector3::zeros())),
                &r,
                &angles,
                &mut gate,
            )
            .unwrap();
        }
        let x_ref = StateVec::from_column_slice(&v[20..26]);
        let mut p_ref = Mat6::zeros();
        let mut k = 26;
        for i in 0..6 {
            for j in i..6 {
                p_ref[(i, j)] = v[k];
                p_ref[(j, i)] = v[k];
                k += 1;
            }
        }
        let p = ukf.covariance();
        for i in 0..6 {
            let sigma_i = p_ref[(i, i)].sqrt();
            let mut dx = ukf.state()[i] - x_ref[i];
            if i >= 3 {
                dx = imu_fdi::math::wrap_pi_f64(dx);
            }
            worst_x = worst_x.max(dx.abs() / x_ref[i].abs().max(sigma_i));
            for j in 0..6 {
                let scale = sigma_i * p_ref[(j, j)].sqrt();
                worst_p = worst_p.max((p[(i, j)] - p_ref[(i, j)]).abs() / scale);
            }
        }
        rows += 1;
    }
    println!("{file}: {rows} steps, worst state error {worst_x:.2e} of scale, worst covariance error {worst_p:.2e} of σiσj");
    assert_eq!(rows, 1200);
    assert!(worst_x < 1e-9, "state disagreement {worst_x:e}");
    assert!(worst_p < 1e-9, "covariance disagreement {worst_p:e}");
}

#[test]
fn ukf_f64_matches_numpy_reference_dvl_compass() {
    check("golden_ukf_m1.csv", AidingKind::DvlCompass);
}

#[test]
fn ukf_f64_matches_numpy_reference_gnss_attitude() {
    check("golden_ukf_m2.csv", AidingKind::GnssAttitude);
}
