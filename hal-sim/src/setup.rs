//! Scenario → monitor set-up and a detection tally, without `std`, so the
//! host runner and the firmware image configure the monitor identically.

use imu_fdi::detect::{Detector, Statistic};
use imu_fdi::math::Real;
use imu_fdi::model::{ImuVec, MeasVec};
use imu_fdi::monitor::{Report, UkfMonitorConfig};

use crate::fault::FaultRow;
use crate::scenario::{Scenario, MAX_FAULTS};
use crate::sim::SimSample;

/// Detector choices a run is parameterised by (the rest of the
/// configuration follows the scenario's sensors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOptions {
    /// Decision rule.
    pub detector: Detector,
    /// Raw or whitened windows.
    pub statistic: Statistic,
    /// Per-tail α of the t-test.
    pub alpha: f64,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            detector: Detector::RuntimeMatrixGlr,
            statistic: Statistic::Normalized,
            alpha: 1e-6,
        }
    }
}

/// The monitor configuration matching a scenario's sensors: the aiding noise
/// σ and IMU full scale are the sensors' specifications (what an integrator
/// knows); everything else is the monitor's defaults for that vehicle class.
pub fn monitor_config<T: Real>(scn: &Scenario, opts: &RunOptions) -> UkfMonitorConfig<T> {
    let mut c = match scn.aiding.kind {
        imu_fdi::model::AidingKind::DvlCompass => UkfMonitorConfig::<T>::auv(),
        imu_fdi::model::AidingKind::GnssAttitude => UkfMonitorConfig::<T>::aircraft(),
    };
    let a = &scn.aiding;
    c.meas_sigma = MeasVec::new(
        T::lit(a.vel_sigma),
        T::lit(a.vel_sigma),
        T::lit(a.vel_sigma),
        T::lit(a.att_sigma[0]),
        T::lit(a.att_sigma[1]),
        T::lit(a.att_sigma[2]),
    );
    let fa = scn.imu_errors.accel.full_scale;
    let fg = scn.imu_errors.gyro.full_scale;
    c.full_scale = ImuVec::new(
        T::lit(fa),
        T::lit(fa),
        T::lit(fa),
        T::lit(fg),
        T::lit(fg),
        T::lit(fg),
    );
    c.imu_period = T::lit(1.0 / scn.imu_rate_hz);
    c.detector = opts.detector;
    c.statistic = opts.statistic;
    c.alpha = opts.alpha;
    c
}

/// Per fault row of a scenario: was it flagged on its channel with the right
/// sign, and when first.
#[derive(Debug, Clone)]
pub struct DetectionTally {
    rows: heapless::Vec<(FaultRow, Option<f64>), MAX_FAULTS>,
}

impl DetectionTally {
    /// A tally for `scn`'s fault table (additive faults only).
    pub fn new(scn: &Scenario) -> Self {
        Self {
            rows: scn
                .faults
                .iter()
                .filter(|r| !r.is_hardware())
                .map(|r| (*r, None))
                .collect(),
        }
    }

    /// Each fault row with the time it was first flagged on its channel
    /// with the right sign (`None`: not detected).
    pub fn rows(&self) -> &[(FaultRow, Option<f64>)] {
        &self.rows
    }

    /// Records one step.
    pub fn record<T: Real>(&mut self, s: &SimSample, r: &Report<T>) {
        self.record_status(s, &r.status);
    }

    /// Records one step from per-channel states (e.g. a task report).
    pub fn record_status(&mut self, s: &SimSample, status: &[imu_fdi::monitor::ChannelState; 6]) {
        for (row, first) in self.rows.iter_mut() {
            if first.is_some() || !row.active(s.t) {
                continue;
            }
            let f = s.fault.get(row.channel).copied().unwrap_or(0.0);
            let want = if f > 0.0 { 1 } else { -1 };
            if f != 0.0 && status.get(row.channel).and_then(|c| c.sign()) == Some(want) {
                *first = Some(s.t);
            }
        }
    }

    /// True when every row was detected.
    pub fn all_detected(&self) -> bool {
        self.rows.iter().all(|(_, f)| f.is_some())
    }

    /// First detection time of each row (None: not detected).
    pub fn first_detections(&self) -> heapless::Vec<Option<f64>, MAX_FAULTS> {
        self.rows.iter().map(|(_, f)| *f).collect()
    }

    /// Number of rows detected, of all rows.
    pub fn counts(&self) -> (usize, usize) {
        (
            self.rows.iter().filter(|(_, f)| f.is_some()).count(),
            self.rows.len(),
        )
    }

