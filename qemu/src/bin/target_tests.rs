//! On-target tests for QEMU's `netduinoplus2` (STM32F405, Cortex-M4F): the
//! crate's numerics in `f32` on the emulated FPU against expectations the
//! host computed in `f64` (`tests/data/target_expectations.txt`, kept current
//! by `hal-sim/tests/target_expectations.rs`).
//!
//! Prints one line per test and a summary over semihosting; exits non-zero
//! if any test fails, on a panic, or on a HardFault. Run by
//! `scripts/qemu-sil.sh` (and so by CI).
#![no_std]
#![no_main]
#![allow(clippy::empty_loop)] // reached only after the semihosting exit has stopped QEMU
#![allow(unsafe_code)] // the cortex-m-rt exception handler attribute

use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use hal_sim::target_checks::{
    monitor_run, monitor_scenarios, otsukf_run, spd6, ANGLES, SQRT_INPUTS, T_QUANTILES,
};
use imu_fdi::detect::TTest;
use imu_fdi::math::{cholesky, sin_cos_f32, sqrt_f32};
use imu_fdi::model::{ImuVec, MeasVec};

use imu_fdi_qemu::instructions;

// The parity monitors' tests (a directory without `main.rs`: no extra bin).
#[path = "target_tests/parity.rs"]
mod parity;
use parity::{parity_flight_on_target, parity_readmit_on_target, parity_s4_on_target};

const EXPECTATIONS: &str = include_str!("../../../tests/data/target_expectations.txt");

/// The numbers of the expectation line `key` with the given leading fields.
fn expected<const K: usize>(key: &str, fields: &[&str]) -> Option<[f64; K]> {
    let line = EXPECTATIONS.lines().find(|l| {
        let mut w = l.split_whitespace();
        w.next() == Some(key) && fields.iter().all(|f| w.next() == Some(*f))
    })?;
    let mut vals = line.split_whitespace().skip(1 + fields.len());
    let mut out = [0.0; K];
    for v in out.iter_mut() {
        *v = vals.next()?.parse().ok()?;
    }
    Some(out)
}

struct Runner {
    passed: u32,
    failed: u32,
}

impl Runner {
    fn check(&mut self, name: &str, result: Result<(), &'static str>) {
        match result {
            Ok(()) => {
                self.passed += 1;
                hprintln!("test {} ... ok", name);
            }
            Err(why) => {
                self.failed += 1;
                hprintln!("test {} ... FAILED: {}", name, why);
            }
        }
    }
}

fn sqrt_is_correctly_rounded() -> Result<(), &'static str> {
    for (i, x) in SQRT_INPUTS.iter().enumerate() {
        let [bits] = expected::<1>("sqrt", &[itoa_buf(i).as_str()]).ok_or("missing expectation")?;
        if sqrt_f32(*x).to_bits() != bits as u32 {
            return Err("vsqrt differs from the host's correctly rounded sqrtf");
        }
    }
    if !sqrt_f32(-1.0).is_nan() {
        return Err("sqrt(-1) is not NaN");
    }
    Ok(())
}

fn sin_cos_within_2e7() -> Result<(), &'static str> {
    for (i, a) in ANGLES.iter().enumerate() {
        let [s, c] =
            expected::<2>("sincos", &[itoa_buf(i).as_str()]).ok_or("missing expectation")?;
        let (s32, c32) = sin_cos_f32(*a as f32);
        if (f64::from(s32) - s).abs() > 2e-7 || (f64::from(c32) - c).abs() > 2e-7 {
            return Err("sin_cos_f32 off by more than 2e-7");
        }
    }
    Ok(())
}

fn cholesky_matches_f64() -> Result<(), &'static str> {
    let l = cholesky(&spd6::<f32>()).map_err(|_| "factorisation failed")?;
    for i in 0..6 {
        for j in 0..=i {
            let [v] = expected::<1>("chol", &[itoa_buf(i).as_str(), itoa_buf(j).as_str()])
                .ok_or("missing expectation")?;
            let got = f64::from(l[(i, j)]);
            // Relative to the column's diagonal: f32 rounding through a
            // condition number of ~1e4.
            let scale = f64::from(l[(j, j)]).abs();
            if (got - v).abs() > 1e-5 * scale {
                return Err("Cholesky factor differs from f64 by more than 1e-5");
            }
        }
    }
    Ok(())
}

