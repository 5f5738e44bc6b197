//! The safe state: what HardFault, an unexpected interrupt, a panic and the clock security
//! system's NMI all do, the reset reason read at start-up, and the state of a board whose
//! CAN configuration did not read back ([`off_bus`]).
//!
//! HardFault and the NMI enter through `board_core::fault_entry!`, which first moves the stack
//! pointer back to the top of the stack region (a stack overflow leaves none).
//!
//! [`fail_safe`]: interrupts off, then board-core's `safe_state::fail_safe` over the board's
//! pins and registers ([`BoardSafeState`]), in this order: PD1 (FDCAN1 TX) taken from the
//! FDCAN as a GPIO push-pull output driven recessive (high), which silences the node even
//! when the FDCAN's kernel clock is gone (a clock-security failure stops PLL1Q, and `INIT` or
//! `TXBCR` writes then never take effect); a mark in a no-init RAM word saying why, flagged
//! "unfinished"; the fault pin (PB14 = LD3, red, on the NUCLEO-H743ZI2) high; only then
//! FDCAN1 into its initialisation state with every pending TX buffer cancelled (should that
//! access fault again, the output, the mark and the pin are already set), and the mark's flag
//! cleared if that step ended cleanly; then a system reset at once (no
//! hold: after a clock failure the core runs from the 64 MHz HSI, and a delay there would
//! outlast the 50 ms watchdog and the reason would read "watchdog"). After the reset the mark
//! and `RCC_RSR` give the reason the node publishes (`LINK`); the pins are back in their reset
//! state (the fault pin low). The order is board-core's, host-tested
//! (`board-core/tests/safe_state.rs`).
//!
//! **A second fault in the FDCAN step.** The step runs at fault priority (`FAULTMASK`, which
//! the HardFault and NMI handlers have anyway) with `SCB_CCR.BFHFNMIGN` set: a data bus fault
//! of its loads and stores is ignored instead of locking the core up. The step then checks
//! the bus fault status (`CFSR.BFSR`, cleared before it) and that FDCAN1 answered (`ENDN`):
//! if not, the mark keeps its "unfinished" flag and the reset that follows at once reads as
//! `nested_fault`. Any other fault there (not a data access of the step) still locks the core
//! up; the independent watchdog resets it, and the flag in the mark turns that watchdog reset
//! into `nested_fault` too (board-core's `ResetReason::decode`). Outside the fault handlers
//! (the off-bus state) `FAULTMASK` and `BFHFNMIGN` are restored after the step.
//!
//! The IWDG is not stopped: if the reset request itself failed, the watchdog resets the MCU.
//!
//! [`off_bus`]: the same signals without the reset: PD1 recessive, FDCAN1 held in its
//! initialisation state, the fault pin high, the mark left (a later software reset reads as
//! `fault`), an error line every second, the watchdog fed. A configuration that reads back
//! wrong is not transient; resetting would only repeat the start-up at its own rate, and the
//! node could publish nothing either way.

#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;

use board_core::fdcan::BringUpError;
use board_core::reset::{MARK_CLOCK, MARK_FAULT};
use board_core::safe_state::{self, SafeStateHw};
use board_core::uninit::{self, NoInitWord};
use board_core::ResetReason;
use cortex_m_rt::exception;
use stm32h7xx_hal::independent_watchdog::IndependentWatchdog;
use stm32h7xx_hal::pac;

use crate::fdcan1;

struct Mark(UnsafeCell<MaybeUninit<u32>>);
// SAFETY: written only by `fail_safe` (interrupts off, never returns) and read/cleared once by
// `take_reset_reason` at start-up before anything else runs.
unsafe impl Sync for Mark {}

/// Survives a system reset (DTCM keeps its contents; `.uninit` is not zeroed by the start-up
/// code); after a power-on or a brown-out it is written before it is read (ECC RAM:
/// board-core's `uninit`).
#[link_section = ".uninit.FAULT_MARK"]
static MARK: Mark = Mark(UnsafeCell::new(MaybeUninit::uninit()));

/// [`MARK`] as board-core's no-init word.
struct MarkWord;

