//! Tests of the HRP-2 multi-body model (`host_sim::eval::multibody`): kinematics, the ZMP formula on
//! cases with a known answer, and the multi-body ZMP error of real walks (printed: run with
//! `--nocapture` to see the figures).

mod pose;

use host_sim::eval::multibody::{evaluate, max_zmp_error, MbError, MbSample};
use host_sim::robot::model::{
    mean_yaw, rot_x, rot_y, rot_z, Body, ClosedForm, IkError, LegAngles, Model, Pose,
};
use host_sim::scenario;
use planner_core::gait::{FootPose, GaitParams, Phase, Reference, Side};
use planner_core::Sample;
use pose::{pose_error, Lcg};

const DT: f64 = 0.005;

/// Replaces the bodies of HRP-2's link table: the trunk and the waist, and per leg the hip
/// housing, thigh, shank and foot (given for the left leg; the right one mirrors them).
fn set_bodies(m: &mut Model, trunk: Body, waist: Body, leg: [Body; 4]) {
    m.root[0].body = trunk;
    m.root[1].body = waist;
    for (k, l) in m.legs.iter_mut().enumerate() {
        for (i, b) in [1, 2, 3, 5].into_iter().zip(leg) {
            l.links[i].bodies = vec![if k == 0 { b } else { b.mirrored() }];
        }
    }
}

/// HRP-2's leg shape.
fn shape(m: &Model) -> ClosedForm {
    m.closed_form.expect("HRP-2's leg shape")
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn random_pose(rng: &mut Lcg, p: [f64; 3], tilt: f64, yaw: f64) -> Pose {
    let r = mat_mul(
        &mat_mul(&rot_z(yaw), &rot_y(rng.uniform(-tilt, tilt))),
        &rot_x(rng.uniform(-tilt, tilt)),
    );
    Pose { p, r }
}

/// FK(IK(pose)) = pose to 1e-9 (position in m, rotation-matrix entries) for random waist and
/// sole poses, both legs; and IK(FK(q)) = q to 1e-9 rad for random joint angles in the branch
/// the IK returns (knee > 0, |hip roll| < π/2).
#[test]
fn ik_fk_round_trip() {
    let m = Model::hrp2();
    let mut rng = Lcg(7);
    let mut worst_pose = 0.0f64;
    let mut solved = 0;
    for _ in 0..2000 {
        let wyaw = rng.uniform(-3.1, 3.1);
        let wp = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), 0.65];
        let waist = random_pose(&mut rng, wp, 0.2, wyaw);
        for side in [Side::Left, Side::Right] {
            let s = if side == Side::Left { 1.0 } else { -1.0 };
            let local = [
                rng.uniform(-0.3, 0.3),
                s * 0.1 + rng.uniform(-0.1, 0.1),
                rng.uniform(-0.62, -0.45),
            ];
            let p = waist.apply(local);
            let syaw = wyaw + rng.uniform(-0.5, 0.5);
            let sole = random_pose(&mut rng, p, 0.2, syaw);
            match m.leg_ik(side, &waist, &sole) {
                Ok(q) => {
                    let f = m.leg_fk(side, &waist, &q);
                    worst_pose = worst_pose.max(pose_error(&f.sole, &sole));
                    solved += 1;
                }
                Err(e) => assert!(e.distance > e.reach, "{e}"),
            }
        }
    }
    println!("IK/FK: {solved} of 4000 random poses in reach, max |FK(IK(pose)) - pose| = {worst_pose:.2e}");
    assert!(solved > 2000, "too few poses in reach: {solved}");
    assert!(worst_pose < 1e-9, "FK(IK(pose)) error {worst_pose:.3e}");

    let mut worst_q = 0.0f64;
    let mut checked = 0;
    for _ in 0..2000 {
        let wyaw = rng.uniform(-3.1, 3.1);
        let waist = random_pose(&mut rng, [0.1, -0.2, 0.7], 0.3, wyaw);
        let q: LegAngles = [
            rng.uniform(-0.8, 0.8),
            rng.uniform(-0.5, 0.5),
            rng.uniform(-1.2, 0.6),
            rng.uniform(0.05, 2.4),
            rng.uniform(-1.2, 0.7),
            rng.uniform(-0.5, 0.5),
        ];
        // The IK's branch: the hip above the ankle in the foot frame.
        if shape(&m).thigh * (q[3] + q[4]).cos() + shape(&m).shank * q[4].cos() <= 0.01 {
            continue;
        }
        for side in [Side::Left, Side::Right] {
            let f = m.leg_fk(side, &waist, &q);
            let back = m
                .leg_ik(side, &waist, &f.sole)
                .expect("FK pose is in reach");
            for i in 0..6 {
                worst_q = worst_q.max((back[i] - q[i]).abs());
            }
            checked += 1;
        }
    }
    println!("IK/FK: max |IK(FK(q)) - q| = {worst_q:.2e} rad over {checked} legs");
    assert!(checked > 2000);
    assert!(worst_q < 1e-9, "IK(FK(q)) error {worst_q:.3e}");
}

