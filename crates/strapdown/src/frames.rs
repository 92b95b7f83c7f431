//! Frame-typed vectors and the body-to-navigation attitude.
//!
//! A [`NavVector`] (NED) and a [`BodyVector`] (forward-right-down) are distinct types, so a body-frame
//! specific force cannot be added to a navigation-frame velocity by mistake: the only way from one frame
//! to the other is through an [`Attitude`] (`attitude.to_nav(&body)`, `attitude.to_body(&nav)`).

use nalgebra::{Matrix3, Rotation3, Vector3};
use std::ops::{Add, Sub};

/// A vector resolved in the navigation frame (north, east, down). Units are those of the quantity.
///
/// Frames cannot be mixed:
/// ```compile_fail
/// use strapdown::{BodyVector, NavVector};
/// let sum = NavVector::new(1.0, 0.0, 0.0) + BodyVector::new(0.0, 1.0, 0.0);
/// ```
/// while the same-frame sum and the conversion through an attitude do compile:
/// ```
/// use strapdown::{Attitude, BodyVector, NavVector};
/// let body = BodyVector::new(0.0, 1.0, 0.0);
/// let sum = NavVector::new(1.0, 0.0, 0.0) + Attitude::identity().to_nav(&body);
/// assert_eq!(sum, NavVector::new(1.0, 1.0, 0.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct NavVector(pub Vector3<f64>);

/// A vector resolved in the body frame (forward, right, down). Units are those of the quantity.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct BodyVector(pub Vector3<f64>);

macro_rules! frame_vector_ops {
    ($t:ident) => {
        impl $t {
            /// The zero vector.
            pub fn zeros() -> Self {
                Self(Vector3::zeros())
            }
            /// A vector from its three components in this frame.
            pub fn new(x: f64, y: f64, z: f64) -> Self {
                Self(Vector3::new(x, y, z))
            }
        }
        impl Add for $t {
            type Output = $t;
            fn add(self, rhs: $t) -> $t {
                $t(self.0 + rhs.0)
            }
        }
        impl Sub for $t {
            type Output = $t;
            fn sub(self, rhs: $t) -> $t {
                $t(self.0 - rhs.0)
            }
        }
    };
}
frame_vector_ops!(NavVector);
frame_vector_ops!(BodyVector);

/// Body-to-navigation direction cosine matrix `C` (Woodman's `C`: its columns are the body axes written
/// in navigation coordinates, `v_nav = C v_body`, Woodman eq 21).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attitude(pub(crate) Matrix3<f64>);

impl Default for Attitude {
    fn default() -> Self {
        Attitude::identity()
    }
}

impl Attitude {
    /// Level, heading north: body axes coincide with north, east, down.
    pub fn identity() -> Attitude {
        Attitude(Matrix3::identity())
    }

