//! The `physics` command: a scenario through the node and the engine, and its files.
//!
//! `host-sim physics <scenario|file.toml> --out DIR` writes:
//!
//! * `DIR/physics.json`: `fell` (bool), `fall_time_s` (trajectory time, null if none),
//!   `fall_cause`, a fall after the end ([`super::metrics::SETTLE_AFTER_S`]) apart:
//!   `fell_after_end`, `fall_after_end_time_s`, `fall_after_end_cause`, `reference_stop_s`,
//!   `fall_window_end_s`, `ended_standing` (the trajectory's last reference standing, both
//!   feet down); `walked` and `verdict` (no fall and the gait within its bounds,
//!   [`super::gait`]), the gait measures `slip_max_m`, `flight_s`, `flight_max_s`,
//!   `cop_outside_s`, `cop_outside_max_s`, `cop_outside_max_m`, `landing_err_max_m`,
//!   `landings`, `gait_violations` and the bounds `gait_bounds`; `max_tilt_deg`, `cop_err_mean_m`, `cop_err_max_m` (see
//!   [`super::metrics`]), `cop_err_max_t_s`, `cog_drift_max_m`, `foot_drift_max_m`,
//!   `simulated_s`, `stabilizer`, `stabilizer_gains`, `servo_kp_kd`, `engine` (the MuJoCo
//!   version), `scenario`, `robot` (its name), `sole_half_m` (the sole box's half-extents),
//!   and the probe settings ([`super::probe::Probe::record`]: `stabilizer_scale`,
//!   `servo_damping`, for `weakest` `weakest_ladder`);
//! * `DIR/physics.csv`: the log every 5 ms (time, tilt, CoP, reference and desired ZMP, the
//!   50 ms tracking error, true and reference COG, waist height);
//! * `DIR/physics_tilt.png`, `DIR/physics_cop_x.png`, `DIR/physics_cop_y.png`: the tilt, and
//!   the measured CoP against the reference ZMP.

use std::fs;
use std::io::Write;
use std::path::Path;

use serde_json::{json, Value};

use super::{run, PhysicsConfig, PhysicsRun, Push};
use crate::output::plot::{write_time_plot, Curve};
use crate::robot::Robot;

use crate::sim::scenario_trajectory;

/// The JSON of a run of `robot` (its name).
pub fn report_json(name: &str, robot: &str, cfg: &PhysicsConfig, r: &PhysicsRun) -> Value {
    let p = &r.report;
    let mut j = json!({
        "scenario": name,
        "robot": robot,
        "sole_half_m": cfg.robot.sole_half(),
        "fell": p.fell,
        "fall_time_s": p.fall_time_s,
        "fall_cause": p.fall_cause.map(|c| c.name()),
        "max_tilt_deg": p.max_tilt_deg,
        "cop_err_mean_m": p.cop_err_mean_m,
        "cop_err_max_m": p.cop_err_max_m,
        "cop_err_max_t_s": p.cop_err_max_t_s,
        "cog_drift_max_m": p.cog_drift_max_m,
        "foot_drift_max_m": p.foot_drift_max_m,
        "simulated_s": p.simulated_s,
        "stabilizer": cfg.gains.enabled,
        "stabilizer_gains": format!("{:?}", cfg.gains),
        "servo_kp_kd": cfg.robot.servo(),
        "engine": format!("MuJoCo {}", p.engine),
        "physics_dt_s": super::PHYSICS_DT,
        "gait_bounds": super::gait::GaitQuality::bounds_json(),
        "push": cfg.push.map(|p| json!({"t_s": p.t_s, "duration_s": p.duration_s, "force_n": p.force})),
    });
    p.add_end_fields(&mut j);
    j
}

