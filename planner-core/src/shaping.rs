//! ZMP shaping: preview-control gains (computed once, `no_std`) and the incremental compensator.
//!
//! After a footstep modification the analytic plan carries a ZMP fluctuation `Δp(t)`, the
//! deviation of its ZMP from the ideal one (paper §IV-B, Fig. 5). A compensator driven by
//! preview control (Kajita et al., ICRA 2003) starts from a **zero state** at the modification,
//! takes `Δp` as its ZMP reference, and its COG `x_c` and ZMP `p_c` are subtracted from the
//! analytic pattern: the shaped ZMP is `p_ideal + (Δp − p_c)`, and the shaped COG `x − x_c`
//! still satisfies the pendulum equation because the compensator obeys the same cart-table
//! dynamics. The zero initial state keeps the shaped COG position, velocity and acceleration
//! (hence ZMP) continuous at the modification.
//!
//! # The cart-table model
//! One horizontal coordinate, control period `dt` (one tick), state `X = [x, ẋ, ẍ]ᵀ` (COG
//! position, velocity, acceleration), input `u` = COG jerk, held constant over a tick:
//!
//! ```text
//! X(k+1) = A X(k) + B u(k),   A = ⎡1 dt dt²/2⎤   B = ⎡dt³/6⎤
//!                                 ⎢0 1  dt   ⎥       ⎢dt²/2⎥
//!                                 ⎣0 0  1    ⎦       ⎣dt   ⎦
//! p(k)   = C X(k),            C = [1, 0, −z_c/g]      (ZMP of the cart-table, p = x − z_c ẍ / g)
//! ```
//!
//! `z_c` is the COG height, `g` gravity, `ω = √(g/z_c)`. Defaults: HRP-2, `dt = 5 ms`,
//! `z_c = 0.814 m`, `g = 9.8 m/s²`, weights `Q_e = 1` (ZMP error), `R = 1e-6` (jerk), preview
//! `N_L = 320` ticks (1.6 s; the const generic `NL`).
//!
//! # The two laws
//! Both are written in one form, which is what [`PreviewGains`] stores and [`Compensator`]
//! runs (`r` is the reference, `e(i) = C X(i) − r(i)` the ZMP error):
//!
//! ```text
//! u(k) = −G_i Σ_{i=0}^{k} e(i) − K X(k) + Σ_{j=1}^{N_L} f_j r(k+j) + f_∞ r(k+N_L)
//! ```
//!
//! **[`Law::FromRest`]** (the planner's law): the LQ tracking law that is optimal from a given
//! initial state `X(0)` (here zero) for a previewed reference:
//!
//! ```text
//! minimise J = Σ_{k≥0} Q_e (C X(k) − r(k))² + R u(k)²      over u(0), u(1), …
//! ```
//!
//! With `Q = Cᵀ Q_e C` and `P` the stabilising solution of the discrete algebraic Riccati
//! equation (DARE)
//!
//! ```text
//! P = Aᵀ P A + Q − Aᵀ P B (R + Bᵀ P B)⁻¹ Bᵀ P A,
//! ```
//!
//! dynamic programming with the value function `V_k(X) = Xᵀ P X − 2 Xᵀ s_k + const` gives
//! `s_k = Cᵀ Q_e r(k) + A_cᵀ s_{k+1}` and
//!
//! ```text
//! G_i = 0,   K = (R + BᵀPB)⁻¹ BᵀPA,   A_c = A − B K,
//! f_j = (R + BᵀPB)⁻¹ Bᵀ (A_cᵀ)^{j−1} Cᵀ Q_e          (j = 1 … N_L),
//! f_∞ = Σ_{j>N_L} f_j = (R + BᵀPB)⁻¹ Bᵀ (I − A_cᵀ)⁻¹ (A_cᵀ)^{N_L} Cᵀ Q_e.
//! ```
//!
//! Index convention: `u(k)` is applied over tick `k → k+1`; it sees `r(k+1) … r(k+N_L)` and
//! **not** `r(k)`, because `e(k)` is already fixed by `X(k)`. Beyond the preview the reference
//! is taken as held at `r(k+N_L)` (the `f_∞` term): the law is then exactly optimal at every
//! tick for any reference that is constant from `k+N_L` on, in particular for one that is zero
//! there (the shaping case: `f_∞` drops out) and for a step. Without `f_∞` a step would be
//! tracked with a 0.8 % steady error (`f_∞/K_0 = 6.46/800`). Identity used as a test:
//! `Σ_{j≥1} f_j = K_0` (`X = [r, 0, 0]` is an equilibrium with zero error).
//!
//! **[`Law::Integral`]** (kept for comparison): Kajita's law, from Katayama et al. (1985): the
//! LQ law of the incremental system with augmented state `X̃ = [e(k); ΔX(k)]`, input `Δu(k)`,
//!
//! ```text
//! Ã = ⎡1 CA⎤  B̃ = ⎡CB⎤  Q̃ = diag(Q_e, 0, 0, 0),  minimise Σ Q_e e(k)² + R Δu(k)²,
//!     ⎣0 A ⎦      ⎣B ⎦
//! H̃ = R + B̃ᵀP̃B̃,  G_i = B̃ᵀP̃Ĩ/H̃,  K = G_x = B̃ᵀP̃F̃/H̃  (Ĩ = [1,0,0,0]ᵀ, F̃ = [CA; A]),
//! f_j = −G_p(j) = B̃ᵀ (Ã_cᵀ)^{j−1} P̃ Ĩ / H̃,   Ã_c = Ã − B̃ B̃ᵀP̃Ã / H̃,   f_∞ = 0.
//! ```
//!
//! Summing the incremental law from `k = 0` assumes the system was at rest **and the previewed
//! reference was zero one tick earlier**: a reference that is non-zero from the first sample is
//! then seen as a step that arrived without preview, and the law answers with a large jerk.
//!
//! # Which law the planner uses, and why
//! [`Law::FromRest`]: the shaping problem is exactly "start at zero, follow `Δp`", which is the
//! cost that law minimises; it needs no integrator state, and the compensator returns to zero
//! state once the reference is back to zero (the closed loop `A_c` is stable), so the shaped
//! pattern rejoins the analytic one. Measured with the defaults (`tests/shaping.rs`, f64):
//!
//! * gains: the recursive law equals an independent batch least-squares optimum over 1000
//!   ticks to 1.4e-12 (relative, all of the first 100 controls); `K` equals a doubling and a
//!   Newton–Kleinman solution of the DARE to 3e-12; `K = [799.96, 472.66, 73.19]`,
//!   `f_1 = −265.8`, `f_{N_L}/max|f| = 4.3e-4`; the slowest closed-loop pole is
//!   `0.98280 ≈ e^{−ω dt}`, the mirror of the cart-table's non-minimum-phase zero.
//! * step `r = 1` from the first sample: `FromRest` has max |u| = 800 (= `K_0`), no overshoot
//!   above the step, a dip to −0.79 (the ZMP must first move away to accelerate the COG), and
//!   an error that follows the minimum-energy curve `2e^{−ωt}` (0.065 at 1 s, < 1e-3 from
//!   2.2 s). `Integral` from rest: max |u| = 7.3e4, ZMP spike to −33.6 on the second tick and
//!   overshoot to 4.3, error energy 28× larger: the spike the design notes warn about.
//! * the quartic fluctuation `Δp = 0.32 s²(1−s)²` over 0.7 s from tick 0 (peak 20 mm): residual
//!   `Δp − p_c` peak 15.4 mm, RMS 3.83 mm over 3 s (reduction ×1.30 peak, ×1.61 RMS);
//!   `Integral`: residual peak 297 mm.
//!
//! # What no compensator from rest can do
//! The divergent component `ξ = x + ẋ/ω` of the compensator obeys `ξ̇ = ω(ξ − p_c)`. With
//! `ξ(0) = 0` and `ξ` bounded, `∫₀^∞ e^{−ωt} p_c(t) dt = 0`, so every such compensator leaves a
//! residual with `∫ e^{−ωt} (Δp − p_c) dt = I = ∫ e^{−ωt} Δp dt`; the smallest residual energy
//! under that constraint is `2ω I²`, reached by the residual `2ωI e^{−ωt}`. For the quartic above
//! this bound is an RMS of 3.74 mm over 3 s (a residual starting at 17 mm): `FromRest` is
//! within 2.3 % of it. A fluctuation that starts at the current tick can therefore only be
//! reduced a little by shaping from rest; the same fluctuation known 0.2 s (0.5 s) ahead is
//! reduced ×2.6 (×7.3) in peak. Larger `R` trades reduction for a smoother residual (`R = 1e-4`:
//! ×1.38 peak, ×1.28 RMS, largest residual change per tick 0.64 mm instead of 5.9 mm).
//!
//! # Gains, computed once
//! [`PreviewGains::compute`] solves the DARE by the fixed-point (Riccati difference) iteration
//! `P ← AᵀPA + Q − AᵀPB (R+BᵀPB)⁻¹ BᵀPA` from `P = Q`, until the largest change of an entry
//! is at most `tolerance × max |P|`, or fails with [`GainError::NotConverged`] after
//! `max_iterations`, or [`GainError::NonFinite`] (never panics). The iteration contracts like
//! `ρ(A_c)² ≈ 0.966` per step; with the defaults it takes 1103 iterations (3×3) and 1335 (4×4),
//! about 50 µs on a host core. The gains are always computed in `f64` (software floating point
//! on a single-precision FPU: a one-off cost at start-up) and then rounded to `T`.
//!
//! # The incremental compensator and its moment tables
//! The reference is a sum of at most `P` polynomial pieces ([`Piece`]); piece `i` covers the
//! ticks `k0 ≤ k < k0 + n` (ticks counted from the last [`Compensator::reset`]) and is zero
//! outside:
//!
//! ```text
//! r_i(k) = Σ_{m=0}^{4} c_m s^m,     s = (k − k0) / n  ∈ [0, 1).
//! ```
//!
//! (For an interval of duration `D` that is not a whole number `n` of ticks, rescale the
//! coefficients of `p(τ/D)` by `c'_m = c_m (n·dt/D)^m`.)
//!
//! The preview sum `S(k) = Σ_{j=1}^{N_L} f_j r(k+j)` is evaluated in closed form. With
//! `σ_j = j/N_L`, the piece at tick `k+j` is `s = a + b σ_j`, `a = (k − k0)/n`, `b = N_L/n`, so
//! a Taylor shift of the coefficients to `a` (`c(a + t) = Σ e_q t^q`, 10 multiply-adds) gives
//! `r_i(k+j) = Σ_q e_q b^q σ_j^q`, and
//!
//! ```text
//! Σ_{j=lo}^{hi} f_j r_i(k+j) = Σ_{q=0}^{4} e_q b^q (M_q[hi] − M_q[lo−1]),
//! M_q[J] = Σ_{j=1}^{J} f_j σ_j^q        (the moment tables, built once with the gains),
//! lo = max(1, k0 − k),  hi = min(N_L, k0 + n − 1 − k).
//! ```
//!
//! Precision. The tables are stored as double-length values (leading part + remainder, accumulated
//! with two-sum), so `M_q[hi] − M_q[lo−1]` keeps the precision of `T` relative to the difference
//! itself. What remains is that the moment form extrapolates a piece from its own ticks back to `j
//! = 0`: a piece of `n` ticks `k0 − k` ticks ahead loses about `((k0 − k)/n)⁴` in relative
//! precision, damped by the small `|f_j|` there. Overlaps of at most [`DIRECT_MAX`] (16) ticks at
//! a piece's start (`k0 > k`) are therefore summed directly, by forward differences from `s = 0`
//! (four additions per tap). A piece that has started (`k0 ≤ k`, so `0 ≤ a < 1`) is never
//! extrapolated: it always takes the moment form, however short its overlap (measured: ≤ 2.5e-16
//! in `f64`, ≤ 1.2e-7 in `f32`, relative to the scale below). Measured against the `f64` direct
//! sum, relative to `Σ|f_j| · max|r|`, over every distance 1…330 ticks: `f64` ≤ 2.2e-13 (pieces of
//! 17 ticks, the worst), ≤ 8e-16 for 140 ticks; `f32` ≤ 1.0e-4 (17 ticks), 3.9e-7 (140).
//! On a 4-piece reference the `f32` compensator stays within 6.2e-8 m of ZMP of the `f64` one.
//!
//! Cost of [`Compensator::step`], per piece that overlaps the window: closed form 53 flops (`a`,
//! `b`: 2; Taylor shift: 20; five double-length table differences: 15; Horner in `b` with the
//! differences: 15; accumulate: 1) or, for a short overlap at a piece's start, at most 19 + 16 × 6
//! = 115 flops by forward differences; plus 8 flops per piece for each of `r(k)` and `r(k+N_L)`.
//! Common part (ZMP, error, feedback, state update): 26 flops. With `P = 4` pieces: 302 flops per
//! call with long pieces, 550 in the worst case (four short overlaps), independent of `N_L`; no
//! division, no buffer refill. Measured on the host (release build): 51 ns per call with 4 long
//! pieces (f64), 41 ns (f32).
//!
//! Memory: `PreviewGains<T, NL>` holds `11·NL` scalars (the gains and ten tables, the five
//! remainder tables in `f32`): 22 KB in `f64`, 14 KB in `f32` for `NL = 320`. Share one between the x and y compensators (they take
//! it by reference on every step), and build it in place with [`PreviewGains::zeroed`] +
//! [`PreviewGains::compute`] to keep it off the stack.

