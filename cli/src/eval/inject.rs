//! Fault injection on top of recorded IMU data, from a fault table written
//! like the papers' tables (the `[sizes]` and `[[faults]]` of a scenario file;
//! a whole scenario file is accepted and its other keys are ignored).
//!
//! ```toml
//! [sizes]                       # only needed for the E1–E3 / F1–F3 shapes
//! accel = [0.5, 0.05, 1.0]      # [a m/s², b m/s³, c m/s²]
//! gyro = [0.05, 0.005, 0.1]     # [a rad/s, b rad/s², c rad/s]
//! f_unit = [1.0, 0.0174533]     # F1–F3 units: [accel, gyro]
//!
//! [[faults]]
//! channel = 5                   # 0–5 = a_x a_y a_z p q r
//! start = 130.0                 # s, in the log's time
//! end = 150.0
//! kind = "E1"                   # or F1–F3, Stuck, Dropout, { Clip = 5.0 }, …
//! sign = 1.0
//! ```

use std::path::Path;

use anyhow::{bail, Context, Result};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use hal_sim::fault::{FaultKind, FaultRow, FaultSizes};

/// A fault table to inject into a log.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct FaultTable {
    /// Sizes of the shaped faults; required when the table has any.
    #[serde(default)]
    pub sizes: Option<FaultSizes>,
    /// The rows.
    pub faults: Vec<FaultRow>,
}

impl FaultTable {
    /// Parses TOML; errors give the line and column.
    pub fn parse(text: &str) -> Result<Self> {
        let t: Self =
            toml::from_str(text).map_err(|e| crate::io::scenario_file::toml_error(text, &e))?;
        if t.faults.is_empty() {
            bail!("no [[faults]] rows");
        }
        crate::io::scenario_file::validate_faults(&t.faults)?;
        if let Some(sizes) = &t.sizes {
            crate::io::scenario_file::validate_sizes(sizes)?;
        }
        if t.sizes.is_none() && t.faults.iter().any(|r| !r.is_hardware()) {
            bail!("shaped faults (E1–E3, F1–F3) need a [sizes] table");
        }
        Ok(t)
    }

    /// Reads a fault-table (or scenario) file; errors name the file.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        Self::parse(&text).with_context(|| format!("{}: not a valid fault table", path.display()))
    }

    /// The same table with every interval moved by `offset_s` (to put a
    /// scenario's table, which starts near 0 s, into a log's time base).
    pub fn shifted(mut self, offset_s: f64) -> Self {
        for r in &mut self.faults {
            r.start += offset_s;
            r.end += offset_s;
        }
        self
    }
}

/// Applies a [`FaultTable`] to a stream of recorded samples, in time order.
#[derive(Debug, Clone)]
pub struct Injector {
    table: FaultTable,
    sigma: [f64; 6],
    last: Option<[f64; 6]>,
    rng: Xoshiro256PlusPlus,
}

impl Injector {
    /// `sigma` is the per-sample noise of each channel in the recording (what
    /// `NoiseIncrease` multiplies); `seed` drives that added noise.
    pub fn new(table: FaultTable, sigma: [f64; 6], seed: u64) -> Self {
        Self {
            table,
            sigma,
            last: None,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
        }
    }

    /// Changes `sample` in place and returns the truth per channel: the
    /// added value for shaped faults, NaN while a hardware fault is active
    /// (a fault of no given sign), 0 otherwise. A `Dropout` makes the sample
    /// NaN: the monitor rejects it, as it would a missing one.
    pub fn apply(&mut self, t: f64, sample: &mut [f64; 6]) -> [f64; 6] {
        let mut truth = [0.0; 6];
        let original = *sample;
        let sizes = self.table.sizes.unwrap_or(FaultSizes {
            accel: [0.0; 3],
            gyro: [0.0; 3],
            f_unit: [0.0; 2],
        });
        for r in self.table.faults.iter().filter(|r| r.active(t)) {
            let (Some(v), Some(tr)) = (sample.get_mut(r.channel), truth.get_mut(r.channel)) else {
                continue;
            };
            if !r.is_hardware() {
                let f = r.additive(t, &sizes);
                *v += f;
                *tr += f;
                continue;
            }
            *tr = f64::NAN;
            let last = self
                .last
                .and_then(|l| l.get(r.channel).copied())
                .unwrap_or(*v);
            let orig = original.get(r.channel).copied().unwrap_or(*v);
            let sigma = self.sigma.get(r.channel).copied().unwrap_or(0.0);
            match r.kind {
                FaultKind::Stuck => *v = last,
                FaultKind::Dropout => *v = f64::NAN,
                FaultKind::Clip(level) => *v = v.clamp(-level, level),
                FaultKind::Spikes(amp) if (t - r.start).rem_euclid(0.5) < 0.03 => *v += amp,
                FaultKind::NoiseIncrease(factor) => {
                    let n: f64 = StandardNormal.sample(&mut self.rng);
                    *v += sigma * (factor * factor - 1.0).max(0.0).sqrt() * n;
                }
                FaultKind::ScaleFactor(s) => *v += s * orig,
                _ => {}
            }
        }
        // "Stuck" holds the last value the IMU *output*, faulty or not.
        if sample.iter().all(|x| x.is_finite()) {
            self.last = Some(*sample);
        }
        truth
    }
}

