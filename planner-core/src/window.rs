//! The plan window: m = 7 intervals, one 20×20 boundary-value system for both planes.
//!
//! # Unknowns and conditions (the reduced form of the paper, section V)
//! Interval `j = 1..7` has duration `D_j`, ZMP polynomial `a^{(j)}` and COG
//! `x^{(j)}(τ) = P_j e^{−ωτ} + Q_j e^{−ω(D_j−τ)} + Σ A_i^{(j)} τ^i` (see [`crate::lipm`]).
//!
//! * The ZMP passes through given **via points** `(p_j, ṗ_j)` at the ends `T_1 … T_7` of the
//!   intervals, starting from the current ZMP `(p_0, ṗ_0)` at `T_0`.
//! * Interior intervals 2…6 are cubic Hermite polynomials, fully fixed by the via points.
//! * Intervals 1 and 7 are quartics: `a_0, a_1` come from the ZMP at their start, and the
//!   unknowns are `β_k = a_k D^k`, `k = 2, 3, 4`: the coefficients of the ZMP in normalised
//!   time `s = τ/D`, in metres.
//!
//! That leaves 20 unknowns per plane, ordered so that the matrix is banded:
//!
//! ```text
//! y = [β_2¹ β_3¹ β_4¹ | P_1 Q_1 | P_2 Q_2 | … | P_7 Q_7 | β_2⁷ β_3⁷ β_4⁷]
//! ```
//!
//! and 20 conditions, every velocity row divided by ω and every quartic ZMP velocity row
//! multiplied by `D` so that all rows are in metres:
//!
//! | rows   | condition                                                     |
//! |--------|---------------------------------------------------------------|
//! | 0, 1   | ZMP position and velocity at the end of interval 1 = via 1   |
//! | 2, 3   | COG position and velocity at `T_0` = initial COG state       |
//! | 4…15   | COG position and velocity continuous at `T_1 … T_6`           |
//! | 16, 17 | COG position and velocity at `T_7` = terminal COG state      |
//! | 18, 19 | ZMP position and velocity at the end of interval 7 = via 7   |
//!
//! The matrix `Z` holds only `E_j = e^{−ωD_j}` and functions of `λ_j = ωD_j`: it depends on
//! the timing alone, so one factorisation serves the x and the y plane (two right-hand sides).
//! Its lower and upper bandwidths are both 5; the LU with partial pivoting below works inside
//! the band (fill-in of U up to 10 above the diagonal), about 3× fewer operations than a
//! dense 20×20 LU.
//!
//! # Conditioning
//! In the paper's basis `V cosh + W sinh` the columns of an interval grow like `cosh ωD` and
//! nearly coincide for long intervals; `P e^{−ωτ} + Q e^{−ω(D−τ)}` keeps every entry of `Z` in
//! `[−1, 1]` for the homogeneous columns, and the particular solutions of [`crate::lipm`] keep
//! the quartic columns small for short intervals. Both homogeneous bases are available
//! ([`Basis`]) so the tests can measure the difference; [`Basis::Exponential`] is the one used
//! by the planner.
//! Positions are solved relative to the initial ZMP (the LIPM is translation invariant), so
//! the world-frame offset never enters the factorised system.

use nalgebra::SMatrix;

use crate::lipm::{
    add_particular, hermite, particular_ends, Particular, Poly, Sample, Segment, State,
    PARTICULAR_LEN,
};
use crate::real::Real;

/// Number of intervals in a window.
pub const M: usize = 7;
/// Number of unknowns (and conditions) per plane.
pub const N: usize = 20;
/// Shortest interval accepted \[s\] (one control cycle).
pub const MIN_DURATION: f64 = 0.005;
/// Longest interval accepted \[s\].
pub const MAX_DURATION: f64 = 10.0;

/// Why a window could not be planned. The planner keeps its previous plan on any of these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PlanError {
    /// Interval `index` (0-based) is shorter than [`MIN_DURATION`], longer than
    /// [`MAX_DURATION`], or not a finite number.
    BadDuration {
        /// 0-based interval index.
        index: u8,
    },
    /// ω is not finite and positive.
    BadOmega,
    /// A boundary value (COG state, via point) is not finite.
    NonFinite,
    /// The boundary-value matrix is numerically singular.
    Singular,
}

