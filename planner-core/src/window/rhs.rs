//! The right-hand sides of both planes, the solve, and the segments of the solution.
//!
//! The right-hand side `w` of a plane holds, besides the boundary values, the start and end
//! values of the particular COG solution of every interval's known ZMP polynomial (a cubic:
//! Hermite between via points, or the start of a quartic). A particular solution is linear in
//! the ZMP, so those ends are `Σ_k c_k` times the ends of the monomials `s^k`, which depend on
//! `λ_j = ωD_j` alone: [`Intervals`] tabulates them once per timing (with `1/λ²` and `1/ω`),
//! and a plane's ends cost a few multiply-adds per interval instead of the particular
//! solution's series. The two planes share the timing, so they are solved together: the
//! factors of the particular solutions' recurrences are computed once for both
//! ([`particular_pair`]), and the particular solutions are only computed for the
//! segments that are written.

use super::{hcol, Basis, PlanError, PlaneBoundary, Solver, Timing, LAST_BETA, M, N};
use crate::lipm::{
    hermite, particular_over, Particular, Poly, Segment, State, INV_PAIR, N_COEFFS, PARTICULAR_LEN,
    SHORT_LAMBDA,
};
use crate::real::Real;

/// Orders of the ZMP monomials of a known part of an interval's ZMP (at most a cubic).
pub(super) const CUBIC: usize = 4;

/// `lipm::monomial_ends` of `s^0 … s^4` at once, `[x(0), ẋ(0)/ω, x(D), ẋ(D)/ω]` per order: for
/// `λ < 1` bit for bit the same values (each order's chain of the series summed over its
/// non-zero terms only); for `λ ≥ 1` the paper's
/// polynomials with `1/λ` and `1/λ²` computed once (equal to `lipm::monomial_ends` to rounding).
/// The ends of the particular solution of a polynomial `c` are then `Σ_k c_k` of these: the
/// same solution, as a particular solution is linear in the ZMP.
pub(super) fn monomials_ends<T: Real>(lambda: T) -> [[T; 4]; N_COEFFS] {
    let mut out = [[T::ZERO; 4]; N_COEFFS];
    if lambda < T::of(SHORT_LAMBDA) {
        let l2 = lambda * lambda;
        for (k, o) in out.iter_mut().enumerate() {
            // g_{k+2} = −m_{k+2}, then g_i = m_i g_{i−2} (c = e_k is zero above k), with
            // m_i = λ²/(i(i−1)): one chain per order, its non-zero terms only.
            let mut i = k + 2;
            let mut g = -(l2 * T::of(INV_PAIR[i]));
            let (mut x1, mut v1) = (T::ZERO, T::ZERO);
            x1 += g;
            v1 += T::of(i as f64) * g;
            i += 2;
            while i < PARTICULAR_LEN {
                g = l2 * T::of(INV_PAIR[i]) * g;
                x1 += g;
                v1 += T::of(i as f64) * g;
                i += 2;
            }
            *o = [T::ZERO, T::ZERO, x1, v1 / lambda];
        }
    } else {
        let inv = T::ONE / lambda;
        let inv2 = T::ONE / (lambda * lambda);
        let (k12, k6, k2) = (T::of(12.0) * inv2, T::of(6.0) * inv2, T::of(2.0) * inv2);
        for (k, o) in out.iter_mut().enumerate() {
            // The paper's m_k: g_k = 1, g_{k−2} = k(k−1)/λ² g_k, … (as `particular_into`).
            let mut g = [T::ZERO; N_COEFFS];
            g[k] = T::ONE;
            g[2] += k12 * g[4];
            g[1] += k6 * g[3];
            g[0] += k2 * g[2];
            let (mut x1, mut v1, mut i) = (T::ZERO, T::ZERO, T::ZERO);
            for &gi in &g {
                x1 += gi;
                v1 += i * gi;
                i += T::ONE;
            }
            *o = [g[0], g[1] * inv, x1, v1 * inv];
        }
    }
    out
}

