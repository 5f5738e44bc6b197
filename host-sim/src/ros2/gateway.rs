//! The gateway's state machine, without DDS and without a bus: ROS 2 messages and the node's
//! frames in, CAN frames and ROS 2 messages out. The gateway is a controller of the node in
//! the sense of the book's *host-sim on a real bus*: it opens the session, heartbeats, appends
//! and modifies footsteps, starts and stops, and reads the answers and the reference stream.
//!
//! Per control cycle the driver calls [`Gateway::poll`] (the frames to send this cycle, at
//! most [`GatewayConfig::max_frames`]), lets the node run its cycle, hands every frame the
//! node sent to [`Gateway::on_frame`], and calls [`Gateway::end_cycle`]; it then publishes
//! what [`Gateway::take_outputs`] returns.
//!
//! **Footsteps.** A list ([`Gateway::on_footstep_list`]) is validated and matched
//! ([`super::plan`]); its new steps are appended (`STEP_APPEND`, numbered from the node's
//! next step number, `DIAG`), its moved steps modified (`STEP_MODIFY`: the paper's immediate
//! modification, until the foot lifts off), and a walk is started (`CONTROL` start, or start
//! with step adjustment if `are_footsteps_adjustable`) once every append of the list is
//! accepted. If one is refused, the rest of its list is not sent; if the robot stood, the
//! list's accepted steps are dropped again (`StopNow` while standing), so a list walks whole
//! or not at all from standing. When the last step not yet lifted off lifts off, the gateway
//! sends `Stop`: the node closes the walk after it. A list that arrives while the node is
//! stopping waits until it stands.
//!
//! **Lift-off and touchdown** are read from the stream (`COG_VEL.phase`): a single support
//! begins when the swing foot lifts off and ends when it lands; the first step not yet lifted
//! off is the one being swung if its foot is the swing foot (else the node is stepping in
//! place or closing the walk, which no list asked for: not reported). The landing is the
//! swing foot's pose in the stream at touchdown: the node's reference, its own step
//! adjustment included.
//!
//! **Frames of reference.** Lists are in the world frame, the node's footsteps and stream in
//! its own frame, which the node moves at every `Reset` after the first (to the midpoint of
//! the feet, see `planner_core::node`): the gateway keeps the node's frame in the world
//! ([`Gateway::frame`]), re-based from the stream's feet (0.1 mm) at each such `Reset`.
//!
//! **Liveness.** The gateway heartbeats the node only while the driver says a peer is there
//! (`peer_alive` of [`Gateway::poll`]: a footstep publisher is matched). When the peer
//! vanishes the heartbeats stop, and the node's own supervision stops a moving robot after
//! its timeout (500 ms). A node that has lost its controller is opened again (`Reset`, once
//! standing) by the next list; an emergency stop is never cleared by the gateway.

use std::collections::VecDeque;

use planner_core::gait::Side;
use planner_core::wire::{
    ids, Ack, Adjust, Command, ControlOp, Diag, RawFrame, Reason, Session, Status, StepBook, Stream,
};

use super::msg::{
    CommandRefusal, FootstepDataListMessage, FootstepStatusMessage, Point, Point32, Quaternion,
    FOOTSTEP_STATUS_COMPLETED, FOOTSTEP_STATUS_STARTED, ROBOT_SIDE_LEFT, ROBOT_SIDE_RIGHT,
    WALKING_ABORT_REQUESTED, WALKING_COMPLETED, WALKING_STARTED,
};
use super::plan::{self, Draft, Known, KnownStep, Pose};
use crate::scenario::expect::reason_name;

/// The gateway's settings.
#[derive(Clone, Copy, Debug)]
pub struct GatewayConfig {
    /// The control period \[s\].
    pub dt: f64,
    /// A heartbeat every this many cycles while a peer is there.
    pub heartbeat_cycles: u64,
    /// The most frames sent in one cycle (the node takes 16).
    pub max_frames: usize,
    /// A command unanswered for this many cycles is reported `no_answer`.
    pub answer_cycles: u64,
    /// The sole's length and width \[m\] (the support polygon).
    pub sole: [f64; 2],
    /// The COG height \[m\] (the published COG's z).
    pub cog_height: f64,
}

