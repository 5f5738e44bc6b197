//! The robot file: the HRP-2 file shipped in the repository is what the code
//! and the firmware use; a second robot (`tests/robots/small.toml`) walks with its own
//! pendulum, timing, soles, reach limits and link table; an inconsistent file is refused with
//! a message that names the key.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use host_sim::eval::multibody::{evaluate, max_zmp_error};
use host_sim::robot::model::Model;
use host_sim::robot::{Robot, HRP2_TOML};
use host_sim::scenario::Failure;
use host_sim::scenario::{self, Command as Cmd};
use host_sim::sim::{outcomes, simulate, SimConfig};
use planner_core::gait::{GaitParams, Phase, Side};
use planner_core::node::NodeConfig;
use planner_core::wire::Reason;

fn robots() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots")
}

fn small() -> Robot {
    Robot::load(&robots().join("small.toml")).expect("the small robot file")
}

#[test]
fn the_shipped_hrp2_file_is_the_code_default() {
    let r = Robot::from_toml(HRP2_TOML).expect("hrp2.toml");
    assert_eq!(r.name(), "HRP-2");
    // Exact equality, float by float: planner-core's no_std defaults (used by its own tests)
    // are the file's values.
    assert_eq!(r.node_config(), NodeConfig::hrp2());
    assert_eq!(r.planner.params, GaitParams::<f64>::hrp2());
    assert_eq!(r.model, Model::hrp2());
    // The published figure the link table is built to (Kaneko et al. 2004).
    assert!((r.model.total_mass() - 58.0).abs() < 1e-9);
    // The file on disk is the one compiled in.
    let on_disk =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/hrp2.toml"))
            .unwrap();
    assert_eq!(on_disk, HRP2_TOML);
}

/// `(what is replaced, by what, a text the error must contain)`: each an inconsistent HRP-2
/// file.
const BROKEN: &[(&str, &str, &str)] = &[
    (
        "max_feet_distance = 0.361",
        "max_feet_distance = 0.6",
        "reach.max_feet_distance",
    ),
    (
        "step_height = 0.05",
        "step_height = 0.6",
        "feet.step_height",
    ),
    ("cog_height = 0.814", "cog_hieght = 0.814", "cog_hieght"),
    ("gravity = 9.8 ", "", "gravity"),
    ("cog_height = 0.814", "cog_height = \"high\"", "cog_height"),
    (
        "cog_height = 0.814",
        "cog_height = nan",
        "pendulum.cog_height",
    ),
    ("gravity = 9.8 ", "gravity = -9.8 ", "pendulum.gravity"),
    (
        "control_period = 0.005",
        "control_period = 0.0",
        "timing.control_period",
    ),
    (
        "control_period = 0.005",
        "control_period = 0.0025",
        "timing.control_period",
    ),
    (
        "control_period = 0.005",
        "control_period = 0.004",
        "timing.stand",
    ),
    (
        "single_support = 0.7",
        "single_support = 0.7013",
        "timing.single_support",
    ),
    (
        "double_support = 0.1",
        "double_support = 0.0",
        "timing.double_support",
    ),
    ("rest = 0.5", "rest = 12.0", "timing.rest"),
    ("min = -0.2", "min = 0.1", "adjustment.min"),
    ("min = -0.2", "min = -0.7", "adjustment.min"),
    ("max = 0.35", "max = -0.05", "adjustment.max"),
    ("sole_width = 0.14", "sole_width = 0.0", "feet.sole_width"),
    ("step_width = 0.2 ", "step_width = 0.12 ", "feet.step_width"),
    (
        "step_height = 0.05",
        "step_height = -0.01",
        "feet.step_height",
    ),
    ("min_width = 0.15", "min_width = 0.22", "feet.step_width"),
    ("min_width = 0.15", "min_width = 0.1", "reach.min_width"),
    (
        "max_feet_distance = 0.361",
        "max_feet_distance = 0.15",
        "reach.max_feet_distance",
    ),
    ("max_stride = 0.43", "max_strde = 0.43", "max_strde"),
    ("r = 1e-6", "r = 0.0", "preview.r"),
    ("shaping = true", "shaping = 1", "shaping"),
    (
        "waist_height = 0.6523",
        "waist_height = 0.62",
        "multibody.waist_height",
    ),
    (
        "waist_height = 0.6523",
        "waist_height = 0.9",
        "multibody.waist_height",
    ),
    (
        "thigh_length = 0.30",
        "thigh_length = 0.0",
        "multibody.thigh_length",
    ),
    ("mass = 28.0", "mass = -28.0", "multibody.trunk"),
    ("box = [0.30, 0.50, 0.60]", "", "multibody.trunk"),
    (
        "box = [0.30, 0.50, 0.60]",
        "box = [0.30, 0.50, 0.60]\ninertia = [1.0, 1.0, 1.0]",
        "multibody.trunk",
    ),
    ("cylinder = [0.06, 0.30]", "cylinder = [0.06]", "cylinder"),
    ("[multibody.foot]", "[multibody.feet]", "feet"),
    (
        "\n[multibody]\n",
        "\n[multibody_table]\n",
        "multibody_table",
    ),
];

