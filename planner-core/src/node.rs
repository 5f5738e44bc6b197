//! The hardware-free node: one call of [`Node::poll`] is one 5 ms control cycle.
//!
//! Time is passed in (`now_ms`, a free-running millisecond counter that may wrap) and the bus
//! is behind the `embedded-can` non-blocking trait, as smoltcp's `poll(timestamp, device)`:
//! the same code runs in the firmware (FDCAN), in host-sim (a virtual bus) and in tests.
//!
//! Per cycle, with bounded work:
//! 1. receive at most [`NodeConfig::max_rx`] frames; each is validated once
//!    ([`Command::decode`]), checked against the state (sequence, reach, side order, emergency
//!    stop) and applied to the [`Gait`], and answered with an `ACK` frame that carries the
//!    reason code when refused. A refused command changes nothing. Commands that plan — a
//!    `Start` (the start window) and a `STEP_MODIFY` of the next swing target while walking
//!    (eq. 17 plans the re-plan it will cause) — cost up to ~60,000 instructions on the Cortex-M7 against ~200
//!    for the others, so at most [`NodeConfig::max_plans`] of them are taken per cycle: after
//!    the last one the node stops receiving, and the frames behind it wait in the device's
//!    queue for the next cycle (their answer comes 5 ms later). This bounds the worst cycle
//!    whatever arrives;
//! 2. advance the gait by one tick;
//! 3. publish the reference (5 frames) and, every 20 cycles, the status (the node's heartbeat);
//!    frames that cannot be sent now wait in a transmit backlog of [`TX_BACKLOG`] frames; an
//!    unsent reference is replaced by the next one rather than sent late.
//!
//! Safety rules: a controller that falls silent for [`NodeConfig::heartbeat_timeout_ms`] while
//! the robot walks makes the node drop the queue and stop (the steps already started are
//! finished, then the robot settles between its feet); an emergency stop does the same at once
//! and refuses every motion command until a `Reset` once standing.
//!
//! Step ids must count up from 0 (after start-up and after a `Reset`): a gap is refused, so a
//! lost step cannot be skipped over.
//!
//! Repeats are harmless (the controller retransmits what it saw no answer to): the node keeps
//! the last [`HISTORY`] footstep frames it accepted, and a footstep frame identical to one of
//! them is answered `Duplicate` and changes nothing — whatever happened since (the step may
//! have lifted off or been walked). A control command repeating the last sequence number is
//! answered `Duplicate` likewise.
//!
//! Reach limits ([`Reach`]): what the HRP-2 legs (thigh and shank 0.3 m) can follow at the
//! gait's COG height, with a margin, measured on host-sim's multi-body model
//! (`host-sim/tests/reach.rs` walks the corners of these limits and asserts the knee margin).
//! A step is measured in the frame of the previous foot of the other side (`forward` along
//! its heading, `width` across, positive on the stepping foot's own side; a negative width is
//! `Crossing`):
//! * box: forward −0.20 … +0.30 m, width 0.15 … 0.28 m, heading change at most 0.30 rad;
//! * distance between the feet `hypot(forward, width)` at most 0.361 m;
//! * a turn costs reach: `forward + 0.3 m/rad · |Δyaw| ≤ 0.30 m`;
//! * stride: the swinging foot travels at most 0.43 m along that heading (steady walking up
//!   to 0.215 m steps);
//! * growth: a step is at most 0.22 m longer than the one before (from standing: than 0).
//!
//! The last two are why a box alone is not enough: a long step needs the speed built up by the
//! steps before it, and the stop after long steps needs room. A modification is checked with
//! its two successors (their rules involve the modified step).

use heapless::Deque;

use crate::gait::{Footstep, Gait, GaitError, GaitParams, Phase, Reference, Side};
use crate::wire::{Ack, Command, ControlOp, RawFrame, Reason, Status, Stream, WireStep};

/// Frames that can wait to be sent.
pub const TX_BACKLOG: usize = 32;

/// Accepted footstep frames remembered to recognise repeats.
pub const HISTORY: usize = 16;

