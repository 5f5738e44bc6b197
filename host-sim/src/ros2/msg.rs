//! The gateway's ROS 2 message types, field for field as `host-sim/interfaces/**/*.msg` define
//! them (IHMC's `controller_msgs` and `ihmc_common_msgs`, ROS 2's standard types, and the
//! gateway's own `walking_node_msgs/CommandRefusal`).
//!
//! On the wire a message is its fields in declaration order, CDR-encoded (little-endian, each
//! primitive aligned to its size from the start of the payload; a sequence or a string is a
//! `u32` count followed by its elements, a string with its terminating NUL): `serde`'s
//! derived order is the declaration order, and the DDS layer encodes it. Bounded sequences
//! (`[<=50]`) are encoded like unbounded ones; their bound is checked where the gateway
//! reads them. [`MSG_FIELDS`] lists every type's fields as the `.msg` files do, so that a test
//! compares the two.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

/// `std_msgs/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The time of the data.
    pub stamp: Time,
    /// The frame the data are expressed in.
    pub frame_id: String,
}

/// `geometry_msgs/Point`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x \[m\].
    pub x: f64,
    /// y \[m\].
    pub y: f64,
    /// z \[m\].
    pub z: f64,
}

/// `geometry_msgs/Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/Twist`: the `cmd_vel` convention (`linear.x` forward, `linear.y` to the
/// left \[m/s\], `angular.z` counter-clockwise \[rad/s\]; the other components are not
/// walked).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity.
    pub linear: Vector3,
    /// Angular velocity.
    pub angular: Vector3,
}

/// `geometry_msgs/Pose2D`: the gateway's relative goal (x forward, y to the left \[m\],
/// theta counter-clockwise \[rad\], from the midpoint of the feet and their mean heading).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose2D {
    /// x \[m\].
    pub x: f64,
    /// y \[m\].
    pub y: f64,
    /// theta \[rad\].
    pub theta: f64,
}

/// `geometry_msgs/Quaternion` (`w` last, as ROS has it).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self::from_yaw(0.0)
    }
}

impl Quaternion {
    /// The rotation by `yaw` about the vertical.
    pub fn from_yaw(yaw: f64) -> Self {
        let (s, c) = (yaw / 2.0).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
}

/// `geometry_msgs/PointStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointStamped {
    /// Time and frame.
    pub header: Header,
    /// The point.
    pub point: Point,
}

/// `geometry_msgs/Point32`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point32 {
    /// x \[m\].
    pub x: f32,
    /// y \[m\].
    pub y: f32,
    /// z \[m\].
    pub z: f32,
}

/// `geometry_msgs/Polygon`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Polygon {
    /// The vertices, in order.
    pub points: Vec<Point32>,
}

/// `geometry_msgs/PolygonStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PolygonStamped {
    /// Time and frame.
    pub header: Header,
    /// The polygon.
    pub polygon: Polygon,
}

/// `ihmc_common_msgs/SE3TrajectoryPointMessage` (taken and ignored).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Se3TrajectoryPointMessage {
    /// Ignored.
    pub sequence_id: u32,
    /// Ignored.
    pub time: f64,
    /// Ignored.
    pub position: Point,
    /// Ignored.
    pub orientation: Quaternion,
    /// Ignored.
    pub linear_velocity: Vector3,
    /// Ignored.
    pub angular_velocity: Vector3,
}

/// `ihmc_common_msgs/QueueableMessage`: only `execution_mode` is read.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct QueueableMessage {
    /// Ignored.
    pub sequence_id: u32,
    /// [`EXECUTION_MODE_OVERRIDE`], [`EXECUTION_MODE_QUEUE`] or [`EXECUTION_MODE_STREAM`].
    pub execution_mode: u8,
    /// Ignored.
    pub message_id: i64,
    /// Ignored.
    pub previous_message_id: i64,
    /// Ignored.
    pub execution_delay_time: f64,
    /// Ignored.
    pub stream_integration_duration: f64,
    /// Ignored.
    pub timestamp: i64,
}

/// `QueueableMessage.execution_mode`: the list replaces the steps not yet lifted off.
pub const EXECUTION_MODE_OVERRIDE: u8 = 0;
/// `QueueableMessage.execution_mode`: the list is appended.
pub const EXECUTION_MODE_QUEUE: u8 = 1;
/// `QueueableMessage.execution_mode`: taken as [`EXECUTION_MODE_OVERRIDE`].
pub const EXECUTION_MODE_STREAM: u8 = 2;

