//! The commands: each validated frame checked against the state (session, freshness, reach,
//! side order, emergency stop, supervision) and carried out on the gait, or refused with its
//! reason and nothing changed (see the parent module's *Sessions and freshness* and *Answers*).

use super::*;

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// The answer refusing `frame` with `reason` without handling it (nothing changes).
    pub(super) fn refusal(
        &self,
        frame: &RawFrame,
        decoded: &Result<Command, (Reason, u8)>,
        reason: Reason,
    ) -> Ack {
        let (command, seq, version) = match decoded {
            Ok(c) => (
                c.code(),
                c.key(),
                c.step_id().and_then(|id| self.steps.version(id)),
            ),
            Err((_, seq)) => ((frame.id & 0xFF) as u8, *seq, None),
        };
        Ack {
            command,
            seq,
            reason: Some(reason),
            queue: self.gait.queued().min(255) as u8,
            echo: crate::wire::echo_of(frame),
            version,
        }
    }

    pub(super) fn refuse(&mut self, reason: Reason) {
        self.counters.refused = self.counters.refused.saturating_add(1);
        if let Some(n) = self.counters.by_reason.get_mut(usize::from(reason.code())) {
            *n = n.saturating_add(1);
        }
    }

    /// The limit that the node's reach check finds broken for a footstep command now
    /// (`Crossing` and `Reach` refusals): appended (`before` = `None`), or replacing the queued
    /// step `before` (then its two successors are checked against it too); `None` if the
    /// footstep passes. The answer on the bus carries only the reason: a host that wants to
    /// say which limit a refused step broke asks here, in the state the command met.
    pub fn reach_broken(&self, step: &Footstep<T>, before: Option<u16>) -> Option<Broken<T>> {
        let r = &self.cfg.reach;
        let feet = self.gait.previous_feet(before);
        let other = Frame::of(&feet[step.side.other().index()]);
        let same = Frame::like(&feet[step.side.index()], &[&other]);
        let f = Frame::like(step, &[&other, &same]);
        // The first swing of a walk from standing: its growth counts from a step of 0.
        let position = match before {
            Some(id) => self.gait.position(id),
            None => Some(self.gait.queued()),
        };
        let from_rest = position == Some(0) && self.gait.next_swing_from_rest();
        let soles = Soles::of(&self.cfg.params);
        if let Some(b) = r.broken_frames(&other, &same, &f, step.side, from_rest, &soles) {
            return Some(b);
        }
        if let Some(id) = before {
            let next = |k: u16| self.gait.queued_step(id.wrapping_add(k));
            if let Some(s1) = next(1) {
                let f1 = Frame::like(&s1, &[&f, &other]);
                if let Some(b) = r.broken_frames(&f, &other, &f1, s1.side, false, &soles) {
                    return Some(b);
                }
                if let Some(s2) = next(2) {
                    let f2 = Frame::like(&s2, &[&f1, &f]);
                    return r.broken_frames(&f1, &f, &f2, s2.side, false, &soles);
                }
            }
        }
        None
    }

    /// [`Node::reach_broken`] for the queued step `id` and the steps after it all moved by
    /// `delta` \[m\] (the step adjustment's shift): the moved step against the feet before it,
    /// and its successor against it; the steps after those keep their places relative to both.
    pub(super) fn reach_broken_moved(&self, id: u16, delta: [T; 2]) -> Option<Broken<T>> {
        let moved = |s: Footstep<T>| Footstep::new(s.side, s.x + delta[0], s.y + delta[1], s.yaw);
        let step = moved(self.gait.queued_step(id)?);
        let r = &self.cfg.reach;
        let feet = self.gait.previous_feet(Some(id));
        let other = Frame::of(&feet[step.side.other().index()]);
        let same = Frame::like(&feet[step.side.index()], &[&other]);
        let f = Frame::like(&step, &[&other, &same]);
        let from_rest = self.gait.position(id) == Some(0) && self.gait.next_swing_from_rest();
        let soles = Soles::of(&self.cfg.params);
        if let Some(b) = r.broken_frames(&other, &same, &f, step.side, from_rest, &soles) {
            return Some(b);
        }
        let s1 = moved(self.gait.queued_step(id.wrapping_add(1))?);
        let f1 = Frame::like(&s1, &[&f, &other]);
        r.broken_frames(&f, &other, &f1, s1.side, false, &soles)
    }

    /// The footstep of a validated frame in `T`: the wire's integers in SI units (`f64`, as
    /// [`WireStep::si`]), each rounded to the nearest `T` (exact for `f64`).
    pub(super) fn footstep(s: &WireStep) -> Footstep<T> {
        let (x, y, yaw) = s.si_in::<T>();
        let side = if s.left { Side::Left } else { Side::Right };
        Footstep::new(side, x, y, yaw)
    }

    /// Handles one frame from the bus (validation, state checks, application) and returns the
    /// answer to send: `None` for a frame that is not the node's (counted, not answered).
    /// [`Node::poll`] receives a cycle's frames first and hands them here in priority order.
    pub fn handle(&mut self, frame: &RawFrame, now_ms: u32) -> Option<Ack> {
        if !ids::is_command(frame.id) {
            self.counters.foreign = self.counters.foreign.saturating_add(1);
            return None;
        }
        let decoded = Command::decode(frame, self.expect());
        Some(self.handle_command(frame, decoded, now_ms))
    }

    pub(super) fn handle_command(
        &mut self,
        frame: &RawFrame,
        decoded: Result<Command, (Reason, u8)>,
        now_ms: u32,
    ) -> Ack {
        let echo = crate::wire::echo_of(frame);
        // (The cut of an accepted `VELOCITY` or `GOAL`, answered in the version byte.)
        let mut cut = None;
        let (command, seq, result) = match decoded {
            Ok(cmd) => {
                let result = match cmd {
                    Command::EmergencyStop { .. } => self.estop(),
                    Command::Control { session, seq, op } => self.control(session, seq, op),
                    Command::Append(s) => self.append(frame, &s),
                    Command::Modify(m) => self.modify(frame, &m),
                    Command::Measured(m) => self.measured(&m),
                    Command::Velocity(v) => self.velocity(&v, now_ms).map(|c| cut = Some(c)),
                    Command::Goal(g) => self.goal(&g).map(|c| cut = Some(c)),
                };
                (cmd.code(), cmd.key(), result)
            }
            Err((reason, seq)) => ((frame.id & 0xFF) as u8, seq, Err(reason)),
        };
        match result {
            // Only an accepted command proves the controller alive, and every accepted one is
            // new (a greater sequence number, the next step number, a greater version); an
            // emergency stop and a measured state (the estimator's) prove nothing.
            Ok(()) if frame.id != ids::ESTOP && frame.id != ids::MEASURED => {
                self.last_heard = Some(now_ms);
                self.heard_cycle = self.cycle;
            }
            Ok(()) => {}
            Err(reason) => self.refuse(reason),
        }
        // Steps the command dropped (emergency stop, stop now) leave the step records. A
        // footstep command drops none (an append adds its record with its step, a modification
        // changes a queued step in place, or nothing if refused), and a heartbeat does not
        // touch the gait.
        if !matches!(
            decoded,
            Ok(Command::Append(_)
                | Command::Modify(_)
                | Command::Measured(_)
                | Command::Control {
                    op: ControlOp::Heartbeat,
                    ..
                })
        ) {
            self.steps.sync(&self.gait, self.first);
        }
        let version = match decoded {
            Ok(Command::Append(s)) => self.steps.version(s.id),
            Ok(Command::Modify(m)) => self.steps.version(m.id),
            _ => cut,
        };
        Ack {
            command,
            seq,
            reason: result.err(),
            queue: self.gait.queued().min(255) as u8,
            echo,
            version,
        }
    }

    /// `Busy` if this cycle has planned [`NodeConfig::max_plans`] times already.
    pub(super) fn plan(&self) -> Result<(), Reason> {
        if self.plans_left == 0 {
            return Err(Reason::Busy);
        }
        Ok(())
    }

    /// `Busy` if `work` does not fit what is left of the cycle's budget
    /// ([`NodeConfig::work_budget`]). Nothing is taken: a command takes its work
    /// ([`Node::spend`]) only once it is accepted, so a refusal spends nothing.
    pub(super) fn afford(&self, work: u32) -> Result<(), Reason> {
        if self.work_left < work {
            return Err(Reason::Busy);
        }
        Ok(())
    }

    /// Takes `work` (afforded) from the cycle's budget.
    pub(super) fn spend(&mut self, work: u32) {
        self.work_left = self.work_left.saturating_sub(work);
    }

    pub(super) fn estop(&mut self) -> Result<(), Reason> {
        if self.estopped {
            return Err(Reason::Duplicate);
        }
        self.estopped = true;
        self.gait.clear_and_stop();
        self.drive.own_stop = false;
        Ok(())
    }

    pub(super) fn control(&mut self, session: u16, seq: u32, op: ControlOp) -> Result<(), Reason> {
        if session != self.epoch as u16 {
            return Err(Reason::WrongSession);
        }
        if seq == self.last_seq && self.last_seq != 0 {
            return Err(Reason::Duplicate);
        }
        if seq <= self.last_seq {
            return Err(Reason::Stale);
        }
        if !self.open && op != ControlOp::Reset {
            return Err(Reason::NoSession);
        }
        let standing = self.gait.is_standing();
        match op {
            ControlOp::Heartbeat => {}
            ControlOp::Start | ControlOp::StartAdjusting => {
                if self.estopped {
                    return Err(Reason::EmergencyStopped);
                }
                if self.lost {
                    return Err(Reason::ControllerLost);
                }
                if !standing || self.gait.queued() == 0 {
                    return Err(Reason::WrongState);
                }
                self.plan()?;
                self.afford(WORK_PLAN)?;
                let started = self.gait.start().map_err(reason_of);
                self.plans_left = self.plans_left.saturating_sub(1);
                started?;
                self.spend(WORK_PLAN);
                self.adj.enabled = op == ControlOp::StartAdjusting;
            }
            ControlOp::Reset => {
                if !standing {
                    return Err(Reason::WrongState);
                }
                // An emergency stop received in the same cycle stands, whatever the order.
                if self.estop_now {
                    return Err(Reason::EmergencyStopped);
                }
                self.reset()?;
            }
            ControlOp::Stop => {
                if !standing {
                    // A stop changes the plan the tick's re-plan takes: in a cycle whose tick
                    // re-plans, once a command has planned, it waits for the next cycle
                    // (`Busy`, nothing changed), so the cycle plans no second window.
                    let planned = self.plans_left < self.cfg.max_plans;
                    if !self.gait.is_stopping() && planned && self.gait.replans_next_tick() {
                        return Err(Reason::Busy);
                    }
                    // The controller's stop: a velocity or a goal does not cancel it.
                    self.gait.stop();
                    self.drive.own_stop = false;
                }
            }
            ControlOp::StopNow => {
                if standing {
                    // Standing: drop what is queued, and nothing else (no stop request for a
                    // later `Start` to find); with nothing queued there is nothing to do.
                    if self.gait.queued() == 0 {
                        return Err(Reason::WrongState);
                    }
                    self.gait.drop_queue().map_err(reason_of)?;
                } else {
                    self.gait.clear_and_stop();
                    self.drive.own_stop = false;
                }
            }
        }
        self.last_seq = seq;
        Ok(())
    }

    /// Opens a new session while standing (see the module docs): the frame is re-based on the
    /// feet, except at the handshake after start-up.
    pub(super) fn reset(&mut self) -> Result<(), Reason> {
        // (The epoch names the session; the freshness of control commands is their sequence
        // number's, so the epoch may wrap.)
        let epoch = self.epoch.wrapping_add(1);
        // The new session numbers its steps past every number the old one could have sent.
        // When the start-up's numbers cannot give that, the new session has none left (its
        // appends are refused `Exhausted`, no frame of the old one can be taken): a `Reset`
        // always opens a session and leaves the latched states, however many came before.
        let skip = if self.open { SESSION_SKIP } else { 0 };
        let numbers = self.appended.saturating_add(skip).min(STEP_NUMBERS);
        if self.open {
            let [l, r] = *self.gait.feet();
            let half = T::of(0.5);
            let (x, y) = (half * (l.x + r.x), half * (l.y + r.y));
            let yaw = (l.yaw.sin() + r.yaw.sin()).atan2(l.yaw.cos() + r.yaw.cos());
            self.gait.rebase(x, y, yaw).map_err(reason_of)?;
        } else {
            // Nothing was accepted before the handshake but emergency stops: the queue is
            // empty already.
            let _ = self.gait.drop_queue();
        }
        self.epoch = epoch;
        self.appended = numbers;
        self.open = true;
        self.estopped = false;
        self.lost = false;
        self.clock_fault = false;
        self.steps.clear();
        self.forget_goal();
        // No shift and no measured state carry over: the new session's measured states name
        // cycles from this one on (this cycle's reference is the new session's first).
        self.adj = Adjusting::ZERO;
        self.adj.opened_at = self.cycle;
        self.adj.from = self.next_step();
        Ok(())
    }

    /// What refuses any footstep frame first: no session, a repeat of what is in force, the
    /// two latched states, then a walk whose steps the node chooses.
    pub(super) fn footstep_gate(&self, frame: &RawFrame) -> Result<(), Reason> {
        if !self.open {
            return Err(Reason::NoSession);
        }
        if self.steps.is_repeat(frame) {
            return Err(Reason::Duplicate);
        }
        if self.estopped {
            return Err(Reason::EmergencyStopped);
        }
        if self.lost {
            return Err(Reason::ControllerLost);
        }
        // While the node chooses the steps (a velocity, a goal) they are its own.
        if self.drive.driver != drive::Driver::Steps {
            return Err(Reason::WrongState);
        }
        Ok(())
    }

    pub(super) fn append(&mut self, frame: &RawFrame, s: &WireStep) -> Result<(), Reason> {
        self.footstep_gate(frame)?;
        // A stop walks the queue it has: a step appended now might or might not be walked
        // before the robot stands (it depends on whether the last window is planned yet), so
        // it is refused, and the controller appends it once standing.
        if self.gait.is_stopping() {
            return Err(Reason::WrongState);
        }
        if self.appended >= STEP_NUMBERS {
            return Err(Reason::Exhausted);
        }
        // Step numbers run on from the start-up's first: a lost step must not let the next
        // one take its place (from standing, a stride twice as long).
        if s.id != self.next_step() {
            return Err(Reason::SequenceGap);
        }
        // Walked where commanded, plus the step adjustment's shift in force.
        let walked = steps::shifted(s, self.adj.shift).ok_or(Reason::OutOfRange)?;
        let step = Self::footstep(&walked);
        if self.gait.next_side().is_some_and(|side| side != step.side) {
            return Err(Reason::SideOrder); // (before the reach check: the clearer reason)
        }
        let gen = self.gait.generation();
        let kept = self.check_reach_kept(&step, None)?;
        self.afford(WORK_APPEND)?;
        let gid = self.appended as u16;
        let pos = self.gait.queued();
        self.gait.push(gid, step).map_err(|(e, _)| reason_of(e))?;
        self.kept_step(gen, pos, kept, step.side);
        self.spend(WORK_APPEND);
        self.forget_goal();
        self.steps.push(Record {
            append: *s,
            commanded: *s,
            append_frame: *frame,
            version: 0,
            in_force: None,
        });
        self.appended += 1;
        Ok(())
    }

    /// `true` if a modification of the queued step `id` (gait id) plans now: the next swing
    /// target while walking (eq. 17 checks the re-plan it will cause).
    pub(super) fn plans_modify(&self, id: u16) -> bool {
        !self.gait.is_standing() && self.gait.next_target() == Some(id)
    }

    /// `true` if `decoded` is a modification that plans now ([`Node::plans_modify`]) and that
    /// the footstep gate lets through (a frame refused anyway, as every footstep command while
    /// the node drives, keeps no work from the others): the cycle acts on it after its other
    /// commands (see [`Node::poll`]).
    pub(super) fn plans_later(
        &self,
        frame: &RawFrame,
        decoded: &Result<Command, (Reason, u8)>,
    ) -> bool {
        match decoded {
            Ok(Command::Modify(m)) => {
                self.footstep_gate(frame).is_ok() && self.plans_modify(self.gait_id(m.id))
            }
            _ => false,
        }
    }

    pub(super) fn modify(&mut self, frame: &RawFrame, m: &WireModify) -> Result<(), Reason> {
        self.footstep_gate(frame)?;
        if self.gait.is_standing() && self.gait.queued() == 0 {
            return Err(Reason::WrongState);
        }
        if self.steps.swinging() == Some(m.id) {
            return Err(Reason::LiftedOff);
        }
        let Some((at, rec)) = self.steps.queued_find(m.id) else {
            return Err(Reason::UnknownStep);
        };
        if !m.is_newer_than(rec.version) {
            return Err(Reason::Stale);
        }
        if m.left != rec.append.left {
            return Err(Reason::SideOrder);
        }
        let s = m.applied_to(&rec.append).ok_or(Reason::OutOfRange)?;
        let walked = steps::shifted(&s, self.adj.shift).ok_or(Reason::OutOfRange)?;
        let step = Self::footstep(&walked);
        let id = self.gait_id(m.id);
        let gen = self.gait.generation();
        let kept = self.check_reach_kept(&step, Some(id))?;
        // A modification of the next swing target while walking plans (eq. 17).
        let plans = self.plans_modify(id);
        let work = if plans {
            WORK_STEP + WORK_PLAN
        } else {
            WORK_STEP
        };
        if plans {
            self.plan()?;
        }
        self.afford(work)?;
        let modified = self.gait.modify(id, step).map_err(reason_of);
        if plans {
            self.plans_left = self.plans_left.saturating_sub(1);
        }
        modified?;
        if let Some(pos) = self.gait.position(id) {
            self.kept_step(gen, pos, kept, step.side);
        }
        self.spend(work);
        if let Some(r) = self.steps.queued_at_mut(at, m.id) {
            r.version = m.version;
            r.in_force = Some(*frame);
            r.commanded = s;
        }
        Ok(())
    }

    /// Carries out (or refuses) the `i`-th command frame of the cycle, `decoded`, and queues
    /// its answer (`true`: accepted): a footstep command that arrived before a `StopNow`
    /// carried out in this cycle is refused `Stale` (the stop dropped it).
    pub(super) fn act(
        &mut self,
        i: usize,
        f: &RawFrame,
        decoded: Result<Command, (Reason, u8)>,
        act: &mut Acting,
        now_ms: u32,
    ) -> bool {
        let footstep = matches!(decoded, Ok(Command::Append(_) | Command::Modify(_)));
        let ack = if footstep && act.stop_at.is_some_and(|s| i < s) {
            self.refuse(Reason::Stale);
            self.refusal(f, &decoded, Reason::Stale)
        } else {
            self.handle_command(f, decoded, now_ms)
        };
        if ack.reason.is_some() {
            act.refused = act.refused.saturating_add(1);
        }
        self.enqueue(ack.encode());
        ack.reason.is_none()
    }
}