/// Leg reach limits (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// Largest forward step \[m\].
    pub max_forward: f64,
    /// Largest backward step \[m\].
    pub max_backward: f64,
    /// Smallest distance across the heading between the feet \[m\].
    pub min_width: f64,
    /// Largest distance across the heading between the feet \[m\].
    pub max_width: f64,
    /// Largest heading change \[rad\].
    pub max_yaw: f64,
    /// Largest distance between the feet \[m\].
    pub max_feet_distance: f64,
    /// Forward reach lost per radian of heading change \[m/rad\].
    pub yaw_cost: f64,
    /// Largest travel of the swinging foot along the other foot's heading \[m\].
    pub max_stride: f64,
    /// Largest growth of the forward step over the step before it \[m\].
    pub max_growth: f64,
}

impl Default for Reach {
    fn default() -> Self {
        Self {
            max_forward: 0.30,
            max_backward: 0.20,
            min_width: 0.15,
            max_width: 0.28,
            max_yaw: 0.30,
            max_feet_distance: 0.361,
            yaw_cost: 0.3,
            max_stride: 0.43,
            max_growth: 0.22,
        }
    }
}

/// A foot as a frame: its pose with the sine and cosine of its yaw (computed once per foot:
/// the reach check runs on the Cortex-M for every footstep frame).
#[derive(Clone, Copy, Debug)]
struct Frame {
    x: f64,
    y: f64,
    yaw: f64,
    sin: f64,
    cos: f64,
}

impl Frame {
    fn of(f: &Footstep<f64>) -> Self {
        Self {
            x: f.x,
            y: f.y,
            yaw: f.yaw,
            sin: libm::sin(f.yaw),
            cos: libm::cos(f.yaw),
        }
    }

    /// `to` in this frame: forward and width (positive on `to_side`'s own side).
    fn forward_width(&self, to: &Frame, to_side: Side) -> (f64, f64) {
        let (dx, dy) = (to.x - self.x, to.y - self.y);
        let forward = self.cos * dx + self.sin * dy;
        let width = -self.sin * dx + self.cos * dy;
        match to_side {
            Side::Left => (forward, width),
            Side::Right => (forward, -width),
        }
    }
}

impl Reach {
    /// Whether the legs can take `step`, where `other` is the previous foot of the other side
    /// (the support foot of this step) and `same` the previous foot of the same side (where
    /// the swinging foot lifts off). `Crossing` or `Reach` if not.
    pub fn check(
        &self,
        other: &Footstep<f64>,
        same: &Footstep<f64>,
        step: &Footstep<f64>,
    ) -> Result<(), Reason> {
        self.check_frames(
            &Frame::of(other),
            &Frame::of(same),
            &Frame::of(step),
            step.side,
        )
    }

    fn check_frames(
        &self,
        other: &Frame,
        same: &Frame,
        step: &Frame,
        side: Side,
    ) -> Result<(), Reason> {
        const EPS: f64 = 1e-9; // values on the limits pass
        let (forward, width) = other.forward_width(step, side);
        if width < 0.0 {
            return Err(Reason::Crossing);
        }
        // Heading change wrapped into [−π, π].
        let d = step.yaw - other.yaw;
        let dyaw = libm::fabs(d - core::f64::consts::TAU * libm::round(d / core::f64::consts::TAU));
        // The step before this one (`other` from `same`), and where the swinging foot was.
        let before = same.forward_width(other, side.other()).0;
        let lift = other.forward_width(same, side).0;
        let ok = forward <= self.max_forward + EPS
            && forward >= -self.max_backward - EPS
            && width >= self.min_width - EPS
            && width <= self.max_width + EPS
            && dyaw <= self.max_yaw + EPS
            && libm::hypot(forward, width) <= self.max_feet_distance + EPS
            && forward + self.yaw_cost * dyaw <= self.max_forward + EPS
            && libm::fabs(forward - lift) <= self.max_stride + EPS
            && forward - before <= self.max_growth + EPS;
        if ok {
            Ok(())
        } else {
            Err(Reason::Reach)
        }
    }
}

