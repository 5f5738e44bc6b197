//! Walking at a velocity and to a goal: the node chooses the footsteps itself
//! ([`velocity::Stepping`](super::velocity::Stepping)) from a `VELOCITY` stream or a `GOAL`.
//!
//! * **Ahead.** While it drives, the node keeps [`AHEAD`] steps queued (the three future steps
//!   the method re-plans with): at every cycle the steps that lifted off are replaced by the
//!   next ones at the end of the queue, each from the one before it.
//! * **A change.** A new velocity (or goal) re-plans every queued step whose foot has not lifted
//!   off, the next swing target first, in the cycle the command is accepted: the change shows
//!   in the very next landing that may still move. The queue is made up to [`AHEAD`] steps
//!   with it (or shortened to the step that closes the feet, for a stop), and the re-plan is
//!   checked once on that final queue and stop, as a modification of the next swing target is
//!   (eq. 17, all steps in place); if refused, nothing changes and the command is refused with
//!   the reason (`Infeasible`). So nothing is appended or dropped after that check in its
//!   cycle (the queue is full, or the walk stops): the re-plan at a start of single support in
//!   the same cycle takes its plan and plans no second time, and it sees the [`AHEAD`] steps
//!   it lands with.
//! * **Work.** Generating a step costs [`WORK_GENERATE`] (its cuts and up to 1 + `HALVINGS`
//!   reach checks), appending it [`WORK_APPEND`] more; a change costs [`AHEAD`] generations,
//!   the appends that make the queue up and a plan ([`WORK_PLAN`]: eq. 17), a start from
//!   standing [`AHEAD`] generations and appends and the start window's plan. All of it is charged to
//!   the cycle's budget like any command: a command whose work does not fit is refused `Busy`
//!   (nothing changed: it is sent again), a step of the queue that does not fit waits for the
//!   next cycle (the queue holds two more). The cheap checks come first (the step numbers
//!   left for the steps it appends, `Exhausted`: walking, once the steps are known, so that
//!   a stop, which appends none, is never refused for them); a command refused once its steps are generated (a step out of the
//!   walking area, a re-plan eq. 17 refuses) is charged the generation (and the plan it
//!   tried), so no burst of frames does more work in a cycle than the budget.
//! * **Saturation.** A velocity the legs cannot take is walked at the nearest one they can; the
//!   `ACK` says which components were cut ([`crate::wire::Ack::cut`]) and `STATUS` flags the
//!   cut while it lasts.
//! * **Stopping.** A zero velocity re-plans the next swing target as the step that closes the
//!   feet (parallel, at the nominal width), drops the queued steps after it (their numbers are
//!   given to the next steps generated) and requests a stop: the robot lands the foot it
//!   swings, closes its feet and stands (a goal reached stops the same way). While it stops,
//!   a zero velocity is taken (it changes nothing: a stick held at zero streams it). The stop
//!   is the drive's own (as is a goal's, once reached): while a step queued after the one
//!   being swung has not lifted off, another velocity or a goal cancels it and re-plans the
//!   queued steps as any change does; once none is left, it is refused `WrongState` (and
//!   taken once the robot stands). A controller's `Stop` or
//!   `StopNow` is not cancelled by a velocity. A `VELOCITY` stream that stops for longer than
//!   [`NodeConfig::velocity_timeout_ms`] (by the clock or by the cycles) while the robot walks
//!   at a velocity stops it as a lost controller does (the state *controller lost*: the queue
//!   dropped, a `Reset` needed once standing). Only an accepted `VELOCITY` keeps the stream
//!   alive: a refused one (stale, replayed, repeated, of another session) does not, and a
//!   heartbeat keeps the controller alive, not the stream.
//! * **Goal.** A `GOAL` (x, y, θ relative to the midpoint of the feet and their mean heading
//!   when accepted) is walked as a velocity that each generated step recomputes from what is
//!   left: `(dx / Tₛ, dy / 2Tₛ, dθ / 2Tₛ)` in the frame of the stance the step leaves from,
//!   cut to the legs as any velocity (so the walk turns, moves across and forward together,
//!   on an arc-like path, each at most what one step can take). When the stance is within
//!   [`GOAL_TOLERANCE`] and [`GOAL_YAW_TOLERANCE`] of the goal, the next step closes the feet
//!   and the robot stops. `STATUS` flags the arrival while the robot stands within those
//!   tolerances of the goal given in this session, with no other walk since (a velocity,
//!   footsteps; a `Reset` ends it too).
//! * **Mixing.** While the node drives, footstep commands are refused `WrongState` (the steps
//!   are the node's); a `Stop` or `StopNow` stops as for any walk; once standing, the
//!   controller's footsteps are taken again. A velocity or goal is refused `WrongState` while
//!   the controller's steps are queued or walked.

