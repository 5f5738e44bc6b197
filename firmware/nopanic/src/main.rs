//! Link-time evidence that the board image's control cycle cannot panic. Never flashed, never
//! run: the proof is that it links.
//!
//! The panic handler calls `walk_control_path_can_panic`, a function defined nowhere. With
//! the release profile (fat LTO, opt-level 3, one codegen unit) and the linker's
//! `--gc-sections`, the handler, and with it that undefined symbol, stays in the image only if
//! some code of the image can reach a panic; then the link fails with
//! `undefined symbol: walk_control_path_can_panic`. `--features selftest-panic` adds one
//! reachable panic (the negative control: that build must fail); `--features diagnose` defines
//! the handler, so that the image links and the panics can be found in its disassembly (the
//! callers of `core::panicking::*`, `llvm-symbolizer -i` for the inlined source lines).
//!
//! # The whole board cycle (`--no-default-features`)
//!
//! `main` is the board's `main` (`board/src/main.rs`) from the node's construction on, with the
//! same per-cycle work, the same types, the board's own CAN adapter (`board/src/can.rs`) and
//! cycle bookkeeping (`board/src/cycle.rs`: overruns, statistics), both compiled into this crate
//! from the board's source:
//!
//! * `Node::<16>::new(walk_robot::NODE_CONFIG)` in a frame of its own, moved into a `static` by
//!   `cortex_m::singleton!` (the board's `place_node`); an error idles instead of panicking;
//! * per cycle: busy pin high, DWT CYCCNT, `node.poll(now_ms, &mut bus)`, busy pin low, the
//!   overrun test (cycles spent or TIM2's update flag already set), `cycle::Stats::record`
//!   (`node.note_overrun()`, the statistics window and its summary once per 200 cycles), the
//!   defmt warnings
//!   (`bus.counters()`), then the wait for the next TIM2 update while `bus.service()` moves
//!   frames between the FDCAN and the software FIFOs; `now_ms` advances by 5 per cycle;
//! * the CAN adapter is `can::FdcanBus` over the `fdcan` crate's driver of FDCAN1 (the register
//!   block and message RAM addresses the HAL gives it), so the frames the node receives are
//!   whatever the message RAM holds. TIM2, GPIOE and DWT are the PAC's / cortex-m's registers
//!   (volatile): the optimiser knows none of the inputs.
//!
//! Not here: the board's set-up (clocks, pins, the HAL's FDCAN and timer constructors). It
//! asserts on the hardware (the `fdcan` crate's `into_config_mode` checks the core's release
//! and endianness registers, the HAL's RCC `freeze` checks the clock tree): start-up code, not
//! the cycle. The configured FDCAN driver is read from memory instead (`stand_in`); the timer
//! and the busy pin are the PAC registers the HAL's `Timer::wait` / `is_irq_clear` and
//! `set_high` / `set_low` use.
//!
//! This build does not link today. The panics that remain are in libraries:
//!
//! * the `fdcan` 0.2.1 driver under the board's adapter: `Mailbox::new`'s `unreachable!()`
//!   (TX put index and RX FIFO get index read from the hardware, `& 3 == 3`), and
//!   `StandardFilterSlot::from(u8)` / `ExtendedFilterSlot::from(u8)` on the filter index of a
//!   received frame (panic above 27 / 7);
//! * defmt-rtt 1.3: every log call's `acquire`/`release` panics when the logger is taken
//!   reentrantly or released out of context (the board logs from `main` only).
//!
//! (`Node::poll` itself had one: `Deque::retain` of heapless 0.9, whose `expect`s and the
//! `assert!`s of `Deque::swap` the optimiser could not discharge; the node now prunes its
//! backlog with `pop_front`/`push_back`.)
//!
//! # The checked scope (default features: `scoped`)
//!
//! * `mock-can`: [`mock::VolatileBus`] instead of the FDCAN adapter: arbitrary received frames
//!   (`black_box`), arbitrary transmit outcome;
//! * `no-log`: the defmt calls (and defmt-rtt) left out.
//!
//! Everything else is the board cycle above, `Node::poll` included: frame decoding and
//! validation, every command with its re-plan (eq. 17, eq. 18, the window solver, shaping),
//! the gait's tick, the heartbeat supervision, the planning limit and the transmit backlog.
//! `tests/tests/nopanic.rs` builds the scope and the negative control on every `cargo test`;
//! the whole board cycle is its ignored test.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

