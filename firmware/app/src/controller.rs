//! The controller's side of the bus: the scenario's timeline as CAN frames, and the node's
//! answers.
//!
//! [`Controller`] does what the controller of `host_sim::sim::simulate` does, frame for frame:
//! at tick `k` it sends the commands due at `k` (in timeline order), footsteps through a
//! [`StepBook`] (`id as u8`; modifications as versioned offsets), `Start`/`Stop`/`StopNow` as
//! `CONTROL` frames with a sequence number counted from 1, then a heartbeat (`CONTROL`,
//! sequence `k / HEARTBEAT_TICKS`, a new one each time) every [`HEARTBEAT_TICKS`] ticks; every frame through [`wire::Command::encode`](Wire::encode).
//! On host-sim's bus the frames of one tick arrive by arbitration, lowest identifier first,
//! in sending order among equal identifiers, all within the 2.5 ms before the node polls
//! (at most 14 frames of ≤ 135 µs at 1 Mbit/s); [`Controller::send_due`] hands them to the
//! device in that order. Frames the node has not taken yet (it takes at most one planning
//! command per cycle) stay in the device's FIFO ahead of them, as in the virtual port's.
//!
//! After the cycle the controller reads what the node transmitted: an `ACK` answers the first
//! unanswered command with the same code and sequence number (step id), as `simulate` pairs
//! them; the other `ACK`s answer heartbeats.

use heapless::Vec;
use planner_core::gait::Side;
use planner_core::wire::{Ack, Command as Wire, ControlOp, RawFrame, Reason, StepBook};

use crate::bus::ScriptedBus;
use crate::script::{Command, Scenario, MAX_COMMANDS};

/// The controller sends a heartbeat every this many ticks (host-sim's
/// `SimConfig::heartbeat_ticks` default).
pub const HEARTBEAT_TICKS: u64 = 20;

/// The node's answer to a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Answer {
    /// Tick of the cycle that answered.
    pub tick: u64,
    /// `None`: accepted.
    pub reason: Option<Reason>,
}

/// A command the controller sent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sent {
    /// Tick at which it was sent.
    pub tick: u64,
    /// The scenario's command.
    pub command: Command,
    /// Its frame.
    pub frame: RawFrame,
    /// The node's answer, once read.
    pub answer: Option<Answer>,
}

impl Sent {
    fn key(&self) -> (u8, u8) {
        // Code = low byte of the identifier; key = sequence number or step id (first byte).
        ((self.frame.id & 0xFF) as u8, self.frame.data[0])
    }
}

/// A footstep of the scenario that the message set cannot carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unrepresentable(pub u16);

/// The scripted controller (see the module docs).
#[derive(Clone, Debug)]
pub struct Controller<'s> {
    scenario: &'s Scenario,
    next: usize,
    seq: u8,
    /// Appended positions and versions of the steps (modifications are offsets from them).
    book: StepBook,
    sent: Vec<Sent, MAX_COMMANDS>,
    heartbeats: u32,
    heartbeat_acks: u32,
    refused_heartbeats: u32,
}

impl<'s> Controller<'s> {
    /// Nothing sent yet.
    pub fn new(scenario: &'s Scenario) -> Self {
        Self {
            scenario,
            next: 0,
            seq: 0,
            book: StepBook::new(),
            sent: Vec::new(),
            heartbeats: 0,
            heartbeat_acks: 0,
            refused_heartbeats: 0,
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> &'s Scenario {
        self.scenario
    }

    /// Tick of the last command of the timeline (0 if none).
    pub fn last_command(&self) -> u64 {
        self.scenario.timeline.last().map(|(t, _)| *t).unwrap_or(0)
    }

    /// `true` once every command of the timeline was sent.
    pub fn all_sent(&self) -> bool {
        self.next >= self.scenario.timeline.len()
    }

    /// The commands sent so far, in sending order, with their answers.
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Heartbeats sent, answered, and refused.
    pub fn heartbeats(&self) -> (u32, u32, u32) {
        (
            self.heartbeats,
            self.heartbeat_acks,
            self.refused_heartbeats,
        )
    }

    /// Sends what is due at tick `k` (see the module docs); the frames arrive in `bus` in
    /// arbitration order.
    pub fn send_due(&mut self, k: u64, bus: &mut ScriptedBus) -> Result<(), Unrepresentable> {
        let timeline = &self.scenario.timeline;
        let mut frames: Vec<RawFrame, { MAX_COMMANDS + 1 }> = Vec::new();
        while self.next < timeline.len() && timeline[self.next].0 <= k {
            let (_, command) = timeline[self.next];
            let wire = match command {
                Command::Push(id, f) => {
                    let left = f.side == Side::Left;
                    self.book
                        .append(id as u8, left, f.x, f.y, f.yaw)
                        .ok_or(Unrepresentable(id))?
                }
                Command::Modify(id, f) => self
                    .book
                    .modify(id as u8, f.x, f.y, f.yaw)
                    .ok_or(Unrepresentable(id))?,
                Command::Start => self.control(ControlOp::Start),
                Command::Stop => self.control(ControlOp::Stop),
                Command::StopNow => self.control(ControlOp::StopNow),
            };
            let frame = wire.encode();
            // Capacities: the timeline has at most MAX_COMMANDS commands.
            let _ = frames.push(frame);
            let _ = self.sent.push(Sent {
                tick: k,
                command,
                frame,
                answer: None,
            });
            self.next += 1;
        }
        if k % HEARTBEAT_TICKS == 0 {
            let hb = Wire::Control {
                // A new sequence number for every heartbeat, as host-sim's controller.
                seq: (k / HEARTBEAT_TICKS) as u8,
                op: ControlOp::Heartbeat,
            };
            let _ = frames.push(hb.encode());
            self.heartbeats += 1;
        }
        // Arbitration: lowest identifier first, sending order among equal ones (a stable
        // insertion sort of at most MAX_COMMANDS + 1 frames).
        for i in 1..frames.len() {
            let mut j = i;
            while j > 0 && frames[j - 1].id > frames[j].id {
                frames.swap(j - 1, j);
                j -= 1;
            }
        }
        for f in frames {
            bus.deliver(f);
        }
        Ok(())
    }

    fn control(&mut self, op: ControlOp) -> Wire {
        self.seq = self.seq.wrapping_add(1);
        Wire::Control { seq: self.seq, op }
    }

    /// Reads one frame the node sent in the cycle of tick `k`: an `ACK` is paired with its
    /// command (returns the command's index in [`Controller::sent`]) or counted as a
    /// heartbeat's answer; the other frames (the stream, the status) are not looked at here.
    pub fn read(&mut self, k: u64, f: &RawFrame) -> Option<usize> {
        let ack = Ack::decode(f)?;
        let found = self
            .sent
            .iter()
            .position(|s| s.answer.is_none() && s.tick <= k && s.key() == (ack.command, ack.seq));
        match found {
            Some(i) => {
                self.sent[i].answer = Some(Answer {
                    tick: k,
                    reason: ack.reason,
                });
                Some(i)
            }
            None => {
                self.heartbeat_acks += 1;
                if ack.reason.is_some() {
                    self.refused_heartbeats += 1;
                }
                None
            }
        }
    }
}
