//! The periodic `MonitorTask` with the real ICM-42688-P driver on the
//! emulated chip, through S2 with 2 % of the SPI reads failing.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code

use core::cell::RefCell;

use embedded_hal_mock::eh1::delay::NoopDelay;
use hal_sim::emulated_icm42688::{EmulatedIcm42688, SharedBus};
use hal_sim::runner::{monitor_config, RunOptions};
use hal_sim::{Scenario, Simulator};
use imu_fdi::imu::icm42688::{AccelRange, Config, GyroRange, Icm42688, Odr};
use imu_fdi::model::{MeasVec, Measurement};
use imu_fdi::monitor::{MonitorTask, Phase, TaskStatus};
use rand::{Rng, SeedableRng};

#[test]
fn s2_with_two_percent_failed_reads_still_detects_every_fault() {
    let scn = Scenario::s2();
    let chip = RefCell::new(EmulatedIcm42688::new());
    let cfg = Config {
        gyro_range: GyroRange::Dps250,
        accel_range: AccelRange::G4,
        odr: Odr::Hz100,
        ui_filter_bw: 1,
    };
    let imu = Icm42688::new(SharedBus(&chip), cfg, &mut NoopDelay::new()).unwrap();
    let mut task =
        MonitorTask::<_>::new(imu, monitor_config(&scn, &RunOptions::default())).unwrap();
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(9);
    let (mut injected, mut detected, mut false_flags) = (0u32, [false; 6], 0u32);
    let mut last = None;
    for s in Simulator::new(&scn, 1) {
        let imu = s.imu.unwrap();
        chip.borrow_mut()
            .set_sample([imu[0], imu[1], imu[2]], [imu[3], imu[4], imu[5]], 25.0);
        if rng.random::<f64>() < 0.02 {
            chip.borrow_mut().fail_next(1);
            injected += 1;
        }
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let r = task.step(
            s.dt as f32,
            &Measurement {
                z,
                available: s.aiding_available,
            },
        );
        assert!(r
            .fault_estimate
            .iter()
            .chain(r.corrected.iter())
            .all(|v| v.is_finite()));
        for c in 0..6 {
            let flag = r.status[c].sign().unwrap_or(0);
            if s.fault[c] != 0.0 && flag == if s.fault[c] > 0.0 { 1 } else { -1 } {
                detected[c] = true;
            }
            let any_fault_recent = scn
                .faults
                .iter()
                .any(|f| s.t >= f.start && s.t < f.end + 4.4);
            if r.phase == Phase::Monitoring && !any_fault_recent && flag != 0 {
                false_flags += 1;
            }
        }
        last = Some(r);
    }
    let r = last.unwrap();
    println!("read failures injected {injected}, counted {}; detected {detected:?}; false flags {false_flags}", r.read_failures);
    assert_eq!(r.read_failures, injected);
    assert!(injected > 80);
    assert_eq!(detected, [true; 6]);
    assert_eq!(false_flags, 0);
}

/// The same task running the OTSUKF instead: S2 through the
/// driver and the emulated chip, every fault flagged on its channel with the
/// right sign, and the corrected sample closer to the truth than the raw one
/// while a fault is active.
#[test]
fn s2_through_the_task_with_the_two_stage_ukf() {
    use hal_sim::ots::{otsukf_config, Setting};
    use imu_fdi::monitor::OtsukfMonitor;
    let scn = Scenario::s2();
    let chip = RefCell::new(EmulatedIcm42688::new());
    let cfg = Config {
        gyro_range: GyroRange::Dps250,
        accel_range: AccelRange::G4,
        odr: Odr::Hz100,
        ui_filter_bw: 1,
    };
    let imu = Icm42688::new(SharedBus(&chip), cfg, &mut NoopDelay::new()).unwrap();
    let ots = OtsukfMonitor::<f32>::new(otsukf_config(&scn, Setting::Realistic)).unwrap();
    let mut task = MonitorTask::with_monitor(imu, ots);
    let (mut detected, mut false_flags) = ([false; 6], 0u32);
    let (mut raw_err, mut corr_err, mut n) = (0.0f64, 0.0f64, 0u32);
    for s in Simulator::new(&scn, 1) {
        let imu = s.imu.unwrap();
        chip.borrow_mut()
            .set_sample([imu[0], imu[1], imu[2]], [imu[3], imu[4], imu[5]], 25.0);
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let r = task.step(
            s.dt as f32,
            &Measurement {
                z,
                available: s.aiding_available,
            },
        );
        for c in 0..6 {
            let flag = r.status[c].sign().unwrap_or(0);
            if s.fault[c] != 0.0 && flag == if s.fault[c] > 0.0 { 1 } else { -1 } {
                detected[c] = true;
            }
            let recent = scn
                .faults
                .iter()
                .any(|f| f.channel == c && s.t >= f.start && s.t < f.end + 2.0);
            if r.phase == Phase::Monitoring && !recent && flag != 0 {
                false_flags += 1;
            }
            // Accelerometer channels during their fault: corrected vs raw
            // error against the true specific force.
            if c < 3 && s.fault_active[c] && r.phase == Phase::Monitoring {
                raw_err += (imu[c] - s.truth.imu[c]).powi(2);
                corr_err += (f64::from(r.corrected[c]) - s.truth.imu[c]).powi(2);
                n += 1;
            }
        }
    }
    let (raw, corr) = (
        (raw_err / f64::from(n)).sqrt(),
        (corr_err / f64::from(n)).sqrt(),
    );
    println!("two-stage task on S2: detected {detected:?}, false flags {false_flags}, accel RMS error raw {raw:.3} corrected {corr:.3} m/s²");
    assert_eq!(detected, [true; 6]);
    assert_eq!(false_flags, 0);
    assert!(corr < 0.5 * raw, "corrected {corr} vs raw {raw}");
}

