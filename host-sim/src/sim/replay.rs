//! Record and replay: a candump log of a controller's frames played into the node, as
//! `canplayer` plays a log onto a bus (`host-sim replay LOG`).
//!
//! The log is candump's `-l` format, `(SSSSSSSSSS.UUUUUU) IFACE ID#DATA`, one frame per line:
//! the log `host-sim run` writes, a controller's (`host-sim/examples/controller.py`), or one
//! recorded on a robot. Times count from the start of the control cycle of the first frame
//! (cycles of `dt`, the robot's control period, on the grid of Unix time, which host-sim's
//! epoch 2026-01-01T00:00:00Z is on), as canplayer plays a log from its first frame.
//!
//! **When a frame is played** (the rule is `planner_core::playback`'s, which the QEMU image's
//! player uses too). The log records a frame when it was delivered; the node polls
//! in the middle of each cycle (`k·dt + dt/2`, as in `host_sim::sim`). A frame logged at `t`
//! is for the first poll at or after `t`, cycle `k = ⌈(t − dt/2) / dt⌉`: it is sent from the
//! start of that cycle, in log order, one at a time (the next goes into the mailbox when the
//! one before is on the wire, so arbitration cannot reorder them). A frame that does not get
//! onto the bus before the poll waits for the next cycle, as it would behind a busy bus. A
//! host-sim log (its controller sends at the start of each cycle, and the log is in
//! arbitration order) replays onto the same cycles at the same times, and the node answers
//! it bit for bit as in the run that wrote it (`host-sim/tests/replay.rs`). Frames the node
//! itself sends (`ACK`, the stream, `STATUS`, `DIAG`, `SESSION`) are not replayed: the node sends its
//! own. Every other frame is, the node's commands and foreign traffic alike.
//!
//! Accepted lines: any interface name, upper- or lower-case hexadecimal, standard (3-digit)
//! identifiers, 0 to 8 data bytes; blank lines are skipped. A log recorded on a robot's bus
//! carries other nodes' traffic too: its extended, remote and CAN FD frames are skipped and
//! counted ([`Parsed::skipped`]; the node's filters never let such a frame in, see
//! [`crate::sim::bus::other_frame_time`]). A line that is none of these or a time going
//! backwards is refused with its line number.
//!
//! The replay runs until every frame has been sent and read by the node and the node stands
//! still, or for at most [`MAX_AFTER_S`] after the log's last frame. Frames the node's
//! receive FIFO had no room for are counted ([`Replayed::lost`]).
//!
//! [`binary_log`] writes a log in the compact binary form that the QEMU image reads over
//! semihosting (`tests/tests/qemu.rs` replays host runs on the emulated target with it).

use planner_core::gait::Reference;
use planner_core::node::{Node, NodeConfig};
use planner_core::playback::{self, LogClock};
use planner_core::wire::{ids, Ack, RawFrame};

use crate::sim::bus::{other_frame_time, parse_candump_line, Bus, Faults, LogEntry, Tap};
use embedded_can::nb::Can;

/// Longest replay after the log's last frame \[s\] (`planner_core::playback::MAX_AFTER_US`).
pub const MAX_AFTER_S: f64 = playback::MAX_AFTER_US as f64 * 1e-6;

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
    /// The node's reference, one per cycle from the cycle that opened the session (the node
    /// does not tick before), after the standing state it started in.
    pub trajectory: Vec<Reference<f64>>,
    /// Every frame delivered on the bus, as a candump log (the replayed ones and the node's).
    pub can_log: Vec<String>,
    /// The node's answers, with the cycle they arrived in.
    pub acks: Vec<(u64, Ack)>,
    /// Every frame the node handed to its port, with the cycle whose poll sent it.
    pub node_frames: Vec<(u64, RawFrame)>,
    /// Frames replayed (put on the bus).
    pub replayed: usize,
    /// Frames lost because a receive FIFO was full (the node's, or the player's own).
    pub lost: u64,
    /// Whether the replay ended at [`MAX_AFTER_S`] rather than standing and idle.
    pub cut: bool,
    /// Cycles polled before the session was open (not in the trajectory).
    pub before_session: u64,
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
            | ids::SESSION
            | ids::ADJUST
    )
}

