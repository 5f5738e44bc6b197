//! One interval of the linear inverted pendulum: a polynomial ZMP and its closed-form COG.
//!
//! # The model
//! With the COG at constant height `z_c` above the ZMP plane, each horizontal coordinate obeys
//!
//! ```text
//! ẍ = ω² (x − p),      ω = √(g / z_c)                                   (paper eq. 1)
//! ```
//!
//! where `x` is the COG and `p` the ZMP. In an interval of duration `D`, with local time
//! `τ ∈ [0, D]`, the ZMP is a polynomial of order `N ≤ 4`
//!
//! ```text
//! p(τ) = Σ a_i τ^i                                                       (eq. 2)
//! ```
//!
//! and the COG is the homogeneous solution plus a polynomial particular solution
//!
//! ```text
//! x(τ) = V cosh ωτ + W sinh ωτ + Σ A_i τ^i                               (eq. 3)
//! ```
//!
//! Substituting into `p = x − ẍ/ω²` and matching powers of τ gives
//!
//! ```text
//! a_i = A_i − (i+1)(i+2) A_{i+2} / ω²     ⇔     A_i = a_i + (i+1)(i+2) A_{i+2} / ω²
//! ```
//!
//! (`A_N = a_N`, `A_{N−1} = a_{N−1}`, then downwards). Equivalently, the ZMP monomial `τ^k`
//! produces the COG polynomial `m_k(τ) = Σ_l k!/(k−2l)! ω^{−2l} τ^{k−2l}`.
//!
//! # The representation used here, and why
//! Time inside an interval is normalised, `s = τ/D ∈ [0, 1]`, `λ = ωD`, and the ZMP is stored as
//! `p = Σ c_k s^k` (`c_k = a_k D^k`, all in metres). The COG is
//!
//! ```text
//! x(τ) = P e^{−ωτ} + Q e^{−ω(D−τ)} + G(s),        G a particular solution, a polynomial in s.
//! ```
//!
//! * The homogeneous part `V cosh ωτ + W sinh ωτ` is stored as `P e^{−ωτ} + Q e^{−ω(D−τ)}`: a
//!   mode that decays from the start and one that decays backwards from the end, both bounded
//!   by 1 on the interval, so no column of the window's matrix grows like `cosh ωD`.
//! * The particular solution is not always the paper's polynomial `Σ A_i τ^i`. For the ZMP term
//!   `s^k` that polynomial is `m_k(s) = Σ_l k!/(k−2l)! λ^{−2l} s^{k−2l}`, whose constant term
//!   `k!/λ^k` is huge for a short interval (`24/λ⁴ ≈ 1600` for a 0.1 s interval), so the COG
//!   would come out as the small difference of large homogeneous and particular parts: in
//!   `f32` that lost 1.5 mm of COG on a window starting with a 0.1 s interval. For `λ < 1` the
//!   planner uses instead the particular solution that starts at rest,
//!   `g_k(s) = −Σ_{n≥1} λ^{2n} k!/(k+2n)! s^{k+2n}` (bounded by `cosh λ − 1 < 0.55`), truncated
//!   after [`SERIES_TERMS`] terms (remainder below 1e-18). For `λ ≥ 1` it uses `m_k`, whose
//!   coefficients are then at most 24. Any particular solution is exact; `P, Q` absorb the
//!   difference.
//! * The paper's coefficients are recovered exactly: `a_i = c_i / D^i`, `A_i` from the recursion
//!   above, and `V = x(0) − A_0`, `W = (ẋ(0) − A_1)/ω` ([`Segment::vw`]).
//!
//! # The paper's typos
//! At `τ = 0`: `x = V + A_0`, `ẋ = ωW + A_1` (eq. 5 omits ω), `p = A_0 − 2A_2/ω²` (eq. 10 has 1
//! instead of 2), `ṗ = A_1 − 6A_3/ω²` (eq. 11). Eq. 7's right-hand side is `ωW^{(j+1)} + A_1^{(j+1)}`.

use crate::real::Real;