use crate::lipm::{Poly, Sample, N_COEFFS};
use crate::real::Real;
use nalgebra::{SMatrix, SVector};

/// Default control period \[s\] (5 ms).
pub const DEFAULT_DT: f64 = 0.005;
/// Default preview length in ticks (1.6 s at 5 ms).
pub const DEFAULT_PREVIEW: usize = 320;
/// Default weight of the squared ZMP error.
pub const DEFAULT_QE: f64 = 1.0;
/// Default weight of the squared input (jerk, or jerk increment for [`Law::Integral`]).
pub const DEFAULT_R: f64 = 1e-6;
/// Default cap on the Riccati iterations.
pub const DEFAULT_MAX_ITERATIONS: u32 = 100_000;
/// Default relative convergence threshold of the Riccati iteration.
pub const DEFAULT_TOLERANCE: f64 = 1e-14;
/// Default number of reference pieces a [`Compensator`] holds.
pub const DEFAULT_PIECES: usize = 4;
/// Overlaps of at most this many ticks of a piece that starts inside the preview window are
/// summed directly (by forward differences, four additions per tick) instead of through the
/// moment tables, which would extrapolate the piece back to the window's start.
pub const DIRECT_MAX: usize = 16;
/// Number of moment tables (`σ^0 … σ^4`, one per polynomial coefficient).
pub const MOMENTS: usize = N_COEFFS;

