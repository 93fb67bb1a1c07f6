//! The block test's decisions: scores, runs, flags, withdrawal.

use super::*;

impl<T: Real> BlockTest<T> {
    /// Scores the newest windows of each length, updates the runs, flags
    /// and estimates.
    pub(super) fn decide(&mut self, cfg: &BlockTestConfig<T>, limits: &ChannelLimits<T>) {
        let longest = usize::from(cfg.lengths[NL - 1]);
        let need = T::lit(longest as f64);
        // Per length and channel: the window mean less the offset and the
        // deviation at threshold (`None`: this length cannot judge yet).
        let mut judged = [[None::<(T, T)>; 3]; NL];
        // Lengths whose newest window is more active than what was learnt.
        let mut uncovered = [false; NL];
        for (k, len) in cfg.lengths.iter().map(|l| usize::from(*l)).enumerate() {
            let Some(w) = self.window(0, len) else {
                continue;
            };
            // The learnt spread holds for the motion it was learnt at: a
            // window is judged only if one longest window of learnt blocks
            // was at least as active (a variance learnt at rest says
            // nothing of flight). Its deviation is still computed: it may
            // show that a fault has ended (below).
            if let Some(u) = uncovered.get_mut(k) {
                *u = self.covered(len) < need;
            }
            for c in 0..3 {
                let Some((m, _, n)) = self.moments(c) else {
                    continue;
                };
                // The offset must rest on two longest windows of blocks.
                if n < T::lit(2.0 * longest as f64) {
                    continue;
                }
                let h = self.window_factor(c, 0, len, longest);
                let Some((var, nu)) = self.window_variance(cfg, k, c, h) else {
                    continue;
                };
                if nu < cfg.min_dof {
                    continue;
                }
                let Some(t) = self.threshold(k, c, nu) else {
                    continue;
                };
                let lim = limits.nominal.get(c).copied().unwrap_or_else(T::zero);
                let off = m.fmax(-lim).fmin(lim);
                let (Some(wc), Some(slot)) =
                    (w.get(c), judged.get_mut(k).and_then(|j| j.get_mut(c)))
                else {
                    continue;
                };
                *slot = Some((*wc - off, var.sqrt_fast() * t));
            }
        }
        if let Some(j) = judged.first() {
            self.shortest = *j;
        }
        let mut best = [T::zero(); 3];
        let mut sign = [0i8; 3];
        let mut est = [T::zero(); 3];
        let mut best_len = [0u8; 3];
        // Every length's ratio, muted or not: what learning is gated on.
        let mut worst = [T::zero(); 3];
        for c in 0..3 {
            let col = |k: usize| judged.get(k).and_then(|j| j.get(c)).copied().flatten();
            // A longer window whose deviation the newest window of a
            // shorter length contradicts (falls short of it, in its sign, by
            // more than the shorter window's own threshold deviation: a
            // false rejection has the test's probability) holds a fault that
            // has ended: the longer lengths are muted on this channel until
            // their windows have flushed. Any shorter length, not only the
            // shortest: where the aiding's errors telescope a window's
            // spread falls as 1/L², and the shortest window's threshold may
            // exceed the longest's whole deviation.
            let ended = (1..NL).any(|k| {
                let Some((d, lim)) = col(k) else {
                    return false;
                };
                let s = if d > T::zero() { T::one() } else { -T::one() };
                d.abs() > lim && (0..k).filter_map(col).any(|(dj, limj)| s * (d - dj) > limj)
            });
            if ended {
                if let Some(m) = self.mute.get_mut(c) {
                    *m = cfg.lengths[NL - 1];
                }
            }
            let muted = self.mute.get(c).is_some_and(|m| *m > 0);
            for k in 0..NL {
                let Some((d, lim)) = col(k) else {
                    continue;
                };
                // A window more active than anything learnt is not judged,
                // nor does it stop learning (its ratio means nothing yet:
                // a spread learnt at rest would otherwise never learn flight).
                if uncovered.get(k).copied().unwrap_or(true) {
                    continue;
                }
                let r = d.abs() / lim;
                if let Some(w) = worst.get_mut(c) {
                    *w = w.fmax(r);
                }
                if muted && k > 0 {
                    continue;
                }
                // Flagged only beyond the smallest fault reported as well
                // (learning stays gated on the statistical ratio above).
                let floor = limits.relevant.get(c).copied().unwrap_or_else(T::zero);
                let r = d.abs() / lim.fmax(floor);
                if let (Some(b), Some(sg), Some(e), Some(bl)) = (
                    best.get_mut(c),
                    sign.get_mut(c),
                    est.get_mut(c),
                    best_len.get_mut(c),
                ) {
                    if r > *b {
                        *b = r;
                        *sg = if d > T::zero() { 1 } else { -1 };
                        *e = d;
                        *bl = k as u8;
                    }
                }
            }
            if let Some(m) = self.mute.get_mut(c) {
                *m = m.saturating_sub(1);
            }
        }
        let hold_blocks = cfg.hold;
        for c in 0..3 {
            // A flag raised by a length that cannot judge this window (more
            // active than anything learnt) is kept as it is: not judged is
            // not nominal. The withdrawal (a fault that ended) still clears
            // it, and so does the end of its evidence: once one longest
            // window has passed since the last confirmed decision, no window
            // holds a block that raised it (simulated aircraft, the
            // velocity-increment test learning little between episodes: a
            // flag kept blind reappeared 11 s after a step had ended).
            let raised_by = self.flag_len.get(c).copied().unwrap_or(0);
            let since = self.since_confirm.get(c).copied().unwrap_or(u8::MAX);
            let blind = since < cfg.lengths[NL - 1]
                && self.detail.flag.get(c).is_some_and(|f| *f != 0)
                && uncovered
                    .get(usize::from(raised_by))
                    .copied()
                    .unwrap_or(false)
                && best.get(c).is_some_and(|r| *r <= T::one())
                && self.mute.get(c).is_none_or(|m| *m == 0);
            if blind {
                if let Some(sc) = self.since_confirm.get_mut(c) {
                    *sc = sc.saturating_add(1);
                }
                continue;
            }
            let (Some(r), Some(sg), Some(run), Some(hold), Some(flag), Some(e), Some(out)) = (
                best.get(c),
                sign.get(c),
                self.run.get_mut(c),
                self.hold.get_mut(c),
                self.detail.flag.get_mut(c),
                est.get(c),
                self.detail.estimate.get_mut(c),
            ) else {
                continue;
            };
            if *r > T::one() {
                *run = if run.1 == *sg {
                    (run.0.saturating_add(1), *sg)
                } else {
                    (1, *sg)
                };
            } else {
                *run = (0, 0);
            }
            if let Some(sc) = self.since_confirm.get_mut(c) {
                *sc = if run.0 >= cfg.confirm {
                    0
                } else {
                    sc.saturating_add(1)
                };
            }
            if run.0 >= cfg.confirm {
                // Confirmed on windows free of the UKF's own flags?
                if let (Some(cl), Some(m)) = (self.confirmed_clean.get_mut(c), self.ukf_mask.get(c))
                {
                    *cl = *m == 0;
                }
                *flag = run.1;
                *hold = hold_blocks;
                *out = *e;
                if let (Some(fl), Some(bl)) = (self.flag_len.get_mut(c), best_len.get(c)) {
                    *fl = *bl;
                }
            } else if *hold > 0 {
                *hold -= 1;
            } else {
                *flag = 0;
                *out = T::zero();
            }
        }
        if let Some(r) = self.slot(0).and_then(|i| self.ratio_at.get_mut(i)) {
            for (x, b) in r.iter_mut().zip(worst.iter()) {
                *x = x.fmax(*b);
            }
        }
        self.detail.ratio = best;
    }
}