/// Highest ZMP polynomial order used by the planner (quartic).
pub const MAX_ORDER: usize = 4;
/// Number of polynomial coefficients stored per interval (`MAX_ORDER + 1`).
pub const N_COEFFS: usize = MAX_ORDER + 1;
/// Terms of the at-rest particular solution used for `λ = ωD < 1`.
pub const SERIES_TERMS: usize = 10;
/// Length of the particular-solution polynomial (degree `MAX_ORDER + 2·SERIES_TERMS`).
pub const PARTICULAR_LEN: usize = MAX_ORDER + 2 * SERIES_TERMS + 1;
/// `λ = ωD` below which the at-rest particular solution is used.
pub const SHORT_LAMBDA: f64 = 1.0;

/// A polynomial of order ≤ 4: `c[0] + c[1] s + … + c[4] s⁴`.
pub type Poly<T> = [T; N_COEFFS];
/// The particular COG solution `G(s)` of an interval, in normalised time.
pub type Particular<T> = [T; PARTICULAR_LEN];

/// Position and velocity of one coordinate (COG or ZMP).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct State<T> {
    /// Position \[m\].
    pub pos: T,
    /// Velocity \[m/s\].
    pub vel: T,
}

impl<T: Real> State<T> {
    /// Position and velocity zero.
    pub const ZERO: Self = Self {
        pos: T::ZERO,
        vel: T::ZERO,
    };

    /// A state from position and velocity.
    pub fn new(pos: T, vel: T) -> Self {
        Self { pos, vel }
    }
    /// A state at rest at `pos`.
    pub fn at_rest(pos: T) -> Self {
        Self { pos, vel: T::ZERO }
    }
}

/// Everything about one coordinate at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample<T> {
    /// COG position \[m\].
    pub cog: T,
    /// COG velocity \[m/s\].
    pub cog_vel: T,
    /// COG acceleration \[m/s²\].
    pub cog_acc: T,
    /// ZMP position \[m\].
    pub zmp: T,
    /// ZMP velocity \[m/s\].
    pub zmp_vel: T,
}

impl<T: Real> Sample<T> {
    /// Every value zero.
    pub const ZERO: Self = Self {
        cog: T::ZERO,
        cog_vel: T::ZERO,
        cog_acc: T::ZERO,
        zmp: T::ZERO,
        zmp_vel: T::ZERO,
    };
}

/// Evaluates a polynomial and its first two derivatives at `t` (Horner).
#[inline]
pub fn poly_eval<T: Real, const L: usize>(c: &[T; L], t: T) -> (T, T, T) {
    poly_eval_slice(c, t)
}

/// [`poly_eval`] on a slice of coefficients (lowest order first).
#[inline]
pub fn poly_eval_slice<T: Real>(c: &[T], t: T) -> (T, T, T) {
    let mut v = T::ZERO;
    let mut d = T::ZERO;
    let mut dd = T::ZERO;
    for &ci in c.iter().rev() {
        dd = dd * t + d + d;
        d = d * t + v;
        v = v * t + ci;
    }
    (v, d, dd)
}

/// The paper's COG polynomial `A` for the ZMP polynomial `a` (both in local time τ, eq. 3).
#[inline]
pub fn cog_poly<T: Real>(a: &Poly<T>, omega: T) -> Poly<T> {
    let w2 = omega * omega;
    let mut big = *a;
    // A_i = a_i + (i+1)(i+2) A_{i+2} / ω², from the top down.
    let mut i = MAX_ORDER - 1;
    while i > 0 {
        i -= 1;
        let k = T::of(((i + 1) * (i + 2)) as f64);
        big[i] = a[i] + k * big[i + 2] / w2;
    }
    big
}

/// The ZMP polynomial `a` of the COG polynomial `A`: `a_i = A_i − (i+1)(i+2) A_{i+2} / ω²`.
#[inline]
pub fn zmp_poly<T: Real>(big: &Poly<T>, omega: T) -> Poly<T> {
    let w2 = omega * omega;
    let mut a = *big;
    for i in 0..MAX_ORDER - 1 {
        let k = T::of(((i + 1) * (i + 2)) as f64);
        a[i] = big[i] - k * big[i + 2] / w2;
    }
    a
}

