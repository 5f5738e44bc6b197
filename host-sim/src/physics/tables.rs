//! The paper's Tables I and II in dynamic simulation: the same 7 × 7 grid of modifications
//! ([`crate::eval::paper`]: steps of length `before`, the step in flight at 4.0 s changed to
//! `after`), each cell run in MuJoCo under the stabilizer twice: with the **plain re-plan**
//! (no single-support adjustment, eq. 18, and no shaping, as Table I) and with the **proposed
//! method** (adjustment and shaping, as Table II). A cell reports whether the robot fell
//! ([`super::metrics`]), when, its largest tilt and worst 50 ms CoP error, beside the kinematic
//! multi-body ZMP error of the same trajectory (the figure of `host-sim tables`) and the
//! paper's.
//!
//! `host-sim physics-tables --out DIR` runs the full grid (98 runs asked, 89 in the engine: the
//! legs cannot reach the other 9) and writes
//! `DIR/physics_tables.json`: `fell_plain` and `fell_proposed` (7 × 7, rows "after", columns
//! "before", in the order of `tables.json`; `null` for a cell not simulated or whose footsteps
//! the legs cannot reach), `walked_plain` and `walked_proposed` (no fall and the gait within
//! its bounds, [`super::gait`]) with `gait_violations_*` and `slip_max_*_m`, the falls after the end apart (`fell_after_end_plain`, …, see
//! [`super::metrics::SETTLE_AFTER_S`]), whether each trajectory ended standing
//! (`ended_standing_plain`, `ended_standing_proposed`: each cell's walk is played to standing)
//! and the per-cell figures; `--cells r,c;r,c` restricts the run to
//! some cells (the test runs a reduced grid). `--stabilizer full|off|weakest|S` and
//! `--servo-damping KD` weaken the stabilizer and the servos ([`super::probe`]; the JSON then
//! has `stabilizer_scale`, `servo_damping` and, for `weakest`, `weakest_ladder`), `--robot
//! FILE` takes another robot file standing as HRP-2 (the grid is HRP-2's footsteps).

use serde_json::{json, Value};

use super::{run, PhysicsConfig, PhysicsReport};
use crate::eval::paper::{self, PAPER_ERROR_WITHOUT_M, PAPER_ERROR_WITH_M, STEP_LENGTHS};
use planner_core::gait::GaitParams;

/// The paper's remark (section IV.C): walking was difficult in dynamic simulation when the ZMP
/// error exceeded about this \[m\].
pub const PAPER_DIFFICULT_ERROR_M: f64 = 0.07;

/// One cell run both ways.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// Row (index of `after` in [`STEP_LENGTHS`]).
    pub row: usize,
    /// Column (index of `before`).
    pub col: usize,
    /// Plain re-plan: the engine's report (`None`: out of the legs' reach).
    pub plain: Option<PhysicsReport>,
    /// Proposed method.
    pub proposed: Option<PhysicsReport>,
    /// Plain re-plan: the worst 50 ms CoP error in the modified single support and the double
    /// support after it ([`MODIFIED_WINDOW_S`]) \[m\].
    pub cop_err_modified_plain_m: Option<f64>,
    /// The same for the proposed method \[m\].
    pub cop_err_modified_proposed_m: Option<f64>,
    /// Kinematic multi-body ZMP error of the plain trajectory \[m\].
    pub mb_error_plain_m: Option<f64>,
    /// The same for the proposed trajectory \[m\].
    pub mb_error_proposed_m: Option<f64>,
}

/// The time window of the modified step in trajectory time \[s\]: from the re-plan at 4.0 s
/// to 1.0 s later (the single support of 0.7 s ± the adjustment and the double support).
pub const MODIFIED_WINDOW_S: (f64, f64) = (4.0, 5.0);

/// The worst logged 50 ms CoP error within [`MODIFIED_WINDOW_S`] \[m\].
fn window_error(samples: &[super::PhysicsSample]) -> f64 {
    window_error_in(samples, MODIFIED_WINDOW_S)
}

/// The worst logged 50 ms CoP error within the window `(t0, t1)` of trajectory time \[m\].
pub fn window_error_in(samples: &[super::PhysicsSample], (t0, t1): (f64, f64)) -> f64 {
    samples
        .iter()
        .filter(|s| s.t >= t0 && s.t <= t1)
        .map(|s| s.cop_err)
        .filter(|e| e.is_finite())
        .fold(0.0, f64::max)
}

pub use crate::eval::paper::plain_params;

