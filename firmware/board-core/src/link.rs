//! The CAN link adapter: `embedded_can::nb::Can` for the node over a small trait of the FDCAN
//! peripheral ([`Fdcan`]), with software queues, the error state machine (bus-off recovery,
//! counters) and the replacement of stale frames.
//!
//! # Message RAM (the board's layout: [`crate::fdcan::layout`])
//! RX FIFO0 has [`RX_ELEMENTS`] (64) elements, RX FIFO1 [`RX1_ELEMENTS`] (16);
//! there are [`TX_SLOTS`] (16) dedicated TX buffers and a TX FIFO of [`TX_FIFO`] (16)
//! elements, 8-byte elements. At 1 Mbit/s a
//! classic frame takes at least 47 bit times (~21
//! frames per ms with 8-byte frames far fewer), so 64 elements hold ≥ 2.9 ms of a saturated bus
//! without being read: the node's worst poll (~0.25 ms) and a whole 5 ms cycle of any
//! realistic command burst fit, and [`Link::service`] drains the FIFO while the loop waits. No
//! interrupt is needed for that; an overflow is still detected (`RF0L`, `RF1L`), counted
//! ([`Health::rx_lost`]) and reported once to the node as a receive error (its `DIAG` bus
//! errors).
//!
//! # `ESTOP` first
//! The acceptance filters put `ESTOP` into RX FIFO1 and the other commands into RX FIFO0.
//! [`Link::receive`](Can::receive) reads FIFO1 first, every time, even before it reports a
//! lost frame: an `ESTOP` reaches the node in the first frames of the poll after it arrived,
//! however many commands wait in FIFO0 and in the software queue (the node takes up to
//! `max_frames` frames a cycle, and stops receiving for the cycle at a receive error).
//! [`Link::service`] leaves FIFO1 to the poll (16 elements: more than the node takes in a
//! cycle).
//!
//! # Transmission
//! Every identifier except [`ids::ACK`] is a stream (a newer frame supersedes the older). A
//! stream frame goes into a free dedicated TX buffer; an `ACK` into the TX FIFO; either
//! waits in a software queue of [`SOFT_TX`] frames when there is no room (the queue is
//! emptied in its order). A stream frame whose identifier already waits **replaces** it: in
//! the software queue in place; in a TX buffer by cancelling that buffer (the new frame takes
//! another free buffer or waits; a buffer is not reused before the core has finished
//! cancelling it, and a frame already on the wire when the cancellation comes is sent). So
//! after a stall the bus gets the newest reference, not 25 ms of old ones.
//!
//! `ACK`s, one per command, are never replaced and leave **in the order of the commands**:
//! the TX FIFO sends its elements in the order they were put, whereas among dedicated
//! buffers of equal identifier the core sends the lowest buffer first, whichever was written
//! last. (The FIFO's oldest element competes with the dedicated buffers by identifier; the
//! `ACK` identifier is below every stream identifier of the node.)
//!
//! # Errors
//! [`Link::service`] reads the protocol status and error counters each time it runs. When the
//! core has gone bus-off (it then sets `CCCR.INIT` by itself), the adapter counts the bus-off
//! and keeps the node **off the bus** for a **back-off** of whole control cycles
//! ([`Link::cycle`], once per cycle): 1 cycle after the first bus-off, doubling at every
//! further one up to [`BACKOFF_CAP`] (64 cycles, 320 ms), and back to 1 after
//! [`BACKOFF_RESET_CYCLES`] cycles error-active on the bus. So a node on a faulty bus (a
//! wiring fault, a wrong bit rate) re-joins at most every 320 ms instead of every ~3 ms, and
//! the joints' traffic sees its error flags that rarely. Entering error-passive counts one
//! episode. The published state ([`Health::state`]) is bus-off for the whole back-off.
//!
//! # Listening during the back-off
//! The node **listens** during the back-off: the adapter puts the core into bus monitoring
//! (`CCCR.MON`), where it receives and filters as usual but never transmits (no frame, no
//! acknowledge bit, no error flag: the bus is not disturbed), so an `ESTOP` sent during the
//! back-off reaches the node in the cycle it arrives, if another node on the bus acknowledges
//! it (without any acknowledge the sender's error flag destroys the frame, and it is
//! repeated until the back-off ends). The sequence at a bus-off:
//!
//! 1. the pending dedicated TX buffers and the stream frames in the software queue (old by
//!    the time the bus is back: the node sends newer ones every cycle) are dropped;
//! 2. both RX FIFOs are **drained** into the software receive queue, RX FIFO1's `ESTOP`s
//!    at its front, in order (the newest commands make room for them; [`Link::receive`](Can::receive)
//!    hands them out even before a loss report), and the `ACK`s still owed in the TX FIFO
//!    are **copied**, in their order, to the front of the software transmit queue (they are
//!    older than every frame there): the next step resets the FIFO statuses and every TX
//!    request (RM0433: setting `CCE` resets `RXF0S`, `RXF1S`, `TXFQS`, `TXBRP`, …);
//! 3. configuration mode (`CCE`, the core being in `INIT`), `MON` set, `INIT` cleared: the
//!    core waits for 129 occurrences of 11 recessive bits, the bus-off recovery (~1.42 ms on
//!    an idle bus at 1 Mbit/s; on a busy bus such a run comes about once per frame, so up to
//!    some 129 frames, ~15 ms), hearing nothing, and then listens.
//!
//! At the back-off's end (once `INIT` reads clear and the recovery is over; else one cycle
//! more) the adapter clears `MON` directly (software may reset it at any time; no `INIT`,
//! which could cut off a frame being received, and no configuration mode: the FIFOs keep what
//! they hold) and reads it back: the core is in normal operation at once, and the software
//! transmit queue empties in its order, the owed `ACK`s first, then those of the commands
//! heard during the back-off. Should `MON` not clear, the core stays listening, the link
//! stays reported bus-off (so the node's link supervision holds) and the adapter tries again
//! every cycle: the node is never mute while reported on the bus. A frame beyond the software receive
//! queue's room when the FIFOs are drained (more than [`SOFT_RX`] frames waiting) is lost,
//! counted ([`Health::rx_lost`]) and reported as a receive error. If the owed `ACK`s do not
//! all fit into the software transmit queue, or configuration mode cannot be entered (a core
//! that does not set `CCE`: nothing is reset then), the adapter falls back to holding the
//! core in `INIT` for the back-off (deaf, its `ACK`s still in the TX FIFO), then clearing
//! `INIT`: no `ACK` is dropped either way.
//!
//! A **message RAM access failure** (`IR.MRAF`: the core could not read or write an element in
//! time; a transmit failure also puts it into restricted operation, `CCCR.ASM`, where it
//! sends nothing) is counted ([`Health::ram_faults`]), the flag cleared and restricted
//! operation left (`ASM` may be cleared at any time): the core transmits again.
//! [`Link::health`] is what the board publishes (TEC, REC, state, counters, the back-off).