#[path = "../../board/src/can.rs"]
#[cfg_attr(feature = "mock-can", allow(dead_code))]
mod can;
/// The board's cycle bookkeeping, compiled from its source.
#[path = "../../board/src/cycle.rs"]
mod cycle;
#[cfg(feature = "mock-can")]
mod mock;

use core::hint::black_box;

use cortex_m::peripheral::DWT;
use cortex_m_rt::entry;
#[cfg(not(feature = "no-log"))]
use defmt_rtt as _; // global logger over RTT, as on the board
use stm32h7xx_hal::pac;

use planner_core::gait::GaitError;
use planner_core::node::{Node, NodeConfig};

/// The board's adapter over FDCAN1.
#[cfg(not(feature = "mock-can"))]
type Bus = crate::can::FdcanBus<stand_in::Fdcan1>;
#[cfg(feature = "mock-can")]
use crate::mock::VolatileBus as Bus;

/// System clock \[Hz\] (the board's).
const SYSCLK_HZ: u32 = 480_000_000;
/// Control cycle \[Hz\] (5 ms).
const CYCLE_HZ: u32 = 200;
/// Control cycle \[ms\].
const CYCLE_MS: u32 = 1000 / CYCLE_HZ;
/// Core cycles in one control cycle.
const PERIOD_CYCLES: u32 = SYSCLK_HZ / CYCLE_HZ;
/// Footstep queue capacity of the node (the board's).
const QUEUE: usize = 16;

/// The only `unsafe` of this crate: what stands in for the hardware set-up, and the panic
/// handler. None of it ever runs (the image is only linked).
#[allow(unsafe_code)]
mod stand_in {
    #[cfg(not(feature = "mock-can"))]
    pub use fdcan1::*;

    #[cfg(not(feature = "mock-can"))]
    mod fdcan1 {
        use core::mem::MaybeUninit;

        use fdcan::{FdCan, NormalOperationMode};
        use stm32h7xx_hal::pac;

        /// FDCAN1 for the `fdcan` crate, at the addresses the HAL's `Can<FDCAN1>` gives it.
        pub struct Fdcan1;

        // SAFETY: the pointers are FDCAN1's register block and its message RAM (the HAL's
        // values); the image is never run.
        unsafe impl fdcan::Instance for Fdcan1 {
            const REGISTERS: *mut fdcan::RegisterBlock = pac::FDCAN1::ptr() as *mut _;
        }
        // SAFETY: as above.
        unsafe impl fdcan::message_ram::Instance for Fdcan1 {
            const MSG_RAM: *mut fdcan::message_ram::RegisterBlock = 0x4000_ac00 as *mut _;
        }

        /// Where the configured driver is read from.
        static CONFIGURED: MaybeUninit<FdCan<Fdcan1, NormalOperationMode>> = MaybeUninit::uninit();

        /// The FDCAN driver in normal operation, as the board's set-up leaves it, but read
        /// from memory (volatile): the only way to that mode is `into_config_mode`, whose
        /// hardware asserts are start-up code, and the check must not depend on what the
        /// configuration is.
        pub fn configured_fdcan1() -> FdCan<Fdcan1, NormalOperationMode> {
            // SAFETY: none needed: this image is never run. The volatile read only keeps the
            // optimiser from knowing the driver's configuration.
            unsafe { core::ptr::read_volatile(CONFIGURED.as_ptr()) }
        }
    }

    #[cfg(not(feature = "diagnose"))]
    extern "C" {
        /// Defined nowhere: referenced only if a panic is reachable, and then the link fails.
        fn walk_control_path_can_panic() -> !;
    }

