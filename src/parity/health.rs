//! Hardware health checks every redundant sensor needs, independent of the
//! parity statistics: frozen output, missing samples, clipping, NaN or
//! out-of-range values and bus errors.

use crate::math::Real;

/// What the driver delivered for one sensor in one period.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reading<T> {
    /// A sample (rad/s or m/s²).
    Sample(T),
    /// No new sample this period (data-ready never came, FIFO empty).
    Missing,
    /// The SPI/I²C transaction failed.
    BusError,
}

impl<T> Reading<T> {
    /// The same reading with its sample converted (e.g. `f64` → `f32`).
    pub fn map<U>(self, f: impl FnOnce(T) -> U) -> Reading<U> {
        match self {
            Self::Sample(x) => Reading::Sample(f(x)),
            Self::Missing => Reading::Missing,
            Self::BusError => Reading::BusError,
        }
    }
}

/// Health of one sensor this period.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SensorStatus {
    /// Sample used.
    #[default]
    Healthy,
    /// Sample within `clip_fraction` of full scale: excluded from the
    /// statistics this period (saturation is not a fault).
    Clipping,
    /// Sample missing this period (not yet a timeout).
    Missing,
    /// NaN, infinite or beyond full scale this period.
    OutOfRange,
    /// Bus error this period.
    BusError,
    /// Failed: identical output for `stuck_samples` periods. This and the
    /// failures below latch until reset, except with the multi-scale
    /// monitor, which judges the sensor for re-admission once its output
    /// is good again (then [`ParityIsolated`](Self::ParityIsolated)), or
    /// takes it back and trains again if it failed while training. Output
    /// frozen on at least half of the sensors in the same period is a
    /// common-mode event (the logger or the driver repeating a sample):
    /// reported `Stuck` while it lasts, the samples unused, not latched.
    Stuck,
    /// Failed: no sample for `timeout_samples` periods.
    Timeout,
    /// Failed: out of range for `out_of_range_limit` periods in a row.
    InvalidOutput,
    /// Failed: `bus_error_limit` bus errors in a row.
    BusFailure,
    /// Failed: clipping for `rail_samples` periods in a row while most other
    /// sensors did not (output railed at full scale).
    Railed,
    /// Out of the set: isolated by the parity test, or excluded by a
    /// hardware failure whose output is good again. The multi-scale
    /// monitor keeps judging it against the sensors in the set and
    /// re-admits it once its error has decayed (see
    /// [`Probation`](Self::Probation)); otherwise latched until reset.
    ParityIsolated,
    /// Out of the set, isolated by the parity test and consistent with the
    /// sensors in the set since the latest decision: counting the probation
    /// that re-admits it (multi-scale monitor, `docs/recovery.md`).
    Probation,
}

impl SensorStatus {
    /// The per-period status behind a bus or output failure
    /// (`InvalidOutput` → `OutOfRange`, `Timeout` → `Missing`,
    /// `BusFailure` → `BusError`); `None` for the others.
    pub fn transient(self) -> Option<Self> {
        match self {
            Self::InvalidOutput => Some(Self::OutOfRange),
            Self::Timeout => Some(Self::Missing),
            Self::BusFailure => Some(Self::BusError),
            _ => None,
        }
    }
}

impl SensorStatus {
    /// True for the states that put the sensor out of the set: the
    /// hardware failures until [`reset`](super::ParityMonitor::reset), a
    /// parity isolation until reset or re-admission
    /// ([`ParityIsolated`](Self::ParityIsolated),
    /// [`Probation`](Self::Probation): its samples are not used while it
    /// is judged).
    pub fn is_failed(self) -> bool {
        matches!(
            self,
            Self::Stuck
                | Self::Timeout
                | Self::InvalidOutput
                | Self::BusFailure
                | Self::Railed
                | Self::ParityIsolated
                | Self::Probation
        )
    }

    /// Out of the set by a parity isolation (may be re-admitted).
    pub fn is_parity_out(self) -> bool {
        matches!(self, Self::ParityIsolated | Self::Probation)
    }
}

/// Limits of the hardware checks.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HealthConfig<T> {
    /// Full scale of the sensors (rad/s or m/s²).
    pub full_scale: T,
    /// A sample at or beyond this fraction of full scale is clipping.
    pub clip_fraction: T,
    /// Consecutive bit-identical samples that mean a frozen output. Chosen
    /// so that noise quantised to a coarse LSB cannot repeat that long by
    /// chance (at 2,000 °/s full scale the LSB is 0.06 °/s, twice the
    /// per-sample noise: two equal samples are common, 50 are not).
    pub stuck_samples: u16,
    /// Consecutive missing samples that mean a timeout.
    pub timeout_samples: u16,
    /// Consecutive out-of-range (NaN, ±∞, beyond full scale) samples that
    /// mean invalid output.
    pub out_of_range_limit: u16,
    /// Consecutive bus errors that mean a failed bus.
    pub bus_error_limit: u16,
    /// Consecutive clipping samples that mean a railed output, when fewer
    /// than half of the sensors clip with it (common-mode saturation in a
    /// violent manoeuvre is not a sensor failure).
    pub rail_samples: u16,
}

