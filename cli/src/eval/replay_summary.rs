//! What a SPEC §10 replay reports: the JSON summary and its per-channel
//! rows.

use super::replay_monitor::MonitorKind;

/// Per-channel summary of a replay.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ChannelSummary {
    /// Channel name.
    pub channel: String,
    /// Samples flagged while monitoring (either sign).
    pub flagged_samples: usize,
    /// Time of the first flag, s.
    pub first_detection_s: Option<f64>,
    /// Flag events while monitoring: runs of consecutive flagged samples
    /// (an alarm raised, whatever its length, counts once).
    pub flag_events: usize,
    /// With truth: flag events that start on a fault-free monitored
    /// sample outside the grace time (false-alarm events).
    pub false_alarm_events: Option<usize>,
    #[serde(skip)]
    pub(crate) was_flagged: bool,
    /// With truth columns: fault-active monitored samples.
    pub fault_samples: Option<usize>,
    /// With truth: of those, flagged with the right sign.
    pub correct_samples: Option<usize>,
    /// Of the flagged samples, those where every IMU of the file flagged
    /// this channel at once: the aiding or the model, not this IMU (files
    /// with two or more IMUs only).
    pub common_mode_samples: usize,
    /// With truth: fault-free monitored samples flagged.
    pub false_alarm_samples: Option<usize>,
    /// With truth: time of the first flag with the right sign during a fault, s.
    pub first_correct_s: Option<f64>,
    /// With truth: RMS error of the fault estimate over this channel's
    /// fault-active monitored samples (SPEC §9), SI units: m/s² for the
    /// accelerometer channels, rad/s for the gyro channels.
    #[serde(skip)]
    pub fault_rmse_si: Option<f64>,
    /// The same for an accelerometer channel, m/s² (JSON `fault_rmse_m_s2`).
    pub fault_rmse_m_s2: Option<f64>,
    /// The same for a gyro channel, rad/s (JSON `fault_rmse_rad_s`).
    pub fault_rmse_rad_s: Option<f64>,
    /// Samples behind `fault_rmse_si`.
    #[serde(skip)]
    pub fault_rmse_n: usize,
    #[serde(skip)]
    pub(crate) fault_sq_sum: f64,
}