impl NoInitWord for MarkWord {
    fn read(&self) -> u32 {
        // SAFETY: a `u32` has no invalid bit patterns; the word is 4-byte aligned in RAM; see
        // `Mark` for who accesses it when.
        unsafe { core::ptr::read_volatile(MARK.0.get() as *const u32) }
    }
    fn write(&mut self, value: u32) {
        // SAFETY: as for `read`.
        unsafe { core::ptr::write_volatile(MARK.0.get() as *mut u32, value) }
    }
}

/// Why the MCU started, and `RCC_RSR` as it was; clears the reset flags and the mark (after a
/// power-on or a brown-out the mark is written before it is read: board-core's
/// `uninit::take`). Call it once, first thing.
pub fn take_reset_reason(rcc: &pac::RCC) -> (ResetReason, u32) {
    let rsr = rcc.rsr.read().bits();
    let mark = uninit::take(&mut MarkWord, rsr);
    rcc.rsr.modify(|_, w| w.rmvf().clear());
    (ResetReason::decode(rsr, mark), rsr)
}

/// Core cycles between two feeds of the watchdog in [`off_bus`] (10 ms at 480 MHz, 12 ms at
/// 400 MHz).
const FEED_CYCLES: u32 = 4_800_000;

/// `RCC_AHB4ENR`: the clocks of GPIOB (bit 1) and GPIOD (bit 3).
const AHB4ENR_GPIOB_GPIOD: u32 = (1 << 1) | (1 << 3);
/// PD1: FDCAN1 TX.
const CAN_TX_PIN: u32 = 1;
/// PB14: the fault pin.
const FAULT_PIN: u32 = 14;
/// `SCB_CCR.BFHFNMIGN`: handlers at priority -1 and -2 ignore data bus faults.
const CCR_BFHFNMIGN: u32 = 1 << 8;
/// `SCB_CFSR`'s bus fault status (`BFSR`, bits 15:8).
const CFSR_BFSR: u32 = 0xFF00;

/// Makes pin `n` of `port` a push-pull output driven high: the level first (`BSRR`), then the
/// output type and the mode, so that it is high from the moment it is an output.
fn drive_high(port: &pac::gpioa::RegisterBlock, n: u32) {
    // SAFETY: `BSRR` sets only pin `n`'s output bit; `OTYPER` and `MODER` change only pin
    // `n`'s bits (read-modify-write with interrupts off, the fault path being the only code
    // running). Every value is a valid bit pattern of these registers.
    unsafe {
        port.bsrr.write(|w| w.bits(1 << n));
        port.otyper.modify(|r, w| w.bits(r.bits() & !(1 << n)));
        port.moder
            .modify(|r, w| w.bits((r.bits() & !(0b11 << (2 * n))) | (0b01 << (2 * n))));
    }
}

/// The board's side of board-core's safe state: PD1, the no-init mark, PB14, FDCAN1, the
/// system reset.
struct BoardSafeState;

impl SafeStateHw for BoardSafeState {
    fn can_tx_recessive(&mut self) {
        // SAFETY: RCC_AHB4ENR gets the two GPIO clocks set (nothing cleared), so that the pins
        // can be driven even from a fault before `main` configured them; then PD1 leaves
        // FDCAN1 (its alternate function) for a GPIO output driven high: recessive at the
        // transceiver.
        let rcc = unsafe { &*pac::RCC::ptr() };
        // SAFETY: setting clock-enable bits only.
        rcc.ahb4enr
            .modify(|r, w| unsafe { w.bits(r.bits() | AHB4ENR_GPIOB_GPIOD) });
        // The clock takes effect some bus cycles after the write (RM0433: a read of the enable
        // register back before the peripheral is accessed); the GPIO writes come after it.
        let _ = rcc.ahb4enr.read().bits();
        // SAFETY: GPIOD's register block at its fixed address; see `drive_high`.
        drive_high(unsafe { &*pac::GPIOD::ptr() }, CAN_TX_PIN);
    }

    fn write_mark(&mut self, mark: u32) {
        // Nothing reads it before the next start-up.
        MarkWord.write(mark);
    }

