//! `Z y = w` by the structure of `Z` in the exponential basis: two scalar recursions and a
//! 2×2 system.
//!
//! # The elimination
//! Write `e_i = e^{−ωD_i}` (0-based intervals `i = 0 … 6`), `P_i, Q_i` for the homogeneous pair
//! of interval `i`, `β¹ = (β_2, β_3, β_4)` for the quartic unknowns of the first interval and
//! `β⁷` for those of the last, and `r_0 … r_19` for the right-hand side `w` (rows as in the
//! table of the parent module). Every COG condition is a pair of rows, position and velocity
//! over ω; in the exponential basis their **sum and difference** separate `P` from `Q`:
//!
//! ```text
//! continuity at the end of interval i (rows 4+2i, 5+2i), i = 0 … 5:
//!     sum:   2 Q_i − 2 e_{i+1} Q_{i+1} = s_i                 s_i = r_{4+2i} + r_{5+2i}
//!     diff:  2 e_i P_i − 2 P_{i+1}     = d_i                 d_i = r_{4+2i} − r_{5+2i}
//! ```
//!
//! (`s_0, d_0` also carry the end values of `β¹`'s particular solutions, `s_5, d_5` the start
//! values of `β⁷`'s.) So `P_{i+1} = e_i P_i − d_i/2` runs **forward** and
//! `Q_i = e_{i+1} Q_{i+1} + s_i/2` runs **backward**, both multiplying by `e ≤ 1`: errors are
//! damped along both recursions, which is the stable dichotomy of the pendulum's decaying and
//! growing modes (a forward shooting of both would amplify them by `e^{ωT}`).
//!
//! The two ZMP rows of each quartic fix it up to one parameter: rows 0 and 1
//! (`β_2 + β_3 + β_4 = r_0`, `2β_2 + 3β_3 + 4β_4 = r_1`) give
//!
//! ```text
//! β¹ = u¹ + v t₁,   u¹ = (3r_0 − r_1, r_1 − 2r_0, 0),   v = (1, −2, 1),   t₁ = β_4¹
//! ```
//!
//! and rows 18, 19 the same for `β⁷ = u⁷ + v t₇`. The initial state (rows 2, 3) gives
//! `P_0` from its difference; the terminal state (rows 16, 17) gives `Q_6` from its sum. Every
//! `P_i` and `Q_i` is then affine in `(t₁, t₇)`, and the two conditions left,
//!
//! ```text
//! A: 2 e_0 Q_0 + S_0(β¹) = r_2 + r_3        (initial state, sum)
//! B: 2 e_6 P_6 + D_6(β⁷) = r_16 − r_17      (terminal state, difference)
//! ```
//!
//! (`S`, `D`: sum and difference of the particular solutions' position and velocity/ω) are a
//! 2×2 system for `(t₁, t₇)`. Its matrix and the `t`-coefficients of every `P_i, Q_i` depend on
//! the timing alone ([`Chain::factor`]: the exponentials of the distinct durations and ~80
//! flops, with the monomial ends of intervals 1 and 7 from the timing's table, module `rhs`);
//! a right-hand side costs ~110 flops ([`Chain::solve`], in place). This is a factorisation
//! of `Z` (block elimination in the order `β` → `P` forward, `Q` backward → Schur complement
//! 2×2, solved with partial pivoting), so `Z` is singular exactly when that 2×2 is; it is
//! checked against the banded LU of the dense `Z` by the tests.

use super::rhs::Intervals;
use super::{PlanError, Timing, LAST_BETA, M, N};
use crate::lipm::N_COEFFS;
use crate::real::Real;

/// `v`: the direction of the free quartic parameter (`β_4`) in `(β_2, β_3, β_4)`.
const V: [f64; 3] = [1.0, -2.0, 1.0];

/// Position and velocity/ω of the particular solution of the ZMP term `s^k`, `k = 0 … 4`, at
/// the start and the end of an interval: `[x(0), ẋ(0)/ω, x(D), ẋ(D)/ω]` per `k`
/// ([`Intervals::mono`]; the quartic unknowns are `k = 2, 3, 4`).
type Ends<T> = [[T; 4]; N_COEFFS];

