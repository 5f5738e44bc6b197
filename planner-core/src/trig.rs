//! Sine and cosine: of an `f32` computed in `f32`, for single-precision FPUs (Cortex-M4F), and
//! of an `f64` without `libm`'s reduction of large arguments (flash on the Cortex-M7).
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
//!
//! `f64` ([`sin_cos_f64`]): `libm`'s `sin` and `cos` each reduce their argument with a routine
//! built for any magnitude (about 4 KB of code, `rem_pio2`), where the node's angles are
//! headings within `[−π, π]`. Here the reduction is the same as above with `π/2` in three
//! parts (`H`, `M` of 33 significant bits each, so `k·H` and `k·M` are exact for `|k| < 2²⁰`,
//! and `L` the rest: about 119 bits of `π/2`), what its two roundings lose carried as a
//! correction `d`, and Taylor polynomials to `r¹⁷/17!` and `r¹⁶/16!` (remainders below
//! `8e-20` and `2e-18` on `|r| ≤ π/4`, far below `2⁻⁵³`); `1 − r²/2` is evaluated with its
//! rounding error recovered. Within one unit in the last place of `libm`'s results (measured
//! in the tests; most are equal), and one reduction for both. Beyond `|x| = 2¹⁹` (and for NaN
//! and infinities) the argument is first taken modulo the `f64` value of `2π`
//! (`libm::remainder`, exact), which is not the exact `2π`: there the result is only as good as
//! that (`|x|·1.2e-16`), and no heading is that large.

/// `π/2` in two parts: `H` exactly representable with 8 significant bits, `L = π/2 − H`.
const PIO2_H: f32 = 1.570_312_5;
const PIO2_L: f32 = (core::f64::consts::FRAC_PI_2 - 1.570_312_5) as f32;
/// Beyond this magnitude the `libm` functions are used.
const LIMIT: f32 = 256.0;

/// `π/2` in three parts for the `f64` reduction: `H64`, `M64` the leading 33 significant bits
/// of `π/2` and of `π/2 − H64`, `L64 = π/2 − H64 − M64` rounded (the rest is below 1e-37).
const PIO2_H64: f64 = 1.570_796_326_734_125_6; // 0x1.921fb544p0
const PIO2_M64: f64 = 6.077_100_506_303_966e-11; // 0x1.0b4611a6p-34
const PIO2_L64: f64 = 2.022_266_248_795_950_6e-21; // 0x1.3198a2e037073p-69
/// Beyond this magnitude the `f64` argument is first reduced modulo `2π` by `libm::remainder`.
const LIMIT64: f64 = 524_288.0; // 2^19
/// Below this magnitude `sin x = x` and `cos x = 1` in `f64` (`x²/6 < 2⁻⁵⁶`).
const TINY64: f64 = 7.450_580_596_923_828e-9; // 2^-27

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

/// `(sin(r + d), cos(r + d))` for `|r| ≤ π/4` (a little more is fine) and a correction `d`
/// below the last place of `r`: `sin(r + d) ≈ sin r + d·cos r`, `cos(r + d) ≈ cos r − d·r`.
#[inline]
fn kernel64(r: f64, d: f64) -> (f64, f64) {
    let z = r * r;
    // sin r − r = r·ps, cos r − 1 + r²/2 = z²·pc: the Taylor coefficients, 1/n! in `f64`.
    let ps = z
        * (-1.0 / 6.0
            + z * (1.0 / 120.0
                + z * (-1.0 / 5_040.0
                    + z * (1.0 / 362_880.0
                        + z * (-1.0 / 39_916_800.0
                            + z * (1.0 / 6_227_020_800.0
                                + z * (-1.0 / 1_307_674_368_000.0
                                    + z * (1.0 / 355_687_428_096_000.0))))))));
    let pc = 1.0 / 24.0
        + z * (-1.0 / 720.0
            + z * (1.0 / 40_320.0
                + z * (-1.0 / 3_628_800.0
                    + z * (1.0 / 479_001_600.0
                        + z * (-1.0 / 87_178_291_200.0 + z * (1.0 / 20_922_789_888_000.0))))));
    // 1 − z/2 rounds to w; (1 − w) − z/2 is exactly what that lost (|z/2| ≤ 0.31).
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + (z * z * pc - r * d));
    let s = r + (r * ps + d * c);
    (s, c)
}