use embedded_can::nb::Can;
use heapless::Deque;
use planner_core::wire::{ids, LinkHealth};

use crate::frame::ClassicFrame;

/// Elements of RX FIFO0 in the board's message-RAM layout.
pub const RX_ELEMENTS: usize = 64;
/// Elements of RX FIFO1, which receives only `ESTOP` (read before everything else at every
/// receive: more `ESTOP`s than the node takes in a cycle).
pub const RX1_ELEMENTS: usize = 16;
/// Dedicated TX buffers in the board's message-RAM layout (buffers 0 … 15; the stream
/// frames: 9 identifiers, with room for buffers still being cancelled).
pub const TX_SLOTS: usize = 16;
/// Elements of the TX FIFO (buffers 16 … 31, after the dedicated ones; the `ACK`s: as many
/// as the commands the node takes in a cycle). Together at the M_CAN maximum of 32.
pub const TX_FIFO: usize = 16;
/// Frames the software receive queue of RX FIFO0 holds (beyond the hardware FIFO).
pub const SOFT_RX: usize = 32;
/// Frames the software transmit queue holds (beyond the TX buffers).
pub const SOFT_TX: usize = 32;
/// The longest bus-off back-off \[control cycles\] (320 ms at 5 ms): the first bus-off waits
/// 1 cycle, each further one twice the one before, up to this.
pub const BACKOFF_CAP: u16 = 64;
/// Control cycles error-active on the bus (no bus-off, no warning, no error-passive) after
/// which the back-off starts again from 1 cycle (1 s).
pub const BACKOFF_RESET_CYCLES: u16 = 200;