/// The timing-only part of the elimination.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Chain<T> {
    /// `e_i = e^{−ωD_i}`.
    e: [T; M],
    /// `∂P_i/∂t₁` (`P_6` also depends on `t₇`: [`Chain::p6_t7`]).
    p_t1: [T; M],
    /// `∂P_6/∂t₇`.
    p6_t7: T,
    /// `∂Q_i/∂t₇` (`Q_0` also depends on `t₁`: [`Chain::q0_t1`]).
    q_t7: [T; M],
    /// `∂Q_0/∂t₁`.
    q0_t1: T,
    /// The 2×2 system's LU with partial pivoting: rows swapped if `swap`, `l` the multiplier,
    /// `u = [u11, u12, u22]`.
    swap: bool,
    l: T,
    u: [T; 3],
}

/// `Σ_k c_k x_k` over the three quartic unknowns, for one column of [`Ends`] combined by `f`.
#[inline]
fn dot3<T: Real>(ends: &Ends<T>, beta: [T; 3], f: impl Fn(&[T; 4]) -> T) -> T {
    f(&ends[2]) * beta[0] + f(&ends[3]) * beta[1] + f(&ends[4]) * beta[2]
}

// Sums and differences of the ends (start: S, D; end: Se, De).
#[inline]
fn s_start<T: Real>(x: &[T; 4]) -> T {
    x[0] + x[1]
}
#[inline]
fn d_start<T: Real>(x: &[T; 4]) -> T {
    x[0] - x[1]
}
#[inline]
fn s_end<T: Real>(x: &[T; 4]) -> T {
    x[2] + x[3]
}
#[inline]
fn d_end<T: Real>(x: &[T; 4]) -> T {
    x[2] - x[3]
}

impl<T: Real> Chain<T> {
    /// All zero (not factorised).
    pub(super) const ZERO: Self = Self {
        e: [T::ZERO; M],
        p_t1: [T::ZERO; M],
        p6_t7: T::ZERO,
        q_t7: [T::ZERO; M],
        q0_t1: T::ZERO,
        swap: false,
        l: T::ZERO,
        u: [T::ZERO; 3],
    };

    /// The timing-only part for a valid timing and its table `iv` (set for it); `Singular` if
    /// the 2×2 system is (numerically).
    pub(super) fn factor(
        &mut self,
        timing: &Timing<T>,
        iv: &Intervals<T>,
    ) -> Result<(), PlanError> {
        let w = timing.omega;
        let d = &timing.durations;
        // A window has few distinct durations (single and double supports alternate): each
        // exponential is computed once, bit for bit the same value.
        for j in 0..M {
            let dj = d[j];
            let seen = (0..j).find(|&i| d[i] == dj);
            self.e[j] = match seen {
                Some(i) => self.e[i],
                None => (-w * dj).exp(),
            };
        }
        let (first, last) = (iv.mono(0), iv.mono(M - 1));
        let v = V.map(T::of);
        let half = T::of(0.5);
        let two = T::of(2.0);
        let e = self.e;
        // P forward, coefficient of t₁.
        self.p_t1[0] = -half * dot3(first, v, d_start);
        self.p_t1[1] = e[0] * self.p_t1[0] + half * dot3(first, v, d_end);
        let mut acc = self.p_t1[1];
        for (pt, &ei) in self.p_t1[2..].iter_mut().zip(&e[1..M - 1]) {
            acc = ei * acc;
            *pt = acc;
        }
        self.p6_t7 = -half * dot3(last, v, d_start);
        // Q backward, coefficient of t₇.
        self.q_t7[M - 1] = -half * dot3(last, v, s_end);
        self.q_t7[M - 2] = e[M - 1] * self.q_t7[M - 1] + half * dot3(last, v, s_start);
        for i in (0..M - 2).rev() {
            self.q_t7[i] = e[i + 1] * self.q_t7[i + 1];
        }
        self.q0_t1 = -half * dot3(first, v, s_end);
        // The 2×2 system [a11 a12; a21 a22] (t₁, t₇).
        let a11 = two * e[0] * self.q0_t1 + dot3(first, v, s_start);
        let a12 = two * e[0] * self.q_t7[0];
        let a21 = two * e[M - 1] * self.p_t1[M - 1];
        let a22 = two * e[M - 1] * self.p6_t7 + dot3(last, v, d_end);
        let ([b11, b12], [b21, b22], swap) = if a21.abs() > a11.abs() {
            ([a21, a22], [a11, a12], true)
        } else {
            ([a11, a12], [a21, a22], false)
        };
        let tol = T::EPSILON * T::of(N as f64);
        let scale1 = b11.abs().max(b21.abs());
        if !scale1.is_finite() || b11.abs().is_nan_or_le(tol * scale1) || b11 == T::ZERO {
            return Err(PlanError::Singular);
        }
        let l = b21 / b11;
        let u22 = b22 - l * b12;
        let scale2 = b22.abs().max((l * b12).abs());
        if !(u22.is_finite() && scale2.is_finite()) || u22.abs().is_nan_or_le(tol * scale2) {
            return Err(PlanError::Singular);
        }
        self.swap = swap;
        self.l = l;
        self.u = [b11, b12, u22];
        Ok(())
    }

