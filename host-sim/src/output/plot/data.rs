//! What the figures show, computed from a trajectory or a run: support phases, sole limits,
//! the ZMP fluctuation, the landings with their step numbers, the modification instants and
//! the comparison runs of `modification.png`.

use planner_core::gait::{Footstep, Gait, GaitParams, Phase, Reference, Side};

use super::{Column, Landing, Mark};
use crate::eval::paper::without_adjustment;
use crate::scenario::{self, Command, Run, Scenario};

/// Same pose within 1 mm and 2 mrad.
fn same_pose(a: &Footstep<f64>, b: &Footstep<f64>) -> bool {
    a.side == b.side
        && (a.x - b.x).abs() <= 1e-3
        && (a.y - b.y).abs() <= 1e-3
        && (a.yaw - b.yaw).abs() <= 2e-3
}

/// The footprints stood on after the initial stance: every new ground pose of a foot (sole
/// height 0) in the trajectory, in time order.
pub fn walked_landings(trajectory: &[Reference<f64>]) -> Vec<Footstep<f64>> {
    let mut out = Vec::new();
    let Some(first) = trajectory.first() else {
        return out;
    };
    let mut last: [(f64, f64, f64); 2] = [0, 1].map(|k| {
        let f = &first.feet[k];
        (f.x, f.y, f.yaw)
    });
    for r in trajectory {
        for (k, f) in r.feet.iter().enumerate() {
            if f.z != 0.0 {
                continue;
            }
            let pose = (f.x, f.y, f.yaw);
            if last[k] != pose {
                last[k] = pose;
                let side = if k == 0 { Side::Left } else { Side::Right };
                out.push(Footstep::new(side, f.x, f.y, f.yaw));
            }
        }
    }
    out
}

/// The landings of a run: the walked footprints, each with the id of the footstep queued at
/// that pose and, if the step was modified after its append, the pose it was appended at.
pub fn landings(run: &Run) -> Vec<Landing> {
    let first_append = |id: u16| {
        run.events
            .iter()
            .find_map(|e| match (e.command, &e.result) {
                (Command::Push(i, f), Ok(())) if i == id => Some(f),
                _ => None,
            })
    };
    let mut used = vec![false; run.footsteps.len()];
    walked_landings(&run.trajectory)
        .into_iter()
        .map(|foot| {
            let found = run
                .footsteps
                .iter()
                .enumerate()
                .find(|(i, (_, f))| !used[*i] && same_pose(f, &foot));
            let id = found.map(|(i, &(id, _))| {
                used[i] = true;
                id
            });
            let planned = id.and_then(first_append).filter(|p| !same_pose(p, &foot));
            Landing { id, foot, planned }
        })
        .collect()
}

/// The index in `run.events` of the first accepted start, if any.
fn first_start(run: &Run) -> Option<usize> {
    run.events
        .iter()
        .position(|e| matches!((e.command, &e.result), (Command::Start, Ok(()))))
}