#[test]
fn an_inconsistent_robot_file_is_refused_naming_the_key() {
    for &(from, to, key) in BROKEN_FOR_THE_PLANNER {
        let text = HRP2_TOML.replacen(from, to, 1);
        assert_ne!(text, HRP2_TOML, "{from:?} is not in hrp2.toml");
        let e = planner_core::robot::Robot::from_toml(&text)
            .err()
            .unwrap_or_else(|| panic!("{from:?} → {to:?} accepted by the planner's reader"));
        assert!(
            e.to_string().contains(key),
            "{from:?} → {to:?}: {e} does not name {key}"
        );
    }
    for &(from, to, key) in BROKEN.iter().chain(BROKEN_FOR_THE_PLANNER) {
        assert!(HRP2_TOML.contains(from), "{from:?} is not in hrp2.toml");
        let text = HRP2_TOML.replacen(from, to, 1);
        match Robot::from_toml(&text) {
            Ok(_) => panic!("{from:?} → {to:?} accepted"),
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(key),
                    "{from:?} → {to:?}: {msg:?} does not name {key}"
                );
            }
        }
    }
    // Without [multibody] the planner's part is still a robot (the firmware needs no more),
    // but host-sim refuses it.
    let cut = &HRP2_TOML[..HRP2_TOML.find("\n[multibody]\n").unwrap()];
    assert!(planner_core::robot::Robot::from_toml(cut).is_ok());
    let e = Robot::from_toml(cut).unwrap_err().to_string();
    assert!(e.contains("[multibody]"), "{e}");
}

/// Files the firmware's reader (the planner's part alone) must refuse as well: values that
/// would start no node, or one that cannot walk.
const BROKEN_FOR_THE_PLANNER: &[(&str, &str, &str)] = &[
    ("r = 1e-6", "r = 1e30", "preview.r"),
    ("qe = 1.0", "qe = 1e-20", "preview.r"),
    (
        "cog_height = 0.814",
        "cog_height = 1e-300",
        "pendulum.cog_height",
    ),
    (
        "cog_height = 0.814",
        "cog_height = 1e-10",
        "pendulum.cog_height",
    ),
    ("gravity = 9.8 ", "gravity = 1e308 ", "pendulum.gravity"),
    ("gravity = 9.8 ", "gravity = 1e-6 ", "pendulum.gravity"),
    (
        "control_period = 0.005",
        "control_period = 1e-300",
        "timing.control_period",
    ),
    (
        "sole_length = 0.24",
        "sole_length = 1e300",
        "feet.sole_length",
    ),
    (
        "step_width = 0.2 ",
        "step_width = 1e-300 ",
        "feet.step_width",
    ),
];

/// The small robot's file, read: every value differs from HRP-2's.
#[test]
fn the_second_robot_is_read_as_written() {
    let r = small();
    let p = r.planner.params;
    assert_eq!(r.name(), "small biped");
    assert_eq!((p.single_ticks, p.double_ticks), (100, 30));
    assert_eq!((p.adjust_min_ticks, p.adjust_max_ticks), (-30, 50));
    assert_eq!((p.sole_half_length, p.sole_half_width), (0.08, 0.045));
    assert!((p.omega - (9.81f64 / 0.48).sqrt()).abs() < 1e-15);
    assert_eq!(r.planner.reach.max_forward, 0.16);
    assert_eq!(r.node_config().left.y, 0.065);
    assert!((r.model.total_mass() - 17.4).abs() < 1e-9);
    assert_eq!(r.model.gravity, 9.81);
}

