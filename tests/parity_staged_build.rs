//! GIVEN the cone-of-six white-noise parity monitor on S4 (seed 1), WHEN
//! training ends, THEN its tests are built one stage per step while the
//! report says it cannot judge yet (issue 17: ≈ 190 k instructions in one
//! step before), the block completed meanwhile is decided once they are
//! built, and the end of calibration gives the thresholds a full rebuild
//! gives: the χ² quantile × margin × the calibration's scale, bit for bit.

use hal_sim::array::{ArraySim, ArraySpec};
use imu_fdi::parity::{BlockStage, Geometry, ParityConfig, ParityMonitor, ParityPhase, Reading};
use imu_fdi::stats::chi_square_upper_quantile;

#[test]
fn the_first_build_is_staged_and_says_it_cannot_judge_until_built() {
    let spec = ArraySpec::s4();
    let sim = ArraySim::new(&spec, 1);
    let mut cfg = ParityConfig::<f32>::gyro(spec.rate_hz, spec.errors.full_scale as f32);
    cfg.set_lead_in(sim.lead_in_samples());
    let block = usize::from(cfg.block_len);
    let mut m = ParityMonitor::<f32, 6, 16>::new(&Geometry::cone6(), cfg).unwrap();
    // Step index of the end of training, of every staged step, of the first
    // decision and of the first monitoring report.
    let (mut trained, mut staged, mut first_decision, mut monitoring) = (None, vec![], None, None);
    for (i, s) in sim.enumerate() {
        if s.t >= 6.0 {
            break; // the fault
        }
        let r: [Reading<f32>; 6] = s.readings.map(|r| r.map(|x| x as f32));
        let stage = m.pending_stage();
        let rep = m.step(&r);
        if matches!(stage, Some(BlockStage::Reconfigure(_))) {
            staged.push((i, rep.phase));
            assert!(
                !rep.fault && !rep.decision && rep.suspect.is_none(),
                "step {i}"
            );
        }
        if trained.is_none() && m.baseline().is_some() {
            trained = Some(i);
        }
        if rep.decision && first_decision.is_none() {
            first_decision = Some(i);
        }
        if rep.phase == ParityPhase::Monitoring && monitoring.is_none() {
            monitoring = Some((i, rep));
        }
        assert!(!rep.fault, "alarm before the fault at step {i}");
    }
    let trained = trained.expect("training ended");
    // 1 + 2 × 6 stages: projections and PCA, then each CUSUM's root search
    // in two halves; all but the last report `Training`, the last one the
    // phase the build leads to.
    let phases: Vec<_> = staged.iter().map(|(_, p)| *p).collect();
    let mut want = vec![ParityPhase::Training; 12];
    want.push(ParityPhase::Calibrating);
    assert_eq!(phases, want);
    let steps: Vec<_> = staged.iter().map(|(i, _)| *i).collect();
    assert_eq!(steps, (trained + 1..=trained + 13).collect::<Vec<_>>());
    // The first block closed at `trained + block` during the build and is
    // decided on the first step after it (4 samples late with 10-sample
    // blocks); the blocks after it close on their usual samples.
    assert_eq!(block, 10);
    assert_eq!(first_decision, Some(trained + 14));
    let (_, rep) = monitoring.expect("calibration ended before the fault");
    let scales = m.threshold_scales();
    let chi2 = |dof| chi_square_upper_quantile(cfg.false_alarm, dof).unwrap() as f32;
    let margin = cfg.threshold_margin;
    assert_eq!(
        rep.glt_threshold.to_bits(),
        (chi2(3) * margin * scales[0]).to_bits()
    );
    assert_eq!(
        rep.pca_threshold.to_bits(),
        (chi2(2) * margin * scales[1]).to_bits()
    );
    assert!(scales.iter().all(|s| *s >= 1.0), "{scales:?}");
}
