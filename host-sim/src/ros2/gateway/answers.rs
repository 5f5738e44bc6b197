//! What the gateway sends for each outbox item, and what it makes of the node's answers
//! (`ACK`, `SESSION`, `DIAG`, `STATUS`, `ADJUST`).

use super::*;

impl Gateway {
    /// The command of an outbox item, or why not now.
    pub(super) fn encode(&mut self, item: Item) -> Encoded {
        match item {
            Item::Append(key) => {
                let s = &self.steps[key];
                if s.state != State::Pending {
                    return Encoded::Skip;
                }
                if self.failed_batches.contains(&s.batch) {
                    self.refuse_step(
                        key,
                        State::Refused,
                        "step_append",
                        Err("after_refused_step"),
                        "not sent: an earlier step of its list was refused".into(),
                    );
                    return Encoded::Skip;
                }
                let Some(number) = self.next_number else {
                    return Encoded::Wait;
                };
                let p = self.frame.relative(&s.pose);
                let left = s.side == Side::Left;
                let Some(c) = self.book.append(number, left, p.x, p.y, p.yaw) else {
                    self.refuse_step(
                        key,
                        State::Refused,
                        "step_append",
                        Err("out_of_range"),
                        "the pose is not representable on the bus".into(),
                    );
                    return Encoded::Skip;
                };
                self.next_number = number.checked_add(1);
                let s = &mut self.steps[key];
                (s.number, s.state) = (Some(number), State::Sent);
                Encoded::Frame(c)
            }
            Item::Modify(key, d, list) => {
                let s = &self.steps[key];
                let Some(number) = s.number else {
                    return Encoded::Skip;
                };
                // One modification of a step at a time, at most one every MODIFY_CYCLES.
                let on_its_way = self
                    .inflight
                    .iter()
                    .any(|f| matches!(f.item, Item::Modify(k, ..) if k == key));
                if on_its_way || self.cycle < s.last_modify + MODIFY_CYCLES {
                    return Encoded::Later;
                }
                if !s.unlifted() {
                    self.refusal(
                        list,
                        d.id,
                        d.index,
                        "step_modify",
                        Err("lifted_off"),
                        "the foot lifted off before the change was sent".into(),
                    );
                    return Encoded::Skip;
                }
                let p = self.frame.relative(&d.pose);
                if self.book.version(number).is_some_and(|v| v >= 127) {
                    self.steps[key].requested = self.steps[key].pose;
                    self.refusal(
                        list,
                        d.id,
                        d.index,
                        "step_modify",
                        Err("versions_exhausted"),
                        "the step has had its 127 modifications; it lands at its last accepted \
                         pose"
                            .into(),
                    );
                    return Encoded::Skip;
                }
                match self.book.modify(number, p.x, p.y, p.yaw) {
                    Some(c) => {
                        self.steps[key].last_modify = self.cycle;
                        Encoded::Frame(c)
                    }
                    None => {
                        self.steps[key].requested = self.steps[key].pose;
                        self.refusal(
                            list,
                            d.id,
                            d.index,
                            "step_modify",
                            Err("out_of_range"),
                            "the move from the appended pose is beyond the bus's ±4.096 m".into(),
                        );
                        Encoded::Skip
                    }
                }
            }
            Item::Control(op, _) => Encoded::Frame(self.control(op)),
            Item::Start(batch, adjusting) => {
                let appending = self
                    .inflight
                    .iter()
                    .any(|f| matches!(f.item, Item::Append(_)));
                if appending {
                    return Encoded::Wait;
                }
                if self.failed_batches.contains(&batch) {
                    // Walk a list whole or not at all from standing: drop what of it the node
                    // queued.
                    let dropped: Vec<usize> = (0..self.steps.len())
                        .filter(|&k| self.steps[k].batch == batch && self.steps[k].unlifted())
                        .collect();
                    for &k in &dropped {
                        self.refuse_step(
                            k,
                            State::Dropped,
                            "step_append",
                            Err("list_not_walked"),
                            "accepted, then dropped: another step of its list was refused".into(),
                        );
                    }
                    if dropped.is_empty() {
                        return Encoded::Skip;
                    }
                    return Encoded::Frame(self.control(ControlOp::StopNow));
                }
                // One start a walk: a walk already started (or starting) takes the list's steps.
                let starting = self
                    .inflight
                    .iter()
                    .any(|f| matches!(f.item, Item::Start(..)));
                if self.walking.is_some()
                    || starting
                    || !self.steps.iter().any(|s| s.state == State::Queued)
                {
                    return Encoded::Skip;
                }
                let op = if adjusting {
                    ControlOp::StartAdjusting
                } else {
                    ControlOp::Start
                };
                Encoded::Frame(self.control(op))
            }
        }
    }

