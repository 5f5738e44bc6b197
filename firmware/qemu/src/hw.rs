//! The two hardware accesses of the QEMU image, and its only `unsafe` code: the CMSDK APB
//! timer's registers (volatile MMIO) and the stack's paint (read back, painted again).

// The crate denies unsafe code; this module is the audited exception.
#![allow(unsafe_code)]

use core::ptr::{addr_of, read_volatile, write_volatile};
use core::sync::atomic::{AtomicBool, Ordering};

/// CMSDK APB timer 0 of the MPS2 board (QEMU `hw/arm/mps2.c`).
const TIMER0_BASE: usize = 0x4000_0000;
/// Control: bit 0 enables the counter.
const CTRL: usize = 0x00;
/// Current value (counts down at the timer's clock, reloads from RELOAD after 0).
const VALUE: usize = 0x04;
/// Reload value.
const RELOAD: usize = 0x08;

/// The timer's clock: the board's SYSCLK \[Hz\].
pub const TIMER_HZ: u32 = 25_000_000;

static TAKEN: AtomicBool = AtomicBool::new(false);

/// CMSDK timer 0 as a free-running 32-bit counter (wraps after 2³² / 25 MHz ≈ 172 s).
pub struct Timer0 {
    _private: (),
}

impl Timer0 {
    /// The timer, once.
    pub fn take() -> Option<Self> {
        if TAKEN.swap(true, Ordering::AcqRel) {
            None
        } else {
            Some(Self { _private: () })
        }
    }

    fn write(&mut self, offset: usize, value: u32) {
        // SAFETY: TIMER0_BASE + offset is a 32-bit register of the CMSDK timer, which exists
        // on every MPS2 machine of QEMU; `&mut self` (a singleton) serialises the accesses.
        unsafe { write_volatile((TIMER0_BASE + offset) as *mut u32, value) }
    }

    fn read(&self, offset: usize) -> u32 {
        // SAFETY: as in `write`; reading VALUE has no side effect.
        unsafe { read_volatile((TIMER0_BASE + offset) as *const u32) }
    }

    /// Starts counting down from `u32::MAX`, reloading `u32::MAX`, no interrupt.
    pub fn start_free_running(&mut self) {
        self.write(CTRL, 0);
        self.write(RELOAD, u32::MAX);
        self.write(VALUE, u32::MAX);
        self.write(CTRL, 1);
    }

    /// Timer ticks since the start (modulo 2³²): an up-counter.
    pub fn count(&self) -> u32 {
        !self.read(VALUE)
    }
}

extern "C" {
    // The stack region (qemu/memory.x sets both: the `STACK` region below `RAM`): the stack
    // grows down from `_stack_start` to `_stack_end`; with the `paint-stack` feature the reset
    // handler fills that range with STACK_PAINT_VALUE before `main`.
    static _stack_start: u32;
    static _stack_end: u32;
}

/// The stack's high-water mark: `(used, size)` in bytes, `used` from the top of the stack
/// down to the lowest word that no longer holds the paint.
pub fn stack_usage() -> (usize, usize) {
    let top = addr_of!(_stack_start) as usize;
    let bottom = addr_of!(_stack_end) as usize;
    let mut p = bottom;
    while p < top {
        // SAFETY: [bottom, top) is RAM reserved for the stack by the linker script, aligned to
        // 4 bytes (link.x asserts it); reading a word there has no side effect.
        let word = unsafe { read_volatile(p as *const u32) };
        if word != cortex_m_rt::STACK_PAINT_VALUE {
            break;
        }
        p += 4;
    }
    (top - p, top - bottom)
}

/// Paints the free part of the stack again (from its bottom up to a little below the present
/// stack pointer), so that [`stack_usage`] then measures the high-water mark of what runs from
/// now on. Called from `main`'s frame between phases (after building the node, before the
/// control loop); nothing lives below the stack pointer (no interrupts are enabled).
#[inline(never)]
pub fn repaint_stack() {
    // Margin for this function's own frame and anything the compiler keeps below it.
    const MARGIN: usize = 256;
    let bottom = addr_of!(_stack_end) as usize;
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = bottom;
    while p + MARGIN < sp {
        // SAFETY: [bottom, sp - MARGIN) is stack below the stack pointer: reserved for the
        // stack by the linker script, 4-byte aligned, and holding no live data (thread mode, no
        // interrupt handler can run and use it).
        unsafe { write_volatile(p as *mut u32, cortex_m_rt::STACK_PAINT_VALUE) };
        p += 4;
    }
}

