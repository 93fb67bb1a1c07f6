//! The real ICM-42688-P driver, unchanged, against hal-sim's register-level
//! emulated chip: identity, configuration, scaling, no-data, bus errors, and
//! scenario S2 fed through chip + driver into the monitor.
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
use imu_fdi::imu::icm42688::{AccelRange, Config, Error, GyroRange, Icm42688, Odr};
use imu_fdi::imu::Imu;
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::UkfMonitor;

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
