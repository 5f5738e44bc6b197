//! Timing-related analysis of a planned interval: the worst ZMP fluctuation (eq. 17).
//!
//! # Eq. 17
//! In the first interval of a window the ZMP is the quartic `p(τ) = Σ a_i τ^i`. When its velocity
//! is zero at both ends (`a_1 = 0` and `ṗ(D) = 0`, the via-point convention of the planner),
//! `ṗ(τ) = τ (2a_2 + 3a_3 τ + 4a_4 τ²)` and `ṗ(D) = 0` gives `4a_4 D² = −(2a_2 + 3a_3 D)`. The
//! quadratic factor then has the roots `D` and
//!
//! ```text
//! τ_max = −2 a_2 D / (2 a_2 + 3 a_3 D)                                         (eq. 17)
//! ```
//!
//! (the paper writes `T_max = T_0 + τ_max`), the one interior extremum of the ZMP: the largest
//! fluctuation. [`eq17_tau`] is that formula; [`worst_deviation`] is the general version for any
//! polynomial of order ≤ 4 and any reference (end velocities not zero), which finds every
//! critical point in `[0, D]` by bracketing: the roots of `p''` split the interval into pieces on
//! which `ṗ` is monotone, so each piece holds at most one root of `ṗ`, found by Newton's method
//! safeguarded by the bracket (a step that would leave it takes the bracket's chord instead; at
//! most 56 steps, about two on average, started at the chord between the bracket's ends). A
//! bracket end where `ṗ` vanishes to rounding (the planner's zero end velocities) is the root
//! without a search. The value at the extremum is insensitive to the root's error to first
//! order.

use crate::lipm::{poly_eval, Poly, Segment};
use crate::real::Real;

/// Most root-finding steps per bracket (bisection alone would reach the resolution of `f64`
/// on `[0, 1]` in 56; the safeguarded Newton iteration takes about two).
const MAX_STEPS: usize = 56;

/// The time and value of the largest ZMP deviation in an interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extremum<T> {
    /// Local time of the extremum in the interval \[s\].
    pub tau: T,
    /// ZMP at that time \[m\].
    pub zmp: T,
    /// `zmp − reference` \[m\] (signed).
    pub deviation: T,
}

/// Eq. 17: local time of the interior ZMP extremum of a quartic with zero velocity at both ends,
/// or `None` when the formula has no extremum strictly inside `(0, D)` (zero denominator, or the
/// ZMP is monotone).
pub fn eq17_tau<T: Real>(a2: T, a3: T, duration: T) -> Option<T> {
    let den = T::of(2.0) * a2 + T::of(3.0) * a3 * duration;
    if den == T::ZERO {
        return None;
    }
    let tau = -T::of(2.0) * a2 * duration / den;
    if tau.is_finite() && tau > T::ZERO && tau < duration {
        Some(tau)
    } else {
        None
    }
}

/// The largest `|p(τ) − reference|` over `τ ∈ [0, D]` for the ZMP polynomial `zmp`.
pub fn worst_deviation<T: Real>(zmp: &Poly<T>, duration: T, reference: T) -> Extremum<T> {
    search(zmp, duration, reference).0
}

