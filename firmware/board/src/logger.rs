//! The board's defmt logger: RTT, **never blocking**, panic-free.
//!
//! defmt-rtt blocks when its channel is in blocking mode, and `probe-rs run` puts it there on
//! attach: after the probe detaches, the 1 KiB buffer fills and the next log call waits for
//! ever. This logger ignores the channel's mode flags: each log frame is staged whole
//! ([`STAGE`] bytes) and copied into the RTT ring only if it fits (board-core's `rtt`,
//! host-tested); otherwise it is dropped and counted ([`dropped`]), so the host decoder never sees a torn frame and the loop never
//! waits. A log call made while another is in progress (a fault handler, if one ever logged)
//! is dropped too, instead of defmt-rtt's panic.
//!
//! The control block is SEGGER's layout (`_SEGGER_RTT`, one up channel named `defmt`, no down
//! channel), which probe-rs finds by its symbol.

#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU32, Ordering};

use board_core::rtt::{self, Stage};

/// Bytes of the RTT ring.
const RING: usize = 1024;
/// Largest log frame (encoded); a longer one is dropped.
const STAGE: usize = 160;

#[repr(C)]
struct UpChannel {
    name: *const u8,
    buffer: *mut u8,
    size: u32,
    write: AtomicU32,
    read: AtomicU32,
    flags: AtomicU32,
}

#[repr(C)]
struct ControlBlock {
    id: [u8; 16],
    max_up: u32,
    max_down: u32,
    up: UpChannel,
}

// SAFETY: the pointers are to statics; the offsets are atomics; the rest is never written.
unsafe impl Sync for ControlBlock {}

/// Word-aligned, so that [`prepare_ring`] writes whole words (ECC RAM).
#[repr(C, align(4))]
struct Ring(UnsafeCell<[u8; RING]>);
// SAFETY: written only by the logger with interrupts disabled; read by the probe.
unsafe impl Sync for Ring {}

#[link_section = ".uninit.defmt-ring"]
static RING_BUF: Ring = Ring(UnsafeCell::new([0; RING]));

#[no_mangle]
static _SEGGER_RTT: ControlBlock = ControlBlock {
    id: *b"SEGGER RTT\0\0\0\0\0\0",
    max_up: 1,
    max_down: 0,
    up: UpChannel {
        name: c"defmt".as_ptr().cast(),
        buffer: RING_BUF.0.get() as *mut u8,
        size: RING as u32,
        write: AtomicU32::new(0),
        read: AtomicU32::new(0),
        flags: AtomicU32::new(0), // non-blocking; whatever a probe writes here is ignored
    },
};

struct State {
    busy: bool,
    nested: bool,
    restore_interrupts: bool,
    encoder: defmt::Encoder,
    stage: Stage<STAGE>,
}

struct Shared(UnsafeCell<State>);
// SAFETY: only touched between `acquire` and `release`, with interrupts disabled (one core).
unsafe impl Sync for Shared {}

static STATE: Shared = Shared(UnsafeCell::new(State {
    busy: false,
    nested: false,
    restore_interrupts: false,
    encoder: defmt::Encoder::new(),
    stage: Stage::new(),
}));

static DROPPED: AtomicU32 = AtomicU32::new(0);

/// Writes the whole ring (zeros, word by word) if the supply was lost (`rsr`: `RCC_RSR` at
/// start-up; board-core's `uninit::power_lost`): ECC RAM never written since power-on may
/// report an error when read (by the probe) or when a byte of it is written (a
/// read-modify-write of its word). Call it before the first log call.
// The no-panic check includes this module but not the start-up that calls this.
#[allow(dead_code)]
pub fn prepare_ring(rsr: u32) {
    if !board_core::uninit::power_lost(rsr) {
        return;
    }
    let words = RING_BUF.0.get() as *mut u32;
    for i in 0..RING / 4 {
        // SAFETY: `RING_BUF` is `RING` bytes, 4-byte aligned (`Ring`); word `i` < RING / 4 is
        // inside it; no log call has run yet (start-up, single-threaded).
        unsafe { core::ptr::write_volatile(words.add(i), 0) };
    }
}

/// Log frames dropped since start-up (ring full, frame too long, or nested).
pub fn dropped() -> u32 {
    DROPPED.load(Ordering::Relaxed)
}

/// Copies the staged frame into the ring if it fits whole (board-core's `rtt::commit`).
fn commit(stage: &Stage<STAGE>) {
    let up = &_SEGGER_RTT.up;
    let read = up.read.load(Ordering::Acquire) as usize;
    let write = up.write.load(Ordering::Relaxed) as usize;
    // SAFETY: interrupts are off and only this function writes the ring; the host reads only
    // the bytes between the read and write offsets, which `rtt::commit` does not touch, and
    // sees the new bytes only after the write offset is published (Release) below.
    let ring = unsafe { &mut *RING_BUF.0.get() };
    match stage
        .frame()
        .and_then(|f| rtt::commit(ring, read, write, f))
    {
        Some(at) => up.write.store(at as u32, Ordering::Release),
        None => {
            DROPPED.fetch_add(1, Ordering::Relaxed);
        }
    }
}

#[defmt::global_logger]
struct Logger;

// SAFETY: `acquire`/`release` bracket every frame with interrupts disabled, and a nested
// `acquire` (a fault handler interrupting a log call) only marks the frame as dropped.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        let active = cortex_m::register::primask::read().is_active();
        cortex_m::interrupt::disable();
        // SAFETY: interrupts are off: nothing else touches the state now.
        let st = unsafe { &mut *STATE.0.get() };
        if st.busy {
            st.nested = true;
            DROPPED.fetch_add(1, Ordering::Relaxed);
            return;
        }
        st.busy = true;
        st.restore_interrupts = active;
        st.stage.clear();
        let mut enc = core::mem::replace(&mut st.encoder, defmt::Encoder::new());
        enc.start_frame(|b| st.stage.push(b));
        st.encoder = enc;
    }

    unsafe fn flush() {}

    unsafe fn release() {
        // SAFETY: between `acquire` and `release`, interrupts are off.
        let st = unsafe { &mut *STATE.0.get() };
        if st.nested {
            st.nested = false;
            return;
        }
        let mut enc = core::mem::replace(&mut st.encoder, defmt::Encoder::new());
        enc.end_frame(|b| st.stage.push(b));
        st.encoder = enc;
        commit(&st.stage);
        st.busy = false;
        if st.restore_interrupts {
            // SAFETY: interrupts were enabled when the frame began.
            unsafe { cortex_m::interrupt::enable() };
        }
    }

    unsafe fn write(bytes: &[u8]) {
        // SAFETY: between `acquire` and `release`, interrupts are off.
        let st = unsafe { &mut *STATE.0.get() };
        if st.nested {
            return;
        }
        let mut enc = core::mem::replace(&mut st.encoder, defmt::Encoder::new());
        enc.write(bytes, |b| st.stage.push(b));
        st.encoder = enc;
    }
}