/// The discrete cart-table model of one horizontal coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CartTable {
    /// Control period \[s\].
    pub dt: f64,
    /// COG height \[m\].
    pub z_c: f64,
    /// Gravity \[m/s²\].
    pub g: f64,
}

impl Default for CartTable {
    /// HRP-2: 5 ms, `z_c = 0.814 m`, `g = 9.8 m/s²`.
    fn default() -> Self {
        Self {
            dt: DEFAULT_DT,
            z_c: crate::HRP2_COG_HEIGHT,
            g: crate::GRAVITY,
        }
    }
}

impl CartTable {
    /// The state matrix `A`.
    pub fn a(&self) -> SMatrix<f64, 3, 3> {
        let dt = self.dt;
        SMatrix::<f64, 3, 3>::new(1.0, dt, dt * dt / 2.0, 0.0, 1.0, dt, 0.0, 0.0, 1.0)
    }
    /// The input vector `B` (input: COG jerk).
    pub fn b(&self) -> SVector<f64, 3> {
        let dt = self.dt;
        SVector::<f64, 3>::new(dt * dt * dt / 6.0, dt * dt / 2.0, dt)
    }
    /// The output row `C` (ZMP), as a column vector `Cᵀ = [1, 0, −z_c/g]ᵀ`.
    pub fn c(&self) -> SVector<f64, 3> {
        SVector::<f64, 3>::new(1.0, 0.0, -self.z_c / self.g)
    }
    fn valid(&self) -> bool {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        pos(self.dt) && pos(self.z_c) && pos(self.g)
    }
}

/// Weights and solver settings of the preview controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewConfig {
    /// The plant.
    pub model: CartTable,
    /// Weight `Q_e` of the squared ZMP error \[1/m²\].
    pub qe: f64,
    /// Weight `R` of the squared input.
    pub r: f64,
    /// Cap on the Riccati fixed-point iterations.
    pub max_iterations: u32,
    /// Stop when the largest change of an entry of `P` is at most `tolerance × max |P|`.
    pub tolerance: f64,
}

impl Default for PreviewConfig {
    /// HRP-2 values: `Q_e = 1`, `R = 1e-6`, [`CartTable::default`].
    fn default() -> Self {
        Self {
            model: CartTable::default(),
            qe: DEFAULT_QE,
            r: DEFAULT_R,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            tolerance: DEFAULT_TOLERANCE,
        }
    }
}