/// Which homogeneous basis the matrix is built in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis {
    /// `P e^{−ωτ} + Q e^{−ω(D−τ)}`: bounded columns, the planner's choice.
    Exponential,
    /// The paper's `V cosh ωτ + W sinh ωτ` (kept to measure the conditioning it costs).
    Hyperbolic,
}

/// The timing of a window: ω and the durations of the 7 intervals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing<T> {
    /// ω = √(g/z_c) \[1/s\].
    pub omega: T,
    /// Durations `D_1 … D_7` \[s\].
    pub durations: [T; M],
}

impl<T: Real> Timing<T> {
    /// Checks ω and the durations.
    pub fn validate(&self) -> Result<(), PlanError> {
        if !(self.omega.is_finite() && self.omega > T::ZERO) {
            return Err(PlanError::BadOmega);
        }
        for (i, &d) in self.durations.iter().enumerate() {
            if !(d.is_finite() && d >= T::of(MIN_DURATION) && d <= T::of(MAX_DURATION)) {
                return Err(PlanError::BadDuration { index: i as u8 });
            }
        }
        Ok(())
    }

    /// Start time of every interval and the end of the window, relative to the window start.
    pub fn boundaries(&self) -> [T; M + 1] {
        let mut t = [T::ZERO; M + 1];
        for j in 0..M {
            t[j + 1] = t[j] + self.durations[j];
        }
        t
    }

    /// Total duration of the window \[s\].
    pub fn total(&self) -> T {
        let mut s = T::ZERO;
        for &d in &self.durations {
            s += d;
        }
        s
    }
}

/// The boundary values of one plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlaneBoundary<T> {
    /// COG position and velocity at the start of the window.
    pub cog_start: State<T>,
    /// ZMP position and velocity at the start of the window.
    pub zmp_start: State<T>,
    /// ZMP via points at the end of each interval (`T_1 … T_7`).
    pub via: [State<T>; M],
    /// COG position and velocity required at the end of the window.
    pub cog_end: State<T>,
}

impl<T: Real> PlaneBoundary<T> {
    fn all_finite(&self) -> bool {
        let mut ok = self.cog_start.pos.is_finite()
            && self.cog_start.vel.is_finite()
            && self.zmp_start.pos.is_finite()
            && self.zmp_start.vel.is_finite()
            && self.cog_end.pos.is_finite()
            && self.cog_end.vel.is_finite();
        for v in &self.via {
            ok &= v.pos.is_finite() && v.vel.is_finite();
        }
        ok
    }
}

/// The solved window in one plane: 7 segments.
pub type PlanePlan<T> = [Segment<T>; M];

/// The solved window: timing and both planes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan<T> {
    /// The timing the plan was solved for.
    pub timing: Timing<T>,
    /// Sagittal plane (x).
    pub x: PlanePlan<T>,
    /// Frontal plane (y).
    pub y: PlanePlan<T>,
}

impl<T: Real> Plan<T> {
    /// An empty plan (all zero) for the given timing, to be filled by [`Factorized::solve`].
    pub fn zeroed(timing: Timing<T>) -> Self {
        Self {
            timing,
            x: [Segment::default(); M],
            y: [Segment::default(); M],
        }
    }

    /// The interval containing window time `t` and the local time in it (`t` is clamped to
    /// the window).
    pub fn locate(&self, t: T) -> (usize, T) {
        let mut start = T::ZERO;
        let mut t = t.max(T::ZERO);
        for j in 0..M {
            let d = self.timing.durations[j];
            if t < start + d || j == M - 1 {
                if t > start + d {
                    t = start + d;
                }
                return (j, t - start);
            }
            start += d;
        }
        (M - 1, self.timing.durations[M - 1])
    }

    /// Both planes at window time `t` (seconds since the window start, clamped to the window).
    pub fn sample(&self, t: T) -> (Sample<T>, Sample<T>) {
        let (j, tau) = self.locate(t);
        (self.x[j].sample(tau), self.y[j].sample(tau))
    }
}

