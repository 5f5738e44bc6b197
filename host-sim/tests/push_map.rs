//! The push-recovery map (`host-sim push-map`, host-sim/src/physics/push_map.rs) and the node
//! in the engine's loop (host-sim/src/physics/closed_loop.rs).
//!
//! * The contract of `push-map --quick`: `push_map.json` with `robot`, `mass_kg`,
//!   `push_duration_s` and the three configurations, each a list of `{phase, direction_deg,
//!   max_force_n, impulse_ns, dv_mps, bw_fraction, steps_adjusted}` over the quick map's two
//!   phases and two of its directions; `Δv = F Δt / m`, `F Δt` and `F / (m g)` as stated; the
//!   stabilizer-only walks never move a step; a polar plot per phase; one cell run alone
//!   (`--cell`) gives the map's cell.
//! * The bisection's claim, checked again for one cell: the reported force is walked through,
//!   one resolution step more fells the robot.
//! * A velocity push (the base's horizontal velocity set at one instant): the engine's base
//!   moves at the velocity set in the next millisecond, in the direction given; a small one is
//!   walked through and a large one fells the robot; a velocity cell's JSON line has `v_mps`
//!   and no force fields. With `WALK_LONG=1`, the quick map of velocity pushes against the
//!   book's summary of it.
//! * The closed loop: without a push no configuration moves a step or falls; with
//!   `StartAdjusting` and a push, every landing is its commanded position plus the shift the
//!   node published in `ADJUST` (the controller's book stays true).
//!
//! * With `WALK_LONG=1`, the full map (576 engine runs) against the book's table and summary
//!   (docs/src/adjust.md) and the front page's row, and the map with capture steps re-planned
//!   from the measured state against the book's summary of it and the front page's sentence.
//!
//! MuJoCo as in tests/physics.rs: skipped with a message when missing, a failure under
//! `WALK_REQUIRE_MUJOCO=1`.

use std::path::PathBuf;
use std::process::Command;

mod engine;

