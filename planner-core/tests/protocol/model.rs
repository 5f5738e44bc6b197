//! The reference model (see the test's docs in `main.rs`).

use super::*;

/// Why an accepted step was not walked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dropped {
    StopNow,
    Estop,
    Lost,
    Reset,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fate {
    Queued,
    Swinging,
    Landed,
    Dropped(Dropped),
}

/// An accepted footstep.
#[derive(Clone, Debug)]
pub(crate) struct Step {
    /// Sessions opened before its append (the handshake's is the first).
    pub(crate) epoch: u32,
    pub(crate) append: WireStep,
    pub(crate) append_frame: RawFrame,
    /// Version in force, and its frame.
    pub(crate) version: u8,
    pub(crate) in_force: Option<RawFrame>,
    /// The pose of the version in force (SI, in the epoch's frame).
    pub(crate) pose: (f64, f64, f64),
    pub(crate) fate: Fate,
    /// The step adjustment's shift in force when it lifted off \[m\].
    pub(crate) shift: (f64, f64),
    pub(crate) walked: u32,
    pub(crate) modified: u32,
}

impl Step {
    pub(crate) fn side(&self) -> Side {
        if self.append.left {
            Side::Left
        } else {
            Side::Right
        }
    }
    pub(crate) fn id(&self) -> u16 {
        self.append.id
    }
    pub(crate) fn is_repeat(&self, f: &RawFrame) -> bool {
        self.append_frame == *f || self.in_force == Some(*f)
    }
}

/// What the model says of a frame.
#[derive(Clone, Debug)]
pub(crate) enum Answer {
    /// Not the node's: no answer, nothing changes.
    Ignored,
    /// One of these answers (`None`: accepted).
    OneOf(Vec<Option<Reason>>),
}

pub(crate) fn must(r: Reason) -> Answer {
    Answer::OneOf(vec![Some(r)])
}

pub(crate) fn accepted() -> Answer {
    Answer::OneOf(vec![None])
}

pub(crate) fn ix(s: Side) -> usize {
    match s {
        Side::Left => 0,
        Side::Right => 1,
    }
}

/// What the protocol promises, from the commands accepted and the lift-offs and landings seen.
#[derive(Debug)]
pub(crate) struct Model {
    pub(crate) timeout: u32,
    /// Every accepted footstep, all epochs.
    pub(crate) steps: Vec<Step>,
    /// Accepted, not lifted off, not dropped: indices into `steps`, in queue order.
    pub(crate) queue: VecDeque<usize>,
    /// The accepted step being swung.
    pub(crate) swing: Option<usize>,
    /// The last `HISTORY` steps walked or dropped (the node recognises their frames).
    pub(crate) done: VecDeque<usize>,
    /// Sessions opened.
    pub(crate) epoch: u32,
    /// The node's session epoch (the start-up's, one more at each `Reset`).
    pub(crate) session: u32,
    pub(crate) open: bool,
    /// The next step number.
    pub(crate) next: u16,
    /// The last accepted control sequence number (0: none).
    pub(crate) last_seq: u32,
    pub(crate) estopped: bool,
    pub(crate) lost: bool,
    /// A stop was requested (`Stop`, `StopNow`, `ESTOP`, controller lost) while moving.
    pub(crate) stopping: bool,
    pub(crate) last_heard: Option<u32>,
    /// The cycle in which the controller was last heard.
    pub(crate) heard_cycle: u64,
    /// Supervision's timeout in cycles.
    pub(crate) timeout_cycles: u64,
    /// The node's cycles before the frame's (the last reference published names this one).
    pub(crate) cycle: u64,
    /// The cycle in which the open session opened, and the cycle the last measured state
    /// taken names.
    pub(crate) opened_at: u64,
    pub(crate) measured: Option<u64>,
    /// The walk was started with step adjustment.
    pub(crate) adjusting: bool,
}

