//! The ROS 2 footstep gateway (`host-sim ros2`): IHMC's footstep messages over ROS 2 turned
//! into the node's CAN commands, and the node's progress back as IHMC's status messages.
//!
//! * [`msg`]: the message types, field for field as `host-sim/interfaces/**/*.msg`;
//! * [`plan`]: a footstep list validated and matched with the steps already sent;
//! * [`gateway`]: the state machine between the two (no DDS, no bus: tested alone);
//! * [`link`]: the node in this process on the virtual bus, or a real node on SocketCAN;
//! * [`cli`]: the `ros2` subcommand's options;
//! * [`dds`]: the ROS 2 side (`ros2-client` over RustDDS: no ROS installation), its topics
//!   and their QoS, and the gateway's real-time loop.
//!
//! The book's chapter *From ROS 2* gives the topics, the semantics and a Python peer.

pub mod cli;
pub mod dds;
pub mod gateway;
pub mod link;
pub mod msg;
pub mod plan;

use std::path::Path;

use crate::robot::Robot;
use link::NodeLink;

/// Runs the gateway for `robot`: on the node in this process (`interface` `None`; with
/// `mujoco`, the robot in MuJoCo follows it and the landings are the engine's) or on a real
/// node on that CAN interface (feature `socketcan`), served on `live` as well if given. With
/// `out`, writes `can.log` (in this process) and `gateway.json` (what the run measured,
/// [`dds::Stats`]) there.
pub fn serve(
    robot: &Robot,
    opts: &dds::Options,
    interface: Option<&str>,
    mujoco: bool,
    out: Option<&Path>,
    live: Option<&crate::output::live::LiveView>,
) -> Result<dds::Stats, String> {
    let mut link: Box<dyn NodeLink> = match interface {
        None if mujoco => Box::new(link::WithEngine::new(robot.node_config(), robot)?),
        None => Box::new(link::InProcess::new(robot.node_config())?),
        #[cfg(feature = "socketcan")]
        Some(i) => Box::new(link::SocketCan::open(i)?),
        #[cfg(not(feature = "socketcan"))]
        Some(i) => {
            return Err(format!(
                "cannot drive a node on {i}: this host-sim was built without SocketCAN \
                 (cargo run --release -p host-sim --features socketcan -- ros2 --interface {i})"
            ))
        }
    };
    let stats = dds::run(link.as_mut(), opts, live)?;
    crate::outln!("{}", latency_summary(&stats));
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let log = link.log();
        if !log.is_empty() {
            let p = dir.join("can.log");
            std::fs::write(&p, log.join("\n") + "\n")
                .map_err(|e| format!("{}: {e}", p.display()))?;
        }
        let p = dir.join("gateway.json");
        let text = serde_json::to_string_pretty(&stats).map_err(|e| e.to_string())?;
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(stats)
}

/// The latencies of a run in one line: median and maximum of each of [`dds::Stats`]'s two.
pub fn latency_summary(stats: &dds::Stats) -> String {
    let describe = |v: &[f64]| {
        if v.is_empty() {
            return "none".to_string();
        }
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let median = if s.len() % 2 == 1 {
            s[s.len() / 2]
        } else {
            0.5 * (s[s.len() / 2 - 1] + s[s.len() / 2])
        };
        format!(
            "median {median:.2} ms, max {:.2} ms ({} samples)",
            s[s.len() - 1],
            s.len()
        )
    };
    format!(
        "latency: footstep list published to its first CAN frame: {}; node's answer to status \
         published: {}; {} cycles, {} late",
        describe(&stats.list_to_frame_ms),
        describe(&stats.answer_to_status_ms),
        stats.cycles,
        stats.late_cycles
    )
}

/// The gateway's settings for `robot`: its control period, sole and COG height.
pub fn gateway_config(robot: &Robot) -> gateway::GatewayConfig {
    let p = robot.node_config().params;
    gateway::GatewayConfig {
        dt: p.dt,
        sole: [2.0 * p.sole_half_length, 2.0 * p.sole_half_width],
        cog_height: p.cog_height,
        ..gateway::GatewayConfig::default()
    }
}
