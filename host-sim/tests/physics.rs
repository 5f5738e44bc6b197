//! The physics engine run (`host-sim physics`, host-sim/src/physics/): the built-in scenarios
//! walk through in MuJoCo under the stabilizer without falling and with the CoP tracking the
//! reference ZMP within stated bounds; a push the stabilizer rejects fells the open-loop
//! playback, and a big push fells both (the fall detector works); the command-line contract
//! of `physics.json`; a missing engine is a clear error.
//!
//! The engine is PyPI's `mujoco` (pinned in `host_sim::physics::bridge::MUJOCO_VERSION`).
//! Without it the engine tests skip and say so, unless `WALK_REQUIRE_MUJOCO=1`
//! (tests/run-all.sh installs it and sets that), which makes a missing engine a failure.
//!
//! The figures the book (docs/src/physics.md) and the front page quote from these runs are
//! checked against the measured ones ([`doc_figures`]): the table of the built-in
//! scenarios (its open-loop column under `WALK_LONG=1`), the headline row, the pushes, the
//! second robot and the deterministic columns of the run-time table (engine runs, simulated
//! seconds; never the wall-clock times). MuJoCo's results are bit-stable from run to run on
//! one machine, so the figures are compared as written (rounded as the document rounds them).

use std::path::PathBuf;
use std::process::Command;

mod engine;

use doc_figures::Quotes;
use engine::engine_here;

use host_sim::physics::bridge::{installed_version, python, Engine};
use host_sim::physics::metrics::FallCause;
use host_sim::physics::{run, PhysicsConfig, PhysicsReport, Push};
use host_sim::robot::Robot;
use host_sim::scenario::BUILT_IN;
use host_sim::sim::scenario_trajectory;

/// Bounds the stabilized walks must meet (the 50 ms-filtered CoP against the reference ZMP;
/// measured: means 7–10 mm, worst 34–42 mm).
const COP_MEAN_BOUND_M: f64 = 0.015;
const COP_MAX_BOUND_M: f64 = 0.060;
const TILT_BOUND_DEG: f64 = 2.0;

/// The command that measures the figures the documents quote from the default tests.
const COMMAND: &str = "cargo test --release -p host-sim --test physics -- --nocapture";
/// The same with the long runs ([`long_runs`]).
const LONG_COMMAND: &str =
    "WALK_LONG=1 cargo test --release -p host-sim --test physics -- --nocapture";
/// The book's page on the engine runs.
const BOOK: &str = "docs/src/physics.md";
/// The heading of its run-time table's column of simulated seconds (the settle, the
/// trajectory and the tail: what the engine steps through).
const SIMULATED: &str = "simulated (settle 1 s + walk + tail 1 s)";

/// `m` metres in millimetres as the book writes them: `3.4 mm`.
fn mm(m: f64) -> String {
    format!("{:.1} mm", m * 1e3)
}

/// A mean and a worst in millimetres: `9.8 / 36.3 mm`.
fn mm_pair(mean_m: f64, worst_m: f64) -> String {
    format!("{:.1} / {:.1} mm", mean_m * 1e3, worst_m * 1e3)
}

