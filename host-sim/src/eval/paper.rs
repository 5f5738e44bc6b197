//! The paper's modification experiments (section IV, Fig. 4, Tables I and II), run through the
//! same gait API as the firmware.
//!
//! Scenario: HRP-2 walks straight with steps of length `before` (step cycle 0.8 s: single
//! support 0.7 s, double support 0.1 s), after standing 0.8 s and a 0.8 s start double
//! support, so that a single support begins at 4.0 s with the swing target at `4·before`. Just
//! before that lift-off (one control cycle earlier) the swing target is moved so that this step
//! has length `after`; the following steps keep the length `before` (the reading of Table II
//! that the design notes point out). The re-plan at 4.0 s applies eq. 18. Right after it the
//! walk is stopped: the queued steps are walked, then the stop window, and the trajectory
//! runs until the robot stands (both feet down), so that an engine run of it ends standing.

use planner_core::gait::{Footstep, Gait, GaitParams, Phase, Reference, Side};
use std::fs;
use std::path::Path;

use serde_json::json;

/// The step lengths of Tables I and II \[m\].
pub const STEP_LENGTHS: [f64; 7] = [-0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3];

/// Table II of the paper: adjustment times \[s\]; rows = length after the modification,
/// columns = length before.
pub const PAPER_ADJUST_S: [[f64; 7]; 7] = [
    [0.0, 0.11, 0.305, 0.0, 0.35, 0.35, 0.35],
    [-0.11, 0.0, 0.19, 0.0, 0.35, 0.35, 0.35],
    [-0.2, -0.2, 0.0, 0.0, 0.35, 0.35, 0.35],
    [-0.2, -0.2, -0.2, 0.0, -0.2, -0.2, -0.2],
    [0.35, 0.35, 0.35, 0.0, 0.0, -0.19, -0.2],
    [0.35, 0.35, 0.35, 0.0, 0.19, 0.0, -0.11],
    [0.35, 0.35, 0.305, 0.0, 0.305, 0.11, 0.0],
];

/// Table I of the paper: maximum multi-body ZMP error without any adjustment \[m\].
pub const PAPER_ERROR_WITHOUT_M: [[f64; 7]; 7] = [
    [0.034, 0.036, 0.046, 0.055, 0.065, 0.075, 0.089],
    [0.033, 0.021, 0.029, 0.039, 0.049, 0.062, 0.077],
    [0.037, 0.023, 0.014, 0.024, 0.035, 0.050, 0.067],
    [0.047, 0.031, 0.017, 0.012, 0.023, 0.039, 0.057],
    [0.061, 0.044, 0.028, 0.014, 0.011, 0.026, 0.047],
    [0.075, 0.058, 0.041, 0.026, 0.022, 0.026, 0.036],
    [0.089, 0.072, 0.056, 0.039, 0.030, 0.033, 0.040],
];

/// Table II of the paper: maximum multi-body ZMP error with the proposed method \[m\].
pub const PAPER_ERROR_WITH_M: [[f64; 7]; 7] = [
    [0.034, 0.031, 0.032, 0.053, 0.033, 0.041, 0.049],
    [0.029, 0.021, 0.024, 0.035, 0.030, 0.037, 0.046],
    [0.034, 0.028, 0.014, 0.019, 0.027, 0.034, 0.042],
    [0.056, 0.040, 0.031, 0.012, 0.029, 0.033, 0.042],
    [0.045, 0.036, 0.028, 0.022, 0.011, 0.037, 0.045],
    [0.049, 0.039, 0.030, 0.039, 0.023, 0.026, 0.042],
    [0.053, 0.042, 0.033, 0.057, 0.028, 0.028, 0.040],
];

/// Tick of the single support in which the modification takes effect (4.0 s).
pub const MODIFICATION_TICK: u64 = 800;

/// The longest the scenario of [`modification`] may take to stand after the stop: 30 s of
/// ticks.
pub const STAND_LIMIT_TICKS: u32 = 6000;

