//! The two-stage UKF monitor under an arbitrary IMU / timing / aiding
//! attack, then valid input: finite outputs every step, back to nominal
//! 10 s after the attack (see `fuzz/src/lib.rs`).
#![no_main]

use std::sync::OnceLock;

use hal_sim::ots::{otsukf_config, Setting};
use hal_sim::recovery::{clean_run, ots_off_nominal};
use hal_sim::Scenario;
use imu_fdi::monitor::{OtsukfMonitor, Phase};
use imu_fdi_fuzz::{count, outputs_finite, single_imu, Base, StepResult};
use libfuzzer_sys::fuzz_target;

fn base(scn: Scenario) -> Base<OtsukfMonitor<f32>> {
    let cfg = otsukf_config::<f32>(&scn, Setting::Realistic);
    let fresh = OtsukfMonitor::<f32>::new(cfg).unwrap();
    let run = clean_run(&scn, 1, 75.0);
    let mut monitor = fresh.clone();
    let start = run.iter().position(|s| s.t >= 12.0).unwrap();
    let mut phase = Phase::Aligning;
    for s in &run[..start] {
        phase = monitor.step(&s.imu, s.dt, &s.aiding).phase;
    }
    assert_eq!(phase, Phase::Monitoring);
    Base {
        monitor,
        fresh,
        run,
        start,
        full_scale: cfg.base.full_scale,
    }
}

fn step(m: &mut OtsukfMonitor<f32>, s: &hal_sim::recovery::Step) -> StepResult {
    let r = m.step(&s.imu, s.dt, &s.aiding);
    outputs_finite(&r, r.detail.fault_sigma.iter())?;
    Ok((ots_off_nominal(&r, m), r.phase == Phase::Monitoring))
}

static BASES: OnceLock<[Base<OtsukfMonitor<f32>>; 2]> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let bases = BASES.get_or_init(|| [base(Scenario::s2()), base(Scenario::s3())]);
    let which = usize::from(data.first().copied().unwrap_or(0) >> 1 & 1);
    count(single_imu(&bases[which], data, step));
});
