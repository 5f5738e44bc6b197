//! One control cycle: the controller's frames, one timed `Node::poll`, the node's answers.
//!
//! [`Runner`] plays a [`Scenario`] against planner-core's [`Node`] exactly as
//! `host_sim::sim::simulate` does with a fault-free bus (same frames at the same ticks, same
//! `now_ms`, same end condition), so every reference, answer and transmitted frame can be
//! compared with host-sim's run.

use core::borrow::Borrow;

use planner_core::gait::{Reference, ReplanInfo, PREVIEW};
use planner_core::node::{Node, PollReport};
use planner_core::shaping::PreviewGains;
use planner_core::wire::{Command, ControlOp, RawFrame};
use planner_core::Real;

use crate::bus::ScriptedBus;
use crate::controller::{Controller, Unrepresentable};
use crate::script::Scenario;
use crate::stats::{Kind, Stats};

/// A free-running up-counter provided by the image (wrapping `u32`; only differences are
/// used).
pub trait Clock {
    /// The present count.
    fn now(&mut self) -> u32;
}

/// What one control cycle did (`T`: the node's scalar).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleRecord<T = f64> {
    /// The gait's tick count after the cycle (the index of `reference` in host-sim's
    /// trajectory); the cycle ran at tick `tick - 1`.
    pub tick: u64,
    /// The kind of the cycle.
    pub kind: Kind,
    /// Clock units spent in `Node::poll`.
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
}

/// Classes of received frames, for [`Kind`].
const RX_PUSH: u8 = 1;
const RX_MODIFY: u8 = 2;
const RX_START: u8 = 4;
const RX_STOP: u8 = 8;

fn class(f: &RawFrame) -> u8 {
    match Command::decode(f) {
        Ok(Command::Append(_)) => RX_PUSH,
        Ok(Command::Modify(_)) => RX_MODIFY,
        Ok(Command::Control {
            op: ControlOp::Start,
            ..
        }) => RX_START,
        Ok(Command::Control {
            op: ControlOp::Stop | ControlOp::StopNow,
            ..
        })
        | Ok(Command::EmergencyStop { .. }) => RX_STOP,
        _ => 0, // heartbeat, reset, invalid
    }
}

/// Frames the node takes per cycle at most (`NodeConfig::max_rx` of `NodeConfig::hrp2`).
const MAX_RX: usize = 16;

/// Plays a scenario, one control cycle per call of [`Runner::cycle`].
#[derive(Clone, Debug)]
pub struct Runner<'s> {
    controller: Controller<'s>,
    bus: ScriptedBus,
    k: u64,
    finished: bool,
    tx_frames: u32,
    tx_digest: Fnv,
}

impl<'s> Runner<'s> {
    /// Plays `scenario` against a node that was just created (standing, nothing queued).
    pub fn new(scenario: &'s Scenario) -> Self {
        Self {
            controller: Controller::new(scenario),
            bus: ScriptedBus::new(),
            k: 0,
            finished: false,
            tx_frames: 0,
            tx_digest: Fnv::default(),
        }
    }

    /// The controller (commands sent, answers).
    pub fn controller(&self) -> &Controller<'s> {
        &self.controller
    }

    /// The device (frame counters).
    pub fn bus(&self) -> &ScriptedBus {
        &self.bus
    }

    /// Frames the node transmitted, and their digest ([`Fnv::add_frame`], in sending order).
    pub fn transmitted(&self) -> (u32, u64) {
        (self.tx_frames, self.tx_digest.0)
    }

    /// `true` once the scenario has ended: standing after its last command (as
    /// `host_sim::sim::simulate` decides), or `max_ticks` cycles run.
    pub fn done(&self) -> bool {
        self.finished || self.k >= self.controller.scenario().max_ticks
    }

    /// One control cycle at tick `k`: the controller sends what is due, the node polls once
    /// at `now_ms = 5k + 2` (host-sim polls 2.5 ms into the tick), then the controller reads
    /// what the node sent; `on_frame` sees every transmitted frame and, for an `ACK` that
    /// answers a command, the command's index in [`Controller::sent`]. Only `Node::poll` is
    /// timed with `clock` (recorded in `stats` by kind and as [`Kind::Cycle`]).
    pub fn cycle<C: Clock, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real>(
        &mut self,
        node: &mut Node<Q, G, T>,
        clock: &mut C,
        stats: &mut Stats,
        mut on_frame: impl FnMut(&RawFrame, Option<usize>),
    ) -> Result<CycleRecord<T>, Unrepresentable> {
        let k = self.k;
        self.controller.send_due(k, &mut self.bus)?;
        // What the node may take in this cycle, by class: `seen[i]` covers the first i + 1
        // waiting frames (it takes a prefix of the FIFO).
        let mut seen = [0u8; MAX_RX];
        let mut acc = 0;
        for (s, f) in seen.iter_mut().zip(self.bus.pending()) {
            acc |= class(f);
            *s = acc;
        }
        let waiting = self.bus.pending_len();
        let was_standing = node.gait().is_standing();
        let now_ms = (k * 5 + 2) as u32;

        let t0 = clock.now();
        let report = poll(node, now_ms, &mut self.bus);
        let units = clock.now().wrapping_sub(t0);

        let taken = waiting - self.bus.pending_len();
        let rx = if taken == 0 {
            0
        } else {
            seen[taken.min(MAX_RX) - 1]
        };
        let tick = node.gait().ticks();
        let replan = node
            .gait()
            .last_replan()
            .filter(|i| i.tick == tick)
            .copied();
        let kind = if rx & RX_MODIFY != 0 {
            Kind::Modify
        } else if rx & RX_START != 0 {
            Kind::Start
        } else if let Some(info) = replan {
            if info.adjust_ticks != 0 {
                Kind::Adjust
            } else {
                Kind::Replan
            }
        } else if rx & RX_STOP != 0 {
            Kind::StopCommand
        } else if rx & RX_PUSH != 0 {
            Kind::Push
        } else if was_standing && node.gait().is_standing() {
            Kind::Standing
        } else {
            Kind::Steady
        };
        stats.record(kind, units, tick);
        stats.record(Kind::Cycle, units, tick);

        while let Some(f) = self.bus.take_sent() {
            self.tx_frames = self.tx_frames.saturating_add(1);
            self.tx_digest.add_frame(&f);
            let answered = self.controller.read(k, &f);
            on_frame(&f, answered);
        }

        if node.gait().is_standing()
            && k > self.controller.last_command()
            && self.controller.all_sent()
        {
            self.finished = true;
        }
        self.k += 1;
        Ok(CycleRecord {
            tick,
            kind,
            units,
            report,
            replan,
        })
    }
}

/// `Node::poll`, in a frame of its own (as the board's loop calls it once per cycle).
#[inline(never)]
fn poll<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real>(
    node: &mut Node<Q, G, T>,
    now_ms: u32,
    bus: &mut ScriptedBus,
) -> PollReport<T> {
    node.poll(now_ms, bus)
}
