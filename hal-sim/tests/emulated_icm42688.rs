//! The real ICM-42688-P driver, unchanged, against hal-sim's register-level
//! emulated chip: identity, configuration, scaling, no-data, bus errors, and
//! scenario S2 fed through chip + driver into the monitor; the FIFO path
//! (watermark, averaging, overflow → status and counted losses, recovery).
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
use hal_sim::setup::DetectionTally;
use hal_sim::{Scenario, Simulator};
use imu_fdi::imu::fifo::{Icm42688Fifo, FIFO_PACKETS};
use imu_fdi::imu::icm42688::{AccelRange, Config, Error, GyroRange, Icm42688, Odr};
use imu_fdi::imu::Imu;
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::{MonitorTask, TaskStatus, UkfMonitor, UkfMonitorConfig};

fn auv_config() -> Config {
    Config {
        gyro_range: GyroRange::Dps250,
        accel_range: AccelRange::G4,
        odr: Odr::Hz100,
        ui_filter_bw: 1,
    }
}

#[test]
fn driver_talks_to_the_emulated_chip() {
    let chip = RefCell::new(EmulatedIcm42688::new());
    let mut dev = Icm42688::new(SharedBus(&chip), auv_config(), &mut NoopDelay::new()).unwrap();
    // Sensors on but no sample yet: the chip's "no data" value.
    assert_eq!(dev.read(), Err(Error::NoData));
    chip.borrow_mut()
        .set_sample([0.1, -0.2, -9.80665], [0.01, -0.02, 0.5], 31.0);
    let s = dev.read().unwrap();
    let alsb = 4.0 * 9.80665 / 32768.0;
    let glsb = 250f32.to_radians() / 32768.0;
    assert!((s.accel[2] + 9.80665).abs() <= alsb);
    assert!((s.accel[0] - 0.1).abs() <= alsb);
    assert!((s.gyro[2] - 0.5).abs() <= glsb);
    assert!((s.temperature - 31.0).abs() < 0.01);
    // Saturation at full scale, never the reserved −32768.
    chip.borrow_mut()
        .set_sample([0.0, 0.0, -100.0], [0.0, 0.0, -10.0], 25.0);
    let s = dev.read().unwrap();
    assert!((s.accel[2] + 4.0 * 9.80665).abs() < 2.0 * alsb);
    assert!((s.gyro[2] + 250f32.to_radians()).abs() < 2.0 * glsb);
    // Injected bus errors are typed, and the next read recovers.
    chip.borrow_mut().fail_next(2);
    assert!(matches!(dev.read(), Err(Error::Spi(_))));
    assert!(matches!(dev.read(), Err(Error::Spi(_))));
    assert!(dev.read().is_ok());
}

#[test]
fn wrong_chip_is_refused() {
    // A chip that does not answer (all transactions fail) never configures.
    let chip = RefCell::new(EmulatedIcm42688::new());
    chip.borrow_mut().fail_next(1);
    assert!(matches!(
        Icm42688::new(SharedBus(&chip), auv_config(), &mut NoopDelay::new()),
        Err(Error::Spi(_))
    ));
}

