//! Step adjustment from the measured state: the node moves the next landing (and the steps
//! after it) to capture a measured deviation from the plan, before that foot lifts off.
//!
//! # The law
//! The state estimator sends the deviation of the measured divergent component of motion
//! `ξ = x + ẋ/ω` from the reference's, `e = ξ_meas(k) − ξ_ref(k)`, against the reference of a
//! named cycle `k` (`MEASURED`, see [`crate::wire`]): exactly against the reference the robot
//! was tracking. With `n` ticks from `k` to the touch-down of the next swing target, the
//! landing moves by `(e − m) e^{ω n dt}` along `e` ([`crate::capture::capture_offset`]): what
//! the robot's stabilizer cannot hold with the ZMP margin `m` in the sole
//! ([`AdjustConfig::margin`]) grows at `ω` until the touch-down, and the foot lands where the
//! stabilizer can hold it again. This is the capture-point step adjustment of Englsberger et
//! al. (IROS 2011) and Khadiv et al. (Humanoids 2016), with the paper's eq. 18 in place of
//! their timing adaptation, held to its direction: the moved step is a capture step
//! ([`crate::gait::Gait::place_steps`]), whose single support eq. 18 may shorten but not
//! lengthen.
//!
//! # One shift for the rest of the walk, and no longer
//! The move is a shift `s` (in the footstep unit, 0.5 mm) of the next swing target and every
//! step after it, queued or appended later in the walk, so that the walk after the landing is
//! the plan, moved: every step lands at its commanded position plus the shift in force when it was
//! queued or moved. The shift a window's adjustments start from is the one in force when the
//! window was planned (`base`): before the next re-plan the reference has not moved with the
//! landing, so `e` is measured against the same plan, and the shift in force is
//! `base + offset(e)`. The shift ends with its walk: once the robot stands it is 0 from the
//! next step number on, so the next walk's steps land where commanded.
//!
//! # Limits
//! * only in a walk started with `StartAdjusting` (a `CONTROL` operation: the controller opts
//!   in per walk), only while walking or stopping, only with a measured state at most
//!   [`AdjustConfig::max_age`] cycles old, only
//!   before the foot lifts off (the next swing target), and only when the shift changes by at
//!   least [`AdjustConfig::min_change`];
//! * the reach limits and the sole gap ([`super::Reach`]) hold for the moved step against the
//!   feet before it and for its successors: a shift that breaks them is cut to the largest
//!   part of it (to the footstep unit, 0.5 mm) that keeps them (`ADJUST` flag *reach
//!   limited*);
//! * the shift's length is at most [`AdjustConfig::max_shift`] (0.30 m): a wanted shift
//!   beyond it (however large the deviation, even beyond `ADJUST`'s fields) is cut to it along
//!   its direction, so no measured state moves the path farther from the commanded one;
//! * a measured state claiming a deviation beyond [`AdjustConfig::max_deviation`] (1.0 m) is
//!   refused `OutOfRange` (plausibility: the robot would have fallen whatever the step);
//! * eq. 17 checks the moved next swing target as it checks a modification (the ZMP stays in
//!   the sole): a shift it refuses is put back and the next attempt in this window takes half
//!   of it (flag *ZMP limited*);
//! * it plans (eq. 17), so it takes the cycle's planning budget ([`super::NodeConfig::max_plans`]):
//!   it runs after the commands that do not plan and before a modification of the next swing
//!   target (which is then refused `Busy` if the adjustment planned), and in a walk that
//!   adjusts its work ([`super::WORK_ADJUST`]) is kept from the commands' budget, so footstep
//!   frames never crowd it out; only a `Start` in the same cycle (which planned) defers it.
//!
//! # From the measured state (an option)
//! With [`AdjustConfig::from_measured`] the re-plan that lifts a capture step's foot starts
//! from the measured state: every cycle the node hands the gait the fresh deviation `e`, the
//! move this window made for it and the margin ([`crate::gait::Gait::set_measured`]), and
//! the window starts with the divergent component moved by the part of `e` that the move
//! captures ([`crate::capture::captured_deviation`]), if eq. 17 holds for it. The try is a
//! plan of its cycle: it takes the cycle's plan and a plan's work from the budget (a
//! modification of the next swing target after it is refused `Busy`), and a lift-off cycle
//! whose step adjustment planned (moved the step) re-plans from the reference's state, on the
//! plan eq. 17 checked; so the tick plans at most once beyond the budget. The
//! reference's COG velocity then steps at that tick; off by default, where the reference
//! stays C¹ as the paper keeps it. A state measured against a reference before that step is
//! refused as stale (and one taken already is no longer fresh): it counts a deviation that
//! the window took as its own. Such a re-plan may plan twice in its cycle (the measured try,
//! then the reference's state if eq. 17 refuses it): the first is the one the budget counts.
//! The timing table's worst admissible cycle includes a log with the option on.
//!
//! Every change of the shift is sent in `ADJUST` (and repeated every 100 ms while the walk
//! adjusts or once the session has adjusted), so that
//! the controller's book of the steps stays true.

