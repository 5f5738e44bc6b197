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
//! `extern "C" fn(u32) -> !` that then has the whole stack region. What the interrupted code
//! had on the stack is abandoned, which is all a handler that never returns needs (the
//! board's safe state ends in a reset). The QEMU image uses the same entry, and
//! `tests/tests/qemu.rs` overflows its stack on purpose: the handler reports, where a Rust
//! entry locks the emulated core up.

/// Defines exception vector `$vector` (`HardFault` or `NonMaskableInt`) as an entry that moves
/// the main stack pointer to `_stack_start` and branches to `$handler`, an
/// `extern "C" fn(sp: u32) -> !` called with the main stack pointer at the fault (see the
/// [module docs](crate::fault_entry)). Replaces cortex-m-rt's
/// `#[exception]` for that vector; use it once per vector, in a module that allows
/// `unsafe_code` (it is `global_asm!`). Expands to nothing except on a bare-metal ARM target.
#[macro_export]
macro_rules! fault_entry {
    ($vector:ident => $handler:path) => {
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
            "isb",
            "b.w {handler}",
            concat!(".size ", stringify!($vector), ", . - ", stringify!($vector)),
            handler = sym $handler,
        );
    };
}