/// `Z` built for one timing and factorised in place (banded LU with partial pivoting).
#[derive(Clone, Debug)]
pub struct Factorized<T: Real> {
    timing: Timing<T>,
    basis: Basis,
    lu: SMatrix<T, N, N>,
    pivots: [u8; N],
    /// Column equilibration: the solution of the scaled system times this is `y`.
    col_scale: [T; N],
    kl: usize,
    ku: usize,
}

/// First column of the homogeneous pair of interval `j` (0-based).
#[inline]
const fn hcol(j: usize) -> usize {
    3 + 2 * j
}
/// Lower and upper bandwidth of `Z` in the ordering above (checked by a test against
/// [`bandwidths`] of the built matrix).
pub const BANDWIDTH: usize = 5;

/// First column of the quartic unknowns of the last interval.
const LAST_BETA: usize = 3 + 2 * M;

/// Rows of the 2×2 block that maps the homogeneous pair of an interval (with `E = e^{−ωD}`)
/// to COG position and scaled velocity at its start (`at_end = false`) or end.
#[inline]
fn basis_block<T: Real>(basis: Basis, e: T, at_end: bool) -> [[T; 2]; 2] {
    match (basis, at_end) {
        (Basis::Exponential, false) => [[T::ONE, e], [-T::ONE, e]],
        (Basis::Exponential, true) => [[e, T::ONE], [-e, T::ONE]],
        (Basis::Hyperbolic, false) => [[T::ONE, T::ZERO], [T::ZERO, T::ONE]],
        (Basis::Hyperbolic, true) => {
            let inv = T::ONE / e;
            let half = T::of(0.5);
            let c = half * (inv + e);
            let s = half * (inv - e);
            [[c, s], [s, c]]
        }
    }
}

/// `(x(0), ẋ(0)/ω, x(D), ẋ(D)/ω)` of the particular solution of the ZMP term `s^k`.
#[inline]
fn monomial_ends<T: Real>(k: usize, lambda: T) -> (T, T, T, T) {
    let mut g: Particular<T> = [T::ZERO; PARTICULAR_LEN];
    add_particular(&mut g, k, T::ONE, lambda);
    particular_ends(&g, lambda)
}

/// Builds `Z` for a timing into `z` (no allocation; `z` is overwritten).
pub fn build_z<T: Real>(timing: &Timing<T>, basis: Basis, z: &mut SMatrix<T, N, N>) {
    z.as_mut_slice().fill(T::ZERO);
    let w = timing.omega;
    let d = &timing.durations;
    // E_j = e^{−ωD_j}, once per interval.
    let mut e = [T::ZERO; M];
    for (ej, &dj) in e.iter_mut().zip(d.iter()) {
        *ej = (-w * dj).exp();
    }
    let l_first = w * d[0];
    let l_last = w * d[M - 1];
    // Rows 0, 1: ZMP at the end of interval 1 (β2 + β3 + β4; 2β2 + 3β3 + 4β4).
    // Rows 18, 19: the same for interval 7.
    for k in 0..3 {
        let kk = T::of((k + 2) as f64);
        z[(0, k)] = T::ONE;
        z[(1, k)] = kk;
        z[(18, LAST_BETA + k)] = T::ONE;
        z[(19, LAST_BETA + k)] = kk;
    }
    // Rows 2, 3: initial COG state.
    let b = basis_block(basis, e[0], false);
    for r in 0..2 {
        z[(2 + r, hcol(0))] = b[r][0];
        z[(2 + r, hcol(0) + 1)] = b[r][1];
    }
    for k in 0..3 {
        let (x0, v0, x1, v1) = monomial_ends(k + 2, l_first);
        z[(2, k)] = x0;
        z[(3, k)] = v0;
        // Continuity at the end of interval 1 (rows 4, 5).
        z[(4, k)] = x1;
        z[(5, k)] = v1;
        let (x0, v0, x1, v1) = monomial_ends(k + 2, l_last);
        // Continuity at the start of interval 7 (rows 14, 15) and terminal state (16, 17).
        z[(14, LAST_BETA + k)] = -x0;
        z[(15, LAST_BETA + k)] = -v0;
        z[(16, LAST_BETA + k)] = x1;
        z[(17, LAST_BETA + k)] = v1;
    }
    // Rows 4..15: continuity of the homogeneous parts at the end of interval j (0-based 0..5).
    for j in 0..M - 1 {
        let row = 4 + 2 * j;
        let end = basis_block(basis, e[j], true);
        let start = basis_block(basis, e[j + 1], false);
        for r in 0..2 {
            z[(row + r, hcol(j))] = end[r][0];
            z[(row + r, hcol(j) + 1)] = end[r][1];
            z[(row + r, hcol(j + 1))] = -start[r][0];
            z[(row + r, hcol(j + 1) + 1)] = -start[r][1];
        }
    }
    // Rows 16, 17: terminal COG state.
    let b = basis_block(basis, e[M - 1], true);
    for r in 0..2 {
        z[(16 + r, hcol(M - 1))] = b[r][0];
        z[(16 + r, hcol(M - 1) + 1)] = b[r][1];
    }
}

