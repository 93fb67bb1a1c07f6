//! What the fuzz targets share: a byte reader, the adversarial stream
//! decoder for single-IMU monitors (IMU values, timing and aiding), the
//! recovery check after it, the parity stream decoder, step counters and a
//! scratch file for the file parsers.
//!
//! A single-IMU input starts from a monitor snapshot taken while it was
//! monitoring a fault-free run (S2-like AUV or S3-like aircraft), corrupts
//! the following samples as the bytes say, then feeds `RECOVERY_S` of the
//! same run unchanged. Every step must give finite outputs; at the end
//! the monitor must be back to nominal (`hal_sim::recovery`). Inputs
//! whose first byte is odd start from a fresh monitor instead (alignment,
//! convergence and learning under attack): every step finite and, after
//! the valid rest of the run, monitoring (the learned values themselves
//! are issue 15's).
#![allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

use hal_sim::recovery::Step;
use imu_fdi::model::ImuVec;

/// Valid input after the attack before the verdict, s (issue 16).
pub const SETTLE_S: f64 = 10.0;
/// Verdict window after it: every step nominal, s.
pub const CHECK_S: f64 = 1.0;
/// Longest attack, in IMU samples (40 s at 100 Hz).
pub const MAX_ATTACK: usize = 4000;

static STEPS: AtomicU64 = AtomicU64::new(0);
static INPUTS: AtomicU64 = AtomicU64::new(0);

/// The single-IMU report's common outputs (state, its σ, fault estimate,
/// corrected sample) and the monitor-specific ones in `extra` are all
/// finite; otherwise the report, for the failure message.
pub fn outputs_finite<'a, X: core::fmt::Debug>(
    r: &'a imu_fdi::monitor::Report<f32, X>,
    extra: impl Iterator<Item = &'a f32>,
) -> Result<(), String> {
    let finite = r
        .state
        .iter()
        .chain(r.state_sigma.iter())
        .chain(r.fault_estimate.iter())
        .chain(r.corrected_imu.iter())
        .chain(extra)
        .all(|v| v.is_finite());
    if finite {
        Ok(())
    } else {
        Err(format!("non-finite output: {r:?}"))
    }
}

/// Counts `steps` monitor steps of one input; every 4096 inputs prints the
/// totals (the campaign's step count is the last line of its log).
pub fn count(steps: u64) {
    let total = STEPS.fetch_add(steps, Ordering::Relaxed) + steps;
    let n = INPUTS.fetch_add(1, Ordering::Relaxed) + 1;
    if n % 4096 == 0 {
        eprintln!("imu-fdi-fuzz: {n} inputs, {total} monitor steps");
    }
}

/// Reads the fuzz input front to back; past the end it yields zeros.
#[derive(Debug)]
pub struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    /// A reader over `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }
    /// True when every byte was read.
    pub fn done(&self) -> bool {
        self.pos >= self.data.len()
    }
    /// The next byte.
    pub fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }
    /// The next four bytes as an `f32` bit pattern (NaN, ∞, subnormal…).
    pub fn f32(&mut self) -> f32 {
        f32::from_bits(u32::from_le_bytes([
            self.u8(),
            self.u8(),
            self.u8(),
            self.u8(),
        ]))
    }
    /// A signed fraction in [−1, 1].
    pub fn frac(&mut self) -> f32 {
        f32::from(self.u8() as i8) / 127.0
    }
}

/// A fault-free run and a snapshot of the monitor at `start` (monitoring).
#[derive(Debug, Clone)]
pub struct Base<M> {
    /// The monitor after `run[..start]`.
    pub monitor: M,
    /// A fresh monitor.
    pub fresh: M,
    /// The fault-free run.
    pub run: Vec<Step>,
    /// Index of the first sample after the snapshot.
    pub start: usize,
    /// IMU full scale.
    pub full_scale: ImuVec<f32>,
}