fn student_t_quantiles_match() -> Result<(), &'static str> {
    for (alpha, nu) in T_QUANTILES {
        let line = EXPECTATIONS
            .lines()
            .filter(|l| l.starts_with("tquantile "))
            .find(|l| {
                let mut w = l.split_whitespace().skip(1);
                w.next().and_then(|a| a.parse::<f64>().ok()) == Some(alpha)
                    && w.next().and_then(|n| n.parse::<u32>().ok()) == Some(nu)
            })
            .ok_or("missing expectation")?;
        let want: f64 = line
            .split_whitespace()
            .nth(3)
            .and_then(|v| v.parse().ok())
            .ok_or("bad expectation")?;
        // TTest takes the window length n; degrees of freedom are n − 1.
        let t = TTest::<f64>::new(alpha, nu as usize + 1).map_err(|_| "quantile failed")?;
        if (t.threshold - want).abs() > 1e-12 * want {
            return Err("Student-t quantile differs from the host");
        }
    }
    Ok(())
}

fn monitor_matches_f64(name: &str) -> Result<(), &'static str> {
    let scn = monitor_scenarios()
        .into_iter()
        .find(|(n, _)| *n == name)
        .ok_or("unknown scenario")?
        .1;
    let (x, _) = monitor_run::<f32>(&scn).ok_or("monitor refused the configuration")?;
    for i in 0..6 {
        let [want, sigma] =
            expected::<2>("monitor", &[name, itoa_buf(i).as_str()]).ok_or("missing expectation")?;
        let err = (f64::from(x[i]) - want).abs();
        // NaN must fail too.
        if err > 0.1 * sigma || !err.is_finite() {
            return Err("f32 state differs from the host's f64 by more than 0.1 sigma");
        }
    }
    Ok(())
}

/// The OTSUKF monitor on S3 in `f32` (13 sigma points, GNSS
/// velocity + attitude, the fault filter): its fault estimate after 15 s
/// (monitoring from 8 s, faults from 10 s) within 0.1 σ_f of the host's
/// `f64`; prints the instruction cost of its monitoring steps.
fn otsukf_s3_matches_f64() -> Result<(), &'static str> {
    use imu_fdi::monitor::{OtsukfMonitor, Phase};
    let (mut sum, mut n, mut max) = (0u64, 0u64, 0u32);
    let (f, _) = otsukf_run::<f32>(|step| {
        let t0 = instructions();
        let phase = core::hint::black_box(step());
        let c = instructions().wrapping_sub(t0);
        if phase == Phase::Monitoring {
            sum += u64::from(c);
            n += 1;
            max = max.max(c);
        }
    })
    .ok_or("OTSUKF monitor refused the configuration")?;
    hprintln!(
        "two-stage UKF monitor (f32, S3 seed 1): per monitoring step mean {} max {} instructions; size {} bytes",
        sum / n.max(1),
        max,
        core::mem::size_of::<OtsukfMonitor<f32>>()
    );
    for i in 0..6 {
        let [want, sigma] =
            expected::<2>("otsukf", &[itoa_buf(i).as_str()]).ok_or("missing expectation")?;
        let err = (f64::from(f[i]) - want).abs();
        if err > 0.1 * sigma || !err.is_finite() {
            return Err("f32 fault estimate differs from the host's f64 by more than 0.1 sigma");
        }
    }
    Ok(())
}

