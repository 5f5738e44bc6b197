//! The STM32H743 image: board set-up, then the CAN node at a fixed 5 ms cycle.
//!
//! * clocks: 480 MHz system clock (VOS0, rev V silicon), I- and D-cache on; PLL1Q = 80 MHz is
//!   the FDCAN kernel clock;
//! * FDCAN1 in classic CAN mode at 1 Mbit/s on the pins of a Nucleo-H743ZI's CN9 (PD0 = RX,
//!   PD1 = TX, AF9), behind `embedded_can::nb::Can` ([`can::FdcanBus`]); the acceptance
//!   filters take exactly the node's command identifiers ([`ids::COMMANDS`], standard data
//!   frames) into RX FIFO0 and reject every other frame in hardware ([`COMMAND_FILTERS`]);
//! * TIM2 overflows every 5 ms: the loop waits for it (servicing the CAN FIFOs meanwhile) and
//!   runs one [`Node::poll`] per overflow, never two: a late cycle still publishes its
//!   reference once, and the next one starts at the next overflow;
//! * DWT CYCCNT measures every cycle; a cycle is an overrun when it took longer than its 5 ms
//!   slot or the next overflow had already happened when it was done. It is logged (defmt)
//!   and counted by [`Node::note_overrun`], so the node's `STATUS` frame reports it;
//! * PE1 (LD2 on the Nucleo-H743ZI) is held high while the node works, for a scope or a logic
//!   analyser (through embedded-hal 1.0's `OutputPin`);
//! * once a second a summary (worst and mean cycle, overruns, frames) goes out over RTT.
//!
//! The node (`Node<16>`, ~47 KB: the gait's two plan windows and preview gains) is built once
//! in a function of its own and moved into a `static` in .bss (DTCM) by
//! `cortex_m::singleton!`: no `static mut` in this crate, no allocator.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod can;
mod cycle;

use core::convert::Infallible;
use core::num::{NonZeroU16, NonZeroU8};

use cortex_m::peripheral::DWT;
use cortex_m_rt::entry;
use defmt_rtt as _; // global logger over RTT
use embedded_hal::digital::{ErrorType, OutputPin};
use fdcan::config::{FrameTransmissionConfig, GlobalFilter, NominalBitTiming};
use fdcan::filter::{
    Action, ExtendedFilter, ExtendedFilterSlot, FilterType, StandardFilter, STANDARD_FILTER_MAX,
};
use fdcan::id::StandardId;
use panic_probe as _; // panics print through defmt, then the core halts
use stm32h7xx_hal::can::CanExt as _;
use stm32h7xx_hal::gpio::{Output, Pin, PushPull, Speed};
use stm32h7xx_hal::rcc::{rec, PllConfigStrategy};
use stm32h7xx_hal::timer::Timer;
use stm32h7xx_hal::{pac, prelude::*};

use planner_core::gait::GaitError;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::ids;

use crate::can::FdcanBus;

/// System clock \[Hz\].
const SYSCLK_HZ: u32 = 480_000_000;
/// FDCAN kernel clock (PLL1Q = VCO 960 MHz / 12) \[Hz\].
const FDCAN_KER_HZ: u32 = 80_000_000;
/// Control cycle \[Hz\] (5 ms).
const CYCLE_HZ: u32 = 200;
/// Control cycle \[ms\].
const CYCLE_MS: u32 = 1000 / CYCLE_HZ;
/// Core cycles in one control cycle.
const PERIOD_CYCLES: u32 = SYSCLK_HZ / CYCLE_HZ;
/// Footstep queue capacity of the node.
const QUEUE: usize = 16;
// A summary every second.
const _: () = assert!(cycle::SUMMARY_EVERY == CYCLE_HZ);

/// Standard-id filter elements of FDCAN1 (all of them, so none is left as it was): element
/// `i` accepts exactly identifier `ids::COMMANDS[i]` into RX FIFO0 (a dual-id filter with both
/// ids equal), the others are disabled. With the global filter rejecting non-matching and
/// remote frames, only the node's own commands reach the software.
const COMMAND_FILTERS: [StandardFilter; STANDARD_FILTER_MAX as usize] = command_filters();