/// Node configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeConfig {
    /// Gait parameters.
    pub params: GaitParams<f64>,
    /// Where the left foot stands at start-up.
    pub left: Footstep<f64>,
    /// Where the right foot stands at start-up.
    pub right: Footstep<f64>,
    /// Silence of the controller after which a walking robot stops \[ms\].
    pub heartbeat_timeout_ms: u32,
    /// Frames handled per cycle at most (the rest wait in the controller's mailbox).
    pub max_rx: usize,
    /// Planning commands (`Start`, `STEP_MODIFY` of the next swing target while walking)
    /// handled per cycle at most (see the module docs).
    pub max_plans: usize,
    /// Reach limits.
    pub reach: Reach,
}

impl NodeConfig {
    /// HRP-2 defaults: feet 0.2 m apart at the origin, 500 ms heartbeat timeout, 16 frames per
    /// cycle.
    pub fn hrp2() -> Self {
        Self {
            params: GaitParams::hrp2(),
            left: Footstep::new(Side::Left, 0.0, 0.1, 0.0),
            right: Footstep::new(Side::Right, 0.0, -0.1, 0.0),
            heartbeat_timeout_ms: 500,
            max_rx: 16,
            max_plans: 1,
            reach: Reach::default(),
        }
    }
}

/// What one cycle did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PollReport {
    /// The reference of this cycle.
    pub reference: Reference<f64>,
    /// Frames received.
    pub received: u8,
    /// Commands refused.
    pub refused: u8,
    /// Frames handed to the bus.
    pub sent: u8,
}

/// Counters kept by the node (all saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Commands refused, total.
    pub refused: u16,
    /// Refusals per reason code (index = code; 0 unused).
    pub by_reason: [u16; 17],
    /// Frames dropped because the transmit backlog was full.
    pub tx_dropped: u16,
    /// Cycles reported late by the firmware.
    pub overruns: u16,
    /// Bus errors on receive or transmit.
    pub bus_errors: u16,
}

/// The node.
#[derive(Clone, Debug)]
pub struct Node<const Q: usize> {
    cfg: NodeConfig,
    gait: Gait<f64, Q>,
    tx: Deque<RawFrame, TX_BACKLOG>,
    /// Accepted footstep frames, oldest first.
    history: Deque<RawFrame, HISTORY>,
    last_append: Option<u8>,
    last_control: Option<u8>,
    last_estop: Option<u8>,
    estopped: bool,
    lost: bool,
    last_heard: Option<u32>,
    counters: Counters,
    cycle: u32,
    replan_failed: bool,
}

fn reason_of(e: GaitError) -> Reason {
    match e {
        GaitError::QueueFull => Reason::QueueFull,
        GaitError::NonFinite => Reason::OutOfRange,
        GaitError::SideOrder => Reason::SideOrder,
        GaitError::UnknownStep => Reason::UnknownStep,
        GaitError::LiftedOff => Reason::LiftedOff,
        GaitError::Infeasible => Reason::Infeasible,
        GaitError::WrongState => Reason::WrongState,
        _ => Reason::PlanFailed,
    }
}

impl<const Q: usize> Node<Q> {
    /// A node standing still (computes the preview gains).
    pub fn new(cfg: NodeConfig) -> Result<Self, GaitError> {
        Ok(Self {
            gait: Gait::new(cfg.params, cfg.left, cfg.right)?,
            cfg,
            tx: Deque::new(),
            history: Deque::new(),
            last_append: None,
            last_control: None,
            last_estop: None,
            estopped: false,
            lost: false,
            last_heard: None,
            counters: Counters::default(),
            cycle: 0,
            replan_failed: false,
        })
    }

    /// The gait.
    pub fn gait(&self) -> &Gait<f64, Q> {
        &self.gait
    }

    /// The counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// Cycles run.
    pub fn cycles(&self) -> u32 {
        self.cycle
    }

