//! The STM32H743 image: board set-up, then the CAN node in fixed 5 ms slots.
//!
//! * board settings ([`HSE`], [`CAN_BIT_TIMING`], [`BOR_LEVEL`], [`WATCHDOG_MS`]) at the top
//!   of this file;
//! * start-up: the reset reason (`RCC_RSR` and the fault handler's mark, [`fault`]; after a
//!   power-on or a brown-out every no-init word is written before it is read: ECC RAM), the
//!   brown-out level (an option byte, programmed once, BEFORE the watchdog runs: the change
//!   stalls the core for a long time; its result checked, a failure not retried until a
//!   power-on: [`hw::ensure_bor_level`]), the independent watchdog, the HSE (its ready wait
//!   bounded: [`hw::start_hse`]; a timeout is a fault with its own mark), then the clocks from
//!   the **HSE** through PLL1: 480 MHz at VOS0 on revision V silicon, 400 MHz at VOS1 on any
//!   other (`DBGMCU_IDC.REV_ID`, board-core's `ClockPlan`), the HSE clock security system on
//!   (its NMI is the safe state), I- and D-cache; PLL1Q = 80 MHz is the FDCAN kernel clock;
//! * FDCAN1 in classic CAN mode at 1 Mbit/s on the pins of a Nucleo-H743ZI's CN9 (PD0 = RX,
//!   PD1 = TX, AF9), configured by board-core's register code (`board_core::fdcan`: bit
//!   timing, message RAM layout, acceptance filters for exactly `ids::COMMANDS` with `ESTOP`
//!   into RX FIFO1 and the others into RX FIFO0, a global filter rejecting everything else),
//!   every configuration register and filter element read back before the node joins the
//!   bus ([`fdcan1::bring_up`]; if anything differs the node stays off the bus with the fault
//!   pin high, [`fault::off_bus`]); at run time [`fdcan1::Fdcan1`] behind board-core's
//!   [`Link`] adapter (`ESTOP` first, queues, bus-off recovery, error counters, stale frames
//!   replaced). The HAL only switches FDCAN's clocks on (RCC) and sets the pins;
//! * the loop is board-core's [`ControlLoop`] (`board_core::control`: the same cycle code the
//!   QEMU image and the no-panic check run) over the board's hardware ([`cycle_io`]: TIM2,
//!   DWT, IWDG; [`Busy`]; [`cycle_log`]: defmt);
//! * TIM2 counts microseconds, free-running over 32 bits; board-core's [`Pacer`] cuts it into
//!   5 ms slots. The loop waits for a slot (servicing the CAN meanwhile) and runs one
//!   [`Node::poll`] in it with the slot's time as `now_ms`; slots missed by a long overrun are
//!   counted (`LINK`) and skipped, so `now_ms` never lags the counter by a slot;
//! * DWT CYCCNT measures every cycle; a cycle is an overrun when it took longer than its slot
//!   or the next slot had already begun when it was done: counted by [`Node::note_overrun`]
//!   (`STATUS`);
//! * the watchdog is fed once per completed cycle (after the poll and its bookkeeping): a loop
//!   that hangs resets the MCU within [`WATCHDOG_MS`] (+8 % LSI tolerance) of its last
//!   completed cycle;
//! * each cycle the link health (TEC, REC, bus state, bus-off and error-passive counts), the
//!   reset reason and the missed slots go to the node ([`Node::set_link_health`]), which
//!   publishes them in `LINK` every 100 ms;
//! * PE1 (LD2 on the Nucleo-H743ZI) is held high while the node works, for a scope or a logic
//!   analyser (board-core's `BusyPin`); PB14 (LD3) is the fault pin;
//! * logging (defmt over [`logger`], never blocking) happens after the timed part of the
//!   cycle: warnings on overruns, missed slots and refusals, and a summary once a second.
//!
//! The node (`walk_robot::Node<16>`, ~14 KB: the gait's two plan windows; the preview gains
//! stay in flash, borrowed) is a `static` in .bss (DTCM), parked ([`ParkedNode`], every byte
//! zero) and configured in place at start-up by [`ParkedNode::start`] ([`place_node`]): nothing
//! of it is built on the stack, no `static mut` in this crate, no allocator. The
//! stack is the lower 64 KiB of the DTCM, below .data and .bss (board/stack.x), painted at
//! reset; its high-water mark is logged ([`stack`]).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod cycle_io;
mod cycle_log;
mod fault;
mod fdcan1;
mod hw;
mod logger;
mod stack;

