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

/// `false` when `qemu-system-arm` is missing and `WALK_SKIP_QEMU=1`; panics when it is missing
/// otherwise.
pub fn qemu_available() -> bool {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if found {
        return true;
    }
    if std::env::var("WALK_SKIP_QEMU").as_deref() == Ok("1") {
        eprintln!("qemu-system-arm not found: QEMU checks skipped (WALK_SKIP_QEMU=1)");
        return false;
    }
    panic!(
        "qemu-system-arm not found: run tests/run-all.sh (it installs Debian's qemu-system-arm), \
         or `apt-get install qemu-system-arm`; set WALK_SKIP_QEMU=1 to skip the QEMU checks"
    );
}

/// `cargo build --release` in `firmware/<dir>` (a workspace with its own target dir); the ELF
/// `target/thumbv7em-none-eabihf/release/<bin>`.
pub fn build_firmware(dir: &str, bin: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("firmware")
        .join(dir);
    let out = firmware_cargo(&dir)
        .args(["build", "--release"])
        .output()
        .expect("cannot run cargo");
    assert!(
        out.status.success(),
        "building {} failed:\n{}",
        dir.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let elf = dir.join("target/thumbv7em-none-eabihf/release").join(bin);
    assert!(elf.is_file(), "no image at {}", elf.display());
    elf
}
