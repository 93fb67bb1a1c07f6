//! The `kfilter` 0.5 crate's unscented Kalman filter on the same 6-state
//! vehicle model and M2 (GNSS velocity + attitude) aiding as imu-fdi's
//! [`Ukf`], counted in instructions on the same emulated Cortex-M4F: the
//! outside reference issue 17 asks the budget to be compared with.
//!
//! kfilter is written on nalgebra 0.34 (imu-fdi on 0.35), so the model is
//! called through a copy of the six state components at each sigma point;
//! that copy is a few dozen instructions of a step of tens of thousands.
//! Both filters use α = 1, β = 2, κ = 0 and the model's `f32` trigonometry.

use imu_fdi::filter::{Gate, SigmaParams, Ukf};
use imu_fdi::model::{
    AidingKind, ImuVec, Mat6, MeasVec, MeasurementModel, StateVec, VehicleModel, STATE_ANGLES,
};
use kfilter::measurement::Measurement;
use kfilter::system::{NoInputSystem, System};
use kfilter::ukf::{UKFParameters, UnscentedKalman};
use kfilter::KalmanPredict;
use kfilter::KalmanUpdate;
use nalgebra as na;
use nalgebra034 as nb;

use crate::instructions;

type KVec = nb::SVector<f32, 6>;
type KMat = nb::SMatrix<f32, 6, 6>;

fn to_k(v: &StateVec<f32>) -> KVec {
    KVec::from_fn(|i, _| v.get(i).copied().unwrap_or(0.0))
}
fn from_k(v: &KVec) -> StateVec<f32> {
    StateVec::from_fn(|i, _| v.get(i).copied().unwrap_or(0.0))
}

/// The vehicle model as a kfilter system (input held in the system, as
/// kfilter's UKF with input would pass it: the same call either way).
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

/// M2 aiding as a kfilter measurement.
struct Aiding {
    z: KVec,
    r: KMat,
    model: MeasurementModel<f32>,
    omega: na::Vector3<f32>,
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
        let m = self.model.predict(&from_k(x), &self.omega);
        KVec::from_fn(|i, _| m.get(i).copied().unwrap_or(0.0))
    }
}

/// Mean instructions of one predict + update over `steps` steps, kfilter's
/// UKF and imu-fdi's [`Ukf`] (split predict, sigma-point update), from the
/// same state, covariance, input and measurement. `None` if either filter
/// refused to start or failed a step.
pub fn predict_update_costs(steps: u32) -> Option<(u32, u32)> {
    let model = VehicleModel::<f32>::default();
    let meas = MeasurementModel::<f32>::new(AidingKind::GnssAttitude);
    let x0 = StateVec::new(2.0, 0.1, -0.05, 0.05, 0.1, 1.0);
    let u = ImuVec::new(0.1, 0.2, -9.7, 0.01, 0.02, 0.05);
    let omega = na::Vector3::new(0.01f32, 0.02, 0.05);
    let dt = 0.01f32;
    let p0 = Mat6::<f32>::from_diagonal_element(1e-2);
    let q = Mat6::<f32>::from_diagonal_element(1e-6);
    let r = MeasVec::from_element(1e-4f32);
    let z = meas.predict(&(x0 + StateVec::from_element(0.01)), &omega);

    let system = Vehicle {
        x: to_k(&x0),
        q: KMat::from_diagonal_element(1e-6),
        model,
        u,
        dt,
    };
    let params = UKFParameters::new(1.0, 2.0, 0.0).ok()?;
    let mut kf = UnscentedKalman::<f32, 6, 0, 13, Vehicle>::new_custom_with_params(
        system,
        KMat::from_diagonal_element(1e-2),
        params,
    );
    let aiding = Aiding {
        z: KVec::from_fn(|i, _| z.get(i).copied().unwrap_or(0.0)),
        r: KMat::from_diagonal_element(1e-4),
        model: meas,
        omega,
    };
    let mut ours = Ukf::<f32, 6, 13>::new(x0, p0, &SigmaParams::default(), STATE_ANGLES)?;
    let mut gate = Gate::<f32, 6>::new(1e6, 2);
    let angles = [false, false, false, true, true, true];
    let (mut k_sum, mut o_sum) = (0u64, 0u64);
    for _ in 0..steps {
        let t0 = instructions();
        kf.predict().ok()?;
        kf.update(&aiding).ok()?;
        let t1 = instructions();
        ours.predict_split(
            &VehicleModel::<f32>::SPLIT_ORDER,
            VehicleModel::<f32>::NONLINEAR_STATES,
            |s| model.step(s, &u, dt),
            |d| model.step_deviation(d, &u, dt),
            &q,
        )
        .ok()?;
        ours.update(
            &z,
            &[true; 6],
            |s| Ok::<_, ()>(meas.predict(s, &omega)),
            &r,
            &angles,
            &mut gate,
        )
        .ok()?;
        let t2 = instructions();
        k_sum += u64::from(t1.wrapping_sub(t0));
        o_sum += u64::from(t2.wrapping_sub(t1));
    }
    let n = u64::from(steps.max(1));
    Some(((k_sum / n) as u32, (o_sum / n) as u32))
}
