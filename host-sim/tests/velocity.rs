//! Velocity and goal walking through the bus: the built-in `velocity` scenario's commands are
//! all taken and the walked velocity settles on each commanded one; a scenario file's
//! `[[velocity]]` and `[[goal]]` entries; a goal walked within the node's tolerance; the
//! velocity figures `host-sim run velocity` writes.

use host_sim::output::velocity::{velocity_series, VelocitySample};
use host_sim::scenario::{self, file, Command};
use host_sim::sim::{outcomes, simulate, SimConfig};
use planner_core::gait::GaitParams;
use planner_core::node::{GOAL_TOLERANCE, GOAL_YAW_TOLERANCE};

fn cycle_ticks() -> usize {
    let p = GaitParams::<f64>::hrp2();
    (p.single_ticks + p.double_ticks) as usize
}

/// The sample at time `t` \[s\].
fn at(samples: &[VelocitySample], t: f64) -> VelocitySample {
    *samples
        .iter()
        .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
        .unwrap()
}

#[test]
fn the_velocity_scenario_walks_each_commanded_velocity() {
    let s = scenario::built_in("velocity").expect("built in");
    let sim = simulate(&s, &SimConfig::default()).unwrap();
    assert!(!sim.cut, "the walk did not end standing");
    for o in outcomes(&s, &sim) {
        assert_eq!(o.failure, None, "{o:?}");
    }
    // Every velocity of the stream taken (the stream's frames and the timeline's).
    let refused: Vec<_> = sim
        .acks
        .iter()
        .filter(|(_, a)| a.command == 0x2F && a.reason.is_some())
        .collect();
    assert!(refused.is_empty(), "{refused:?}");
    let samples = velocity_series(&sim.run, 0.005, cycle_ticks());
    // Just before each change the walked velocity is the commanded one (the turns: vx and ω;
    // the forward speed on a curve is measured along the mean heading).
    let changes: Vec<(f64, [f64; 3])> = s
        .timeline
        .iter()
        .filter_map(|&(k, c)| match c {
            Command::Velocity(vx, vy, wz) => Some((k as f64 * 0.005, [vx, vy, wz])),
            _ => None,
        })
        .collect();
    for w in changes.windows(2) {
        let (_, v) = w[0];
        let (t_next, _) = w[1];
        let got = at(&samples, t_next - 0.01);
        assert_eq!(got.commanded, v);
        let tol = [0.015, 0.005, 0.005];
        for i in 0..3 {
            assert!(
                (got.walked[i] - v[i]).abs() <= tol[i],
                "{v:?} until {t_next} s: walked {:?}",
                got.walked
            );
        }
    }
    // After the zero velocity the robot stands: the last samples walk nothing.
    let last = samples.last().unwrap();
    assert!(last.walked.iter().all(|v| v.abs() < 0.05), "{last:?}");
}

#[test]
fn a_scenario_file_gives_velocities_and_goals_over_time() {
    let text = r#"
        name = "stick"
        [[velocity]]
        at_s = 0.1
        vx = 0.1
        [[velocity]]
        at_s = 4.0
        vy = -0.03
        wz = 0.1
        [[goal]]
        at_s = 8.0
        x = 0.3
        y = 0.1
        yaw = -0.2
        [[step]]
        id = 0
        side = "right"
        x = 0.1
        y = -0.1
        at_s = 9.0
        expect = "wrong_state"
    "#;
    let f = file::parse_file(text).unwrap();
    let kinds: Vec<_> = f.scenario.timeline.iter().map(|(k, c)| (*k, *c)).collect();
    assert_eq!(
        kinds,
        vec![
            (20, Command::Velocity(0.1, 0.0, 0.0)),
            (800, Command::Velocity(0.0, -0.03, 0.1)),
            (1600, Command::Goal(0.3, 0.1, -0.2)),
            (
                1800,
                Command::Push(
                    0,
                    planner_core::gait::Footstep::new(
                        planner_core::gait::Side::Right,
                        0.1,
                        -0.1,
                        0.0
                    )
                )
            ),
        ]
    );
    assert!(f.entries[0].label.contains("[[velocity]] #1"));
    assert!(f.entries[2].label.contains("[[goal]] #1"));
    // Values that are not numbers and unknown keys are refused, naming the entry.
    for bad in [
        "name = \"x\"\n[[velocity]]\nat_s = 0.0\nvx = nan\n",
        "name = \"x\"\n[[goal]]\nat_s = 0.0\nx = 1.0\nspeed = 2.0\n",
        "name = \"x\"\n[[goal]]\nat_s = 0.0\n",
    ] {
        assert!(file::parse_file(bad).is_err(), "{bad}");
    }
    // Played through the bus: the footstep while the node walks the goal is refused as the
    // file expects, and the goal is reached.
    let sim = simulate(&f.scenario, &SimConfig::default()).unwrap();
    let o = outcomes(&f.scenario, &sim);
    assert_eq!(o.iter().filter(|o| o.failure.is_some()).count(), 1, "{o:?}");
    assert_eq!(o[3].failure, f.entries[3].expect);
}

