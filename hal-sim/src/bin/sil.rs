//! Software-in-the-loop firmware for QEMU's `netduinoplus2` (STM32F405,
//! Cortex-M4F): scenario S2 from hal-sim's emulated vehicle and sensors,
//! through the same `f32` monitor as on the host, with the cost of every
//! monitor step counted in instructions.
//!
//! Under `qemu-system-arm -icount shift=0` the STM32 TIM2 counter register
//! advances once per executed instruction without any timer set-up, so two
//! reads around `step` give its instruction count, repeatably. The stack is
//! painted at boot (cortex-m-rt `paint-stack`) and the high-water mark read
//! at the end. Output goes over semihosting; the exit status is non-zero if
//! the run did not detect S2's faults as on the host.
//!
//! Build and run: `scripts/qemu-bench.sh` (see the README).
#![no_std]
#![no_main]
#![allow(unsafe_code)] // volatile reads of the timer counter and of the painted stack

use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use hal_sim::setup::{monitor_config, DetectionTally, RunOptions};
use hal_sim::{Scenario, Simulator};
use imu_fdi::model::{ImuVec, MeasVec, Measurement};
use imu_fdi::monitor::UkfMonitor;

/// TIM2 counter (CNT) of the STM32F4: TIM2 base 0x4000_0000 + 0x24.
const TIM2_CNT: *const u32 = 0x4000_0024 as *const u32;
const PAINT: u32 = 0xcccc_cccc;

fn instructions() -> u32 {
    // SAFETY: a read-only, aligned, always-mapped peripheral register.
    unsafe { core::ptr::read_volatile(TIM2_CNT) }
}

extern "C" {
    static _stack_end: u32;
    static _stack_start: u32;
}

/// Bytes of stack ever used: the painted region no longer holding the paint.
fn stack_high_water() -> u32 {
    // SAFETY: the linker-provided bounds of the stack region; reads only.
    unsafe {
        let lo = core::ptr::addr_of!(_stack_end) as usize;
        let hi = core::ptr::addr_of!(_stack_start) as usize;
        let mut p = lo;
        while p < hi && core::ptr::read_volatile(p as *const u32) == PAINT {
            p += 4;
        }
        (hi - p) as u32
    }
}

#[derive(Default)]
struct Cost {
    n: u32,
    sum: u64,
    max: u32,
}

impl Cost {
    fn add(&mut self, c: u32) {
        self.n += 1;
        self.sum += u64::from(c);
        self.max = self.max.max(c);
    }
    fn mean(&self) -> u64 {
        if self.n == 0 {
            0
        } else {
            self.sum / u64::from(self.n)
        }
    }
}

#[entry]
fn main() -> ! {
    let scn = Scenario::s2();
    let cfg = monitor_config::<f32>(&scn, &RunOptions::default());
    let Ok(mut monitor) = UkfMonitor::<f32>::new(cfg) else {
        hprintln!("invalid monitor configuration");
        debug::exit(debug::EXIT_FAILURE);
        loop {}
    };
    let overhead = {
        let a = instructions();
        let b = instructions();
        b.wrapping_sub(a)
    };
    let (mut all, mut predict_only, mut with_update) =
        (Cost::default(), Cost::default(), Cost::default());
    let mut tally = DetectionTally::new(&scn);
    for s in Simulator::new(&scn, 1) {
        let u = ImuVec::from_fn(|i, _| s.imu.map_or(f32::NAN, |v| v[i] as f32));
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let m = Measurement {
            z,
            available: s.aiding_available,
        };
        let t0 = instructions();
        let r = monitor.step(&u, s.dt as f32, &m);
        let cost = instructions().wrapping_sub(t0).saturating_sub(overhead);
        all.add(cost);
        if r.updated {
            with_update.add(cost);
        } else {
            predict_only.add(cost);
        }
        tally.record(&s, &r);
    }
    hprintln!(
        "S2 seed 1 on the emulated Cortex-M4F (f32 monitor, {} steps)",
        all.n
    );
    hprintln!("instructions per step: mean {} max {}", all.mean(), all.max);
    hprintln!(
        "  predict only: mean {} max {} ({} steps)",
        predict_only.mean(),
        predict_only.max,
        predict_only.n
    );
    hprintln!(
        "  with aiding update: mean {} max {} ({} steps)",
        with_update.mean(),
        with_update.max,
        with_update.n
    );
    hprintln!("peak stack: {} bytes", stack_high_water());
    profile();
    tally.print(|line| hprintln!("{}", line));
    if tally.all_detected() {
        hprintln!("OK: every S2 fault detected on its channel with the right sign");
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        hprintln!("FAIL: S2 detections differ from the host");
        debug::exit(debug::EXIT_FAILURE);
    }
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
    use imu_fdi::math::{cholesky, sin_cos_f32};
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
    let mut ukf = Ukf::<f32, 6, 13>::new(x, p, &SigmaParams::default(), STATE_ANGLES)
        .unwrap_or_else(|| loop {});
    let _ = cost!(
        "ukf.predict (model.step)",
        ukf.predict(|s| m.step(s, &u, 0.01), &p)
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
        "ukf.update (M1)",
        ukf.update(
            &z,
            &[true; 6],
            |s| Ok::<_, ()>(meas.predict(s, &omega)),
            &r,
            &[false, false, false, true, true, true],
            &mut gate
        )
    );
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