use super::velocity::{Saturation, Stepping, Velocity};
use super::*;
use crate::wire::{WireGoal, WireVelocity, SEQ_ADVANCE};

/// Steps the node keeps queued while it drives.
pub const AHEAD: usize = 3;
const _: () = assert!(AHEAD <= crate::gait::MODIFY_FRONT);

/// See the module docs: generating one step (the cuts in closed form, at most
/// 1 + [`HALVINGS`](super::velocity::HALVINGS) reach checks, the step record), estimated as seven of
/// the checks that [`WORK_STEP`] counts three of (each try, as those checks, computes only the
/// step's frame: the feet's frames are computed once for all tries).
pub const WORK_GENERATE: u32 = 4_900;

/// The most work one `VELOCITY` or `GOAL` can need: a start from standing ([`AHEAD`]
/// generations and appends and the start window's plan). A re-plan while walking needs no
/// more ([`AHEAD`] generations, the appends that make the queue up and eq. 17's plan). [`NodeConfig::work_budget`] is at least this
/// (checked at start-up), so a drive command refused `Busy` fits a later cycle.
pub const WORK_DRIVE: u32 = AHEAD as u32 * (WORK_GENERATE + WORK_APPEND) + WORK_PLAN;

/// How near the stance must come to a goal's position \[m\] (each of x and y).
pub const GOAL_TOLERANCE: f64 = 0.02;
/// How near the stance must come to a goal's heading \[rad\].
pub const GOAL_YAW_TOLERANCE: f64 = 0.035;

/// Who chooses the footsteps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Driver {
    /// The controller, by footstep commands.
    Steps,
    /// The node, from a `VELOCITY` stream.
    Velocity,
    /// The node, toward a `GOAL`.
    Goal,
}

/// What the node keeps of the velocity or goal it walks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Drive<T> {
    pub(super) driver: Driver,
    /// The velocity in force (as commanded; for a goal, the last one computed).
    pub(super) v: Velocity<T>,
    /// What was cut of it.
    pub(super) cut: Saturation,
    /// When the last `VELOCITY` was accepted: the clock and the cycle.
    pub(super) heard_ms: u32,
    pub(super) heard_cycle: u32,
    /// The goal in the node's frame: x, y, heading.
    pub(super) goal: [T; 3],
    /// A `GOAL` was accepted in this session and no other walk (a velocity, footsteps) since:
    /// `goal` is the one whose arrival `STATUS` may report.
    pub(super) goal_given: bool,
    /// The stop under way is the drive's own (a zero velocity, a goal reached): a velocity or
    /// a goal may cancel it while a step that has not lifted off is queued.
    pub(super) own_stop: bool,
}

impl<T: Real> Drive<T> {
    pub(super) const ZERO: Self = Self {
        driver: Driver::Steps,
        v: Velocity::ZERO,
        cut: Saturation {
            forward: false,
            lateral: false,
            turn: false,
            in_place: false,
        },
        heard_ms: 0,
        heard_cycle: 0,
        goal: [T::ZERO; 3],
        goal_given: false,
        own_stop: false,
    };
}

/// The steps a drive planned (`Node::plan_drive`).
struct Planned<T> {
    steps: [Footstep<T>; AHEAD],
    /// What was cut of them.
    cut: Saturation,
    /// A zero velocity or the goal reached: the robot stops after them.
    stop: bool,
    /// The velocity of the first (for a goal, the one computed).
    v: Velocity<T>,
    /// The steps kept: a stop keeps those up to the one that closes the feet.
    keep: usize,
}

