//! The harness (see the test's docs in `main.rs`).

use super::*;

/// Totals over a run (printed with `--nocapture`).
#[derive(Debug, Default)]
pub(crate) struct Stats {
    pub(crate) programs: u32,
    pub(crate) cycles: u64,
    pub(crate) frames: u64,
    pub(crate) foreign: u64,
    pub(crate) accepted: u64,
    /// Refusals by reason code.
    pub(crate) refused: [u64; Reason::CODES],
    /// Refusals the model demanded (rather than allowed).
    pub(crate) demanded: [u64; Reason::CODES],
    pub(crate) appends: u64,
    pub(crate) modifications: u64,
    pub(crate) measured: u64,
    /// Cycles in which the node's step adjustment moved its steps.
    pub(crate) adjusted: u64,
    pub(crate) walked: u64,
    pub(crate) walked_modified: u64,
    pub(crate) padded: u64,
    pub(crate) dropped: [u64; 4],
    pub(crate) lost: u64,
    pub(crate) resets: u64,
    pub(crate) clock_jumps: u64,
    /// Steps appended while stopping and still queued when the robot stood.
    pub(crate) left_queued: u64,
    /// The longest time from the controller last heard to a lift-off \[ms\].
    pub(crate) liftoff_silence: u32,
    pub(crate) zmp_single: f64,
    pub(crate) zmp_double: f64,
    /// The closest the ZMP came to the polygon's edge from inside \[m\].
    pub(crate) zmp_margin_single: f64,
    pub(crate) zmp_margin_double: f64,
}

impl Stats {
    pub(crate) fn new() -> Self {
        Self {
            zmp_margin_single: f64::NEG_INFINITY,
            zmp_margin_double: f64::NEG_INFINITY,
            ..Self::default()
        }
    }
}

pub(crate) struct Harness<'a> {
    pub(crate) n: N,
    pub(crate) bus: Bus,
    pub(crate) now: u32,
    pub(crate) cycles: u64,
    pub(crate) model: Model,
    pub(crate) book: StepBook,
    /// Every frame sent, and the modifications among them.
    pub(crate) sent: Vec<RawFrame>,
    pub(crate) modifies: Vec<RawFrame>,
    /// Sequence numbers sent in control commands.
    pub(crate) seqs: Vec<u32>,
    pub(crate) estop_seq: u8,
    /// The reference and the swing of the cycle before.
    pub(crate) prev: Reference<f64>,
    pub(crate) prev_swing: Option<u16>,
    /// The node's step-adjustment shift after the last cycle \[0.5 mm\].
    pub(crate) shift: [i32; 2],
    /// The side of the padded step being swung.
    pub(crate) padded: Option<Side>,
    pub(crate) stats: &'a mut Stats,
}

macro_rules! ensure {
    ($c:expr, $($t:tt)+) => {
        {
            let ok: bool = $c;
            if !ok {
                return Err(format!($($t)+));
            }
        }
    };
}

impl<'a> Harness<'a> {
    pub(crate) fn new(t0: u32, stats: &'a mut Stats) -> Self {
        let cfg = NodeConfig::hrp2();
        let n = N::new(cfg).expect("node");
        let prev = *n.gait().last();
        Self {
            n,
            bus: Bus::default(),
            now: t0,
            cycles: 0,
            model: Model::new(cfg.heartbeat_timeout_ms),
            book: StepBook::new(),
            sent: vec![],
            modifies: vec![],
            seqs: vec![],
            estop_seq: 0,
            prev,
            prev_swing: None,
            shift: [0, 0],
            padded: None,
            stats,
        }
    }

