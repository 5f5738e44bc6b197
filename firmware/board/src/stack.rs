//! The stack's high-water mark. cortex-m-rt's `paint-stack` fills the stack region
//! (`_stack_end` … `_stack_start`, the lower 64 KiB of the DTCM: board/stack.x) with
//! `STACK_PAINT_VALUE` at reset; [`high_water`] finds the lowest word that has lost it, and
//! [`repaint_below_sp`] paints the free part again, so that what follows is measured alone
//! (the board does it once the node is built: the summary then reports the control loop's own
//! high-water mark, not the frames that build the node).

#![allow(unsafe_code)]

use core::ptr::{addr_of, read_volatile, write_volatile};

extern "C" {
    // cortex-m-rt's linker script and board/stack.x.
    static _stack_start: u32;
    static _stack_end: u32;
}

/// Bytes of the stack used so far at most (from its top down to the lowest scrubbed word).
/// Reads the whole unused part (up to 64 KiB): call it outside the timed part, rarely.
pub fn high_water() -> u32 {
    let top = addr_of!(_stack_start) as usize;
    let bottom = addr_of!(_stack_end) as usize;
    let mut p = bottom;
    while p < top {
        // SAFETY: [bottom, top) is the stack region of the linker script (DTCM, mapped and
        // clocked from reset), 4-byte aligned (link.x asserts it); a read has no side effect.
        let word = unsafe { read_volatile(p as *const u32) };
        if word != cortex_m_rt::STACK_PAINT_VALUE {
            break;
        }
        p += 4;
    }
    (top - p) as u32
}

/// Paints the stack again from its bottom up to a little below the stack pointer. Call it from
/// `main` between phases, with no interrupt handler that could use the stack below `sp`.
#[inline(never)]
pub fn repaint_below_sp() {
    // Margin for this function's own frame and what the compiler keeps below it.
    const MARGIN: usize = 256;
    let bottom = addr_of!(_stack_end) as usize;
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = bottom;
    while p + MARGIN < sp {
        // SAFETY: [bottom, sp - MARGIN) is stack below the stack pointer: reserved for the
        // stack, 4-byte aligned, holding no live data (thread mode; the only handlers are the
        // fault handlers, which never return).
        unsafe { write_volatile(p as *mut u32, cortex_m_rt::STACK_PAINT_VALUE) };
        p += 4;
    }
}