/// The FIFO path's own work per 50 Hz period on the M4F: parsing 20
/// packet-3 records (1 kHz ODR) and integrating them with coning and
/// sculling corrections (the SPI transfer itself is the bus's time, not
/// instructions). Checked against the mean of the samples fed.
fn fifo_integration_on_target() -> Result<(), &'static str> {
    use imu_fdi::imu::fifo::{parse_packet, Packet, PACKET_LEN};
    use imu_fdi::imu::DeltaIntegrator;
    let mut packets = [[0u8; PACKET_LEN]; 20];
    let mut sum = [0f32; 6];
    for (k, p) in packets.iter_mut().enumerate() {
        let k = k as i16;
        // Varying specific force, a constant 100 °/s rate (parallel
        // increments: no coning, so the mean rate is exact).
        let words = [100 + k, -50, -2048 + 3 * k, 300, 40, -1640];
        p[0] = 0x68;
        for (i, w) in words.iter().enumerate() {
            let [hi, lo] = w.to_be_bytes();
            p[1 + 2 * i] = hi;
            p[2 + 2 * i] = lo;
            sum[i] += f32::from(*w);
        }
        let [t1, t0] = (1000u16 + 62 * k as u16).to_be_bytes();
        p[14] = t1;
        p[15] = t0;
    }
    let (alsb, glsb) = (16.0 * 9.806_65 / 32768.0, 2000f32.to_radians() / 32768.0);
    let t0 = instructions();
    let mut integ = DeltaIntegrator::new();
    for p in core::hint::black_box(&packets).iter() {
        if let Packet::Sample(raw) = parse_packet(p) {
            integ.push(
                raw.gyro.map(|c| f32::from(c) * glsb),
                raw.accel.map(|c| f32::from(c) * alsb),
                1e-3,
            );
        }
    }
    let d = core::hint::black_box(integ.take()).ok_or("nothing integrated")?;
    let c = instructions().wrapping_sub(t0);
    hprintln!(
        "FIFO path: 20 packets parsed and integrated (coning + sculling) in {} instructions",
        c
    );
    if d.samples != 20 {
        return Err("not every packet was integrated");
    }
    let (f, w) = (d.mean_specific_force(), d.mean_rate());
    for i in 0..3 {
        let (ef, ew) = (sum[i] / 20.0 * alsb, sum[3 + i] / 20.0 * glsb);
        // Rotation compensation and sculling move Δv/T by at most about
        // |ω| T |f| (0.35 m/s² at this 100 °/s); the rates are exact.
        let wn = libm::sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        let fnorm = libm::sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        if (f[i] - ef).abs() > wn * d.dt * fnorm + 1e-4 || (w[i] - ew).abs() > 1e-5 {
            return Err("averages differ from the samples' mean");
        }
    }
    Ok(())
}

/// A small decimal formatter (indices < 100) for the expectation keys.
fn itoa_buf(i: usize) -> heapless::String<4> {
    let mut s = heapless::String::new();
    let _ = core::fmt::write(&mut s, format_args!("{i}"));
    s
}