impl Default for GatewayConfig {
    fn default() -> Self {
        Self {
            dt: 0.005,
            heartbeat_cycles: 10,
            max_frames: 8,
            answer_cycles: 40,
            sole: [0.24, 0.14],
            cog_height: 0.814,
        }
    }
}

/// What the gateway publishes.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// A footstep lifted off or landed.
    Footstep(FootstepStatusMessage),
    /// The walk started, completed or was aborted (value, sequence id).
    Walking(u8, u32),
    /// A command refused by the gateway or by the node.
    Refusal(CommandRefusal),
    /// The reference of one cycle in the world frame: COG (z its height), ZMP (z 0), support
    /// polygon (counter-clockwise, z 0), and the cycle.
    Reference {
        /// COG.
        cog: Point,
        /// ZMP.
        zmp: Point,
        /// The support polygon.
        support: Vec<Point32>,
        /// The node's cycle (the stream's 24-bit tick).
        tick: u32,
    },
    /// A line for the log.
    Log(String),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// In the outbox, not yet sent.
    Pending,
    /// Its append is on its way.
    Sent,
    /// In the node's queue.
    Queued,
    /// Being swung.
    Swinging,
    /// Landed.
    Landed,
    /// Dropped by a stop, an abort or the node's safety.
    Dropped,
    /// Refused.
    Refused,
    /// Held by a pause, to be sent again at the resume.
    Held,
}

#[derive(Clone, Debug)]
struct Step {
    id: u32,
    list: u32,
    index: i32,
    side: Side,
    /// The pose in force (world).
    pose: Pose,
    number: Option<u16>,
    state: State,
    lift: Option<(u64, Pose)>,
}

impl Step {
    fn unlifted(&self) -> bool {
        matches!(self.state, State::Pending | State::Sent | State::Queued)
    }
}

/// Who asked for a control command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Origin {
    Gateway,
    List(u32),
    Pause(u32),
    Resume(u32),
    Abort(u32),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Item {
    Append(usize),
    Modify(usize, Draft, u32),
    Control(ControlOp, Origin),
    /// Start the walk once no append of the list is on its way.
    Start(u32, bool),
}

#[derive(Clone, Copy, Debug)]
struct InFlight {
    code: u8,
    key: u8,
    echo: u8,
    item: Item,
    cycle: u64,
    /// Expected to be refused (an append after a refused one): not reported.
    silent: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Link {
    WaitSession,
    Opening,
    Open,
}

/// The gateway (see the module docs).
#[derive(Clone, Debug)]
pub struct Gateway {
    cfg: GatewayConfig,
    link: Link,
    epoch: u32,
    seq: u32,
    book: StepBook,
    next_number: Option<u16>,
    steps: Vec<Step>,
    outbox: VecDeque<Item>,
    inflight: Vec<InFlight>,
    deferred: VecDeque<FootstepDataListMessage>,
    failed_lists: Vec<u32>,
    /// The node's frame in the world.
    frame: Pose,
    stream: Stream,
    have_stream: bool,
    phase: u8,
    node_state: u8,
    cycle: u64,
    walking: Option<u32>,
    moved: bool,
    stop_sent: bool,
    stopping: bool,
    paused: bool,
    shift: [f64; 2],
    peer_alive: bool,
    resetting: bool,
    session_seen: bool,
    outputs: Vec<Output>,
}

impl Gateway {
    /// A gateway that has heard nothing yet.
    pub fn new(cfg: GatewayConfig) -> Self {
        Self {
            cfg,
            link: Link::WaitSession,
            epoch: 0,
            seq: 0,
            book: StepBook::new(),
            next_number: None,
            steps: Vec::new(),
            outbox: VecDeque::new(),
            inflight: Vec::new(),
            deferred: VecDeque::new(),
            failed_lists: Vec::new(),
            frame: Pose::default(),
            stream: Stream::default(),
            have_stream: false,
            phase: 0,
            node_state: 5,
            cycle: 0,
            walking: None,
            moved: false,
            stop_sent: false,
            stopping: false,
            paused: false,
            shift: [0.0; 2],
            peer_alive: false,
            resetting: false,
            session_seen: false,
            outputs: Vec::new(),
        }
    }

