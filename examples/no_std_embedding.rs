//! Embedding in firmware: everything below uses `core` only (no `std`, no
//! allocation) — the monitor lives in a `static`-friendly struct sized at
//! compile time, and `step` never allocates or panics. On a board the loop
//! body runs in the IMU data-ready interrupt or a periodic task; this
//! example's `main` merely drives it on the host. See `src/bin/firmware.rs`
//! for the full STM32F405 + ICM-42688-P firmware.
//!
//! `cargo run --release --example no_std_embedding`

use imu_fdi::monitor::{ChannelState, Report, UkfMonitor, UkfMonitorConfig};
use imu_fdi::{ImuVec, MeasVec, Measurement};

/// The firmware's state: one monitor with a 10-epoch window, in `f32` (the
/// Cortex-M4F's FPU), of a size known at compile time.
struct Firmware {
    monitor: UkfMonitor<f32, 10>,
}

impl Firmware {
    fn new() -> Option<Self> {
        let mut cfg = UkfMonitorConfig::auv();
        cfg.imu_period = 0.01;
        // `validate` names the offending field; on a board, log it.
        Some(Self {
            monitor: UkfMonitor::new(cfg).ok()?,
        })
    }

    /// One IMU period: `imu` in `[a_x, a_y, a_z, p, q, r]` (SI units), the
    /// measured `dt`, and the aiding that arrived. Returns whether any
    /// channel is faulty, for a LED or a failover.
    fn on_sample(&mut self, imu: [f32; 6], dt: f32, aiding: Option<[f32; 6]>) -> bool {
        let aiding = match aiding {
            Some(z) => Measurement {
                z: MeasVec::from(z),
                available: [true; 6],
            },
            None => Measurement {
                z: MeasVec::zeros(),
                available: [false; 6],
            },
        };
        let report: Report<f32> = self.monitor.step(&ImuVec::from(imu), dt, &aiding);
        report
            .status
            .iter()
            .any(|s| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative))
    }
}

fn main() {
    let Some(mut fw) = Firmware::new() else {
        return;
    };
    println!(
        "monitor state: {} bytes, no heap",
        core::mem::size_of::<Firmware>()
    );
    let mut any_fault = false;
    for k in 1..=2000u32 {
        // A level vehicle at rest with a little sensor jitter (a
        // bit-identical output would rightly be reported frozen).
        let jitter = ((k * 7919) % 13) as f32 - 6.0;
        let imu = [
            1e-3 * jitter,
            -1e-3 * jitter,
            -9.806_65 + 1e-3 * jitter,
            1e-4 * jitter,
            -1e-4 * jitter,
            1e-4 * jitter,
        ];
        let aiding = (k % 10 == 0).then_some([0.0; 6]);
        any_fault |= fw.on_sample(imu, 0.01, aiding);
    }
    println!("20 s at rest, fault flagged: {any_fault}");
}