/// What S2 through the task gave with a share of the reads failing.
#[derive(Debug)]
struct FailedReadRun {
    injected: u32,
    missed_samples: u32,
    read_failures: u32,
    detected: [bool; 6],
    /// First detection time after each fault's start, s.
    latency: [Option<f64>; 6],
    false_flags: u32,
    monitoring_from: Option<f64>,
    unavailable_periods: u32,
    longest_run: u32,
}

/// S2 through the driver and the emulated chip with `share` of the reads
/// failing (seeded), the report checked every period.
fn s2_with_failed_reads(share: f64, seed: u64) -> FailedReadRun {
    let scn = Scenario::s2();
    let chip = RefCell::new(EmulatedIcm42688::new());
    let cfg = Config {
        gyro_range: GyroRange::Dps250,
        accel_range: AccelRange::G4,
        odr: Odr::Hz100,
        ui_filter_bw: 1,
    };
    let imu = Icm42688::new(SharedBus(&chip), cfg, &mut NoopDelay::new()).unwrap();
    let mut task =
        MonitorTask::<_>::new(imu, monitor_config(&scn, &RunOptions::default())).unwrap();
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut out = FailedReadRun {
        injected: 0,
        missed_samples: 0,
        read_failures: 0,
        detected: [false; 6],
        latency: [None; 6],
        false_flags: 0,
        monitoring_from: None,
        unavailable_periods: 0,
        longest_run: 0,
    };
    let mut run = 0u32;
    for s in Simulator::new(&scn, 1) {
        let imu = s.imu.unwrap();
        chip.borrow_mut()
            .set_sample([imu[0], imu[1], imu[2]], [imu[3], imu[4], imu[5]], 25.0);
        let fail = rng.random::<f64>() < share;
        if fail {
            chip.borrow_mut().fail_next(1);
            out.injected += 1;
            run += 1;
            out.longest_run = out.longest_run.max(run);
        } else {
            run = 0;
        }
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let r = task.step(
            s.dt as f32,
            &Measurement {
                z,
                available: s.aiding_available,
            },
        );
        assert_eq!(r.read_failed, fail);
        assert_eq!(r.missed_samples, out.injected);
        assert!(r
            .fault_estimate
            .iter()
            .chain(r.corrected.iter())
            .all(|v| v.is_finite()));
        if r.task_status == TaskStatus::ImuUnavailable {
            out.unavailable_periods += 1;
        }
        if r.phase == Phase::Monitoring && out.monitoring_from.is_none() {
            out.monitoring_from = Some(s.t);
        }
        for c in 0..6 {
            let flag = r.status[c].sign().unwrap_or(0);
            if s.fault[c] != 0.0 && flag == if s.fault[c] > 0.0 { 1 } else { -1 } {
                if !out.detected[c] {
                    let start = scn
                        .faults
                        .iter()
                        .filter(|f| f.channel == c && f.start <= s.t)
                        .map(|f| f.start)
                        .fold(f64::NEG_INFINITY, f64::max);
                    out.latency[c] = Some(s.t - start);
                }
                out.detected[c] = true;
            }
            let any_fault_recent = scn
                .faults
                .iter()
                .any(|f| s.t >= f.start && s.t < f.end + 4.4);
            if r.phase == Phase::Monitoring && !any_fault_recent && flag != 0 {
                out.false_flags += 1;
            }
        }
        out.missed_samples = r.missed_samples;
        out.read_failures = r.read_failures;
    }
    println!("S2, {:.0} % failed reads: {out:?}", share * 100.0);
    out
}