    /// One cycle `dt` ms after the last, with `frame` alone on the bus; checks the answer and
    /// every invariant, and returns the answer (`None` if there was none).
    pub(crate) fn cycle(
        &mut self,
        frame: Option<RawFrame>,
        dt: u32,
    ) -> Result<Option<Option<Reason>>, String> {
        let now = self.now.wrapping_add(dt);
        let standing = self.n.gait().is_standing();
        let next_side = self.n.gait().next_side();
        self.model.cycle = u64::from(self.n.cycles());
        let expect = frame.map(|f| self.model.expect(&f, standing, next_side));
        let without = frame.map(|_| {
            let mut w = self.n.clone();
            w.poll(now, &mut Bus::default());
            w
        });
        if let Some(f) = frame {
            self.bus.rx.push_back(f);
            self.sent.push(f);
            self.stats.frames += 1;
        }
        self.n.poll(now, &mut self.bus);
        self.now = now;
        self.cycles += 1;
        self.stats.cycles += 1;
        ensure!(self.bus.rx.is_empty(), "the frame was not taken");
        let mut acks = vec![];
        let mut diag = None;
        for f in self.bus.tx.drain(..) {
            if let Some(a) = Ack::decode(&f) {
                acks.push(a);
            } else if let Some(d) = Diag::decode(&f) {
                diag = Some(d);
            }
        }

        // The answer.
        let (mut answer, mut started, mut rebased) = (None, false, false);
        match (frame, expect, without) {
            (Some(f), Some(Answer::Ignored), Some(without)) => {
                ensure!(acks.is_empty(), "foreign frame {f:?} answered: {acks:?}");
                ensure!(
                    self.n.same_state(&without),
                    "foreign frame {f:?} changed the node"
                );
                self.stats.foreign += 1;
            }
            (Some(f), Some(Answer::OneOf(allowed)), Some(without)) => {
                let cmd = Command::decode(&f, self.model.expect_for_decode());
                ensure!(acks.len() == 1, "{f:?} ({cmd:?}): answers {acks:?}");
                let a = acks[0];
                let echo = f.bytes().last().copied().unwrap_or(0);
                // The low byte of the sequence number (control) or step number (footsteps).
                let at = usize::from(f.id == 0x020) * 2;
                let key = f.bytes().get(at).copied().unwrap_or(0);
                ensure!(
                    a.command == (f.id & 0xFF) as u8 && a.seq == key && a.echo == echo,
                    "{f:?}: the answer {a:?} is not about it"
                );
                ensure!(
                    allowed.contains(&a.reason),
                    "{cmd:?}: the node answered {:?}, the model allows {allowed:?} \
                     (standing {standing}, next side {next_side:?}, model {})",
                    a.reason,
                    self.describe()
                );
                match a.reason {
                    Some(r) => {
                        ensure!(
                            self.n.same_state(&without),
                            "{cmd:?} refused with {r:?} changed the node"
                        );
                        self.stats.refused[usize::from(r.code())] += 1;
                        if allowed.len() == 1 {
                            self.stats.demanded[usize::from(r.code())] += 1;
                        }
                    }
                    None => {
                        let c = cmd.expect("accepted: decodes");
                        self.model.accept(&f, c, now, self.cycles, standing);
                        self.stats.accepted += 1;
                        match c {
                            Command::Control { op, .. } => {
                                started =
                                    matches!(op, ControlOp::Start | ControlOp::StartAdjusting);
                                rebased = op == ControlOp::Reset;
                            }
                            Command::Append(s) => {
                                // The controller's book follows what the node accepted.
                                let (x, y, yaw) = s.si();
                                let b = self.book.append(s.id, s.left, x, y, yaw);
                                ensure!(b == Some(c), "the book re-encodes {s:?} as {b:?}");
                                self.stats.appends += 1;
                            }
                            Command::Modify(_) => self.stats.modifications += 1,
                            Command::EmergencyStop { .. } => {}
                            Command::Measured(_) => self.stats.measured += 1,
                            // (The programs give the footsteps: no velocity or goal.)
                            Command::Velocity(_) | Command::Goal(_) => {}
                        }
                        if rebased {
                            self.book.clear();
                            self.stats.resets += 1;
                        }
                    }
                }
                ensure!(
                    usize::from(a.queue) == self.model.queue.len(),
                    "{cmd:?}: the ACK says {} queued, the model {}",
                    a.queue,
                    self.model.queue.len()
                );
                let version = match cmd {
                    Ok(Command::Append(s)) => self.model.version(s.id),
                    Ok(Command::Modify(m)) => self.model.version(m.id),
                    _ => None,
                };
                ensure!(
                    a.version == version,
                    "{cmd:?}: the ACK says version {:?} in force, the model {version:?}",
                    a.version
                );
                answer = Some(a.reason);
            }
            _ => ensure!(acks.is_empty(), "answers without a frame: {acks:?}"),
        }

        // Supervision (after the commands, before the tick).
        if self.model.supervise(now, self.cycles, !standing || started) {
            self.stats.lost += 1;
        }

        // What the cycle did.
        let g = self.n.gait();
        let r = *g.last();
        let swing = g.swinging();
        let feet = *g.feet();
        let standing_now = g.is_standing();
        let queued = g.queued();
        let side_now = g.next_side();
        let width = g.params().step_width;
        let (hl, hw) = (g.params().sole_half_length, g.params().sole_half_width);
        let state = self.n.state();
        let heard = self.n.last_heard();

        if let Some(a) = self.prev_swing {
            if swing != Some(a) {
                // Landed: the foot stands where the step put it.
                if a == u16::MAX {
                    let side = self
                        .padded
                        .take()
                        .ok_or("a padded landing without lift-off")?;
                    let want = feet[ix(side.other())].beside(width);
                    let f = feet[ix(side)];
                    ensure!(
                        (f.x - want.x).abs() <= POSE_TOLERANCE
                            && (f.y - want.y).abs() <= POSE_TOLERANCE
                            && wrapped(f.yaw - want.yaw).abs() <= POSE_TOLERANCE,
                        "a padded step landed at {f:?}, not beside the other foot ({want:?})"
                    );
                    self.stats.padded += 1;
                } else {
                    let i = self
                        .model
                        .swing
                        .take()
                        .ok_or(format!("step {a} landed, the model swings none"))?;
                    let st = &mut self.model.steps[i];
                    ensure!(
                        st.id() == a && st.fate == Fate::Swinging,
                        "step {a} landed, the model swings {st:?}"
                    );
                    let f = feet[ix(st.side())];
                    // Where it was commanded, moved by the step adjustment's shift that was in
                    // force when it lifted off.
                    let (x, y, yaw) = (st.pose.0 + st.shift.0, st.pose.1 + st.shift.1, st.pose.2);
                    ensure!(
                        (f.x - x).abs() <= POSE_TOLERANCE
                            && (f.y - y).abs() <= POSE_TOLERANCE
                            && wrapped(f.yaw - yaw).abs() <= POSE_TOLERANCE,
                        "step {a} landed at {f:?}, its last accepted version {} is at {:?}",
                        st.version,
                        st.pose
                    );
                    st.fate = Fate::Landed;
                    st.walked += 1;
                    self.stats.walked += 1;
                    if st.modified > 0 {
                        self.stats.walked_modified += 1;
                    }
                    self.model.retire(i);
                }
            }
        }
        if let Some(b) = swing {
            if self.prev_swing != Some(b) {
                // Lifted off: within the supervision bound, in single support on the other
                // foot, the model's next step (or padding with nothing to walk).
                ensure!(
                    self.model
                        .last_heard
                        .is_some_and(|h| now.wrapping_sub(h) <= self.model.timeout),
                    "step {b} lifted off at {now} ms, the controller was last heard at {:?}",
                    self.model.last_heard
                );
                let silence = self.model.last_heard.map_or(0, |h| now.wrapping_sub(h));
                self.stats.liftoff_silence = self.stats.liftoff_silence.max(silence);
                let Phase::Single(support) = r.phase else {
                    return Err(format!("step {b} lifted off in {:?}", r.phase));
                };
                if b == u16::MAX {
                    ensure!(
                        self.model.queue.is_empty() && !self.model.stopping,
                        "a padded step lifted off (queued {:?}, stopping {})",
                        self.model.queue,
                        self.model.stopping
                    );
                    self.padded = Some(support.other());
                } else {
                    let i = self
                        .model
                        .queue
                        .pop_front()
                        .ok_or(format!("step {b} lifted off, the model has none queued"))?;
                    let st = &mut self.model.steps[i];
                    ensure!(
                        st.id() == b && st.epoch == self.model.epoch,
                        "step {b} lifted off, the model's next is {st:?}"
                    );
                    ensure!(
                        st.side() == support.other(),
                        "step {b} ({:?}) lifted off while the {support:?} foot supports",
                        st.side()
                    );
                    st.fate = Fate::Swinging;
                    let [sx, sy] = self.n.shift();
                    st.shift = (f64::from(sx) * 5e-4, f64::from(sy) * 5e-4);
                    self.model.swing = Some(i);
                }
            }
        }

        ensure!(
            !self.n.gait().replan_failed(),
            "a re-plan failed (the gait dropped its queue and settles)"
        );
        // Steps move only in a walk the controller started with step adjustment.
        let shift = self.n.shift();
        ensure!(
            shift == self.shift || self.model.adjusting || (rebased && shift == [0, 0]),
            "the node moved its steps ({:?} to {shift:?}) in a walk started without adjustment",
            self.shift
        );
        if shift != self.shift {
            self.stats.adjusted += 1;
        }
        self.shift = shift;
        ensure!(
            queued == self.model.queue.len(),
            "the gait queues {queued} steps, the model {}",
            self.model.queue.len()
        );
        let last = self.model.queue.back().copied().or(self.model.swing);
        if let Some(i) = last {
            let want = self.model.steps[i].side().other();
            ensure!(
                side_now == Some(want),
                "next side {side_now:?}, after step {} the model says {want:?}",
                self.model.steps[i].id()
            );
        }
        if standing && !standing_now {
            ensure!(started, "the robot started without an accepted Start");
        }
        if !standing && standing_now {
            // Standing after a stop: the queue walked (no step is accepted while stopping:
            // `a_step_appended_while_stopping_is_refused`).
            let left = self.model.queue.iter().map(|&i| &self.model.steps[i]);
            let left_ok = left.clone().count() == 0;
            ensure!(
                self.model.stopping && left_ok && self.model.swing.is_none(),
                "the robot stopped, the model: {}",
                self.describe()
            );
            self.stats.left_queued += left.count() as u64;
        }
        if standing_now {
            self.model.stopping = false;
        }
        let want = self.model.state(standing_now);
        ensure!(
            state == want,
            "state {state:?}, the model says {want:?} ({})",
            self.describe()
        );
        ensure!(
            heard == self.model.last_heard,
            "last heard {heard:?}, the model {:?}",
            self.model.last_heard
        );
        if let Some(d) = diag {
            ensure!(
                d.next_step == self.model.next,
                "DIAG next step {}, the model {}",
                d.next_step,
                self.model.next
            );
        }
        ensure!(
            self.n.session().epoch == self.model.session
                && self.n.session().last_seq == self.model.last_seq,
            "session {:?}, the model's epoch {} and last seq {}",
            self.n.session(),
            self.model.session,
            self.model.last_seq
        );
        ensure!(
            !self.n.clock_fault(),
            "a clock fault with a clock that advances"
        );

        // The support foot never moves; the swinging foot is the one the step names.
        let supports = |p: Phase, i: usize| match p {
            Phase::Single(s) => ix(s) == i,
            _ => true,
        };
        for i in 0..2 {
            if supports(r.phase, i) {
                ensure!(r.feet[i].z == 0.0, "support foot {i} off the floor: {r:?}");
                if supports(self.prev.phase, i) && !rebased {
                    ensure!(
                        r.feet[i] == self.prev.feet[i],
                        "support foot {i} moved: {:?} -> {:?} ({:?})",
                        self.prev.feet[i],
                        r.feet[i],
                        r.phase
                    );
                }
            }
        }
        if let (Phase::Single(s), Some(i)) = (r.phase, self.model.swing) {
            ensure!(
                self.model.steps[i].side() == s.other(),
                "step {} ({:?}) swings in single support on {s:?}",
                self.model.steps[i].id(),
                self.model.steps[i].side()
            );
        }

        // The ZMP is inside the support polygon.
        let (poly, worst, margin) = match r.phase {
            Phase::Single(s) => (
                hull(sole(&r.feet[ix(s)], hl, hw).to_vec()),
                &mut self.stats.zmp_single,
                &mut self.stats.zmp_margin_single,
            ),
            _ => {
                let mut p = sole(&r.feet[0], hl, hw).to_vec();
                p.extend(sole(&r.feet[1], hl, hw));
                (
                    hull(p),
                    &mut self.stats.zmp_double,
                    &mut self.stats.zmp_margin_double,
                )
            }
        };
        let e = outside(&poly, (r.x.zmp, r.y.zmp));
        *worst = worst.max(e.max(0.0));
        *margin = margin.max(e.min(0.0));
        ensure!(
            e <= ZMP_TOLERANCE,
            "ZMP ({}, {}) {:.3} mm outside the support polygon in {:?} (feet {:?})",
            r.x.zmp,
            r.y.zmp,
            e * 1e3,
            r.phase,
            r.feet
        );

        self.prev = r;
        self.prev_swing = swing;
        Ok(answer)
    }

