//! One timed control cycle: one `Node::poll` over the in-memory device, timed by a [`Clock`]
//! and classified by [`Kind`] from the frames it took and what its tick did.

use core::borrow::Borrow;

use planner_core::gait::{Reference, ReplanInfo, PREVIEW};
use planner_core::node::{Node, PollReport};
use planner_core::shaping::PreviewGains;
use planner_core::wire::{Command, ControlOp, RawFrame};
use planner_core::Real;

use crate::bus::{ScriptedBus, FIFO};
use crate::stats::Kind;

/// A free-running up-counter provided by the image (wrapping `u32`; only differences are
/// used).
pub trait Clock {
    /// The present count.
    fn now(&mut self) -> u32;
}

/// What one control cycle did (`T`: the node's scalar).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleRecord<T = f64> {
    /// The gait's tick count after the cycle (the index of `report.reference` in the run's
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
        _ => 0, // heartbeat, reset, invalid, foreign
    }
}

/// One control cycle: `Node::poll(now_ms, bus)`, and only it, timed with `clock`
/// (through [`poll`], a frame of its own), then classified (see [`Kind`]): by the classes of
/// the frames the node took from the device's receive FIFO (a prefix of it), by whether its
/// tick re-planned, and by whether the node stood before and after.
pub fn timed_poll<C: Clock, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real>(
    node: &mut Node<Q, G, T>,
    now_ms: u32,
    bus: &mut ScriptedBus,
    clock: &mut C,
) -> CycleRecord<T> {
    // What the node may take, by class: `seen[i]` covers the first i + 1 waiting frames.
    let mut seen = [0u8; FIFO];
    let mut acc = 0;
    for (s, f) in seen.iter_mut().zip(bus.pending()) {
        acc |= class(f);
        *s = acc;
    }
    let waiting = bus.pending_len();
    let was_standing = node.gait().is_standing();

    let t0 = clock.now();
    let report = poll(node, now_ms, bus);
    let units = clock.now().wrapping_sub(t0);

    let taken = waiting.saturating_sub(bus.pending_len());
    let rx = match taken.checked_sub(1) {
        None => 0,
        Some(i) => seen.get(i).copied().unwrap_or(acc),
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
    CycleRecord {
        tick,
        kind,
        units,
        report,
        replan,
    }
}

/// `Node::poll`, in a frame of its own (as the board's loop calls it once per cycle).
#[inline(never)]
pub fn poll<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real>(
    node: &mut Node<Q, G, T>,
    now_ms: u32,
    bus: &mut ScriptedBus,
) -> PollReport<T> {
    node.poll(now_ms, bus)
}