/// The outcome of one modification run.
#[derive(Clone, Debug)]
pub struct Modification {
    /// Step length before \[m\].
    pub before: f64,
    /// Step length after \[m\].
    pub after: f64,
    /// Single-support adjustment applied \[s\].
    pub adjust_s: f64,
    /// `r` of eq. 18.
    pub ratio: f64,
    /// Largest sagittal ZMP deviation from the support-foot centre during the modified single
    /// support, sampled every tick (signed) \[m\].
    pub sagittal_m: f64,
    /// The same in the frontal plane \[m\].
    pub frontal_m: f64,
    /// RMS of the frontal deviation over that single support \[m\].
    pub frontal_rms_m: f64,
    /// Every reference of the run, one per 5 ms tick, to standing at the end.
    pub trajectory: Vec<Reference<f64>>,
    /// The footsteps as walked (after the modification).
    pub footsteps: Vec<Footstep<f64>>,
}

/// The footsteps of the scenario (`shift` added from the 4th step on).
fn footsteps(before: f64, shift: f64, n: u16) -> Vec<Footstep<f64>> {
    (0..n)
        .map(|i| {
            let side = if i % 2 == 0 { Side::Right } else { Side::Left };
            let y = if side == Side::Left { 0.1 } else { -0.1 };
            let s = if i >= 3 { shift } else { 0.0 };
            Footstep::new(side, before * f64::from(i + 1) + s, y, 0.0)
        })
        .collect()
}

/// [`footsteps`] and a closing step: the foot of step `n` beside the last one (the walk's
/// end, feet side by side, as the built-in scenarios end theirs).
fn closed_footsteps(before: f64, shift: f64, n: u16) -> Vec<Footstep<f64>> {
    let mut steps = footsteps(before, shift, n);
    if let Some(&last) = steps.last() {
        let side = last.side.other();
        let y = if side == Side::Left { 0.1 } else { -0.1 };
        steps.push(Footstep::new(side, last.x, y, 0.0));
    }
    steps
}

/// Runs the scenario with the given parameters (set `adjust_min_ticks = adjust_max_ticks = 0`
/// for "without adjustment").
pub fn modification(params: GaitParams<f64>, before: f64, after: f64) -> Modification {
    let n = 12;
    let mut g: Gait<f64, 16> = Gait::new(
        params,
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    )
    .expect("valid gait parameters");
    for (i, s) in closed_footsteps(before, 0.0, n).into_iter().enumerate() {
        g.push(i as u16, s).expect("queue holds the scenario");
    }
    let mut trajectory = vec![*g.last()];
    for _ in 0..160 {
        trajectory.push(g.tick());
    }
    g.start().expect("standing with steps queued");
    while g.ticks() < MODIFICATION_TICK - 1 {
        trajectory.push(g.tick());
    }
    let modified = closed_footsteps(before, after - before, n);
    // The later steps first, then the swing target (the one checked by eq. 17).
    for i in (3..modified.len() as u16).rev() {
        // A refusal (eq. 17) leaves the step as it was; the figures then show that.
        let _ = g.modify(i, modified[usize::from(i)]);
    }
    trajectory.push(g.tick());
    let info = *g.last_replan().expect("a re-plan at 4.0 s");
    assert_eq!(info.tick, MODIFICATION_TICK, "scenario timing");
    // The queued steps are walked, then the robot stands (a stop after the re-plan leaves the
    // modified step's plan as it is: the windows see three landings ahead, all queued).
    g.stop();
    // The swing target is step 3 (left foot); the support is step 2 (right foot).
    let support = (before * 3.0, -0.1);
    let (mut sag, mut fro, mut sq, mut cnt) = (0.0_f64, 0.0_f64, 0.0, 0.0);
    loop {
        let r = *trajectory.last().expect("non-empty");
        if r.phase != Phase::Single(Side::Right) {
            break;
        }
        let (dx, dy) = (r.x.zmp - support.0, r.y.zmp - support.1);
        if dx.abs() > sag.abs() {
            sag = dx;
        }
        if dy.abs() > fro.abs() {
            fro = dy;
        }
        sq += dy * dy;
        cnt += 1.0;
        trajectory.push(g.tick());
    }
    // Until standing (the walk ends within seconds; the bound only keeps a broken gait from
    // looping: the trajectory then ends walking, which the engine's report says).
    for _ in 0..STAND_LIMIT_TICKS {
        if g.is_standing() {
            break;
        }
        trajectory.push(g.tick());
    }
    Modification {
        before,
        after,
        adjust_s: f64::from(info.adjust_ticks) * params.dt,
        ratio: info.ratio,
        sagittal_m: sag,
        frontal_m: fro,
        frontal_rms_m: if cnt > 0.0 { (sq / cnt).sqrt() } else { 0.0 },
        trajectory,
        footsteps: modified,
    }
}

