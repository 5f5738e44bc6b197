//! The ROS 2 side of the gateway: its topics and their QoS over `ros2-client` (RustDDS; no
//! ROS installation), and the real-time loop that drives the [`Gateway`] and the node.
//!
//! Topics, under a namespace that follows IHMC's naming (`/ihmc/<robot>/humanoid_control` by
//! default; the DDS topic is `rt` + the ROS name, the type `<pkg>::msg::dds_::<Name>_`):
//!
//! | topic | type | direction | QoS |
//! |---|---|---|---|
//! | `input/footstep_data_list` | `controller_msgs/FootstepDataListMessage` | in | reliable, volatile, keep last 16 |
//! | `input/pause_walking` | `controller_msgs/PauseWalkingMessage` | in | reliable, volatile, keep last 16 |
//! | `input/abort_walking` | `controller_msgs/AbortWalkingMessage` | in | reliable, volatile, keep last 16 |
//! | `input/cmd_vel` | `geometry_msgs/Twist` | in | reliable, volatile, keep last 16 |
//! | `input/goal_relative` | `geometry_msgs/Pose2D` | in | reliable, volatile, keep last 16 |
//! | `output/footstep_status` | `controller_msgs/FootstepStatusMessage` | out | reliable, transient-local, keep last 64 |
//! | `output/walking_status` | `controller_msgs/WalkingStatusMessage` | out | reliable, transient-local, keep last 16 |
//! | `output/command_refusal` | `walking_node_msgs/CommandRefusal` | out | reliable, transient-local, keep last 64 |
//! | `output/reference/cog` | `geometry_msgs/PointStamped` | out | reliable, volatile, keep last 1 |
//! | `output/reference/zmp` | `geometry_msgs/PointStamped` | out | reliable, volatile, keep last 1 |
//! | `output/reference/support_polygon` | `geometry_msgs/PolygonStamped` | out | reliable, volatile, keep last 1 |
//!
//! A volatile subscription takes what a volatile or a transient-local publisher sends; the
//! statuses are transient-local so that a peer that joins late still reads the last walking
//! status and the recent footstep statuses and refusals. The reference is published every
//! control cycle (200 Hz) in frame `world`, stamped with the wall clock. No publish ever
//! waits: a sample that finds the send window full is counted and dropped
//! ([`WhenFull::Fail`]).
//!
//! Each control cycle (5 ms of wall-clock time) the loop takes every message that arrived,
//! hands it to the gateway, sends the gateway's frames, lets the node run its cycle, hands
//! the node's frames back and publishes what came of them. A message that cannot be decoded
//! (a writer of the same type name with another layout) is refused `malformed`; a writer of
//! another type on an input topic never reaches the gateway (DDS does not match it) and is
//! reported once, `wrong_type`. A peer is *there* while a footstep or `cmd_vel` publisher is
//! matched; the
//! gateway heartbeats the node only then (see [`super::gateway`]).

use std::collections::BTreeSet;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use ros2_client::{
    qos::{Durability, History, WhenFull},
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher,
    QosProfile, Subscription,
};
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::gateway::{Gateway, GatewayConfig, Output};
use super::link::NodeLink;
use super::msg::{
    AbortWalkingMessage, CommandRefusal, FootstepDataListMessage, FootstepStatusMessage, Header,
    PauseWalkingMessage, Point, PointStamped, Polygon, PolygonStamped, Pose2D, Time, Twist,
    WalkingStatusMessage,
};
use crate::output::live::LiveView;
use crate::output::mcap::{log_time_ns, LogFrame};

/// Where the gateway's topics live: `<namespace>/input/…` and `<namespace>/output/…`.
pub fn default_namespace(robot: &str) -> String {
    let name: String = robot
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_ascii_lowercase();
    format!("/ihmc/{name}/humanoid_control")
}

/// The input topics' QoS.
pub fn input_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 16 })
}

/// The statuses' QoS (`depth` samples kept for late joiners).
pub fn status_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth })
}

/// The reference's QoS.
pub fn reference_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 1 })
}

/// One message from the peer.
enum Input {
    List(Box<FootstepDataListMessage>),
    Pause(PauseWalkingMessage),
    Abort(AbortWalkingMessage),
    CmdVel(Twist),
    Goal(Pose2D),
}