/// 10 % of the reads failing: every failed read is a missed sample, the
/// monitor reaches monitoring on time and flags all six S2 faults with the
/// right sign and no false flag.
#[test]
fn s2_with_ten_percent_failed_reads() {
    let r = s2_with_failed_reads(0.10, 10);
    assert!(r.injected > 500, "{r:?}");
    assert!(
        r.latency.iter().all(|l| l.is_some_and(|l| l < 3.0)),
        "{r:?}"
    );
    assert_eq!(r.missed_samples, r.injected);
    assert_eq!(r.read_failures, r.injected);
    assert!(r.monitoring_from.is_some_and(|t| t < 40.0), "{r:?}");
    assert_eq!(r.detected, [true; 6]);
    assert_eq!(r.false_flags, 0);
}

/// 30 % of the reads failing: the same, with runs of consecutive failures
/// long enough to be reported as `ImuUnavailable`.
#[test]
fn s2_with_thirty_percent_failed_reads() {
    let r = s2_with_failed_reads(0.30, 30);
    assert!(r.injected > 1500, "{r:?}");
    assert!(r.unavailable_periods > 0, "{r:?}");
    assert!(
        r.latency.iter().all(|l| l.is_some_and(|l| l < 3.0)),
        "{r:?}"
    );
    assert_eq!(r.missed_samples, r.injected);
    assert_eq!(r.read_failures, r.injected);
    assert!(r.monitoring_from.is_some_and(|t| t < 40.0), "{r:?}");
    assert_eq!(r.detected, [true; 6]);
    assert_eq!(r.false_flags, 0);
}

/// A driver with its own sample clock (100 Hz time stamps), at rest, whose
/// reads all fail from sample 2000 on.
struct StampedImu {
    n: u32,
}

impl imu_fdi::imu::Imu for StampedImu {
    type Error = ();
    fn read(&mut self) -> Result<imu_fdi::imu::ImuSample, ()> {
        self.n += 1;
        if self.n > 2000 {
            return Err(());
        }
        Ok(imu_fdi::imu::ImuSample {
            accel: [0.0, 0.0, -9.806_65 + 1e-3 * (self.n % 7) as f32],
            gyro: [1e-5 * (self.n % 5) as f32, 0.0, 0.0],
            temperature: 25.0,
            sequence: self.n,
            timestamp_us: Some(self.n.wrapping_mul(10_000)),
        })
    }
}

/// `dt` comes from the samples' time stamps, not from the caller (who says
/// 20 ms when the samples are 10 ms apart), and a dead IMU is reported as
/// `ImuUnavailable` with no channel monitored, not as a healthy verdict.
#[test]
fn sample_clock_and_unavailable_imu() {
    use imu_fdi::monitor::{ChannelState, UkfMonitorConfig};
    let cfg = UkfMonitorConfig::<f32>::auv();
    let settle = f64::from(cfg.converge_s + cfg.learn_s);
    let mut task = MonitorTask::new(StampedImu { n: 0 }, cfg).unwrap();
    let mut monitoring_at = None;
    let mut last = None;
    for k in 1..=2100u32 {
        let aiding = Measurement {
            z: MeasVec::zeros(),
            available: [k % 10 == 0; 6],
        };
        let r = task.step(0.02, &aiding);
        if r.phase == Phase::Monitoring && monitoring_at.is_none() {
            monitoring_at = Some(f64::from(k) * 0.01);
        }
        if k <= 2000 {
            assert_eq!(r.task_status, TaskStatus::Running);
        }
        last = Some(r);
    }
    // Aligned at the first aiding epoch (0.1 s), then converge + learn on
    // the sample clock.
    let t = monitoring_at.unwrap();
    assert!((t - 0.1 - settle).abs() < 0.1, "monitoring at {t} s");
    let r = last.unwrap();
    assert_eq!(r.task_status, TaskStatus::ImuUnavailable);
    assert_eq!(r.status, [ChannelState::NotMonitored; 6]);
    assert_eq!(r.missed_samples, 100);
    assert_eq!(r.consecutive_failures, 100);
}

