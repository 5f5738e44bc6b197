//! # planner-core
//!
//! A real-time walking pattern generator for a humanoid robot after Morisawa et al., *"Experimentation
//! of Humanoid Walking Allowing Immediate Modification of Foot Place Based on Analytical Solution"*,
//! ICRA 2007. `no_std`, no allocator, no panics on the planning path.
//!
//! * [`lipm`]: one interval of the linear inverted pendulum (polynomial ZMP, closed-form COG).
//! * [`window`]: the 7-interval plan window, its 20×20 boundary-value matrix `Z`, factorised once
//!   per timing and solved for the x and y planes.
//! * [`timing`]: eq. 17, the time and size of the worst ZMP fluctuation in a quartic interval.
//! * [`capture`]: the divergent component of motion and the step offset that captures a
//!   measured deviation from the plan (the law of the node's step adjustment).
//! * `robot` (feature `robot`, std): the robot file, one TOML file per robot.
//! * [`real`]: the scalar type (`f64` or `f32`), all transcendental functions through `libm`.
//!
//! Symbols used throughout: `ω = √(g/z_c)`; `τ` local time in an interval of duration `D`;
//! `p` ZMP, `x` COG (either plane); `a_i` ZMP polynomial coefficients, `A_i` the COG polynomial
//! of the particular solution, `P, Q` the homogeneous coefficients (see [`lipm`]).
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
#![warn(missing_docs)]

// The robot file reader and the build-time table writers (feature `robot`) are std code.
#[cfg(feature = "robot")]
extern crate std;

pub mod capture;
pub mod gait;
pub mod lipm;
#[cfg(feature = "robot")]
pub mod literal;
pub mod node;
pub mod playback;
pub mod real;
#[cfg(feature = "robot")]
pub mod robot;
pub mod shaping;
pub mod timing;
mod trig;
pub use node::velocity;
pub mod window;
pub mod wire;

pub use lipm::{Sample, Segment, State};
pub use real::Real;
pub use window::{Basis, Factorized, Plan, PlanError, PlaneBoundary, Timing};

/// Standard gravity used by the HRP-2 defaults \[m/s²\] (the paper's value).
pub const GRAVITY: f64 = 9.8;
/// HRP-2 COG height \[m\].
pub const HRP2_COG_HEIGHT: f64 = 0.814;

/// ω = √(g / z_c) for a COG height `z_c` \[m\] and gravity `g` \[m/s²\].
pub fn omega<T: Real>(g: T, z_c: T) -> T {
    (g / z_c).sqrt()
}

/// The unit tests' deterministic generator: xorshift64 from `seed`, uniform in `[0, 1)`.
#[cfg(test)]
pub(crate) fn test_uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
