//! The push-recovery map (`host-sim push-map`): for every phase of the walk and direction, the
//! largest horizontal push on the trunk's centre of mass that does not fell the robot, with the
//! stabilizer only, with step adjustment and the plain re-plan, and with step adjustment and
//! the proposed method ([`Stepping`]).
//!
//! # Protocol
//!
//! The protocol of IHMC's Atlas push-recovery tests: a force `F` for `Δt` = 0.1 s, reported as
//! the velocity change `Δv = F Δt / m` \[m/s\] (`m` the robot's total mass) and as the fraction
//! of body weight `F / (m g)`. The walk is [`Walk::default`] (straight, 0.15 m steps); the
//! push comes in the double support after the second landing, or at the start, in the middle,
//! or at the end of the third single support ([`PushPhase`]); its direction is in the walking
//! frame (0° forward, 90° to the left: outward for the left support foot of the third single
//! support). Each cell is a bisection on the force between 0 and one body weight, down to 2 %
//! of body weight (`--quick`: 12.5 %); the reported force is the largest one that was walked
//! through, and `steps_adjusted` the steps that this run landed away from their commanded
//! positions.
//!
//! Each cell is also given as the impulse `F Δt` \[N·s\].
//!
//! `--push velocity` maps the convention of learning-based locomotion benchmarks instead: at
//! the same instant, the floating base's horizontal velocity is **set** to `v` in the push's
//! direction (the rest of the state unchanged), and each cell is the largest `v` walked
//! through, bisected between 0 and [`V_MAX_MPS`] down to the same fraction of it. Such a push
//! replaces the walk's own velocity rather than adding to it, and it acts on the base's
//! velocity, not on the whole body's momentum, so its `v` is not the `Δv` of a force push.
//!
//! A cell whose engine run cannot be
//! carried out (a leg out of reach in the inverse kinematics, the walk never reaching the push)
//! is reported as failed with its cause; it never stops the rest of the map, and the command
//! ends with an error naming the failed cells after writing everything else.
//!
//! The engine runs of different cells are independent: they run on every core, or one cell per
//! process with `--cell CONFIG,PHASE,DIRECTION` (one JSON line on standard output), so that a
//! large map can be spread over machines by any scheduler.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use serde_json::{json, Value};

use super::closed_loop::{run, PushKind, PushPhase, PushSpec, Stepping, Walk};
use super::PhysicsConfig;
use planner_core::node::NodeConfig;

mod cli;
pub use cli::{cell_line, cli, parse_cell, parse_directions, parse_phases, MapArgs};

/// The push duration \[s\].
pub const PUSH_S: f64 = 0.1;
/// The bisection's resolution as a fraction of body weight.
pub const RESOLUTION_BW: f64 = 0.02;
/// The same for `--quick`.
pub const QUICK_RESOLUTION_BW: f64 = 0.125;
/// The largest push tried \[fraction of body weight\].
pub const MAX_BW: f64 = 1.0;
/// The largest base velocity tried by a velocity push \[m/s\].
pub const V_MAX_MPS: f64 = 1.5;

/// How a push is given: a force for [`PUSH_S`], or the base's velocity set at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Convention {
    /// A force on the trunk for [`PUSH_S`], bisected in fractions of body weight.
    #[default]
    Force,
    /// The base's horizontal velocity set to `v`, bisected in fractions of [`V_MAX_MPS`].
    Velocity,
}

impl Convention {
    /// The name on the command line and in `push_map.json`.
    pub fn name(self) -> &'static str {
        match self {
            Convention::Force => "force",
            Convention::Velocity => "velocity",
        }
    }

    /// The convention named `s`.
    pub fn parse(s: &str) -> Option<Self> {
        [Convention::Force, Convention::Velocity]
            .into_iter()
            .find(|c| c.name() == s)
    }
}

/// The phases of `--quick`.
pub const QUICK_PHASES: [PushPhase; 2] = [PushPhase::Double, PushPhase::SingleMiddle];
/// The directions of `--quick` \[deg\].
pub const QUICK_DIRECTIONS: [f64; 4] = [0.0, 90.0, 180.0, 270.0];

