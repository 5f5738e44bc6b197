//! FDCAN1's registers and message RAM: board-core's `FdcanRegs` on the hardware
//! ([`Fdcan1Regs`], volatile accesses), the bring-up over it ([`bring_up`]), the run-time
//! `board_core::Fdcan` over it ([`Fdcan1`]) and the fault handler's [`silence`]. The only
//! `unsafe` of the CAN path.
//!
//! Everything else is board-core's, written once and host-tested against a register-level
//! model of FDCAN1 (`board-core/tests/fdcan_model.rs`): the configuration (bit timing,
//! message RAM layout, acceptance filters, `GFC`), its read-back, the layout
//! (`board_core::fdcan::layout`: 4 standard filter elements, RX FIFO0 64 elements, RX FIFO1 16
//! elements for `ESTOP`, 16 dedicated TX buffers for the streams, a TX FIFO of 16 for the `ACK`s) and the run-time accesses
//! (`board_core::fdcan::RegFdcan`). FDCAN1's part of the shared 10 KiB message RAM is its
//! first 1,024 words, from 0x4000_AC00.

#![allow(unsafe_code)]

use board_core::fdcan::{self, BitTiming, BringUpError, FdcanRegs, Reg, RegFdcan, RAM_WORDS};
use board_core::Fdcan;
use stm32h7xx_hal::pac;

/// Start of FDCAN1's register block.
const REGS: usize = 0x4000_A000;
/// Start of the message RAM (SRAMCAN), FDCAN1's part first.
const MSG_RAM: usize = 0x4000_AC00;

/// FDCAN1's registers and message RAM (zero-sized: the addresses are fixed). The board owns
/// FDCAN1 and runs single-threaded, without CAN interrupts; the fault handler's [`silence`]
/// may interrupt an access, and only ever stops the core.
pub struct Fdcan1Regs {
    _private: (),
}

impl FdcanRegs for Fdcan1Regs {
    fn read(&self, reg: Reg) -> u32 {
        // SAFETY: `reg.offset()` is one of FDCAN1's register offsets (below 0x100, in its
        // 1 KiB block); a volatile 32-bit read of a peripheral register.
        unsafe { core::ptr::read_volatile((REGS + reg.offset() as usize) as *const u32) }
    }

    fn write(&mut self, reg: Reg, value: u32) {
        // SAFETY: as for `read`; a volatile 32-bit write of an FDCAN1 register (what the
        // value does to the peripheral is the caller's, board-core's, business).
        unsafe { core::ptr::write_volatile((REGS + reg.offset() as usize) as *mut u32, value) }
    }

    fn ram_read(&self, word: u32) -> u32 {
        if word >= RAM_WORDS {
            return 0;
        }
        // SAFETY: a word of FDCAN1's 4 KiB of the message RAM (checked above), 4-byte
        // aligned; volatile, as the core writes it.
        unsafe { core::ptr::read_volatile((MSG_RAM + 4 * word as usize) as *const u32) }
    }

    fn ram_write(&mut self, word: u32, value: u32) {
        if word >= RAM_WORDS {
            return;
        }
        // SAFETY: as for `ram_read`. board-core writes only elements the core does not
        // read now (configuration mode, or TX buffers without a pending request).
        unsafe { core::ptr::write_volatile((MSG_RAM + 4 * word as usize) as *mut u32, value) }
    }
}

/// Configures FDCAN1 (`board_core::fdcan::bring_up`: configuration mode, the bit timing
/// `timing` (the board's setting),
/// message RAM layout, filters, `GFC`, every value read back) and joins the bus only if all
/// of it reads back as written; otherwise the core stays in its initialisation state, off
/// the bus. Takes the PAC's FDCAN1: nothing else configures it. Call it with FDCAN1's
/// clocks on (RCC) and its pins in their alternate function.
pub fn bring_up(_fdcan1: pac::FDCAN1, timing: &BitTiming) -> Result<(), BringUpError> {
    fdcan::bring_up(&mut Fdcan1Regs { _private: () }, timing)
}

/// Stops FDCAN1 sending (the safe state's FDCAN step, after PD1 was taken as a recessive
/// GPIO): the core is asked into its initialisation state and every pending TX buffer is
/// cancelled. Takes effect only while FDCAN1's clocks run. `true` if the register block
/// answered (`ENDN` read back).
pub fn silence() -> bool {
    fdcan::silence(&mut Fdcan1Regs { _private: () })
}

/// FDCAN1 in normal operation after [`bring_up`]: board-core's `RegFdcan` over its
/// registers.
pub struct Fdcan1(RegFdcan<Fdcan1Regs>);

impl Fdcan1 {
    /// Takes over FDCAN1 once [`bring_up`] has joined the bus.
    pub fn new() -> Self {
        Self(RegFdcan::new(Fdcan1Regs { _private: () }))
    }
}

impl Fdcan for Fdcan1 {
    fn rx_pop(&mut self) -> Option<[u32; 4]> {
        self.0.rx_pop()
    }
    fn rx_pop_fifo1(&mut self) -> Option<[u32; 4]> {
        self.0.rx_pop_fifo1()
    }
    fn rx_take_lost(&mut self) -> bool {
        self.0.rx_take_lost()
    }
    fn tx_pending(&self) -> u32 {
        self.0.tx_pending()
    }
    fn tx_start(&mut self, slot: usize, element: &[u32; 4]) {
        self.0.tx_start(slot, element)
    }
    fn tx_fifo_put(&mut self, element: &[u32; 4]) -> bool {
        self.0.tx_fifo_put(element)
    }
    fn tx_cancel(&mut self, mask: u32) {
        self.0.tx_cancel(mask)
    }
    fn protocol_status(&self) -> u32 {
        self.0.protocol_status()
    }
    fn error_counters(&self) -> u32 {
        self.0.error_counters()
    }
    fn in_init(&self) -> bool {
        self.0.in_init()
    }
    fn leave_init(&mut self) {
        self.0.leave_init()
    }
    fn take_ram_failure(&mut self) -> bool {
        self.0.take_ram_failure()
    }
    fn leave_monitoring(&mut self) -> bool {
        self.0.leave_monitoring()
    }
    fn restart(&mut self, monitoring: bool) -> bool {
        self.0.restart(monitoring)
    }
    fn tx_fifo_owed(&self, k: usize) -> Option<[u32; 4]> {
        self.0.tx_fifo_owed(k)
    }
}