/// `PSR` bits the adapter reads (RM0433 FDCAN_PSR).
pub mod psr {
    /// Error-passive.
    pub const EP: u32 = 1 << 5;
    /// Error warning (a counter ≥ 96).
    pub const EW: u32 = 1 << 6;
    /// Bus-off.
    pub const BO: u32 = 1 << 7;
}

/// The few accesses to the FDCAN peripheral that the adapter needs at run time. The board
/// uses [`crate::fdcan::RegFdcan`] (over FDCAN1's registers and message RAM); the host tests
/// that and simpler models.
pub trait Fdcan {
    /// Reads the oldest element of RX FIFO0 and acknowledges it (`RXF0A`); `None` if empty.
    fn rx_pop(&mut self) -> Option<[u32; 4]>;
    /// Reads the oldest element of RX FIFO1 (`ESTOP`) and acknowledges it (`RXF1A`); `None`
    /// if empty. The default is for a device without FIFO1 (every frame in FIFO0).
    fn rx_pop_fifo1(&mut self) -> Option<[u32; 4]> {
        None
    }
    /// `true` once after a frame was lost because an RX FIFO was full (`IR.RF0L` or
    /// `IR.RF1L`, cleared).
    fn rx_take_lost(&mut self) -> bool;
    /// Pending TX buffers (`TXBRP`: bit `i` = buffer `i` waits for or is in transmission).
    fn tx_pending(&self) -> u32;
    /// Writes dedicated buffer `slot` (< [`TX_SLOTS`], not pending) and requests its
    /// transmission.
    fn tx_start(&mut self, slot: usize, element: &[u32; 4]);
    /// Writes `element` into the TX FIFO at its put index (`TXFQS.TFQPI`) and requests it
    /// (`TXBAR`); `false` (nothing written) if the FIFO is full (`TXFQS.TFQF`). The FIFO sends
    /// its elements in the order they were put.
    fn tx_fifo_put(&mut self, element: &[u32; 4]) -> bool;
    /// Requests the cancellation of the buffers in `mask` (`TXBCR`); a buffer stays pending
    /// until the core has cancelled it (or sent it, if it was already on the bus).
    fn tx_cancel(&mut self, mask: u32);
    /// The protocol status register (`PSR`).
    fn protocol_status(&self) -> u32;
    /// The error counter register (`ECR`: TEC 7:0, REC 14:8, RP 15).
    fn error_counters(&self) -> u32;
    /// `true` while the core is in its initialisation state (`CCCR.INIT`; set by the core
    /// itself on bus-off).
    fn in_init(&self) -> bool;
    /// Leaves the initialisation state (clears `CCCR.INIT`): bus-off recovery begins.
    fn leave_init(&mut self);
    /// `true` once after a message RAM access failure (`IR.MRAF`, cleared) or in restricted
    /// operation (`CCCR.ASM`, left): the core is back in normal operation afterwards.
    fn take_ram_failure(&mut self) -> bool;
    /// From the initialisation state: configuration mode (`CCE`), bus monitoring
    /// (`CCCR.MON`) set to `monitoring` (the other mode bits unchanged), then `INIT` cleared:
    /// the core joins the bus, receiving only if `monitoring`. Entering configuration mode
    /// resets the RX FIFOs' and the TX FIFO's statuses and every TX request: drain and copy
    /// first. `true` if configuration mode was entered (the statuses are reset; should `MON`
    /// not read back as asked, the core stays in `INIT`); `false` if nothing changed (not in
    /// `INIT`, or `CCE` refused). The default (a device without bus monitoring) refuses.
    fn restart(&mut self, monitoring: bool) -> bool {
        let _ = monitoring;
        false
    }
    /// Leaves bus monitoring (clears `CCCR.MON`, which software may reset at any time, outside
    /// configuration mode too: the FIFOs and TX requests keep their state); `true` once `MON`
    /// reads clear. The default (a device without bus monitoring) is never in it.
    fn leave_monitoring(&mut self) -> bool {
        true
    }
    /// The element `k` places after the TX FIFO's get index (`k` < [`TX_FIFO`]) if its
    /// transmission is still pending (`TXBRP`), else `None`: the `ACK`s still owed, in their
    /// order. The default: none.
    fn tx_fifo_owed(&self, k: usize) -> Option<[u32; 4]> {
        let _ = k;
        None
    }
}

