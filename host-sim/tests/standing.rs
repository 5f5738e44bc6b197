//! Every engine run ends standing, and a fall counts only until the settle time after the
//! reference stops (`host_sim::physics::metrics::SETTLE_AFTER_S`).
//!
//! * The trajectory each engine command hands to `physics::run` ends standing (the last
//!   reference in the phase `Standing`, both feet on the floor): `physics` (every built-in
//!   scenario), `physics-tables` (every cell of the grid, both patterns), `physics-sequence`
//!   (both patterns) and `physics-faults` (the fault-free row and the heavy rows, plain and
//!   adjusting walks, on both sweep scenarios). No engine is needed for these.
//! * In the engine: a robot that stands still on its reference and is pushed over later than
//!   the settle time after the reference stopped is reported as a fall after the end
//!   (`fell_after_end`), not as a fall; the same push within the settle time is a fall.

mod engine;

use engine::engine_here;
use host_sim::eval::faults::{self, run_walk_with, Walk, SCENARIOS};
use host_sim::eval::paper::{self, modification, plain_params, STEP_LENGTHS};
use host_sim::physics::metrics::SETTLE_AFTER_S;
use host_sim::physics::{ends_standing, run, PhysicsConfig, Push};
use host_sim::robot::Robot;
use host_sim::scenario::BUILT_IN;
use host_sim::sim::scenario_trajectory;
use planner_core::gait::{Phase, Reference};

fn assert_standing(what: &str, t: &[Reference<f64>]) {
    let last = t.last().unwrap_or_else(|| panic!("{what}: empty"));
    assert_eq!(last.phase, Phase::Standing, "{what}: {last:?}");
    assert!(last.feet.iter().all(|f| f.z == 0.0), "{what}: {last:?}");
    assert!(ends_standing(t), "{what}");
}

/// `host-sim physics NAME`: every built-in scenario, as the node publishes it.
#[test]
fn the_physics_command_hands_over_walks_that_end_standing() {
    let robot = Robot::hrp2();
    for name in BUILT_IN {
        let (_, t, _) = scenario_trajectory(name, &robot).expect("scenario");
        assert_standing(name, &t);
    }
}

/// `host-sim physics-tables`: every cell of the grid, the plain re-plan and the proposed
/// method, played to standing (the walk is not cut after the modified step); a trajectory
/// cut in the swing is not standing.
#[test]
fn the_grid_hands_over_walks_that_end_standing() {
    let params = Robot::hrp2().planner.params;
    for p in [plain_params(params), params] {
        for &after in &STEP_LENGTHS {
            for &before in &STEP_LENGTHS {
                let m = modification(p, before, after);
                assert_standing(&format!("cell {before} → {after}"), &m.trajectory);
                // In the air 400 ticks after the modified single support ends (the old cut).
                let swing = (paper::MODIFICATION_TICK as usize..m.trajectory.len())
                    .find(|&k| m.trajectory[k].feet.iter().any(|f| f.z > 0.0))
                    .expect("a swing");
                assert!(!ends_standing(&m.trajectory[..=swing]));
            }
        }
    }
}

/// `host-sim physics-sequence`: both patterns.
#[test]
fn the_sequence_hands_over_walks_that_end_standing() {
    let params = Robot::hrp2().planner.params;
    for p in [plain_params(params), params] {
        let s = paper::consecutive(p, paper::SEQUENCE_BEFORE_M, &paper::SEQUENCE_AFTERS_M)
            .expect("the sequence");
        assert_standing("sequence", &s.trajectory);
    }
}

/// `host-sim physics-faults`: the fault-free row and the heavy mixed rows on both sweep
/// scenarios, plain and adjusting (every row: `WALK_LONG=1` in `tests/physics.rs`, from
/// `physics_faults.json`'s `ended_standing`).
#[test]
fn the_fault_rows_hand_over_walks_that_end_standing() {
    let robot = Robot::hrp2();
    for walk in [Walk::Plain, Walk::Adjusting] {
        let rows = faults::rows(walk);
        let picked = rows
            .iter()
            .filter(|(k, _)| matches!(k, faults::FaultKind::None | faults::FaultKind::Mixed(_)));
        for &(kind, rate) in picked {
            for s in SCENARIOS {
                let sc = host_sim::scenario::built_in(s).expect("scenario");
                let case =
                    run_walk_with(&sc, walk, kind, rate, 1, robot.node_config(), &robot.model)
                        .expect("the case plays");
                assert_standing(
                    &format!("{} on {s} ({walk:?})", kind.name()),
                    &case.trajectory,
                );
            }
        }
    }
}

/// A standing robot pushed over by a large sideways push: after the settle time past the
/// reference's stop, the fall is reported apart (`fell_after_end`) and does not count; at the
/// same time after a reference that stops later, it counts.
#[test]
fn a_fall_after_the_settle_time_is_reported_apart() {
    if !engine_here("a_fall_after_the_settle_time_is_reported_apart") {
        return;
    }
    let robot = Robot::hrp2();
    let (_, walk, dt) = scenario_trajectory("straight", &robot).expect("scenario");
    // Standing still: the walk's last (standing) reference, held 0.5 s.
    let still = vec![*walk.last().expect("a reference"); 101];
    let push_at = SETTLE_AFTER_S + 0.3;
    let cfg = PhysicsConfig {
        settle_s: 0.2,
        tail_s: 2.5,
        push: Some(Push {
            t_s: push_at,
            duration_s: 0.1,
            force: [0.0, 900.0],
        }),
        ..PhysicsConfig::for_robot(&robot)
    };
    let r = run(&still, dt, &cfg).expect("engine run").report;
    assert_eq!(r.reference_stop_s, 0.0, "{r:?}");
    assert!(r.ended_standing, "{r:?}");
    assert!(!r.fell, "{r:?}");
    assert!(r.fall_time_s.is_none(), "{r:?}");
    assert!(r.fell_after_end, "the push fells the robot: {r:?}");
    let t = r.fall_after_end_time_s.expect("its time");
    assert!(t > push_at && t > SETTLE_AFTER_S, "{r:?}");
    assert!(r.fall_after_end_cause.is_some(), "{r:?}");
    // The same push after a reference that stops later (it changes once, by 1 µm, at 1.0 s):
    // within the settle time after that, a fall.
    let mut moving = vec![still[0]; 200];
    let mut moved = still[0];
    moved.x.cog += 1e-6;
    moving.extend(std::iter::repeat_n(moved, 200));
    let r2 = run(&moving, dt, &cfg).expect("engine run").report;
    assert!((r2.reference_stop_s - 1.0).abs() < 1e-9, "{r2:?}");
    assert!(r2.fell && !r2.fell_after_end, "{r2:?}");
    assert!(r2.fall_time_s.expect("a fall time") <= r2.reference_stop_s + SETTLE_AFTER_S);
}