/// Builds [`COMMAND_FILTERS`] at compile time (an identifier above 0x7FF or more commands than
/// filter elements fail the build, not the board).
const fn command_filters() -> [StandardFilter; STANDARD_FILTER_MAX as usize] {
    const DISABLED: StandardFilter = StandardFilter {
        filter: FilterType::Disabled,
        action: Action::Disable,
    };
    const _: () = assert!(ids::COMMANDS.len() <= STANDARD_FILTER_MAX as usize);
    let mut filters = [DISABLED; STANDARD_FILTER_MAX as usize];
    let mut i = 0;
    while i < ids::COMMANDS.len() {
        let Some(id) = StandardId::new(ids::COMMANDS[i]) else {
            panic!("a command identifier is not an 11-bit identifier");
        };
        filters[i] = StandardFilter {
            filter: FilterType::DedicatedSingle(id),
            action: Action::StoreInFifo0,
        };
        i += 1;
    }
    filters
}

/// 1 Mbit/s from the 80 MHz kernel clock: prescaler 2 gives 40 time quanta per bit,
/// 1 (sync) + 34 + 5, sample point at 35/40 = 87.5 % (CiA 301), SJW 5.
fn bit_timing() -> NominalBitTiming {
    const PRESCALER: NonZeroU16 = match NonZeroU16::new(2) {
        Some(v) => v,
        None => panic!(),
    };
    const SEG1: NonZeroU8 = match NonZeroU8::new(34) {
        Some(v) => v,
        None => panic!(),
    };
    const SEG2: NonZeroU8 = match NonZeroU8::new(5) {
        Some(v) => v,
        None => panic!(),
    };
    const _: () = assert!(FDCAN_KER_HZ / 2 / (1 + 34 + 5) == 1_000_000);
    NominalBitTiming {
        prescaler: PRESCALER,
        seg1: SEG1,
        seg2: SEG2,
        sync_jump_width: SEG2,
    }
}

/// The busy pin at the seam: the HAL's push-pull output behind embedded-hal 1.0.
struct BusyPin<const P: char, const N: u8>(Pin<P, N, Output<PushPull>>);

impl<const P: char, const N: u8> ErrorType for BusyPin<P, N> {
    type Error = Infallible;
}

impl<const P: char, const N: u8> OutputPin for BusyPin<P, N> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.set_low();
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.set_high();
        Ok(())
    }
}

/// Builds the node and moves it into its `static` (in .bss). Not inlined: the temporaries of
/// `Node::new` (the gait and the preview-gain computation) live in this frame and are gone
/// once the node is in place, instead of staying reserved in `main`'s frame forever.
#[inline(never)]
fn place_node(cfg: NodeConfig) -> Result<&'static mut Node<QUEUE>, GaitError> {
    let node = Node::new(cfg)?;
    match cortex_m::singleton!(: Node<QUEUE> = node) {
        Some(n) => Ok(n),
        None => panic!("place_node called twice"),
    }
}