use board_core::clock::ClockPlan;
use board_core::control::{BusyPin, ControlLoop, Io};
use board_core::fdcan::BitTiming;
use board_core::reset::MARK_HSE;
use board_core::{cycle, Link, Pacer};
use cortex_m::peripheral::DWT;
use cortex_m_rt::entry;
use stm32h7xx_hal::gpio::{Output, Pin, PushPull, Speed};
use stm32h7xx_hal::independent_watchdog::IndependentWatchdog;
use stm32h7xx_hal::rcc::rec::ResetEnable as _;
use stm32h7xx_hal::rcc::{rec, PllConfigStrategy};
use stm32h7xx_hal::rng::RngExt as _;
use stm32h7xx_hal::{pac, prelude::*};

use planner_core::gait::GaitError;
use planner_core::node::NodeConfig;
use static_cell::ConstStaticCell;
use walk_robot::{Gains, Node, ParkedNode};

use crate::fdcan1::Fdcan1;

/// The board's external clock (a board setting).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hse {
    /// An external clock signal on PH0 (OSC_IN), oscillator bypassed: the NUCLEO-H743ZI2's
    /// 8 MHz MCO from its ST-LINK (the board's default solder bridges).
    Bypass(u32),
    /// A crystal or resonator between PH0 and PH1 (a robot board).
    Crystal(u32),
}

/// The HSE of this board: NUCLEO-H743ZI2, ST-LINK MCO at 8 MHz. A robot board with a crystal:
/// `Hse::Crystal(its frequency)`; the PLL set-up below derives 480 MHz and 80 MHz from it.
pub const HSE: Hse = Hse::Bypass(8_000_000);
/// CAN nominal bit timing (a board setting: it must suit the bus's other nodes): 1 Mbit/s from
/// the 80 MHz FDCAN kernel clock (PLL1Q): prescaler 2 gives 40 time quanta per bit, 1 (sync) +
/// 34 + 5, sample point 35/40 = 87.5 %, SJW 5. A bus whose nodes sample elsewhere (e.g. 75 %
/// at 1 Mbit/s) needs `seg1`/`seg2` moved to match.
pub const CAN_BIT_TIMING: BitTiming = BitTiming {
    prescaler: 2,
    seg1: 34,
    seg2: 5,
    sjw: 5,
};
/// Brown-out reset level (`BOR_LEV`): 3 = about 2.7 V rising (datasheet VBOR3), for a 3.3 V
/// supply; programmed into the option bytes once if different (a failed change is not retried
/// until a power-on).
pub const BOR_LEVEL: u8 = 3;
/// Independent watchdog period \[ms\] (10 control cycles; LSI 32 kHz nominal, 29.76-33.6 kHz
/// over temperature: 47.6-53.8 ms).
pub const WATCHDOG_MS: u32 = 50;

/// FDCAN kernel clock (PLL1Q = VCO 960 MHz / 12) \[Hz\].
const FDCAN_KER_HZ: u32 = 80_000_000;
/// Control cycle \[Hz\] (5 ms).
const CYCLE_HZ: u32 = 200;
/// Control cycle \[ms\].
const CYCLE_MS: u32 = 1000 / CYCLE_HZ;
/// Control cycle in ticks of the microsecond counter.
const PERIOD_US: u32 = 1_000_000 / CYCLE_HZ;
/// Reads of the random number generator before the node gives up its start-up.
const RNG_TRIES: u32 = 8;
/// Footstep queue capacity of the node.
const QUEUE: usize = 16;
// A summary every second.
const _: () = assert!(cycle::SUMMARY_EVERY == CYCLE_HZ);

// The bit timing assumes exactly this kernel clock (checked at run time below too).
const _: () = assert!(CAN_BIT_TIMING.is_valid());
const _: () = assert!(CAN_BIT_TIMING.bit_rate(FDCAN_KER_HZ) == 1_000_000);

/// The busy pin: the HAL's push-pull output behind board-core's [`BusyPin`].
struct Busy<const P: char, const N: u8>(Pin<P, N, Output<PushPull>>);

impl<const P: char, const N: u8> BusyPin for Busy<P, N> {
    fn set_busy(&mut self, busy: bool) {
        if busy {
            self.0.set_high();
        } else {
            self.0.set_low();
        }
    }
}