#[cfg(feature = "robot")]
impl<T: crate::robot::Literal, const NL: usize> PreviewGains<T, NL> {
    /// These gains as a Rust constant expression ([`PreviewGains::from_parts`], every float by
    /// its bits), for a build script (feature `robot`, std).
    pub fn source(&self) -> std::string::String {
        use core::fmt::Write;
        let mut s = std::string::String::new();
        let f = |v: T| v.literal();
        let list = |vs: &[T]| {
            let items: std::vec::Vec<_> = vs.iter().map(|&v| f(v)).collect();
            std::format!("[{}]", items.join(", "))
        };
        let made_for = |vs: &[f64; 5]| {
            let items: std::vec::Vec<_> = vs
                .iter()
                .map(|&v| crate::robot::Literal::literal(v))
                .collect();
            std::format!("[{}]", items.join(", "))
        };
        let tables = |t: &[[T; NL]; MOMENTS]| {
            let rows: std::vec::Vec<_> = t.iter().map(|r| list(r)).collect();
            std::format!("[{}]", rows.join(",\n"))
        };
        let tables_f32 = |t: &[[f32; NL]; MOMENTS]| {
            let rows: std::vec::Vec<_> = t
                .iter()
                .map(|r| {
                    let items: std::vec::Vec<_> = r
                        .iter()
                        .map(|&v| crate::robot::Literal::literal(v))
                        .collect();
                    std::format!("[{}]", items.join(", "))
                })
                .collect();
            std::format!("[{}]", rows.join(",\n"))
        };
        let law = match self.law {
            Law::FromRest => "FromRest",
            Law::Integral => "Integral",
        };
        let _ = write!(
            s,
            "::planner_core::shaping::PreviewGains::from_parts(\n\
             ::planner_core::shaping::Law::{law},\n{},\n{},\n{},\n{},\n{},\n{},\n{},\n{},\n{},\n{})",
            made_for(&self.made_for),
            list(&self.dt),
            f(self.zg),
            f(self.k_int),
            list(&self.k_state),
            f(self.tail),
            list(&self.preview),
            tables(&self.moments),
            tables_f32(&self.moments_lo),
            self.iterations
        );
        s
    }
}

/// A tick count as `i32` (converted to `T` exactly by the hardware's 32-bit conversion; an
/// `i64` or `u32` would take a software routine on the Cortex-M). Counts here are within a
/// window (well inside 2³¹); beyond that they saturate.
#[inline]
fn tick_i32(x: u32) -> i32 {
    i32::try_from(x).unwrap_or(i32::MAX)
}

/// `Σ_i f_i g(i)` over the taps `f` (tap `i` at `s = i h`) for the piece `g(i) = Σ_q c_q (i h)^q`,
/// by forward differences: with `g_q = c_q h^q`, the differences at `i = 0` are
/// `Δ⁰ = g_0`, `Δ¹ = g_1 + g_2 + g_3 + g_4`, `Δ² = 2g_2 + 6g_3 + 14g_4`, `Δ³ = 6g_3 + 36g_4`,
/// `Δ⁴ = 24g_4`, and each tap costs four additions. Rounding grows about linearly with the
/// number of taps (at most [`DIRECT_MAX`]), each `|Δ^m|` being about `|g^{(m)}| h^m` with
/// `i h ≤ 1` over the piece: within `DIRECT_MAX · ε · Σ|c_q|`.
#[inline]
fn forward_sum<T: Real>(c: &Poly<T>, h: T, taps: &[T]) -> T {
    let h2 = h * h;
    let (g1, g2, g3, g4) = (c[1] * h, c[2] * h2, c[3] * (h2 * h), c[4] * (h2 * h2));
    let mut d = [
        c[0],
        g1 + g2 + g3 + g4,
        T::of(2.0) * g2 + T::of(6.0) * g3 + T::of(14.0) * g4,
        T::of(6.0) * g3 + T::of(36.0) * g4,
    ];
    let d4 = T::of(24.0) * g4;
    let mut acc = T::ZERO;
    for &f in taps {
        acc += f * d[0];
        d[0] += d[1];
        d[1] += d[2];
        d[2] += d[3];
        d[3] += d4;
    }
    acc
}

/// Which preview-control law the gains implement (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Law {
    /// LQ tracking optimal from the given (zero) initial state: `G_i = 0`. The planner's law.
    FromRest,
    /// Kajita/Katayama integral action on the incremental system (comparison only).
    Integral,
}

/// Why gains could not be computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum GainError {
    /// `dt`, `z_c`, `g`, `Q_e`, `R` or the tolerance is not finite and positive, or
    /// `max_iterations` is zero.
    BadConfig,
    /// The Riccati iteration did not meet the tolerance within `max_iterations`.
    NotConverged,
    /// The Riccati iteration or the gains produced a NaN or an infinity.
    NonFinite,
}

/// Why a reference could not be set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PieceError {
    /// More pieces than the compensator holds; the previous reference is kept.
    TooManyPieces,
    /// Piece `index` has zero ticks; the previous reference is kept.
    Empty {
        /// 0-based piece index.
        index: u8,
    },
    /// Piece `index` has a coefficient that is not finite; the previous reference is kept.
    NonFinite {
        /// 0-based piece index.
        index: u8,
    },
}

/// Solves the DARE `P = AᵀPA + Q − AᵀPB (r + BᵀPB)⁻¹ BᵀPA` (single input) by fixed-point
/// iteration from `P = Q`.
///
/// Returns `P` and the number of iterations. Stops when the largest change of an entry is at
/// most `tolerance × max|P|`; fails with [`GainError::NotConverged`] after `max_iterations`,
/// or [`GainError::NonFinite`] as soon as an entry is not finite.
pub fn solve_dare<const S: usize>(
    a: &SMatrix<f64, S, S>,
    b: &SVector<f64, S>,
    q: &SMatrix<f64, S, S>,
    r: f64,
    max_iterations: u32,
    tolerance: f64,
) -> Result<(SMatrix<f64, S, S>, u32), GainError> {
    let at = a.transpose();
    let mut p = *q;
    for it in 1..=max_iterations {
        let pb = p * b;
        let h = r + b.dot(&pb);
        // Bᵀ P A as a column: Aᵀ (P B).
        let atpb = at * pb;
        let mut next = at * p * a + q - atpb * atpb.transpose() / h;
        // Keep P exactly symmetric.
        next = (next + next.transpose()) * 0.5;
        let mut change = 0.0_f64;
        let mut scale = 0.0_f64;
        for (n, o) in next.iter().zip(p.iter()) {
            if !n.is_finite() {
                return Err(GainError::NonFinite);
            }
            change = Real::max(change, Real::abs(*n - *o));
            scale = Real::max(scale, Real::abs(*n));
        }
        p = next;
        if change <= tolerance * scale {
            return Ok((p, it));
        }
    }
    Err(GainError::NotConverged)
}