/// IHMC's Atlas push-recovery thresholds \[m/s\] (forward, backward, inward, outward in
/// transfer), for the tables and plots.
pub const ATLAS: [(&str, f64); 4] = [
    ("forward", 0.78),
    ("backward", 0.49),
    ("inward", 0.22),
    ("outward in transfer", 0.25),
];
/// iCub's: 150 N for 0.05 s on 33 kg \[m/s\].
pub const ICUB_DV: f64 = 150.0 * 0.05 / 33.0;

/// One cell of the map.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// The configuration.
    pub stepping: Stepping,
    /// The phase.
    pub phase: PushPhase,
    /// The direction \[deg\].
    pub direction_deg: f64,
    /// How the push was given.
    pub convention: Convention,
    /// The largest force walked through \[N\] (0 for a velocity push).
    pub max_force_n: f64,
    /// Its velocity change \[m/s\]; for a velocity push, the largest base velocity set and
    /// walked through.
    pub dv_mps: f64,
    /// Its fraction of body weight (for a velocity push: of [`V_MAX_MPS`]).
    pub bw_fraction: f64,
    /// Steps landed away from their commanded positions in that run.
    pub steps_adjusted: usize,
    /// Engine runs of the bisection (and of the scan, with `--scan`).
    pub runs: usize,
    /// The gait measures of the run at the largest force walked through (of the unpushed
    /// run when none was): slip, flight, the CoP outside the support polygon and the landing
    /// error ([`super::gait`]); the bisection's survival is the fall's.
    pub gait: super::gait::GaitQuality,
    /// Why the cell could not be measured (its force fields are then 0).
    pub error: Option<String>,
    /// The scan around the bisected force (`--scan`; [`super::push_scan`]).
    pub scan: Option<super::push_scan::Scan>,
}

impl Cell {
    /// The cell's entry in `push_map.json` (`error` only for a failed cell).
    /// A velocity push's cell has `v_mps` and `dv_mps` (the velocity set) and no force fields.
    pub fn json(&self) -> Value {
        let mut j = json!({
            "phase": self.phase.name(),
            "direction_deg": self.direction_deg,
            "push": self.convention.name(),
            "dv_mps": self.dv_mps,
            "steps_adjusted": self.steps_adjusted,
            "gait_within_bounds": self.gait.within_bounds(),
            "gait": self.gait.fields().into_iter().map(|(k, v)| (k.to_string(), v)).collect::<serde_json::Map<_, _>>(),
        });
        match self.convention {
            Convention::Force => {
                j["max_force_n"] = json!(self.max_force_n);
                j["impulse_ns"] = json!(self.impulse_ns());
                j["bw_fraction"] = json!(self.bw_fraction);
            }
            Convention::Velocity => j["v_mps"] = json!(self.dv_mps),
        }
        if let Some(e) = &self.error {
            j["error"] = Value::String(e.clone());
        }
        if let Some(scan) = &self.scan {
            j["scan"] = scan.json();
        }
        j
    }

    /// The push's impulse `F Δt` \[N·s\].
    pub fn impulse_ns(&self) -> f64 {
        self.max_force_n * PUSH_S
    }

    /// `true` when the cell was measured.
    pub fn ok(&self) -> bool {
        self.error.is_none()
    }

    /// A failed cell: `error` is why.
    pub fn failed(stepping: Stepping, phase: PushPhase, direction_deg: f64, error: String) -> Self {
        Self {
            stepping,
            phase,
            direction_deg,
            convention: Convention::Force,
            max_force_n: 0.0,
            dv_mps: 0.0,
            bw_fraction: 0.0,
            steps_adjusted: 0,
            runs: 0,
            gait: Default::default(),
            error: Some(error),
            scan: None,
        }
    }
}

/// What to map.
#[derive(Clone, Debug)]
pub struct MapSpec {
    /// The phases.
    pub phases: Vec<PushPhase>,
    /// The directions \[deg\].
    pub directions: Vec<f64>,
    /// The bisection's resolution \[fraction of body weight\].
    pub resolution_bw: f64,
    /// The configurations.
    pub steppings: Vec<Stepping>,
    /// Engine runs at once.
    pub threads: usize,
    /// How the pushes are given.
    pub convention: Convention,
    /// Each cell also scanned around its bisected force (forces only; [`scan_cell`]).
    pub scan: bool,
}

