//! Several modified steps in a row in the engine (`host-sim physics-sequence`).
//!
//! The Tables I/II grid ([`super::tables`]) changes one step. Here consecutive steps are each
//! changed one control cycle before their lift-off ([`paper::consecutive`]: by default a walk
//! planned with 0.1 m steps whose steps 3–7 become +0.3, −0.1, +0.12, +0.3 and −0.1 m long),
//! and the
//! walk is run in MuJoCo twice, as a grid cell is: with the **plain re-plan**
//! ([`paper::plain_params`]: no adjustment, no shaping, the switch `physics-tables` uses) and
//! with the **proposed method**. The footsteps as planned after every modification are
//! checked against the robot's reach limits first (the node's [`Reach`] rules), so that the
//! sequence is one the node would accept.
//!
//! `host-sim physics-sequence --out DIR [--before M] [--afters M,M,...]` (and the probe options
//! of [`super::probe`]) writes `DIR/physics_sequence.json`: `before_m`, `afters_m`, the probe
//! settings, and `plain` and `proposed`, each with the engine's `fell`, `fall_time_s`,
//! `fall_cause`, the end of the run ([`super::PhysicsReport::end_fields`]: `fell_after_end`,
//! `ended_standing`, …), `max_tilt_deg`, `cop_err_mean_m`, `cop_err_max_m`, the worst 50 ms CoP error
//! in the modified steps' window (`cop_err_modified_m`, `modified_window_s`), the kinematic
//! multi-body ZMP error of those single supports (`mb_zmp_error_m`), and per modification
//! `accepted` (eq. 17), `adjust_s` and the lift-off time; and `DIR/physics_sequence.md`.

use std::fs;
use std::path::Path;

use serde_json::{json, Value};

use super::probe::ProbeArgs;
use super::tables::window_error_in;
use super::{run, PhysicsConfig, PhysicsReport};
use crate::eval::paper::{self, plain_params, Sequence};
use crate::robot::Robot;
use planner_core::gait::GaitParams;
use planner_core::node::{Reach, Soles};

/// `--afters` by default: [`paper::SEQUENCE_AFTERS_M`] as text.
pub const DEFAULT_AFTERS: &str = "0.3,-0.1,0.12,0.3,-0.1";

/// The sequence run one way in the engine.
#[derive(Clone, Debug)]
pub struct SequenceRun {
    /// The walk (its trajectory cleared after the run).
    pub sequence: Sequence,
    /// The engine's report.
    pub report: PhysicsReport,
    /// The window of the modified steps \[s\] ([`Sequence::window_s`]).
    pub window_s: (f64, f64),
    /// The worst 50 ms CoP error in that window \[m\].
    pub cop_err_modified_m: f64,
    /// The kinematic multi-body ZMP error of the modified single supports \[m\] (`None`: the
    /// legs cannot reach).
    pub mb_error_m: Option<f64>,
    /// The control period \[s\].
    pub dt: f64,
}

/// Runs the walk with the gait `params` (`plain`: [`plain_params`] of them) in the engine
/// after checking every plan of it against `reach`. Errors: a footstep out of reach, the gait
/// or the engine failed.
pub fn run_one(
    params: GaitParams<f64>,
    plain: bool,
    before: f64,
    afters: &[f64],
    reach: &Reach,
    cfg: &PhysicsConfig,
) -> Result<SequenceRun, String> {
    let params = if plain { plain_params(params) } else { params };
    let mut sequence = paper::consecutive(params, before, afters)?;
    for (k, plan) in sequence.plans.iter().enumerate() {
        paper::check_reach(reach, &Soles::of(&params), plan).map_err(|e| {
            format!("the footsteps after {k} modifications are out of the legs' reach: {e}")
        })?;
    }
    let mb_error_m = paper::sequence_support_error(cfg.robot.link_table(), &sequence, params.dt);
    let r = run(&sequence.trajectory, params.dt, cfg)?;
    let window_s = sequence.window_s(&params);
    sequence.trajectory = Vec::new();
    Ok(SequenceRun {
        sequence,
        cop_err_modified_m: window_error_in(&r.samples, window_s),
        report: r.report,
        window_s,
        mb_error_m,
        dt: params.dt,
    })
}

