//! host-sim: the HRP-2 simulation around the planner (the project's main job).
//!
//! * [`paper`]: the paper's modification experiments (Fig. 4, Tables I and II) through the gait
//!   API.
//! * [`scenario`]: timelines of footstep commands and the built-in HRP-2 scenarios.
pub mod bus;
pub mod faults;
pub mod multibody;
pub mod paper;
pub mod plot;
pub mod replay;
pub mod robot;
pub mod scenario;
pub mod sim;
#[cfg(feature = "socketcan")]
pub mod socketcan_link;
pub mod toml_scenario;
