//! The STM32H743 image: board init, then the gait loop at a fixed 5 ms cycle.
//!
//! * clocks: 480 MHz system clock (VOS0, rev V silicon), I- and D-cache on;
//! * TIM2 overflows every 5 ms: the loop waits for it, runs one control cycle, and counts an
//!   overrun when the next overflow has already happened by the time the cycle's work is done;
//! * PE1 (an LED on the Nucleo-H743ZI) is held high while the planner works, for a scope or a
//!   logic analyser; the loop sees it through embedded-hal 1.0's `OutputPin`;
//! * DWT CYCCNT times every gait call (cycles at 480 MHz), classified per kind of cycle;
//! * the footsteps come from the scripted source of `gait-loop` (host-sim's `fig4` and
//!   `lateral`, played in turn forever) until the CAN node exists; a summary per scenario
//!   goes out over RTT (defmt).
//!
//! The gait (~38 KB, most of it the preview-control gains) lives on the stack, in DTCM, in
//! the frame of `run_scenario`: no `static mut`, no allocator. The frames are laid out as in
//! the QEMU image (`new_gait`, `control_cycle` and the gait calls not inlined), whose painted
//! stack measures the high-water mark: ~93 KB of the 128 KB.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

use core::convert::Infallible;

use cortex_m::peripheral::DWT;
use cortex_m_rt::entry;
use defmt_rtt as _; // global logger over RTT
use embedded_hal::digital::{ErrorType, OutputPin};
use panic_probe as _; // panics print through defmt, then the core halts
use stm32h7xx_hal::gpio::{Output, Pin, PushPull};
use stm32h7xx_hal::rcc::PllConfigStrategy;
use stm32h7xx_hal::timer::Timer;
use stm32h7xx_hal::{pac, prelude::*};

use gait_loop::{new_gait, script, Clock, Kind, Player, Scenario, Stats, QUEUE};
use planner_core::gait::{Gait, GaitParams};

/// System clock \[Hz\].
const SYSCLK_HZ: u32 = 480_000_000;
/// Control cycle \[Hz\] (5 ms).
const CYCLE_HZ: u32 = 200;
/// Core cycles in one control cycle.
const PERIOD_CYCLES: u32 = SYSCLK_HZ / CYCLE_HZ;

/// The DWT cycle counter as the loop's clock.
struct Cycles;

impl Clock for Cycles {
    fn now(&mut self) -> u32 {
        DWT::cycle_count()
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

/// One control cycle with the busy pin held high around the planner's work; returns the
/// cycles spent between raising and lowering the pin. Not inlined: the planner's temporaries
/// get a frame of their own, not one next to the gait's.
#[inline(never)]
fn control_cycle<B: OutputPin>(
    busy: &mut B,
    player: &mut Player<'_>,
    gait: &mut Gait<f64, QUEUE>,
    stats: &mut Stats,
) -> u32 {
    // Infallible on this board; a pin error must not stop the control loop anyway.
    let _ = busy.set_high();
    let t0 = DWT::cycle_count();
    let record = player.cycle(gait, &mut Cycles, stats, |c| {
        if let Err(e) = c.result {
            defmt::warn!(
                "tick {=u64}: {=str} refused: {}",
                c.tick,
                c.command.name(),
                e
            );
        }
    });
    let spent = DWT::cycle_count().wrapping_sub(t0);
    let _ = busy.set_low();
    if let Some(info) = record.replan {
        if info.adjust_ticks != 0 {
            defmt::info!(
                "tick {=u64}: single support adjusted by {=i32} ticks",
                record.tick,
                info.adjust_ticks
            );
        }
    }
    spent
}

fn report(name: &str, stats: &Stats, overruns: u32, worst_busy: u32) {
    for kind in Kind::ALL {
        let s = stats.get(kind);
        if s.n == 0 {
            continue;
        }
        defmt::info!(
            "TIMING scenario={=str} kind={=str} n={=u32} max={=u32} mean={=u64} max_tick={=u64} (cycles)",
            name,
            kind.name(),
            s.n,
            s.max,
            s.sum / u64::from(s.n),
            s.max_tick
        );
    }
    defmt::info!(
        "scenario {=str}: worst busy time {=u32} cycles of {=u32}, {=u32} overruns",
        name,
        worst_busy,
        PERIOD_CYCLES,
        overruns
    );
}

/// Plays one scenario with a fresh gait at one control cycle per timer overflow. The gait
/// lives in this function's frame (not inlined: one frame, in DTCM).
#[inline(never)]
fn run_scenario<B: OutputPin>(
    scenario: &Scenario,
    params: GaitParams<f64>,
    timer: &mut Timer<pac::TIM2>,
    busy: &mut B,
) {
    let mut stats = Stats::new();
    let t0 = DWT::cycle_count();
    let mut created = new_gait(params, scenario);
    stats.record(Kind::New, DWT::cycle_count().wrapping_sub(t0), 0);
    // Borrowed where `new_gait` returned it (moving it would copy 38 KB).
    let gait = match &mut created {
        Ok(g) => g,
        Err(e) => {
            defmt::error!("Gait::new failed: {}", e);
            return;
        }
    };
    let mut player = Player::new(scenario);
    let mut overruns = 0u32;
    let mut worst_busy = 0u32;
    // Align the first cycle on a timer overflow.
    let _ = nb::block!(timer.wait());
    while !player.done(gait) {
        let spent = control_cycle(busy, &mut player, gait, &mut stats);
        worst_busy = worst_busy.max(spent);
        // The overflow that ends this cycle has already happened: the work (or the logging
        // after it) took longer than 5 ms.
        if !timer.is_irq_clear() {
            overruns += 1;
        }
        let _ = nb::block!(timer.wait());
    }
    report(scenario.name, &stats, overruns, worst_busy);
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
        .freeze(pwrcfg, &dp.SYSCFG);
    cp.SCB.enable_icache();
    cp.SCB.enable_dcache(&mut cp.CPUID);

    // Cycle counter (the Cortex-M7's DWT has a software lock).
    cp.DCB.enable_trace();
    DWT::unlock();
    cp.DWT.enable_cycle_counter();

    let gpioe = dp.GPIOE.split(ccdr.peripheral.GPIOE);
    let mut busy = BusyPin(gpioe.pe1.into_push_pull_output());
    let _ = busy.set_low();

    let mut timer = dp
        .TIM2
        .timer(CYCLE_HZ.Hz(), ccdr.peripheral.TIM2, &ccdr.clocks);
    defmt::info!(
        "sysclk {=u32} Hz, control cycle {=u32} cycles",
        ccdr.clocks.sys_ck().raw(),
        PERIOD_CYCLES
    );

    let params = GaitParams::<f64>::hrp2();
    loop {
        for name in script::NAMES {
            if let Some(scenario) = Scenario::by_name(name) {
                run_scenario(&scenario, params, &mut timer, &mut busy);
            }
        }
    }
}