    pub(super) fn track(&mut self, c: &Command, item: Item) {
        self.inflight.push(InFlight {
            code: c.code(),
            key: c.key(),
            echo: c.echo(),
            item,
            cycle: self.cycle,
            silent: false,
            resend: false,
        });
    }

    /// Commands unanswered for too long.
    pub(super) fn expire(&mut self) {
        let limit = self.cfg.answer_cycles;
        let cycle = self.cycle;
        let (old, keep): (Vec<InFlight>, Vec<InFlight>) = self
            .inflight
            .drain(..)
            .partition(|f| cycle.saturating_sub(f.cycle) > limit);
        self.inflight = keep;
        for f in old {
            if let Item::Append(key) = f.item {
                if self.steps[key].state == State::Sent {
                    self.steps[key].state = State::Refused;
                }
                // The node's next number is read again from DIAG.
                self.next_number = None;
            }
            if matches!(f.item, Item::Control(ControlOp::Heartbeat, _)) {
                continue;
            }
            let (list, id, index, what) = self.describe(&f.item);
            self.refusal(
                list,
                id,
                index,
                what,
                Err("no_answer"),
                format!("no answer from the node within {limit} cycles"),
            );
        }
    }

    pub(super) fn describe(&self, item: &Item) -> (u32, u32, i32, &'static str) {
        match *item {
            Item::Append(k) => {
                let s = &self.steps[k];
                (s.list, s.id, s.index, "step_append")
            }
            Item::Modify(_, d, list) => (list, d.id, d.index, "step_modify"),
            Item::Start(batch, _) => (self.list_of(batch), 0, -1, "start"),
            Item::Control(op, origin) => {
                let list = match origin {
                    Origin::Gateway => 0,
                    Origin::List(i) | Origin::Pause(i) | Origin::Abort(i) => i,
                };
                let name = match op {
                    ControlOp::Heartbeat => "heartbeat",
                    ControlOp::Start | ControlOp::StartAdjusting => "start",
                    ControlOp::Stop => "stop",
                    ControlOp::StopNow => match origin {
                        Origin::Pause(_) => "pause",
                        Origin::Abort(_) => "abort",
                        _ => "stop_now",
                    },
                    ControlOp::Reset => "reset",
                };
                (list, 0, -1, name)
            }
        }
    }

    /// A frame the node sent.
    pub fn on_frame(&mut self, f: &RawFrame) {
        if let Some(a) = Ack::decode(f) {
            return self.on_ack(a);
        }
        if let Some(s) = Session::decode(f) {
            if self.link == Link::WaitSession {
                self.epoch = s.epoch;
                self.session_seen = true;
            } else if self.link == Link::Open && s.epoch != self.epoch && !self.resetting {
                self.session_taken(s.epoch);
            }
            self.seq = self.seq.max(s.last_seq);
            return;
        }
        if let Some(d) = Diag::decode(f) {
            let appending = self
                .inflight
                .iter()
                .any(|f| matches!(f.item, Item::Append(_)));
            // Before the handshake's Reset is answered the number holds too: that Reset skips
            // none (a later one does, and its number is waited for).
            if !appending && !self.resetting {
                self.next_number = Some(d.next_step);
            }
            return;
        }
        if let Some(s) = Status::decode(f) {
            return self.on_status(s);
        }
        if let Some(a) = Adjust::decode(f) {
            self.shift = a.shift_si();
            return;
        }
        if f.id >= ids::COG && f.id <= ids::FOOT_RIGHT && self.stream.decode_into(f) {
            self.have_stream = true;
        }
    }

    pub(super) fn on_status(&mut self, s: Status) {
        let was = self.node_state;
        self.node_state = s.state;
        if (s.state == 2 || s.state == 3) && was != s.state {
            // The node's safety stopped the walk: nothing not yet lifted off will be walked.
            let why = if s.state == 2 {
                Reason::EmergencyStopped
            } else {
                Reason::ControllerLost
            };
            self.drop_plan(Ok(why), "dropped: the node stopped the walk");
            self.outbox.clear();
            self.paused = false;
            self.resume = false;
            if self.walking.take().is_some() {
                self.outputs
                    .push(Output::Walking(WALKING_ABORT_REQUESTED, 0));
            }
            self.close_walk();
            self.stopping = false;
            self.stop_sent = false;
        }
    }