/// The instants of the accepted modifications: one mark per control cycle with modifications,
/// at the first reference computed after them (a command applied in tick `k` can shape the
/// reference of row `k + 1` on; a modification of a step that is not the next to swing
/// changes the walk only once that step lifts off), labelled with the steps moved and the
/// single-support adjustment of the re-plan in that row, if any. A modification applied
/// before the first accepted start (the robot still stood) is flagged
/// [`Mark::before_start`] and labelled so, with the start's time (that of its command).
pub fn modification_marks(run: &Run, dt: f64) -> Vec<Mark> {
    let start = first_start(run);
    let start_label = match start {
        Some(i) => format!(
            ", before the start ({:.3} s)",
            run.events[i].tick as f64 * dt
        ),
        None => ", before any start".into(),
    };
    let mut ticks: Vec<(u64, bool, Vec<u16>)> = Vec::new();
    for (i, e) in run.events.iter().enumerate() {
        if let (Command::Modify(id, _), Ok(())) = (e.command, &e.result) {
            let before = start.is_none_or(|s| i < s);
            match ticks.last_mut() {
                Some((t, b, ids)) if *t == e.tick && *b == before => ids.push(id),
                _ => ticks.push((e.tick, before, vec![id])),
            }
        }
    }
    ticks
        .into_iter()
        .map(|(tick, before_start, mut ids)| {
            ids.sort_unstable();
            ids.dedup();
            let row = tick + 1;
            let steps = match (ids.first(), ids.last()) {
                (Some(a), Some(b)) if a == b => format!("step {a}"),
                (Some(a), Some(b)) if usize::from(b - a) + 1 == ids.len() => {
                    format!("steps {a}–{b}")
                }
                _ => format!(
                    "steps {}",
                    ids.iter()
                        .map(|i| i.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            };
            let adjust = run
                .adjustments
                .iter()
                .find(|a| a.tick == row)
                .map(|a| format!(" (ΔT {:+.3} s)", a.adjust_s))
                .unwrap_or_default();
            let when = if before_start {
                start_label.as_str()
            } else {
                ""
            };
            Mark {
                t: row as f64 * dt,
                label: format!(
                    "modification at {:.3} s{when}: {steps}{adjust}",
                    row as f64 * dt
                ),
                before_start,
            }
        })
        .collect()
}

/// The comparison columns of `modification.png` for a run of `s` with accepted
/// modifications during the walk (none otherwise), and the plane of the first adjustment (0
/// if none).
///
/// A modification applied before the first accepted start changes the plan before anything
/// is walked: there is no walk without it to compare with (the run without it was never
/// begun, and the time adjustment has nothing to adjust), so such modifications alone give no
/// columns, and column (a) keeps them when the walk has later ones too.
pub(super) fn comparison(
    s: &Scenario,
    run: &Run,
    params: GaitParams<f64>,
) -> Result<(Vec<Column>, usize), String> {
    let plane = run
        .adjustments
        .first()
        .map_or(0, |a| usize::from(a.plane))
        .min(1);
    let start = first_start(run);
    let accepted = |i: usize| matches!(run.events[i].result, Ok(()));
    let is_modify = |i: usize| matches!(run.events[i].command, Command::Modify(..));
    let during = |i: usize| start.is_some_and(|s| i > s);
    let n = run.events.len();
    if !(0..n).any(|i| is_modify(i) && accepted(i) && during(i)) {
        return Ok((Vec::new(), plane));
    }
    let before = (0..n).any(|i| is_modify(i) && accepted(i) && !during(i));
    let bare = without_adjustment(params);
    // scenario::run expects parameters the gait accepts: check them here.
    for p in [params, bare] {
        let [left, right] = s.start_feet(p.step_width);
        Gait::<f64, 64>::new(p, left, right)
            .map_err(|e| format!("comparison runs of {}: gait parameters: {e:?}", s.name))?;
    }
    // Event `i` is the answer to timeline entry `i` (played in order, each once).
    let mut first = s.clone();
    first.timeline = s
        .timeline
        .iter()
        .enumerate()
        .filter(|&(i, (_, c))| !(matches!(c, Command::Modify(..)) && start.is_some_and(|s| i > s)))
        .map(|(_, e)| *e)
        .collect();
    let columns = vec![
        Column {
            title: if before {
                "(a) as planned at the start: no modification during the walk".into()
            } else {
                "(a) as first planned: no modification".into()
            },
            trajectory: scenario::run(&first, params).trajectory,
        },
        Column {
            title: "(b) modified, without the time adjustment".into(),
            trajectory: scenario::run(s, bare).trajectory,
        },
    ];
    Ok((columns, plane))
}

/// One support phase: `[t0, t1)` and the phase.
pub(super) type Span = (f64, f64, Phase);

/// The phases of a trajectory as time intervals (row `k` covers `[k·dt, (k+1)·dt)`).
pub(super) fn phase_spans(trajectory: &[Reference<f64>], dt: f64) -> Vec<Span> {
    let mut out: Vec<Span> = Vec::new();
    for (k, r) in trajectory.iter().enumerate() {
        let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
        match out.last_mut() {
            Some(s) if s.2 == r.phase => s.1 = t1,
            _ => out.push((t0, t1, r.phase)),
        }
    }
    out
}

fn plane_of(x: f64, y: f64, plane: usize) -> f64 {
    if plane == 0 {
        x
    } else {
        y
    }
}

/// Half the extent of a sole (length, width) with heading `yaw` along axis `plane`.
fn half_extent(yaw: f64, plane: usize, sole: [f64; 2]) -> f64 {
    let (s, c) = yaw.sin_cos();
    let (a, b) = (0.5 * sole[0], 0.5 * sole[1]);
    if plane == 0 {
        a * c.abs() + b * s.abs()
    } else {
        a * s.abs() + b * c.abs()
    }
}

/// The extent of the support polygon along axis `plane` (0: x, otherwise y), as (lowest,
/// highest) coordinate \[m\]: the support sole in single support, both soles otherwise;
/// `sole`: its length and width \[m\].
pub fn sole_limits(r: &Reference<f64>, plane: usize, sole: [f64; 2]) -> (f64, f64) {
    let feet: &[usize] = match r.phase {
        Phase::Single(Side::Left) => &[0],
        Phase::Single(Side::Right) => &[1],
        _ => &[0, 1],
    };
    feet.iter()
        .map(|&k| {
            let f = &r.feet[k];
            let (c, h) = (plane_of(f.x, f.y, plane), half_extent(f.yaw, plane, sole));
            (c - h, c + h)
        })
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        })
}

/// The planned ZMP minus the support-sole centre along axis `plane` (0: x, otherwise y) in
/// single support \[m\]; `None` in double support.
pub fn fluctuation(r: &Reference<f64>, plane: usize) -> Option<f64> {
    let k = match r.phase {
        Phase::Single(Side::Left) => 0,
        Phase::Single(Side::Right) => 1,
        _ => return None,
    };
    let f = &r.feet[k];
    let zmp = if plane == 0 { r.x.zmp } else { r.y.zmp };
    Some(zmp - plane_of(f.x, f.y, plane))
}

/// The COG along axis `plane`.
pub(super) fn cog(r: &Reference<f64>, plane: usize) -> f64 {
    if plane == 0 {
        r.x.cog
    } else {
        r.y.cog
    }
}

/// The planned ZMP along axis `plane`.
pub(super) fn zmp(r: &Reference<f64>, plane: usize) -> f64 {
    if plane == 0 {
        r.x.zmp
    } else {
        r.y.zmp
    }
}