impl MapSpec {
    /// The full map (`quick`: two phases, four directions, coarse).
    pub fn new(quick: bool) -> Self {
        let threads = std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1);
        if quick {
            Self {
                phases: QUICK_PHASES.to_vec(),
                directions: QUICK_DIRECTIONS.to_vec(),
                resolution_bw: QUICK_RESOLUTION_BW,
                steppings: Stepping::ALL.to_vec(),
                threads,
                convention: Convention::Force,
                scan: false,
            }
        } else {
            Self {
                phases: PushPhase::ALL.to_vec(),
                directions: (0..8).map(|i| 45.0 * f64::from(i)).collect(),
                resolution_bw: RESOLUTION_BW,
                steppings: Stepping::ALL.to_vec(),
                threads,
                convention: Convention::Force,
                scan: false,
            }
        }
    }
}

/// The bisection of one cell (`resolution_bw`: of body weight, or of [`V_MAX_MPS`] for a
/// velocity push).
pub fn bisect(
    node: &NodeConfig,
    cfg: &PhysicsConfig,
    stepping: Stepping,
    phase: PushPhase,
    direction_deg: f64,
    resolution_bw: f64,
    convention: Convention,
) -> Result<Cell, String> {
    bisect_tried(
        node,
        cfg,
        stepping,
        phase,
        direction_deg,
        resolution_bw,
        convention,
    )
    .map(|(c, _)| c)
}

/// The bisection of one cell, with its pushes (fraction of body weight, survived), for a scan
/// above it ([`super::push_scan`]).
#[allow(clippy::too_many_arguments)]
pub fn bisect_tried(
    node: &NodeConfig,
    cfg: &PhysicsConfig,
    stepping: Stepping,
    phase: PushPhase,
    direction_deg: f64,
    resolution_bw: f64,
    convention: Convention,
) -> Result<(Cell, Vec<(f64, bool)>), String> {
    let mut tried = Vec::new();
    let m = cfg.robot.total_mass();
    let weight = m * cfg.robot.gravity();
    let kind = |x: f64| match convention {
        Convention::Force => PushKind::Force {
            force_n: x * weight,
            duration_s: PUSH_S,
        },
        Convention::Velocity => PushKind::Velocity {
            v_mps: x * V_MAX_MPS,
        },
    };
    let (mut lo, mut hi) = (0.0, MAX_BW);
    let mut steps_adjusted = 0;
    let mut gait = super::gait::GaitQuality::default();
    let mut runs = 0;
    while hi - lo > resolution_bw {
        let mid = 0.5 * (lo + hi);
        let push = PushSpec {
            phase,
            direction_deg,
            kind: kind(mid),
        };
        let o = run(node, cfg, Walk::default(), stepping, Some(push))?;
        runs += 1;
        if !o.pushed && !o.fell {
            return Err(format!(
                "the walk never reached the push ({}, {direction_deg}°)",
                phase.name()
            ));
        }
        tried.push((mid, !o.fell));
        if o.fell {
            hi = mid;
        } else {
            lo = mid;
            steps_adjusted = o.steps_adjusted;
            gait = o.gait;
        }
    }
    let (f, dv) = match convention {
        Convention::Force => (lo * weight, lo * weight * PUSH_S / m),
        Convention::Velocity => (0.0, lo * V_MAX_MPS),
    };
    let cell = Cell {
        stepping,
        phase,
        direction_deg,
        convention,
        max_force_n: f,
        dv_mps: dv,
        bw_fraction: lo,
        steps_adjusted,
        runs,
        gait,
        error: None,
        scan: None,
    };
    Ok((cell, tried))
}

