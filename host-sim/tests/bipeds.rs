//! Every biped of PyPI's `example-robot-data` with two six-joint legs (found here from the
//! URDFs, not listed by hand): each is imported with soles that fit its feet, stands in MuJoCo
//! and walks every built-in scenario under ideal and realistic sensors by the engine's walked
//! verdict (no fall; slip, flight, CoP and landings within their bounds; an exception, with
//! its measure and why, would be listed in [`NOT_WALKED`]), or is refused with a reason
//! naming what is missing. A biped the package adds, or one whose outcome changes, fails the
//! test until the table below says what it does. The soles of the feet Coal reads
//! (not COLLADA) are compared with Pinocchio's placement of the same geometry.
//!
//! The default run imports every one, stands Alexander, iCub and Romeo in the engine and walks
//! [`QUICK_WALKS`]; `WALK_LONG=1` stands every imported one and walks every built-in scenario
//! under both sensor models with each ([`SENSORS`]).

mod engine;
mod urdf;

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

use engine::engine_here;
use host_sim::physics::sensors::SensorModel;
use host_sim::physics::{run, start::stands, PhysicsConfig};
use host_sim::robot::import::import;
use host_sim::robot::import::sole::{CONTACT_BAND_M, SOLE_COVER};
use host_sim::robot::model::{norm, rot_rpy, sub, Pose};
use host_sim::robot::Robot;
use host_sim::scenario::BUILT_IN;
use host_sim::sim::scenario_trajectory;
use planner_core::gait::Side;
use urdf::{all_robot_files, pinocchio_here};

/// What a biped does.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outcome {
    /// Imported; stands and walks every built-in scenario under both sensor models by the
    /// engine's walked verdict (no fall, slip, flight, CoP and landings within their bounds).
    Walks,
    /// Refused, the message containing this.
    Refused(&'static str),
}

/// The sensor models every biped walks under: the engine's values, and noise, bias and 2 ms
/// of latency with the stabilizer's gains for that delay (as `--sensors realistic`).
const SENSORS: [(&str, SensorModel); 2] = [
    ("ideal", SensorModel::IDEAL),
    ("realistic", SensorModel::REALISTIC),
];

/// The walks that stay up but are not walked by the verdict: (biped, scenario, sensors, the
/// gait measure beyond its bound). None: every walk of every imported biped is walked.
const NOT_WALKED: &[(&str, &str, &str, &str)] = &[];

/// Alexander, whose joints lag their servos the most of the imported bipeds (its support hip
/// pitch about 32 mrad behind its target in `lateral`, within its effort limits: no actuator
/// saturates).
const ALEXANDER: &str = "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf";

/// The walks of the default run: (biped, scenario, sensors).
const QUICK_WALKS: &[(&str, &str, &str)] = &[
    (ALEXANDER, "lateral", "ideal"),
    ("icub_description/robots/icub.urdf", "straight", "realistic"),
    ("romeo_description/urdf/romeo.urdf", "lateral", "ideal"),
];

/// The bipeds of example-robot-data 6.0.0, by the path under its `robots/` directory.
const BIPEDS: &[(&str, Outcome)] = &[
    (ALEXANDER, Outcome::Walks),
    ("g1_description/urdf/g1_29dof_rev_1_0.urdf", Outcome::Walks),
    (
        "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
        Outcome::Walks,
    ),
    (
        "human_description/robots/human.urdf",
        Outcome::Refused("no pair of feet below the base"),
    ),
    ("icub_description/robots/icub.urdf", Outcome::Walks),
    ("icub_description/robots/icub_reduced.urdf", Outcome::Walks),
    ("romeo_description/urdf/romeo.urdf", Outcome::Walks),
    (
        "romeo_description/urdf/romeo_laas_small.urdf",
        Outcome::Refused("<link name=\"body\"> (the base): its inertia tensor"),
    ),
    ("romeo_description/urdf/romeo_small.urdf", Outcome::Walks),
    (
        "simple_humanoid_description/urdf/simple_humanoid.urdf",
        Outcome::Refused("_ankle\">) has no <collision> or <visual> geometry"),
    ),
    (
        "simple_humanoid_description/urdf/simple_humanoid_classical.urdf",
        Outcome::Refused("_ankle\">) has no <collision> or <visual> geometry"),
    ),
    ("talos_data/robots/talos_full_v2.urdf", Outcome::Walks),
    ("talos_data/robots/talos_full_v2_box.urdf", Outcome::Walks),
    ("talos_data/robots/talos_reduced.urdf", Outcome::Walks),
    ("talos_data/robots/talos_reduced_box.urdf", Outcome::Walks),
    (
        "talos_data/robots/talos_reduced_corrected.urdf",
        Outcome::Walks,
    ),
];