    pub(crate) fn describe(&self) -> String {
        let m = &self.model;
        format!(
            "queue {:?}, swing {:?}, estopped {}, lost {}, stopping {}, open {}, session {}, \
             last seq {}, next step {}, last heard {:?}, now {}",
            m.queue.iter().map(|&i| m.steps[i].id()).collect::<Vec<_>>(),
            m.swing.map(|i| m.steps[i].id()),
            m.estopped,
            m.lost,
            m.stopping,
            m.open,
            m.session,
            m.last_seq,
            m.next,
            m.last_heard,
            self.now
        )
    }

    pub(crate) fn send(&mut self, c: Command) -> Result<Option<Reason>, String> {
        Ok(self.cycle(Some(c.encode()), 5)?.flatten())
    }

    pub(crate) fn poll(&mut self, k: u32) -> Result<(), String> {
        for i in 0..k {
            let f = (i % 20 == 0).then(|| self.heartbeat().encode());
            self.cycle(f, 5)?;
        }
        Ok(())
    }

    /// The next heartbeat (a new sequence number: a repeated one proves nothing).
    pub(crate) fn heartbeat(&mut self) -> Command {
        self.control(self.fresh_seq(), ControlOp::Heartbeat)
    }

    /// Control command `op` with `seq`, in the session the node publishes.
    pub(crate) fn control(&self, seq: u32, op: ControlOp) -> Command {
        Command::Control {
            session: self.n.session().tag(),
            seq,
            op,
        }
    }