/// The gateway's options.
#[derive(Clone, Debug)]
pub struct Options {
    /// The topics' namespace.
    pub namespace: String,
    /// The DDS domain (`ROS_DOMAIN_ID`).
    pub domain: u16,
    /// Stop after this long \[s\] (forever if `None`).
    pub seconds: Option<f64>,
    /// Exit once this many walks have completed or been aborted (none if `None`).
    pub walks: Option<usize>,
    /// The gateway's settings.
    pub gateway: GatewayConfig,
}

/// What one run measured, for the benchmark and the log.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Stats {
    /// Control cycles run.
    pub cycles: u64,
    /// Cycles that started more than one period late.
    pub late_cycles: u64,
    /// Footstep lists taken.
    pub lists: u64,
    /// Per list: from the peer's publish (source timestamp) to the list's first frame handed to
    /// the bus \[ms\].
    pub list_to_frame_ms: Vec<f64>,
    /// Per cycle with a status: from the node's frames read to the status published \[ms\].
    pub answer_to_status_ms: Vec<f64>,
    /// Messages refused as undecodable.
    pub malformed: u64,
    /// Publishes dropped (send window full).
    pub dropped_publishes: u64,
}

struct Io {
    lists: Subscription<FootstepDataListMessage>,
    pauses: Subscription<PauseWalkingMessage>,
    aborts: Subscription<AbortWalkingMessage>,
    cmd_vel: Subscription<Twist>,
    goals: Subscription<Pose2D>,
    footstep_status: Publisher<FootstepStatusMessage>,
    walking_status: Publisher<WalkingStatusMessage>,
    refusals: Publisher<CommandRefusal>,
    cog: Publisher<PointStamped>,
    zmp: Publisher<PointStamped>,
    support: Publisher<PolygonStamped>,
    lists_topic: String,
    cmd_vel_topic: String,
}

fn err(what: &str, e: impl std::fmt::Debug) -> String {
    format!("ROS 2: {what}: {e:?}")
}

fn subscription<T: DeserializeOwned + 'static>(
    node: &mut Node,
    ns: &str,
    name: &str,
    pkg: &str,
    ty: &str,
) -> Result<Subscription<T>, String> {
    let topic = node
        .create_topic(
            &Name::new(ns, name).map_err(|e| err(name, e))?,
            MessageTypeName::new(pkg, ty),
            &input_qos(),
        )
        .map_err(|e| err(name, e))?;
    node.create_subscription::<T>(&topic, Some(input_qos()))
        .map_err(|e| err(name, e))
}

fn publisher<T: Serialize>(
    node: &mut Node,
    ns: &str,
    name: &str,
    (pkg, ty): (&str, &str),
    qos: QosProfile,
) -> Result<Publisher<T>, String> {
    let topic = node
        .create_topic(
            &Name::new(ns, name).map_err(|e| err(name, e))?,
            MessageTypeName::new(pkg, ty),
            &qos,
        )
        .map_err(|e| err(name, e))?;
    node.create_publisher::<T>(&topic, Some(qos))
        .map_err(|e| err(name, e))
}

impl Io {
    fn new(node: &mut Node, ns: &str) -> Result<Self, String> {
        let input = format!("{ns}/input");
        let output = format!("{ns}/output");
        let reference = format!("{ns}/output/reference");
        let c = "controller_msgs";
        Ok(Self {
            lists: subscription(
                node,
                &input,
                "footstep_data_list",
                c,
                "FootstepDataListMessage",
            )?,
            pauses: subscription(node, &input, "pause_walking", c, "PauseWalkingMessage")?,
            aborts: subscription(node, &input, "abort_walking", c, "AbortWalkingMessage")?,
            cmd_vel: subscription(node, &input, "cmd_vel", "geometry_msgs", "Twist")?,
            goals: subscription(node, &input, "goal_relative", "geometry_msgs", "Pose2D")?,
            footstep_status: publisher(
                node,
                &output,
                "footstep_status",
                (c, "FootstepStatusMessage"),
                status_qos(64),
            )?,
            walking_status: publisher(
                node,
                &output,
                "walking_status",
                (c, "WalkingStatusMessage"),
                status_qos(16),
            )?,
            refusals: publisher(
                node,
                &output,
                "command_refusal",
                ("walking_node_msgs", "CommandRefusal"),
                status_qos(64),
            )?,
            cog: publisher(
                node,
                &reference,
                "cog",
                ("geometry_msgs", "PointStamped"),
                reference_qos(),
            )?,
            zmp: publisher(
                node,
                &reference,
                "zmp",
                ("geometry_msgs", "PointStamped"),
                reference_qos(),
            )?,
            support: publisher(
                node,
                &reference,
                "support_polygon",
                ("geometry_msgs", "PolygonStamped"),
                reference_qos(),
            )?,
            lists_topic: format!("{input}/footstep_data_list"),
            cmd_vel_topic: format!("{input}/cmd_vel"),
        })
    }
}

