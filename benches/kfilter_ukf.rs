//! Host cost of one UKF predict + update on the 6-state vehicle model with
//! M2 aiding (GNSS velocity + attitude), the `kfilter` 0.5 crate's UKF beside
//! imu-fdi's `Ukf` (split predict, sigma-point update), both `f32`, both
//! α = 1, β = 2, κ = 0: `cargo bench --bench kfilter_ukf`. The same pair is
//! counted in instructions on the emulated Cortex-M4F by
//! `scripts/qemu-sil.sh` (`qemu/src/kfilter_cmp.rs`).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing
)]

use criterion::{criterion_group, criterion_main, Criterion};
use imu_fdi::filter::{Gate, SigmaParams, Ukf};
use imu_fdi::model::{
    AidingKind, ImuVec, Mat6, MeasVec, MeasurementModel, StateVec, VehicleModel, STATE_ANGLES,
};
use kfilter::measurement::Measurement;
use kfilter::system::{NoInputSystem, System};
use kfilter::ukf::{UKFParameters, UnscentedKalman};
use kfilter::{KalmanPredict, KalmanUpdate};
use nalgebra034 as nb;

type KVec = nb::SVector<f32, 6>;
type KMat = nb::SMatrix<f32, 6, 6>;

fn to_k(v: &StateVec<f32>) -> KVec {
    KVec::from_column_slice(v.as_slice())
}
fn from_k(v: &KVec) -> StateVec<f32> {
    StateVec::from_column_slice(v.as_slice())
}

struct Vehicle {
    x: KVec,
    q: KMat,
    model: VehicleModel<f32>,
    u: ImuVec<f32>,
    dt: f32,
}

impl System<f32, 6, 0> for Vehicle {
    fn covariance(&self) -> &KMat {
        &self.q
    }
    fn state(&self) -> &KVec {
        &self.x
    }
    fn state_mut(&mut self) -> &mut KVec {
        &mut self.x
    }
}

impl NoInputSystem<f32, 6> for Vehicle {
    fn predict(&self, x: &KVec) -> KVec {
        let s = from_k(x);
        to_k(&self.model.step(&s, &self.u, self.dt).unwrap_or(s))
    }
}

struct Aiding {
    z: KVec,
    r: KMat,
    model: MeasurementModel<f32>,
    omega: nalgebra::Vector3<f32>,
}

impl Measurement<f32, 6, 6> for Aiding {
    fn covariance(&self) -> &KMat {
        &self.r
    }
    fn measurement(&self) -> &KVec {
        &self.z
    }
    fn set_measurement(&mut self, z: KVec) {
        self.z = z;
    }
    fn predict(&self, x: &KVec) -> KVec {
        KVec::from_column_slice(self.model.predict(&from_k(x), &self.omega).as_slice())
    }
}

fn benches(c: &mut Criterion) {
    let model = VehicleModel::<f32>::default();
    let meas = MeasurementModel::<f32>::new(AidingKind::GnssAttitude);
    let x0 = StateVec::new(2.0, 0.1, -0.05, 0.05, 0.1, 1.0);
    let u = ImuVec::new(0.1, 0.2, -9.7, 0.01, 0.02, 0.05);
    let omega = nalgebra::Vector3::new(0.01f32, 0.02, 0.05);
    let dt = 0.01f32;
    let p0 = Mat6::<f32>::from_diagonal_element(1e-2);
    let q = Mat6::<f32>::from_diagonal_element(1e-6);
    let r = MeasVec::from_element(1e-4f32);
    let z = meas.predict(&(x0 + StateVec::from_element(0.01)), &omega);

    let mut g = c.benchmark_group("ukf_predict_update_m2_f32");
    g.sample_size(50);
    let system = Vehicle {
        x: to_k(&x0),
        q: KMat::from_diagonal_element(1e-6),
        model,
        u,
        dt,
    };
    let mut kf = UnscentedKalman::<f32, 6, 0, 13, Vehicle>::new_custom_with_params(
        system,
        KMat::from_diagonal_element(1e-2),
        UKFParameters::new(1.0, 2.0, 0.0).unwrap(),
    );
    let aiding = Aiding {
        z: KVec::from_column_slice(z.as_slice()),
        r: KMat::from_diagonal_element(1e-4),
        model: meas,
        omega,
    };
    g.bench_function("kfilter 0.5", |b| {
        b.iter(|| {
            kf.predict().unwrap();
            std::hint::black_box(kf.update(&aiding).unwrap());
        })
    });
    let mut ours = Ukf::<f32, 6, 13>::new(x0, p0, &SigmaParams::default(), STATE_ANGLES).unwrap();
    let mut gate = Gate::<f32, 6>::new(1e6, 2);
    let angles = [false, false, false, true, true, true];
    g.bench_function("imu-fdi Ukf", |b| {
        b.iter(|| {
            ours.predict_split(
                &VehicleModel::<f32>::SPLIT_ORDER,
                VehicleModel::<f32>::NONLINEAR_STATES,
                |s| model.step(s, &u, dt),
                |d| model.step_deviation(d, &u, dt),
                &q,
            )
            .unwrap();
            let out = ours
                .update(
                    &z,
                    &[true; 6],
                    |s| Ok::<_, ()>(meas.predict(s, &omega)),
                    &r,
                    &angles,
                    &mut gate,
                )
                .unwrap();
            std::hint::black_box(out);
        })
    });
    g.finish();
}

criterion_group!(kfilter_ukf, benches);
criterion_main!(kfilter_ukf);
