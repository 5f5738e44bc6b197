//! The gait: footstep queue, phases, re-planning at every start of single support, and the
//! immediate modification of the next landing with the single-support adjustment of eq. 18.
//!
//! # Windows
//! The gait re-plans a 7-interval [window](crate::window) at every start of single support
//! (Fig. 2 of the paper): with `S₀` the support foot and `L₁, L₂, L₃` the next three landings,
//!
//! ```text
//! SS on S₀ (T_ss + ΔT) | DS → L₁ | SS on L₁ | DS → L₂ | SS on L₂ | DS → L₃ | tail
//! ```
//!
//! The ZMP via points are the foot centres: the support-foot centre in single support, the
//! next foot's centre at the end of double support, zero ZMP velocity at every via point.
//! Steps not given yet have zero length (the swing foot lands beside the support foot at the
//! nominal step width, the paper's rule), and the window ends with the COG at rest over its
//! last via point. The *tail* is a settling interval that brings the ZMP to the midpoint of the
//! last two footholds ([`Tail::Settle`], the default) or a single support on `L₃`
//! ([`Tail::Single`]); which of the two the paper used is not stated, and the Table II test
//! measures both.
//!
//! Walking starts from standing with a start window whose first interval is a double support
//! that shifts the ZMP from between the feet to the first support foot; it stops with a stop
//! window (the last landing, a settle to the midpoint of the feet, then standing intervals).
//! Only the first interval(s) of every window are executed: the next re-plan replaces the rest.
//!
//! # Immediate modification (section IV.A, eq. 18)
//! A queued footstep may be modified until its swing starts (the swing foot lifts off at the
//! start of single support); the step being swung and executed steps are refused with a reason.
//! When the swing target `L₁` was modified after the current window was planned, the re-plan
//! compares, at that instant, the executed pattern (`x_i`, the present reference state) with the
//! pattern that the previous re-plan would have produced had it known the footsteps as they are
//! now (`x_f`: the previous window solved again from its own initial state with the current
//! footsteps), through their divergent components `d = ω(x − p) + (ẋ − ṗ)`:
//!
//! ```text
//! r = d_f / d_i,     ΔT = ln(r) / ω  clamped to [ΔT_min, ΔT_max] and rounded to the 5 ms grid.
//! ```
//!
//! Choices where the paper is silent (each measured in the Table II test):
//! * the plane that decides is the one in which the modification moves the divergent component
//!   most (`|d_f − d_i|` larger); the other plane keeps the shaped fluctuation;
//! * a vanishing denominator (`|d_i|` below 1 mm/s·ω: the COG is not moving in that plane, e.g.
//!   walking in place) gives `ΔT = 0`: there is no motion to slow down or speed up (Table II's
//!   "before 0" column is all zeros);
//! * `r ≤ 0` (the modification reverses the motion) gives `ΔT_max` as eq. 18 says, except when
//!   `|d_f|` is itself below the threshold: the target pattern is at rest, `r → 0⁺`, and
//!   `ln r → −∞` gives `ΔT_min` (Table II's "after 0" row);
//! * a capture step (the node's own move of the landing, [`Gait::place_steps`]) takes
//!   `min(ΔT, 0)`: it must come early, so its single support is shortened, never lengthened.
//!
//! # Feasibility (eq. 17)
//! A modification of the next swing target is checked when it arrives: the re-plan it would
//! cause is computed and the worst ZMP excursion of the first interval, in the support foot's
//! frame (the ZMP polynomials rotated into the foot frame are quartics, so
//! [`worst_deviation`] gives their exact extrema), must stay inside the sole. Otherwise the
//! modification is refused with [`GaitError::Infeasible`] and the queue is unchanged.

mod active;
mod params;
mod predict;
mod queue;
pub use queue::MODIFY_FRONT;
mod reference;
mod relocate;
mod shape;
mod spec;
mod step;
mod tick;

use active::*;
pub use params::*;
use predict::*;
pub use reference::*;
use shape::*;
use spec::*;
pub use step::*;

use core::borrow::Borrow;

