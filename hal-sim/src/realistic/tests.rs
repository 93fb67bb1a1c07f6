//! Unit tests of the realistic array.

use super::*;

#[test]
fn biases_are_the_drift_state_plus_the_thermal_term() {
    // IMU1's x gyro has no bias instability in the log171 profile: its
    // bias is its thermal coefficient times the board temperature,
    // exactly. IMU2's y gyro wanders with its fitted instability
    // (0.142 °/s, 30-s correlation): over 20 correlation times its
    // spread is that within the sampling error of ~20 independent
    // values.
    let p = RealisticProfile::log171().with_duration(600.0);
    let thermal = p.imus[1].thermal[GX];
    let sd = p.imus[2].bias_instability[GY];
    let mut sim = RealisticArray::new(&p, 7);
    let (mut n, mut s1, mut s2, mut hot) = (0.0, 0.0, 0.0, 0.0_f64);
    while sim.next().is_some() {
        let b = sim.biases();
        let temp = sim.temperature_k();
        assert_eq!(b[1][GX], thermal * temp);
        hot = hot.max(temp);
        let y = b[2][GY] - p.imus[2].thermal[GY] * temp;
        n += 1.0;
        s1 += y;
        s2 += y * y;
    }
    assert!(hot > 1.0, "the board warmed by {hot} K");
    let spread = (s2 / n - (s1 / n) * (s1 / n)).sqrt();
    assert!(spread > 0.5 * sd && spread < 1.5 * sd, "{spread} vs {sd}");
}