/// The state of the node on the bus (ISO 11898-1 fault confinement).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BusState {
    /// Error-active, both counters below 96.
    #[default]
    Active = 0,
    /// Error-active, a counter at 96 or above (warning).
    Warning = 1,
    /// Error-passive (a counter above 127).
    Passive = 2,
    /// Bus-off (TEC above 255): not on the bus until recovered.
    BusOff = 3,
}

impl BusState {
    /// Every state, in the order of its code (checked against `LINK`'s `bus_state` value
    /// table in host-sim/can/walking.dbc).
    pub const ALL: [BusState; 4] = [Self::Active, Self::Warning, Self::Passive, Self::BusOff];
}

/// What the board publishes about the link (counters saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Health {
    /// Transmit error counter.
    pub tec: u8,
    /// Receive error counter (7 bits).
    pub rec: u8,
    /// The receive error counter reached the error-passive level (`ECR.RP`).
    pub rx_passive: bool,
    /// Bus state at the last [`Link::service`]; bus-off for the whole back-off (also while
    /// the core listens in bus monitoring: it sends nothing).
    pub state: BusState,
    /// Bus-off events since start-up (each one recovered).
    pub bus_offs: u16,
    /// Entries into error-passive since start-up.
    pub passive_episodes: u16,
    /// RX FIFO overflows seen (frames lost while FIFO0 or FIFO1 was full).
    pub rx_lost: u16,
    /// Frames superseded before they were sent (software queue or cancelled TX buffer).
    pub replaced: u16,
    /// Received elements that were not classic standard data frames (dropped).
    pub rx_foreign: u16,
    /// The bus-off back-off: 0 none (no bus-off since the last error-free stretch); `n` ≥ 1:
    /// the last bus-off kept the node off the bus for 2^(n-1) control cycles (7: the cap, 64).
    pub backoff: u8,
    /// Message RAM access failures (`IR.MRAF`, `CCCR.ASM`) since start-up, each recovered.
    pub ram_faults: u16,
}

impl Health {
    /// The `LINK` frame's content: this health, the reset reason and the missed slots
    /// (saturating at 255).
    pub fn to_wire(&self, reset: crate::ResetReason, missed_slots: u32) -> LinkHealth {
        LinkHealth {
            tec: self.tec,
            rec: self.rec,
            rx_passive: self.rx_passive,
            bus_state: self.state as u8,
            reset: reset as u8,
            bus_offs: self.bus_offs,
            passive_episodes: self.passive_episodes,
            missed_slots: missed_slots.min(255) as u8,
            backoff: self.backoff,
            ram_faults: self.ram_faults.min(u16::from(u8::MAX)) as u8,
        }
    }
}

/// The receive error: frames were lost (an RX FIFO overflowed) since the last report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RxLost;

impl embedded_can::Error for RxLost {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Overrun
    }
}

/// The adapter over peripheral `P`.
pub struct Link<P: Fdcan> {
    hw: P,
    rx: Deque<ClassicFrame, SOFT_RX>,
    tx: Deque<ClassicFrame, SOFT_TX>,
    /// Identifier in each TX buffer since it was started (meaningful while pending).
    slot_id: [u16; TX_SLOTS],
    /// Buffers whose cancellation the adapter requested and that are still pending.
    cancelling: u32,
    /// An overflow was seen and not yet reported to the receiver.
    lost_unreported: bool,
    /// Control cycles the core stays off the bus (bus-off back-off); 0: not backing off.
    backoff_wait: u16,
    /// Control cycles error-active since the last bus-off (up to [`BACKOFF_RESET_CYCLES`]).
    quiet_cycles: u16,
    /// `INIT` clear requested after a back-off and not yet seen clear.
    rejoining: bool,
    /// The core was put into bus monitoring for the back-off (configuration mode entered).
    monitoring: bool,
    /// The bus state as the registers last said (the published one is bus-off during the
    /// back-off).
    seen: BusState,
    health: Health,
}

