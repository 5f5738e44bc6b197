//! Tests of `host_sim::scenario::file`: the shipped example files give the same timelines as the
//! built-in scenarios (and the same runs), the documented defaults and ordering hold, and every
//! kind of bad input is refused with a message that says what is wrong.

use std::path::Path;

use host_sim::scenario::file::{load, parse, DEFAULT_MAX_TIME_S};
use host_sim::scenario::TICK_S;
use host_sim::scenario::{self, Command, Scenario};
use planner_core::gait::{Footstep, GaitParams, Side};

/// Coordinates written as decimals in the files differ from the built-ins' computed values by
/// float rounding only (`0.1 * 3.0` is 0.30000000000000004, the file says 0.3).
const TOL: f64 = 1e-12;

fn example(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(format!("{name}.toml"));
    load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn same_footstep(a: &Footstep<f64>, b: &Footstep<f64>) -> bool {
    a.side == b.side
        && (a.x - b.x).abs() <= TOL
        && (a.y - b.y).abs() <= TOL
        && (a.yaw - b.yaw).abs() <= TOL
}

/// Same command: same kind, id and side exactly, coordinates within `TOL`.
fn same_command(a: &Command, b: &Command) -> bool {
    match (a, b) {
        (Command::Push(i, f), Command::Push(j, g))
        | (Command::Modify(i, f), Command::Modify(j, g)) => i == j && same_footstep(f, g),
        (Command::Start, Command::Start)
        | (Command::Stop, Command::Stop)
        | (Command::StopNow, Command::StopNow) => true,
        _ => false,
    }
}

fn assert_same_scenario(file: &Scenario, built: &Scenario) {
    assert_eq!(file.name, built.name);
    assert_eq!(file.about, built.about);
    assert_eq!(file.max_ticks, built.max_ticks);
    assert_eq!(file.start_feet(0.2), built.start_feet(0.2));
    assert_eq!(
        file.timeline.len(),
        built.timeline.len(),
        "{}: number of commands",
        built.name
    );
    let mut bitwise = 0;
    for (k, ((ta, ca), (tb, cb))) in file.timeline.iter().zip(&built.timeline).enumerate() {
        assert_eq!(ta, tb, "{}: tick of command {k}", built.name);
        assert!(
            same_command(ca, cb),
            "{}: command {k}: {ca:?} vs {cb:?}",
            built.name
        );
        bitwise += usize::from(ca == cb);
    }
    println!(
        "{}: {} commands, same ticks and commands ({bitwise} bit for bit, the others within {TOL:e} m)",
        built.name,
        built.timeline.len()
    );
}

#[test]
fn examples_match_the_built_ins() {
    for name in ["fig4", "lateral"] {
        assert_same_scenario(&example(name), &scenario::built_in(name).unwrap());
    }
}

#[test]
fn examples_run_like_the_built_ins() {
    let params = GaitParams::hrp2();
    for name in ["fig4", "lateral"] {
        let a = scenario::run(&example(name), params);
        let b = scenario::run(&scenario::built_in(name).unwrap(), params);
        assert_eq!(a.trajectory.len(), b.trajectory.len(), "{name}");
        let results = |r: &scenario::Run| -> Vec<_> {
            r.events
                .iter()
                .map(|e| (e.tick, e.result.clone()))
                .collect()
        };
        assert_eq!(results(&a), results(&b), "{name}: command answers");
        let adj = |r: &scenario::Run| -> Vec<_> {
            r.adjustments
                .iter()
                .map(|a| (a.tick, a.adjust_s, a.plane))
                .collect()
        };
        assert_eq!(adj(&a), adj(&b), "{name}: single-support adjustments");
        let worst = a
            .trajectory
            .iter()
            .zip(&b.trajectory)
            .map(|(p, q)| {
                (p.x.cog - q.x.cog)
                    .abs()
                    .max((p.y.cog - q.y.cog).abs())
                    .max((p.x.zmp - q.x.zmp).abs())
                    .max((p.y.zmp - q.y.zmp).abs())
            })
            .fold(0.0f64, f64::max);
        println!(
            "{name}: {} ticks, adjustments {:?}, largest COG/ZMP difference {worst:.1e} m",
            a.trajectory.len(),
            adj(&a)
        );
        assert!(worst < 1e-9, "{name}: trajectories differ by {worst} m");
    }
}

#[test]
fn tick_matches_the_gait() {
    assert_eq!(TICK_S, GaitParams::<f64>::hrp2().dt);
}

#[test]
fn defaults_rounding_and_order() {
    let s = parse(
        r#"
name = "defaults"

[[command]]
at_s = 0.1
kind = "stop"

[[command]]
at_s = 0.1
kind = "start"

[[modify]]
at_s = 0.1
id = 1
x = 0.3
y = 0.1

[[step]]
id = 1
side = "left"
x = 0
y = 0.1
at_s = 0.1

[[step]]
id = 0
side = "right"
x = 0.2
y = -0.1
yaw = 0.5

[[command]]
at_s = 0.0026
kind = "stop_now"

[[modify]]
at_s = 0.0024
id = 7
side = "right"
x = 1.0
y = -1.0
"#,
    )
    .unwrap();
    assert_eq!(s.about, "");
    assert_eq!(s.max_ticks, (DEFAULT_MAX_TIME_S / TICK_S) as u64);
    // No [feet]: the robot's stance (HRP-2: 0.2 m apart).
    assert_eq!(s.feet, None);
    assert_eq!(
        s.start_feet(0.2),
        [
            Footstep::new(Side::Left, 0.0, 0.1, 0.0),
            Footstep::new(Side::Right, 0.0, -0.1, 0.0)
        ]
    );
    let right = |x, y, yaw| Footstep::new(Side::Right, x, y, yaw);
    let left = |x, y| Footstep::new(Side::Left, x, y, 0.0);
    assert_eq!(
        s.timeline,
        vec![
            // 0.0024 s rounds to tick 0; steps before modifications at the same tick.
            (0, Command::Push(0, right(0.2, -0.1, 0.5))),
            (0, Command::Modify(7, right(1.0, -1.0, 0.0))),
            // 0.0026 s rounds to tick 1.
            (1, Command::StopNow),
            // Tick 20: step, then modification (side from the step), then commands in file
            // order.
            (20, Command::Push(1, left(0.0, 0.1))),
            (20, Command::Modify(1, left(0.3, 0.1))),
            (20, Command::Stop),
            (20, Command::Start),
        ]
    );
    // 3.995 s is tick 799 (not 798 by truncation of 798.999…).
    let s = parse("name = \"t\"\nmax_time_s = 3.995\n").unwrap();
    assert_eq!(s.max_ticks, 799);
}

/// Parses `text` expecting an error that contains every one of `needles`.
fn refused(text: &str, needles: &[&str]) {
    let e = match parse(text) {
        Ok(s) => panic!("accepted: {s:?}\n--- input:\n{text}"),
        Err(e) => e,
    };
    for n in needles {
        assert!(e.contains(n), "error {e:?} does not mention {n:?}");
    }
}

const STEP: &str = "[[step]]\nid = 0\nside = \"right\"\nx = 0.2\ny = -0.1\n";

#[test]
fn bad_files_are_refused_with_clear_messages() {
    // Syntax.
    refused(
        "name = \"a\"\nx = = 1\n",
        &["invalid scenario TOML", "line 2"],
    );
    // Unknown keys, at every level.
    refused("name = \"a\"\nspeed = 1.0\n", &["unknown field `speed`"]);
    refused(
        &format!("name = \"a\"\n{STEP}height = 0.1\n"),
        &["unknown field `height`"],
    );
    refused(
        "name = \"a\"\n[feet]\nleft = { x = 0.0, y = 0.1, z = 0.0 }\nright = { x = 0.0, y = -0.1 }\n",
        &["unknown field `z`"],
    );
    refused(
        "name = \"a\"\n[[command]]\nat_s = 0.0\nkind = \"start\"\nwhen = 1\n",
        &["unknown field `when`"],
    );
    refused(
        "name = \"a\"\n[[steps]]\nid = 0\n",
        &["unknown field `steps`"],
    );
    // Missing keys and wrong types.
    refused("about = \"no name\"\n", &["missing field `name`"]);
    refused(
        "name = \"a\"\n[[step]]\nid = 0\nside = \"left\"\nx = 0.1\n",
        &["missing field `y`"],
    );
    refused(
        "name = \"a\"\n[[command]]\nkind = \"start\"\n",
        &["missing field `at_s`"],
    );
    refused(
        "name = \"a\"\n[[step]]\nid = -1\nside = \"left\"\nx = 0.1\ny = 0.1\n",
        &["id"],
    );
    refused(
        "name = \"a\"\n[[step]]\nid = 0\nside = \"left\"\nx = \"far\"\ny = 0.1\n",
        &["x"],
    );
    // Unknown side and command kind.
    refused(
        "name = \"a\"\n[[step]]\nid = 0\nside = \"middle\"\nx = 0.1\ny = 0.0\n",
        &["unknown variant `middle`", "left", "right"],
    );
    refused(
        "name = \"a\"\n[[command]]\nat_s = 1.0\nkind = \"jump\"\n",
        &["unknown variant `jump`", "start", "stop_now"],
    );
    // Times.
    refused(
        "name = \"a\"\n[[command]]\nat_s = -0.5\nkind = \"start\"\n",
        &["[[command]] #1", "must not be negative", "-0.5"],
    );
    refused(
        &format!("name = \"a\"\n{STEP}at_s = nan\n"),
        &["[[step]] #1 (id 0)", "finite"],
    );
    refused(
        "name = \"a\"\n[[modify]]\nat_s = inf\nid = 0\nside = \"left\"\nx = 0.0\ny = 0.0\n",
        &["[[modify]] #1 (id 0)", "finite"],
    );
    refused(
        "name = \"a\"\n[[command]]\nat_s = 1e300\nkind = \"start\"\n",
        &["too large"],
    );
    refused(
        "name = \"a\"\nmax_time_s = -1.0\n",
        &["max_time_s", "negative"],
    );
    refused(
        "name = \"a\"\nmax_time_s = 0.001\n",
        &["max_time_s", "at least one tick"],
    );
    // Coordinates.
    refused(
        "name = \"a\"\n[[step]]\nid = 0\nside = \"left\"\nx = inf\ny = 0.1\n",
        &["[[step]] #1 (id 0)", "x must be finite"],
    );
    refused(
        "name = \"a\"\n[feet]\nleft = { x = 0.0, y = 0.1, yaw = nan }\nright = { x = 0.0, y = -0.1 }\n",
        &["feet.left", "yaw must be finite"],
    );
    // Duplicate ids.
    refused(
        &format!("name = \"a\"\n{STEP}{STEP}"),
        &["[[step]] #2 (id 0)", "duplicate step id 0", "[[step]] #1"],
    );
    // Modification of a step the file does not define, without a side.
    refused(
        "name = \"a\"\n[[modify]]\nat_s = 1.0\nid = 4\nx = 0.0\ny = 0.0\n",
        &["[[modify]] #1 (id 4)", "no [[step]] has id 4", "side"],
    );
    // Empty name.
    refused("name = \"  \"\n", &["`name` must not be empty"]);
}

#[test]
fn load_names_the_file() {
    let e = load(Path::new("/nonexistent/walk.toml")).unwrap_err();
    assert!(e.contains("/nonexistent/walk.toml"), "{e}");
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("bad-scenario.toml");
    std::fs::write(&path, "name = \"a\"\nspeed = 1\n").unwrap();
    let e = load(&path).unwrap_err();
    assert!(e.starts_with(&path.display().to_string()), "{e}");
    assert!(e.contains("unknown field `speed`"), "{e}");
}

/// The example scenario file of the book's chapter on scenario files is valid and walks as
/// written.
#[test]
fn the_book_example_walks() {
    let book = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/src/scenarios.md"
    ))
    .expect("docs/src/scenarios.md");
    let start = book
        .find("name = \"my-walk\"")
        .expect("the book's scenario example");
    let end = start + book[start..].find("```").expect("end of the example");
    let file = host_sim::scenario::file::parse_file(&book[start..end]).expect("valid example");
    let sim = host_sim::sim::simulate(&file.scenario, &host_sim::sim::SimConfig::default())
        .expect("runs");
    let outcomes = host_sim::sim::outcomes(&file.scenario, &sim);
    assert_eq!(outcomes.len(), 5);
    for o in outcomes {
        assert_eq!(o.failure, None, "{:?}: {}", o.command, o.detail);
    }
    assert!(!sim.cut);
}
