//! The incremental compensator: one tick of the preview-control law per call, on a reference
//! held as at most `P` polynomial pieces (see the [parent module](super) for the law and the
//! cost per tick).

use super::{PieceError, PreviewGains, DEFAULT_PIECES, DIRECT_MAX, MOMENTS};
use crate::lipm::{Poly, Sample};
use crate::real::Real;

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
    /// `Σ e(i)` over the ticks done so far (used by [`crate::shaping::Law::Integral`] only).
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