impl<T: Real> HealthConfig<T> {
    /// Defaults for a sensor of the given full scale at ~100 Hz: clipping
    /// at 98 % of full scale, stuck after 50 samples, timeout after 10,
    /// invalid after 5, bus failure after 10 and railed after 100 in a row.
    pub fn new(full_scale: T) -> Self {
        Self {
            full_scale,
            clip_fraction: T::lit(0.98),
            stuck_samples: 50,
            timeout_samples: 10,
            out_of_range_limit: 5,
            bus_error_limit: 10,
            rail_samples: 100,
        }
    }
}

/// Running health state of one sensor.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SensorHealth<T> {
    last: Option<T>,
    same: u16,
    missing: u16,
    out_of_range: u16,
    bus_errors: u16,
    bus_errors_total: u32,
    clipping: u16,
    latched: Option<SensorStatus>,
    /// See [`out_sample`](Self::out_sample); after a hardware failure, the
    /// latest sample that passed the checks, for [`resume`](Self::resume).
    out_sample: Option<T>,
}

impl<T: Real> SensorHealth<T> {
    /// Checks one reading: returns the usable value (or `None`) and the
    /// sensor's status for this period. Latched failures stay latched.
    pub fn check(
        &mut self,
        reading: Reading<T>,
        cfg: &HealthConfig<T>,
    ) -> (Option<T>, SensorStatus) {
        let (value, status) = self.check_unlatched(reading, cfg);
        if self.latched != Some(status) {
            self.latch(status);
        }
        (value, status)
    }

    /// As [`check`](Self::check), but a new failure is not latched: the
    /// caller decides (with [`latch`](Self::latch)) after seeing the other
    /// sensors — a failure on most sensors at once is a common-mode event.
    pub fn check_unlatched(
        &mut self,
        reading: Reading<T>,
        cfg: &HealthConfig<T>,
    ) -> (Option<T>, SensorStatus) {
        let (value, status) = self.classify(reading, cfg);
        if let Some(failed) = self.latched {
            if failed.is_parity_out() {
                return self.out_of_set(value, status, failed);
            }
            // Kept (never handed out) for `resume`.
            self.out_sample = value;
            return (None, failed);
        }
        (value, status)
    }

    /// A hardware failure whose output is good again — this period's
    /// sample passed the checks: the first changed sample after a freeze,
    /// a sample after a timeout, a finite in-range one after invalid
    /// output, one below the rail — becomes a parity isolation: out of the
    /// set, its samples judged against the others by the multi-scale
    /// monitor, which re-admits it on the parity tests' own evidence
    /// (issue 14, "never stuck": a frozen or silent spell that ended used
    /// to cost the board that sensor until reset). True when it did. The
    /// monitor calls it for the sensors it judges; the others stay latched
    /// until reset.
    pub fn resume(&mut self) -> bool {
        let hardware = self.latched.is_some_and(|s| !s.is_parity_out());
        if hardware && self.out_sample.is_some() {
            self.latched = Some(SensorStatus::ParityIsolated);
            return true;
        }
        false
    }

    /// A sensor out of the set by the parity test: still checked, its
    /// usable sample kept for [`out_sample`](Self::out_sample) (the monitor
    /// judges it for re-admission, never fuses it). A hardware failure now
    /// latches over the isolation (judged, it becomes an isolation again
    /// once the output is good, [`resume`](Self::resume)). Out of line: the
    /// usual sample never comes here.
    #[inline(never)]
    fn out_of_set(
        &mut self,
        value: Option<T>,
        status: SensorStatus,
        out: SensorStatus,
    ) -> (Option<T>, SensorStatus) {
        self.out_sample = value;
        if status.is_failed() {
            self.latched = Some(status);
            return (None, status);
        }
        (None, out)
    }

    /// The latest usable sample of a sensor out of the set by the parity
    /// test (`None`: unusable this period, or not out of the set).
    pub fn out_sample(&self) -> Option<T> {
        if self.latched.is_some_and(SensorStatus::is_parity_out) {
            self.out_sample
        } else {
            None
        }
    }

    /// Latches `status` (a failure) until reset.
    pub fn latch(&mut self, status: SensorStatus) {
        if status.is_failed() {
            if !status.is_parity_out() {
                // No sample from before the failure to resume on.
                self.out_sample = None;
            }
            self.latched = Some(status);
        }
    }