fn write_csv(path: &Path, r: &PhysicsRun) -> Result<(), String> {
    let named = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let mut f = std::io::BufWriter::new(fs::File::create(path).map_err(named)?);
    writeln!(
        f,
        "t,tilt_deg,cop_x,cop_y,zmp_ref_x,zmp_ref_y,zmp_des_x,zmp_des_y,zmp_ft_x,zmp_ft_y,cop_err,cog_x,cog_y,cog_ref_x,cog_ref_y,base_z"
    )
    .map_err(named)?;
    for s in &r.samples {
        writeln!(
            f,
            "{:.3},{:.4},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5}",
            s.t,
            s.tilt_deg,
            s.cop[0],
            s.cop[1],
            s.zmp_ref[0],
            s.zmp_ref[1],
            s.zmp_desired[0],
            s.zmp_desired[1],
            s.zmp_sensed[0],
            s.zmp_sensed[1],
            s.cop_err,
            s.cog[0],
            s.cog[1],
            s.cog_ref[0],
            s.cog_ref[1],
            s.base_z
        )
        .map_err(named)?;
    }
    f.flush().map_err(named)
}

/// The 50 ms moving average of the CoP samples (every 5 ms: 10 samples), as plotted.
fn smoothed(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for i in 9..points.len() {
        let w = &points[i - 9..=i];
        if w.iter().all(|p| p.1.is_finite()) {
            out.push((points[i].0, w.iter().map(|p| p.1).sum::<f64>() / 10.0));
        }
    }
    out
}

/// How the run was controlled, for the captions: `open loop`, `stabilized`, or `stabilizer
/// × s` for weakened gains ([`super::probe`]); `, contact from the reference` follows when the
/// stabilizer takes the contact phase from the reference instead of the force sensors.
fn mode(cfg: &PhysicsConfig) -> String {
    let full = super::stabilizer::Gains::default();
    let g = cfg.gains;
    if !g.enabled {
        return "open loop".into();
    }
    let gains = super::stabilizer::Gains {
        contact_from_sensors: full.contact_from_sensors,
        design_delay_s: full.design_delay_s,
        ..g
    };
    let mut m = if gains == full {
        "stabilized".to_string()
    } else {
        format!(
            "stabilizer × {}",
            (g.k_cog / full.k_cog * 1e3).round() / 1e3
        )
    };
    if !g.contact_from_sensors {
        m += ", contact from the reference";
    }
    if g.design_delay_s > 0.0 {
        m += &format!(", gains designed for {} ms", g.design_delay_s * 1e3);
    }
    m
}

/// Writes `physics.json`, `physics.csv` and the plots into `out` (`robot`: its name); returns
/// the names of the files written, in that order.
pub fn write_outputs(
    out: &Path,
    name: &str,
    robot: &str,
    cfg: &PhysicsConfig,
    r: &PhysicsRun,
) -> Result<Vec<String>, String> {
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let json = serde_json::to_string_pretty(&report_json(name, robot, cfg, r))
        .map_err(|e| e.to_string())?;
    let path = out.join("physics.json");
    fs::write(&path, json).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    write_csv(&out.join("physics.csv"), r)?;
    let mut written = vec!["physics.json".to_string(), "physics.csv".to_string()];
    if r.samples.is_empty() {
        // A fall before the first sample (in the settle before the walk): nothing to plot.
        return Ok(written);
    }
    let mode = mode(cfg);
    let tilt: Vec<(f64, f64)> = r.samples.iter().map(|s| (s.t, s.tilt_deg)).collect();
    let limit: Vec<(f64, f64)> = r
        .samples
        .iter()
        .map(|s| (s.t, super::metrics::FALL_TILT_DEG))
        .step_by(20)
        .collect();
    let mut plot = |file: &str, caption: String, axis: &str, curves: &[Curve]| {
        let p = out.join(file);
        write_time_plot(&p, &caption, axis, curves).map_err(|e| format!("{}: {e}", p.display()))?;
        written.push(file.to_string());
        Ok::<(), String>(())
    };
    plot(
        "physics_tilt.png",
        format!("{name} in MuJoCo ({mode}): waist tilt"),
        "tilt [deg]",
        &[
            ("waist tilt".into(), (0x1f, 0x5f, 0xbf), tilt),
            ("fall threshold".into(), (0x80, 0x80, 0x80), limit),
        ],
    )?;
    for (q, axis) in ["x", "y"].iter().enumerate() {
        let cop: Vec<(f64, f64)> = r.samples.iter().map(|s| (s.t, s.cop[q])).collect();
        plot(
            &format!("physics_cop_{axis}.png"),
            format!("{name} in MuJoCo ({mode}): CoP {axis} against the reference ZMP"),
            &format!("{axis} [m]"),
            &[
                (
                    format!("ZMP {axis} (reference)"),
                    (0xd6, 0x27, 0x28),
                    r.samples.iter().map(|s| (s.t, s.zmp_ref[q])).collect(),
                ),
                (
                    format!("CoP {axis} (engine, 50 ms)"),
                    (0x2c, 0xa0, 0x2c),
                    smoothed(&cop),
                ),
                (
                    format!("COG {axis} (engine)"),
                    (0x1f, 0x5f, 0xbf),
                    r.samples.iter().map(|s| (s.t, s.cog[q])).collect(),
                ),
            ],
        )?;
    }
    Ok(written)
}