    /// The node's frame in the world.
    pub fn frame(&self) -> Pose {
        self.frame
    }

    /// The session is open.
    pub fn is_open(&self) -> bool {
        self.link == Link::Open
    }

    /// The node's step adjustment (`ADJUST`'s shift) \[m\].
    pub fn shift(&self) -> [f64; 2] {
        self.shift
    }

    /// A walk is under way (started and not yet standing again).
    pub fn is_walking(&self) -> bool {
        self.walking.is_some()
    }

    /// What to publish, since the last call.
    pub fn take_outputs(&mut self) -> Vec<Output> {
        std::mem::take(&mut self.outputs)
    }

    fn refusal(
        &mut self,
        list: u32,
        id: u32,
        index: i32,
        command: &str,
        reason: Result<Reason, &str>,
        detail: String,
    ) {
        let (code, name) = match reason {
            Ok(r) => (r.code(), reason_name(r)),
            Err(n) => (0, n.to_string()),
        };
        self.outputs.push(Output::Log(format!(
            "refused: {command} (list {list}, step {id}, index {index}): {name}: {detail}"
        )));
        self.outputs.push(Output::Refusal(CommandRefusal {
            footstep_list_sequence_id: list,
            footstep_sequence_id: id,
            footstep_index: index,
            command: command.to_string(),
            reason_code: code,
            reason: name,
            detail,
        }));
    }

    fn refuse_list(&mut self, msg: &FootstepDataListMessage, e: plan::ListError) {
        self.refusal(
            msg.sequence_id,
            e.id,
            e.index,
            "footstep_list",
            Err(e.reason),
            e.detail,
        );
    }

    /// A footstep list from the peer.
    pub fn on_footstep_list(&mut self, msg: FootstepDataListMessage) {
        // Validate at once, whatever the node's state: a malformed list is answered now.
        if let Err(e) = plan::validate(&msg, &self.frame) {
            self.refuse_list(&msg, e);
            return;
        }
        if self.node_state == 2 {
            self.refusal(
                msg.sequence_id,
                0,
                -1,
                "footstep_list",
                Ok(Reason::EmergencyStopped),
                "the node is emergency-stopped; the gateway does not clear an emergency stop \
                 (a Reset on the node's bus does, once standing)"
                    .into(),
            );
            return;
        }
        self.deferred.push_back(msg);
        self.run_deferred();
    }

    /// Ready to plan a list now: the session is open, the next step number known, nothing
    /// stopping and no `Reset` on its way.
    fn ready(&self) -> bool {
        self.link == Link::Open
            && self.next_number.is_some()
            && !self.stopping
            && !self.resetting
            && !self
                .inflight
                .iter()
                .any(|f| matches!(f.item, Item::Append(_)))
    }

    fn run_deferred(&mut self) {
        while !self.deferred.is_empty() {
            if self.node_state == 3 && self.link == Link::Open && !self.resetting {
                // The node lost its controller (this gateway): open the session again once
                // the robot stands.
                if self.phase == 0 && self.have_stream {
                    self.resetting = true;
                    self.outbox
                        .push_back(Item::Control(ControlOp::Reset, Origin::Gateway));
                }
                return;
            }
            if !self.ready() {
                return;
            }
            let Some(msg) = self.deferred.pop_front() else {
                return;
            };
            self.plan_list(msg);
        }
    }