/// `controller_msgs/StepConstraintsListMessage` (taken and ignored).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepConstraintsListMessage {
    /// Ignored.
    pub sequence_id: u32,
    /// Ignored.
    pub region_origin: Vec<Point>,
    /// Ignored.
    pub region_orientation: Vec<Quaternion>,
    /// Ignored.
    pub region_normal: Vec<Vector3>,
    /// Ignored.
    pub concave_hulls_size: Vec<i32>,
    /// Ignored.
    pub number_of_holes_in_region: Vec<i32>,
    /// Ignored.
    pub hole_polygons_size: Vec<i32>,
    /// Ignored.
    pub vertex_buffer: Vec<Point>,
}

/// `robot_side` of the left foot.
pub const ROBOT_SIDE_LEFT: u8 = 0;
/// `robot_side` of the right foot.
pub const ROBOT_SIDE_RIGHT: u8 = 1;

/// `controller_msgs/FootstepDataMessage`: `sequence_id`, `robot_side`, `location` (x, y) and
/// `orientation` (yaw) are read; the rest is taken and ignored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootstepDataMessage {
    /// The step's identity (0: a new step every time).
    pub sequence_id: u32,
    /// [`ROBOT_SIDE_LEFT`] or [`ROBOT_SIDE_RIGHT`].
    pub robot_side: u8,
    /// The sole centre in the world frame (z ignored).
    pub location: Point,
    /// The sole's orientation (level).
    pub orientation: Quaternion,
    /// Ignored.
    pub predicted_contact_points_2d: Vec<Point>,
    /// Ignored.
    pub trajectory_type: u8,
    /// Ignored.
    pub swing_height: f64,
    /// Ignored.
    pub custom_waypoint_proportions: Vec<f64>,
    /// Ignored.
    pub custom_position_waypoints: Vec<Point>,
    /// Ignored.
    pub swing_trajectory: Vec<Se3TrajectoryPointMessage>,
    /// Ignored.
    pub swing_trajectory_blend_duration: f64,
    /// Ignored.
    pub swing_duration: f64,
    /// Ignored.
    pub transfer_duration: f64,
    /// Ignored.
    pub execution_delay_time: f64,
    /// Ignored.
    pub touchdown_duration: f64,
    /// Ignored.
    pub liftoff_duration: f64,
    /// Ignored.
    pub step_constraints: StepConstraintsListMessage,
    /// Ignored.
    pub should_check_for_reachability: bool,
}

impl FootstepDataMessage {
    /// A footstep with the `.msg` file's defaults for every ignored field.
    pub fn new(sequence_id: u32, robot_side: u8, x: f64, y: f64, yaw: f64) -> Self {
        Self {
            sequence_id,
            robot_side,
            location: Point { x, y, z: 0.0 },
            orientation: Quaternion::from_yaw(yaw),
            predicted_contact_points_2d: Vec::new(),
            trajectory_type: 0,
            swing_height: -1.0,
            custom_waypoint_proportions: Vec::new(),
            custom_position_waypoints: Vec::new(),
            swing_trajectory: Vec::new(),
            swing_trajectory_blend_duration: 0.0,
            swing_duration: -1.0,
            transfer_duration: -1.0,
            execution_delay_time: 0.0,
            touchdown_duration: -1.0,
            liftoff_duration: -1.0,
            step_constraints: StepConstraintsListMessage::default(),
            should_check_for_reachability: false,
        }
    }
}

/// `controller_msgs/FootstepDataListMessage`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootstepDataListMessage {
    /// The list's identity.
    pub sequence_id: u32,
    /// The footsteps (at most [`MAX_LIST`]).
    pub footstep_data_list: Vec<FootstepDataMessage>,
    /// Ignored.
    pub execution_timing: u8,
    /// Ignored.
    pub default_swing_duration: f64,
    /// Ignored.
    pub default_transfer_duration: f64,
    /// Ignored.
    pub final_transfer_duration: f64,
    /// Ignored.
    pub trust_height_of_footsteps: bool,
    /// True: a walk this list starts uses the node's step adjustment.
    pub are_footsteps_adjustable: bool,
    /// Ignored.
    pub offset_footsteps_with_execution_error: bool,
    /// Ignored.
    pub offset_footsteps_height_with_execution_error: bool,
    /// The execution mode.
    pub queueing_properties: QueueableMessage,
    /// Ignored.
    pub default_step_constraints: StepConstraintsListMessage,
    /// Ignored.
    pub should_check_for_reachability: bool,
}

/// The bound of `footstep_data_list` (`FootstepDataMessage[<=50]`).
pub const MAX_LIST: usize = 50;

