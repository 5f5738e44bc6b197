//! Minimal firmware image for the STM32H743: plans one HRP-2 walking window with
//! `planner-core` at start-up, logs a sample over RTT (defmt) and sleeps.
//!
//! It proves that the planner links and runs on the target without an allocator and without
//! `unsafe` in the application. The full board firmware (STM32H743 HAL clock and peripheral
//! set-up, the fixed 5 ms cycle around `planner_core`'s node, FDCAN) comes later and keeps
//! this file thin: board init, then the loop.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

use cortex_m_rt::entry;
use defmt_rtt as _; // global logger over RTT
use panic_probe as _; // panics print through defmt, then the core halts

use planner_core::{
    omega, Factorized, Plan, PlaneBoundary, State, Timing, GRAVITY, HRP2_COG_HEIGHT,
};

/// Single support 0.7 s and double support 0.1 s, alternating (the paper's HRP-2 timing).
const DURATIONS: [f64; 7] = [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7];
/// Step length \[m\] and half the lateral distance between the feet \[m\].
const STEP: f64 = 0.1;
const HALF_WIDTH: f64 = 0.1;

/// A straight walk from rest: the ZMP stays on a foot during single support and moves to the
/// next foot during double support.
fn straight_walk() -> (PlaneBoundary<f64>, PlaneBoundary<f64>) {
    let at = State::at_rest;
    // Sagittal: 0 | 0.1 0.1 | 0.2 0.2 | 0.3 0.3.
    let x = PlaneBoundary {
        cog_start: at(0.0),
        zmp_start: at(0.0),
        via: [
            at(0.0),
            at(STEP),
            at(STEP),
            at(2.0 * STEP),
            at(2.0 * STEP),
            at(3.0 * STEP),
            at(3.0 * STEP),
        ],
        cog_end: at(3.0 * STEP),
    };
    // Frontal: the support foot alternates between +0.1 and -0.1.
    let (l, r) = (HALF_WIDTH, -HALF_WIDTH);
    let y = PlaneBoundary {
        cog_start: at(0.0),
        zmp_start: at(l),
        via: [at(l), at(r), at(r), at(l), at(l), at(r), at(r)],
        cog_end: at(0.0),
    };
    (x, y)
}

#[entry]
fn main() -> ! {
    let timing = Timing {
        omega: omega(GRAVITY, HRP2_COG_HEIGHT),
        durations: DURATIONS,
    };
    // Both live on the stack (DTCM): no `static mut`, no allocator.
    let mut plan = Plan::zeroed(timing);
    match Factorized::new(&timing) {
        Ok(factorized) => {
            let (bx, by) = straight_walk();
            match factorized.solve(&bx, &by, &mut plan) {
                Ok(()) => {
                    let t = 1.0;
                    let (sx, sy) = plan.sample(t);
                    defmt::info!(
                        "t={=f64} s: cog=({=f64}, {=f64}) m, zmp=({=f64}, {=f64}) m",
                        t,
                        sx.cog,
                        sy.cog,
                        sx.zmp,
                        sy.zmp
                    );
                }
                Err(e) => defmt::error!("solve failed: {}", e),
            }
        }
        Err(e) => defmt::error!("factorisation failed: {}", e),
    }

    loop {
        cortex_m::asm::wfi();
    }
}
