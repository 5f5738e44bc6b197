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
//! In the exponential basis it is solved by its structure ([`Factorized`], module `chain`):
//! the sum and the difference of each pair of COG rows separate the decaying coefficients `P`
//! (solved forward) from the growing ones `Q` (solved backward), and what is left is a 2×2
//! system for one free coefficient of each quartic: ~120 flops per timing and ~110 per plane,
//! against ~2,000 and ~400 for the banded LU of the dense matrix ([`Banded`], band width 5,
//! which the tests use as the reference and which serves the `cosh`/`sinh` basis). The
//! right-hand sides take the particular solutions' ends from a table of the monomials' ends
//! per distinct duration (module `rhs`: a few multiply-adds per interval and plane), and both
//! planes are solved together, sharing the timing's factors.
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

mod banded;
mod chain;
mod rhs;

pub use banded::{bandwidths, build_z, Banded, BANDWIDTH};
use chain::Chain;
use rhs::{solve_pair, write_segment, write_segments, Intervals};

use crate::lipm::{Sample, Segment, State};
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
    /// Every value zero.
    pub const ZERO: Self = Self {
        cog_start: State::ZERO,
        zmp_start: State::ZERO,
        via: [State::ZERO; M],
        cog_end: State::ZERO,
    };

    /// Every value finite: `v · 0` is `0` for a finite `v` and NaN for an infinite or NaN
    /// one, so the sum of those products is `0` exactly when all are finite (no branch per
    /// value, and no overflow whatever the magnitudes).
    fn all_finite(&self) -> bool {
        let z = |s: &State<T>| s.pos * T::ZERO + s.vel * T::ZERO;
        let mut sum = z(&self.cog_start) + z(&self.zmp_start) + z(&self.cog_end);
        for v in &self.via {
            sum += z(v);
        }
        sum == T::ZERO
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
    /// Every value zero, the timing too (ω = 0: no plan; a placeholder in a buffer that is
    /// filled before use, e.g. a `static`).
    pub const ZERO: Self = Self {
        timing: Timing {
            omega: T::ZERO,
            durations: [T::ZERO; M],
        },
        x: [Segment::ZERO; M],
        y: [Segment::ZERO; M],
    };

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
        Segment::sample_pair(&self.x[j], &self.y[j], tau)
    }
}

/// First column of the homogeneous pair of interval `j` (0-based).
#[inline]
pub(crate) const fn hcol(j: usize) -> usize {
    3 + 2 * j
}
/// First column of the quartic unknowns of the last interval.
pub(crate) const LAST_BETA: usize = 3 + 2 * M;

/// The planner's factorisation of `Z` ([`Basis::Exponential`]): the timing-only part of the
/// structured elimination of [`chain`](self) (two damped scalar recursions and a 2×2 Schur
/// complement, ~0.5 KB), kept in place and reused while the timing does not change. The
/// dense banded LU of the same matrix, in either basis, is [`Banded`].
#[derive(Clone, Debug)]
pub struct Factorized<T: Real> {
    timing: Timing<T>,
    chain: Chain<T>,
    intervals: Intervals<T>,
}

/// What the plane solves need from a factorisation of `Z`.
trait Solver<T: Real> {
    /// The timing factorised for (`ω = 0`: none, or a failed one).
    fn timing(&self) -> &Timing<T>;
    /// The homogeneous basis of `y`.
    fn basis(&self) -> Basis;
    /// The timing-only table of the right-hand sides.
    fn intervals(&self) -> &Intervals<T>;
    /// `y = Z⁻¹ y`, in place.
    fn solve_in_place(&self, y: &mut [T; N]);
}

/// Both planes into `out` (see [`Factorized::solve`]).
fn solve_both<T: Real, S: Solver<T>>(
    s: &S,
    x: &PlaneBoundary<T>,
    y: &PlaneBoundary<T>,
    out: &mut Plan<T>,
) -> Result<(), PlanError> {
    if !(x.all_finite() && y.all_finite()) {
        return Err(PlanError::NonFinite);
    }
    if s.timing().omega == T::ZERO {
        // A failed refactor.
        return Err(PlanError::Singular);
    }
    let mut sol = [[T::ZERO; N]; 2];
    solve_pair(s, [x, y], &mut sol)?;
    out.timing = *s.timing();
    for (j, (sx, sy)) in out.x.iter_mut().zip(out.y.iter_mut()).enumerate() {
        write_segments(s, [x, y], &sol, j, sx, sy);
    }
    Ok(())
}

/// One plane (see [`Factorized::solve_plane`]).
fn solve_plane_new<T: Real, S: Solver<T>>(
    s: &S,
    b: &PlaneBoundary<T>,
) -> Result<PlanePlan<T>, PlanError> {
    if !b.all_finite() {
        return Err(PlanError::NonFinite);
    }
    if s.timing().omega == T::ZERO {
        return Err(PlanError::Singular);
    }
    let mut sol = [[T::ZERO; N]; 2];
    solve_pair(s, [b, b], &mut sol)?;
    let mut plan = [Segment::default(); M];
    let mut other = Segment::default();
    for (j, seg) in plan.iter_mut().enumerate() {
        write_segments(s, [b, b], &sol, j, seg, &mut other);
    }
    Ok(plan)
}