    /// One more than the last accepted control sequence number (`SESSION` publishes it).
    pub(crate) fn fresh_seq(&self) -> u32 {
        self.n.session().last_seq + 1
    }

    pub(crate) fn seq(&mut self, s: Seq) -> u32 {
        let v = match s {
            Seq::Fresh => self.fresh_seq(),
            Seq::Reuse(k) if !self.seqs.is_empty() => self.seqs[k % self.seqs.len()],
            Seq::Reuse(_) => self.fresh_seq(),
            Seq::After(d) => (self.fresh_seq() - 1).wrapping_add(u32::from(d)),
            Seq::Any(v) => u32::from(v),
        };
        self.seqs.push(v);
        v
    }

    pub(crate) fn append_frame(
        &self,
        kind: AppendKind,
        forward: f64,
        lateral: f64,
        turn: f64,
        left: bool,
    ) -> Option<RawFrame> {
        let g = self.n.gait();
        let expected = self.model.expected_id();
        let free = if left { Side::Left } else { Side::Right };
        let want = g.next_side().unwrap_or(free);
        let (id, side, forward) = match kind {
            AppendKind::Next => (expected, want, forward),
            AppendKind::WrongSide => (expected, want.other(), forward),
            AppendKind::Far => (expected, want, forward + 0.5),
            AppendKind::Skip(k) => (expected.wrapping_add(u16::from(k)), want, forward),
            AppendKind::Old(p) if expected > 0 => {
                ((p % usize::from(expected)) as u16, want, forward)
            }
            AppendKind::Old(p) => (0xFFFF - (p % 8) as u16, want, forward),
        };
        // Beside the previous foot of the other side, `forward` along its heading.
        let other = g.previous_other(side, None);
        let spot = other.beside(0.2);
        let (s, c) = other.yaw.sin_cos();
        let out = if side == Side::Left {
            lateral
        } else {
            -lateral
        };
        let x = spot.x + forward * c - out * s;
        let y = spot.y + forward * s + out * c;
        let step = WireStep::from_si(id, side == Side::Left, x, y, other.yaw + turn)?;
        Some(Command::Append(step).encode())
    }

