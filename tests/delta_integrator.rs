//! The f32 delta-angle / delta-velocity integrator against f64 closed forms:
//! constant rate and specific force, classic coning (Savage 1998, Part 1),
//! classic sculling (Part 2). The integrator is fed the exact increments of
//! each 1 ms sample (what an ideal band-limited chip sample stands for), so
//! every remaining error is the algorithm's.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code

use imu_fdi::imu::{Delta, DeltaIntegrator};

const H: f64 = 1e-3; // 1 kHz ODR
const PERIOD: usize = 20; // 50 Hz monitor

type Q = [f64; 4]; // scalar first

fn qmul(a: Q, b: Q) -> Q {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn qconj(a: Q) -> Q {
    [a[0], -a[1], -a[2], -a[3]]
}

/// Rotation vector of a unit quaternion.
fn qlog(q: Q) -> [f64; 3] {
    let s = (q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let angle = 2.0 * s.atan2(q[0]);
    let k = if s > 0.0 { angle / s } else { 2.0 };
    [q[1] * k, q[2] * k, q[3] * k]
}

fn run(periods: usize, inc: impl Fn(f64, f64) -> ([f64; 3], [f64; 3])) -> Vec<(f64, Delta)> {
    let mut integ = DeltaIntegrator::new();
    let mut out = Vec::new();
    for p in 0..periods {
        let t0 = (p * PERIOD) as f64 * H;
        for k in 0..PERIOD {
            let a = t0 + k as f64 * H;
            let (da, dv) = inc(a, a + H);
            let g = da.map(|x| (x / H) as f32);
            let f = dv.map(|x| (x / H) as f32);
            assert!(integ.push(g, f, H as f32));
        }
        out.push((t0, integ.take().unwrap()));
    }
    out
}

#[test]
fn constant_rate_and_force_match_the_closed_form() {
    let w = [0.3f64, -0.2, 0.5]; // rad/s
    let f = [1.0f64, -2.0, -9.8]; // m/s²
    let deltas = run(5, |a, b| (w.map(|x| x * (b - a)), f.map(|x| x * (b - a))));
    let t = PERIOD as f64 * H;
    // Exact: φ = ωT; Δv = ∫₀ᵀ exp(t[ω×]) f dt = fT + T²/2 ω×f + T³/6 ω×(ω×f) + …
    let wxf = [
        w[1] * f[2] - w[2] * f[1],
        w[2] * f[0] - w[0] * f[2],
        w[0] * f[1] - w[1] * f[0],
    ];
    let wwf = [
        w[1] * wxf[2] - w[2] * wxf[1],
        w[2] * wxf[0] - w[0] * wxf[2],
        w[0] * wxf[1] - w[1] * wxf[0],
    ];
    for (_, d) in &deltas {
        assert_eq!(d.samples, PERIOD as u32);
        assert!((f64::from(d.dt) - t).abs() < 1e-7);
        for i in 0..3 {
            let phi = w[i] * t;
            assert!(
                (f64::from(d.delta_angle[i]) - phi).abs() < 1e-8,
                "{i}: {} vs {phi}",
                d.delta_angle[i]
            );
            let dv = f[i] * t + 0.5 * t * t * wxf[i] + t * t * t / 6.0 * wwf[i];
            // The algorithm is exact to second order; the third-order term
            // is ≈ 1e-6 here: allow that plus f32 rounding.
            let tol = (t * t * t / 6.0 * wwf[i]).abs() + 2e-7;
            assert!(
                (f64::from(d.delta_velocity[i]) - dv).abs() < tol,
                "{i}: {} vs {dv}",
                d.delta_velocity[i]
            );
        }
        let r = d.mean_rate();
        for i in 0..3 {
            assert!((f64::from(r[i]) - w[i]).abs() < 1e-6);
        }
    }
}

/// Classic coning (half-angle β, cone rate Ω): attitude
/// q(t) = [cos β/2, 0, sin β/2 cos Ωt, sin β/2 sin Ωt], body rate
/// ω = [−2Ω sin²(β/2), −Ω sin β sin Ωt, Ω sin β cos Ωt]. Summing the rate
/// increments misses the coning term, whose first-order closed form over a
/// period T is ½ sin²β (ΩT − sin ΩT) about x (Savage 1998, Part 1).
#[test]
fn classic_coning_is_corrected() {
    let beta = 2f64.to_radians();
    let om = 2.0 * std::f64::consts::PI * 10.0; // 10 Hz cone: vibration-class
    let (cb, sb) = ((beta / 2.0).cos(), (beta / 2.0).sin());
    let q = |t: f64| -> Q { [cb, 0.0, sb * (om * t).cos(), sb * (om * t).sin()] };
    let inc = |a: f64, b: f64| {
        let da = [
            -2.0 * om * sb * sb * (b - a),
            beta.sin() * ((om * b).cos() - (om * a).cos()),
            beta.sin() * ((om * b).sin() - (om * a).sin()),
        ];
        (da, [0.0; 3])
    };
    let deltas = run(50, inc);
    let t = PERIOD as f64 * H;
    let coning = 0.5 * beta.sin().powi(2) * (om * t - (om * t).sin());
    let mut worst_corrected = 0f64;
    let mut worst_plain_rel = 0f64;
    for (t0, d) in deltas.iter().skip(1) {
        let truth = qlog(qmul(qconj(q(*t0)), q(t0 + t)));
        // The plain sum of increments, x axis.
        let (a0, a1) = (*t0, t0 + t);
        let plain_x = -2.0 * om * sb * sb * (a1 - a0);
        let plain_err = plain_x - truth[0];
        worst_plain_rel = worst_plain_rel.max(((plain_err + coning) / coning).abs());
        for i in 0..3 {
            worst_corrected = worst_corrected.max((f64::from(d.delta_angle[i]) - truth[i]).abs());
        }
    }
    println!(
        "coning term {coning:.3e} rad/period ({:.3} °/s); plain sum misses it within {:.2} %; \
         corrected worst error {worst_corrected:.3e} rad ({:.2} % of it)",
        (coning / t).to_degrees(),
        100.0 * worst_plain_rel,
        100.0 * worst_corrected / coning
    );
    // The closed form describes what the plain sum misses (first order in β²).
    assert!(worst_plain_rel < 0.01, "{worst_plain_rel}");
    // Miller's correction leaves a small part of it (the algorithm's
    // higher-order residual in Ωh and f32 rounding): measured 0.27 %.
    assert!(
        worst_corrected < 0.01 * coning,
        "{worst_corrected} vs {coning}"
    );
}

/// Classic sculling: roll oscillation θ = a sin Ωt (ω_x = aΩ cos Ωt) in
/// phase with a y specific force A cos Ωt. In the body axes at the start of
/// the period the velocity change has a z component the plain sum of
/// increments misses; truth by f64 quadrature of R_x(θ(t) − θ(t₀)) f(t).
#[test]
fn classic_sculling_is_corrected() {
    let amp = 1f64.to_radians();
    let acc = 5.0;
    let om = 2.0 * std::f64::consts::PI * 8.0;
    let inc = |a: f64, b: f64| {
        let s = (om * b).sin() - (om * a).sin();
        ([amp * s, 0.0, 0.0], [0.0, acc / om * s, 0.0])
    };
    let deltas = run(40, inc);
    let t = PERIOD as f64 * H;
    let (mut worst_corrected, mut worst_plain) = (0f64, 0f64);
    for (t0, d) in deltas.iter().skip(1) {
        let n = 20_000;
        let dt = t / n as f64;
        let th0 = amp * (om * t0).sin();
        let mut truth = [0f64; 3];
        for k in 0..n {
            let s = t0 + (k as f64 + 0.5) * dt;
            let f = acc * (om * s).cos();
            let phi = amp * (om * s).sin() - th0;
            truth[1] += f * phi.cos() * dt;
            truth[2] += f * phi.sin() * dt;
        }
        let plain_z = 0.0;
        worst_plain = worst_plain.max((plain_z - truth[2]).abs());
        for i in 0..3 {
            worst_corrected =
                worst_corrected.max((f64::from(d.delta_velocity[i]) - truth[i]).abs());
        }
    }
    println!(
        "sculling: plain sum misses up to {worst_plain:.3e} m/s per period; corrected worst error {worst_corrected:.3e}"
    );
    assert!(worst_plain > 1e-5, "the motion must exercise sculling");
    // Measured 0.56 % of what the plain sum misses.
    assert!(
        worst_corrected < 0.02 * worst_plain,
        "{worst_corrected} vs {worst_plain}"
    );
}

#[test]
fn bad_samples_are_refused_and_counted() {
    let mut i = DeltaIntegrator::new();
    assert!(!i.push([f32::NAN, 0.0, 0.0], [0.0; 3], 1e-3));
    assert!(!i.push([0.0; 3], [0.0; 3], 0.0));
    assert!(!i.push([0.0; 3], [f32::INFINITY, 0.0, 0.0], 1e-3));
    assert_eq!(i.rejected(), 3);
    assert_eq!(i.take(), None);
    // Without rotation the averages are exactly the mean of the samples.
    assert!(i.push([0.0; 3], [4.0, 5.0, 6.0], 1e-3));
    assert!(i.push([0.0; 3], [6.0, 7.0, 8.0], 1e-3));
    let d = i.take().unwrap();
    assert_eq!(d.samples, 2);
    assert_eq!(d.mean_rate(), [0.0; 3]);
    let f = d.mean_specific_force();
    for (x, y) in f.iter().zip([5.0, 6.0, 7.0]) {
        assert!((x - y).abs() < 1e-5, "{f:?}");
    }
    // And the period restarts empty.
    assert_eq!(i.take(), None);
}
