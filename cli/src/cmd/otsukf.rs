//! `imu-fdi-sim otsukf`: The optimal two-stage UKF (OTSUKF) on S3 (s3: realistic sensors; s3-paper: the paper's noise, aiding at the IMU rate): SPEC §9 RMSE over seeds, beside the 12-state augmented UKF and the paper's numbers.

use anyhow::{anyhow, Result};

use super::scenario;

// The arguments of `otsukf` (its help text is the doc comment on `Cmd::Otsukf`
// in main.rs, where the subcommands are listed).
#[derive(clap::Args)]
pub(crate) struct Args {
    /// Scenario: s3 or s3-paper.
    #[arg(default_value = "s3")]
    name: String,
    /// First seed (held-out seeds start at 100).
    #[arg(long, default_value_t = 100)]
    first_seed: u64,
    /// Number of seeds.
    #[arg(long, default_value_t = 20)]
    seeds: u64,
    /// Also run the 12-state augmented UKF on the same seeds.
    #[arg(long)]
    augmented: bool,
    /// Run the OTSUKF monitor in f32 (default f64).
    #[arg(long)]
    f32: bool,
    /// Q^f multiplier while a fault is tracked (1 = no adaptation: the
    /// augmented UKF's fixed Q^f, for a like-for-like comparison): one
    /// value for every channel or six (a_x a_y a_z p q r).
    #[arg(long, value_delimiter = ',')]
    adapt_gain: Option<Vec<f64>>,
    /// Standardised move of one update that starts the adaptation.
    #[arg(long)]
    adapt_k: Option<f64>,
    /// How long the adaptation holds, s.
    #[arg(long)]
    adapt_hold: Option<f64>,
    /// The adaptation also holds while |f̂ − b| ≥ this many σ_f
    /// (0: only sudden moves start it).
    #[arg(long)]
    adapt_level: Option<f64>,
    /// Multiplier of the accelerometer and gyro fault random walk Q^f
    /// (both filters), e.g. `1,3`.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "ACCEL,GYRO",
        allow_negative_numbers = true
    )]
    qf_scale: Option<Vec<f64>>,
    /// Run the scenario with its fault table removed: the fault rows
    /// are then empty and the last row gives the estimates' noise.
    #[arg(long)]
    fault_free: bool,
    /// Keep only the fault rows of one shape (F1 step, F2 ramp, F3 sine).
    #[arg(long)]
    shape: Option<String>,
    /// One JSON object on stdout instead of the table (docs/cli-json.md).
    #[arg(long)]
    json: bool,
}

