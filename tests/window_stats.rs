//! `f32` window statistics against an `f64` recomputation over 10⁷ samples
//! of a biased signal (the case where Σx² − n·mean² collapses).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use imu_fdi::detect::InnovationWindow;
use rand::{Rng, SeedableRng};

#[test]
fn f32_window_matches_f64_over_ten_million_samples() {
    const N: usize = 10;
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let mut w = InnovationWindow::<f32, N>::new();
    let mut ring = [0f64; N];
    let (mut worst_mean, mut worst_std) = (0.0f64, 0.0f64);
    for k in 0..10_000_000usize {
        // A large bias with a slow drift and small noise.
        let x = (5.0 + 1e-7 * k as f64 + 0.01 * (rng.random::<f64>() - 0.5)) as f32;
        w.push(x);
        ring[k % N] = f64::from(x);
        if k >= N && k % 97 == 0 {
            let s = w.stats().unwrap();
            let mean = ring.iter().sum::<f64>() / N as f64;
            let std =
                (ring.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (N - 1) as f64).sqrt();
            worst_mean = worst_mean.max((f64::from(s.mean) - mean).abs() / mean.abs());
            worst_std = worst_std.max((f64::from(s.std) - std).abs() / std);
        }
    }
    println!("worst relative error: mean {worst_mean:.2e}, std {worst_std:.2e}");
    assert!(worst_mean < 1e-5 && worst_std < 1e-5);
}