    pub(crate) fn modify_frame(
        &mut self,
        kind: ModifyKind,
        pick: usize,
        dx: f64,
        dy: f64,
        dyaw: f64,
    ) -> Option<RawFrame> {
        let m = &self.model;
        let queued: Vec<u16> = m.queue.iter().map(|&i| m.steps[i].id()).collect();
        let known: Vec<usize> = (0..m.steps.len())
            .filter(|&i| m.steps[i].epoch == m.epoch)
            .collect();
        let id = if !queued.is_empty() && pick % 4 != 0 {
            queued[(pick / 4) % queued.len()]
        } else if !known.is_empty() {
            m.steps[known[(pick / 4) % known.len()]].id()
        } else {
            (pick % 4) as u16
        };
        let step = known.iter().rev().find(|&&i| m.steps[i].id() == id);
        let (px, py, pyaw) = match step {
            Some(&i) => m.steps[i].pose,
            None => (0.2, -0.1, 0.0),
        };
        let version = m.version(id).unwrap_or(0);
        let (x, y, yaw) = (px + dx, py + dy, pyaw + dyaw);
        let Some(base) = self.book.appended(id) else {
            // Never accepted: a modification of a step the node does not know.
            let base = WireStep::from_si(id, pick % 2 == 0, 0.2, 0.1, 0.0)?;
            let m = WireModify::from_si(&base, 1, x, y, yaw)?;
            return Some(Command::Modify(m).encode());
        };
        let m = match kind {
            ModifyKind::Next => match self.book.modify(id, x, y, yaw)? {
                Command::Modify(m) => m,
                _ => return None,
            },
            ModifyKind::FlipSide => match self.book.modify(id, x, y, yaw)? {
                Command::Modify(m) => WireModify { left: !m.left, ..m },
                _ => return None,
            },
            ModifyKind::Jump(j) => {
                // Any version 1 … 127, older or newer than the one in force.
                let v = (u16::from(version) + u16::from(j)) % 127 + 1;
                WireModify::from_si(&base, v as u8, x, y, yaw)?
            }
        };
        Some(Command::Modify(m).encode())
    }

