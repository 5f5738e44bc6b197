//! The board's defmt logger: RTT, **never blocking**, panic-free.
//!
//! defmt-rtt blocks when its channel is in blocking mode, and `probe-rs run` puts it there on
//! attach: after the probe detaches, the 1 KiB buffer fills and the next log call waits for
//! ever. This logger ignores the channel's mode flags: each log frame is staged whole
//! ([`STAGE`] bytes) and copied into the RTT ring only if it fits; otherwise it is dropped and
//! counted ([`dropped`]), so the host decoder never sees a torn frame and the loop never
//! waits. A log call made while another is in progress (a fault handler, if one ever logged)
//! is dropped too, instead of defmt-rtt's panic.
//!
//! The control block is SEGGER's layout (`_SEGGER_RTT`, one up channel named `defmt`, no down
//! channel), which probe-rs finds by its symbol.

#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU32, Ordering};

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
    stage: [u8; STAGE],
    len: usize,
    overflow: bool,
}

struct Shared(UnsafeCell<State>);
// SAFETY: only touched between `acquire` and `release`, with interrupts disabled (one core).
unsafe impl Sync for Shared {}

static STATE: Shared = Shared(UnsafeCell::new(State {
    busy: false,
    nested: false,
    restore_interrupts: false,
    encoder: defmt::Encoder::new(),
    stage: [0; STAGE],
    len: 0,
    overflow: false,
}));

static DROPPED: AtomicU32 = AtomicU32::new(0);

/// Log frames dropped since start-up (ring full, frame too long, or nested).
pub fn dropped() -> u32 {
    DROPPED.load(Ordering::Relaxed)
}

fn stage(st: &mut State, bytes: &[u8]) {
    for &b in bytes {
        match st.stage.get_mut(st.len) {
            Some(slot) => {
                *slot = b;
                st.len += 1;
            }
            None => st.overflow = true,
        }
    }
}

/// Copies the staged frame into the ring if it fits whole.
fn commit(st: &State) {
    let up = &_SEGGER_RTT.up;
    let read = up.read.load(Ordering::Acquire) as usize % RING;
    let write = up.write.load(Ordering::Relaxed) as usize % RING;
    // One byte stays free to tell a full ring from an empty one.
    let free = (read + RING - write - 1) % RING;
    let frame = st.stage.get(..st.len).unwrap_or(&[]);
    if st.overflow || frame.len() > free {
        DROPPED.fetch_add(1, Ordering::Relaxed);
        return;
    }
    let base = RING_BUF.0.get() as *mut u8;
    let mut at = write;
    for &b in frame {
        // SAFETY: `at` < RING; the bytes between the write and read offsets are ours.
        unsafe { base.add(at).write_volatile(b) };
        at = (at + 1) % RING;
    }
    up.write.store(at as u32, Ordering::Release);
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
        st.len = 0;
        st.overflow = false;
        let mut enc = core::mem::replace(&mut st.encoder, defmt::Encoder::new());
        enc.start_frame(|b| stage(st, b));
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
        enc.end_frame(|b| stage(st, b));
        st.encoder = enc;
        commit(st);
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
        enc.write(bytes, |b| stage(st, b));
        st.encoder = enc;
    }
}