use heapless::Deque;

use crate::lipm::{Poly, Sample, Segment, State};
use crate::real::Real;
use crate::shaping::{
    CartTable, Compensation, Compensator, GainError, Law, Piece, PreviewConfig, PreviewGains,
};
use crate::timing::worst_deviation;
use crate::window::{Factorized, Plan, PlanError, PlaneBoundary, Timing, M};

/// A queued footstep.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Queued<T> {
    id: u16,
    step: Footstep<T>,
    /// Modified after the current window was planned.
    modified: bool,
    /// Its last move was the node's step adjustment (a capture step): eq. 18 may shorten its
    /// single support, never lengthen it.
    capture: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Standing,
    Walking,
}

/// The gait generator: a footstep queue of capacity `Q` and the window being executed.
///
/// `G` holds the preview-control gains: by value (the default, computed by [`Gait::new`]) or
/// anything that lends them ([`Borrow`]), such as a reference to gains in flash or a
/// zero-sized type that names them (the firmware keeps its 22 KB of gains out of RAM this way:
/// [`Gait::with_gains`]).
#[derive(Clone, Debug)]
pub struct Gait<T: Real, const Q: usize, G = PreviewGains<T, PREVIEW>> {
    params: GaitParams<T>,
    queue: Deque<Queued<T>, Q>,
    /// Where each foot stands (the swing foot: where it lifted off).
    feet: [Footstep<T>; 2],
    /// The step being swung, with its id.
    swing: Option<Queued<T>>,
    /// The side of the last step that landed (none since start-up or a re-basing).
    landed: Option<Side>,
    /// The last re-plan failed (see [`Gait::replan_failed`]).
    failed: bool,
    /// The queued ids are consecutive (each the successor of the one before it, `+1` modulo
    /// 2¹⁶), so they are distinct and a lookup by id is arithmetic ([`Gait::index_of`]). A lookup hint (set by `push`), always `false` while
    /// the queue is empty, so that a gait emptied and a fresh one compare equal.
    consecutive: bool,
    mode: Mode,
    stop_requested: bool,
    /// Two window buffers: the one being executed and the one the next re-plan is built in.
    wins: [Active<T>; 2],
    /// The buffer being executed, if walking.
    cur: Option<usize>,
    /// Changes whenever the footsteps or the stop request change.
    gen: u32,
    /// Changes whenever a new window becomes the current one.
    serial: u32,
    /// Cached `x_f` of eq. 18: (gen, serial, window tick, state).
    target: Option<(u32, u32, u32, [Sample<T>; 2])>,
    /// The re-plan that the feasibility check of a modification planned into the spare
    /// buffer: (gen, serial, window tick, its inputs and initial state). The re-plan at that
    /// tick takes the spare buffer as it is if all of these are still the same (the plan is a
    /// function of them: bit for bit what it would compute again).
    predicted: Option<Predicted<T>>,
    /// The worst first-interval excursion (eq. 17) of the predicted plan, for the re-plan
    /// that takes it (valid while `predicted` is `Some`).
    predicted_worst: [T; 2],
    /// Walking windows planned since the (re)start, wrapping: every prediction of eq. 17 and
    /// every re-plan that does not take a predicted plan ([`Gait::walk_plans`]).
    walk_plans: u32,
    /// The measured state the next re-plan of a capture step starts from (zero: the
    /// reference's own state); set every cycle by the node's step adjustment
    /// ([`Gait::set_measured`]).
    measured: Deviation<T>,
    /// The last re-plan started from the measured state.
    from_measured: bool,
    tick: u64,
    last: Reference<T>,
    info: Option<ReplanInfo<T>>,
    /// Preview-control gains (shared by both planes) and the two compensators.
    gains: G,
    comp: [Compensator<T>; 2],
}

/// Preview length of the shaping compensator \[ticks\] (1.6 s at 5 ms).
pub const PREVIEW: usize = 320;

