//! S4 (\[PAR\]): a 0.5 °/s bias on sensor 5 of a manoeuvring cone6 gyro array.

use hal_sim::array::{cone6_directions, triad_directions, ArrayKind, ArraySpec, Layout};
use hal_sim::array_run::{array_config, run_array};

#[test]
fn explore() {
    let t = std::time::Instant::now();
    let spec = ArraySpec::fault_free(
        "cone",
        cone6_directions(),
        ArrayKind::Gyro,
        Layout::Single,
        3600.0,
    );
    let run = run_array::<f32, 6>(&spec, 7, array_config(&spec)).unwrap();
    println!("cone gyro: {run:?} {:?}", t.elapsed());
    let spec = ArraySpec::fault_free(
        "cone",
        cone6_directions(),
        ArrayKind::Accel,
        Layout::Single,
        3600.0,
    );
    let run = run_array::<f32, 6>(&spec, 7, array_config(&spec)).unwrap();
    println!("cone accel: {run:?} {:?}", t.elapsed());
    let d = triad_directions::<9>(&[0.0, std::f64::consts::FRAC_PI_2, std::f64::consts::PI]);
    let spec = ArraySpec::fault_free("triads", d, ArrayKind::Gyro, Layout::Triads, 3600.0);
    let run = run_array::<f32, 9>(&spec, 7, array_config(&spec)).unwrap();
    println!("triad gyro: {run:?} {:?}", t.elapsed());
    let spec = ArraySpec::fault_free("triads", d, ArrayKind::Accel, Layout::Triads, 3600.0);
    let run = run_array::<f32, 9>(&spec, 7, array_config(&spec)).unwrap();
    println!("triad accel: {run:?} {:?}", t.elapsed());
}
