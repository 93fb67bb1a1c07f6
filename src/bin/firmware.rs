//! imu-fdi firmware for an STM32F405 flight controller with an ICM-42688-P
//! on SPI1 (SCK PA5, MISO PA6, MOSI PA7, CS PA4), 8 MHz HSE, 168 MHz core.
//!
//! A hardware timer (TIM2) paces the monitor task at 100 Hz. The chip runs
//! at 1 kHz and is read through its FIFO ([`imu_fdi::imu::Icm42688Fifo`]):
//! each period the 10 samples it holds are integrated (delta angle / delta
//! velocity, coning and sculling corrected) and their average goes, with the
//! chip's own time stamps for `dt`, into [`imu_fdi::monitor::MonitorTask`]
//! (no point sampling: vibration above 50 Hz is averaged, not aliased). A
//! one-line report with the FIFO's overflow and loss counters is logged over
//! RTT with defmt once per second. Panics and HardFaults are reported and
//! stop.
//!
//! Aiding: this image is the bench build — the board is assumed at rest, so
//! zero body velocity and the accelerometer's levelling (roll, pitch; heading
//! held at 0) are fed as M1 aiding at 10 Hz. On a vehicle, replace
//! `bench_aiding` with the DVL/compass or GNSS receiver.
//!
//! Build: `cargo build-firmware`; flash and run with probe-rs:
//! `probe-rs run --chip STM32F405RGTx target/thumbv7em-none-eabihf/mcu/firmware`.
#![no_std]
#![no_main]

use cortex_m_rt::{entry, exception, ExceptionFrame};
use defmt_rtt as _;
use embedded_hal_bus::spi::{ExclusiveDevice, NoDelay};
use imu_fdi::imu::icm42688::{AccelRange, Config, GyroRange, Icm42688, Odr};
use imu_fdi::imu::Icm42688Fifo;
use imu_fdi::model::{MeasVec, Measurement};
use imu_fdi::monitor::{ConfigError, MonitorTask, UkfMonitorConfig};
use stm32f4xx_hal::{pac, prelude::*, rcc, spi::Mode};

const RATE_HZ: u32 = 100;
const AIDING_EVERY: u32 = 10;

/// The board's IMU: the ICM-42688-P's FIFO on SPI1, chip select PA4.
type BoardImu = Icm42688Fifo<
    ExclusiveDevice<
        stm32f4xx_hal::spi::Spi<pac::SPI1>,
        stm32f4xx_hal::gpio::Pin<'A', 4, stm32f4xx_hal::gpio::Output>,
        NoDelay,
    >,
>;

/// The monitor task with its configuration, constructed straight into
/// static RAM (the constructor's `Result` is the static) in a frame of its
/// own. Kept in `main`'s frame, the task (≈ 5 KB) and the temporaries of
/// its inlined construction stayed under every step for the firmware's
/// life: `main`'s frame was 10,680 B (`sub sp` in its prologue), now 1,072
/// (issue 17).
#[inline(never)]
fn new_task(imu: BoardImu) -> &'static mut MonitorTask<BoardImu> {
    let mut cfg = UkfMonitorConfig::<f32>::auv();
    cfg.imu_period = 1.0 / RATE_HZ as f32;
    let built = cortex_m::singleton!(
        : Result<MonitorTask<BoardImu>, ConfigError> = MonitorTask::new(imu, cfg)
    );
    match built {
        // Opaque to the optimiser: the monitor's methods address it
        // through their `self` pointer as before.
        Some(Ok(task)) => core::hint::black_box(task),
        Some(Err(e)) => defmt::panic!("monitor configuration: {}", e),
        None => defmt::panic!("monitor task constructed twice"),
    }
}

/// Bench aiding: at rest, velocity 0 and attitude from the accelerometer.
fn bench_aiding(accel: [f32; 3]) -> Measurement<f32> {
    let [ax, ay, az] = accel;
    // Specific force at rest is (g sinθ, −g cosθ sinφ, −g cosθ cosφ).
    let roll = libm::atan2f(-ay, -az);
    let pitch = libm::atan2f(ax, libm::sqrtf(ay * ay + az * az));
    Measurement {
        z: MeasVec::new(0.0, 0.0, 0.0, roll, pitch, 0.0),
        available: [true; 6],
    }
}