/// Per-sample noise σ of each channel from first differences
/// (`var(Δx)/2`, white-noise assumption), over the finite samples given.
pub fn difference_sigma<'a>(samples: impl IntoIterator<Item = &'a [f64; 6]>) -> [f64; 6] {
    let mut sum = [0.0; 6];
    let mut sum2 = [0.0; 6];
    let mut n = 0usize;
    let mut prev: Option<&[f64; 6]> = None;
    for s in samples {
        if !s.iter().all(|x| x.is_finite()) {
            prev = None;
            continue;
        }
        if let Some(p) = prev {
            for c in 0..6 {
                let d = s[c] - p[c];
                sum[c] += d;
                sum2[c] += d * d;
            }
            n += 1;
        }
        prev = Some(s);
    }
    if n < 2 {
        return [0.0; 6];
    }
    let nf = n as f64;
    std::array::from_fn(|c| ((sum2[c] / nf - (sum[c] / nf).powi(2)).max(0.0) / 2.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_applies_steps_stuck_and_shift() {
        let t = FaultTable::parse(
            "[sizes]\naccel=[0.5,0.1,1.0]\ngyro=[0.05,0.01,0.1]\nf_unit=[1.0,0.01]\n\
             [[faults]]\nchannel=5\nstart=1.0\nend=2.0\nkind=\"E1\"\nsign=-1.0\n\
             [[faults]]\nchannel=0\nstart=1.5\nend=3.0\nkind=\"Stuck\"\nsign=1.0\n",
        )
        .expect("valid table")
        .shifted(10.0);
        let mut inj = Injector::new(t, [0.0; 6], 1);
        let mut s = [1.0, 0.0, 0.0, 0.0, 0.0, 0.2];
        assert_eq!(inj.apply(10.5, &mut s), [0.0; 6]);
        let mut s = [2.0, 0.0, 0.0, 0.0, 0.0, 0.2];
        let tr = inj.apply(11.2, &mut s);
        assert!((s[5] - 0.15).abs() < 1e-12 && (tr[5] + 0.05).abs() < 1e-12);
        let mut s = [3.0, 0.0, 0.0, 0.0, 0.0, 0.2];
        let tr = inj.apply(11.6, &mut s);
        assert_eq!(s[0], 2.0, "stuck at the last output");
        assert!(tr[0].is_nan());
    }

    #[test]
    fn shaped_faults_need_sizes() {
        let e =
            FaultTable::parse("[[faults]]\nchannel=1\nstart=1.0\nend=2.0\nkind=\"E1\"\nsign=1.0\n")
                .unwrap_err();
        assert!(e.to_string().contains("[sizes]"), "{e}");
    }

    #[test]
    fn difference_sigma_of_white_noise() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let xs: Vec<[f64; 6]> = (0..20_000)
            .map(|_| {
                std::array::from_fn(|c| {
                    let n: f64 = StandardNormal.sample(&mut rng);
                    0.1 * (c as f64 + 1.0) * n + 5.0
                })
            })
            .collect();
        let s = difference_sigma(&xs);
        for (c, v) in s.iter().enumerate() {
            let want = 0.1 * (c as f64 + 1.0);
            assert!((v / want - 1.0).abs() < 0.03, "channel {c}: {v} vs {want}");
        }
    }
}