    fn known(&self) -> Vec<KnownStep> {
        let mut lifted: Vec<KnownStep> = Vec::new();
        let mut unlifted: Vec<KnownStep> = Vec::new();
        for (key, s) in self.steps.iter().enumerate() {
            let known = match s.state {
                State::Swinging | State::Landed => Known::Lifted,
                State::Pending | State::Sent | State::Queued => Known::Unlifted,
                _ => continue,
            };
            let k = KnownStep {
                key,
                id: s.id,
                side: s.side,
                pose: s.pose,
                known,
            };
            if known == Known::Lifted {
                lifted.push(k);
            } else {
                unlifted.push(k);
            }
        }
        lifted.extend(unlifted);
        lifted
    }

    fn plan_list(&mut self, msg: FootstepDataListMessage) {
        // The frame may have moved since the list was validated (a Reset in between).
        let drafts = match plan::validate(&msg, &self.frame) {
            Ok(d) => d,
            Err(e) => return self.refuse_list(&msg, e),
        };
        let standing = self.walking.is_none() && self.phase == 0;
        let mode = msg.queueing_properties.execution_mode;
        let planned = match plan::plan(&drafts, mode, &self.known(), standing) {
            Ok(p) => p,
            Err(e) => return self.refuse_list(&msg, e),
        };
        let list = msg.sequence_id;
        if planned.drop_queue {
            for s in self.steps.iter_mut().filter(|s| s.unlifted()) {
                s.state = State::Dropped;
            }
            self.outbox
                .retain(|i| !matches!(i, Item::Append(_) | Item::Modify(..)));
            self.outbox
                .push_back(Item::Control(ControlOp::StopNow, Origin::List(list)));
        }
        for (key, d) in planned.late {
            let pose = self.steps[key].pose;
            self.refusal(
                list,
                d.id,
                d.index,
                "step_modify",
                Err("lifted_off"),
                format!(
                    "footstep {} lifted off before the change reached the node; it lands at \
                     ({:.4}, {:.4}) m, not ({:.4}, {:.4}) m",
                    d.id, pose.x, pose.y, d.pose.x, d.pose.y
                ),
            );
        }
        for (key, d) in planned.modify {
            if self.steps[key].state == State::Pending {
                // Not yet sent: the append carries the new pose.
                let s = &mut self.steps[key];
                (s.pose, s.list, s.index) = (d.pose, list, d.index);
            } else {
                self.outbox.push_back(Item::Modify(key, d, list));
            }
        }
        let new = !planned.append.is_empty();
        for d in planned.append {
            self.steps.push(Step {
                id: d.id,
                list,
                index: d.index,
                side: d.side,
                pose: d.pose,
                number: None,
                state: State::Pending,
                lift: None,
            });
            self.outbox.push_back(Item::Append(self.steps.len() - 1));
        }
        if new && self.walking.is_none() && !self.paused {
            self.outbox
                .push_back(Item::Start(list, msg.are_footsteps_adjustable));
        }
        self.outputs.push(Output::Log(format!(
            "list {list}: {} footsteps (mode {mode})",
            drafts.len()
        )));
    }

    /// A pause (`true`) or resume (`false`) from the peer; `clear`: drop the held steps.
    pub fn on_pause(&mut self, id: u32, pause: bool, clear: bool) {
        if pause {
            if self.walking.is_none() || self.paused {
                let why = if self.paused {
                    "already paused"
                } else {
                    "no walk to pause"
                };
                return self.refusal(id, 0, -1, "pause", Err("not_walking"), why.into());
            }
            self.paused = true;
            let held = if clear { State::Dropped } else { State::Held };
            for s in self.steps.iter_mut().filter(|s| s.unlifted()) {
                s.state = held;
            }
            self.outbox
                .retain(|i| !matches!(i, Item::Append(_) | Item::Modify(..) | Item::Start(..)));
            self.outbox
                .push_back(Item::Control(ControlOp::StopNow, Origin::Pause(id)));
        } else {
            if !self.paused {
                return self.refusal(id, 0, -1, "resume", Err("not_paused"), "no pause".into());
            }
            self.paused = false;
            let held: Vec<usize> = (0..self.steps.len())
                .filter(|&k| self.steps[k].state == State::Held)
                .collect();
            if held.is_empty() {
                return;
            }
            for &k in &held {
                let mut s = self.steps[k].clone();
                self.steps[k].state = State::Dropped;
                (s.state, s.number) = (State::Pending, None);
                self.steps.push(s);
                self.outbox.push_back(Item::Append(self.steps.len() - 1));
            }
            let list = self.steps[held[0]].list;
            self.outbox.push_back(Item::Start(list, false));
            let _ = Origin::Resume(id);
        }
    }