/// `1 / (m (m − 1))` for `m < PARTICULAR_LEN` (multiplications instead of divisions in the series).
pub(crate) const INV_PAIR: [f64; PARTICULAR_LEN] = {
    let mut t = [0.0; PARTICULAR_LEN];
    let mut m = 2;
    while m < PARTICULAR_LEN {
        t[m] = 1.0 / ((m * (m - 1)) as f64);
        m += 1;
    }
    t
};

/// Writes the particular solution `G(s) = Σ g_i s^i` for the normalised ZMP polynomial `c`
/// over an interval with `λ = ωD` into `g`, every coefficient (the unused tail is zeroed):
///
/// * `λ < 1`, at rest at `s = 0`: `g_0 = g_1 = 0` and `g_i = λ²/(i(i−1)) (g_{i−2} − c_{i−2})`
///   upwards (`c_i = 0` beyond the quartic), which sums `−Σ_{n≥1} λ^{2n} k!/(k+2n)! c_k` over
///   the terms with `k + 2n = i`, up to degree [`PARTICULAR_LEN`]` − 1`;
/// * `λ ≥ 1`, the paper's polynomial: `g_4 = c_4`, `g_3 = c_3` and
///   `g_i = c_i + (i+1)(i+2) g_{i+2} / λ²` downwards.
#[inline]
pub fn particular_into<T: Real>(g: &mut Particular<T>, c: &Poly<T>, lambda: T) {
    particular_over(g, c, lambda, T::ZERO);
}

/// [`particular_into`] over a particular solution `g` computed before for `λ = old_lambda`:
/// its tail is zero already if `old_lambda ≥ 1` (see [`particular_len`]), and then is not
/// written again.
#[inline]
pub(crate) fn particular_over<T: Real>(
    g: &mut Particular<T>,
    c: &Poly<T>,
    lambda: T,
    old_lambda: T,
) {
    if lambda < T::of(SHORT_LAMBDA) {
        let l2 = lambda * lambda;
        g[0] = T::ZERO;
        g[1] = T::ZERO;
        for i in 2..PARTICULAR_LEN {
            let ci = if i - 2 < N_COEFFS { c[i - 2] } else { T::ZERO };
            g[i] = l2 * T::of(INV_PAIR[i]) * (g[i - 2] - ci);
        }
    } else {
        let inv2 = T::ONE / (lambda * lambda);
        g[4] = c[4];
        g[3] = c[3];
        g[2] = c[2] + T::of(12.0) * inv2 * g[4];
        g[1] = c[1] + T::of(6.0) * inv2 * g[3];
        g[0] = c[0] + T::of(2.0) * inv2 * g[2];
        // A NaN `old_lambda` zeroes too.
        let tail_zero = old_lambda >= T::of(SHORT_LAMBDA);
        if !tail_zero {
            for gi in g.iter_mut().skip(N_COEFFS) {
                *gi = T::ZERO;
            }
        }
    }
}

/// The particular solution for the normalised ZMP polynomial `c` over an interval with `λ = ωD`
/// (see [`particular_into`]).
#[inline]
pub fn particular<T: Real>(c: &Poly<T>, lambda: T) -> Particular<T> {
    let mut g = [T::ZERO; PARTICULAR_LEN];
    particular_into(&mut g, c, lambda);
    g
}

