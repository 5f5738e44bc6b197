//! An in-memory CAN device: the node's side of the bus inside the image.
//!
//! [`ScriptedBus`] implements `embedded_can::nb::Can` with planner-core's own frame type
//! ([`RawFrame`], standard identifiers, data frames). The [`Player`](crate::Player) puts the
//! logged frames due into the receive FIFO before a cycle; the node takes them from there in
//! `Node::poll`, and what the node transmits is kept in the transmit FIFO until the player
//! drains it after the cycle. Both FIFOs hold [`FIFO`] frames, like a port of
//! host-sim's virtual bus (`host_sim::bus::MAILBOX`, `RX_FIFO`): a full receive FIFO loses the
//! newest frame (counted), a full transmit FIFO answers `WouldBlock`.
//!
//! What the device does inside `poll` is a `Deque` push or pop of a 12-byte frame: the
//! instructions counted for a cycle are the node's, not a bus model's.

use heapless::Deque;
use planner_core::wire::RawFrame;

/// The replay's side of the node's CAN device: what the [`Player`](crate::Player) and the
/// classification of a cycle ([`crate::cycle::Pending`]) need. Implemented by
/// [`ScriptedBus`] and by the board's link adapter over the in-memory FDCAN
/// ([`crate::fdcan::ReplayLink`]).
pub trait Device {
    /// A frame from the log arrives (lost and counted if the receive side is full).
    fn deliver(&mut self, f: RawFrame);
    /// The oldest frame the node transmitted that the player has not read yet.
    fn take_sent(&mut self) -> Option<RawFrame>;
    /// Number of frames waiting for the node.
    fn pending_len(&self) -> usize;
    /// The frames waiting for the node, oldest (the next one it receives) first, each given to
    /// `f` until it returns `false`.
    fn each_pending(&self, f: impl FnMut(&RawFrame) -> bool);
    /// Frames lost because the receive side was full.
    fn rx_overflow(&self) -> u32;
}

/// Capacity of each FIFO (host-sim's mailbox and receive FIFO hold 64 frames too).
pub const FIFO: usize = 64;

/// The device never fails (no bus-off, no error frames).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoError {}

impl embedded_can::Error for NoError {
    fn kind(&self) -> embedded_can::ErrorKind {
        match *self {}
    }
}

/// The in-memory device (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct ScriptedBus {
    rx: Deque<RawFrame, FIFO>,
    tx: Deque<RawFrame, FIFO>,
    rx_overflow: u32,
}

impl ScriptedBus {
    /// Both FIFOs empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// A frame from the log arrives (lost and counted if the receive FIFO is full).
    pub fn deliver(&mut self, f: RawFrame) {
        if self.rx.push_back(f).is_err() {
            self.rx_overflow = self.rx_overflow.saturating_add(1);
        }
    }

    /// Frames waiting for the node.
    pub fn pending(&self) -> impl Iterator<Item = &RawFrame> {
        self.rx.iter()
    }

    /// Number of frames waiting for the node.
    pub fn pending_len(&self) -> usize {
        self.rx.len()
    }

    /// The oldest frame the node transmitted and the player has not read yet.
    pub fn take_sent(&mut self) -> Option<RawFrame> {
        self.tx.pop_front()
    }

    /// Frames lost because the receive FIFO was full.
    pub fn rx_overflow(&self) -> u32 {
        self.rx_overflow
    }
}

impl Device for ScriptedBus {
    fn deliver(&mut self, f: RawFrame) {
        ScriptedBus::deliver(self, f);
    }
    fn take_sent(&mut self) -> Option<RawFrame> {
        ScriptedBus::take_sent(self)
    }
    fn pending_len(&self) -> usize {
        ScriptedBus::pending_len(self)
    }
    fn each_pending(&self, mut f: impl FnMut(&RawFrame) -> bool) {
        for frame in self.rx.iter() {
            if !f(frame) {
                break;
            }
        }
    }
    fn rx_overflow(&self) -> u32 {
        ScriptedBus::rx_overflow(self)
    }
}

impl embedded_can::nb::Can for ScriptedBus {
    type Frame = RawFrame;
    type Error = NoError;

    fn transmit(&mut self, frame: &RawFrame) -> nb::Result<Option<RawFrame>, NoError> {
        match self.tx.push_back(*frame) {
            Ok(()) => Ok(None),
            Err(_) => Err(nb::Error::WouldBlock),
        }
    }

    fn receive(&mut self) -> nb::Result<RawFrame, NoError> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}
