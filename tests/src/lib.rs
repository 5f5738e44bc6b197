//! End-to-end checks, and what the firmware tests share.

use std::process::Command;

/// A `cargo` command run in `dir` (a firmware workspace) with this test's own build settings
/// removed, so that they do not leak into the firmware's build: its target and rustflags come
/// from `firmware/.cargo/config.toml`.
pub fn firmware_cargo(dir: &std::path::Path) -> Command {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(dir);
    for var in [
        "CARGO_TARGET_DIR",
        "CARGO_BUILD_TARGET",
        "CARGO_BUILD_TARGET_DIR",
        "RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
        "CARGO_BUILD_RUSTFLAGS",
    ] {
        cmd.env_remove(var);
    }
    cmd
}
