use crate::math::{keep_rolled, rolled, rolled_mut};

/// Debounce of a ternary decision per channel: the output changes only after
/// the same new value was proposed `length` times in a row — the paper's rule
/// "mean over l samples, |mean| < 1 → 0", which for values in {−1, 0, 1} is
/// exactly l-fold agreement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Persistence<const C: usize> {
    length: u16,
    output: [i8; C],
    candidate: [i8; C],
    count: [u16; C],
}

impl<const C: usize> Persistence<C> {
    /// A debouncer needing `length` (≥ 1) consecutive agreements.
    pub fn new(length: u16) -> Self {
        Self {
            length: length.max(1),
            output: [0; C],
            candidate: [0; C],
            count: [0; C],
        }
    }
    /// Feeds one proposed decision vector; returns the debounced output.
    pub fn update(&mut self, proposed: &[i8; C]) -> [i8; C] {
        // A rolled loop (`math::rolled`): unrolled over the six channels
        // it was 0.5 KB of the firmware, for ≈ 30 instructions an aiding
        // epoch (issue 17).
        let length = self.length;
        for (((out, cand), cnt), p) in rolled_mut(&mut self.output)
            .iter_mut()
            .zip(rolled_mut(&mut self.candidate).iter_mut())
            .zip(rolled_mut(&mut self.count).iter_mut())
            .zip(rolled(proposed))
        {
            keep_rolled();
            if *p == *out {
                *cnt = 0;
                *cand = *out;
                continue;
            }
            if *p == *cand {
                *cnt = cnt.saturating_add(1);
            } else {
                *cand = *p;
                *cnt = 1;
            }
            if *cnt >= length {
                *out = *p;
                *cnt = 0;
            }
        }
        self.output
    }
    /// The current debounced output.
    pub fn output(&self) -> [i8; C] {
        self.output
    }
    /// Forgets everything (re-alignment, explicit reset of latched faults).
    pub fn reset(&mut self) {
        *self = Self::new(self.length);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn needs_l_agreements_both_ways() {
        let mut p = Persistence::<2>::new(3);
        assert_eq!(p.update(&[1, 0]), [0, 0]);
        assert_eq!(p.update(&[1, 0]), [0, 0]);
        assert_eq!(p.update(&[1, -1]), [1, 0]);
        assert_eq!(p.update(&[0, -1]), [1, 0]);
        assert_eq!(p.update(&[1, 0]), [1, 0]);
        assert_eq!(p.update(&[0, 0]), [1, 0]);
        assert_eq!(p.update(&[0, 0]), [1, 0]);
        assert_eq!(p.update(&[0, 0]), [0, 0]);
    }
}