/// Runs one cell both ways with the gait `params` (the proposed method; the plain re-plan is
/// [`plain_params`] of it) and the robot of `cfg` (its link table for the kinematic error).
/// Errors: the engine failed (an unreachable footstep is `None`).
pub fn cell(
    row: usize,
    col: usize,
    params: &GaitParams<f64>,
    cfg: &PhysicsConfig,
) -> Result<Cell, String> {
    let (after, before) = (STEP_LENGTHS[row], STEP_LENGTHS[col]);
    let proposed_params = *params;
    let dt = proposed_params.dt;
    let mut out = Cell {
        row,
        col,
        plain: None,
        proposed: None,
        cop_err_modified_plain_m: None,
        cop_err_modified_proposed_m: None,
        mb_error_plain_m: None,
        mb_error_proposed_m: None,
    };
    for (params, plain) in [
        (plain_params(proposed_params), true),
        (proposed_params, false),
    ] {
        let m = paper::modification(params, before, after);
        let mb = paper::modified_support_error(cfg.robot.link_table(), &m, dt);
        // Out of reach kinematically: no engine run either.
        let (report, window) = match mb {
            Some(_) => {
                let r = run(&m.trajectory, dt, cfg)?;
                (Some(r.report), Some(window_error(&r.samples)))
            }
            None => (None, None),
        };
        if plain {
            (
                out.plain,
                out.cop_err_modified_plain_m,
                out.mb_error_plain_m,
            ) = (report, window, mb);
        } else {
            (
                out.proposed,
                out.cop_err_modified_proposed_m,
                out.mb_error_proposed_m,
            ) = (report, window, mb);
        }
    }
    Ok(out)
}

fn grid<T: Clone>(cells: &[Cell], f: impl Fn(&Cell) -> Option<T>) -> Vec<Vec<Option<T>>> {
    let n = STEP_LENGTHS.len();
    let mut g = vec![vec![None; n]; n];
    for c in cells {
        g[c.row][c.col] = f(c);
    }
    g
}

/// The JSON of `physics_tables.json` for the cells run.
pub fn tables_json(cells: &[Cell]) -> Value {
    let fell = |r: &Option<PhysicsReport>| r.as_ref().map(|r| r.fell);
    let fig = |r: &Option<PhysicsReport>, k: &str| {
        r.as_ref().map(|r| match k {
            "tilt" => r.max_tilt_deg,
            "cop" => r.cop_err_max_m,
            _ => r.fall_time_s.unwrap_or(f64::NAN),
        })
    };
    let fall_t = |r: &Option<PhysicsReport>| r.as_ref().and_then(|r| r.fall_time_s);
    let late = |r: &Option<PhysicsReport>| r.as_ref().map(|r| r.fell_after_end);
    let late_t = |r: &Option<PhysicsReport>| r.as_ref().and_then(|r| r.fall_after_end_time_s);
    let standing = |r: &Option<PhysicsReport>| r.as_ref().map(|r| r.ended_standing);
    let walked = |r: &Option<PhysicsReport>| r.as_ref().map(|r| r.walked());
    let slip = |r: &Option<PhysicsReport>| r.as_ref().map(|r| r.gait.slip_max_m);
    let violations = |r: &Option<PhysicsReport>| r.as_ref().map(|r| r.gait.violations());
    json!({
        "step_lengths_m": STEP_LENGTHS,
        "rows": "length after the modification",
        "columns": "length before the modification",
        "cells_simulated": cells.len(),
        "fell_plain": grid(cells, |c| fell(&c.plain)),
        "fell_proposed": grid(cells, |c| fell(&c.proposed)),
        "walked_plain": grid(cells, |c| walked(&c.plain)),
        "walked_proposed": grid(cells, |c| walked(&c.proposed)),
        "gait_violations_plain": grid(cells, |c| violations(&c.plain)),
        "gait_violations_proposed": grid(cells, |c| violations(&c.proposed)),
        "slip_max_plain_m": grid(cells, |c| slip(&c.plain)),
        "slip_max_proposed_m": grid(cells, |c| slip(&c.proposed)),
        "gait_bounds": super::gait::GaitQuality::bounds_json(),
        "fall_time_plain_s": grid(cells, |c| fall_t(&c.plain)),
        "fall_time_proposed_s": grid(cells, |c| fall_t(&c.proposed)),
        "fell_after_end_plain": grid(cells, |c| late(&c.plain)),
        "fell_after_end_proposed": grid(cells, |c| late(&c.proposed)),
        "fall_after_end_time_plain_s": grid(cells, |c| late_t(&c.plain)),
        "fall_after_end_time_proposed_s": grid(cells, |c| late_t(&c.proposed)),
        "ended_standing_plain": grid(cells, |c| standing(&c.plain)),
        "ended_standing_proposed": grid(cells, |c| standing(&c.proposed)),
        "settle_after_s": super::metrics::SETTLE_AFTER_S,
        "max_tilt_plain_deg": grid(cells, |c| fig(&c.plain, "tilt")),
        "max_tilt_proposed_deg": grid(cells, |c| fig(&c.proposed, "tilt")),
        "cop_err_max_plain_m": grid(cells, |c| fig(&c.plain, "cop")),
        "cop_err_max_proposed_m": grid(cells, |c| fig(&c.proposed, "cop")),
        "cop_err_modified_plain_m": grid(cells, |c| c.cop_err_modified_plain_m),
        "cop_err_modified_proposed_m": grid(cells, |c| c.cop_err_modified_proposed_m),
        "modified_window_s": [MODIFIED_WINDOW_S.0, MODIFIED_WINDOW_S.1],
        "mb_zmp_error_plain_m": grid(cells, |c| c.mb_error_plain_m),
        "mb_zmp_error_proposed_m": grid(cells, |c| c.mb_error_proposed_m),
        "paper_max_zmp_error_without_m": PAPER_ERROR_WITHOUT_M,
        "paper_max_zmp_error_with_m": PAPER_ERROR_WITH_M,
        "paper_difficult_error_m": PAPER_DIFFICULT_ERROR_M,
        "plain": "no single-support adjustment (eq. 18) and no shaping (Table I)",
        "proposed": "adjustment and shaping (Table II)",
    })
}

