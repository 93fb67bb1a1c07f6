//! The identity test of `nalgebra::Matrix::is_identity(0)` without its
//! generic code (2.2 KB of flash on the Cortex-M4F for a 6×6 `f32`).

use nalgebra::SMatrix;

use super::Real;

/// True when `m` is the identity as `m.is_identity(T::zero())` judges it
/// (approx's `relative_eq!` with zero absolute tolerance and the default
/// relative one, `T::default_max_relative()`): the diagonal within that
/// relative tolerance of one, every other element exactly zero. NaN and
/// infinity are never equal.
pub fn is_identity<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>) -> bool {
    let rel = T::default_max_relative();
    let one = T::one();
    // Column by column (the storage is column-major): no index arithmetic.
    m.as_slice().chunks_exact(R).enumerate().all(|(j, col)| {
        col.iter().enumerate().all(|(i, &v)| {
            if i == j {
                v == one || (v.finite() && (v - one).abs() <= v.abs().fmax(one) * rel)
            } else {
                v == T::zero()
            }
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_nalgebra() {
        let id = SMatrix::<f32, 6, 6>::identity();
        let mut cases = [id; 7];
        cases[1][(2, 2)] = 1.0 + f32::EPSILON;
        cases[2][(2, 2)] = 1.0 + 4.0 * f32::EPSILON;
        cases[3][(1, 4)] = 1e-30;
        cases[4][(0, 0)] = f32::NAN;
        cases[5][(5, 5)] = f32::INFINITY;
        cases[6][(3, 3)] = 0.0;
        for (i, c) in cases.iter().enumerate() {
            assert_eq!(is_identity(c), c.is_identity(0.0), "case {i}");
        }
        let rect = SMatrix::<f64, 3, 6>::identity();
        assert!(is_identity(&rect) && rect.is_identity(0.0));
        assert!(is_identity(&id) && !is_identity(&(id * 2.0)));
    }
}
