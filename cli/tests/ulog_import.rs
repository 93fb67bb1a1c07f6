//! PX4 ULog → SPEC §10 replay CSV, on a real flight
//! (`tests/data/px4_fmuv3_outdoor_flight.ulg`, MIT, see its licence note).

use std::path::Path;

use imu_fdi_cli::io::log_import::{quaternion_to_euler, ulog_to_replay_csv};

#[test]
fn a_real_px4_flight_converts_with_consistent_axes() {
    let input = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/px4_fmuv3_outdoor_flight.ulg"
    ));
    let out = std::env::temp_dir().join(format!("imu-fdi-ulog-{}.csv", std::process::id()));
    let s = ulog_to_replay_csv(input, &out).unwrap();
    assert_eq!((s.rows, s.gnss_rows, s.att_rows), (341, 175, 340));
    assert!((s.imu_rate_hz - 8.6).abs() < 0.1, "{}", s.imu_rate_hz);
    // Axes and quaternion convention: the logged attitude rotates the
    // measured specific force onto (0, 0, −g) in NED. Single 8.6 Hz point
    // samples carry several m/s² of aliased vibration, so compare the mean
    // over the flight (vibration and manoeuvres average out).
    let mut rdr = csv::Reader::from_path(&out).unwrap();
    let (mut sum, mut n) = ([0.0; 3], 0.0);
    for rec in rdr.records() {
        let r = rec.unwrap();
        let f = |i: usize| r.get(i).unwrap().parse::<f64>().ok();
        let (Some(phi), Some(th), Some(psi)) = (f(10), f(11), f(12)) else {
            continue;
        };
        let a = [f(1).unwrap(), f(2).unwrap(), f(3).unwrap()];
        let (sp, cp, st, ct, ss, cs) = (
            phi.sin(),
            phi.cos(),
            th.sin(),
            th.cos(),
            psi.sin(),
            psi.cos(),
        );
        // R_nb a with R_nb = R_z(ψ) R_y(θ) R_x(φ).
        let ned = [
            ct * cs * a[0] + (sp * st * cs - cp * ss) * a[1] + (cp * st * cs + sp * ss) * a[2],
            ct * ss * a[0] + (sp * st * ss + cp * cs) * a[1] + (cp * st * ss - sp * cs) * a[2],
            -st * a[0] + ct * sp * a[1] + ct * cp * a[2],
        ];
        for k in 0..3 {
            sum[k] += ned[k];
        }
        n += 1.0;
    }
    let mean = sum.map(|x| x / n);
    assert!(mean[0].abs() < 0.5 && mean[1].abs() < 0.5, "{mean:?}");
    // Measured: (−0.24, −0.29, −10.42) m/s²; the climb-out and vibration
    // rectification add to gravity on the down axis.
    assert!((mean[2] + 9.81).abs() < 1.0, "{mean:?}");
    // The Euler conversion itself: a 90° yaw quaternion.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let e = quaternion_to_euler([h, 0.0, 0.0, h]);
    assert!(
        e[0].abs() < 1e-12
            && e[1].abs() < 1e-12
            && (e[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-12
    );
}