/// Preview-control gains in the form
/// `u(k) = −G_i Σ_{i≤k} e(i) − K X(k) + Σ_{j=1}^{NL} f_j r(k+j) + f_∞ r(k+NL)`, with the
/// moment tables `M_q[J] = Σ_{j=1}^{J} f_j (j/NL)^q` of the closed-form preview sum.
///
/// `11·NL` scalars (22 KB for `f64`, 14 KB for `f32`, `NL = 320`): compute once and share
/// between the x and y compensators (they take the gains by reference on every step).
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewGains<T, const NL: usize> {
    law: Law,
    /// What the gains were computed for: `dt, z_c, g, Q_e, R` (zero: not computed).
    made_for: [f64; 5],
    /// `dt, dt²/2, dt³/6, z_c/g` in `T`.
    dt: [T; 3],
    zg: T,
    k_int: T,
    k_state: [T; 3],
    tail: T,
    preview: [T; NL],
    /// `moments[q][J−1] + moments_lo[q][J−1] = M_q[J]` (a double-length value: the leading
    /// part and the rounding remainder). The remainder is stored in `f32` whatever `T`: it is
    /// below half a unit in the last place of the leading part, so its own rounding to `f32`
    /// (2⁻²⁴ of it) is far below the precision of `T` (for `f64` it halves the tables' flash).
    moments: [[T; NL]; MOMENTS],
    moments_lo: [[f32; NL]; MOMENTS],
    iterations: u32,
}

impl<T: Real, const NL: usize> PreviewGains<T, NL> {
    /// All-zero gains (a placeholder to [`compute`](Self::compute) into in place, e.g. in a
    /// `static`, without moving the tables through the stack).
    pub const fn zeroed() -> Self {
        Self {
            law: Law::FromRest,
            made_for: [0.0; 5],
            dt: [T::ZERO; 3],
            zg: T::ZERO,
            k_int: T::ZERO,
            k_state: [T::ZERO; 3],
            tail: T::ZERO,
            preview: [T::ZERO; NL],
            moments: [[T::ZERO; NL]; MOMENTS],
            moments_lo: [[0.0; NL]; MOMENTS],
            iterations: 0,
        }
    }

    /// Computes the gains of `law` for `config` (see [`compute`](Self::compute)).
    pub fn new(config: &PreviewConfig, law: Law) -> Result<Self, GainError> {
        let mut g = Self::zeroed();
        g.compute(config, law)?;
        Ok(g)
    }