/// One monitor step: `Err` with a reason when an output is not finite;
/// `Ok(Some(reason))` when the monitor is not nominal, `Ok(None)` when it is,
/// plus whether it is monitoring.
pub type StepResult = Result<(Option<&'static str>, bool), String>;

/// Applies the attack in `bytes` to the run from `from`, calling `step` on
/// every corrupted step; returns the index of the first clean sample after
/// it and the number of steps taken.
fn attack<M>(
    m: &mut M,
    bytes: &mut Bytes,
    run: &[Step],
    from: usize,
    full_scale: &ImuVec<f32>,
    step: &impl Fn(&mut M, &Step) -> StepResult,
) -> (usize, u64) {
    let end = (from + MAX_ATTACK).min(run.len());
    let mut k = from;
    let mut steps = 0u64;
    let mut carried = 0.0f32;
    let mut frozen: Option<ImuVec<f32>> = None;
    while !bytes.done() && k < end {
        let op = bytes.u8();
        let repeat = 1 + usize::from(op >> 4);
        let kind = op & 0x0F;
        let a = bytes.u8();
        let ch = usize::from(a) % 6;
        let value = bytes.f32();
        let frac = bytes.frac();
        for _ in 0..repeat {
            let Some(clean) = run.get(k) else { break };
            k += 1;
            let mut s = *clean;
            s.dt += carried;
            carried = 0.0;
            match kind {
                // Any bit pattern on one IMU channel.
                1 => s.imu[ch] = value,
                // An in-range offset (a fault, or saturation) on one channel.
                2 => s.imu[ch] += frac * full_scale[ch],
                // Frozen output.
                3 => s.imu = *frozen.get_or_insert(s.imu),
                // Any period.
                4 => s.dt = value,
                // Jitter: 0 … 4 periods, either sign.
                5 => s.dt *= 4.0 * frac,
                // Dropout: the sample never arrives, its time is carried.
                6 => {
                    carried = s.dt;
                    continue;
                }
                // Any bit pattern on one aiding channel, present.
                7 => {
                    s.aiding.z[ch] = value;
                    s.aiding.available[ch] = true;
                }
                // An in-range aiding offset on a channel that arrived:
                // up to 60 m/s or 1 rad.
                8 => {
                    let scale = if ch < 3 { 60.0 } else { 1.0 };
                    s.aiding.z[ch] += frac * scale;
                }
                // Aiding lost.
                9 => s.aiding.available = [false; 6],
                // Arbitrary availability (partial triads).
                10 => {
                    for (i, av) in s.aiding.available.iter_mut().enumerate() {
                        *av = a & (1 << i) != 0;
                    }
                }
                // A pitch-rate kick towards the Euler singularity.
                11 => s.imu[4] += frac * full_scale[4],
                _ => {}
            }
            if kind != 3 {
                frozen = None;
            }
            if let Err(e) = step(m, &s) {
                panic!("attack step {k}: {e}");
            }
            steps += 1;
        }
        // Kinds ≥ 12 pass clean samples: the attack also spreads out in time.
        if kind >= 12 {
            let skip = usize::from(a);
            for clean in run.iter().skip(k).take(skip) {
                if let Err(e) = step(m, clean) {
                    panic!("clean step in attack: {e}");
                }
                steps += 1;
            }
            k += skip;
        }
    }
    (k.min(run.len()), steps)
}

/// Runs one fuzz input against `base` (see the crate docs) and asserts
/// the recovery property; returns the monitor steps taken.
pub fn single_imu<M: Clone>(
    base: &Base<M>,
    data: &[u8],
    step: impl Fn(&mut M, &Step) -> StepResult,
) -> u64 {
    let mut bytes = Bytes::new(data);
    let mode = bytes.u8();
    let fresh = mode & 1 == 1;
    let (mut m, from) = if fresh {
        (base.fresh.clone(), 0)
    } else {
        (base.monitor.clone(), base.start)
    };
    let (mut k, mut steps) = attack(&mut m, &mut bytes, &base.run, from, &base.full_scale, &step);
    // The first valid sample after a dropout carries its time.
    let t_end = base.run.get(k).map_or(f64::INFINITY, |s| s.t);
    let mut last: Option<(f64, &'static str)> = None;
    let mut monitoring = false;
    while let Some(s) = base.run.get(k) {
        let r = step(&mut m, s);
        steps += 1;
        k += 1;
        let (why, mon) = match r {
            Ok(v) => v,
            Err(e) => panic!("valid step at t = {:.2} s: {e}", s.t),
        };
        monitoring = mon;
        let age = s.t - t_end;
        if age >= SETTLE_S + CHECK_S && !fresh {
            break;
        }
        if age >= SETTLE_S && !fresh {
            if let Some(w) = why {
                last.get_or_insert((age, w));
            }
        }
    }
    if !fresh {
        if let Some((age, why)) = last {
            panic!("not back to nominal {age:.2} s after the attack: {why}");
        }
    } else {
        assert!(monitoring, "not monitoring at the end of the valid run");
    }
    steps
}

/// A scratch file for this process, named with `ext`.
pub fn scratch(ext: &str) -> PathBuf {
    std::env::temp_dir().join(format!("imu-fdi-fuzz-{}.{ext}", std::process::id()))
}

/// A CLI error must be one line that names the file (issue 16).
pub fn check_error(e: &anyhow::Error, path: &std::path::Path) {
    let msg = format!("{e:#}");
    assert!(!msg.contains('\n'), "multi-line error: {msg}");
    let name = path.display().to_string();
    assert!(msg.contains(&name), "error does not name {name}: {msg}");
}
