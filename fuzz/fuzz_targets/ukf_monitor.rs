//! The UKF innovation monitor under an arbitrary IMU / timing / aiding
//! attack, then valid input: finite outputs every step, back to nominal
//! 10 s after the attack (see `fuzz/src/lib.rs`).
#![no_main]

use std::sync::OnceLock;

use hal_sim::recovery::{clean_run, ukf_off_nominal};
use hal_sim::runner::{monitor_config, RunOptions};
use hal_sim::Scenario;
use imu_fdi::monitor::{Phase, UkfMonitor};
use imu_fdi_fuzz::{count, outputs_finite, single_imu, Base, StepResult};
use libfuzzer_sys::fuzz_target;

fn base(scn: Scenario) -> Base<UkfMonitor<f32>> {
    let cfg = monitor_config::<f32>(&scn, &RunOptions::default());
    let fresh = UkfMonitor::<f32>::new(cfg).unwrap();
    let run = clean_run(&scn, 1, 75.0);
    let mut monitor = fresh.clone();
    let start = run.iter().position(|s| s.t >= 12.0).unwrap();
    for s in &run[..start] {
        monitor.step(&s.imu, s.dt, &s.aiding);
    }
    assert_eq!(monitor.phase(), Phase::Monitoring);
    Base {
        monitor,
        fresh,
        run,
        start,
        full_scale: cfg.full_scale,
    }
}

fn step(m: &mut UkfMonitor<f32>, s: &hal_sim::recovery::Step) -> StepResult {
    let r = m.step(&s.imu, s.dt, &s.aiding);
    outputs_finite(&r, r.detail.t_statistic.iter())?;
    Ok((ukf_off_nominal(&r, m), r.phase == Phase::Monitoring))
}

static BASES: OnceLock<[Base<UkfMonitor<f32>>; 2]> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let bases = BASES.get_or_init(|| [base(Scenario::s2()), base(Scenario::s3())]);
    let which = usize::from(data.first().copied().unwrap_or(0) >> 1 & 1);
    count(single_imu(&bases[which], data, step));
});