    /// Tells the node that the last cycle overran its time budget (counted and published).
    pub fn note_overrun(&mut self) {
        self.counters.overruns = self.counters.overruns.saturating_add(1);
    }

    /// The status as published.
    pub fn status(&self) -> Status {
        let state = if self.estopped {
            2
        } else if self.lost {
            3
        } else if self.gait.is_standing() {
            0
        } else {
            1
        };
        let adjust = self
            .gait
            .last_replan()
            .map(|i| i.adjust_ticks.clamp(-128, 127) as i8)
            .unwrap_or(0);
        let mut flags = 0;
        if self.gait.params().shaping {
            flags |= 1;
        }
        if self.replan_failed {
            flags |= 2;
        }
        if self.counters.tx_dropped > 0 {
            flags |= 4;
        }
        Status {
            state,
            queue: self.gait.queued().min(255) as u8,
            rejected: self.counters.refused,
            overruns: self.counters.overruns,
            last_adjust: adjust,
            flags,
        }
    }

    fn refuse(&mut self, reason: Reason) {
        self.counters.refused = self.counters.refused.saturating_add(1);
        if let Some(n) = self.counters.by_reason.get_mut(usize::from(reason.code())) {
            *n = n.saturating_add(1);
        }
    }

    /// Reach and crossing check of a footstep: appended (`before` = `None`), or replacing the
    /// queued step `before`, with its two successors then checked against it.
    fn check_reach(&self, step: &Footstep<f64>, before: Option<u16>) -> Result<(), Reason> {
        let r = &self.cfg.reach;
        let other = Frame::of(&self.gait.previous_other(step.side, before));
        let same = Frame::of(&self.gait.previous_other(step.side.other(), before));
        let f = Frame::of(step);
        r.check_frames(&other, &same, &f, step.side)?;
        if let Some(id) = before {
            let next = |k: u16| self.gait.queued_step(id.wrapping_add(k) & 0xFF);
            if let Some(s1) = next(1) {
                let f1 = Frame::of(&s1);
                r.check_frames(&f, &other, &f1, s1.side)?;
                if let Some(s2) = next(2) {
                    r.check_frames(&f1, &f, &Frame::of(&s2), s2.side)?;
                }
            }
        }
        Ok(())
    }

    fn footstep(s: &WireStep) -> Footstep<f64> {
        let (x, y, yaw) = s.si();
        let side = if s.left { Side::Left } else { Side::Right };
        Footstep::new(side, x, y, yaw)
    }

    /// Handles one frame from the bus (validation, state checks, application) and returns the
    /// answer to send.
    pub fn handle(&mut self, frame: &RawFrame, now_ms: u32) -> Ack {
        self.handle_planned(frame, now_ms).0
    }

    /// [`Node::handle`], and whether the command ran the planner.
    fn handle_planned(&mut self, frame: &RawFrame, now_ms: u32) -> (Ack, bool) {
        // Known before handling: a `Start`, or a modification of the next swing target while
        // walking (the only one that plans, see `Gait::modify`).
        let decoded = Command::decode(frame);
        let may_plan = match decoded {
            Ok(Command::Control {
                op: ControlOp::Start,
                ..
            }) => true,
            Ok(Command::Modify(s)) => {
                !self.gait.is_standing() && self.gait.next_target() == Some(u16::from(s.id))
            }
            _ => false,
        };
        let ack = self.handle_frame(frame, decoded, now_ms);
        // It did plan if the gait was reached: accepted, or refused by the planner itself.
        let planned = may_plan
            && matches!(
                ack.reason,
                None | Some(Reason::Infeasible | Reason::PlanFailed)
            );
        (ack, planned)
    }

