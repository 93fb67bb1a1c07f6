//! Delta angle / delta velocity over the monitor period from full-rate
//! samples, with coning and sculling corrections.
//!
//! A monitor that runs at 50–100 Hz and takes the *latest* sample of a chip
//! sampling at 1 kHz sees every vibration component above its own Nyquist
//! frequency folded into its band (point sampling). Integrating every sample
//! of the period instead hands it the period's average rate and specific
//! force: a moving-average (sinc) low-pass whose nulls sit at multiples of
//! the monitor rate, so rotor vibration is attenuated, not aliased.
//!
//! The increments follow Savage's two-speed structure (P. G. Savage,
//! "Strapdown Inertial Navigation Integration Algorithm Design, Part 1:
//! Attitude Algorithms" and "Part 2: Velocity and Position Algorithms",
//! JGCD 21(1) and 21(2), 1998), with the high-rate coning term of
//! Miller's algorithm form (R. B. Miller, "A New Strapdown Attitude
//! Algorithm", JGCD 6(4), 1983) using the previous increment (the form
//! PX4's `IntegratorConing` uses):
//!
//! * `α_l = α_{l−1} + Δα_l`,  `β_l = β_{l−1} + ½ (α_{l−1} + Δα_{l−1}/6) × Δα_l`;
//!   rotation vector over the period `φ = α_m + β_m` (coning);
//! * `υ_l = υ_{l−1} + Δυ_l`,
//!   `γ_l = γ_{l−1} + ½ [(α_{l−1} + Δα_{l−1}/6) × Δυ_l + (υ_{l−1} + Δυ_{l−1}/6) × Δα_l]`;
//!   velocity change `Δv = υ_m + ½ α_m × υ_m + γ_m` (rotation compensation
//!   and sculling), in the body axes at the start of the period.
//!
//! `Δα_l = ω_l·h_l`, `Δυ_l = f_l·h_l` are the rectangular increments of the
//! chip's samples (each sample stands for its ODR period), so without
//! rotation `φ/T` and `Δv/T` are exactly the mean of the period's samples,
//! the band-limited average the monitor wants. `no_std`, no allocation,
//! `f32`, no panics.

/// One period's increments, in the body (sensor) axes at its start.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Delta {
    /// Rotation vector over the period (coning-corrected), rad.
    pub delta_angle: [f32; 3],
    /// Velocity change from specific force (rotation- and
    /// sculling-corrected), m/s.
    pub delta_velocity: [f32; 3],
    /// Length of the period: the sum of the samples' intervals, s.
    pub dt: f32,
    /// Samples integrated.
    pub samples: u32,
}

impl Delta {
    /// Average angular rate over the period, `Δθ/T`, rad/s (zero for an
    /// empty period).
    pub fn mean_rate(&self) -> [f32; 3] {
        self.per_second(self.delta_angle)
    }

    /// Average specific force over the period, `Δv/T`, m/s² (zero for an
    /// empty period).
    pub fn mean_specific_force(&self) -> [f32; 3] {
        self.per_second(self.delta_velocity)
    }

    fn per_second(&self, v: [f32; 3]) -> [f32; 3] {
        if self.dt > 0.0 {
            v.map(|x| x / self.dt)
        } else {
            [0.0; 3]
        }
    }
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0]
}

fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [a0 + b0, a1 + b1, a2 + b2]
}

fn scale(a: [f32; 3], k: f32) -> [f32; 3] {
    a.map(|x| x * k)
}

/// Accumulates full-rate gyro and accelerometer samples into one period's
/// [`Delta`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DeltaIntegrator {
    alpha: [f32; 3],
    beta: [f32; 3],
    nu: [f32; 3],
    gamma: [f32; 3],
    /// The previous sample's increments (carried across periods: Miller's
    /// term uses the increment before the first one of the period).
    last_dalpha: [f32; 3],
    last_dnu: [f32; 3],
    dt: f32,
    samples: u32,
    rejected: u32,
}

impl DeltaIntegrator {
    /// An empty integrator.
    pub const fn new() -> Self {
        Self {
            alpha: [0.0; 3],
            beta: [0.0; 3],
            nu: [0.0; 3],
            gamma: [0.0; 3],
            last_dalpha: [0.0; 3],
            last_dnu: [0.0; 3],
            dt: 0.0,
            samples: 0,
            rejected: 0,
        }
    }

    /// Adds one sample: angular rate `gyro` (rad/s) and specific force
    /// `accel` (m/s²) held over `h` seconds (the sample's ODR period, or
    /// several when samples were lost). A sample with a non-finite value or
    /// a non-positive or non-finite `h` is not integrated (it would poison
    /// the whole period); it is counted in [`rejected`](Self::rejected) and
    /// `false` is returned.
    pub fn push(&mut self, gyro: [f32; 3], accel: [f32; 3], h: f32) -> bool {
        let finite = gyro.iter().chain(accel.iter()).all(|x| x.is_finite());
        if !(finite && h.is_finite() && h > 0.0) {
            self.rejected = self.rejected.saturating_add(1);
            return false;
        }
        let da = scale(gyro, h);
        let dv = scale(accel, h);
        let a_prev = add(self.alpha, scale(self.last_dalpha, 1.0 / 6.0));
        let v_prev = add(self.nu, scale(self.last_dnu, 1.0 / 6.0));
        // Coning (Miller/Savage): the non-commutativity of successive
        // increments within the period.
        self.beta = add(self.beta, scale(cross(a_prev, da), 0.5));
        // Sculling (Savage Part 2): rotation and acceleration in phase.
        let scul = add(cross(a_prev, dv), cross(v_prev, da));
        self.gamma = add(self.gamma, scale(scul, 0.5));
        self.alpha = add(self.alpha, da);
        self.nu = add(self.nu, dv);
        self.last_dalpha = da;
        self.last_dnu = dv;
        self.dt += h;
        self.samples = self.samples.saturating_add(1);
        true
    }

    /// Samples integrated in the current period.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Samples refused since start (non-finite values or intervals).
    pub fn rejected(&self) -> u32 {
        self.rejected
    }

    /// The period's increments so far, without ending the period.
    pub fn peek(&self) -> Delta {
        let rot = scale(cross(self.alpha, self.nu), 0.5);
        Delta {
            delta_angle: add(self.alpha, self.beta),
            delta_velocity: add(add(self.nu, rot), self.gamma),
            dt: self.dt,
            samples: self.samples,
        }
    }

    /// Ends the period: returns its increments and starts the next one
    /// (the last increment is kept for the next period's coning term).
    /// `None` when no sample was integrated.
    pub fn take(&mut self) -> Option<Delta> {
        if self.samples == 0 {
            return None;
        }
        let d = self.peek();
        self.alpha = [0.0; 3];
        self.beta = [0.0; 3];
        self.nu = [0.0; 3];
        self.gamma = [0.0; 3];
        self.dt = 0.0;
        self.samples = 0;
        Some(d)
    }

    /// Forgets everything, including the last increment (after a gap in
    /// the data the previous increment no longer precedes the next one).
    pub fn reset(&mut self) {
        let rejected = self.rejected;
        *self = Self::new();
        self.rejected = rejected;
    }
}