/// `yes` or `no`.
fn yes_no(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

/// What the engine steps through for a run that reports `simulated_s` (trajectory time at
/// its end: the trajectory and the tail) [s]: the settle before it too.
fn engine_seconds(simulated_s: f64) -> f64 {
    PhysicsConfig::default().settle_s + simulated_s
}

fn report(scenario: &str, cfg: &PhysicsConfig) -> PhysicsReport {
    let (_, trajectory, dt) = scenario_trajectory(scenario, &Robot::hrp2()).expect("scenario");
    run(&trajectory, dt, cfg).expect("engine run").report
}

/// The figures of a run that the book's table of the built-in scenarios quotes (from a
/// [`PhysicsReport`] or from the `physics.json` it was written to).
#[derive(Clone, Copy, Debug)]
struct Walk {
    fell: bool,
    fall_time_s: Option<f64>,
    max_tilt_deg: f64,
    cop_err_mean_m: f64,
    cop_err_max_m: f64,
    cog_drift_max_m: f64,
    foot_drift_max_m: f64,
    simulated_s: f64,
    walked: bool,
    slip_max_m: f64,
    landing_err_max_m: f64,
}

impl Walk {
    fn of(r: &PhysicsReport) -> Self {
        Walk {
            fell: r.fell,
            fall_time_s: r.fall_time_s,
            max_tilt_deg: r.max_tilt_deg,
            cop_err_mean_m: r.cop_err_mean_m,
            cop_err_max_m: r.cop_err_max_m,
            cog_drift_max_m: r.cog_drift_max_m,
            foot_drift_max_m: r.foot_drift_max_m,
            simulated_s: r.simulated_s,
            walked: r.walked(),
            slip_max_m: r.gait.slip_max_m,
            landing_err_max_m: r.gait.landing_err_max_m,
        }
    }

    fn from_json(j: &serde_json::Value) -> Self {
        let num = |k: &str| j[k].as_f64().unwrap_or_else(|| panic!("{k} in {j}"));
        Walk {
            fell: j["fell"].as_bool().unwrap_or_else(|| panic!("fell in {j}")),
            fall_time_s: j["fall_time_s"].as_f64(),
            max_tilt_deg: num("max_tilt_deg"),
            cop_err_mean_m: num("cop_err_mean_m"),
            cop_err_max_m: num("cop_err_max_m"),
            cog_drift_max_m: num("cog_drift_max_m"),
            foot_drift_max_m: num("foot_drift_max_m"),
            simulated_s: num("simulated_s"),
            walked: j["walked"]
                .as_bool()
                .unwrap_or_else(|| panic!("walked in {j}")),
            slip_max_m: num("slip_max_m"),
            landing_err_max_m: num("landing_err_max_m"),
        }
    }
}

fn assert_walked(name: &str, r: &Walk) {
    assert!(!r.fell, "{name}: fell at {:?} s: {r:?}", r.fall_time_s);
    assert!(r.max_tilt_deg < TILT_BOUND_DEG, "{name}: tilt {r:?}");
    assert!(r.cop_err_mean_m < COP_MEAN_BOUND_M, "{name}: {r:?}");
    assert!(r.cop_err_max_m < COP_MAX_BOUND_M, "{name}: {r:?}");
    assert!(r.foot_drift_max_m < 0.02, "{name}: the feet slid: {r:?}");
    assert!(r.walked, "{name}: a gait measure beyond its bound: {r:?}");
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-physics-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The built-in scenarios under the stabilizer, run once for the tests that read them:
/// `straight` through the command line (`host-sim physics straight --out DIR`), the others
/// through [`run`] with the default configuration (HRP-2's; the book's table was made with
/// `host-sim physics NAME`, which gives the same figures). `None` without the engine.
struct BuiltInWalks {
    /// `straight`'s `DIR/physics.json`.
    straight_json: String,
    /// The files `host-sim physics straight` wrote into DIR.
    straight_files: Vec<String>,
    /// What it printed.
    straight_stdout: String,
    /// Every built-in scenario in [`BUILT_IN`]'s order (`straight` from its `physics.json`).
    walks: Vec<(&'static str, Walk)>,
}

fn built_in_walks() -> Option<&'static BuiltInWalks> {
    static WALKS: std::sync::OnceLock<Option<BuiltInWalks>> = std::sync::OnceLock::new();
    WALKS
        .get_or_init(|| {
            if !engine_here("the built-in scenarios under the stabilizer") {
                return None;
            }
            let dir = temp_dir("straight");
            let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
                .args(["physics", "straight", "--out"])
                .arg(&dir)
                .output()
                .expect("host-sim runs");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let straight_json =
                std::fs::read_to_string(dir.join("physics.json")).expect("physics.json");
            let mut straight_files: Vec<String> = std::fs::read_dir(&dir)
                .expect("the output directory")
                .map(|e| {
                    e.expect("an entry")
                        .file_name()
                        .to_string_lossy()
                        .into_owned()
                })
                .collect();
            straight_files.sort();
            let straight_stdout = String::from_utf8_lossy(&out.stdout).into_owned();
            let _ = std::fs::remove_dir_all(&dir);
            let j: serde_json::Value = serde_json::from_str(&straight_json).expect("JSON");
            let walks = BUILT_IN
                .iter()
                .map(|&name| {
                    let w = if name == "straight" {
                        Walk::from_json(&j)
                    } else {
                        Walk::of(&report(name, &PhysicsConfig::default()))
                    };
                    (name, w)
                })
                .collect();
            Some(BuiltInWalks {
                straight_json,
                straight_files,
                straight_stdout,
                walks,
            })
        })
        .as_ref()
}

/// The contract: `host-sim physics straight --out DIR` writes DIR/physics.json with the
/// figures, and the straight walk does not fall.
#[test]
fn straight_walks_through_the_command_line_contract() {
    let Some(b) = built_in_walks() else { return };
    let text = &b.straight_json;
    let j: serde_json::Value = serde_json::from_str(text).expect("JSON");
    assert_eq!(j["fell"], serde_json::Value::Bool(false), "{text}");
    assert!(j["fall_time_s"].is_null(), "{text}");
    let num = |k: &str| j[k].as_f64().unwrap_or_else(|| panic!("{k} in {text}"));
    assert!(num("max_tilt_deg") < TILT_BOUND_DEG, "{text}");
    assert!(num("cop_err_mean_m") < COP_MEAN_BOUND_M, "{text}");
    assert!(num("cop_err_max_m") < COP_MAX_BOUND_M, "{text}");
    assert!(num("cop_err_mean_m") > 0.0 && num("cop_err_max_m") >= num("cop_err_mean_m"));
    // The whole walk was simulated (10 steps of 0.8 s and the stop).
    assert!(num("simulated_s") > 9.0, "{text}");
    // The probe settings (the defaults: the robot as stated).
    assert_eq!(j["stabilizer"], true, "{text}");
    assert_eq!(num("stabilizer_scale"), 1.0, "{text}");
    assert_eq!(num("servo_damping"), 600.0, "{text}");
    for f in [
        "physics.csv",
        "physics_tilt.png",
        "physics_cop_x.png",
        "physics_cop_y.png",
    ] {
        assert!(
            b.straight_files.iter().any(|g| g == f),
            "{f} missing: {:?}",
            b.straight_files
        );
    }
    // It prints the seconds the book's run-time table quotes (with the settle) beside the
    // walk's own.
    let engine = engine_seconds(num("simulated_s"));
    assert!(
        b.straight_stdout
            .contains(&format!("{engine:.2} s in the engine with the 1 s settle")),
        "{}",
        b.straight_stdout
    );
    // It names every file it wrote.
    let results = b
        .straight_stdout
        .lines()
        .find(|l| l.contains("results"))
        .unwrap_or_else(|| panic!("no results line: {}", b.straight_stdout));
    for f in &b.straight_files {
        assert!(results.contains(f.as_str()), "{f} not named: {results}");
    }
}

/// Every other built-in scenario walks through too.
#[test]
fn other_built_in_scenarios_walk_through() {
    let Some(b) = built_in_walks() else { return };
    for (name, w) in b.walks.iter().filter(|(n, _)| *n != "straight") {
        assert_walked(name, w);
    }
}

/// The book's table of the built-in scenarios under the stabilizer quotes every one as
/// measured (fell, max tilt, CoP error mean / worst, COG drift, foot drift; the open-loop
/// column: [`built_in_scenarios_open_loop_long`]), as do its sentence above the table and the
/// front page's headline row (the falls and the largest tilt over all of them), and the
/// run-time table's `physics straight` row and `fig4`'s length (simulated seconds: the
/// trajectories, the same on every machine; the wall-clock times are not checked).
#[test]
fn the_documents_quote_the_built_in_scenarios_as_measured() {
    let Some(b) = built_in_walks() else { return };
    assert_eq!(b.walks.len(), BUILT_IN.len());
    let mut q = Quotes::new(COMMAND);
    for (name, w) in &b.walks {
        let row = format!("| {name} |");
        // Each figure as it rounds, or as it would round 0.002 mm (0.0002°) away: a value on a
        // rounding boundary may round either way on another CPU.
        let (dm, dd) = (2e-6, 2e-4);
        let around = |v: f64, d: f64| [v, v - d, v + d];
        let spell = |f: &dyn Fn(f64) -> String, v: f64, d: f64| -> Vec<String> {
            let mut out: Vec<String> = around(v, d).iter().map(|&x| f(x)).collect();
            out.dedup();
            out
        };
        let mut pairs = Vec::new();
        for a in around(w.cop_err_mean_m, dm) {
            for b in around(w.cop_err_max_m, dm) {
                let p = mm_pair(a, b);
                if !pairs.contains(&p) {
                    pairs.push(p);
                }
            }
        }
        q = q
            .cell(BOOK, &row, "fell", yes_no(w.fell))
            .cell_any(
                BOOK,
                &row,
                "max tilt",
                &spell(&|x| format!("{x:.2}°"), w.max_tilt_deg, dd),
            )
            .cell_any(BOOK, &row, "CoP error mean / worst", &pairs)
            .cell_any(
                BOOK,
                &row,
                "COG drift",
                &spell(&|x| mm(x), w.cog_drift_max_m, dm),
            )
            .cell_any(
                BOOK,
                &row,
                "foot drift",
                &spell(&|x| mm(x), w.foot_drift_max_m, dm),
            )
            .cell(BOOK, &row, "walked", yes_no(w.walked))
            .cell_any(
                BOOK,
                &row,
                "slip / landing error",
                &spell(
                    &|x| format!("{:.1} / {}", x * 1e3, mm(w.landing_err_max_m)),
                    w.slip_max_m,
                    dm,
                ),
            );
    }
    let falls = b.walks.iter().filter(|(_, w)| w.fell).count();
    let walked = b.walks.iter().filter(|(_, w)| w.walked).count();
    let tilt = b
        .walks
        .iter()
        .map(|(_, w)| w.max_tilt_deg)
        .fold(0.0, f64::max);
    let walk = |name: &str| b.walks.iter().find(|(n, _)| *n == name).expect(name).1;
    q.line(
        BOOK,
        "Every built-in scenario walks through with",
        &format!("{falls} falls"),
    )
    .cell(
        "README.md",
        "| the built-in scenarios in MuJoCo under the stabilizer |",
        "figure",
        &format!(
            "{walked} of {} walked (no fall; slip, flight, CoP and landings within bounds), \
             tilt at most {tilt:.2}°",
            b.walks.len()
        ),
    )
    .cell(BOOK, "`physics straight --out out/t`", "engine runs", "1")
    .cell(
        BOOK,
        "`physics straight --out out/t`",
        SIMULATED,
        &format!("{:.1} s", engine_seconds(walk("straight").simulated_s)),
    )
    .line(
        BOOK,
        "(The fig4 length:",
        &format!("{:.2} s", walk("fig4").simulated_s),
    )
    .assert();
}

/// `WALK_LONG=1`: every built-in scenario played open loop (`host-sim physics NAME
/// --open-loop`: the stabilizer off) is quoted as measured in the book's table (its last
/// column: the CoP error mean / worst and whether it fell).
#[test]
fn built_in_scenarios_open_loop_long() {
    if !long_runs("built_in_scenarios_open_loop_long") {
        return;
    }
    let mut cfg = PhysicsConfig::default();
    cfg.gains.enabled = false;
    let mut q = Quotes::new(LONG_COMMAND);
    for name in BUILT_IN {
        let r = report(name, &cfg);
        let fell = match r.fall_time_s {
            Some(t) => format!("fell at {t:.2} s"),
            None => "no fall".into(),
        };
        q = q.cell(
            BOOK,
            &format!("| {name} |"),
            "open loop: CoP mean / worst",
            &format!("{} ({fell})", mm_pair(r.cop_err_mean_m, r.cop_err_max_m)),
        );
    }
    q.assert();
}

/// A 150 N push for 0.1 s (15 N s) forward on the trunk in single support: the stabilizer
/// keeps walking, the same pattern played open loop falls over (the book quotes the
/// stabilized worst CoP error and the open-loop fall).
#[test]
fn the_stabilizer_rejects_a_push_that_fells_open_loop_playback() {
    if !engine_here("the_stabilizer_rejects_a_push_that_fells_open_loop_playback") {
        return;
    }
    let push = Push {
        t_s: 3.0,
        duration_s: 0.1,
        force: [150.0, 0.0],
    };
    let mut cfg = PhysicsConfig {
        push: Some(push),
        ..PhysicsConfig::default()
    };
    let stabilized = report("straight", &cfg);
    assert!(!stabilized.fell, "{stabilized:?}");
    cfg.gains.enabled = false;
    let open = report("straight", &cfg);
    assert!(open.fell, "{open:?}");
    let t = open.fall_time_s.expect("a fall time");
    assert!(t > push.t_s, "fell before the push: {open:?}");
    assert_eq!(open.fall_cause, Some(FallCause::Tilt));
    assert!(open.max_tilt_deg > 20.0);
    Quotes::new(COMMAND)
        .line(
            BOOK,
            "separates the two: the stabilizer recovers",
            &format!(
                "worst {:.0} mm at the push, {}",
                stabilized.cop_err_max_m * 1e3,
                if stabilized.fell { "fell" } else { "no fall" }
            ),
        )
        .line(
            BOOK,
            "450 N sideways fells both",
            &format!("falls at {t:.2} s (tilt)"),
        )
        .assert();
}

/// A 450 N push sideways for 0.1 s fells the robot even with the stabilizer, soon after it.
#[test]
fn a_big_push_fells_the_robot() {
    if !engine_here("a_big_push_fells_the_robot") {
        return;
    }
    let cfg = PhysicsConfig {
        push: Some(Push {
            t_s: 3.0,
            duration_s: 0.1,
            force: [0.0, 450.0],
        }),
        ..PhysicsConfig::default()
    };
    let r = report("straight", &cfg);
    assert!(r.fell, "{r:?}");
    let t = r.fall_time_s.expect("a fall time");
    assert!(t > 3.0 && t < 4.5, "{r:?}");
    // The run stops at the fall.
    assert!((r.simulated_s - t).abs() < 1e-9, "{r:?}");
}

/// Without the engine the bridge fails with a message naming what to install.
#[test]
fn a_missing_engine_is_a_clear_error() {
    let xml = host_sim::physics::model::Robot::default().mjcf();
    let e = Engine::start_with("/nonexistent/python3", &xml)
        .err()
        .expect("no interpreter there");
    assert!(e.contains("pip install mujoco==3.2.7"), "{e}");
    // An interpreter that runs but has no MuJoCo: `false` exits at once.
    let e = Engine::start_with("false", &xml).err().expect("no engine");
    assert!(e.contains("pip install mujoco==3.2.7"), "{e}");
    let e = installed_version("/nonexistent/python3").expect_err("no interpreter");
    assert!(e.contains("mujoco==3.2.7"), "{e}");
}

/// The engine rejects a broken model with its own message (not a hang or a panic).
#[test]
fn a_rejected_model_is_an_error() {
    if !engine_here("a_rejected_model_is_an_error") {
        return;
    }
    let e = Engine::start_with(&python(), "<mujoco><worldbody><body>")
        .err()
        .expect("rejected");
    assert!(e.starts_with("MuJoCo: MJCF rejected"), "{e}");
}

/// The reduced grid of CI, run once for the tests that read it: `host-sim physics-tables
/// --cells '5,1;1,5'` (0.2 m backward steps, the step in flight changed to 0.2 m forward, and
/// the mirror cell; the plain re-plan's kinematic error is above the paper's 0.07 m in both,
/// the proposed method's below). `None` without the engine.
fn reduced_grid() -> Option<&'static serde_json::Value> {
    static GRID: std::sync::OnceLock<Option<serde_json::Value>> = std::sync::OnceLock::new();
    GRID.get_or_init(|| {
        if !engine_here("the reduced physics-tables grid") {
            return None;
        }
        let dir = temp_dir("tables");
        let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(["physics-tables", "--cells", "5,1;1,5", "--out"])
            .arg(&dir)
            .output()
            .expect("host-sim runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(dir.join("physics_tables.json")).expect("json");
        let _ = std::fs::remove_dir_all(&dir);
        Some(serde_json::from_str(&text).expect("JSON"))
    })
    .as_ref()
}

const REDUCED: [(usize, usize); 2] = [(5, 1), (1, 5)];

/// `physics_tables.json` of the reduced grid: 7 × 7 `fell_plain` / `fell_proposed` with these
/// cells filled in, the others null; under the stabilizer neither falls, and both walk
/// (`walked_plain` / `walked_proposed`).
#[test]
fn physics_tables_reduced_grid() {
    let Some(j) = reduced_grid() else { return };
    let text = j.to_string();
    for key in ["fell_plain", "fell_proposed"] {
        let g = j[key].as_array().expect(key);
        assert_eq!(g.len(), 7);
        for (r, row) in g.iter().enumerate() {
            let row = row.as_array().expect("row");
            assert_eq!(row.len(), 7);
            for (c, v) in row.iter().enumerate() {
                if REDUCED.contains(&(r, c)) {
                    assert_eq!(v, &serde_json::Value::Bool(false), "{key}: {text}");
                } else {
                    assert!(v.is_null(), "{key}[{r}][{c}] = {v}");
                }
            }
        }
    }
    // Both walk by the verdict (no fall; slip, flight, CoP and landings within bounds).
    for key in ["walked_plain", "walked_proposed"] {
        for (r, c) in REDUCED {
            assert_eq!(j[key][r][c], serde_json::Value::Bool(true), "{key}: {text}");
        }
        assert!(j[key][0][0].is_null(), "{key}: {text}");
    }
    for (r, c) in REDUCED {
        let mb_plain = j["mb_zmp_error_plain_m"][r][c].as_f64().expect("mb plain");
        let mb_prop = j["mb_zmp_error_proposed_m"][r][c]
            .as_f64()
            .expect("mb proposed");
        assert!(mb_plain > 0.07 && mb_prop < 0.07, "({r}, {c}): {text}");
        for key in ["cop_err_modified_plain_m", "cop_err_modified_proposed_m"] {
            let e = j[key][r][c].as_f64().expect(key);
            assert!(e > 0.0 && e < 0.2, "{key}: {text}");
        }
    }
    assert_eq!(j["stabilizer_scale"], 1.0);
    assert_eq!(j["servo_damping"], 600.0);
}

/// `physics_tables.json` is in the order of `tables.json` (`host-sim tables`): the same step
/// lengths, rows "after" and columns "before", and each simulated cell's kinematic multi-body
/// error is `tables.json`'s for that cell (plain re-plan: Table I's `max_zmp_error_without_m`,
/// proposed: Table II's `max_zmp_error_with_m`). The reduced grid's two cells are each
/// other's mirror with different errors, so a transposed grid fails. The book's run-time
/// table quotes the full grid's engine runs (a run for every cell and pattern the legs reach
/// in `tables.json`: [`physics_tables_full_grid_long`] checks that those are the ones run)
/// and their simulated seconds (the trajectories' lengths).
#[test]
fn physics_tables_follow_tables_json() {
    let Some(p) = reduced_grid() else { return };
    let dir = temp_dir("kinematic-tables");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["tables", "--out"])
        .arg(&dir)
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("tables.json")).expect("tables.json");
    let t: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let _ = std::fs::remove_dir_all(&dir);
    for key in ["step_lengths_m", "rows", "columns"] {
        assert_eq!(p[key], t[key], "{key}");
    }
    for (physics, kinematic) in [
        ("mb_zmp_error_plain_m", "max_zmp_error_without_m"),
        ("mb_zmp_error_proposed_m", "max_zmp_error_with_m"),
    ] {
        for (r, c) in REDUCED {
            let a = p[physics][r][c].as_f64().expect(physics);
            let b = t[kinematic][r][c].as_f64().expect(kinematic);
            assert_eq!(a, b, "{physics} vs {kinematic} at ({r}, {c})");
            // The mirror cell differs: the comparison would catch a transposition.
            let m = t[kinematic][c][r].as_f64().expect(kinematic);
            assert!((a - m).abs() > 1e-4, "({r}, {c}) and its mirror: {a} {m}");
        }
    }
    use host_sim::eval::paper::{modification, plain_params, STEP_LENGTHS};
    let params = Robot::hrp2().planner.params;
    let n = STEP_LENGTHS.len();
    // The trajectory of each cell and pattern the legs reach: its walk [s] and the single
    // support's adjustment in it.
    let (mut asked, mut walks) = (0, vec![]);
    for (kinematic, params) in [
        ("max_zmp_error_without_m", plain_params(params)),
        ("max_zmp_error_with_m", params),
    ] {
        for r in 0..n {
            for c in 0..n {
                asked += 1;
                if t[kinematic][r][c].is_f64() {
                    let m = modification(params, STEP_LENGTHS[c], STEP_LENGTHS[r]);
                    walks.push(((m.trajectory.len() - 1) as f64 * params.dt, m.adjust_s));
                }
            }
        }
    }
    let runs = walks.len();
    // The scenario's timing: the walk less the adjustment, the same in every cell.
    let unadjusted = walks[0].0 - walks[0].1;
    for (walk, adjust) in &walks {
        assert!((walk - adjust - unadjusted).abs() < 1e-9, "{walks:?}");
    }
    let seconds = |walk: f64| engine_seconds(walk + PhysicsConfig::default().tail_s);
    let (lo, hi) = walks.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), w| {
        (lo.min(seconds(w.0)), hi.max(seconds(w.0)))
    });
    let row = "`physics-tables --out out/t` (full grid)";
    Quotes::new(COMMAND)
        .line(
            BOOK,
            "physics-tables --out out/physics_tables ",
            &format!("{runs} engine runs"),
        )
        .cell(
            BOOK,
            row,
            "engine runs",
            &format!("{runs} ({asked} asked, {} out of reach)", asked - runs),
        )
        .cell(
            BOOK,
            row,
            SIMULATED,
            &format!("{lo:.1}–{hi:.1} s each ({unadjusted:.1} s ± the adjustment"),
        )
        .line(
            "host-sim/src/main.rs",
            "The cells to run: `all`",
            &format!(
                "{asked} runs asked, {runs} in the engine, {} out",
                asked - runs
            ),
        )
        .assert();
}

