//! The UKF the monitor runs each period: the predict with the closed-loop
//! fault sensitivity `X ← X + (A X + B) dt`, and the aiding update (with
//! the heading-offset and latency corrections) that records each
//! channel's innovation, signature row `−H X` and window sample, then
//! `X ← (I − K H) X`.

use nalgebra::Vector3;

use super::{UkfMonitor, MEAS_ANGLES};
use crate::detect::Statistic;
use crate::filter::UkfError;
use crate::math::{sub_product, Real};
use crate::model::{
    discrete_process_noise_structured, ImuVec, Mat6, Measurement, ModelError, VehicleModel,
};
use crate::monitor::input::usable_aiding;

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn predict(&mut self, u: &ImuVec<T>, dt: T) -> Result<bool, ModelError> {
        let x = *self.ukf.state();
        let trig = self.model.attitude_trig(&x)?;
        let (a, b) = self.model.jacobians(&x, u, &trig);
        let q = discrete_process_noise_structured(&a, &b, &self.cfg.process_noise, dt);
        let model = self.model;
        let reset = match self.ukf.predict_split(
            &VehicleModel::<T>::SPLIT_ORDER,
            VehicleModel::<T>::NONLINEAR_STATES,
            // The sigma points' attitude trigonometry shifted from the mean's.
            |s| model.step_near(s, &x, &trig, u, dt),
            |d| model.step_deviation(d, u, dt),
            &q,
        ) {
            Ok(()) => false,
            Err(UkfError::CovarianceReset(_)) => true,
            Err(UkfError::Model(e)) => return Err(e),
            Err(_) => return Err(ModelError::NonFinite),
        };
        // First-order transition `Φ ≈ I + A dt` for the sensitivity: the
        // second-order term changes X by < 1e-3 relative per step (largest
        // entry of A² dt²/2 ≈ g·ω·dt² against g·dt) and X is re-anchored by
        // every update, while it saves a 6×6 product per IMU period.
        // X ← X + (A X + B) dt: one scaling by dt instead of two.
        self.sensitivity += (VehicleModel::mul_state_jacobian(&a, &self.sensitivity) + b) * dt;
        if self.tracking_on() && self.tracker.active {
            // The same first-order transition, for the fault's state
            // deviation between aiding epochs.
            self.tracker.advance(&a, dt);
        }
        self.last_input_at = Some((x, trig));
        // The state history serves a configured or estimated aiding latency.
        if self.keeps_history() {
            self.history.write(*self.ukf.state());
            self.history_fresh = self.history_fresh.saturating_add(1);
            self.delay_estimator.tick();
            self.heading.tick();
        }
        Ok(reset)
    }

    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn update(
        &mut self,
        aiding: &Measurement<T>,
        omega: &Vector3<T>,
    ) -> Result<(bool, bool), UkfError<ModelError>> {
        // An offset step first turns the filter's heading with the aiding
        // (`heading.rs`), so the step itself is no innovation.
        if self.heading_on() {
            self.learn_heading_offset(aiding, omega);
        }
        let x_prior = *self.ukf.state();
        // M1's Jacobian is the identity (`MeasurementModel::jacobian`).
        let affine = self.m1();
        let h = if affine {
            Mat6::identity()
        } else {
            self.meas.jacobian(&x_prior, omega)
        };
        let r = self.cfg.meas_sigma.component_mul(&self.cfg.meas_sigma);
        let meas = self.meas;
        let corrected;
        let aiding = if self.heading_on() {
            corrected = self.correct_heading(aiding);
            &corrected
        } else {
            aiding
        };
        let available = usable_aiding(aiding);
        if self.delay_on() {
            self.estimate_delay(aiding, &available, omega);
        }
        // With a known latency, predict the measurement from the state of its
        // time (the history holds one state per IMU step, newest last).
        let delayed = if self.delay_steps > 0 {
            self.history_at(self.delay_steps)
        } else {
            None
        };
        // Centred on the current state this is the ordinary update.
        let center = delayed.unwrap_or(x_prior);
        // A velocity with its own latency, brought to that horizon
        // (`velocity_delay.rs`).
        let translated;
        let aiding = match self.velocity_at_horizon(aiding, &center, omega) {
            Some(t) => {
                translated = t;
                &translated
            }
            None => aiding,
        };
        // Both forms with the same (infallible-model) error type: one
        // `Result` slot, and the output read where the update left it, not
        // moved into the caller's error type (a 380-byte copy, issue 17).
        let res = if affine {
            self.ukf.update_identity(
                &meas.predict(&center, omega),
                &aiding.z,
                &available,
                &r,
                &MEAS_ANGLES,
                &mut self.gate,
            )
        } else {
            // M2 is affine in the body velocity given the attitude: the split
            // update maps those sigma points through the Jacobian at the
            // centre (7 evaluations of `h` instead of 13, issue 17).
            let (order, nonlinear) = meas.split();
            let h_center = if delayed.is_some() {
                meas.jacobian(&center, omega)
            } else {
                h
            };
            self.ukf.update_split(
                &center,
                &order,
                nonlinear,
                &aiding.z,
                &available,
                |s| Ok::<_, core::convert::Infallible>(meas.predict(s, omega)),
                &h_center,
                &r,
                &MEAS_ANGLES,
                &mut self.gate,
            )
        };
        let out = match &res {
            Ok(o) => o,
            Err(e) => return Err(e.widen()),
        };
        // M1's Jacobian is the identity: skip the product, and the copy
        // (`H X` is read in place).
        let hx_m2 = if affine {
            None
        } else {
            Some(h * self.sensitivity)
        };
        let hx = hx_m2.as_ref().unwrap_or(&self.sensitivity);
        let record = self.stats_holdoff <= T::zero();
        // The tracker's epoch is staged here and run by the next step
        // (`FaultTracker::begin_epoch`, issue 17).
        let track = self.tracking_on() && self.tracker.active;
        if track {
            self.tracker
                .begin_epoch(&self.sensitivity, self.cfg.gate_sigma);
        }
        let mut rejected = false;
        for (i, d) in out.diag.iter().enumerate() {
            if !d.available {
                continue;
            }
            rejected |= !d.fused;
            if let Some(n) = self.rejection_run.get_mut(i) {
                *n = if d.fused { 0 } else { n.saturating_add(1) };
            }
            if d.fused {
                if let Some(s) = self.since_fused.get_mut(i) {
                    *s = T::zero();
                }
            }
            if let Some(s) = self.since_seen.get_mut(i) {
                *s = T::zero();
            }
            let row = -hx.row(i);
            self.signature.set_row(i, &row);
            if let Some(v) = self.latest_innovation.get_mut(i) {
                *v = d.innovation;
            }
            if let Some(v) = self.latest_variance.get_mut(i) {
                *v = d.variance;
            }
            if record && d.fused {
                let v = match self.statistic() {
                    Statistic::Raw => d.innovation,
                    Statistic::Whitened | Statistic::Normalized => {
                        d.innovation / d.variance.sqrt_fast()
                    }
                };
                if let Some(w) = self.windows.get_mut(i) {
                    w.push(v);
                }
            }
        }
        if track && record {
            self.tracker.observe_all(&out.diag, &self.inflation);
        }
        self.report.detail.diag = out.diag;
        // (I − K H) X = X − K (H X), with H X already at hand (M1: X).
        sub_product(&mut self.sensitivity, &out.gain, hx_m2.as_ref());
        if track {
            let h = if affine { None } else { Some(&h) };
            self.tracker.end_epoch(&out.gain, h);
        }
        // The correction moved the current state: shift the history with it so
        // the next delayed measurement sees a consistent past.
        if self.keeps_history() {
            self.shift_history(&x_prior);
        }
        // M1's stays the identity it starts as: no 36-value store.
        if !affine {
            self.last_h = h;
        }
        Ok((rejected, out.covariance_reset.is_some()))
    }
}
