// Dense fixed-size kernel: every index below is a loop variable bounded by
// the matrix's own const dimension, so no index can be out of range.
#![allow(clippy::indexing_slicing)]

use crate::math::{cholesky, cholesky_solve_right, Real};
use crate::model::{ImuVec, Mat6};

/// Outcome of signature-based isolation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlrResult<T> {
    /// Fault sign per IMU channel (0 = not isolated).
    pub signs: [i8; 6],
    /// Least-squares fault sizes of the isolated channels (0 elsewhere).
    pub estimate: ImuVec<T>,
    /// GLR statistic of the first (strongest) channel.
    pub first_statistic: T,
}

impl<T: Real> Default for GlrResult<T> {
    fn default() -> Self {
        Self {
            signs: [0; 6],
            estimate: ImuVec::zeros(),
            first_statistic: T::zero(),
        }
    }
}

/// Greedy generalised-likelihood-ratio isolation (SPEC §5).
///
/// With `r̄` the window-mean innovation and `w` the inverse variances of its
/// components (0 for channels not monitored), the best single fault channel
/// maximises `λ_j = (m_jᵀ W r̃)² / (m_jᵀ W m_j)` where `r̃` is the residual
/// left by the channels already chosen. Channels are added while
/// `λ ≥ threshold` and `λ ≥ relative × λ_first` (a further channel must
/// explain a meaningful share of what the first did, not the few-percent
/// mismatch a linearised `M` leaves under a large fault), up to `max_faults`;
/// the sizes of all chosen channels
/// are re-estimated jointly by weighted least squares each round — so three
/// simultaneous faults (S2) are isolated as three channels.
pub fn glr_isolate<T: Real>(
    m: &Mat6<T>,
    rbar: &ImuVec<T>,
    w: &ImuVec<T>,
    threshold: T,
    relative: T,
    max_faults: usize,
) -> GlrResult<T> {
    let mut chosen = [false; 6];
    let mut out = GlrResult::<T>::default();
    let mut residual = *rbar;
    for round in 0..max_faults.min(6) {
        let mut best = None;
        for (j, taken) in chosen.iter().enumerate() {
            if *taken {
                continue;
            }
            let col = m.column(j);
            let mut a = T::zero();
            let mut b = T::zero();
            for i in 0..6 {
                a += col[i] * w[i] * residual[i];
                b += col[i] * w[i] * col[i];
            }
            if b > T::zero() {
                let lambda = a * a / b;
                if best.is_none_or(|(_, l)| lambda > l) {
                    best = Some((j, lambda));
                }
            }
        }
        let Some((j, lambda)) = best else { break };
        if round == 0 {
            out.first_statistic = lambda;
        }
        if lambda < threshold || (round > 0 && lambda < relative * out.first_statistic) {
            break;
        }
        if let Some(c) = chosen.get_mut(j) {
            *c = true;
        }
        // Joint weighted least squares over the chosen columns; unchosen
        // columns are decoupled with a unit diagonal so the size stays fixed.
        let mut normal = Mat6::<T>::zeros();
        let mut rhs = nalgebra::SMatrix::<T, 1, 6>::zeros();
        for a in 0..6 {
            for b in 0..6 {
                let both = chosen.get(a).copied().unwrap_or(false)
                    && chosen.get(b).copied().unwrap_or(false);
                if both {
                    let mut s = T::zero();
                    for i in 0..6 {
                        s += m[(i, a)] * w[i] * m[(i, b)];
                    }
                    normal[(a, b)] = s;
                } else if a == b {
                    normal[(a, b)] = T::one();
                }
            }
            if chosen.get(a).copied().unwrap_or(false) {
                let mut s = T::zero();
                for i in 0..6 {
                    s += m[(i, a)] * w[i] * rbar[i];
                }
                rhs[a] = s;
            }
        }
        let Ok(l) = cholesky(&normal) else { break };
        let f = cholesky_solve_right(&l, &rhs).transpose();
        out.estimate = f;
        residual = rbar - m * f;
    }
    for ((s, c), f) in out
        .signs
        .iter_mut()
        .zip(chosen.iter())
        .zip(out.estimate.iter())
    {
        if *c {
            *s = if *f > T::zero() { 1 } else { -1 };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isolates_three_simultaneous_faults() {
        // Block upper-triangular signature like M1's.
        #[rustfmt::skip]
        let m = Mat6::<f64>::new(
            -0.7, 0.0, 0.0, 0.0, 0.3, -0.1,
            0.0, -0.7, 0.0, -0.2, 0.0, 0.5,
            0.0, 0.0, -0.7, 0.1, -1.2, 0.0,
            0.0, 0.0, 0.0, -0.3, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, -0.3, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, -0.3,
        );
        let f = ImuVec::new(0.2, -0.1, 0.15, 0.0, 0.0, 0.0);
        let r = m * f;
        let w = ImuVec::repeat(1.0 / (0.003f64 * 0.003));
        let g = glr_isolate(&m, &r, &w, 25.0, 0.0, 6);
        assert_eq!(g.signs, [1, -1, 1, 0, 0, 0]);
        assert!((g.estimate - f).amax() < 1e-12);
        let g = glr_isolate(&m, &ImuVec::zeros(), &w, 25.0, 0.0, 6);
        assert_eq!(g.signs, [0; 6]);
    }
}
