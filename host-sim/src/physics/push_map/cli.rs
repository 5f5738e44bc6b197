//! The `push-map` command: its arguments and what it writes (`push_map.json`, `push_map.md`,
//! a polar plot per phase, or one cell as a JSON line).

use std::fs;
use std::path::Path;

use serde_json::{json, Value};

use super::{
    cell, map, map_json, markdown, scan_cell, summary_lines, Cell, Convention, MapSpec, PUSH_S,
};
use crate::physics::closed_loop::{PushPhase, Stepping};

/// Parses `--phases` (comma-separated names).
pub fn parse_phases(s: &str) -> Result<Vec<PushPhase>, String> {
    s.split(',')
        .map(|p| {
            PushPhase::parse(p.trim()).ok_or_else(|| {
                format!(
                    "unknown phase {p:?} (one of {})",
                    PushPhase::ALL.map(PushPhase::name).join(", ")
                )
            })
        })
        .collect()
}

/// Parses `--directions` (comma-separated degrees).
pub fn parse_directions(s: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|d| {
            d.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| (-180.0..=360.0).contains(v))
                .ok_or_else(|| {
                    format!("{d:?} is not a direction in degrees (-180 … 360, 0 forward, 90 left)")
                })
        })
        .collect()
}

/// What the `push-map` command was asked for.
#[derive(Clone, Debug)]
pub struct MapArgs<'a> {
    /// The output directory (not used with `cell`).
    pub out: &'a Path,
    /// The quick map.
    pub quick: bool,
    /// `--phases`.
    pub phases: Option<&'a str>,
    /// `--directions`.
    pub directions: Option<&'a str>,
    /// The node re-plans a capture step from the measured state rather than from the
    /// reference's (its default).
    pub from_measured: bool,
    /// `--cell CONFIG,PHASE,DIRECTION`: that cell only, one JSON line on standard output.
    pub cell: Option<&'a str>,
    /// `--push force|velocity`.
    pub push: &'a str,
    /// `--scan`: each cell's scan around its bisected force ([`crate::physics::push_scan`]),
    /// in the cell's line or in the map's table, JSON and summary.
    pub scan: bool,
}

/// Parses `--cell CONFIG,PHASE,DIRECTION` (for example `proposed,double,90`).
pub fn parse_cell(s: &str) -> Result<(Stepping, PushPhase, f64), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [config, phase, direction] = parts.as_slice() else {
        return Err(format!(
            "--cell {s:?}: expected CONFIG,PHASE,DIRECTION (for example proposed,double,90)"
        ));
    };
    let stepping = Stepping::ALL
        .into_iter()
        .find(|st| st.name() == *config)
        .ok_or_else(|| {
            format!(
                "unknown configuration {config:?} (one of {})",
                Stepping::ALL.map(Stepping::name).join(", ")
            )
        })?;
    let phase = parse_phases(phase)?[0];
    let direction = parse_directions(direction)?[0];
    Ok((stepping, phase, direction))
}

/// The JSON line of `push-map --cell`: the robot, its mass and the cell (with its
/// configuration and engine runs).
pub fn cell_line(robot: &str, mass_kg: f64, resolution_bw: f64, c: &Cell) -> Value {
    let mut j = c.json();
    j["robot"] = Value::String(robot.into());
    j["mass_kg"] = json!(mass_kg);
    j["config"] = Value::String(c.stepping.name().into());
    if c.convention == Convention::Force {
        j["push_duration_s"] = json!(PUSH_S);
    }
    j["resolution_bw"] = json!(resolution_bw);
    j["engine_runs"] = json!(c.runs);
    j
}

/// The `push-map` command: the map of `robot`, written to `args.out` (`push_map.json`,
/// `push_map.md`, a polar plot per phase), or one cell as a JSON line. Failed cells are written
/// as failed; the command then ends with an error that names them.
pub fn cli(
    args: &MapArgs,
    robot: &crate::robot::Robot,
    probe: &crate::physics::probe::ProbeArgs,
) -> Result<(), Box<dyn std::error::Error>> {
    let probe = probe.resolve(robot)?;
    let cfg = probe.cfg;
    let mut spec = MapSpec::new(args.quick);
    if let Some(p) = args.phases {
        spec.phases = parse_phases(p)?;
    }
    if let Some(d) = args.directions {
        spec.directions = parse_directions(d)?;
    }
    spec.convention = Convention::parse(args.push)
        .ok_or_else(|| format!("--push {:?}: force or velocity", args.push))?;
    if args.scan && spec.convention != Convention::Force {
        return Err("--scan pushes with forces: not with --push velocity".into());
    }
    spec.scan = args.scan;
    let cell_asked = args.cell.map(parse_cell).transpose()?;
    // An engine that cannot start fails the command, not each cell.
    crate::physics::bridge::installed_version(&crate::physics::bridge::python())?;
    let mut node = robot.node_config();
    node.adjust.from_measured = args.from_measured;
    let mass = cfg.robot.total_mass();
    if let Some((s, p, d)) = cell_asked {
        let (c, scan) = if args.scan {
            match scan_cell(&node, &cfg, s, p, d, spec.resolution_bw) {
                Ok((c, scan)) => (c, Some(scan)),
                Err(e) => (Cell::failed(s, p, d, e), None),
            }
        } else {
            (
                cell(&node, &cfg, s, p, d, spec.resolution_bw, spec.convention),
                None,
            )
        };
        let mut line = cell_line(robot.name(), mass, spec.resolution_bw, &c);
        if let Some(scan) = scan {
            line["scan"] = scan.json();
        }
        crate::outln!("{line}");
        return match c.error {
            Some(e) => Err(format!("the cell failed: {e}").into()),
            None => Ok(()),
        };
    }
    let out = args.out;
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let cells = map(&node, &cfg, &spec);
    let j = map_json(robot.name(), mass, &spec, &cells);
    let sums = summary_lines(&spec, &cells);
    let write = |name: &str, text: String| {
        let path = out.join(name);
        fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
    };
    write("push_map.json", serde_json::to_string_pretty(&j)?)?;
    let md = format!("{}\n{sums}", markdown(&spec, &cells));
    write("push_map.md", md.clone())?;
    for &p in &spec.phases {
        let series: Vec<(&str, Vec<(f64, f64)>)> = spec
            .steppings
            .iter()
            .map(|&s| {
                (
                    s.name(),
                    cells
                        .iter()
                        .filter(|c| c.stepping == s && c.phase == p && c.ok())
                        .map(|c| (c.direction_deg, c.dv_mps))
                        .collect(),
                )
            })
            .collect();
        crate::output::plot::polar::write_polar(
            &out.join(format!("push_map_{}.png", p.name())),
            &format!(
                "{}: largest push walked through, {}",
                robot.name(),
                p.name()
            ),
            &series,
        )?;
    }
    crate::out!("{md}");
    crate::outln!(
        "{} engine runs; wrote {}",
        cells.iter().map(|c| c.runs).sum::<usize>(),
        out.join("push_map.json").display()
    );
    let failed: Vec<String> = cells
        .iter()
        .filter_map(|c| {
            c.error.as_ref().map(|e| {
                format!(
                    "{}, {}, {}°: {e}",
                    c.stepping.name(),
                    c.phase.name(),
                    c.direction_deg
                )
            })
        })
        .collect();
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} of {} cells failed (written as failed):\n  {}",
            failed.len(),
            cells.len(),
            failed.join("\n  ")
        )
        .into())
    }
}
