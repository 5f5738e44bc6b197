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
//! * per cycle: board-core's `ControlLoop::step` (`board_core::control`, the board's own loop
//!   body), over the board's hardware types (`board/src/cycle_io.rs`: TIM2's `CNT` as the
//!   clock, DWT CYCCNT, the HAL's `IndependentWatchdog::feed`, one write of `IWDG_KR`) and its
//!   log lines (`board/src/cycle_log.rs`): the wait (`Link::service` until `Pacer::due`),
//!   `Node::set_link_health` with `Health::to_wire`, busy pin high (here PE1's `BSRR`
//!   directly: the HAL's pin needs the clock set-up), DWT CYCCNT, the poll, busy pin low, the
//!   overrun test (cycles spent or `Pacer::behind`), `cycle::Stats::record`, the watchdog
//!   feed, and every defmt call of the board's loop through the board's logger
//!   (`board/src/logger.rs`: non-blocking RTT; its reentrancy is handled without panics), the
//!   summary's stack high-water mark (`board/src/stack.rs`) included.
//!
//! TIM2, GPIOE, IWDG, FDCAN1 and DWT are registers (volatile): the optimiser knows none of the
//! inputs.
//!
//! Not here: the board's set-up (clocks, pins, FDCAN1's bring-up with its read-back, the option
//! bytes): start-up code, some of which asserts on the hardware (the HAL's RCC `freeze` checks
//! the clock tree), not the cycle; and the fault handlers (`board/src/fault.rs`:
//! register writes and a reset). Nor what is not a panic: stack overflow, integer overflow
//! (wraps in release builds), NaN.
//!
//! A narrower scope is available as `--features scoped` (`mock-can`: arbitrary frames instead
//! of the adapter; `no-log`: without the log calls), for when a dependency brings a reachable
//! panic (as the `fdcan` 0.2.1 driver's `Mailbox::new` `unreachable!()` on hardware indices
//! and defmt-rtt's reentrancy panics do; the board uses neither).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

/// The board's hardware behind board-core's control-cycle traits, compiled from its source.
#[path = "../../board/src/cycle_io.rs"]
mod cycle_io;
/// The board's log lines of the control cycle, compiled from its source.
#[cfg(not(feature = "no-log"))]
#[path = "../../board/src/cycle_log.rs"]
mod cycle_log;
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

use board_core::control::{BusyPin, ControlLoop, Io};
use board_core::{Pacer, ResetReason};
use cortex_m_rt::entry;
use static_cell::ConstStaticCell;
use stm32h7xx_hal::independent_watchdog::IndependentWatchdog;
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

/// The busy pin, PE1, by its `BSRR` (the board drives it through the HAL's pin, which needs
/// the clock set-up this image leaves out: the same single store).
struct Pe1(pac::GPIOE);

impl BusyPin for Pe1 {
    fn set_busy(&mut self, busy: bool) {
        if busy {
            self.0.bsrr.write(|w| w.bs1().set_bit());
        } else {
            self.0.bsrr.write(|w| w.br1().set_bit());
        }
    }
}

/// The log sink: the board's (defmt through its logger).
#[cfg(not(feature = "no-log"))]
type Log = cycle_log::DefmtLog;
/// `no-log`: every log call's arguments to `black_box` instead.
#[cfg(feature = "no-log")]
type Log = black_box_log::BlackBoxLog;

#[cfg(feature = "no-log")]
mod black_box_log {
    use board_core::control::{LogSink, SummaryLine};
    use board_core::Slot;
    use core::hint::black_box;

    /// Opaque log calls (the scoped check's: no logger).
    #[derive(Default)]
    pub struct BlackBoxLog;

    impl LogSink for BlackBoxLog {
        fn missed_slots(&mut self, slot: &Slot, total: u32) {
            black_box((slot, total));
        }
        fn overrun(&mut self, cycle: u32, spent: u32, period: u32, total: u32) {
            black_box((cycle, spent, period, total));
        }
        fn refused(&mut self, cycle: u32, refused: u8, received: u8) {
            black_box((cycle, refused, received));
        }
        fn summary(&mut self, line: &SummaryLine) {
            black_box((line, line.window.mean(), crate::stack::high_water()));
        }
    }
}

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

    let pacer = Pacer::new(
        hw::now_us(&dp.TIM2).wrapping_add(PERIOD_US),
        PERIOD_US,
        CYCLE_MS,
    );
    let mut ctl = ControlLoop::new(
        Io {
            clock: cycle_io::Tim2Clock(dp.TIM2),
            counter: cycle_io::Dwt,
            watchdog: cycle_io::Iwdg(IndependentWatchdog::new(dp.IWDG)),
            busy: Pe1(dp.GPIOE),
            log: Log::default(),
        },
        pacer,
        PERIOD_CYCLES,
        reset,
    );
    loop {
        // board-core's control cycle, as the board runs it.
        let run = ctl.step(node, &mut bus);

        // The negative control: a panic the optimiser cannot rule out.
        #[cfg(feature = "selftest-panic")]
        {
            let table = black_box([0u8; 4]);
            black_box(table[black_box(run.slot.now_ms) as usize]);
        }
        #[cfg(not(feature = "selftest-panic"))]
        black_box(run.spent);
    }
}
