//! Inputs the fuzz targets (`fuzz/`) found, reduced to the monitor call
//! that failed: each one must stay fixed.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)] // test code

use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::{OtsukfConfig, OtsukfMonitor, UkfMonitor, UkfMonitorConfig};

const G: f32 = 9.806_65;

fn level() -> ImuVec<f32> {
    ImuVec::new(0.01, -0.02, -G, 0.001, -0.002, 0.0)
}

fn attitude() -> Measurement<f32> {
    Measurement {
        z: MeasVec::zeros(),
        available: [true; 6],
    }
}

/// `fuzz/artifacts/…/crash-4fb71c78`, `crash-825392ab`: a NaN or ∞ IMU
/// channel made the reported corrected sample non-finite (the state stayed
/// finite). The corrected sample of an invalid input is now the stand-in
/// the filter used: the last good sample, corrected.
#[test]
fn corrected_sample_of_an_invalid_input_is_finite() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30] {
        let mut ukf = UkfMonitor::<f32>::new(UkfMonitorConfig::auv()).unwrap();
        let mut ots =
            OtsukfMonitor::<f32>::new(OtsukfConfig::from_base(UkfMonitorConfig::auv())).unwrap();
        let none = Measurement::<f32>::none();
        for k in 0..5 {
            let mut imu = level();
            if k >= 3 {
                imu[k % 6] = bad;
            }
            let aiding = if k == 0 { attitude() } else { none };
            let r = ukf.step(&imu, 0.01, &aiding);
            assert_eq!(r.health.input_invalid, k >= 3);
            assert!(
                r.corrected_imu.iter().all(|v| v.is_finite()),
                "UKF {bad}: {r:?}"
            );
            let r = ots.step(&imu, 0.01, &aiding);
            assert_eq!(r.health.input_invalid, k >= 3);
            assert!(
                r.corrected_imu.iter().all(|v| v.is_finite()),
                "OTSUKF {bad}: {r:?}"
            );
        }
    }
}

/// `fuzz/…/parity_monitor/crash-e41ed475`: two sensors of the cone out
/// (parity dimension 1: detect-only), then a gross transient on a third
/// pushed the CUSUM to hundreds of times its threshold; once the input was
/// valid again the alarm stayed for minutes while the CUSUM decayed by κ
/// per block. The CUSUM is now held below `h + 50 κ`: the alarm clears
/// within 5 s of valid input.
#[test]
fn parity_cusum_alarm_clears_after_a_gross_transient() {
    use hal_sim::array::{cone6_directions, ArrayKind, ArraySim, ArraySpec, Layout};
    use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading};

    let spec = ArraySpec::fault_free(
        "cone6",
        cone6_directions(),
        ArrayKind::Gyro,
        Layout::Single,
        40.0,
    );
    let sim = ArraySim::new(&spec, 1);
    let fs = spec.errors.full_scale as f32;
    let dirs = spec.directions.map(|d| d.map(|v| v as f32));
    let mut cfg = ParityConfig::<f32>::gyro(100.0, fs);
    cfg.set_lead_in(sim.lead_in_samples());
    let mut m = ParityMonitor::<f32, 6, 16>::new(&Geometry::new(&dirs).unwrap(), cfg).unwrap();
    let mut last_alarm = f64::NAN;
    let mut peak = 0.0f32;
    for s in sim {
        let mut r = s.readings.map(|r| r.map(|v| v as f32));
        // Sensors 2 and 5 time out at 1 s (latched): dimension 1 remains.
        if s.t >= 1.0 {
            r[2] = Reading::Missing;
            r[5] = Reading::Missing;
        }
        // 3 s of +30 °/s on sensor 0 (not isolable in dimension 1).
        if (5.0..8.0).contains(&s.t) {
            if let Reading::Sample(x) = &mut r[0] {
                *x += 30f32.to_radians();
            }
        }
        let rep = m.step(&r);
        if s.t >= 0.0 && rep.fault {
            last_alarm = s.t;
        }
        peak = peak.max(rep.cusum_ratio);
    }
    assert_eq!(m.phase(), ParityPhase::Monitoring);
    assert!(
        peak > 1.0,
        "the transient must raise the CUSUM alarm: {peak}"
    );
    assert!(
        last_alarm < 8.0 + 5.5,
        "alarm at {last_alarm:.2} s, more than 5.5 s after the transient ended at 8 s"
    );
}