/// The known part of the normalised ZMP polynomial of every interval (the quartic unknowns
/// set to zero), relative to `origin`.
fn known_zmp<T: Real>(timing: &Timing<T>, b: &PlaneBoundary<T>, origin: T) -> [Poly<T>; M] {
    let rel = |s: State<T>| State::new(s.pos - origin, s.vel);
    let d = &timing.durations;
    let mut polys = [[T::ZERO; 5]; M];
    let z0 = rel(b.zmp_start);
    polys[0] = [z0.pos, z0.vel * d[0], T::ZERO, T::ZERO, T::ZERO];
    for j in 1..M - 1 {
        polys[j] = hermite(rel(b.via[j - 1]), rel(b.via[j]), d[j]);
    }
    let zl = rel(b.via[M - 2]);
    polys[M - 1] = [zl.pos, zl.vel * d[M - 1], T::ZERO, T::ZERO, T::ZERO];
    polys
}

/// The right-hand side `w` of one plane, relative to `origin`, and the known ZMP polynomials;
/// the particular solutions of the known parts are written into `segs`.
fn build_rhs<T: Real>(
    timing: &Timing<T>,
    b: &PlaneBoundary<T>,
    origin: T,
    segs: &mut PlanePlan<T>,
) -> ([T; N], [Poly<T>; M]) {
    let w = timing.omega;
    let d = &timing.durations;
    let polys = known_zmp(timing, b, origin);
    // Known particular COG (position, velocity/ω) at the start and end of every interval.
    let mut starts = [State::default(); M];
    let mut ends = [State::default(); M];
    for j in 0..M {
        let lambda = w * d[j];
        let g = &mut segs[j].particular;
        *g = [T::ZERO; PARTICULAR_LEN];
        for (k, &ck) in polys[j].iter().enumerate() {
            add_particular(g, k, ck, lambda);
        }
        let (x0, v0, x1, v1) = particular_ends(g, lambda);
        starts[j] = State::new(x0, v0);
        ends[j] = State::new(x1, v1);
    }
    let mut r = [T::ZERO; N];
    let (c0, c1) = (polys[0][0], polys[0][1]);
    r[0] = b.via[0].pos - origin - c0 - c1;
    r[1] = b.via[0].vel * d[0] - c1;
    r[2] = b.cog_start.pos - origin - starts[0].pos;
    r[3] = b.cog_start.vel / w - starts[0].vel;
    for j in 0..M - 1 {
        r[4 + 2 * j] = starts[j + 1].pos - ends[j].pos;
        r[5 + 2 * j] = starts[j + 1].vel - ends[j].vel;
    }
    r[16] = b.cog_end.pos - origin - ends[M - 1].pos;
    r[17] = b.cog_end.vel / w - ends[M - 1].vel;
    let (l0, l1) = (polys[M - 1][0], polys[M - 1][1]);
    r[18] = b.via[M - 1].pos - origin - l0 - l1;
    r[19] = b.via[M - 1].vel * d[M - 1] - l1;
    (r, polys)
}

impl<T: Real> Factorized<T> {
    /// Builds and factorises `Z` for a timing in the planner's basis.
    pub fn new(timing: &Timing<T>) -> Result<Self, PlanError> {
        Self::with_basis(timing, Basis::Exponential)
    }