/// Parses `--afters`: comma-separated finite lengths \[m\], at least one.
pub fn parse_afters(s: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|x| match x.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!("--afters: {x:?} is not a length in m")),
        })
        .collect()
}

/// The JSON of one run.
pub fn run_json(r: &SequenceRun) -> Value {
    let p = &r.report;
    let mut j = json!({
        "fell": p.fell,
        "fall_time_s": p.fall_time_s,
        "fall_cause": p.fall_cause.map(|c| c.name()),
        "max_tilt_deg": p.max_tilt_deg,
        "cop_err_mean_m": p.cop_err_mean_m,
        "cop_err_max_m": p.cop_err_max_m,
        "cop_err_modified_m": r.cop_err_modified_m,
        "modified_window_s": [r.window_s.0, r.window_s.1],
        "mb_zmp_error_m": r.mb_error_m,
        "simulated_s": p.simulated_s,
        "modifications": r.sequence.steps.iter().map(|s| json!({
            "step": s.id,
            "after_m": s.after,
            "accepted": s.accepted,
            "liftoff_s": s.liftoff_tick as f64 * r.dt,
            "adjust_s": s.adjust_s,
            "ratio": s.ratio,
        })).collect::<Vec<_>>(),
    });
    p.add_end_fields(&mut j);
    j
}

/// The two runs as a Markdown table.
pub fn markdown(before: f64, afters: &[f64], mode: &str, runs: &[(&str, &SequenceRun)]) -> String {
    let lengths: Vec<String> = afters.iter().map(|a| format!("{a:+.2}")).collect();
    let mut md = format!(
        "Steps of {before:.2} m, steps {}–{} changed to {} m one control cycle before each \
         lift-off, in MuJoCo ({mode})\n\n\
         | pattern | fell | walked | max tilt (°) | CoP error mean / worst (mm) | worst in the modified steps (mm) | kinematic multi-body error (mm) | adjustments (s) |\n\
         |---|---|---|---|---|---|---|---|\n",
        paper::SEQUENCE_FIRST_STEP,
        usize::from(paper::SEQUENCE_FIRST_STEP) + afters.len() - 1,
        lengths.join(", ")
    );
    for (name, r) in runs {
        let p = &r.report;
        let adj: Vec<String> = r
            .sequence
            .steps
            .iter()
            .map(|s| {
                if s.accepted {
                    format!("{:+.3}", s.adjust_s)
                } else {
                    "refused".into()
                }
            })
            .collect();
        md += &format!(
            "| {name} | {} | {} | {:.2} | {:.1} / {:.1} | {:.1} | {} | {} |\n",
            p.fell_text(),
            p.walked_text(),
            p.max_tilt_deg,
            p.cop_err_mean_m * 1e3,
            p.cop_err_max_m * 1e3,
            r.cop_err_modified_m * 1e3,
            r.mb_error_m
                .map_or("n/a".to_string(), |e| format!("{:.1}", e * 1e3)),
            adj.join(", ")
        );
    }
    md
}

