//! Sine and cosine of an `f32` computed in `f32`, for single-precision FPUs (Cortex-M4F).
//!
//! `libm`'s `sinf`/`cosf` evaluate their polynomials in `f64`; on an FPU without double
//! precision every one of those operations is a software routine, about 1,000 instructions per
//! call, and the node's reach check takes up to ten per footstep frame. Here everything is
//! single precision:
//!
//! ```text
//! k = nearest integer to x · 2/π,     r = (x − k·H) − k·L ∈ [−π/4, π/4]   (H + L = π/2)
//! sin r = r (1 − r²/3! + r⁴/5! − r⁶/7! + r⁸/9!)
//! cos r = 1 − r²/2! + r⁴/4! − r⁶/6! + r⁸/8! − r¹⁰/10!
//! sin x, cos x from (sin r, cos r) by the quadrant k mod 4
//! ```
//!
//! `H = 1.5703125` has 8 significant bits, so `k·H` and `x − k·H` are exact for `|k| < 2¹⁶`;
//! `L = π/2 − H` rounded to `f32`. The Taylor remainders on `|r| ≤ π/4` are below
//! `(π/4)¹¹/11! ≈ 2e-9` and `(π/4)¹²/12! ≈ 1e-10`, far below the `f32` rounding of the result
//! (`2⁻²⁴ ≈ 6e-8`): the error is a few units in the last place, measured in the tests against
//! `libm`'s double-precision functions. Beyond `|x| = 256` (no heading is that large; the
//! reduction would lose bits) the `libm` functions are used.

/// `π/2` in two parts: `H` exactly representable with 8 significant bits, `L = π/2 − H`.
const PIO2_H: f32 = 1.570_312_5;
const PIO2_L: f32 = (core::f64::consts::FRAC_PI_2 - 1.570_312_5) as f32;
/// Beyond this magnitude the `libm` functions are used.
const LIMIT: f32 = 256.0;

/// `(sin r, cos r)` for `|r| ≤ π/4` (a little more is fine).
#[inline]
fn kernel(r: f32) -> (f32, f32) {
    let r2 = r * r;
    // 1/3!, 1/5!, … as f32 constants.
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5_040.0 + r2 * (1.0 / 362_880.0)))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0 + r2 * (-1.0 / 3_628_800.0)))));
    (s, c)
}

/// `(sin x, cos x)` in single precision.
#[inline]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    // `!(≤)`: NaN and infinities go to libm too.
    if x.abs() > LIMIT || x.is_nan() {
        return (libm::sinf(x), libm::cosf(x));
    }
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    // Truncation towards zero of x·2/π ± 0.5: the nearest integer (|k| ≤ 163).
    let k = (x * core::f32::consts::FRAC_2_PI + half) as i32;
    let kf = k as f32;
    let r = (x - kf * PIO2_H) - kf * PIO2_L;
    let (s, c) = kernel(r);
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against `libm`'s `f64` functions on every 997th `f32` bit pattern of `[−256, 256]`
    /// and on a fine grid of `[−π, π]`: within 4 units of `f32` rounding (`2⁻²⁴`) of the
    /// result's size (at least that of 1 for values near zero, where the error is absolute).
    #[test]
    fn single_precision_sine_and_cosine_are_accurate() {
        let mut worst = 0.0_f64;
        let mut check = |x: f32| {
            let (s, c) = sin_cos_f32(x);
            let xd = f64::from(x);
            for (got, want) in [(s, libm::sin(xd)), (c, libm::cos(xd))] {
                let err = (f64::from(got) - want).abs() / want.abs().max(0.5);
                worst = worst.max(err);
            }
        };
        let mut bits = 0u32;
        while bits < 0x4380_0000 {
            // 0x4380_0000 = 256.0
            let x = f32::from_bits(bits);
            check(x);
            check(-x);
            bits += 997;
        }
        for i in -200_000..=200_000 {
            check(i as f32 * (core::f32::consts::PI / 200_000.0));
        }
        println!(
            "sin_cos_f32: worst relative error {worst:.2e} (f32 rounding {:.2e})",
            f64::from(f32::EPSILON) / 2.0
        );
        assert!(
            worst <= 4.0 * f64::from(f32::EPSILON) / 2.0,
            "worst {worst:e}"
        );
        // Signs of zero, and what goes to libm.
        assert_eq!(sin_cos_f32(-0.0).0.to_bits(), (-0.0_f32).to_bits());
        assert_eq!(sin_cos_f32(0.0), (0.0, 1.0));
        assert!(sin_cos_f32(f32::NAN).0.is_nan() && sin_cos_f32(f32::INFINITY).1.is_nan());
        assert_eq!(sin_cos_f32(1e6), (libm::sinf(1e6), libm::cosf(1e6)));
    }
}