/// The oldest measured state the node takes \[cycles\] (`AdjustConfig::DEFAULT`).
const MAX_AGE: u64 = 4;

impl Model {
    pub(crate) fn new(timeout: u32) -> Self {
        Self {
            timeout,
            steps: vec![],
            queue: VecDeque::new(),
            swing: None,
            done: VecDeque::new(),
            epoch: 0,
            session: 0,
            open: false,
            next: 0,
            last_seq: 0,
            estopped: false,
            lost: false,
            stopping: false,
            last_heard: None,
            heard_cycle: 0,
            timeout_cycles: u64::from(timeout).div_ceil(5),
            cycle: 0,
            opened_at: 0,
            measured: None,
            adjusting: false,
        }
    }

    /// What the node's decoder depends on (the next step number, the session epoch).
    pub(crate) fn expect_for_decode(&self) -> Expect {
        Expect {
            next_step: self.next,
            epoch: self.session,
            last_seq: self.last_seq,
        }
    }

    pub(crate) fn expected_id(&self) -> u16 {
        self.next
    }

    /// The steps whose frames the node remembers: queued, swinging, the last done.
    pub(crate) fn remembered(&self) -> impl Iterator<Item = &Step> {
        self.queue
            .iter()
            .chain(self.swing.iter())
            .chain(self.done.iter())
            .map(|&i| &self.steps[i])
    }

    pub(crate) fn is_repeat(&self, f: &RawFrame) -> bool {
        self.remembered().any(|s| s.is_repeat(f))
    }

    /// The version in force of step `id` as the node's `ACK` reports it: queued, swinging,
    /// else the latest done.
    pub(crate) fn version(&self, id: u16) -> Option<u8> {
        let of = |&i: &usize| (self.steps[i].id() == id).then_some(self.steps[i].version);
        self.queue
            .iter()
            .find_map(of)
            .or_else(|| self.swing.iter().find_map(of))
            .or_else(|| self.done.iter().rev().find_map(of))
    }

    pub(crate) fn queued(&self, id: u16) -> Option<usize> {
        self.queue
            .iter()
            .copied()
            .find(|&i| self.steps[i].id() == id)
    }

    pub(crate) fn retire(&mut self, i: usize) {
        if self.done.len() == HISTORY {
            self.done.pop_front();
        }
        self.done.push_back(i);
    }

    pub(crate) fn drop_queue(&mut self, why: Dropped) {
        while let Some(i) = self.queue.pop_front() {
            self.steps[i].fate = Fate::Dropped(why);
            self.retire(i);
        }
    }

