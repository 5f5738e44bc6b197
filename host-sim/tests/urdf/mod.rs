//! Robot descriptions from PyPI's `example-robot-data` (its URDFs, used where pip installed
//! them; none of its files is in this repository) and Pinocchio (`pin`), the oracle of the
//! imported models. Without them a test skips and says so, unless `WALK_REQUIRE_ROBOT_DATA=1`
//! (tests/run-all.sh installs both and sets it), which makes a missing package a failure.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Stdio};

/// The variable that makes a missing package a failure.
pub const REQUIRE: &str = "WALK_REQUIRE_ROBOT_DATA";

fn required() -> bool {
    std::env::var(REQUIRE).is_ok_and(|v| !v.is_empty() && v != "0")
}

fn python() -> String {
    host_sim::physics::bridge::python()
}

/// The installed file of `example-robot-data` whose path ends with `tail`, or why not.
fn installed(tail: &str) -> Result<PathBuf, String> {
    let script = format!(
        "import importlib.metadata as m\n\
         fs = [f for f in (m.files('example-robot-data') or []) if str(f).endswith({tail:?})]\n\
         print(fs[0].locate() if fs else '')"
    );
    let out = Command::new(python())
        .args(["-c", &script])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run python3: {e}"))?;
    let path = String::from_utf8_lossy(&out.stdout).trim().to_string();
    if out.status.success() && !path.is_empty() {
        Ok(PathBuf::from(path))
    } else {
        Err(format!(
            "example-robot-data has no {tail} (python3 -m pip install example-robot-data): {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// The URDF of `example-robot-data` ending in `tail`; `None` after saying that `test` is
/// skipped (a failure under `WALK_REQUIRE_ROBOT_DATA=1`).
pub fn robot_file(tail: &str, test: &str) -> Option<PathBuf> {
    match installed(tail) {
        Ok(p) => Some(p),
        Err(e) => {
            assert!(!required(), "{e} ({REQUIRE}=1)");
            eprintln!("SKIPPED {test}: {e} ({REQUIRE}=1 makes this a failure)");
            None
        }
    }
}

/// Talos (PAL Robotics), 90.3 kg in this description.
pub const TALOS: &str = "talos_data/robots/talos_reduced.urdf";
/// Unitree G1 (29 DoF): hip pitch, roll, yaw.
pub const G1: &str = "g1_description/urdf/g1_29dof_rev_1_0.urdf";

/// Whether Pinocchio can be imported; `false` after saying that `test` is skipped (a failure
/// under `WALK_REQUIRE_ROBOT_DATA=1`).
pub fn pinocchio_here(test: &str) -> bool {
    let ok = Command::new(python())
        .args(["-c", "import pinocchio"])
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        let e = "python3 cannot import pinocchio (python3 -m pip install pin)";
        assert!(!required(), "{e} ({REQUIRE}=1)");
        eprintln!("SKIPPED {test}: {e} ({REQUIRE}=1 makes this a failure)");
    }
    ok
}

/// The script of the Pinocchio oracle.
pub fn pinocchio_script() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/urdf/pinocchio_zmp.py")
}

/// A scratch directory for a test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-urdf-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// Every URDF of the installed `example-robot-data` (sorted by path), or `None` after saying
/// that `test` is skipped (a failure under `WALK_REQUIRE_ROBOT_DATA=1`).
pub fn all_robot_files(test: &str) -> Option<Vec<PathBuf>> {
    let script = "import importlib.metadata as m\n\
                  fs = [str(f.locate()) for f in (m.files('example-robot-data') or []) \
                  if str(f).endswith('.urdf')]\n\
                  print('\\n'.join(sorted(fs)))";
    let out = Command::new(python())
        .args(["-c", script])
        .stdin(Stdio::null())
        .output();
    let files: Vec<PathBuf> = match &out {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.is_empty())
            .map(PathBuf::from)
            .collect(),
        _ => Vec::new(),
    };
    if files.is_empty() {
        let e = "example-robot-data is not installed (python3 -m pip install example-robot-data)";
        assert!(!required(), "{e} ({REQUIRE}=1)");
        eprintln!("SKIPPED {test}: {e} ({REQUIRE}=1 makes this a failure)");
        return None;
    }
    Some(files)
}