/// The bipeds in the default run's engine check.
const QUICK: &[&str] = &[
    ALEXANDER,
    "icub_description/robots/icub.urdf",
    "romeo_description/urdf/romeo.urdf",
];

fn long() -> bool {
    std::env::var("WALK_LONG").as_deref() == Ok("1")
}

/// Whether a URDF has two six-joint legs: of its end bodies (links joined by fixed joints, no
/// moving joint below them) six moving joints from the root, exactly one mirrored pair (at
/// zero joint angles, the same position but for the sign of one coordinate, to 1 mm; a head
/// six joints from the root has no twin, a quadruped has two pairs).
fn two_six_joint_legs(path: &Path) -> bool {
    let text = std::fs::read_to_string(path)
        .expect("URDF")
        .replace("<texture />", "")
        .replace("<texture/>", "");
    let Ok(u) = urdf_rs::read_from_string(&text) else {
        panic!("{}: urdf-rs cannot read it", path.display());
    };
    let parent: BTreeMap<&str, &urdf_rs::Joint> = u
        .joints
        .iter()
        .map(|j| (j.child.link.as_str(), j))
        .collect();
    let moving = |j: &urdf_rs::Joint| j.joint_type != urdf_rs::JointType::Fixed;
    // Links with a moving joint somewhere below them.
    let mut above_moving = std::collections::BTreeSet::new();
    for j in u.joints.iter().filter(|j| moving(j)) {
        let mut at = j.parent.link.as_str();
        while above_moving.insert(at) {
            match parent.get(at) {
                Some(p) => at = p.parent.link.as_str(),
                None => break,
            }
        }
    }
    let mut ends = Vec::new();
    for j in u.joints.iter().filter(|j| moving(j)) {
        let end = j.child.link.as_str();
        if above_moving.contains(end) {
            continue;
        }
        let (mut n, mut first, mut at) = (0, "", end);
        let mut pose = Pose::IDENTITY;
        while let Some(p) = parent.get(at) {
            if moving(p) {
                n += 1;
                first = p.name.as_str();
            }
            let o = Pose {
                p: p.origin.xyz.0,
                r: rot_rpy(p.origin.rpy.0),
            };
            pose = o.then(&pose);
            at = p.parent.link.as_str();
        }
        if n == 6 {
            ends.push((first.to_string(), pose.p));
        }
    }
    let twins = |a: [f64; 3], b: [f64; 3]| {
        (0..3).any(|k| {
            (0..3).all(|i| {
                let s = if i == k { -1.0 } else { 1.0 };
                (a[i] - s * b[i]).abs() < 1e-3
            }) && a[k].abs() > 1e-3
        })
    };
    let mut pairs = 0;
    for (i, a) in ends.iter().enumerate() {
        pairs += ends[i + 1..]
            .iter()
            .filter(|b| b.0 != a.0 && twins(a.1, b.1))
            .count();
    }
    pairs == 1
}

/// The sum of the URDF's link masses.
fn urdf_mass(path: &Path) -> f64 {
    let text = std::fs::read_to_string(path)
        .expect("URDF")
        .replace("<texture />", "")
        .replace("<texture/>", "");
    let u = urdf_rs::read_from_string(&text).expect("URDF");
    u.links.iter().map(|l| l.inertial.mass.value).sum()
}

/// An imported robot's soles against its legs: below the ankles, at least 0.2 leg lengths
/// long and 0.08 wide (a sole of 0.058 × 0.059 m under iCub's 0.437 m legs, a frame under its
/// ankle taken for the sole's middle, is not), the whole URDF's mass, the written file the
/// robot.
fn check_import(tail: &str, path: &Path, toml: &str, r: &Robot) {
    let m = &r.model;
    assert!(
        (m.total_mass() - urdf_mass(path)).abs() < 1e-6,
        "{tail}: {} kg",
        m.total_mass()
    );
    let p = &r.planner.params;
    let (length, width) = (2.0 * p.sole_half_length, 2.0 * p.sole_half_width);
    for side in [Side::Left, Side::Right] {
        let z = m.leg_fk(side, &Pose::IDENTITY, &[0.0; 6]);
        let leg = norm(sub(z.ankle().p, z.links[0].p));
        assert!(
            z.sole.p[2] < z.ankle().p[2],
            "{tail}: a sole above its ankle"
        );
        assert!(
            length >= 0.2 * leg && width >= 0.08 * leg,
            "{tail}: soles {length:.3} × {width:.3} m on legs {leg:.3} m long"
        );
    }
    assert_eq!(
        &Robot::from_toml(toml).expect("the written file reads"),
        r,
        "{tail}"
    );
}

