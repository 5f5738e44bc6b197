//! # walk-robot
//!
//! The robot the firmware is built for: [`NODE_CONFIG`], the node's configuration, and
//! [`GAINS`], its preview-control gains (in flash: `Node::with_gains(NODE_CONFIG, &GAINS)`
//! lends them to the node, which neither computes nor copies them; its type is
//! [`Node`]`<Q, `[`Gains`]`>`), generated
//! at build time (`build.rs`) from a robot file: HRP-2's `host-sim/robots/hrp2.toml`, or the
//! file named by the `WALK_ROBOT` environment variable
//! (`WALK_ROBOT=/path/robot.toml cargo build --release`). The file is read by
//! `planner_core::robot`, as host-sim reads it, so the board's node and the simulated node
//! agree exactly for the same file (`tests/tests/robot.rs` compares them).
//!
//! [`NODE_CONFIG_F32`] and [`GAINS_F32`] are the same robot for the `f32` node
//! ([`NodeF32`]: a single-precision FPU such as the Cortex-M4F's), generated from the same
//! file (the configuration rounded to `f32`, the gains computed for it); an image that does
//! not use them does not link them.
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

include!(concat!(env!("OUT_DIR"), "/robot.rs"));

/// How the firmware's node holds its gains: a reference to [`GAINS`] in flash.
pub type Gains = &'static planner_core::shaping::PreviewGains<f64, { planner_core::gait::PREVIEW }>;

/// The firmware's node type, with `Q` queued steps and [`GAINS`] lent from flash.
pub type Node<const Q: usize> = planner_core::node::Node<Q, Gains>;

/// How the `f32` node holds its gains: a reference to [`GAINS_F32`] in flash.
pub type GainsF32 =
    &'static planner_core::shaping::PreviewGains<f32, { planner_core::gait::PREVIEW }>;

/// The `f32` node (single-precision FPUs such as the Cortex-M4F's), with `Q` queued steps and
/// [`GAINS_F32`] lent from flash: `NodeF32::with_gains(NODE_CONFIG_F32, &GAINS_F32)`.
pub type NodeF32<const Q: usize> = planner_core::node::Node<Q, GainsF32, f32>;