/// One cell in the engine: its bisection ([`bisect_tried`]) and the scan
/// around the bisected force.
pub fn scan_cell(
    node: &NodeConfig,
    cfg: &PhysicsConfig,
    stepping: Stepping,
    phase: PushPhase,
    direction_deg: f64,
    resolution_bw: f64,
) -> Result<(Cell, super::push_scan::Scan), String> {
    let (cell, tried) = bisect_tried(
        node,
        cfg,
        stepping,
        phase,
        direction_deg,
        resolution_bw,
        Convention::Force,
    )?;
    let weight = cfg.robot.total_mass() * cfg.robot.gravity();
    let scan = super::push_scan::scan_with(cell.bw_fraction, tried, |bw| {
        let push = PushSpec {
            phase,
            direction_deg,
            kind: PushKind::Force {
                force_n: bw * weight,
                duration_s: PUSH_S,
            },
        };
        let o = run(node, cfg, Walk::default(), stepping, Some(push))?;
        Ok(!o.fell)
    })?;
    // Every tried push is one engine run: the bisection's and the scan's.
    let cell = Cell {
        runs: scan.tried.len(),
        ..cell
    };
    Ok((cell, scan))
}

/// One cell, failed (with its cause) rather than an error.
pub fn cell(
    node: &NodeConfig,
    cfg: &PhysicsConfig,
    stepping: Stepping,
    phase: PushPhase,
    direction_deg: f64,
    resolution_bw: f64,
    convention: Convention,
) -> Cell {
    bisect(
        node,
        cfg,
        stepping,
        phase,
        direction_deg,
        resolution_bw,
        convention,
    )
    .unwrap_or_else(|e| Cell {
        convention,
        ..Cell::failed(stepping, phase, direction_deg, e)
    })
}

/// Every cell of `spec`, the bisections spread over `spec.threads` threads (in the order of
/// `spec`: configuration, phase, direction). A cell that cannot be measured is in the list as
/// failed ([`Cell::error`]).
pub fn map(node: &NodeConfig, cfg: &PhysicsConfig, spec: &MapSpec) -> Vec<Cell> {
    let mut jobs = Vec::new();
    for &s in &spec.steppings {
        for &p in &spec.phases {
            for &d in &spec.directions {
                jobs.push((s, p, d));
            }
        }
    }
    let bar = crate::console::Progress::new("push-map", jobs.len() as u64);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Cell>>> = Mutex::new(vec![None; jobs.len()]);
    std::thread::scope(|scope| {
        for _ in 0..spec.threads.max(1).min(jobs.len().max(1)) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&(s, p, d)) = jobs.get(i) else {
                    break;
                };
                let r = if spec.scan {
                    match scan_cell(node, cfg, s, p, d, spec.resolution_bw) {
                        Ok((c, scan)) => Cell {
                            scan: Some(scan),
                            ..c
                        },
                        Err(e) => Cell::failed(s, p, d, e),
                    }
                } else {
                    cell(node, cfg, s, p, d, spec.resolution_bw, spec.convention)
                };
                bar.inc(format!("{}, {}, {d}°", s.name(), p.name()));
                if let Ok(mut v) = results.lock() {
                    v[i] = Some(r);
                }
            });
        }
    });
    // A poisoned lock only means a thread panicked after storing; the cells it stored stand.
    let results = results
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    results
        .into_iter()
        .zip(&jobs)
        .map(|(r, &(s, p, d))| {
            r.unwrap_or_else(|| Cell {
                convention: spec.convention,
                ..Cell::failed(s, p, d, "the cell's engine run did not end".into())
            })
        })
        .collect()
}

/// One configuration against the stabilizer only, over the cells both have.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// The configuration.
    pub stepping: Stepping,
    /// The mean of its cells' Δv \[m/s\].
    pub mean_dv_mps: f64,
    /// Cells where it walks through a larger push than the stabilizer only.
    pub raised: usize,
    /// Cells where it walks through a smaller one.
    pub lowered: usize,
    /// Cells compared.
    pub cells: usize,
}