impl<T: Real, const Q: usize> Gait<T, Q> {
    /// A robot standing on `left` and `right`, its COG at rest above their midpoint. Computes
    /// the preview-control gains (once; about 1100 Riccati iterations).
    pub fn new(
        params: GaitParams<T>,
        left: Footstep<T>,
        right: Footstep<T>,
    ) -> Result<Self, GaitError> {
        let gains = Self::gains_for(&params, &left, &right)?;
        Self::with_gains(params, left, right, gains)
    }

    /// The preview gains [`Gait::new`] computes for `params` (all zero when it does not shape),
    /// after the checks of [`Gait::restart`] (whose errors come first).
    pub(crate) fn gains_for(
        params: &GaitParams<T>,
        left: &Footstep<T>,
        right: &Footstep<T>,
    ) -> Result<PreviewGains<T, PREVIEW>, GaitError> {
        Self::check(params, left, right)?;
        let mut gains = PreviewGains::zeroed();
        if params.shaping {
            gains
                .compute(&params.preview_config(), Law::FromRest)
                .map_err(GaitError::Gains)?;
        }
        Ok(gains)
    }
}

impl<T: Real, const Q: usize, G> Gait<T, Q, G> {
    /// A gait that is not configured yet, holding `gains`: zero parameters, both feet at the
    /// origin, empty buffers. Its one use is to be configured in place by
    /// [`Gait::restart`] (the node's [`ParkedNode`](crate::node::ParkedNode)): a `static`
    /// initialised with it needs no start-up stack, and, when `G` is zero-sized (gains named
    /// by a type, not a reference), no flash either, because every byte of it is zero (the
    /// fields with a niche hold the value whose bytes are zero, e.g. `Some(Side::Left)`; the
    /// firmware's size check fails if the node's static leaves .bss). Not a gait to tick.
    pub(crate) const fn parked(gains: G) -> Self {
        Self {
            params: GaitParams::PARKED,
            queue: Deque::new(),
            feet: [Footstep::PARKED; 2],
            swing: Some(Queued {
                id: 0,
                step: Footstep::PARKED,
                modified: false,
                capture: false,
            }),
            landed: Some(Side::Left),
            failed: false,
            consecutive: false,
            mode: Mode::Standing,
            stop_requested: false,
            wins: [Active::PARKED, Active::PARKED],
            cur: None,
            gen: 0,
            serial: 0,
            predicted: Some(Predicted {
                gen: 0,
                serial: 0,
                at: 0,
                inputs: Inputs::PARKED,
                cog: [State::ZERO; 2],
                zmp: [State::ZERO; 2],
            }),
            predicted_worst: [T::ZERO; 2],
            walk_plans: 0,
            measured: Deviation::ZERO,
            from_measured: false,
            target: None,
            tick: 0,
            last: Reference {
                x: Sample::ZERO,
                y: Sample::ZERO,
                phase: Phase::Single(Side::Left),
                feet: [FootPose {
                    x: T::ZERO,
                    y: T::ZERO,
                    z: T::ZERO,
                    yaw: T::ZERO,
                }; 2],
            },
            info: None,
            gains,
            comp: [Compensator::new(), Compensator::new()],
        }
    }