/// S2 through emulated chip → driver → monitor detects every fault, within
/// one aiding interval of the direct path (the chip re-quantises at the
/// same LSB the simulator already applied; f32 rounding of the two paths
/// differs in the last bit).
#[test]
fn s2_through_the_emulated_chip_matches_the_direct_path() {
    let scn = Scenario::s2();
    let cfg = monitor_config::<f32>(&scn, &RunOptions::default());
    let chip = RefCell::new(EmulatedIcm42688::new());
    let mut dev = Icm42688::new(SharedBus(&chip), auv_config(), &mut NoopDelay::new()).unwrap();
    let mut via_chip = UkfMonitor::<f32>::new(cfg).unwrap();
    let mut direct = UkfMonitor::<f32>::new(cfg).unwrap();
    let (mut tally_chip, mut tally_direct) = (DetectionTally::new(&scn), DetectionTally::new(&scn));
    for s in Simulator::new(&scn, 1) {
        let imu = s.imu.unwrap();
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let m = Measurement {
            z,
            available: s.aiding_available,
        };
        chip.borrow_mut()
            .set_sample([imu[0], imu[1], imu[2]], [imu[3], imu[4], imu[5]], 25.0);
        let sample = dev.read().unwrap();
        let r = via_chip.step(&ImuVec::from(sample.channels()), s.dt as f32, &m);
        tally_chip.record(&s, &r);
        let r = direct.step(&ImuVec::from_fn(|i, _| imu[i] as f32), s.dt as f32, &m);
        tally_direct.record(&s, &r);
    }
    let mut a = Vec::new();
    let mut b = Vec::new();
    tally_chip.print(|l| a.push(l.to_string()));
    tally_direct.print(|l| b.push(l.to_string()));
    println!("via chip:\n{}\ndirect:\n{}", a.join("\n"), b.join("\n"));
    assert!(tally_chip.all_detected());
    assert_eq!(tally_chip.counts(), tally_direct.counts());
    for (x, y) in tally_chip
        .first_detections()
        .iter()
        .zip(tally_direct.first_detections().iter())
    {
        assert!(
            (x.unwrap() - y.unwrap()).abs() <= 0.2 + 1e-9,
            "{x:?} vs {y:?}"
        );
    }
}

// ---- The FIFO path: full-ODR packets, watermark, overflow, recovery ----

fn fifo_config() -> Config {
    Config {
        gyro_range: GyroRange::Dps2000,
        accel_range: AccelRange::G16,
        odr: Odr::Hz1000,
        ui_filter_bw: 1,
    }
}

/// 20 packets per read: a 50 Hz monitor on a 1 kHz chip.
const WM: u16 = 20;

fn fifo_driver(chip: &RefCell<EmulatedIcm42688>) -> Icm42688Fifo<SharedBus<'_>> {
    let dev = Icm42688::new(SharedBus(chip), fifo_config(), &mut NoopDelay::new()).unwrap();
    Icm42688Fifo::new(dev, WM).unwrap()
}

/// A slowly varying sample k (distinct values to check the average).
fn sample(k: u32) -> ([f64; 3], [f64; 3]) {
    let x = f64::from(k % 50) * 0.01;
    ([0.2 + x, -0.1, -9.80665 + x], [0.05 + 0.1 * x, -0.02, 0.3])
}

#[test]
fn fifo_average_and_watermark() {
    let chip = RefCell::new(EmulatedIcm42688::new());
    let mut dev = fifo_driver(&chip);
    // Nothing sampled yet: no data, said so (not a stale value).
    assert_eq!(dev.read(), Err(Error::NoData));
    let mut k = 0;
    for _ in 0..WM - 1 {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 30.0);
        k += 1;
    }
    let s = dev.read().unwrap();
    let st = *dev.fifo_status();
    assert_eq!((st.count, st.samples), (WM - 1, WM - 1));
    assert!(!st.watermark_reached && !st.overflowed);
    // The average of the samples, within the quantisation of the counts.
    let mean = |f: &dyn Fn(u32) -> f64, n: u32, from: u32| {
        (from..from + n).map(f).sum::<f64>() / f64::from(n)
    };
    let ax = mean(&|k| sample(k).0[0], u32::from(WM) - 1, 0);
    let gx = mean(&|k| sample(k).1[0], u32::from(WM) - 1, 0);
    let alsb = 16.0 * 9.80665 / 32768.0;
    let glsb = 2000f64.to_radians() / 32768.0;
    assert!(
        (f64::from(s.accel[0]) - ax).abs() < alsb,
        "{} vs {ax}",
        s.accel[0]
    );
    assert!(
        (f64::from(s.gyro[0]) - gx).abs() < glsb,
        "{} vs {gx}",
        s.gyro[0]
    );
    assert!((s.temperature - 30.0).abs() < 0.5);
    assert_eq!(s.timestamp_us, Some(19_000));
    for _ in 0..WM {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 30.0);
        k += 1;
    }
    let s2 = dev.read().unwrap();
    let st = *dev.fifo_status();
    assert_eq!((st.count, st.samples, st.packets_lost), (WM, WM, 0));
    assert!(st.watermark_reached && !st.overflowed);
    assert_eq!(s2.sequence, s.sequence + 1);
    assert_eq!(s2.timestamp_us, Some(39_000));
}