    fn handle_frame(
        &mut self,
        frame: &RawFrame,
        decoded: Result<Command, (Reason, u8)>,
        now_ms: u32,
    ) -> Ack {
        let queue = |n: &Self| n.gait.queued().min(255) as u8;
        let echo = crate::wire::echo_of(frame);
        let cmd = match decoded {
            Ok(c) => c,
            Err((reason, seq)) => {
                self.refuse(reason);
                return Ack {
                    command: (frame.id & 0xFF) as u8,
                    seq,
                    reason: Some(reason),
                    queue: queue(self),
                    echo,
                };
            }
        };
        // Anything valid from the controller proves it is alive.
        self.last_heard = Some(now_ms);
        let (seq, result) = match cmd {
            Command::EmergencyStop { seq } => {
                let r = if self.last_estop == Some(seq) && self.estopped {
                    Err(Reason::Duplicate)
                } else {
                    self.last_estop = Some(seq);
                    self.estopped = true;
                    self.gait.clear_and_stop();
                    Ok(())
                };
                (seq, r)
            }
            Command::Control { seq, op } => {
                let r = if op != ControlOp::Heartbeat && self.last_control == Some(seq) {
                    Err(Reason::Duplicate)
                } else {
                    if op != ControlOp::Heartbeat {
                        self.last_control = Some(seq);
                    }
                    self.control(op)
                };
                (seq, r)
            }
            Command::Append(s) | Command::Modify(s) => {
                let r = if self.history.iter().any(|h| h == frame) {
                    Err(Reason::Duplicate)
                } else if let Command::Append(s) = cmd {
                    self.append(&s)
                } else {
                    self.modify(&s)
                };
                if r.is_ok() {
                    if self.history.is_full() {
                        self.history.pop_front();
                    }
                    let _ = self.history.push_back(*frame);
                }
                (s.id, r)
            }
        };
        if let Err(reason) = result {
            self.refuse(reason);
        }
        Ack {
            command: cmd.code(),
            seq,
            reason: result.err(),
            queue: queue(self),
            echo,
        }
    }

    fn control(&mut self, op: ControlOp) -> Result<(), Reason> {
        match op {
            ControlOp::Heartbeat => Ok(()),
            ControlOp::Start => {
                if self.estopped {
                    return Err(Reason::EmergencyStopped);
                }
                self.lost = false;
                self.gait.start().map_err(reason_of)
            }
            ControlOp::Stop => {
                self.gait.stop();
                Ok(())
            }
            ControlOp::StopNow => {
                self.gait.clear_and_stop();
                Ok(())
            }
            ControlOp::Reset => {
                if !self.gait.is_standing() {
                    return Err(Reason::WrongState);
                }
                self.estopped = false;
                self.lost = false;
                // The controller starts a new sequence of step ids from 0.
                self.last_append = None;
                self.history.clear();
                Ok(())
            }
        }
    }

    fn append(&mut self, s: &WireStep) -> Result<(), Reason> {
        if self.estopped {
            return Err(Reason::EmergencyStopped);
        }
        // Step ids count from 0 after start-up and after a reset: a lost first step must not
        // let the second one become the first (a stride from standing twice as long).
        // (An exact repeat of an accepted append was answered `Duplicate` before this.)
        let expected = self.last_append.map_or(0, |l| l.wrapping_add(1));
        if s.id != expected {
            return Err(Reason::SequenceGap);
        }
        let step = Self::footstep(s);
        if self.gait.next_side().is_some_and(|side| side != step.side) {
            return Err(Reason::SideOrder); // (before the reach check: the clearer reason)
        }
        self.check_reach(&step, None)?;
        self.gait
            .push(u16::from(s.id), step)
            .map_err(|(e, _)| reason_of(e))?;
        self.last_append = Some(s.id);
        Ok(())
    }

    fn modify(&mut self, s: &WireStep) -> Result<(), Reason> {
        if self.estopped {
            return Err(Reason::EmergencyStopped);
        }
        if self.gait.is_standing() && self.gait.queued() == 0 {
            return Err(Reason::WrongState);
        }
        let id = u16::from(s.id);
        if self.gait.swinging() == Some(id) {
            return Err(Reason::LiftedOff);
        }
        if !self.gait.is_queued(id) {
            return Err(Reason::UnknownStep);
        }
        let step = Self::footstep(s);
        if self
            .gait
            .queued_step(id)
            .is_some_and(|q| q.side != step.side)
        {
            return Err(Reason::SideOrder);
        }
        self.check_reach(&step, Some(id))?;
        self.gait.modify(id, step).map_err(reason_of)
    }

