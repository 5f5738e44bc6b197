//! What one control cycle did: its [`CycleRecord`], classified by [`Kind`] from the frames
//! the node took ([`Pending`]) and what its tick did; the [`Fnv`] digests of the replay. The
//! cycle itself is the board's (board-core's `control::ControlLoop`, which times the poll).

use core::borrow::Borrow;

use planner_core::gait::{Reference, ReplanInfo, PREVIEW};
use planner_core::node::{Node, NodeState, PollReport};
use planner_core::shaping::PreviewGains;
use planner_core::wire::{Command, ControlOp, Expect, RawFrame};
use planner_core::Real;

use crate::bus::Device;
use crate::stats::Kind;

/// What one control cycle did (`T`: the node's scalar).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleRecord<T = f64> {
    /// The gait's tick count after the cycle (the index of `report.reference` in the run's
    /// trajectory); the cycle ran at tick `tick - 1`.
    pub tick: u64,
    /// The kind of the cycle.
    pub kind: Kind,
    /// Timer units spent in `Node::poll`.
    pub units: u32,
    /// The node's report (its reference, frames received, refused and sent).
    pub report: PollReport<T>,
    /// The re-plan done by this cycle's tick, if any.
    pub replan: Option<ReplanInfo<T>>,
}

/// FNV-1a 64.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Adds bytes.
    pub fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// Adds the bits of (cog, cog_vel, cog_acc, zmp, zmp_vel) of x, then of y (as `f64`:
    /// an `f32` reference widened, exactly).
    pub fn add_reference<T: Real>(&mut self, r: &Reference<T>) {
        for s in [&r.x, &r.y] {
            for v in [s.cog, s.cog_vel, s.cog_acc, s.zmp, s.zmp_vel] {
                self.add(&v.f64().to_bits().to_le_bytes());
            }
        }
    }

    /// Adds a frame: its identifier (2 bytes, little endian) and its data bytes.
    pub fn add_frame(&mut self, f: &RawFrame) {
        self.add(&f.id.to_le_bytes());
        self.add(f.bytes());
    }

    /// Adds a frame the node sent with the cycle that sent it: the cycle (8 bytes, little
    /// endian), then [`Fnv::add_frame`].
    pub fn add_sent(&mut self, cycle: u64, f: &RawFrame) {
        self.add(&cycle.to_le_bytes());
        self.add_frame(f);
    }
}

/// Classes of received frames, for [`Kind`].
const RX_PUSH: u8 = 1;
const RX_MODIFY: u8 = 2;
const RX_START: u8 = 4;
const RX_STOP: u8 = 8;
const RX_HEARTBEAT: u8 = 16;
/// A reset, an invalid frame, or a frame of another node.
const RX_OTHER: u8 = 32;
/// The estimator's measured state (`MEASURED`: up to one every cycle, part of a steady one).
const RX_MEASURED: u8 = 64;
/// A drive command (`VELOCITY`, `GOAL`).
const RX_DRIVE: u8 = 128;

fn class(f: &RawFrame, expect: Expect) -> u8 {
    match Command::decode(f, expect) {
        Ok(Command::Measured(_)) => RX_MEASURED,
        Ok(Command::Velocity(_) | Command::Goal(_)) => RX_DRIVE,
        Ok(Command::Append(_)) => RX_PUSH,
        Ok(Command::Modify(_)) => RX_MODIFY,
        Ok(Command::Control {
            op: ControlOp::Start | ControlOp::StartAdjusting,
            ..
        }) => RX_START,
        Ok(Command::Control {
            op: ControlOp::Stop | ControlOp::StopNow,
            ..
        })
        | Ok(Command::EmergencyStop { .. }) => RX_STOP,
        Ok(Command::Control {
            op: ControlOp::Heartbeat,
            ..
        }) => RX_HEARTBEAT,
        _ => RX_OTHER,
    }
}

/// Frames the classification looks at (the node takes at most its `max_frames` frames of all
/// kinds per poll; beyond this many the classes of the rest count as one).
const SEEN: usize = 128;

/// What waited for the node before a cycle, to classify the cycle after it ([`Kind`]): by the
/// classes of the frames the node took from its device (a prefix of what waited), by whether
/// its tick re-planned, and by whether the node stood before and after. Taken outside the
/// timed poll.
#[derive(Clone, Debug)]
pub struct Pending {
    /// `seen[i]`: the classes of the first i + 1 waiting frames.
    seen: [u8; SEEN],
    /// The classes of every waiting frame.
    all: u8,
    waiting: usize,
    was_standing: bool,
    plans: u32,
    state: NodeState,
    /// The node's count of step adjustments worked on.
    adjustments: u32,
    /// The node's next step number (it moves when a step is appended).
    next_step: u16,
}

impl Pending {
    /// Before the cycle: what waits in `bus` for `node`.
    pub fn before<D: Device, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real>(
        node: &Node<Q, G, T>,
        bus: &D,
    ) -> Self {
        let mut seen = [0u8; SEEN];
        let (mut acc, mut i) = (0u8, 0usize);
        let expect = node.expect();
        bus.each_pending(|f| {
            acc |= class(f, expect);
            if let Some(s) = seen.get_mut(i) {
                *s = acc;
            }
            i += 1;
            true
        });
        Self {
            seen,
            all: acc,
            waiting: bus.pending_len(),
            was_standing: node.gait().is_standing(),
            plans: node.gait().plans(),
            state: node.state(),
            adjustments: node.adjustment_attempts(),
            next_step: node.next_step(),
        }
    }

    /// After the cycle: its record (`units` of the clock spent in the poll, the node's
    /// `report`).
    pub fn after<D: Device, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real>(
        &self,
        node: &Node<Q, G, T>,
        bus: &D,
        units: u32,
        report: PollReport<T>,
    ) -> CycleRecord<T> {
        let taken = self.waiting.saturating_sub(bus.pending_len());
        let rx = match taken.checked_sub(1) {
            None => 0,
            Some(i) => self.seen.get(i).copied().unwrap_or(self.all),
        };
        let tick = node.gait().ticks();
        let replan = node
            .gait()
            .last_replan()
            .filter(|i| i.tick == tick)
            .copied();
        let kind =
            if rx & RX_DRIVE != 0 || (rx & RX_PUSH == 0 && node.next_step() != self.next_step) {
                Kind::Drive
            } else if rx & RX_MODIFY != 0 {
                Kind::Modify
            } else if rx & RX_START != 0 {
                Kind::Start
            } else if let Some(info) = replan {
                if info.adjust_ticks != 0 {
                    Kind::Adjust
                } else {
                    Kind::Replan
                }
            } else if node.adjustment_attempts() != self.adjustments {
                Kind::StepAdjust
            } else if rx & RX_STOP != 0 {
                Kind::StopCommand
            } else if rx & RX_PUSH != 0 {
                Kind::Push
            } else if self.was_standing && node.gait().is_standing() {
                Kind::Standing
            } else if node.gait().plans() != self.plans {
                Kind::Settle
            } else if node.state() != self.state {
                Kind::Transition
            } else if taken > 1 + usize::from(rx & RX_MEASURED != 0) || rx & RX_OTHER != 0 {
                Kind::Traffic
            } else {
                Kind::Steady
            };
        CycleRecord {
            tick,
            kind,
            units,
            report,
            replan,
        }
    }
}
