//! The board's hardware behind board-core's control-cycle traits (`board_core::control`):
//! TIM2 as the microsecond clock, DWT CYCCNT as the poll's timer, the independent watchdog.
//! (The busy pin is `main.rs`'s: a HAL pin type.) The no-panic check (`firmware/nopanic`)
//! compiles this file too.

use board_core::control::{CycleCounter, MicrosClock, Watchdog};
use cortex_m::peripheral::DWT;
use stm32h7xx_hal::independent_watchdog::IndependentWatchdog;
use stm32h7xx_hal::pac;

/// TIM2, free-running at 1 MHz (`hw::start_us_counter`): the slots' clock. The loop spins
/// while it waits (servicing the CAN link), so [`MicrosClock::idle_until`] does nothing.
pub struct Tim2Clock(pub pac::TIM2);

impl MicrosClock for Tim2Clock {
    fn now_us(&mut self) -> u32 {
        crate::hw::now_us(&self.0)
    }
}

/// DWT CYCCNT (enabled at start-up): core cycles.
pub struct Dwt;

impl CycleCounter for Dwt {
    fn cycles(&mut self) -> u32 {
        DWT::cycle_count()
    }
}

/// The independent watchdog (the HAL's; started at start-up): one write of `IWDG_KR`.
pub struct Iwdg(pub IndependentWatchdog);

impl Watchdog for Iwdg {
    fn feed(&mut self) {
        self.0.feed();
    }
}
