use crate::math::Real;

/// The PX4-style record of one measurement channel at one update.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelDiag<T> {
    /// The channel was present in this epoch.
    pub available: bool,
    /// Innovation `r = z − ẑ` (angles wrapped to (−π, π]).
    pub innovation: T,
    /// Innovation variance `S_ii` (prediction spread plus measurement noise).
    pub variance: T,
    /// Normalised test ratio `r² / (gate² · S_ii)`; above 1 the sample is an
    /// outlier for the gate.
    pub test_ratio: T,
    /// The channel was fused into the state.
    pub fused: bool,
}

/// Innovation gate for aiding outliers with a persistence rule.
///
/// A channel whose normalised innovation exceeds `sigma` is rejected for at
/// most `max_rejections` consecutive epochs. Rejecting for longer would let an
/// IMU fault push the filter away from its aiding for ever; past that count
/// the channel is fused again (and the monitor's detectors, which see every
/// innovation whether fused or not, attribute the persistent disagreement).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gate<T, const M: usize> {
    /// Gate width in innovation standard deviations (≤ 0 disables gating).
    pub sigma: T,
    /// Longest run of consecutive rejections per channel.
    pub max_rejections: u8,
    run: [u8; M],
    rejected_total: u32,
}

impl<T: Real, const M: usize> Gate<T, M> {
    /// A gate of `sigma` standard deviations.
    pub fn new(sigma: T, max_rejections: u8) -> Self {
        Self {
            sigma,
            max_rejections,
            run: [0; M],
            rejected_total: 0,
        }
    }

    /// Decides whether to fuse a channel with the given test ratio.
    pub fn admit(&mut self, channel: usize, test_ratio: T) -> bool {
        let Some(run) = self.run.get_mut(channel) else {
            return false;
        };
        if self.sigma <= T::zero() || !self.sigma.finite() || test_ratio <= T::one() {
            *run = 0;
            return true;
        }
        if *run < self.max_rejections {
            *run += 1;
            self.rejected_total = self.rejected_total.saturating_add(1);
            false
        } else {
            true
        }
    }

    /// The test ratio of an innovation against this gate.
    pub fn ratio(&self, innovation: T, variance: T) -> T {
        let g2 = if self.sigma > T::zero() {
            self.sigma * self.sigma
        } else {
            T::one()
        };
        innovation * innovation / (g2 * variance)
    }

    /// Number of samples rejected since start.
    pub fn rejected_total(&self) -> u32 {
        self.rejected_total
    }
}