use super::*;
use crate::capture::capture_offset;
use crate::gait::Deviation;
use crate::wire::{Adjust, Measured, STAMPS, STEP_UNIT};

/// The bound of [`AdjustConfig::max_age`] \[cycles\].
pub const MAX_AGE: u32 = 40;

/// The bound of [`AdjustConfig::max_shift`] \[m\]: what `ADJUST`'s 16-bit fields of 0.5 mm
/// carry.
pub const MAX_SHIFT: f64 = 16.0;

/// The step adjustment's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdjustConfig<T = f64> {
    /// The oldest measured state used \[cycles\] (at most [`MAX_AGE`]).
    pub max_age: u32,
    /// The ZMP margin `m` the robot's stabilizer has in the support sole \[m\]: a deviation
    /// within it is the stabilizer's to absorb (no step).
    pub margin: T,
    /// The least change of the shift that is carried out \[m\].
    pub min_change: T,
    /// The farthest the node moves the path from the commanded one \[m\]: the shift's length
    /// never exceeds it (a wanted shift beyond it is cut to it along its direction), so no
    /// measured state, true or not, moves a landing farther from where it was commanded.
    /// At most [`MAX_SHIFT`].
    pub max_shift: T,
    /// The largest deviation a measured state may claim \[m\] (plausibility): beyond it the
    /// robot has fallen whatever the step, and a state that claims more is refused
    /// `OutOfRange` (it changes nothing).
    pub max_deviation: T,
    /// The re-plan that lifts a capture step's foot starts from the measured state (see
    /// [`crate::gait::Gait::set_measured`]): the reference's COG velocity then steps by the
    /// captured deviation times `ω` at that tick (its position, acceleration and ZMP stay
    /// continuous). `false` (the default): from the reference's state, as every other re-plan,
    /// and the reference stays C¹.
    pub from_measured: bool,
}

impl AdjustConfig {
    /// 4 cycles (20 ms), a 20 mm margin, 5 mm changes, the path moved by at most 0.30 m
    /// (about a step's length: what one capture step can move), measured deviations up to
    /// 1.0 m (a COG velocity error of about 3.5 m/s at HRP-2's `ω`, ten times the pushes
    /// the robot survives), capture steps re-planned from the reference's state (the
    /// reference stays C¹).
    pub const DEFAULT: Self = Self {
        max_age: 4,
        margin: 0.02,
        min_change: 0.005,
        max_shift: 0.30,
        max_deviation: 1.0,
        from_measured: false,
    };
}

impl<T: Real> AdjustConfig<T> {
    /// This configuration in the scalar `T`.
    pub fn cast<U: Real>(&self) -> AdjustConfig<U> {
        AdjustConfig {
            max_age: self.max_age,
            margin: U::of(self.margin.f64()),
            min_change: U::of(self.min_change.f64()),
            max_shift: U::of(self.max_shift.f64()),
            max_deviation: U::of(self.max_deviation.f64()),
            from_measured: self.from_measured,
        }
    }
}

