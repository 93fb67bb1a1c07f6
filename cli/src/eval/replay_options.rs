//! The options of a SPEC §10 replay ([`super::replay::replay`]): tuning
//! profile, learning, aiding noise and latencies, the monitor.

use imu_fdi::model::{AidingKind, ImuVec, MeasVec};
use imu_fdi::monitor::{AttitudeRateConfig, UkfMonitorConfig, VelocityIncrementConfig};

use super::replay_monitor::MonitorKind;

/// How the monitor is tuned for a replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// The built-in scenarios' tuning (S2 for DVL aiding, S3 for GNSS):
    /// for simulated runs written by `simulate`.
    Sim,
    /// A real flight: aiding noise widened for an autopilot's own attitude
    /// estimate and consumer GNSS, IMU noise measured on the log.
    Flight,
    /// `Sim` when the file has truth columns (`fault_imu0_*`), else `Flight`.
    Auto,
}

/// Options of [`replay`](super::replay::replay) beyond the files.
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// With truth: seconds after a fault during which flags count neither as
    /// false alarms nor as detections (the window is flushing).
    pub grace_s: f64,
    /// Rows before this time are ignored (start the monitor in flight).
    pub from_s: Option<f64>,
    /// Rows after this time are ignored.
    pub to_s: Option<f64>,
    /// Faults to inject, and the IMU instance they go on.
    pub inject: Option<(crate::eval::inject::FaultTable, usize)>,
    /// Seed of injected noise.
    pub seed: u64,
    /// Tuning.
    pub profile: Profile,
    /// Learning phase, s (None: the profile's).
    pub learn_s: Option<f64>,
    /// Flight profile: GNSS (or DVL) velocity σ, m/s.
    pub vel_sigma: f64,
    /// Flight profile: attitude σ (roll, pitch, yaw), rad.
    pub att_sigma: [f64; 3],
    /// The monitor to run on every IMU.
    pub monitor: MonitorKind,
    /// Bound of the learned innovation inflation (UKF monitor; 1 disables;
    /// None: 25 for the flight profile, 1 for the simulated one).
    pub max_inflation: Option<f64>,
    /// Memory of the learned inflation in flight, s (UKF monitor; 0:
    /// frozen; None: 120 for the flight profile, 0 for the simulated one).
    pub inflation_memory: Option<f64>,
    /// Aiding latency (UKF monitor): fixed, or estimated online.
    pub aiding_delay: AidingDelay,
    /// Estimate the attitude aiding's heading offset online (UKF monitor).
    pub estimate_heading_offset: bool,
    /// Latency of the velocity aiding alone (GNSS or DVL columns), fixed or
    /// learned on each IMU's learning span ([`super::gnss_lag`]); either
    /// monitor. The replay fuses each velocity sample at the row it
    /// describes (the log is at hand: the offline equivalent of delayed
    /// fusion at a known lag).
    pub velocity_delay: AidingDelay,
    /// The velocity aiding's latency the monitor compensates itself,
    /// causally, fixed or (`Auto`) fitted on each IMU's learning span as
    /// `velocity_delay`'s `auto` is, in the flight profile with GNSS aiding
    /// (0 otherwise). OTSUKF: `OtsukfConfig::velocity_lag_s`, `None` is
    /// `Auto`. UKF monitor: `UkfMonitorConfig::velocity_delay_s` (the
    /// velocity brought to the attitude's fusion horizon), `None` shares
    /// the attitude's latency (`aiding_delay`).
    pub velocity_lag: Option<AidingDelay>,
    /// Flight profile, either monitor: run the gyro/attitude-aiding
    /// consistency test (`UkfMonitorConfig::attitude_rate`, default on).
    pub attitude_rate: bool,
    /// Flight profile, either monitor: run the accelerometer/GNSS-velocity
    /// consistency test (`UkfMonitorConfig::velocity_increment`, default
    /// on; GNSS aiding only).
    pub velocity_increment: bool,
    /// Flight profile: the turn-on bias bound `[accelerometer x/y m/s²,
    /// accelerometer z m/s², gyro rad/s]`
    /// (`UkfMonitorConfig::max_nominal_bias`).
    pub turn_on_bias: [f64; 3],
}

/// How the UKF monitor treats the aiding's latency
/// ([`imu_fdi::monitor::UkfMonitorConfig::aiding_delay_s`],
/// [`imu_fdi::monitor::UkfMonitorConfig::estimate_aiding_delay`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AidingDelay {
    /// A known latency, s (0: fused on arrival).
    Fixed(f64),
    /// Estimated online from the attitude aiding's changes, starting at 0.
    Auto,
}

