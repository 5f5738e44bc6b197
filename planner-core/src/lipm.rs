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
//! # The homogeneous part, and why it is not stored as `V, W`
//! `V cosh ωτ + W sinh ωτ` is stored as `P e^{−ωτ} + Q e^{−ω(D−τ)}`: a mode that decays from
//! the start of the interval and one that decays backwards from its end. Both are bounded by 1
//! on `[0, D]`, which keeps the boundary-value system of the window well conditioned (see
//! `window.rs`); the paper's coefficients follow from `E = e^{−ωD}`:
//!
//! ```text
//! V = P + Q E,      W = −P + Q E.
//! ```
//!
//! # The paper's typos
//! At `τ = 0`: `x = V + A_0`, `ẋ = ωW + A_1` (eq. 5 omits ω), `p = A_0 − 2A_2/ω²` (eq. 10 has 1
//! instead of 2), `ṗ = A_1 − 6A_3/ω²` (eq. 11). Eq. 7's right-hand side is `ωW^{(j+1)} + A_1^{(j+1)}`.

use crate::real::Real;

/// Highest ZMP polynomial order used by the planner (quartic).
pub const MAX_ORDER: usize = 4;
/// Number of polynomial coefficients stored per interval (`MAX_ORDER + 1`).
pub const N_COEFFS: usize = MAX_ORDER + 1;

/// A polynomial of order ≤ 4 in local time: `c[0] + c[1] τ + … + c[4] τ⁴`.
pub type Poly<T> = [T; N_COEFFS];

/// Position and velocity of one coordinate (COG or ZMP).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct State<T> {
    /// Position \[m\].
    pub pos: T,
    /// Velocity \[m/s\].
    pub vel: T,
}

impl<T: Real> State<T> {
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

/// Evaluates a polynomial and its first two derivatives at `t` (Horner).
#[inline]
pub fn poly_eval<T: Real>(c: &Poly<T>, t: T) -> (T, T, T) {
    let mut v = c[MAX_ORDER];
    let mut d = T::ZERO;
    let mut dd = T::ZERO;
    let mut i = MAX_ORDER;
    while i > 0 {
        i -= 1;
        dd = dd * t + d + d;
        d = d * t + v;
        v = v * t + c[i];
    }
    (v, d, dd)
}

/// The COG polynomial `A` of the particular solution for the ZMP polynomial `a` (eq. 3).
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

/// `m_k(D) / D^k` and `m_k'(D) / (ω D^k)`: the COG position and scaled velocity produced at
/// the end of an interval by the ZMP term `β (τ/D)^k` per unit `β`, as functions of
/// `u = 1/(ωD)`. These are the dimensionless columns of the window's unknown quartic
/// coefficients.
#[inline]
pub fn monomial_end<T: Real>(k: usize, u: T) -> (T, T) {
    // m_k(τ)/D^k at τ = D: Σ_l k!/(k−2l)! u^{2l};  derivative: Σ_l k!/(k−2l−1)! u^{2l+1}.
    let mut pos = T::ZERO;
    let mut vel = T::ZERO;
    let mut coef = 1.0_f64; // k!/(k−j)! for the current power j of u
    let mut upow = T::ONE;
    for j in 0..=k {
        if j % 2 == 0 {
            pos += T::of(coef) * upow;
        } else {
            vel += T::of(coef) * upow;
        }
        coef *= (k - j) as f64;
        upow *= u;
    }
    (pos, vel)
}

/// `m_k(0) / D^k` and `m_k'(0) / (ω D^k)`: as [`monomial_end`] at the start of the interval
/// (only the constant, respectively linear, term of `m_k` survives).
#[inline]
pub fn monomial_start<T: Real>(k: usize, u: T) -> (T, T) {
    let mut fact = 1.0_f64;
    let mut upow = T::ONE;
    for j in 1..=k {
        fact *= j as f64;
        upow *= u;
    }
    if k % 2 == 0 {
        (T::of(fact) * upow, T::ZERO)
    } else {
        (T::ZERO, T::of(fact) * upow)
    }
}

/// One interval of the plan in one plane: the ZMP polynomial and the closed-form COG.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Segment<T> {
    /// ω = √(g/z_c) \[1/s\].
    pub omega: T,
    /// Duration `D` \[s\].
    pub duration: T,
    /// Coefficient of `e^{−ωτ}` (the mode that decays from the start) \[m\].
    pub p: T,
    /// Coefficient of `e^{−ω(D−τ)}` (the mode that decays backwards from the end) \[m\].
    pub q: T,
    /// ZMP polynomial `a_i` (eq. 2) \[m/s^i\].
    pub zmp: Poly<T>,
    /// COG particular-solution polynomial `A_i` (eq. 3) \[m/s^i\].
    pub cog: Poly<T>,
}

impl<T: Real> Segment<T> {
    /// A segment from its ZMP polynomial and homogeneous coefficients `P, Q`.
    pub fn from_pq(omega: T, duration: T, zmp: Poly<T>, p: T, q: T) -> Self {
        Self {
            omega,
            duration,
            p,
            q,
            zmp,
            cog: cog_poly(&zmp, omega),
        }
    }