/// [`worst_deviation`] and the number of root-finding steps it took (each one evaluation of
/// `p`, `ṗ` and `p̈`).
fn search<T: Real>(zmp: &Poly<T>, duration: T, reference: T) -> (Extremum<T>, u32) {
    let mut steps = 0u32;
    let eval = |tau: T| poly_eval(zmp, tau);
    let mut best = Extremum {
        tau: T::ZERO,
        zmp: zmp[0],
        deviation: zmp[0] - reference,
    };
    // `p` is `p(tau)`, evaluated already where `ṗ` and `p̈` were (the same value: no second
    // evaluation).
    let mut consider = |tau: T, p: T| {
        let dev = p - reference;
        if dev.abs() > best.deviation.abs() {
            best = Extremum {
                tau,
                zmp: p,
                deviation: dev,
            };
        }
    };
    let at_end = eval(duration);
    consider(duration, at_end.0);
    // A bound of |p| on [0, D] for the stopping test below (|Σ a_i τ^i| ≤ Σ |a_i| D^i).
    let mut scale = T::ZERO;
    let mut dpow = T::ONE;
    for &c in zmp.iter() {
        scale += c.abs() * dpow;
        dpow *= duration;
    }
    // Split [0, D] at the roots of p'' = 2a2 + 6a3 τ + 12a4 τ².
    let mut cuts = [T::ZERO, duration, duration, duration];
    let mut n = 1;
    let (c0, c1, c2) = (
        T::of(2.0) * zmp[2],
        T::of(6.0) * zmp[3],
        T::of(12.0) * zmp[4],
    );
    let mut push = |r: T| {
        if r.is_finite() && r > T::ZERO && r < duration {
            cuts[n] = r;
            n += 1;
        }
    };
    if c2 != T::ZERO {
        let disc = c1 * c1 - T::of(4.0) * c2 * c0;
        if disc >= T::ZERO {
            // Numerically stable pair of roots.
            let sq = disc.sqrt();
            let qd = if c1 >= T::ZERO {
                -T::of(0.5) * (c1 + sq)
            } else {
                -T::of(0.5) * (c1 - sq)
            };
            if qd != T::ZERO {
                push(qd / c2);
                push(c0 / qd);
            }
        }
    } else if c1 != T::ZERO {
        push(-c0 / c1);
    }
    cuts[n] = duration;
    // Sort the (at most 2) interior cuts.
    if n == 3 && cuts[2] < cuts[1] {
        cuts.swap(1, 2);
    }
    // `ṗ(x) = v` is zero to rounding where `p(x)` is within about `ε·scale` of the value at
    // the root (near a simple root the extremum lies ≈ v²/(2|p̈|) from p(x)).
    let settled = |v: T, a: T| v == T::ZERO || v * v <= T::EPSILON * a.abs() * scale;
    // The end of a piece is the start of the next: evaluated once.
    let mut at_lo = eval(cuts[0]);
    for piece in 0..n {
        let (mut lo, mut hi) = (cuts[piece], cuts[piece + 1]);
        let at_hi = if piece + 1 == n { at_end } else { eval(hi) };
        let (plo, mut vlo, alo) = at_lo;
        let (phi, mut vhi, ahi) = at_hi;
        at_lo = at_hi;
        // An end where ṗ vanishes to rounding (the planner's zero end velocities) is the
        // piece's critical point (ṗ is monotone on the piece): no search. Considering an end
        // is always safe (it is a point of [0, D]).
        if settled(vlo, alo) {
            consider(lo, plo);
            continue;
        }
        if settled(vhi, ahi) {
            consider(hi, phi);
            continue;
        }
        if (vlo < T::ZERO) == (vhi < T::ZERO) {
            continue;
        }
        let lo_negative = vlo < T::ZERO;
        // The chord between the bracket's ends crosses zero inside it (ṗ is monotone there;
        // the midpoint if rounding says otherwise), and its inverse slope, by the mean value
        // theorem `1/p̈` somewhere on the bracket.
        let chord = |lo: T, vlo: T, hi: T, vhi: T| {
            let inv = (hi - lo) / (vhi - vlo);
            let c = lo - vlo * inv;
            if c > lo && c < hi {
                (c, inv)
            } else {
                (T::of(0.5) * (lo + hi), inv)
            }
        };
        // Newton's method on ṗ inside the bracket, which every step shrinks, without a divide:
        // `1/p̈` is tracked by one Newton–Raphson step of the reciprocal per step
        // (`r ← r (2 − p̈ r)`, which squares its relative error; `0 < p̈ r < 2` is where it
        // converges), seeded with the chord's inverse slope. A step that would leave the
        // bracket, or a reciprocal out of its range, takes the chord of the bracket instead
        // (regula falsi, which seeds the reciprocal again: a root close to an end, where Newton
        // overshoots, is reached in a step or two; bisection took up to ~25), or, every second
        // time, bisects. ṗ is monotone on the piece, so the root is unique and the iteration
        // converges superlinearly once close (typically 2–5 steps); the count is bounded by
        // `MAX_STEPS` whatever the polynomial.
        let (mut x, mut r) = chord(lo, vlo, hi, vhi);
        let mut fallbacks = 0u32;
        // `p(x)` once `x` is evaluated.
        let mut px = None;
        for _ in 0..MAX_STEPS {
            steps += 1;
            let (p, v, a) = eval(x);
            if settled(v, a) {
                px = Some(p);
                break;
            }
            if (v < T::ZERO) == lo_negative {
                (lo, vlo) = (x, v);
            } else {
                (hi, vhi) = (x, v);
            }
            let ar = a * r;
            let near = ar > T::ZERO && ar < T::of(2.0);
            r *= T::of(2.0) - ar;
            r *= T::of(2.0) - a * r;
            let newton = x - v * r;
            let next = if near && newton >= lo && newton <= hi {
                newton
            } else {
                // Fallbacks alternate chord and bisection (regula falsi alone can creep from
                // one end; every second fallback halves the bracket, whatever Newton does in
                // between).
                fallbacks += 1;
                if fallbacks % 2 == 1 {
                    let (c, inv) = chord(lo, vlo, hi, vhi);
                    r = inv;
                    c
                } else {
                    T::of(0.5) * (lo + hi)
                }
            };
            let done = (next - x).abs() <= T::EPSILON * T::of(4.0) * duration;
            x = next;
            if done {
                break;
            }
        }
        let p = match px {
            Some(p) => p,
            None => eval(x).0,
        };
        consider(x, p);
    }
    (best, steps)
}

