//! The scalar type of the planner: `f64` on the host and on double-precision FPUs (Cortex-M7),
//! `f32` on single-precision FPUs (Cortex-M4F).
//!
//! Every transcendental function goes through [`libm`] or this crate's own (sine and cosine,
//! `crate::trig`), on the host as on the target, so the host simulation and the firmware
//! compute the same numbers bit for bit (the standard library's `f64::exp` may round
//! differently from `libm::exp`). nalgebra is only used for
//! fixed-size storage; none of its maths (which switches to `std` when another crate in the
//! build enables that feature) is on the planner's path.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real scalar: the arithmetic and the few functions that the planner needs.
pub trait Real:
    Copy
    + Debug
    + Default
    + PartialEq
    + PartialOrd
    + nalgebra::Scalar
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + 'static
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Machine epsilon (the gap between 1 and the next representable number).
    const EPSILON: Self;
    /// The nearest value of this type to `v`.
    fn of(v: f64) -> Self;
    /// This value as an `f64` (exact for both implementations).
    fn f64(self) -> f64;
    /// `v` in this type (exact for both implementations).
    fn of_f32(v: f32) -> Self;
    /// e^self (libm).
    fn exp(self) -> Self;
    /// Square root (libm).
    fn sqrt(self) -> Self;
    /// Cube root (libm).
    fn cbrt(self) -> Self;
    /// Arc cosine (libm).
    fn acos(self) -> Self;
    /// Cosine ([`sin_cos`](Self::sin_cos)'s).
    fn cos(self) -> Self;
    /// Sine ([`sin_cos`](Self::sin_cos)'s).
    fn sin(self) -> Self;
    /// `(sin, cos)`, from `crate::trig`: for `f32` computed in single precision (libm's
    /// `sinf`/`cosf` work in `f64`, software on a Cortex-M4F); for `f64` within an ulp of
    /// libm's `sin`/`cos`, without their reduction of arguments of any size (4 KB of flash).
    fn sin_cos(self) -> (Self, Self);
    /// The bits of the value (`f32`'s widened to `u64`): equal exactly for equal values of
    /// equal sign.
    fn bits(self) -> u64;
    /// Four-quadrant arc tangent of `self / x` (libm).
    fn atan2(self, x: Self) -> Self;
    /// Nearest integer, halves away from zero (libm).
    fn round(self) -> Self;
    /// Toward zero as an `i32`, saturated at the `i32` range, `NaN` to 0 (Rust's `as`: one
    /// hardware conversion when the FPU has this precision).
    fn trunc_i32(self) -> i32;
    /// The nearest value of this type to `v` (exact for `f64`; the hardware conversion).
    fn of_i32(v: i32) -> Self;
    /// Natural logarithm (libm).
    fn ln(self) -> Self;
    /// Absolute value.
    fn abs(self) -> Self;
    /// Neither infinite nor NaN.
    fn is_finite(self) -> bool;
    /// `true` when `self` is NaN or `self <= other`.
    #[inline]
    fn is_nan_or_le(self, other: Self) -> bool {
        !matches!(self.partial_cmp(&other), Some(core::cmp::Ordering::Greater))
    }
    /// The larger of two values (NaN-free inputs assumed).
    #[inline]
    fn max(self, other: Self) -> Self {
        if other > self {
            other
        } else {
            self
        }
    }
    /// The smaller of two values (NaN-free inputs assumed).
    #[inline]
    fn min(self, other: Self) -> Self {
        if other < self {
            other
        } else {
            self
        }
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const EPSILON: Self = f64::EPSILON;
    #[inline]
    fn of(v: f64) -> Self {
        v
    }
    #[inline]
    fn f64(self) -> f64 {
        self
    }
    #[inline]
    fn of_f32(v: f32) -> Self {
        f64::from(v)
    }
    #[inline]
    fn exp(self) -> Self {
        libm::exp(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    #[inline]
    fn cbrt(self) -> Self {
        libm::cbrt(self)
    }
    #[inline]
    fn acos(self) -> Self {
        libm::acos(self)
    }
    #[inline]
    fn cos(self) -> Self {
        crate::trig::sin_cos_f64(self).1
    }
    #[inline]
    fn sin(self) -> Self {
        crate::trig::sin_cos_f64(self).0
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        crate::trig::sin_cos_f64(self)
    }
    #[inline]
    fn bits(self) -> u64 {
        self.to_bits()
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
    #[inline]
    fn round(self) -> Self {
        libm::round(self)
    }
    #[inline]
    fn trunc_i32(self) -> i32 {
        self as i32
    }
    #[inline]
    fn of_i32(v: i32) -> Self {
        f64::from(v)
    }
    #[inline]
    fn ln(self) -> Self {
        libm::log(self)
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const EPSILON: Self = f32::EPSILON;
    #[inline]
    fn of(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn of_f32(v: f32) -> Self {
        v
    }
    #[inline]
    fn exp(self) -> Self {
        libm::expf(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        libm::sqrtf(self)
    }
    #[inline]
    fn cbrt(self) -> Self {
        libm::cbrtf(self)
    }
    #[inline]
    fn acos(self) -> Self {
        libm::acosf(self)
    }
    #[inline]
    fn cos(self) -> Self {
        crate::trig::sin_cos_f32(self).1
    }
    #[inline]
    fn sin(self) -> Self {
        crate::trig::sin_cos_f32(self).0
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        crate::trig::sin_cos_f32(self)
    }
    #[inline]
    fn bits(self) -> u64 {
        u64::from(self.to_bits())
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        libm::atan2f(self, x)
    }
    #[inline]
    fn round(self) -> Self {
        libm::roundf(self)
    }
    #[inline]
    fn trunc_i32(self) -> i32 {
        self as i32
    }
    #[inline]
    fn of_i32(v: i32) -> Self {
        v as f32
    }
    #[inline]
    fn ln(self) -> Self {
        libm::logf(self)
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_and_f64_agree_on_the_functions_used() {
        for &v in &[0.0_f64, 0.3, 1.0, 2.5, 4.0] {
            assert!(
                (<f32 as Real>::exp(v as f32).f64() - Real::exp(v)).abs() < 1e-6 * Real::exp(v)
            );
            assert!((<f32 as Real>::sqrt(v as f32).f64() - Real::sqrt(v)).abs() < 1e-6);
        }
        assert_eq!(Real::max(1.0_f64, 2.0), 2.0);
        assert_eq!(Real::min(1.0_f64, 2.0), 1.0);
        assert!(!Real::is_finite(f64::NAN));
    }
}
