//! Unit tests of the block variance's regression on motion: the learnt
//! factor against the closed form, and what it changes for a step in calm
//! flight after manoeuvres.

// Test code: a panic is a failed assertion.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
use super::test_noise::Noise;
use super::*;

/// Calm blocks (motion 1, sd `CALM` per axis) and manoeuvring ones
/// (motion 25, sd `ACTIVE`), in alternating 15-block stretches.
const CALM: f64 = 0.1;
const ACTIVE: f64 = 0.4;
fn motion_at(k: usize) -> f64 {
    if (k / 15).is_multiple_of(2) {
        1.0
    } else {
        25.0
    }
}

fn limits() -> ChannelLimits<f64> {
    ChannelLimits {
        nominal: Vector3::from_element(2.0),
        relevant: Vector3::zeros(),
    }
}

/// Feeds blocks `from..to` (bias `bias(k)` on x) and returns the first
/// block flagged on x (`None`: never), asserting y and z never are.
fn feed(
    t: &mut BlockTest<f64>,
    cfg: &BlockTestConfig<f64>,
    n: &mut Noise,
    from: usize,
    to: usize,
    bias: impl Fn(usize) -> f64,
) -> Option<usize> {
    let mut first = None;
    for k in from..to {
        let m = motion_at(k);
        let sd = if m > 1.0 { ACTIVE } else { CALM };
        let b = Vector3::new(n.gauss() * sd + bias(k), n.gauss() * sd, n.gauss() * sd);
        t.close_block(cfg, b, m, &limits());
        assert_eq!(t.detail.flag[1..], [0, 0], "y/z flagged at block {k}");
        if first.is_none() && t.detail.flag[0] != 0 {
            first = Some(k);
        }
    }
    first
}

#[test]
fn the_learnt_factor_follows_the_spread_per_motion() {
    let cfg = BlockTestConfig::velocity();
    let mut t = BlockTest::new(cfg.alpha());
    let mut n = Noise(5);
    feed(&mut t, &cfg, &mut n, 0, 600, |_| 0.0);
    // Variance 0.01 calm and 0.16 active, equal shares: h = v / 0.085.
    let (calm, active) = (t.motion_factor(0, 1.0, 10), t.motion_factor(0, 25.0, 10));
    assert!((calm - 0.01 / 0.085).abs() < 0.06, "calm factor {calm}");
    assert!(
        (active - 0.16 / 0.085).abs() < 0.25,
        "active factor {active}"
    );
}

#[test]
fn a_step_in_calm_flight_is_judged_against_the_calm_spread() {
    // 0.25 on x over a calm stretch: 2.5 calm block sd, 0.9 of the spread
    // of all blocks. With one variance for every block the 10-block
    // window's threshold (≈ 4.5 × 0.29/√10 = 0.41) never lets it through;
    // judged against the calm spread it is found within the stretch. The
    // manoeuvres before it raise no flag.
    let cfg = BlockTestConfig::velocity();
    let mut t = BlockTest::new(cfg.alpha());
    let mut n = Noise(9);
    feed(&mut t, &cfg, &mut n, 0, 120, |_| 0.0);
    t.start_judging();
    assert_eq!(feed(&mut t, &cfg, &mut n, 120, 300, |_| 0.0), None);
    // Blocks 300–314 are calm.
    let found = feed(&mut t, &cfg, &mut n, 300, 315, |k| {
        if k >= 301 {
            0.25
        } else {
            0.0
        }
    });
    let found = found.expect("calm step never flagged");
    assert!(found <= 312, "flagged at block {found}");
}