/// The first step the consecutive modifications of [`consecutive`] change: step 3 (left foot),
/// lifting off at 4.0 s as in the grid.
pub const SEQUENCE_FIRST_STEP: u16 = 3;

/// The default consecutive modifications (`host-sim physics-sequence`): a walk planned with
/// 0.1 m steps whose steps 3 to 7 are changed, each one control cycle before its lift-off, to
/// +0.3, −0.1, +0.12, +0.3 and −0.1 m: five modifications in a row, four of them by 0.2 m,
/// each inside the node's reach limits (`Reach::default()`) given the steps before it (a step
/// may grow by 0.22 m at most over the one before, so after −0.1 m the next is at most
/// +0.12 m), the later steps keeping 0.1 m.
pub const SEQUENCE_BEFORE_M: f64 = 0.1;

/// The lengths of the modified steps of the default sequence \[m\] (see [`SEQUENCE_BEFORE_M`]).
pub const SEQUENCE_AFTERS_M: [f64; 5] = [0.3, -0.1, 0.12, 0.3, -0.1];

/// One modification of a [`Sequence`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequenceStep {
    /// The step modified.
    pub id: u16,
    /// Its new length \[m\].
    pub after: f64,
    /// The gait accepted the modification (eq. 17); if not, the step kept its length.
    pub accepted: bool,
    /// Tick of its lift-off (the re-plan that applied it).
    pub liftoff_tick: u64,
    /// Tick of its landing (the first tick of the double support after its swing).
    pub landing_tick: u64,
    /// Single-support adjustment of that re-plan \[s\].
    pub adjust_s: f64,
    /// `r` of eq. 18.
    pub ratio: f64,
}

/// A walk with several consecutive steps modified ([`consecutive`]).
#[derive(Clone, Debug)]
pub struct Sequence {
    /// The planned step length \[m\].
    pub before: f64,
    /// The modifications, in order.
    pub steps: Vec<SequenceStep>,
    /// Every reference of the run, one per tick, to standing at the end.
    pub trajectory: Vec<Reference<f64>>,
    /// The footsteps as planned after each modification (the first: before any), for the
    /// reach check.
    pub plans: Vec<Vec<Footstep<f64>>>,
}

impl Sequence {
    /// The footsteps as walked.
    pub fn walked(&self) -> &[Footstep<f64>] {
        self.plans.last().map_or(&[], |p| p.as_slice())
    }

    /// The time window of the modified steps \[s\]: from the first modified lift-off to the end
    /// of the double support after the last modified landing.
    pub fn window_s(&self, params: &GaitParams<f64>) -> (f64, f64) {
        let dt = params.dt;
        match (self.steps.first(), self.steps.last()) {
            (Some(a), Some(b)) => (
                a.liftoff_tick as f64 * dt,
                (b.landing_tick + u64::from(params.double_ticks)) as f64 * dt,
            ),
            _ => (0.0, 0.0),
        }
    }
}

