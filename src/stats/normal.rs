//! Standard normal quantile in closed form: Wichura's rational
//! approximations (Algorithm AS 241, PPND16; M. J. Wichura, "The percentage
//! points of the normal distribution", *Applied Statistics* 37(3),
//! 477–484, 1988), relative error about 1e-16 — no root finding, one `log`
//! and one `sqrt`, so no `erfc` is linked for it.

// The coefficients as Wichura printed them (more digits than f64 holds).
#![allow(clippy::excessive_precision)]

use super::StatsError;

/// `Σ c_k r^k` by Horner's rule (`c` lowest order first).
fn horner(c: &[f64; 8], r: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * r + ck)
}

/// Central region `|p − ½| ≤ 0.425`: `q·A(r)/B(r)`, `r = 0.180625 − q²`.
const A: [f64; 8] = [
    3.387_132_872_796_366_608,
    133.141_667_891_784_377_45,
    1_971.590_950_306_551_442_7,
    13_731.693_765_509_461_125,
    45_921.953_931_549_871_457,
    67_265.770_927_008_700_853,
    33_430.575_583_588_128_105,
    2_509.080_928_730_122_672_7,
];
const B: [f64; 8] = [
    1.0,
    42.313_330_701_600_911_252,
    687.187_007_492_057_908_3,
    5_394.196_021_424_751_107_7,
    21_213.794_301_586_595_867,
    39_307.895_800_092_710_61,
    28_729.085_735_721_942_674,
    5_226.495_278_852_854_561,
];
/// Tail, `r = √(−ln p) ≤ 5`: `C(r − 1.6)/D(r − 1.6)`.
const C: [f64; 8] = [
    1.423_437_110_749_683_577_34,
    4.630_337_846_156_545_295_9,
    5.769_497_221_460_691_405_5,
    3.647_848_324_763_204_605_04,
    1.270_458_252_452_368_382_58,
    0.241_780_725_177_450_611_77,
    0.022_723_844_989_269_184_583_3,
    7.745_450_142_783_414_076_4e-4,
];
const D: [f64; 8] = [
    1.0,
    2.053_191_626_637_758_821_87,
    1.676_384_830_183_803_849_4,
    0.689_767_334_985_100_004_55,
    0.148_103_976_427_480_074_59,
    0.015_198_666_563_616_457_196_6,
    5.475_938_084_995_344_946e-4,
    1.050_750_071_644_416_843_24e-9,
];
/// Far tail, `r > 5`: `E(r − 5)/F(r − 5)`.
const E: [f64; 8] = [
    6.657_904_643_501_103_777_2,
    5.463_784_911_164_114_369_9,
    1.784_826_539_917_291_335_8,
    0.296_560_571_828_504_891_23,
    0.026_532_189_526_576_123_093,
    1.242_660_947_388_078_438_6e-3,
    2.711_555_568_743_487_578_15e-5,
    2.010_334_399_292_288_132_65e-7,
];
const F: [f64; 8] = [
    1.0,
    0.599_832_206_555_887_937_69,
    0.136_929_880_922_735_805_31,
    0.014_875_361_290_850_614_852_5,
    7.868_691_311_456_132_591e-4,
    1.846_318_317_510_054_681_8e-5,
    1.421_511_758_316_445_888_7e-7,
    2.044_263_103_389_939_785_64e-15,
];

/// Upper `alpha` quantile of the standard normal distribution (the t
/// quantile in the limit of infinite degrees of freedom), `alpha ∈ (0, ½]`.
pub fn normal_upper_quantile(alpha: f64) -> Result<f64, StatsError> {
    if alpha.is_nan() || alpha <= 0.0 || alpha > 0.5 {
        return Err(StatsError::Probability);
    }
    // The upper quantile at α is minus the lower one at α.
    let q = 0.5 - alpha;
    if q <= 0.425 {
        let r = 0.180_625 - q * q;
        return Ok(q * horner(&A, r) / horner(&B, r));
    }
    let r = libm::sqrt(-libm::log(alpha));
    Ok(if r <= 5.0 {
        horner(&C, r - 1.6) / horner(&D, r - 1.6)
    } else {
        horner(&E, r - 5.0) / horner(&F, r - 5.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lower tail `Φ(−z)` through `erfc`, to invert against.
    fn upper_tail(z: f64) -> f64 {
        0.5 * libm::erfc(z / core::f64::consts::SQRT_2)
    }

    #[test]
    fn inverts_the_normal_tail() {
        // Tabulated: z(0.025) = 1.959963984540054, z(1e-6) = 4.753424308822899.
        assert!((normal_upper_quantile(0.025).unwrap() - 1.959_963_984_540_054).abs() < 1e-14);
        assert!((normal_upper_quantile(1e-6).unwrap() - 4.753_424_308_822_899).abs() < 1e-13);
        assert_eq!(normal_upper_quantile(0.5).unwrap(), 0.0);
        let mut a = 0.5;
        while a > 1e-300 {
            let z = normal_upper_quantile(a).unwrap();
            let back = upper_tail(z);
            // erfc is accurate to a few ulp; the tail's slope turns a
            // quantile error δ into a relative tail error ≈ z·δ.
            assert!(
                (back / a - 1.0).abs() < 1e-13 * z.max(1.0),
                "{a}: {z} → {back}"
            );
            a *= 0.37;
        }
        for bad in [0.0, -1.0, 0.6, f64::NAN] {
            assert_eq!(normal_upper_quantile(bad), Err(StatsError::Probability));
        }
    }
}