    /// The segment that starts from the COG state `start` under the ZMP polynomial `zmp`
    /// (an initial-value problem: used by the tests and by forward simulation).
    pub fn from_start(omega: T, duration: T, zmp: Poly<T>, start: State<T>) -> Self {
        let cog = cog_poly(&zmp, omega);
        let e = (-omega * duration).exp();
        let dx = start.pos - cog[0];
        let dv = (start.vel - cog[1]) / omega;
        let half = T::of(0.5);
        // x(0) = P + QE, ẋ(0)/ω = −P + QE.
        let p = half * (dx - dv);
        let q = half * (dx + dv) / e;
        Self {
            omega,
            duration,
            p,
            q,
            zmp,
            cog,
        }
    }

    /// The paper's homogeneous coefficients `(V, W)` of `V cosh ωτ + W sinh ωτ`.
    pub fn vw(&self) -> (T, T) {
        let qe = self.q * (-self.omega * self.duration).exp();
        (self.p + qe, qe - self.p)
    }

    /// COG and ZMP at local time `tau` (clamped to `[0, D]`).
    pub fn sample(&self, tau: T) -> Sample<T> {
        let tau = tau.max(T::ZERO).min(self.duration);
        let w = self.omega;
        let e_start = (-w * tau).exp();
        let e_end = (-w * (self.duration - tau)).exp();
        let hp = self.p * e_start;
        let hq = self.q * e_end;
        let (xp, vp, ap) = poly_eval(&self.cog, tau);
        let (z, zv, _) = poly_eval(&self.zmp, tau);
        Sample {
            cog: hp + hq + xp,
            cog_vel: w * (hq - hp) + vp,
            cog_acc: w * w * (hp + hq) + ap,
            zmp: z,
            zmp_vel: zv,
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

    /// The same segment with every position shifted by `d` (the LIPM is translation invariant).
    pub fn shifted(mut self, d: T) -> Self {
        self.zmp[0] += d;
        self.cog[0] += d;
        self
    }
}

/// The cubic Hermite ZMP polynomial from `(p0, v0)` at τ = 0 to `(p1, v1)` at τ = D.
#[inline]
pub fn hermite<T: Real>(p0: State<T>, p1: State<T>, duration: T) -> Poly<T> {
    let d = duration;
    let dp = p1.pos - p0.pos;
    let three = T::of(3.0);
    let two = T::of(2.0);
    let a2 = (three * dp - (two * p0.vel + p1.vel) * d) / (d * d);
    let a3 = (-two * dp + (p0.vel + p1.vel) * d) / (d * d * d);
    [p0.pos, p0.vel, a2, a3, T::ZERO]
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
        // Direct check of the recursion for the quartic term: A_0 = a0 + 2a2/ω² + 24a4/ω⁴.
        let expect = a[0] + 2.0 * a[2] / (W * W) + 24.0 * a[4] / (W * W * W * W);
        assert!((big[0] - expect).abs() < 1e-14);
    }

    #[test]
    fn sample_satisfies_the_pendulum_equation() {
        let seg = Segment::from_start(W, 0.7, [0.05, 0.1, -0.3, 0.2, 0.1], State::new(0.02, -0.1));
        for i in 0..=20 {
            let s = seg.sample(0.7 * i as f64 / 20.0);
            assert!((s.cog_acc - W * W * (s.cog - s.zmp)).abs() < 1e-12);
        }
        let s0 = seg.start_state();
        assert!((s0.pos - 0.02).abs() < 1e-14 && (s0.vel + 0.1).abs() < 1e-14);
    }

    #[test]
    fn vw_matches_the_hyperbolic_form() {
        let seg = Segment::from_pq(W, 0.8, [0.0; 5], 0.3, -0.2);
        let (v, w) = seg.vw();
        for i in 0..=8 {
            let t = 0.1 * i as f64;
            let s = seg.sample(t);
            let hyp = v * libm::cosh(W * t) + w * libm::sinh(W * t);
            assert!((s.cog - hyp).abs() < 1e-12);
        }
    }

    #[test]
    fn monomial_columns_match_direct_evaluation() {
        let d = 0.6;
        let u = 1.0 / (W * d);
        for k in 0..=4 {
            let mut a = [0.0; 5];
            a[k] = 1.0 / libm::pow(d, k as f64); // β = 1
            let big = cog_poly(&a, W);
            let (xe, ve, _) = poly_eval(&big, d);
            let (xs, vs, _) = poly_eval(&big, 0.0);
            let (pe, pve) = monomial_end(k, u);
            let (ps, pvs) = monomial_start(k, u);
            assert!((xe - pe).abs() < 1e-12, "end pos k={k}");
            assert!((ve / W - pve).abs() < 1e-12, "end vel k={k}");
            assert!((xs - ps).abs() < 1e-12, "start pos k={k}");
            assert!((vs / W - pvs).abs() < 1e-12, "start vel k={k}");
        }
    }

    #[test]
    fn hermite_meets_its_ends() {
        let c = hermite(State::new(0.1, 0.2), State::new(-0.3, 0.5), 0.4);
        let (p0, v0, _) = poly_eval(&c, 0.0);
        let (p1, v1, _) = poly_eval(&c, 0.4);
        assert!((p0 - 0.1).abs() < 1e-14 && (v0 - 0.2).abs() < 1e-14);
        assert!((p1 + 0.3).abs() < 1e-14 && (v1 - 0.5).abs() < 1e-13);
    }
}
