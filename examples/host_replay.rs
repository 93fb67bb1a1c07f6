//! Host replay: a simulated AUV run (scenario S2 of `hal-sim`, with its
//! injected faults) through the `f32` UKF innovation monitor, printing when
//! each channel is first flagged. The same loop replays a recorded log: feed
//! it the log's IMU rows and aiding instead of the simulator's.
//!
//! `cargo run --release --example host_replay`

use hal_sim::setup::{monitor_config, RunOptions};
use hal_sim::{Scenario, Simulator};
use imu_fdi::model::CHANNEL_NAMES;
use imu_fdi::monitor::{ChannelState, UkfMonitor};
use imu_fdi::{ImuVec, MeasVec, Measurement};

fn main() -> Result<(), imu_fdi::monitor::ConfigError> {
    let scenario = Scenario::s2();
    let mut monitor = UkfMonitor::<f32>::new(monitor_config(&scenario, &RunOptions::default()))?;
    let mut first_flag: [Option<f64>; 6] = [None; 6];
    for s in Simulator::new(&scenario, 1) {
        // A missing IMU sample is NaN: the monitor reports it and bridges the gap.
        let imu = s.imu.map_or(ImuVec::from_element(f32::NAN), |v| {
            ImuVec::from(v.map(|x| x as f32))
        });
        let aiding = Measurement {
            z: MeasVec::from(s.aiding.map(|x| x as f32)),
            available: s.aiding_available,
        };
        let report = monitor.step(&imu, s.dt as f32, &aiding);
        for (first, status) in first_flag.iter_mut().zip(report.status) {
            let faulty = matches!(
                status,
                ChannelState::FaultPositive | ChannelState::FaultNegative
            );
            if faulty && first.is_none() {
                *first = Some(s.t);
            }
        }
    }
    for (name, t) in CHANNEL_NAMES.iter().zip(first_flag) {
        match t {
            Some(t) => println!("{name}: first flagged at {t:.2} s"),
            None => println!("{name}: never flagged"),
        }
    }
    Ok(())
}