    /// Builds and factorises `Z` in the given basis.
    pub fn with_basis(timing: &Timing<T>, basis: Basis) -> Result<Self, PlanError> {
        let mut f = Self::empty(basis);
        f.refactor(timing)?;
        Ok(f)
    }

    /// A factorisation of nothing yet (all zero), to be filled by [`Factorized::refactor`]:
    /// lets a caller keep its matrices in place (no 3 KB moves on the control path).
    pub fn empty(basis: Basis) -> Self {
        Self {
            // ω = 0 marks "not factorised" (no valid timing has it).
            timing: Timing {
                omega: T::ZERO,
                durations: [T::ONE; M],
            },
            basis,
            lu: SMatrix::<T, N, N>::from_element(T::ZERO),
            pivots: [0; N],
            col_scale: [T::ONE; N],
            kl: BANDWIDTH,
            ku: BANDWIDTH,
        }
    }

    /// Builds and factorises `Z` for a new timing in place; keeps the factorisation when the
    /// timing is the one it was built for (`Z` depends on the timing alone, and the
    /// factorisation of the same matrix is the same, bit for bit: steady walking re-plans
    /// with the same timing every step). On error the factorisation is unusable until the
    /// next successful call.
    pub fn refactor(&mut self, timing: &Timing<T>) -> Result<(), PlanError> {
        if self.timing == *timing && self.timing.omega > T::ZERO {
            return Ok(());
        }
        timing.validate()?;
        // Mark unusable until the end (a failed refactor must not look like the old timing).
        self.timing.omega = T::ZERO;
        let lu = &mut self.lu;
        build_z(timing, self.basis, lu);
        let (kl, ku) = (BANDWIDTH, BANDWIDTH);
        // Equilibrate the columns (largest entry 1): the quartic columns of a short interval
        // carry 24/(ωD)⁴, which would otherwise dominate the singularity threshold.
        for (j, s) in self.col_scale.iter_mut().enumerate() {
            let rows = j.saturating_sub(ku)..(j + kl + 1).min(N);
            let mut m = T::ZERO;
            for i in rows.clone() {
                m = m.max(lu[(i, j)].abs());
            }
            if !(m.is_finite() && m > T::ZERO) {
                return Err(PlanError::Singular);
            }
            *s = T::ONE / m;
            for i in rows {
                lu[(i, j)] *= *s;
            }
        }
        self.pivots = factor_banded(lu, kl, ku)?;
        self.kl = kl;
        self.ku = ku;
        self.timing = *timing;
        Ok(())
    }

    /// The timing this factorisation was built for.
    pub fn timing(&self) -> &Timing<T> {
        &self.timing
    }

    /// Lower and upper bandwidth of `Z` as built.
    pub fn bandwidths(&self) -> (usize, usize) {
        (self.kl, self.ku)
    }

    /// Solves `Z y = w` in place for one right-hand side.
    pub fn solve_vector(&self, rhs: &mut [T; N]) {
        solve_banded(&self.lu, &self.pivots, self.kl, self.ku, rhs);
        for (v, s) in rhs.iter_mut().zip(self.col_scale.iter()) {
            *v *= *s;
        }
    }

    /// Solves both planes into `out`, in place (no copies of the plan). Non-finite boundary
    /// values are rejected before `out` is touched; if the solution itself overflows (only
    /// possible for absurd magnitudes) `Err(NonFinite)` is returned and `out` is partly
    /// overwritten, so a caller that must keep a valid plan solves into a spare buffer.
    pub fn solve(
        &self,
        x: &PlaneBoundary<T>,
        y: &PlaneBoundary<T>,
        out: &mut Plan<T>,
    ) -> Result<(), PlanError> {
        if !(x.all_finite() && y.all_finite()) {
            return Err(PlanError::NonFinite);
        }
        if self.timing.omega == T::ZERO {
            // A failed refactor.
            return Err(PlanError::Singular);
        }
        out.timing = self.timing;
        self.solve_plane_into(x, &mut out.x)?;
        self.solve_plane_into(y, &mut out.y)
    }

