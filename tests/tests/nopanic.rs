//! The firmware's control cycle cannot panic: a link-time check (`firmware/nopanic`).
//!
//! `firmware/nopanic` is the board image's `main` from the node's construction on, built for
//! `thumbv7em-none-eabihf` with the release profile (fat LTO, opt-level 3), whose panic
//! handler calls `walk_control_path_can_panic`, a function defined nowhere: the image links
//! only if no panic is reachable from its code (see `firmware/nopanic/src/main.rs`).
//!
//! * `control_cycle_cannot_panic`: the whole board cycle (default features: `Node::poll`, the
//!   board's CAN link adapter over its FDCAN1 register accesses, the slot pacer, the cycle
//!   bookkeeping, the watchdog feed, every defmt call through the board's logger) links, and
//!   the image holds the planner (a `.text` of tens of KB: nothing was optimised away); the
//!   narrower `scoped` variant (arbitrary frames instead of the adapter, no logging) links too,
//!   and so does the `f32` variant (the whole cycle with the f32 node of the M4F image); both
//!   whole-cycle images keep their parked node in .bss (all zero bytes: no flash, no copy);
//!   then the negative control, the same build with `selftest-panic` (one reachable
//!   out-of-range index), must FAIL to link with that symbol in the linker's message, which
//!   shows that the check is live.
//!
//! The builds run cargo in `firmware/` (its workspace, `.cargo/config.toml` and target dir,
//! shared with `cd firmware && cargo build --release`), one at a time. When a positive build
//! fails, `cargo build --release -p firmware-nopanic --features diagnose` in `firmware/` links
//! anyway, and the callers of `core::panicking::*` in its disassembly are the panics.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::Mutex;

const SYMBOL: &str = "walk_control_path_can_panic";
const TARGET: &str = "thumbv7em-none-eabihf";
/// The whole cycle's `.text` is ~66 KB (the planner: window solver, gait, shaping, node
/// command handling, wire codec); far less would mean that the cycle was optimised away.
const MIN_TEXT: u32 = 40_000;

/// The builds share `firmware/target` and the same output file: one at a time.
static BUILD: Mutex<()> = Mutex::new(());

fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("firmware")
}

/// `cargo build --release -p firmware-nopanic` in firmware/ with these cargo arguments.
fn build(args: &[&str]) -> Output {
    let mut cmd = walk_tests::firmware_cargo(&firmware_dir());
    cmd.args(["build", "--release", "-p", "firmware-nopanic"])
        .args(args);
    cmd.output().expect("cannot run cargo")
}

/// The linker's lines about the undefined symbol (or the tail of stderr).
fn explain(stderr: &str) -> String {
    let lines: Vec<&str> = stderr.lines().collect();
    match lines.iter().position(|l| l.contains("undefined symbol")) {
        Some(i) => lines[i..lines.len().min(i + 6)].join("\n"),
        None => lines[lines.len().saturating_sub(30)..].join("\n"),
    }
}

/// Builds with `args` and requires the link to succeed; the image's path.
fn links(args: &[&str]) -> PathBuf {
    let out = build(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "firmware-nopanic ({args:?}) did not link: a panic is reachable from the control cycle \
         (or the build failed). Find it with `cargo build --release -p firmware-nopanic \
         --features diagnose` in firmware/ and the disassembly.\n{}",
        explain(&stderr)
    );
    let elf = firmware_dir().join(format!("target/{TARGET}/release/nopanic"));
    assert!(elf.is_file(), "no image at {}", elf.display());
    elf
}

#[test]
fn control_cycle_cannot_panic() {
    let _one = BUILD.lock().unwrap_or_else(|e| e.into_inner());

    links(&["--features", "scoped"]);
    // The same cycle with the f32 node (the M4F image's), its parked node in .bss as the
    // board's (8 KB).
    let elf = links(&["--features", "f32"]);
    walk_tests::assert_parked_node_in_bss(&elf, 8_000);
    let elf = links(&[]);
    walk_tests::assert_parked_node_in_bss(&elf, 14_000);
    let bytes = std::fs::read(&elf).expect("cannot read the image");
    let text =
        walk_tests::elf32_section_size(&elf, ".text").expect("no .text section in the image");
    println!("firmware-nopanic (whole board cycle): links, .text {text} bytes");
    assert!(
        text >= MIN_TEXT,
        ".text is only {text} bytes: the control cycle was optimised away, the check proves nothing"
    );
    assert!(
        bytes.windows(12).any(|w| w == b"_SEGGER_RTT\0"),
        "the board's logger is not in the image"
    );

    // The negative control: one reachable panic must break the link, naming the symbol.
    let out = build(&["--features", "selftest-panic"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "with `selftest-panic` the image linked: the check is not live"
    );
    assert!(
        stderr.contains(&format!("undefined symbol: {SYMBOL}")),
        "with `selftest-panic` the build failed, but not on `{SYMBOL}`:\n{}",
        explain(&stderr)
    );
    println!(
        "negative control (selftest-panic): fails to link as it must:\n{}",
        explain(&stderr)
    );
}