/// `host-sim physics-faults --rows 19` (the first heavy mixed row: 30 % each of 600 ms delays,
/// drops and corruptions, seed 1, on both sweep scenarios): `physics_faults.json` has one entry
/// per scenario with the kinematic and the engine verdicts; neither falls. The book quotes
/// the default command's engine runs (every row on both scenarios) and their simulated
/// seconds (the node's references without a fault, seed 1).
#[test]
fn physics_faults_heavy_row() {
    if !engine_here("physics_faults_heavy_row") {
        return;
    }
    let dir = temp_dir("faults");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["physics-faults", "--rows", "19", "--out"])
        .arg(&dir)
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("physics_faults.json")).expect("json");
    let j: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let runs = j["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 2, "{text}");
    // The probe settings of the default run.
    assert_eq!(j["stabilizer"], true, "{text}");
    assert_eq!(j["stabilizer_scale"], 1.0, "{text}");
    assert_eq!(j["servo_damping"], 600.0, "{text}");
    assert_eq!(j["seed"], 1, "{text}");
    for (r, scenario) in runs.iter().zip(["straight", "fig4"]) {
        assert_eq!(r["scenario"], scenario);
        assert_eq!(r["fault"], "mixed");
        assert_eq!(r["kinematic_fell"], false, "{text}");
        assert_eq!(r["fell"], false, "{text}");
        assert_eq!(r["walked"], true, "a gait measure beyond its bound: {text}");
        assert!(r["fall_time_s"].is_null());
        let e = r["cop_err_max_m"].as_f64().expect("cop error");
        assert!(e > 0.0 && e < COP_MAX_BOUND_M, "{text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    use host_sim::eval::faults::{run_case_with, FaultKind};
    use host_sim::physics::fault_sweep::{parse_rows, plan, DEFAULT_ROWS};
    let runs = plan(&parse_rows(DEFAULT_ROWS).expect("the default rows"))
        .expect("the plan")
        .len();
    let robot = Robot::hrp2();
    let node = robot.node_config();
    let seconds = |name: &str| {
        let s = host_sim::scenario::built_in(name).expect(name);
        let case = run_case_with(&s, FaultKind::None, 0.0, 1, node, &robot.model).expect(name);
        let walk = (case.trajectory.len() - 1) as f64 * node.params.dt;
        engine_seconds(walk + PhysicsConfig::default().tail_s)
    };
    let row = "`physics-faults --out out/t` (every row, seed 1)";
    Quotes::new(COMMAND)
        .cell(BOOK, row, "engine runs", &runs.to_string())
        .cell(
            BOOK,
            row,
            SIMULATED,
            &format!(
                "{:.1} s (straight) / {:.1} s (fig4) each",
                seconds("straight"),
                seconds("fig4")
            ),
        )
        .line(
            BOOK,
            "physics-faults --out out/physics_faults`,",
            &format!("{runs} engine"),
        )
        .assert();
}

/// `host-sim physics-faults --walk adjusting --rows 0` (the adjusting walk without a fault,
/// seed 1, on both sweep scenarios: two engine runs): the node's references of a walk whose
/// pushed robot's estimator sent `MEASURED` every cycle and whose steps the node moved, in the
/// engine: the node adjusted in both, and neither falls, kinematically or in the engine.
#[test]
fn physics_faults_adjusting_row() {
    if !engine_here("physics_faults_adjusting_row") {
        return;
    }
    let dir = temp_dir("faults-adjusting");
    let args = ["physics-faults", "--walk", "adjusting", "--rows", "0"];
    let j = host_sim_json(&args, &dir, "physics_faults.json");
    let text = j.to_string();
    assert_eq!(j["walk"], "adjusting", "{text}");
    let runs = j["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 2, "{text}");
    for (r, scenario) in runs.iter().zip(["straight", "fig4"]) {
        assert_eq!(r["scenario"], scenario, "{text}");
        assert_eq!(
            (&r["walk"], &r["fault"]),
            (&"adjusting".into(), &"none".into())
        );
        assert!(r["adjustments"].as_u64().is_some_and(|n| n > 0), "{text}");
        assert_eq!(r["kinematic_fell"], false, "{text}");
        assert_eq!(r["fell"], false, "{text}");
        assert_eq!(r["lost"], 0, "{text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `host-sim physics-faults` takes the probe options of `physics-tables` (one definition):
/// `--rows 0` (no fault, both sweep scenarios: two engine runs) with the stabilizer × 0.5 and
/// the servo damping 300 N m s/rad records them in `physics_faults.json` and in the
/// Markdown's title; a bad setting is a usage error before any engine run.
#[test]
fn physics_faults_takes_the_probe_options() {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["physics-faults", "--rows", "0", "--stabilizer", "weak"])
        .output()
        .expect("host-sim runs");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("full, off, weakest or a scale"), "{err}");
    if !engine_here("physics_faults_takes_the_probe_options") {
        return;
    }
    let dir = temp_dir("faults-probe");
    let j = host_sim_json(
        &[
            "physics-faults",
            "--rows",
            "0",
            "--stabilizer",
            "0.5",
            "--servo-damping",
            "300",
        ],
        &dir,
        "physics_faults.json",
    );
    let text = j.to_string();
    assert_eq!(j["stabilizer"], true, "{text}");
    assert_eq!(j["stabilizer_scale"], 0.5, "{text}");
    assert_eq!(j["servo_damping"], 300.0, "{text}");
    assert!(j.get("weakest_ladder").is_none(), "{text}");
    let runs = j["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 2, "{text}");
    for (r, scenario) in runs.iter().zip(["straight", "fig4"]) {
        assert_eq!(r["scenario"], scenario);
        assert_eq!(r["fault"], "none");
        assert!(r["fell"].is_boolean(), "{text}");
        assert!(
            r["cop_err_max_m"].as_f64().is_some_and(|e| e > 0.0),
            "{text}"
        );
    }
    let md = std::fs::read_to_string(dir.join("physics_faults.md")).expect("md");
    assert!(
        md.contains("stabilizer × 0.5, servo damping 300 N m s/rad"),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `host-sim physics-sequence` (its default: 0.1 m steps, steps 3–7 changed to +0.3, −0.1,
/// +0.12, +0.3, −0.1 m, each one control cycle before its lift-off; two engine runs): every
/// modification is accepted by both patterns, the plain re-plan adjusts no single support
/// and the proposed method does, the proposed method walks it with no fall, and its
/// kinematic multi-body error over the modified single supports is below the plain re-plan's.
#[test]
fn consecutive_modifications_in_the_engine() {
    if !engine_here("consecutive_modifications_in_the_engine") {
        return;
    }
    let dir = temp_dir("sequence");
    let j = host_sim_json(&["physics-sequence"], &dir, "physics_sequence.json");
    let text = j.to_string();
    let afters = &host_sim::eval::paper::SEQUENCE_AFTERS_M;
    assert_eq!(j["afters_m"], serde_json::json!(afters), "{text}");
    assert_eq!(j["stabilizer_scale"], 1.0, "{text}");
    for key in ["plain", "proposed"] {
        let r = &j[key];
        let mods = r["modifications"].as_array().expect("modifications");
        assert_eq!(mods.len(), afters.len(), "{text}");
        for (k, m) in mods.iter().enumerate() {
            assert_eq!(m["accepted"], true, "{key} {k}: {text}");
            assert_eq!(m["step"], 3 + k, "{text}");
        }
        let adjusted = mods
            .iter()
            .filter(|m| m["adjust_s"].as_f64() != Some(0.0))
            .count();
        if key == "plain" {
            assert_eq!(adjusted, 0, "{text}");
        } else {
            assert!(adjusted > 0, "{text}");
        }
        assert!(r["fell"].is_boolean(), "{text}");
        let e = r["cop_err_modified_m"].as_f64().expect("cop error");
        assert!(
            e > 0.0 && e <= r["cop_err_max_m"].as_f64().unwrap(),
            "{text}"
        );
        let w = r["modified_window_s"].as_array().expect("window");
        assert!((w[0].as_f64().unwrap() - 4.0).abs() < 1e-9, "{text}");
        assert!(
            w[1].as_f64().unwrap() > 4.0 + 0.8 * (afters.len() - 1) as f64,
            "{text}"
        );
    }
    let p = &j["proposed"];
    assert_eq!(p["fell"], false, "{text}");
    assert!(p["fall_time_s"].is_null(), "{text}");
    assert!(
        p["cop_err_max_m"].as_f64().unwrap() < COP_MAX_BOUND_M,
        "{text}"
    );
    let mb = |k: &str| j[k]["mb_zmp_error_m"].as_f64().expect("mb error");
    assert!(mb("proposed") < mb("plain"), "{text}");
    let md = std::fs::read_to_string(dir.join("physics_sequence.md")).expect("md");
    assert!(md.contains("| plain re-plan |") && md.contains("| proposed method |"));
    let _ = std::fs::remove_dir_all(&dir);
    let seconds = |k: &str| engine_seconds(j[k]["simulated_s"].as_f64().expect("simulated_s"));
    let row = "`physics-sequence --out out/t`";
    Quotes::new(COMMAND)
        .cell(BOOK, row, "engine runs", "2")
        .cell(
            BOOK,
            row,
            SIMULATED,
            &format!("{:.1} + {:.1} s", seconds("plain"), seconds("proposed")),
        )
        .assert();
}

/// `host-sim physics small-walk.toml --robot small.toml`: the second robot (17.4 kg, soles
/// 0.16 × 0.09 m) walks through in the engine, on its own soles; a built-in (HRP-2) scenario
/// is refused for it.
#[test]
fn a_second_robot_walks_on_its_own_soles() {
    if !engine_here("a_second_robot_walks_on_its_own_soles") {
        return;
    }
    let robots = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    let dir = temp_dir("small");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("physics")
        .arg(robots.join("small-walk.toml"))
        .arg("--robot")
        .arg(robots.join("small.toml"))
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("physics.json")).expect("physics.json");
    let j: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(j["robot"], "small biped", "{text}");
    assert_eq!(
        j["sole_half_m"],
        serde_json::json!([0.08, 0.045, 0.03]),
        "{text}"
    );
    assert_eq!(j["fell"], false, "{text}");
    let num = |k: &str| j[k].as_f64().unwrap_or_else(|| panic!("{k} in {text}"));
    // Four 8 cm steps and the closing step: 5.9 s.
    assert!(num("simulated_s") > 5.5, "{text}");
    assert!(num("max_tilt_deg") < TILT_BOUND_DEG, "{text}");
    assert!(num("cop_err_mean_m") < COP_MEAN_BOUND_M, "{text}");
    assert!(num("cop_err_max_m") < COP_MAX_BOUND_M, "{text}");
    assert!(num("foot_drift_max_m") < 0.02, "{text}");
    Quotes::new(COMMAND)
        .line(
            BOOK,
            "with HRP-2's unscaled servos",
            &format!(
                "tilt {:.2}°, CoP error mean {:.1} mm, worst {:.1} mm",
                num("max_tilt_deg"),
                num("cop_err_mean_m") * 1e3,
                num("cop_err_max_m") * 1e3
            ),
        )
        .assert();
    // A built-in scenario is drawn in its proportions (feet 0.13 m apart, shorter steps).
    let j = host_sim_json(
        &[
            "physics",
            "straight",
            "--robot",
            robots.join("small.toml").to_str().expect("path"),
        ],
        &dir,
        "physics.json",
    );
    assert_eq!(j["fell"], false, "{j}");
    assert!(
        j["max_tilt_deg"].as_f64().expect("tilt") < TILT_BOUND_DEG,
        "{j}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `WALK_LONG=1` (tests/run-all.sh's release runs) turns on the full-grid and full-sweep
/// engine runs (minutes each); otherwise they skip and say so.
fn long_runs(test: &str) -> bool {
    let long = std::env::var("WALK_LONG").is_ok_and(|v| v == "1");
    if !long {
        eprintln!("physics: SKIPPED {test} (WALK_LONG=1 runs it)");
    }
    long && engine_here(test)
}

fn host_sim_json(args: &[&str], dir: &std::path::Path, file: &str) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .arg("--out")
        .arg(dir)
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join(file)).expect(file);
    serde_json::from_str(&text).expect("JSON")
}

/// The full grid (98 runs asked, 89 in the engine) with the full stabilizer and the harder probe (the weakest
/// stabilizer that walks the built-in scenarios, with servo damping 150 N m s/rad; see
/// `host_sim::physics::probe`), against `tables.json`: every cell the legs reach in
/// `tables.json` is simulated, with `tables.json`'s kinematic error, and no cell falls in
/// either (the book's result); every cell's trajectory ends standing and nothing falls after
/// the end.
#[test]
fn physics_tables_full_grid_long() {
    if !long_runs("physics_tables_full_grid_long") {
        return;
    }
    let dir = temp_dir("full-grid");
    let t = host_sim_json(&["tables"], &dir, "tables.json");
    for (args, scale) in [
        (&["physics-tables"][..], 1.0),
        (
            &[
                "physics-tables",
                "--stabilizer",
                "weakest",
                "--servo-damping",
                "150",
            ][..],
            0.05,
        ),
    ] {
        let p = host_sim_json(args, &dir, "physics_tables.json");
        assert_eq!(p["stabilizer_scale"], scale, "{args:?}");
        for (physics, kinematic, fell) in [
            (
                "mb_zmp_error_plain_m",
                "max_zmp_error_without_m",
                "fell_plain",
            ),
            (
                "mb_zmp_error_proposed_m",
                "max_zmp_error_with_m",
                "fell_proposed",
            ),
        ] {
            for r in 0..7 {
                for c in 0..7 {
                    assert_eq!(p[physics][r][c], t[kinematic][r][c], "{physics} ({r}, {c})");
                    let reached = t[kinematic][r][c].is_f64();
                    let v = &p[fell][r][c];
                    assert_eq!(v.is_boolean(), reached, "{args:?} {fell} ({r}, {c}): {v}");
                    assert_ne!(
                        v,
                        &serde_json::Value::Bool(true),
                        "{args:?} {fell} ({r}, {c})"
                    );
                    // Each cell's walk is played until standing, and nothing falls after.
                    let end = |k: &str| &p[format!("{k}_{}", &fell[5..])][r][c];
                    if reached {
                        assert_eq!(end("ended_standing"), true, "{args:?} {fell} ({r}, {c})");
                        assert_eq!(end("fell_after_end"), false, "{args:?} {fell} ({r}, {c})");
                    }
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `host-sim physics-faults` with its defaults simulates every row of the sweep (seed 1) on
/// both sweep scenarios in the engine (44 runs), and the engine's verdict agrees with the
/// kinematic one on every run.
#[test]
fn physics_faults_every_row_long() {
    use host_sim::physics::fault_sweep::rows;
    if !long_runs("physics_faults_every_row_long") {
        return;
    }
    let dir = temp_dir("faults-all");
    let j = host_sim_json(&["physics-faults"], &dir, "physics_faults.json");
    let runs = j["runs"].as_array().expect("runs");
    let scenarios = host_sim::eval::faults::SCENARIOS;
    assert_eq!(runs.len(), rows().len() * scenarios.len());
    for (kind, rate) in rows() {
        for s in scenarios {
            let hits: Vec<_> = runs
                .iter()
                .filter(|r| {
                    r["fault"] == kind.name()
                        && r["rate"] == kind.rate_label(rate)
                        && r["scenario"] == s
                })
                .collect();
            assert_eq!(
                hits.len(),
                1,
                "{} {} on {s}",
                kind.name(),
                kind.rate_label(rate)
            );
            let r = hits[0];
            assert_eq!(r["seed"], 1);
            assert!(r["fell"].is_boolean() && r["cop_err_max_m"].as_f64().is_some());
            assert_eq!(r["fell"], r["kinematic_fell"], "{r}");
            // No fault row makes the engine's walk slip, hop or land off.
            assert_eq!(r["walked"], true, "{r}");
            assert_eq!(r["ended_standing"], true, "{r}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `host-sim physics-faults --walk adjusting` simulates every row of the adjusting walk's
/// sweep (seed 1, the silent estimator among them) on both sweep scenarios in the engine, and
/// the engine's verdict agrees with the kinematic one on every run.
#[test]
fn physics_faults_adjusting_every_row_long() {
    use host_sim::eval::faults::Walk;
    use host_sim::physics::fault_sweep::rows_of;
    if !long_runs("physics_faults_adjusting_every_row_long") {
        return;
    }
    let dir = temp_dir("faults-adjusting-all");
    let j = host_sim_json(
        &["physics-faults", "--walk", "adjusting"],
        &dir,
        "physics_faults.json",
    );
    let runs = j["runs"].as_array().expect("runs");
    let scenarios = host_sim::eval::faults::SCENARIOS;
    let rows = rows_of(Walk::Adjusting);
    assert_eq!(runs.len(), rows.len() * scenarios.len());
    for (kind, rate) in rows {
        for s in scenarios {
            let hits: Vec<_> = runs
                .iter()
                .filter(|r| {
                    r["fault"] == kind.name()
                        && r["rate"] == kind.rate_label(rate)
                        && r["scenario"] == s
                })
                .collect();
            let what = format!("{} {} on {s}", kind.name(), kind.rate_label(rate));
            assert_eq!(hits.len(), 1, "{what}");
            let r = hits[0];
            assert_eq!(r["walk"], "adjusting", "{what}");
            assert_eq!(r["fell"], r["kinematic_fell"], "{what}: {r}");
            assert_eq!(r["ended_standing"], true, "{what}: {r}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