    /// Solves `Z y = r` (the layout of the parent module) in place: `r` in, `y` out (every
    /// entry of `r` is read before the first of `y` is written over it: the constants of `P`
    /// and `Q` go straight to their places in `y`, and the free parameters are added there).
    pub(super) fn solve(&self, iv: &Intervals<T>, y: &mut [T; N]) {
        let (first, last) = (iv.mono(0), iv.mono(M - 1));
        let e = &self.e;
        let half = T::of(0.5);
        let two = T::of(2.0);
        let three = T::of(3.0);
        let r = |i: usize, y: &[T; N]| y[i];
        let u1 = [three * y[0] - y[1], y[1] - two * y[0], T::ZERO];
        let u7 = [three * y[18] - y[19], y[19] - two * y[18], T::ZERO];
        // The differences and sums of the COG rows, read before `y` is written.
        let (s0, d0) = (r(2, y) + r(3, y), r(2, y) - r(3, y));
        let (s6, d6) = (r(16, y) + r(17, y), r(16, y) - r(17, y));
        let mut dif = [T::ZERO; M - 1];
        let mut sum = [T::ZERO; M - 1];
        for i in 0..M - 1 {
            dif[i] = y[4 + 2 * i] - y[5 + 2 * i];
            sum[i] = y[4 + 2 * i] + y[5 + 2 * i];
        }
        // Constants of P (forward) and Q (backward) with t₁ = t₇ = 0, at P_i's and Q_i's places.
        let (pc, qc) = (|i: usize| 3 + 2 * i, |i: usize| 4 + 2 * i);
        y[pc(0)] = half * (d0 - dot3(first, u1, d_start));
        y[pc(1)] = e[0] * y[pc(0)] + half * (dot3(first, u1, d_end) - dif[0]);
        for i in 1..M - 2 {
            y[pc(i + 1)] = e[i] * y[pc(i)] - half * dif[i];
        }
        y[pc(M - 1)] = e[M - 2] * y[pc(M - 2)] - half * (dif[M - 2] + dot3(last, u7, d_start));
        y[qc(M - 1)] = half * (s6 - dot3(last, u7, s_end));
        y[qc(M - 2)] = e[M - 1] * y[qc(M - 1)] + half * (sum[M - 2] + dot3(last, u7, s_start));
        for i in (1..M - 2).rev() {
            y[qc(i)] = e[i + 1] * y[qc(i + 1)] + half * sum[i];
        }
        y[qc(0)] = e[1] * y[qc(1)] + half * (sum[0] - dot3(first, u1, s_end));
        // The 2×2 system.
        let ra = s0 - two * e[0] * y[qc(0)] - dot3(first, u1, s_start);
        let rb = d6 - two * e[M - 1] * y[pc(M - 1)] - dot3(last, u7, d_end);
        let (b1, b2) = if self.swap { (rb, ra) } else { (ra, rb) };
        let [u11, u12, u22] = self.u;
        let t7 = (b2 - self.l * b1) / u22;
        let t1 = (b1 - u12 * t7) / u11;
        // Back-substitution.
        for k in 0..3 {
            let vk = T::of(V[k]);
            y[k] = u1[k] + vk * t1;
            y[LAST_BETA + k] = u7[k] + vk * t7;
        }
        for i in 0..M {
            y[pc(i)] += self.p_t1[i] * t1;
            y[qc(i)] += self.q_t7[i] * t7;
        }
        y[pc(M - 1)] += self.p6_t7 * t7;
        y[qc(0)] += self.q0_t1 * t1;
    }
}
