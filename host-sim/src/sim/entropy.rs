//! The node's start-up entropy on a host: the operating system's random number generator.
//!
//! A node draws its session epoch and the number of its first step from
//! [`NodeConfig::entropy`] at every start-up, so that the frames of an earlier start-up (a
//! controller's log replayed after a restart) are refused but by chance (2⁻¹⁶ for a control
//! command). `host-sim node` takes it from here at every start; without an entropy source
//! it does not start (a constant would repeat the same session at every start-up). The
//! simulations keep the robot file's entropy (0): their runs are reproducible, and each
//! simulates one start-up.

use std::io::{self, Read};

use planner_core::node::NodeConfig;

/// 32 bits of the operating system's random number generator (`/dev/urandom`: the kernel's
/// CSPRNG, seeded before user space starts).
pub fn os_entropy() -> io::Result<u32> {
    let mut b = [0u8; 4];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut b)?;
    Ok(u32::from_le_bytes(b))
}

/// `cfg` for a start-up of the node: its entropy drawn from the operating system
/// ([`os_entropy`]); an error if there is none to draw.
pub fn start_up(cfg: NodeConfig) -> io::Result<NodeConfig> {
    Ok(NodeConfig {
        entropy: os_entropy()?,
        ..cfg
    })
}