/// The `physics` command: runs the scenario with `robot` (`cfg.robot` should be
/// [`super::model::Robot::of`] it), writes the files, returns the JSON and the names of the
/// files written.
pub fn physics_command(
    name: &str,
    out: &Path,
    robot: &Robot,
    cfg: &PhysicsConfig,
) -> Result<(Value, Vec<String>), String> {
    let (j, written, _) = physics_played(name, out, robot, cfg)?;
    Ok((j, written))
}

/// What a `physics` run played: the trajectory, its tick \[s\] and the engine's run.
pub struct Played {
    /// The node's references.
    pub trajectory: Vec<planner_core::gait::Reference<f64>>,
    /// Their tick \[s\].
    pub dt: f64,
    /// The run in the engine.
    pub run: super::PhysicsRun,
}

/// [`physics_command`], handing back what was played as well (for the live view).
pub fn physics_played(
    name: &str,
    out: &Path,
    robot: &Robot,
    cfg: &PhysicsConfig,
) -> Result<(Value, Vec<String>, Played), String> {
    let (sname, trajectory, dt) = scenario_trajectory(name, robot)?;
    let r = run(&trajectory, dt, cfg).map_err(|e| format!("{sname} in MuJoCo: {e}"))?;
    let written = write_outputs(out, &sname, robot.name(), cfg, &r)?;
    let j = report_json(&sname, robot.name(), cfg, &r);
    Ok((
        j,
        written,
        Played {
            trajectory,
            dt,
            run: r,
        },
    ))
}

/// Plays an engine run on the live view in real time: every sample's reference, the robot's
/// links (`/tf`, from the engine's waist pose and the leg encoders) and the measured COG and
/// CoP.
pub fn play_live(view: &crate::output::live::LiveView, cfg: &PhysicsConfig, played: &Played) {
    use crate::output::live::{quaternion_of, LinkPose};
    let start = std::time::Instant::now();
    let first = played.run.samples.first().map(|s| s.t).unwrap_or(0.0);
    for s in &played.run.samples {
        let due = std::time::Duration::from_secs_f64((s.t - first).max(0.0));
        if let Some(wait) = due.checked_sub(start.elapsed()) {
            std::thread::sleep(wait);
        }
        let r = super::reference_at(&played.trajectory, played.dt, s.t.max(0.0));
        view.sample(s.t.max(0.0), &r, None);
        view.measured(s.t.max(0.0), s.cog, s.cop);
        let base = crate::robot::model::Pose {
            p: s.base.0,
            r: super::quat_to_mat(s.base.1),
        };
        let links: Vec<LinkPose> = cfg
            .robot
            .link_frames(&base, &s.legs)
            .into_iter()
            .map(|(name, p)| LinkPose {
                child: name,
                parent: crate::output::mcap::WORLD_FRAME.to_string(),
                position: p.p,
                orientation: quaternion_of(&p.r),
            })
            .collect();
        view.transforms(s.t.max(0.0), &links);
    }
}

/// The line that names the files a `physics` run wrote into `out`.
pub fn results_line(out: &Path, written: &[String]) -> String {
    format!("  results in {}: {}", out.display(), written.join(", "))
}

