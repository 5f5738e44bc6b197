//! The fault sweep's "fall" measured in the engine: every row of [`crate::eval::faults`] (each fault
//! kind at each rate, and the heavy mixed rows) played through the bus and the node with one
//! seed, the node's references then run in MuJoCo under the stabilizer. Beside the engine's
//! verdict ([`super::metrics`]) each row keeps the sweep's kinematic one (the multi-body ZMP
//! more than 20 mm outside the support polygon).
//!
//! `host-sim physics-faults --out DIR [--rows all|i,j,...] [--seed N] [--walk plain|adjusting]`
//! (and the probe options of [`super::probe`]: `--stabilizer`, `--servo-damping`,
//! `--open-loop`) writes `DIR/physics_faults.json`: an object with the settings (`robot`,
//! `seed`, `walk`, `stabilizer`, `stabilizer_scale`, `servo_damping`, for `weakest` also
//! `weakest_ladder`) and `runs`, one object per row and scenario ([`json()`]: `fault`, `rate`,
//! `scenario`, `walk`, `seed`, `kinematic_fell`, `fell`, `fall_time_s`, `max_tilt_deg`,
//! `cop_err_mean_m`, `cop_err_max_m`, `safety_stop`, `lost`, `adjustments`, and the end of
//! the run: [`super::PhysicsReport::end_fields`], `ended_standing` false where the node's walk
//! was cut at the scenario's end before it stood); and
//! `DIR/physics_faults.md`. With `--walk adjusting` the rows are the adjusting walk's
//! ([`rows_of`]): the node's references of a walk started with `start_adjusting` whose pushed
//! pendulum robot's estimator sent `MEASURED` every cycle, played in the engine (the engine's
//! robot is not pushed: what it walks is the node's adjusted plan).

use serde_json::{json, Value};

use super::{run, PhysicsConfig, PhysicsReport};
use crate::eval::faults::{self, run_walk_with, FaultKind, Walk, SCENARIOS};
use crate::robot::Robot;
use crate::scenario;

/// Every row of the sweep in its order: the [`faults::SWEEP`] rates, then the
/// [`faults::HEAVY`] mixes.
pub fn rows() -> Vec<(FaultKind, f64)> {
    rows_of(Walk::Plain)
}

/// Every row of `walk`'s sweep in its order ([`faults::rows`]).
pub fn rows_of(walk: Walk) -> Vec<(FaultKind, f64)> {
    faults::rows(walk)
}

/// One row and scenario run in the engine.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultRun {
    /// The fault.
    pub kind: FaultKind,
    /// Its rate.
    pub rate: f64,
    /// The scenario.
    pub scenario: String,
    /// How it was walked.
    pub walk: Walk,
    /// The seed.
    pub seed: u64,
    /// The sweep's kinematic verdict.
    pub kinematic_fell: bool,
    /// The node stopped on its own.
    pub safety_stop: bool,
    /// Lost commands.
    pub lost: usize,
    /// Changes of the node's shift (adjusting walks).
    pub adjustments: usize,
    /// The engine's report.
    pub report: PhysicsReport,
}

/// Runs row `(kind, rate)` of the sweep on `scenario` with `seed` through `robot`'s node,
/// then in the engine (`cfg.robot` should be [`super::model::Robot::of`] it).
pub fn fault_run(
    scenario_name: &str,
    kind: FaultKind,
    rate: f64,
    seed: u64,
    robot: &Robot,
    cfg: &PhysicsConfig,
) -> Result<FaultRun, String> {
    fault_run_walk(scenario_name, Walk::Plain, kind, rate, seed, robot, cfg)
}