impl FootstepDataListMessage {
    /// A list with the `.msg` file's defaults for every ignored field.
    pub fn new(sequence_id: u32, mode: u8, steps: Vec<FootstepDataMessage>) -> Self {
        Self {
            sequence_id,
            footstep_data_list: steps,
            execution_timing: 0,
            default_swing_duration: -1.0,
            default_transfer_duration: -1.0,
            final_transfer_duration: -1.0,
            trust_height_of_footsteps: true,
            are_footsteps_adjustable: false,
            offset_footsteps_with_execution_error: false,
            offset_footsteps_height_with_execution_error: false,
            queueing_properties: QueueableMessage {
                execution_mode: mode,
                message_id: -1,
                ..QueueableMessage::default()
            },
            default_step_constraints: StepConstraintsListMessage::default(),
            should_check_for_reachability: false,
        }
    }
}

/// `FootstepStatusMessage.footstep_status`: the foot lifted off.
pub const FOOTSTEP_STATUS_STARTED: u8 = 0;
/// `FootstepStatusMessage.footstep_status`: the foot landed.
pub const FOOTSTEP_STATUS_COMPLETED: u8 = 1;

/// `controller_msgs/FootstepStatusMessage`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FootstepStatusMessage {
    /// The step's id as its list gave it.
    pub sequence_id: u32,
    /// [`FOOTSTEP_STATUS_STARTED`] or [`FOOTSTEP_STATUS_COMPLETED`].
    pub footstep_status: u8,
    /// The step's index in the list that last set its pose.
    pub footstep_index: i32,
    /// The foot.
    pub robot_side: u8,
    /// The pose the list asked for.
    pub desired_foot_position_in_world: Point,
    /// The heading the list asked for.
    pub desired_foot_orientation_in_world: Quaternion,
    /// The landing (the node's reference, its step adjustment included); in a STARTED
    /// status, where the foot lifted off from.
    pub actual_foot_position_in_world: Point,
    /// The landing's heading.
    pub actual_foot_orientation_in_world: Quaternion,
    /// The swing as walked \[s\] (STARTED: the nominal single support).
    pub swing_duration: f64,
}

/// `WalkingStatusMessage.walking_status`: a walk began.
pub const WALKING_STARTED: u8 = 0;
/// `WalkingStatusMessage.walking_status`: the robot stands again after a walk.
pub const WALKING_COMPLETED: u8 = 1;
/// `WalkingStatusMessage.walking_status`: an abort (or a safety stop) was carried out.
pub const WALKING_ABORT_REQUESTED: u8 = 2;

/// `controller_msgs/WalkingStatusMessage`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WalkingStatusMessage {
    /// The list that started the walk, or the abort's or pause's id (0: the node's safety).
    pub sequence_id: u32,
    /// One of the `WALKING_*` values.
    pub walking_status: u8,
}

/// `controller_msgs/PauseWalkingMessage`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PauseWalkingMessage {
    /// The pause's id.
    pub sequence_id: u32,
    /// True: pause; false: resume.
    pub pause: bool,
    /// With `pause`: drop the steps not yet walked as well.
    pub clear_remaining_footstep_queue: bool,
}

/// `controller_msgs/AbortWalkingMessage`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AbortWalkingMessage {
    /// The abort's id.
    pub sequence_id: u32,
}

/// `walking_node_msgs/CommandRefusal`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CommandRefusal {
    /// The list's id (0: a pause or an abort).
    pub footstep_list_sequence_id: u32,
    /// The step's id (0: the whole list or a control command).
    pub footstep_sequence_id: u32,
    /// The step's index in its list (−1: the whole list or a control command).
    pub footstep_index: i32,
    /// What was refused.
    pub command: String,
    /// The node's reason code, 0 when the gateway refused before sending anything.
    pub reason_code: u8,
    /// The reason's name.
    pub reason: String,
    /// The reason in words.
    pub detail: String,
}

