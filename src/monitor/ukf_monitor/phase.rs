//! The UKF monitor's phases: converging, learning, monitoring, and the
//! restart of learning when an aiding estimate moves.

use super::{Phase, UkfMonitor};
use crate::math::Real;
use crate::model::NZ;
use crate::monitor::input::next_phase;

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// Moves converging → learning → monitoring when the phase's time is up
    /// (learning starts the lag it learns at; monitoring freezes the
    /// inflation and starts the windows afresh).
    pub(super) fn advance_phase(&mut self) {
        let next = next_phase(
            self.phase,
            self.phase_time,
            self.cfg.converge_s,
            self.cfg.learn_s,
        );
        match next {
            Some(Phase::Learning) => {
                self.phase = Phase::Learning;
                self.learn_clock = self.phase_time;
                self.learned_lag = self.delay_steps;
            }
            Some(Phase::Monitoring) => {
                self.phase = Phase::Monitoring;
                self.freeze_inflation();
                let smallest = self.cfg.min_fault * self.cfg.threshold_fraction;
                self.power_up
                    .start(&self.cfg.nominal_bias_bound(), &smallest);
                #[cfg(feature = "inflation-tracking")]
                {
                    let floor = T::lit(2.0 * W as f64);
                    self.cover.set_need(&self.inflation_n, floor);
                }
                self.att_rate_start();
                self.vel_inc_start();
                // The fault estimate starts from "no fault", as uncertain
                // as the smallest fault to detect.
                if self.tracking_on() {
                    self.tracker.start(&self.cfg.min_fault, &self.sensitivity);
                }
                for w in self.windows.iter_mut() {
                    w.clear();
                }
                self.persistence.reset();
            }
            _ => {}
        }
    }

    /// During learning, starts it again (an aiding-timing or heading
    /// estimate moved: what was learnt so far fits the old one); once
    /// monitoring, does nothing, since a restart would absorb whatever fault
    /// is present into the nominal bias.
    pub(super) fn restart_learning(&mut self) {
        if self.phase != Phase::Learning {
            return;
        }
        self.phase_time = self.cfg.converge_s;
        self.learn_clock = self.phase_time;
        self.inflation_sum = [T::zero(); NZ];
        self.inflation_n = [T::zero(); NZ];
        #[cfg(feature = "inflation-tracking")]
        {
            self.cover = super::inflation_cover::InflationCover::default();
        }
        self.inflation = [T::one(); NZ];
        self.power_up = super::power_up::PowerUpCheck::default();
        self.att_rate_reset();
        self.vel_inc_reset();
        for w in self.windows.iter_mut() {
            w.clear();
        }
        self.persistence.reset();
    }
}
