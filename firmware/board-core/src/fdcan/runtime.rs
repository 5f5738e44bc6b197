//! The run-time accesses of the link adapter ([`crate::link::Fdcan`]) over the registers and
//! message RAM of a configured FDCAN ([`RegFdcan`]), in the layout of [`super::layout`].

use super::config::{layout, RX1_ELEMENTS};
use super::regs::{cccr, ir, rxfs, txfqs, FdcanRegs, Reg};
use crate::link::{Fdcan, RX_ELEMENTS, TX_FIFO, TX_SLOTS};

/// `link::Fdcan` over an FDCAN brought up by [`super::bring_up`]: RX FIFO0 and FIFO1 read
/// by their get index and acknowledged, dedicated TX buffers written and requested, the TX
/// FIFO written at its put index and requested, `PSR`, `ECR` and `CCCR.INIT`. The board's `Fdcan1` is this over FDCAN1's volatile accesses; the host tests
/// run it over the register model.
pub struct RegFdcan<R> {
    regs: R,
}

impl<R: FdcanRegs> RegFdcan<R> {
    /// Takes over a configured FDCAN (after a successful [`super::bring_up`]).
    pub const fn new(regs: R) -> Self {
        Self { regs }
    }

    /// The register accesses (the tests' model).
    pub fn regs(&self) -> &R {
        &self.regs
    }

    /// The register accesses, mutably.
    pub fn regs_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    /// The oldest element of the FIFO whose status, acknowledge register, first word and size
    /// are given, acknowledged; `None` if it is empty. Not inlined: one copy for both FIFOs
    /// and every call site (flash; a call is nothing next to four message RAM reads).
    #[inline(never)]
    fn pop(&mut self, status: Reg, ack: Reg, start: u32, elements: usize) -> Option<[u32; 4]> {
        let s = self.regs.read(status);
        if rxfs::fill(s) == 0 {
            return None;
        }
        // The get index is below the FIFO's size in hardware; the remainder keeps the reads
        // inside the FIFO whatever the register says (checked: no panic path, whatever
        // `elements`).
        let gi = rxfs::get(s).checked_rem(elements as u32).unwrap_or(0);
        let base = start + layout::ELEMENT_WORDS * gi;
        let mut e = [0u32; 4];
        for (k, w) in (0u32..).zip(e.iter_mut()) {
            *w = self.regs.ram_read(base + k);
        }
        self.regs.write(ack, gi);
        Some(e)
    }
}

impl<R: FdcanRegs> Fdcan for RegFdcan<R> {
    fn rx_pop(&mut self) -> Option<[u32; 4]> {
        self.pop(Reg::Rxf0s, Reg::Rxf0a, layout::RX_FIFO0, RX_ELEMENTS)
    }

    fn rx_pop_fifo1(&mut self) -> Option<[u32; 4]> {
        self.pop(Reg::Rxf1s, Reg::Rxf1a, layout::RX_FIFO1, RX1_ELEMENTS)
    }

    fn rx_take_lost(&mut self) -> bool {
        let lost = self.regs.read(Reg::Ir) & (ir::RF0L | ir::RF1L);
        if lost == 0 {
            return false;
        }
        self.regs.write(Reg::Ir, lost); // write 1 to clear (only these)
        true
    }

    fn tx_pending(&self) -> u32 {
        self.regs.read(Reg::Txbrp)
    }

    fn tx_start(&mut self, slot: usize, element: &[u32; 4]) {
        if slot >= TX_SLOTS {
            return;
        }
        let base = layout::TX_BUFFERS + layout::ELEMENT_WORDS * slot as u32;
        for (w, v) in (base..).zip(element) {
            self.regs.ram_write(w, *v);
        }
        self.regs.write(Reg::Txbar, 1 << slot);
    }