impl<T: Real> Solver<T> for Factorized<T> {
    fn timing(&self) -> &Timing<T> {
        &self.timing
    }
    fn basis(&self) -> Basis {
        Basis::Exponential
    }
    fn intervals(&self) -> &Intervals<T> {
        &self.intervals
    }
    fn solve_in_place(&self, y: &mut [T; N]) {
        self.chain.solve(&self.intervals, y);
    }
}

impl<T: Real> Factorized<T> {
    /// Factorises `Z` for a timing.
    pub fn new(timing: &Timing<T>) -> Result<Self, PlanError> {
        let mut f = Self::empty();
        f.refactor(timing)?;
        Ok(f)
    }

    /// A factorisation of nothing yet (all zero), to be filled by [`Factorized::refactor`]:
    /// lets a caller keep it in place.
    pub const fn empty() -> Self {
        Self {
            // ω = 0 marks "not factorised" (no valid timing has it).
            timing: Timing {
                omega: T::ZERO,
                durations: [T::ZERO; M],
            },
            chain: Chain::ZERO,
            intervals: Intervals::ZERO,
        }
    }

    /// Factorises `Z` for a new timing in place; keeps the factorisation when the timing is the
    /// one it was built for (`Z` depends on the timing alone, and the factorisation of the same
    /// matrix is the same, bit for bit: steady walking re-plans with the same timing every
    /// step). On error the factorisation is unusable until the next successful call.
    pub fn refactor(&mut self, timing: &Timing<T>) -> Result<(), PlanError> {
        if self.timing == *timing && self.timing.omega > T::ZERO {
            return Ok(());
        }
        timing.validate()?;
        // Mark unusable until the end (a failed refactor must not look like the old timing).
        self.timing.omega = T::ZERO;
        self.intervals.set(timing);
        self.chain.factor(timing, &self.intervals)?;
        self.timing = *timing;
        Ok(())
    }

    /// The timing this factorisation was built for.
    pub fn timing(&self) -> &Timing<T> {
        &self.timing
    }

    /// Solves `Z y = w` for one right-hand side (`w` in the row order of the module
    /// documentation, `y` in its column order).
    pub fn solve_vector(&self, rhs: &mut [T; N]) {
        self.chain.solve(&self.intervals, rhs);
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
        solve_both(self, x, y, out)
    }

    /// Solves one plane and returns it (a convenience for tests and tools).
    pub fn solve_plane(&self, b: &PlaneBoundary<T>) -> Result<PlanePlan<T>, PlanError> {
        solve_plane_new(self, b)
    }