/// The imported soles against Pinocchio and Coal's reading of the same feet
/// (`tests/urdf/pinocchio_soles.py`): the sole plane within [`CONTACT_BAND_M`] of the foot's
/// lowest point below the ankle, and the sole rectangle inside the bounds of its contact
/// points (to 1 mm), spanning at least [`SOLE_COVER`] of them. Feet of COLLADA meshes are not
/// compared (Coal does not turn a COLLADA up axis). The number of feet compared.
fn soles_against_pinocchio(tail: &str, path: &Path, r: &Robot) -> usize {
    let m = &r.model;
    let package_dir = path
        .ancestors()
        .find(|a| a.file_name().is_some_and(|n| n == "example-robot-data"))
        .and_then(Path::parent)
        .expect("the package's directory");
    let job = serde_json::json!({
        "urdf": path,
        "package_dir": package_dir,
        "ankles": [&m.legs[0].links[5].joint.name, &m.legs[1].links[5].joint.name],
    });
    let mut child = Command::new(host_sim::physics::bridge::python())
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/urdf/pinocchio_soles.py"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 runs");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(job.to_string().as_bytes())
        .expect("job written");
    let out = child.wait_with_output().expect("the oracle ends");
    assert!(
        out.status.success(),
        "{tail}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let feet: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).expect("JSON");
    let p = &r.planner.params;
    let half = [p.sole_half_length, p.sole_half_width];
    let mut compared = 0;
    for (foot, side) in feet.iter().zip([Side::Left, Side::Right]) {
        if foot.get("skipped").is_some() {
            continue;
        }
        let num = |k: &str, i: usize| foot[k][i].as_f64().expect("a number");
        let z = m.leg_fk(side, &Pose::IDENTITY, &[0.0; 6]);
        let (ankle, sole) = (z.ankle().p, z.sole.p);
        let depth = num("ankle", 2) - foot["lowest"].as_f64().expect("lowest");
        assert!(
            ((ankle[2] - sole[2]) - depth).abs() <= CONTACT_BAND_M,
            "{tail} {side:?}: sole {:.4} m below the ankle, the foot's lowest point {depth:.4} m",
            ankle[2] - sole[2]
        );
        for (i, k) in ["x", "y"].iter().enumerate() {
            let (lo, hi) = (num(k, 0) - num("ankle", i), num(k, 1) - num("ankle", i));
            let c = sole[i] - ankle[i];
            assert!(
                c - half[i] >= lo - 1e-3 && c + half[i] <= hi + 1e-3,
                "{tail} {side:?} {k}: sole {:.4} … {:.4} m from the ankle, contact {lo:.4} … {hi:.4}",
                c - half[i],
                c + half[i]
            );
            assert!(
                2.0 * half[i] >= SOLE_COVER * (hi - lo) - 2e-3,
                "{tail} {side:?} {k}: sole {:.4} m of a contact {:.4} m",
                2.0 * half[i],
                hi - lo
            );
        }
        compared += 1;
    }
    compared
}