#[test]
fn the_second_robot_walks_with_its_own_pendulum_timing_and_soles() {
    let robot = small();
    let p = robot.planner.params;
    let file = scenario::file::load_file(&robots().join("small-walk.toml")).unwrap();
    let s = &file.scenario;
    let cfg = SimConfig {
        node: robot.node_config(),
        ..SimConfig::default()
    };
    let sim = simulate(s, &cfg).unwrap();
    for o in outcomes(s, &sim) {
        assert_eq!(o.failure, None, "{:?}: {}", o.command, o.detail);
    }
    assert!(!sim.cut, "the walk ended standing");
    let traj = &sim.run.trajectory;

    // The cart-table relation of the reference, p = x − (z_c/g) ẍ, holds with this robot's
    // z_c and g (to round-off), and not with HRP-2's.
    let residual = |zc_over_g: f64| {
        traj.iter()
            .flat_map(|r| [&r.x, &r.y])
            .map(|a| (a.zmp - (a.cog - zc_over_g * a.cog_acc)).abs())
            .fold(0.0, f64::max)
    };
    assert!(residual(0.48 / 9.81) < 1e-9, "{}", residual(0.48 / 9.81));
    assert!(residual(0.814 / 9.8) > 1e-3, "{}", residual(0.814 / 9.8));

    // Single supports last the file's 0.5 s (100 ticks); none was adjusted in this walk.
    let mut runs = Vec::new();
    let mut n = 0;
    for w in traj.windows(2) {
        if matches!(w[0].phase, Phase::Single(_)) {
            n += 1;
        }
        if matches!(w[0].phase, Phase::Single(_)) && !matches!(w[1].phase, Phase::Single(_)) {
            runs.push(n);
            n = 0;
        }
    }
    assert_eq!(runs.len(), 5, "{runs:?}");
    assert!(runs.iter().all(|&k| k == 100), "{runs:?}");

    // In single support the ZMP stays on the small sole (0.16 × 0.09 m).
    for r in traj {
        if let Phase::Single(side) = r.phase {
            let f = &r.feet[usize::from(side == Side::Right)];
            let (s, c) = f.yaw.sin_cos();
            let (dx, dy) = (r.x.zmp - f.x, r.y.zmp - f.y);
            assert!((c * dx + s * dy).abs() <= p.sole_half_length + 1e-9);
            assert!((-s * dx + c * dy).abs() <= p.sole_half_width + 1e-9);
        }
    }

    // The small link table follows it (the legs reach every pose), and its multi-body ZMP
    // stays near the reference: a stated 30 mm (measured 21.5 mm, on a sole 90 mm wide; HRP-2's
    // straight walk: 41 mm).
    let mb = evaluate(&robot.model, traj, p.dt).expect("the small legs follow the walk");
    let err = max_zmp_error(traj, &mb);
    assert!(err < 0.030, "multi-body ZMP error {err} m");
    eprintln!("small biped: multi-body ZMP error {:.1} mm", err * 1e3);
}