    /// Why `params`, `left` and `right` start no gait (in [`Gait::restart`]'s order), if they
    /// do not.
    fn check(
        params: &GaitParams<T>,
        left: &Footstep<T>,
        right: &Footstep<T>,
    ) -> Result<(), GaitError> {
        if !(left.is_finite() && right.is_finite()) {
            return Err(GaitError::NonFinite);
        }
        params.validate()
    }
}

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    /// [`Gait::new`] with preview gains computed beforehand (the firmware compiles them into
    /// flash from the robot file) and lent by `gains` (a reference, or a type that names
    /// them: nothing is copied). `Gains(BadConfig)` unless they are the gains [`Gait::new`]
    /// would compute for `params` ([`PreviewGains::are_for`]); not used when `params.shaping`
    /// is off.
    pub fn with_gains(
        params: GaitParams<T>,
        left: Footstep<T>,
        right: Footstep<T>,
        gains: G,
    ) -> Result<Self, GaitError> {
        let mut g = Self::parked(gains);
        g.restart(params, left, right)?;
        Ok(g)
    }

    /// Makes this gait, in place, the one [`Gait::with_gains`] would build for `params`,
    /// `left` and `right` with its own gains: standing, the queue empty, the buffers unused,
    /// tick 0. Nothing is built on the stack (the gait is 12 KB; a `static` parked gait, inside
    /// a [`ParkedNode`](crate::node::ParkedNode), is configured this way). On error (the same checks and the same
    /// errors as [`Gait::with_gains`]) nothing changes.
    pub fn restart(
        &mut self,
        params: GaitParams<T>,
        left: Footstep<T>,
        right: Footstep<T>,
    ) -> Result<(), GaitError> {
        Self::check(&params, &left, &right)?;
        if params.shaping
            && !self
                .gains
                .borrow()
                .are_for(&params.preview_config(), Law::FromRest)
        {
            return Err(GaitError::Gains(GainError::BadConfig));
        }
        let mut left = left;
        let mut right = right;
        left.side = Side::Left;
        right.side = Side::Right;
        let feet = [left, right];
        let mid = midpoint(left.centre(), right.centre());
        let at = |v: T| Sample {
            cog: v,
            zmp: v,
            ..Sample::default()
        };
        self.params = params;
        self.queue.clear();
        self.consecutive = false;
        self.feet = feet;
        self.swing = None;
        self.landed = None;
        self.failed = false;
        self.mode = Mode::Standing;
        self.stop_requested = false;
        for w in &mut self.wins {
            w.clear(&params, &feet);
        }
        self.cur = None;
        self.gen = 0;
        self.serial = 0;
        self.predicted = None;
        self.predicted_worst = [T::ZERO; 2];
        self.walk_plans = 0;
        self.measured = Deviation::ZERO;
        self.from_measured = false;
        self.target = None;
        self.tick = 0;
        self.last = Reference {
            x: at(mid[0]),
            y: at(mid[1]),
            phase: Phase::Standing,
            feet: [FootPose::default(); 2],
        };
        self.info = None;
        self.comp = [Compensator::new(), Compensator::new()];
        self.last.feet = self.ground_poses();
        Ok(())
    }

    /// The parameters.
    pub fn params(&self) -> &GaitParams<T> {
        &self.params
    }

    /// The reference of the last tick.
    pub fn last(&self) -> &Reference<T> {
        &self.last
    }

    /// What the last re-plan did.
    pub fn last_replan(&self) -> Option<&ReplanInfo<T>> {
        self.info.as_ref()
    }

    /// How many windows have been planned and made current since the last (re)start,
    /// wrapping: the start window, every re-plan and every stop window. A change between two
    /// ticks means the tick in between planned one.
    pub fn plans(&self) -> u32 {
        self.serial
    }

    /// How many walking windows have been planned since the last (re)start, wrapping: every
    /// check of eq. 17 (the re-plan a modification or a move of the next swing target will
    /// cause, planned ahead) and every re-plan at a start of single support that does not take
    /// the plan predicted for it. What a cycle's planning costs is counted by it.
    pub fn walk_plans(&self) -> u32 {
        self.walk_plans
    }

    /// Where the foot of the other side than `side` will be just before a step of `side` is
    /// taken: the last such step queued before the step `before` (or before the end of the
    /// queue), else the one being swung, else where that foot stands. Used to check reach.
    pub fn previous_other(&self, side: Side, before: Option<u16>) -> Footstep<T> {
        self.previous_feet(before)[side.other().index()]
    }

    /// Where each foot will stand just before the queued step `before` is taken (or after the
    /// whole queue, for `None`), indexed by side (`[left, right]`): the last queued step of that
    /// side before it, else the swing target of that side, else where the foot stands. One
    /// pass over the queue for both feet ([`previous_other`](Self::previous_other) is one of
    /// them).
    #[inline]
    pub fn previous_feet(&self, before: Option<u16>) -> [Footstep<T>; 2] {
        let mut last: [Option<&Footstep<T>>; 2] = [None, None];
        // Backwards from the step before `before`: the queue alternates sides, so two steps
        // settle both (the first of each side met is the last before `before`).
        let end = before
            .and_then(|id| self.index_of(id))
            .unwrap_or(self.queue.len());
        for i in (0..end).rev() {
            if let Some(q) = self.queue.get(i) {
                let l = &mut last[q.step.side.index()];
                if l.is_none() {
                    *l = Some(&q.step);
                }
            }
            if last[0].is_some() && last[1].is_some() {
                break;
            }
        }
        let resolve = |side: Side| match (last[side.index()], self.swing) {
            (Some(step), _) => *step,
            (None, Some(s)) if s.step.side == side => s.step,
            (None, _) => self.feet[side.index()],
        };
        [resolve(Side::Left), resolve(Side::Right)]
    }

    /// `true` if the step `id` is queued (not yet swung).
    pub fn is_queued(&self, id: u16) -> bool {
        self.index_of(id).is_some()
    }

    /// `true` if the queued ids are consecutive (each the one before it plus one, modulo
    /// 2¹⁶): the step `id + k` is then `k` places after the step `id`. Always `false` with
    /// nothing queued.
    pub fn consecutive_ids(&self) -> bool {
        self.consecutive
    }

    /// The position of the first queued step `id`. With consecutive ids (every walk the node
    /// drives) the position is `id − front` (modulo 2¹⁶), checked; otherwise a search of the
    /// queue.
    fn index_of(&self, id: u16) -> Option<usize> {
        let front = self.queue.front()?.id;
        if self.consecutive && Q <= 256 {
            // At most 256 consecutive ids are distinct: the one match is there, if anywhere.
            let i = usize::from(id.wrapping_sub(front));
            return self.queue.get(i).is_some_and(|q| q.id == id).then_some(i);
        }
        self.queue.iter().position(|q| q.id == id)
    }

    /// The id of the next swing target (the first queued step), if any. While walking, a
    /// modification of this step plans the re-plan it will cause (eq. 17).
    pub fn next_target(&self) -> Option<u16> {
        self.queue.front().map(|q| q.id)
    }

    /// The footstep at queue position `pos` (0: the next swing target), if any.
    pub fn queued_at(&self, pos: usize) -> Option<Footstep<T>> {
        self.queue.get(pos).map(|q| q.step)
    }

    /// A number that changes whenever the footsteps or the stop request change (wrapping): what
    /// is computed from the queued steps may be kept while it stays the same.
    pub fn generation(&self) -> u32 {
        self.gen
    }

    /// The footstep queued as `id` (not yet swung), if any.
    pub fn queued_step(&self, id: u16) -> Option<Footstep<T>> {
        self.index_of(id)
            .and_then(|i| self.queue.get(i))
            .map(|q| q.step)
    }

    /// The id of the step being swung, if any.
    pub fn swinging(&self) -> Option<u16> {
        self.swing.map(|s| s.id)
    }

    /// Number of queued steps (not counting the one being swung).
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// `true` while standing still.
    pub fn is_standing(&self) -> bool {
        self.mode == Mode::Standing
    }

    /// Ticks since the gait was created.
    pub fn ticks(&self) -> u64 {
        self.tick
    }

    /// The side the next appended step must have; `None` only when either foot may step
    /// (standing, with nothing queued, and no step landed since start-up or the last
    /// [`Gait::rebase`]). Steps always alternate: the other side than the last queued step,
    /// else than the step being swung, else than the support foot of the current window's
    /// next single support (while walking, the foot that will swing next is fixed by the
    /// plan), else than the last step that landed.
    pub fn next_side(&self) -> Option<Side> {
        if let Some(b) = self.queue.back() {
            return Some(b.step.side.other());
        }
        if let Some(s) = self.swing {
            return Some(s.step.side.other());
        }
        if let Some(c) = self.cur_buf() {
            let w = &self.wins[c];
            if let Some(side) = w
                .spec
                .replan
                .and_then(|j| w.spec.support.get(j).copied().flatten())
            {
                return Some(side.other());
            }
        }
        self.landed.map(Side::other)
    }
}
