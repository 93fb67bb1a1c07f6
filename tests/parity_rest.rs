//! The gyro rest check on hal-sim's redundant arrays (issue 14): three
//! triads of gyros and accelerometers flying the array manoeuvre through
//! training, then at rest for 12 s of monitoring before manoeuvring again.
//! A 2 °/s gyro bias present from power-up (learned into the in-flight
//! calibration as a relative offset) is isolated by the absolute means at
//! rest within 10 s of monitoring start; with no fault nothing is isolated.
//! Seeds 100–119, none of them looked at while the check was designed
//! (it was designed on log171).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code: a panic is a failed assertion

use hal_sim::array::{
    triad_directions, ArrayFault, ArrayFaultKind, ArrayKind, ArraySim, ArraySpec, Layout,
};
use imu_fdi::parity::{
    Geometry, ParityConfig, ParityMonitor, ParityPhase, RestCheck, RestConfig, RestState,
};

const DEG: f64 = core::f64::consts::PI / 180.0;
const REST_S: f64 = 12.0;

fn spec(kind: ArrayKind, fault: Option<(usize, f64)>) -> ArraySpec<9> {
    let mut s = ArraySpec::fault_free(
        "triads at rest",
        triad_directions::<9>(&[0.0, 0.0, 0.0]),
        kind,
        Layout::Triads,
        40.0,
    );
    s.motion_start = REST_S;
    if let Some((sensor, b)) = fault {
        s = s.with_fault(ArrayFault {
            sensor,
            start: f64::NEG_INFINITY,
            end: f64::INFINITY,
            kind: ArrayFaultKind::Bias(b),
        });
    }
    s
}

struct Outcome {
    /// Isolations `(sensor, scenario time)` by the rest check.
    rest: Vec<(usize, f64)>,
    /// Isolations by the parity tests.
    tests: Vec<(usize, f64)>,
    /// Scenario time monitoring started.
    from: f64,
    /// Seconds judged at rest.
    at_rest_s: f64,
    common_mode: bool,
}

fn run(seed: u64, fault: Option<(usize, f64)>, with_rest: bool) -> Outcome {
    let gs = spec(ArrayKind::Gyro, fault);
    let as_ = spec(ArrayKind::Accel, None);
    let rate = gs.rate_hz;
    let dirs = gs.directions.map(|d| d.map(|v| v as f32));
    let geometry = Geometry::<f32, 9>::new(&dirs).unwrap();
    let mut cfg = ParityConfig::<f32>::gyro_flight(rate, gs.errors.full_scale as f32);
    let gyro = ArraySim::new(&gs, seed);
    cfg.train_samples = gyro.training_samples();
    let mut m = ParityMonitor::<f32, 9, 40>::new(&geometry, cfg).unwrap();
    let mut rest = RestCheck::new(
        &geometry,
        &geometry,
        RestConfig::new(rate, cfg.multiscale.offset_limit),
    )
    .unwrap();
    let mut out = Outcome {
        rest: Vec::new(),
        tests: Vec::new(),
        from: f64::NAN,
        at_rest_s: 0.0,
        common_mode: false,
    };
    for (g, a) in gyro.zip(ArraySim::new(&as_, seed)) {
        let gr = g.readings.map(|r| r.map(|v| v as f32));
        let ar = a.readings.map(|r| r.map(|v| v as f32));
        if with_rest {
            let v = rest.step(&gr, &ar, m.space().active());
            if v.state != RestState::Moving {
                out.at_rest_s += 1.0 / rate;
            }
            out.common_mode |= v.state == RestState::CommonMode;
            if let Some(k) = v.isolate.filter(|k| m.isolate_external(*k)) {
                out.rest.push((k, g.t));
            }
        }
        let r = m.step(&gr);
        if out.from.is_nan() && r.phase == ParityPhase::Monitoring {
            out.from = g.t;
        }
        if let Some(k) = r.isolated {
            out.tests.push((k, g.t));
        }
    }
    out
}

#[test]
fn a_fault_free_array_at_rest_isolates_nothing() {
    let mut by_tests = 0;
    for seed in 100..120 {
        let o = run(seed, None, true);
        assert!(o.rest.is_empty(), "seed {seed}: {:?}", o.rest);
        assert!(!o.common_mode, "seed {seed}");
        // At rest for the 12 s less the settling second; in motion never.
        assert!(
            (o.at_rest_s - 11.0).abs() < 0.1,
            "seed {seed}: {}",
            o.at_rest_s
        );
        // The rest check leaves the parity tests' own verdicts alone.
        assert_eq!(o.tests, run(seed, None, false).tests, "seed {seed}");
        by_tests += o.tests.len();
    }
    // Measured: the flight tests isolate a healthy gyro in 3 of these 20
    // flights (seeds 108, 110, 111; 11–22 s after the manoeuvre resumes),
    // with or without the rest check — the white-noise array's rest pause
    // is not what `gyro_flight` was fitted to.
    assert!(by_tests <= 3, "{by_tests}");
}

#[test]
fn a_gyro_bias_from_power_up_is_isolated_and_no_healthy_sensor_named() {
    for seed in 100..120u64 {
        let k = (seed % 9) as usize;
        let b = if seed % 2 == 0 { 2.0 } else { -2.0 } * DEG;
        let o = run(seed, Some((k, b)), true);
        let all: Vec<_> = o.rest.iter().chain(o.tests.iter()).copied().collect();
        assert!(all.iter().all(|(j, _)| *j == k), "seed {seed}: {all:?}");
        let first = all.iter().map(|(_, t)| *t).fold(f64::INFINITY, f64::min);
        // Measured: 0.68 s after monitoring start in all 20, by the
        // offset check (the white-noise array's healthy relative offsets
        // are small), before the rest check has its 4.65 s of rest.
        assert!(first - o.from < 1.0, "seed {seed}: {first} from {}", o.from);
    }
}