/// The node's `static`: parked ([`ParkedNode`]: every byte zero, so it is in .bss, DTCM, and
/// costs no flash), configured once by [`place_node`].
static NODE: ConstStaticCell<ParkedNode<QUEUE>> = ConstStaticCell::new(ParkedNode::new(Gains));

/// Takes the node's `static` and configures it in place ([`ParkedNode::start`]): nothing of the
/// node's 14 KB is built on the stack. Not inlined: its frame is the start-up's only.
#[inline(never)]
fn place_node(cfg: NodeConfig) -> Result<&'static mut Node<QUEUE>, GaitError> {
    let Some(parked) = NODE.try_take() else {
        panic!("place_node called twice");
    };
    parked.start(cfg)
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        panic!("core peripherals taken twice");
    };
    let Some(dp) = pac::Peripherals::take() else {
        panic!("device peripherals taken twice");
    };

    // No speculative reads of the external-memory space (no memory behind the FMC).
    hw::guard_external_memory(&mut cp.MPU);
    // Nothing accessible below the stack: an overflow faults at once, into the safe state.
    let guarded = hw::guard_below_stack(&mut cp.MPU);
    // Why we started (before anything can reset again). After a power-on or a brown-out every
    // no-init word is written before it is read (ECC RAM): the fault mark here, then the BOR
    // mark and the logger's ring.
    let (reset, rsr) = fault::take_reset_reason(&dp.RCC);
    hw::prepare_bor_mark(rsr);
    logger::prepare_ring(rsr);
    // Cycle counter (the Cortex-M7's DWT has a software lock): it bounds the option-byte and
    // HSE waits.
    cp.DCB.enable_trace();
    DWT::unlock();
    cp.DWT.enable_cycle_counter();
    // The brown-out level BEFORE the watchdog: an option-byte change stalls the core for a
    // long time (~300 ms reported), and a watchdog reset in the middle of it is what ST warns
    // against. Bounded by its own wait; a failure is reported and not retried until a
    // power-on. Then the watchdog, so that every later start-up step is bounded by it.
    let bor = hw::ensure_bor_level(&dp.FLASH, BOR_LEVEL);
    hw::freeze_iwdg_in_debug(&dp.DBGMCU);
    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    watchdog.start(WATCHDOG_MS.millis());

    // The HSE first, bounded: one that does not become ready (no MCO, no crystal, or
    // `Hse::Bypass` on a board with a crystal) is a fault with its own mark (reset reason
    // `hse_not_ready`, the fault pin pulsed), not silent watchdog resets.
    if !hw::start_hse(&dp.RCC, matches!(HSE, Hse::Bypass(_))) {
        fault::fail_safe(MARK_HSE);
    }
    // 480 MHz needs voltage scale 0, which only revision V silicon has (board-core's
    // `ClockPlan`: other revisions run 400 MHz at VOS1), and a wide-range VCO: the PLL's
    // default ("normal") strategy stays in the 150-420 MHz medium range.
    let plan = ClockPlan::for_revision(ClockPlan::rev_id(dp.DBGMCU.idc.read().bits()));
    let pwr = dp.PWR.constrain();
    let pwrcfg = if plan.vos0 { pwr.vos0(&dp.SYSCFG) } else { pwr }.freeze();
    let rcc = match HSE {
        Hse::Bypass(hz) => dp.RCC.constrain().use_hse(hz.Hz()).bypass_hse(),
        Hse::Crystal(hz) => dp.RCC.constrain().use_hse(hz.Hz()),
    };
    let ccdr = rcc
        .pll1_strategy(PllConfigStrategy::Iterative)
        .sys_ck(plan.sysclk_hz.Hz())
        .pll1_q_ck(FDCAN_KER_HZ.Hz())
        .freeze(pwrcfg, &dp.SYSCFG);
    hw::enable_css();
    cp.SCB.enable_icache();
    cp.SCB.enable_dcache(&mut cp.CPUID);
    // The bit timing assumes exactly 80 MHz.
    match ccdr.clocks.pll1_q_ck() {
        Some(f) if f.raw() == FDCAN_KER_HZ => {}
        _ => panic!("PLL1Q is not 80 MHz: no CAN bit timing for it"),
    }

    let gpioe = dp.GPIOE.split(ccdr.peripheral.GPIOE);
    let mut busy = Busy(gpioe.pe1.into_push_pull_output());
    busy.set_busy(false);
    // The fault pin, low until `fault::fail_safe` raises it.
    let gpiob = dp.GPIOB.split(ccdr.peripheral.GPIOB);
    let mut fault_pin = gpiob.pb14.into_push_pull_output();
    fault_pin.set_low();

    // FDCAN1 on PD0 (RX) / PD1 (TX), classic CAN, 1 Mbit/s. The HAL: pins, and FDCAN's
    // kernel clock (PLL1Q), bus clock and reset (RCC); the rest is board-core's register
    // code (fdcan1.rs): configuration mode, bit timing, layout, filters, read-back, join.
    let gpiod = dp.GPIOD.split(ccdr.peripheral.GPIOD);
    let _can_pins = (
        gpiod.pd0.into_alternate::<9>().speed(Speed::VeryHigh),
        gpiod.pd1.into_alternate::<9>().speed(Speed::VeryHigh),
    );
    ccdr.peripheral
        .FDCAN
        .kernel_clk_mux(rec::FdcanClkSel::Pll1Q)
        .enable()
        .reset();
    watchdog.feed();
    let can = fdcan1::bring_up(dp.FDCAN1, &CAN_BIT_TIMING);

    defmt::info!(
        "reset: {=u8}; sysclk {=u32} Hz from HSE; BOR level {=u8}{=str}; CAN 1 Mbit/s on PD0/PD1 {=str}; stack guard {=bool}",
        reset as u8,
        ccdr.clocks.sys_ck().raw(),
        hw::bor_level(&dp.FLASH),
        bor.note(),
        if can.is_ok() { "joined" } else { "NOT joined" },
        guarded,
    );
    if let Some(why) = bor.failure() {
        defmt::warn!(
            "BOR level {=u8} not programmed: {=str}",
            BOR_LEVEL,
            why.name()
        );
    }
    if let Err(e) = can {
        fault::off_bus(&mut watchdog, e);
    }
    let mut bus = Link::new(Fdcan1::new());

    // The node's entropy: 32 bits of the true random number generator (its kernel clock from
    // PLL1Q, 80 MHz), so that every start-up draws another session epoch and first step
    // number (frames of an earlier start-up are then refused). A clock or seed error is tried
    // again ([`RNG_TRIES`] reads); a generator that gives nothing keeps the node off the bus
    // (`fault::no_entropy`): no stand-in value (a counter, a timer) is sure to differ from
    // an earlier start-up's.
    let mut rng = dp.RNG.constrain(
        ccdr.peripheral.RNG.kernel_clk_mux(rec::RngClkSel::Pll1Q),
        &ccdr.clocks,
    );
    let Some(entropy) = (0..RNG_TRIES).find_map(|_| rng.value().ok()) else {
        fault::no_entropy(&mut watchdog, RNG_TRIES)
    };
    let t0 = DWT::cycle_count();
    // (The constant configuration as it is, the entropy after: the compiler folds the one.)
    let node = match place_node(walk_robot::NODE_CONFIG) {
        Ok(n) => n,
        Err(e) => defmt::panic!("Node::new failed: {}", e),
    };
    let _ = node.set_entropy(entropy);
    watchdog.feed();
    defmt::info!(
        "node ready ({=usize} bytes) in {=u32} cycles; start-up stack {=u32} bytes",
        core::mem::size_of::<Node<QUEUE>>(),
        DWT::cycle_count().wrapping_sub(t0),
        stack::high_water()
    );
    // From here on the high-water mark is the control loop's.
    stack::repaint_below_sp();
    watchdog.feed();

    // The microsecond counter; slot 0 begins one period from now.
    ccdr.peripheral.TIM2.enable().reset();
    hw::start_us_counter(&dp.TIM2, ccdr.clocks.timx_ker_ck().raw());
    let pacer = Pacer::new(
        hw::now_us(&dp.TIM2).wrapping_add(PERIOD_US),
        PERIOD_US,
        CYCLE_MS,
    );
    let mut ctl = ControlLoop::new(
        Io {
            clock: cycle_io::Tim2Clock(dp.TIM2),
            counter: cycle_io::Dwt,
            watchdog: cycle_io::Iwdg(watchdog),
            busy,
            log: cycle_log::DefmtLog,
        },
        pacer,
        // Core cycles in one control cycle.
        plan.sysclk_hz / CYCLE_HZ,
        reset,
    );
    // board-core's control cycle: wait (servicing the link), link health, the timed poll, the
    // late decision, the statistics, the watchdog feed, then the log lines.
    loop {
        ctl.step(node, &mut bus);
    }
}