/// Waits for the next TIM2 overflow, moving CAN frames between the hardware and software
/// FIFOs meanwhile.
fn wait_tick<I: fdcan::Instance>(timer: &mut Timer<pac::TIM2>, bus: &mut FdcanBus<I>) {
    loop {
        bus.service();
        if timer.wait().is_ok() {
            return;
        }
    }
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        panic!("core peripherals taken twice");
    };
    let Some(dp) = pac::Peripherals::take() else {
        panic!("device peripherals taken twice");
    };

    // 480 MHz needs voltage scale 0, and a wide-range VCO (960 MHz): the PLL's default
    // ("normal") strategy stays in the 150-420 MHz medium range and cannot reach it.
    let pwrcfg = dp.PWR.constrain().vos0(&dp.SYSCFG).freeze();
    let ccdr = dp
        .RCC
        .constrain()
        .pll1_strategy(PllConfigStrategy::Iterative)
        .sys_ck(SYSCLK_HZ.Hz())
        .pll1_q_ck(FDCAN_KER_HZ.Hz())
        .freeze(pwrcfg, &dp.SYSCFG);
    cp.SCB.enable_icache();
    cp.SCB.enable_dcache(&mut cp.CPUID);
    // The bit timing assumes exactly 80 MHz.
    match ccdr.clocks.pll1_q_ck() {
        Some(f) if f.raw() == FDCAN_KER_HZ => {}
        _ => panic!("PLL1Q is not 80 MHz: no CAN bit timing for it"),
    }

    // Cycle counter (the Cortex-M7's DWT has a software lock).
    cp.DCB.enable_trace();
    DWT::unlock();
    cp.DWT.enable_cycle_counter();

    let gpioe = dp.GPIOE.split(ccdr.peripheral.GPIOE);
    let mut busy = BusyPin(gpioe.pe1.into_push_pull_output());
    let _ = busy.set_low();

    // FDCAN1 on PD0 (RX) / PD1 (TX), classic CAN, 1 Mbit/s.
    let gpiod = dp.GPIOD.split(ccdr.peripheral.GPIOD);
    let rx = gpiod.pd0.into_alternate::<9>().speed(Speed::VeryHigh);
    let tx = gpiod.pd1.into_alternate::<9>().speed(Speed::VeryHigh);
    let prec = ccdr
        .peripheral
        .FDCAN
        .kernel_clk_mux(rec::FdcanClkSel::Pll1Q);
    let mut fdcan = dp.FDCAN1.fdcan(tx, rx, prec);
    fdcan.set_protocol_exception_handling(false);
    fdcan.set_frame_transmit(FrameTransmissionConfig::ClassicCanOnly);
    fdcan.set_nominal_bit_timing(bit_timing());
    // Only the node's commands (standard data frames) into RX FIFO0. Extended frames are not
    // part of the message set: one extended filter rejects them all (the global filter would
    // too); the global filter rejects non-matching standard frames and every remote frame.
    fdcan.set_standard_filters(&COMMAND_FILTERS);
    fdcan.set_extended_filter(ExtendedFilterSlot::_0, ExtendedFilter::reject_all());
    fdcan.set_global_filter(GlobalFilter::reject_all());
    let mut bus = FdcanBus::new(fdcan.into_normal());

    defmt::info!(
        "sysclk {=u32} Hz, control cycle {=u32} cycles, CAN 1 Mbit/s on PD0/PD1",
        ccdr.clocks.sys_ck().raw(),
        PERIOD_CYCLES
    );

    let t0 = DWT::cycle_count();
    let node = match place_node(walk_robot::NODE_CONFIG) {
        Ok(n) => n,
        Err(e) => defmt::panic!("Node::new failed: {}", e),
    };
    defmt::info!(
        "node ready ({=usize} bytes) in {=u32} cycles",
        core::mem::size_of::<Node<QUEUE>>(),
        DWT::cycle_count().wrapping_sub(t0)
    );

    // Started once the node exists (building it takes ~1 ms): the first cycle then starts on
    // a fresh overflow.
    let mut timer = dp
        .TIM2
        .timer(CYCLE_HZ.Hz(), ccdr.peripheral.TIM2, &ccdr.clocks);

    // A free-running millisecond clock: one control cycle = 5 ms. A cycle that overruns by
    // more than a whole period loses that time (the timer only remembers one overflow).
    let mut now_ms: u32 = 0;
    let mut stats = cycle::Stats::default();
    // Align the first cycle on a timer overflow.
    wait_tick(&mut timer, &mut bus);
    loop {
        let _ = busy.set_high();
        let t0 = DWT::cycle_count();
        let report = node.poll(now_ms, &mut bus);
        let spent = DWT::cycle_count().wrapping_sub(t0);
        let _ = busy.set_low();

        // Late: the work did not fit the slot, or the overflow that ends this cycle has
        // already happened (so the next cycle starts late).
        let late = spent > PERIOD_CYCLES || !timer.is_irq_clear();
        let outcome = stats.record(node, &report, spent, late);
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
        if let Some(w) = outcome.summary {
            let c = bus.counters();
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

        wait_tick(&mut timer, &mut bus);
        now_ms = now_ms.wrapping_add(CYCLE_MS);
    }
}