/// What the node keeps for its step adjustment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Adjusting<T> {
    /// The last measured state taken: the node cycle it names and its DCM's deviation from
    /// that cycle's reference.
    pub measured: Option<(u32, [T; 2])>,
    /// The walk being walked adjusts its steps (it was started with `StartAdjusting`).
    pub enabled: bool,
    /// The cycle in which the open session opened (a measured state before it is another
    /// session's).
    pub opened_at: u32,
    /// The shift in force \[0.5 mm\], and the number of the first step it applies to.
    pub shift: [i32; 2],
    pub from: u16,
    /// The shift in force when the window being executed was planned, with the window's count.
    pub base: [i32; 2],
    pub base_plans: u32,
    /// The fraction (a power of ½) of the offset tried after eq. 17 refused one in this window.
    pub halvings: u8,
    /// Adjustments since the session opened (saturating), and `ADJUST`'s flags.
    pub count: u8,
    pub flags: u8,
    /// `ADJUST` is due (the shift changed).
    pub due: bool,
    /// Moves the node worked on (the reach's bisection, eq. 17's check) since the session
    /// opened, carried out or not (wrapping): what a cycle's cost is classified by.
    pub attempts: u32,
}

impl<T: Real> Adjusting<T> {
    /// Nothing measured, no shift (every byte zero).
    pub const ZERO: Self = Self {
        measured: None,
        enabled: false,
        opened_at: 0,
        shift: [0; 2],
        from: 0,
        base: [0; 2],
        base_plans: 0,
        halvings: 0,
        count: 0,
        flags: 0,
        due: false,
        attempts: 0,
    };
}