/// Runs `otsukf`.
pub(crate) fn run(args: Args) -> Result<()> {
    let Args {
        name,
        first_seed,
        seeds,
        augmented,
        f32,
        adapt_gain,
        adapt_k,
        adapt_hold,
        adapt_level,
        qf_scale,
        fault_free,
        shape,
        json,
    } = args;
    use hal_sim::ots::{run_augmented, run_otsukf, RmseAccumulator, Setting, PAPER_RMSE};
    use imu_fdi::model::ImuVec;
    let mut scn = scenario(&name)?;
    if fault_free {
        scn.faults.clear();
    }
    if let Some(shape) = shape.as_deref() {
        let kind = match shape.to_ascii_uppercase().as_str() {
            "F1" => hal_sim::FaultKind::F1,
            "F2" => hal_sim::FaultKind::F2,
            "F3" => hal_sim::FaultKind::F3,
            other => return Err(anyhow!("--shape {other}: expected F1, F2 or F3")),
        };
        scn.faults.retain(|r| r.kind == kind);
    }
    if seeds == 0 {
        return Err(anyhow!("--seeds must be at least 1"));
    }
    let setting = if name.contains("paper") {
        Setting::Paper
    } else {
        Setting::Realistic
    };
    let qf = match qf_scale.as_deref() {
        None => [1.0, 1.0],
        Some([a, g]) if *a > 0.0 && *g > 0.0 => [*a, *g],
        Some(_) => return Err(anyhow!("--qf-scale needs two positive numbers")),
    };
    let adapt_gain = match adapt_gain.as_deref() {
        None => None,
        Some(g) if g.iter().any(|v| !v.is_finite() || *v < 1.0) => {
            return Err(anyhow!("--adapt-gain values must be at least 1"))
        }
        Some([g]) => Some(ImuVec::from_element(*g)),
        Some(g) if g.len() == 6 => Some(ImuVec::from_row_slice(g)),
        Some(_) => return Err(anyhow!("--adapt-gain takes one value or six")),
    };
    let tuning = OtsTuning {
        qf,
        gain: adapt_gain,
        k: adapt_k,
        hold: adapt_hold,
        level: adapt_level,
    };
    let (mut two, mut aug) = (RmseAccumulator::default(), RmseAccumulator::default());
    let mut false_flags = 0u64;
    for seed in first_seed..first_seed + seeds {
        let (acc, ff) = if f32 {
            run_otsukf::<f32>(&scn, seed, tuning.config(&scn, setting))
        } else {
            run_otsukf::<f64>(&scn, seed, tuning.config(&scn, setting))
        }
        .ok_or_else(|| anyhow!("the OTSUKF monitor refused its configuration"))?;
        two.merge(&acc);
        false_flags += ff;
        if augmented {
            let c = tuning.fault_walk_only().config::<f64>(&scn, setting);
            let a = run_augmented(&scn, seed, &c).ok_or_else(|| anyhow!("augmented UKF failed"))?;
            aug.merge(&a);
        }
    }
    if json {
        // Keys carry the unit of each RMSE (SPEC §9 table units).
        const KEYS: [&str; 12] = [
            "u_m_s",
            "v_m_s",
            "w_m_s",
            "roll_deg",
            "pitch_deg",
            "yaw_deg",
            "f_ax_m_s2",
            "f_ay_m_s2",
            "f_az_m_s2",
            "f_p_deg_s",
            "f_q_deg_s",
            "f_r_deg_s",
        ];
        let obj = |v: &[f64]| {
            serde_json::Value::Object(
                KEYS.iter()
                    .zip(v.iter())
                    .map(|(k, x)| ((*k).to_string(), serde_json::json!(x)))
                    .collect(),
            )
        };
        let (r2, ra) = (two.rmse(), aug.rmse());
        let (q2, qa) = (two.quiet_rms(), aug.quiet_rms());
        let quiet = |q: &[f64]| {
            serde_json::Value::Object(
                KEYS[6..]
                    .iter()
                    .zip(q.iter())
                    .map(|(k, x)| ((*k).to_string(), serde_json::json!(x)))
                    .collect(),
            )
        };
        super::json::emit(&serde_json::json!({
            "scenario": scn.name,
            "first_seed": first_seed,
            "seeds": seeds,
            "rmse": {
                "otsukf": obj(&r2),
                "augmented": if augmented { obj(&ra) } else { serde_json::Value::Null },
                "paper": obj(&PAPER_RMSE),
            },
            "fault_free_noise": {
                "otsukf": quiet(&q2),
                "augmented": if augmented { quiet(&qa) } else { serde_json::Value::Null },
            },
            "false_flags": false_flags,
        }));
        return Ok(());
    }
    out!(
            "{} — SPEC §9 RMSE over seeds {}..{} (states over fault-active samples; each fault over its own)",
            scn.name,
            first_seed,
            first_seed + seeds - 1
        );
    out!("units: u v w m/s; φ θ ψ deg; f_a m/s²; f_g °/s");
    out!(
        "{:<6} {:>12} {:>12} {:>10}",
        "",
        "two-stage",
        if augmented { "augmented" } else { "" },
        "paper"
    );
    let names = [
        "u", "v", "w", "φ", "θ", "ψ", "f_ax", "f_ay", "f_az", "f_p", "f_q", "f_r",
    ];
    let (r2, ra) = (two.rmse(), aug.rmse());
    for i in 0..12 {
        if augmented {
            out!(
                "{:<6} {:>12.4} {:>12.4} {:>10.4}",
                names[i],
                r2[i],
                ra[i],
                PAPER_RMSE[i]
            );
        } else {
            out!(
                "{:<6} {:>12.4} {:>12} {:>10.4}",
                names[i],
                r2[i],
                "",
                PAPER_RMSE[i]
            );
        }
    }
    let (q2, qa) = (two.quiet_rms(), aug.quiet_rms());
    out!("fault-free noise: RMS of each fault estimate before its channel's first fault");
    for c in 0..6 {
        if augmented {
            out!("{:<6} {:>12.4} {:>12.4}", names[6 + c], q2[c], qa[c]);
        } else {
            out!("{:<6} {:>12.4}", names[6 + c], q2[c]);
        }
    }
    out!("false flags (monitoring samples flagged on a channel without a fault in the last 2 s): {false_flags}");
    Ok(())
}

/// The command line's changes to the S3 two-stage configuration
/// (`cargo sim otsukf`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct OtsTuning {
    /// Multipliers of the accelerometer and gyro fault random walk.
    qf: [f64; 2],
    /// `adapt_gain` per channel.
    gain: Option<imu_fdi::model::ImuVec<f64>>,
    /// `adapt_k`.
    k: Option<f64>,
    /// `adapt_hold_s`.
    hold: Option<f64>,
    /// `adapt_level` (≤ 0: none).
    level: Option<f64>,
}

impl OtsTuning {
    /// The paper's or realistic configuration with these changes.
    fn config<T: imu_fdi::math::Real>(
        &self,
        scn: &hal_sim::Scenario,
        setting: hal_sim::ots::Setting,
    ) -> imu_fdi::monitor::OtsukfConfig<T> {
        let mut c = hal_sim::ots::otsukf_config::<T>(scn, setting);
        for (i, q) in c.fault_psd.iter_mut().enumerate() {
            *q *= T::lit(if i < 3 { self.qf[0] } else { self.qf[1] });
        }
        if let Some(g) = self.gain {
            c.adapt_gain = g.map(T::lit);
        }
        if let Some(k) = self.k {
            c.adapt_k = T::lit(k);
        }
        if let Some(h) = self.hold {
            c.adapt_hold_s = T::lit(h);
        }
        match self.level {
            Some(l) if l > 0.0 => c.adapt_level = Some(T::lit(l)),
            Some(_) => c.adapt_level = None,
            None => {}
        }
        c
    }

    /// Only the fault random walk: what the augmented UKF shares (it has
    /// no adaptation).
    fn fault_walk_only(&self) -> Self {
        Self {
            qf: self.qf,
            gain: None,
            k: None,
            hold: None,
            level: None,
        }
    }
}
