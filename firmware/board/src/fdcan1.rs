//! FDCAN1's run-time register and message-RAM accesses: `board_core::Fdcan` on the hardware,
//! and the message-RAM layout the adapter relies on. The only `unsafe` of the CAN path.
//!
//! The `fdcan` crate configures the peripheral at start-up (bit timing, filters, global
//! filter, mode: its asserts there are start-up checks). Its run-time path is not used: its
//! fixed layout has 3 RX elements per FIFO and 3 TX buffers, and it keeps panics on indices
//! read from the hardware (see firmware/README.md). [`layout`] re-lays the message RAM while
//! the core is still in configuration mode, keeping the filter lists where the `fdcan` crate
//! wrote them:
//!
//! | words (from 0x4000_AC00) | what |
//! |---|---|
//! | 0 … 27    | 28 standard filter elements (the `fdcan` crate's, [`crate::COMMAND_FILTERS`]) |
//! | 28 … 43   | 8 extended filter elements (2 words each) |
//! | 44 … 299  | RX FIFO0: [`RX_ELEMENTS`] elements of 4 words (8-byte data), blocking mode |
//! | 300 … 427 | [`TX_SLOTS`] dedicated TX buffers of 4 words |
//!
//! RX FIFO1, the RX buffers and the TX event FIFO have no elements. FDCAN1's part of the
//! shared 10 KiB message RAM is its first 1,024 words (the HAL puts FDCAN2 at word 0x400).

#![allow(unsafe_code)]

use board_core::link::{RX_ELEMENTS, TX_SLOTS};
use board_core::Fdcan;
use stm32h7xx_hal::pac;

/// Start of the message RAM (SRAMCAN).
const MSG_RAM: usize = 0x4000_AC00;
/// Word offset of the standard filter list (the `fdcan` crate's layout).
const FILTERS_STD: u32 = 0;
/// Word offset of RX FIFO0: after 28 standard and 8 two-word extended filter elements.
const RX_FIFO0: u32 = FILTERS_STD + 28 + 2 * 8;
/// Word offset of the dedicated TX buffers.
const TX_BUFFERS: u32 = RX_FIFO0 + 4 * RX_ELEMENTS as u32;
/// Words an element takes with an 8-byte data field.
const ELEMENT_WORDS: u32 = 4;
const _: () = assert!(TX_BUFFERS + ELEMENT_WORDS * TX_SLOTS as u32 <= 1024);
const _: () = assert!(RX_ELEMENTS <= 64 && TX_SLOTS <= 32);

fn regs() -> &'static pac::fdcan1::RegisterBlock {
    // SAFETY: FDCAN1's register block exists for the program's lifetime; every access below
    // is a volatile read or write of one register. The board owns FDCAN1 (the `fdcan` driver
    // that configured it is not used after start-up) and runs single-threaded, without CAN
    // interrupts.
    unsafe { &*pac::FDCAN1::ptr() }
}

/// Lays out the message RAM as in the table above. Call it in configuration mode
/// (`CCCR.INIT` = `CCCR.CCE` = 1: after the HAL's `fdcan()`, before `into_normal()`).
pub fn layout() {
    let can = regs();
    // SAFETY (all writes): the start addresses and sizes are those of the table above, within
    // FDCAN1's part of the message RAM (checked at compile time); 0 elements disables a part.
    can.rxf0c.write(|w| unsafe {
        w.f0sa()
            .bits(RX_FIFO0 as u16)
            .f0s()
            .bits(RX_ELEMENTS as u8)
            .f0wm()
            .bits(0)
            .f0om()
            .clear_bit() // blocking: a frame arriving at a full FIFO is dropped (IR.RF0L)
    });
    can.rxf1c.write(|w| unsafe { w.f1s().bits(0) });
    can.txefc.write(|w| unsafe { w.efs().bits(0) });
    can.txbc.write(|w| unsafe {
        w.tbsa()
            .bits(TX_BUFFERS as u16)
            .ndtb()
            .bits(TX_SLOTS as u8)
            .tfqs()
            .bits(0)
            .tfqm()
            .clear_bit()
    });
    // 8-byte data fields everywhere (classic CAN).
    can.rxesc
        .write(|w| unsafe { w.f0ds().bits(0).f1ds().bits(0).rbds().bits(0) });
    can.txesc.write(|w| unsafe { w.tbds().bits(0) });
}

/// Stops FDCAN1 sending (fault handler): the core enters its initialisation state, the pins
/// stay recessive, and every pending TX buffer is cancelled. Works from any context.
pub fn silence() {
    let can = regs();
    can.cccr.modify(|_, w| w.init().set_bit());
    // SAFETY: any mask is a valid cancellation request.
    can.txbcr.write(|w| unsafe { w.bits(u32::MAX) });
}

fn word(offset: u32) -> *mut u32 {
    (MSG_RAM + 4 * offset as usize) as *mut u32
}

/// FDCAN1 in normal operation, laid out by [`layout`].
pub struct Fdcan1 {
    _private: (),
}

impl Fdcan1 {
    /// Takes over FDCAN1 once the `fdcan` driver has put it in normal operation.
    pub fn new() -> Self {
        Self { _private: () }
    }
}

impl Fdcan for Fdcan1 {
    fn rx_pop(&mut self) -> Option<[u32; 4]> {
        let can = regs();
        let s = can.rxf0s.read();
        if s.f0fl().bits() == 0 {
            return None;
        }
        let gi = u32::from(s.f0gi().bits()) % RX_ELEMENTS as u32;
        let base = RX_FIFO0 + ELEMENT_WORDS * gi;
        let mut e = [0u32; 4];
        for (k, w) in (0u32..).zip(e.iter_mut()) {
            // SAFETY: element `gi` of RX FIFO0 lies within the message RAM (`gi` < 64).
            *w = unsafe { core::ptr::read_volatile(word(base + k)) };
        }
        // SAFETY: acknowledging the element just read (an index < 64).
        can.rxf0a.write(|w| unsafe { w.f0ai().bits(gi as u8) });
        Some(e)
    }

    fn rx_take_lost(&mut self) -> bool {
        let can = regs();
        if can.ir.read().rf0l().bit_is_set() {
            can.ir.write(|w| w.rf0l().set_bit()); // write 1 to clear
            true
        } else {
            false
        }
    }

    fn tx_pending(&self) -> u32 {
        regs().txbrp.read().bits()
    }

    fn tx_start(&mut self, slot: usize, element: &[u32; 4]) {
        if slot >= TX_SLOTS {
            return;
        }
        let base = TX_BUFFERS + ELEMENT_WORDS * slot as u32;
        for (k, w) in (0u32..).zip(element) {
            // SAFETY: buffer `slot` (< 32) lies within the message RAM; it is not pending
            // (the adapter only writes free buffers), so the core does not read it now.
            unsafe { core::ptr::write_volatile(word(base + k), *w) };
        }
        // SAFETY: one request bit of an existing buffer.
        regs().txbar.write(|w| unsafe { w.bits(1 << slot) });
    }

    fn tx_cancel(&mut self, mask: u32) {
        // SAFETY: any mask is a valid cancellation request.
        regs().txbcr.write(|w| unsafe { w.bits(mask) });
    }

    fn protocol_status(&self) -> u32 {
        regs().psr.read().bits()
    }

    fn error_counters(&self) -> u32 {
        regs().ecr.read().bits()
    }

    fn in_init(&self) -> bool {
        regs().cccr.read().init().bit_is_set()
    }

    fn leave_init(&mut self) {
        regs().cccr.modify(|_, w| w.init().clear_bit());
    }
}