/// `d·k/n` rounded toward zero, for `n ≥ 1`, `0 ≤ k ≤ n` and `|d| ≤ n` (the part `k/n` of a
/// move's component `d`): in 32 bits when `n²` fits them (a move of up to 23 m, in 0.5 mm; a
/// 64-bit division is a library call on the target), else in 64; the same value either way.
fn fraction(d: i32, k: i64, n: i64) -> i32 {
    // (`n` ≥ 1: the checked divisions only keep a panic out of the code)
    if (1..=46_340).contains(&n) {
        // |d·k| ≤ n² < 2³¹
        return d.wrapping_mul(k as i32).checked_div(n as i32).unwrap_or(0);
    }
    (i64::from(d) * k).checked_div(n).unwrap_or(0) as i32
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// Takes (or refuses) a measured state (see the module docs of [`crate::wire`] for its
    /// freshness rules).
    pub(super) fn measured(&mut self, m: &Measured) -> Result<(), Reason> {
        if !self.open {
            return Err(Reason::NoSession);
        }
        if self.estopped {
            return Err(Reason::EmergencyStopped);
        }
        if self.lost {
            return Err(Reason::ControllerLost);
        }
        let e = m.deviation_in::<T>();
        // (`!(… <= …)`: a bound that is not a number refuses every state.)
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !((e[0] * e[0] + e[1] * e[1]).sqrt() <= self.cfg.adjust.max_deviation) {
            return Err(Reason::OutOfRange);
        }
        // The last reference published is this cycle's predecessor's.
        if self.cycle >= STAMPS {
            return Err(Reason::Exhausted);
        }
        let latest = self.cycle.wrapping_sub(1);
        let age = latest.wrapping_sub(m.stamp) & (STAMPS - 1);
        if age > self.cfg.adjust.max_age || age > latest {
            return Err(Reason::Stale);
        }
        let at = latest - age;
        if at < self.adj.opened_at {
            return Err(Reason::WrongSession);
        }
        if self.before_jump(at) {
            return Err(Reason::Stale);
        }
        match self.adj.measured {
            Some((last, _)) if last == at => return Err(Reason::Duplicate),
            Some((last, _)) if last > at => return Err(Reason::Stale),
            _ => {}
        }
        self.adj.measured = Some((at, e));
        Ok(())
    }

    /// The measured state's deviation and the cycle it names, if fresh (at most `max_age`
    /// cycles old).
    fn fresh_measurement(&self) -> Option<(u32, [T; 2])> {
        let (at, e) = self.adj.measured?;
        let age = self.cycle.wrapping_sub(1).wrapping_sub(at);
        (age <= self.cfg.adjust.max_age && !self.before_jump(at)).then_some((at, e))
    }

    /// A state measured against the reference of cycle `at` predates the step of the
    /// reference to the measured state ([`AdjustConfig::from_measured`] only; see
    /// [`Self::jumped_at`]).
    fn before_jump(&self, at: u32) -> bool {
        self.cfg.adjust.from_measured && at < self.jumped_at()
    }

    /// The first cycle whose reference a measured state may be compared with: the cycle of
    /// the re-plan that started the window being executed from the measured state (the
    /// reference's divergent component stepped there, so a state measured against an earlier
    /// reference counts a deviation the window has taken as its own), else 0. Called between
    /// ticks: the gait ticks once a cycle, so the re-plan's cycle is the last published one
    /// less the gait's ticks since. Out of line, so that a cycle without the option pays for
    /// one test of it.
    #[inline(never)]
    fn jumped_at(&self) -> u32 {
        if !self.gait.replanned_from_measured() {
            return 0;
        }
        let Some(info) = self.gait.last_replan() else {
            return 0;
        };
        let since = self
            .gait
            .ticks()
            .saturating_sub(info.tick)
            .min(u64::from(u32::MAX));
        self.cycle.wrapping_sub(1).saturating_sub(since as u32)
    }

    /// The shift of the steps from `shift` to `to` \[0.5 mm\] placed in the gait: every queued
    /// step at its commanded position plus `to`. `false` if a position leaves the footstep
    /// range (nothing moved then).
    fn place_shift(&mut self, to: [i32; 2]) -> bool {
        if !self.steps.all_shiftable(to) {
            return false;
        }
        let (steps, first) = (&self.steps, self.first);
        self.gait.place_steps(|id| {
            steps
                .commanded(id.wrapping_add(first), to)
                .map(Self::position)
        });
        true
    }

    fn position(s: WireStep) -> [T; 2] {
        let (x, y, _) = s.si_in::<T>();
        [x, y]
    }

    /// `true` while the step adjustment works on the walk: one started with `StartAdjusting`,
    /// in an open session, neither emergency-stopped nor with the controller lost.
    pub(super) fn adjusts(&self) -> bool {
        self.adj.enabled && self.open && !self.estopped && !self.lost && !self.gait.is_standing()
    }

    /// The step adjustment of this cycle (see the module docs): after the commands, before the
    /// supervision and the tick. Kept out of `poll` (which it would otherwise crowd).
    #[inline(never)]
    pub(super) fn adjust_step(&mut self) {
        let fresh = self.fresh_measurement();
        self.adj.flags &= !Adjust::FRESH;
        if fresh.is_some() {
            self.adj.flags |= Adjust::FRESH;
        }
        let adjusting = self.adjusts();
        if adjusting {
            self.move_steps(fresh);
        }
        // What a re-plan of a capture step starts from: the fresh measurement and the move
        // this window made for it (nothing without a fresh state or a move). The try is a plan
        // of the cycle (its budget): in the cycle whose tick re-plans, it takes the cycle's plan
        // and a plan's work, so that the tick plans at most once more, uncounted (the plan from
        // the reference's state if eq. 17 refuses the try); a cycle whose step adjustment
        // planned (eq. 17 of a move) re-plans from the reference's state, on that plan.
        let (shift, base) = (self.adj.shift, self.adj.base);
        let tries = adjusting && self.cfg.adjust.from_measured && shift != base;
        let charged = tries && (!self.gait.replans_next_tick() || self.charge_plan());
        let measured = match fresh {
            Some((_, e)) if charged => {
                let unit = T::of(STEP_UNIT);
                let moved = |k: usize| T::of_i32(shift[k].saturating_sub(base[k])) * unit;
                Deviation {
                    error: e,
                    moved: [moved(0), moved(1)],
                    margin: self.cfg.adjust.margin,
                }
            }
            _ => Deviation::ZERO,
        };
        self.gait.set_measured(measured);
    }

    /// Takes a plan and its work ([`WORK_PLAN`]) from the cycle's budget, if it has them.
    fn charge_plan(&mut self) -> bool {
        if self.plans_left == 0 || self.afford(WORK_PLAN).is_err() {
            return false;
        }
        self.plans_left -= 1;
        self.spend(WORK_PLAN);
        true
    }

    /// The move of the steps for a fresh measured state (see the module docs).
    fn move_steps(&mut self, fresh: Option<(u32, [T; 2])>) {
        let plans = self.gait.plans();
        if plans != self.adj.base_plans {
            self.adj.base = self.adj.shift;
            self.adj.base_plans = plans;
            self.adj.halvings = 0;
        }
        let Some((at, e)) = fresh else {
            return;
        };
        let Some(front) = self.gait.next_target() else {
            return;
        };
        let number = front.wrapping_add(self.first);
        if self.plans_left == 0 || self.afford(WORK_ADJUST).is_err() {
            return;
        }
        let Some(ticks) = self.gait.ticks_to_next_landing() else {
            return;
        };
        let p = &self.cfg.params;
        let n = ticks.saturating_add(self.cycle.wrapping_sub(1).wrapping_sub(at));
        let remaining = p.dt * T::of_i32(n.min(1 << 20) as i32);
        let offset = capture_offset(e, self.cfg.adjust.margin, p.omega, remaining);
        let unit = T::of(STEP_UNIT);
        // The shift wanted: the window's base and the offset (a power of ½ of it after eq. 17
        // refused more), cut along its direction to `max_shift` (which `ADJUST`'s fields
        // carry): however large the deviation, the node tries the largest shift it allows.
        let half = T::of_i32(1 << self.adj.halvings.min(8));
        let mut wanted_m = [
            T::of_i32(self.adj.base[0]) * unit + offset[0] / half,
            T::of_i32(self.adj.base[1]) * unit + offset[1] / half,
        ];
        if !(wanted_m[0].is_finite() && wanted_m[1].is_finite()) {
            return;
        }
        let length = (wanted_m[0] * wanted_m[0] + wanted_m[1] * wanted_m[1]).sqrt();
        let max_shift = self.cfg.adjust.max_shift;
        if length > max_shift {
            wanted_m = [
                wanted_m[0] * max_shift / length,
                wanted_m[1] * max_shift / length,
            ];
        }
        // (within ±MAX_SHIFT: the integers are exact, the clamp only keeps them so)
        let units = |v: T| {
            (v / unit)
                .round()
                .max(T::of(-32767.0))
                .min(T::of(32767.0))
                .trunc_i32()
        };
        let wanted = [units(wanted_m[0]), units(wanted_m[1])];
        let delta = [wanted[0] - self.adj.shift[0], wanted[1] - self.adj.shift[1]];
        let (dx, dy) = (T::of_i32(delta[0]), T::of_i32(delta[1]));
        let change = (dx * dx + dy * dy).sqrt() * unit;
        if change < self.cfg.adjust.min_change {
            return;
        }
        // Only a move spends the adjustment's share: a state that moves nothing leaves it to
        // the modification that plans. The reach cut's part now, eq. 17's (a plan's work) when
        // it plans: a move the reach cuts to nothing leaves a plan's work to the cycle.
        self.spend(WORK_ADJUST.saturating_sub(WORK_PLAN));
        self.adj.attempts = self.adj.attempts.wrapping_add(1);
        let old = self.adj.shift;
        let mut flags = self.adj.flags & Adjust::FRESH;
        // The reach: the whole move if it keeps the limits, else the largest part of it that
        // does, to the footstep unit (bisection on k/n of the move, n its longer component in
        // 0.5 mm: at most 16 halvings; the limits are checked on the moved step and its
        // successor, the steps after them keeping their places relative to both).
        let (k, n) = self.reach_cut(front, old, delta);
        if k < n {
            flags |= Adjust::REACH_LIMITED;
        }
        let part = |k: i64| {
            let at = |o: i32, d: i32| o + fraction(d, k, n);
            [at(old[0], delta[0]), at(old[1], delta[1])]
        };
        let to = part(k);
        if k == 0 || !self.place_shift(to) {
            self.adj.flags = flags | Adjust::REACH_LIMITED;
            return;
        }
        // Eq. 17 (plans: the cycle's budget).
        self.plans_left = self.plans_left.saturating_sub(1);
        self.spend(WORK_PLAN);
        if self.gait.check_next_target().is_err() {
            let _ = self.place_shift(old);
            self.adj.halvings = self.adj.halvings.saturating_add(1);
            self.adj.flags = flags | Adjust::ZMP_LIMITED;
            return;
        }
        self.adj.shift = to;
        self.adj.from = number;
        self.adj.count = self.adj.count.saturating_add(1);
        self.adj.flags = flags;
        self.adj.due = true;
    }

    /// The reach cut of a move of the steps from the shift `old` by `delta` \[0.5 mm\] (see
    /// `move_steps`): `(k, n)`, the move's largest part `k/n` that keeps the limits, `n` its
    /// longer component (the whole move if it keeps them, else a bisection to the footstep
    /// unit: at most 16 halvings; the limits are checked on the moved step and its successor,
    /// the steps after them keeping their places relative to both). Out of line, so that the
    /// frames it checks on are off the stack before eq. 17 plans.
    #[inline(never)]
    fn reach_cut(&mut self, front: u16, old: [i32; 2], delta: [i32; 2]) -> (i64, i64) {
        let unit = T::of(STEP_UNIT);
        let n = i64::from(delta[0].unsigned_abs().max(delta[1].unsigned_abs()).max(1));
        let part = |k: i64| {
            let at = |o: i32, d: i32| o + fraction(d, k, n);
            [at(old[0], delta[0]), at(old[1], delta[1])]
        };
        // (On the frames kept for the cycle's reach checks, fetched once for the bisection.
        // They always apply to the node's queue, whose sides alternate and whose numbers are
        // consecutive; where they would not, nothing moves.)
        let Some(kept) = self.move_frames(front) else {
            return (0, n);
        };
        let keeps = |node: &Self, k: i64| {
            let to = part(k);
            let d = [
                T::of_i32(to[0] - old[0]) * unit,
                T::of_i32(to[1] - old[1]) * unit,
            ];
            let broken = node.reach_broken_move(&kept, d);
            debug_assert!(
                broken.map(|b| (b.limit, b.value.bits()))
                    == node
                        .reach_broken_moved(front, d)
                        .map(|b| (b.limit, b.value.bits())),
                "kept frames of a move"
            );
            broken.is_none()
        };
        if keeps(self, n) {
            return (n, n);
        }
        let (mut lo, mut hi) = (0, n);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if keeps(self, mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (lo, n)
    }

    /// The end of a walk (the gait stands): the shift ends with it, so that the next walk's
    /// steps land where commanded (a `Start`'s as an adjusting one's, which adjusts afresh).
    /// The change is sent in `ADJUST` (from the next step number on, shift 0), and repeated
    /// every 100 ms as long as the session lasts, as every shift is while it is in force.
    pub(super) fn end_of_walk(&mut self) {
        if !self.gait.is_standing() || (self.adj.shift == [0, 0] && !self.adj.enabled) {
            return;
        }
        self.adj.enabled = false;
        self.adj.halvings = 0;
        if self.adj.shift != [0, 0] {
            self.adj.shift = [0, 0];
            self.adj.base = [0, 0];
            self.adj.from = self.next_step();
            self.adj.count = self.adj.count.saturating_add(1);
            self.adj.due = true;
        }
    }

    /// The step adjustment as `ADJUST` reports it.
    pub fn adjustment(&self) -> Adjust {
        let clamp = |v: i32| v.clamp(i16::MIN.into(), i16::MAX.into()) as i16;
        Adjust {
            from: self.adj.from as u8,
            shift: [clamp(self.adj.shift[0]), clamp(self.adj.shift[1])],
            count: self.adj.count,
            flags: self.adj.flags,
        }
    }

    /// The moves of the steps the node worked on since the session opened (wrapping), carried
    /// out or not: a cycle that changes it ran the step adjustment's checks (the reach's
    /// bisection, eq. 17).
    pub fn adjustment_attempts(&self) -> u32 {
        self.adj.attempts
    }

    /// The shift in force \[0.5 mm\]: every step queued from now on lands at its commanded
    /// position plus it.
    pub fn shift(&self) -> [i32; 2] {
        self.adj.shift
    }
}

#[cfg(test)]
mod tests {
    use super::fraction;

    /// The 32-bit part of a move is the 64-bit one, at the ends of its range and across it.
    #[test]
    fn the_part_of_a_move_is_the_64_bit_quotient() {
        let wide = |d: i32, k: i64, n: i64| (i64::from(d) * k / n) as i32;
        for n in [1i64, 2, 3, 599, 600, 601, 46_339, 46_340, 46_341, 65_534] {
            for d in [-n, -n + 1, -(n / 2) - 1, -1, 0, 1, n / 3, n - 1, n] {
                let d = d as i32;
                for k in [0, 1, n / 2, n / 2 + 1, n - 1, n] {
                    assert_eq!(fraction(d, k, n), wide(d, k, n), "{d}·{k}/{n}");
                }
            }
        }
    }
}
