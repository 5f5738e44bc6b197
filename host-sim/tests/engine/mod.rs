//! Whether the engine tests can run: MuJoCo from PyPI, pinned in
//! `host_sim::physics::bridge::MUJOCO_VERSION`. Without it an engine test skips and says so,
//! unless `WALK_REQUIRE_MUJOCO=1` (tests/run-all.sh installs it and sets that), which makes a
//! missing or other engine a failure.

use host_sim::physics::bridge::{installed_version, python, MUJOCO_VERSION};

/// The variable that makes a missing engine a failure.
pub const REQUIRE: &str = "WALK_REQUIRE_MUJOCO";

/// `true` when MuJoCo can be used; otherwise a failure under `WALK_REQUIRE_MUJOCO=1`, else
/// `false` after saying that `test` is skipped.
pub fn engine_here(test: &str) -> bool {
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
            eprintln!("SKIPPED {test}: {e} ({REQUIRE}=1 makes this a failure)");
            false
        }
    }
}

/// Asserts that every summary line of a push map (`push_map::summary_lines`) is in the book's
/// `docs/src/adjust.md`, after printing them. (Used by the push-map tests only.)
#[allow(dead_code)]
pub fn map_summary_is_the_books(
    spec: &host_sim::physics::push_map::MapSpec,
    cells: &[host_sim::physics::push_map::Cell],
) {
    assert!(cells.iter().all(|c| c.ok()), "failed cells: {cells:?}");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/src/adjust.md");
    let book = std::fs::read_to_string(&path).expect("the book");
    let sums = host_sim::physics::push_map::summary_lines(spec, cells);
    eprintln!("{sums}");
    for line in sums.lines().filter(|l| !l.is_empty()) {
        assert!(book.contains(line), "docs/src/adjust.md lacks: {line}");
    }
}
