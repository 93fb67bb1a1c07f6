//! Faults injected into the realistic array.

#[cfg(doc)]
use super::{AX, GZ};

/// A fault on one channel of one IMU: an additive bias step, entering at
/// the sensing element so it goes through the IMU's filters like a real
/// one.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct ChannelFault {
    /// IMU, 0–2.
    pub imu: usize,
    /// Channel, [`AX`]…[`GZ`].
    pub channel: usize,
    /// Onset, s (logger time).
    pub start_s: f64,
    /// End (exclusive), s.
    pub end_s: f64,
    /// Step size, m/s² or rad/s.
    pub bias: f64,
}

impl ChannelFault {
    /// A bias step of `bias` on `imu`'s `channel` over `[start_s, end_s)`.
    pub fn bias(imu: usize, channel: usize, start_s: f64, end_s: f64, bias: f64) -> Self {
        Self {
            imu,
            channel,
            start_s,
            end_s,
            bias,
        }
    }

    /// True at time `t`.
    pub fn active(&self, t: f64) -> bool {
        t >= self.start_s && t < self.end_s
    }
}