    fn tx_fifo_put(&mut self, element: &[u32; 4]) -> bool {
        let s = self.regs.read(Reg::Txfqs);
        let put = txfqs::put(s);
        // Full, or a put index outside the FIFO's buffers (never in hardware): refused.
        if s & txfqs::FULL != 0
            || txfqs::free(s) == 0
            || !(TX_SLOTS as u32..(TX_SLOTS + TX_FIFO) as u32).contains(&put)
        {
            return false;
        }
        let base = layout::TX_BUFFERS + layout::ELEMENT_WORDS * put;
        for (w, v) in (base..).zip(element) {
            self.regs.ram_write(w, *v);
        }
        // The request of the put index's buffer advances the put index.
        self.regs.write(Reg::Txbar, 1 << put);
        true
    }

    fn tx_cancel(&mut self, mask: u32) {
        self.regs.write(Reg::Txbcr, mask);
    }

    fn protocol_status(&self) -> u32 {
        self.regs.read(Reg::Psr)
    }

    fn error_counters(&self) -> u32 {
        self.regs.read(Reg::Ecr)
    }

    fn in_init(&self) -> bool {
        self.regs.read(Reg::Cccr) & cccr::INIT != 0
    }

    fn take_ram_failure(&mut self) -> bool {
        let mraf = self.regs.read(Reg::Ir) & ir::MRAF;
        if mraf != 0 {
            self.regs.write(Reg::Ir, mraf); // write 1 to clear (only this)
        }
        let c = self.regs.read(Reg::Cccr);
        if c & cccr::ASM != 0 {
            // Restricted operation left: ASM may be cleared at any time (RM0433 §56.5.6);
            // nothing else changes.
            self.regs.write(Reg::Cccr, c & !(cccr::ASM | cccr::CSA));
        }
        mraf != 0 || c & cccr::ASM != 0
    }

    fn leave_init(&mut self) {
        // Only INIT changes (the protected bits are written back as they are).
        let c = self.regs.read(Reg::Cccr) & !(cccr::INIT | cccr::CCE | cccr::CSA);
        self.regs.write(Reg::Cccr, c);
    }

    #[inline(never)]
    fn leave_monitoring(&mut self) -> bool {
        // Only MON changes (a clock stop request is withdrawn).
        let c = self.regs.read(Reg::Cccr) & !(cccr::CSA | cccr::CSR);
        self.regs.write(Reg::Cccr, c & !cccr::MON);
        self.regs.read(Reg::Cccr) & cccr::MON == 0
    }

    #[inline(never)]
    fn restart(&mut self, monitoring: bool) -> bool {
        let c = self.regs.read(Reg::Cccr) & !(cccr::CSA | cccr::CSR);
        if c & cccr::INIT == 0 {
            return false;
        }
        // CCE (INIT reads set): RXF0S, RXF1S, TXFQS, TXBRP, … are reset from here on.
        self.regs.write(Reg::Cccr, c | cccr::CCE);
        let c = self.regs.read(Reg::Cccr) & !(cccr::CSA | cccr::CSR);
        if c & cccr::CCE == 0 {
            return false;
        }
        let mon = if monitoring { cccr::MON } else { 0 };
        self.regs.write(Reg::Cccr, (c & !cccr::MON) | mon);
        if self.regs.read(Reg::Cccr) & cccr::MON != mon {
            // Not in the mode asked for: stay off the bus (the caller's fallback).
            return true;
        }
        // INIT (and CCE with it) cleared, MON kept.
        self.regs
            .write(Reg::Cccr, (c & !(cccr::MON | cccr::INIT | cccr::CCE)) | mon);
        true
    }

    #[inline(never)]
    fn tx_fifo_owed(&self, k: usize) -> Option<[u32; 4]> {
        let first = TX_SLOTS as u32;
        let size = TX_FIFO as u32;
        let k = u32::try_from(k).ok().filter(|k| *k < size)?;
        // The get index is a FIFO buffer in hardware; anything else: nothing owed.
        let off = txfqs::get(self.regs.read(Reg::Txfqs))
            .checked_sub(first)
            .filter(|o| *o < size)?;
        let buffer = first + (off + k) % size;
        if self.regs.read(Reg::Txbrp) & (1 << buffer) == 0 {
            return None;
        }
        let base = layout::TX_BUFFERS + layout::ELEMENT_WORDS * buffer;
        let mut e = [0u32; 4];
        for (w, v) in (base..).zip(e.iter_mut()) {
            *v = self.regs.ram_read(w);
        }
        Some(e)
    }
}
