//! The general multi-body model: the numerical inverse kinematics against HRP-2's closed form,
//! and legs of other joint orders (a pitch–roll–yaw hip with tilted axes, a sole centre ahead
//! of the ankle) round-tripped through forward kinematics.

mod pose;

use host_sim::robot::model::{
    rot_rpy, rot_x, rot_y, rot_z, Body, Joint, LegAngles, Link, Model, Pose, Vec3,
};
use planner_core::gait::Side;
use pose::{pose_error, Lcg};

/// HRP-2's model, and the same with the closed form switched off (the numerical inverse
/// kinematics from the closed form's standing posture).
fn closed_and_numeric() -> (Model, Model) {
    let closed = Model::hrp2();
    let mut numeric = closed.clone();
    numeric.closed_form = None;
    let (waist, soles) = closed.stance_pose(0.2);
    numeric.stance = [
        closed.leg_ik(Side::Left, &waist, &soles[0]).unwrap(),
        closed.leg_ik(Side::Right, &waist, &soles[1]).unwrap(),
    ];
    (closed, numeric)
}

/// HRP-2's model with the closed form switched off: the numerical inverse kinematics must
/// find the closed form's angles (1e-9 rad) for random walking poses, from the standing
/// posture.
#[test]
fn numerical_ik_finds_the_closed_form() {
    let (closed, numeric) = closed_and_numeric();
    let mut rng = Lcg(7);
    let mut worst = 0.0f64;
    for _ in 0..500 {
        let waist = Pose {
            p: [
                rng.uniform(-0.1, 0.1),
                rng.uniform(-0.08, 0.08),
                closed.waist_height + rng.uniform(-0.03, 0.02),
            ],
            r: rot_z(rng.uniform(-0.3, 0.3)),
        };
        for (k, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            let y = if k == 0 { 0.1 } else { -0.1 };
            let sole = Pose {
                p: [
                    rng.uniform(-0.25, 0.25),
                    y + rng.uniform(-0.05, 0.05),
                    rng.uniform(0.0, 0.08),
                ],
                r: rot_z(rng.uniform(-0.3, 0.3)),
            };
            let Ok(want) = closed.leg_ik(side, &waist, &sole) else {
                continue;
            };
            let got = numeric
                .leg_ik(side, &waist, &sole)
                .expect("reachable: the closed form found it");
            for (a, b) in got.iter().zip(want) {
                worst = worst.max((a - b).abs());
            }
        }
    }
    assert!(worst < 1e-9, "{worst:.3e} rad");
}

/// A G1-like leg: hip pitch, roll, yaw with offsets between the axes and a tilted roll axis,
/// knee, ankle pitch and roll, the sole centre 35 mm ahead of and below the ankle.
fn g1_like() -> Model {
    let leg = |s: f64| {
        let j = |name: &str, p: Vec3, rpy: Vec3, axis: Vec3| {
            Joint::new(name, Pose { p, r: rot_rpy(rpy) }, axis)
        };
        let link = |name: &str, joint: Joint, mass: f64, com: Vec3| Link {
            name: name.into(),
            joint,
            bodies: vec![Body::cuboid(mass, com, [0.06, 0.06, 0.1])],
        };
        host_sim::robot::model::Leg {
            links: [
                link(
                    "hp",
                    j(
                        "hip_pitch",
                        [0.0, s * 0.064, -0.103],
                        [0.0; 3],
                        [0.0, 1.0, 0.0],
                    ),
                    1.4,
                    [0.0, s * 0.04, -0.02],
                ),
                link(
                    "hr",
                    j(
                        "hip_roll",
                        [0.0, s * 0.052, -0.030],
                        [0.0, -0.175, 0.0],
                        [1.0, 0.0, 0.0],
                    ),
                    1.5,
                    [0.03, 0.0, -0.05],
                ),
                link(
                    "hy",
                    j("hip_yaw", [0.025, 0.0, -0.124], [0.0; 3], [0.0, 0.0, 1.0]),
                    1.7,
                    [-0.05, 0.0, -0.09],
                ),
                link(
                    "kn",
                    j(
                        "knee",
                        [-0.078, s * 0.002, -0.177],
                        [0.0, 0.175, 0.0],
                        [0.0, 1.0, 0.0],
                    ),
                    2.0,
                    [0.0, 0.0, -0.14],
                ),
                link(
                    "ap",
                    j("ankle_pitch", [0.0, 0.0, -0.300], [0.0; 3], [0.0, 1.0, 0.0]),
                    0.07,
                    [0.0, 0.0, -0.01],
                ),
                link(
                    "ar",
                    j("ankle_roll", [0.0, 0.0, -0.018], [0.0; 3], [1.0, 0.0, 0.0]),
                    0.6,
                    [0.026, 0.0, -0.016],
                ),
            ],
            sole: Pose {
                p: [0.035, 0.0, -0.035],
                r: rot_x(0.0),
            },
        }
    };
    let mut m = Model::hrp2();
    m.legs = [leg(1.0), leg(-1.0)];
    m.closed_form = None;
    m.waist_height = 0.72;
    m.stance = [[0.0, 0.0, 0.0, 0.5, 0.0, 0.0]; 2];
    let (waist, soles) = m.stance_pose(0.2);
    for (k, side) in [Side::Left, Side::Right].into_iter().enumerate() {
        let q = m
            .numerical_ik(side, &waist, &soles[k], m.stance[k])
            .unwrap();
        m.stance[k] = q;
    }
    m
}