/// `(x(0), ẋ(0)/ω, x(D), ẋ(D)/ω)` of the particular solution of the ZMP monomial `s^k`
/// (`k ≤ MAX_ORDER`; a larger `k` is the zero polynomial): [`particular_ends`] of
/// [`particular`], summed as the recurrences of [`particular_into`] produce the coefficients
/// (the same operations in the same order: bit for bit the same), without a buffer.
#[inline]
pub fn monomial_ends<T: Real>(k: usize, lambda: T) -> (T, T, T, T) {
    if k > MAX_ORDER {
        return (T::ZERO, T::ZERO, T::ZERO, T::ZERO);
    }
    let (mut x1, mut v1) = (T::ZERO, T::ZERO);
    let (g0, g1);
    if lambda < T::of(SHORT_LAMBDA) {
        // g_i = λ²/(i(i−1)) (g_{i−2} − c_{i−2}), c = e_k: zero below k + 2, then one chain.
        let l2 = lambda * lambda;
        (g0, g1) = (T::ZERO, T::ZERO);
        let mut prev = T::ZERO; // g_{i−2} on the chain i ≡ k (mod 2)
        let mut i = T::ZERO;
        for (n, &inv) in INV_PAIR.iter().enumerate() {
            let g = if n >= k + 2 && (n - k) % 2 == 0 {
                let c = if n - 2 == k { T::ONE } else { T::ZERO };
                let v = l2 * T::of(inv) * (prev - c);
                prev = v;
                v
            } else {
                T::ZERO
            };
            x1 += g;
            v1 += i * g;
            i += T::ONE;
        }
    } else {
        // g_k = 1, g_{k−2} = k(k−1)/λ², …: the paper's m_k, as `particular_into` computes it.
        let mut c = [T::ZERO; N_COEFFS];
        c[k] = T::ONE;
        let inv2 = T::ONE / (lambda * lambda);
        let mut g = [T::ZERO; N_COEFFS];
        g[4] = c[4];
        g[3] = c[3];
        g[2] = c[2] + T::of(12.0) * inv2 * g[4];
        g[1] = c[1] + T::of(6.0) * inv2 * g[3];
        g[0] = c[0] + T::of(2.0) * inv2 * g[2];
        (g0, g1) = (g[0], g[1]);
        let mut i = T::ZERO;
        for &gi in &g {
            x1 += gi;
            v1 += i * gi;
            i += T::ONE;
        }
    }
    (g0, g1 / lambda, x1, v1 / lambda)
}

/// Number of coefficients of the particular solution that can be non-zero for `λ = ωD`.
#[inline]
pub fn particular_len<T: Real>(lambda: T) -> usize {
    if lambda < T::of(SHORT_LAMBDA) {
        PARTICULAR_LEN
    } else {
        N_COEFFS
    }
}

/// Position and scaled velocity `ẋ/ω` of a particular solution at the start and the end of the
/// interval: `(x(0), ẋ(0)/ω, x(D), ẋ(D)/ω)`.
#[inline]
pub fn particular_ends<T: Real>(g: &Particular<T>, lambda: T) -> (T, T, T, T) {
    let len = particular_len(lambda);
    let (mut x1, mut v1) = (T::ZERO, T::ZERO);
    let mut i = T::ZERO;
    for &gi in g.iter().take(len) {
        x1 += gi;
        v1 += i * gi;
        i += T::ONE;
    }
    (g[0], g[1] / lambda, x1, v1 / lambda)
}

/// The part of a sample that depends on `ω`, `D` and `τ` only ([`Segment::sample_pair`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct At<T> {
    /// `τ / D`.
    s: T,
    /// `1 / D`.
    inv_d: T,
    /// `e^{−ωτ}`.
    ep: T,
    /// `e^{−ω(D−τ)}`.
    eq: T,
}

/// One interval of the plan in one plane: the ZMP polynomial and the closed-form COG.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment<T> {
    /// ω = √(g/z_c) \[1/s\].
    pub omega: T,
    /// Duration `D` \[s\].
    pub duration: T,
    /// Coefficient of `e^{−ωτ}` (the mode that decays from the start) \[m\].
    pub p: T,
    /// Coefficient of `e^{−ω(D−τ)}` (the mode that decays backwards from the end) \[m\].
    pub q: T,
    /// ZMP polynomial in normalised time, `p = Σ c_k s^k`, `s = τ/D` \[m\].
    pub zmp: Poly<T>,
    /// The particular COG solution `G(s)` \[m\].
    pub particular: Particular<T>,
}

