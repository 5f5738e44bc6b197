//! The ROS 2 side of the gateway (placeholder while the core is tested).