/// FK(IK(pose)) = pose (1e-10) for random reachable sole poses of the G1-like leg, and the
/// knee stays bent forward (the branch of the standing posture).
#[test]
fn a_pitch_roll_yaw_hip_round_trips() {
    let m = g1_like();
    assert!(m.stance[0][3] > 0.1, "{:?}", m.stance[0]);
    let mut rng = Lcg(11);
    let mut solved = 0;
    for _ in 0..400 {
        let waist = Pose {
            p: [rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), 0.72],
            r: rot_z(rng.uniform(-0.2, 0.2)),
        };
        let q: LegAngles = [
            rng.uniform(-0.6, 0.3),
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
            rng.uniform(0.3, 1.2),
            rng.uniform(-0.5, 0.2),
            rng.uniform(-0.15, 0.15),
        ];
        for side in [Side::Left, Side::Right] {
            let target = m.leg_fk(side, &waist, &q).sole;
            let got = m
                .leg_ik(side, &waist, &target)
                .expect("an FK pose is reachable");
            let back = m.leg_fk(side, &waist, &got).sole;
            assert!(pose_error(&back, &target) < 1e-10, "{q:?} → {got:?}");
            assert!(got[3] > 0.0, "knee backwards: {got:?}");
            solved += 1;
        }
    }
    assert_eq!(solved, 800);
    // Out of reach: 1 m below the hip.
    let waist = Pose {
        p: [0.0, 0.0, 0.72],
        r: rot_y(0.0),
    };
    let far = Pose {
        p: [0.0, 0.1, -0.5],
        r: rot_z(0.0),
    };
    let e = m.leg_ik(Side::Left, &waist, &far).unwrap_err();
    assert!(e.distance > e.reach, "{e:?}");
}

/// Near the knee's singularity: with the leg almost straight (the ankle up to 0.05 % short of
/// the leg's full reach, as a capture step's long stride asks), the numerical inverse
/// kinematics still finds the closed form's angles wherever the closed form has them.
#[test]
fn numerical_ik_converges_with_the_leg_almost_straight() {
    let (closed, numeric) = closed_and_numeric();
    let (waist, soles) = closed.stance_pose(0.2);
    let mut tried = 0;
    for &forward in &[0.0, 0.1, 0.2, 0.3, -0.2] {
        for &short in &[1e-2, 3e-3, 1e-3, 5e-4, 2e-4, 1e-4, 3e-5] {
            // The waist lowered until the sole, `forward` ahead, is `short` of full reach.
            let side = Side::Left;
            let mut lo = closed.waist_height - 0.3;
            let mut hi = closed.waist_height + 0.3;
            let sole = Pose {
                p: [forward, soles[0].p[1], 0.0],
                r: soles[0].r,
            };
            let at = |h: f64| Pose {
                p: [waist.p[0], waist.p[1], h],
                r: waist.r,
            };
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                // The highest waist from which the closed form reaches the sole.
                if closed.leg_ik(side, &at(mid), &sole).is_ok() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let reach = closed.reach(side);
            // Lower the waist until the ankle is `short · reach` nearer than full reach.
            let mut h = lo;
            for _ in 0..80 {
                let e = match closed.leg_ik(side, &at(h), &sole) {
                    Ok(q) => {
                        let ankle = closed.leg_fk(side, &at(h), &q);
                        let hip = ankle.links[0].p;
                        let d = ((ankle.links[5].p[0] - hip[0]).powi(2)
                            + (ankle.links[5].p[1] - hip[1]).powi(2)
                            + (ankle.links[5].p[2] - hip[2]).powi(2))
                        .sqrt();
                        reach - d
                    }
                    Err(_) => 0.0,
                };
                if e >= short * reach {
                    break;
                }
                h -= 0.25 * short * reach;
            }
            let Ok(want) = closed.leg_ik(side, &at(h), &sole) else {
                continue;
            };
            tried += 1;
            let got = numeric
                .leg_ik(side, &at(h), &sole)
                .unwrap_or_else(|e| panic!("forward {forward}, {short} short of reach: {e}"));
            for (a, b) in got.iter().zip(want) {
                assert!(
                    (a - b).abs() < 1e-7,
                    "forward {forward}, short {short}: {got:?} vs {want:?}"
                );
            }
        }
    }
    assert!(tried >= 15, "{tried} poses tried");
}