/// A reader that stalls for 300 ms: the 128-packet FIFO (stop-on-full)
/// overflows; the driver says so on the next read, counts the samples the
/// chip dropped from its time stamps (checked against the emulator's
/// ground truth), the task counts the missed periods, and the following
/// reads are normal again.
#[test]
fn slow_reader_overflow_is_reported_counted_and_recovered() {
    let chip = RefCell::new(EmulatedIcm42688::new());
    let dev = fifo_driver(&chip);
    let mut task = MonitorTask::new(dev, UkfMonitorConfig::auv()).unwrap();
    let feed = |n: u32, k: &mut u32| {
        for _ in 0..n {
            let (a, g) = sample(*k);
            chip.borrow_mut().sample_odr(a, g, 25.0);
            *k += 1;
        }
    };
    let mut k = 0;
    for _ in 0..5 {
        feed(u32::from(WM), &mut k);
        let r = task.step(0.02, &imu_fdi::Measurement::none());
        assert_eq!(r.task_status, TaskStatus::Running);
    }
    assert_eq!(task.imu().fifo_status().packets_lost, 0);
    // Stall: 300 samples arrive, the FIFO holds 128.
    feed(300, &mut k);
    let dropped = chip.borrow().fifo_dropped();
    assert_eq!(dropped, 300 - FIFO_PACKETS as u64);
    let r = task.step(0.3, &imu_fdi::Measurement::none());
    assert_eq!(r.task_status, TaskStatus::Running);
    let st = *task.imu().fifo_status();
    assert!(st.overflowed, "{st:?}");
    assert_eq!(usize::from(st.samples), FIFO_PACKETS);
    // The loss is seen at the first packet after the gap.
    feed(u32::from(WM), &mut k);
    let r = task.step(0.02, &imu_fdi::Measurement::none());
    let st = *task.imu().fifo_status();
    assert_eq!(u64::from(st.packets_lost), dropped, "{st:?}");
    assert!(!st.overflowed);
    // 172 lost samples = 8 whole 20-sample periods: missed by the task.
    assert_eq!(r.missed_samples, 172 / u32::from(WM));
    let totals = *task.imu().fifo_totals();
    assert_eq!(
        (totals.overflows, u64::from(totals.packets_lost)),
        (1, dropped)
    );
    // Recovery: normal periods, nothing lost, nothing more missed.
    for _ in 0..5 {
        feed(u32::from(WM), &mut k);
        let r2 = task.step(0.02, &imu_fdi::Measurement::none());
        let st = *task.imu().fifo_status();
        assert_eq!((st.samples, st.packets_lost), (WM, 0));
        assert!(!st.overflowed);
        assert_eq!(r2.missed_samples, r.missed_samples);
    }
}

/// Stream-to-FIFO mode (set by hand: the driver uses stop-on-full) keeps
/// the newest 128 packets; the driver counts the oldest ones dropped.
#[test]
fn stream_mode_overflow_drops_the_oldest_and_is_counted() {
    let chip = RefCell::new(EmulatedIcm42688::new());
    let mut dev = fifo_driver(&chip);
    dev.device().write_register(0x16, 0x40).unwrap();
    let mut k = 0;
    for _ in 0..WM {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 25.0);
        k += 1;
    }
    dev.read().unwrap();
    for _ in 0..200 {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 25.0);
        k += 1;
    }
    dev.read().unwrap();
    let st = *dev.fifo_status();
    assert!(st.overflowed);
    assert_eq!(usize::from(st.samples), FIFO_PACKETS);
    assert_eq!(u64::from(st.packets_lost), chip.borrow().fifo_dropped());
    assert_eq!(st.packets_lost, 200 - FIFO_PACKETS as u32);
}

