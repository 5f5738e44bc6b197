//! The entry of the fault handlers: a stack that has overflowed is left behind first.
//!
//! The images put the stack at the bottom of RAM (the board: the lower 64 KiB of the DTCM,
//! `_stack_start = 0x2001_0000` down to `_stack_end = 0x2000_0000`), so an overflow runs below
//! the first RAM address and faults on its first store instead of overwriting the node. The
//! fault is escalated to HardFault, whose exception entry cannot stack its frame there either
//! (a stacking error, `BFSR.STKERR`): the handler starts with the stack pointer below RAM.
//! A handler written in Rust saves registers first, faults again at HardFault priority, and
//! the core **locks up**: no safe state (the CAN output not silenced, no fault pin, no mark)
//! until the independent watchdog resets it tens of milliseconds later.
//!
//! [`fault_entry!`](crate::fault_entry) defines the exception vector (`HardFault` or
//! `NonMaskableInt`, the names cortex-m-rt's vector table links to) as a few instructions
//! that use no stack: the main stack pointer at the fault into `r0` (the handler's argument:
//! below `_stack_end` for an overflow), `_stack_start` (the top of the stack region, from the
//! linker script) into the main stack pointer, and a branch to the handler, a Rust
//! `extern "C" fn(u32) -> !` that then has the whole stack region. The entry also clears
//! `FPCCR.LSPACT`: the faulting code has usually used the FPU, so the hardware reserved room for
//! its floating-point registers in the exception frame and saves them lazily, at the handler's
//! first floating-point instruction, to `FPCAR`, an address in the abandoned (for an overflow:
//! inaccessible) stack; that deferred save would fault at HardFault priority, a lock-up. With
//! `LSPACT` clear the save is dropped (nothing returns to that context). The handler's type is
//! checked at compile time (a handler that returned would take an exception return from the
//! reset stack pointer). What the interrupted code
//! had on the stack is abandoned, which is all a handler that never returns needs (the
//! board's safe state ends in a reset). The QEMU image uses the same entry, and
//! `tests/tests/qemu.rs` overflows its stack on purpose: the handler reports, where a Rust
//! entry locks the emulated core up.

/// Defines exception vector `$vector` (`HardFault` or `NonMaskableInt`) as an entry that moves
/// the main stack pointer to `_stack_start`, drops a pending lazy floating-point save (for
/// cores with an FPU: every image of this project) and branches to `$handler`, an
/// `extern "C" fn(sp: u32) -> !` called with the main stack pointer at the fault (see the
/// [module docs](crate::fault_entry)). Replaces cortex-m-rt's
/// `#[exception]` for that vector; use it once per vector, in a module that allows
/// `unsafe_code` (it is `global_asm!`). Expands to nothing except on a bare-metal ARM target.
#[macro_export]
macro_rules! fault_entry {
    ($vector:ident => $handler:path) => {
        const _: extern "C" fn(u32) -> ! = $handler;
        #[cfg(all(target_arch = "arm", target_os = "none"))]
        ::core::arch::global_asm!(
            concat!(".section .HardFault.entry_", stringify!($vector), ",\"ax\",%progbits"),
            concat!(".global ", stringify!($vector)),
            concat!(".type ", stringify!($vector), ",%function"),
            ".thumb_func",
            concat!(stringify!($vector), ":"),
            "mrs r0, MSP",
            "movw r1, :lower16:_stack_start",
            "movt r1, :upper16:_stack_start",
            "msr MSP, r1",
            // FPCCR (0xE000_EF34): clear LSPACT, the pending lazy save into the old frame.
            "movw r2, #0xEF34",
            "movt r2, #0xE000",
            "ldr r3, [r2]",
            "bic r3, r3, #1",
            "str r3, [r2]",
            "isb",
            "b.w {handler}",
            concat!(".size ", stringify!($vector), ", . - ", stringify!($vector)),
            handler = sym $handler,
        );
    };
}

/// One PMSAv7 MPU region that makes `size` bytes below `stack_end` (the bottom of the stack
/// region) inaccessible: no access at any privilege, never executable (the images program it
/// as region 0, with the default memory map elsewhere, `PRIVDEFENA`, and the MPU off in
/// HardFault and NMI, `HFNMIENA` clear, so the fault handler is not stopped by it). A stack
/// overflow then faults on its first store below the stack, precisely (MemManage, escalated
/// to HardFault), whatever the memory map there is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StackGuard {
    /// `MPU_RBAR`: the region's base address (region number taken from `MPU_RNR`).
    pub rbar: u32,
    /// `MPU_RASR`: `XN`, `AP = 000` (no access), the size field, enabled.
    pub rasr: u32,
}

impl StackGuard {
    /// `MPU_CTRL` with the guard: enabled, `PRIVDEFENA`, `HFNMIENA` clear.
    pub const CTRL: u32 = 0b101;

    /// The guard of `size` bytes below `stack_end`; `None` unless `size` is a power of two
    /// from 32 B to 4 GiB and `stack_end` a multiple of it above it (the region must be
    /// aligned to its size).
    pub const fn below(stack_end: u32, size: u32) -> Option<StackGuard> {
        if size < 32 || !size.is_power_of_two() || stack_end % size != 0 || stack_end < size {
            return None;
        }
        Some(StackGuard {
            rbar: stack_end - size,
            rasr: (1 << 28) | ((size.trailing_zeros() - 1) << 1) | 1,
        })
    }
}