/// [`fault_run`] walked as `walk`.
pub fn fault_run_walk(
    scenario_name: &str,
    walk: Walk,
    kind: FaultKind,
    rate: f64,
    seed: u64,
    robot: &Robot,
    cfg: &PhysicsConfig,
) -> Result<FaultRun, String> {
    let s =
        scenario::built_in(scenario_name).ok_or_else(|| format!("no scenario {scenario_name}"))?;
    let node = robot.node_config();
    let dt = node.params.dt;
    let case = run_walk_with(&s, walk, kind, rate, seed, node, &robot.model)?;
    let report = run(&case.trajectory, dt, cfg)?.report;
    Ok(FaultRun {
        kind,
        rate,
        scenario: scenario_name.to_string(),
        walk,
        seed,
        kinematic_fell: case.fell,
        safety_stop: case.safety_stop,
        lost: case.lost,
        adjustments: case.adjustments,
        report,
    })
}

/// The rows `physics-faults` runs by default: `all`, so that every row of the sweep is
/// simulated in the engine with (at least) one seed.
pub const DEFAULT_ROWS: &str = "all";

/// What [`sweep`] runs for the rows with the given indices (into [`rows`]): each row on every
/// sweep scenario ([`SCENARIOS`]), in that order. Errors: an index out of range.
pub fn plan(indices: &[usize]) -> Result<Vec<(FaultKind, f64, &'static str)>, String> {
    plan_walk(indices, Walk::Plain)
}

/// [`plan`] for `walk`'s rows (indices into [`rows_of`]).
pub fn plan_walk(
    indices: &[usize],
    walk: Walk,
) -> Result<Vec<(FaultKind, f64, &'static str)>, String> {
    let all = rows_of(walk);
    let mut out = Vec::new();
    for &i in indices {
        let (kind, rate) = *all
            .get(i)
            .ok_or_else(|| format!("row {i}: the sweep has rows 0..{}", all.len()))?;
        out.extend(SCENARIOS.iter().map(|s| (kind, rate, *s)));
    }
    Ok(out)
}

/// Runs the rows with the given indices (into [`rows`]) on every sweep scenario ([`plan`]).
pub fn sweep(
    indices: &[usize],
    seed: u64,
    robot: &Robot,
    cfg: &PhysicsConfig,
) -> Result<Vec<FaultRun>, String> {
    sweep_walk(indices, Walk::Plain, seed, robot, cfg)
}

/// [`sweep`] of `walk`'s rows (indices into [`rows_of`]).
pub fn sweep_walk(
    indices: &[usize],
    walk: Walk,
    seed: u64,
    robot: &Robot,
    cfg: &PhysicsConfig,
) -> Result<Vec<FaultRun>, String> {
    let plan = plan_walk(indices, walk)?;
    let bar = crate::console::Progress::new("physics-faults", plan.len() as u64);
    plan.into_iter()
        .map(|(kind, rate, s)| {
            let what = format!("{} {} on {s}", kind.name(), kind.rate_label(rate));
            bar.message(what.clone());
            let r = fault_run_walk(s, walk, kind, rate, seed, robot, cfg)
                .map_err(|e| format!("{what}: {e}"));
            bar.inc(what);
            r
        })
        .collect()
}

/// The JSON of the runs (`physics_faults.json`'s `runs`).
pub fn json(runs: &[FaultRun]) -> Value {
    Value::Array(
        runs.iter()
            .map(|r| {
                let mut j = json!({
                    "fault": r.kind.name(),
                    "rate": r.kind.rate_label(r.rate),
                    "scenario": r.scenario,
                    "walk": r.walk.name(),
                    "seed": r.seed,
                    "kinematic_fell": r.kinematic_fell,
                    "fell": r.report.fell,
                    "fall_time_s": r.report.fall_time_s,
                    "fall_cause": r.report.fall_cause.map(|c| c.name()),
                    "max_tilt_deg": r.report.max_tilt_deg,
                    "cop_err_mean_m": r.report.cop_err_mean_m,
                    "cop_err_max_m": r.report.cop_err_max_m,
                    "safety_stop": r.safety_stop,
                    "lost": r.lost,
                    "adjustments": r.adjustments,
                });
                r.report.add_end_fields(&mut j);
                j
            })
            .collect(),
    )
}