/// [`ClassicFrame::from_element`], not inlined: one copy for the bus-off path's conversions
/// (flash; the poll's receive has its own).
#[inline(never)]
fn frame_of(e: &[u32; 4]) -> Option<ClassicFrame> {
    ClassicFrame::from_element(e)
}

/// `true` for identifiers where a newer frame supersedes a waiting one (all but `ACK`).
pub fn supersedes(id: u16) -> bool {
    id != ids::ACK
}

/// [`Health::backoff`] at the cap: 2^(7-1) = [`BACKOFF_CAP`] cycles.
const BACKOFF_LEVEL_CAP: u8 = BACKOFF_CAP.trailing_zeros() as u8 + 1;
const _: () = assert!(BACKOFF_CAP.is_power_of_two() && BACKOFF_LEVEL_CAP <= 15);

/// Buffer mask covering the dedicated TX buffers (the TX FIFO's buffers follow them).
const ALL_SLOTS: u32 = if TX_SLOTS >= 32 {
    u32::MAX
} else {
    (1 << TX_SLOTS) - 1
};

impl<P: Fdcan> Link<P> {
    /// The adapter over a configured peripheral in normal operation.
    pub fn new(hw: P) -> Self {
        Self {
            hw,
            rx: Deque::new(),
            tx: Deque::new(),
            slot_id: [0; TX_SLOTS],
            cancelling: 0,
            lost_unreported: false,
            backoff_wait: 0,
            quiet_cycles: 0,
            rejoining: false,
            monitoring: false,
            seen: BusState::Active,
            health: Health::default(),
        }
    }

    /// The peripheral (for the tests' model, and the fault handler's silencing).
    pub fn peripheral(&self) -> &P {
        &self.hw
    }

    /// The peripheral, mutably.
    pub fn peripheral_mut(&mut self) -> &mut P {
        &mut self.hw
    }

    /// What the board publishes.
    pub fn health(&self) -> Health {
        self.health
    }

    /// The frames waiting in the software receive queue (of RX FIFO0), oldest first (the
    /// node receives them after RX FIFO1's and before those still in RX FIFO0).
    pub fn rx_waiting(&self) -> impl Iterator<Item = &ClassicFrame> {
        self.rx.iter()
    }

    /// Frames waiting in the software transmit queue.
    pub fn tx_waiting(&self) -> usize {
        self.tx.len()
    }

    /// `true` while the core listens in bus monitoring (the back-off after a bus-off).
    pub fn listening(&self) -> bool {
        self.monitoring
    }

    /// Error state machine, then RX FIFO0 into the software queue (RX FIFO1 is left to
    /// [`Link::receive`](Can::receive)) and the software transmit queue into free TX buffers.
    /// Call it often while the loop waits (cheap when idle).
    pub fn service(&mut self) {
        self.check_errors();
        self.drain_rx();
        self.pump_tx();
    }

    /// One control cycle has passed (call it once per cycle): the bus-off back-off counts
    /// down and, at its end, the core leaves bus monitoring (or `INIT`) and joins the bus;
    /// on the bus, error-active cycles count towards resetting the back-off.
    pub fn cycle(&mut self) {
        if self.backoff_wait > 0 {
            self.backoff_wait -= 1;
            if self.backoff_wait == 0 {
                self.end_backoff();
            }
            return;
        }
        if self.health.state != BusState::Active {
            self.quiet_cycles = 0;
            return;
        }
        self.quiet_cycles = self.quiet_cycles.saturating_add(1);
        if self.quiet_cycles >= BACKOFF_RESET_CYCLES {
            self.health.backoff = 0;
        }
    }

