//! Start-up register accesses the HAL does not offer: the brown-out level (an option byte,
//! with the no-init word that remembers a failed change), the clock security system, the
//! free-running microsecond counter on TIM2, the IWDG's freeze while a debugger halts the
//! core, and the MPU regions (the guard below the stack, the external-memory background region).

#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;

use board_core::bor::{self, BorPlan, BorStatus};
use board_core::uninit::{self, NoInitWord};
use cortex_m::peripheral::DWT;
use stm32h7xx_hal::pac;

/// Option-byte keys (RM0433 §4.9.4).
const OPTKEY1: u32 = 0x0819_2A3B;
const OPTKEY2: u32 = 0x4C5D_6E7F;

/// The longest wait for an option-byte change \[core cycles\]: 3 s at the reset clock (HSI,
/// 64 MHz), ten times the ~300 ms reported for an STM32H743.
const OPT_WAIT_CYCLES: u32 = 192_000_000;
/// The same bound in polls of `OPT_BUSY` (each takes more than 3 cycles), should the cycle
/// counter not run.
const OPT_WAIT_POLLS: u32 = OPT_WAIT_CYCLES / 3;

struct Word(UnsafeCell<MaybeUninit<u32>>);
// SAFETY: read and written only by `ensure_bor_level`, once, at start-up, before anything
// else could touch it (no interrupts are enabled; the fault handler does not use it).
unsafe impl Sync for Word {}

/// Survives every reset but a power-on or a brown-out (DTCM keeps its contents; `.uninit` is
/// not zeroed): board-core's `bor` mark of an attempt to change the brown-out level, so that a
/// failed or interrupted change is not tried again at every boot. Written 0 before any read
/// after a loss of supply ([`prepare_bor_mark`]: ECC RAM).
#[link_section = ".uninit.BOR_MARK"]
static BOR_MARK: Word = Word(UnsafeCell::new(MaybeUninit::uninit()));

/// [`BOR_MARK`] as board-core's no-init word.
struct BorWord;

impl NoInitWord for BorWord {
    fn read(&self) -> u32 {
        // SAFETY: a `u32` has no invalid bit patterns; the word is 4-byte aligned RAM; see
        // `Word`.
        unsafe { core::ptr::read_volatile(BOR_MARK.0.get() as *const u32) }
    }
    fn write(&mut self, value: u32) {
        // SAFETY: as for `read`.
        unsafe { core::ptr::write_volatile(BOR_MARK.0.get() as *mut u32, value) }
    }
}

fn mark() -> u32 {
    BorWord.read()
}

fn set_mark(value: u32) {
    BorWord.write(value)
}

/// Writes the brown-out mark before anything reads it if the supply was lost (`rsr`: `RCC_RSR`
/// at start-up; board-core's `uninit::prepare`). Call it before [`ensure_bor_level`].
pub fn prepare_bor_mark(rsr: u32) {
    uninit::prepare(&mut BorWord, rsr);
}

/// The longest wait for `HSERDY` \[core cycles\]: 10 ms at the reset clock (HSI, 64 MHz), a
/// crystal's start-up being a few ms; well inside the 50 ms watchdog.
const HSE_WAIT_CYCLES: u32 = 640_000;

/// Starts the HSE (`HSEBYP` for an external clock, set while the HSE is off, then `HSEON`) and
/// waits for `HSERDY` at most [`HSE_WAIT_CYCLES`] (DWT, or as many polls should the counter
/// not run); `false` if it did not become ready. The HAL's clock set-up then finds it ready
/// (its own wait is unbounded). Call it with the DWT cycle counter running.
pub fn start_hse(rcc: &pac::RCC, bypass: bool) -> bool {
    if rcc.cr.read().hseon().is_off() {
        rcc.cr.modify(|_, w| w.hsebyp().bit(bypass));
    }
    rcc.cr.modify(|_, w| w.hseon().on());
    let t0 = DWT::cycle_count();
    let mut polls = 0u32;
    loop {
        if rcc.cr.read().hserdy().is_ready() {
            return true;
        }
        polls += 1;
        if DWT::cycle_count().wrapping_sub(t0) > HSE_WAIT_CYCLES || polls > HSE_WAIT_CYCLES {
            return false;
        }
    }
}