fn is_zero<T: Real>(v: &Velocity<T>) -> bool {
    v.vx == T::ZERO && v.vy == T::ZERO && v.wz == T::ZERO
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// Who chooses the footsteps now.
    pub fn driver(&self) -> Driver {
        self.drive.driver
    }

    /// The velocity in force while the node drives (for a goal, the last one it computed) and
    /// what was cut of it; `None` while the controller gives the footsteps.
    pub fn drive_velocity(&self) -> Option<(Velocity<T>, Saturation)> {
        (self.drive.driver != Driver::Steps).then_some((self.drive.v, self.drive.cut))
    }

    /// `true` while the robot stands within [`GOAL_TOLERANCE`] and [`GOAL_YAW_TOLERANCE`] of
    /// the goal given in this session (the midpoint of the feet and their mean heading), with
    /// no other walk since: a stop short of it, a `Reset`, a velocity or a footstep walk end
    /// the arrival.
    pub fn at_goal(&self) -> bool {
        if !self.drive.goal_given || self.drive.driver != Driver::Steps || !self.gait.is_standing()
        {
            return false;
        }
        let [l, r] = *self.gait.feet();
        let half = T::of(0.5);
        let (dx, dy) = (
            self.drive.goal[0] - half * (l.x + r.x),
            self.drive.goal[1] - half * (l.y + r.y),
        );
        let h = (l.yaw.sin() + r.yaw.sin()).atan2(l.yaw.cos() + r.yaw.cos());
        let (s, c) = h.sin_cos();
        let d = self.drive.goal[2] - h;
        // (A rounding's slack: the walk stops on the same tolerance, from the support foot.)
        let slack = T::of(1e-6);
        let tol = T::of(GOAL_TOLERANCE) + slack;
        (c * dx + s * dy).abs() <= tol
            && (-s * dx + c * dy).abs() <= tol
            && d.sin().atan2(d.cos()).abs() <= T::of(GOAL_YAW_TOLERANCE) + slack
    }

    /// A footstep walk or a new session: no goal's arrival is reported any more.
    pub(super) fn forget_goal(&mut self) {
        self.drive.goal_given = false;
    }

    fn stepping(&self) -> Stepping<T> {
        Stepping::of(&self.cfg.params, self.cfg.reach)
    }

    /// What refuses a `VELOCITY` or `GOAL` first: freshness (the control sequence), the
    /// session (no session open; a number read more than [`SEQ_ADVANCE`] ahead), the latched
    /// states.
    fn drive_gate(&self, seq: u32) -> Result<(), Reason> {
        if seq == self.last_seq && self.last_seq != 0 {
            return Err(Reason::Duplicate);
        }
        if seq <= self.last_seq {
            return Err(Reason::Stale);
        }
        if !self.open {
            return Err(Reason::NoSession);
        }
        // Read that far ahead, the frame was sent for another session (see `wire`'s `drive`).
        if seq - self.last_seq > SEQ_ADVANCE {
            return Err(Reason::WrongSession);
        }
        if self.estopped {
            return Err(Reason::EmergencyStopped);
        }
        if self.lost {
            return Err(Reason::ControllerLost);
        }
        Ok(())
    }

    /// A `VELOCITY` (see the module docs); the answer's cut mask when accepted. Out of line:
    /// its frame is not on the stack of the other commands.
    #[inline(never)]
    pub(super) fn velocity(&mut self, w: &WireVelocity, now_ms: u32) -> Result<u8, Reason> {
        self.drive_gate(w.seq)?;
        let (vx, vy, wz) = w.si_in::<T>();
        let v = Velocity { vx, vy, wz };
        let cut = self.drive_to(Driver::Velocity, v, None)?;
        self.last_seq = w.seq;
        self.drive.heard_ms = now_ms;
        self.drive.heard_cycle = self.cycle;
        Ok(cut.mask())
    }

    /// A `GOAL` (see the module docs); the answer's cut mask when accepted (out of line, as
    /// the `VELOCITY`'s).
    #[inline(never)]
    pub(super) fn goal(&mut self, w: &WireGoal) -> Result<u8, Reason> {
        self.drive_gate(w.seq)?;
        let cut = self.drive_to(Driver::Goal, Velocity::ZERO, Some(w))?;
        self.last_seq = w.seq;
        Ok(cut.mask())
    }

    /// The goal `w` in the node's frame: relative to the midpoint of the feet and their mean
    /// heading now.
    fn goal_frame(&self, w: &WireGoal) -> [T; 3] {
        let (x, y, yaw) = w.si_in::<T>();
        let [l, r] = *self.gait.feet();
        let half = T::of(0.5);
        let (cx, cy) = (half * (l.x + r.x), half * (l.y + r.y));
        let h = (l.yaw.sin() + r.yaw.sin()).atan2(l.yaw.cos() + r.yaw.cos());
        let (s, c) = h.sin_cos();
        [cx + c * x - s * y, cy + s * x + c * y, h + yaw]
    }

    /// From standing: `Some` (with the goal in the node's frame, if one is given) when
    /// nothing moves (a zero velocity, a goal reached). Out of line: its frame is off the
    /// stack when the drive plans.
    #[inline(never)]
    fn still_from_standing(
        &self,
        v: &Velocity<T>,
        goal: Option<&WireGoal>,
    ) -> Option<Option<[T; 3]>> {
        let (_, [support, _], side, _) = self.drive_stance(v);
        match goal.map(|w| self.goal_frame(w)) {
            Some(g) => self
                .goal_velocity(&support, side, &g)
                .is_none()
                .then_some(Some(g)),
            None => is_zero(v).then_some(None),
        }
    }

    /// Where the next step a drive plans leaves from: the step that starts the steps planned
    /// (`None` from standing or with nothing queued), the feet before it (support, same
    /// side), its side and whether it swings from rest.
    fn drive_stance(&self, v: &Velocity<T>) -> (Option<u16>, [Footstep<T>; 2], Side, bool) {
        let standing = self.gait.is_standing();
        let front = if standing {
            None
        } else {
            self.gait.next_target()
        };
        let first_side = match self.gait.next_side() {
            Some(s) => s,
            None if v.vy > T::ZERO || (v.vy == T::ZERO && v.wz > T::ZERO) => Side::Left,
            None => Side::Right,
        };
        let feet = self.gait.previous_feet(front);
        let side = match front.and_then(|id| self.gait.queued_step(id)) {
            Some(s) => s.side,
            None => first_side,
        };
        let from_rest = standing || self.gait.next_swing_from_rest();
        (
            front,
            [feet[side.other().index()], feet[side.index()]],
            side,
            from_rest,
        )
    }

    /// Drives by `driver` at `v` (or toward `goal`): from standing, a start; walking, a
    /// re-plan of the queued steps. Nothing changes on error.
    #[inline(never)] // (out of the command path's frame: the firmware's flash and stack)
    fn drive_to(
        &mut self,
        driver: Driver,
        v: Velocity<T>,
        goal: Option<&WireGoal>,
    ) -> Result<Saturation, Reason> {
        let standing = self.gait.is_standing();
        let stopping = self.gait.is_stopping();
        let drives = self.drive.driver != Driver::Steps;
        // A zero velocity while a drive stops: the stop it asks for is under way (a stick
        // held at zero streams it). It is taken and changes nothing but who drives.
        if stopping && drives && goal.is_none() && is_zero(&v) {
            self.drive.driver = Driver::Velocity;
            self.drive.v = Velocity::ZERO;
            self.drive.cut = Saturation::default();
            self.drive.goal_given = false;
            return Ok(Saturation::default());
        }
        // A stop the drive asked for (a zero velocity, a goal reached) is cancelled while a
        // step that has not lifted off is queued; any other stop stands.
        let resume = stopping && drives && self.drive.own_stop && self.gait.resumable();
        if (standing && self.gait.queued() > 0) || (!standing && !drives) || (stopping && !resume) {
            return Err(Reason::WrongState);
        }
        // The steps: from standing a new queue; walking, the queued ones re-planned and the
        // queue made up to `AHEAD` with new ones, all before the one plan (eq. 17) that the
        // re-plan at the next start of single support takes (nothing is appended after it).
        let n = AHEAD;
        let queued = if standing { 0 } else { self.gait.queued() };
        let appends = n.saturating_sub(queued);
        // A goal already reached, or a zero velocity, from standing: nothing moves (taken
        // without work, so decided before the budget; a goal reads the stance for it).
        if standing {
            if let Some(g) = self.still_from_standing(&v, goal) {
                self.drive.goal_given = g.is_some();
                self.drive.goal = g.unwrap_or(self.drive.goal);
                self.drive.v = Velocity::ZERO;
                self.drive.cut = Saturation::default();
                return Ok(Saturation::default());
            }
        }
        // The cheap checks first (the plan, the budget, the step numbers), before any geometry
        // while walking: what is refused after them has generated its steps, and that work is
        // charged.
        let generating = n as u32 * WORK_GENERATE;
        let work = generating + WORK_PLAN + appends as u32 * WORK_APPEND;
        self.plan()?;
        self.afford(work)?;
        // From standing every step is appended; walking, only those beyond the queue, which a
        // stop (the steps up to the closing one) may not need: counted once they are known.
        if standing && self.appended.saturating_add(appends as u32) > STEP_NUMBERS {
            return Err(Reason::Exhausted);
        }
        let (front, [support, same], _, from_rest) = self.drive_stance(&v);
        let goal = goal.map(|w| self.goal_frame(w));
        let target = goal.unwrap_or(self.drive.goal);
        // The step numbers: from standing the next ones, walking the queued steps'.
        let first = if standing {
            self.next_step()
        } else {
            front.map_or(self.next_step(), |id| id.wrapping_add(self.first))
        };
        let Some(p) = self.plan_drive(v, goal, n, [support, same], from_rest, first) else {
            self.spend(generating);
            return Err(Reason::OutOfRange);
        };
        let (steps, cut, stop, last_v, keep) = (p.steps, p.cut, p.stop, p.v, p.keep);
        if self
            .appended
            .saturating_add(keep.saturating_sub(queued) as u32)
            > STEP_NUMBERS
        {
            self.spend(generating);
            return Err(Reason::Exhausted);
        }
        if standing {
            for (i, s) in steps.iter().enumerate().take(keep) {
                let gid = (self.appended as u16).wrapping_add(i as u16);
                if self.gait.push(gid, *s).is_err() {
                    let _ = self.gait.drop_queue();
                    self.spend(generating);
                    return Err(Reason::QueueFull);
                }
            }
            let started = self.gait.start().map_err(reason_of);
            self.plans_left = self.plans_left.saturating_sub(1);
            if let Err(e) = started {
                let _ = self.gait.drop_queue();
                self.spend(generating + WORK_PLAN);
                return Err(e);
            }
            for (i, s) in steps.iter().enumerate().take(keep) {
                if let Some(w) = Self::wire_of(first.wrapping_add(i as u16), s) {
                    self.steps.push(Self::record_of(&w));
                }
            }
            self.appended += keep as u32;
            self.adj.enabled = false;
        } else {
            // One call: the queue re-planned and made up, the stop requested (a zero velocity,
            // a goal reached: the steps after the closing one dropped) or cancelled (checked
            // resumable above), then eq. 17 checked once; refused, all is put back.
            let next = self.next_step();
            let replaced = self
                .gait
                .replace_front(steps.get(..keep).unwrap_or(&[]), self.appended as u16, stop)
                .map_err(reason_of);
            self.plans_left = self.plans_left.saturating_sub(1);
            if let Err(e) = replaced {
                self.spend(generating + WORK_PLAN);
                return Err(e);
            }
            for (i, s) in steps.iter().enumerate().take(keep.min(queued)) {
                let Some(w) = Self::wire_of(first.wrapping_add(i as u16), s) else {
                    continue;
                };
                if let Some((at, _)) = self.steps.queued_find(w.id) {
                    if let Some(r) = self.steps.queued_at_mut(at, w.id) {
                        *r = Self::record_of(&w);
                    }
                }
            }
            // The steps after the closing one: dropped, the newest numbers given back.
            let dropped = queued.saturating_sub(keep);
            if dropped > 0 {
                self.steps.truncate_queued(keep);
                self.appended = self.appended.saturating_sub(dropped as u32);
            }
            // The steps appended: numbered on from the queued ones.
            for (k, s) in steps.iter().take(keep).skip(queued).enumerate() {
                if let Some(w) = Self::wire_of(next.wrapping_add(k as u16), s) {
                    self.steps.push(Self::record_of(&w));
                }
            }
            self.appended += keep.saturating_sub(queued) as u32;
        }
        self.spend(work);
        self.drive.own_stop = stop;
        if stop && standing {
            self.gait.stop();
        }
        self.drive.driver = driver;
        self.drive.v = last_v;
        self.drive.cut = cut;
        self.drive.goal = target;
        self.drive.goal_given = goal.is_some();
        Ok(cut)
    }

    /// The steps a drive at `v` (or toward `goal`) plans from `support` and `same` (the feet
    /// before the first), numbered from `first`: at most `n`, each generated and checked to be
    /// in the wire's range (the walking area) before anything changes; a stop keeps the steps
    /// up to the one that closes the feet. `None` if a step cannot be generated or is out of
    /// the wire's range. Out of line, so that its frame is off the stack when the gait plans.
    #[inline(never)]
    fn plan_drive(
        &self,
        v: Velocity<T>,
        goal: Option<[T; 3]>,
        n: usize,
        [mut support, mut same]: [Footstep<T>; 2],
        from_rest: bool,
        first: u16,
    ) -> Option<Planned<T>> {
        let stepping = self.stepping();
        let mut p = Planned {
            steps: [support; AHEAD],
            cut: Saturation::default(),
            stop: is_zero(&v) && goal.is_none(),
            v,
            keep: n,
        };
        for (i, slot) in p.steps.iter_mut().enumerate().take(n) {
            if p.stop {
                p.keep = i + 1;
            }
            let vi = match goal {
                Some(g) => match self.goal_velocity(&support, support.side.other(), &g) {
                    Some(vg) => vg,
                    None => {
                        p.stop = true;
                        p.keep = i + 1;
                        Velocity::ZERO
                    }
                },
                None => v,
            };
            let (step, c) = stepping
                .next_step(&vi, &support, &same, from_rest && i == 0)
                .ok()?;
            if i == 0 {
                p.v = vi;
            }
            Self::wire_of(first.wrapping_add(i as u16), &step)?;
            p.cut = p.cut.or(c);
            *slot = step;
            same = support;
            support = step;
            if p.stop {
                break;
            }
        }
        Some(p)
    }

    /// The velocity that walks the stance of `support` (the other foot beside it) toward
    /// `goal` with the next step of `side`; `None` when the stance is at the goal.
    #[inline(never)]
    fn goal_velocity(
        &self,
        support: &Footstep<T>,
        side: Side,
        goal: &[T; 3],
    ) -> Option<Velocity<T>> {
        let half_w = T::of(0.5) * self.cfg.params.step_width;
        let toward = match side {
            Side::Left => half_w,
            Side::Right => -half_w,
        };
        let (s, c) = support.yaw.sin_cos();
        // The stance's centre: the support foot moved half the width toward the other side.
        let (cx, cy) = (support.x - s * toward, support.y + c * toward);
        let (dx, dy) = (goal[0] - cx, goal[1] - cy);
        let fx = c * dx + s * dy;
        let fy = -s * dx + c * dy;
        let d = goal[2] - support.yaw;
        let dyaw = d.sin().atan2(d.cos());
        let tol = T::of(GOAL_TOLERANCE);
        if fx.abs() <= tol && fy.abs() <= tol && dyaw.abs() <= T::of(GOAL_YAW_TOLERANCE) {
            return None;
        }
        let period = self.stepping().period;
        let two = T::of(2.0);
        Some(Velocity {
            vx: fx / period,
            vy: fy / (two * period),
            wz: dyaw / (two * period),
        })
    }

    #[inline(never)]
    fn wire_of(number: u16, s: &Footstep<T>) -> Option<WireStep> {
        WireStep::from_si(
            number,
            s.side == Side::Left,
            s.x.f64(),
            s.y.f64(),
            s.yaw.f64(),
        )
    }

    #[inline(never)]
    fn record_of(w: &WireStep) -> Record {
        Record {
            append: *w,
            commanded: *w,
            append_frame: Command::Append(*w).encode(),
            version: 0,
            in_force: None,
        }
    }

    /// Once a cycle, after the commands: the queue topped up to [`AHEAD`] steps while the node
    /// drives (as far as the budget goes); a goal reached closes the feet and stops.
    #[inline(never)]
    pub(super) fn drive_ahead(&mut self) {
        if self.drive.driver == Driver::Steps
            || self.gait.is_standing()
            || self.gait.is_stopping()
            || self.lost
            || self.estopped
        {
            return;
        }
        let stepping = self.stepping();
        while self.gait.queued() < AHEAD && self.afford(WORK_GENERATE + WORK_APPEND).is_ok() {
            let Some(side) = self.gait.next_side() else {
                return;
            };
            let feet = self.gait.previous_feet(None);
            let (support, same) = (feet[side.other().index()], feet[side.index()]);
            let from_rest = self.gait.queued() == 0 && self.gait.next_swing_from_rest();
            let mut stop = false;
            let v = match self.drive.driver {
                Driver::Goal => match self.goal_velocity(&support, side, &self.drive.goal) {
                    Some(v) => v,
                    None => {
                        stop = true;
                        Velocity::ZERO
                    }
                },
                _ => self.drive.v,
            };
            let Ok((step, cut)) = stepping.next_step(&v, &support, &same, from_rest) else {
                return;
            };
            let Some(w) = Self::wire_of(self.next_step(), &step) else {
                // Out of the walking area: the robot stops.
                self.gait.stop();
                return;
            };
            if self.appended >= STEP_NUMBERS || self.gait.push(self.appended as u16, step).is_err()
            {
                self.gait.stop();
                return;
            }
            self.spend(WORK_GENERATE + WORK_APPEND);
            self.steps.push(Self::record_of(&w));
            self.appended += 1;
            if self.drive.driver == Driver::Goal {
                self.drive.v = v;
                self.drive.cut = cut;
            }
            if stop {
                self.gait.stop();
                self.drive.own_stop = true;
                return;
            }
        }
    }

    /// Once a cycle, before supervision: a robot walking at a velocity whose stream has been
    /// silent for longer than [`NodeConfig::velocity_timeout_ms`] (by the clock or by the
    /// cycles) is stopped as for a lost controller.
    pub(super) fn drive_supervise(&mut self, now_ms: u32) {
        if self.drive.driver != Driver::Velocity || self.gait.is_standing() {
            return;
        }
        let dt_us = (self.cfg.params.dt * T::of(1e6)).round().trunc_i32().max(1) as u32;
        let cycles = self
            .cfg
            .velocity_timeout_ms
            .saturating_mul(1000)
            .div_ceil(dt_us);
        let silent = now_ms.wrapping_sub(self.drive.heard_ms) > self.cfg.velocity_timeout_ms
            || self.cycle.wrapping_sub(self.drive.heard_cycle) > cycles;
        // (A stop the stream asked for, a zero velocity, is walked out whatever follows.)
        if silent && !self.gait.is_stopping() {
            self.lost = true;
        }
    }

    /// Once a cycle, after the tick: a drive ends when the robot stands.
    pub(super) fn drive_end(&mut self) {
        if self.drive.driver != Driver::Steps && self.gait.is_standing() {
            self.drive.driver = Driver::Steps;
            self.drive.own_stop = false;
            self.drive.v = Velocity::ZERO;
            self.drive.cut = Saturation::default();
        }
    }
}
