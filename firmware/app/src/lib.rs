//! # gait-loop
//!
//! The QEMU image's control loop around planner-core's CAN node, without any hardware: it
//! replays a CAN log recorded on the host (host-sim's candump log of a run, as `canplayer`
//! replays one onto a bus) into the node and times every poll.
//!
//! * [`binlog`]: the compact binary log the image reads (header: name, control period, start
//!   feet; then the frames to replay with their times), a validated, panic-free decoder;
//! * [`player`]: the player of such a log by `planner_core::playback`'s rule (the one
//!   `host-sim replay` uses): each frame delivered before the poll of its cycle;
//! * [`bus`]: an in-memory `embedded_can::nb::Can` device between the log and the node, and
//!   the [`Device`] trait of the replay's side of a device;
//! * [`fdcan`]: an in-memory FDCAN under the board's own link adapter (board-core's `Link`):
//!   the QEMU image's device;
//! * [`cycle`]: what one 5 ms control cycle did (the board's cycle, board-core's
//!   `control::ControlLoop`, runs and times it), classified by [`Kind`];
//! * [`stats`]: count, maximum and sum per kind.
//!
//! The board image runs the same control cycle over FDCAN1 instead of the in-memory one.
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod binlog;
pub mod bus;
pub mod cycle;
pub mod fdcan;
pub mod player;
pub mod stats;

pub use bus::{Device, ScriptedBus};
pub use cycle::{CycleRecord, Fnv, Pending};
pub use fdcan::{ReplayFdcan, ReplayLink};
pub use player::{LogFrame, Player, Source, Truncated};
pub use stats::{Kind, Stat, Stats};

/// The queue capacity of the firmware's node (`Node<16>`, as on the board).
pub const QUEUE: usize = 16;