/// The brown-out level in force (`FLASH_OPTSR_CUR.BOR_LEV`).
pub fn bor_level(flash: &pac::FLASH) -> u8 {
    bor::level(flash.optsr_cur().read().bits())
}

/// Makes `FLASH_OPTSR.BOR_LEV` equal to `level` (0 off, 1 ≈ 2.1 V, 2 ≈ 2.4 V, 3 ≈ 2.7 V,
/// rising thresholds of the datasheet), board-core's `bor::plan` deciding: programs the option
/// byte only when it differs (so once per board: option bytes are flash and wear), and not
/// again after a failed or interrupted attempt until a power-on. Call it BEFORE the
/// independent watchdog starts (the change stalls the core for a long time; a watchdog reset
/// in the middle of it is what ST warns against), with the DWT cycle counter running (it
/// bounds the wait). The change's result is checked: `OPT_BUSY` clear within
/// [`OPT_WAIT_CYCLES`], `OPTCHANGEERR` clear, `BOR_LEV` the new level; a failure is left in
/// the no-init mark and reported, and the start-up goes on at the current level.
pub fn ensure_bor_level(flash: &pac::FLASH, level: u8) -> BorStatus {
    let level = level & 3;
    match bor::plan(bor_level(flash), level, mark()) {
        BorPlan::Keep => {
            set_mark(0);
            return BorStatus::Kept;
        }
        BorPlan::GiveUp(why) => {
            set_mark(bor::failure_mark(level, why));
            return BorStatus::NotRetried(why);
        }
        BorPlan::Program => {}
    }
    // A reset from here until the mark is replaced reads as an interrupted attempt.
    set_mark(bor::attempt_mark(level));
    if flash.optcr().read().optlock().bit_is_set() {
        // SAFETY: the documented unlock sequence of the option bytes.
        flash.optkeyr().write(|w| unsafe { w.bits(OPTKEY1) });
        // SAFETY: as above.
        flash.optkeyr().write(|w| unsafe { w.bits(OPTKEY2) });
    }
    // An error flag of an earlier change would read as this one's.
    flash.optccr().write(|w| w.clr_optchangeerr().set_bit());
    // OPTSR_PRG holds the current options after reset: only BOR_LEV changes.
    // SAFETY: a 2-bit field given a value in 0..=3.
    flash
        .optsr_prg()
        .modify(|_, w| unsafe { w.bor_lev().bits(level) });
    flash.optcr().modify(|_, w| w.optstart().set_bit());
    let t0 = DWT::cycle_count();
    let mut polls = 0u32;
    let timed_out = loop {
        if flash.optsr_cur().read().opt_busy().bit_is_clear() {
            break false;
        }
        polls += 1;
        if DWT::cycle_count().wrapping_sub(t0) > OPT_WAIT_CYCLES || polls > OPT_WAIT_POLLS {
            break true;
        }
    };
    let result = bor::outcome(flash.optsr_cur().read().bits(), timed_out, level);
    flash.optcr().modify(|_, w| w.optlock().set_bit());
    match result {
        Ok(()) => {
            set_mark(0);
            BorStatus::Programmed
        }
        Err(why) => {
            set_mark(bor::failure_mark(level, why));
            BorStatus::Failed(why)
        }
    }
}

/// Turns on the HSE clock security system (`RCC_CR.HSECSSON`): a failing HSE raises the NMI
/// (see `fault.rs`). Call it once the HSE is ready (after the HAL's `freeze`).
pub fn enable_css() {
    // SAFETY: one bit of RCC_CR, set once at start-up after the HAL's clock set-up, which
    // does not touch RCC_CR again; the bit can only be cleared by a reset.
    let rcc = unsafe { &*pac::RCC::ptr() };
    rcc.cr.modify(|_, w| w.hsecsson().set_bit());
}