/// The runs as a Markdown table (the scenario named with its walk when it adjusts).
pub fn markdown(runs: &[FaultRun]) -> String {
    let mut md = String::from(
        "| fault | rate | scenario | kinematic fall | engine: fell | engine: walked | max tilt (°) | CoP error mean / worst (mm) | slip (mm) |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in runs {
        let scenario = match r.walk {
            Walk::Plain => r.scenario.clone(),
            Walk::Velocity => format!("{} (stick)", r.scenario),
            Walk::Adjusting => format!("{} (adjusting, {} adjustments)", r.scenario, r.adjustments),
        };
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {:.2} | {:.1} / {:.1} | {:.1} |\n",
            r.kind.name(),
            r.kind.rate_label(r.rate),
            scenario,
            if r.kinematic_fell { "yes" } else { "no" },
            r.report.fell_text(),
            r.report.walked_text(),
            r.report.max_tilt_deg,
            r.report.cop_err_mean_m * 1e3,
            r.report.cop_err_max_m * 1e3,
            r.report.gait.slip_max_m * 1e3
        );
    }
    md
}

/// Parses `--rows`: `all` or comma-separated indices into [`rows`].
pub fn parse_rows(s: &str) -> Result<Vec<usize>, String> {
    parse_rows_of(s, Walk::Plain)
}

/// [`parse_rows`] for `walk`'s rows ([`rows_of`]).
pub fn parse_rows_of(s: &str, walk: Walk) -> Result<Vec<usize>, String> {
    let n = rows_of(walk).len();
    if s == "all" {
        return Ok((0..n).collect());
    }
    s.split(',')
        .map(|x| match x.trim().parse::<usize>() {
            Ok(i) if i < n => Ok(i),
            _ => Err(format!("--rows: {x:?} is not a row index 0..{n}")),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::faults::{HEAVY, SWEEP};

    #[test]
    fn rows_cover_the_sweep() {
        let r = rows();
        assert_eq!(r.len(), 19 + HEAVY.len());
        assert_eq!(r[0], (FaultKind::None, 0.0));
        assert_eq!(r[r.len() - 1], (FaultKind::Mixed(HEAVY.len() - 1), 0.0));
        assert_eq!(parse_rows("all").unwrap().len(), r.len());
        assert_eq!(parse_rows("0, 3").unwrap(), vec![0, 3]);
        assert!(parse_rows("99").is_err());
    }

    /// The default run simulates every row of the sweep (each fault kind at each of its
    /// rates, and every heavy mix) on every sweep scenario, once.
    #[test]
    fn the_default_run_simulates_every_row() {
        let p = plan(&parse_rows(DEFAULT_ROWS).unwrap()).unwrap();
        assert_eq!(p.len(), rows().len() * SCENARIOS.len());
        for (kind, rates) in SWEEP {
            for &rate in rates {
                for s in SCENARIOS {
                    let n = p.iter().filter(|x| **x == (kind, rate, s)).count();
                    assert_eq!(n, 1, "{} {} on {s}", kind.name(), kind.rate_label(rate));
                }
            }
        }
        for i in 0..HEAVY.len() {
            for s in SCENARIOS {
                assert!(
                    p.contains(&(FaultKind::Mixed(i), 0.0, s)),
                    "heavy row {i} on {s}"
                );
            }
        }
        assert!(plan(&[rows().len()]).is_err());
    }

    /// The adjusting walk's rows: the plain ones and the silent estimator, each on every
    /// sweep scenario; `--rows` indexes them.
    #[test]
    fn the_adjusting_walk_has_every_row_and_a_silent_estimator() {
        let a = rows_of(Walk::Adjusting);
        assert_eq!(a.len(), rows().len() + 1);
        for r in rows() {
            assert!(a.contains(&r), "{r:?}");
        }
        assert!(a.contains(&(FaultKind::Blind, 0.0)));
        let all = parse_rows_of("all", Walk::Adjusting).unwrap();
        assert_eq!(plan_walk(&all, Walk::Adjusting).unwrap().len(), a.len() * 2);
        assert!(parse_rows_of(&a.len().to_string(), Walk::Adjusting).is_err());
    }
}
