//! The on-target Student-t quantile against scipy (`scripts/student_t_reference.py`)
//! over SPEC §5's range, on a grid and at random off-grid (n, α) pairs, and the
//! round trip through the t CDF.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use imu_fdi::stats::{student_t_upper_quantile, student_t_upper_tail};

#[test]
fn quantile_matches_scipy_to_1e_4_relative() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/student_t_ppf.csv"
    ))
    .unwrap();
    let mut worst = 0.0f64;
    let mut n = 0;
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
        let (nu, alpha, t_ref) = (v[0], v[1], v[2]);
        let t = student_t_upper_quantile(alpha, nu).unwrap();
        let rel = (t / t_ref - 1.0).abs();
        worst = worst.max(rel);
        assert!(rel < 1e-4, "nu={nu} alpha={alpha}: {t} vs scipy {t_ref}");
        n += 1;
    }
    println!("{n} pairs, worst relative error vs scipy {worst:.2e}");
    assert!(n > 150);
}

#[test]
fn quantile_round_trips_through_the_cdf() {
    for nu in [2.0, 3.5, 9.0, 29.0, 199.0, 999.0] {
        for alpha in [1e-6, 3e-5, 1e-3, 0.05, 0.2] {
            let t = student_t_upper_quantile(alpha, nu).unwrap();
            let back = student_t_upper_tail(t, nu);
            assert!(
                (back / alpha - 1.0).abs() < 1e-9,
                "nu={nu} alpha={alpha}: tail(t) = {back}"
            );
        }
    }
}
