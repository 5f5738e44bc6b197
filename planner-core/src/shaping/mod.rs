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

//!
//! # Rooms
//! [`gains`] computes [`PreviewGains`] (the Riccati equation and the moment tables, once);
//! [`compensator`] runs the [`Compensator`] on them every tick.

use crate::lipm::N_COEFFS;
use nalgebra::{SMatrix, SVector};

pub mod compensator;
pub mod gains;

pub use compensator::{Compensation, Compensator, Piece};
pub use gains::{solve_dare, PreviewGains};

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