    /// The back-off is over: out of bus monitoring (once its recovery has ended: else one
    /// more cycle), or out of `INIT` (recovery: 129 × 11 recessive bits), onto the bus.
    #[cold]
    #[inline(never)]
    fn end_backoff(&mut self) {
        if self.monitoring {
            // MON is cleared directly (no INIT, which could cut off a frame being received,
            // and no configuration mode): the core goes from listening to normal operation
            // with its FIFOs as they are. Should MON not clear, the core stays listening, the
            // link stays reported bus-off (and so the node's link supervision holds) and the
            // adapter tries again next cycle: never mute while reported on the bus.
            // Not before the core listens: INIT's clear has taken (MON's write must not
            // write INIT back) and the recovery's recessive bits are counted.
            let not_listening = self.hw.in_init() || self.hw.protocol_status() & psr::BO != 0;
            if not_listening || !self.hw.leave_monitoring() {
                self.backoff_wait = 1;
                return;
            }
            self.monitoring = false;
        } else {
            self.hw.leave_init();
        }
        self.rejoining = true;
    }

    /// Control cycles the core still stays off the bus (0: not backing off).
    pub fn backoff_remaining(&self) -> u16 {
        self.backoff_wait
    }

    fn check_errors(&mut self) {
        if self.hw.take_ram_failure() {
            self.health.ram_faults = self.health.ram_faults.saturating_add(1);
        }
        let psr = self.hw.protocol_status();
        let ecr = self.hw.error_counters();
        let h = &mut self.health;
        h.tec = (ecr & 0xFF) as u8;
        h.rec = ((ecr >> 8) & 0x7F) as u8;
        h.rx_passive = ecr & (1 << 15) != 0;
        let state = if psr & psr::BO != 0 {
            BusState::BusOff
        } else if psr & psr::EP != 0 {
            BusState::Passive
        } else if psr & psr::EW != 0 {
            BusState::Warning
        } else {
            BusState::Active
        };
        let in_init = state == BusState::BusOff && self.hw.in_init();
        if !in_init {
            self.rejoining = false;
        }
        // A bus-off event: the state becomes bus-off, or the core has set INIT again (a new
        // bus-off that came before this adapter saw the recovery end); not while the adapter
        // itself keeps the core off the bus (the back-off) or has just asked it out.
        let waiting = self.backoff_wait > 0 || self.rejoining;
        if state == BusState::BusOff && !waiting && (self.seen != BusState::BusOff || in_init) {
            self.bus_off();
        }
        if state == BusState::Passive && self.seen != BusState::Passive {
            self.health.passive_episodes = self.health.passive_episodes.saturating_add(1);
        }
        self.seen = state;
        self.health.state = if self.backoff_wait > 0 {
            BusState::BusOff
        } else {
            state
        };
    }

    /// A bus-off: counted; old stream frames cancelled; the RX FIFOs drained and the owed
    /// `ACK`s copied; the core into bus monitoring (module docs) for the back-off.
    #[cold]
    #[inline(never)]
    fn bus_off(&mut self) {
        let h = &mut self.health;
        h.bus_offs = h.bus_offs.saturating_add(1);
        // The back-off: 1, 2, 4, … cycles, up to the cap.
        h.backoff = h.backoff.saturating_add(1).min(BACKOFF_LEVEL_CAP);
        self.backoff_wait = 1 << (h.backoff - 1);
        self.quiet_cycles = 0;
        // What waits in the dedicated TX buffers is old by the time the bus is back (stream
        // frames in the software queue are replaced by the newer ones the node sends).
        let pending = self.hw.tx_pending() & ALL_SLOTS;
        if pending != 0 {
            self.hw.tx_cancel(pending);
            self.cancelling |= pending;
        }
        self.drain_all_rx();
        // The ACKs still owed in the TX FIFO go in front of the software queue, in order (they
        // are older than every frame there), last first; if they do not all fit, or the core
        // refuses configuration mode, they are taken out again and the core stays in INIT
        // for the back-off (deaf, the ACKs kept in the TX FIFO).
        let mut copied = 0;
        for k in (0..TX_FIFO).rev() {
            let Some(e) = self.hw.tx_fifo_owed(k) else {
                continue;
            };
            let Some(f) = frame_of(&e) else {
                continue;
            };
            if self.tx.push_front(f).is_err() {
                self.unqueue(copied);
                return;
            }
            copied += 1;
        }
        self.monitoring = self.hw.restart(true);
        if !self.monitoring {
            // Nothing was reset: the ACKs are still in the TX FIFO.
            self.unqueue(copied);
        }
    }

