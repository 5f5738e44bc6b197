//! An imported robot's reach limits against its legs: every step the node's limits admit
//! (a 1 cm grid over forward and width, with no turn and with the largest turn either way, and
//! the exact corners of the region) is reached by the leg's inverse kinematics with the
//! import's stated margin (`host_sim::robot::import::reach`): the feet 1 cm farther apart and
//! the waist anywhere from 30 % to 70 % of the way between them.
//!
//! Admission is the node's own check ([`Reach::broken`]), with a step before this one that the
//! stride and growth limits let through, so the grid is the region the limits draw, not the
//! import's list of corners. The default run checks G1 (whose offset hip axes reach less far
//! than the sum of its joint distances), iCub and Talos; `WALK_LONG=1` every biped of
//! example-robot-data the import accepts.

mod urdf;

use host_sim::robot::import::import;
use host_sim::robot::import::reach::{corners, feet, Corner, STRETCH_M, WAIST_SPREAD};
use host_sim::robot::model::Pose;
use host_sim::robot::Robot;
use planner_core::gait::{Footstep, Side};
use planner_core::node::{Reach, Soles};

/// The bipeds of example-robot-data 6.0.0 that the import accepts (`tests/bipeds.rs`).
const ACCEPTED: &[&str] = &[
    "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf",
    "g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
    "icub_description/robots/icub.urdf",
    "icub_description/robots/icub_reduced.urdf",
    "romeo_description/urdf/romeo.urdf",
    "romeo_description/urdf/romeo_small.urdf",
    "talos_data/robots/talos_full_v2.urdf",
    "talos_data/robots/talos_full_v2_box.urdf",
    "talos_data/robots/talos_reduced.urdf",
    "talos_data/robots/talos_reduced_box.urdf",
    "talos_data/robots/talos_reduced_corrected.urdf",
];

/// The default run's subset.
const QUICK: &[&str] = &[
    "g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "icub_description/robots/icub.urdf",
    "talos_data/robots/talos_reduced.urdf",
];

fn long() -> bool {
    std::env::var("WALK_LONG").as_deref() == Ok("1")
}

/// Whether the node admits a left step `c` from the right foot at the origin, after a step
/// before it that leaves the stride and growth limits as loose as they can be.
fn admitted(r: &Reach, soles: &Soles, c: &Corner) -> bool {
    let f = c.forward;
    // The left foot was `s` ahead of the right one: the stride is |f − s|, the growth f + s.
    let s = f.min(r.max_growth - f);
    let other = Footstep {
        side: Side::Right,
        x: 0.0,
        y: 0.0,
        yaw: 0.0,
    };
    let same = Footstep {
        side: Side::Left,
        x: s,
        y: 0.5 * (r.min_width + r.max_width),
        yaw: 0.0,
    };
    let step = Footstep {
        side: Side::Left,
        x: c.forward,
        y: c.width,
        yaw: c.yaw,
    };
    r.broken(&other, &same, &step, false, soles).is_none()
}

/// The admitted steps of the grid and the corners.
fn admitted_steps(r: &Reach, soles: &Soles) -> Vec<Corner> {
    let mut steps = corners(r);
    for yaw in [0.0, r.max_yaw, -r.max_yaw] {
        let mut f = -r.max_backward - 0.02;
        while f <= r.max_forward + 0.02 {
            let mut w = r.min_width - 0.02;
            while w <= r.max_width + 0.02 {
                steps.push(Corner {
                    forward: f,
                    width: w,
                    yaw,
                });
                w += 0.01;
            }
            f += 0.01;
        }
    }
    steps.retain(|c| admitted(r, soles, c));
    steps
}

/// The admitted steps whose IK fails with the margin, described.
fn unreached(r: &Robot) -> (usize, Vec<String>) {
    let m = &r.model;
    let soles = Soles::of(&r.planner.params);
    let steps = admitted_steps(&r.planner.reach, &soles);
    let mut out = Vec::new();
    for c in &steps {
        for side in [Side::Left, Side::Right] {
            let f = feet(c, side, STRETCH_M);
            let (a, b) = (f[0].p, f[1].p);
            for t in [0.5 - WAIST_SPREAD, 0.5, 0.5 + WAIST_SPREAD] {
                let waist = Pose::upright(
                    a[0] + t * (b[0] - a[0]),
                    a[1] + t * (b[1] - a[1]),
                    m.waist_height,
                    0.5 * c.yaw,
                );
                if let Err(e) = m.cog(&waist, &f) {
                    out.push(format!("{side:?} step {c:?}, waist at {t:.2}: {e}"));
                }
            }
        }
    }
    (steps.len(), out)
}