    /// Solves one plane and returns it (a convenience for tests and tools).
    pub fn solve_plane(&self, b: &PlaneBoundary<T>) -> Result<PlanePlan<T>, PlanError> {
        if !b.all_finite() {
            return Err(PlanError::NonFinite);
        }
        let mut plan = [Segment::default(); M];
        self.solve_plane_into(b, &mut plan)?;
        Ok(plan)
    }

    /// Solves one plane into `out` (boundary values assumed finite).
    fn solve_plane_into(
        &self,
        b: &PlaneBoundary<T>,
        out: &mut PlanePlan<T>,
    ) -> Result<(), PlanError> {
        let origin = b.zmp_start.pos;
        let (mut rhs, polys) = build_rhs(&self.timing, b, origin, out);
        self.solve_vector(&mut rhs);
        if !rhs.iter().all(|v| v.is_finite()) {
            return Err(PlanError::NonFinite);
        }
        let w = self.timing.omega;
        let d = &self.timing.durations;
        for (j, seg) in out.iter_mut().enumerate() {
            let (c0, c1) = (rhs[hcol(j)], rhs[hcol(j) + 1]);
            let (p, q) = match self.basis {
                Basis::Exponential => (c0, c1),
                Basis::Hyperbolic => {
                    // V = P + QE, W = −P + QE.
                    let half = T::of(0.5);
                    let e = (-w * d[j]).exp();
                    (half * (c0 - c1), half * (c0 + c1) / e)
                }
            };
            seg.omega = w;
            seg.duration = d[j];
            seg.p = p;
            seg.q = q;
            seg.zmp = polys[j];
        }
        // The quartic unknowns are the normalised coefficients c_2, c_3, c_4; their particular
        // solutions are added to the known ones (linearity).
        for (j, col) in [(0usize, 0usize), (M - 1, LAST_BETA)] {
            for k in 0..3 {
                out[j].zmp[k + 2] = rhs[col + k];
                add_particular(&mut out[j].particular, k + 2, rhs[col + k], w * d[j]);
            }
        }
        for seg in out.iter_mut() {
            seg.zmp[0] += origin;
            seg.particular[0] += origin;
        }
        Ok(())
    }
}

/// Lower and upper bandwidth of a matrix (largest `i − j` and `j − i` of a non-zero entry).
pub fn bandwidths<T: Real>(z: &SMatrix<T, N, N>) -> (usize, usize) {
    let (mut kl, mut ku) = (0, 0);
    for i in 0..N {
        for j in 0..N {
            if z[(i, j)] != T::ZERO {
                if i > j {
                    kl = kl.max(i - j);
                } else {
                    ku = ku.max(j - i);
                }
            }
        }
    }
    (kl, ku)
}

/// In-place LU with partial pivoting inside the band, for a matrix whose columns have been
/// equilibrated to a largest entry of 1 (LINPACK style: row interchanges are
/// recorded in `pivots` and applied to the right-hand side during the solve; the multipliers
/// of earlier columns are not permuted). `U` has upper bandwidth `kl + ku`.
fn factor_banded<T: Real>(
    a: &mut SMatrix<T, N, N>,
    kl: usize,
    ku: usize,
) -> Result<[u8; N], PlanError> {
    // The columns are equilibrated (largest entry 1), so the threshold is absolute.
    let tol = T::EPSILON * T::of(N as f64);
    let mut pivots = [0u8; N];
    // Column-major storage: column j is data[j*N .. j*N + N], so every inner loop below runs
    // down one contiguous column.
    let data = a.as_mut_slice();
    for k in 0..N {
        let last = (k + kl).min(N - 1);
        let right = (k + kl + ku).min(N - 1);
        let (before, rest) = data.split_at_mut((k + 1) * N);
        let colk = &mut before[k * N..];
        let mut p = k;
        let mut best = colk[k].abs();
        for (i, v) in colk.iter().enumerate().take(last + 1).skip(k + 1) {
            if v.abs() > best {
                best = v.abs();
                p = i;
            }
        }
        // Written so that a NaN pivot is rejected too.
        if best.is_nan_or_le(tol) {
            return Err(PlanError::Singular);
        }
        pivots[k] = p as u8;
        // `k ≤ p < N`; the slice pattern swaps `colk[k]` and `colk[p]` without a panic path.
        if let Some([a, .., b]) = colk.get_mut(k..=p) {
            core::mem::swap(a, b);
        }
        let inv = T::ONE / colk[k];
        for v in &mut colk[k + 1..=last] {
            *v *= inv;
        }
        let mults = &colk[k + 1..=last];
        for colj in rest.chunks_exact_mut(N).take(right - k) {
            if let Some([a, .., b]) = colj.get_mut(k..=p) {
                core::mem::swap(a, b); // colj.swap(k, p), as above
            }
            let ukj = colj[k];
            if ukj != T::ZERO {
                for (v, &l) in colj[k + 1..=last].iter_mut().zip(mults) {
                    *v -= l * ukj;
                }
            }
        }
    }
    Ok(pivots)
}