    /// The answer the protocol allows to `f`, the node standing or not and requiring
    /// `next_side` (both as before the cycle).
    pub(crate) fn expect(&self, f: &RawFrame, standing: bool, next_side: Option<Side>) -> Answer {
        use Reason::*;
        if !COMMAND_IDS.contains(&f.id) {
            return Answer::Ignored;
        }
        let cmd = match Command::decode(f, self.expect_for_decode()) {
            Ok(c) => c,
            Err((r, _)) => return must(r),
        };
        let footstep = matches!(cmd, Command::Append(_) | Command::Modify(_));
        if footstep && !self.open {
            return must(NoSession);
        }
        match cmd {
            Command::EmergencyStop { .. } => {
                if self.estopped {
                    must(Duplicate)
                } else {
                    accepted()
                }
            }
            Command::Control { session, seq, op } => {
                if session != self.session as u16 {
                    return must(WrongSession);
                }
                if seq == self.last_seq && seq != 0 {
                    return must(Duplicate);
                }
                if seq <= self.last_seq {
                    return must(Stale);
                }
                if !self.open && op != ControlOp::Reset {
                    return must(NoSession);
                }
                match op {
                    ControlOp::Reset => {
                        if standing {
                            accepted()
                        } else {
                            must(WrongState)
                        }
                    }
                    ControlOp::Start | ControlOp::StartAdjusting => {
                        if self.estopped {
                            must(EmergencyStopped)
                        } else if self.lost {
                            must(ControllerLost)
                        } else if !standing || self.queue.is_empty() {
                            must(WrongState)
                        } else {
                            // No `PlanFailed`: a validated configuration leaves none (README).
                            accepted()
                        }
                    }
                    ControlOp::StopNow if standing && self.queue.is_empty() => must(WrongState),
                    _ => accepted(),
                }
            }
            Command::Append(s) => {
                let side = if s.left { Side::Left } else { Side::Right };
                if self.is_repeat(f) {
                    must(Duplicate)
                } else if self.estopped {
                    must(EmergencyStopped)
                } else if self.lost {
                    must(ControllerLost)
                } else if self.stopping && !standing {
                    must(WrongState)
                } else if s.id != self.expected_id() {
                    must(SequenceGap)
                } else if next_side.is_some_and(|n| n != side) {
                    must(SideOrder)
                } else if self.queue.len() >= Q {
                    Answer::OneOf(vec![Some(Reach), Some(Crossing), Some(QueueFull)])
                } else {
                    Answer::OneOf(vec![None, Some(Reach), Some(Crossing)])
                }
            }
            // The node's freshness and latched states; what it drives then is not modelled (the
            // programs give the footsteps: `velocity_walk.rs` and the model check cover it).
            Command::Velocity(_) | Command::Goal(_) => {
                let seq = match cmd {
                    Command::Velocity(v) => v.seq,
                    Command::Goal(g) => g.seq,
                    _ => 0,
                };
                if seq == self.last_seq && seq != 0 {
                    must(Duplicate)
                } else if seq <= self.last_seq {
                    must(Stale)
                } else if !self.open {
                    must(NoSession)
                } else if self.estopped {
                    must(EmergencyStopped)
                } else if self.lost {
                    must(ControllerLost)
                } else {
                    Answer::OneOf(vec![None, Some(WrongState), Some(Busy)])
                }
            }
            Command::Measured(m) => {
                if !self.open {
                    return must(NoSession);
                } else if self.estopped {
                    return must(EmergencyStopped);
                } else if self.lost {
                    return must(ControllerLost);
                }
                let latest = self.cycle;
                let age = latest.wrapping_sub(u64::from(m.stamp)) & u64::from(STAMPS - 1);
                if age > MAX_AGE || age > latest {
                    return must(Stale);
                }
                let at = latest - age;
                if at < self.opened_at {
                    must(WrongSession)
                } else if self.measured == Some(at) {
                    must(Duplicate)
                } else if self.measured.is_some_and(|last| last > at) {
                    must(Stale)
                } else {
                    accepted()
                }
            }
            Command::Modify(m) => {
                if self.is_repeat(f) {
                    return must(Duplicate);
                } else if self.estopped {
                    return must(EmergencyStopped);
                } else if self.lost {
                    return must(ControllerLost);
                } else if standing && self.queue.is_empty() {
                    return must(WrongState);
                } else if self.swing.is_some_and(|i| self.steps[i].id() == m.id) {
                    return must(LiftedOff);
                }
                let Some(i) = self.queued(m.id) else {
                    return must(UnknownStep);
                };
                let st = &self.steps[i];
                if !m.is_newer_than(st.version) {
                    must(Stale)
                } else if m.left != st.append.left {
                    must(SideOrder)
                } else if m.applied_to(&st.append).is_none() {
                    must(OutOfRange)
                } else {
                    // Reach and eq. 17 depend on geometry; no `PlanFailed` (README).
                    Answer::OneOf(vec![None, Some(Reach), Some(Crossing), Some(Infeasible)])
                }
            }
        }
    }

