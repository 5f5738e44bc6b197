//! An imported robot drives the firmware: Talos's URDF (PyPI's `example-robot-data`, used where
//! pip installed it) through `host-sim robot import`, the written robot file compiled into the
//! QEMU image (`WALK_ROBOT=FILE`, its own target dir), and the image replaying a host-sim walk
//! of Talos (`straight`, drawn in its proportions) bit for bit as the host does
//! (`walk_tests::logs::compare`), with its worst cycle within the budget.
//!
//! Skips and says so without `qemu-system-arm` (`WALK_SKIP_QEMU=1`) or without the package;
//! under `WALK_REQUIRE_ROBOT_DATA=1` (tests/run-all.sh) a missing package fails.

use std::process::{Command, Stdio};

use host_sim::robot::import::import;
use host_sim::sim::{simulate, start_config, SimConfig};
use walk_tests::logs::{self, compare, expected, Case};
use walk_tests::report::run_qemu;
use walk_tests::{build_firmware_env, qemu_available};

/// 5 % of a 5 ms control cycle at 480 MHz, in cycles (compared with instruction counts).
const BUDGET: u64 = 120_000;

fn talos_urdf() -> Option<std::path::PathBuf> {
    let script = "import importlib.metadata as m\n\
                  fs = [f for f in (m.files('example-robot-data') or []) \
                  if str(f).endswith('talos_data/robots/talos_reduced.urdf')]\n\
                  print(fs[0].locate() if fs else '')";
    let out = Command::new(host_sim::physics::bridge::python())
        .args(["-c", script])
        .stdin(Stdio::null())
        .output()
        .ok()?;
    let path = String::from_utf8_lossy(&out.stdout).trim().to_string();
    if out.status.success() && !path.is_empty() {
        return Some(path.into());
    }
    let required = std::env::var("WALK_REQUIRE_ROBOT_DATA").is_ok_and(|v| v == "1");
    assert!(
        !required,
        "example-robot-data is not installed (python3 -m pip install example-robot-data)"
    );
    eprintln!("SKIPPED qemu_robot: example-robot-data is not installed");
    None
}

#[test]
fn an_imported_robot_file_drives_the_qemu_image() {
    if !qemu_available() {
        return;
    }
    let Some(urdf) = talos_urdf() else {
        return;
    };
    let imported = import(&urdf, None).expect("Talos imports");
    let dir = std::env::temp_dir().join(format!("walk-qemu-robot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("talos.toml");
    std::fs::write(&file, &imported.toml).unwrap();
    let elf = build_firmware_env(
        "qemu",
        "qemu",
        None,
        &[],
        "target-imported",
        &[("WALK_ROBOT", file.as_os_str())],
    );
    let robot = imported.robot;
    let sim = SimConfig {
        node: robot.node_config(),
        ..SimConfig::default()
    };
    let s = robot.built_in("straight").expect("straight");
    let run = simulate(&s, &sim).expect("Talos walks straight through the node");
    let case = Case {
        name: "talos-straight".into(),
        cfg: start_config(&s, &sim.node),
        log: run.can_log,
        adjusts: false,
    };
    let bytes = logs::binary(&case);
    let want = expected(&case, &bytes);
    std::fs::write(dir.join("replay.wlog"), &bytes).unwrap();
    let q = run_qemu("mps2-an500", &elf, &dir);
    compare(&q, &case, &want);
    let worst: u64 = q
        .timing("all", "cycle")
        .expect("no TIMING line for the whole cycle")
        .num("max");
    println!("talos-straight on the M7 image: worst cycle {worst} instructions");
    assert!(worst < BUDGET, "{worst}");
    let _ = std::fs::remove_dir_all(&dir);
}
