//! Alignment from the first attitude (and velocity) measurement, shared by
//! every monitor.

use nalgebra::Vector3;

use crate::math::Real;
use crate::model::{Measurement, MeasurementModel, StateVec, VehicleModel, ROLL, YAW};

/// The initial state from one aiding epoch: attitude from the attitude
/// channels, body velocity from the velocity channels when present (rotated
/// into body axes and corrected for the lever arm with the body rate
/// `omega`), zero otherwise. `None` when the attitude is missing, not finite
/// or at the Euler singularity.
pub fn align_state<T: Real>(
    model: &VehicleModel<T>,
    meas: &MeasurementModel<T>,
    aiding: &Measurement<T>,
    omega: &Vector3<T>,
) -> Option<StateVec<T>> {
    let att = aiding
        .available
        .get(ROLL..=YAW)
        .is_some_and(|a| a.iter().all(|v| *v));
    if !att || !aiding.z.iter().skip(ROLL).all(|v| v.finite()) {
        return None;
    }
    let mut x = StateVec::zeros();
    x.fixed_rows_mut::<3>(ROLL)
        .copy_from(&aiding.z.fixed_rows::<3>(ROLL));
    model.check_attitude(&x).ok()?;
    let vel =
        aiding.available.iter().take(3).all(|v| *v) && aiding.z.iter().take(3).all(|v| v.finite());
    if vel {
        let v: Vector3<T> = aiding.z.fixed_rows::<3>(0).into_owned();
        let v_imu = meas.velocity_to_body(&x, &v) - omega.cross(&meas.lever_arm);
        x.fixed_rows_mut::<3>(0).copy_from(&v_imu);
    }
    Some(x)
}
