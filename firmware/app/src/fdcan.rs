//! An in-memory FDCAN for the board's link adapter: the QEMU image runs board-core's real
//! [`Link`] (the adapter the board runs over FDCAN1) on it, fed by the replay.
//!
//! [`ReplayFdcan`] implements [`board_core::Fdcan`] as a peripheral on an idle bus:
//!
//! * **receive**: RX FIFO0 of [`RX_ELEMENTS`] (64) message-RAM elements, as the board's layout;
//!   the player delivers the logged frames into it before a cycle (a full FIFO drops the frame
//!   and flags it, `IR.RF0L`, as the hardware does). No acceptance filter: the hardware's
//!   filters are configuration, not the adapter's, and the host's replay the image is compared
//!   with feeds the node every logged frame (foreign ones included);
//! * **transmit**: a frame written into a TX buffer or the TX FIFO is on the wire at once, in the order the
//!   node sent it (the in-memory device has no bus time, as [`crate::ScriptedBus`] had none):
//!   no buffer is ever pending, so the adapter never replaces a stale frame here and the wire
//!   carries exactly the node's frames. The wire holds [`WIRE`] frames until the player reads
//!   them after the cycle; a frame that finds it full is lost and counted
//!   ([`ReplayFdcan::wire_lost`]);
//! * **errors**: none (error-active, counters 0, never in INIT).
//!
//! So what the adapter's replacement, bus-off and error paths do is host-tested against the
//! mock FDCAN in board-core (`tests/link.rs`), not replayed here; what runs on the target is the
//! adapter's receive and transmit path, its `service`, and the health the node publishes.

use board_core::link::{RX_ELEMENTS, TX_SLOTS};
use board_core::{ClassicFrame, Fdcan, Link};
use heapless::Deque;
use planner_core::wire::RawFrame;

use crate::bus::Device;

/// Frames the wire holds until the player reads them (after every cycle): the node sends at
/// most its transmit backlog per poll.
pub const WIRE: usize = planner_core::node::TX_BACKLOG;

/// The in-memory FDCAN (module docs).
#[derive(Clone, Debug)]
pub struct ReplayFdcan {
    rx: Deque<[u32; 4], RX_ELEMENTS>,
    rx_lost_flag: bool,
    rx_overflow: u32,
    /// The wire: `wire[read..written]` not read yet (emptied whenever it is all read).
    wire: [[u32; 4]; WIRE],
    written: usize,
    read: usize,
    wire_lost: u32,
}

impl Default for ReplayFdcan {
    fn default() -> Self {
        Self {
            rx: Deque::new(),
            rx_lost_flag: false,
            rx_overflow: 0,
            wire: [[0; 4]; WIRE],
            written: 0,
            read: 0,
            wire_lost: 0,
        }
    }
}

/// The board's link adapter over the in-memory FDCAN: the QEMU image's CAN device.
pub type ReplayLink = Link<ReplayFdcan>;

impl ReplayFdcan {
    /// Empty FIFO and wire.
    pub fn new() -> Self {
        Self::default()
    }

    /// A frame arrives from the bus (dropped and flagged if RX FIFO0 is full).
    pub fn arrive(&mut self, f: &RawFrame) {
        let Some(frame) = f.to_frame::<ClassicFrame>() else {
            return; // not a classic standard frame: never in a log
        };
        if self.rx.push_back(frame.to_element()).is_err() {
            self.rx_lost_flag = true;
            self.rx_overflow = self.rx_overflow.saturating_add(1);
        }
    }

    /// The oldest frame on the wire not read yet.
    pub fn take_wire(&mut self) -> Option<RawFrame> {
        if self.read >= self.written {
            (self.read, self.written) = (0, 0);
            return None;
        }
        let e = self.wire.get(self.read).copied()?;
        self.read += 1;
        ClassicFrame::from_element(&e).and_then(|f| RawFrame::from_frame(&f))
    }

    /// A frame onto the wire (as the board's buffer write: a few stores); lost and counted if
    /// the wire is full.
    fn put_on_wire(&mut self, element: &[u32; 4]) {
        match self.wire.get_mut(self.written) {
            Some(e) => {
                *e = *element;
                self.written += 1;
            }
            None => self.wire_lost = self.wire_lost.saturating_add(1),
        }
    }

    /// Frames lost because RX FIFO0 was full.
    pub fn rx_overflow(&self) -> u32 {
        self.rx_overflow
    }

    /// Frames lost because the wire was full (the player did not read it).
    pub fn wire_lost(&self) -> u32 {
        self.wire_lost
    }

    /// The elements in RX FIFO0, oldest first.
    pub fn fifo(&self) -> impl Iterator<Item = &[u32; 4]> {
        self.rx.iter()
    }
}

impl Fdcan for ReplayFdcan {
    fn rx_pop(&mut self) -> Option<[u32; 4]> {
        self.rx.pop_front()
    }
    fn rx_take_lost(&mut self) -> bool {
        core::mem::take(&mut self.rx_lost_flag)
    }
    fn tx_pending(&self) -> u32 {
        0
    }
    fn tx_start(&mut self, slot: usize, element: &[u32; 4]) {
        if slot < TX_SLOTS {
            self.put_on_wire(element);
        } else {
            self.wire_lost = self.wire_lost.saturating_add(1);
        }
    }
    fn tx_fifo_put(&mut self, element: &[u32; 4]) -> bool {
        // The TX FIFO on an idle bus: never full, on the wire at once.
        self.put_on_wire(element);
        true
    }
    fn tx_cancel(&mut self, _mask: u32) {}
    fn protocol_status(&self) -> u32 {
        0
    }
    fn error_counters(&self) -> u32 {
        0
    }
    fn in_init(&self) -> bool {
        false
    }
    fn leave_init(&mut self) {}
    fn take_ram_failure(&mut self) -> bool {
        false
    }
}

impl Device for ReplayLink {
    fn deliver(&mut self, f: RawFrame) {
        self.peripheral_mut().arrive(&f);
    }
    fn take_sent(&mut self) -> Option<RawFrame> {
        self.peripheral_mut().take_wire()
    }
    fn pending_len(&self) -> usize {
        self.rx_waiting().count() + self.peripheral().rx.len()
    }
    fn each_pending(&self, mut f: impl FnMut(&RawFrame) -> bool) {
        let queued = self.rx_waiting().copied();
        let fifo = self
            .peripheral()
            .fifo()
            .filter_map(ClassicFrame::from_element);
        for frame in queued.chain(fifo) {
            if let Some(raw) = RawFrame::from_frame(&frame) {
                if !f(&raw) {
                    break;
                }
            }
        }
    }
    fn rx_overflow(&self) -> u32 {
        self.peripheral().rx_overflow()
    }
}