/// Parses `--push T,FX,FY`: a push of 0.1 s starting at `T` (trajectory time) \[s\] with the
/// horizontal force `(FX, FY)` \[N\].
pub fn parse_push(s: &str) -> Result<Push, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--push {s:?}: expected T,FX,FY (numbers)"))?;
    match v[..] {
        [t, fx, fy] if v.iter().all(|x| x.is_finite()) => Ok(Push {
            t_s: t,
            duration_s: 0.1,
            force: [fx, fy],
        }),
        _ => Err(format!(
            "--push {s:?}: expected T,FX,FY (three finite numbers)"
        )),
    }
}

/// The command line's `physics` subcommand: runs `robot`, writes, prints the figures; the
/// stabilizer and the servos as the probe options say (see [`super::probe`]; recorded in
/// `physics.json`).
pub fn cli(
    name: &str,
    out: Option<&Path>,
    robot: &Robot,
    push: Option<&str>,
    probe: &super::probe::ProbeArgs,
    live: Option<&crate::output::live::LiveView>,
) -> Result<(), Box<dyn std::error::Error>> {
    let probe = probe.resolve(robot)?;
    let mut cfg = probe.cfg.clone();
    cfg.push = push.map(parse_push).transpose()?;
    let default_out;
    let out = match out {
        Some(o) => o,
        None => {
            let stem = Path::new(name)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| name.to_string());
            default_out = Path::new("out/physics").join(stem);
            &default_out
        }
    };
    let (mut j, written, played) = physics_played(name, out, robot, &cfg)?;
    if let Some(view) = live {
        if view.wait_for_client(
            std::time::Duration::from_secs(60),
            std::time::Duration::from_millis(500),
        ) {
            play_live(view, &cfg, &played);
            crate::outln!("live view: played the run");
        } else {
            crate::outln!("live view: no client within 60 s");
        }
    }
    probe.record(&mut j);
    let path = out.join("physics.json");
    fs::write(&path, serde_json::to_string_pretty(&j)?)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let num = |k: &str| j[k].as_f64().unwrap_or(f64::NAN);
    crate::outln!(
        "{} ({}): {} in MuJoCo ({}), {:.2} s simulated (walk and tail; {:.2} s in the engine \
         with the {} s settle before it)",
        j["scenario"].as_str().unwrap_or(name),
        robot.name(),
        if j["fell"].as_bool() == Some(true) {
            format!(
                "FELL at {:.3} s ({})",
                num("fall_time_s"),
                j["fall_cause"].as_str().unwrap_or("?")
            )
        } else {
            let gait = if j["walked"].as_bool() == Some(true) {
                "walked (no fall, gait within bounds)".to_string()
            } else {
                format!(
                    "DID NOT WALK (no fall, but beyond bounds: {})",
                    j["gait_violations"]
                        .as_array()
                        .map(|v| v
                            .iter()
                            .filter_map(|x| x.as_str())
                            .collect::<Vec<_>>()
                            .join(", "))
                        .unwrap_or_default()
                )
            };
            if j["fell_after_end"].as_bool() == Some(true) {
                format!(
                    "{gait}; fell after the end, at {:.3} s: {}",
                    num("fall_after_end_time_s"),
                    j["fall_after_end_cause"].as_str().unwrap_or("?")
                )
            } else {
                gait
            }
        },
        mode(&cfg),
        num("simulated_s"),
        cfg.settle_s + num("simulated_s"),
        cfg.settle_s
    );
    crate::outln!(
        "  max tilt {:.2} deg; CoP vs reference ZMP (50 ms): mean {:.1} mm, worst {:.1} mm; COG drift {:.1} mm, foot drift {:.1} mm",
        num("max_tilt_deg"),
        num("cop_err_mean_m") * 1e3,
        num("cop_err_max_m") * 1e3,
        num("cog_drift_max_m") * 1e3,
        num("foot_drift_max_m") * 1e3
    );
    crate::outln!(
        "  slip {:.1} mm, {:.3} rad (bounds {:.0}, {}); flight {:.0} ms, longest {:.0} ms (bound {:.0}); CoP \
         outside the support polygon {:.0} ms, longest {:.0} ms (bound {:.0}), farthest {:.1} mm; \
         landing error {:.1} mm, {:.3} rad (bounds {:.0}, {}) over {} landings",
        num("slip_max_m") * 1e3,
        num("slip_yaw_max_rad"),
        super::gait::SLIP_MAX_M * 1e3,
        super::gait::SLIP_YAW_MAX_RAD,
        num("flight_s") * 1e3,
        num("flight_max_s") * 1e3,
        super::gait::FLIGHT_MAX_S * 1e3,
        num("cop_outside_s") * 1e3,
        num("cop_outside_max_s") * 1e3,
        super::gait::COP_OUTSIDE_MAX_S * 1e3,
        num("cop_outside_max_m") * 1e3,
        num("landing_err_max_m") * 1e3,
        num("landing_yaw_err_max_rad"),
        super::gait::LANDING_MAX_M * 1e3,
        super::gait::LANDING_YAW_MAX_RAD,
        j["landings"].as_u64().unwrap_or(0)
    );
    if j["ended_standing"].as_bool() == Some(false) {
        crate::outln!("  the scenario's walk did not end standing (cut at its max_time_s?)");
    }
    crate::outln!("{}", results_line(out, &written));
    match super::start::not_started(&j) {
        Some(why) => Err(why.into()),
        None => Ok(()),
    }
}

