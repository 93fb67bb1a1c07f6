//! Settings of the multi-scale parity tests and their validation.

use crate::math::Real;

use super::SCALES;

/// Configuration of the multi-scale tests (part of
/// [`ParityConfig`](crate::parity::ParityConfig)).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MultiscaleConfig<T> {
    /// Window lengths in blocks, ascending, the longest at most the
    /// monitor's `W`.
    pub scales: [u16; SCALES],
    /// False-alarm probability of one score (one sensor hypothesis, one
    /// window length, one decision, both signs); the threshold is the
    /// squared Student-t quantile at `false_alarm / 2` with
    /// `variance_blocks / length` degrees of freedom.
    pub false_alarm: f64,
    /// Likelihood-ratio margin (χ² units) by which the named sensor's
    /// hypothesis must beat the runner-up before it is isolated.
    pub isolation_margin: T,
    /// Block residuals are clipped to a Mahalanobis norm of
    /// `√dim + huber` (block-covariance units).
    pub huber: T,
    /// The shortest window is also tested *unclipped*, against this
    /// multiple of the threshold: clipping bounds what one block can add,
    /// so without this a fault of any size would score no more than a
    /// clipped one. Large faults are found here at once; manoeuvre
    /// transients stay below it (on log171 the accelerometers' vibration
    /// events reach 20× the threshold on a 2.5-s window; 50× is a window
    /// mean about 35 σ off, which any fault ten times the detectable size
    /// exceeds).
    pub gross_factor: T,
    /// Memory of the in-flight calibration, blocks (RLS forgetting).
    pub calibration_blocks: T,
    /// Memory of the learned covariances, blocks.
    pub variance_blocks: T,
    /// Learning is frozen while any score is at or above this fraction of
    /// the threshold, and for the longest window after it; the
    /// covariances learn a block only once every window containing it
    /// has been judged. With that delay, near one: covariances learned
    /// only from windows that look quiet underestimate the spread
    /// (censoring). Without the delay, a quarter gave 35 false-alarm
    /// events in 2 h of the realistic profile and a half 4; with it, 0.95
    /// gave fewer false alarms than 0.5 or 0.75 on seeds not diagnosed on
    /// (`docs/parity-real-flights.md`, step 5).
    pub learn_below: T,
    /// Ridge on each leakage (scale/misalignment) coefficient, unit² per
    /// block: the prior that the IMUs agree in scale.
    pub ridge_motion: T,
    /// Ridge on each skew coefficient, unit² per block.
    pub ridge_skew: T,
    /// Ridge on the vibration-rectification coefficients, unit² per block.
    pub ridge_vibration: T,
    /// Use each sensor's block variance as a regressor (vibration
    /// rectification). On log171 it is what keeps the accelerometers quiet;
    /// for the gyros it adds parameters and costs sensitivity, so their
    /// defaults leave it off.
    pub vibration: bool,
    /// Largest relative bias one sensor may carry once trained (after the
    /// turn-on calibration the autopilot applies); a larger one is a fault
    /// present from power-up, reported instead of learned. Infinite: no
    /// such test (the monitor cannot judge a fault present since power-up,
    /// and says so in its documentation) — the accelerometer default, see
    /// [`ParityConfig::accel_flight`](crate::parity::ParityConfig::accel_flight).
    pub offset_limit: T,
}

impl<T: Real> MultiscaleConfig<T> {
    /// Defaults for blocks of ≈ 0.25 s: windows of 10, 20, 40 blocks,
    /// α = 1e-6 per score (with 4 decisions/s and three window lengths
    /// ≈ 0.4 expected false scores in 10 h if the statistic were exact),
    /// isolation margin 10.8 (χ²(1) at 1e-3), Huber excess 0.5,
    /// calibration memory 480 blocks (2 min), covariance memory 960 blocks
    /// (4 min: 96, 48 and 24 degrees of freedom for the three lengths,
    /// thresholds 28, 33 and 48 in χ² units), learning frozen at 0.95 of
    /// the threshold. `unit` is the sensor's natural scale (1 °/s for gyros,
    /// 0.1 m/s² for accelerometers) and sets the ridges and offset limit.
    pub fn new(unit: T, offset_limit: T) -> Self {
        Self {
            scales: [10, 20, 40],
            false_alarm: 1e-6,
            isolation_margin: T::lit(10.8),
            huber: T::lit(0.5),
            gross_factor: T::lit(50.0),
            calibration_blocks: T::lit(480.0),
            variance_blocks: T::lit(960.0),
            learn_below: T::lit(0.95),
            ridge_motion: unit * unit * T::lit(10.0),
            ridge_skew: unit * unit * T::lit(0.1),
            ridge_vibration: unit * unit * T::lit(0.1),
            vibration: false,
            offset_limit,
        }
    }

    /// Checks every field: ascending non-zero scales within `w` blocks,
    /// α in (0, 0.5), finite positive margins, memories above one block,
    /// `learn_below` in (0, 1], non-negative ridges and a positive
    /// (possibly infinite) offset limit. Returns the name of the first bad field.
    pub fn check(&self, w: usize) -> Result<(), &'static str> {
        let [a, b, c] = self.scales;
        if a == 0 || a > b || b > c || usize::from(c) > w {
            return Err("multiscale.scales");
        }
        if !(self.false_alarm > 0.0 && self.false_alarm < 0.5) {
            return Err("multiscale.false_alarm");
        }
        let positive = |x: T| x.finite() && x > T::zero();
        if !positive(self.isolation_margin) {
            return Err("multiscale.isolation_margin");
        }
        if !positive(self.huber) {
            return Err("multiscale.huber");
        }
        if !(self.gross_factor.finite() && self.gross_factor >= T::one()) {
            return Err("multiscale.gross_factor");
        }
        if !(self.calibration_blocks.finite() && self.calibration_blocks > T::one()) {
            return Err("multiscale.calibration_blocks");
        }
        if !(self.variance_blocks.finite() && self.variance_blocks > T::one()) {
            return Err("multiscale.variance_blocks");
        }
        if !(positive(self.learn_below) && self.learn_below <= T::one()) {
            return Err("multiscale.learn_below");
        }
        if !(self.ridge_motion.finite() && self.ridge_motion >= T::zero()) {
            return Err("multiscale.ridge_motion");
        }
        if !(self.ridge_skew.finite() && self.ridge_skew >= T::zero()) {
            return Err("multiscale.ridge_skew");
        }
        if !(self.ridge_vibration.finite() && self.ridge_vibration >= T::zero()) {
            return Err("multiscale.ridge_vibration");
        }
        // Infinite is allowed (no power-up test); NaN, zero and negative
        // are not.
        if self.offset_limit.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
            return Err("multiscale.offset_limit");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offset_limit_may_be_infinite_but_not_nan_or_zero() {
        let ok = MultiscaleConfig::<f32>::new(0.1, f32::INFINITY);
        assert_eq!(ok.check(40), Ok(()));
        for bad in [f32::NAN, 0.0, -1.0] {
            let c = MultiscaleConfig::<f32>::new(0.1, bad);
            assert_eq!(c.check(40), Err("multiscale.offset_limit"), "{bad}");
        }
    }
}
