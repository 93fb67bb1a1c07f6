//! Unit tests of the staged block work: the reused factors and the
//! window means are those of a fresh computation.

use super::super::lin::{cholesky_dim, pad};
use super::super::MultiscaleConfig;
use super::*;

fn block(i: usize) -> (SVector<f32, 9>, Phi<f32>) {
    let p = SVector::<f32, 9>::from_fn(|k, _| {
        if k < 6 {
            ((i * 9 + k) as f32 * 0.37).sin() * 0.02
        } else {
            0.0
        }
    });
    let phi = Phi::<f32>::from_fn(|k, _| {
        if k == 0 {
            1.0
        } else {
            ((i * 16 + k) as f32 * 0.91).cos()
        }
    });
    (p, phi)
}

/// The factor a block reuses is the one the current `sxx` gives, bit for
/// bit, and a learned block makes the next one factorise anew.
#[test]
fn the_reused_calibration_factor_is_that_of_the_current_matrix() {
    let cfg = MultiscaleConfig::<f32>::new(0.0175, f32::INFINITY);
    let mut ms = Multiscale::<f32, 9, 40>::new(cfg, 6, [30.0; SCALES]);
    for i in 0..40 {
        let (p, phi) = block(i);
        ms.learn_calibration(&p, &phi, i > 20);
    }
    let bits = |m: &SMatrix<f32, REGRESSORS, REGRESSORS>| m.map(f32::to_bits);
    let fresh = |ms: &Multiscale<f32, 9, 40>| bits(&ms.calibration_factor().unwrap());
    let v = SMatrix::<f32, 9, 9>::identity();
    let active = [true; 9];
    for (i, learn) in [(40, false), (41, false), (42, true), (43, false)] {
        let (p, phi) = block(i);
        if learn {
            ms.learn_calibration(&p, &phi, true);
            assert!(!ms.cal_current);
        }
        let reused = ms.cal_current;
        ms.begin(&p, &phi, 1.0, None);
        assert_eq!(ms.pending(), Some(BlockStage::Factor));
        ms.advance(&v, &active);
        assert!(ms.cal_current);
        assert_eq!(bits(&ms.work.cal), fresh(&ms), "block {i}");
        // Reused exactly when nothing was learned since the last block.
        assert_eq!(reused, i != 40 && !learn, "block {i}");
    }
}

/// The kept covariance factors are those of the current matrices, bit
/// for bit, after a learned block and after a reconfiguration.
#[test]
fn the_kept_covariance_factors_are_those_of_the_current_matrices() {
    let cfg = MultiscaleConfig::<f32>::new(0.0175, f32::INFINITY);
    let mut ms = Multiscale::<f32, 9, 40>::new(cfg, 6, [30.0; SCALES]);
    let bits = |m: &SMatrix<f32, 9, 9>| m.map(f32::to_bits);
    let check = |ms: &mut Multiscale<f32, 9, 40>, when: &str| {
        let dim = ms.dim;
        let fresh = [
            cholesky_dim(&ms.block_cov, dim).unwrap(),
            cholesky_dim(&ms.window_cov[0], dim).unwrap(),
            cholesky_dim(&ms.window_cov[SCALES - 1], dim).unwrap(),
        ];
        let (b, w0, wl) = (ms.block_cov, ms.window_cov[0], ms.window_cov[SCALES - 1]);
        let kept = [
            *ms.block_factor.get(&b, dim).unwrap(),
            *ms.short_factor.get(&w0, dim).unwrap(),
            *ms.long_factor.get(&wl, dim).unwrap(),
        ];
        for (k, f) in kept.iter().zip(fresh.iter()) {
            assert_eq!(bits(k), bits(f), "{when}");
        }
    };
    check(&mut ms, "new");
    for i in 0..40 {
        let (p, phi) = block(i);
        ms.push(&p, &p, &phi, 1.0, 0.0);
        ms.decided_means[i] = [p * 3.0; SCALES];
        ms.decided_set[i] = 0b111;
        ms.norms[i] = 2.0;
    }
    ms.quiet_blocks = 40;
    // A small learning weight: the covariances stay positive definite.
    ms.updates = 100;
    for _ in 0..3 {
        ms.learn_oldest();
        // The learning moved the matrices: the old factors are stale.
        check(&mut ms, "learned");
        ms.head = (ms.head + 1) % 40;
    }
    let c = SMatrix::<f32, 9, 9>::from_fn(|i, j| if i < 3 && i == j { 1.0 } else { 0.0 });
    for part in 0..super::super::TRANSFORM_PARTS {
        ms.transform_part(&c, 3, part);
        check(&mut ms, "transformed");
    }
    assert_eq!(ms.dim, 3);
}

/// The attribution's unclipped window mean is the plain mean of the
/// newest blocks' standardised residuals (each times its own gain),
/// whatever the clip did to them, and absent until the window is full.
#[test]
fn the_unclipped_mean_is_the_mean_of_the_standardised_blocks() {
    let cfg = MultiscaleConfig::<f32>::new(0.0175, f32::INFINITY);
    let mut ms = Multiscale::<f32, 9, 40>::new(cfg, 6, [30.0; SCALES]);
    let raw = |i: usize| block(i).0 * (1.0 + i as f32);
    let gain = |i: usize| 1.0 / (1.0 + 0.1 * i as f32);
    for i in 0..45 {
        let (_, phi) = block(i);
        // A clipped copy a tenth of the size: the mean must ignore it.
        ms.push(&(raw(i) * 0.1), &raw(i), &phi, gain(i), 0.0);
        if i + 1 < 20 {
            assert_eq!(ms.raw_mean(20), None);
        }
    }
    let expected = (25..45).fold(SVector::<f64, 9>::zeros(), |acc, i| {
        acc + (raw(i) * gain(i)).map(f64::from)
    }) / 20.0;
    let got = ms.raw_mean(20).unwrap().map(f64::from);
    assert!(
        (got - expected).norm() < 1e-6 * expected.norm().max(1e-3),
        "{got} {expected}"
    );
}

/// The in-place covariance update is the expression it replaced, bit for
/// bit, for every dimension, a non-symmetric input included.
#[test]
fn the_in_place_covariance_update_is_the_padded_expression_bit_for_bit() {
    for dim in 1..=9 {
        for (s, wt) in [(1.0f32, 0.5f32), (-3.7, 1.0 / 3.0), (0.013, 1.0 / 400.0)] {
            let mut cov = SMatrix::<f32, 9, 9>::from_fn(|i, j| {
                ((i * 13 + j * 7) % 11) as f32 * s / 7.0 + if i == j { 2.0 } else { 0.0 }
            });
            let r = SVector::<f32, 9>::from_fn(|i, _| (i as f32 - 4.3) * s / 3.0);
            let expected = pad(&(cov * (1.0 - wt) + r * r.transpose() * wt), dim);
            ewma_outer_padded(&mut cov, &r, wt, dim);
            let same = cov
                .iter()
                .zip(expected.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "dim {dim}: {cov} vs {expected}");
        }
    }
}