/// `(sin x, cos x)` in double precision (see the module documentation: within one unit in the
/// last place of `libm`'s for `|x| ≤ 2¹⁹`).
#[inline]
pub fn sin_cos_f64(x: f64) -> (f64, f64) {
    // Also keeps the sign of a zero.
    if x.abs() < TINY64 {
        return (x, 1.0);
    }
    // `!(≤)`: NaN and infinities are reduced too (to NaN).
    let x = if x.abs() <= LIMIT64 {
        x
    } else {
        libm::remainder(x, core::f64::consts::TAU)
    };
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    // Truncation towards zero of x·2/π ± 0.5: the nearest integer (|k| ≤ 333,790).
    let k = (x * core::f64::consts::FRAC_2_PI + half) as i32;
    let kf = f64::from(k);
    // x − k·H is exact (the two are within a factor 2, or k = 0); so is k·M.
    let a = x - kf * PIO2_H64;
    let km = kf * PIO2_M64;
    let b = a - km;
    let kl = kf * PIO2_L64;
    let r = b - kl;
    // What the two subtractions rounded away (each exact when the first term is the larger).
    let d = ((a - b) - km) + ((b - r) - kl);
    let (s, c) = kernel64(r, d);
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
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

    /// The `f64` constants: `H` and `M` have 33 significant bits, and `H + M + L` is `π/2`
    /// (as far as `f64` shows it).
    #[test]
    fn the_f64_reduction_constants_are_pi_over_2() {
        // 2^e built from its bits (exact; `powi` is not guaranteed exact, and Miri perturbs it).
        let pow2 = |e: i32| f64::from_bits(((1023 + e) as u64) << 52);
        assert_eq!(pow2(-1), 0.5);
        assert_eq!(pow2(3), 8.0);
        assert_eq!(PIO2_H64.to_bits() & 0xF_FFFF, 0);
        assert_eq!(PIO2_M64.to_bits() & 0xF_FFFF, 0);
        assert_eq!(
            PIO2_H64 + (PIO2_M64 + PIO2_L64),
            core::f64::consts::FRAC_PI_2
        );
        assert!(PIO2_M64 < pow2(-33) && PIO2_L64 < PIO2_M64 * pow2(-33));
        assert_eq!(TINY64, pow2(-27));
        assert_eq!(LIMIT64, pow2(19));
    }

    /// Units in the last place of `want` between `got` and `want` (the gap above `|want|`).
    fn ulps(got: f64, want: f64) -> f64 {
        if got == want {
            return 0.0;
        }
        let a = want.abs();
        let gap = f64::from_bits(a.to_bits() + 1) - a;
        (got - want).abs() / gap
    }

    /// Against `libm`'s `sin` and `cos`: on a grid of 4,000,001 points of `[−π, π]`, on
    /// 4,000,000 random magnitudes below `2¹⁹` (both signs), and on the 50 `f64` values either
    /// side of `k·π/2` for `1 ≤ |k| ≤ 2000` (the cancellation of the reduction): at most one unit in
    /// the last place apart, most of them equal. Zeros keep their sign; NaN and infinities
    /// give NaN; beyond `2¹⁹` the argument is taken modulo `f64`'s `2π`.
    #[test]
    fn double_precision_sine_and_cosine_are_libms_within_an_ulp() {
        let (mut n, mut differ, mut worst) = (0_u64, 0_u64, 0.0_f64);
        let mut check = |x: f64| {
            let (s, c) = sin_cos_f64(x);
            let (us, uc) = (ulps(s, libm::sin(x)), ulps(c, libm::cos(x)));
            n += 1;
            if us > 0.0 || uc > 0.0 {
                differ += 1;
            }
            worst = worst.max(us).max(uc);
        };
        let m = 2_000_000;
        for i in -m..=m {
            check(f64::from(i) * (core::f64::consts::PI / f64::from(m)));
        }
        let mut u = crate::test_uniform(0x05EE_DF64);
        for _ in 0..4_000_000 {
            let x = u() * LIMIT64;
            check(x);
            check(-x);
        }
        for k in 1..=2000 {
            let base = f64::from(k) * core::f64::consts::FRAC_PI_2;
            let (mut up, mut down) = (base, base);
            for _ in 0..50 {
                for x in [up, down] {
                    check(x);
                    check(-x);
                }
                up = f64::from_bits(up.to_bits() + 1);
                down = f64::from_bits(down.to_bits() - 1);
            }
        }
        println!(
            "sin_cos_f64: {n} arguments, {differ} differ from libm ({:.2} %), by at most {worst} ulp",
            100.0 * differ as f64 / n as f64
        );
        assert!(worst <= 1.0, "worst {worst} ulp");
        assert!(differ * 20 < n, "{differ} of {n} differ");
        let (s, c) = sin_cos_f64(-0.0);
        assert_eq!((s.to_bits(), c), ((-0.0_f64).to_bits(), 1.0));
        assert_eq!(sin_cos_f64(0.0), (0.0, 1.0));
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (s, c) = sin_cos_f64(x);
            assert!(s.is_nan() && c.is_nan(), "{x}");
        }
        let y = libm::remainder(1e10, core::f64::consts::TAU);
        assert_eq!(sin_cos_f64(1e10), sin_cos_f64(y));
    }
}