    /// Computes the gains of `law` for `config` in place (in `f64`, then rounded to `T`).
    /// On error `self` is left unchanged.
    pub fn compute(&mut self, config: &PreviewConfig, law: Law) -> Result<(), GainError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !config.model.valid()
            || !pos(config.qe)
            || !pos(config.r)
            || !pos(config.tolerance)
            || config.max_iterations == 0
        {
            return Err(GainError::BadConfig);
        }
        let m = &config.model;
        let (a, b, c) = (m.a(), m.b(), m.c());
        let mut f = [0.0_f64; NL];
        let (k_int, k_state, tail, iterations) = match law {
            Law::FromRest => {
                let q = c * c.transpose() * config.qe;
                let (p, it) = solve_dare(
                    &a,
                    &b,
                    &q,
                    config.r,
                    config.max_iterations,
                    config.tolerance,
                )?;
                let pb = p * b;
                let h = config.r + b.dot(&pb);
                let k = a.transpose() * pb / h;
                let ac_t = (a - b * k.transpose()).transpose();
                // f_j = Bᵀ v_j / h, v_1 = Cᵀ Q_e, v_{j+1} = A_cᵀ v_j.
                let mut v = c * config.qe;
                for fj in f.iter_mut() {
                    *fj = b.dot(&v) / h;
                    v = ac_t * v;
                }
                // Σ_{j>NL} f_j = Bᵀ (I − A_cᵀ)⁻¹ (A_cᵀ)^{NL} Cᵀ Q_e / h.
                let inv = (SMatrix::<f64, 3, 3>::identity() - ac_t)
                    .try_inverse()
                    .ok_or(GainError::NonFinite)?;
                let tail = b.dot(&(inv * v)) / h;
                (0.0, [k[0], k[1], k[2]], tail, it)
            }
            Law::Integral => {
                let ca = (c.transpose() * a).transpose();
                let cb = c.dot(&b);
                let mut at = SMatrix::<f64, 4, 4>::zeros();
                at[(0, 0)] = 1.0;
                for i in 0..3 {
                    at[(0, 1 + i)] = ca[i];
                    for j in 0..3 {
                        at[(1 + i, 1 + j)] = a[(i, j)];
                    }
                }
                let bt = SVector::<f64, 4>::new(cb, b[0], b[1], b[2]);
                let mut qt = SMatrix::<f64, 4, 4>::zeros();
                qt[(0, 0)] = config.qe;
                let (p, it) = solve_dare(
                    &at,
                    &bt,
                    &qt,
                    config.r,
                    config.max_iterations,
                    config.tolerance,
                )?;
                let pb = p * bt;
                let h = config.r + bt.dot(&pb);
                // [G_i, G_x] = B̃ᵀ P̃ Ã / h.
                let kt = at.transpose() * pb / h;
                let ac_t = (at - bt * kt.transpose()).transpose();
                // f_j = −G_p(j) = B̃ᵀ w_j / h, w_1 = P̃ Ĩ, w_{j+1} = Ã_cᵀ w_j.
                let mut w: SVector<f64, 4> = p.column(0).into_owned();
                for fj in f.iter_mut() {
                    *fj = bt.dot(&w) / h;
                    w = ac_t * w;
                }
                (kt[0], [kt[1], kt[2], kt[3]], 0.0, it)
            }
        };
        if !k_int.is_finite()
            || !tail.is_finite()
            || k_state.iter().chain(f.iter()).any(|v| !v.is_finite())
        {
            return Err(GainError::NonFinite);
        }
        self.fill_preview(&f);
        self.law = law;
        self.made_for = [m.dt, m.z_c, m.g, config.qe, config.r];
        let dt = m.dt;
        self.dt = [T::of(dt), T::of(dt * dt / 2.0), T::of(dt * dt * dt / 6.0)];
        self.zg = T::of(m.z_c / m.g);
        self.k_int = T::of(k_int);
        self.k_state = k_state.map(T::of);
        self.tail = T::of(tail);
        self.iterations = iterations;
        Ok(())
    }

    /// Stores the preview gains and their prefix moment tables, accumulated with compensated
    /// (two-sum) addition so that each entry is a double-length value `hi + lo`.
    fn fill_preview(&mut self, f: &[f64; NL]) {
        let inv = if NL > 0 { 1.0 / NL as f64 } else { 0.0 };
        let mut hi = [0.0_f64; MOMENTS];
        let mut lo = [0.0_f64; MOMENTS];
        for (j, &fj) in f.iter().enumerate() {
            let sigma = (j + 1) as f64 * inv;
            let mut w = fj;
            for q in 0..MOMENTS {
                // Knuth's two-sum: hi + w = s + err exactly.
                let s = hi[q] + w;
                let bb = s - hi[q];
                let err = (hi[q] - (s - bb)) + (w - bb);
                hi[q] = s;
                lo[q] += err;
                let lead = T::of(hi[q]);
                self.moments[q][j] = lead;
                self.moments_lo[q][j] = ((hi[q] - lead.f64()) + lo[q]) as f32;
                w *= sigma;
            }
            self.preview[j] = T::of(fj);
        }
    }

    /// The law these gains implement.
    pub fn law(&self) -> Law {
        self.law
    }
    /// `G_i`, the gain on the error sum (0 for [`Law::FromRest`]).
    pub fn integral_gain(&self) -> T {
        self.k_int
    }
    /// `K` (or `G_x`), the state-feedback gain on `[x, ẋ, ẍ]`.
    pub fn state_gain(&self) -> [T; 3] {
        self.k_state
    }
    /// `f_∞ = Σ_{j>NL} f_j`, the weight of the held reference `r(k + NL)` beyond the preview
    /// ([`Law::FromRest`]; 0 for [`Law::Integral`]).
    pub fn tail_gain(&self) -> T {
        self.tail
    }
    /// `f_1 … f_NL`: `preview()[j − 1] = f_j`, the weight of `r(k + j)` in `u(k)`.
    pub fn preview(&self) -> &[T; NL] {
        &self.preview
    }
    /// `f_lo … f_hi` (1 ≤ lo ≤ hi ≤ NL; empty otherwise).
    #[inline]
    fn preview_range(&self, lo: u32, hi: u32) -> &[T] {
        let lo = (lo as usize).wrapping_sub(1);
        self.preview.get(lo..hi as usize).unwrap_or(&[])
    }
    /// The prefix moment table `M_q[J] = Σ_{j=1}^{J} f_j (j/NL)^q` at index `J − 1`: its
    /// leading part and its remainder, in `f32` (`M_q[J] ≈ lead[J−1] + rest[J−1]` to about
    /// twice the precision of `T`). `q > 4` returns the last table.
    pub fn moment(&self, q: usize) -> (&[T; NL], &[f32; NL]) {
        let q = q.min(MOMENTS - 1);
        (&self.moments[q], &self.moments_lo[q])
    }
    /// Riccati iterations used.
    pub fn iterations(&self) -> u32 {
        self.iterations
    }
    /// What these gains were computed for: `[dt, z_c, g, Q_e, R]` (all zero for
    /// [`zeroed`](Self::zeroed) gains).
    pub fn made_for(&self) -> [f64; 5] {
        self.made_for
    }

    /// Whether these are the gains of `law` for `config` (its plant and weights; the solver
    /// settings aside).
    pub fn are_for(&self, config: &PreviewConfig, law: Law) -> bool {
        let m = &config.model;
        self.law == law && self.made_for == [m.dt, m.z_c, m.g, config.qe, config.r]
    }

    /// Copies `other` into `self` in place (the tables are 22 KB: no temporary copy).
    pub fn copy_from(&mut self, other: &Self) {
        self.law = other.law;
        self.made_for = other.made_for;
        self.dt = other.dt;
        self.zg = other.zg;
        self.k_int = other.k_int;
        self.k_state = other.k_state;
        self.tail = other.tail;
        self.preview.copy_from_slice(&other.preview);
        for q in 0..MOMENTS {
            self.moments[q].copy_from_slice(&other.moments[q]);
            self.moments_lo[q].copy_from_slice(&other.moments_lo[q]);
        }
        self.iterations = other.iterations;
    }

    /// Gains from their parts, as `PreviewGains::source` (feature `robot`) writes them: for tables
    /// computed before the program runs (the firmware's build script computes them from the
    /// robot file and compiles them into flash). Anything else should call
    /// [`compute`](Self::compute); [`Gait::with_gains`](crate::gait::Gait::with_gains) checks
    /// what the gains were made for.
    #[allow(clippy::too_many_arguments)]
    pub const fn from_parts(
        law: Law,
        made_for: [f64; 5],
        dt: [T; 3],
        zg: T,
        k_int: T,
        k_state: [T; 3],
        tail: T,
        preview: [T; NL],
        moments: [[T; NL]; MOMENTS],
        moments_lo: [[f32; NL]; MOMENTS],
        iterations: u32,
    ) -> Self {
        Self {
            law,
            made_for,
            dt,
            zg,
            k_int,
            k_state,
            tail,
            preview,
            moments,
            moments_lo,
            iterations,
        }
    }

    /// `z_c / g` \[s²\].
    pub fn zmp_factor(&self) -> T {
        self.zg
    }
    /// `M_q[hi] − M_q[lo − 1]` for `1 ≤ lo ≤ hi ≤ NL`, from the table indices `u = hi − 1`
    /// and `l = lo − 2` (`None` for `lo = 1`: `M_q[0] = 0`). Indices are clamped to the table,
    /// which also lets the compiler drop the bounds checks.
    #[inline]
    fn moment_range(&self, q: usize, u: usize, l: Option<usize>) -> T {
        let last = NL.saturating_sub(1);
        let at = |t: &[T; NL], i: usize| t.get(i.min(last)).copied().unwrap_or(T::ZERO);
        let at_lo = |t: &[f32; NL], i: usize| t.get(i.min(last)).copied().unwrap_or(0.0);
        let (lead, rest) = (&self.moments[q], &self.moments_lo[q]);
        match l {
            // Leading parts first (exact when they are within a factor 2), then the
            // remainders (their difference in `f32`: its rounding is 2⁻²⁴ of a remainder).
            Some(l) => (at(lead, u) - at(lead, l)) + T::of_f32(at_lo(rest, u) - at_lo(rest, l)),
            None => at(lead, u) + T::of_f32(at_lo(rest, u)),
        }
    }
}