/// The command line's `physics-sequence` subcommand: the walk with the plain re-plan and with
/// the proposed method, `robot`'s gait, reach and link table (it must stand as HRP-2), the
/// probe options; `DIR/physics_sequence.json` and `.md`.
pub fn cli(
    out: &Path,
    before: f64,
    afters: &str,
    robot: &Robot,
    probe: &ProbeArgs,
) -> Result<(), Box<dyn std::error::Error>> {
    let afters = parse_afters(afters)?;
    robot.check_hrp2_footsteps("physics-sequence")?;
    let probe = probe.resolve(robot)?;
    let params = robot.planner.params;
    let reach = robot.node_config().reach;
    let plain = run_one(params, true, before, &afters, &reach, &probe.cfg)?;
    let proposed = run_one(params, false, before, &afters, &reach, &probe.cfg)?;
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let mut j = json!({
        "robot": robot.name(),
        "before_m": before,
        "afters_m": afters,
        "first_modified_step": paper::SEQUENCE_FIRST_STEP,
        "plain_pattern": "no single-support adjustment (eq. 18) and no shaping (Table I)",
        "proposed_pattern": "adjustment and shaping (Table II)",
        "plain": run_json(&plain),
        "proposed": run_json(&proposed),
    });
    probe.record(&mut j);
    let path = out.join("physics_sequence.json");
    fs::write(&path, serde_json::to_string_pretty(&j)?)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let md = markdown(
        before,
        &afters,
        &probe.mode(),
        &[("plain re-plan", &plain), ("proposed method", &proposed)],
    ) + &probe.ladder_markdown();
    let mdpath = out.join("physics_sequence.md");
    fs::write(&mdpath, &md).map_err(|e| format!("cannot write {}: {e}", mdpath.display()))?;
    crate::outln!("{md}");
    crate::outln!("results: {} and {}", path.display(), mdpath.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn afters_parse() {
        assert_eq!(
            parse_afters(DEFAULT_AFTERS).unwrap(),
            paper::SEQUENCE_AFTERS_M.to_vec()
        );
        assert_eq!(parse_afters("0.1, -0.1").unwrap(), vec![0.1, -0.1]);
        assert!(parse_afters("").is_err());
        assert!(parse_afters("0.1,x").is_err());
        assert!(parse_afters("nan").is_err());
    }

    /// The default sequence: every modification accepted with both patterns, one control
    /// cycle before the lift-off of consecutive steps, within the node's reach limits; the
    /// plain re-plan adjusts nothing, the proposed method does.
    #[test]
    fn the_default_sequence_is_consecutive_and_reachable() {
        let params = GaitParams::<f64>::hrp2();
        for plain in [true, false] {
            let p = if plain { plain_params(params) } else { params };
            let s =
                paper::consecutive(p, paper::SEQUENCE_BEFORE_M, &paper::SEQUENCE_AFTERS_M).unwrap();
            assert_eq!(s.steps.len(), paper::SEQUENCE_AFTERS_M.len());
            assert_eq!(s.steps[0].liftoff_tick, paper::MODIFICATION_TICK);
            for (k, st) in s.steps.iter().enumerate() {
                assert_eq!(st.id, paper::SEQUENCE_FIRST_STEP + k as u16);
                assert!(st.accepted, "plain {plain}: {st:?}");
                assert!(st.landing_tick > st.liftoff_tick, "{st:?}");
                if k > 0 {
                    // The next lift-off follows the landing by the double support.
                    let prev = s.steps[k - 1];
                    assert_eq!(
                        st.liftoff_tick,
                        prev.landing_tick + u64::from(p.double_ticks),
                        "{st:?} after {prev:?}"
                    );
                }
                // Walked at the new length, from the step before.
                let w = s.walked();
                let i = usize::from(st.id);
                assert!((w[i].x - w[i - 1].x - st.after).abs() < 1e-12);
            }
            for plan in &s.plans {
                paper::check_reach(&Reach::default(), &Soles::of(&params), plan).unwrap();
            }
            let adjusted = s.steps.iter().filter(|st| st.adjust_s != 0.0).count();
            if plain {
                assert_eq!(adjusted, 0);
            } else {
                assert!(adjusted > 0, "{:?}", s.steps);
            }
            assert_eq!(
                s.trajectory.last().unwrap().phase,
                planner_core::gait::Phase::Standing
            );
        }
        // Beyond the reach limits: a step back of 0.3 m; a 0.3 m step right after a backward
        // one (growth 0.4 m).
        for afters in [&[0.0, -0.3][..], &[-0.1, 0.3]] {
            let s = paper::consecutive(params, 0.1, afters).unwrap();
            assert!(
                paper::check_reach(&Reach::default(), &Soles::of(&params), s.walked()).is_err(),
                "{afters:?}"
            );
        }
    }
}
