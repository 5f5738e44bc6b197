//! # gait-loop
//!
//! The gait loop that both firmware images run, without any hardware:
//!
//! * [`script`]: a scripted footstep source (the stand-in for the CAN bus): the `fig4` and
//!   `lateral` scenarios of `host-sim`, as data;
//! * [`cycle`]: one 5 ms control cycle (apply the commands that are due, then
//!   [`Gait::tick`](planner_core::gait::Gait::tick)), each part timed by a [`cycle::Clock`]
//!   that the image provides, and classified by [`Kind`];
//! * [`stats`]: count, maximum and sum per kind.
//!
//! The images differ only in the clock (QEMU: the CMSDK timer under `-icount`; board: DWT
//! cycles), the 5 ms pacing and the output.
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod cycle;
pub mod script;
pub mod stats;

pub use cycle::{new_gait, Clock, CommandRecord, CycleRecord, Player};
pub use script::{Command, Scenario};
pub use stats::{Kind, Stat, Stats};

/// The queue capacity of the firmware's gait (both scenarios queue at most 13 steps).
pub const QUEUE: usize = 16;