/// A candump log read for replay.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Parsed {
    /// The frames to replay, in log order.
    pub frames: Vec<Timed>,
    /// Extended, remote and CAN FD frames: skipped, as the node ignores them.
    pub skipped: usize,
}

/// One non-blank line of a candump log: a classic standard frame, or the time of another
/// node's frame the node never receives (skipped). The error names the line.
fn log_line(n: usize, line: &str) -> Result<Result<LogEntry, u64>, String> {
    match parse_candump_line(line) {
        Some(e) => Ok(Ok(e)),
        None => other_frame_time(line).map(Err).ok_or_else(|| {
            format!(
                "line {n}: not a candump -l line (a classic frame with a standard or \
                 extended identifier, a remote or a CAN FD frame): {line:?}"
            )
        }),
    }
}

/// Reads a candump log (see the module docs) into the frames to replay, for a control period
/// of `dt` seconds. The error names the line.
pub fn parse(text: &str, dt: f64) -> Result<Parsed, String> {
    let period_us = (dt * 1e6).round() as u64;
    if period_us < 2 {
        return Err(format!("control period {dt} s is below 2 µs"));
    }
    let mut out = Parsed::default();
    let mut base = None;
    let mut last_us = 0;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let entry = log_line(n, line)?;
        let us = match entry {
            Ok(e) => e.unix_us,
            Err(us) => us,
        };
        if us < last_us {
            return Err(format!("line {n}: time goes backwards"));
        }
        last_us = us;
        let Ok(entry) = entry else {
            out.skipped += 1;
            continue;
        };
        // The start of the first frame's cycle, on the grid of Unix time.
        let clock = *base.get_or_insert_with(|| LogClock::new(us, period_us));
        let Some(clock) = clock else {
            return Err(format!("control period {dt} s is below 2 µs"));
        };
        if !node_sends(entry.frame.id) {
            out.frames.push(Timed {
                tick: clock.cycle(us),
                frame: entry.frame,
            });
        }
    }
    Ok(out)
}

/// The compact binary log the QEMU image replays (the format is `gait_loop::binlog`'s, in
/// `firmware/app/src/binlog.rs`): the candump log `log` (see the module docs: blank lines
/// skipped, times not going backwards) as one log named `name` (at most 32 ASCII graphic
/// bytes), for a node configured by `cfg` (its control period and start feet). The frames are
/// the ones [`parse`] replays (not the node's own, nor those it skips), with their times; the
/// cycle grid starts at
/// the log's first line, as in [`parse`].
pub fn binary_log(name: &str, log: &[String], cfg: &NodeConfig) -> Result<Vec<u8>, String> {
    if name.is_empty() || name.len() > 32 || !name.bytes().all(|b| b.is_ascii_graphic()) {
        return Err(format!(
            "log name {name:?}: not 1 to 32 ASCII graphic bytes"
        ));
    }
    let period_us = (cfg.params.dt * 1e6).round() as u64;
    let period_us = u32::try_from(period_us)
        .ok()
        .filter(|&p| p >= 2)
        .ok_or_else(|| format!("control period {} s", cfg.params.dt))?;
    let mut first_us = None;
    let mut frames: Vec<(u64, RawFrame)> = Vec::new();
    let mut last_us = 0;
    for (i, line) in log.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let entry = log_line(i + 1, line)?;
        let us = match entry {
            Ok(e) => e.unix_us,
            Err(us) => us,
        };
        if us < last_us {
            return Err(format!("line {}: time goes backwards", i + 1));
        }
        last_us = us;
        // Another node's frame the node never receives: not in the log.
        let Ok(entry) = entry else {
            continue;
        };
        first_us.get_or_insert(entry.unix_us);
        if !node_sends(entry.frame.id) {
            frames.push((entry.unix_us, entry.frame));
        }
    }
    let first_us = first_us.unwrap_or(0);
    let count = u32::try_from(frames.len()).map_err(|_| "more than 2^32 frames".to_string())?;
    let mut out = Vec::with_capacity(96 + 8 * frames.len());
    out.extend_from_slice(b"WLOG");
    out.push(1);
    out.push(name.len() as u8);
    out.extend_from_slice(name.as_bytes());
    out.extend_from_slice(&period_us.to_le_bytes());
    out.extend_from_slice(&first_us.to_le_bytes());
    let last = frames.last().map_or(first_us, |&(us, _)| us);
    out.extend_from_slice(&last.to_le_bytes());
    out.extend_from_slice(&count.to_le_bytes());
    for f in [cfg.left, cfg.right] {
        for v in [f.x, f.y, f.yaw] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let mut t = first_us;
    for (us, frame) in frames {
        // ULEB128 of the time since the frame before (the first: since the log's start).
        let mut dt = us - t;
        t = us;
        loop {
            let low = (dt & 0x7F) as u8;
            dt >>= 7;
            if dt == 0 {
                out.push(low);
                break;
            }
            out.push(low | 0x80);
        }
        out.extend_from_slice(&frame.id.to_le_bytes());
        out.push(frame.len);
        out.extend_from_slice(frame.bytes());
    }
    Ok(out)
}