#[test]
fn every_biped_of_example_robot_data_imports_stands_and_walks_or_is_refused() {
    let test = "every_biped_of_example_robot_data_imports_stands_and_walks_or_is_refused";
    let Some(files) = all_robot_files(test) else {
        return;
    };
    let engine = engine_here(test);
    let pinocchio = pinocchio_here(test);
    let mut compared = 0;
    let mut found = Vec::new();
    let mut not_walked = Vec::new();
    for path in files.iter().filter(|p| two_six_joint_legs(p)) {
        let s = path.to_string_lossy();
        let tail = s
            .split_once("example-robot-data/robots/")
            .map_or(&*s, |(_, t)| t)
            .to_string();
        let Some(&(_, want)) = BIPEDS.iter().find(|(t, _)| *t == tail) else {
            panic!("{tail}: a biped with two six-joint legs this test does not know: add it");
        };
        found.push(tail.clone());
        let imported = import(path, None);
        let r = match (want, imported) {
            (Outcome::Refused(why), Err(e)) => {
                assert!(e.to_string().contains(why), "{tail}: {e}");
                println!("{tail}: refused: {e}");
                continue;
            }
            (Outcome::Refused(_), Ok(_)) => panic!("{tail}: imported, expected refused"),
            (_, Err(e)) => panic!("{tail}: {e}"),
            (_, Ok(i)) => {
                check_import(&tail, path, &i.toml, &i.robot);
                if pinocchio {
                    compared += soles_against_pinocchio(&tail, path, &i.robot);
                }
                for w in &i.warnings {
                    println!("{tail}: warning: {w}");
                }
                i.robot
            }
        };
        let p = &r.planner.params;
        println!(
            "{tail}: soles {:.3} × {:.3} m, feet {:.3} m apart",
            2.0 * p.sole_half_length,
            2.0 * p.sole_half_width,
            p.step_width
        );
        if !engine || !(long() || QUICK.contains(&tail.as_str())) {
            continue;
        }
        stands(&r).unwrap_or_else(|e| panic!("{tail}: {e}"));
        if want != Outcome::Walks {
            continue;
        }
        for scenario in BUILT_IN {
            for (sensors, model) in SENSORS {
                if !long() && !QUICK_WALKS.contains(&(tail.as_str(), scenario, sensors)) {
                    continue;
                }
                let (_, trajectory, dt) = scenario_trajectory(scenario, &r).expect("built in");
                let mut cfg = PhysicsConfig::for_robot(&r);
                cfg.sensors = model;
                cfg.gains = cfg.gains.for_delay(model.latency_ticks as f64 * 1e-3);
                let out = run(&trajectory, dt, &cfg).expect("the engine");
                let what = format!("{tail}: {scenario}, {sensors} sensors");
                let known = NOT_WALKED
                    .iter()
                    .find(|k| (k.0, k.1, k.2) == (tail.as_str(), scenario, sensors));
                let text = out.report.walked_text();
                if let Some(k) = known {
                    if out.report.fell || out.report.walked() || !text.contains(k.3) {
                        not_walked.push(format!("{what}: expected no fall and {}: {text}", k.3));
                    } else {
                        println!("{what}: no fall, not walked: {text}");
                    }
                } else if out.report.walked() {
                    println!("{what}: walked, tilt {:.2}°", out.report.max_tilt_deg);
                } else {
                    println!("{what}: {}", out.report.walked_text());
                    not_walked.push(format!(
                        "{what}: {}: {:?}",
                        out.report.walked_text(),
                        out.report
                    ));
                }
            }
        }
    }
    assert!(
        not_walked.is_empty(),
        "not walked:\n{}",
        not_walked.join("\n")
    );
    // Talos (5 descriptions), G1 (2) and Alexander: two feet each.
    assert!(
        !pinocchio || compared == 16,
        "{compared} feet compared with Pinocchio"
    );
    println!("{compared} feet's soles against Pinocchio and Coal");
    let listed: Vec<String> = BIPEDS.iter().map(|(t, _)| t.to_string()).collect();
    assert_eq!(found, listed, "the bipeds found are not the table's");
}

/// Alexander's `lateral` walk with ideal sensors: each swing sole lands short of its plan by
/// its joints' servo lag (about 2 mm); with the stabilizer's soles at their references the
/// shortfalls add up over the 13 landings beyond the 20 mm bound; with the foot placement
/// from leg odometry (the default) each step is aimed at its planned landing in the world,
/// the landing error stays within the bound and the walk is walked.
#[test]
fn alexanders_landings_do_not_add_up_with_leg_odometry() {
    let test = "alexanders_landings_do_not_add_up_with_leg_odometry";
    let Some(files) = all_robot_files(test) else {
        return;
    };
    if !engine_here(test) {
        return;
    }
    let path = files
        .iter()
        .find(|p| p.to_string_lossy().ends_with(ALEXANDER))
        .expect("Alexander in example-robot-data");
    let r = import(path, None).expect("Alexander imports").robot;
    let (_, trajectory, dt) = scenario_trajectory("lateral", &r).expect("built in");
    let mut landing = [0.0; 2];
    for (i, odometry) in [false, true].into_iter().enumerate() {
        let mut cfg = PhysicsConfig::for_robot(&r);
        cfg.gains.foot_odometry = odometry;
        let out = run(&trajectory, dt, &cfg).expect("the engine");
        assert!(!out.report.fell, "odometry {odometry}: {:?}", out.report);
        landing[i] = out.report.gait.landing_err_max_m;
        println!(
            "odometry {odometry}: {}, landing error {:.1} mm",
            out.report.walked_text(),
            landing[i] * 1e3
        );
        assert_eq!(
            out.report.walked(),
            odometry,
            "{}",
            out.report.walked_text()
        );
    }
    assert!(
        landing[0] > 1.5 * landing[1],
        "landing errors without and with odometry: {landing:?}"
    );
}