#[test]
fn a_goal_is_reached_within_the_nodes_tolerance() {
    for (x, y, yaw) in [(1.2, 0.0, 0.0), (0.6, -0.3, 0.8), (-0.3, 0.2, -1.5)] {
        let s = scenario::Scenario {
            name: "goal".into(),
            about: String::new(),
            feet: None,
            timeline: vec![(20, Command::Goal(x, y, yaw))],
            max_ticks: 8000,
        };
        let sim = simulate(&s, &SimConfig::default()).unwrap();
        assert!(!sim.cut, "goal {x} {y} {yaw} not reached in 40 s");
        let last = sim.run.trajectory.last().unwrap();
        let (l, r) = (&last.feet[0], &last.feet[1]);
        let (mx, my) = (0.5 * (l.x + r.x), 0.5 * (l.y + r.y));
        let h = (l.yaw.sin() + r.yaw.sin()).atan2(l.yaw.cos() + r.yaw.cos());
        // The goal as the wire carries it: 1 cm, 2π/1024 rad.
        let tol = GOAL_TOLERANCE * 2f64.sqrt() + 0.005 + 1e-3;
        assert!((mx - x).hypot(my - y) <= tol, "goal {x} {y}: at {mx} {my}");
        assert!(
            (h - yaw).abs() <= GOAL_YAW_TOLERANCE + 0.004,
            "goal {yaw}: heading {h}"
        );
    }
}

#[allow(dead_code)] // (the map's helper is the push map's)
mod engine;

/// In MuJoCo under the stabilizer, the built-in `velocity` scenario (forward, a step change to
/// sideways, a turn and its reversal, zero) walks without a fall, by the engine's verdict, on
/// HRP-2 and on the test robot `host-sim/tests/robots/small.toml` (the scenario drawn in its
/// proportions): `host-sim physics velocity [--robot FILE]` prints the same runs.
#[test]
fn the_velocity_scenario_walks_in_mujoco_without_a_fall() {
    use host_sim::physics::{run, PhysicsConfig};
    use host_sim::robot::Robot;
    use host_sim::sim::scenario_trajectory;
    if !engine::engine_here("velocity") {
        return;
    }
    let small = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots/small.toml");
    for robot in [Robot::hrp2(), Robot::load(&small).expect("the test robot")] {
        let (_, trajectory, dt) = scenario_trajectory("velocity", &robot).expect("scenario");
        let cfg = PhysicsConfig::for_robot(&robot);
        let r = run(&trajectory, dt, &cfg).expect("engine run").report;
        let name = robot.name();
        assert!(!r.fell, "{name}: fell at {:?} s", r.fall_time_s);
        assert!(
            r.walked(),
            "{name}: a gait measure beyond its bound: {:?}",
            r.gait
        );
        assert!(r.max_tilt_deg < 2.0, "{name}: tilt {} deg", r.max_tilt_deg);
    }
}