/// [`worst_deviation`] of a planned segment's ZMP from `reference` (typically the via point at
/// the end of the interval: the centre of the support foot in single support).
pub fn worst_zmp_deviation<T: Real>(seg: &Segment<T>, reference: T) -> Extremum<T> {
    // The segment stores its ZMP in normalised time s = τ/D: search on [0, 1], then rescale.
    let mut e = worst_deviation(&seg.zmp, T::ONE, reference);
    e.tau *= seg.duration;
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the largest deviation on a fine grid.
    fn grid_max(zmp: &Poly<f64>, d: f64, r: f64) -> (f64, f64) {
        let mut best = (0.0, 0.0);
        for i in 0..=200_000 {
            let t = d * i as f64 / 200_000.0;
            let dev = poly_eval(zmp, t).0 - r;
            if dev.abs() > best.1.abs() {
                best = (t, dev);
            }
        }
        best
    }

    #[test]
    fn eq17_matches_brute_force_for_zero_end_velocities() {
        let d = 0.7;
        // a0 = 0, a1 = 0; choose a2, a3 and a4 from ṗ(D) = 0.
        for &(a2, a3) in &[(0.3, -0.2), (-0.5, 0.4), (0.1, 0.5), (2.0, -3.0)] {
            let a4 = -(2.0 * a2 + 3.0 * a3 * d) / (4.0 * d * d);
            let zmp = [0.0, 0.0, a2, a3, a4];
            let (_, v_end, _) = poly_eval(&zmp, d);
            assert!(v_end.abs() < 1e-12);
            let p_end = poly_eval(&zmp, d).0;
            let (t_grid, dev_grid) = grid_max(&zmp, d, p_end);
            let e = worst_deviation(&zmp, d, p_end);
            assert!((e.deviation - dev_grid).abs() < 1e-9, "{e:?} vs {dev_grid}");
            if let Some(t17) = eq17_tau(a2, a3, d) {
                let dev17 = poly_eval(&zmp, t17).0 - p_end;
                // When the extremum is interior, eq. 17 finds it.
                if t_grid > 1e-6 && t_grid < d - 1e-6 {
                    assert!((t17 - t_grid).abs() < 1e-4, "{t17} vs {t_grid}");
                    assert!((dev17 - dev_grid).abs() < 1e-9);
                }
            }
        }
    }

    #[test]
    fn general_quartics_match_brute_force() {
        let cases: [Poly<f64>; 4] = [
            [0.1, 0.3, -1.0, 0.4, 0.9],
            [0.0, -0.2, 0.0, 0.0, 0.0],
            [0.05, 0.0, 0.0, 1.0, -1.5],
            [0.0, 0.0, 0.0, 0.0, 0.0],
        ];
        for zmp in &cases {
            for &r in &[0.0, 0.05, -0.1] {
                let e = worst_deviation(zmp, 0.8, r);
                let (_, g) = grid_max(zmp, 0.8, r);
                assert!((e.deviation.abs() - g.abs()).abs() < 1e-9, "{zmp:?} r={r}");
            }
        }
    }

    /// Random quartics (deterministic generator), against a 20,001-point grid: the bracketed
    /// Newton search finds the largest deviation to within what the grid resolves
    /// (`½ max|p''| (Δ/2)²` ≤ 2e-8 here), and never less than the grid's.
    #[test]
    fn random_quartics_match_brute_force() {
        let mut uniform = crate::test_uniform(0x9e37_79b9_7f4a_7c15_u64);
        let mut next = || uniform() - 0.5;
        for _ in 0..200 {
            let zmp = [
                next() * 0.2,
                next(),
                next() * 4.0,
                next() * 8.0,
                next() * 8.0,
            ];
            let r = next() * 0.2;
            let e = worst_deviation(&zmp, 1.0, r);
            let mut g = 0.0_f64;
            for i in 0..=20_000 {
                let dev = poly_eval(&zmp, i as f64 / 20_000.0).0 - r;
                if dev.abs() > g.abs() {
                    g = dev;
                }
            }
            assert!(e.deviation.abs() >= g.abs() - 1e-12, "{zmp:?}: {e:?} < {g}");
            assert!(e.deviation.abs() - g.abs() < 2e-8, "{zmp:?}: {e:?} vs {g}");
            let (p, _, _) = poly_eval(&zmp, e.tau);
            assert!((p - r - e.deviation).abs() < 1e-15);
        }
    }

    /// The root-finding cost is small and does not depend on the last bits of the
    /// polynomial. A quartic from a fig4 fault run whose `ṗ` vanishes at the end to within
    /// 4e-20 (a root an ulp from the bracket's end, where Newton overshoots: it took 21
    /// bisection steps there, 24 in all, before the end test) needs no search there; random quartics, and random
    /// quartics with zero end velocities (the planner's via points), need about two steps
    /// each.
    #[test]
    fn the_search_takes_few_steps() {
        let zmp = [
            0.299982839148372,
            5.8765227902614475e-5,
            0.0014009850089965756,
            -0.002909622295188969,
            0.0014670329099177853,
        ];
        let (e, steps) = search(&zmp, 1.0, 0.3);
        let (_, g) = grid_max(&zmp, 1.0, 0.3);
        assert!((e.deviation.abs() - g.abs()).abs() < 1e-12, "{e:?} vs {g}");
        // Its other bracket, [0.20, 0.79], holds an interior root (3 steps).
        assert!(steps <= 4, "a root at the end: {steps} steps");
        let mut uniform = crate::test_uniform(0x2545_f491_4f6c_dd1d_u64);
        let mut next = || uniform() - 0.5;
        let (mut worst, mut total, mut calls) = (0u32, 0u32, 0u32);
        for i in 0..2000 {
            let d = 0.3 + next().abs();
            let mut zmp = [
                next() * 0.2,
                next(),
                next() * 4.0,
                next() * 8.0,
                next() * 8.0,
            ];
            if i % 2 == 0 {
                // ṗ(0) = ṗ(D) = 0, as the planner's via points: a1 = 0, a4 from ṗ(D) = 0.
                zmp[1] = 0.0;
                zmp[4] = -(2.0 * zmp[2] + 3.0 * zmp[3] * d) / (4.0 * d * d);
            }
            let r = next() * 0.2;
            let (e, steps) = search(&zmp, d, r);
            // Never below a 2,001-point grid's largest deviation.
            let g = (0..=2000)
                .map(|i| poly_eval(&zmp, d * f64::from(i) / 2000.0).0 - r)
                .fold(0.0_f64, |m, v| m.max(v.abs()));
            assert!(e.deviation.abs() >= g - 1e-12, "{zmp:?}: {e:?} < {g}");
            worst = worst.max(steps);
            total += steps;
            calls += 1;
        }
        println!("search: {calls} quartics, {total} steps, at most {worst}");
        // Two brackets whose Newton starts beside an inflection cut (p̈ ≈ 0 there) take ~16.
        assert!(worst <= 20, "{worst} steps");
        assert!(total <= 3 * calls, "{total} steps for {calls} quartics");
    }
}
