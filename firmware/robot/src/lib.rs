//! # walk-robot
//!
//! The robot the firmware is built for: [`NODE_CONFIG`], the node's configuration, generated
//! at build time (`build.rs`) from a robot file: HRP-2's `host-sim/robots/hrp2.toml`, or the
//! file named by the `WALK_ROBOT` environment variable
//! (`WALK_ROBOT=/path/robot.toml cargo build --release`). The file is read by
//! `planner_core::robot`, as host-sim reads it, so the board's node and the simulated node
//! agree exactly for the same file (`tests/tests/robot.rs` compares them).
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

include!(concat!(env!("OUT_DIR"), "/robot.rs"));
