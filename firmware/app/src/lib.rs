//! # gait-loop
//!
//! The QEMU image's control loop around planner-core's CAN node, without any hardware:
//!
//! * [`script`]: the `fig4` and `lateral` scenarios of `host-sim`, as data (a timeline of
//!   footstep commands at given ticks);
//! * [`controller`]: the controller of `host_sim::sim::simulate`: the timeline as CAN frames
//!   (`wire::Command::encode`) at the same ticks, heartbeats, and the pairing of the node's
//!   `ACK`s with the commands;
//! * [`bus`]: an in-memory `embedded_can::nb::Can` device between the two;
//! * [`cycle`]: one 5 ms control cycle: the controller's frames, one
//!   [`Node::poll`](planner_core::node::Node::poll) timed by a [`cycle::Clock`] that the image
//!   provides and classified by [`Kind`], the node's answers;
//! * [`stats`]: count, maximum and sum per kind;
//! * [`player`]: the player of a recorded CAN log by `planner_core::playback`'s rule (not yet
//!   used by the image).
//!
//! The board image runs the same `Node::poll` over FDCAN1 instead of the in-memory device.
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod bus;
pub mod controller;
pub mod cycle;
pub mod player;
pub mod script;
pub mod stats;

pub use bus::ScriptedBus;
pub use controller::{Answer, Controller, Sent, Unrepresentable, HEARTBEAT_TICKS};
pub use cycle::{Clock, CycleRecord, Fnv, Runner};
pub use script::{Command, Scenario};
pub use stats::{Kind, Stat, Stats};

/// The queue capacity of the firmware's node (`Node<16>`, as on the board; both scenarios
/// queue at most 13 steps).
pub const QUEUE: usize = 16;
