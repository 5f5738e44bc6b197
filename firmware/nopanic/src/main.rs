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
//! # The whole board cycle (default features)
//!
//! `main` is the board's `main` (`board/src/main.rs`) from the node's construction on, with the
//! same per-cycle work and the board's own code, compiled into this crate from its source
//! (`#[path]`) or taken from board-core:
//!
//! * the node's `static`, parked (`ParkedNode`) and configured in place by `ParkedNode::start`
//!   from `walk_robot::NODE_CONFIG` (the board's `place_node`); an error idles instead of
//!   panicking;
//! * the CAN link: board-core's `Link` (software queues, bus-off recovery, error counters,
//!   stale-frame replacement) over the board's `fdcan1::Fdcan1` (`board/src/fdcan1.rs`: the
//!   register and message-RAM accesses of FDCAN1), so the frames the node receives are
//!   whatever the message RAM holds and every register value is the hardware's;
//! * the slot pacer (board-core's `Pacer`) over the board's microsecond counter
//!   (`board/src/hw.rs`: TIM2's `CNT`);
//! * per cycle: `wait_slot` (`Link::service` until `Pacer::due`), `Node::set_link_health`
//!   with `Health::to_wire`, busy pin high, DWT CYCCNT, `node.poll(slot.now_ms, &mut bus)`,
//!   busy pin low, the overrun test (cycles spent or `Pacer::behind`), `cycle::Stats::record`
//!   (board-core's `cycle`), the watchdog feed (the HAL's `IndependentWatchdog::feed`: one
//!   write of `IWDG_KR`), and every defmt call of the board's loop through the board's logger
//!   (`board/src/logger.rs`: non-blocking RTT; its reentrancy is handled without panics), the
//!   summary's stack high-water mark (`board/src/stack.rs`) included.
//!
//! TIM2, GPIOE, IWDG, FDCAN1 and DWT are registers (volatile): the optimiser knows none of the
//! inputs.
//!
//! Not here: the board's set-up (clocks, pins, the HAL's and the `fdcan` crate's FDCAN
//! configuration, the option bytes): start-up code that asserts on the hardware (the `fdcan`
//! crate's `into_config_mode` checks the core's release and endianness registers, the HAL's RCC
//! `freeze` checks the clock tree), not the cycle; and the fault handlers (`board/src/fault.rs`:
//! register writes and a reset). Nor what is not a panic: stack overflow, integer overflow
//! (wraps in release builds), NaN.
//!
//! History: before the board's own FDCAN accesses, this build did not link: the `fdcan` 0.2.1
//! driver's `Mailbox::new` `unreachable!()` on hardware indices and its filter-slot
//! conversions, and defmt-rtt's reentrancy panics, were reachable; the check then covered a
//! scope without them, still available as `--features scoped` (`mock-can`: arbitrary frames
//! instead of the adapter; `no-log`: without the log calls).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

/// The board's FDCAN1 accesses, compiled from its source.
#[path = "../../board/src/fdcan1.rs"]
#[allow(dead_code)] // `layout` and `silence` are start-up and fault-handler code
mod fdcan1;
/// The board's start-up registers and microsecond counter, compiled from its source.
#[path = "../../board/src/hw.rs"]
#[allow(dead_code)] // only `now_us` is on the cycle's path
mod hw;
/// The board's logger, compiled from its source.
#[cfg(not(feature = "no-log"))]
#[path = "../../board/src/logger.rs"]
mod logger;
#[cfg(feature = "mock-can")]
mod mock;
/// The board's stack high-water mark, compiled from its source.
#[path = "../../board/src/stack.rs"]
#[allow(dead_code)] // `repaint_below_sp` is start-up code
mod stack;

use core::hint::black_box;

use board_core::{cycle, Pacer, ResetReason, Slot};
use cortex_m::peripheral::DWT;
use cortex_m_rt::entry;
use static_cell::ConstStaticCell;
use stm32h7xx_hal::pac;

use planner_core::gait::GaitError;
use planner_core::node::NodeConfig;
#[cfg(not(feature = "f32"))]
use walk_robot::{Gains as NodeGains, Node, ParkedNode, NODE_CONFIG};
// `--features f32`: the same cycle with the f32 node (the M4F image's).
#[cfg(feature = "f32")]
use walk_robot::{
    GainsF32 as NodeGains, NodeF32 as Node, ParkedNodeF32 as ParkedNode,
    NODE_CONFIG_F32 as NODE_CONFIG,
};

/// The node's scalar.
#[cfg(not(feature = "f32"))]
type Scalar = f64;
/// The node's scalar.
#[cfg(feature = "f32")]
type Scalar = f32;

/// The board's adapter over FDCAN1.
#[cfg(not(feature = "mock-can"))]
type Bus = board_core::Link<fdcan1::Fdcan1>;
#[cfg(feature = "mock-can")]
use crate::mock::VolatileBus as Bus;