    /// Takes `n` frames off the front of the software transmit queue.
    fn unqueue(&mut self, n: usize) {
        for _ in 0..n {
            self.tx.pop_front();
        }
    }

    /// Both RX FIFOs into the software queue (before configuration mode resets their
    /// statuses): RX FIFO1's `ESTOP`s in front, in order (they come first, as from RX FIFO1),
    /// the newest commands making room for them if it is full; a frame beyond the queue's room
    /// is lost, counted and reported.
    #[cold]
    #[inline(never)]
    fn drain_all_rx(&mut self) {
        let mut estops = [[0u32; 4]; RX1_ELEMENTS];
        let mut n = 0;
        while let Some(slot) = estops.get_mut(n) {
            let Some(e) = self.hw.rx_pop_fifo1() else {
                break;
            };
            *slot = e;
            n += 1;
        }
        self.drain_rx();
        let mut lost = false;
        while self.hw.rx_pop().is_some() {
            lost = true;
        }
        for e in estops.iter().take(n).rev() {
            let Some(f) = frame_of(e) else {
                self.health.rx_foreign = self.health.rx_foreign.saturating_add(1);
                continue;
            };
            if self.rx.is_full() {
                self.rx.pop_back();
                lost = true;
            }
            let _ = self.rx.push_front(f); // room: made above
        }
        if lost {
            self.health.rx_lost = self.health.rx_lost.saturating_add(1);
            self.lost_unreported = true;
        }
    }

    fn take_lost(&mut self) {
        if self.hw.rx_take_lost() {
            self.health.rx_lost = self.health.rx_lost.saturating_add(1);
            self.lost_unreported = true;
        }
    }

    /// RX FIFO0 into the software queue, up to its room. Not inlined: one copy for
    /// [`Link::service`] and the bus-off path (flash).
    #[inline(never)]
    fn drain_rx(&mut self) {
        self.take_lost();
        while !self.rx.is_full() {
            let Some(f) = self.read_hw() else {
                break;
            };
            // Not full: checked by the loop condition.
            let _ = self.rx.push_back(f);
        }
    }

    /// The next classic frame of RX FIFO0 (others are counted and dropped).
    fn read_hw(&mut self) -> Option<ClassicFrame> {
        self.read_hw_after(None)
    }

    /// The next classic frame: `first` (an element already read) if it is one, else the next
    /// of RX FIFO0 (others are counted and dropped). RX FIFO1's element comes through here
    /// too (`receive`), so that the poll inlines one element conversion, not two (~300 B of
    /// flash on the board); with `first` = `None` this is the plain FIFO0 loop.
    fn read_hw_after(&mut self, mut first: Option<[u32; 4]>) -> Option<ClassicFrame> {
        while let Some(e) = first.take().or_else(|| self.hw.rx_pop()) {
            match ClassicFrame::from_element(&e) {
                Some(f) => return Some(f),
                None => self.health.rx_foreign = self.health.rx_foreign.saturating_add(1),
            }
        }
        None
    }

    /// Buffers neither pending nor being cancelled.
    fn free_slots(&mut self) -> u32 {
        let pending = self.hw.tx_pending() & ALL_SLOTS;
        self.cancelling &= pending;
        !pending & !self.cancelling & ALL_SLOTS
    }

    /// Starts `f`: an `ACK` in the TX FIFO, a stream frame in a free dedicated buffer;
    /// `false` if there is no room (or the bus is off).
    fn start(&mut self, f: &ClassicFrame) -> bool {
        if self.health.state == BusState::BusOff {
            return false;
        }
        if !supersedes(f.raw_id()) {
            return self.hw.tx_fifo_put(&f.to_element());
        }
        let free = self.free_slots();
        if free == 0 {
            return false;
        }
        let slot = free.trailing_zeros() as usize;
        let Some(id) = self.slot_id.get_mut(slot) else {
            return false;
        };
        *id = f.raw_id();
        self.hw.tx_start(slot, &f.to_element());
        true
    }

