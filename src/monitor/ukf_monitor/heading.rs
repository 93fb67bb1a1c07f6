//! A constant heading offset between the attitude aiding's frame and the
//! IMU's (issue 15): a mis-surveyed GNSS antenna baseline, an AHRS or
//! compass mounted a few degrees off. Fused as is, the offset turns the
//! filter's heading by (most of) it, so the NED velocity it propagates from
//! the accelerometers turns away from the GNSS velocity whenever the
//! vehicle accelerates, and the innovations this leaves look like sensor
//! faults (measured: 3° gives ≈ 220 false-alarm events per hour on the
//! aircraft).
//!
//! The yaw innovation says little (the filter follows the 0.2° yaw aiding);
//! the velocity says it: over a block of [`HEADING_BLOCK_EPOCHS`] aiding
//! epochs, the horizontal change of the GNSS velocity `Δz` and the change
//! of the filter's predicted velocity `Δh` (IMU propagation alone: the
//! per-epoch changes of the state history telescope over the block, as in
//! `delay.rs`) differ by the rotation `e` between the filter's heading and
//! the truth, `Δz ≈ R(−e)·Δh`, and by what the horizontal accelerometers'
//! bias error adds: per block, `y = Δz − Δh − C·b̂ = e·g − C·β + c`, with
//! `g = (Δh_e, −Δh_n)`, `C = Σ C_bn·dt` the horizontal rows of the
//! body-to-NED rotation's x and y columns over the block (what a unit bias
//! on a_x / a_y adds), `b̂` the nominal bias compensated, `β` the true
//! horizontal bias and `c` a constant NED offset per block (a tilt error
//! over a straight leg). `e`, `β` and `c` are solved for together by least
//! squares over the blocks (two rows per block, normal equations of five
//! unknowns); `se(ê) = σ_v·√2·√(N⁻¹)₀₀`. The bias has to be in the fit:
//! in a coordinated turn the heading error's `e·g` lies along the track, as
//! does an a_x bias error (measured with the angle alone, seeds 500 and
//! 517: estimates wandering between 1.2° and 5°, `u` below the offset
//! actually left, a_x learnt 0.10 m/s² off from turns so marked clean, and
//! every post-clear event of seeds 500–519 on a_x). With it, turns
//! all one way leave `e` and `β` confounded and `se` says so; turns both
//! ways separate them.
//! When `ê` is significant (beyond three standard errors) it is added to
//! the offset, which is taken off the yaw aiding before fusion; the blocks
//! so far stay in the sums, re-referenced to the residual `e − step`
//! (the model is linear in `e`), so each step leaves a better-determined
//! residual; a residual too small to be significant keeps
//! accumulating until it is. Only horizontal manoeuvres inform `ê`: in
//! straight flight the sums do not grow and nothing is applied. Learning
//! pauses while a fault is flagged (an accelerometer fault turns `Δh` as
//! well), and the estimate is bounded to ±[`HEADING_OFFSET_MAX_DEG`]:
//! larger is a mounting error to fix, not to learn. While learning, each
//! applied step restarts learning, so monitoring begins at a settled
//! offset once the vehicle has manoeuvred (in straight flight nothing is
//! applied and learning ends as usual). Needs the aiding's
//! velocity in NED (GNSS, M2); with body-frame DVL velocity (M1) the
//! heading does not enter the velocity and nothing is learnt.
//!
//! **What the unresolved offset contaminates.** A heading error `δψ` turns
//! the propagated horizontal specific force, so while the vehicle
//! accelerates horizontally the velocity innovations carry about `δψ·|a_h|`,
//! which the nominal-bias learner would take for an accelerometer bias (a
//! 25° banked turn: 4.6 m/s², 0.24 m/s² per 3°; measured: 0.14 m/s² learnt
//! on a_x for a true 0.01, then a_x flagged for the rest of the hour). The
//! estimator keeps a bound `u` on the offset still unresolved: the learnt
//! range ±[`HEADING_OFFSET_MAX_DEG`] until a block evaluation is precise
//! (standard error below [`HEADING_MAX_SE_DEG`]), then `|ê| + 3·se` of its
//! residual (after an applied step, what the step leaves of it). An aiding
//! epoch whose IMU-propagated horizontal acceleration gives
//! `u·|a_h| > ½·min_fault` (smaller horizontal accelerometer) is marked
//! contaminated: the horizontal accelerometers' nominal biases are not
//! learnt from it (a_z's and the gyros' are: a vertical velocity error is
//! not turned by a heading error), and the learning phase does not count
//! it, so learning lasts until it has `learn_s` of clean epochs (on the
//! aircraft 12.5–50 s on seeds 500–519, up to 68 s on 520–559, instead of
//! 10 s; the report says `Learning` and
//! `NotMonitored` meanwhile). Once monitoring, a contaminated epoch leaves
//! a_x and a_y `NotMonitored` (`detection.rs`): learning can end on
//! straight flight before any block evaluation is precise, and the first
//! turn then put the whole offset into the velocity innovations (seed 413:
//! 4 a_x events at 27–31 s with two decisions, 12 with one). Once the
//! offset is resolved such epochs are rare (0–0.9 % of the monitoring time
//! on the aircraft). Each applied step also turns the filter's
//! heading with the corrected yaw aiding (`turn_heading`).

