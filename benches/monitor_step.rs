//! Host cost of one `UkfMonitor::step` (f32 and f64) on recorded S2 inputs:
//! the whole 65 s run is stepped per iteration and the time per step reported.
//! `cargo bench --bench monitor_step`. (Instruction counts on the Cortex-M4F
//! are the MCU issue's benchmark.)
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing
)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use hal_sim::runner::{monitor_config, RunOptions};
use hal_sim::{Scenario, Simulator};
use imu_fdi::math::Real;
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::UkfMonitor;

fn inputs<T: Real>(scn: &Scenario) -> Vec<(ImuVec<T>, Measurement<T>)> {
    Simulator::new(scn, 1)
        .map(|s| {
            let u = ImuVec::from_fn(|i, _| T::lit(s.imu.map_or(f64::NAN, |v| v[i])));
            let z = MeasVec::from_fn(|i, _| T::lit(s.aiding[i]));
            (
                u,
                Measurement {
                    z,
                    available: s.aiding_available,
                },
            )
        })
        .collect()
}

fn bench_precision<T: Real>(c: &mut Criterion, name: &str) {
    let scn = Scenario::s2();
    let cfg = monitor_config::<T>(&scn, &RunOptions::default());
    let data = inputs::<T>(&scn);
    let mut g = c.benchmark_group(name);
    g.throughput(Throughput::Elements(data.len() as u64));
    g.sample_size(20);
    g.bench_function("s2 run, per step", |b| {
        b.iter(|| {
            let mut m = UkfMonitor::<T>::new(cfg).unwrap();
            let mut flagged = 0usize;
            for (u, z) in &data {
                let r = m.step(u, T::lit(0.01), z);
                flagged += usize::from(r.status.iter().any(|s| s.sign().is_some_and(|v| v != 0)));
            }
            std::hint::black_box(flagged)
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_precision::<f32>(c, "monitor_step_f32");
    bench_precision::<f64>(c, "monitor_step_f64");
}

criterion_group!(monitor, benches);
criterion_main!(monitor);
