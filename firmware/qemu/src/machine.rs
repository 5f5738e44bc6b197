//! What differs between the two QEMU images, chosen by the `m4f` feature: the node's scalar,
//! its configuration and gains (both from walk-robot, generated from the same robot file),
//! and the machine's name. The memory layout is chosen by `build.rs` (`memory.x` or
//! `memory-m4f.x`), the CPU by the build's `target-cpu` (see `Cargo.toml`).
//!
//! | feature | QEMU machine | CPU | FPU | scalar |
//! |---|---|---|---|---|
//! | (default) | `mps2-an500` | Cortex-M7 | double precision (FPv5-D16) | `f64` |
//! | `m4f` | `mps2-an386` | Cortex-M4F | single precision (FPv4-SP-D16) | `f32` |
//!
//! Both machines map their code RAM at 0, data RAM at 0x2000_0000 and the CMSDK APB timer 0
//! at 0x4000_0000, clocked at 25 MHz (QEMU 7.2 `hw/arm/mps2.c` treats AN385, AN386 and AN500
//! alike there), so `hw.rs` and the 40 instructions per timer tick hold for both.

/// The node's scalar.
#[cfg(not(feature = "m4f"))]
pub type Scalar = f64;
/// The node's scalar.
#[cfg(feature = "m4f")]
pub type Scalar = f32;

/// How the node holds its gains (a zero-sized name of the gains in flash).
#[cfg(not(feature = "m4f"))]
pub type Gains = walk_robot::Gains;
/// How the node holds its gains (a zero-sized name of the gains in flash).
#[cfg(feature = "m4f")]
pub type Gains = walk_robot::GainsF32;

/// The image's node type, with `Q` queued steps.
#[cfg(not(feature = "m4f"))]
pub type Node<const Q: usize> = walk_robot::Node<Q>;
/// The image's node before it is configured.
#[cfg(not(feature = "m4f"))]
pub type ParkedNode<const Q: usize> = walk_robot::ParkedNode<Q>;
/// The image's node before it is configured.
#[cfg(feature = "m4f")]
pub type ParkedNode<const Q: usize> = walk_robot::ParkedNodeF32<Q>;
/// The image's node type, with `Q` queued steps.
#[cfg(feature = "m4f")]
pub type Node<const Q: usize> = walk_robot::NodeF32<Q>;

/// The node's configuration (the robot file compiled in).
#[cfg(not(feature = "m4f"))]
pub const NODE_CONFIG: planner_core::node::NodeConfig<Scalar> = walk_robot::NODE_CONFIG;
/// The node's configuration (the robot file compiled in, rounded to `f32`).
#[cfg(feature = "m4f")]
pub const NODE_CONFIG: planner_core::node::NodeConfig<Scalar> = walk_robot::NODE_CONFIG_F32;

/// The end of the name of a log that the image replays with [`NODE_CONFIG_MEASURED`].
pub const MEASURED_SUFFIX: &str = "-measured";

/// [`NODE_CONFIG`] with `AdjustConfig::from_measured` (a capture step's re-plan starts from
/// the measured state; off on the board): the node of a log whose name ends in
/// [`MEASURED_SUFFIX`] (`host_sim::sim::worst`'s `worst-measured`).
pub const NODE_CONFIG_MEASURED: planner_core::node::NodeConfig<Scalar> = {
    let mut cfg = NODE_CONFIG;
    cfg.adjust.from_measured = true;
    cfg
};

/// The node's preview gains in flash.
#[cfg(not(feature = "m4f"))]
#[inline(always)]
pub const fn gains() -> Gains {
    walk_robot::Gains
}
/// The node's preview gains in flash.
#[cfg(feature = "m4f")]
#[inline(always)]
pub const fn gains() -> Gains {
    walk_robot::GainsF32
}

/// The QEMU machine the image is built for.
#[cfg(not(feature = "m4f"))]
pub const NAME: &str = "mps2-an500";
/// The QEMU machine the image is built for.
#[cfg(feature = "m4f")]
pub const NAME: &str = "mps2-an386";

/// Whether the node of [`NODE_CONFIG`] stands where a log's feet start (given in `f64`;
/// each rounded to the node's scalar). (It reads the constant rather than borrowing `main`'s
/// copy: with a borrow, the M7 image built its node through one more copy, 45,080
/// instructions and 49.5 KB of stack instead of 24,320 and 25 KB.)
pub fn starts_at(feet: &[planner_core::gait::Footstep<f64>; 2]) -> bool {
    use planner_core::gait::Footstep;
    use planner_core::Real;
    let same = |f: &Footstep<f64>, c: &Footstep<Scalar>| {
        f.side == c.side
            && Scalar::of(f.x) == c.x
            && Scalar::of(f.y) == c.y
            && Scalar::of(f.yaw) == c.yaw
    };
    same(&feet[0], &NODE_CONFIG.left) && same(&feet[1], &NODE_CONFIG.right)
}
