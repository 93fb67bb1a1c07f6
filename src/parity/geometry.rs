//! Sensing directions of a redundant array of single-axis sensors.

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::math::Real;

use super::ConfigError;

/// The measurement matrix `H` (N×3) of N single-axis sensors of one kind:
/// sensor `i` measures `h_iᵀ x` of the body-frame vector `x` (rate or
/// specific force). Rows are unit vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry<T: Real, const N: usize> {
    h: SMatrix<T, N, 3>,
}

impl<T: Real, const N: usize> Geometry<T, N> {
    /// A user geometry from one direction per sensor. Directions are
    /// normalised; a zero or non-finite direction is a configuration error
    /// naming the sensor. Rank is checked when the parity space is built
    /// ([`ParitySpace::new`](super::ParitySpace::new)).
    pub fn new(directions: &[[T; 3]; N]) -> Result<Self, ConfigError> {
        let mut h = SMatrix::<T, N, 3>::zeros();
        for (i, d) in directions.iter().enumerate() {
            let v = Vector3::new(d[0], d[1], d[2]);
            let norm = v.norm();
            if !norm.finite() || norm <= T::lit(1e-6) {
                return Err(ConfigError::BadDirection(i));
            }
            h.set_row(i, &(v / norm).transpose());
        }
        Ok(Self { h })
    }

    /// `K` co-located orthogonal triads (N = 3K), each mounted with its own
    /// rotation: `rotations[k]` maps IMU `k`'s axes into the body frame, so
    /// its sensor `j` (x, y, z) points along column `j` of that matrix.
    /// Sensor index = 3k + j. Errors when `N ≠ 3·rotations.len()`.
    pub fn triads(rotations: &[Matrix3<T>]) -> Result<Self, ConfigError> {
        if rotations.len().saturating_mul(3) != N {
            return Err(ConfigError::TriadCount);
        }
        let mut dirs = [[T::zero(); 3]; N];
        for (i, d) in dirs.iter_mut().enumerate() {
            let Some(r) = rotations.get(i / 3) else {
                return Err(ConfigError::TriadCount);
            };
            let c: Vector3<T> = r.column(i % 3).into_owned();
            *d = [c.x, c.y, c.z];
        }
        Self::new(&dirs)
    }

    /// The matrix `H`.
    pub fn h(&self) -> &SMatrix<T, N, 3> {
        &self.h
    }

    /// Direction of sensor `i` (`None` out of range).
    pub fn direction(&self, i: usize) -> Option<Vector3<T>> {
        (i < N).then(|| self.h.row(i).transpose())
    }
}

impl<T: Real> Geometry<T, 6> {
    /// The six-sensor cone of \[PAR\]: every axis tilted `arccos(1/√3)`
    /// (54.74°) from body z and spaced 60° in azimuth,
    /// `h_i = [sinα cos(iπ/3), sinα sin(iπ/3), cosα]`. No two sensors are
    /// parallel, so any single faulty sensor can be isolated.
    pub fn cone6() -> Self {
        let cos_a = 1.0 / libm::sqrt(3.0);
        let sin_a = libm::sqrt(1.0 - cos_a * cos_a);
        let h = SMatrix::<T, 6, 3>::from_fn(|i, j| {
            let az = i as f64 * core::f64::consts::PI / 3.0;
            T::lit(match j {
                0 => sin_a * libm::cos(az),
                1 => sin_a * libm::sin(az),
                _ => cos_a,
            })
        });
        Self { h }
    }
}

/// Rotation by `angle` (rad) about body z: a board mounted yawed.
pub fn yaw_rotation<T: Real>(angle: T) -> Matrix3<T> {
    let (s, c) = angle.sin_cos_fast();
    let (o, z) = (T::one(), T::zero());
    Matrix3::new(c, -s, z, s, c, z, z, z, o)
}

/// Rotation `R_z(ψ) R_y(θ) R_x(φ)` (rad): a board mounted at arbitrary
/// Euler angles (ZYX, the aerospace convention).
pub fn euler_rotation<T: Real>(roll: T, pitch: T, yaw: T) -> Matrix3<T> {
    let (sp, cp) = roll.sin_cos_fast();
    let (st, ct) = pitch.sin_cos_fast();
    let (o, z) = (T::one(), T::zero());
    let rx = Matrix3::new(o, z, z, z, cp, -sp, z, sp, cp);
    let ry = Matrix3::new(ct, z, st, z, o, z, -st, z, ct);
    yaw_rotation(yaw) * ry * rx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone6_axes_are_54_74_degrees_from_z_and_60_apart() {
        let g = Geometry::<f64, 6>::cone6();
        for i in 0..6 {
            let d = g.direction(i).unwrap();
            assert!((d.norm() - 1.0).abs() < 1e-15);
            assert!((d.z.acos().to_degrees() - 54.7356).abs() < 1e-3);
        }
        let (a, b) = (g.direction(0).unwrap(), g.direction(1).unwrap());
        let az = |v: Vector3<f64>| v.y.atan2(v.x).to_degrees();
        assert!((az(b) - az(a) - 60.0).abs() < 1e-9);
    }

    #[test]
    fn triads_take_their_columns_from_the_rotation() {
        let r = yaw_rotation(core::f64::consts::FRAC_PI_2);
        let g = Geometry::<f64, 6>::triads(&[Matrix3::identity(), r]).unwrap();
        // IMU 1's x axis points along body y.
        assert!((g.direction(3).unwrap() - Vector3::y()).norm() < 1e-15);
        assert_eq!(
            Geometry::<f64, 9>::triads(&[r, r]),
            Err(ConfigError::TriadCount)
        );
        let mut dirs = [[1.0, 0.0, 0.0]; 4];
        dirs[2] = [0.0, 0.0, 0.0];
        assert_eq!(
            Geometry::<f64, 4>::new(&dirs),
            Err(ConfigError::BadDirection(2))
        );
    }
}
