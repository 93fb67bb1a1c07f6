//! A custom IMU driver: implement [`imu_fdi::imu::Imu`] for your sensor and
//! the periodic [`MonitorTask`] reads it, checks its sequence counter for
//! missed samples, carries the elapsed time over failed reads and runs the
//! monitor. Here the "sensor" is a level, motionless vehicle with white
//! sensor noise (a noise-free, bit-identical output would rightly be
//! reported frozen), whose z gyro gains a 2 °/s bias after 20 s and whose
//! bus fails once.
//!
//! `cargo run --release --example custom_imu_driver`

use imu_fdi::imu::{Imu, ImuSample};
use imu_fdi::monitor::{ChannelState, MonitorTask, UkfMonitorConfig};
use imu_fdi::{MeasVec, Measurement};

/// A driver for an imaginary sensor: anything that yields SI samples in the
/// sensor's axes with a running sequence counter can be one.
struct StillVehicle {
    sequence: u32,
    /// State of the noise generator (xorshift32).
    noise: u32,
}

impl StillVehicle {
    /// Roughly normal noise of standard deviation `sigma` (sum of four
    /// uniforms), enough for an example.
    fn noise(&mut self, sigma: f32) -> f32 {
        let mut sum = 0.0;
        for _ in 0..4 {
            self.noise ^= self.noise << 13;
            self.noise ^= self.noise >> 17;
            self.noise ^= self.noise << 5;
            sum += self.noise as f32 / u32::MAX as f32 - 0.5;
        }
        sum * sigma * 3.0f32.sqrt()
    }
}

/// The imaginary bus's error.
#[derive(Debug)]
struct BusError;

impl Imu for StillVehicle {
    type Error = BusError;

    fn read(&mut self) -> Result<ImuSample, BusError> {
        self.sequence = self.sequence.wrapping_add(1);
        if self.sequence == 1500 {
            return Err(BusError);
        }
        let t = self.sequence as f32 * 0.01;
        let r_bias = if t > 20.0 { 2.0f32.to_radians() } else { 0.0 };
        // ICM-42688-P class noise at 100 Hz.
        let (sa, sg) = (0.01, 0.001);
        Ok(ImuSample {
            accel: [self.noise(sa), self.noise(sa), -9.806_65 + self.noise(sa)],
            gyro: [self.noise(sg), self.noise(sg), r_bias + self.noise(sg)],
            temperature: 25.0,
            sequence: self.sequence,
            timestamp_us: None,
        })
    }
}

fn main() -> Result<(), imu_fdi::monitor::ConfigError> {
    let mut task = MonitorTask::new(
        StillVehicle {
            sequence: 0,
            noise: 0x2545_f491,
        },
        UkfMonitorConfig::auv(),
    )?;
    let mut flagged_at = None;
    for k in 1..=4000u32 {
        // DVL velocity (zero: at rest) and compass attitude (level, north)
        // at 10 Hz; nothing in between.
        let available = k % 10 == 0;
        let aiding = Measurement {
            z: MeasVec::zeros(),
            available: [available; 6],
        };
        let report = task.step(0.01, &aiding);
        if flagged_at.is_none() && report.status[5] == ChannelState::FaultPositive {
            flagged_at = Some(k as f32 * 0.01);
        }
        if k % 1000 == 0 {
            println!(
                "t {:>4.1} s: {:?}, r {:?}, r fault estimate {:.2} °/s, read failures {}",
                k as f32 * 0.01,
                report.phase,
                report.status[5],
                report.fault_estimate[5].to_degrees(),
                report.read_failures
            );
        }
    }
    match flagged_at {
        Some(t) => println!("2 °/s bias on r from 20 s flagged at {t:.2} s"),
        None => println!("the r bias was not flagged"),
    }
    Ok(())
}
