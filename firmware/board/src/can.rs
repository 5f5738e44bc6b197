//! `embedded_can::nb::Can` over the STM32H7's FDCAN (the `fdcan` crate behind stm32h7xx-hal's
//! `can` feature), classic CAN only: standard 11-bit identifiers, at most 8 data bytes.
//!
//! The `fdcan` crate lays out the message RAM with **3** TX mailboxes and **3** elements per RX
//! FIFO. The node publishes 5 stream frames per cycle (6 with the status, plus one ACK per
//! command), and it drops a stream frame it could not hand over in its cycle (a newer reference
//! supersedes it): with 3 mailboxes, `FOOT_LEFT`/`FOOT_RIGHT` would never reach the bus. So
//! each direction has a software FIFO of [`SOFT_FIFO`] frames in front of the hardware one:
//!
//! * [`FdcanBus::transmit`] puts the frame into a free mailbox (behind any frame still waiting
//!   in the software FIFO, so the order is kept) or into the software FIFO, and answers
//!   `WouldBlock` only when both are full. It never aborts a pending frame (`Ok(None)`).
//! * [`FdcanBus::receive`] returns the oldest frame of the software FIFO, then of RX FIFO0, and
//!   `WouldBlock` when both are empty. Extended, remote and CAN FD frames are not ours and are
//!   skipped (the filters already reject extended and remote frames).
//! * [`FdcanBus::service`] moves frames between the two levels; the firmware calls it while it
//!   waits for the next 5 ms tick, so the mailboxes are refilled as the bus frees them and RX
//!   FIFO0 (3 frames) is emptied between cycles.
//!
//! No `unsafe` here: the register and message-RAM accesses are the HAL's.

use core::convert::Infallible;

use embedded_can::{Frame, Id, StandardId};
use fdcan::frame::{FrameFormat, TxFrameHeader};
use fdcan::{FdCan, Instance, NormalOperationMode, ReceiveOverrun};
use heapless::Deque;

/// Frames each software FIFO holds.
pub const SOFT_FIFO: usize = 32;

/// A classic CAN data frame with a standard identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClassicFrame {
    id: StandardId,
    len: u8,
    data: [u8; 8],
}

impl Frame for ClassicFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        let Id::Standard(id) = id.into() else {
            return None;
        };
        if data.len() > 8 {
            return None;
        }
        let mut buf = [0; 8];
        buf[..data.len()].copy_from_slice(data);
        Some(Self {
            id,
            len: data.len() as u8,
            data: buf,
        })
    }

    /// Remote frames are not part of the message set.
    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }

    fn is_extended(&self) -> bool {
        false
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> Id {
        Id::Standard(self.id)
    }

    fn dlc(&self) -> usize {
        usize::from(self.len)
    }

    fn data(&self) -> &[u8] {
        // `len ≤ 8` (checked by `new`); `get` keeps this panic-free (firmware/nopanic).
        self.data.get(..usize::from(self.len)).unwrap_or(&self.data)
    }
}

/// Counters of the adapter (saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BusCounters {
    /// RX FIFO0 overflowed at least once before a frame was read (frames were lost).
    pub rx_overruns: u32,
    /// Frames received that were not classic standard data frames (skipped).
    pub rx_foreign: u32,
}

/// The FDCAN instance in normal operation, behind `embedded_can::nb::Can`.
pub struct FdcanBus<I: Instance> {
    can: FdCan<I, NormalOperationMode>,
    tx: Deque<ClassicFrame, SOFT_FIFO>,
    rx: Deque<ClassicFrame, SOFT_FIFO>,
    counters: BusCounters,
}

impl<I: Instance> FdcanBus<I> {
    /// Wraps a configured FDCAN in normal operation (classic frames, RX FIFO0).
    pub fn new(can: FdCan<I, NormalOperationMode>) -> Self {
        Self {
            can,
            tx: Deque::new(),
            rx: Deque::new(),
            counters: BusCounters::default(),
        }
    }