    pub(crate) fn op(&mut self, op: &Op) -> Result<(), String> {
        let frame = match *op {
            Op::Append {
                kind,
                forward,
                lateral,
                turn,
                left,
            } => self.append_frame(kind, forward, lateral, turn, left),
            Op::Modify {
                kind,
                pick,
                dx,
                dy,
                dyaw,
            } => {
                let f = self.modify_frame(kind, pick, dx, dy, dyaw);
                self.modifies.extend(f);
                f
            }
            Op::ResendModify(k) => (!self.modifies.is_empty())
                .then(|| self.modifies[self.modifies.len() - 1 - k % self.modifies.len()]),
            Op::Resend(k) => (!self.sent.is_empty()).then(|| self.sent[k % self.sent.len()]),
            Op::ResendStep(k, in_force) => {
                let m = &self.model;
                let epoch: Vec<&Step> = m.steps.iter().filter(|s| s.epoch == m.epoch).collect();
                epoch.len().checked_sub(1 + k).map(|i| {
                    let st = epoch[i];
                    match st.in_force {
                        Some(f) if in_force => f,
                        _ => st.append_frame,
                    }
                })
            }
            Op::RepeatLast => self.sent.last().copied(),
            Op::Control(op, s) => {
                let seq = self.seq(s);
                Some(self.control(seq, op).encode())
            }
            Op::OldSession(op, back) => {
                // A fresh sequence number, the session `back` + 1 epochs before (or after).
                let seq = self.fresh_seq();
                let tag = self.n.session().tag();
                let session = if back % 2 == 0 {
                    tag.wrapping_sub(1 + u16::from(back / 2))
                } else {
                    tag.wrapping_add(1 + u16::from(back / 2))
                };
                Some(Command::Control { session, seq, op }.encode())
            }
            Op::Estop(s) => {
                let seq = match s {
                    Seq::Fresh => {
                        self.estop_seq = self.estop_seq.wrapping_add(1);
                        self.estop_seq
                    }
                    Seq::Reuse(_) | Seq::After(0) => self.estop_seq,
                    Seq::After(d) => self.estop_seq.wrapping_add(d),
                    Seq::Any(v) => v,
                };
                Some(Command::EmergencyStop { seq }.encode())
            }
            Op::Foreign(i, n, b) => RawFrame::new(FOREIGN_IDS[i], &vec![b; usize::from(n % 9)]),
            Op::Measure(back, valid, this_session) => {
                let stamp = self.n.cycles().wrapping_sub(back);
                let dev = [0.01 * f64::from(back % 7), if valid { -0.02 } else { 0.0 }];
                let m = Measured::from_si(stamp, dev).ok_or("a measured state out of range")?;
                let epoch = self.n.session().epoch;
                Some(m.encode(if this_session {
                    epoch
                } else {
                    epoch.wrapping_sub(1)
                }))
            }
            Op::Corrupt(k, bit) => {
                let protected: Vec<RawFrame> = self
                    .sent
                    .iter()
                    .copied()
                    .filter(|f| {
                        matches!(f.id, 0x020 | 0x0D8 | 0x100 | 0x101)
                            && Command::decode(f, self.model.expect_for_decode()).is_ok()
                    })
                    .collect();
                let mut f = protected
                    .get(k % protected.len().max(1))
                    .copied()
                    .unwrap_or_else(|| self.heartbeat().encode());
                let b = usize::from(bit) % (8 * usize::from(f.len));
                f.data[b / 8] ^= 1 << (b % 8);
                Some(f)
            }
            Op::Truncate(k, n) => {
                let ours: Vec<RawFrame> = self
                    .sent
                    .iter()
                    .copied()
                    .filter(|f| {
                        COMMAND_IDS.contains(&f.id)
                            && Command::decode(f, self.model.expect_for_decode()).is_ok()
                    })
                    .collect();
                let f = ours
                    .get(k % ours.len().max(1))
                    .copied()
                    .unwrap_or_else(|| self.heartbeat().encode());
                let len = usize::from(f.len);
                // Shorter, or (an `ESTOP`, one byte) longer.
                let new = if len == 1 {
                    2 + usize::from(n) % 7
                } else {
                    usize::from(n) % len
                };
                let mut d = f.data;
                if new > len {
                    d[len..new].fill(n);
                }
                RawFrame::new(f.id, &d[..new])
            }
            Op::Poll(k) => return self.poll(k),
            Op::Silence(k) => {
                for _ in 0..k {
                    self.cycle(None, 5)?;
                }
                return Ok(());
            }
            Op::ClockJump(ms) => {
                self.stats.clock_jumps += 1;
                self.cycle(None, 5 + ms)?;
                return Ok(());
            }
            Op::Recover => {
                self.send(self.control(self.fresh_seq(), ControlOp::Stop))?;
                self.until_standing(4000)?;
                self.send(self.control(self.fresh_seq(), ControlOp::Reset))?;
                return Ok(());
            }
        };
        if let Some(f) = frame {
            self.cycle(Some(f), 5)?;
        }
        Ok(())
    }

