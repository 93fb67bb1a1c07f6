//! The multi-scale tests' two storage slots: the live tests and the
//! re-admission shadow (`readmit.rs`), with a flag saying which is live.
//!
//! Re-admission makes the shadow the live tests and drops the reduced
//! set's: flipping the flag does that without moving either. Swapped in
//! place, the two ≈ 20 KB states (nine sensors, `W` = 40) cost the
//! re-admitting step 27,495 instructions on the M4F, over issue 17's
//! 20,000. The slot left behind holds the reduced set's tests, as the
//! swap left them in the shadow's storage: unused until the next
//! isolation copies the learning over it.

use crate::math::Real;

use super::super::multiscale::Multiscale;

/// The live multi-scale tests and the re-admission shadow's storage.
///
/// Slot `a` is an `Option` (`None`: no multi-scale tests — the white-noise
/// detector, or no parity space left), slot `b` is always there; they are
/// built as the fields of the monitor (a `TestSlots` value built first and
/// moved in was two more ≈ 20 KB temporaries on `ParityMonitor::new`'s
/// frame, past the M4F's 128 KB of RAM in the on-target tests).
#[derive(Debug, Clone)]
pub(super) struct TestSlots<T: Real, const N: usize, const W: usize> {
    pub(super) a: Option<Multiscale<T, N, W>>,
    pub(super) b: Multiscale<T, N, W>,
    /// `b` holds the live tests (`a` the shadow).
    pub(super) b_live: bool,
}

impl<T: Real, const N: usize, const W: usize> TestSlots<T, N, W> {
    /// There are multi-scale tests.
    #[inline]
    pub(super) fn is_some(&self) -> bool {
        self.a.is_some()
    }

    /// No more multi-scale tests (no parity space left).
    pub(super) fn clear(&mut self) {
        self.a = None;
    }

    /// The live tests.
    #[inline]
    pub(super) fn live(&self) -> Option<&Multiscale<T, N, W>> {
        let a = self.a.as_ref()?;
        Some(if self.b_live { &self.b } else { a })
    }

    /// The live tests, mutably.
    #[inline]
    pub(super) fn live_mut(&mut self) -> Option<&mut Multiscale<T, N, W>> {
        self.split_mut().map(|(live, _)| live)
    }

    /// The shadow.
    #[inline]
    pub(super) fn shadow(&self) -> Option<&Multiscale<T, N, W>> {
        let a = self.a.as_ref()?;
        Some(if self.b_live { a } else { &self.b })
    }

    /// The shadow, mutably.
    #[inline]
    pub(super) fn shadow_mut(&mut self) -> Option<&mut Multiscale<T, N, W>> {
        self.split_mut().map(|(_, shadow)| shadow)
    }

    /// The live tests and the shadow, both mutably.
    #[inline]
    #[allow(clippy::type_complexity)]
    pub(super) fn split_mut(
        &mut self,
    ) -> Option<(&mut Multiscale<T, N, W>, &mut Multiscale<T, N, W>)> {
        let a = self.a.as_mut()?;
        Some(if self.b_live {
            (&mut self.b, a)
        } else {
            (a, &mut self.b)
        })
    }

    /// The shadow becomes the live tests (re-admission) and the live ones
    /// the shadow's storage.
    pub(super) fn flip(&mut self) {
        self.b_live = !self.b_live;
    }
}