#[test]
fn ik_reports_out_of_reach() {
    let m = Model::hrp2();
    let waist = Pose::upright(0.0, 0.0, m.waist_height, 0.0);
    let far = Pose::upright(0.5, 0.1, 0.0, 0.0);
    let e: IkError = m.leg_ik(Side::Left, &waist, &far).unwrap_err();
    assert_eq!(e.side, Side::Left);
    assert!((e.reach - 0.6).abs() < 1e-15);
    // Hip (0, 0.06, 0.6523), ankle (0.5, 0.1, 0.105).
    let d = (0.5f64 * 0.5 + 0.04 * 0.04 + (m.waist_height - 0.105).powi(2)).sqrt();
    assert!((e.distance - d).abs() < 1e-12);
    // The same through evaluate: a standing trajectory with the left foot far ahead.
    let mut r = reference(0.0, 0.0, [foot(0.5, 0.1, 0.0), foot(0.0, -0.1, 0.0)]);
    r.x.cog = 0.25;
    let traj = vec![r; 5];
    assert!(matches!(
        evaluate(&m, &traj, DT),
        Err(MbError::OutOfReach(
            0,
            IkError {
                side: Side::Left,
                ..
            }
        ))
    ));
    assert_eq!(evaluate(&m, &traj[..2], DT), Err(MbError::TooShort(2)));
}

/// The model's stance: mass 58 kg, COG 0.814 m high (to 1 mm, the waist height being rounded
/// to 0.1 mm), knees bent.
#[test]
fn stance_matches_hrp2() {
    let m = Model::hrp2();
    assert!((m.total_mass() - 58.0).abs() < 1e-12);
    let z = m.stance_cog_height(0.2).unwrap();
    println!(
        "stance COG height {z:.5} m at waist height {} m",
        m.waist_height
    );
    assert!((z - 0.814).abs() < 1e-3, "stance COG height {z}");
    let waist = Pose::upright(0.0, 0.0, m.waist_height, 0.0);
    let q = m
        .leg_ik(Side::Left, &waist, &Pose::upright(0.0, 0.1, 0.0, 0.0))
        .unwrap();
    println!(
        "stance left leg [deg]: {:?}",
        q.map(|a| (a.to_degrees() * 10.0).round() / 10.0)
    );
    assert!(q[3] > 0.5 && q[3] < 1.0, "knee {}", q[3]);
}

fn foot(x: f64, y: f64, yaw: f64) -> FootPose<f64> {
    FootPose { x, y, z: 0.0, yaw }
}

fn sample(cog: f64, cog_acc: f64, zmp: f64) -> Sample<f64> {
    Sample {
        cog,
        cog_vel: 0.0,
        cog_acc,
        zmp,
        zmp_vel: 0.0,
    }
}

fn reference(x: f64, y: f64, feet: [FootPose<f64>; 2]) -> Reference<f64> {
    Reference {
        x: sample(x, 0.0, x),
        y: sample(y, 0.0, y),
        phase: Phase::Standing,
        feet,
    }
}

