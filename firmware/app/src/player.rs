//! The target's player of a recorded CAN log (record and replay): the QEMU image
//! replays host-sim's logs with it ([`crate::binlog`] reads them).
//!
//! [`Player`] feeds logged frames into the node through an in-memory [`Device`] (the
//! [`ScriptedBus`], or the board's link adapter over [`crate::fdcan::ReplayFdcan`]) by the
//! rule of `planner_core::playback`, the one `host-sim replay` uses: a frame is for cycle
//! [`LogClock::cycle`] of its time; before the poll of cycle `k` every frame for a cycle
//! `≤ k` is delivered, in log order (the in-memory device has no bus time: a log denser than
//! the bus carries before a poll is not replayed as host-sim's bus would); the node polls at
//! [`playback::poll_ms`]; the replay ends by [`playback::finished`] or after
//! [`playback::max_cycles`].

use core::borrow::Borrow;

use planner_core::gait::PREVIEW;
use planner_core::node::Node;
use planner_core::playback::{self, LogClock};
use planner_core::shaping::PreviewGains;
use planner_core::wire::{ids, RawFrame};
use planner_core::Real;

use crate::bus::{Device, ScriptedBus};
use crate::cycle::Fnv;

/// A logged frame: its time \[µs, in the log's time\] and the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogFrame {
    /// When the log recorded it.
    pub us: u64,
    /// The frame.
    pub frame: RawFrame,
}

/// Where the player reads the log's frames from, in log order.
pub trait Source {
    /// The next frame, `None` if there is none (any more).
    fn next_frame(&mut self) -> Option<LogFrame>;
}

/// The log ended before the number of frames its header announced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Truncated;

/// Plays one log into a node through the device `D`, one control cycle per [`Player::cycle`].
#[derive(Clone, Debug)]
pub struct Player<D = ScriptedBus> {
    clock: LogClock,
    remaining: u32,
    ahead: Option<(u64, RawFrame)>,
    last: u64,
    max: u64,
    bus: D,
    k: u64,
    finished: bool,
    fed: u32,
    tx_frames: u32,
    tx_digest: Fnv,
    link_frames: u32,
    link_digest: Fnv,
}

impl Player {
    /// A log of `count` frames to replay, the last one at `last_us`, on the grid `clock`,
    /// through a [`ScriptedBus`].
    pub fn new(clock: LogClock, count: u32, last_us: u64) -> Self {
        Self::with_device(clock, count, last_us, ScriptedBus::new())
    }
}

impl<D: Device> Player<D> {
    /// [`Player::new`] through `device` (e.g. the board's link adapter over the in-memory
    /// FDCAN, [`crate::fdcan::ReplayLink`]).
    pub fn with_device(clock: LogClock, count: u32, last_us: u64, device: D) -> Self {
        let last = if count == 0 { 0 } else { clock.cycle(last_us) };
        Self {
            clock,
            remaining: count,
            ahead: None,
            last,
            max: playback::max_cycles(last, clock.period_us()),
            bus: device,
            k: 0,
            finished: false,
            fed: 0,
            tx_frames: 0,
            tx_digest: Fnv::default(),
            link_frames: 0,
            link_digest: Fnv::default(),
        }
    }

    /// `true` once the replay has ended (standing and idle, or at its longest).
    pub fn done(&self) -> bool {
        self.finished || self.k >= self.max
    }

    /// Whether it ended at its longest rather than standing and idle.
    pub fn cut(&self) -> bool {
        !self.finished
    }

    /// Frames fed to the node so far.
    pub fn fed(&self) -> u32 {
        self.fed
    }

    /// The device (frame counters).
    pub fn bus(&self) -> &D {
        &self.bus
    }

    /// Frames the node transmitted, and their digest ([`Fnv::add_sent`]: each with the cycle
    /// that sent it), `LINK` frames left out (see [`Player::link`]).
    pub fn transmitted(&self) -> (u32, u64) {
        (self.tx_frames, self.tx_digest.0)
    }

    /// The `LINK` frames the node transmitted and their digest (as [`Player::transmitted`]).
    /// Only a node told its link health sends `LINK` (the board's control cycle does, every
    /// cycle): kept apart, so that [`Player::transmitted`] is comparable with a node that is
    /// never told, such as host-sim's.
    pub fn link(&self) -> (u32, u64) {
        (self.link_frames, self.link_digest.0)
    }

    /// The control cycle that [`Player::cycle`] runs next.
    pub fn next_cycle(&self) -> u64 {
        self.k
    }

    /// One control cycle: the frames due, one `poll(node, now_ms, device)` (which the image
    /// times; its result is returned), then `on_frame(cycle, frame)` for every frame the
    /// node sent. `Err(Truncated)` if `source` ended before the frames announced.
    pub fn cycle<S, const Q: usize, G, T, R>(
        &mut self,
        node: &mut Node<Q, G, T>,
        source: &mut S,
        poll: impl FnOnce(&mut Node<Q, G, T>, u32, &mut D) -> R,
        mut on_frame: impl FnMut(u64, &RawFrame),
    ) -> Result<R, Truncated>
    where
        S: Source,
        G: Borrow<PreviewGains<T, PREVIEW>>,
        T: Real,
    {
        let k = self.k;
        loop {
            if self.ahead.is_none() && self.remaining > 0 {
                let f = source.next_frame().ok_or(Truncated)?;
                self.remaining -= 1;
                self.ahead = Some((self.clock.cycle(f.us), f.frame));
            }
            match self.ahead {
                Some((tick, frame)) if tick <= k => {
                    self.bus.deliver(frame);
                    self.fed = self.fed.saturating_add(1);
                    self.ahead = None;
                }
                _ => break,
            }
        }
        let report = poll(
            node,
            playback::poll_ms(k, self.clock.period_us()),
            &mut self.bus,
        );
        while let Some(f) = self.bus.take_sent() {
            if f.id == ids::LINK {
                self.link_frames = self.link_frames.saturating_add(1);
                self.link_digest.add_sent(k, &f);
            } else {
                self.tx_frames = self.tx_frames.saturating_add(1);
                self.tx_digest.add_sent(k, &f);
            }
            on_frame(k, &f);
        }
        let idle = self.remaining == 0 && self.ahead.is_none() && self.bus.pending_len() == 0;
        if playback::finished(k, self.last, idle, node.gait().is_standing()) {
            self.finished = true;
        }
        self.k += 1;
        Ok(report)
    }
}
