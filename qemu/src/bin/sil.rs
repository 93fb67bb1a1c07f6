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
//! the run did not detect S2's faults as on the host, or if the image's
//! peak stack exceeds issue 17's budget (`STACK_BUDGET`). With the feature
//! `sil-chip` the samples take the firmware's data path instead (driver,
//! emulated chip, Monitor task); both images keep their run's state in
//! static RAM, constructed out of line, so the steps' frame holds none of it.
//!
//! Build and run: `scripts/qemu-sil.sh` (see the README).
#![no_std]
#![no_main]
#![allow(clippy::empty_loop)] // reached only after the semihosting exit has stopped QEMU
#![allow(unsafe_code)] // the exception handler attribute; volatile reads of the painted stack

use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use hal_sim::Scenario;

use imu_fdi_qemu::instructions;

const PAINT: u32 = 0xcccc_cccc;

/// Issue 17's stack budget for both images, bytes: an image fails (and CI
/// with it) when its peak exceeds it, as a firmware's own tasks need the
/// headroom.
const STACK_BUDGET: u32 = 12 * 1024;

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

/// Bytes of stack below the caller's frame that one monitor step may use
/// at most, for the per-step measurement (the whole stack region is larger).
const STEP_REGION: usize = 32 * 1024;
/// Gap left below the stack pointer read in `main` for the painting
/// helpers' own frames.
const GAP: usize = 256;

/// Paints the `STEP_REGION` bytes that end `GAP` below `sp`.
#[inline(never)]
fn paint_below(sp: usize) {
    let hi = sp - GAP;
    let mut p = hi - STEP_REGION;
    while p < hi {
        // SAFETY: free stack below the caller's frame (no interrupts run),
        // above the stack's end (the region is far smaller than the stack).
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

#[cfg(not(feature = "sil-chip"))]
/// Bytes below `sp` reached since [`paint_below`]: the deepest word no
/// longer holding the paint.
#[inline(never)]
fn depth_below(sp: usize) -> u32 {
    let hi = sp - GAP;
    let mut p = hi - STEP_REGION;
    // SAFETY: reads of the region painted by `paint_below`.
    while p < hi && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    (sp - p) as u32
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

fn overhead() -> u32 {
    let a = instructions();
    let b = instructions();
    b.wrapping_sub(a)
}

/// Ends the run: failure when the peak stack (bytes) is over issue 17's
/// budget or S2 was not detected as on the host (`ok`), else success.
fn finish(peak: u32, ok: bool) -> ! {
    if peak > STACK_BUDGET {
        hprintln!(
            "FAIL: peak stack {} bytes, over the budget of {} (issue 17)",
            peak,
            STACK_BUDGET
        );
        debug::exit(debug::EXIT_FAILURE);
    } else if ok {
        hprintln!("OK: every S2 fault detected on its channel with the right sign");
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        hprintln!("FAIL: S2 not detected as on the host");
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {}
}

#[cfg(not(feature = "sil-chip"))]
/// The S2 run's state, in static RAM (`.bss`), constructed once, as a
/// flight controller keeps its monitors: on `main`'s stack they were 10 KB
/// of a 16 KB peak (issue 17).
struct Run {
    monitor: &'static mut imu_fdi::monitor::UkfMonitor<f32>,
    sim: &'static mut hal_sim::Simulator,
    tally: &'static mut hal_sim::setup::DetectionTally,
}

#[cfg(not(feature = "sil-chip"))]
/// Constructs the run's state into static RAM, each part in a frame of its
/// own that is popped before the next part and before the steps: inlined
/// into `main`, the construction's temporaries (the configuration, the
/// monitor's fields being assembled) stayed in `main`'s frame under every
/// step (that frame was 8.7 KB of an 11.96 KB peak; docs/performance.md,
/// Stack).
#[inline(never)]
fn setup() -> Option<Run> {
    let scn = new_scenario()?;
    Some(Run {
        monitor: new_monitor(scn)?,
        sim: new_simulator(scn)?,
        tally: new_tally(scn)?,
    })
}

/// Scenario S2, in static RAM (see `setup` and `chip_setup`, whichever the image has).
#[inline(never)]
fn new_scenario() -> Option<&'static Scenario> {
    Some(cortex_m::singleton!(: Scenario = Scenario::s2())?)
}

#[cfg(not(feature = "sil-chip"))]
/// The `f32` monitor with the host's configuration for `scn`, in static
/// RAM (see [`setup`]). The constructor's `Result` is the static itself, so
/// the 5 KB monitor is not also moved out of it through this frame.
#[inline(never)]
fn new_monitor(scn: &Scenario) -> Option<&'static mut imu_fdi::monitor::UkfMonitor<f32>> {
    use hal_sim::setup::{monitor_config, RunOptions};
    use imu_fdi::monitor::{ConfigError, UkfMonitor};

    #[allow(unused_mut)] // set only with the feature `fault-tracking`
    let mut cfg = monitor_config::<f32>(scn, &RunOptions::default());
    #[cfg(feature = "fault-tracking")]
    {
        cfg.fault_psd = Some(imu_fdi::monitor::UkfMonitorConfig::fault_tracking_psd());
    }
    let built = cortex_m::singleton!(
        : Result<UkfMonitor<f32>, ConfigError> = UkfMonitor::<f32>::new(cfg)
    )?;
    match built {
        Ok(m) => Some(m),
        Err(_) => {
            hprintln!("invalid monitor configuration");
            None
        }
    }
}

/// The seed-1 simulator of `scn`, in static RAM (see `setup` and `chip_setup`, whichever the image has).
#[inline(never)]
fn new_simulator(scn: &Scenario) -> Option<&'static mut hal_sim::Simulator> {
    cortex_m::singleton!(: hal_sim::Simulator = hal_sim::Simulator::new(scn, 1))
}

/// The detection tally of `scn`, in static RAM (see `setup` and `chip_setup`, whichever the image has).
#[inline(never)]
fn new_tally(scn: &Scenario) -> Option<&'static mut hal_sim::setup::DetectionTally> {
    cortex_m::singleton!(: hal_sim::setup::DetectionTally = hal_sim::setup::DetectionTally::new(scn))
}