impl Default for AidingDelay {
    fn default() -> Self {
        Self::Fixed(0.0)
    }
}

impl Default for ReplayOptions {
    fn default() -> Self {
        let deg = core::f64::consts::PI / 180.0;
        Self {
            grace_s: 4.4,
            from_s: None,
            to_s: None,
            inject: None,
            seed: 1,
            profile: Profile::Auto,
            learn_s: None,
            vel_sigma: 0.3,
            att_sigma: [1.0 * deg, 1.0 * deg, 10.0 * deg],
            monitor: MonitorKind::Ukf,
            max_inflation: None,
            inflation_memory: None,
            aiding_delay: AidingDelay::default(),
            estimate_heading_offset: false,
            velocity_delay: AidingDelay::default(),
            velocity_lag: None,
            attitude_rate: true,
            velocity_increment: true,
            turn_on_bias: [1.5, 3.0, 5.0 * deg],
        }
    }
}

/// The monitor tuning of the `Flight` profile: `base` (its detector and
/// test settings are kept) with the aiding noise of `opts`, period `dt` and
/// the process noise measured on IMU samples `imu` (rows within the learning
/// span).
pub fn flight_config(
    mut c: UkfMonitorConfig<f64>,
    dt: f64,
    imu: &[[f64; 6]],
    opts: &ReplayOptions,
) -> UkfMonitorConfig<f64> {
    let [r, p, y] = opts.att_sigma;
    c.meas_sigma = MeasVec::new(opts.vel_sigma, opts.vel_sigma, opts.vel_sigma, r, p, y);
    // Vibration dominates a flying vehicle's IMU noise; measure it, with a
    // floor at the datasheet-class default (a bench log reads ~0).
    let sigma = crate::eval::inject::difference_sigma(imu);
    for (i, s) in sigma.iter().enumerate() {
        if let Some(q) = c.process_noise.psd.get_mut(i) {
            *q = q.max(s * s * dt);
        }
    }
    c.imu_period = dt;
    c.learn_s = opts.learn_s.unwrap_or(20.0);
    // A calibrated autopilot IMU's turn-on bias, not 20 × `min_fault`
    // (4 m/s², 20 °/s on the GNSS preset, which absorbed a 20 °/s gyro bias
    // present from power-up on log171 without a word). What a healthy
    // vehicle shows against its aiding: on log171 the learnt biases stay
    // within 0.3 m/s² on x/y and 0.82 °/s at the end of learning, while
    // vibration rectification moves a_z by up to 1 m/s² in flight and
    // 2–2.7 m/s² in IMU2's climb (which the learner follows when learning
    // spans take-off: the thrust axis gets twice the room), and a learner
    // spanning take-off follows a gyro transient beyond 3 °/s (learning
    // from 65 s: one more event in flight with a 3 °/s bound, none with
    // 4 °/s). PX4's EKF2 starts its bias states at σ 0.2 m/s² and
    // 0.1 rad/s (`EKF2_ABIAS_INIT`, `EKF2_GBIAS_INIT`).
    let [a, z, g] = opts.turn_on_bias;
    c.max_nominal_bias = Some(ImuVec::new(a, a, z, g, g, g));
    // Real aiding errors are time-correlated: learn the t statistic's
    // inflation on the flight's own healthy start (bounded: a fault up to
    // √25 = 5× the white-noise detectable size is still found).
    c.max_innovation_inflation = opts.max_inflation.unwrap_or(25.0);
    // ... followed in flight: learnt on the ground it says nothing of
    // flight (log171 from its start: 80–105 events per IMU frozen).
    c.inflation_memory_s = opts.inflation_memory.unwrap_or(120.0);
    // The tracking fault estimate (the window mean lags and is noisy).
    c.fault_psd = Some(UkfMonitorConfig::fault_tracking_psd());
    // Small gyro biases against an autopilot's wandering attitude: the gyro
    // against the attitude aiding over windows of seconds, their spread
    // learnt on this flight (issue 15).
    if opts.attitude_rate {
        c.attitude_rate = Some(AttitudeRateConfig::flight());
    }
    // Small accelerometer biases against GNSS velocity: the velocity
    // increment over windows of seconds (issue 15). It needs NED velocity.
    if opts.velocity_increment && c.aiding == AidingKind::GnssAttitude {
        c.velocity_increment = Some(VelocityIncrementConfig::velocity());
    }
    c
}
