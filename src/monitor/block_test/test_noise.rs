//! The block tests' unit tests' noise: a small deterministic Gaussian
//! source (xorshift + Box–Muller), one sequence per seed.

use nalgebra::Vector3;

/// Deterministic N(0, 1) samples from seed `.0` (non-zero).
pub(in crate::monitor) struct Noise(pub u64);

impl Noise {
    /// A uniform sample in (0, 1).
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// A standard normal sample.
    pub fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        libm::sqrt(-2.0 * libm::log(u)) * libm::cos(2.0 * core::f64::consts::PI * v)
    }

    /// Three independent normal samples of standard deviation `s`.
    pub fn vec(&mut self, s: f64) -> Vector3<f64> {
        Vector3::new(self.gauss(), self.gauss(), self.gauss()) * s
    }
}