use super::{UkfMonitor, MAX_DELAY_STEPS};
use crate::math::{try_inverse, wrap_pi, Real};
use crate::model::{AidingKind, MeasVec, Measurement, StateVec, PITCH, ROLL, YAW};
use crate::monitor::{ChannelState, Phase};

/// Aiding epochs per block (2 s at 10 Hz).
const HEADING_BLOCK_EPOCHS: u16 = 20;
/// Largest offset learnt, degrees.
const HEADING_OFFSET_MAX_DEG: f64 = 10.0;
/// Significance of an applied step, standard errors.
const HEADING_SIGNIFICANCE: f64 = 3.0;
/// Largest standard error of an applied step, degrees: a block or two of
/// manoeuvre is not enough, whatever its noise says, because the filter's
/// own transients after a step are not noise.
const HEADING_MAX_SE_DEG: f64 = 0.5;
/// Fraction of a significant angle applied per step: the filter's heading
/// follows a changed aiding over a few seconds, and the next blocks measure
/// what is left.
const HEADING_GAIN: f64 = 0.5;
/// Fraction of the accelerometers' `min_fault` the contamination `u·|a_h|`
/// may reach in an epoch the accelerometer biases are learnt from: half the
/// smallest fault the monitor reports.
const HEADING_CONTAMINATION_FRACTION: f64 = 0.5;

/// Unknowns of the block least squares: the heading error, the horizontal
/// accelerometers' bias (body x, y) and a constant NED velocity-change
/// offset per block (north, east).
const HEADING_PARAMS: usize = 5;

/// Block sums of the horizontal velocity changes and the normal equations
/// over blocks.
#[derive(Debug, Clone)]
pub(super) struct HeadingEstimator<T> {
    /// Learnt offset, rad.
    pub(super) offset: T,
    /// Bound on the offset not yet resolved, rad (module docs).
    uncertainty: T,
    /// The velocity innovations of this epoch may carry the unresolved
    /// offset (module docs).
    pub(super) contaminated: bool,
    /// Previous horizontal GNSS velocity and IMU periods since it.
    prev: Option<([T; 2], usize)>,
    block_z: [T; 2],
    block_h: [T; 2],
    /// `Σ C·dt` over the block: what a unit body-frame x / y accelerometer
    /// bias adds to the horizontal velocity change (rows north, east).
    block_c: [[T; 2]; 2],
    /// `Σ C·b̂·dt`: what the nominal bias compensated did (module docs).
    block_cb: [T; 2],
    block_epochs: u16,
    /// Blocks in the normal equations.
    n: T,
    /// Normal matrix and right-hand side of the block least squares.
    normal: nalgebra::SMatrix<T, HEADING_PARAMS, HEADING_PARAMS>,
    rhs: nalgebra::SVector<T, HEADING_PARAMS>,
}

impl<T: Real> HeadingEstimator<T> {
    pub(super) fn new() -> Self {
        Self {
            offset: T::zero(),
            uncertainty: T::lit(HEADING_OFFSET_MAX_DEG.to_radians()),
            contaminated: false,
            prev: None,
            block_z: [T::zero(); 2],
            block_h: [T::zero(); 2],
            block_c: [[T::zero(); 2]; 2],
            block_cb: [T::zero(); 2],
            block_epochs: 0,
            n: T::zero(),
            normal: nalgebra::SMatrix::zeros(),
            rhs: nalgebra::SVector::zeros(),
        }
    }

    /// One IMU period passed.
    pub(super) fn tick(&mut self) {
        if let Some((_, age)) = self.prev.as_mut() {
            *age = age.saturating_add(1);
        }
    }

    fn interrupt(&mut self) {
        self.contaminated = false;
        self.prev = None;
        self.clear_block();
    }