    pub(crate) fn until_standing(&mut self, limit: u32) -> Result<(), String> {
        for k in 0..limit {
            if self.n.gait().is_standing() {
                return Ok(());
            }
            let f = (k % 20 == 0).then(|| self.heartbeat().encode());
            self.cycle(f, 5)?;
        }
        Err(format!(
            "not standing after {limit} cycles: {}",
            self.describe()
        ))
    }

    /// The controller stops the robot; every accepted step was walked exactly once or
    /// dropped by an event.
    pub(crate) fn drain(&mut self) -> Result<(), String> {
        if !self.model.open {
            // No session yet (and so nothing moved): the handshake.
            let a = self.send(self.control(self.fresh_seq(), ControlOp::Reset))?;
            ensure!(a.is_none(), "drain: the handshake refused with {a:?}");
        }
        let hb = self.heartbeat();
        self.send(hb)?;
        for _ in 0..2 {
            if self.n.state() == NodeState::Standing && !self.model.queue.is_empty() {
                let a = self.send(self.control(self.fresh_seq(), ControlOp::Start))?;
                ensure!(a.is_none(), "drain: Start refused with {a:?}");
            }
            let a = self.send(self.control(self.fresh_seq(), ControlOp::Stop))?;
            ensure!(a.is_none(), "drain: Stop refused with {a:?}");
            self.until_standing(16 * 200 + 1000)?;
        }
        for st in &self.model.steps {
            match st.fate {
                Fate::Landed => ensure!(st.walked == 1, "walked {} times: {st:?}", st.walked),
                Fate::Dropped(why) => {
                    ensure!(st.walked == 0, "dropped and walked: {st:?}");
                    self.stats.dropped[why as usize] += 1;
                }
                _ => return Err(format!("neither walked nor dropped: {st:?}")),
            }
        }
        Ok(())
    }
}