/// One polynomial piece of the reference: `r(k) = Σ c_m s^m`, `s = (k − start)/ticks`, for
/// `start ≤ k < start + ticks` (ticks counted from the last [`Compensator::reset`]); zero
/// elsewhere.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Piece<T> {
    /// First tick of the piece.
    pub start: u32,
    /// Number of ticks (≥ 1); also the normalisation of `s`.
    pub ticks: u32,
    /// `c_0 … c_4` \[m\].
    pub coeffs: Poly<T>,
}

impl<T: Real> Piece<T> {
    /// A piece from its first tick, its length in ticks and its coefficients.
    pub fn new(start: u32, ticks: u32, coeffs: Poly<T>) -> Self {
        Self {
            start,
            ticks,
            coeffs,
        }
    }
    /// The piece's value at tick `k` (zero outside).
    pub fn value(&self, k: u32) -> T {
        self.value_with(k, T::ONE / T::of(f64::from(self.ticks)))
    }
    /// [`value`](Self::value) with `1/ticks` precomputed (Horner, value only).
    #[inline]
    fn value_with(&self, k: u32, inv_ticks: T) -> T {
        if k < self.start || k - self.start >= self.ticks {
            return T::ZERO;
        }
        let s = T::of_i32(tick_i32(k - self.start)) * inv_ticks;
        let [c0, c1, c2, c3, c4] = self.coeffs;
        (((c4 * s + c3) * s + c2) * s + c1) * s + c0
    }
}

/// What the compensator produces for one tick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Compensation<T> {
    /// The tick this sample belongs to (ticks since the last reset).
    pub tick: u32,
    /// Compensating COG position `x_c` \[m\].
    pub cog: T,
    /// Compensating COG velocity \[m/s\].
    pub cog_vel: T,
    /// Compensating COG acceleration \[m/s²\].
    pub cog_acc: T,
    /// Compensating ZMP `p_c = x_c − (z_c/g) ẍ_c` \[m\].
    pub zmp: T,
    /// The reference `r(k)` at this tick \[m\].
    pub reference: T,
    /// The jerk `u(k)` applied from this tick to the next \[m/s³\].
    pub jerk: T,
}

impl<T: Real> Compensation<T> {
    /// As a [`Sample`] (`zmp_vel = ẋ_c − (z_c/g) u`, the ZMP slope over the coming tick), to
    /// subtract from the analytic pattern.
    pub fn sample(&self, zmp_factor: T) -> Sample<T> {
        Sample {
            cog: self.cog,
            cog_vel: self.cog_vel,
            cog_acc: self.cog_acc,
            zmp: self.zmp,
            zmp_vel: self.cog_vel - zmp_factor * self.jerk,
        }
    }
}

/// The incremental shaping compensator: one tick per [`step`](Self::step), fixed cost, no
/// buffers. Holds at most `P` reference pieces; the gains are passed in on every step so that
/// both planes share one [`PreviewGains`].
#[derive(Clone, Debug, PartialEq)]
pub struct Compensator<T, const P: usize = DEFAULT_PIECES> {
    state: [T; 3],
    error_sum: T,
    tick: u32,
    pieces: heapless::Vec<Piece<T>, P>,
    /// `1 / ticks` of each piece.
    inv_ticks: [T; P],
}

impl<T: Real, const P: usize> Default for Compensator<T, P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const P: usize> Compensator<T, P> {
    /// At rest, tick 0, no reference.
    pub const fn new() -> Self {
        Self {
            state: [T::ZERO; 3],
            error_sum: T::ZERO,
            tick: 0,
            pieces: heapless::Vec::new(),
            inv_ticks: [T::ZERO; P],
        }
    }

    /// Zero state, zero error sum, tick 0; the reference pieces are dropped.
    pub fn reset(&mut self) {
        self.state = [T::ZERO; 3];
        self.error_sum = T::ZERO;
        self.tick = 0;
        self.pieces.clear();
    }