/// A 7 × 7 Markdown grid of the cells (rows: after, columns: before); `-` where not run.
pub fn markdown(title: &str, cells: &[Cell], f: impl Fn(&Cell) -> String) -> String {
    paper::grid_markdown(title, |r, c| {
        cells
            .iter()
            .find(|x| x.row == r && x.col == c)
            .map(&f)
            .unwrap_or_else(|| "-".into())
    })
}

/// One cell as text: `fell`, a gait measure beyond its bound (`slip`, `flight`, `cop`,
/// `landing`: [`PhysicsReport::verdict`]) or `ok` (`ok†`: a fall after the end), the worst CoP error of the modified step and the
/// kinematic multi-body error, in cm: `ok 3.1 / 7.5`.
pub fn cell_text(r: &Option<PhysicsReport>, window: Option<f64>, mb: Option<f64>) -> String {
    match (r, window, mb) {
        (Some(r), Some(w), Some(e)) => {
            format!("{} {:.1} / {:.1}", r.verdict(), w * 100.0, e * 100.0)
        }
        _ => "n/a".into(),
    }
}

/// One cell side by side: the verdicts of the plain re-plan and of the proposed method, then
/// their kinematic multi-body errors in cm, the plain one marked `*` above the paper's 0.07 m:
/// `ok / ok, 9.3* / 5.0`.
pub fn side_by_side_text(c: &Cell) -> String {
    let verdict = |r: &Option<PhysicsReport>| r.as_ref().map_or("n/a".into(), |r| r.verdict());
    let cm = |e: Option<f64>| e.map_or("n/a".to_string(), |e| format!("{:.1}", e * 100.0));
    let mark = match c.mb_error_plain_m {
        Some(e) if e > PAPER_DIFFICULT_ERROR_M => "*",
        _ => "",
    };
    format!(
        "{} / {}, {}{mark} / {}",
        verdict(&c.plain),
        verdict(&c.proposed),
        cm(c.mb_error_plain_m),
        cm(c.mb_error_proposed_m)
    )
}

/// Parses `--cells`: `r,c;r,c;...` (indices 0..7), or `all`.
pub fn parse_cells(s: &str) -> Result<Vec<(usize, usize)>, String> {
    let n = STEP_LENGTHS.len();
    if s == "all" {
        return Ok((0..n).flat_map(|r| (0..n).map(move |c| (r, c))).collect());
    }
    s.split(';')
        .map(|rc| {
            let v: Vec<usize> = rc
                .split(',')
                .map(|x| x.trim().parse::<usize>())
                .collect::<Result<_, _>>()
                .map_err(|_| format!("cell {rc:?}: expected row,column"))?;
            match v[..] {
                [r, c] if r < n && c < n => Ok((r, c)),
                _ => Err(format!("cell {rc:?}: row,column each in 0..{n}")),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_parse() {
        assert_eq!(parse_cells("0,6;3,3").unwrap(), vec![(0, 6), (3, 3)]);
        assert_eq!(parse_cells("all").unwrap().len(), 49);
        assert!(parse_cells("7,0").is_err());
        assert!(parse_cells("1").is_err());
        assert!(parse_cells("a,b").is_err());
    }

    #[test]
    fn json_grid_marks_cells_not_run() {
        let c = Cell {
            row: 1,
            col: 2,
            plain: None,
            proposed: None,
            cop_err_modified_plain_m: None,
            cop_err_modified_proposed_m: None,
            mb_error_plain_m: Some(0.05),
            mb_error_proposed_m: None,
        };
        let j = tables_json(std::slice::from_ref(&c));
        assert_eq!(j["fell_plain"].as_array().unwrap().len(), 7);
        assert!(j["fell_plain"][1][2].is_null());
        assert_eq!(j["mb_zmp_error_plain_m"][1][2], json!(0.05));
        assert!(j["mb_zmp_error_plain_m"][0][0].is_null());
        assert_eq!(side_by_side_text(&c), "n/a / n/a, 5.0 / n/a");
        let big = Cell {
            mb_error_plain_m: Some(0.093),
            mb_error_proposed_m: Some(0.05),
            ..c
        };
        assert_eq!(side_by_side_text(&big), "n/a / n/a, 9.3* / 5.0");
    }
}
