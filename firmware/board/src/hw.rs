//! Start-up register accesses the HAL does not offer: the brown-out level (an option byte),
//! the clock security system, the free-running microsecond counter on TIM2, the IWDG's
//! freeze while a debugger halts the core, and the MPU guard below the stack.

#![allow(unsafe_code)]

use stm32h7xx_hal::pac;

/// Option-byte keys (RM0433 §4.9.4).
const OPTKEY1: u32 = 0x0819_2A3B;
const OPTKEY2: u32 = 0x4C5D_6E7F;

/// Makes `FLASH_OPTSR.BOR_LEV` equal to `level` (0 off, 1 ≈ 2.1 V, 2 ≈ 2.4 V, 3 ≈ 2.7 V,
/// rising thresholds of the datasheet). Programs the option byte only when it differs (so
/// once per board: option bytes are flash and wear); `true` if it did.
pub fn ensure_bor_level(flash: &pac::FLASH, level: u8) -> bool {
    let level = level & 3;
    if flash.optsr_cur().read().bor_lev().bits() == level {
        return false;
    }
    if flash.optcr().read().optlock().bit_is_set() {
        // SAFETY: the documented unlock sequence of the option bytes.
        flash.optkeyr().write(|w| unsafe { w.bits(OPTKEY1) });
        // SAFETY: as above.
        flash.optkeyr().write(|w| unsafe { w.bits(OPTKEY2) });
    }
    // OPTSR_PRG holds the current options after reset: only BOR_LEV changes.
    // SAFETY: a 2-bit field given a value in 0..=3.
    flash
        .optsr_prg()
        .modify(|_, w| unsafe { w.bor_lev().bits(level) });
    flash.optcr().modify(|_, w| w.optstart().set_bit());
    // Bounded by the independent watchdog, which runs already.
    while flash.optsr_cur().read().opt_busy().bit_is_set() {}
    flash.optcr().modify(|_, w| w.optlock().set_bit());
    true
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
    // unused (neither the HAL nor this image programs the MPU), only the 64 KiB below the
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
