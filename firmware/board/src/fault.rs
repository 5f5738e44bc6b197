//! The safe state: what HardFault, an unexpected interrupt, a panic and the clock security
//! system's NMI all do, the reset reason read at start-up, and the state of a board whose
//! CAN configuration did not read back ([`off_bus`]).
//!
//! HardFault and the NMI enter through `board_core::fault_entry!`, which first moves the stack
//! pointer back to the top of the stack region (a stack overflow leaves none).
//!
//! [`fail_safe`]: interrupts off; FDCAN1 into its initialisation state with every pending TX
//! buffer cancelled (the node falls silent on the bus at once: recessive, no error frames,
//! no stale references); the fault pin (PB14 = LD3, red, on the NUCLEO-H743ZI2;
//! configured by `main`) high; a mark in a no-init RAM word saying why; about 20 ms so that the pin
//! is seen; then a system reset. After the reset the mark and `RCC_RSR` give the reason the
//! node publishes (`LINK`), and the fault pin is low again (GPIO reset).
//!
//! The IWDG is not stopped: if the reset request itself failed, the watchdog resets the MCU.
//!
//! [`off_bus`]: the same signals without the reset: FDCAN1 held in its initialisation state,
//! the fault pin high, the mark left (a later software reset reads as `fault`), one error line,
//! the watchdog fed. A configuration that reads back wrong is not transient;
//! resetting would only repeat the start-up at its own rate, and the node could publish
//! nothing either way.

#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;

use board_core::fdcan::BringUpError;
use board_core::reset::{MARK_CLOCK, MARK_FAULT};
use board_core::ResetReason;
use cortex_m_rt::exception;
use stm32h7xx_hal::independent_watchdog::IndependentWatchdog;
use stm32h7xx_hal::pac;

use crate::fdcan1;

/// Core cycles the fault pin stays high before the reset (20 ms at 480 MHz; longer if the
/// clock has fallen back to the 64 MHz HSI).
const HOLD_CYCLES: u32 = 9_600_000;

struct Mark(UnsafeCell<MaybeUninit<u32>>);
// SAFETY: written only by `fail_safe` (interrupts off, never returns) and read/cleared once by
// `take_reset_reason` at start-up before anything else runs.
unsafe impl Sync for Mark {}

/// Survives a system reset (DTCM keeps its contents; `.uninit` is not zeroed by the start-up
/// code); garbage after a power-on, which `ResetReason::decode` never reads as a fault.
#[link_section = ".uninit.FAULT_MARK"]
static MARK: Mark = Mark(UnsafeCell::new(MaybeUninit::uninit()));

/// Why the MCU started; clears the reset flags and the mark. Call it once, first thing.
pub fn take_reset_reason(rcc: &pac::RCC) -> ResetReason {
    let rsr = rcc.rsr.read().bits();
    // SAFETY: a `u32` has no invalid bit patterns; the word is 4-byte aligned in RAM; no other
    // code runs yet.
    let mark = unsafe { core::ptr::read_volatile(MARK.0.get() as *const u32) };
    // SAFETY: as above.
    unsafe { core::ptr::write_volatile(MARK.0.get() as *mut u32, 0) };
    rcc.rsr.modify(|_, w| w.rmvf().clear());
    ResetReason::decode(rsr, mark)
}

/// Core cycles between two feeds of the watchdog in [`off_bus`] (10 ms at 480 MHz).
const FEED_CYCLES: u32 = 4_800_000;

/// CAN output off, fault pin high, `mark` left in the no-init word.
fn signal(mark: u32) {
    fdcan1::silence();
    // SAFETY: a single write of the port's set/reset register (bit-set only: no other pin
    // changes); GPIOB's clock is on and PB14 is a push-pull output since start-up.
    unsafe { (*pac::GPIOB::ptr()).bsrr.write(|w| w.bs14().set_bit()) };
    // SAFETY: see `MARK`; nothing reads it before the next start-up.
    unsafe { core::ptr::write_volatile(MARK.0.get() as *mut u32, mark) };
}

/// Silences the CAN output, raises the fault pin, leaves `mark` and resets the MCU.
pub fn fail_safe(mark: u32) -> ! {
    cortex_m::interrupt::disable();
    signal(mark);
    cortex_m::asm::delay(HOLD_CYCLES);
    cortex_m::peripheral::SCB::sys_reset()
}

/// FDCAN1's bring-up failed (`err`): the node does not join the bus. CAN output off, fault
/// pin high, the fault mark left, one error line (the RTT ring keeps it for a probe that
/// attaches later); then, for ever, the watchdog fed (no reset loop). Call it once the fault
/// pin is configured.
pub fn off_bus(watchdog: &mut IndependentWatchdog, err: BringUpError) -> ! {
    signal(MARK_FAULT);
    let (what, detail) = err.describe();
    defmt::error!(
        "FDCAN1 configuration did not read back ({=str}, {=u32:#x}): off the bus",
        what,
        detail
    );
    loop {
        cortex_m::asm::delay(FEED_CYCLES);
        watchdog.feed();
    }
}

// HardFault and the clock security system's NMI enter through board-core's `fault_entry!`:
// the main stack pointer is moved back to the top of the stack region before any Rust code
// runs, so a stack overflow (a fault below 0x2000_0000, with no stack left for the handler's
// frame) reaches the safe state instead of locking the core up until the watchdog bites.
board_core::fault_entry!(HardFault => hard_fault);
board_core::fault_entry!(NonMaskableInt => clock_failure);

/// HardFault (any fault: none of the configurable ones is enabled, so all escalate here),
/// stack overflow included (`_sp`, the stack pointer at the fault, is then below 0x2000_0000).
extern "C" fn hard_fault(_sp: u32) -> ! {
    fail_safe(MARK_FAULT)
}

/// An interrupt nobody enabled: treated as a fault.
#[exception]
unsafe fn DefaultHandler(_irqn: i16) {
    fail_safe(MARK_FAULT)
}

/// The clock security system's NMI: the HSE failed and the hardware switched the system clock
/// to the HSI (the PLLs, and with them the FDCAN kernel clock, stop). The node cannot keep its
/// bit timing: safe state and reset (the next start-up waits for the HSE; if it never comes
/// back, the IWDG resets the MCU every watchdog period and the node stays off the bus).
extern "C" fn clock_failure(_sp: u32) -> ! {
    fail_safe(MARK_CLOCK)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    fail_safe(MARK_FAULT)
}