use engine::engine_here;
use host_sim::physics::closed_loop::{run, PushKind, PushPhase, PushSpec, Stepping, Walk};
use host_sim::physics::push_map::{
    bisect, compare, map, markdown, summary_lines, Cell, Convention, MapSpec, PUSH_S,
    QUICK_DIRECTIONS, QUICK_PHASES,
};
use host_sim::physics::PhysicsConfig;
use host_sim::robot::Robot;
use serde_json::Value;

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("push-map-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn quick_map_keeps_its_contract() {
    if !engine_here("quick_map_keeps_its_contract") {
        return;
    }
    // The quick map's two phases, two of its directions (half its engine runs).
    const DIRECTIONS: [f64; 2] = [0.0, 180.0];
    assert!(DIRECTIONS.iter().all(|d| QUICK_DIRECTIONS.contains(d)));
    let out = out_dir("quick");
    let status = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["push-map", "--quick", "--directions", "0,180", "--out"])
        .arg(&out)
        .status()
        .expect("host-sim runs");
    assert!(status.success());
    let j: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("push_map.json")).unwrap()).unwrap();
    let robot = Robot::hrp2();
    let model = PhysicsConfig::for_robot(&robot).robot;
    let (m, g) = (model.total_mass(), model.gravity());
    assert_eq!(j["robot"].as_str(), Some(robot.name()));
    assert!((j["mass_kg"].as_f64().unwrap() - m).abs() < 1e-9);
    assert_eq!(j["push_duration_s"].as_f64(), Some(PUSH_S));
    for config in ["stabilizer_only", "plain", "proposed"] {
        let cells = j["configs"][config].as_array().expect(config);
        assert_eq!(
            cells.len(),
            QUICK_PHASES.len() * DIRECTIONS.len(),
            "{config}"
        );
        for p in QUICK_PHASES {
            for d in DIRECTIONS {
                let c = cells
                    .iter()
                    .find(|c| c["phase"] == p.name() && c["direction_deg"].as_f64() == Some(d))
                    .unwrap_or_else(|| panic!("{config}: no cell {} {d}", p.name()));
                let f = c["max_force_n"].as_f64().unwrap();
                let dv = c["dv_mps"].as_f64().unwrap();
                let bw = c["bw_fraction"].as_f64().unwrap();
                assert!((0.0..=m * g).contains(&f), "{c}");
                assert!((dv - f * PUSH_S / m).abs() < 1e-9, "{c}");
                assert!((bw - f / (m * g)).abs() < 1e-9, "{c}");
                let impulse = c["impulse_ns"].as_f64().unwrap();
                assert!((impulse - f * PUSH_S).abs() < 1e-9, "{c}");
                let adjusted = c["steps_adjusted"].as_u64().unwrap();
                if config == "stabilizer_only" {
                    assert_eq!(adjusted, 0, "{c}");
                }
            }
        }
    }
    for p in QUICK_PHASES {
        let png = out.join(format!("push_map_{}.png", p.name()));
        let bytes = std::fs::read(&png).unwrap_or_else(|_| panic!("{}", png.display()));
        assert_eq!(&bytes[1..4], b"PNG");
    }
    assert!(out.join("push_map.md").exists());
    // One cell in a process of its own (`--cell`): one JSON line, the map's cell.
    let one = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["push-map", "--quick", "--cell", "stabilizer_only,double,0"])
        .output()
        .expect("host-sim runs");
    assert!(
        one.status.success(),
        "{}",
        String::from_utf8_lossy(&one.stderr)
    );
    let text = String::from_utf8_lossy(&one.stdout);
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{text}");
    let line: Value = serde_json::from_str(lines[0]).expect("one JSON line");
    let in_map = j["configs"]["stabilizer_only"]
        .as_array()
        .and_then(|cells| {
            cells
                .iter()
                .find(|c| c["phase"] == "double" && c["direction_deg"].as_f64() == Some(0.0))
        })
        .expect("the map's cell");
    assert_eq!(line["config"].as_str(), Some("stabilizer_only"));
    assert_eq!(line["robot"].as_str(), Some(robot.name()));
    assert!(
        line["engine_runs"].as_u64().is_some_and(|n| n > 0),
        "{line}"
    );
    for key in ["max_force_n", "impulse_ns", "dv_mps", "bw_fraction"] {
        assert_eq!(line[key], in_map[key], "{key}: {line} against {in_map}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The bisection's answer for one cell holds when run again: its force is walked through and
/// one resolution step more is not.
#[test]
fn a_cells_force_is_walked_through_and_one_step_more_is_not() {
    if !engine_here("a_cells_force_is_walked_through_and_one_step_more_is_not") {
        return;
    }
    let robot = Robot::hrp2();
    let cfg = PhysicsConfig::for_robot(&robot);
    let node = robot.node_config();
    let res = 0.125;
    let phase = PushPhase::SingleMiddle;
    let cell = bisect(
        &node,
        &cfg,
        Stepping::Fixed,
        phase,
        90.0,
        res,
        Convention::Force,
    )
    .unwrap();
    let weight = cfg.robot.total_mass() * cfg.robot.gravity();
    let push = |bw: f64| PushSpec {
        phase,
        direction_deg: 90.0,
        kind: PushKind::Force {
            force_n: bw * weight,
            duration_s: PUSH_S,
        },
    };
    let walked = run(
        &node,
        &cfg,
        Walk::default(),
        Stepping::Fixed,
        Some(push(cell.bw_fraction)),
    );
    assert!(!walked.unwrap().fell, "{cell:?}");
    // The bisection's upper bound: the midpoint above the answer fell.
    let above = run(
        &node,
        &cfg,
        Walk::default(),
        Stepping::Fixed,
        Some(push(cell.bw_fraction + res)),
    )
    .unwrap();
    assert!(above.fell, "{cell:?}: {above:?}");
}

/// Without a push nothing moves and nothing falls; with a push and `StartAdjusting` every
/// landing is the commanded position plus a shift the node published, whether the capture
/// step is re-planned from the reference's state (the default) or from the measured one.
#[test]
fn the_closed_loop_lands_where_adjust_says() {
    if !engine_here("the_closed_loop_lands_where_adjust_says") {
        return;
    }
    let robot = Robot::hrp2();
    let cfg = PhysicsConfig::for_robot(&robot);
    let node = robot.node_config();
    for s in Stepping::ALL {
        let o = run(&node, &cfg, Walk::default(), s, None).unwrap();
        assert!(!o.fell, "{s:?}: {o:?}");
        // The walk is run until the node stands, and the tail after it.
        let stood = o.stood_s.expect("the node stood again");
        assert!(!o.fell_after_end, "{s:?}: {o:?}");
        assert!(
            (o.simulated_s - stood - cfg.tail_s).abs() < 0.011,
            "{s:?}: {o:?}"
        );
        assert_eq!(o.steps_adjusted, 0, "{s:?}");
        assert_eq!(
            o.landings.len(),
            usize::from(Walk::default().steps),
            "{s:?}"
        );
    }
    let push = PushSpec {
        phase: PushPhase::SingleMiddle,
        direction_deg: 0.0,
        kind: PushKind::Force {
            force_n: 0.3 * cfg.robot.total_mass() * cfg.robot.gravity(),
            duration_s: PUSH_S,
        },
    };
    // The node's default, and capture steps re-planned from the measured state.
    let mut measured = node;
    measured.adjust.from_measured = true;
    for (node, from_measured) in [(node, false), (measured, true)] {
        let o = run(&node, &cfg, Walk::default(), Stepping::Plain, Some(push)).unwrap();
        assert!(o.pushed);
        assert!(o.steps_adjusted > 0, "{o:?}");
        assert_eq!(o.replans_from_measured > 0, from_measured, "{o:?}");
        for (t, commanded, landed) in &o.landings {
            let ok = std::iter::once([0.0, 0.0])
                .chain(o.adjusts.iter().map(|a| a.shift_si()))
                .any(|s| {
                    (commanded[0] + s[0] - landed[0]).abs() < 1e-9
                        && (commanded[1] + s[1] - landed[1]).abs() < 1e-9
                });
            assert!(ok, "landing at {t} s: {commanded:?} → {landed:?}");
        }
    }
}

/// A full map of HRP-2 (`WALK_LONG=1`, the engine here; else `None`, with a message), capture
/// steps re-planned from the measured state or not, with the book and the front page (its
/// prose wraps anywhere: its whitespace collapsed to single spaces).
fn full_map(test: &str, from_measured: bool) -> Option<(MapSpec, Vec<Cell>, String, String)> {
    if std::env::var("WALK_LONG").as_deref() != Ok("1") {
        eprintln!("push_map: {test} runs with WALK_LONG=1");
        return None;
    }
    if !engine_here(test) {
        return None;
    }
    let robot = Robot::hrp2();
    let cfg = PhysicsConfig::for_robot(&robot);
    let spec = MapSpec::new(false);
    let mut node = robot.node_config();
    node.adjust.from_measured = from_measured;
    let cells = map(&node, &cfg, &spec);
    assert!(cells.iter().all(|c| c.ok()), "failed cells: {cells:?}");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let book = std::fs::read_to_string(root.join("docs/src/adjust.md")).unwrap();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let readme = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    Some((spec, cells, book, readme))
}

/// The full map, as the book and the front page quote it (`WALK_LONG=1`; about 9 minutes of a
/// release build on 2 cores).
#[test]
fn the_full_map_is_the_books() {
    let Some((spec, cells, book, readme)) = full_map("the_full_map_is_the_books", false) else {
        return;
    };
    let table = markdown(&spec, &cells);
    let sums = summary_lines(&spec, &cells);
    eprintln!("{table}\n{sums}");
    for line in table.lines().chain(sums.lines()).filter(|l| !l.is_empty()) {
        assert!(book.contains(line), "docs/src/adjust.md lacks: {line}");
    }
    // The front page: the mean Δv of the three configurations.
    let means: Vec<String> = host_sim::physics::push_map::summary(&spec, &cells)
        .iter()
        .map(|s| format!("{:.3}", s.mean_dv_mps))
        .collect();
    let quoted = format!("mean Δv {} m/s", means.join(" / "));
    assert!(readme.contains(&quoted), "README.md lacks: {quoted}");
    let (larger, smaller, _) = compare(&cells, Stepping::Proposed, Stepping::Plain);
    let noun = |n: usize| if n == 1 { "cell" } else { "cells" };
    let quoted = format!(
        "better than the plain re-plan in {larger} {}, worse in {smaller}",
        noun(larger)
    );
    assert!(readme.contains(&quoted), "README.md lacks: {quoted}");
    let raised: Vec<String> = host_sim::physics::push_map::summary(&spec, &cells)
        .iter()
        .skip(1)
        .map(|s| s.raised.to_string())
        .collect();
    let quoted = format!("adjustment raises it in {} of 32 cells", raised.join(" / "));
    assert!(readme.contains(&quoted), "README.md lacks: {quoted}");
}

/// The full map with capture steps re-planned from the measured state
/// (`push-map --replan-from measured`, `WALK_LONG=1`; about 9 minutes), against its summary in
/// the book and the front page's sentence on it.
#[test]
fn the_measured_start_map_is_the_books() {
    let Some((spec, cells, book, readme)) = full_map("the_measured_start_map_is_the_books", true)
    else {
        return;
    };
    let sums = summary_lines(&spec, &cells);
    eprintln!("{sums}");
    for line in sums.lines().filter(|l| !l.is_empty()) {
        assert!(book.contains(line), "docs/src/adjust.md lacks: {line}");
    }
    let means: Vec<String> = host_sim::physics::push_map::summary(&spec, &cells)
        .iter()
        .skip(1)
        .map(|s| format!("{:.3}", s.mean_dv_mps))
        .collect();
    let quoted = format!("from the measured state, mean Δv {} m/s", means.join(" / "));
    assert!(readme.contains(&quoted), "README.md lacks: {quoted}");
}

/// A cell that cannot be measured is written as failed with its cause: it is left out of the
/// summary and the comparison (not counted as a zero), and the table names the cause.
#[test]
fn a_failed_cell_is_reported_not_counted() {
    let spec = MapSpec {
        phases: vec![PushPhase::Double],
        directions: vec![0.0, 90.0],
        resolution_bw: 0.125,
        steppings: Stepping::ALL.to_vec(),
        threads: 1,
        convention: Convention::Force,
        scan: false,
    };
    let ok = |s: Stepping, d: f64, bw: f64| Cell {
        stepping: s,
        phase: PushPhase::Double,
        direction_deg: d,
        convention: Convention::Force,
        max_force_n: bw * 1000.0,
        dv_mps: bw,
        bw_fraction: bw,
        steps_adjusted: 0,
        runs: 3,
        gait: Default::default(),
        error: None,
        scan: None,
    };
    let cause = "left ankle out of reach: 0.6980 m, reach 0.6983 m";
    let cells = vec![
        ok(Stepping::Fixed, 0.0, 0.25),
        ok(Stepping::Fixed, 90.0, 0.25),
        ok(Stepping::Plain, 0.0, 0.5),
        Cell::failed(Stepping::Plain, PushPhase::Double, 90.0, cause.into()),
        ok(Stepping::Proposed, 0.0, 0.125),
        ok(Stepping::Proposed, 90.0, 0.5),
    ];
    let sums = summary_lines(&spec, &cells);
    assert!(
        sums.contains("plain: mean Δv 0.500 m/s; larger than the stabilizer only in 1 of 1 cells, smaller in 0"),
        "{sums}"
    );
    assert!(
        sums.contains("proposed against plain: larger in 0 of 1 cells, smaller in 1"),
        "{sums}"
    );
    let md = markdown(&spec, &cells);
    assert!(md.contains(&format!("failed: {cause}")), "{md}");
    let j = host_sim::physics::push_map::map_json("test", 100.0, &spec, &cells);
    let plain = j["configs"]["plain"].as_array().unwrap();
    assert_eq!(plain[1]["error"].as_str(), Some(cause));
    assert!(plain[0].get("error").is_none());
    assert!((plain[0]["impulse_ns"].as_f64().unwrap() - 500.0 * PUSH_S).abs() < 1e-12);
}

/// A map with `--scan`: each cell's sure force and the share survived above it are in the
/// table and the JSON, the summary counts the cells whose survival is not monotonic, and the
/// proposed method is compared with the plain re-plan only beyond the cells' spread.
#[test]
fn a_scanned_map_carries_the_scan_and_compares_beyond_the_spread() {
    use host_sim::physics::push_scan::Scan;
    let spec = MapSpec {
        phases: vec![PushPhase::Double],
        directions: vec![0.0, 90.0],
        resolution_bw: 0.02,
        steppings: Stepping::ALL.to_vec(),
        threads: 1,
        convention: Convention::Force,
        scan: true,
    };
    let cell = |s: Stepping, d: f64, tried: Vec<(f64, bool)>| {
        let scan = Scan::of(tried);
        let bw = scan
            .tried
            .iter()
            .filter(|t| t.1)
            .map(|t| t.0)
            .fold(0.0, f64::max);
        Cell {
            stepping: s,
            phase: PushPhase::Double,
            direction_deg: d,
            convention: Convention::Force,
            max_force_n: bw * 1000.0,
            dv_mps: bw,
            bw_fraction: bw,
            steps_adjusted: 0,
            runs: scan.tried.len(),
            gait: Default::default(),
            error: None,
            scan: Some(scan),
        }
    };
    let cells = vec![
        cell(Stepping::Fixed, 0.0, vec![(0.2, true), (0.3, false)]),
        cell(Stepping::Fixed, 90.0, vec![(0.2, true), (0.3, false)]),
        // Plain at 0°: falls at 0.35, survives 0.40 and 0.45 (a capture step): sure 0.30,
        // spread 0.10; the bisection alone would say 0.45.
        cell(
            Stepping::Plain,
            0.0,
            vec![
                (0.3, true),
                (0.35, false),
                (0.4, true),
                (0.45, true),
                (0.5, false),
            ],
        ),
        cell(Stepping::Plain, 90.0, vec![(0.2, true), (0.25, false)]),
        // Proposed at 0°: sure 0.35, 0.05 above plain's, inside plain's spread: no difference.
        cell(Stepping::Proposed, 0.0, vec![(0.35, true), (0.4, false)]),
        // Proposed at 90°: sure 0.40 against 0.20, beyond both spreads: larger.
        cell(Stepping::Proposed, 90.0, vec![(0.4, true), (0.45, false)]),
    ];
    let md = markdown(&spec, &cells);
    assert!(md.contains("0.450 (0.45; sure 0.30, 50 % above)"), "{md}");
    let sums = summary_lines(&spec, &cells);
    assert!(
        sums.contains(
            "plain (scan): mean sure force 0.250 BW; a push survived above a fall in 1 of 2 cells"
        ),
        "{sums}"
    );
    assert!(
        sums.contains(
            "proposed against plain, sure force beyond the cells' spread: larger in 1 of 2 cells, \
             smaller in 0, within the spread in 1"
        ),
        "{sums}"
    );
    // The bisection's comparison alone counts the 0° cell as worse.
    assert!(
        sums.contains("proposed against plain: larger in 1 of 2 cells, smaller in 1"),
        "{sums}"
    );
    let j = host_sim::physics::push_map::map_json("test", 100.0, &spec, &cells);
    let plain = j["configs"]["plain"].as_array().unwrap();
    assert!((plain[0]["scan"]["sure_bw"].as_f64().unwrap() - 0.3).abs() < 1e-12);
    assert!((plain[0]["scan"]["spread_bw"].as_f64().unwrap() - 0.1).abs() < 1e-12);
}

/// A malformed `push-map --cell` is refused with the expected form (the cell itself is
/// checked against the quick map in `quick_map_keeps_its_contract`).
#[test]
fn a_malformed_cell_is_refused() {
    let bad = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["push-map", "--cell", "proposed,double"])
        .output()
        .expect("host-sim runs");
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("CONFIG,PHASE,DIRECTION"), "{err}");
}

