//! The ROS 2 footstep gateway (`host-sim ros2`): IHMC's footstep messages over ROS 2 turned
//! into the node's CAN commands, and the node's progress back as IHMC's status messages.
//!
//! * [`msg`]: the message types, field for field as `host-sim/interfaces/**/*.msg`;
//! * [`plan`]: a footstep list validated and matched with the steps already sent;
//! * [`gateway`]: the state machine between the two (no DDS, no bus: tested alone);
//! * [`link`]: the node in this process on the virtual bus, or a real node on SocketCAN;
//! * [`dds`]: the ROS 2 side (`ros2-client` over RustDDS: no ROS installation), its topics
//!   and their QoS, and the gateway's real-time loop.
//!
//! The book's chapter *From ROS 2* gives the topics, the semantics and a Python peer.

pub mod dds;
pub mod gateway;
pub mod link;
pub mod msg;
pub mod plan;
