//! The UKF innovation monitor: filter, closed-loop fault signatures, start-up
//! learning, drift tracking, detection and estimation in one periodic `step`.

mod align;
mod attitude_rate_config;
#[cfg(any(feature = "attitude-rate-test", feature = "velocity-increment-test"))]
mod block_test;
mod config;
mod config_error;
mod input;
mod otsukf_monitor;
mod realign;
mod report;
mod stale_aiding;
mod task;
mod ukf_monitor;

pub use align::align_state;
pub use attitude_rate_config::{
    AttitudeRateConfig, AttitudeRateDetail, BlockTestConfig, BlockTestDetail,
    VelocityIncrementConfig, VelocityIncrementDetail, ATTITUDE_RATE_LENGTHS,
    ATTITUDE_RATE_MAX_BLOCKS,
};
pub use config::UkfMonitorConfig;
pub use config_error::ConfigError;
pub use otsukf_monitor::{OtsukfConfig, OtsukfMonitor};
pub use report::{
    ChannelState, Health, OtsukfDetail, OtsukfReport, Phase, Report, UkfDetail, UkfReport,
};
#[allow(deprecated)] // the former name, kept for users
pub use task::Monitor;
pub use task::{
    MonitorTask, PeriodicMonitor, TaskReport, TaskStatus, Verdict, MAX_CONSECUTIVE_FAILURES,
};
pub use ukf_monitor::{UkfMonitor, DEFAULT_WINDOW, MAX_DELAY_STEPS};