/// The engine's velocity push sets the floating base's horizontal velocity in the world frame:
/// over the next millisecond the base moves by `v dt` in x and y (the floor's friction and the
/// servos change the velocity by far less than `v` within a millisecond).
#[test]
fn a_velocity_push_sets_the_base_velocity() {
    if !engine_here("a_velocity_push_sets_the_base_velocity") {
        return;
    }
    use host_sim::physics::bridge::Engine;
    let robot = Robot::hrp2();
    let cfg = PhysicsConfig::for_robot(&robot);
    let node = planner_core::node::Node::<16>::new(robot.node_config()).unwrap();
    let r0 = *node.gait().last();
    let (_, qpos) = host_sim::physics::initial_pose(&cfg.robot, &r0).unwrap();
    let mut engine = Engine::start(&cfg.robot.mjcf()).unwrap();
    let hold = qpos[7..7 + engine.nu()].to_vec();
    let before = engine.reset(&qpos).unwrap();
    let v = [0.4, -0.3];
    let pushed = engine.set_base_velocity(v).unwrap();
    assert_eq!(
        pushed.base_pos, before.base_pos,
        "a velocity set moves nothing at once"
    );
    // (An observation after a step reads the positions the step started from.)
    let first = engine.step(1, &hold, [0.0; 6]).unwrap();
    let after = engine.step(1, &hold, [0.0; 6]).unwrap();
    let dt = after.time - first.time;
    for (k, v) in v.into_iter().enumerate() {
        let moved = after.base_pos[k] - first.base_pos[k];
        assert!(
            (moved - v * dt).abs() < 0.2 * v.abs() * dt,
            "axis {k}: moved {moved} m in {dt} s, set {v} m/s"
        );
    }
}

