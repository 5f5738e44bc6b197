//! The `ros2` subcommand's options and its body (the command line in `src/main.rs` hands it
//! its arguments).

use std::error::Error;
use std::path::PathBuf;

use crate::robot::Robot;

/// `host-sim ros2`'s options.
#[derive(clap::Args, Debug, Clone)]
pub struct Ros2Args {
    /// The topics' namespace [default: /ihmc/<robot>/humanoid_control].
    #[arg(long, value_name = "NS")]
    pub namespace: Option<String>,
    /// The DDS domain [default: $ROS_DOMAIN_ID, else 0].
    #[arg(long, value_name = "N")]
    pub domain: Option<u16>,
    /// Stop after this many seconds (default: run until killed).
    #[arg(long, value_name = "S", value_parser = positive_seconds, allow_negative_numbers = true)]
    pub seconds: Option<f64>,
    /// Exit after this many walks ended (completed or aborted).
    #[arg(long, value_name = "N")]
    pub walks: Option<usize>,
    /// Drive a real node on this CAN interface (feature `socketcan`) instead of the node in
    /// this process.
    #[arg(long, value_name = "IFACE", conflicts_with = "mujoco")]
    pub interface: Option<String>,
    /// The robot in MuJoCo follows the node in this process (needs `python3 -m pip install
    /// mujoco==3.2.7`): the landings reported are the engine's soles.
    #[arg(long)]
    pub mujoco: bool,
    /// Write can.log and gateway.json (what the run measured) here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Serve the walk live to Foxglove on this port (ws://127.0.0.1:PORT).
    #[arg(long, value_name = "PORT")]
    pub live: Option<u16>,
    /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
    #[arg(long, value_name = "FILE")]
    pub robot: Option<PathBuf>,
}

fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a positive number of seconds")),
    }
}

/// Runs `host-sim ros2` for `robot` (loaded from `args.robot` by the caller).
pub fn command(args: &Ros2Args, robot: &Robot) -> Result<(), Box<dyn Error>> {
    let domain = match args.domain {
        Some(d) => d,
        None => match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) => v
                .parse()
                .map_err(|_| format!("ROS_DOMAIN_ID={v} is not a domain id (0 … 232)"))?,
            Err(_) => 0,
        },
    };
    let opts = super::dds::Options {
        namespace: args
            .namespace
            .clone()
            .unwrap_or_else(|| super::dds::default_namespace(robot.name())),
        domain,
        seconds: args.seconds,
        walks: args.walks,
        gateway: super::gateway_config(robot),
    };
    crate::outln!(
        "ROS 2 gateway: topics under {} (domain {}), node: {}",
        opts.namespace,
        opts.domain,
        match (args.interface.as_deref(), args.mujoco) {
            (Some(i), _) => i,
            (None, true) => "in this process, the robot in MuJoCo",
            (None, false) => "in this process",
        }
    );
    let view = match args.live {
        Some(port) => Some(crate::output::live::LiveView::announce(port, robot)?),
        None => None,
    };
    super::serve(
        robot,
        &opts,
        args.interface.as_deref(),
        args.mujoco,
        args.out.as_deref(),
        view.as_ref(),
    )?;
    Ok(())
}