/// System clock \[Hz\] (the board's).
const SYSCLK_HZ: u32 = 480_000_000;
/// Control cycle \[Hz\] (5 ms).
const CYCLE_HZ: u32 = 200;
/// Control cycle \[ms\].
const CYCLE_MS: u32 = 1000 / CYCLE_HZ;
/// Control cycle in ticks of the microsecond counter.
const PERIOD_US: u32 = 1_000_000 / CYCLE_HZ;
/// Core cycles in one control cycle.
const PERIOD_CYCLES: u32 = SYSCLK_HZ / CYCLE_HZ;
/// Footstep queue capacity of the node (the board's).
const QUEUE: usize = 16;

/// The only `unsafe` of this crate apart from the board's files: the panic handler. It never
/// runs (the image is only linked).
#[allow(unsafe_code)]
mod stand_in {
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

/// The node's `static`, parked (all zero bytes, .bss), as the board's.
static NODE: ConstStaticCell<ParkedNode<QUEUE>> = ConstStaticCell::new(ParkedNode::new(NodeGains));

/// Takes the node's `static` and configures it in place, as the board's `place_node` (which
/// panics if called twice; here `None`).
#[inline(never)]
fn place_node(cfg: NodeConfig<Scalar>) -> Result<Option<&'static mut Node<QUEUE>>, GaitError> {
    let Some(parked) = NODE.try_take() else {
        return Ok(None);
    };
    parked.start(cfg).map(Some)
}

/// The board's `wait_slot`.
fn wait_slot(tim2: &pac::TIM2, pacer: &mut Pacer, bus: &mut Bus) -> Slot {
    loop {
        bus.service();
        if let Some(slot) = pacer.due(hw::now_us(tim2)) {
            return slot;
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
    // The board reads RCC_RSR and its fault mark: any value.
    let reset = ResetReason::decode(dp.RCC.rsr.read().bits(), black_box(0));
    #[cfg(not(feature = "mock-can"))]
    let mut bus = Bus::new(fdcan1::Fdcan1::new());
    #[cfg(feature = "mock-can")]
    let mut bus = Bus::default();

    let cfg = NODE_CONFIG;
    let node = match place_node(cfg) {
        Ok(Some(n)) => n,
        Ok(None) | Err(_) => idle(),
    };

    let mut pacer = Pacer::new(
        hw::now_us(&dp.TIM2).wrapping_add(PERIOD_US),
        PERIOD_US,
        CYCLE_MS,
    );
    let mut stats = cycle::Stats::default();
    loop {
        let slot = wait_slot(&dp.TIM2, &mut pacer, &mut bus);
        node.set_link_health(bus.health().to_wire(reset, pacer.missed()));

        dp.GPIOE.bsrr.write(|w| w.bs1().set_bit()); // busy pin high
        let t0 = DWT::cycle_count();
        let report = node.poll(slot.now_ms, &mut bus);
        let spent = DWT::cycle_count().wrapping_sub(t0);
        dp.GPIOE.bsrr.write(|w| w.br1().set_bit()); // busy pin low

        let late = spent > PERIOD_CYCLES || pacer.behind(hw::now_us(&dp.TIM2));
        let outcome = stats.record(node, &report, spent, late);
        dp.IWDG.kr.write(|w| w.key().reset()); // the HAL's IndependentWatchdog::feed

        // The negative control: a panic the optimiser cannot rule out.
        #[cfg(feature = "selftest-panic")]
        {
            let table = black_box([0u8; 4]);
            black_box(table[black_box(slot.now_ms) as usize]);
        }

        #[cfg(feature = "no-log")]
        black_box((slot, outcome.overrun, stats.overruns, report.refused));
        #[cfg(not(feature = "no-log"))]
        {
            if slot.skipped > 0 {
                defmt::warn!(
                    "{=u32} slot(s) missed before slot {=u32} ({=u32} so far)",
                    slot.skipped,
                    slot.index,
                    pacer.missed()
                );
            }
            if outcome.overrun {
                defmt::warn!(
                    "overrun: cycle {=u32} took {=u32} cycles (slot {=u32}), {=u32} so far",
                    node.cycles(),
                    spent,
                    PERIOD_CYCLES,
                    stats.overruns
                );
            }
            if report.refused > 0 {
                defmt::warn!(
                    "cycle {=u32}: {=u8} of {=u8} commands refused",
                    node.cycles(),
                    report.refused,
                    report.received
                );
            }
        }
        if let Some(w) = outcome.summary {
            let h = bus.health();
            #[cfg(feature = "no-log")]
            black_box((w.mean(), w, h, stack::high_water()));
            #[cfg(not(feature = "no-log"))]
            defmt::info!(
                "cycles {=u32}: worst {=u32} mean {=u64} of {=u32}; rx {=u32} refused {=u32} tx {=u32}; overruns {=u32} missed {=u32}; TEC {=u8} REC {=u8} state {=u8} bus-offs {=u16} passive {=u16} rx lost {=u16} replaced {=u16}; log dropped {=u32}; loop stack {=u32} B",
                node.cycles(),
                w.worst,
                w.mean(),
                PERIOD_CYCLES,
                w.received,
                w.refused,
                w.sent,
                stats.overruns,
                pacer.missed(),
                h.tec,
                h.rec,
                h.state as u8,
                h.bus_offs,
                h.passive_episodes,
                h.rx_lost,
                h.replaced,
                logger::dropped(),
                stack::high_water()
            );
        }
    }
}