/// A velocity push that the stabilizer takes, and one that fells the robot; `--cell` with
/// `--push velocity` gives a velocity cell (`v_mps`, no force fields).
#[test]
fn a_small_velocity_push_is_walked_through_and_a_large_one_fells() {
    if !engine_here("a_small_velocity_push_is_walked_through_and_a_large_one_fells") {
        return;
    }
    let robot = Robot::hrp2();
    let cfg = PhysicsConfig::for_robot(&robot);
    let node = robot.node_config();
    let push = |v_mps: f64| PushSpec {
        phase: PushPhase::Double,
        direction_deg: 90.0,
        kind: PushKind::Velocity { v_mps },
    };
    let small = run(
        &node,
        &cfg,
        Walk::default(),
        Stepping::Fixed,
        Some(push(0.05)),
    )
    .unwrap();
    assert!(small.pushed && !small.fell, "{small:?}");
    let large = run(
        &node,
        &cfg,
        Walk::default(),
        Stepping::Fixed,
        Some(push(1.5)),
    )
    .unwrap();
    assert!(large.pushed && large.fell, "{large:?}");
    let cell = Cell {
        convention: Convention::Velocity,
        dv_mps: 0.25,
        ..Cell::failed(Stepping::Fixed, PushPhase::Double, 90.0, String::new())
    };
    let j = Cell {
        error: None,
        ..cell
    }
    .json();
    assert_eq!(j["push"], "velocity");
    assert_eq!(j["v_mps"], 0.25);
    assert!(
        j.get("max_force_n").is_none() && j.get("impulse_ns").is_none(),
        "{j}"
    );
}

/// The quick map of velocity pushes (`WALK_LONG=1`; 72 engine runs), against its summary in
/// the book (`docs/src/adjust.md`).
#[test]
fn the_quick_velocity_map_is_the_books() {
    if std::env::var("WALK_LONG").as_deref() != Ok("1") {
        eprintln!("push_map: the velocity map runs with WALK_LONG=1");
        return;
    }
    if !engine_here("the_quick_velocity_map_is_the_books") {
        return;
    }
    let robot = Robot::hrp2();
    let cfg = PhysicsConfig::for_robot(&robot);
    let spec = MapSpec {
        convention: Convention::Velocity,
        ..MapSpec::new(true)
    };
    let cells = map(&robot.node_config(), &cfg, &spec);
    engine::map_summary_is_the_books(&spec, &cells);
}
