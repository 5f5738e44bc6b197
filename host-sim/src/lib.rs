//! host-sim: the HRP-2 simulation around the planner (the project's main job).
//!
//! * [`paper`]: the paper's modification experiments (Fig. 4, Tables I and II) through the gait
//!   API.
//! * [`mcap_log`]: the walk as an MCAP file for robotics viewers (Foxglove).
//! * [`physics`]: the walk in the MuJoCo physics engine under a stabilizer (`host-sim
//!   physics`).
//! * [`scenario`]: timelines of footstep commands and the built-in HRP-2 scenarios.
pub mod bus;
pub mod faults;
pub mod mcap_log;
pub mod multibody;
pub mod paper;
pub mod physics;
pub mod plot;
pub mod replay;
pub mod robot;
pub mod scenario;
pub mod sim;
#[cfg(feature = "socketcan")]
pub mod socketcan_link;
pub mod toml_scenario;