/// Solves with the factors of [`factor_banded`].
fn solve_banded<T: Real>(
    lu: &SMatrix<T, N, N>,
    pivots: &[u8; N],
    kl: usize,
    ku: usize,
    b: &mut [T; N],
) {
    let data = lu.as_slice();
    // Written with `get` and slice patterns so that no index can panic (`k ≤ p < N` and
    // `k < N` hold by construction; the fallbacks are never taken).
    for (k, (col, &p)) in data.chunks_exact(N).zip(pivots).enumerate() {
        // b.swap(k, p)
        if let Some([a, .., z]) = b.get_mut(k..=usize::from(p)) {
            core::mem::swap(a, z);
        }
        let Some(&bk) = b.get(k) else {
            break;
        };
        let last = (k + kl).min(N - 1);
        let (Some(bs), Some(ls)) = (b.get_mut(k + 1..=last), col.get(k + 1..=last)) else {
            continue;
        };
        for (v, &l) in bs.iter_mut().zip(ls) {
            *v -= l * bk;
        }
    }
    // Column-oriented back substitution: U has upper bandwidth kl + ku.
    let bw = kl + ku;
    for (k, col) in data.chunks_exact(N).enumerate().rev() {
        let bk = b[k] / col[k];
        b[k] = bk;
        let first = k.saturating_sub(bw);
        for (v, &u) in b[first..k].iter_mut().zip(&col[first..k]) {
            *v -= u * bk;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing() -> Timing<f64> {
        Timing {
            omega: libm::sqrt(9.8 / 0.814),
            durations: [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7],
        }
    }

    #[test]
    fn z_is_banded_as_documented() {
        for basis in [Basis::Exponential, Basis::Hyperbolic] {
            let mut z = SMatrix::<f64, N, N>::from_element(0.0);
            build_z(&timing(), basis, &mut z);
            assert_eq!(bandwidths(&z), (BANDWIDTH, BANDWIDTH));
        }
    }

    #[test]
    fn banded_lu_solves_a_dense_check() {
        let t = timing();
        let mut z = SMatrix::<f64, N, N>::from_element(0.0);
        build_z(&t, Basis::Exponential, &mut z);
        let f = Factorized::new(&t).unwrap();
        let mut b = [0.0; N];
        for (i, v) in b.iter_mut().enumerate() {
            *v = libm::sin(i as f64 + 0.3);
        }
        let mut y = b;
        f.solve_vector(&mut y);
        for i in 0..N {
            let mut s = 0.0;
            for j in 0..N {
                s += z[(i, j)] * y[j];
            }
            assert!((s - b[i]).abs() < 1e-12, "row {i}: {s} vs {}", b[i]);
        }
    }

    #[test]
    fn bad_timing_is_an_error() {
        let mut t = timing();
        t.durations[3] = 0.0;
        assert_eq!(
            Factorized::new(&t).unwrap_err(),
            PlanError::BadDuration { index: 3 }
        );
        t.durations[3] = f64::NAN;
        assert!(Factorized::new(&t).is_err());
        let mut t = timing();
        t.omega = -1.0;
        assert_eq!(Factorized::new(&t).unwrap_err(), PlanError::BadOmega);
    }
}