impl<T: Real> Default for Segment<T> {
    fn default() -> Self {
        Self {
            omega: T::ONE,
            duration: T::ONE,
            p: T::ZERO,
            q: T::ZERO,
            zmp: [T::ZERO; N_COEFFS],
            particular: [T::ZERO; PARTICULAR_LEN],
        }
    }
}

impl<T: Real> Segment<T> {
    /// Every field zero (ω and `D` too: not a segment to sample; a placeholder in a buffer
    /// that is filled before use).
    pub const ZERO: Self = Self {
        omega: T::ZERO,
        duration: T::ZERO,
        p: T::ZERO,
        q: T::ZERO,
        zmp: [T::ZERO; N_COEFFS],
        particular: [T::ZERO; PARTICULAR_LEN],
    };

    /// A segment from its normalised ZMP polynomial `zmp` and homogeneous coefficients `P, Q`.
    pub fn new(omega: T, duration: T, zmp: Poly<T>, p: T, q: T) -> Self {
        Self {
            omega,
            duration,
            p,
            q,
            zmp,
            particular: particular(&zmp, omega * duration),
        }
    }

    /// A segment from its parts, with the particular solution already computed (it must be
    /// `particular(&zmp, omega * duration)` up to a constant, see [`Segment::shifted`]).
    pub fn from_parts(
        omega: T,
        duration: T,
        zmp: Poly<T>,
        particular: Particular<T>,
        p: T,
        q: T,
    ) -> Self {
        Self {
            omega,
            duration,
            p,
            q,
            zmp,
            particular,
        }
    }

    /// The segment that starts from the COG state `start` under the normalised ZMP polynomial
    /// `zmp` (an initial-value problem).
    pub fn from_start(omega: T, duration: T, zmp: Poly<T>, start: State<T>) -> Self {
        let lambda = omega * duration;
        let g = particular(&zmp, lambda);
        let (x0, v0, _, _) = particular_ends(&g, lambda);
        let e = (-lambda).exp();
        let dx = start.pos - x0;
        let dv = start.vel / omega - v0;
        let half = T::of(0.5);
        // x(0) = P + QE, ẋ(0)/ω = −P + QE.
        Self {
            omega,
            duration,
            p: half * (dx - dv),
            q: half * (dx + dv) / e,
            zmp,
            particular: g,
        }
    }

    /// The paper's ZMP coefficients `a_i` in local time τ (eq. 2).
    pub fn zmp_tau(&self) -> Poly<T> {
        let mut a = self.zmp;
        let mut dk = T::ONE;
        for ai in a.iter_mut() {
            *ai /= dk;
            dk *= self.duration;
        }
        a
    }

    /// The paper's COG polynomial `A_i` in local time τ (eq. 3).
    pub fn cog_tau(&self) -> Poly<T> {
        cog_poly(&self.zmp_tau(), self.omega)
    }

    /// The paper's homogeneous coefficients `(V, W)` of `V cosh ωτ + W sinh ωτ + Σ A_i τ^i`.
    pub fn vw(&self) -> (T, T) {
        let start = self.start_state();
        let big = self.cog_tau();
        (start.pos - big[0], (start.vel - big[1]) / self.omega)
    }

    /// COG and ZMP at local time `tau` (clamped to `[0, D]`).
    pub fn sample(&self, tau: T) -> Sample<T> {
        self.sample_at(&self.at(tau))
    }

    /// Both planes of a window at local time `tau`: `(x.sample(tau), y.sample(tau))`, bit for
    /// bit, with the exponentials computed once when the two segments have the same `ω` and
    /// `D` (as the two planes of a window always do).
    pub fn sample_pair(x: &Self, y: &Self, tau: T) -> (Sample<T>, Sample<T>) {
        let a = x.at(tau);
        if x.omega == y.omega && x.duration == y.duration {
            (x.sample_at(&a), y.sample_at(&a))
        } else {
            (x.sample_at(&a), y.sample(tau))
        }
    }

