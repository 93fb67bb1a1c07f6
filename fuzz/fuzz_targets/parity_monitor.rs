//! The parity monitor (cone of six gyros; white-noise tests and the
//! multi-scale `gyro_flight` detector) under an arbitrary stream of
//! readings — any value, missing, bus errors, offsets, frozen, clipped —
//! then 10 s of the valid run: finite fused output whenever three sensors
//! are usable, and no stale state: every sensor either healthy or latched
//! failed (reported, out of the set until `reset`), no alarm, monitoring
//! while at least four sensors remain.
#![no_main]
#![allow(clippy::indexing_slicing, clippy::unwrap_used)]

use std::sync::OnceLock;

use hal_sim::array::{cone6_directions, ArrayKind, ArraySim, ArraySpec, Layout};
use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading};
use imu_fdi_fuzz::{count, Bytes};
use libfuzzer_sys::fuzz_target;

type Monitor = ParityMonitor<f32, 6, 40>;

struct Base {
    monitor: Monitor,
    run: Vec<[Reading<f32>; 6]>,
    start: usize,
    full_scale: f32,
}

const RATE: f64 = 100.0;

fn base(flight: bool) -> Base {
    let spec = ArraySpec::fault_free(
        "cone6",
        cone6_directions(),
        ArrayKind::Gyro,
        Layout::Single,
        60.0,
    );
    let sim = ArraySim::new(&spec, 1);
    let fs = spec.errors.full_scale as f32;
    let dirs = spec.directions.map(|d| d.map(|v| v as f32));
    let geometry = Geometry::<f32, 6>::new(&dirs).unwrap();
    let mut cfg = if flight {
        ParityConfig::<f32>::gyro_flight(RATE, fs)
    } else {
        ParityConfig::<f32>::gyro(RATE, fs)
    };
    cfg.set_lead_in(sim.lead_in_samples());
    let mut monitor = Monitor::new(&geometry, cfg).unwrap();
    let mut run = Vec::new();
    let mut start = 0;
    for s in sim {
        if s.t < 2.0 {
            monitor.step(&s.readings.map(|r| r.map(|v| v as f32)));
            start += 1;
        }
        run.push(s.readings.map(|r| r.map(|v| v as f32)));
    }
    assert_eq!(monitor.phase(), ParityPhase::Monitoring);
    Base {
        monitor,
        run,
        start,
        full_scale: fs,
    }
}

static BASES: OnceLock<[Base; 2]> = OnceLock::new();

fn check_finite(r: &imu_fdi::parity::ParityReport<f32, 6>) {
    if let Some(v) = r.fused {
        assert!(v.iter().all(|x| x.is_finite()), "non-finite fused {v:?}");
    }
    assert!(
        r.glt.is_finite() && r.pca.is_finite() && r.cusum_ratio.is_finite(),
        "non-finite statistic: {r:?}"
    );
}

fuzz_target!(|data: &[u8]| {
    let bases = BASES.get_or_init(|| [base(false), base(true)]);
    let mut bytes = Bytes::new(data);
    let b = &bases[usize::from(bytes.u8() & 1)];
    let mut m = b.monitor.clone();
    let mut k = b.start;
    let end = (k + 3000).min(b.run.len() - 1200);
    let mut steps = 0u64;
    let mut frozen = [None::<f32>; 6];
    while !bytes.done() && k < end {
        let op = bytes.u8();
        let mask = bytes.u8();
        let value = bytes.f32();
        let frac = bytes.frac();
        let repeat = 1 + usize::from(op >> 3);
        for _ in 0..repeat {
            let Some(clean) = b.run.get(k) else { break };
            k += 1;
            let mut readings = *clean;
            for (i, r) in readings.iter_mut().enumerate() {
                if mask & (1 << i) == 0 {
                    frozen[i] = None;
                    continue;
                }
                let x = match *r {
                    Reading::Sample(x) => x,
                    _ => 0.0,
                };
                *r = match op & 7 {
                    0 => Reading::Sample(value),
                    1 => Reading::Missing,
                    2 => Reading::BusError,
                    3 => Reading::Sample(x + frac * b.full_scale),
                    4 => Reading::Sample(*frozen[i].get_or_insert(x)),
                    5 => Reading::Sample(x.clamp(-0.5, 0.5) * 2.0 * b.full_scale),
                    _ => *r,
                };
            }
            let r = m.step(&readings);
            check_finite(&r);
            steps += 1;
        }
    }
    // 10 s of the valid run, then the verdict over 1 s.
    let t_end = k;
    let mut verdict = None;
    for readings in b.run.iter().skip(k).take(1100) {
        let r = m.step(readings);
        check_finite(&r);
        steps += 1;
        k += 1;
        if k - t_end <= 1000 {
            continue;
        }
        let failed = r.status.iter().filter(|s| s.is_failed()).count();
        let stale = r
            .status
            .iter()
            .any(|s| !s.is_failed() && *s != imu_fdi::parity::SensorStatus::Healthy);
        let why = if stale {
            Some("a sensor neither healthy nor failed")
        } else if r.fault {
            // In any parity dimension, one (detect-only) included: the input
            // that kept the CUSUM up there is `seed-detect-only-alarm`.
            Some("alarm")
        } else if failed <= 2 && r.phase != ParityPhase::Monitoring {
            Some("four or more sensors but not monitoring")
        } else if failed <= 3 && r.fused.is_none() {
            Some("three or more sensors but no fused output")
        } else {
            None
        };
        if let Some(w) = why {
            verdict.get_or_insert((r, w));
        }
    }
    if let Some((r, why)) = verdict {
        panic!("not back to nominal 10 s after the attack: {why}: {r:?}");
    }
    count(steps);
});