    /// Replaces the reference (ticks relative to the last reset; see [`tick`](Self::tick)).
    /// The state is kept. On error the previous reference is kept.
    pub fn set_pieces(&mut self, pieces: &[Piece<T>]) -> Result<(), PieceError> {
        if pieces.len() > P {
            return Err(PieceError::TooManyPieces);
        }
        for (i, p) in pieces.iter().enumerate() {
            let index = u8::try_from(i).unwrap_or(u8::MAX);
            if p.ticks == 0 {
                return Err(PieceError::Empty { index });
            }
            if p.coeffs.iter().any(|c| !c.is_finite()) {
                return Err(PieceError::NonFinite { index });
            }
        }
        self.pieces.clear();
        for (p, inv) in pieces.iter().zip(self.inv_ticks.iter_mut()) {
            // Cannot fail: the length was checked above.
            let _ = self.pieces.push(*p);
            *inv = T::ONE / T::of(f64::from(p.ticks));
        }
        Ok(())
    }

    /// The reference pieces.
    pub fn pieces(&self) -> &[Piece<T>] {
        &self.pieces
    }
    /// The next tick [`step`](Self::step) will produce.
    pub fn tick(&self) -> u32 {
        self.tick
    }
    /// The state `[x_c, ẋ_c, ẍ_c]` at the current tick.
    pub fn state(&self) -> [T; 3] {
        self.state
    }
    /// `Σ e(i)` over the ticks done so far (used by [`Law::Integral`] only).
    pub fn error_sum(&self) -> T {
        self.error_sum
    }

    /// The reference `r(k)` (sum of the pieces at tick `k`).
    pub fn reference(&self, k: u32) -> T {
        self.pieces
            .iter()
            .zip(self.inv_ticks.iter())
            .fold(T::ZERO, |acc, (p, &inv)| acc + p.value_with(k, inv))
    }

    /// `Σ_{j=1}^{NL} f_j r(k + j)` in closed form from the moment tables (`O(P)`, not `O(NL)`);
    /// overlaps of at most [`DIRECT_MAX`] ticks at a piece's start are summed directly.
    pub fn preview_sum<const NL: usize>(&self, gains: &PreviewGains<T, NL>, k: u32) -> T {
        let mut sum = T::ZERO;
        let nl = u32::try_from(NL).unwrap_or(u32::MAX);
        for (p, &inv_n) in self.pieces.iter().zip(self.inv_ticks.iter()) {
            // The taps j = lo ..= hi see the piece (ticks k0 ≤ k + j < k0 + n).
            let (k0, last) = (p.start, p.start.saturating_add(p.ticks.saturating_sub(1)));
            let ahead = k0 > k;
            let lo = if ahead { k0 - k } else { 1 };
            if lo > nl || last <= k {
                continue;
            }
            let hi = (last - k).min(nl);
            if ahead && hi - lo < DIRECT_MAX as u32 {
                // A short overlap at a piece's start: summed directly (the moment form would
                // extrapolate the piece far outside its ticks). From s = 0 at tap `lo` in
                // steps of h = 1/n by forward differences of g(i) = Σ c_q (i h)^q.
                sum += forward_sum(&p.coeffs, inv_n, gains.preview_range(lo, hi));
                continue;
            }
            // s at tap 0: a = (k − k0)/n (negative ahead of the piece).
            let rel = if ahead {
                -tick_i32(k0 - k)
            } else {
                tick_i32(k - k0)
            };
            let a = T::of_i32(rel) * inv_n;
            let b = T::of_i32(tick_i32(nl)) * inv_n;
            // Taylor shift: e(t) = c(a + t).
            let mut e = p.coeffs;
            for i in 0..MOMENTS - 1 {
                for j in (i..MOMENTS - 1).rev() {
                    e[j] += a * e[j + 1];
                }
            }
            // Σ_q e_q b^q ΔM_q by Horner in b.
            let (u, l) = ((hi - 1) as usize, (lo as usize).checked_sub(2));
            let mut acc = T::ZERO;
            for q in (0..MOMENTS).rev() {
                acc = acc * b + e[q] * gains.moment_range(q, u, l);
            }
            sum += acc;
        }
        sum
    }

    /// Advances one tick: returns the compensation at the current tick `k` (state `X(k)`,
    /// `p_c(k)`, `r(k)`, `u(k)`) and moves the state to `X(k+1) = A X(k) + B u(k)`, with
    /// `u(k) = −G_i Σ_{i≤k} e(i) − K X(k) + Σ_{j=1}^{NL} f_j r(k+j) + f_∞ r(k+NL)`.
    /// `gains` must be the same on every call between resets (it is not stored).
    pub fn step<const NL: usize>(&mut self, gains: &PreviewGains<T, NL>) -> Compensation<T> {
        let c = self.peek(gains);
        let [dt, dt2, dt3] = gains.dt;
        let (x, v, acc, u) = (c.cog, c.cog_vel, c.cog_acc, c.jerk);
        self.error_sum += c.zmp - c.reference;
        self.state = [
            x + dt * v + dt2 * acc + dt3 * u,
            v + dt * acc + dt2 * u,
            acc + dt * u,
        ];
        self.tick = self.tick.saturating_add(1);
        c
    }

    /// What [`step`](Self::step) would return now, without advancing.
    #[inline(always)]
    pub fn peek<const NL: usize>(&self, gains: &PreviewGains<T, NL>) -> Compensation<T> {
        let k = self.tick;
        let [x, v, acc] = self.state;
        let r = self.reference(k);
        let zmp = x - gains.zg * acc;
        let error_sum = self.error_sum + (zmp - r);
        let ks = &gains.k_state;
        let u = self.preview_sum(gains, k)
            + gains.tail * self.reference(k.saturating_add(u32::try_from(NL).unwrap_or(u32::MAX)))
            - gains.k_int * error_sum
            - (ks[0] * x + ks[1] * v + ks[2] * acc);
        Compensation {
            tick: k,
            cog: x,
            cog_vel: v,
            cog_acc: acc,
            zmp,
            reference: r,
            jerk: u,
        }
    }
}