    fn classify(
        &mut self,
        reading: Reading<T>,
        cfg: &HealthConfig<T>,
    ) -> (Option<T>, SensorStatus) {
        match reading {
            Reading::Missing => {
                self.missing = self.missing.saturating_add(1);
                if self.missing >= cfg.timeout_samples {
                    return (None, SensorStatus::Timeout);
                }
                (None, SensorStatus::Missing)
            }
            Reading::BusError => {
                self.bus_errors = self.bus_errors.saturating_add(1);
                self.bus_errors_total = self.bus_errors_total.saturating_add(1);
                if self.bus_errors >= cfg.bus_error_limit {
                    return (None, SensorStatus::BusFailure);
                }
                (None, SensorStatus::BusError)
            }
            Reading::Sample(x) => {
                self.missing = 0;
                self.bus_errors = 0;
                if !x.finite() || x.abs() > cfg.full_scale {
                    self.out_of_range = self.out_of_range.saturating_add(1);
                    if self.out_of_range >= cfg.out_of_range_limit {
                        return (None, SensorStatus::InvalidOutput);
                    }
                    return (None, SensorStatus::OutOfRange);
                }
                self.out_of_range = 0;
                if x.abs() >= cfg.clip_fraction * cfg.full_scale {
                    // A railed output repeats legitimately: not "stuck".
                    self.last = None;
                    self.same = 0;
                    self.clipping = self.clipping.saturating_add(1);
                    return (None, SensorStatus::Clipping);
                }
                self.clipping = 0;
                if self.last == Some(x) {
                    self.same = self.same.saturating_add(1);
                } else {
                    self.same = 0;
                }
                self.last = Some(x);
                // `same` counts repeats, so N identical samples = N − 1 repeats.
                if self.same.saturating_add(1) >= cfg.stuck_samples {
                    return (None, SensorStatus::Stuck);
                }
                (Some(x), SensorStatus::Healthy)
            }
        }
    }

    /// Marks the sensor failed by the parity test.
    pub fn isolate(&mut self) {
        self.latched = Some(SensorStatus::ParityIsolated);
    }

    /// Marks a parity-isolated sensor on probation (`true`) or back to
    /// isolated (`false`); a hardware failure stays as it is.
    pub fn set_probation(&mut self, on: bool) {
        if self.latched.is_some_and(SensorStatus::is_parity_out) {
            self.latched = Some(if on {
                SensorStatus::Probation
            } else {
                SensorStatus::ParityIsolated
            });
        }
    }

    /// Re-admits a parity-isolated sensor (its hardware checks go on from
    /// their running state); a hardware failure stays latched. True when
    /// it was re-admitted.
    pub fn readmit(&mut self) -> bool {
        if self.latched.is_some_and(SensorStatus::is_parity_out) {
            self.latched = None;
            return true;
        }
        false
    }

    /// Consecutive repeats of the same sample so far (N identical samples
    /// are N − 1 repeats).
    pub fn repeats(&self) -> u16 {
        self.same
    }

    /// Consecutive clipping samples so far.
    pub fn clipping_run(&self) -> u16 {
        self.clipping
    }

    /// Marks the sensor railed (decided by the monitor, which sees whether
    /// the other sensors clip too).
    pub fn rail(&mut self) {
        self.out_sample = None;
        self.latched = Some(SensorStatus::Railed);
    }

    /// The latched failure, if any.
    pub fn failure(&self) -> Option<SensorStatus> {
        self.latched
    }