    fn pump_tx(&mut self) {
        while let Some(f) = self.tx.front().copied() {
            if !self.start(&f) {
                break;
            }
            self.tx.pop_front();
        }
    }

    /// Replaces a waiting frame of `f`'s identifier; `true` if `f` is taken care of.
    fn replace(&mut self, f: &ClassicFrame) -> bool {
        let id = f.raw_id();
        if !supersedes(id) {
            return false;
        }
        let mut queued = false;
        if let Some(old) = self.tx.iter_mut().find(|w| w.raw_id() == id) {
            *old = *f;
            queued = true;
        }
        let cancelled = self.cancel_stale(id);
        if queued && !cancelled {
            self.health.replaced = self.health.replaced.saturating_add(1);
        }
        // Replaced in the queue: done; only cancelled in a buffer: still to be queued.
        queued
    }

    /// Cancels the pending TX buffers that hold a frame of identifier `id` if it is a stream
    /// ([`supersedes`]); `true` if there was one (counted as replaced).
    fn cancel_stale(&mut self, id: u16) -> bool {
        if !supersedes(id) {
            return false;
        }
        // Only the pending buffers (a few: what the bus has not sent yet), lowest first.
        let mut pending = self.hw.tx_pending() & ALL_SLOTS & !self.cancelling;
        let mut hit = 0u32;
        while pending != 0 {
            let bit = pending & pending.wrapping_neg();
            let slot = pending.trailing_zeros() as usize;
            if self.slot_id.get(slot) == Some(&id) {
                hit |= bit;
            }
            pending &= !bit;
        }
        if hit == 0 {
            return false;
        }
        self.hw.tx_cancel(hit);
        self.cancelling |= hit;
        self.health.replaced = self.health.replaced.saturating_add(1);
        true
    }
}

impl<P: Fdcan> Can for Link<P> {
    type Frame = ClassicFrame;
    type Error = RxLost;

    /// Never displaces a frame (`Ok(None)`); `WouldBlock` only when the frame's TX buffers
    /// (the TX FIFO for an `ACK`, the dedicated ones for a stream frame) and the software
    /// queue are taken.
    fn transmit(&mut self, frame: &ClassicFrame) -> nb::Result<Option<ClassicFrame>, RxLost> {
        if self.tx.is_empty() {
            // The common case: nothing waits in software, so only a TX buffer can hold a
            // stale frame of this identifier.
            self.cancel_stale(frame.raw_id());
            if self.start(frame) {
                return Ok(None);
            }
        } else {
            if self.replace(frame) {
                return Ok(None);
            }
            self.pump_tx();
            if self.tx.is_empty() && self.start(frame) {
                return Ok(None);
            }
        }
        match self.tx.push_back(*frame) {
            Ok(()) => Ok(None),
            Err(_) => Err(nb::Error::WouldBlock),
        }
    }

    /// `ESTOP` first (RX FIFO1), then, once after an overflow, [`RxLost`], then the oldest
    /// other frame (the software queue, then RX FIFO0; `ESTOP`s drained at a bus-off are at
    /// its front).
    fn receive(&mut self) -> nb::Result<ClassicFrame, RxLost> {
        // RX FIFO1's oldest element, converted by the same code as RX FIFO0's below; one that
        // is not a classic frame is counted and dropped, and this call goes on as without.
        let estop = match self.hw.rx_pop_fifo1() {
            Some(e) if !ClassicFrame::is_classic(&e) => {
                self.health.rx_foreign = self.health.rx_foreign.saturating_add(1);
                None
            }
            e => e,
        };
        if estop.is_none() {
            self.take_lost();
            if self.lost_unreported {
                // `ESTOP`s drained at a bus-off wait at the queue's front: still first.
                if self.rx.front().is_some_and(|f| f.raw_id() == ids::ESTOP) {
                    if let Some(f) = self.rx.pop_front() {
                        return Ok(f);
                    }
                }
                self.lost_unreported = false;
                return Err(nb::Error::Other(RxLost));
            }
            if let Some(f) = self.rx.pop_front() {
                return Ok(f);
            }
        }
        match self.read_hw_after(estop) {
            Some(f) => Ok(f),
            None => Err(nb::Error::WouldBlock),
        }
    }
}
