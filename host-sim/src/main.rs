//! `host-sim`: the HRP-2 simulation around the planner (the project's main job).
//!
//! ```text
//! host-sim                         the default demo (the `straight` scenario into out/demo)
//! host-sim list                    the built-in scenarios
//! host-sim run <scenario|file.toml> [--out DIR] [--robot FILE]
//! host-sim replay LOG [--out DIR] [--robot FILE]   a controller's candump log into the node
//! host-sim tables [--out DIR]      the paper's Tables I and II recomputed
//! host-sim physics <scenario|file.toml> [--out DIR] [--push T,FX,FY] [PROBE] [--robot FILE]   MuJoCo run
//! host-sim physics-tables [--out DIR] [--cells all|r,c;...] [PROBE] [--robot FILE]   Tables I/II in MuJoCo
//! host-sim physics-faults [--out DIR] [--rows all|i,j] [--seed N] [--walk plain|adjusting] [PROBE] [--robot FILE]
//!                                  faults in MuJoCo
//! host-sim physics-sequence [--out DIR] [--before M] [--afters M,M,...] [PROBE] [--robot FILE]
//!                                  consecutive modified steps in MuJoCo, plain and proposed
//! host-sim push-map [--out DIR] [--quick] [--phases P,...] [--directions D,...] [--cell C,P,D] [--scan] [--push force|velocity] [PROBE] [--robot FILE]
//!                                  the push-recovery map in MuJoCo, with and without step adjustment
//! host-sim node <interface> [--seconds S] [--robot FILE]   the node on SocketCAN (feature `socketcan`)
//!
//! PROBE (the same for the five engine commands): [--open-loop] [--stabilizer full|off|weakest|S]
//!       [--servo-damping KD]
//! ```
//!
//! `run` prints every command that failed (refused by the node, never answered, or accepted
//! and never carried out) with its time, step id and reason, and exits with status 1 if one
//! failed that the scenario did not expect (`expect` in a TOML entry, see
//! `host_sim::scenario::file`). Exit status 2: a usage error, an invalid scenario, a file that
//! cannot be read or written, an engine command whose robot falls before its first step.

use std::error::Error;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use host_sim::eval::faults::Walk;
use host_sim::eval::multibody::{evaluate, max_zmp_error};
use host_sim::eval::{max_fluctuation, paper};
use host_sim::output::csv::write_trajectory;
use host_sim::output::{plot, velocity};
use host_sim::physics::probe::ProbeArgs;
use host_sim::robot::Robot;
use host_sim::scenario::file::{Entry, ScenarioFile};
use host_sim::scenario::{self, Run, Scenario, BUILT_IN};
use host_sim::sim::replay;
use host_sim::sim::report::{report, Report};
use host_sim::sim::{outcomes, simulate, SimConfig};
use host_sim::{errln, outln};
use parse::{positive_seconds, walk};
use serde_json::json;

mod parse;

/// The HRP-2 walking simulation around the planner-core node: a virtual CAN bus, the
/// multi-body model, CSV/JSON/PNG results. Without a subcommand: the demo (the `straight`
/// scenario into out/demo).
#[derive(Parser)]
#[command(
    name = "host-sim",
    version,
    after_help = "Exit status: 0 done; 1 `run` (and the demo): a command failed (refused, never \
                  answered, accepted and never carried out) that the scenario did not expect, \
                  or the multi-body model cannot follow the walk; 1 `replay`: a command was \
                  refused, frames were lost, or the log ends before the robot stands; 2 a \
                  usage error, an invalid scenario, a file that cannot be read or written, or \
                  an engine command whose robot falls before its first step."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
}

