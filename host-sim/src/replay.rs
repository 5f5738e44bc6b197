//! Record and replay: a candump log of a controller's frames played into the node, as
//! `canplayer` plays a log onto a bus (`host-sim replay LOG`).
//!
//! The log is candump's `-l` format, `(SSSSSSSSSS.UUUUUU) IFACE ID#DATA`, one frame per line,
//! the time absolute from host-sim's epoch ([`LOG_EPOCH_S`], 2026-01-01T00:00:00Z): the log
//! `host-sim run` writes, or one a controller wrote (`host-sim/examples/controller.py`). A frame
//! logged at simulated time `t` (the log time less the epoch) is sent on the bus at the start
//! of its control cycle, `k = ⌊t / dt⌋` (`dt` the robot's control period), before the node's
//! poll of that cycle: a controller sends its commands at the start of a cycle and the log
//! records them a little later, when they are delivered, so a host-sim log replays onto the
//! same cycles, in the same arbitration order, and the node answers it bit for bit as in the
//! run that wrote it (`host-sim/tests/replay.rs`). Frames the node itself sends (`ACK`, the
//! stream, `STATUS`, `DIAG`) are not replayed: the node sends its own. Every other frame is,
//! the node's commands and foreign traffic alike.
//!
//! Accepted lines: any interface name, upper- or lower-case hexadecimal, standard (3-digit)
//! identifiers, 0 to 8 data bytes; blank lines are skipped. A line that is none of these, a
//! time before the epoch or a time going backwards is refused with its line number.
//!
//! The replay runs until the node stands still after the log's last frame, or for at most
//! [`MAX_AFTER_S`] more.

use planner_core::gait::Reference;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{ids, Ack, RawFrame};

use crate::bus::{parse_log_line, Bus, Faults, LOG_EPOCH_S, LOG_IFACE};
use embedded_can::nb::Can;

/// Longest replay after the log's last frame \[s\].
pub const MAX_AFTER_S: f64 = 60.0;

/// A frame to replay and the control cycle it is sent in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timed {
    /// The control cycle.
    pub tick: u64,
    /// The frame.
    pub frame: RawFrame,
}

/// What a replay produced.
#[derive(Clone, Debug)]
pub struct Replayed {
    /// The node's reference, one per cycle, from the standing state at cycle 0.
    pub trajectory: Vec<Reference<f64>>,
    /// Every frame delivered on the bus, as a candump log (the replayed ones and the node's).
    pub can_log: Vec<String>,
    /// The node's answers, with the cycle they arrived in.
    pub acks: Vec<(u64, Ack)>,
    /// Frames replayed.
    pub replayed: usize,
    /// Whether the replay ended at [`MAX_AFTER_S`] rather than standing.
    pub cut: bool,
}

/// Whether the node sends frames of this identifier (they are not replayed).
pub fn node_sends(id: u16) -> bool {
    matches!(
        id,
        ids::ACK
            | ids::COG
            | ids::ZMP
            | ids::COG_VEL
            | ids::FOOT_LEFT
            | ids::FOOT_RIGHT
            | ids::STATUS
            | ids::DIAG
    )
}

/// Reads a candump log (see the module docs) into the frames to replay, for a control period
/// of `dt` seconds. The error names the line.
pub fn parse(text: &str, dt: f64) -> Result<Vec<Timed>, String> {
    let period_us = (dt * 1e6).round() as u64;
    if period_us == 0 {
        return Err(format!("control period {dt} s is below 1 µs"));
    }
    let mut out = Vec::new();
    let mut last_us = 0;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        // `(time) IFACE ID#DATA` → the strict form of host-sim's own log.
        let bad =
            || format!("line {n}: not a candump -l line with a standard identifier: {line:?}");
        let mut parts = line.split_whitespace();
        let (Some(time), Some(_iface), Some(frame), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(bad());
        };
        let strict = format!("{time} {LOG_IFACE} {}", frame.to_ascii_uppercase());
        let entry = parse_log_line(&strict).ok_or_else(bad)?;
        let us = entry
            .sim_us()
            .ok_or_else(|| format!("line {n}: time before the epoch ({LOG_EPOCH_S} s)"))?;
        if us < last_us {
            return Err(format!("line {n}: time goes backwards"));
        }
        last_us = us;
        if !node_sends(entry.frame.id) {
            out.push(Timed {
                tick: us / period_us,
                frame: entry.frame,
            });
        }
    }
    Ok(out)
}

/// Plays `frames` into a node configured by `cfg` over the virtual bus at `bitrate` (see the
/// module docs).
pub fn replay(frames: &[Timed], cfg: &NodeConfig, bitrate: u32) -> Result<Replayed, String> {
    let mut node: Node<64> = Node::new(*cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let bus = Bus::new(bitrate, 2, Faults::default(), 1);
    bus.record();
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let period_ns = (cfg.params.dt * 1e9).round() as u64;
    let last = frames.last().map_or(0, |f| f.tick);
    let max_ticks = last + (MAX_AFTER_S / cfg.params.dt).ceil() as u64;
    let mut trajectory = vec![*node.gait().last()];
    let mut acks = Vec::new();
    let mut next = 0;
    let mut cut = true;
    for k in 0..max_ticks {
        let t0 = k * period_ns;
        bus.advance(t0);
        while next < frames.len() && frames[next].tick <= k {
            // The mailbox queues 64 frames; a log with more in one cycle loses the rest, as a
            // controller's would.
            let _ = ctl.transmit(&frames[next].frame);
            next += 1;
        }
        bus.advance(t0 + period_ns / 2);
        let now_ms = ((t0 + period_ns / 2) / 1_000_000) as u32;
        trajectory.push(node.poll(now_ms, &mut nport).reference);
        bus.advance(t0 + period_ns);
        while let Ok(f) = ctl.receive() {
            if let Some(a) = Ack::decode(&f) {
                acks.push((k, a));
            }
        }
        if k > last && next >= frames.len() && node.gait().is_standing() {
            cut = false;
            break;
        }
    }
    Ok(Replayed {
        trajectory,
        can_log: bus.log(),
        acks,
        replayed: next,
        cut,
    })
}