/// S2 straight into the `f32` monitor: the instruction budget figures.
#[cfg(not(feature = "sil-chip"))]
#[entry]
fn main() -> ! {
    let Some(run) = setup() else { finish(0, false) };
    // The boot paint still holds the set-up's deepest write (the steps
    // repaint the stack below their caller's frame, erasing it).
    let setup_stack = stack_high_water();
    steps(run, setup_stack)
}

/// The S2 steps and the report. Out of line from `main`, so that its frame
/// does not hold the set-up's.
#[cfg(not(feature = "sil-chip"))]
#[inline(never)]
fn steps(run: Run, setup_stack: u32) -> ! {
    use imu_fdi::model::{ImuVec, MeasVec, Measurement};
    use imu_fdi::monitor::{ChannelState, Phase};

    let Run {
        monitor,
        sim,
        tally,
    } = run;
    let overhead = overhead();
    let (mut all, mut predict_only, mut with_update) =
        (Cost::default(), Cost::default(), Cost::default());
    // Deepest stack use below this frame: of the monitor steps, and of
    // everything else (simulator, tally) between them.
    let (mut step_stack, mut other_stack) = (0u32, 0u32);
    let mut sp = 0usize;
    // The most expensive step: its index, whether monitoring, how many
    // channels it flagged, whether it had an aiding update.
    let mut slowest = (0u32, false, 0usize, false);
    // The set-up's writes below this frame are in `setup_stack` already:
    // repainted, so that `other_stack` is the simulator's and the tally's.
    paint_below(cortex_m::register::msp::read() as usize);
    for s in sim {
        let u = ImuVec::from_fn(|i, _| s.imu.map_or(f32::NAN, |v| v[i] as f32));
        let z = MeasVec::from_fn(|i, _| s.aiding[i] as f32);
        let m = Measurement {
            z,
            available: s.aiding_available,
        };
        // The monitor's own stack, apart from the simulator's: paint the
        // free stack below this frame, step, see how deep the step wrote.
        sp = cortex_m::register::msp::read() as usize;
        other_stack = other_stack.max(depth_below(sp));
        paint_below(sp);
        let t0 = instructions();
        // By reference: the report stays in the monitor (no 320-byte copy).
        let r = monitor.step_ref(&u, s.dt as f32, &m);
        let cost = instructions().wrapping_sub(t0).saturating_sub(overhead);
        step_stack = step_stack.max(depth_below(sp));
        // Repainted, so that `other_stack` is not the step's depth again.
        paint_below(sp);
        if cost > all.max {
            let flagged = r
                .status
                .iter()
                .filter(|c| matches!(c, ChannelState::FaultPositive | ChannelState::FaultNegative));
            slowest = (
                all.n,
                r.phase == Phase::Monitoring,
                flagged.count(),
                r.updated,
            );
        }
        all.add(cost);
        if r.updated {
            with_update.add(cost);
        } else {
            predict_only.add(cost);
        }
        tally.record(&s, r);
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
    hprintln!(
        "  slowest: step {} (monitoring {}, {} channels flagged, aiding update {})",
        slowest.0,
        slowest.1,
        slowest.2,
        slowest.3
    );
    if sp == 0 {
        hprintln!("no steps");
        finish(0, false)
    }
    other_stack = other_stack.max(depth_below(sp));
    // Repainting erased the boot paint's record below `main`: the peak is
    // the largest of what the boot paint still shows, the set-up's depth,
    // and the steps' depth plus the deepest use below their frame.
    // The linker-provided top of the stack; its address only.
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let frame = (top - sp) as u32;
    let peak = stack_high_water()
        .max(setup_stack)
        .max(frame + step_stack.max(other_stack));
    hprintln!("peak stack: {} bytes", peak);
    hprintln!(
        "  set-up {}; steps: {} to their frame + monitor step {} / simulator and tally {}",
        setup_stack,
        frame,
        step_stack,
        other_stack
    );
    hprintln!(
        "monitor step stack: {} bytes (deepest write below the caller's frame)",
        step_stack
    );
    tally.print(|line| hprintln!("{}", line));
    finish(peak, tally.all_detected())
}

#[cfg(feature = "sil-chip")]
/// The chip-path run's state, in static RAM, constructed once as in the
/// monitor image: on the stack of `hal_sim::setup::run_via_chip` (scenario,
/// emulated chip, task, simulator and tally in one frame) the image peaked
/// at 20,184 B, over the budget.
struct ChipRun {
    chip: &'static core::cell::RefCell<hal_sim::emulated_icm42688::EmulatedIcm42688>,
    task: &'static mut hal_sim::setup::ChipTask<'static>,
    sim: &'static mut hal_sim::Simulator,
    tally: &'static mut hal_sim::setup::DetectionTally,
}

#[cfg(feature = "sil-chip")]
/// Constructs the chip-path run's state into static RAM, each part in a
/// frame of its own popped before the next part and before the steps (as
/// `setup` in the monitor image).
#[inline(never)]
fn chip_setup() -> Option<ChipRun> {
    let scn = new_scenario()?;
    let chip = new_chip()?;
    Some(ChipRun {
        task: new_task(chip, scn)?,
        chip,
        sim: new_simulator(scn)?,
        tally: new_tally(scn)?,
    })
}

#[cfg(feature = "sil-chip")]
/// The emulated ICM-42688-P in its power-on state, in static RAM (see
/// [`chip_setup`]).
#[inline(never)]
fn new_chip() -> Option<&'static core::cell::RefCell<hal_sim::emulated_icm42688::EmulatedIcm42688>>
{
    use hal_sim::emulated_icm42688::EmulatedIcm42688;
    Some(cortex_m::singleton!(
        : core::cell::RefCell<EmulatedIcm42688> = core::cell::RefCell::new(EmulatedIcm42688::new())
    )?)
}

#[cfg(feature = "sil-chip")]
/// The driver on `chip` and the Monitor task for `scn`
/// (`hal_sim::setup::chip_task`, as the host runs it), in static RAM (see
/// [`chip_setup`]). The constructor's `Option` is the static itself, so the
/// task is not also moved out of it through this frame.
#[inline(never)]
// The `&'static mut` is the task's own static (a singleton), not a mutable
// view of `chip`: the task only keeps the shared reference its bus needs.
#[allow(clippy::mut_from_ref)]
fn new_task(
    chip: &'static core::cell::RefCell<hal_sim::emulated_icm42688::EmulatedIcm42688>,
    scn: &Scenario,
) -> Option<&'static mut hal_sim::setup::ChipTask<'static>> {
    use hal_sim::setup::{chip_task, ChipTask};
    let built = cortex_m::singleton!(: Option<ChipTask<'static>> = chip_task(chip, scn))?;
    if built.is_none() {
        hprintln!("the driver or the monitor refused to start");
    }
    built.as_mut()
}

/// S2 along the firmware's data path: the ICM-42688-P driver reading
/// hal-sim's emulated chip over `SpiDevice`, into the periodic `Monitor`
/// task — the parts and the steps of `hal_sim::setup::run_via_chip` (the
/// code the host CLI runs for `detections --via-chip`), with the parts in
/// static RAM.
#[cfg(feature = "sil-chip")]
#[entry]
fn main() -> ! {
    let Some(run) = chip_setup() else {
        finish(0, false)
    };
    // The boot paint still holds the set-up's deepest write; the steps
    // repaint below their frame (see `chip_steps`).
    let setup_stack = stack_high_water();
    chip_steps(run, setup_stack)
}

/// The chip-path steps and the report. Out of line from `main`, so that its
/// frame does not hold the set-up's.
#[cfg(feature = "sil-chip")]
#[inline(never)]
fn chip_steps(run: ChipRun, setup_stack: u32) -> ! {
    let ChipRun {
        chip,
        task,
        sim,
        tally,
    } = run;
    let overhead = overhead();
    let mut cost = Cost::default();
    // The set-up's writes below this frame are in `setup_stack` already:
    // repainted, so that the boot paint's high-water mark at the end is the
    // steps' own.
    paint_below(cortex_m::register::msp::read() as usize);
    hal_sim::setup::chip_steps(sim, chip, task, tally, |step| {
        let t0 = instructions();
        step();
        cost.add(instructions().wrapping_sub(t0).saturating_sub(overhead));
    });
    let steps_stack = stack_high_water();
    let peak = setup_stack.max(steps_stack);
    hprintln!("S2 seed 1 through the ICM-42688-P driver, the emulated chip and the Monitor task");
    hprintln!(
        "instructions per task step (driver read of the emulated chip + monitor): mean {} max {}",
        cost.mean(),
        cost.max
    );
    hprintln!("peak stack: {} bytes", peak);
    hprintln!("  set-up {}; steps {}", setup_stack, steps_stack);
    tally.print(|line| hprintln!("{}", line));
    finish(peak, tally.all_detected())
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    hprintln!("HardFault at pc {:#010x}", ef.pc());
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // The location only: formatting the message would link the float
    // formatter (≈ 20 KB of flash) for messages that never occur.
    match info.location() {
        Some(l) => hprintln!("panic at {}:{}", l.file(), l.line()),
        None => hprintln!("panic"),
    }
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}