/// What a replay did.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ReplaySummary {
    /// The monitor replayed (`ukf` or `otsukf`).
    pub monitor: MonitorKind,
    /// Input rows read.
    pub rows: usize,
    /// Rows skipped (non-increasing or missing time, unparsable values).
    pub skipped_rows: usize,
    /// Rows whose IMU sample the monitor rejected (NaN, out of range).
    pub rejected_imu_rows: usize,
    /// Set when the CSV's last row was cut short (a log that ends
    /// mid-write) and dropped: one line naming the file and the line.
    pub ended_early: Option<String>,
    /// Set when IMU cells were infinite or beyond the plausible range and
    /// read as missing samples: one line naming the file, the count and
    /// the first.
    pub corrupt_cells: Option<String>,
    /// Aiding model detected from the columns.
    pub aiding: String,
    /// Tuning profile used (`Sim` or `Flight`).
    pub profile: String,
    /// IMU instances monitored.
    pub imus: usize,
    /// Median IMU rate of the rows replayed, Hz.
    pub imu_rate_hz: f64,
    /// First and last time replayed, s.
    pub span_s: (f64, f64),
    /// IMU 0's process-noise PSD `[a_x … r]` ((m/s²)²/Hz, (rad/s)²/Hz).
    #[serde(skip)]
    pub process_noise_psd: Vec<f64>,
    /// Its accelerometer part, (m/s²)²/Hz = m²/s³.
    pub process_noise_psd_accel_m2_s3: Vec<f64>,
    /// Its gyro part, (rad/s)²/Hz = rad²/s.
    pub process_noise_psd_gyro_rad2_s: Vec<f64>,
    /// Measurement σ `[v×3 (m/s), roll, pitch, yaw (rad)]`.
    #[serde(skip)]
    pub meas_sigma: Vec<f64>,
    /// Its velocity part, m/s.
    pub meas_sigma_velocity_m_s: Vec<f64>,
    /// Its attitude part, rad.
    pub meas_sigma_attitude_rad: Vec<f64>,
    /// Time monitoring started, s.
    pub monitoring_from_s: Option<f64>,
    /// Rows IMU 0's monitor spent monitoring.
    pub monitored_samples: usize,
    /// Per channel.
    pub channels: Vec<ChannelSummary>,
    /// Per IMU, the accelerometer nominal bias the monitor learnt and
    /// removes on the last row `[x, y, z]`: bounded by the turn-on bias
    /// (`--turn-on-bias`), beyond which a bias present from power-up is
    /// reported as a fault.
    pub nominal_bias_accel_m_s2: Vec<[f64; 3]>,
    /// Per IMU, the gyro nominal bias, likewise.
    pub nominal_bias_gyro_rad_s: Vec<[f64; 3]>,
    /// Per IMU, the UKF monitor's learned inflation of each aiding
    /// channel's t statistic `[v×3, roll, pitch, yaw]` (empty for the
    /// OTSUKF).
    #[serde(rename = "innovation_inflation_factor")]
    pub innovation_inflation: Vec<[f64; 6]>,
    /// How the UKF monitor's aiding latency (the OTSUKF's attitude
    /// latency) was set: `fixed` (`--aiding-delay SECONDS`, default 0) or
    /// `auto` (estimated online); `None` for the OTSUKF without the option
    /// (attitude fused on arrival).
    pub aiding_delay_mode: Option<String>,
    /// Per IMU, the aiding latency the UKF monitor fused at on the last
    /// row, s: the configured value, or with `--aiding-delay auto` the
    /// online estimate (the OTSUKF's attitude latency; empty for the
    /// OTSUKF without the option).
    pub aiding_delay_s: Vec<f64>,
    /// Whether the heading offset of the attitude aiding was estimated
    /// (`--heading-offset auto`).
    pub heading_offset_estimated: bool,
    /// Per IMU, the heading offset the UKF monitor took off the yaw aiding
    /// on the last row, degrees (0 unless estimated; empty for the OTSUKF).
    pub heading_offset_deg: Vec<f64>,
    /// How the velocity aiding's own latency was set: `fixed`
    /// (`--velocity-delay SECONDS`, default 0) or `auto` (fitted on each
    /// IMU's learning span, `imu_fdi_cli::eval::gnss_lag`).
    pub velocity_delay_mode: String,
    /// Per IMU, that latency, s (a multiple of the IMU period).
    pub velocity_delay_s: Vec<f64>,
    /// Per IMU, with `--velocity-delay auto`: RMS of the fit's residual
    /// velocity change between consecutive aiding samples at that lag, m/s
    /// (two aiding errors and the IMU's integration error over one
    /// interval).
    pub velocity_fit_rms_m_s: Vec<f64>,
    /// Per IMU, the OTSUKF's own compensated velocity latency
    /// (`--velocity-lag`), s (empty for the UKF monitor).
    pub otsukf_velocity_lag_s: Vec<f64>,
    /// Per IMU, the UKF monitor's own compensated velocity latency
    /// (`--velocity-lag`, `UkfMonitorConfig::velocity_delay_s`), s (empty
    /// without the option and for the OTSUKF).
    pub ukf_velocity_lag_s: Vec<f64>,
    /// Per IMU (UKF monitor, `--velocity-increment on`): the GNSS lag the
    /// accelerometer/GNSS-velocity test used on the last row, s.
    pub velocity_increment_lag_s: Vec<f64>,
    /// Per IMU: that test's learnt accelerometer offset against the GNSS
    /// velocity (x, y, z), m/s².
    pub velocity_increment_offset_m_s2: Vec<[f64; 3]>,
}