    /// What a sample at `tau` needs of `ω`, `D` and `τ` only.
    #[inline]
    pub(crate) fn at(&self, tau: T) -> At<T> {
        let tau = tau.max(T::ZERO).min(self.duration);
        let w = self.omega;
        let inv_d = T::ONE / self.duration;
        At {
            s: tau * inv_d,
            inv_d,
            ep: (-w * tau).exp(),
            eq: (-w * (self.duration - tau)).exp(),
        }
    }

    #[inline]
    pub(crate) fn sample_at(&self, a: &At<T>) -> Sample<T> {
        let w = self.omega;
        let (s, inv_d) = (a.s, a.inv_d);
        let hp = self.p * a.ep;
        let hq = self.q * a.eq;
        let len = particular_len(w * self.duration);
        let (xp, vp, ap) = poly_eval_slice(&self.particular[..len], s);
        let (z, zv, _) = poly_eval(&self.zmp, s);
        Sample {
            cog: hp + hq + xp,
            cog_vel: w * (hq - hp) + vp * inv_d,
            cog_acc: w * w * (hp + hq) + ap * inv_d * inv_d,
            zmp: z,
            zmp_vel: zv * inv_d,
        }
    }

    /// COG state at the start of the interval.
    pub fn start_state(&self) -> State<T> {
        let s = self.sample(T::ZERO);
        State::new(s.cog, s.cog_vel)
    }

    /// COG state at the end of the interval.
    pub fn end_state(&self) -> State<T> {
        let s = self.sample(self.duration);
        State::new(s.cog, s.cog_vel)
    }

    /// The same segment with every position shifted by `d` (the LIPM is translation invariant:
    /// a constant added to a particular solution is a particular solution for the shifted ZMP).
    pub fn shifted(mut self, d: T) -> Self {
        self.zmp[0] += d;
        self.particular[0] += d;
        self
    }
}

