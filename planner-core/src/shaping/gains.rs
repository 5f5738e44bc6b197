//! Preview-control gains: the discrete algebraic Riccati equation, the two laws' gains and the
//! moment tables of the closed-form preview sum (see the [parent module](super) for the
//! maths), computed once in `f64` and rounded to the scalar type `T`.

use super::{GainError, Law, PreviewConfig, MOMENTS};
use crate::real::Real;
use nalgebra::{SMatrix, SVector};

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
    pub(super) dt: [T; 3],
    pub(super) zg: T,
    pub(super) k_int: T,
    pub(super) k_state: [T; 3],
    pub(super) tail: T,
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
    pub(super) fn preview_range(&self, lo: u32, hi: u32) -> &[T] {
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
    pub(super) fn moment_range(&self, q: usize, u: usize, l: Option<usize>) -> T {
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

#[cfg(feature = "robot")]
impl<T: crate::literal::Literal, const NL: usize> PreviewGains<T, NL> {
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
                .map(|&v| crate::literal::Literal::literal(v))
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
                        .map(|&v| crate::literal::Literal::literal(v))
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
