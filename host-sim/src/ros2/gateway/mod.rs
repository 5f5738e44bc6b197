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
//!
//! **Velocity and goal.** A `Twist` (`cmd_vel`) or a relative goal is sent as the node's
//! `VELOCITY` (streamed) or `GOAL`, and the node chooses the footsteps: see `drive.rs`.
//!
//! Files: `mod.rs` (this file): the state and the footstep lists; `control.rs`: pause, resume
//! and abort; `drive.rs`: velocity and goal; `answers.rs`: what is sent and what the node answers; `stream.rs`: lift-off,
//! touchdown and the reference, from the stream.

mod answers;
mod control;
mod drive;
mod stream;

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
    /// The reference of one cycle in the world frame, as the stream carries it (COG, its
    /// velocity, ZMP, phase, feet; no accelerations), the support polygon (counter-clockwise,
    /// z 0), and the cycle.
    Reference {
        /// The reference (the COG at the robot's COG height when published).
        reference: planner_core::gait::Reference<f64>,
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
    /// The pose in force (world): as appended, or as the node's last accepted modification.
    pose: Pose,
    /// The pose last asked for (a modification on its way included): what a list is
    /// compared with.
    requested: Pose,
    /// The gateway's own number of the list that appended it (the peer's list ids may repeat).
    batch: u32,
    /// Its walk has ended: its id names no step any more.
    closed: bool,
    /// The cycle its last modification was sent in.
    last_modify: u64,
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
    Abort(u32),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Item {
    Append(usize),
    Modify(usize, Draft, u32),
    Control(ControlOp, Origin),
    /// Start the walk once no append of the batch (the gateway's list number) is on its way.
    Start(u32, bool),
}

/// The fewest cycles between two modifications of one step: a peer that streams its plan
/// spends the step's 127 versions over at least 127 · 4 cycles (2.5 s), and only the newest
/// pose waits.
pub const MODIFY_CYCLES: u64 = 4;

#[derive(Clone, Copy, Debug)]
struct InFlight {
    code: u8,
    key: u8,
    echo: u8,
    item: Item,
    cycle: u64,
    /// Expected to be refused (an append after a refused one): not reported.
    silent: bool,
    /// An append of another list behind a refused one: refused as a gap, and sent again.
    resend: bool,
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
    resume: bool,
    measured: Option<[Pose; 2]>,
    batch: u32,
    failed_batches: Vec<u32>,
    adjusting: bool,
    resend: Vec<usize>,
    /// After another controller took the session: open one only when a list asks for it.
    claim_on_demand: bool,
    /// The soles in the world frame and in the node's frame at the last cycle (a `Reset`
    /// moves the node's frame while the feet stand: the frame is found again from them).
    last_feet: Option<([Pose; 2], [Pose; 2])>,
    outputs: Vec<Output>,
    /// The velocity stream and the goal (see `drive`).
    drive: drive::DriveLink,
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
            resume: false,
            measured: None,
            batch: 0,
            failed_batches: Vec::new(),
            adjusting: false,
            resend: Vec::new(),
            claim_on_demand: false,
            last_feet: None,
            outputs: Vec::new(),
            drive: drive::DriveLink::default(),
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

    /// The soles where the robot has them (left, right; world frame), when the link has a robot
    /// (MuJoCo): a landing is reported where the robot's sole is at touchdown. `None`: where
    /// the node's reference puts it.
    pub fn set_measured_soles(&mut self, soles: Option<[(f64, f64, f64); 2]>) {
        self.measured = soles.map(|s| s.map(|(x, y, yaw)| Pose { x, y, yaw }));
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

    /// Puts step `key` in `state` and publishes the refusal of `command` for it.
    fn refuse_step(
        &mut self,
        key: usize,
        state: State,
        command: &str,
        reason: Result<Reason, &str>,
        detail: String,
    ) {
        let s = &self.steps[key];
        let (list, id, index) = (s.list, s.id, s.index);
        self.steps[key].state = state;
        self.refusal(list, id, index, command, reason, detail);
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
        if self.node_state == 2 && !self.claim_on_demand {
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
            && !self.stop_sent
            && !self.resetting
            && !self
                .inflight
                .iter()
                .any(|f| matches!(f.item, Item::Append(_)))
    }

    fn run_deferred(&mut self) {
        if self.resume && self.ready() && self.phase == 0 {
            self.resume_now();
        }
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
            if s.closed {
                continue;
            }
            let known = match s.state {
                State::Swinging | State::Landed => Known::Lifted,
                State::Pending | State::Sent | State::Queued | State::Held => Known::Unlifted,
                _ => continue,
            };
            let k = KnownStep {
                key,
                id: s.id,
                side: s.side,
                pose: s.requested,
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
        // Paused, the held steps are the plan and the robot stands (or will): a list is
        // matched with them, and its steps are held too until the resume.
        let standing = (self.walking.is_none() && self.phase == 0) || self.paused;
        let mode = msg.queueing_properties.execution_mode;
        let planned = match plan::plan(&drafts, mode, &self.known(), standing) {
            Ok(p) => p,
            Err(e) => return self.refuse_list(&msg, e),
        };
        let list = msg.sequence_id;
        self.batch += 1;
        let batch = self.batch;
        if planned.drop_queue {
            // The node's queue is dropped only if it holds some of them (a StopNow while
            // standing with nothing queued is refused); steps not yet sent just stay unsent.
            let in_node = self
                .steps
                .iter()
                .any(|s| matches!(s.state, State::Sent | State::Queued));
            for s in self
                .steps
                .iter_mut()
                .filter(|s| s.unlifted() || s.state == State::Held)
            {
                s.state = State::Dropped;
            }
            // Nothing of the plan it replaces is sent any more, its start included.
            self.outbox
                .retain(|i| !matches!(i, Item::Append(_) | Item::Modify(..) | Item::Start(..)));
            if in_node {
                self.outbox
                    .push_back(Item::Control(ControlOp::StopNow, Origin::List(list)));
            }
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
            let s = &mut self.steps[key];
            s.requested = d.pose;
            if matches!(s.state, State::Pending | State::Held) {
                // Not yet sent: the append carries the new pose.
                (s.pose, s.list, s.index) = (d.pose, list, d.index);
            } else {
                // Only the newest pose of a step waits to be sent.
                self.outbox
                    .retain(|i| !matches!(i, Item::Modify(k, ..) if *k == key));
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
                requested: d.pose,
                batch,
                closed: false,
                last_modify: 0,
                number: None,
                state: if self.paused {
                    State::Held
                } else {
                    State::Pending
                },
                lift: None,
            });
            if !self.paused {
                self.outbox.push_back(Item::Append(self.steps.len() - 1));
            }
        }
        if new && self.walking.is_none() && !self.paused {
            self.adjusting = msg.are_footsteps_adjustable;
            self.outbox
                .push_back(Item::Start(batch, msg.are_footsteps_adjustable));
        }
        self.outputs.push(Output::Log(format!(
            "list {list}: {} footsteps (mode {mode}{})",
            drafts.len(),
            if self.paused {
                ", held by the pause"
            } else {
                ""
            }
        )));
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
        let wanted = !self.claim_on_demand || !self.deferred.is_empty() || self.drive_wanted();
        if self.link == Link::WaitSession && self.have_session() && wanted {
            self.claim_on_demand = false;
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
        // Steps refused as a gap behind another list's refused step go first, in order.
        let mut resend = std::mem::take(&mut self.resend);
        resend.sort_unstable();
        for key in resend.into_iter().rev() {
            self.outbox.push_front(Item::Append(key));
        }
        // The node carries out a StopNow before every other command of its cycle: sent first,
        // it takes the lowest sequence number, so the commands after it are not stale.
        if let Some(i) = self
            .outbox
            .iter()
            .position(|i| matches!(i, Item::Control(ControlOp::StopNow, _)))
        {
            if let Some(item) = self.outbox.remove(i) {
                self.outbox.push_front(item);
            }
        }
        let mut later = Vec::new();
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
                Encoded::Later => {
                    self.outbox.pop_front();
                    later.push(item);
                }
                Encoded::Wait => break,
            }
        }
        for item in later.into_iter().rev() {
            self.outbox.push_front(item);
        }
        // The heartbeat last: its sequence number is above every command of the cycle.
        // None while a Reset is on its way: it opens a session the heartbeat does not carry.
        let resetting = self
            .inflight
            .iter()
            .any(|f| matches!(f.item, Item::Control(ControlOp::Reset, _)));
        // A velocity or a goal (none while a Reset is on its way), then no heartbeat.
        let drove = !resetting && self.drive_frames(&mut frames);
        if self.link == Link::Open
            && !drove
            && peer_alive
            && !resetting
            && self.cycle % self.cfg.heartbeat_cycles == 0
        {
            let hb = self.control(ControlOp::Heartbeat);
            self.track(&hb, Item::Control(ControlOp::Heartbeat, Origin::Gateway));
            frames.push(hb.encode());
        }
        frames
    }

    fn have_session(&self) -> bool {
        self.session_seen
    }
}

/// What an outbox item became.
enum Encoded {
    /// Send this.
    Frame(Command),
    /// Nothing to send: drop the item.
    Skip,
    /// Not this cycle; the items behind it may go.
    Later,
    /// Not this cycle, nor anything behind it.
    Wait,
}