/// `lipm::particular_over` for the two planes of one interval at once (the same `λ`; `inv_l2` is
/// `1/λ²`, used for `λ ≥ 1`): the factors of the recurrences are computed once for both, and
/// each plane's coefficients are bit for bit those of `lipm::particular_over` with its own old
/// `λ`.
#[inline]
pub(super) fn particular_pair<T: Real>(
    gx: &mut Particular<T>,
    gy: &mut Particular<T>,
    c: [&Poly<T>; 2],
    lambda: T,
    inv_l2: T,
    old: [T; 2],
) {
    if lambda < T::of(SHORT_LAMBDA) {
        let l2 = lambda * lambda;
        gx[0] = T::ZERO;
        gx[1] = T::ZERO;
        gy[0] = T::ZERO;
        gy[1] = T::ZERO;
        for i in 2..N_COEFFS + 2 {
            let m = l2 * T::of(INV_PAIR[i]);
            gx[i] = m * (gx[i - 2] - c[0][i - 2]);
            gy[i] = m * (gy[i - 2] - c[1][i - 2]);
        }
        // Beyond the quartic `c_i = 0`, and `g − 0 = g` exactly.
        for i in N_COEFFS + 2..PARTICULAR_LEN {
            let m = l2 * T::of(INV_PAIR[i]);
            gx[i] = m * gx[i - 2];
            gy[i] = m * gy[i - 2];
        }
    } else {
        let (k12, k6, k2) = (
            T::of(12.0) * inv_l2,
            T::of(6.0) * inv_l2,
            T::of(2.0) * inv_l2,
        );
        for (g, (c, old)) in [&mut *gx, &mut *gy].into_iter().zip(c.into_iter().zip(old)) {
            g[4] = c[4];
            g[3] = c[3];
            g[2] = c[2] + k12 * g[4];
            g[1] = c[1] + k6 * g[3];
            g[0] = c[0] + k2 * g[2];
            // A NaN `old` zeroes too.
            let tail_zero = old >= T::of(SHORT_LAMBDA);
            if !tail_zero {
                for gi in g.iter_mut().skip(N_COEFFS) {
                    *gi = T::ZERO;
                }
            }
        }
    }
}

/// What the right-hand sides need of the timing alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Intervals<T> {
    /// `λ_j = ωD_j`.
    pub(super) lambda: [T; M],
    /// `1/λ_j²`.
    pub(super) inv_l2: [T; M],
    /// `1/ω`.
    pub(super) inv_omega: T,
    /// The entry of [`Intervals::mono`] of every interval (the first interval of its duration).
    slot: [u8; M],
    /// The ends of the particular solutions of `s^0 … s^4` ([`monomials_ends`]), at the slot
    /// of the first interval of each distinct duration.
    mono: [[[T; 4]; N_COEFFS]; M],
}

impl<T: Real> Intervals<T> {
    /// All zero (no timing).
    pub(super) const ZERO: Self = Self {
        lambda: [T::ZERO; M],
        inv_l2: [T::ZERO; M],
        inv_omega: T::ZERO,
        slot: [0; M],
        mono: [[[T::ZERO; 4]; N_COEFFS]; M],
    };

    /// The table of a valid timing, in place; an interval with the duration of an earlier one
    /// shares its entries (a window alternates few durations: nothing is computed or copied
    /// twice).
    pub(super) fn set(&mut self, timing: &Timing<T>) {
        let w = timing.omega;
        let d = &timing.durations;
        self.inv_omega = T::ONE / w;
        for j in 0..M {
            match (0..j).find(|&i| d[i] == d[j]) {
                Some(i) => {
                    self.lambda[j] = self.lambda[i];
                    self.inv_l2[j] = self.inv_l2[i];
                    self.slot[j] = self.slot[i];
                }
                None => {
                    let l = w * d[j];
                    self.lambda[j] = l;
                    self.inv_l2[j] = T::ONE / (l * l);
                    self.slot[j] = j as u8;
                    self.mono[j] = monomials_ends(l);
                }
            }
        }
    }