    /// The node accepted `cmd` (frame `f`) at `now`, in cycle `cycle`.
    pub(crate) fn accept(
        &mut self,
        f: &RawFrame,
        cmd: Command,
        now: u32,
        cycle: u64,
        standing: bool,
    ) {
        // Every accepted command but an emergency stop (and the estimator's measured state)
        // proves the controller alive.
        if !matches!(cmd, Command::EmergencyStop { .. } | Command::Measured(_)) {
            self.last_heard = Some(now);
            self.heard_cycle = cycle;
        }
        match cmd {
            Command::EmergencyStop { .. } => {
                self.estopped = true;
                self.drop_queue(Dropped::Estop);
                self.stopping |= !standing;
            }
            Command::Velocity(v) => self.last_seq = v.seq,
            Command::Goal(g) => self.last_seq = g.seq,
            Command::Control { seq, op, .. } => {
                self.last_seq = seq;
                match op {
                    ControlOp::Heartbeat => {}
                    ControlOp::Start | ControlOp::StartAdjusting => {
                        self.stopping = false;
                        self.adjusting = op == ControlOp::StartAdjusting;
                    }
                    ControlOp::Stop => self.stopping |= !standing,
                    ControlOp::StopNow => {
                        self.drop_queue(Dropped::StopNow);
                        self.stopping |= !standing;
                    }
                    ControlOp::Reset => {
                        self.drop_queue(Dropped::Reset);
                        self.done.clear();
                        self.swing = None;
                        self.estopped = false;
                        self.lost = false;
                        self.stopping = false;
                        self.epoch += 1;
                        self.session += 1;
                        if self.open {
                            // A new session numbers its steps 256 past the old one's.
                            self.next = self.next.wrapping_add(256);
                        }
                        self.open = true;
                        self.measured = None;
                        self.opened_at = self.cycle + 1;
                        self.adjusting = false;
                    }
                }
            }
            Command::Append(s) => {
                self.steps.push(Step {
                    epoch: self.epoch,
                    append: s,
                    append_frame: *f,
                    version: 0,
                    in_force: None,
                    pose: s.si(),
                    fate: Fate::Queued,
                    shift: (0.0, 0.0),
                    walked: 0,
                    modified: 0,
                });
                self.queue.push_back(self.steps.len() - 1);
                self.next = self.next.wrapping_add(1);
            }
            Command::Measured(m) => {
                let age = self.cycle.wrapping_sub(u64::from(m.stamp)) & u64::from(STAMPS - 1);
                self.measured = Some(self.cycle - age);
            }
            Command::Modify(m) => {
                let i = self.queued(m.id).expect("the model allowed it: queued");
                let st = &mut self.steps[i];
                let s = m
                    .applied_to(&st.append)
                    .expect("the model allowed it: in range");
                st.version = m.version;
                st.in_force = Some(*f);
                st.pose = s.si();
                st.modified += 1;
            }
        }
    }

    /// The supervision rule at `now` (after the cycle's commands): a moving robot whose
    /// controller was not heard within the timeout is lost; once lost, the queue is dropped.
    /// Returns `true` if it became lost now.
    pub(crate) fn supervise(&mut self, now: u32, cycle: u64, moving: bool) -> bool {
        if !moving {
            return false;
        }
        let silent = self.last_heard.is_none_or(|h| {
            now.wrapping_sub(h) > self.timeout || cycle - self.heard_cycle > self.timeout_cycles
        });
        let became = silent && !self.lost;
        self.lost |= silent;
        if self.lost {
            self.drop_queue(Dropped::Lost);
            self.stopping = true;
        }
        became
    }

    pub(crate) fn state(&self, standing: bool) -> NodeState {
        if !self.open && !self.estopped {
            NodeState::NoSession
        } else if self.estopped {
            NodeState::EmergencyStopped
        } else if self.lost {
            NodeState::ControllerLost
        } else if standing {
            NodeState::Standing
        } else if self.stopping {
            NodeState::Stopping
        } else {
            NodeState::Walking
        }
    }
}