    pub(super) fn on_ack(&mut self, a: Ack) {
        if self.on_drive_ack(&a) {
            return;
        }
        let Some(pos) = self
            .inflight
            .iter()
            .position(|f| f.code == a.command && f.key == a.seq && f.echo == a.echo)
        else {
            return;
        };
        let f = self.inflight.remove(pos);
        match f.item {
            Item::Append(key) if f.resend && a.reason.is_some() => {
                // Refused as a gap behind another list's refused step: sent again.
                let s = &mut self.steps[key];
                (s.state, s.number) = (State::Pending, None);
                self.resend.push(key);
            }
            Item::Append(key) => self.on_append_answer(key, a.reason, f.silent),
            Item::Modify(key, d, list) => match a.reason {
                None => {
                    let s = &mut self.steps[key];
                    (s.pose, s.list, s.index) = (d.pose, list, d.index);
                }
                Some(r) => {
                    // The pose in force stays; a newer one waiting is still compared with.
                    let waiting = self
                        .outbox
                        .iter()
                        .any(|i| matches!(i, Item::Modify(k, ..) if *k == key));
                    if !waiting {
                        self.steps[key].requested = self.steps[key].pose;
                    }
                    self.refusal(
                        list,
                        d.id,
                        d.index,
                        "step_modify",
                        Ok(r),
                        format!("to ({:.4}, {:.4}) m", d.pose.x, d.pose.y),
                    )
                }
            },
            Item::Start(batch, _) => match a.reason {
                None if self.failed_batches.contains(&batch) => self.stopping = true,
                None => {
                    let list = self.list_of(batch);
                    self.walking = Some(list);
                    self.moved = false;
                    self.stop_sent = false;
                    self.outputs.push(Output::Walking(WALKING_STARTED, list));
                }
                Some(r) => {
                    let list = self.list_of(batch);
                    self.refusal(list, 0, -1, "start", Ok(r), "the walk did not start".into());
                    self.drop_unlifted();
                    if self.steps.iter().any(|s| s.state == State::Dropped) {
                        self.outbox
                            .push_back(Item::Control(ControlOp::StopNow, Origin::List(list)));
                    }
                }
            },
            Item::Control(op, origin) => self.on_control_answer(op, origin, a.reason),
        }
    }

    /// Another controller opened a session (`epoch`): the gateway's commands are of an old
    /// session now. Every step not yet walked is dropped, the heartbeats stop, and the next
    /// list opens a session of the gateway's own (a `Reset`, once standing). The other
    /// controller's `Reset` moved the node's frame: it is found again from the feet, which did
    /// not move (see `end_cycle`).
    pub(super) fn session_taken(&mut self, epoch: u32) {
        self.outputs.push(Output::Log(format!(
            "session {epoch:#x} opened by another controller; the next list opens one again"
        )));
        self.drop_plan(
            Err("session_taken"),
            "dropped: another controller opened a session on the node",
        );
        if self.walking.take().is_some() {
            self.outputs
                .push(Output::Walking(WALKING_ABORT_REQUESTED, 0));
        }
        self.close_walk();
        self.outbox.clear();
        self.inflight.clear();
        (self.paused, self.resume, self.stop_sent, self.stopping) = (false, false, false, false);
        self.epoch = epoch;
        self.link = Link::WaitSession;
        self.claim_on_demand = true;
        self.next_number = None;
        self.book.clear();
    }

    /// Every step not yet walked (held ones included) dropped, each refused with `reason`.
    pub(super) fn drop_plan(&mut self, reason: Result<Reason, &str>, detail: &str) {
        let dropped: Vec<usize> = (0..self.steps.len())
            .filter(|&k| self.steps[k].unlifted() || self.steps[k].state == State::Held)
            .collect();
        for k in dropped {
            self.refuse_step(k, State::Dropped, "step_append", reason, detail.into());
        }
    }

    /// The steps of the walk that ended: their ids name no step any more (a peer may use
    /// them again for new steps).
    pub(super) fn close_walk(&mut self) {
        for s in self
            .steps
            .iter_mut()
            .filter(|s| !s.unlifted() && s.state != State::Held && s.state != State::Swinging)
        {
            s.closed = true;
        }
    }

    /// The peer's id of the list the gateway numbered `batch`.
    pub(super) fn list_of(&self, batch: u32) -> u32 {
        self.steps
            .iter()
            .find(|s| s.batch == batch)
            .map(|s| s.list)
            .unwrap_or(0)
    }