/// The scenario of [`modification`] with several consecutive steps modified: steps of length
/// `before`; one control cycle before the lift-off of step [`SEQUENCE_FIRST_STEP`] `+ k` (the
/// moment found by ticking a copy of the gait ahead), that step is moved to length `afters[k]`
/// from the step before it, the later steps with it (so they keep the length `before`). After
/// the last modified re-plan the walk is stopped; the trajectory runs until standing. Errors:
/// the gait failed to plan, or did not stand within 30 s.
pub fn consecutive(
    params: GaitParams<f64>,
    before: f64,
    afters: &[f64],
) -> Result<Sequence, String> {
    let first = SEQUENCE_FIRST_STEP;
    let n = first + afters.len() as u16 + 3;
    let mut g: Gait<f64, 16> = Gait::new(
        params,
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    )
    .map_err(|e| format!("gait parameters: {e:?}"))?;
    let mut plan = footsteps(before, 0.0, n);
    for (i, s) in plan.iter().enumerate() {
        g.push(i as u16, *s)
            .map_err(|e| format!("step {i}: {e:?}"))?;
    }
    let mut trajectory = vec![*g.last()];
    for _ in 0..160 {
        trajectory.push(g.tick());
    }
    g.start().map_err(|e| format!("start: {e:?}"))?;
    let mut plans = vec![plan.clone()];
    let mut steps: Vec<SequenceStep> = Vec::new();
    let limit = 6000; // 30 s
                      // One tick, noting the landing of the last modified step (the first double support after
                      // its lift-off).
    let advance = |g: &mut Gait<f64, 16>,
                   trajectory: &mut Vec<Reference<f64>>,
                   steps: &mut Vec<SequenceStep>| {
        let r = g.tick();
        if let Some(s) = steps.last_mut() {
            if s.landing_tick == 0 && r.phase == Phase::Double {
                s.landing_tick = g.ticks();
            }
        }
        trajectory.push(r);
    };
    for (k, &after) in afters.iter().enumerate() {
        let id = first + k as u16;
        // Up to one control cycle before the lift-off of `id`.
        loop {
            let mut ahead = g.clone();
            ahead.tick();
            if ahead.swinging() == Some(id) {
                break;
            }
            if g.ticks() > limit {
                return Err(format!("step {id} never lifted off"));
            }
            advance(&mut g, &mut trajectory, &mut steps);
        }
        let i = usize::from(id);
        let delta = plan[i - 1].x + after - plan[i].x;
        let mut moved = plan.clone();
        for s in moved.iter_mut().skip(i) {
            s.x += delta;
        }
        // The later steps first, then the swing target (the one checked by eq. 17); if that
        // is refused, the later steps go back.
        for j in (i + 1..usize::from(n)).rev() {
            g.modify(j as u16, moved[j])
                .map_err(|e| format!("step {j}: {e:?}"))?;
        }
        let accepted = g.modify(id, moved[i]).is_ok();
        if accepted {
            plan = moved;
        } else {
            for j in (i + 1..usize::from(n)).rev() {
                g.modify(j as u16, plan[j])
                    .map_err(|e| format!("step {j}: {e:?}"))?;
            }
        }
        plans.push(plan.clone());
        advance(&mut g, &mut trajectory, &mut steps);
        let info = *g.last_replan().ok_or("no re-plan at the lift-off")?;
        if g.swinging() != Some(id) || info.tick != g.ticks() {
            return Err(format!("step {id}: the re-plan was not at its lift-off"));
        }
        steps.push(SequenceStep {
            id,
            after,
            accepted,
            liftoff_tick: info.tick,
            landing_tick: 0,
            adjust_s: f64::from(info.adjust_ticks) * params.dt,
            ratio: info.ratio,
        });
    }
    g.stop();
    while !g.is_standing() {
        if g.ticks() > limit {
            return Err("the walk did not stop within 30 s".into());
        }
        advance(&mut g, &mut trajectory, &mut steps);
    }
    Ok(Sequence {
        before,
        steps,
        trajectory,
        plans,
    })
}

/// Parameters with the single-support adjustment switched off.
pub fn without_adjustment(mut params: GaitParams<f64>) -> GaitParams<f64> {
    params.adjust_min_ticks = 0;
    params.adjust_max_ticks = 0;
    params
}

/// The plain re-plan of Table I: the gait `params` with no single-support adjustment (eq. 18)
/// and no shaping (what `host-sim tables`, `physics-tables` and `physics-sequence` call
/// "plain").
pub fn plain_params(params: GaitParams<f64>) -> GaitParams<f64> {
    let mut p = without_adjustment(params);
    p.shaping = false;
    p
}

/// The 7×7 grid of Table II (rows: after, columns: before).
pub fn table(params: GaitParams<f64>) -> Vec<Vec<Modification>> {
    STEP_LENGTHS
        .iter()
        .map(|&after| {
            STEP_LENGTHS
                .iter()
                .map(|&before| {
                    let mut m = modification(params, before, after);
                    m.trajectory = Vec::new();
                    m
                })
                .collect()
        })
        .collect()
}