/// Each configuration of `spec` against the stabilizer only.
pub fn summary(spec: &MapSpec, cells: &[Cell]) -> Vec<Summary> {
    let base = |c: &Cell| {
        cells.iter().find(|b| {
            b.stepping == Stepping::Fixed
                && b.ok()
                && b.phase == c.phase
                && b.direction_deg == c.direction_deg
        })
    };
    spec.steppings
        .iter()
        .map(|&s| {
            let mine: Vec<&Cell> = cells.iter().filter(|c| c.stepping == s && c.ok()).collect();
            let n = mine.len().max(1) as f64;
            let mut out = Summary {
                stepping: s,
                mean_dv_mps: mine.iter().map(|c| c.dv_mps).sum::<f64>() / n,
                raised: 0,
                lowered: 0,
                cells: 0,
            };
            for c in mine {
                if let Some(b) = base(c) {
                    out.cells += 1;
                    out.raised += usize::from(c.dv_mps > b.dv_mps);
                    out.lowered += usize::from(c.dv_mps < b.dv_mps);
                }
            }
            out
        })
        .collect()
}

/// Cells where `a` walks through a larger push than `b`, and where a smaller one.
pub fn compare(cells: &[Cell], a: Stepping, b: Stepping) -> (usize, usize, usize) {
    let (mut larger, mut smaller, mut n) = (0, 0, 0);
    for c in cells.iter().filter(|c| c.stepping == a && c.ok()) {
        if let Some(d) = cells.iter().find(|d| {
            d.stepping == b && d.ok() && d.phase == c.phase && d.direction_deg == c.direction_deg
        }) {
            n += 1;
            larger += usize::from(c.dv_mps > d.dv_mps);
            smaller += usize::from(c.dv_mps < d.dv_mps);
        }
    }
    (larger, smaller, n)
}

/// The summary lines of `push_map.md` and the command's output.
pub fn summary_lines(spec: &MapSpec, cells: &[Cell]) -> String {
    let mut s = summary_of(spec, cells);
    if spec.steppings.contains(&Stepping::Plain) && spec.steppings.contains(&Stepping::Proposed) {
        let (larger, smaller, n) = compare(cells, Stepping::Proposed, Stepping::Plain);
        s += &format!(
            "proposed against plain: larger in {larger} of {n} cells, smaller in {smaller}\n"
        );
        if spec.scan {
            s += &scan_lines(spec, cells);
        }
    }
    s
}

/// With `--scan`: per configuration, the cells whose survival is not monotonic in the force
/// (a push survived above a fall) and the mean sure force; the proposed method against the
/// plain re-plan where their `sure_bw` differ beyond the larger of the two cells' spreads
/// ([`super::push_scan::beyond_spread`]).
fn scan_lines(spec: &MapSpec, cells: &[Cell]) -> String {
    let scanned = |st: Stepping| -> Vec<&Cell> {
        cells
            .iter()
            .filter(|c| c.stepping == st && c.scan.is_some())
            .collect()
    };
    let mut s = String::new();
    for &st in &spec.steppings {
        let mine = scanned(st);
        let mixed = mine
            .iter()
            .filter(|c| c.scan.as_ref().is_some_and(|x| x.survived_above > 0.0))
            .count();
        let mean = mine
            .iter()
            .filter_map(|c| c.scan.as_ref().map(|x| x.sure_bw))
            .sum::<f64>()
            / mine.len().max(1) as f64;
        s += &format!(
            "{} (scan): mean sure force {mean:.3} BW; a push survived above a fall in {mixed} of {} cells\n",
            st.name(),
            mine.len()
        );
    }
    let (mut larger, mut smaller, mut inside) = (0, 0, 0);
    for a in scanned(Stepping::Proposed) {
        let Some(b) = scanned(Stepping::Plain)
            .into_iter()
            .find(|b| b.phase == a.phase && b.direction_deg == a.direction_deg)
        else {
            continue;
        };
        if let (Some(x), Some(y)) = (&a.scan, &b.scan) {
            match super::push_scan::beyond_spread(x, y, spec.resolution_bw) {
                Some(std::cmp::Ordering::Greater) => larger += 1,
                Some(std::cmp::Ordering::Less) => smaller += 1,
                _ => inside += 1,
            }
        }
    }
    s += &format!(
        "proposed against plain, sure force beyond the cells' spread: larger in {larger} of {} \
         cells, smaller in {smaller}, within the spread in {inside}\n",
        larger + smaller + inside
    );
    s
}