    /// An abort from the peer: the node drops every step not yet walked (`StopNow`).
    pub fn on_abort(&mut self, id: u32) {
        let had = self
            .steps
            .iter()
            .any(|s| s.unlifted() || s.state == State::Held);
        for s in self
            .steps
            .iter_mut()
            .filter(|s| s.unlifted() || s.state == State::Held)
        {
            s.state = State::Dropped;
        }
        self.deferred.clear();
        self.paused = false;
        self.outbox
            .retain(|i| !matches!(i, Item::Append(_) | Item::Modify(..) | Item::Start(..)));
        if self.walking.is_some() || had {
            self.outbox
                .push_back(Item::Control(ControlOp::StopNow, Origin::Abort(id)));
        } else {
            self.refusal(id, 0, -1, "abort", Err("not_walking"), "no walk".into());
        }
    }

    fn control(&mut self, op: ControlOp) -> Command {
        self.seq += 1;
        Command::Control {
            session: self.epoch as u16,
            seq: self.seq,
            op,
        }
    }

    /// The frames to send this cycle; `peer_alive`: a peer is there (heartbeats go out only
    /// then).
    pub fn poll(&mut self, peer_alive: bool) -> Vec<RawFrame> {
        self.cycle += 1;
        self.peer_alive = peer_alive;
        let mut frames = Vec::new();
        if self.link == Link::WaitSession && self.have_session() {
            let reset = self.control(ControlOp::Reset);
            self.track(&reset, Item::Control(ControlOp::Reset, Origin::Gateway));
            frames.push(reset.encode());
            self.link = Link::Opening;
        }
        self.expire();
        self.run_deferred();
        // The walk is closed once the last step not yet lifted off has lifted off.
        if self.walking.is_some()
            && !self.stop_sent
            && !self.paused
            && !self.steps.iter().any(|s| s.unlifted())
            && self.outbox.is_empty()
            && self.moved
        {
            self.stop_sent = true;
            self.outbox
                .push_back(Item::Control(ControlOp::Stop, Origin::Gateway));
        }
        if self.link == Link::Open && peer_alive && self.cycle % self.cfg.heartbeat_cycles == 0 {
            let hb = self.control(ControlOp::Heartbeat);
            self.track(&hb, Item::Control(ControlOp::Heartbeat, Origin::Gateway));
            frames.push(hb.encode());
        }
        while frames.len() < self.cfg.max_frames && self.link == Link::Open {
            let Some(&item) = self.outbox.front() else {
                break;
            };
            match self.encode(item) {
                Encoded::Frame(c) => {
                    self.outbox.pop_front();
                    self.track(&c, item);
                    frames.push(c.encode());
                }
                Encoded::Skip => {
                    self.outbox.pop_front();
                }
                Encoded::Wait => break,
            }
        }
        frames
    }

