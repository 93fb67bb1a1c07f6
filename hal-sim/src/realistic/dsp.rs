//! Small signal-processing blocks of the realistic simulator: biquads (the
//! 2nd-order Butterworth low-pass every IMU chain uses, and the band-pass
//! that shapes broadband vibration), a phase rotator for the rotor tones and
//! a cheap uniform noise source.

use core::f64::consts::PI;

use rand::RngCore;
use rand_xoshiro::Xoshiro256PlusPlus;

/// A direct-form-II-transposed biquad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    s: [f64; 2],
}

impl Biquad {
    /// The identity (a disabled filter stage).
    pub const PASS: Self = Self {
        b: [1.0, 0.0, 0.0],
        a: [0.0, 0.0],
        s: [0.0, 0.0],
    };

    /// 2nd-order Butterworth low-pass at `fc` for sample rate `fs` (bilinear
    /// transform with pre-warping, as ArduPilot's `LowPassFilter2p` and
    /// PX4's `LowPassFilter2p` compute it). `fc <= 0` or `fc >= fs/2`
    /// returns [`Biquad::PASS`].
    pub fn lowpass(fc: f64, fs: f64) -> Self {
        if fc <= 0.0 || fc >= 0.5 * fs {
            return Self::PASS;
        }
        let k = libm::tan(PI * fc / fs);
        let q = core::f64::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Self {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
            s: [0.0, 0.0],
        }
    }

    /// Band-pass (RBJ cookbook, 0 dB peak) centred on `fc` with quality `q`.
    pub fn bandpass(fc: f64, q: f64, fs: f64) -> Self {
        if fc <= 0.0 || fc >= 0.5 * fs || q <= 0.0 {
            return Self::PASS;
        }
        let w0 = 2.0 * PI * fc / fs;
        let alpha = libm::sin(w0) / (2.0 * q);
        let a0 = 1.0 + alpha;
        Self {
            b: [alpha / a0, 0.0, -alpha / a0],
            a: [-2.0 * libm::cos(w0) / a0, (1.0 - alpha) / a0],
            s: [0.0, 0.0],
        }
    }

    /// Sets the state as if `x` had been applied forever (no start-up
    /// transient).
    pub fn settle(&mut self, x: f64) {
        let dc = (self.b[0] + self.b[1] + self.b[2]) / (1.0 + self.a[0] + self.a[1]);
        let y = dc * x;
        self.s[1] = self.b[2] * x - self.a[1] * y;
        self.s[0] = self.b[1] * x - self.a[0] * y + self.s[1];
    }

    /// One sample through the filter.
    #[inline]
    pub fn step(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.s[0];
        self.s[0] = self.b[1] * x - self.a[0] * y + self.s[1];
        self.s[1] = self.b[2] * x - self.a[1] * y;
        y
    }
}

/// A unit phasor advanced by a (slowly varying) frequency: one complex
/// multiply per step instead of a `sin` per tone, renormalised each step so
/// the amplitude cannot drift over hours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rotator {
    /// Real part (cos of the phase).
    pub re: f64,
    /// Imaginary part (sin of the phase).
    pub im: f64,
}

impl Rotator {
    /// At phase `phi`, rad.
    pub fn new(phi: f64) -> Self {
        Self {
            re: libm::cos(phi),
            im: libm::sin(phi),
        }
    }

    /// Advances the phase by `d` rad (|d| ≲ 0.8: a 5th-order series).
    #[inline]
    pub fn advance(&mut self, d: f64) {
        let d2 = d * d;
        let c = 1.0 - d2 * (0.5 - d2 / 24.0);
        let s = d * (1.0 - d2 * (1.0 / 6.0 - d2 / 120.0));
        let re = self.re * c - self.im * s;
        let im = self.re * s + self.im * c;
        let g = 1.5 - 0.5 * (re * re + im * im);
        self.re = re * g;
        self.im = im * g;
    }

    /// The phasor squared (second harmonic).
    #[inline]
    pub fn square(&self) -> Self {
        Self {
            re: self.re * self.re - self.im * self.im,
            im: 2.0 * self.re * self.im,
        }
    }

    /// The product of two phasors.
    #[inline]
    pub fn mul(&self, o: &Self) -> Self {
        Self {
            re: self.re * o.re - self.im * o.im,
            im: self.re * o.im + self.im * o.re,
        }
    }
}

/// Two zero-mean, unit-variance uniform deviates from one 64-bit draw. The
/// broadband vibration is band-pass filtered, so its distribution is
/// Gaussian by the central limit theorem whatever the source; uniform draws
/// are several times cheaper than normal ones at kHz rates.
#[inline]
pub fn uniform_pair(rng: &mut Xoshiro256PlusPlus) -> (f64, f64) {
    // √12 · (u − ½) has unit variance for u uniform on [0, 1).
    const K: f64 = 3.464_101_615_137_754_6 / 4_294_967_296.0;
    let r = rng.next_u64();
    let hi = (r >> 32) as f64;
    let lo = (r & 0xffff_ffff) as f64;
    (
        K * hi - 1.732_050_807_568_877_2,
        K * lo - 1.732_050_807_568_877_2,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn butterworth_is_minus_3_db_at_cutoff_and_unity_at_dc() {
        let fs = 1000.0;
        for (f, want) in [(0.0, 1.0), (20.0, core::f64::consts::FRAC_1_SQRT_2)] {
            let mut lp = Biquad::lowpass(20.0, fs);
            let mut peak: f64 = 0.0;
            for n in 0..20_000 {
                let x = libm::cos(2.0 * PI * f * n as f64 / fs);
                let y = lp.step(x);
                if n > 10_000 {
                    peak = peak.max(y.abs());
                }
            }
            assert!((peak - want).abs() < 2e-3, "{f} Hz: {peak}");
        }
    }

    #[test]
    fn rotator_keeps_unit_amplitude_and_phase() {
        let mut r = Rotator::new(0.0);
        let d = 2.0 * PI * 150.0 / 4000.0;
        for _ in 0..4_000_000 {
            r.advance(d);
        }
        // 4e6 steps of 150/4000 turn = 150 000 turns exactly: back to 0.
        // The series and rounding leave a phase error of 0.19 rad after
        // these 1,000 s: a frequency error of 30 µHz (2e-7 relative),
        // nothing next to the throttle's wander.
        assert!((r.re * r.re + r.im * r.im - 1.0).abs() < 1e-9);
        assert!(r.im.abs() < 0.3, "{}", r.im);
    }

    #[test]
    fn uniform_pair_has_unit_variance() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..100_000 {
            let (a, b) = uniform_pair(&mut rng);
            s += a + b;
            s2 += a * a + b * b;
        }
        assert!((s / 2e5).abs() < 0.01 && (s2 / 2e5 - 1.0).abs() < 0.01);
    }
}