    /// One line per fault row through `out`.
    pub fn print(&self, mut out: impl FnMut(core::fmt::Arguments<'_>)) {
        for (row, first) in self.rows.iter() {
            let name = imu_fdi::model::CHANNEL_NAMES
                .get(row.channel)
                .copied()
                .unwrap_or("?");
            // Times as integer centiseconds: the same text on host and target,
            // without pulling float formatting (≈ 20 KB) into the firmware.
            let cs = |t: f64| libm::round(t * 100.0) as i64;
            let (start, end) = (cs(row.start) / 100, cs(row.end) / 100);
            match first {
                Some(t) => {
                    let (at, after) = (cs(*t), cs(*t - row.start));
                    out(format_args!(
                        "fault {} {}-{} s: detected at {}.{:02} s ({}.{:02} s after onset)",
                        name,
                        start,
                        end,
                        at / 100,
                        at % 100,
                        after / 100,
                        after % 100
                    ))
                }
                None => out(format_args!(
                    "fault {} {}-{} s: NOT detected",
                    name, start, end
                )),
            }
        }
    }
}

/// The ICM-42688-P configuration the chip-in-the-loop runs use: the
/// narrowest ranges that hold the AUV scenarios with their faults.
pub fn chip_config() -> imu_fdi::imu::icm42688::Config {
    use imu_fdi::imu::icm42688::{AccelRange, Config, GyroRange, Odr};
    Config {
        gyro_range: GyroRange::Dps250,
        accel_range: AccelRange::G4,
        odr: Odr::Hz100,
        ui_filter_bw: 1,
    }
}

/// The Monitor task of the chip-in-the-loop runs: the ICM-42688-P driver
/// on the emulated chip's shared bus, into the UKF monitor.
pub type ChipTask<'a> = imu_fdi::monitor::MonitorTask<
    imu_fdi::imu::icm42688::Icm42688<crate::emulated_icm42688::SharedBus<'a>>,
>;

/// The emulated chip needs no waiting between the driver's set-up writes.
struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

/// The driver started on `chip` ([`chip_config`]) and the Monitor task
/// configured for `scn` ([`monitor_config`], default options), or `None`
/// if the driver or the monitor refused to start. A part of
/// [`run_via_chip`] of its own so that an image can construct the task
/// where it keeps it (the QEMU image: static RAM) instead of in the run's
/// frame.
pub fn chip_task<'a>(
    chip: &'a core::cell::RefCell<crate::emulated_icm42688::EmulatedIcm42688>,
    scn: &Scenario,
) -> Option<ChipTask<'a>> {
    use imu_fdi::imu::icm42688::Icm42688;

    let imu = Icm42688::new(
        crate::emulated_icm42688::SharedBus(chip),
        chip_config(),
        &mut NoDelay,
    )
    .ok()?;
    ChipTask::new(imu, monitor_config(scn, &RunOptions::default())).ok()
}

/// The steps of [`run_via_chip`]: each sample of `sim` presented by `chip`,
/// read by `task`'s driver and monitored, the task's verdict recorded in
/// `tally`. `timed` is handed each `task.step` call to run (the QEMU image
/// counts its instructions). The parts are passed in, not owned, so that
/// their storage is the caller's choice.
pub fn chip_steps(
    sim: impl Iterator<Item = SimSample>,
    chip: &core::cell::RefCell<crate::emulated_icm42688::EmulatedIcm42688>,
    task: &mut ChipTask<'_>,
    tally: &mut DetectionTally,
    mut timed: impl FnMut(&mut dyn FnMut()),
) {
    use imu_fdi::model::Measurement;

    for s in sim {
        if let Some(v) = s.imu {
            chip.borrow_mut()
                .set_sample([v[0], v[1], v[2]], [v[3], v[4], v[5]], 25.0);
        }
        let m = Measurement {
            z: MeasVec::from_fn(|i, _| s.aiding.get(i).map_or(f32::NAN, |v| *v as f32)),
            available: s.aiding_available,
        };
        let mut report = None;
        timed(&mut || report = Some(task.step(s.dt as f32, &m)));
        if let Some(r) = report {
            tally.record_status(&s, &r.status);
        }
    }
}

/// Scenario `scn` (seed `seed`) through the real ICM-42688-P driver reading
/// hal-sim's register-level emulated chip, into the periodic
/// [`MonitorTask`](imu_fdi::monitor::MonitorTask) — the firmware's data path,
/// shared by the host CLI (`detections --via-chip`) and the QEMU image so
/// both run the same code ([`chip_task`], then [`chip_steps`]; the QEMU
/// image calls the two itself, with its parts in static RAM). `timed` is
/// handed each `task.step` call to run (the QEMU image counts its
/// instructions). Returns the tally, or `None` if the driver or the monitor
/// refused to start.
pub fn run_via_chip(
    scn: &Scenario,
    seed: u64,
    timed: impl FnMut(&mut dyn FnMut()),
) -> Option<DetectionTally> {
    let chip = core::cell::RefCell::new(crate::emulated_icm42688::EmulatedIcm42688::new());
    let mut task = chip_task(&chip, scn)?;
    let mut tally = DetectionTally::new(scn);
    chip_steps(
        crate::sim::Simulator::new(scn, seed),
        &chip,
        &mut task,
        &mut tally,
        timed,
    );
    Some(tally)
}
