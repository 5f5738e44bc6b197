//! host-sim: the HRP-2 simulation around the planner (the project's main job).
//!
//! The crate is in rooms by role; a room uses only the rooms listed before it:
//!
//! * [`console`]: standard output that a closed reader cannot crash, and progress bars.
//! * [`scenario`]: what is played: timelines of footstep commands, the built-in scenarios,
//!   scenario files (TOML), the names of what may become of a command, and the encoding of a
//!   scenario's commands for the bus.
//! * [`robot`]: the robot file: the planner's robot and host-sim's link model (the multi-body
//!   description and its kinematics).
//! * [`sim`]: the closed loop over the virtual CAN link: the bus with its fault layers, the
//!   node fed a scenario or a recorded log (replay), the report of what became of a scenario's
//!   commands, and the SocketCAN front end.
//! * [`eval`]: the evaluation of a walk: the multi-body ZMP, the paper's modification
//!   experiments (Fig. 4, Tables I and II), the fault sweep.
//! * [`output`]: what a run writes besides its JSON: the trajectory's CSV, the plots and the
//!   MCAP file.
//! * [`physics`]: the walk in the MuJoCo physics engine under a stabilizer, with its own
//!   outputs (`host-sim physics` and its siblings).
//! * [`ros2`]: the ROS 2 footstep gateway (`host-sim ros2`): IHMC's footstep messages in, the
//!   node's commands over the bus (the virtual one, or SocketCAN), IHMC's statuses out.
//!
//! The command line (`src/main.rs`) sits on top of all of them.
pub mod console;
pub mod eval;
pub mod output;
pub mod physics;
pub mod robot;
pub mod ros2;
pub mod scenario;
pub mod sim;
