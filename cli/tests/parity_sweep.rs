//! The redundant-IMU sensitivity targets on a 3-IMU board: ≤ 0.2 °/s and
//! ≤ 0.05 m/s² detected in ≥ 99 % of runs with zero false alarms over a
//! fault-free hour, ≥ 10× smaller than what the PX4-like and ArduPilot-like
//! consistency checks detect reliably (≥ 99 % of runs). (The full grid: `cargo sim parity-sweep`.)

use std::f64::consts::{FRAC_PI_2, PI};

use hal_sim::array::{triad_directions, ArrayKind, ArraySpec, Layout};
use imu_fdi_cli::eval::array_sweep::sweep;

fn board(kind: ArrayKind) -> ArraySpec<9> {
    ArraySpec::fault_free(
        "triads3",
        triad_directions::<9>(&[0.0, FRAC_PI_2, PI]),
        kind,
        Layout::Triads,
        0.0,
    )
}

fn check(kind: ArrayKind, target: f64) {
    // Target, and 10× the target for the baselines.
    let s = sweep(&board(kind), &[target, 10.0 * target], 100, 1, 500).unwrap();
    let by = |name: &str| s.iter().find(|m| m.method == name).unwrap();
    for name in ["chi2/GLT", "CUSUM"] {
        let m = by(name);
        assert_eq!(m.false_alarms, 0, "{name}");
        let r = &m.sizes[0];
        assert!(r.detected >= 99, "{name}: {r:?}");
        // Per-axis 2-of-3 isolation names the faulty sensor.
        assert!(r.correct_blame >= 99, "{name}: {r:?}");
        assert!(r.max_delay < 2.0, "{name}: {r:?}");
    }
    for name in ["PX4-like", "ArduPilot-like"] {
        let m = by(name);
        assert_eq!(m.false_alarms, 0, "{name}");
        // Not reliably detected at 10× (turn-on biases sometimes push a
        // faulty IMU over the coarse threshold: ArduPilot-like sees 33 of
        // 100 accelerometer runs at 0.5 m/s²).
        let r = &m.sizes[1];
        assert!(r.detected < 99, "{name} at 10x target: {r:?}");
    }
}

#[test]
fn three_imu_board_gyro_0_2_deg_s_and_baselines_miss_2_deg_s() {
    check(ArrayKind::Gyro, 0.2 * PI / 180.0);
}

#[test]
fn three_imu_board_accel_0_05_m_s2_and_baselines_miss_0_5_m_s2() {
    check(ArrayKind::Accel, 0.05);
}