    fn stream(&self, r: &Reference<f64>) -> Stream {
        let phase = match r.phase {
            Phase::Standing => 0,
            Phase::Double => 1,
            Phase::Single(Side::Left) => 2,
            Phase::Single(Side::Right) => 3,
        };
        let f = |k: usize| [r.feet[k].x, r.feet[k].y, r.feet[k].z, r.feet[k].yaw];
        Stream {
            cog: [r.x.cog, r.y.cog],
            cog_vel: [r.x.cog_vel, r.y.cog_vel],
            zmp: [r.x.zmp, r.y.zmp],
            phase,
            tick: (self.cycle & 0xFF) as u8,
            feet: [f(0), f(1)],
        }
    }

    fn enqueue(&mut self, f: RawFrame) {
        if self.tx.push_back(f).is_err() {
            self.counters.tx_dropped = self.counters.tx_dropped.saturating_add(1);
        }
    }

    /// One control cycle (see the module docs).
    pub fn poll<C>(&mut self, now_ms: u32, can: &mut C) -> PollReport
    where
        C: embedded_can::nb::Can,
    {
        self.cycle = self.cycle.wrapping_add(1);
        let (mut received, mut refused, mut plans) = (0u8, 0u8, 0usize);
        for _ in 0..self.cfg.max_rx {
            if plans >= self.cfg.max_plans {
                break; // the rest waits for the next cycle
            }
            match can.receive() {
                Ok(f) => {
                    received = received.saturating_add(1);
                    let Some(raw) = RawFrame::from_frame(&f) else {
                        continue; // extended or remote frames are not ours
                    };
                    let (ack, planned) = self.handle_planned(&raw, now_ms);
                    if ack.reason.is_some() {
                        refused = refused.saturating_add(1);
                    }
                    plans += usize::from(planned);
                    self.enqueue(ack.encode());
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    self.counters.bus_errors = self.counters.bus_errors.saturating_add(1);
                    break;
                }
            }
        }
        // The controller's silence while walking: stop safely.
        if let Some(heard) = self.last_heard {
            let silent = now_ms.wrapping_sub(heard);
            if silent > self.cfg.heartbeat_timeout_ms && !self.gait.is_standing() && !self.lost {
                self.lost = true;
                self.gait.clear_and_stop();
            }
        }
        let reference = self.gait.tick();
        // A stale reference in the backlog is dropped: the new one supersedes it. (One pass
        // of pop and push rather than `Deque::retain`, whose heapless implementation keeps
        // panicking branches the optimiser cannot remove: see firmware/nopanic.)
        for _ in 0..self.tx.len() {
            if let Some(f) = self.tx.pop_front() {
                if f.id < crate::wire::ids::COG || f.id == crate::wire::ids::STATUS {
                    let _ = self.tx.push_back(f);
                }
            }
        }
        for f in self.stream(&reference).encode() {
            self.enqueue(f);
        }
        if self.cycle % 20 == 0 {
            let s = self.status().encode();
            self.enqueue(s);
        }
        let mut sent = 0u8;
        while let Some(raw) = self.tx.pop_front() {
            let Some(frame) = raw.to_frame::<C::Frame>() else {
                continue;
            };
            match can.transmit(&frame) {
                Ok(displaced) => {
                    sent = sent.saturating_add(1);
                    if let Some(d) = displaced.as_ref().and_then(RawFrame::from_frame) {
                        let _ = self.tx.push_front(d);
                        break;
                    }
                }
                Err(nb::Error::WouldBlock) => {
                    let _ = self.tx.push_front(raw);
                    break;
                }
                Err(nb::Error::Other(_)) => {
                    self.counters.bus_errors = self.counters.bus_errors.saturating_add(1);
                    let _ = self.tx.push_front(raw);
                    break;
                }
            }
        }
        PollReport {
            reference,
            received,
            refused,
            sent,
        }
    }
}
