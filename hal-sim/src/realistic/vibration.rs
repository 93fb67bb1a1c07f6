//! The board's common vibration at run time: rotor tones on phase
//! rotators (no `sin` per step), the high rotor line, broadband band-pass
//! noise, all scaled with throttle.

use core::f64::consts::PI;

use rand_xoshiro::Xoshiro256PlusPlus;

use super::dsp::{uniform_pair, Biquad, Rotator};
use super::{VibrationParams, CHANNELS};

/// The common vibration source.
#[derive(Debug, Clone)]
pub(super) struct Vibration {
    p: VibrationParams,
    rotors: [Rotator; 2],
    /// Complex coupling of each harmonic into each channel (random phase).
    coupling: [[Rotator; CHANNELS]; 3],
    band: [Biquad; CHANNELS],
    /// Gain from unit uniform noise to the band-pass output sd of 1.
    band_gain: f64,
}

impl Vibration {
    pub(super) fn new(p: VibrationParams, internal_hz: f64, rng: &mut Xoshiro256PlusPlus) -> Self {
        let mut phase = || {
            let (u, _) = uniform_pair(rng);
            Rotator::new(u * PI / 1.732_050_807_568_877_2)
        };
        let rotors = [phase(), phase()];
        let coupling = core::array::from_fn(|_| core::array::from_fn(|_| phase()));
        let (fc, q) = p.broadband_band;
        let band = Biquad::bandpass(fc, q, internal_hz);
        // Noise-equivalent bandwidth of the RBJ band-pass ≈ π fc /(2Q)
        // (one-sided), so unit white noise at fs gives sd² ≈ 2·ENBW/fs.
        let enbw = PI * fc / (2.0 * q);
        let band_gain = 1.0 / libm::sqrt((2.0 * enbw / internal_hz).min(1.0));
        Self {
            p,
            rotors,
            coupling,
            band: [band; CHANNELS],
            band_gain,
        }
    }

    #[inline]
    pub(super) fn step(
        &mut self,
        throttle: f64,
        hover: f64,
        dt: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> [f64; CHANNELS] {
        let (f0, f1) = self.p.blade_pass_hz;
        let f = f0 + (f1 - f0) * libm::sqrt(throttle.clamp(0.0, 1.0));
        let d = 2.0 * PI * f * dt;
        self.rotors[0].advance(d);
        self.rotors[1].advance(d * (1.0 + self.p.rotor_spread));
        let h1 = self.rotors;
        let h2 = [h1[0].square(), h1[1].square()];
        let h3 = [h2[0].mul(&h1[0]), h2[1].mul(&h1[1])];
        let line = if self.p.line_order > 0 {
            let mut z = h1;
            for _ in 1..self.p.line_order {
                z = [z[0].mul(&h1[0]), z[1].mul(&h1[1])];
            }
            Some(z)
        } else {
            None
        };
        let r = throttle / hover.max(1e-3);
        let scale = if self.p.throttle_exponent == 2.0 {
            r * r
        } else {
            libm::pow(r, self.p.throttle_exponent)
        };
        let (u0, u1) = uniform_pair(rng);
        let (u2, u3) = uniform_pair(rng);
        let (u4, u5) = uniform_pair(rng);
        let u = [u0, u1, u2, u3, u4, u5];
        let mut out = [0.0; CHANNELS];
        for (ch, o) in out.iter_mut().enumerate() {
            let mut v = 0.0;
            for (h, z) in [h1, h2, h3].iter().enumerate() {
                let c = &self.coupling[h][ch];
                // Re(c · (z_a + z_b)/√2): the two rotor pairs, unit rms sum.
                let re = (z[0].re + z[1].re) * c.re - (z[0].im + z[1].im) * c.im;
                v += self.p.harmonic_amp[h][ch] * re * core::f64::consts::FRAC_1_SQRT_2;
            }
            if let Some(z) = line {
                // Its coupling phase: the fundamental's, rotated.
                let c = &self.coupling[0][ch];
                let re = (z[0].re + z[1].re) * c.im + (z[0].im + z[1].im) * c.re;
                v += self.p.line_amp[ch] * re * core::f64::consts::FRAC_1_SQRT_2;
            }
            v += self.p.broadband_sd[ch] * self.band_gain * self.band[ch].step(u[ch]);
            *o = scale * v;
        }
        out
    }
}