/// A driver returning whatever sample the test put in its slot.
struct ReplayImu {
    sample: std::rc::Rc<core::cell::Cell<imu_fdi::imu::ImuSample>>,
}

impl imu_fdi::imu::Imu for ReplayImu {
    type Error = ();
    fn read(&mut self) -> Result<imu_fdi::imu::ImuSample, ()> {
        Ok(self.sample.get())
    }
}

/// GIVEN S2 with the IMU mounted upside down and yawed 90° on the vehicle
/// (ArduPilot `ROLL_180_YAW_90`), WHEN the task is told the mounting, THEN
/// every verdict and fault estimate is the one of a body-aligned IMU (to
/// f32 rounding), and without the mounting the monitor flags at once.
#[test]
fn a_rotated_board_gives_the_body_aligned_verdicts_once_its_mounting_is_set() {
    use imu_fdi::parity::euler_rotation;
    let scn = Scenario::s2();
    let board_to_body = euler_rotation(core::f32::consts::PI, 0.0, core::f32::consts::FRAC_PI_2);
    let body_to_board = board_to_body.transpose();
    let cfg = monitor_config(&scn, &RunOptions::default());
    let blank = imu_fdi::imu::ImuSample {
        accel: [0.0; 3],
        gyro: [0.0; 3],
        temperature: 25.0,
        sequence: 0,
        timestamp_us: None,
    };
    let slots: [std::rc::Rc<core::cell::Cell<_>>; 3] =
        core::array::from_fn(|_| std::rc::Rc::new(core::cell::Cell::new(blank)));
    let mut aligned = MonitorTask::with_monitor(
        ReplayImu {
            sample: slots[0].clone(),
        },
        imu_fdi::monitor::UkfMonitor::<f32>::new(cfg).unwrap(),
    );
    let mut rotated = MonitorTask::with_monitor(
        ReplayImu {
            sample: slots[1].clone(),
        },
        imu_fdi::monitor::UkfMonitor::<f32>::new(cfg).unwrap(),
    )
    .with_mounting(board_to_body)
    .unwrap();
    let mut unmounted = MonitorTask::with_monitor(
        ReplayImu {
            sample: slots[2].clone(),
        },
        imu_fdi::monitor::UkfMonitor::<f32>::new(cfg).unwrap(),
    );
    let (mut n, mut worst, mut differing, mut unmounted_flags) = (0u32, 0.0f32, 0u32, 0u32);
    for s in Simulator::new(&scn, 1) {
        let imu = s.imu.unwrap();
        let a = nalgebra::Vector3::new(imu[0] as f32, imu[1] as f32, imu[2] as f32);
        let g = nalgebra::Vector3::new(imu[3] as f32, imu[4] as f32, imu[5] as f32);
        let (ab, gb) = (body_to_board * a, body_to_board * g);
        n += 1;
        let body = imu_fdi::imu::ImuSample {
            accel: a.into(),
            gyro: g.into(),
            sequence: n,
            ..blank
        };
        let board = imu_fdi::imu::ImuSample {
            accel: ab.into(),
            gyro: gb.into(),
            sequence: n,
            ..blank
        };
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let m = Measurement {
            z,
            available: s.aiding_available,
        };
        let dt = s.dt as f32;
        slots[0].set(body);
        slots[1].set(board);
        slots[2].set(board);
        let (ra, rr, ru) = (
            aligned.step(dt, &m),
            rotated.step(dt, &m),
            unmounted.step(dt, &m),
        );
        if ra.status != rr.status {
            differing += 1;
        }
        for (x, y) in ra.fault_estimate.iter().zip(rr.fault_estimate.iter()) {
            worst = worst.max((x - y).abs());
        }
        if ru.status.iter().any(|c| c.sign().is_some()) {
            unmounted_flags += 1;
        }
    }
    assert_eq!(differing, 0);
    assert!(worst < 1e-3, "{worst}");
    assert!(rotated.mounting() == &board_to_body);
    // Not told the mounting, the monitor sees gravity upside down: flags.
    assert!(unmounted_flags > 1000, "{unmounted_flags}");
    // A reflection is not a mounting.
    let mirror = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0f32, 1.0, -1.0));
    let t = MonitorTask::with_monitor(
        ReplayImu {
            sample: slots[0].clone(),
        },
        imu_fdi::monitor::UkfMonitor::<f32>::new(cfg).unwrap(),
    );
    assert!(t.with_mounting(mirror).is_err());
}
