//! Every configuration is validated completely: a zero, NaN or inverted
//! field is rejected by `validate()` (and by the monitor's `new`), and the
//! error names the field. The defaults validate.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic is a failed assertion

use imu_fdi::model::ImuVec;
use imu_fdi::monitor::{ConfigError, OtsukfConfig, OtsukfMonitor, UkfMonitor, UkfMonitorConfig};
use imu_fdi::parity::{self, Geometry, ParityConfig, ParityMonitor};

type Ukf = UkfMonitorConfig<f64>;

/// `change` applied to the AUV defaults must be rejected naming `field`.
fn ukf_rejects(field: &str, change: impl Fn(&mut Ukf)) {
    for base in [Ukf::auv(), Ukf::aircraft()] {
        let mut c = base;
        change(&mut c);
        let e = c.validate().expect_err(field);
        assert_eq!(e.field(), field, "{e}");
        assert!(e.to_string().starts_with(field), "{e}");
        assert_eq!(UkfMonitor::<f64>::new(c).err(), Some(e));
    }
}

#[test]
fn ukf_monitor_config_rejects_zero_nan_and_inverted_fields() {
    Ukf::auv().validate().unwrap();
    Ukf::aircraft().validate().unwrap();
    UkfMonitorConfig::<f32>::auv().validate().unwrap();

    ukf_rejects("process_noise", |c| c.process_noise.psd[0] = 0.0);
    ukf_rejects("process_noise", |c| c.process_noise.psd[5] = f64::NAN);
    ukf_rejects("meas_sigma", |c| c.meas_sigma[3] = -1.0);
    ukf_rejects("initial_sigma", |c| c.initial_sigma[0] = f64::INFINITY);
    ukf_rejects("full_scale", |c| c.full_scale[2] = 0.0);
    ukf_rejects("imu_period", |c| c.imu_period = 0.0);
    ukf_rejects("learn_tau_s", |c| c.learn_tau_s = f64::NAN);
    ukf_rejects("drift_tau_s", |c| c.drift_tau_s = 0.0);
    ukf_rejects("aiding_timeout_s", |c| c.aiding_timeout_s = -1.0);
    ukf_rejects("gravity", |c| c.gravity = f64::NAN);
    ukf_rejects("aiding_delay_s", |c| c.aiding_delay_s = -0.01);
    ukf_rejects("aiding_delay_s", |c| c.aiding_delay_s = 10.0);
    ukf_rejects("alpha", |c| c.alpha = 0.0);
    ukf_rejects("alpha", |c| c.alpha = f64::NAN);
    ukf_rejects("sigma", |c| c.sigma.alpha = 0.0);
    ukf_rejects("sigma", |c| c.sigma.kappa = -7.0);
    ukf_rejects("gate_sigma", |c| c.gate_sigma = 0.0);
    ukf_rejects("glr_threshold", |c| c.glr_threshold = f64::NAN);
    ukf_rejects("min_fault", |c| c.min_fault[4] = 0.0);
    ukf_rejects("threshold_fraction", |c| c.threshold_fraction = 0.0);
    ukf_rejects("persistence", |c| c.persistence = 0);
    ukf_rejects("frozen_samples", |c| c.frozen_samples = 0);
    ukf_rejects("lever_arm", |c| c.lever_arm[1] = f64::NAN);
    ukf_rejects("cos_pitch_min", |c| c.cos_pitch_min = 0.0);
    ukf_rejects("cos_pitch_min", |c| c.cos_pitch_min = 1.5);
    ukf_rejects("outlier_k", |c| c.outlier_k = -1.0);
    ukf_rejects("glr_relative", |c| c.glr_relative = 2.0);
    ukf_rejects("sign_deadband", |c| c.sign_deadband = 1.0);
    ukf_rejects("converge_s", |c| c.converge_s = f64::NAN);
    ukf_rejects("learn_s", |c| c.learn_s = -1.0);
    ukf_rejects("drift_rate_limit", |c| c.drift_rate_limit[0] = -1e-3);
}