/// How many cells of an adjustment grid agree with Table II within `cycles` control cycles.
pub fn cells_within(grid: &[Vec<Modification>], dt: f64, cycles: f64) -> usize {
    let mut n = 0;
    for (r, row) in grid.iter().enumerate() {
        for (c, m) in row.iter().enumerate() {
            if (m.adjust_s - PAPER_ADJUST_S[r][c]).abs() <= cycles * dt + 1e-9 {
                n += 1;
            }
        }
    }
    n
}

/// Largest distance between the multi-body ZMP of `model` and the support-foot centre during
/// the single support in which the modification takes effect \[m\] (the paper's "maximum ZMP
/// error", as `host-sim tables` and `host-sim physics-tables` report it); `None` when the
/// model's legs cannot reach the footsteps.
pub fn modified_support_error(
    model: &crate::robot::model::Model,
    m: &Modification,
    dt: f64,
) -> Option<f64> {
    let mb = crate::eval::multibody::evaluate(model, &m.trajectory, dt).ok()?;
    let start = MODIFICATION_TICK as usize;
    let support = (m.before * 3.0, -0.1);
    let mut worst: f64 = 0.0;
    for (r, s) in m.trajectory.iter().zip(&mb).skip(start) {
        if r.phase != Phase::Single(Side::Right) {
            break;
        }
        worst = worst.max((s.mb_zmp_x - support.0).hypot(s.mb_zmp_y - support.1));
    }
    Some(worst)
}

/// Checks footsteps walked from the scenario's stance (feet at (0, ±0.1) m) against the leg
/// reach limits `reach` as the node does (the first step from rest), with feet of `soles`.
/// Errors: the first step refused, and why.
pub fn check_reach(
    reach: &planner_core::node::Reach,
    soles: &planner_core::node::Soles,
    steps: &[Footstep<f64>],
) -> Result<(), String> {
    let mut feet = [
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    ];
    let index = |s: Side| if s == Side::Left { 0 } else { 1 };
    for (i, step) in steps.iter().enumerate() {
        let (same, other) = (feet[index(step.side)], feet[index(step.side.other())]);
        reach
            .check_with(&other, &same, step, i == 0, soles)
            .map_err(|e| format!("step {i} at x = {:.3} m: {e:?}", step.x))?;
        feet[index(step.side)] = *step;
    }
    Ok(())
}

/// [`modified_support_error`] over the single supports of the modified steps of a
/// [`Sequence`]: the largest distance between the multi-body ZMP of `model` and the centre of
/// the support foot (the step before the one swinging) \[m\]; `None` when the legs cannot
/// reach the footsteps.
pub fn sequence_support_error(
    model: &crate::robot::model::Model,
    seq: &Sequence,
    dt: f64,
) -> Option<f64> {
    let mb = crate::eval::multibody::evaluate(model, &seq.trajectory, dt).ok()?;
    let walked = seq.walked();
    let mut worst: f64 = 0.0;
    for s in &seq.steps {
        let support = walked.get(usize::from(s.id).checked_sub(1)?)?;
        let (a, b) = (s.liftoff_tick as usize, s.landing_tick as usize);
        for m in mb.get(a..b.min(mb.len()))? {
            worst = worst.max((m.mb_zmp_x - support.x).hypot(m.mb_zmp_y - support.y));
        }
    }
    Some(worst)
}

/// A 7×7 grid over [`STEP_LENGTHS`] as a Markdown table (rows: after, columns: before), the
/// text of cell `(row, column)` from `cell`.
pub fn grid_markdown(title: &str, cell: impl Fn(usize, usize) -> String) -> String {
    let mut md = format!("{title}\n\n| after \\ before |");
    for b in STEP_LENGTHS {
        md += &format!(" {b:+.1} |");
    }
    md += "\n|---|";
    for _ in STEP_LENGTHS {
        md += "---|";
    }
    md += "\n";
    for (r, after) in STEP_LENGTHS.iter().enumerate() {
        md += &format!("| {after:+.1} |");
        for c in 0..STEP_LENGTHS.len() {
            md += &format!(" {} |", cell(r, c));
        }
        md += "\n";
    }
    md
}