/// One message type: package, name, and its fields as `(type, name)`.
pub type MsgFields = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// Every message type of the gateway as `(package, name, fields)`, each field as
/// `(type, name)` in the `.msg` syntax of `host-sim/interfaces` (for the types of those
/// files) and of ROS 2 (for the standard ones).
pub const MSG_FIELDS: &[MsgFields] = &[
    (
        "controller_msgs",
        "FootstepDataListMessage",
        &[
            ("uint32", "sequence_id"),
            ("FootstepDataMessage[<=50]", "footstep_data_list"),
            ("byte", "execution_timing"),
            ("float64", "default_swing_duration"),
            ("float64", "default_transfer_duration"),
            ("float64", "final_transfer_duration"),
            ("bool", "trust_height_of_footsteps"),
            ("bool", "are_footsteps_adjustable"),
            ("bool", "offset_footsteps_with_execution_error"),
            ("bool", "offset_footsteps_height_with_execution_error"),
            ("ihmc_common_msgs/QueueableMessage", "queueing_properties"),
            ("StepConstraintsListMessage", "default_step_constraints"),
            ("bool", "should_check_for_reachability"),
        ],
    ),
    (
        "controller_msgs",
        "FootstepDataMessage",
        &[
            ("uint32", "sequence_id"),
            ("byte", "robot_side"),
            ("geometry_msgs/Point", "location"),
            ("geometry_msgs/Quaternion", "orientation"),
            ("geometry_msgs/Point[<=10]", "predicted_contact_points_2d"),
            ("byte", "trajectory_type"),
            ("float64", "swing_height"),
            ("float64[<=2]", "custom_waypoint_proportions"),
            ("geometry_msgs/Point[<=12]", "custom_position_waypoints"),
            (
                "ihmc_common_msgs/SE3TrajectoryPointMessage[<=12]",
                "swing_trajectory",
            ),
            ("float64", "swing_trajectory_blend_duration"),
            ("float64", "swing_duration"),
            ("float64", "transfer_duration"),
            ("float64", "execution_delay_time"),
            ("float64", "touchdown_duration"),
            ("float64", "liftoff_duration"),
            ("StepConstraintsListMessage", "step_constraints"),
            ("bool", "should_check_for_reachability"),
        ],
    ),
    (
        "controller_msgs",
        "FootstepStatusMessage",
        &[
            ("uint32", "sequence_id"),
            ("byte", "footstep_status"),
            ("int32", "footstep_index"),
            ("byte", "robot_side"),
            ("geometry_msgs/Point", "desired_foot_position_in_world"),
            (
                "geometry_msgs/Quaternion",
                "desired_foot_orientation_in_world",
            ),
            ("geometry_msgs/Point", "actual_foot_position_in_world"),
            (
                "geometry_msgs/Quaternion",
                "actual_foot_orientation_in_world",
            ),
            ("float64", "swing_duration"),
        ],
    ),
    (
        "controller_msgs",
        "WalkingStatusMessage",
        &[("uint32", "sequence_id"), ("byte", "walking_status")],
    ),
    (
        "controller_msgs",
        "PauseWalkingMessage",
        &[
            ("uint32", "sequence_id"),
            ("bool", "pause"),
            ("bool", "clear_remaining_footstep_queue"),
        ],
    ),
    (
        "controller_msgs",
        "AbortWalkingMessage",
        &[("uint32", "sequence_id")],
    ),
    (
        "controller_msgs",
        "StepConstraintsListMessage",
        &[
            ("uint32", "sequence_id"),
            ("geometry_msgs/Point[<=20]", "region_origin"),
            ("geometry_msgs/Quaternion[<=20]", "region_orientation"),
            ("geometry_msgs/Vector3[<=20]", "region_normal"),
            ("int32[<=100]", "concave_hulls_size"),
            ("int32[<=100]", "number_of_holes_in_region"),
            ("int32[<=100]", "hole_polygons_size"),
            ("geometry_msgs/Point[<=50000]", "vertex_buffer"),
        ],
    ),
    (
        "ihmc_common_msgs",
        "QueueableMessage",
        &[
            ("uint32", "sequence_id"),
            ("byte", "execution_mode"),
            ("int64", "message_id"),
            ("int64", "previous_message_id"),
            ("float64", "execution_delay_time"),
            ("float64", "stream_integration_duration"),
            ("int64", "timestamp"),
        ],
    ),
    (
        "ihmc_common_msgs",
        "SE3TrajectoryPointMessage",
        &[
            ("uint32", "sequence_id"),
            ("float64", "time"),
            ("geometry_msgs/Point", "position"),
            ("geometry_msgs/Quaternion", "orientation"),
            ("geometry_msgs/Vector3", "linear_velocity"),
            ("geometry_msgs/Vector3", "angular_velocity"),
        ],
    ),
    (
        "walking_node_msgs",
        "CommandRefusal",
        &[
            ("uint32", "footstep_list_sequence_id"),
            ("uint32", "footstep_sequence_id"),
            ("int32", "footstep_index"),
            ("string", "command"),
            ("uint8", "reason_code"),
            ("string", "reason"),
            ("string", "detail"),
        ],
    ),
];