    pub(super) fn drop_unlifted(&mut self) {
        for s in self.steps.iter_mut().filter(|s| s.unlifted()) {
            s.state = State::Dropped;
        }
    }

    pub(super) fn on_append_answer(&mut self, key: usize, reason: Option<Reason>, silent: bool) {
        match reason {
            None => self.steps[key].state = State::Queued,
            Some(r) => {
                let s = &self.steps[key];
                let (list, id, index, number, pose, batch) =
                    (s.list, s.id, s.index, s.number, s.pose, s.batch);
                self.steps[key].state = State::Refused;
                if silent {
                    return;
                }
                self.refusal(
                    list,
                    id,
                    index,
                    "step_append",
                    Ok(r),
                    format!("at ({:.4}, {:.4}) m", pose.x, pose.y),
                );
                // The rest of its list is not sent; what is on its way is refused as a gap
                // (another list's steps on their way are sent again, renumbered).
                self.failed_batches.push(batch);
                for f in self.inflight.iter_mut() {
                    if let Item::Append(k) = f.item {
                        if self.steps[k].batch != batch {
                            f.silent = true;
                            f.resend = true;
                            continue;
                        }
                        f.silent = true;
                        let s = &self.steps[k];
                        self.outputs.push(Output::Refusal(CommandRefusal {
                            footstep_list_sequence_id: list,
                            footstep_sequence_id: s.id,
                            footstep_index: s.index,
                            command: "step_append".into(),
                            reason_code: 0,
                            reason: "after_refused_step".into(),
                            detail: "an earlier step of its list was refused".into(),
                        }));
                    }
                }
                self.next_number = number;
            }
        }
    }

    pub(super) fn on_control_answer(
        &mut self,
        op: ControlOp,
        origin: Origin,
        reason: Option<Reason>,
    ) {
        match (op, reason) {
            (ControlOp::Reset, None) => {
                if self.link == Link::Opening {
                    self.epoch = self.epoch.wrapping_add(1);
                    self.link = Link::Open;
                    self.outputs
                        .push(Output::Log(format!("session {:#x} open", self.epoch)));
                } else {
                    // The node re-based its frame on the feet.
                    self.epoch = self.epoch.wrapping_add(1);
                    let [l, r] = self.stream.feet;
                    let yaw = (l[3].sin() + r[3].sin()).atan2(l[3].cos() + r[3].cos());
                    let base = Pose {
                        x: 0.5 * (l[0] + r[0]),
                        y: 0.5 * (l[1] + r[1]),
                        yaw,
                    };
                    self.frame = self.frame.compose(&base);
                    self.book.clear();
                    self.next_number = None;
                    self.node_state = 0;
                    self.drop_unlifted();
                    self.outputs.push(Output::Log(format!(
                        "session {:#x} open again; the node's frame is at ({:.4}, {:.4}, {:.4})",
                        self.epoch, self.frame.x, self.frame.y, self.frame.yaw
                    )));
                }
                self.resetting = false;
            }
            (ControlOp::Reset, Some(r)) => {
                self.resetting = false;
                if self.link == Link::Opening {
                    // Hear the session again and retry.
                    self.link = Link::WaitSession;
                    self.session_seen = false;
                }
                self.outputs
                    .push(Output::Log(format!("reset refused: {}", reason_name(r))));
            }
            (ControlOp::Stop, None) => self.stopping = true,
            (ControlOp::StopNow, None) => {
                self.stopping = true;
                match origin {
                    Origin::Abort(id) | Origin::Pause(id) => {
                        // The walk ends here: no COMPLETED follows when the robot stands.
                        self.walking = None;
                        if matches!(origin, Origin::Abort(_)) {
                            self.close_walk();
                        }
                        self.outputs
                            .push(Output::Walking(WALKING_ABORT_REQUESTED, id));
                    }
                    _ => {}
                }
            }
            // A heartbeat answers nothing the peer asked: refused, it is only logged.
            (ControlOp::Heartbeat, r) => {
                if let Some(r) = r {
                    self.outputs.push(Output::Log(format!(
                        "heartbeat refused: {}",
                        reason_name(r)
                    )));
                }
            }
            (_, Some(r)) => {
                let (list, _, _, what) = self.describe(&Item::Control(op, origin));
                self.refusal(list, 0, -1, what, Ok(r), String::new());
            }
            (_, None) => {}
        }
    }
}