/// The `host-sim tables` command: the paper's Tables I and II and the Fig. 4 adjustment
/// recomputed with the multi-body HRP-2 model; writes `out/tables.json` and `out/tables.md`.
pub fn tables_command(out: &Path) -> Result<(), String> {
    let params = GaitParams::<f64>::hrp2();
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let n = STEP_LENGTHS.len();
    let mut adjust = vec![vec![0.0; n]; n];
    let mut with = vec![vec![0.0; n]; n];
    let mut without = vec![vec![0.0; n]; n];
    let mut lipm_with = vec![vec![0.0; n]; n];
    let mut lipm_without = vec![vec![0.0; n]; n];
    let mut grid = Vec::new();
    // Table I: no adjustment of the COG and ZMP at all (no eq. 18, no shaping).
    let bare = plain_params(params);
    let bar = crate::console::Progress::new("tables", (n * n) as u64);
    for (r, &after) in STEP_LENGTHS.iter().enumerate() {
        let mut row = Vec::new();
        for (c, &before) in STEP_LENGTHS.iter().enumerate() {
            bar.message(format!("cell ({r}, {c})"));
            let m = modification(params, before, after);
            let w = modification(bare, before, after);
            adjust[r][c] = m.adjust_s;
            lipm_with[r][c] = m.sagittal_m.abs().max(m.frontal_m.abs());
            lipm_without[r][c] = w.sagittal_m.abs().max(w.frontal_m.abs());
            with[r][c] = modified_support_error(&crate::robot::model::Model::hrp2(), &m, params.dt)
                .unwrap_or(f64::NAN);
            without[r][c] =
                modified_support_error(&crate::robot::model::Model::hrp2(), &w, params.dt)
                    .unwrap_or(f64::NAN);
            let mut m = m;
            m.trajectory.clear();
            row.push(m);
            bar.inc(format!("cell ({r}, {c})"));
        }
        grid.push(row);
    }
    drop(bar);
    let within = cells_within(&grid, params.dt, 1.0);
    let json = json!({
        "step_lengths_m": STEP_LENGTHS,
        "rows": "length after the modification",
        "columns": "length before the modification",
        "adjust_s": adjust,
        "paper_adjust_s": PAPER_ADJUST_S,
        "cells_within_one_cycle": within,
        "zmp_error_model": "multi-body HRP-2 model (host-sim/src/eval/multibody.rs): largest distance between its ZMP and the support-foot centre in the single support where the modification takes effect",
        "max_zmp_error_without_m": without,
        "max_zmp_error_with_m": with,
        "lipm_zmp_fluctuation_without_m": lipm_without,
        "lipm_zmp_fluctuation_with_m": lipm_with,
        "paper_max_zmp_error_without_m": PAPER_ERROR_WITHOUT_M,
        "paper_max_zmp_error_with_m": PAPER_ERROR_WITH_M,
    });
    write_file(
        &out.join("tables.json"),
        serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?,
    )?;
    let mut md = grid_markdown(
        "Adjustment time [s], ours / paper's Table II (rows: after, columns: before)",
        |r, c| format!("{:.3} / {:.3}", adjust[r][c], PAPER_ADJUST_S[r][c]),
    );
    md += &format!("\n{within}/49 cells within one control cycle (5 ms) of the paper.\n");
    let cell = |v: f64| {
        if v.is_finite() {
            format!("{:.1}", v * 100.0)
        } else {
            "n/a".to_string()
        }
    };
    for (title, ours, theirs) in [
        (
            "Table I: maximum ZMP error without any adjustment [cm], ours (multi-body) / paper",
            &without,
            &PAPER_ERROR_WITHOUT_M,
        ),
        (
            "Table II: maximum ZMP error with the proposed method [cm], ours (multi-body) / paper",
            &with,
            &PAPER_ERROR_WITH_M,
        ),
    ] {
        md += "\n";
        md += &grid_markdown(title, |r, c| {
            format!("{} / {:.1}", cell(ours[r][c]), theirs[r][c] * 100.0)
        });
    }
    md += "\nn/a: the model's legs (thigh and shank 0.3 m) cannot reach the footsteps.\n";
    write_file(&out.join("tables.md"), &md)?;
    crate::outln!("{md}");
    crate::outln!(
        "results: {} and {}",
        out.join("tables.json").display(),
        out.join("tables.md").display()
    );
    Ok(())
}

/// Writes `contents` to `path`; the error names it.
fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), String> {
    fs::write(path, contents).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