fn now_stamp() -> Time {
    let d = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    Time {
        sec: d.as_secs() as i32,
        nanosec: d.subsec_nanos(),
    }
}

fn unix_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as i64)
        .unwrap_or(0)
}

/// Publishes, counting what the send window refused.
fn put<T>(p: &Publisher<T>, m: T, stats: &mut Stats)
where
    T: Serialize,
{
    if p.publish(m).is_err() {
        stats.dropped_publishes += 1;
    }
}

/// Runs the gateway on `link` until `opts` says stop, serving the walk on `live` as well (the
/// reference and every frame on the bus).
pub fn run(
    link: &mut dyn NodeLink,
    opts: &Options,
    live: Option<&LiveView>,
) -> Result<Stats, String> {
    let ctx = Context::with_options(ContextOptions::new().domain_id(opts.domain))
        .map_err(|e| err("context", e))?;
    let mut node = ctx
        .new_node(
            NodeName::new("/", "walking_gateway").map_err(|e| err("node name", e))?,
            NodeOptions::new().enable_rosout(false),
        )
        .map_err(|e| err("node", e))?;
    let io = Io::new(&mut node, &opts.namespace)?;
    let mut gw = Gateway::new(opts.gateway);
    let mut stats = Stats::default();
    let period = Duration::from_secs_f64(opts.gateway.dt);
    let start = Instant::now();
    let mut next = start;
    let mut walks = 0usize;
    let mut wrong_types: BTreeSet<String> = BTreeSet::new();
    let frame_id = "world".to_string();
    loop {
        next += period;
        let now = Instant::now();
        if now < next {
            std::thread::sleep(next - now);
        } else if now - next > period {
            stats.late_cycles += 1;
        }
        stats.cycles += 1;
        // Inputs, in the order the peer published them (source timestamps; across the three
        // topics, so that an abort followed by a new plan is carried out in that order).
        let mut first_list_ns: Option<i64> = None;
        let mut inputs: Vec<(i64, usize, Input)> = Vec::new();
        let stamp = |info: &ros2_client::MessageInfo| {
            info.source_timestamp()
                .map(|t| t.to_nanos())
                .unwrap_or(i64::MAX)
        };
        loop {
            match io.lists.take() {
                Ok(Some((msg, info))) => {
                    inputs.push((stamp(&info), inputs.len(), Input::List(Box::new(msg))))
                }
                Ok(None) => break,
                Err(e) => {
                    stats.malformed += 1;
                    let r = CommandRefusal {
                        footstep_index: -1,
                        command: "footstep_list".into(),
                        reason: "malformed".into(),
                        detail: format!("the message could not be decoded: {e:?}"),
                        ..CommandRefusal::default()
                    };
                    crate::errln!("refused: footstep_list: malformed: {e:?}");
                    put(&io.refusals, r, &mut stats);
                }
            }
        }
        while let Ok(Some((m, info))) = io.pauses.take() {
            inputs.push((stamp(&info), inputs.len(), Input::Pause(m)));
        }
        while let Ok(Some((m, info))) = io.aborts.take() {
            inputs.push((stamp(&info), inputs.len(), Input::Abort(m)));
        }
        while let Ok(Some((m, info))) = io.cmd_vel.take() {
            inputs.push((stamp(&info), inputs.len(), Input::CmdVel(m)));
        }
        while let Ok(Some((m, info))) = io.goals.take() {
            inputs.push((stamp(&info), inputs.len(), Input::Goal(m)));
        }
        inputs.sort_by_key(|(t, n, _)| (*t, *n));
        for (t, _, input) in inputs {
            match input {
                Input::List(msg) => {
                    stats.lists += 1;
                    if first_list_ns.is_none() && t != i64::MAX {
                        first_list_ns = Some(t);
                    }
                    gw.on_footstep_list(*msg);
                }
                Input::Pause(m) => {
                    gw.on_pause(m.sequence_id, m.pause, m.clear_remaining_footstep_queue)
                }
                Input::Abort(m) => gw.on_abort(m.sequence_id),
                Input::CmdVel(t) => gw.on_cmd_vel(t.linear.x, t.linear.y, t.angular.z),
                Input::Goal(g) => gw.on_goal(g.x, g.y, g.theta),
            }
        }
        // Writers of another type on the footstep topic (DDS does not match them).
        if stats.cycles % 200 == 1 {
            for w in ctx.domain_participant().discovered_writers() {
                let t = &w.publication_topic_data;
                let dds_topic = format!("rt{}", io.lists_topic);
                let expected = "controller_msgs::msg::dds_::FootstepDataListMessage_";
                if t.topic_name == dds_topic
                    && t.type_name != expected
                    && wrong_types.insert(t.type_name.clone())
                {
                    let r = CommandRefusal {
                        footstep_index: -1,
                        command: "footstep_list".into(),
                        reason: "wrong_type".into(),
                        detail: format!(
                            "a writer of {} on {}: this topic takes {expected}",
                            t.type_name, io.lists_topic
                        ),
                        ..CommandRefusal::default()
                    };
                    crate::errln!("refused: {}", r.detail);
                    put(&io.refusals, r, &mut stats);
                }
            }
        }
        let alive = node.publisher_count(&io.lists_topic) > 0
            || node.publisher_count(&io.cmd_vel_topic) > 0;
        // One control cycle.
        let frames = gw.poll(alive);
        if let (Some(t), false) = (first_list_ns, frames.is_empty()) {
            stats.list_to_frame_ms.push((unix_ns() - t) as f64 * 1e-6);
        }
        let answers = link.cycle(&frames);
        let read = Instant::now();
        let t = stats.cycles as f64 * opts.gateway.dt;
        if let Some(v) = live {
            let us = log_time_ns(t) / 1000;
            for f in frames.iter().chain(&answers) {
                v.can(&LogFrame {
                    unix_us: us,
                    id: f.id,
                    data: f.bytes().to_vec(),
                });
            }
        }
        for f in &answers {
            gw.on_frame(f);
        }
        gw.set_measured_soles(link.measured_soles());
        gw.end_cycle();
        // Outputs.
        let mut status_published = false;
        for o in gw.take_outputs() {
            match o {
                Output::Footstep(s) => {
                    put(&io.footstep_status, s, &mut stats);
                    status_published = true;
                }
                Output::Walking(w, id) => {
                    put(
                        &io.walking_status,
                        WalkingStatusMessage {
                            sequence_id: id,
                            walking_status: w,
                        },
                        &mut stats,
                    );
                    status_published = true;
                    if w != super::msg::WALKING_STARTED {
                        walks += 1;
                    }
                }
                Output::Refusal(r) => {
                    put(&io.refusals, r, &mut stats);
                    status_published = true;
                }
                Output::Reference {
                    reference: r,
                    support,
                    ..
                } => {
                    if let Some(v) = live {
                        v.sample(t, &r, None);
                    }
                    let cog = Point {
                        x: r.x.cog,
                        y: r.y.cog,
                        z: opts.gateway.cog_height,
                    };
                    let zmp = Point {
                        x: r.x.zmp,
                        y: r.y.zmp,
                        z: 0.0,
                    };
                    let header = Header {
                        stamp: now_stamp(),
                        frame_id: frame_id.clone(),
                    };
                    put(
                        &io.cog,
                        PointStamped {
                            header: header.clone(),
                            point: cog,
                        },
                        &mut stats,
                    );
                    put(
                        &io.zmp,
                        PointStamped {
                            header: header.clone(),
                            point: zmp,
                        },
                        &mut stats,
                    );
                    put(
                        &io.support,
                        PolygonStamped {
                            header,
                            polygon: Polygon { points: support },
                        },
                        &mut stats,
                    );
                }
                Output::Log(line) => {
                    crate::outln!("{:8.3} s  {line}", start.elapsed().as_secs_f64())
                }
            }
        }
        if status_published {
            stats
                .answer_to_status_ms
                .push(read.elapsed().as_secs_f64() * 1e3);
        }
        if opts.walks.is_some_and(|n| walks >= n) {
            break;
        }
        if opts
            .seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break;
        }
    }
    Ok(stats)
}