    /// The monomials' ends of interval `j`, `[x(0), ẋ(0)/ω, x(D), ẋ(D)/ω]` of the particular
    /// solution of `s^k`, `k = 0 … 4`.
    #[inline(always)]
    pub(super) fn mono(&self, j: usize) -> &[[T; 4]; N_COEFFS] {
        // `slot[j] ≤ j < M` by construction; the `min` keeps the index in range without a
        // bounds check (no panic path).
        &self.mono[usize::from(self.slot[j]).min(M - 1)]
    }
}

/// `[x(0), ẋ(0)/ω, x(D), ẋ(D)/ω]` of the particular solution of the cubic `c` (`c_4` is
/// zero; `K = 2` when `c_2 = c_3 = 0` too) from the monomials' ends `m`, skipping the entries
/// that are zero or one by construction ([`monomials_ends`]).
#[inline(always)]
fn ends_of<T: Real, const K: usize>(c: &Poly<T>, m: &[[T; 4]; N_COEFFS], short: bool) -> [T; 4] {
    if short {
        // At rest at the start.
        let mut x1 = c[0] * m[0][2];
        let mut v1 = c[0] * m[0][3];
        for k in 1..K {
            x1 += c[k] * m[k][2];
            v1 += c[k] * m[k][3];
        }
        [T::ZERO, T::ZERO, x1, v1]
    } else if K == 2 {
        [c[0], c[1] * m[1][1], c[0] + c[1], c[1] * m[1][3]]
    } else {
        [
            c[0] + c[2] * m[2][0],
            c[1] * m[1][1] + c[3] * m[3][1],
            c[0] + c[1] + c[2] * m[2][2] + c[3] * m[3][2],
            c[1] * m[1][3] + c[2] * m[2][3] + c[3] * m[3][3],
        ]
    }
}

/// The known part of the normalised ZMP polynomial of interval `j` (the quartic unknowns set
/// to zero), relative to the plane's initial ZMP.
#[inline(always)]
fn known_zmp<T: Real>(timing: &Timing<T>, b: &PlaneBoundary<T>, j: usize) -> Poly<T> {
    let origin = b.zmp_start.pos;
    let rel = |s: State<T>| State::new(s.pos - origin, s.vel);
    let d = &timing.durations;
    if j == 0 {
        [T::ZERO, b.zmp_start.vel * d[0], T::ZERO, T::ZERO, T::ZERO]
    } else if j == M - 1 {
        let zl = rel(b.via[M - 2]);
        [zl.pos, zl.vel * d[M - 1], T::ZERO, T::ZERO, T::ZERO]
    } else {
        // `1 ≤ j ≤ M − 2` here; the clamp lets the compiler see it (no panic path).
        let i = j.clamp(1, M - 2);
        hermite(rel(b.via[i - 1]), rel(b.via[i]), d[i])
    }
}

/// The right-hand side `w` of one plane, relative to its initial ZMP, into `r`.
fn rhs<T: Real>(timing: &Timing<T>, iv: &Intervals<T>, b: &PlaneBoundary<T>, r: &mut [T; N]) {
    let origin = b.zmp_start.pos;
    let d = &timing.durations;
    let short = |j: usize| iv.lambda[j] < T::of(SHORT_LAMBDA);
    let first = known_zmp(timing, b, 0);
    let (c0, c1) = (first[0], first[1]);
    r[0] = b.via[0].pos - origin - c0 - c1;
    r[1] = b.via[0].vel * d[0] - c1;
    let mut prev = ends_of::<T, 2>(&first, iv.mono(0), short(0));
    r[2] = b.cog_start.pos - origin - prev[0];
    r[3] = b.cog_start.vel * iv.inv_omega - prev[1];
    for j in 1..M - 1 {
        let e = ends_of::<T, CUBIC>(&known_zmp(timing, b, j), iv.mono(j), short(j));
        r[2 + 2 * j] = e[0] - prev[2];
        r[3 + 2 * j] = e[1] - prev[3];
        prev = e;
    }
    let last = known_zmp(timing, b, M - 1);
    let e = ends_of::<T, 2>(&last, iv.mono(M - 1), short(M - 1));
    r[14] = e[0] - prev[2];
    r[15] = e[1] - prev[3];
    r[16] = b.cog_end.pos - origin - e[2];
    r[17] = b.cog_end.vel * iv.inv_omega - e[3];
    let (l0, l1) = (last[0], last[1]);
    r[18] = b.via[M - 1].pos - origin - l0 - l1;
    r[19] = b.via[M - 1].vel * d[M - 1] - l1;
}

