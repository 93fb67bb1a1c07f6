//! The IMU instances of an ArduPilot DataFlash `.bin` log as an [`ImuLog`]
//! for the parity replay (split from `parity_replay.rs`, which re-exports
//! these).

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::parity_replay::{ImuLog, MAX_IMUS};

/// Reads the IMU instances of an ArduPilot DataFlash `.bin` log (messages
/// `IMU`, `IMU2`, `IMU3`, or `IMU` with an instance field `I`), with the
/// `ardupilot-binlog` parser. Rows are the timestamps at which every
/// instance logged a sample (ArduPilot logs them synchronously). A log that
/// ends mid-message (truncated, or power lost) is read up to that point;
/// the number of such errors is returned in [`ImuLog::skipped`].
pub fn read_dataflash(path: &Path) -> Result<ImuLog> {
    let log = read_dataflash_imus(path)?;
    if log.count < 2 {
        bail!(
            "{}: fewer than two IMU instances (IMU, IMU2, IMU3) in the log",
            path.display()
        );
    }
    Ok(log)
}

/// Largest |acceleration| (m/s²) and |rate| (rad/s) an IMU sample may carry
/// before it is taken for a corrupt record rather than a measurement.
const PLAUSIBLE_ACCEL: f64 = 2000.0;
const PLAUSIBLE_GYRO: f64 = 200.0;

/// Reads every IMU instance of a DataFlash log (one or more), keeping the
/// rows where all instances share a timestamp. How far the file could be
/// read and what was skipped (garbage bytes, a truncated last message,
/// samples with non-finite or implausible values) is described in
/// [`ImuLog::warnings`]; a file with fewer than 10 usable rows is an error
/// naming the file. A panic inside the parser becomes such an error too.
pub fn read_dataflash_imus(path: &Path) -> Result<ImuLog> {
    use std::collections::BTreeMap;
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let scan = crate::io::dataflash_scan::scan(&bytes);
    if scan.messages == 0 {
        bail!(
            "{}: not a DataFlash log (no valid message in {} bytes)",
            path.display(),
            bytes.len()
        );
    }
    let mut by_time: BTreeMap<u64, [Option<[f64; 6]>; MAX_IMUS]> = BTreeMap::new();
    let mut instances = 0usize;
    let mut implausible = 0usize;
    let parsed = crate::io::guard::catch_quietly(|| {
        let reader = ardupilot_binlog::Reader::new(std::io::Cursor::new(&bytes[..]));
        for e in reader {
            // The reader resynchronises on garbage itself; an error here is
            // an unreadable tail.
            let Ok(e) = e else { break };
            let inst = match e.name.as_str() {
                "IMU" => e.get_u64("I").map_or(0, |i| i as usize),
                "IMU2" => 1,
                "IMU3" => 2,
                _ => continue,
            };
            if inst >= MAX_IMUS {
                continue;
            }
            let t_us = e
                .get_u64("TimeUS")
                .or_else(|| e.get_u64("TimeMS").map(|ms| ms.saturating_mul(1000)))
                .or(e.timestamp_usec);
            let Some(t_us) = t_us else { continue };
            let v = |k: &str| e.get_f64(k).unwrap_or(f64::NAN);
            let sample = [
                v("AccX"),
                v("AccY"),
                v("AccZ"),
                v("GyrX"),
                v("GyrY"),
                v("GyrZ"),
            ];
            instances = instances.max(inst + 1);
            let ok = sample.iter().enumerate().all(|(i, x)| {
                x.is_finite()
                    && x.abs()
                        <= if i < 3 {
                            PLAUSIBLE_ACCEL
                        } else {
                            PLAUSIBLE_GYRO
                        }
            });
            if !ok {
                implausible += 1;
                continue;
            }
            if let Some(slot) = by_time.entry(t_us).or_default().get_mut(inst) {
                *slot = Some(sample);
            }
        }
    });
    if let Err(why) = parsed {
        bail!(
            "{}: corrupt DataFlash log: the parser failed ({why})",
            path.display()
        );
    }
    if instances == 0 {
        bail!("{}: no IMU messages in the log", path.display());
    }
    let mut log = ImuLog {
        count: instances,
        skipped: usize::from(scan.truncated_at.is_some()),
        ..ImuLog::default()
    };
    for (t_us, row) in by_time {
        let Some(all) = row
            .iter()
            .take(instances)
            .copied()
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        log.t.push(t_us as f64 * 1e-6);
        log.imus.push(all);
    }
    if log.t.len() < 10 {
        bail!(
            "{}: fewer than 10 synchronous IMU rows ({} found{})",
            path.display(),
            log.t.len(),
            scan.describe_problems()
                .map_or(String::new(), |p| format!("; {p}"))
        );
    }
    let mut problems: Vec<String> = scan.describe_problems().into_iter().collect();
    if implausible > 0 {
        problems.push(format!(
            "dropped {implausible} IMU samples with non-finite or implausible values"
        ));
    }
    if !problems.is_empty() {
        log.warnings.push(format!(
            "{}: read {} IMU rows up to t = {:.1} s; {}",
            path.display(),
            log.t.len(),
            log.t.last().copied().unwrap_or(0.0),
            problems.join("; ")
        ));
    }
    Ok(log)
}