/// `fuzz/…/parity_monitor/detect-only-alarm` (was `fuzz/open/`; white-noise
/// detector, cone of six gyros, `ParityMonitor<f32, 6, 40>`): 31 samples of
/// sensors 4 and 5 frozen, then 31 at a constant ≈ 0 — replayed here
/// reading for reading from the fuzz target's snapshot (2 s of seed 1).
/// Sensors 4 and 0 are isolated (parity dimension 1, detect-only) and the
/// CUSUM sits at its cap. Once valid input returned, the offset the drift
/// tracker had not followed during the alarm (bias random walk: 0.33 block
/// σ on the 1-D parity direction over the next 11 s, against 0.13 before)
/// slowed its decay from κ to κ − 0.33 per block on the sensor with
/// κ = 0.52: alarm until 11.0 s after the attack. The CUSUM excess a gross
/// bias built is now cut to `h + window_blocks · κ` once the window test
/// clears: last alarm 4.4 s after the attack.
#[test]
fn parity_detect_only_alarm_clears_after_valid_input() {
    use hal_sim::array::{cone6_directions, ArrayKind, ArraySim, ArraySpec, Layout};
    use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading};

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
    let mut cfg = ParityConfig::<f32>::gyro(100.0, fs);
    cfg.set_lead_in(sim.lead_in_samples());
    let mut m = ParityMonitor::<f32, 6, 40>::new(&Geometry::new(&dirs).unwrap(), cfg).unwrap();
    let run: Vec<_> = sim
        .map(|s| (s.t, s.readings.map(|r| r.map(|v| v as f32))))
        .collect();
    let start = run.iter().take_while(|(t, _)| *t < 2.0).count();
    for (_, r) in run.iter().take(start) {
        m.step(r);
    }
    assert_eq!(m.phase(), ParityPhase::Monitoring);
    let tiny = f32::from_bits(u32::from_le_bytes([0x00, 0xf4, 0xa7, 0x02]));
    let attack_end = start + 62;
    let mut frozen = [None::<f32>; 6];
    let mut last_alarm = None;
    for (k, (_, clean)) in run.iter().enumerate().skip(start).take(62 + 1100) {
        let mut r = *clean;
        if k < attack_end {
            for i in [4, 5] {
                let x = match r[i] {
                    Reading::Sample(x) => x,
                    _ => 0.0,
                };
                r[i] = Reading::Sample(if k < start + 31 {
                    *frozen[i].get_or_insert(x)
                } else {
                    tiny
                });
            }
        }
        let rep = m.step(&r);
        if rep.fault {
            last_alarm = Some(k);
        }
    }
    let after = last_alarm.map_or(0.0, |k| (k as f64 - attack_end as f64) / 100.0);
    println!("last alarm {after:.2} s after the attack");
    assert!(
        after < 10.0,
        "alarm {after:.2} s after valid input returned"
    );
}

/// The other side of `parity_detect_only_alarm_clears_after_valid_input`:
/// the drift tracking that follows the offset during a detect-only alarm
/// must not absorb a fault. Parity dimension 1 (sensors 2 and 5 out), a
/// persistent bias of the CUSUM's design size (`cusum_bias`, 0.05 °/s) on
/// sensor 0 from 5 s, alone or after 1 s of +30 °/s (a gross transient the
/// window test flags, after which the CUSUM excess is cut): raised, and
/// still raised at every decision from 15 s to the end (45 s).
#[test]
fn parity_detect_only_alarm_stands_while_the_bias_does() {
    use hal_sim::array::{cone6_directions, ArrayKind, ArraySim, ArraySpec, Layout};
    use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading};

    let spec = ArraySpec::fault_free(
        "cone6",
        cone6_directions(),
        ArrayKind::Gyro,
        Layout::Single,
        45.0,
    );
    for (seed, gross) in (1..=3).flat_map(|s| [(s, false), (s, true)]) {
        let sim = ArraySim::new(&spec, seed);
        let fs = spec.errors.full_scale as f32;
        let dirs = spec.directions.map(|d| d.map(|v| v as f32));
        let mut cfg = ParityConfig::<f32>::gyro(100.0, fs);
        cfg.set_lead_in(sim.lead_in_samples());
        let bias = cfg.cusum_bias;
        let mut m = ParityMonitor::<f32, 6, 40>::new(&Geometry::new(&dirs).unwrap(), cfg).unwrap();
        let (mut decisions, mut raised, mut first) = (0, 0, None);
        for s in sim {
            let mut r = s.readings.map(|r| r.map(|v| v as f32));
            if s.t >= 1.0 {
                r[2] = Reading::Missing;
                r[5] = Reading::Missing;
            }
            if s.t >= 5.0 {
                if let Reading::Sample(x) = &mut r[0] {
                    *x += bias;
                    if gross && s.t < 6.0 {
                        *x += 30f32.to_radians();
                    }
                }
            }
            let rep = m.step(&r);
            if s.t >= 5.0 && rep.fault && first.is_none() {
                first = Some(s.t - 5.0);
            }
            if s.t >= 15.0 && rep.decision {
                assert_eq!(rep.parity_dim, 1);
                decisions += 1;
                raised += usize::from(rep.fault);
            }
        }
        assert_eq!(m.phase(), ParityPhase::Monitoring);
        println!(
            "seed {seed}, gross transient {gross}: raised after {first:?} s, \
             then {raised}/{decisions} decisions"
        );
        assert!(
            first.is_some_and(|t| t < 10.0),
            "seed {seed}: not raised: {first:?}"
        );
        assert_eq!(
            raised, decisions,
            "seed {seed}: the alarm dropped while the bias stayed"
        );
    }
}