/// Standing still, feet turned and staggered, COG off-centre: no acceleration anywhere, so
/// the multi-body ZMP is the ground projection of the COG, which is the reference COG
/// (to 1e-9 m), at every tick including the first and last.
#[test]
fn static_stance_zmp_is_cog_projection() {
    let m = Model::hrp2();
    let feet = [foot(0.05, 0.12, 0.1), foot(-0.04, -0.09, -0.05)];
    let traj = vec![reference(0.012, 0.017, feet); 20];
    let mb = evaluate(&m, &traj, DT).unwrap();
    assert_eq!(mb.len(), 20);
    let mut worst = 0.0f64;
    for s in &mb {
        worst = worst
            .max((s.mb_zmp_x - 0.012).abs())
            .max((s.mb_zmp_y - 0.017).abs())
            .max((s.mb_cog[0] - 0.012).abs())
            .max((s.mb_cog[1] - 0.017).abs());
        assert!((s.waist_yaw - 0.025).abs() < 1e-15);
    }
    println!("static stance: max |ZMP - COG projection| = {worst:.2e} m");
    assert!(worst < 1e-9, "{worst:.3e}");
    // The waist is not at the COG (the feet are staggered and turned), so the solve did work.
    assert!((mb[0].waist[0] - 0.012).abs() > 1e-4 || (mb[0].waist[1] - 0.017).abs() > 1e-4);
}

/// Massless legs and waist, the trunk a point mass at z = 0.814 m: the model is the linear
/// inverted pendulum, and the multi-body ZMP of a waist swaying sinusoidally in x (1 Hz,
/// 3 cm) and y (0.8 Hz, 5 cm) must be `x − z ẍ / g`.
///
/// * Against the analytic `ẍ = −A Ω² sin Ωt`: within the finite-difference truncation error
///   `z/g · A Ω⁴ dt² / 12` (8.1e-6 m in x, 5.3e-6 m in y): tolerance 1e-5 m.
/// * Against the exact second difference of the sinusoid,
///   `ẍ_fd = x · (2 cos Ωdt − 2) / dt²`: tolerance 1e-10 m (only rounding remains).
#[test]
fn massless_legs_give_the_lipm_zmp() {
    let mut m = Model::hrp2();
    let z = 0.814;
    let trunk = Body::point(30.0, [0.0, 0.0, z - m.waist_height]);
    set_bodies(&mut m, trunk, Body::NONE, [Body::NONE; 4]);
    let g = m.gravity;
    let (ax, wx) = (0.03, 2.0 * std::f64::consts::PI * 1.0);
    let (ay, wy, phy) = (0.05, 2.0 * std::f64::consts::PI * 0.8, 0.4);
    let feet = [foot(0.0, 0.1, 0.0), foot(0.0, -0.1, 0.0)];
    let n = 401;
    let traj: Vec<Reference<f64>> = (0..n)
        .map(|k| {
            let t = k as f64 * DT;
            let x = ax * (wx * t).sin();
            let y = ay * (wy * t + phy).sin();
            Reference {
                x: sample(x, -wx * wx * x, x + z * wx * wx * x / g),
                y: sample(y, -wy * wy * y, y + z * wy * wy * y / g),
                phase: Phase::Standing,
                feet,
            }
        })
        .collect();
    let mb: Vec<MbSample> = evaluate(&m, &traj, DT).unwrap();
    let fd = |w: f64| (2.0 * (w * DT).cos() - 2.0) / (DT * DT);
    let (mut e_analytic, mut e_fd, mut e_inner) = (0.0f64, 0.0f64, 0.0f64);
    for k in 1..n - 1 {
        let (x, y) = (traj[k].x.cog, traj[k].y.cog);
        assert!((mb[k].mb_cog[2] - z).abs() < 1e-12);
        e_analytic = e_analytic
            .max((mb[k].mb_zmp_x - traj[k].x.zmp).abs())
            .max((mb[k].mb_zmp_y - traj[k].y.zmp).abs());
        if (2..n - 2).contains(&k) {
            e_inner =
                e_inner.max((mb[k].mb_zmp_x - traj[k].x.zmp).hypot(mb[k].mb_zmp_y - traj[k].y.zmp));
        }
        e_fd = e_fd
            .max((mb[k].mb_zmp_x - (x - z * fd(wx) * x / g)).abs())
            .max((mb[k].mb_zmp_y - (y - z * fd(wy) * y / g)).abs());
    }
    let bound = z / g * (ax * wx.powi(4)).max(ay * wy.powi(4)) * DT * DT / 12.0;
    println!(
        "LIPM check: max |mb ZMP - (x - z xdd/g)| = {e_analytic:.2e} m (truncation bound {bound:.2e} m); \
         against the exact second difference {e_fd:.2e} m"
    );
    assert!(e_analytic < 1e-5, "{e_analytic:.3e}");
    assert!(
        e_analytic > 1e-7,
        "finite-difference error unexpectedly absent"
    );
    assert!(e_fd < 1e-10, "{e_fd:.3e}");
    // max_zmp_error agrees (it skips two ticks at each end).
    assert_eq!(max_zmp_error(&traj, &mb), e_inner);
}