    /// Bus errors seen since start (or the last reset).
    pub fn bus_errors_total(&self) -> u32 {
        self.bus_errors_total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_check_has_its_status_and_latches() {
        let cfg = HealthConfig::new(10.0_f64);
        let mut h = SensorHealth::default();
        assert_eq!(
            h.check(Reading::Sample(1.0), &cfg),
            (Some(1.0), SensorStatus::Healthy)
        );
        assert_eq!(
            h.check(Reading::Sample(9.9), &cfg),
            (None, SensorStatus::Clipping)
        );
        assert_eq!(
            h.check(Reading::Sample(f64::NAN), &cfg).1,
            SensorStatus::OutOfRange
        );
        for _ in 0..3 {
            h.check(Reading::Sample(11.0), &cfg);
        }
        assert_eq!(
            h.check(Reading::Sample(11.0), &cfg).1,
            SensorStatus::InvalidOutput
        );
        assert_eq!(
            h.check(Reading::Sample(1.0), &cfg).1,
            SensorStatus::InvalidOutput
        );

        let mut h = SensorHealth::default();
        for k in 0..49 {
            assert_eq!(
                h.check(Reading::Sample(0.5), &cfg).1,
                SensorStatus::Healthy,
                "{k}"
            );
        }
        assert_eq!(h.check(Reading::Sample(0.5), &cfg).1, SensorStatus::Stuck);

        let mut h = SensorHealth::default();
        for _ in 0..9 {
            assert_eq!(h.check(Reading::Missing, &cfg).1, SensorStatus::Missing);
        }
        assert_eq!(h.check(Reading::Missing, &cfg).1, SensorStatus::Timeout);

        let mut h = SensorHealth::default();
        for _ in 0..9 {
            assert_eq!(h.check(Reading::BusError, &cfg).1, SensorStatus::BusError);
        }
        h.check(Reading::Sample(0.1), &cfg);
        assert_eq!(h.check(Reading::BusError, &cfg).1, SensorStatus::BusError);
        assert_eq!(h.bus_errors_total(), 10);
    }

    #[test]
    fn a_parity_isolated_sensor_is_still_checked_and_a_hardware_failure_latches_over_it() {
        let cfg = HealthConfig::new(10.0_f64);
        let mut h = SensorHealth::default();
        h.isolate();
        // Its sample is kept for the shadow tests, never handed out.
        assert_eq!(
            h.check_unlatched(Reading::Sample(1.0), &cfg),
            (None, SensorStatus::ParityIsolated)
        );
        assert_eq!(h.out_sample(), Some(1.0));
        h.set_probation(true);
        assert_eq!(
            h.check_unlatched(Reading::Missing, &cfg),
            (None, SensorStatus::Probation)
        );
        assert_eq!(h.out_sample(), None);
        assert!(SensorStatus::Probation.is_failed());
        // Re-admitted: back to its per-period statuses.
        assert!(h.readmit());
        assert_eq!(
            h.check_unlatched(Reading::Sample(2.0), &cfg),
            (Some(2.0), SensorStatus::Healthy)
        );
        // Isolated again, then five NaN: the hardware latch replaces the
        // isolation and is not re-admitted.
        h.isolate();
        for _ in 0..4 {
            assert_eq!(
                h.check_unlatched(Reading::Sample(f64::NAN), &cfg).1,
                SensorStatus::ParityIsolated
            );
        }
        assert_eq!(
            h.check_unlatched(Reading::Sample(f64::NAN), &cfg).1,
            SensorStatus::InvalidOutput
        );
        h.set_probation(true);
        assert!(!h.readmit());
        assert_eq!(
            h.check_unlatched(Reading::Sample(1.0), &cfg),
            (None, SensorStatus::InvalidOutput)
        );
        assert_eq!(h.out_sample(), None);
    }

    #[test]
    fn a_hardware_failure_resumes_as_an_isolation_once_the_output_is_good() {
        let cfg = HealthConfig::new(10.0_f64);
        let mut h = SensorHealth::default();
        for _ in 0..49 {
            h.check(Reading::Sample(0.5), &cfg);
        }
        assert_eq!(h.check(Reading::Sample(0.5), &cfg).1, SensorStatus::Stuck);
        // Still frozen: still stuck, nothing handed out, nothing to resume.
        assert_eq!(
            h.check(Reading::Sample(0.5), &cfg),
            (None, SensorStatus::Stuck)
        );
        assert!(!h.resume());
        assert_eq!(h.out_sample(), None);
        // The first changed sample: still reported stuck this period and
        // latched until reset unless resumed; resumed, out of the set as an
        // isolation with its sample kept for the shadow.
        assert_eq!(
            h.check(Reading::Sample(0.6), &cfg),
            (None, SensorStatus::Stuck)
        );
        assert!(!h.readmit());
        assert!(h.resume());
        assert_eq!(h.failure(), Some(SensorStatus::ParityIsolated));
        assert_eq!(h.out_sample(), Some(0.6));
        assert!(h.readmit());
        assert_eq!(
            h.check(Reading::Sample(0.7), &cfg),
            (Some(0.7), SensorStatus::Healthy)
        );
        // A timeout: good again with the first sample, not before.
        let mut h = SensorHealth::default();
        for _ in 0..10 {
            h.check(Reading::Missing, &cfg);
        }
        assert_eq!(h.check(Reading::Missing, &cfg).1, SensorStatus::Timeout);
        assert!(!h.resume());
        h.check(Reading::Sample(0.1), &cfg);
        assert!(h.resume());
        // An isolated sensor (its sample kept) latched by a hardware
        // failure does not resume on that old sample.
        let mut h = SensorHealth::default();
        h.isolate();
        h.check(Reading::Sample(0.2), &cfg);
        assert_eq!(h.out_sample(), Some(0.2));
        h.latch(SensorStatus::Timeout);
        assert!(!h.resume());
    }
}