/// The command line's `physics-tables` subcommand: the cells (`all`, or `r,c;r,c`) both ways,
/// `DIR/physics_tables.json` and `DIR/physics_tables.md`, with `robot` (its gait parameters,
/// link table and soles; it must stand as HRP-2, the grid being HRP-2's footsteps) and the
/// probe options (see [`super::probe`]; recorded in the JSON).
pub fn tables_cli(
    out: &Path,
    cells: &str,
    robot: &Robot,
    probe: &super::probe::ProbeArgs,
) -> Result<(), Box<dyn std::error::Error>> {
    use super::tables::{cell, cell_text, markdown, parse_cells, side_by_side_text, tables_json};
    let list = parse_cells(cells)?;
    robot.check_hrp2_footsteps("physics-tables")?;
    let probe = probe.resolve(robot)?;
    let cfg = probe.cfg.clone();
    let mode = probe.mode();
    let mut done = Vec::new();
    let bar = crate::console::Progress::new("physics-tables", list.len() as u64);
    for &(r, c) in &list {
        bar.message(format!("cell ({r}, {c})"));
        done.push(
            cell(r, c, &robot.planner.params, &cfg).map_err(|e| format!("cell ({r}, {c}): {e}"))?,
        );
        bar.inc(format!("cell ({r}, {c})"));
    }
    drop(bar);
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let path = out.join("physics_tables.json");
    let mut json = tables_json(&done);
    probe.record(&mut json);
    json["robot"] = robot.name().into();
    fs::write(&path, serde_json::to_string_pretty(&json)?)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let mut md = markdown(
        &format!(
            "Plain re-plan (Table I: no adjustment, no shaping) in MuJoCo, {mode}: fell / ok, \
             worst 50 ms CoP error of the modified step [cm] / kinematic multi-body ZMP error [cm]"
        ),
        &done,
        |c| cell_text(&c.plain, c.cop_err_modified_plain_m, c.mb_error_plain_m),
    );
    md += "\n";
    md += &markdown(
        &format!(
            "Proposed method (Table II: adjustment and shaping) in MuJoCo, {mode}: fell / ok, \
             worst 50 ms CoP error of the modified step [cm] / kinematic multi-body ZMP error [cm]"
        ),
        &done,
        |c| {
            cell_text(
                &c.proposed,
                c.cop_err_modified_proposed_m,
                c.mb_error_proposed_m,
            )
        },
    );
    let count = |f: &dyn Fn(&super::tables::Cell) -> bool| done.iter().filter(|c| f(c)).count();
    md += "\n";
    md += &markdown(
        &format!(
            "Side by side, {mode}: plain re-plan / proposed method fell or ok, their kinematic \
             multi-body ZMP errors [cm] (* above the paper's 0.07 m)"
        ),
        &done,
        side_by_side_text,
    );
    md += &probe.ladder_markdown();
    let late = |r: &Option<super::PhysicsReport>| r.as_ref().is_some_and(|r| r.fell_after_end);
    let cut = |r: &Option<super::PhysicsReport>| r.as_ref().is_some_and(|r| !r.ended_standing);
    md += &format!(
        "\n{} cells simulated; falls: plain {}, proposed {}; not walked (a fall or a gait \
         measure beyond its bound): plain {}, proposed {}; falls after the end (not counted): \
         plain {}, proposed {}; trajectories not ending standing: {}.\n\n{}\n",
        done.len(),
        count(&|c| c.plain.as_ref().is_some_and(|r| r.fell)),
        count(&|c| c.proposed.as_ref().is_some_and(|r| r.fell)),
        count(&|c| c.plain.as_ref().is_some_and(|r| !r.walked())),
        count(&|c| c.proposed.as_ref().is_some_and(|r| !r.walked())),
        count(&|c| late(&c.plain)),
        count(&|c| late(&c.proposed)),
        count(&|c| cut(&c.plain)) + count(&|c| cut(&c.proposed)),
        super::AFTER_END_NOTE
    );
    let mdpath = out.join("physics_tables.md");
    fs::write(&mdpath, &md).map_err(|e| format!("cannot write {}: {e}", mdpath.display()))?;
    crate::outln!("{md}");
    crate::outln!("results: {} and {}", path.display(), mdpath.display());
    Ok(())
}