#[test]
fn no_data_packets_and_a_misaligned_stream_are_reported() {
    let chip = RefCell::new(EmulatedIcm42688::new());
    let mut dev = fifo_driver(&chip);
    // Sensors off: packets carry −32768: counted, not integrated.
    dev.device().write_register(0x4E, 0).unwrap();
    for k in 0..5 {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 25.0);
    }
    assert_eq!(dev.read(), Err(Error::NoData));
    assert_eq!(dev.fifo_status().invalid_packets, 5);
    dev.device().write_register(0x4E, 0x0F).unwrap();
    for k in 0..5 {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 25.0);
    }
    // Someone reads 3 bytes of the FIFO behind the driver's back.
    let mut junk = [0u8; 3];
    dev.device().read_registers(0x30, &mut junk).unwrap();
    let _ = dev.read();
    let st = *dev.fifo_status();
    assert!(st.resynchronised && st.invalid_packets >= 1, "{st:?}");
    assert_eq!(chip.borrow().fifo_bytes(), 0);
    // Aligned again afterwards.
    for k in 0..5 {
        let (a, g) = sample(k);
        chip.borrow_mut().sample_odr(a, g, 25.0);
    }
    assert!(dev.read().is_ok());
    assert_eq!(dev.fifo_status().samples, 5);
    assert_eq!(dev.fifo_totals().resyncs, 1);
}

/// S2 (AUV, 100 Hz) through the FIFO path: each simulated sample is held
/// for the 10 samples a 1 kHz chip produces in the period, the FIFO driver
/// integrates them back into the period's average, the monitor steps on it
/// with the chip's time stamps for `dt`. Detections match the direct path
/// (the average of 10 equal quantised samples is that sample up to f32
/// rounding).
#[test]
fn s2_through_the_fifo_path_matches_the_direct_path() {
    let scn = Scenario::s2();
    let cfg = monitor_config::<f32>(&scn, &RunOptions::default());
    let chip = RefCell::new(EmulatedIcm42688::new());
    let dev = Icm42688::new(
        SharedBus(&chip),
        Config {
            odr: Odr::Hz1000,
            ..auv_config()
        },
        &mut NoopDelay::new(),
    )
    .unwrap();
    let mut fifo: Icm42688Fifo<_> = Icm42688Fifo::new(dev, 10).unwrap();
    let mut via_fifo = UkfMonitor::<f32>::new(cfg).unwrap();
    let mut direct = UkfMonitor::<f32>::new(cfg).unwrap();
    let (mut tally_fifo, mut tally_direct) = (DetectionTally::new(&scn), DetectionTally::new(&scn));
    let mut last_ts = None;
    for s in Simulator::new(&scn, 1) {
        let imu = s.imu.unwrap();
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let m = Measurement {
            z,
            available: s.aiding_available,
        };
        for _ in 0..10 {
            chip.borrow_mut()
                .sample_odr([imu[0], imu[1], imu[2]], [imu[3], imu[4], imu[5]], 25.0);
        }
        let sample = fifo.read().unwrap();
        assert_eq!(fifo.fifo_status().samples, 10);
        let ts = sample.timestamp_us.unwrap();
        let dt = last_ts.map_or(s.dt as f32, |p: u32| ts.wrapping_sub(p) as f32 * 1e-6);
        last_ts = Some(ts);
        assert!((f64::from(dt) - s.dt).abs() < 1e-6, "{dt} vs {}", s.dt);
        let r = via_fifo.step(&ImuVec::from(sample.channels()), dt, &m);
        tally_fifo.record(&s, &r);
        let r = direct.step(&ImuVec::from_fn(|i, _| imu[i] as f32), s.dt as f32, &m);
        tally_direct.record(&s, &r);
    }
    assert!(tally_fifo.all_detected());
    assert_eq!(tally_fifo.counts(), tally_direct.counts());
    for (x, y) in tally_fifo
        .first_detections()
        .iter()
        .zip(tally_direct.first_detections().iter())
    {
        assert!(
            (x.unwrap() - y.unwrap()).abs() <= 0.2 + 1e-9,
            "{x:?} vs {y:?}"
        );
    }
}