/// A PMSAv7 MPU **background region** over the external-memory space: the whole 4 GiB with
/// its eight 512 MiB subregions enabled only for 0x6000_0000-0xDFFF_FFFF (subregions 3-6:
/// the FMC banks and the QUADSPI window, where the STM32H743 has nothing this board uses),
/// no access at any privilege, never executable, strongly ordered. The Cortex-M7 may read
/// speculatively from any Normal memory of the default map, and the default map makes
/// 0x6000_0000-0x9FFF_FFFF Normal memory ("external RAM"): a speculative read there, with no
/// memory behind the FMC, can stall the bus matrix. Strongly-ordered no-access memory is never
/// read speculatively. The other subregions are disabled, so the default map
/// (`PRIVDEFENA`) applies there, and the region overlaps no other region of the images (the
/// stack guard lies in subregion 0). Programmed by the board as region 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExternalMemoryGuard {
    /// `MPU_RBAR`: the base address, 0 (region number taken from `MPU_RNR`).
    pub rbar: u32,
    /// `MPU_RASR`: `XN`, `AP = 000`, `TEX = 000`, `C = B = 0` (strongly ordered), `SRD`, the
    /// size field (4 GiB), enabled.
    pub rasr: u32,
}

impl ExternalMemoryGuard {
    /// First address the region covers (subregion 3).
    pub const START: u32 = 0x6000_0000;
    /// Last address the region covers (subregion 6's last byte).
    pub const END: u32 = 0xDFFF_FFFF;
    /// The subregion disable mask: 0, 1, 2 (code, SRAM, peripherals) and 7 (the system).
    const SRD: u32 = 0b1000_0111;

    /// The region.
    pub const fn new() -> ExternalMemoryGuard {
        ExternalMemoryGuard {
            rbar: 0,
            // XN (28), AP 000 (26:24), TEX 000 (21:19), S C B 0 (18:16), SRD (15:8),
            // SIZE 31 (5:1: 2^(31+1) = 4 GiB), ENABLE (0).
            rasr: (1 << 28) | (Self::SRD << 8) | (31 << 1) | 1,
        }
    }

    /// `true` if the region makes `addr` inaccessible (an enabled subregion).
    pub const fn covers(&self, addr: u32) -> bool {
        let subregion = addr >> 29;
        (self.rasr >> 8) & (1 << subregion) == 0
    }
}

impl Default for ExternalMemoryGuard {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::{ExternalMemoryGuard, StackGuard};

    #[test]
    fn the_external_memory_guard_covers_the_fmc_and_quadspi_space_only() {
        let g = ExternalMemoryGuard::new();
        assert_eq!(g.rbar, 0);
        assert_eq!(g.rasr, 0x1000_873F);
        // No access, never executable, strongly ordered (TEX = C = B = 0), 4 GiB.
        assert_eq!((g.rasr >> 24) & 7, 0);
        assert_eq!(g.rasr >> 28 & 1, 1);
        assert_eq!((g.rasr >> 16) & 0x3F, 0);
        assert_eq!(1u64 << (((g.rasr >> 1) & 0x1F) + 1), 1 << 32);
        // FMC banks 1-6 and the QUADSPI window: covered.
        for addr in [
            0x6000_0000,
            0x7000_0000,
            0x8000_0000,
            0x9000_0000,
            0xC000_0000,
        ] {
            assert!(g.covers(addr), "{addr:#x}");
        }
        assert!(g.covers(ExternalMemoryGuard::START));
        assert!(g.covers(ExternalMemoryGuard::END));
        // Flash, ITCM, DTCM, the stack guard, the SRAMs, the peripherals (FDCAN1, its message
        // RAM, RCC, GPIO) and the system space: the default map.
        for addr in [
            0x0000_0000,
            0x0800_0000,
            0x1FFF_0000,
            0x2000_0000,
            0x2400_0000,
            0x3800_0000,
            0x4000_A000,
            0x4000_AC00,
            0x5802_4400,
            0x5FFF_FFFF,
            0xE000_ED00,
        ] {
            assert!(!g.covers(addr), "{addr:#x}");
        }
        assert!(!g.covers(ExternalMemoryGuard::START - 1));
        assert!(!g.covers(ExternalMemoryGuard::END + 1));
    }

    #[test]
    fn the_guard_below_the_dtcm_stack_is_64_kib_no_access() {
        let g = StackGuard::below(0x2000_0000, 64 * 1024).unwrap();
        assert_eq!(g.rbar, 0x1FFF_0000);
        // XN (28), AP = 000 (26:24), SIZE = 15 (5:1: 2^(15+1) = 64 KiB), ENABLE (0).
        assert_eq!(g.rasr, 0x1000_001F);
        assert_eq!((g.rasr >> 24) & 7, 0);
        assert_eq!(1u64 << (((g.rasr >> 1) & 0x1F) + 1), 64 * 1024);
    }

    #[test]
    fn a_misaligned_or_odd_sized_guard_is_refused() {
        assert_eq!(StackGuard::below(0x2000_0100, 64 * 1024), None);
        assert_eq!(StackGuard::below(0x2000_0000, 48 * 1024), None);
        assert_eq!(StackGuard::below(0x2000_0000, 16), None);
        assert_eq!(StackGuard::below(0x8000, 64 * 1024), None);
        assert!(StackGuard::below(0x2000_0000, 32).is_some());
    }
}