/// The command line's `physics-faults` subcommand: the sweep rows (`all` or indices) of a walk
/// with `seed` through `robot`'s node and the engine, with the probe options (see
/// [`super::probe`]); `DIR/physics_faults.json` (the settings and the runs, see
/// [`super::fault_sweep`]) and `.md`.
pub fn faults_cli(
    out: &Path,
    rows: &str,
    walk: crate::eval::faults::Walk,
    seed: u64,
    robot: &Robot,
    probe: &super::probe::ProbeArgs,
) -> Result<(), Box<dyn std::error::Error>> {
    use super::fault_sweep::{json, markdown, parse_rows_of, sweep_walk};
    let idx = parse_rows_of(rows, walk)?;
    robot.check_hrp2_footsteps("physics-faults")?;
    let probe = probe.resolve(robot)?;
    let runs = sweep_walk(&idx, walk, seed, robot, &probe.cfg)?;
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let path = out.join("physics_faults.json");
    let mut j = serde_json::json!({
        "robot": robot.name(),
        "seed": seed,
        "walk": walk.name(),
        "runs": json(&runs),
    });
    probe.record(&mut j);
    fs::write(&path, serde_json::to_string_pretty(&j)?)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let md = format!(
        "Probe: {}.\n\n{}{}",
        probe.mode(),
        markdown(&runs),
        probe.ladder_markdown()
    );
    let mdpath = out.join("physics_faults.md");
    fs::write(&mdpath, &md).map_err(|e| format!("cannot write {}: {e}", mdpath.display()))?;
    crate::outln!("{md}");
    let falls = runs.iter().filter(|r| r.report.fell).count();
    crate::outln!(
        "{} runs, {falls} fell in the engine; results: {} and {}",
        runs.len(),
        path.display(),
        mdpath.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_parses() {
        let p = parse_push("3.0,150,-20").unwrap();
        assert_eq!((p.t_s, p.force, p.duration_s), (3.0, [150.0, -20.0], 0.1));
        assert!(parse_push("3.0,150").is_err());
        assert!(parse_push("x,1,2").is_err());
        assert!(parse_push("inf,1,2").is_err());
    }

    #[test]
    fn smoothing_is_a_50_ms_mean() {
        let pts: Vec<(f64, f64)> = (0..12).map(|k| (k as f64 * 0.005, k as f64)).collect();
        let s = smoothed(&pts);
        assert_eq!(s.len(), 3);
        assert!((s[0].1 - 4.5).abs() < 1e-12 && (s[0].0 - 0.045).abs() < 1e-12);
    }
}
