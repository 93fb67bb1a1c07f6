//! One sensor's signal chain at run time: analog anti-alias filter, the ADC
//! sampling on the chip's own clock (between two internal steps), noise,
//! clipping, quantisation, the chip's digital low-pass, the driver filters,
//! and what the logger takes (latest value or the interval's mean).

use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use super::dsp::Biquad;
use super::{Decimation, SensorChain};

/// One sensor's running chain (3 axes).
#[derive(Debug, Clone)]
pub(super) struct ChainState {
    spec: SensorChain,
    aa: [Biquad; 3],
    chip: [Biquad; 3],
    driver: [[Biquad; 2]; 3],
    period: f64,
    next_t: f64,
    prev: [f64; 3],
    latest: [f64; 3],
    sum: [f64; 3],
    count: u32,
    pub(super) clips: u64,
    sigma: f64,
}

impl ChainState {
    pub(super) fn new(spec: SensorChain, internal_hz: f64) -> Self {
        let odr = spec.odr_hz;
        let aa = Biquad::lowpass(spec.analog_aa_hz, internal_hz);
        let chip = Biquad::lowpass(spec.chip_lpf_hz, odr);
        let d = spec.driver_lpf_hz.map(|f| Biquad::lowpass(f, odr));
        Self {
            spec,
            aa: [aa; 3],
            chip: [chip; 3],
            driver: [d; 3],
            period: 1.0 / (odr * (1.0 + spec.clock_ppm * 1e-6)),
            next_t: spec.clock_offset_s,
            prev: [0.0; 3],
            latest: [0.0; 3],
            sum: [0.0; 3],
            count: 0,
            clips: 0,
            // Per-sample σ of white noise of this density at this ODR.
            sigma: spec.noise_density * libm::sqrt(0.5 * odr),
        }
    }

    pub(super) fn settle(&mut self, x: [f64; 3]) {
        for (i, &xi) in x.iter().enumerate() {
            self.aa[i].settle(xi);
            self.chip[i].settle(xi);
            for d in self.driver[i].iter_mut() {
                d.settle(xi);
            }
        }
        self.prev = x;
        self.latest = x;
    }

    /// One internal step: `x` is the sensing element's input at `t`
    /// (the previous one at `t − dt`).
    #[inline]
    pub(super) fn step(&mut self, t: f64, dt: f64, x: [f64; 3], rng: &mut Xoshiro256PlusPlus) {
        let mut a = x;
        if self.spec.analog_aa_hz > 0.0 {
            for (ai, f) in a.iter_mut().zip(self.aa.iter_mut()) {
                *ai = f.step(*ai);
            }
        }
        while self.next_t <= t {
            // The ADC samples at its own clock, between two internal steps.
            let frac = 1.0 - (t - self.next_t) / dt;
            for (i, &ai) in a.iter().enumerate() {
                let v = self.prev[i] + frac * (ai - self.prev[i]);
                let n: f64 = StandardNormal.sample(rng);
                let mut v = v + self.sigma * n;
                let fs = self.spec.full_scale;
                if v > fs || v < -fs {
                    self.clips += 1;
                    v = v.clamp(-fs, fs);
                }
                if self.spec.lsb > 0.0 {
                    v = libm::round(v / self.spec.lsb) * self.spec.lsb;
                }
                let c = self.chip[i].step(v);
                self.sum[i] += c;
                let mut y = c;
                for d in self.driver[i].iter_mut() {
                    y = d.step(y);
                }
                self.latest[i] = y;
            }
            self.count += 1;
            self.next_t += self.period;
        }
        self.prev = a;
    }

    pub(super) fn take(&mut self, decimation: Decimation) -> [f64; 3] {
        match decimation {
            Decimation::PointSample => self.latest,
            Decimation::Integrated => {
                let out = if self.count > 0 {
                    self.sum.map(|s| s / self.count as f64)
                } else {
                    self.latest
                };
                self.sum = [0.0; 3];
                self.count = 0;
                out
            }
        }
    }
}