/// The cubic Hermite ZMP polynomial, in normalised time, from `(p0, v0)` at the start to
/// `(p1, v1)` at the end of an interval of duration `D`.
#[inline]
pub fn hermite<T: Real>(p0: State<T>, p1: State<T>, duration: T) -> Poly<T> {
    let dp = p1.pos - p0.pos;
    let (v0, v1) = (p0.vel * duration, p1.vel * duration);
    let three = T::of(3.0);
    let two = T::of(2.0);
    [
        p0.pos,
        v0,
        three * dp - two * v0 - v1,
        -two * dp + v0 + v1,
        T::ZERO,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: f64 = 3.5;

    #[test]
    fn a_and_big_a_are_inverse() {
        let a = [0.1, -0.2, 0.3, 0.4, -0.5];
        let big = cog_poly(&a, W);
        let back = zmp_poly(&big, W);
        for i in 0..N_COEFFS {
            assert!((a[i] - back[i]).abs() < 1e-14, "{i}");
        }
        // Direct check of the recursion: A_0 = a0 + 2a2/ω² + 24a4/ω⁴.
        let expect = a[0] + 2.0 * a[2] / (W * W) + 24.0 * a[4] / (W * W * W * W);
        assert!((big[0] - expect).abs() < 1e-14);
    }

    #[test]
    fn both_particular_regimes_satisfy_the_pendulum_equation() {
        // G''/λ² − G = −Σ c_k s^k (the ODE in normalised time), for λ on both sides of 1.
        let c = [0.05, 0.1, -0.3, 0.2, 0.1];
        for &lambda in &[0.02, 0.35, 0.99, 1.0, 2.4, 3.6] {
            let g = particular(&c, lambda);
            for i in 0..=20 {
                let s = i as f64 / 20.0;
                let (x, _, a) = poly_eval(&g, s);
                let (p, _, _) = poly_eval(&c, s);
                let r = a / (lambda * lambda) - x + p;
                assert!(r.abs() < 1e-12, "λ={lambda} s={s}: residual {r}");
            }
        }
    }

    #[test]
    fn particular_recurrences_equal_the_sums_they_stand_for() {
        // λ < 1: g_i = −Σ λ^{2n} k!/(k+2n)! c_k over k + 2n = i, n ≥ 1; λ ≥ 1: g_i =
        // Σ_k k!/i! λ^{i−k} c_k over k − i even, k ≥ i. Written out term by term here.
        let fact = |n: usize| (1..=n).map(|v| v as f64).product::<f64>();
        let c = [0.05, 0.1, -0.3, 0.2, 0.1];
        for &lambda in &[0.02, 0.35, 0.99, 1.0, 2.4, 3.6] {
            // Into a buffer full of garbage: every coefficient is written.
            let mut g = [7.0; PARTICULAR_LEN];
            particular_into(&mut g, &c, lambda);
            for (i, &gi) in g.iter().enumerate() {
                let mut want = 0.0;
                for (k, &ck) in c.iter().enumerate() {
                    if lambda < SHORT_LAMBDA && i > k && (i - k) % 2 == 0 {
                        want -= libm::pow(lambda, (i - k) as f64) * fact(k) / fact(i) * ck;
                    } else if lambda >= SHORT_LAMBDA && k >= i && (k - i) % 2 == 0 {
                        want += fact(k) / fact(i) / libm::pow(lambda, (k - i) as f64) * ck;
                    }
                }
                assert!(
                    (gi - want).abs() <= 1e-15 * (1.0 + want.abs()),
                    "λ={lambda} g_{i}: {gi} vs {want}"
                );
            }
        }
    }

    #[test]
    fn monomial_ends_are_those_of_the_whole_particular() {
        for k in 0..=MAX_ORDER {
            let mut c = [0.0; N_COEFFS];
            c[k] = 1.0;
            for &lambda in &[0.005, 0.02, 0.35, 0.99, 1.0, 2.4, 3.6, 40.0] {
                let want = particular_ends(&particular(&c, lambda), lambda);
                let got = monomial_ends(k, lambda);
                // Bit for bit (the same operations on the same values).
                assert_eq!(
                    [got.0, got.1, got.2, got.3].map(f64::to_bits),
                    [want.0, want.1, want.2, want.3].map(f64::to_bits),
                    "k={k} λ={lambda}"
                );
            }
        }
        assert_eq!(monomial_ends(MAX_ORDER + 1, 0.5), (0.0, 0.0, 0.0, 0.0));
    }

    #[test]
    fn sample_satisfies_the_pendulum_equation() {
        for &d in &[0.1, 0.7] {
            let seg =
                Segment::from_start(W, d, [0.05, 0.1, -0.3, 0.2, 0.1], State::new(0.02, -0.1));
            for i in 0..=20 {
                let s = seg.sample(d * i as f64 / 20.0);
                assert!((s.cog_acc - W * W * (s.cog - s.zmp)).abs() < 1e-11);
            }
            let s0 = seg.start_state();
            assert!((s0.pos - 0.02).abs() < 1e-14 && (s0.vel + 0.1).abs() < 1e-13);
        }
    }

    #[test]
    fn vw_and_big_a_give_the_paper_form() {
        for &d in &[0.1, 0.8] {
            let seg = Segment::new(W, d, [0.01, 0.02, 0.03, -0.04, 0.05], 0.3, -0.2);
            let (v, w) = seg.vw();
            let big = seg.cog_tau();
            for i in 0..=8 {
                let t = d * i as f64 / 8.0;
                let s = seg.sample(t);
                let (poly, _, _) = poly_eval(&big, t);
                let paper = v * libm::cosh(W * t) + w * libm::sinh(W * t) + poly;
                assert!((s.cog - paper).abs() < 1e-11, "d={d} t={t}");
                let (zmp, _, _) = poly_eval(&seg.zmp_tau(), t);
                assert!((s.zmp - zmp).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn hermite_meets_its_ends() {
        let d = 0.4;
        let c = hermite(State::new(0.1, 0.2), State::new(-0.3, 0.5), d);
        let (p0, v0, _) = poly_eval(&c, 0.0);
        let (p1, v1, _) = poly_eval(&c, 1.0);
        assert!((p0 - 0.1).abs() < 1e-14 && (v0 / d - 0.2).abs() < 1e-14);
        assert!((p1 + 0.3).abs() < 1e-14 && (v1 / d - 0.5).abs() < 1e-13);
    }
}