/// `change` applied to the two-stage defaults must be rejected naming `field`.
fn ots_rejects(field: &str, change: impl Fn(&mut OtsukfConfig<f64>)) {
    let mut c = OtsukfConfig::from_base(Ukf::aircraft());
    change(&mut c);
    let e = c.validate().expect_err(field);
    assert_eq!(e.field(), field, "{e}");
    assert!(e.to_string().starts_with(field), "{e}");
    assert_eq!(OtsukfMonitor::<f64>::new(c).err(), Some(e));
}

#[test]
fn otsukf_config_rejects_zero_nan_and_inverted_fields() {
    OtsukfConfig::from_base(Ukf::aircraft()).validate().unwrap();
    OtsukfConfig::from_base(Ukf::auv()).validate().unwrap();

    // The base is validated with it.
    ots_rejects("meas_sigma", |c| c.base.meas_sigma[0] = 0.0);
    ots_rejects("fault_psd", |c| c.fault_psd[3] = 0.0);
    ots_rejects("fault_sigma0", |c| c.fault_sigma0[0] = f64::NAN);
    ots_rejects("k_on", |c| c.k_on = f64::NAN);
    ots_rejects("k_off", |c| c.k_off = 0.0);
    ots_rejects("k_off", |c| {
        c.k_on = 2.0;
        c.k_off = 4.0;
    });
    ots_rejects("adapt_k", |c| c.adapt_k = 0.0);
    ots_rejects("adapt_level", |c| c.adapt_level = Some(0.0));
    ots_rejects("adapt_gain", |c| c.adapt_gain = ImuVec::from_element(0.5));
    ots_rejects("adapt_hold_s", |c| c.adapt_hold_s = f64::NAN);
}

/// `change` applied to the gyro defaults must be rejected with `expected`.
fn parity_rejects(expected: parity::ConfigError, change: impl Fn(&mut ParityConfig<f64>)) {
    let mut c = ParityConfig::gyro(100.0, 34.9);
    change(&mut c);
    assert_eq!(c.validate(), Err(expected));
    assert_eq!(
        ParityMonitor::<f64, 6, 16>::new(&Geometry::cone6(), c).err(),
        Some(expected)
    );
}

#[test]
fn parity_config_rejects_zero_nan_and_inverted_fields() {
    use parity::ConfigError::{Field, Probability, Window};
    ParityConfig::<f64>::gyro(100.0, 34.9).validate().unwrap();
    ParityConfig::<f32>::accel(1000.0, 160.0)
        .validate()
        .unwrap();

    // Zero samples per block: NaN statistics and never an alarm.
    parity_rejects(Field("block_len"), |c| c.block_len = 0);
    parity_rejects(Window, |c| c.window_blocks = 0);
    parity_rejects(Field("train_samples"), |c| c.train_samples = 0);
    parity_rejects(Probability, |c| c.false_alarm = f64::NAN);
    parity_rejects(Probability, |c| c.cusum_arl0 = 0.5);
    parity_rejects(Field("threshold_margin"), |c| c.threshold_margin = 0.0);
    parity_rejects(Field("cusum_bias"), |c| c.cusum_bias = f64::NAN);
    parity_rejects(Field("ridge"), |c| c.ridge = -1.0);
    parity_rejects(Field("drift_blocks"), |c| c.drift_blocks = f64::INFINITY);
    parity_rejects(Field("isolate_after"), |c| c.isolate_after = 0);
    parity_rejects(Field("health.full_scale"), |c| c.health.full_scale = 0.0);
    parity_rejects(Field("health.clip_fraction"), |c| {
        c.health.clip_fraction = 1.5
    });
    parity_rejects(Field("health.stuck_samples"), |c| {
        c.health.stuck_samples = 0
    });
    parity_rejects(Field("health.rail_samples"), |c| c.health.rail_samples = 0);

    let e = Field("block_len");
    assert!(e.to_string().starts_with("block_len"), "{e}");
}

#[test]
fn errors_display_the_field() {
    assert_eq!(
        ConfigError::NonPositive("gate_sigma").to_string(),
        "gate_sigma: must be finite and positive"
    );
    assert!(ConfigError::AidingDelay
        .to_string()
        .starts_with("aiding_delay_s"));
}