/// The parity fuzz target's attack decoder (`fuzz/fuzz_targets/
/// parity_monitor.rs`, white-noise base only): replays `data` on the
/// target's snapshot, then 11 s of the valid run; the reports of the last
/// second.
fn replay_parity_attack(data: &[u8]) -> Vec<imu_fdi::parity::ParityReport<f32, 6>> {
    use hal_sim::array::{cone6_directions, ArrayKind, ArraySim, ArraySpec, Layout};
    use imu_fdi::parity::{Geometry, ParityConfig, ParityMonitor, Reading};

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
    let mut cfg = ParityConfig::<f32>::gyro(100.0, fs);
    cfg.set_lead_in(sim.lead_in_samples());
    let mut m = ParityMonitor::<f32, 6, 40>::new(&Geometry::new(&dirs).unwrap(), cfg).unwrap();
    let run: Vec<_> = sim
        .map(|s| (s.t, s.readings.map(|r| r.map(|v| v as f32))))
        .collect();
    let mut k = run.iter().take_while(|(t, _)| *t < 2.0).count();
    for (_, r) in run.iter().take(k) {
        m.step(r);
    }
    assert_eq!(
        data.first().map(|b| b & 1),
        Some(0),
        "white-noise base only"
    );
    let pos = std::cell::Cell::new(1);
    let byte = || {
        let b = data.get(pos.get()).copied().unwrap_or(0);
        pos.set(pos.get() + 1);
        b
    };
    let end = (k + 3000).min(run.len() - 1200);
    let mut frozen = [None::<f32>; 6];
    while pos.get() < data.len() && k < end {
        let (op, mask) = (byte(), byte());
        let value = f32::from_bits(u32::from_le_bytes([byte(), byte(), byte(), byte()]));
        let frac = f32::from(byte() as i8) / 127.0;
        for _ in 0..1 + usize::from(op >> 3) {
            let Some((_, clean)) = run.get(k) else { break };
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
                    3 => Reading::Sample(x + frac * fs),
                    4 => Reading::Sample(*frozen[i].get_or_insert(x)),
                    5 => Reading::Sample(x.clamp(-0.5, 0.5) * 2.0 * fs),
                    _ => *r,
                };
            }
            m.step(&readings);
        }
    }
    let reports: Vec<_> = run
        .iter()
        .skip(k)
        .take(1100)
        .map(|(_, r)| m.step(r))
        .collect();
    reports[1000..].to_vec()
}

/// `crash-78a8d4e6` of the parity target (found once it checked parity
/// dimension 1 too): sensors 4 and 5 frozen long enough to latch `Stuck`
/// after sensor 0 had been isolated — three sensors left, no parity space
/// (`NoRedundancy`) — and the report kept the last alarm for good, with
/// the stale dimension 1. Without a parity space the report now raises
/// nothing and says dimension 0; the phase says the monitor cannot judge.
#[test]
fn parity_no_redundancy_reports_no_stale_alarm() {
    use imu_fdi::parity::ParityPhase;
    let data = [
        0x80, 0xf4, 0xfa, 0xf0, 0xf0, 0xf0, 0x00, 0xf4, 0xf4, 0xf0, 0xa7, 0xf0, 0xa7, 0x02,
    ];
    for r in replay_parity_attack(&data) {
        assert_eq!(r.phase, ParityPhase::NoRedundancy);
        assert!(!r.fault && r.parity_dim == 0, "{r:?}");
        assert_eq!(r.status.iter().filter(|s| s.is_failed()).count(), 3);
        assert!(r.fused.is_some_and(|v| v.iter().all(|x| x.is_finite())));
    }
}