/// Solves both planes into `y` (every entry written; boundary values assumed finite, the factorisation valid).
pub(super) fn solve_pair<T: Real, S: Solver<T>>(
    s: &S,
    b: [&PlaneBoundary<T>; 2],
    y: &mut [[T; N]; 2],
) -> Result<(), PlanError> {
    let timing = s.timing();
    let iv = s.intervals();
    for (b, y) in b.iter().zip(y.iter_mut()) {
        rhs(timing, iv, b, y);
        s.solve_in_place(y);
    }
    // The sum of all 40 is finite exactly when all are (a sum of finite values that overflows
    // needs values near `T::MAX`, absurd for a plan in metres: rejected too).
    let mut sum = T::ZERO;
    for y in y.iter() {
        for &v in y.iter() {
            sum += v;
        }
    }
    if !sum.is_finite() {
        return Err(PlanError::NonFinite);
    }
    Ok(())
}

/// Writes interval `j` of both planes of the solution `y` for the boundary values `b` into `sx` and `sy` (their old
/// `ω` and `D` tell whether the particular solutions' tails are zero already).
pub(super) fn write_segments<T: Real, S: Solver<T>>(
    s: &S,
    b: [&PlaneBoundary<T>; 2],
    y: &[[T; N]; 2],
    j: usize,
    sx: &mut Segment<T>,
    sy: &mut Segment<T>,
) {
    // `j < M` (the clamp lets the compiler see it: no panic path).
    let j = j.min(M - 1);
    let timing = s.timing();
    let iv = s.intervals();
    let w = timing.omega;
    let d = timing.durations[j];
    let old = [sx.omega * sx.duration, sy.omega * sy.duration];
    let mut zmp = [known_zmp(timing, b[0], j), known_zmp(timing, b[1], j)];
    // The quartic unknowns are the normalised coefficients c_2, c_3, c_4 of the first and
    // the last interval.
    let quartic = match j {
        0 => Some(0),
        j if j == M - 1 => Some(LAST_BETA),
        _ => None,
    };
    if let Some(col) = quartic {
        for (z, y) in zmp.iter_mut().zip(y.iter()) {
            z[2..].copy_from_slice(&y[col..col + 3]);
        }
    }
    particular_pair(
        &mut sx.particular,
        &mut sy.particular,
        [&zmp[0], &zmp[1]],
        iv.lambda[j],
        iv.inv_l2[j],
        old,
    );
    let e = match s.basis() {
        Basis::Exponential => T::ONE,
        // V = P + QE, W = −P + QE.
        Basis::Hyperbolic => (-w * d).exp(),
    };
    for (p, seg) in [&mut *sx, &mut *sy].into_iter().enumerate() {
        let (c0, c1) = (y[p][hcol(j)], y[p][hcol(j) + 1]);
        let (pp, qq) = match s.basis() {
            Basis::Exponential => (c0, c1),
            Basis::Hyperbolic => {
                let half = T::of(0.5);
                (half * (c0 - c1), half * (c0 + c1) / e)
            }
        };
        seg.omega = w;
        seg.duration = d;
        seg.p = pp;
        seg.q = qq;
        seg.zmp = zmp[p];
        let origin = b[p].zmp_start.pos;
        seg.zmp[0] += origin;
        seg.particular[0] += origin;
    }
}