#[derive(Subcommand)]
enum Cmd {
    /// List the built-in scenarios.
    List,
    /// Run a built-in scenario or a TOML scenario file through the virtual CAN bus and the
    /// node; print every failed command, exit 1 if one failed unexpectedly.
    Run {
        /// A built-in scenario (see `host-sim list`) or a file ending in .toml.
        #[arg(value_name = "SCENARIO|FILE.toml")]
        scenario: String,
        /// The output directory, for trajectory.csv, summary.json, can.log, walk.mcap and the
        /// PNG figures [default: out/<scenario name>].
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
        /// Serve the walk live to Foxglove on this port (ws://127.0.0.1:PORT) once computed:
        /// wait up to 60 s for a client, then play it in real time.
        #[arg(long, value_name = "PORT")]
        live: Option<u16>,
    },
    /// Replay a candump log of a controller's frames into the node (as canplayer does); print
    /// every refused command, exit 1 if one was refused.
    Replay {
        /// The candump -l log (the times from host-sim's epoch 2026-01-01T00:00:00Z).
        #[arg(value_name = "LOG")]
        log: PathBuf,
        /// The output directory.
        #[arg(long, value_name = "DIR", default_value = "out/replay")]
        out: PathBuf,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
    },
    /// Recompute the paper's Tables I and II.
    Tables {
        /// The output directory.
        #[arg(long, value_name = "DIR", default_value = "out/tables")]
        out: PathBuf,
    },
    /// Run a scenario in the MuJoCo physics engine under the stabilizer (needs
    /// `python3 -m pip install mujoco==3.2.7`); writes DIR/physics.json, physics.csv and plots.
    Physics {
        /// A built-in scenario (see `host-sim list`) or a file ending in .toml.
        #[arg(value_name = "SCENARIO|FILE.toml")]
        scenario: String,
        /// The output directory [default: out/physics/<scenario>].
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Push the trunk: `T,FX,FY` (start in trajectory time [s], force [N]; 0.1 s).
        #[arg(long, value_name = "T,FX,FY", allow_hyphen_values = true)]
        push: Option<String>,
        /// Serve the run live to Foxglove on this port (ws://127.0.0.1:PORT) once computed:
        /// wait up to 60 s for a client, then play it in real time with the robot's links.
        #[arg(long, value_name = "PORT")]
        live: Option<u16>,
        #[command(flatten)]
        probe: ProbeArgs,
        /// The robot file (its link table and soles) [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
    },
    /// The paper's Tables I and II in MuJoCo: each modification cell with the plain re-plan
    /// and with the proposed method; writes DIR/physics_tables.json and .md.
    PhysicsTables {
        /// The output directory.
        #[arg(long, value_name = "DIR", default_value = "out/physics_tables")]
        out: PathBuf,
        /// The cells to run: `all` (49 cells both ways: 98 runs asked, 89 in the engine, 9 out
        /// of reach) or `row,col;row,col` (indices 0..7).
        #[arg(long, value_name = "CELLS", default_value = "all")]
        cells: String,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
        #[command(flatten)]
        probe: ProbeArgs,
    },
    /// The fault sweep's rows (one seed) through the node and then MuJoCo; writes
    /// DIR/physics_faults.json and .md.
    PhysicsFaults {
        /// The output directory.
        #[arg(long, value_name = "DIR", default_value = "out/physics_faults")]
        out: PathBuf,
        /// The rows: `all` or comma-separated indices (0 = no fault).
        #[arg(long, value_name = "ROWS", default_value = host_sim::physics::fault_sweep::DEFAULT_ROWS)]
        rows: String,
        /// The seed of every row.
        #[arg(long, value_name = "N", default_value_t = 1)]
        seed: u64,
        /// The walk: `plain` (the scenarios as written) or `adjusting` (started with
        /// `start_adjusting`, a pushed robot's estimator sending MEASURED; its rows have the
        /// silent estimator too).
        #[arg(long, value_name = "WALK", default_value = "plain", value_parser = walk)]
        walk: Walk,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
        #[command(flatten)]
        probe: ProbeArgs,
    },
    /// Several consecutive steps modified, each one control cycle before its lift-off, in
    /// MuJoCo with the plain re-plan and with the proposed method; writes
    /// DIR/physics_sequence.json and .md.
    PhysicsSequence {
        /// The output directory.
        #[arg(long, value_name = "DIR", default_value = "out/physics_sequence")]
        out: PathBuf,
        /// The planned step length [m].
        #[arg(long, value_name = "M", default_value_t = host_sim::eval::paper::SEQUENCE_BEFORE_M, allow_negative_numbers = true)]
        before: f64,
        /// The new lengths of the consecutive modified steps (from step 3), comma-separated [m].
        #[arg(long, value_name = "M,M,...", default_value = host_sim::physics::sequence::DEFAULT_AFTERS, allow_hyphen_values = true)]
        afters: String,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
        #[command(flatten)]
        probe: ProbeArgs,
    },
    /// The push-recovery map in MuJoCo: for each phase and direction the largest 0.1 s trunk
    /// push walked through, with the stabilizer only, with step adjustment and the plain
    /// re-plan, and with step adjustment and the proposed method; writes DIR/push_map.json,
    /// push_map.md and a polar plot per phase.
    PushMap {
        /// The output directory.
        #[arg(long, value_name = "DIR", default_value = "out/push_map")]
        out: PathBuf,
        /// Two phases, four directions, a coarse bisection (12.5 % of body weight).
        #[arg(long)]
        quick: bool,
        /// The phases, comma-separated: double, single_start, single_middle, single_end.
        #[arg(long, value_name = "P,P,...")]
        phases: Option<String>,
        /// The directions in the walking frame [deg], comma-separated (0 forward, 90 left;
        /// -180 … 360).
        #[arg(long, value_name = "D,D,...", allow_hyphen_values = true)]
        directions: Option<String>,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
        /// What the re-plan that lifts a capture step's foot starts from: the reference's state
        /// (the node's default) or the measured one.
        #[arg(long, value_name = "reference|measured", default_value = "reference", value_parser = ["reference", "measured"])]
        replan_from: String,
        /// One cell only, CONFIG,PHASE,DIRECTION (for example `proposed,double,90`; CONFIG is
        /// stabilizer_only, plain or proposed): its result as one JSON line on standard
        /// output, nothing written to DIR; for spreading a map over processes or machines.
        #[arg(
            long,
            value_name = "CONFIG,PHASE,DIRECTION",
            allow_hyphen_values = true
        )]
        cell: Option<String>,
        /// How a push is given: a force for 0.1 s, or the base's velocity set at one instant.
        #[arg(long, value_name = "force|velocity", default_value = "force", value_parser = ["force", "velocity"])]
        push: String,
        /// Also push around each cell's bisected force (4 forces above, 4 below, 0.05 body
        /// weight apart) and give, under `scan`, the largest force below which every tried
        /// push survived, the fraction survived above it and the cell's spread; in a map, the
        /// table and summary carry them and compare the configurations beyond the spread.
        #[arg(long)]
        scan: bool,
        #[command(flatten)]
        probe: ProbeArgs,
    },
    /// Robot files: `robot import URDF --out FILE.toml` writes one from a robot description.
    Robot {
        #[command(subcommand)]
        action: RobotCmd,
    },
    /// The ROS 2 footstep gateway: IHMC's footstep list, pause and abort in, footstep and
    /// walking status, refusals and the reference out, driving the node in this process (or a
    /// real node with --interface); see the book's "From ROS 2".
    Ros2(host_sim::ros2::cli::Ros2Args),
    /// Run the node on a Linux SocketCAN interface (needs the `socketcan` feature).
    Node {
        /// The CAN interface, e.g. can0.
        interface: String,
        /// Stop after this many seconds (default: run until killed).
        #[arg(long, value_name = "S", value_parser = positive_seconds, allow_negative_numbers = true)]
        seconds: Option<f64>,
        /// The robot file [default: HRP-2, host-sim/robots/hrp2.toml].
        #[arg(long, value_name = "FILE")]
        robot: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum RobotCmd {
    /// Write a robot file from a URDF: the multi-body model (every link; the upper body at
    /// zero joint angles merged into the trunk), the legs' six joints each in any order, the
    /// soles from the feet's collision geometry, the standing height and the reach limits
    /// from the legs' workspace (see the book's "your own robot" page).
    Import {
        /// The URDF file (`package://` meshes are found in the directory of that name above
        /// it, or on ROS_PACKAGE_PATH).
        urdf: PathBuf,
        /// The feet: the left and the right sole (or foot) link [default: on each side, the
        /// foot whose geometry reaches lowest].
        #[arg(long, value_name = "LEFT,RIGHT")]
        sole: Option<String>,
        /// The robot file to write.
        #[arg(long, value_name = "FILE.toml")]
        out: PathBuf,
    },
}

/// Something the run should not have had: commands that failed against the scenario's
/// expectations (exit status 1).
#[derive(Debug)]
struct Unexpected(String);

impl std::fmt::Display for Unexpected {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl Error for Unexpected {}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let status = match dispatch(cli.command) {
        Ok(()) => 0,
        Err(e) => {
            errln!("host-sim: {e}");
            if e.is::<Unexpected>() {
                1
            } else {
                2
            }
        }
    };
    // Output a reader closed on purpose (`| head`) is no failure; any other write error is.
    if let Some(e) = host_sim::console::stdout_failure() {
        errln!("host-sim: cannot write to standard output: {e}");
        return ExitCode::from(2);
    }
    ExitCode::from(status)
}

fn dispatch(command: Option<Cmd>) -> Result<(), Box<dyn Error>> {
    match command {
        None => run_scenario(
            "straight",
            Some(Path::new("out/demo")),
            &Robot::hrp2(),
            None,
        ),
        Some(Cmd::List) => {
            for name in BUILT_IN.iter().chain(scenario::DRIVEN.iter()) {
                let s = scenario::built_in(name).ok_or("missing built-in")?;
                outln!("{name:<10} {}", s.about);
            }
            Ok(())
        }
        Some(Cmd::Run {
            scenario,
            out,
            robot,
            live,
        }) => run_scenario(
            &scenario,
            out.as_deref(),
            &load_robot(robot.as_deref())?,
            live,
        ),
        Some(Cmd::Replay { log, out, robot }) => {
            replay_log(&log, &out, &load_robot(robot.as_deref())?)
        }
        Some(Cmd::Tables { out }) => Ok(paper::tables_command(&out)?),
        Some(Cmd::Physics {
            scenario,
            out,
            push,
            live,
            robot,
            probe,
        }) => {
            let robot = load_robot(robot.as_deref())?;
            let view = match live {
                Some(port) => Some(host_sim::output::live::LiveView::announce(port, &robot)?),
                None => None,
            };
            host_sim::physics::output::cli(
                &scenario,
                out.as_deref(),
                &robot,
                push.as_deref(),
                &probe,
                view.as_ref(),
            )
        }
        Some(Cmd::PhysicsTables {
            out,
            cells,
            robot,
            probe,
        }) => host_sim::physics::output::tables_cli(
            &out,
            &cells,
            &engine_robot(robot.as_deref())?,
            &probe,
        ),
        Some(Cmd::PhysicsFaults {
            out,
            rows,
            seed,
            walk,
            robot,
            probe,
        }) => host_sim::physics::output::faults_cli(
            &out,
            &rows,
            walk,
            seed,
            &engine_robot(robot.as_deref())?,
            &probe,
        ),
        Some(Cmd::PhysicsSequence {
            out,
            before,
            afters,
            robot,
            probe,
        }) => host_sim::physics::sequence::cli(
            &out,
            before,
            &afters,
            &engine_robot(robot.as_deref())?,
            &probe,
        ),
        Some(Cmd::PushMap {
            out,
            quick,
            phases,
            directions,
            robot,
            replan_from,
            cell,
            push,
            scan,
            probe,
        }) => host_sim::physics::push_map::cli(
            &host_sim::physics::push_map::MapArgs {
                out: &out,
                quick,
                phases: phases.as_deref(),
                directions: directions.as_deref(),
                from_measured: replan_from == "measured",
                cell: cell.as_deref(),
                push: &push,
                scan,
            },
            &engine_robot(robot.as_deref())?,
            &probe,
        ),
        Some(Cmd::Robot {
            action: RobotCmd::Import { urdf, sole, out },
        }) => host_sim::robot::import::cli::command(&urdf, sole.as_deref(), &out),
        Some(Cmd::Node {
            interface,
            seconds,
            robot,
        }) => node(&interface, seconds, &load_robot(robot.as_deref())?),
        Some(Cmd::Ros2(args)) => {
            let robot = load_robot(args.robot.as_deref())?;
            host_sim::ros2::cli::command(&args, &robot)
        }
    }
}

/// A robot for a command of many engine runs: a robot file's robot must stand in the engine
/// first (HRP-2's built-in file is checked by the tests).
fn engine_robot(path: Option<&Path>) -> Result<Robot, Box<dyn Error>> {
    let robot = load_robot(path)?;
    if path.is_some() {
        host_sim::physics::start::stands(&robot)?;
    }
    Ok(robot)
}

/// The robot file at `path`, or HRP-2.
fn load_robot(path: Option<&Path>) -> Result<Robot, Box<dyn Error>> {
    Ok(match path {
        Some(p) => Robot::load(p)?,
        None => Robot::hrp2(),
    })
}

#[cfg(feature = "socketcan")]
fn node(interface: &str, seconds: Option<f64>, robot: &Robot) -> Result<(), Box<dyn Error>> {
    host_sim::sim::socketcan::run_node(interface, seconds, robot.node_config())
        .map_err(|e| format!("CAN interface {interface}: {e}").into())
}

#[cfg(not(feature = "socketcan"))]
fn node(interface: &str, _seconds: Option<f64>, _robot: &Robot) -> Result<(), Box<dyn Error>> {
    Err(format!(
        "cannot run the node on {interface}: this host-sim was built without SocketCAN \
         (cargo run -p host-sim --features socketcan -- node {interface})"
    )
    .into())
}

/// Creates `dir` (and its parents); the error names it.
fn create_dir(dir: &Path) -> Result<(), String> {
    fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the output directory {}: {e}", dir.display()))
}

/// Writes `contents` to `path`; the error names it.
fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), String> {
    fs::write(path, contents).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The scenario `name` (built-in, or a file ending in .toml) and the entry behind each of its
/// commands.
fn load_scenario(name: &str, robot: &Robot) -> Result<ScenarioFile, Box<dyn Error>> {
    if name.ends_with(".toml") {
        return Ok(scenario::file::load_file(Path::new(name))?);
    }
    let s: Scenario = robot.built_in(name).ok_or_else(|| {
        format!(
            "unknown scenario {name:?}; built-in: {} (or a .toml file)",
            [BUILT_IN.as_slice(), &scenario::DRIVEN].concat().join(", ")
        )
    })?;
    let entries = (0..s.timeline.len())
        .map(|i| Entry {
            label: format!("command #{}", i + 1),
            expect: None,
        })
        .collect();
    Ok(ScenarioFile {
        scenario: s,
        entries,
    })
}

fn run_scenario(
    name: &str,
    out: Option<&Path>,
    robot: &Robot,
    live: Option<u16>,
) -> Result<(), Box<dyn Error>> {
    let ScenarioFile {
        scenario: s,
        entries,
    } = load_scenario(name, robot)?;
    let default_out = PathBuf::from(format!("out/{}", s.name));
    let out = out.unwrap_or(&default_out);
    let name = s.name.as_str();
    let cfg = SimConfig {
        node: robot.node_config(),
        ..SimConfig::default()
    };
    let dt = cfg.node.params.dt;
    let sim = simulate(&s, &cfg).map_err(|e| format!("{name}: {e}"))?;
    let run = &sim.run;
    // A walk the model's legs cannot follow still writes its results (without the multi-body
    // columns), then fails.
    let (mb, mb_failure) = match evaluate(&robot.model, &run.trajectory, dt) {
        Ok(mb) => (mb, None),
        Err(e) => (Vec::new(), Some(e)),
    };
    let mb_error = if mb.is_empty() {
        f64::NAN
    } else {
        max_zmp_error(&run.trajectory, &mb)
    };
    create_dir(out)?;
    let traj = out.join("trajectory.csv");
    write_trajectory(&traj, run, &mb, dt)?;
    write_file(&out.join("can.log"), sim.can_log.join("\n") + "\n")?;
    let mcap = out.join("walk.mcap");
    host_sim::output::mcap::write_mcap(
        &mcap,
        &host_sim::output::mcap::McapInput {
            trajectory: &run.trajectory,
            dt,
            mb: &mb,
            can_log: &sim.can_log,
            cog_height: cfg.node.params.cog_height,
            sole: [
                2.0 * cfg.node.params.sole_half_length,
                2.0 * cfg.node.params.sole_half_width,
            ],
        },
    )?;
    let (along, across) = max_fluctuation(run);
    let results = outcomes(&s, &sim);
    let Report {
        lines,
        notes,
        unexpected,
        failed,
    } = report(&results, &entries, dt);
    let summary = json!({
        "scenario": name,
        "about": s.about,
        "robot": robot.name(),
        "duration_s": (run.trajectory.len() - 1) as f64 * dt,
        "ended_by_max_time": sim.cut,
        "adjust_s": run.adjustments.iter().map(|a| a.adjust_s).collect::<Vec<_>>(),
        "adjustments": run.adjustments.iter().map(|a| json!({
            "t_s": a.tick as f64 * dt, "adjust_s": a.adjust_s, "ratio": a.ratio,
            "plane": if a.plane == 0 { "x" } else { "y" }})).collect::<Vec<_>>(),
        "max_zmp_fluctuation_m": along.max(across),
        "max_zmp_fluctuation_along_m": along,
        "max_zmp_fluctuation_across_m": across,
        "max_mb_zmp_error_m": mb_error,
        "bus_load": sim.bus_load,
        "bus_bitrate": cfg.bitrate,
        "frames_sent": sim.bus.sent,
        "refused_commands": failed,
        "unexpected_outcomes": unexpected,
    });
    write_file(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    if let Some(port) = live {
        host_sim::output::live::serve_walk(port, robot, &run.trajectory, dt, &mb, &sim.can_log)?;
    }
    let mb_plot = (!mb.is_empty()).then_some(mb.as_slice());
    let walk = plot::Walk::from_run(name, &s, run, dt, cfg.node.params, mb_plot)?;
    let mut plots =
        plot::write_plots(out, &walk).map_err(|e| format!("plots in {}: {e}", out.display()))?;
    let velocity_lines = velocity::outputs(out, name, run, &cfg.node.params, &mut plots)?;
    if s.about.is_empty() {
        outln!("{name}");
    } else {
        outln!("{name}: {}", s.about);
    }
    outln!(
        "  {}: {:.2} s simulated in {} ticks of {} ms, over a virtual CAN bus at {} kbit/s (load {:.1} %){}",
        robot.name(),
        (run.trajectory.len() - 1) as f64 * dt,
        run.trajectory.len() - 1,
        dt * 1e3,
        cfg.bitrate / 1000,
        sim.bus_load * 100.0,
        if sim.cut { ", ended by max_time_s" } else { "" }
    );
    for a in &run.adjustments {
        outln!(
            "  re-plan at {:.3} s: single support adjusted by {:+.3} s (r = {:.3}, plane {})",
            a.tick as f64 * dt,
            a.adjust_s,
            a.ratio,
            if a.plane == 0 { "x" } else { "y" }
        );
    }
    velocity_lines.iter().for_each(|l| outln!("{l}"));
    outln!(
        "  largest ZMP fluctuation in single support: {:.1} mm along the foot, {:.1} mm across",
        along * 1e3,
        across * 1e3
    );
    outln!(
        "  largest multi-body ZMP error ({} model): {:.1} mm",
        robot.name(),
        mb_error * 1e3
    );
    outln!(
        "  results: {}, summary.json, can.log, walk.mcap and {} plots in {}",
        traj.display(),
        plots.len(),
        out.display()
    );
    for (note, ids) in &notes {
        outln!("  steps {}: {note}", ids.join(", "));
    }
    if !lines.is_empty() {
        outln!("  commands that failed (time sent, entry: command: what happened):");
        for l in &lines {
            outln!("{l}");
        }
    }
    if let Some(e) = mb_failure {
        return Err(Unexpected(format!(
            "{name}: the {} multi-body model cannot follow the walk: {e} (results written \
             without the multi-body columns)",
            robot.name()
        ))
        .into());
    }
    if unexpected > 0 {
        return Err(Unexpected(format!(
            "{name}: {unexpected} command{} did not go as the scenario expected (marked \
             UNEXPECTED above; a TOML entry that should fail says so with `expect`)",
            if unexpected == 1 { "" } else { "s" }
        ))
        .into());
    }
    Ok(())
}

fn replay_log(log: &Path, out: &Path, robot: &Robot) -> Result<(), Box<dyn Error>> {
    let text =
        fs::read_to_string(log).map_err(|e| format!("cannot read {}: {e}", log.display()))?;
    let cfg = robot.node_config();
    let dt = cfg.params.dt;
    let parsed = replay::parse(&text, dt).map_err(|e| format!("{}: {e}", log.display()))?;
    if parsed.frames.is_empty() {
        return Err(format!(
            "{}: nothing to replay: no frame for the node in the log ({} other frames skipped)",
            log.display(),
            parsed.skipped
        )
        .into());
    }
    let r = replay::replay(&parsed.frames, &cfg, SimConfig::default().bitrate)?;
    let run = Run {
        trajectory: r.trajectory,
        events: Vec::new(),
        adjustments: Vec::new(),
        footsteps: Vec::new(),
    };
    let mb = evaluate(&robot.model, &run.trajectory, dt).unwrap_or_else(|e| {
        outln!("  the multi-body model cannot follow the walk ({e}): no multi-body columns");
        Vec::new()
    });
    create_dir(out)?;
    write_trajectory(&out.join("trajectory.csv"), &run, &mb, dt)?;
    write_file(&out.join("can.log"), r.can_log.join("\n") + "\n")?;
    let refused: Vec<_> = r
        .acks
        .iter()
        .filter_map(|(k, a)| a.reason.map(|reason| (k, a, reason)))
        .map(|(k, a, reason)| {
            json!({
                "t_s": *k as f64 * dt,
                "command": host_sim::scenario::wire::command_name(a.command),
                "seq": a.seq,
                "reason": host_sim::scenario::expect::reason_name(reason),
            })
        })
        .collect();
    let summary = json!({
        "log": log.display().to_string(),
        "robot": robot.name(),
        "frames_replayed": r.replayed,
        "frames_skipped": parsed.skipped,
        "frames_lost": r.lost,
        "answers": r.acks.len(),
        "refused": refused,
        "duration_s": (run.trajectory.len() - 1) as f64 * dt,
        "ended_standing": !r.cut,
    });
    write_file(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    outln!(
        "{}: {} frames replayed into the {} node, {} answers, {:.2} s{}; results in {}",
        log.display(),
        r.replayed,
        robot.name(),
        r.acks.len(),
        (run.trajectory.len() - 1) as f64 * dt,
        if r.cut {
            " (cut: not standing at the end)"
        } else {
            ""
        },
        out.display()
    );
    if parsed.skipped > 0 {
        outln!(
            "  {} frames skipped: extended, remote or CAN FD frames (other nodes' traffic; the \
             node never receives them)",
            parsed.skipped
        );
    }
    for v in &refused {
        outln!(
            "  refused at {:.3} s: command {} seq/id {}: {}",
            v["t_s"].as_f64().unwrap_or(f64::NAN),
            v["command"].as_str().unwrap_or(""),
            v["seq"],
            v["reason"].as_str().unwrap_or("")
        );
    }
    if r.lost > 0 {
        outln!("  {} frames lost: a receive FIFO was full", r.lost);
    }
    if !refused.is_empty() || r.cut || r.lost > 0 {
        return Err(Unexpected(format!(
            "{}: {} command{} refused, {} frames lost{}",
            log.display(),
            refused.len(),
            if refused.len() == 1 { "" } else { "s" },
            r.lost,
            if r.cut {
                ", and the robot was still moving at the end"
            } else {
                ""
            }
        ))
        .into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// clap's own checks of every subcommand's arguments (unique names, valid defaults), which
    /// a release build skips.
    #[test]
    fn the_command_line_is_well_formed() {
        use clap::CommandFactory;
        super::Cli::command().debug_assert();
    }
}