    /// Both planes of the solution at local time `tau` of interval `j` (0-based, clamped to
    /// the window), bit for bit the samples of the plan [`Factorized::solve`] gives, but with
    /// only that interval's segments built: no plan is written.
    pub fn sample(
        &self,
        x: &PlaneBoundary<T>,
        y: &PlaneBoundary<T>,
        j: usize,
        tau: T,
    ) -> Result<(Sample<T>, Sample<T>), PlanError> {
        if !(x.all_finite() && y.all_finite()) {
            return Err(PlanError::NonFinite);
        }
        if self.timing.omega == T::ZERO {
            return Err(PlanError::Singular);
        }
        let mut sol = [[T::ZERO; N]; 2];
        solve_pair(self, [x, y], &mut sol)?;
        // One segment at a time in one buffer (a small stack), the exponentials of the sample
        // shared by both planes as in `Segment::sample_pair`.
        let j = j.min(M - 1);
        let mut seg = Segment::ZERO;
        write_segment(self, x, &sol[0], j, &mut seg);
        let at = seg.at(tau);
        let sx = seg.sample_at(&at);
        write_segment(self, y, &sol[1], j, &mut seg);
        Ok((sx, seg.sample_at(&at)))
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

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

    /// `max_i |(Z y − b)_i|` over the rows of the dense `Z`.
    fn residual(z: &SMatrix<f64, N, N>, y: &[f64; N], b: &[f64; N]) -> f64 {
        let mut worst = 0.0_f64;
        for i in 0..N {
            let mut s = 0.0;
            for j in 0..N {
                s += z[(i, j)] * y[j];
            }
            worst = worst.max((s - b[i]).abs());
        }
        worst
    }

    #[test]
    fn banded_lu_and_the_structured_elimination_solve_the_dense_system() {
        let t = timing();
        let mut z = SMatrix::<f64, N, N>::from_element(0.0);
        build_z(&t, Basis::Exponential, &mut z);
        let mut b = [0.0; N];
        for (i, v) in b.iter_mut().enumerate() {
            *v = libm::sin(i as f64 + 0.3);
        }
        let mut y = b;
        Banded::with_basis(&t, Basis::Exponential)
            .unwrap()
            .solve_vector(&mut y);
        assert!(residual(&z, &y, &b) < 1e-12);
        let mut yc = b;
        Factorized::new(&t).unwrap().solve_vector(&mut yc);
        assert!(residual(&z, &yc, &b) < 1e-12);
    }

    /// Every mix of 5 ms and 10 s intervals, and durations from 5 ms to 3 s in every interval (a
    /// deterministic pseudo-random sweep): the
    /// structured elimination agrees with the banded LU relative to the size of the solution,
    /// and its residual in the dense system is at rounding level (rows are in metres).
    #[test]
    fn structured_elimination_agrees_with_banded_lu_over_many_timings() {
        let mut next = crate::test_uniform(0x2545_f491_4f6c_dd1d_u64);
        let mut worst = 0.0_f64;
        for case in 0..2128 {
            let mut t = timing();
            if case < 128 {
                // Every mix of the extremes: 5 ms and 10 s (MAX_DURATION) intervals.
                for (j, d) in t.durations.iter_mut().enumerate() {
                    *d = if case >> j & 1 == 1 {
                        MAX_DURATION
                    } else {
                        MIN_DURATION
                    };
                }
            } else {
                for d in t.durations.iter_mut() {
                    // Log-uniform in [0.005, 3] s, rounded to whole 5 ms ticks.
                    let v = 0.005 * libm::exp(next() * libm::log(600.0));
                    *d = (libm::round(v / 0.005)).max(1.0) * 0.005;
                }
            }
            let mut z = SMatrix::<f64, N, N>::from_element(0.0);
            build_z(&t, Basis::Exponential, &mut z);
            let mut b = [0.0; N];
            for v in b.iter_mut() {
                *v = next() - 0.5;
            }
            let (mut yb, mut yc) = (b, b);
            Banded::with_basis(&t, Basis::Exponential)
                .unwrap()
                .solve_vector(&mut yb);
            Factorized::new(&t).unwrap().solve_vector(&mut yc);
            let scale = yb.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
            for (a, c) in yb.iter().zip(yc.iter()) {
                worst = worst.max((a - c).abs() / scale);
            }
            assert!(
                residual(&z, &yc, &b) < 1e-11 * scale,
                "{:?}: residual {}",
                t.durations,
                residual(&z, &yc, &b)
            );
        }
        assert!(worst < 1e-10, "relative difference {worst}");
    }

    /// A plan solved over the plan of another timing (the node's two buffers take turns) is
    /// exactly the plan solved into a fresh buffer: the particular solutions' unused tails
    /// (`particular_len`) are zero in both, whatever the buffer held before, including after a
    /// solve that failed half-way.
    #[test]
    fn a_reused_plan_buffer_gives_the_fresh_plan() {
        let mut next = crate::test_uniform(0x9e37_79b9_7f4a_7c15_u64);
        let mut reused = Plan::zeroed(timing());
        for case in 0..300 {
            let mut t = timing();
            for d in t.durations.iter_mut() {
                // 5 ms to 1.5 s: λ = ωD on both sides of 1.
                *d = (libm::round(next() * 300.0)).max(1.0) * 0.005;
            }
            let mut bound = || {
                let mut s = || State::new(next() - 0.5, next() - 0.5);
                PlaneBoundary {
                    cog_start: s(),
                    zmp_start: s(),
                    via: [s(), s(), s(), s(), s(), s(), s()],
                    cog_end: s(),
                }
            };
            let (mut bx, by) = (bound(), bound());
            let f = Factorized::new(&t).unwrap();
            if case % 7 == 3 {
                // Fails in the solve of y (after x was written): the buffer is left dirty.
                let mut bad = by;
                bad.cog_end.pos = f64::MAX;
                bad.via[3].pos = -f64::MAX;
                let _ = f.solve(&bx, &bad, &mut reused);
                bx.cog_start.vel += 1e-3;
            }
            let mut fresh = Plan::zeroed(t);
            f.solve(&bx, &by, &mut fresh).unwrap();
            f.solve(&bx, &by, &mut reused).unwrap();
            assert_eq!(reused, fresh, "case {case}: {:?}", t.durations);
        }
    }

    /// The sample of one interval without a plan is, bit for bit, the sample of the solved
    /// plan (eq. 18's target state), in every interval and on both sides of `λ = 1`.
    #[test]
    fn a_sample_without_a_plan_is_the_plan_s() {
        let mut next = crate::test_uniform(0x1234_5678_9abc_def1_u64);
        for case in 0..200 {
            let mut t = timing();
            for d in t.durations.iter_mut() {
                *d = (libm::round(next() * 300.0)).max(1.0) * 0.005;
            }
            let mut bound = || {
                let mut s = || State::new(next() - 0.5, next() - 0.5);
                PlaneBoundary {
                    cog_start: s(),
                    zmp_start: s(),
                    via: [s(), s(), s(), s(), s(), s(), s()],
                    cog_end: s(),
                }
            };
            let (bx, by) = (bound(), bound());
            let f = Factorized::new(&t).unwrap();
            let mut plan = Plan::zeroed(t);
            f.solve(&bx, &by, &mut plan).unwrap();
            let j = case % M;
            let tau = next() * t.durations[j];
            let want = Segment::sample_pair(&plan.x[j], &plan.y[j], tau);
            assert_eq!(f.sample(&bx, &by, j, tau).unwrap(), want, "case {case}");
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