#[test]
fn the_second_robot_refuses_what_its_legs_cannot_reach() {
    // The built-in straight walk has HRP-2's 0.2 m steps: beyond the small robot's growth and
    // stride limits, so the node refuses them (as `Reach`), where HRP-2's node takes them.
    let s = scenario::built_in("straight").unwrap();
    for (robot, refused) in [(small(), true), (Robot::hrp2(), false)] {
        let cfg = SimConfig {
            node: robot.node_config(),
            ..SimConfig::default()
        };
        let sim = simulate(&s, &cfg).unwrap();
        let reach = outcomes(&s, &sim).iter().any(|o| {
            matches!(o.command, Cmd::Push(..)) && o.failure == Some(Failure::Refused(Reason::Reach))
        });
        assert_eq!(reach, refused, "{}", robot.name());
    }
}

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("run host-sim")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-robot-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn the_command_line_takes_a_robot_file() {
    let dir = temp_dir("cli");
    let robot = robots().join("small.toml");
    let walk = robots().join("small-walk.toml");
    let out = dir.join("out");
    let o = host_sim(&[
        "run",
        walk.to_str().unwrap(),
        "--robot",
        robot.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(text.contains("small biped"), "{text}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["robot"], "small biped");

    // The same walk on HRP-2 (the default): its 0.13 m stance is inside HRP-2's reach limits?
    // No: narrower than its 0.15 m minimum width, so the steps are refused and run exits 1.
    let o = host_sim(&[
        "run",
        walk.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));

    // A broken robot file: exit 2, the message names the file and the key.
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, HRP2_TOML.replacen("min = -0.2", "min = 0.3", 1)).unwrap();
    let o = host_sim(&[
        "run",
        "straight",
        "--robot",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(bad.to_str().unwrap()) && err.contains("adjustment.min"),
        "{err}"
    );
    let missing = dir.join("missing.toml");
    let o = host_sim(&["run", "straight", "--robot", missing.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(missing.to_str().unwrap()), "{err}");
}

/// HRP-2's leg joints in the generated MJCF carry the movable ranges of Kaneko et al., ICRA
/// 2004 (left leg, degrees: hip yaw −30 … 45, hip roll −20 … 35, hip pitch −125 … 42, knee
/// 0 … 150, ankle pitch −75 … 42, ankle roll −35 … 20; the right leg mirrored) and no effort
/// limit (none is published there: the assumption the book states).
#[test]
fn hrp2s_mjcf_has_the_published_joint_ranges() {
    let xml = host_sim::physics::model::Robot::default().mjcf();
    let left = [
        ("hip_yaw", -30.0, 45.0, false),
        ("hip_roll", -20.0, 35.0, false),
        ("hip_pitch", -125.0, 42.0, true),
        ("knee", 0.0, 150.0, true),
        ("ankle_pitch", -75.0, 42.0, true),
        ("ankle_roll", -35.0, 20.0, false),
    ];
    for (name, lo, hi, pitch) in left {
        for (side, [lo, hi]) in [
            ("l", [lo, hi]),
            ("r", if pitch { [lo, hi] } else { [-hi, -lo] }),
        ] {
            let tag = format!("<joint name=\"{side}_{name}\"");
            let at = xml
                .find(&tag)
                .unwrap_or_else(|| panic!("{tag} in the MJCF"));
            let joint = &xml[at..at + xml[at..].find("/>").expect("closed")];
            let range = joint
                .split_once("range=\"")
                .and_then(|(_, r)| r.split_once('"'))
                .map(|(r, _)| r)
                .unwrap_or_else(|| panic!("{joint}: no range"));
            let v: Vec<f64> = range
                .split_whitespace()
                .map(|x| x.parse().expect("a number"))
                .collect();
            let want = [f64::to_radians(lo), f64::to_radians(hi)];
            assert!(
                v.len() == 2 && (v[0] - want[0]).abs() < 1e-5 && (v[1] - want[1]).abs() < 1e-5,
                "{joint}: want {want:?}"
            );
            assert!(!joint.contains("damping=\"0\""), "{joint}: an effort limit");
        }
    }
    assert!(
        !xml.contains("forcerange"),
        "HRP-2 has no published torque limits"
    );
}

/// A `[multibody.limits]` entry must name one of the six joints, with an ordered range.
#[test]
fn hrp2_limits_table_is_checked() {
    for (edit, want) in [
        (
            "[multibody.limits.elbow]\nrange = [0.0, 1.0]\n",
            "\"elbow\": not a joint",
        ),
        (
            "[multibody.limits.knee]\nrange = [1.0, 0.0]\n",
            "knee: range must be",
        ),
        (
            "[multibody.limits.knee]\neffort = -3.0\n",
            "knee: effort must be",
        ),
    ] {
        let text = HRP2_TOML.replace("[multibody.limits.knee]\nrange = [0.0, 2.617994]\n", "")
            + "\n"
            + edit;
        let e = Robot::from_toml(&text).expect_err("refused").to_string();
        assert!(e.contains("multibody.limits") && e.contains(want), "{e}");
    }
}