/// A trunk with inertia (a box) yawing with the feet: its `L̇` is along z only, so the ZMP
/// must stay at the COG projection (1e-9 m). Catches an `L̇` component taken from the wrong
/// axis or a wrong world inertia.
#[test]
fn yawing_trunk_does_not_move_the_zmp() {
    let mut m = Model::hrp2();
    let trunk = Body::cuboid(30.0, [0.0, 0.0, 0.8 - m.waist_height], [0.3, 0.5, 0.6]);
    set_bodies(&mut m, trunk, Body::NONE, [Body::NONE; 4]);
    let traj: Vec<Reference<f64>> = (0..200)
        .map(|k| {
            let yaw = 0.3 * (k as f64 * DT * 3.0).sin();
            reference(0.0, 0.0, [foot(0.0, 0.1, yaw), foot(0.0, -0.1, yaw)])
        })
        .collect();
    let mb = evaluate(&m, &traj, DT).unwrap();
    assert!((mean_yaw(&traj[50].feet) - mb[50].waist_yaw).abs() < 1e-15);
    let worst = mb
        .iter()
        .map(|s| s.mb_zmp_x.hypot(s.mb_zmp_y))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "{worst:.3e}");
}

/// The angular-momentum terms, sign included: only the thighs have mass, their centres of
/// mass at the hip joints (so the COG never moves) and an isotropic inertia `I`; the left leg
/// swings rigidly (knee fixed) about the hip pitch axis, `θ(t) = 0.3 sin 2πt`, then about the
/// hip roll axis, `φ(t)` likewise, the foot kept flat. The thigh's angular velocity is then
/// exactly `θ̇ e_y` (`φ̇ e_x`), and `p_x = −I θ̈ / (M g)`, `p_y = +I φ̈ / (M g)`
/// (M = both thighs). With `θ̈` the exact second difference of the sinusoid, tolerance 1e-9 m
/// (the signal is 0.1 m; the opposite sign would be off by 0.2 m).
#[test]
fn swinging_thigh_angular_momentum() {
    let mut m = Model::hrp2();
    let inertia = 0.5;
    let thigh = Body::principal(4.0, [0.0; 3], [inertia; 3]);
    set_bodies(
        &mut m,
        Body::NONE,
        Body::NONE,
        [Body::NONE, thigh, Body::NONE, Body::NONE],
    );
    let c = shape(&m);
    let total = 8.0;
    let g = m.gravity;
    let depth = m.waist_height - c.ankle_height - 0.02; // hip to ankle, knee bent
    let (amp, w) = (0.3, 2.0 * std::f64::consts::PI);
    let n = 201;
    let fd = (2.0 * (w * DT).cos() - 2.0) / (DT * DT);
    for pitch in [true, false] {
        let traj: Vec<Reference<f64>> = (0..n)
            .map(|k| {
                let a = amp * (w * k as f64 * DT).sin();
                let ankle = if pitch {
                    [
                        -depth * a.sin(),
                        c.hip_offset,
                        m.waist_height - depth * a.cos(),
                    ]
                } else {
                    [
                        0.0,
                        c.hip_offset + depth * a.sin(),
                        m.waist_height - depth * a.cos(),
                    ]
                };
                let left = FootPose {
                    x: ankle[0],
                    y: ankle[1],
                    z: ankle[2] - c.ankle_height,
                    yaw: 0.0,
                };
                reference(0.0, 0.0, [left, foot(0.0, -c.hip_offset, 0.0)])
            })
            .collect();
        let mb = evaluate(&m, &traj, DT).unwrap();
        let mut worst = 0.0f64;
        for k in 1..n - 1 {
            let a = amp * (w * k as f64 * DT).sin();
            let l_dot = inertia * fd * a;
            let (ex, ey) = if pitch {
                (-l_dot / (total * g), 0.0)
            } else {
                (0.0, l_dot / (total * g))
            };
            worst = worst
                .max((mb[k].mb_zmp_x - ex).abs())
                .max((mb[k].mb_zmp_y - ey).abs());
            // The leg does swing about the axis meant: hip pitch (roll) follows the angle.
            let j = if pitch { 2 } else { 1 };
            assert!((mb[k].q[0][j] - mb[0].q[0][j] - a).abs() < 1e-9);
        }
        let peak = inertia * amp * w * w / (total * g);
        println!(
            "swinging thigh ({}): peak ZMP {:.1} mm, max error {worst:.2e} m",
            if pitch { "pitch" } else { "roll" },
            peak * 1e3
        );
        assert!(worst < 1e-9, "{worst:.3e}");
    }
}