/// Freezes the IWDG while a debugger halts the core (so that a breakpoint does not reset the
/// board; no effect without a debugger).
pub fn freeze_iwdg_in_debug(dbg: &pac::DBGMCU) {
    dbg.apb4fz1.modify(|_, w| w.dbg_iwdg1().set_bit());
}

/// TIM2, free-running from 0 to `u32::MAX` at 1 MHz (its clock `timer_hz`, a multiple of
/// 1 MHz, divided by the prescaler). The slot pacer reads it ([`now_us`]).
pub fn start_us_counter(tim2: &pac::TIM2, timer_hz: u32) {
    let prescaler = (timer_hz / 1_000_000).clamp(1, 65_536) - 1;
    tim2.cr1.modify(|_, w| w.cen().clear_bit());
    // SAFETY: a 16-bit prescaler value.
    tim2.psc.write(|w| unsafe { w.bits(prescaler) });
    tim2.arr.write(|w| w.bits(u32::MAX));
    tim2.egr.write(|w| w.ug().set_bit()); // load the prescaler, counter to 0
    tim2.sr.write(|w| w.uif().clear_bit());
    tim2.cr1.modify(|_, w| w.cen().set_bit());
}

/// The microsecond counter (TIM2's `CNT`).
pub fn now_us(tim2: &pac::TIM2) -> u32 {
    tim2.cnt.read().bits()
}

extern "C" {
    /// The bottom of the stack region (board/stack.x: 0x2000_0000, the start of the DTCM).
    static _stack_end: u32;
}

/// MPU region 1: board-core's [`ExternalMemoryGuard`](board_core::ExternalMemoryGuard), the
/// external-memory space 0x6000_0000-0xDFFF_FFFF (FMC, QUADSPI: nothing there on this board)
/// strongly ordered and inaccessible, so the Cortex-M7 never reads there speculatively (the
/// default map makes part of it Normal memory); the MPU on, the default map elsewhere.
pub fn guard_external_memory(mpu: &mut cortex_m::peripheral::MPU) {
    let guard = board_core::ExternalMemoryGuard::new();
    // SAFETY: the MPU's own registers through the owned peripheral; region 1 is otherwise
    // unused, and the addresses it closes hold nothing of the image's (no FMC or QUADSPI
    // memory is configured); the barriers make the map apply to what follows.
    unsafe {
        mpu.rnr.write(1);
        mpu.rbar.write(guard.rbar);
        mpu.rasr.write(guard.rasr);
        mpu.ctrl.write(board_core::StackGuard::CTRL);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

/// Makes the 64 KiB below the stack region inaccessible (board-core's
/// [`StackGuard`](board_core::StackGuard), MPU region 0, the default map elsewhere): a stack
/// overflow then faults precisely on its first store below 0x2000_0000 (MemManage, escalated to
/// HardFault, whose entry leaves the overflowed stack behind) instead of depending on what
/// the bus does with the reserved addresses there (an imprecise BusFault, later). `false` if
/// the stack region is not aligned for the guard (then nothing is changed).
pub fn guard_below_stack(mpu: &mut cortex_m::peripheral::MPU) -> bool {
    let bottom = core::ptr::addr_of!(_stack_end) as u32;
    let Some(guard) = board_core::StackGuard::below(bottom, 64 * 1024) else {
        return false;
    };
    // SAFETY: the MPU's own registers through the owned peripheral; region 0 is otherwise
    // unused (the HAL does not program the MPU; this image's other region, 1, does not
    // overlap it), only the 64 KiB below the
    // stack region (reserved addresses, nothing of the image's) become inaccessible, and the
    // barriers make the map apply to what follows.
    unsafe {
        mpu.rnr.write(0);
        mpu.rbar.write(guard.rbar);
        mpu.rasr.write(guard.rasr);
        mpu.ctrl.write(board_core::StackGuard::CTRL);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    true
}
