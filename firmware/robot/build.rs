//! Generates `robot.rs`: the node configuration of the robot file, as constants.
//!
//! The file is `WALK_ROBOT` if set (a path, relative to this package or absolute), otherwise
//! HRP-2's, `host-sim/robots/hrp2.toml`. It is read with the same reader as host-sim's
//! (`planner_core::robot`), and every float is written by its bits, so the image's node is
//! configured exactly as the simulator's for the same file. A file the reader refuses fails
//! the build with its message (which names the key).
use std::path::PathBuf;

/// The control period of the firmware's loops (the board's TIM2 and the QEMU image's timer).
const LOOP_PERIOD_S: f64 = 0.005;

fn main() {
    println!("cargo:rerun-if-env-changed=WALK_ROBOT");
    let dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let path = match std::env::var("WALK_ROBOT") {
        Ok(p) if !p.is_empty() => dir.join(p),
        _ => dir.join("../../host-sim/robots/hrp2.toml"),
    };
    println!("cargo:rerun-if-changed={}", path.display());
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => fail(&format!(
            "robot file {}: cannot be read: {e}",
            path.display()
        )),
    };
    let robot = match planner_core::robot::Robot::from_toml(&text) {
        Ok(r) => r,
        Err(e) => fail(&format!("robot file {}: {e}", path.display())),
    };
    let dt = robot.params.dt;
    if (dt - LOOP_PERIOD_S).abs() > 1e-12 {
        fail(&format!(
            "robot file {}: key `timing.control_period`: {dt} s, but the firmware's loops run \
             every {LOOP_PERIOD_S} s",
            path.display()
        ));
    }
    let node_config = robot.node_config();
    let node_config_f32 = node_config.cast::<f32>();
    let cfg = planner_core::robot::node_config_source(&node_config);
    let cfg_f32 = planner_core::robot::node_config_source(&node_config_f32);
    // The preview gains, computed here once (the reader has checked that they can be), so
    // that the image copies them at start-up instead of iterating the Riccati equation. The
    // f32 node's from its own (rounded) parameters, as `Node::new` computes them on the host.
    let gains = gains_source(&node_config.params, &path);
    let gains_f32 = gains_source(&node_config_f32.params, &path);
    let out = format!(
        "/// The robot's name (`name` in its file).\n\
         pub const NAME: &str = {name:?};\n\
         /// The node's configuration for the robot file.\n\
         pub const NODE_CONFIG: ::planner_core::node::NodeConfig = {cfg};\n\
         /// The preview-control gains of the robot file (in flash), for\n\
         /// `Node::with_gains(NODE_CONFIG, &GAINS)`.\n\
         pub static GAINS: ::planner_core::shaping::PreviewGains<f64, {{ ::planner_core::gait::PREVIEW }}> = {gains};\n\
         /// [`NODE_CONFIG`] in `f32` (every real rounded to the nearest `f32`), for the node of\n\
         /// a single-precision FPU.\n\
         pub const NODE_CONFIG_F32: ::planner_core::node::NodeConfig<f32> = {cfg_f32};\n\
         /// The preview-control gains of [`NODE_CONFIG_F32`] (in flash; a `static` that only\n\
         /// an image that uses it links), for `Node::with_gains(NODE_CONFIG_F32, &GAINS_F32)`.\n\
         pub static GAINS_F32: ::planner_core::shaping::PreviewGains<f32, {{ ::planner_core::gait::PREVIEW }}> = {gains_f32};\n",
        name = robot.name,
    );
    let dest = PathBuf::from(std::env::var("OUT_DIR").expect("set by cargo")).join("robot.rs");
    if let Err(e) = std::fs::write(&dest, out) {
        fail(&format!("cannot write {}: {e}", dest.display()));
    }
}

/// The preview gains of `params` (computed in f64, rounded to `T`) as a constant expression;
/// all-zero gains if the robot does not shape its ZMP.
fn gains_source<T: planner_core::robot::Literal>(
    params: &planner_core::gait::GaitParams<T>,
    path: &std::path::Path,
) -> String {
    if !params.shaping {
        return "::planner_core::shaping::PreviewGains::zeroed()".to_string();
    }
    let config = params.preview_config();
    let mut g = Box::new(planner_core::shaping::PreviewGains::<
        T,
        { planner_core::gait::PREVIEW },
    >::zeroed());
    if let Err(e) = g.compute(&config, planner_core::shaping::Law::FromRest) {
        fail(&format!(
            "robot file {}: preview gains: {e:?}",
            path.display()
        ));
    }
    g.source()
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}
