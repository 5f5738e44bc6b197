//! The dense `Z` and its banded LU with partial pivoting, in either homogeneous basis.
//!
//! [`build_z`] writes the 20×20 matrix of the parent module; [`Banded`] equilibrates its
//! columns (largest entry 1) and factorises it inside the band (lower and upper bandwidth
//! [`BANDWIDTH`] = 5, fill-in of `U` up to 10 above the diagonal; LINPACK-style row
//! interchanges). The planner itself uses the structured elimination of
//! [`Factorized`](super::Factorized); this is the general method, kept for the paper's
//! `cosh`/`sinh` basis ([`Basis::Hyperbolic`], whose conditioning the tests measure), as the
//! tests' reference for the structured one, and for the benchmarks.

use nalgebra::SMatrix;

use super::{
    hcol, solve_both, solve_plane_new, Basis, Intervals, Plan, PlanError, PlaneBoundary, PlanePlan,
    Solver, Timing, LAST_BETA, M, N,
};
use crate::lipm::monomial_ends;
use crate::real::Real;

/// Lower and upper bandwidth of `Z` in the ordering of the parent module (checked by a test
/// against [`bandwidths`] of the built matrix).
pub const BANDWIDTH: usize = 5;

/// `Z` built for one timing and factorised in place (banded LU with partial pivoting).
#[derive(Clone, Debug)]
pub struct Banded<T: Real> {
    timing: Timing<T>,
    basis: Basis,
    lu: SMatrix<T, N, N>,
    pivots: [u8; N],
    /// Column equilibration: the solution of the scaled system times this is `y`.
    col_scale: [T; N],
    /// The timing-only table of the right-hand sides.
    intervals: Intervals<T>,
}

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

impl<T: Real> Solver<T> for Banded<T> {
    fn timing(&self) -> &Timing<T> {
        &self.timing
    }
    fn basis(&self) -> Basis {
        self.basis
    }
    fn intervals(&self) -> &Intervals<T> {
        &self.intervals
    }
    fn solve_in_place(&self, y: &mut [T; N]) {
        self.solve_vector(y);
    }
}

impl<T: Real> Banded<T> {
    /// Builds and factorises `Z` in the given basis.
    pub fn with_basis(timing: &Timing<T>, basis: Basis) -> Result<Self, PlanError> {
        let mut f = Self::empty(basis);
        f.refactor(timing)?;
        Ok(f)
    }

    /// A factorisation of nothing yet (all zero), to be filled by [`Banded::refactor`].
    pub fn empty(basis: Basis) -> Self {
        Self {
            timing: Timing {
                omega: T::ZERO,
                durations: [T::ONE; M],
            },
            basis,
            lu: SMatrix::<T, N, N>::from_element(T::ZERO),
            pivots: [0; N],
            col_scale: [T::ONE; N],
            intervals: Intervals::ZERO,
        }
    }

    /// Builds and factorises `Z` for a timing in place (kept if the timing is the same).
    pub fn refactor(&mut self, timing: &Timing<T>) -> Result<(), PlanError> {
        if self.timing == *timing && self.timing.omega > T::ZERO {
            return Ok(());
        }
        timing.validate()?;
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
        self.intervals.set(timing);
        self.timing = *timing;
        Ok(())
    }

    /// The timing this factorisation was built for.
    pub fn timing(&self) -> &Timing<T> {
        &self.timing
    }

    /// Solves `Z y = w` in place for one right-hand side.
    pub fn solve_vector(&self, rhs: &mut [T; N]) {
        solve_banded(&self.lu, &self.pivots, BANDWIDTH, BANDWIDTH, rhs);
        for (v, s) in rhs.iter_mut().zip(self.col_scale.iter()) {
            *v *= *s;
        }
    }

    /// Solves both planes into `out` (as [`Factorized::solve`](super::Factorized::solve)).
    pub fn solve(
        &self,
        x: &PlaneBoundary<T>,
        y: &PlaneBoundary<T>,
        out: &mut Plan<T>,
    ) -> Result<(), PlanError> {
        solve_both(self, x, y, out)
    }

    /// Solves one plane and returns it.
    pub fn solve_plane(&self, b: &PlaneBoundary<T>) -> Result<PlanePlan<T>, PlanError> {
        solve_plane_new(self, b)
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