    fn clear_block(&mut self) {
        self.block_z = [T::zero(); 2];
        self.block_h = [T::zero(); 2];
        self.block_c = [[T::zero(); 2]; 2];
        self.block_cb = [T::zero(); 2];
        self.block_epochs = 0;
    }

    /// Adds the finished block to the normal equations: two rows (north,
    /// east) of `y = e·g − C·β + c` (module docs).
    fn add_block(&mut self) {
        let [hn, he] = self.block_h;
        let [[c00, c01], [c10, c11]] = self.block_c;
        let y = [
            self.block_z[0] - hn - self.block_cb[0],
            self.block_z[1] - he - self.block_cb[1],
        ];
        let rows = [
            [he, -c00, -c01, T::one(), T::zero()],
            [-hn, -c10, -c11, T::zero(), T::one()],
        ];
        for (phi, y) in rows.iter().zip(y.iter()) {
            for (i, a) in phi.iter().enumerate() {
                if let Some(r) = self.rhs.get_mut(i) {
                    *r += *a * *y;
                }
                for (j, b) in phi.iter().enumerate() {
                    if let Some(m) = self.normal.get_mut((i, j)) {
                        *m += *a * *b;
                    }
                }
            }
        }
        self.n += T::one();
        self.clear_block();
    }

    /// After a step of `turn` the unknown is the residual `e − turn`: the
    /// past rows `y = e·g + …` read `y − turn·g = (e − turn)·g + …`, so the
    /// right-hand side loses `turn` times the normal matrix's first column
    /// and the blocks so far keep informing the estimate (exact for the
    /// linear model).
    fn rereference(&mut self, turn: T) {
        let col = self.normal.column(0).clone_owned();
        self.rhs -= col * turn;
    }
}

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The aiding with the learnt offset taken off its yaw.
    pub(super) fn correct_heading(&self, aiding: &Measurement<T>) -> Measurement<T> {
        let mut m = *aiding;
        if let Some(z) = m.z.get_mut(YAW) {
            *z = wrap_pi(*z - self.heading.offset);
        }
        m
    }

    /// The heading offset between the attitude aiding and the IMU frame
    /// learnt so far, rad (0 unless
    /// [`estimate_heading_offset`](super::UkfMonitorConfig::estimate_heading_offset)).
    pub fn heading_offset_estimate(&self) -> T {
        self.heading.offset
    }

    /// Before an update: one epoch of horizontal velocity changes; a
    /// significant residual turns the offset and the filter's heading.
    #[inline(never)] // own stack frame and one copy (issue 17)
    pub(super) fn learn_heading_offset(
        &mut self,
        aiding: &Measurement<T>,
        omega: &nalgebra::Vector3<T>,
    ) {
        let flagged = self
            .report
            .status
            .iter()
            .any(|s| matches!(s, ChannelState::FaultPositive | ChannelState::FaultNegative));
        let learning = matches!(self.phase, Phase::Learning | Phase::Monitoring);
        let has_vel = aiding.available.iter().take(2).all(|a| *a);
        if flagged || !learning || self.cfg.aiding != AidingKind::GnssAttitude {
            self.heading.interrupt();
            return;
        }
        if !has_vel {
            return;
        }
        let z = [aiding.z.x, aiding.z.y];
        let prev = self.heading.prev.replace((z, 0));
        let Some((z0, age)) = prev else { return };
        // The history's states at the velocity's own lag and one aiding
        // interval before it (newest first).
        let lag = self.velocity_lag_steps();
        if lag + age > MAX_DELAY_STEPS {
            self.heading.interrupt();
            return;
        }
        let mut now = None;
        let mut then = None;
        for (k, x) in self.history.oldest_ordered().rev().enumerate() {
            if k == lag {
                now = Some(*x);
            }
            if k == lag + age {
                then = Some(*x);
            }
        }
        let (Some(now), Some(then)) = (now, then) else {
            self.heading.interrupt();
            return;
        };
        let (a, b): (MeasVec<T>, MeasVec<T>) = (
            self.meas.predict(&now, omega),
            self.meas.predict(&then, omega),
        );
        // What the unresolved offset can put into this epoch's velocity
        // innovations, against half the smallest horizontal accelerometer
        // fault (module docs). `age ≥ 1`: the history advanced since `z0`.
        let span = T::lit(age.max(1) as f64) * self.cfg.imu_period;
        let (an, ae) = ((a.x - b.x) / span, (a.y - b.y) / span);
        let a_h = (an * an + ae * ae).sqrt_fast();
        let smallest = self.cfg.min_fault.x.min(self.cfg.min_fault.y);
        // The horizontal rows of the body-to-NED rotation's x and y
        // columns at the epoch, times its span: the velocity change a unit
        // bias on a_x / a_y adds (module docs).
        let (sr, cr) = now
            .get(ROLL)
            .copied()
            .unwrap_or_else(T::zero)
            .sin_cos_fast();
        let (sp, cp) = now
            .get(PITCH)
            .copied()
            .unwrap_or_else(T::zero)
            .sin_cos_fast();
        let (sy, cy) = now.get(YAW).copied().unwrap_or_else(T::zero).sin_cos_fast();
        let c = [
            [cp * cy * span, (sr * sp * cy - cr * sy) * span],
            [cp * sy * span, (sr * sp * sy + cr * cy) * span],
        ];
        let (bx, by) = (self.nominal_bias.x, self.nominal_bias.y);
        let h = &mut self.heading;
        h.contaminated = h.uncertainty * a_h > smallest * T::lit(HEADING_CONTAMINATION_FRACTION);
        h.block_z[0] += z[0] - z0[0];
        h.block_z[1] += z[1] - z0[1];
        h.block_h[0] += a.x - b.x;
        h.block_h[1] += a.y - b.y;
        for (acc, row) in h.block_c.iter_mut().zip(c.iter()) {
            acc[0] += row[0];
            acc[1] += row[1];
        }
        h.block_cb[0] += c[0][0] * bx + c[0][1] * by;
        h.block_cb[1] += c[1][0] * bx + c[1][1] * by;
        h.block_epochs += 1;
        if h.block_epochs < HEADING_BLOCK_EPOCHS {
            return;
        }
        h.add_block();
        // Three blocks: six rows for the five unknowns.
        if h.n < T::lit(3.0) {
            return;
        }
        // The angle with the accelerometer bias and the NED offset solved
        // for alongside: its variance is the (0, 0) element of the inverse
        // normal matrix, which grows where the manoeuvres do not tell the
        // heading from a bias (turns all one way).
        let Some(inv) = try_inverse(&h.normal) else {
            return;
        };
        let theta = inv * h.rhs;
        let (e, var) = (theta.x, inv.m11);
        if !(var > T::zero() && e.finite()) {
            return;
        }
        let sigma = self.cfg.meas_sigma.x.max(self.cfg.meas_sigma.y);
        let se = sigma * T::lit(core::f64::consts::SQRT_2) * var.sqrt_fast();
        let max = T::lit(HEADING_OFFSET_MAX_DEG.to_radians());
        let significance = T::lit(HEADING_SIGNIFICANCE);
        let precise = se < T::lit(HEADING_MAX_SE_DEG.to_radians());
        if precise {
            h.uncertainty = (e.abs() + significance * se).min(max);
        }
        if e.abs() > significance * se && precise {
            let before = h.offset;
            h.offset = (h.offset + e * T::lit(HEADING_GAIN)).max(-max).min(max);
            let turn = h.offset - before;
            h.uncertainty = (e.abs() * T::lit(1.0 - HEADING_GAIN) + significance * se).min(max);
            h.rereference(turn);
            self.turn_heading(turn);
            // Learning started against the old offset: start it again.
            self.restart_learning();
        }
    }
}