#[entry]
fn main() -> ! {
    let mut r = Runner {
        passed: 0,
        failed: 0,
    };
    r.check("sqrt_is_correctly_rounded", sqrt_is_correctly_rounded());
    r.check("sin_cos_within_2e7", sin_cos_within_2e7());
    r.check("cholesky_matches_f64", cholesky_matches_f64());
    r.check("student_t_quantiles_match", student_t_quantiles_match());
    r.check("monitor_s2_matches_f64", monitor_matches_f64("s2"));
    r.check(
        "monitor_aircraft_matches_f64",
        monitor_matches_f64("aircraft"),
    );
    r.check("otsukf_s3_matches_f64", otsukf_s3_matches_f64());
    r.check("parity_s4_on_target", parity_s4_on_target());
    r.check("parity_flight_on_target", parity_flight_on_target());
    r.check("parity_readmit_on_target", parity_readmit_on_target());
    r.check("fifo_integration_on_target", fifo_integration_on_target());
    profile();
    match imu_fdi_qemu::kfilter_cmp::predict_update_costs(50) {
        Some((k, o)) => hprintln!(
            "kfilter 0.5 UKF, same 6-state model and M2 aiding (f32): predict+update mean {} instructions; imu-fdi Ukf predict_split+update mean {}",
            k,
            o
        ),
        None => hprintln!("kfilter comparison: a filter failed"),
    }
    hprintln!("on-target tests: {} passed, {} failed", r.passed, r.failed);
    debug::exit(if r.failed == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {}
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    hprintln!("HardFault at pc {:#010x}", ef.pc());
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}

/// Instruction cost of the pieces of one monitor step, for profiling.
fn profile() {
    use imu_fdi::filter::{SigmaParams, Ukf};

    use imu_fdi::model::{
        discrete_process_noise_from, ImuNoisePsd, Mat6, StateVec, VehicleModel, STATE_ANGLES,
    };
    let m = VehicleModel::<f32>::default();
    let x = core::hint::black_box(StateVec::new(2.0, 0.1, -0.05, 0.05, 0.1, 1.0));
    let u = core::hint::black_box(ImuVec::new(0.1, 0.2, -9.7, 0.01, 0.02, 0.05));
    let p = Mat6::<f32>::from_diagonal_element(1e-4);
    macro_rules! cost {
        ($name:expr, $e:expr) => {{
            let t0 = instructions();
            let r = core::hint::black_box($e);
            let c = instructions().wrapping_sub(t0);
            hprintln!("  {:<28} {:>6}", $name, c);
            r
        }};
    }
    hprintln!("profile (instructions, one call):");
    cost!("sin_cos_f32", sin_cos_f32(core::hint::black_box(0.3)));
    cost!("libm::sqrtf", libm::sqrtf(core::hint::black_box(0.3)));
    cost!("sqrt_f32 (vsqrt)", sqrt_f32(core::hint::black_box(0.3)));
    let _ = cost!("model.derivative", m.derivative(&x, &u));
    let _ = cost!("model.step (RK2)", m.step(&x, &u, 0.01));
    let a = cost!(
        "jacobian_state",
        m.jacobian_state(&x, &u).unwrap_or_default()
    );
    let b = cost!("jacobian_input", m.jacobian_input(&x).unwrap_or_default());
    cost!("6x6 matmul", a * b);
    cost!(
        "process noise Q",
        discrete_process_noise_from(&a, &b, &ImuNoisePsd::uniform(6e-5, 2e-7), 0.01)
    );
    cost!(
        "process noise Q structured",
        imu_fdi::model::discrete_process_noise_structured(
            &a,
            &b,
            &ImuNoisePsd::uniform(6e-5, 2e-7),
            0.01
        )
    );
    let _ = cost!("cholesky 6x6", cholesky(&p));
    let _ = cost!("nalgebra Cholesky 6x6", nalgebra::Cholesky::new(p));
    let _ = cost!(
        "cholesky_reference 6x6",
        imu_fdi::math::cholesky_reference(&p)
    );
    let mut q = p;
    cost!("ger rank-1 6x6", {
        q.ger(0.1, &x, &x, 1.0);
        core::hint::black_box(&mut q);
    });
    cost!("syger rank-1 6x6", {
        q.syger(0.1, &x, &x, 1.0);
        core::hint::black_box(&mut q);
    });
    let _ = cost!("outer d*d^T*w", p + x * x.transpose() * 0.1);
    let mut q2 = p;
    cost!("add_outer_lower", {
        imu_fdi::math::add_outer_lower(&mut q2, &x, 0.1);
        core::hint::black_box(&mut q2);
    });
    cost!("mirror_lower", {
        imu_fdi::math::mirror_lower(&mut q2);
        core::hint::black_box(&mut q2);
    });
    cost!(
        "wrap_pi",
        imu_fdi::math::wrap_pi(core::hint::black_box(0.3f32))
    );
    cost!(
        "wrap_pi (4)",
        imu_fdi::math::wrap_pi(core::hint::black_box(4.0f32))
    );
    {
        // The per-sample pieces of the real-flight parity monitor (three
        // triads, all active; issue 14).
        use imu_fdi::parity::{Geometry, HealthConfig, ParitySpace, Reading, SensorHealth};
        let g = Geometry::<f32, 9>::triads(&[nalgebra::Matrix3::identity(); 3])
            .unwrap_or_else(|_| loop {});
        let space = ParitySpace::new(&g, &[true; 9]).unwrap_or_else(|_| loop {});
        let m9 =
            core::hint::black_box(nalgebra::SVector::<f32, 9>::from_fn(|i, _| 0.01 * i as f32));
        let _ = cost!("parity V m (9x9)", space.parity(&m9));
        let _ = cost!("parity fuse (3x9)", space.fuse(&m9));
        let hc = HealthConfig::new(30.0f32);
        let mut hs = [SensorHealth::<f32>::default(); 9];
        cost!("parity health checks (9)", {
            for (h, v) in hs.iter_mut().zip(m9.iter()) {
                core::hint::black_box(h.check_unlatched(Reading::Sample(*v), &hc));
            }
        });
    }
    let mut ukf = Ukf::<f32, 6, 13>::new(x, p, &SigmaParams::default(), STATE_ANGLES)
        .unwrap_or_else(|| loop {});
    let _ = cost!(
        "ukf.predict (model.step)",
        ukf.predict(|s| m.step(s, &u, 0.01), &p)
    );
    let _ = cost!(
        "ukf.predict_split (model)",
        ukf.predict_split(
            &VehicleModel::<f32>::SPLIT_ORDER,
            VehicleModel::<f32>::NONLINEAR_STATES,
            |s| m.step(s, &u, 0.01),
            |d| m.step_deviation(d, &u, 0.01),
            &p
        )
    );
    let _ = cost!(
        "ukf.predict (identity)",
        ukf.predict(|s| Ok::<_, ()>(*s), &p)
    );
    use imu_fdi::detect::{estimate_as_written, estimate_corrected, glr_isolate, InnovationWindow};
    use imu_fdi::filter::Gate;
    use imu_fdi::model::{AidingKind, MeasurementModel};
    let meas = MeasurementModel::<f32>::new(AidingKind::DvlCompass);
    let omega = nalgebra::Vector3::new(0.01f32, 0.02, 0.05);
    let mut gate = Gate::<f32, 6>::new(8.0, 2);
    let z = MeasVec::new(2.0, 0.1, -0.05, 0.05, 0.1, 1.0);
    let r = MeasVec::from_element(1e-4f32);
    let _ = cost!(
        "ukf.update (sigma points, M1)",
        ukf.update(
            &z,
            &[true; 6],
            |s| Ok::<_, ()>(meas.predict(s, &omega)),
            &r,
            &[false, false, false, true, true, true],
            &mut gate
        )
    );
    let h = imu_fdi::model::Mat6::<f32>::identity();
    let _ = cost!(
        "ukf.update_affine (M1)",
        ukf.update_affine(
            &meas.predict(&x, &omega),
            &h,
            &z,
            &[true; 6],
            &r,
            &[false, false, false, true, true, true],
            &mut gate
        )
    );
    // The two-stage filter's own steps (the monitor adds the Jacobians,
    // Φ, F and Q^x of the predict, 2.6k, and the measurement Jacobian).
    let mut ts = imu_fdi::filter::Otsukf::<f32, 6, 13, 6>::new(
        x,
        p,
        ImuVec::zeros(),
        p,
        p * 1e-3,
        &SigmaParams::default(),
        STATE_ANGLES,
    )
    .unwrap_or_else(|| loop {});
    let _ = cost!(
        "two-stage predict",
        ts.predict(|s| m.step(s, &u, 0.01), &a, &b, &p)
    );
    let _ = cost!(
        "two-stage predict_split",
        ts.predict_split(
            &VehicleModel::<f32>::SPLIT_ORDER,
            VehicleModel::<f32>::NONLINEAR_STATES,
            |s| m.step(s, &u, 0.01),
            |d| m.step_deviation(d, &u, 0.01),
            |v| a * v + b,
            &p
        )
    );
    let m2 = MeasurementModel::<f32>::new(AidingKind::GnssAttitude);
    let hj = m2.jacobian(&x, &omega);
    let _ = cost!(
        "two-stage update (M2)",
        ts.update(
            &z,
            &[true; 6],
            |s| Ok::<_, ()>(m2.predict(s, &omega)),
            &hj,
            &r,
            &[false, false, false, true, true, true],
            &mut gate
        )
    );
    let (order, nonlinear) = m2.split();
    let _ = cost!(
        "two-stage update_split (M2)",
        ts.update_split(
            &order,
            nonlinear,
            &z,
            &[true; 6],
            |s| Ok::<_, ()>(m2.predict(s, &omega)),
            &hj,
            &r,
            &[false, false, false, true, true, true],
            &mut gate
        )
    );
    cost!("m2.predict", m2.predict(&x, &omega));
    cost!("m2.jacobian", m2.jacobian(&x, &omega));
    let w = MeasVec::from_element(1e4f32);
    let _ = cost!("glr_isolate", glr_isolate(&a, &x, &w, 40.0, 0.02, 3));
    let _ = cost!(
        "estimate_corrected",
        estimate_corrected(&a, &w, &x, &[true; 6])
    );
    let _ = cost!("estimate_as_written", estimate_as_written(&a, &b, 0.01, &x));
    let mut win = InnovationWindow::<f32, 10>::new();
    for k in 0..10 {
        win.push(k as f32 * 0.1);
    }
    let _ = cost!("window stats (10)", win.stats());
}
