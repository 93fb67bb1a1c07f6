//! Fault injection: the papers' fault shapes (E1–E3 of \[UKF\], F1–F3 of \[OTS\])
//! and the hardware faults of S5, described as table rows.

use core::f64::consts::PI;

/// What goes wrong on a channel.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub enum FaultKind {
    /// \[UKF\] E1: step `a`.
    E1,
    /// \[UKF\] E2: ramp `b (t − t₀)`.
    E2,
    /// \[UKF\] E3: `c sin(0.005π (t − t₀))` (400 s period: a slow ramp at first).
    E3,
    /// \[OTS\] F1: step 1 (× the table's unit scale).
    F1,
    /// \[OTS\] F2: ramp `0.1 (t − t₀)`.
    F2,
    /// \[OTS\] F3: `sin(0.5π (t − t₀))`.
    F3,
    /// S5: output stuck at the last good value.
    Stuck,
    /// S5: no sample at all (bus timeout / missing data).
    Dropout,
    /// S5: clipping at ± the given level (unit of the channel).
    Clip(f64),
    /// S5: spike bursts of the given amplitude, every 0.5 s for 30 ms.
    Spikes(f64),
    /// S5: white-noise σ multiplied by the given factor.
    NoiseIncrease(f64),
    /// S5: scale-factor error (fraction, e.g. 0.05 for +5 %).
    ScaleFactor(f64),
}

/// Sizes of the \[UKF\] shapes per channel kind (SPEC §8 leaves a, b, c open).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct FaultSizes {
    /// Accelerometer `[a m/s², b m/s³, c m/s²]`.
    pub accel: [f64; 3],
    /// Gyro `[a rad/s, b rad/s², c rad/s]`.
    pub gyro: [f64; 3],
    /// Unit of the \[OTS\] F1–F3 shapes: `[accel, gyro]` (1 m/s² and e.g.
    /// 1 °/s = 0.01745 rad/s: the paper does not state gyro units).
    pub f_unit: [f64; 2],
}

/// One row of a fault table, as in the papers: channel, interval, shape, sign.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct FaultRow {
    /// IMU channel 0–5 = `[a_x, a_y, a_z, p, q, r]`.
    pub channel: usize,
    /// Onset, s.
    pub start: f64,
    /// End (exclusive), s.
    pub end: f64,
    /// Shape.
    pub kind: FaultKind,
    /// +1 or −1 (the papers' "−E1").
    pub sign: f64,
}

impl FaultRow {
    /// True while the fault is active.
    pub fn active(&self, t: f64) -> bool {
        t >= self.start && t < self.end
    }

    /// Additive value of an additive-shape fault at `t` (0 for hardware
    /// faults, which act on the sample itself, and outside the interval).
    pub fn additive(&self, t: f64, sizes: &FaultSizes) -> f64 {
        if !self.active(t) {
            return 0.0;
        }
        let tau = t - self.start;
        let gyro = self.channel >= 3;
        let abc = if gyro { sizes.gyro } else { sizes.accel };
        let unit = if gyro {
            sizes.f_unit[1]
        } else {
            sizes.f_unit[0]
        };
        let v = match self.kind {
            FaultKind::E1 => abc[0],
            FaultKind::E2 => abc[1] * tau,
            FaultKind::E3 => abc[2] * libm::sin(0.005 * PI * tau),
            FaultKind::F1 => unit,
            FaultKind::F2 => 0.1 * tau * unit,
            FaultKind::F3 => libm::sin(0.5 * PI * tau) * unit,
            _ => 0.0,
        };
        self.sign * v
    }

    /// True for the S5 hardware kinds.
    pub fn is_hardware(&self) -> bool {
        !matches!(
            self.kind,
            FaultKind::E1
                | FaultKind::E2
                | FaultKind::E3
                | FaultKind::F1
                | FaultKind::F2
                | FaultKind::F3
        )
    }
}