    #[cfg(not(feature = "diagnose"))]
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        // SAFETY: never linked into a working image (see the crate docs).
        unsafe { walk_control_path_can_panic() }
    }

    /// `--features diagnose`: the image links even with panics, so that the callers of
    /// `core::panicking::*` can be read off its disassembly.
    #[cfg(feature = "diagnose")]
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        cortex_m::asm::udf()
    }
}

/// Builds the node and moves it into its `static`, as the board's `place_node` (which panics
/// if called twice; here `None`).
#[inline(never)]
fn place_node(cfg: NodeConfig) -> Result<Option<&'static mut Node<QUEUE>>, GaitError> {
    let node = Node::new(cfg)?;
    Ok(cortex_m::singleton!(: Node<QUEUE> = node))
}

/// Waits for the next TIM2 update, moving CAN frames meanwhile (the board's `wait_tick` with
/// the HAL's `Timer::wait` written out on the PAC).
fn wait_tick(tim2: &pac::TIM2, bus: &mut Bus) {
    loop {
        bus.service();
        if tim2.sr.read().uif().bit_is_set() {
            tim2.sr.modify(|_, w| w.uif().clear_bit());
            let _ = tim2.sr.read();
            let _ = tim2.sr.read();
            return;
        }
    }
}

/// Start-up failed (the board panics here): idle.
fn idle() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

#[entry]
fn main() -> ! {
    let Some(dp) = pac::Peripherals::take() else {
        idle()
    };
    #[cfg(not(feature = "mock-can"))]
    let mut bus = Bus::new(stand_in::configured_fdcan1());
    #[cfg(feature = "mock-can")]
    let mut bus = Bus::default();

    let cfg = walk_robot::NODE_CONFIG;
    let node = match place_node(cfg) {
        Ok(Some(n)) => n,
        Ok(None) | Err(_) => idle(),
    };

    let mut now_ms: u32 = 0;
    let mut stats = cycle::Stats::default();
    wait_tick(&dp.TIM2, &mut bus);
    loop {
        dp.GPIOE.bsrr.write(|w| w.bs1().set_bit()); // busy pin high
        let t0 = DWT::cycle_count();
        let report = node.poll(now_ms, &mut bus);
        let spent = DWT::cycle_count().wrapping_sub(t0);
        dp.GPIOE.bsrr.write(|w| w.br1().set_bit()); // busy pin low

        let late = spent > PERIOD_CYCLES || dp.TIM2.sr.read().uif().bit_is_set();
        let outcome = stats.record(node, &report, spent, late);
        #[cfg(not(feature = "no-log"))]
        if outcome.overrun {
            defmt::warn!(
                "overrun: cycle {=u32} took {=u32} cycles (slot {=u32}), {=u32} so far",
                node.cycles(),
                spent,
                PERIOD_CYCLES,
                stats.overruns
            );
        }
        #[cfg(not(feature = "no-log"))]
        if report.refused > 0 {
            defmt::warn!(
                "cycle {=u32}: {=u8} of {=u8} commands refused",
                node.cycles(),
                report.refused,
                report.received
            );
        }

        // The negative control: a panic the optimiser cannot rule out.
        #[cfg(feature = "selftest-panic")]
        {
            let table = black_box([0u8; 4]);
            black_box(table[black_box(now_ms) as usize]);
        }

        if let Some(w) = outcome.summary {
            let c = bus.counters();
            #[cfg(feature = "no-log")]
            black_box((w.mean(), w, c.rx_overruns, stats.overruns, outcome.overrun));
            #[cfg(not(feature = "no-log"))]
            defmt::info!(
                "cycles {=u32}: worst {=u32} mean {=u64} of {=u32}; rx {=u32} refused {=u32} tx {=u32}; overruns {=u32}; rx FIFO overruns {=u32}",
                node.cycles(),
                w.worst,
                w.mean(),
                PERIOD_CYCLES,
                w.received,
                w.refused,
                w.sent,
                stats.overruns,
                c.rx_overruns
            );
        }

        wait_tick(&dp.TIM2, &mut bus);
        now_ms = black_box(now_ms.wrapping_add(CYCLE_MS));
    }
}