#[test]
fn every_admitted_step_of_an_imported_robot_is_reached_by_its_legs() {
    let test = "every_admitted_step_of_an_imported_robot_is_reached_by_its_legs";
    let mut failed = Vec::new();
    for tail in ACCEPTED {
        if !long() && !QUICK.contains(tail) {
            continue;
        }
        let Some(path) = urdf::robot_file(tail, test) else {
            return;
        };
        let robot = import(&path, None)
            .unwrap_or_else(|e| panic!("{tail}: {e}"))
            .robot;
        let (n, bad) = unreached(&robot);
        // The grid covers the region: thousands of steps, not a handful of corners.
        assert!(n > 500, "{tail}: {n} admitted steps");
        println!(
            "{tail}: max_forward {} m, {n} admitted steps, {} not reached",
            robot.planner.reach.max_forward,
            bad.len()
        );
        failed.extend(bad.into_iter().take(3).map(|b| format!("{tail}: {b}")));
    }
    assert!(failed.is_empty(), "not reached:\n{}", failed.join("\n"));
}

/// The test's check is not empty: G1's limits before the import checked them (a 0.336 m
/// forward step, 0.412 m between the feet, HRP-2's scaled by 1.12) admit steps its legs do not
/// reach with the margin.
#[test]
fn g1s_former_limits_are_not_reached() {
    let test = "g1s_former_limits_are_not_reached";
    let Some(path) = urdf::robot_file(urdf::G1, test) else {
        return;
    };
    let mut robot = import(&path, None).expect("G1 imports").robot;
    robot.planner.reach = Reach {
        max_forward: 0.336,
        max_backward: 0.224,
        min_width: 0.181,
        max_width: 0.327,
        max_feet_distance: 0.412,
        yaw_cost: 0.336,
        max_stride: 0.495,
        max_growth: 0.246,
        ..robot.planner.reach
    };
    let (_, bad) = unreached(&robot);
    assert!(!bad.is_empty(), "G1's former limits reached everywhere");
    println!("G1's former limits: {} not reached, {}", bad.len(), bad[0]);
}

/// The engine's waist search where G1's rear leg is at the end of its reach (a tick of a
/// capture step after a push, taken from a run that stopped there): the leg's inverse
/// kinematics saturates, the COG Jacobian is rough, and a whole Newton step threw the waist
/// half a metre behind the feet, where the next tick's inverse kinematics failed. Each step is
/// now taken only as far as it brings the COG nearer its target.
#[test]
fn g1s_waist_search_stays_with_a_leg_at_the_end_of_its_reach() {
    let test = "g1s_waist_search_stays_with_a_leg_at_the_end_of_its_reach";
    let Some(path) = urdf::robot_file(urdf::G1, test) else {
        return;
    };
    let robot = import(&path, None).expect("G1 imports").robot;
    let engine = host_sim::physics::model::Robot::of(&robot);
    let soles = [
        Pose::upright(0.7635, 0.0295, -2.327e-5, 0.0),
        Pose::upright(0.428_574_218_5, -0.208_255_078_2, 0.001_383_296_9, 0.0),
    ];
    let target = [0.669_444_326_8, -0.013_307_712_3];
    let start = Pose::upright(
        0.699_370_969_7,
        -0.000_859_783_3,
        engine.waist_height(),
        0.0,
    );
    let cog_error = |w: &Pose| {
        let q = [
            engine.leg_ik(Side::Left, w, &soles[0]).expect("left"),
            engine.leg_ik(Side::Right, w, &soles[1]).expect("right"),
        ];
        let c = engine.fk(w, &q).2;
        (target[0] - c[0]).hypot(target[1] - c[1])
    };
    let before = cog_error(&start);
    let (w, _) = engine
        .solve_waist(start, &soles, target)
        .expect("the waist search ends");
    let after = cog_error(&w);
    assert!(after <= before, "COG error {before} → {after} m");
    // The waist stays over the feet (between the rear sole and the front one, along x).
    assert!(
        (soles[1].p[0]..=soles[0].p[0]).contains(&w.p[0]),
        "waist at {:?}",
        w.p
    );
    println!(
        "COG error {before:.4} → {after:.4} m, waist at x {:.4}",
        w.p[0]
    );
}