/// Ticks at which a foot pose jumps away and back (more than 1 cm from both neighbours, which
/// agree to 1 mm): `(tick, foot index)`.
fn one_tick_foot_jumps(traj: &[Reference<f64>]) -> Vec<(usize, usize)> {
    let d = |a: &FootPose<f64>, b: &FootPose<f64>| {
        (a.x - b.x).hypot(a.y - b.y).hypot(a.z - b.z) + (a.yaw - b.yaw).abs()
    };
    let mut out = Vec::new();
    for k in 1..traj.len().saturating_sub(1) {
        for i in 0..2 {
            let (p, c, n) = (&traj[k - 1].feet[i], &traj[k].feet[i], &traj[k + 1].feet[i]);
            if d(p, c) > 0.01 && d(c, n) > 0.01 && d(p, n) < 0.001 {
                out.push((k, i));
            }
        }
    }
    out
}

/// The planner's foot poses must be continuous: no one-tick jump of a foot. (This caught a
/// gait bug: on the touchdown tick the landed foot was reported at its lift-off spot.)
#[test]
fn planner_feet_are_continuous() {
    for name in ["straight", "fig4"] {
        let s = scenario::built_in(name).unwrap();
        let run = scenario::run(&s, GaitParams::<f64>::hrp2());
        let jumps = one_tick_foot_jumps(&run.trajectory);
        assert!(jumps.is_empty(), "{name}: one-tick foot jumps at {jumps:?}");
    }
}

/// Runs a built-in scenario and evaluates it on the default model.
fn walk(name: &str) -> (Vec<Reference<f64>>, Vec<MbSample>) {
    let s = scenario::built_in(name).expect("built-in scenario");
    let params = GaitParams::<f64>::hrp2();
    let traj = scenario::run(&s, params).trajectory;
    assert!(one_tick_foot_jumps(&traj).is_empty());
    let mb = evaluate(&Model::hrp2(), &traj, params.dt).expect("multi-body run");
    (traj, mb)
}

fn report(name: &str, traj: &[Reference<f64>], mb: &[MbSample]) -> f64 {
    let err = max_zmp_error(traj, mb);
    let (k, _) = (2..traj.len() - 2)
        .map(|k| {
            (
                k,
                (traj[k].x.zmp - mb[k].mb_zmp_x).hypot(traj[k].y.zmp - mb[k].mb_zmp_y),
            )
        })
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    let zmin = mb.iter().map(|s| s.mb_cog[2]).fold(f64::INFINITY, f64::min);
    let zmax = mb.iter().map(|s| s.mb_cog[2]).fold(0.0, f64::max);
    let knee_min = mb
        .iter()
        .flat_map(|s| [s.q[0][3], s.q[1][3]])
        .fold(f64::INFINITY, f64::min);
    let (ex, ey) = (2..traj.len() - 2).fold((0.0f64, 0.0f64), |a, k| {
        (
            a.0.max((traj[k].x.zmp - mb[k].mb_zmp_x).abs()),
            a.1.max((traj[k].y.zmp - mb[k].mb_zmp_y).abs()),
        )
    });
    println!(
        "{name}: {} ticks, max multi-body ZMP error {:.1} mm (x {:.1} mm, y {:.1} mm) at t = {:.3} s ({:?}); \
         COG z {:.4}..{:.4} m; smallest knee angle {:.1} deg",
        traj.len(),
        err * 1e3,
        ex * 1e3,
        ey * 1e3,
        mb[k].t,
        traj[k].phase,
        zmin,
        zmax,
        knee_min.to_degrees()
    );
    err
}