impl<T: Real, const W: usize> UkfMonitor<T, W> {
    /// The offset grew by `turn`: the corrected yaw aiding moves by `−turn`
    /// from now on, and so do the filter's heading and its history, at
    /// unchanged NED velocity (the body velocity turns with the heading).
    /// Without this the filter followed the jump over seconds and its yaw
    /// innovations looked like a yaw-rate fault (measured: flags on r at
    /// each applied step).
    fn turn_heading(&mut self, turn: T) {
        if self.cfg.aiding != AidingKind::GnssAttitude {
            return;
        }
        let meas = self.meas;
        let zero = nalgebra::Vector3::zeros();
        let turned = |x: &StateVec<T>| {
            let v = meas.predict(x, &zero);
            let mut n = *x;
            if let Some(y) = n.get_mut(YAW) {
                *y = wrap_pi(*y - turn);
            }
            let vb = meas.velocity_to_body(&n, &nalgebra::Vector3::new(v.x, v.y, v.z));
            n.x = vb.x;
            n.y = vb.y;
            n.z = vb.z;
            n
        };
        let x = turned(self.ukf.state());
        let p = *self.ukf.covariance();
        self.reset_filter(x, p);
        let mut shifted = heapless::HistoryBuf::<StateVec<T>, { MAX_DELAY_STEPS + 1 }>::new();
        for s in self.history.oldest_ordered() {
            shifted.write(turned(s));
        }
        self.history = shifted;
    }
}