    fn raise_fault_pin(&mut self) {
        // SAFETY: GPIOB's register block at its fixed address (clock on since
        // `can_tx_recessive`); see `drive_high`.
        drive_high(unsafe { &*pac::GPIOB::ptr() }, FAULT_PIN);
    }

    fn silence_fdcan(&mut self) -> bool {
        let was_masked = cortex_m::register::faultmask::read().is_active();
        // SAFETY: the System Control Block's CCR and CFSR at their fixed address. CCR gets
        // BFHFNMIGN set (a data bus fault at priority -1 or -2 is ignored, not a lock-up);
        // CFSR's bus fault bits are write-1-to-clear (cleared so that only this step's count).
        // `cpsid f` raises the priority to -1 (HardFault's: a panic or an unexpected interrupt
        // comes here at thread or interrupt priority); ignored in the NMI, already at -2.
        let scb = unsafe { &*cortex_m::peripheral::SCB::PTR };
        let ccr = scb.ccr.read();
        unsafe {
            scb.ccr.write(ccr | CCR_BFHFNMIGN);
            scb.cfsr.write(CFSR_BFSR);
            core::arch::asm!("cpsid f", options(nomem, nostack, preserves_flags));
        }
        cortex_m::asm::dsb();
        cortex_m::asm::isb();
        let answered = fdcan1::silence();
        // Buffered writes complete: an imprecise bus fault of the step is recorded by now.
        cortex_m::asm::dsb();
        let faulted = scb.cfsr.read() & CFSR_BFSR != 0;
        if !was_masked {
            // SAFETY: back to the priority and the CCR this code was entered with (the
            // off-bus state, which goes on running).
            unsafe {
                core::arch::asm!("cpsie f", options(nomem, nostack, preserves_flags));
                scb.ccr.write(ccr);
            }
        }
        answered && !faulted
    }

    fn reset(&mut self) -> ! {
        cortex_m::peripheral::SCB::sys_reset()
    }
}

/// Silences the CAN output, leaves `mark`, raises the fault pin, stops FDCAN1 and resets the
/// MCU at once (board-core's `safe_state::fail_safe`).
pub fn fail_safe(mark: u32) -> ! {
    cortex_m::interrupt::disable();
    safe_state::fail_safe(&mut BoardSafeState, mark)
}

/// Feeds of the watchdog in [`off_bus`] between two error lines (one a second).
const FEEDS_PER_LINE: u32 = 100;

/// FDCAN1's bring-up failed (`err`): the node does not join the bus. CAN output off (PD1
/// recessive, FDCAN1 in `INIT`), fault pin high, the fault mark left (board-core's
/// `safe_state::signal`); then, for ever, the watchdog fed every 10 ms (no reset loop) and an
/// error line every second (the RTT ring keeps the latest for a probe that attaches later).
pub fn off_bus(watchdog: &mut IndependentWatchdog, err: BringUpError) -> ! {
    let (what, detail) = err.describe();
    stay_off_bus(
        watchdog,
        "FDCAN1 configuration did not read back",
        what,
        detail,
    )
}

/// The random number generator gave no value (`detail`: the attempts): without one of its
/// own, a start-up would repeat an earlier start-up's session epoch, and a controller's log
/// recorded before this start-up could be taken. The node does not start: off the bus as
/// [`off_bus`] (the robot stands; nothing of this start-up can be replayed later).
pub fn no_entropy(watchdog: &mut IndependentWatchdog, detail: u32) -> ! {
    stay_off_bus(
        watchdog,
        "the random number generator failed",
        "no session epoch",
        detail,
    )
}

/// Off the bus for ever, saying why every second (see [`off_bus`]).
fn stay_off_bus(watchdog: &mut IndependentWatchdog, why: &str, what: &str, detail: u32) -> ! {
    safe_state::signal(&mut BoardSafeState, MARK_FAULT);
    let mut feeds = 0u32;
    loop {
        if feeds == 0 {
            defmt::error!("{=str} ({=str}, {=u32:#x}): off the bus", why, what, detail);
            feeds = FEEDS_PER_LINE;
        }
        feeds -= 1;
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