/// Makes the 64 KiB below the stack region (`_stack_end` = 0x2000_0000) inaccessible with
/// board-core's [`StackGuard`](board_core::StackGuard), as the board does: QEMU's MPS2 machines
/// map memory (or nothing that faults) there, so without it a stack overflow would run on
/// silently. Instruction counts are not affected (QEMU counts instructions, and the MPU adds
/// none to the code). `false` if the stack region is not aligned for the guard.
pub fn guard_below_stack() -> bool {
    const MPU_CTRL: usize = 0xE000_ED94;
    const MPU_RNR: usize = 0xE000_ED98;
    const MPU_RBAR: usize = 0xE000_ED9C;
    const MPU_RASR: usize = 0xE000_EDA0;
    let Some(guard) = board_core::StackGuard::below(addr_of!(_stack_end) as u32, 64 * 1024) else {
        return false;
    };
    // SAFETY: the architectural MPU registers of the Cortex-M (PMSAv7, present on QEMU's M7
    // and M4 cores); region 0 is otherwise unused, and only the 64 KiB below the stack region,
    // which holds nothing of the image's, becomes inaccessible. The barriers make the new map
    // apply to what follows.
    unsafe {
        write_volatile(MPU_RNR as *mut u32, 0);
        write_volatile(MPU_RBAR as *mut u32, guard.rbar);
        write_volatile(MPU_RASR as *mut u32, guard.rasr);
        write_volatile(MPU_CTRL as *mut u32, board_core::StackGuard::CTRL);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    true
}

// HardFault enters through the board's entry (board-core's `fault_entry!`): the stack pointer
// is moved back to the top of the stack region before any Rust code runs, so a stack overflow
// (the stack running below 0x2000_0000 into the MPU guard, `guard_below_stack`) reaches the
// handler instead of locking the core up. `tests/tests/qemu.rs` overflows the stack on purpose (`-append
// overflow`) and expects the `FAULT` line.
board_core::fault_entry!(HardFault => hard_fault);

/// A fault prints a `FAULT hardfault sp=… overflow=…` line (`overflow=1`: the stack pointer
/// at the fault was below the stack region; with the faulting code's `pc` and `lr` when its
/// exception frame was stacked inside the stack region), then runs the board's safe state,
/// board-core's `safe_state::fail_safe`, over QEMU stand-ins ([`QemuSafeState`]: each step
/// prints a `SAFE step=…` line, the reset ends the run with exit code 1) instead of
/// cortex-m-rt's default endless loop, which would only show as a timeout.
extern "C" fn hard_fault(sp: u32) -> ! {
    // SAFETY: FPCCR (0xE000_EF34), an architectural register of the FPU; reading it has no
    // side effect. Bit 0 (LSPACT) must be clear: the entry dropped the lazy save into the
    // abandoned stack (`lspact=` below, checked by the test).
    let lspact = unsafe { read_volatile(0xE000_EF34 as *const u32) } & 1;
    let top = addr_of!(_stack_start) as usize;
    let bottom = addr_of!(_stack_end) as usize;
    let sp = sp as usize;
    if (bottom..top.saturating_sub(32)).contains(&sp) {
        // SAFETY: the 8-word exception frame at `sp` lies inside the stack region (checked),
        // 4-byte aligned (the hardware stacks it so); reading it has no side effect.
        let (lr, pc) = unsafe {
            (
                read_volatile((sp + 20) as *const u32),
                read_volatile((sp + 24) as *const u32),
            )
        };
        cortex_m_semihosting::hprintln!(
            "FAULT hardfault sp={:#010x} overflow=0 lspact={} pc={:#010x} lr={:#010x}",
            sp,
            lspact,
            pc,
            lr
        );
    } else {
        cortex_m_semihosting::hprintln!(
            "FAULT hardfault sp={:#010x} overflow={} lspact={}",
            sp,
            u8::from(sp < bottom),
            lspact
        );
    }
    board_core::safe_state::fail_safe(&mut QemuSafeState, board_core::reset::MARK_FAULT)
}

/// The safe state's steps on the QEMU image: the MPS2 board has no CAN, no fault pin and no
/// reset mark, so each step prints what it stands for (`SAFE step=tx_recessive`,
/// `SAFE step=mark mark=0x…`, `SAFE step=fault_pin`, `SAFE step=fdcan`, the mark again
/// without its "unfinished" flag, `SAFE step=reset`), in the order board-core calls them; the reset ends the run with exit code 1.
/// `tests/tests/qemu.rs` checks the order after a stack overflow.
struct QemuSafeState;

impl board_core::safe_state::SafeStateHw for QemuSafeState {
    fn can_tx_recessive(&mut self) {
        cortex_m_semihosting::hprintln!("SAFE step=tx_recessive");
    }
    fn write_mark(&mut self, mark: u32) {
        cortex_m_semihosting::hprintln!("SAFE step=mark mark={:#010x}", mark);
    }
    fn raise_fault_pin(&mut self) {
        cortex_m_semihosting::hprintln!("SAFE step=fault_pin");
    }
    fn silence_fdcan(&mut self) -> bool {
        cortex_m_semihosting::hprintln!("SAFE step=fdcan");
        true
    }
    fn reset(&mut self) -> ! {
        cortex_m_semihosting::hprintln!("SAFE step=reset");
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::wfi();
        }
    }
}