/// [`write_segments`] for plane `p` alone (`0`: x, `1`: y), bit for bit the same segment, into
/// `seg` (whose old `ω` and `D` tell whether its particular solution's tail is zero already).
pub(super) fn write_segment<T: Real, S: Solver<T>>(
    s: &S,
    b: &PlaneBoundary<T>,
    y: &[T; N],
    j: usize,
    seg: &mut Segment<T>,
) {
    // `j < M` (the clamp lets the compiler see it: no panic path).
    let j = j.min(M - 1);
    let timing = s.timing();
    let iv = s.intervals();
    let w = timing.omega;
    let d = timing.durations[j];
    let old = seg.omega * seg.duration;
    let mut zmp = known_zmp(timing, b, j);
    let quartic = match j {
        0 => Some(0),
        j if j == M - 1 => Some(LAST_BETA),
        _ => None,
    };
    if let Some(col) = quartic {
        zmp[2..].copy_from_slice(&y[col..col + 3]);
    }
    particular_over(&mut seg.particular, &zmp, iv.lambda[j], old);
    let (c0, c1) = (y[hcol(j)], y[hcol(j) + 1]);
    let (pp, qq) = match s.basis() {
        Basis::Exponential => (c0, c1),
        Basis::Hyperbolic => {
            let half = T::of(0.5);
            (half * (c0 - c1), half * (c0 + c1) / (-w * d).exp())
        }
    };
    seg.omega = w;
    seg.duration = d;
    seg.p = pp;
    seg.q = qq;
    seg.zmp = zmp;
    let origin = b.zmp_start.pos;
    seg.zmp[0] += origin;
    seg.particular[0] += origin;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lipm::monomial_ends;

    #[test]
    fn the_table_of_monomials_ends_is_monomial_ends() {
        for &lambda in &[0.005, 0.02, 0.35, 0.99, 1.0, 2.4, 3.6, 40.0] {
            let got = monomials_ends(lambda);
            for (k, g) in got.iter().enumerate() {
                let w = monomial_ends(k, lambda);
                let want = [w.0, w.1, w.2, w.3];
                if lambda < SHORT_LAMBDA {
                    // Bit for bit (the same operations on the same values).
                    assert_eq!(
                        g.map(f64::to_bits),
                        want.map(f64::to_bits),
                        "k={k} λ={lambda}"
                    );
                } else {
                    for (a, b) in g.iter().zip(want.iter()) {
                        assert!(
                            (a - b).abs() <= 4.0 * f64::EPSILON * b.abs(),
                            "k={k} λ={lambda}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_pair_of_particulars_is_each_plane_s_own() {
        let cx = [0.05, 0.1, -0.3, 0.2, 0.1];
        let cy = [-0.02, 0.3, 0.1, -0.2, 0.0];
        for &lambda in &[0.02, 0.35, 0.99, 1.0, 2.4, 3.6] {
            for old in [[0.5, 2.0], [2.0, 0.5], [f64::NAN, 2.0]] {
                let (mut gx, mut gy) = ([7.0; PARTICULAR_LEN], [7.0; PARTICULAR_LEN]);
                let (mut wx, mut wy) = (gx, gy);
                if old[1] >= SHORT_LAMBDA {
                    // A tail zero already, as `particular_over` assumes.
                    gy[N_COEFFS..].fill(0.0);
                    wy[N_COEFFS..].fill(0.0);
                }
                particular_pair(
                    &mut gx,
                    &mut gy,
                    [&cx, &cy],
                    lambda,
                    1.0 / (lambda * lambda),
                    old,
                );
                particular_over(&mut wx, &cx, lambda, old[0]);
                particular_over(&mut wy, &cy, lambda, old[1]);
                assert_eq!(gx.map(f64::to_bits), wx.map(f64::to_bits), "λ={lambda}");
                assert_eq!(gy.map(f64::to_bits), wy.map(f64::to_bits), "λ={lambda}");
            }
        }
    }
}