fn summary_of(spec: &MapSpec, cells: &[Cell]) -> String {
    summary(spec, cells)
        .iter()
        .map(|s| {
            format!(
                "{}: mean {} {:.3} m/s; larger than the stabilizer only in {} of {} cells, smaller in {}\n",
                s.stepping.name(),
                match spec.convention {
                    Convention::Force => "Δv",
                    Convention::Velocity => "v",
                },
                s.mean_dv_mps,
                s.raised,
                s.cells,
                s.lowered
            )
        })
        .collect()
}

/// `push_map.json`: the robot, its mass, the push duration and each configuration's cells.
pub fn map_json(robot: &str, mass_kg: f64, spec: &MapSpec, cells: &[Cell]) -> Value {
    let mut configs = serde_json::Map::new();
    for s in Stepping::ALL {
        let list: Vec<Value> = cells
            .iter()
            .filter(|c| c.stepping == s)
            .map(Cell::json)
            .collect();
        if spec.steppings.contains(&s) {
            configs.insert(s.name().into(), Value::Array(list));
        }
    }
    json!({
        "robot": robot,
        "mass_kg": mass_kg,
        "push": spec.convention.name(),
        "push_duration_s": PUSH_S,
        "resolution_bw": spec.resolution_bw,
        "max_bw": MAX_BW,
        "max_v_mps": V_MAX_MPS,
        "walk": {"steps": Walk::default().steps, "length_m": Walk::default().length},
        "engine_runs": cells.iter().map(|c| c.runs).sum::<usize>(),
        "configs": Value::Object(configs),
        "summary": summary(spec, cells).iter().map(|s| json!({
            "config": s.stepping.name(),
            "mean_dv_mps": s.mean_dv_mps,
            "raised": s.raised,
            "lowered": s.lowered,
            "cells": s.cells,
        })).collect::<Vec<_>>(),
        "references": {
            "atlas_mps": ATLAS.iter().map(|(k, v)| json!({"direction": k, "dv_mps": v})).collect::<Vec<_>>(),
            "icub_dv_mps": ICUB_DV,
        },
    })
}

/// The table of `push_map.md`: one row per phase and direction, Δv of each configuration.
pub fn markdown(spec: &MapSpec, cells: &[Cell]) -> String {
    let velocity = spec.convention == Convention::Velocity;
    let mut s = String::from("| phase | direction [deg] |");
    for st in &spec.steppings {
        if velocity {
            s += &format!(" {} v [m/s] |", st.name());
        } else {
            s += &format!(" {} Δv [m/s] (BW) |", st.name());
        }
    }
    s += " steps adjusted (proposed) |\n|---|---|";
    for _ in &spec.steppings {
        s += "---|";
    }
    s += "---|\n";
    for &p in &spec.phases {
        for &d in &spec.directions {
            s += &format!("| {} | {d:.0} |", p.name());
            let mut adjusted = String::from("–");
            for &st in &spec.steppings {
                match cells
                    .iter()
                    .find(|c| c.stepping == st && c.phase == p && c.direction_deg == d)
                {
                    Some(Cell { error: Some(e), .. }) => s += &format!(" failed: {e} |"),
                    Some(c) => {
                        if velocity {
                            s += &format!(" {:.3} |", c.dv_mps);
                        } else if let Some(x) = &c.scan {
                            s += &format!(
                                " {:.3} ({:.2}; sure {:.2}, {:.0} % above) |",
                                c.dv_mps,
                                c.bw_fraction,
                                x.sure_bw,
                                100.0 * x.survived_above
                            );
                        } else {
                            s += &format!(" {:.3} ({:.2}) |", c.dv_mps, c.bw_fraction);
                        }
                        if st == Stepping::Proposed {
                            adjusted = c.steps_adjusted.to_string();
                        }
                    }
                    None => s += " – |",
                }
            }
            s += &format!(" {adjusted} |\n");
        }
    }
    s += &format!(
        "\nReferences: IHMC's Atlas {}; iCub {ICUB_DV:.3} m/s (150 N for 0.05 s, 33 kg).\n",
        ATLAS
            .iter()
            .map(|(k, v)| format!("{k} {v} m/s"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    s
}
