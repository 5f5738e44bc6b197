//! # walk-robot
//!
//! The robot the firmware is built for: [`NODE_CONFIG`], the node's configuration, and
//! [`GAINS`], its preview-control gains (in flash: the node borrows them through [`Gains`],
//! so it neither computes nor copies them; its type is [`Node`]`<Q>`), generated at build time (`build.rs`) from a robot file: HRP-2's `host-sim/robots/hrp2.toml`, or the
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

use core::borrow::Borrow;

use planner_core::gait::PREVIEW;
use planner_core::shaping::PreviewGains;

/// How the firmware's node holds its gains: [`GAINS`] in flash, named by a zero-sized type
/// (a reference would do as well, but its address is not zero: a parked node,
/// `Node::parked(Gains)`, would then no longer be all zero bytes and its `static` would
/// move from .bss into .data, 14 KB of flash).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Gains;

impl Borrow<PreviewGains<f64, PREVIEW>> for Gains {
    #[inline(always)]
    fn borrow(&self) -> &PreviewGains<f64, PREVIEW> {
        &GAINS
    }
}

/// The firmware's node type, with `Q` queued steps and [`GAINS`] lent from flash
/// ([`Gains`]).
pub type Node<const Q: usize> = planner_core::node::Node<Q, Gains>;

/// The firmware's node before start-up: `ParkedNode::new(Gains)` in a `static` (all zero
/// bytes: .bss), then `start(NODE_CONFIG)` configures it in place.
pub type ParkedNode<const Q: usize> = planner_core::node::ParkedNode<Q, Gains>;

/// How the `f32` node holds its gains: [`GAINS_F32`] in flash (see [`Gains`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GainsF32;

impl Borrow<PreviewGains<f32, PREVIEW>> for GainsF32 {
    #[inline(always)]
    fn borrow(&self) -> &PreviewGains<f32, PREVIEW> {
        &GAINS_F32
    }
}

/// The `f32` node (single-precision FPUs such as the Cortex-M4F's), with `Q` queued steps and
/// [`GAINS_F32`] lent from flash ([`GainsF32`]).
pub type NodeF32<const Q: usize> = planner_core::node::Node<Q, GainsF32, f32>;

/// The `f32` node before start-up (see [`ParkedNode`]).
pub type ParkedNodeF32<const Q: usize> = planner_core::node::ParkedNode<Q, GainsF32, f32>;