#[entry]
fn main() -> ! {
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        defmt::panic!("peripherals already taken");
    };
    let mut rcc = dp.RCC.freeze(rcc::Config::hse(8.MHz()).sysclk(168.MHz()));
    let sysclk = rcc.clocks.sysclk().raw() as f32;
    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();

    let gpioa = dp.GPIOA.split(&mut rcc);
    let sck = gpioa.pa5.into_alternate();
    let miso = gpioa.pa6.into_alternate();
    let mosi = gpioa.pa7.into_alternate();
    let cs = gpioa.pa4.into_push_pull_output();
    let bus = dp.SPI1.spi(
        (Some(sck), Some(miso), Some(mosi)),
        Mode::from(embedded_hal::spi::MODE_3),
        8.MHz(),
        &mut rcc,
    );
    // The HAL's output pin cannot fail (`Infallible`).
    let Ok(spi) = ExclusiveDevice::new_no_delay(bus, cs);
    let mut delay = dp.TIM5.delay_us(&mut rcc);
    let imu_cfg = Config {
        gyro_range: GyroRange::Dps2000,
        accel_range: AccelRange::G16,
        odr: Odr::Hz1000,
        ui_filter_bw: 1,
    };
    let dev = match Icm42688::new(spi, imu_cfg, &mut delay) {
        Ok(dev) => dev,
        Err(imu_fdi::imu::icm42688::Error::WrongDevice(id)) => {
            defmt::panic!("ICM-42688-P: WHO_AM_I = {=u8:#04x}", id)
        }
        Err(imu_fdi::imu::icm42688::Error::NoData) => defmt::panic!("ICM-42688-P: no data"),
        Err(imu_fdi::imu::icm42688::Error::Spi(_)) => defmt::panic!("ICM-42688-P: SPI bus error"),
    };
    // Watermark: the ODR samples of one monitor period (1 kHz / 100 Hz).
    let imu: BoardImu = match Icm42688Fifo::new(dev, (1000 / RATE_HZ) as u16) {
        Ok(imu) => imu,
        Err(_) => defmt::panic!("ICM-42688-P: FIFO configuration failed"),
    };
    let task = new_task(imu);

    let mut timer = dp.TIM2.counter_hz(&mut rcc);
    if timer.start(RATE_HZ.Hz()).is_err() {
        defmt::panic!("timer");
    }
    defmt::info!("imu-fdi: monitoring at {} Hz", RATE_HZ);
    let mut last = cortex_m::peripheral::DWT::cycle_count();
    let mut n: u32 = 0;
    let mut last_accel = [0.0f32, 0.0, -9.806_65];
    loop {
        // Sleep-free busy wait for the next period (the task owns the core).
        while timer.wait().is_err() {}
        let now = cortex_m::peripheral::DWT::cycle_count();
        let dt = now.wrapping_sub(last) as f32 / sysclk;
        last = now;
        let aiding = if n.is_multiple_of(AIDING_EVERY) {
            bench_aiding(last_accel)
        } else {
            Measurement::none()
        };
        let t0 = cortex_m::peripheral::DWT::cycle_count();
        let r = task.step(dt, &aiding);
        let cycles = cortex_m::peripheral::DWT::cycle_count().wrapping_sub(t0);
        if !r.read_failed {
            last_accel = [r.corrected[0], r.corrected[1], r.corrected[2]];
        }
        if n.is_multiple_of(RATE_HZ) {
            defmt::info!(
                "t={}s {} status={} fault={} health={} reads failed={} fifo={} step={} cycles",
                n / RATE_HZ,
                r.phase,
                r.status,
                r.fault_estimate,
                r.health,
                r.read_failures,
                task.imu().fifo_totals(),
                cycles
            );
        }
        n = n.wrapping_add(1);
    }
}

/// Panics (the `defmt::panic!`s above: a missing chip, a bad configuration)
/// log their location and stop at a breakpoint. The location only: formatting
/// the message, as `panic-probe` does, links `core::fmt`'s padding and
/// integer formatting (≈ 4 KB, issue 17) for messages defmt already printed.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    match info.location() {
        Some(l) => defmt::error!("panic at {=str}:{=u32}", l.file(), l.line()),
        None => defmt::error!("panic"),
    }
    loop {
        cortex_m::asm::bkpt();
    }
}

#[exception]
#[allow(unsafe_code)] // cortex-m-rt's HardFault handler signature is `unsafe fn`
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    defmt::error!("HardFault at pc {=u32:#010x}", ef.pc());
    loop {
        cortex_m::asm::bkpt();
    }
}