    /// The counters.
    pub fn counters(&self) -> BusCounters {
        self.counters
    }

    /// Moves waiting frames into free TX mailboxes and empties RX FIFO0 into the software
    /// FIFO. Cheap when there is nothing to do; call it often between cycles.
    /// When the software RX FIFO is full, further frames wait in RX FIFO0 (and beyond its 3
    /// elements the hardware drops them: `rx_overruns`).
    pub fn service(&mut self) {
        self.pump_tx();
        while !self.rx.is_full() {
            match self.read_fifo0() {
                Some(frame) => {
                    // Not full: checked by the loop condition.
                    let _ = self.rx.push_back(frame);
                }
                None => break,
            }
        }
    }

    /// Moves frames of the software TX FIFO into free mailboxes, oldest first.
    fn pump_tx(&mut self) {
        while let Some(frame) = self.tx.front().copied() {
            if !self.try_mailbox(&frame) {
                break;
            }
            self.tx.pop_front();
        }
    }

    /// Puts `frame` into a free mailbox; `false` when all 3 are pending.
    fn try_mailbox(&mut self, frame: &ClassicFrame) -> bool {
        let (_, tx, _, _) = self.can.split_by_ref();
        if tx.tx_queue_is_full() {
            return false;
        }
        let Some(id) = fdcan::id::StandardId::new(frame.id.as_raw()) else {
            return true; // unreachable: an embedded-can StandardId is 11 bits
        };
        let data = frame.data();
        let header = TxFrameHeader {
            // `data.len() ≤ 8`, visibly to the optimiser (`frame.len` is the same number).
            len: data.len() as u8,
            frame_format: FrameFormat::Standard,
            id: id.into(),
            bit_rate_switching: false,
            marker: None,
        };
        // A free mailbox exists, so nothing is aborted and this cannot block.
        tx.transmit(header, data).is_ok()
    }

    /// The next classic standard data frame of RX FIFO0, if any (others are skipped).
    fn read_fifo0(&mut self) -> Option<ClassicFrame> {
        let mut buf = [0u8; 64];
        loop {
            let info = match self.can.receive0(&mut buf) {
                Ok(ReceiveOverrun::NoOverrun(info)) => info,
                Ok(ReceiveOverrun::Overrun(info)) => {
                    self.counters.rx_overruns = self.counters.rx_overruns.saturating_add(1);
                    info
                }
                Err(nb::Error::WouldBlock) => return None,
                Err(nb::Error::Other(e)) => match e {},
            };
            let classic = info.frame_format == FrameFormat::Standard && !info.rtr;
            let frame = match info.id {
                fdcan::id::Id::Standard(id) if classic && info.len <= 8 => {
                    StandardId::new(id.as_raw())
                        .and_then(|id| ClassicFrame::new(id, &buf[..usize::from(info.len)]))
                }
                _ => None,
            };
            match frame {
                Some(f) => return Some(f),
                None => self.counters.rx_foreign = self.counters.rx_foreign.saturating_add(1),
            }
        }
    }
}

impl<I: Instance> embedded_can::nb::Can for FdcanBus<I> {
    type Frame = ClassicFrame;
    type Error = Infallible;

    fn transmit(&mut self, frame: &ClassicFrame) -> nb::Result<Option<ClassicFrame>, Infallible> {
        self.pump_tx();
        if self.tx.is_empty() && self.try_mailbox(frame) {
            return Ok(None);
        }
        match self.tx.push_back(*frame) {
            Ok(()) => Ok(None),
            Err(_) => Err(nb::Error::WouldBlock),
        }
    }

    fn receive(&mut self) -> nb::Result<ClassicFrame, Infallible> {
        if let Some(f) = self.rx.pop_front() {
            return Ok(f);
        }
        match self.read_fifo0() {
            Some(f) => Ok(f),
            None => Err(nb::Error::WouldBlock),
        }
    }
}
