//! Inverse of a small square matrix by Gauss–Jordan elimination with
//! partial pivoting (Golub & Van Loan, *Matrix Computations*, 4th ed.,
//! §3.4): a few loops in the image instead of nalgebra's generic LU inverse,
//! which the firmware linked as 6.4 KB of unrolled code (issue 17) for the
//! 6×6 decision matrices inverted at start-up and on a flagged epoch.

use nalgebra::SMatrix;

use super::Real;

/// `m⁻¹`, or `None` when a pivot is zero or not finite (singular, or NaN in
/// the input). Partial pivoting bounds the growth of the multipliers by 1,
/// as in the LU inverse it replaces.
pub fn try_inverse<T: Real, const N: usize>(m: &SMatrix<T, N, N>) -> Option<SMatrix<T, N, N>> {
    let mut a = *m;
    let mut inv = SMatrix::<T, N, N>::identity();
    gauss_jordan(a.as_mut_slice(), inv.as_mut_slice(), N).then_some(inv)
}

/// The elimination on column-major `n × n` slices, `a` reduced to the
/// identity while `inv` takes the same row operations. Out of line and with
/// `n` a run-time value, so one rolled copy serves every size (unrolled
/// for N = 6 it was 1.6 KB of flash; it runs at start-up and on epochs
/// with flagged channels, not on every step).
#[inline(never)]
fn gauss_jordan<T: Real>(a: &mut [T], inv: &mut [T], n: usize) -> bool {
    let at = |s: &[T], i: usize, j: usize| s.get(j * n + i).copied();
    for k in 0..n {
        let mut pivot_row = k;
        let mut best = T::zero();
        for i in k..n {
            let Some(v) = at(a, i, k) else { return false };
            if v.abs() > best {
                best = v.abs();
                pivot_row = i;
            }
        }
        if !(best > T::zero() && best.finite()) {
            return false;
        }
        for s in [&mut *a, &mut *inv] {
            if pivot_row != k {
                for j in 0..n {
                    s.swap(j * n + k, j * n + pivot_row);
                }
            }
        }
        let Some(akk) = at(a, k, k) else { return false };
        let d = T::one() / akk;
        // Columns left of k are eliminated in `a` and column k is read no
        // more there: the row operations on `a` start right of it.
        for (s, from) in [(&mut *a, k + 1), (&mut *inv, 0)] {
            for j in from..n {
                if let Some(v) = s.get_mut(j * n + k) {
                    *v *= d;
                }
            }
        }
        for i in (0..n).filter(|i| *i != k) {
            let Some(f) = at(a, i, k) else { return false };
            if f == T::zero() {
                continue;
            }
            for (s, from) in [(&mut *a, k + 1), (&mut *inv, 0)] {
                for j in from..n {
                    let Some(skj) = at(s, k, j) else { return false };
                    if let Some(v) = s.get_mut(j * n + i) {
                        *v -= f * skj;
                    }
                }
            }
        }
    }
    inv.iter().all(|v| v.finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix6;

    #[test]
    fn matches_nalgebra_and_refuses_singular() {
        let m = Matrix6::<f64>::from_fn(|i, j| {
            ((i * 7 + j * 3) % 11) as f64 - 5.0 + if i == j { 0.5 } else { 0.0 }
        });
        let want = m.try_inverse().unwrap();
        let got = try_inverse(&m).unwrap();
        assert!(
            (got - want).amax() < 1e-12 * want.amax(),
            "{:e}",
            (got - want).amax()
        );
        assert!((m * got - Matrix6::identity()).amax() < 1e-12);
        // A zero leading entry needs the row swap.
        let p = Matrix6::<f64>::identity().remove_row(0).insert_row(5, 0.0);
        let mut p = p;
        p[(5, 0)] = 1.0;
        assert_eq!(try_inverse(&p).unwrap(), p.transpose());
        let mut s = m;
        let r0 = s.row(0).into_owned();
        s.set_row(3, &(r0 * 2.0));
        assert!(try_inverse(&s).is_none());
        let mut n = m;
        n[(2, 2)] = f64::NAN;
        assert!(try_inverse(&n).is_none());
    }
}
