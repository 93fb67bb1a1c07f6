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
use imu_fdi::monitor::{MonitorTask, Phase};
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

/// The same task running the optimal two-stage UKF instead: S2 through the
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