/// The straight walk (eight 0.2 m steps) on HRP-2 defaults: the multi-body ZMP stays within
/// 0.1 m of the plan (the paper's Table I diagonal is 11–12 mm for unmodified walks), and the
/// whole-body COG tracks the reference to 1e-9 m.
#[test]
fn straight_walk_multibody_zmp_error() {
    let (traj, mb) = walk("straight");
    let err = report("straight", &traj, &mb);
    assert!(err.is_finite() && err < 0.1, "{err}");
    assert!(
        err > 1e-4,
        "a walking robot cannot match the LIPM exactly: {err}"
    );
    for (r, s) in traj.iter().zip(&mb) {
        assert!((r.x.cog - s.mb_cog[0]).abs() < 1e-9 && (r.y.cog - s.mb_cog[1]).abs() < 1e-9);
    }
}

/// The paper's Fig. 4 modification (0.1 m steps, one landing moved 0.2 m further at 4.0 s).
#[test]
fn fig4_multibody_zmp_error() {
    let (traj, mb) = walk("fig4");
    let err = report("fig4", &traj, &mb);
    assert!(err.is_finite() && err < 0.1, "{err}");
}

/// The command that computes Tables I and II.
const TABLES_COMMAND: &str = "cargo run --release -p host-sim -- tables --out out/tables";

/// The table rows (`| … |` lines) that follow the line of `text` starting with `title`.
fn table_rows(text: &str, title: &str) -> Vec<String> {
    let start = text
        .lines()
        .position(|l| l.starts_with(title))
        .unwrap_or_else(|| panic!("no line starts with {title:?}"));
    text.lines()
        .skip(start + 1)
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| l.starts_with('|'))
        .map(str::to_string)
        .collect()
}

/// `host-sim tables`: the book's Tables I and II (`docs/src/host-sim.md`) are the command's
/// `tables.md`, row by row, and the diagonal figures of the text above them are its cells.
#[test]
fn the_book_quotes_tables_one_and_two_as_computed() {
    let dir = std::env::temp_dir().join(format!("host-sim-tables-{}", std::process::id()));
    host_sim::eval::paper::tables_command(&dir).expect("host-sim tables");
    let md = std::fs::read_to_string(dir.join("tables.md")).expect("tables.md");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("tables.json")).expect("json"))
            .expect("tables.json");
    let _ = std::fs::remove_dir_all(&dir);
    let book = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/src/host-sim.md"
    ))
    .expect("docs/src/host-sim.md");
    let mut stale = vec![];
    for title in [
        "Table I: maximum ZMP error without any adjustment",
        "Table II: maximum ZMP error with the proposed method",
    ] {
        let ours = table_rows(&md, title);
        assert_eq!(
            ours.len(),
            9,
            "{title}: header, separator and 7 rows: {ours:#?}"
        );
        let quoted = table_rows(&book, title);
        for (i, row) in ours.iter().enumerate() {
            if quoted.get(i) != Some(row) {
                stale.push(format!(
                    "{title}, line {}: the book has {:?}, the command gives {row:?}",
                    i + 1,
                    quoted.get(i).map_or("nothing", String::as_str)
                ));
            }
        }
        if quoted.len() > ours.len() {
            stale.push(format!(
                "{title}: the book has {} lines, the command {}",
                quoted.len(),
                ours.len()
            ));
        }
    }
    assert!(
        stale.is_empty(),
        "docs/src/host-sim.md does not quote Tables I and II as `{TABLES_COMMAND}` computes them \
         (copy them from its tables.md):\n{}",
        stale.join("\n")
    );
    // The diagonal, without modification: (+0.0, +0.0) and (+0.1, +0.1), Table I.
    let cm = |key: &str, i: usize| json[key][i][i].as_f64().expect(key) * 100.0;
    let diagonal = |i: usize| {
        format!(
            "{:.1} / {:.1} cm",
            cm("max_zmp_error_without_m", i),
            cm("paper_max_zmp_error_without_m", i)
        )
    };
    doc_figures::Quotes::new(TABLES_COMMAND)
        .line(
            "docs/src/host-sim.md",
            "cm at 0 m, ",
            &format!("{} at 0 m, {} at 0.1 m", diagonal(3), diagonal(4)),
        )
        .assert();
}