    fn have_session(&self) -> bool {
        self.session_seen
    }
}

/// What an outbox item became.
enum Encoded {
    Frame(Command),
    Skip,
    Wait,
}

impl Gateway {
    /// The command of an outbox item, or why not now.
    fn encode(&mut self, item: Item) -> Encoded {
        match item {
            Item::Append(key) => {
                let s = &self.steps[key];
                if s.state != State::Pending {
                    return Encoded::Skip;
                }
                if self.failed_lists.contains(&s.list) {
                    let (list, id, index) = (s.list, s.id, s.index);
                    self.steps[key].state = State::Refused;
                    self.refusal(
                        list,
                        id,
                        index,
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
                    let (list, id, index) = (s.list, s.id, s.index);
                    self.steps[key].state = State::Refused;
                    self.refusal(
                        list,
                        id,
                        index,
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
                match self.book.modify(number, p.x, p.y, p.yaw) {
                    Some(c) => Encoded::Frame(c),
                    None => {
                        self.refusal(
                            list,
                            d.id,
                            d.index,
                            "step_modify",
                            Err("out_of_range"),
                            "the move from the appended pose is beyond the bus's ±4.096 m, or \
                             the step had its 127 versions"
                                .into(),
                        );
                        Encoded::Skip
                    }
                }
            }
            Item::Control(op, _) => Encoded::Frame(self.control(op)),
            Item::Start(list, adjusting) => {
                let appending = self
                    .inflight
                    .iter()
                    .any(|f| matches!(f.item, Item::Append(_)));
                if appending {
                    return Encoded::Wait;
                }
                if self.failed_lists.contains(&list) {
                    // Walk a list whole or not at all from standing: drop what of it the node
                    // queued.
                    let dropped: Vec<usize> = (0..self.steps.len())
                        .filter(|&k| self.steps[k].list == list && self.steps[k].unlifted())
                        .collect();
                    for &k in &dropped {
                        let s = &self.steps[k];
                        let (id, index) = (s.id, s.index);
                        self.steps[k].state = State::Dropped;
                        self.refusal(
                            list,
                            id,
                            index,
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
                if !self.steps.iter().any(|s| s.state == State::Queued) {
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

    fn track(&mut self, c: &Command, item: Item) {
        self.inflight.push(InFlight {
            code: c.code(),
            key: c.key(),
            echo: c.echo(),
            item,
            cycle: self.cycle,
            silent: false,
        });
    }

    /// Commands unanswered for too long.
    fn expire(&mut self) {
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

    fn describe(&self, item: &Item) -> (u32, u32, i32, &'static str) {
        match *item {
            Item::Append(k) => {
                let s = &self.steps[k];
                (s.list, s.id, s.index, "step_append")
            }
            Item::Modify(_, d, list) => (list, d.id, d.index, "step_modify"),
            Item::Start(list, _) => (list, 0, -1, "start"),
            Item::Control(op, origin) => {
                let list = match origin {
                    Origin::Gateway => 0,
                    Origin::List(i) | Origin::Pause(i) | Origin::Resume(i) | Origin::Abort(i) => i,
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
            }
            self.seq = self.seq.max(s.last_seq);
            return;
        }
        if let Some(d) = Diag::decode(f) {
            let appending = self
                .inflight
                .iter()
                .any(|f| matches!(f.item, Item::Append(_)));
            if self.link == Link::Open && !appending && !self.resetting {
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

    fn on_status(&mut self, s: Status) {
        let was = self.node_state;
        self.node_state = s.state;
        if (s.state == 2 || s.state == 3) && was != s.state {
            // The node's safety stopped the walk: nothing not yet lifted off will be walked.
            let why = if s.state == 2 {
                Reason::EmergencyStopped
            } else {
                Reason::ControllerLost
            };
            let dropped: Vec<usize> = (0..self.steps.len())
                .filter(|&k| self.steps[k].unlifted() || self.steps[k].state == State::Held)
                .collect();
            for k in dropped {
                let s = &self.steps[k];
                let (list, id, index) = (s.list, s.id, s.index);
                self.steps[k].state = State::Dropped;
                self.refusal(
                    list,
                    id,
                    index,
                    "step_append",
                    Ok(why),
                    "dropped: the node stopped the walk".into(),
                );
            }
            self.outbox.clear();
            self.paused = false;
            if self.walking.take().is_some() {
                self.outputs
                    .push(Output::Walking(WALKING_ABORT_REQUESTED, 0));
            }
            self.stopping = false;
            self.stop_sent = false;
        }
    }

    fn on_ack(&mut self, a: Ack) {
        let Some(pos) = self
            .inflight
            .iter()
            .position(|f| f.code == a.command && f.key == a.seq && f.echo == a.echo)
        else {
            return;
        };
        let f = self.inflight.remove(pos);
        match f.item {
            Item::Append(key) => self.on_append_answer(key, a.reason, f.silent),
            Item::Modify(key, d, list) => match a.reason {
                None => {
                    let s = &mut self.steps[key];
                    (s.pose, s.list, s.index) = (d.pose, list, d.index);
                }
                Some(r) => self.refusal(
                    list,
                    d.id,
                    d.index,
                    "step_modify",
                    Ok(r),
                    format!("to ({:.4}, {:.4}) m", d.pose.x, d.pose.y),
                ),
            },
            Item::Start(list, _) => match a.reason {
                None if self.failed_lists.contains(&list) => self.stopping = true,
                None => {
                    self.walking = Some(list);
                    self.moved = false;
                    self.stop_sent = false;
                    self.outputs.push(Output::Walking(WALKING_STARTED, list));
                }
                Some(r) => {
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

    fn drop_unlifted(&mut self) {
        for s in self.steps.iter_mut().filter(|s| s.unlifted()) {
            s.state = State::Dropped;
        }
    }

    fn on_append_answer(&mut self, key: usize, reason: Option<Reason>, silent: bool) {
        match reason {
            None => self.steps[key].state = State::Queued,
            Some(r) => {
                let s = &self.steps[key];
                let (list, id, index, number, pose) = (s.list, s.id, s.index, s.number, s.pose);
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
                // The rest of its list is not sent; what is on its way is refused as a gap.
                self.failed_lists.push(list);
                for f in self.inflight.iter_mut() {
                    if let Item::Append(k) = f.item {
                        if self.steps[k].list == list {
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
                }
                self.next_number = number;
            }
        }
    }

    fn on_control_answer(&mut self, op: ControlOp, origin: Origin, reason: Option<Reason>) {
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
                        self.outputs
                            .push(Output::Walking(WALKING_ABORT_REQUESTED, id));
                    }
                    _ => {}
                }
            }
            (ControlOp::Heartbeat, None) => {}
            (_, Some(r)) => {
                let (list, _, _, what) = self.describe(&Item::Control(op, origin));
                self.refusal(list, 0, -1, what, Ok(r), String::new());
            }
            (_, None) => {}
        }
    }

    /// After every frame of the node's cycle: lift-offs and touchdowns, the end of a walk, the
    /// reference.
    pub fn end_cycle(&mut self) {
        if !self.have_stream {
            return;
        }
        let phase = self.stream.phase;
        let was = self.phase;
        self.phase = phase;
        let single = |p: u8| p == 2 || p == 3;
        if single(phase) && !single(was) {
            // Support on the left (2): the right foot swings.
            let swing = if phase == 2 { Side::Right } else { Side::Left };
            self.lift_off(swing);
        }
        if !single(phase) && single(was) {
            let swing = if was == 2 { Side::Right } else { Side::Left };
            self.touch_down(swing);
        }
        if phase != 0 {
            self.moved = true;
        }
        if phase == 0 && self.moved {
            self.moved = false;
            self.stopping = false;
            self.stop_sent = false;
            if let Some(list) = self.walking.take() {
                if !self.paused {
                    self.outputs.push(Output::Walking(WALKING_COMPLETED, list));
                }
            }
        }
        if phase == 0 && self.walking.is_none() {
            self.stopping = false;
        }
        self.publish_reference();
        self.run_deferred();
    }

    fn foot(&self, side: Side) -> Pose {
        let f = self.stream.feet[usize::from(side == Side::Right)];
        self.frame.compose(&Pose {
            x: f[0],
            y: f[1],
            yaw: f[3],
        })
    }

    fn status(&self, k: usize, status: u8, actual: Pose, swing: f64) -> FootstepStatusMessage {
        let s = &self.steps[k];
        FootstepStatusMessage {
            sequence_id: s.id,
            footstep_status: status,
            footstep_index: s.index,
            robot_side: if s.side == Side::Left {
                ROBOT_SIDE_LEFT
            } else {
                ROBOT_SIDE_RIGHT
            },
            desired_foot_position_in_world: Point {
                x: s.pose.x,
                y: s.pose.y,
                z: 0.0,
            },
            desired_foot_orientation_in_world: Quaternion::from_yaw(s.pose.yaw),
            actual_foot_position_in_world: Point {
                x: actual.x,
                y: actual.y,
                z: 0.0,
            },
            actual_foot_orientation_in_world: Quaternion::from_yaw(actual.yaw),
            swing_duration: swing,
        }
    }

    fn lift_off(&mut self, swing: Side) {
        let Some(k) = self.steps.iter().position(|s| s.unlifted()) else {
            return;
        };
        if self.steps[k].side != swing || self.steps[k].state != State::Queued {
            return;
        }
        let from = self.foot(swing);
        self.steps[k].state = State::Swinging;
        self.steps[k].lift = Some((self.cycle, from));
        let out = self.status(k, FOOTSTEP_STATUS_STARTED, from, 0.0);
        self.outputs.push(Output::Footstep(out));
    }

    fn touch_down(&mut self, swing: Side) {
        let Some(k) = self.steps.iter().position(|s| s.state == State::Swinging) else {
            return;
        };
        if self.steps[k].side != swing {
            return;
        }
        let landed = self.foot(swing);
        let swing_s = self.steps[k]
            .lift
            .map(|(c, _)| (self.cycle - c) as f64 * self.cfg.dt)
            .unwrap_or(0.0);
        self.steps[k].state = State::Landed;
        let out = self.status(k, FOOTSTEP_STATUS_COMPLETED, landed, swing_s);
        self.outputs.push(Output::Footstep(out));
    }

    fn publish_reference(&mut self) {
        let st = self.stream;
        let w = |x: f64, y: f64| self.frame.compose(&Pose { x, y, yaw: 0.0 });
        let cog = w(st.cog[0], st.cog[1]);
        let zmp = w(st.zmp[0], st.zmp[1]);
        let mut corners = Vec::with_capacity(8);
        for side in [Side::Left, Side::Right] {
            let on_floor = match st.phase {
                2 => side == Side::Left,
                3 => side == Side::Right,
                _ => true,
            };
            if !on_floor {
                continue;
            }
            let f = self.foot(side);
            let (s, c) = f.yaw.sin_cos();
            let (hl, hw) = (self.cfg.sole[0] / 2.0, self.cfg.sole[1] / 2.0);
            for (dx, dy) in [(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)] {
                corners.push((f.x + c * dx - s * dy, f.y + s * dx + c * dy));
            }
        }
        let support = convex_hull(corners)
            .into_iter()
            .map(|(x, y)| Point32 {
                x: x as f32,
                y: y as f32,
                z: 0.0,
            })
            .collect();
        self.outputs.push(Output::Reference {
            cog: Point {
                x: cog.x,
                y: cog.y,
                z: self.cfg.cog_height,
            },
            zmp: Point {
                x: zmp.x,
                y: zmp.y,
                z: 0.0,
            },
            support,
            tick: st.tick,
        });
    }
}

/// The convex hull of `pts`, counter-clockwise (Andrew's monotone chain).
pub fn convex_hull(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(pts.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_two_soles_is_their_outline() {
        let h = convex_hull(vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.5, 0.5),
        ]);
        assert_eq!(h.len(), 4);
        // Counter-clockwise: positive area.
        let area: f64 = (0..h.len())
            .map(|i| {
                let (a, b) = (h[i], h[(i + 1) % h.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0;
        assert!((area - 1.0).abs() < 1e-12);
    }

    #[test]
    fn nothing_is_sent_before_the_node_is_heard() {
        let mut g = Gateway::new(GatewayConfig::default());
        assert!(g.poll(true).is_empty());
        assert!(!g.is_open());
    }
}
