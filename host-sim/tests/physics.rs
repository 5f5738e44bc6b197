//! The physics engine run (`host-sim physics`, host-sim/src/physics/): the built-in scenarios
//! walk through in MuJoCo under the stabilizer without falling and with the CoP tracking the
//! reference ZMP within stated bounds; a push the stabilizer rejects fells the open-loop
//! playback, and a big push fells both (the fall detector works); the command-line contract
//! of `physics.json`; a missing engine is a clear error.
//!
//! The engine is PyPI's `mujoco` (pinned in `host_sim::physics::bridge::MUJOCO_VERSION`).
//! Without it the engine tests skip and say so, unless `WALK_REQUIRE_MUJOCO=1`
//! (tests/run-all.sh installs it and sets that), which makes a missing engine a failure.

use std::path::PathBuf;
use std::process::Command;

use host_sim::physics::bridge::{installed_version, python, Engine, MUJOCO_VERSION};
use host_sim::physics::metrics::FallCause;
use host_sim::physics::{run, PhysicsConfig, PhysicsReport, Push};
use host_sim::robot::Robot;
use host_sim::scenario::BUILT_IN;
use host_sim::sim::scenario_trajectory;

const REQUIRE: &str = "WALK_REQUIRE_MUJOCO";

/// Bounds the stabilized walks must meet (the 50 ms-filtered CoP against the reference ZMP;
/// measured: means 7–10 mm, worst 34–42 mm).
const COP_MEAN_BOUND_M: f64 = 0.015;
const COP_MAX_BOUND_M: f64 = 0.060;
const TILT_BOUND_DEG: f64 = 2.0;

/// `true` when MuJoCo can be used; otherwise a failure under `WALK_REQUIRE_MUJOCO=1`, else
/// `false` after saying that the test is skipped.
fn engine_here(test: &str) -> bool {
    let required = std::env::var(REQUIRE).is_ok_and(|v| !v.is_empty() && v != "0");
    match installed_version(&python()) {
        Ok(v) => {
            assert!(
                !required || v == MUJOCO_VERSION,
                "MuJoCo {v} installed, {MUJOCO_VERSION} expected under {REQUIRE}=1 \
                 (python3 -m pip install mujoco=={MUJOCO_VERSION})"
            );
            true
        }
        Err(e) => {
            assert!(!required, "{e} ({REQUIRE}=1)");
            eprintln!("physics: SKIPPED {test}: {e} ({REQUIRE}=1 makes this a failure)");
            false
        }
    }
}

fn report(scenario: &str, cfg: &PhysicsConfig) -> PhysicsReport {
    let (_, trajectory, dt) = scenario_trajectory(scenario, &Robot::hrp2()).expect("scenario");
    run(&trajectory, dt, cfg).expect("engine run").report
}

fn assert_walked(name: &str, r: &PhysicsReport) {
    assert!(
        !r.fell,
        "{name}: fell at {:?} s ({:?})",
        r.fall_time_s, r.fall_cause
    );
    assert!(r.max_tilt_deg < TILT_BOUND_DEG, "{name}: tilt {r:?}");
    assert!(r.cop_err_mean_m < COP_MEAN_BOUND_M, "{name}: {r:?}");
    assert!(r.cop_err_max_m < COP_MAX_BOUND_M, "{name}: {r:?}");
    assert!(r.foot_drift_max_m < 0.02, "{name}: the feet slid: {r:?}");
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-physics-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The contract: `host-sim physics straight --out DIR` writes DIR/physics.json with the
/// figures, and the straight walk does not fall.
#[test]
fn straight_walks_through_the_command_line_contract() {
    if !engine_here("straight_walks_through_the_command_line_contract") {
        return;
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
    let text = std::fs::read_to_string(dir.join("physics.json")).expect("physics.json");
    let j: serde_json::Value = serde_json::from_str(&text).expect("JSON");
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
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every other built-in scenario walks through too.
#[test]
fn other_built_in_scenarios_walk_through() {
    if !engine_here("other_built_in_scenarios_walk_through") {
        return;
    }
    for name in BUILT_IN.iter().filter(|n| **n != "straight") {
        let r = report(name, &PhysicsConfig::default());
        assert_walked(name, &r);
    }
}

/// A 150 N push for 0.1 s (15 N s) forward on the trunk in single support: the stabilizer
/// keeps walking, the same pattern played open loop falls over.
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
/// cells filled in, the others null; under the stabilizer neither falls.
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
/// other's mirror with different errors, so a transposed grid fails.
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
}

/// `host-sim physics-faults --rows 19` (the first heavy mixed row: 30 % each of 600 ms delays,
/// drops and corruptions, seed 1, on both sweep scenarios): `physics_faults.json` has one entry
/// per scenario with the kinematic and the engine verdicts; neither falls.
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
        assert!(r["fall_time_s"].is_null());
        let e = r["cop_err_max_m"].as_f64().expect("cop error");
        assert!(e > 0.0 && e < COP_MAX_BOUND_M, "{text}");
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
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["physics", "straight", "--robot"])
        .arg(robots.join("small.toml"))
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("host-sim runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("0.13 m apart"), "{err}");
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

/// The full grid (98 engine runs) with the full stabilizer and the harder probe (the weakest
/// stabilizer that walks the built-in scenarios, with servo damping 150 N m s/rad; see
/// `host_sim::physics::probe`), against `tables.json`: every cell the legs reach in
/// `tables.json` is simulated, with `tables.json`'s kinematic error, and no cell falls in
/// either (the book's result).
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
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