/// Plays `frames` into a node (`Node<64>`) configured by `cfg` over the virtual bus at
/// `bitrate` (see the module docs).
pub fn replay(frames: &[Timed], cfg: &NodeConfig, bitrate: u32) -> Result<Replayed, String> {
    replay_into::<64>(frames, cfg, bitrate)
}

/// [`replay`] into a node with a queue of `Q` steps (the firmware's is `Node<16>`).
pub fn replay_into<const Q: usize>(
    frames: &[Timed],
    cfg: &NodeConfig,
    bitrate: u32,
) -> Result<Replayed, String> {
    let mut node: Node<Q> = Node::new(*cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let bus = Bus::new(bitrate, 2, Faults::default(), 1);
    bus.record();
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let period_us = (cfg.params.dt * 1e6).round() as u64;
    let period_ns = period_us * 1000;
    let last = frames.last().map_or(0, |f| f.tick);
    let max_ticks = playback::max_cycles(last, period_us);
    let mut trajectory = vec![*node.gait().last()];
    let mut before_session = 0;
    let mut acks = Vec::new();
    let mut node_frames = Vec::new();
    let mut next = 0;
    let mut cut = true;
    for k in 0..max_ticks {
        let t0 = k * period_ns;
        let poll = t0 + period_ns / 2;
        bus.advance(t0);
        // This cycle's frames, in log order, one at a time, while there is time before the
        // poll.
        while next < frames.len() && frames[next].tick <= k {
            while ctl.pending() > 0 && bus.free_at() < poll {
                bus.advance(bus.free_at() + 1);
            }
            if ctl.pending() > 0 || bus.free_at() >= poll {
                break;
            }
            if ctl.transmit(&frames[next].frame).is_err() {
                break;
            }
            next += 1;
            bus.advance(bus.free_at().max(t0) + 1);
        }
        bus.advance(poll);
        let now_ms = playback::poll_ms(k, period_us);
        let mut tap = Tap::new(&mut nport, k);
        let reference = node.poll(now_ms, &mut tap).reference;
        // The trajectory from the cycle that opened the session (the node does not tick
        // before: a cycle with nothing to say), as `host_sim::sim` records it.
        if node.session_open() {
            trajectory.push(reference);
        } else {
            before_session += 1;
        }
        node_frames.append(&mut tap.sent);
        bus.advance(t0 + period_ns);
        while let Ok(f) = ctl.receive() {
            if let Some(a) = Ack::decode(&f) {
                acks.push((k, a));
            }
        }
        let idle = next >= frames.len() && ctl.pending() == 0 && nport.received() == 0;
        if playback::finished(k, last, idle, node.gait().is_standing()) {
            cut = false;
            break;
        }
    }
    Ok(Replayed {
        trajectory,
        can_log: bus.log(),
        acks,
        node_frames,
        replayed: next,
        lost: bus.stats().rx_overflow,
        cut,
        before_session,
    })
}