    /// From aerospace (z-y-x) Euler angles: `C = Rz(yaw) Ry(pitch) Rx(roll)`, the convention of
    /// nalgebra's `Rotation3::from_euler_angles(roll, pitch, yaw)` (whose docs define the order).
    pub fn from_euler_rad(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> Attitude {
        Attitude(*Rotation3::from_euler_angles(roll_rad, pitch_rad, yaw_rad).matrix())
    }

    /// The z-y-x Euler angles `(roll, pitch, yaw)` in radians (nalgebra `Rotation3::euler_angles`).
    pub fn euler_rad(&self) -> (f64, f64, f64) {
        Rotation3::from_matrix_unchecked(self.0).euler_angles()
    }

    /// From a direction cosine matrix; `None` unless it is orthonormal with determinant +1 within `1e-9`.
    pub fn from_matrix(dcm: Matrix3<f64>) -> Option<Attitude> {
        // Orthonormality tolerance: far above rounding (1e-16 per element), far below any physical angle.
        const ORTHONORMAL_TOL: f64 = 1e-9;
        let gram_err = (dcm.transpose() * dcm - Matrix3::identity()).abs().max();
        (gram_err < ORTHONORMAL_TOL && (dcm.determinant() - 1.0).abs() < ORTHONORMAL_TOL)
            .then_some(Attitude(dcm))
    }

    /// The rotation `exp([rotvec x])` (Rodrigues form, Woodman eq 41) as an attitude.
    pub fn from_rotation_vector(rotvec_rad: &Vector3<f64>) -> Attitude {
        Attitude(so3_exp(rotvec_rad))
    }

    /// The direction cosine matrix, body to navigation.
    pub fn matrix(&self) -> &Matrix3<f64> {
        &self.0
    }

    /// `v_nav = C v_body` (Woodman eq 21).
    #[inline]
    pub fn to_nav(&self, v: &BodyVector) -> NavVector {
        NavVector(self.0 * v.0)
    }

    /// `v_body = C^T v_nav` (Woodman eq 22).
    #[inline]
    pub fn to_body(&self, v: &NavVector) -> BodyVector {
        BodyVector(self.0.tr_mul(&v.0))
    }

    /// `self` followed by a body-frame rotation: `C A` (Woodman eq 24).
    pub fn then_body_rotation(&self, body_rotation: &Matrix3<f64>) -> Attitude {
        Attitude(self.0 * body_rotation)
    }
}

/// `(sin s / s, (1 - cos s) / s^2)` as functions of `s^2`: the coefficients of Woodman eq 41.
/// Below `s = 0.1` the Taylor series (docs/model.md §1.1 note) is used; truncated after the `s^8` term its
/// remainder is below `0.1^10 / 10! < 3e-17`, i.e. it is exact to rounding, and needs no sqrt/sin/cos.
#[inline]
pub(crate) fn rodrigues_coefficients(s2: f64) -> (f64, f64) {
    if s2 < 1e-2 {
        rodrigues_series(s2)
    } else {
        // Half-angle forms avoid the cancellation in 1 - cos s: sin s = 2 sin(s/2) cos(s/2),
        // 1 - cos s = 2 sin^2(s/2).
        let s = s2.sqrt();
        let (sh, ch) = (0.5 * s).sin_cos();
        (2.0 * sh * ch / s, 2.0 * sh * sh / s2)
    }
}

/// [`rodrigues_coefficients`] for `s^2 < 1e-2`: the series in Horner form with constant
/// coefficients (multiplications only: a chain of divisions would dominate the cost of a
/// mechanisation step). sin s/s = sum (-s^2)^n/(2n+1)!, (1 - cos s)/s^2 = sum (-s^2)^n/(2n+2)!.
#[inline(always)]
pub(crate) fn rodrigues_series(s2: f64) -> (f64, f64) {
    const A: [f64; 5] = [1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362_880.0];
    const B: [f64; 5] = [
        0.5,
        -1.0 / 24.0,
        1.0 / 720.0,
        -1.0 / 40_320.0,
        1.0 / 3_628_800.0,
    ];
    let a = A[0] + s2 * (A[1] + s2 * (A[2] + s2 * (A[3] + s2 * A[4])));
    let b = B[0] + s2 * (B[1] + s2 * (B[2] + s2 * (B[3] + s2 * B[4])));
    (a, b)
}

/// `exp([phi x]) = I + (sin s/s) B + ((1 - cos s)/s^2) B^2` with `B = [phi x]`, `s = |phi|` (Woodman eq 41).
/// `B^2 = phi phi^T - s^2 I` (Woodman's `B^3 = -s^2 B` identity, eqs 38-40), written out to avoid a
/// matrix product.
#[inline]
pub(crate) fn so3_exp(phi: &Vector3<f64>) -> Matrix3<f64> {
    let s2 = phi.norm_squared();
    let (a, b) = rodrigues_coefficients(s2);
    Matrix3::from_row_slice(&rodrigues_entries(a, b, s2, phi.x, phi.y, phi.z))
}

/// The entries of `I + a B + b B^2` row by row, `B = [phi x]`, `phi = (x, y, z)`, `s2 = |phi|^2`,
/// with `B^2 = phi phi^T - s2 I` written out (see [`so3_exp`]); shared with the lanes' step.
#[inline(always)]
pub(crate) fn rodrigues_entries(a: f64, b: f64, s2: f64, x: f64, y: f64, z: f64) -> [f64; 9] {
    let d = 1.0 - b * s2;
    [
        d + b * x * x,
        b * x * y - a * z,
        b * x * z + a * y,
        b * y * x + a * z,
        d + b * y * y,
        b * y * z - a * x,
        b * z * x - a * y,
        b * z * y + a * x,
        d + b * z * z,
    ]
}

/// Rotation vector of a rotation matrix near or far from identity, accurate for tiny angles.
/// From Woodman eq 41: the antisymmetric part of `exp(B)` is `(sin s/s) B` and its trace `1 + 2 cos s`,
/// so `s = atan2(|vee(antisym)|, (trace - 1)/2)` without the precision loss of `acos` near 1.
pub(crate) fn so3_log(r: &Matrix3<f64>) -> Vector3<f64> {
    let v = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let sin_s = v.norm();
    let cos_s = 0.5 * (r.trace() - 1.0);
    let s = sin_s.atan2(cos_s);
    if sin_s < 1e-300 {
        if cos_s > 0.0 {
            return Vector3::zeros();
        }
        // Half-turn: the antisymmetric part vanishes; nalgebra recovers the axis from the symmetric part.
        return Rotation3::from_matrix_unchecked(*r).scaled_axis();
    }
    if s > 3.0 {
        // Near a half-turn sin s loses relative precision; the symmetric-part route is then better.
        return Rotation3::from_matrix_unchecked(*r).scaled_axis();
    }
    v * (s / sin_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_log_round_trip_small_and_large() {
        // Rounding only: a few ulps of the angle.
        const ROUND_TRIP_TOL_RAD: f64 = 1e-14;
        for phi in [
            Vector3::new(1e-9, -2e-9, 3e-10),
            Vector3::new(0.01, 0.02, -0.05),
            Vector3::new(0.3, -1.2, 0.7),
            Vector3::new(-2.0, 1.0, 1.5),
        ] {
            let r = so3_exp(&phi);
            let back = so3_log(&r);
            assert!(
                (back - phi).norm() < ROUND_TRIP_TOL_RAD * (1.0 + phi.norm()),
                "{phi:?} -> {back:?}"
            );
            let reference = *Rotation3::from_scaled_axis(phi).matrix();
            assert!(
                (r - reference).abs().max() < 1e-15,
                "exp differs from nalgebra for {phi:?}"
            );
        }
    }

    #[test]
    fn series_and_trig_branches_agree_at_switch() {
        // Just below the switch (series) against sin/cos at the same argument: a few ulps apart.
        let s2 = 1e-2 * (1.0 - 1e-12);
        let (a_series, b_series) = rodrigues_coefficients(s2);
        let s = s2.sqrt();
        assert!((a_series - s.sin() / s).abs() < 1e-15);
        assert!((b_series - 2.0 * (0.5 * s).sin().powi(2) / s2).abs() < 1e-15);
    }

    #[test]
    fn euler_round_trip_and_frame_transforms() {
        let att = Attitude::from_euler_rad(0.1, -0.2, 2.5);
        let (r, p, y) = att.euler_rad();
        assert!((r - 0.1).abs() < 1e-14 && (p + 0.2).abs() < 1e-14 && (y - 2.5).abs() < 1e-14);
        let b = BodyVector::new(1.0, 2.0, 3.0);
        let back = att.to_body(&att.to_nav(&b));
        assert!((back.0 - b.0).norm() < 1e-14);
        assert!(Attitude::from_matrix(*att.matrix()).is_some());
        assert!(Attitude::from_matrix(Matrix3::identity() * 1.01).is_none());
    }
}
