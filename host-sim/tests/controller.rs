//! The example controller (`host-sim/examples/controller.py`: python-can and cantools, the DBC
//! alone) walks the robot through the host-sim node. This machine has no CAN interface, so the
//! controller writes its frames as a candump log, `host-sim replay` plays them into the node,
//! and the controller checks the node's answers and stream in the bus log: every command
//! accepted, standing at the end with the feet on the last two steps. A plan the robot cannot
//! walk (steps out of reach, or a heartbeat that ends mid-walk) is caught by the same check.
//!
//! Skipped (and said so) without python3, python-can and cantools, unless
//! `WALK_REQUIRE_CAN_TOOLS=1` (set by tests/run-all.sh, which installs them).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn required() -> bool {
    std::env::var("WALK_REQUIRE_CAN_TOOLS").is_ok_and(|v| !v.is_empty() && v != "0")
}

fn tools_present() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import can, cantools"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        ok || !required(),
        "python3 with python-can and cantools is missing and WALK_REQUIRE_CAN_TOOLS=1 \
         (pip install python-can cantools)"
    );
    if !ok {
        eprintln!("controller: SKIPPED: python3 with python-can and cantools not installed");
    }
    ok
}

fn controller(args: &[&str]) -> Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/controller.py");
    Command::new("python3")
        .arg(script)
        .args(args)
        .output()
        .expect("python3")
}

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-ctl-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Plans with `extra` options, replays, checks: (replay's exit code, check's exit code, the
/// check's output).
fn walk(name: &str, extra: &[&str]) -> (Option<i32>, Option<i32>, String) {
    let d = dir(name);
    let log = d.join("ctl.log");
    let out = d.join("out");
    let mut args = vec!["plan", "--out", log.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = controller(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = host_sim(&[
        "replay",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    // The check plans again with the same options, to know where the feet should end.
    let bus_log = out.join("can.log");
    let mut args = vec!["check", bus_log.to_str().unwrap()];
    args.extend_from_slice(extra);
    let c = controller(&args);
    let text = String::from_utf8_lossy(&c.stdout).to_string() + &String::from_utf8_lossy(&c.stderr);
    (r.status.code(), c.status.code(), text)
}

#[test]
fn the_example_controller_walks_the_robot() {
    if !tools_present() {
        return;
    }
    let (replay, check, text) = walk("ok", &[]);
    assert_eq!((replay, check), (Some(0), Some(0)), "{text}");
    assert!(text.contains("every command accepted"), "{text}");
    // A longer walk with shorter steps.
    let (replay, check, text) = walk(
        "short",
        &["--steps", "10", "--length", "0.1", "--seconds", "12"],
    );
    assert_eq!((replay, check), (Some(0), Some(0)), "{text}");
}

#[test]
fn the_check_catches_a_walk_that_went_wrong() {
    if !tools_present() {
        return;
    }
    // 0.5 m steps: refused as out of reach.
    let (replay, check, text) = walk("reach", &["--length", "0.5"]);
    assert_eq!((replay, check), (Some(1), Some(1)), "{text}");
    assert!(text.contains("reach"), "{text}");
    // The heartbeat stops after 2 s of a 9 s walk: the node stops the robot (controller
    // lost), and the feet do not reach the last steps.
    let (_, check, text) = walk("silent", &["--seconds", "2"]);
    assert_eq!(check, Some(1), "{text}");
    assert!(text.contains("foot at"), "{text}");
}

/// `controller.py frame` prints a `CONTROL` frame for `cansend` (the bring-up checklist's hand
/// commands) that the node's own decoder reads as that command of that session.
#[test]
fn the_frame_mode_prints_what_the_node_decodes() {
    use planner_core::wire::{Command, ControlOp, RawFrame};
    if !tools_present() {
        return;
    }
    for (op, name, session, seq) in [
        (ControlOp::Reset, "reset", 0xBEEFu16, 1u32),
        (ControlOp::Heartbeat, "heartbeat", 0xBEF0, 70_000),
    ] {
        let o = controller(&[
            "frame",
            name,
            "--session",
            &format!("{session:#x}"),
            "--seq",
            &seq.to_string(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let line = String::from_utf8_lossy(&o.stdout).trim().to_string();
        let (id, data) = line.split_once('#').expect("ID#DATA");
        let bytes: Vec<u8> = (0..data.len() / 2)
            .map(|i| u8::from_str_radix(&data[2 * i..2 * i + 2], 16).unwrap())
            .collect();
        let f = RawFrame::new(u16::from_str_radix(id, 16).unwrap(), &bytes).unwrap();
        assert_eq!(
            Command::decode(&f, 0),
            Ok(Command::Control { session, seq, op }),
            "{line}"
        );
    }
}

/// `python3` is on the machine (skipped, and said so, without it unless
/// `WALK_REQUIRE_CAN_TOOLS=1`).
fn python_present() -> bool {
    let ok = Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        ok || !required(),
        "python3 is missing and WALK_REQUIRE_CAN_TOOLS=1"
    );
    if !ok {
        eprintln!("controller: SKIPPED: no python3");
    }
    ok
}

/// The script's stdout and stderr together.
fn all_output(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr)
}

/// `controller.py check` of a log that does not exist is a usage error (exit 2) that says
/// where `host-sim replay` writes the bus log, not a traceback; with or without the python
/// packages installed.
#[test]
fn checking_a_missing_log_names_where_replay_writes_it() {
    if !python_present() {
        return;
    }
    let o = controller(&["check", "/nonexistent/can.log"]);
    let text = all_output(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(
        text.contains("/nonexistent/can.log: no such file"),
        "{text}"
    );
    assert!(
        text.contains("`host-sim replay LOG --out DIR` writes DIR/can.log"),
        "{text}"
    );
    assert!(!text.contains("Traceback"), "{text}");
}

/// Without python-can (a `can` package that fails to import stands in for a missing one),
/// the script says which module is missing and how to install it (exit 2), not a traceback.
#[test]
fn a_missing_python_package_is_a_clear_error() {
    if !python_present() {
        return;
    }
    let d = dir("nocan");
    std::fs::create_dir_all(d.join("can")).unwrap();
    std::fs::write(
        d.join("can/__init__.py"),
        "raise ImportError(\"No module named 'can'\", name=\"can\")\n",
    )
    .unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/controller.py");
    let o = Command::new("python3")
        .arg(script)
        .args(["plan", "--out", d.join("ctl.log").to_str().unwrap()])
        .env("PYTHONPATH", &d)
        .output()
        .expect("python3");
    let text = all_output(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains("the python module can is missing"), "{text}");
    assert!(text.contains("pip install python-can cantools"), "{text}");
    assert!(!text.contains("Traceback"), "{text}");
    assert!(
        !d.join("ctl.log").exists(),
        "a plan was written without its packages"
    );
}

/// `live` on an interface that cannot be opened (this machine's kernel has no CAN; elsewhere
/// the interface does not exist) ends in one line that names the interface and what is
/// missing, exit 2, no traceback.
#[test]
fn live_without_a_can_interface_says_what_is_missing() {
    if !tools_present() {
        return;
    }
    let o = controller(&["live", "--channel", "walknocan0"]);
    let text = all_output(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(!text.contains("Traceback"), "{text}");
    assert_eq!(text.trim().lines().count(), 1, "{text}");
    assert!(text.contains("CAN interface walknocan0"), "{text}");
    assert!(
        text.contains("no SocketCAN") || text.contains("there is no interface walknocan0"),
        "{text}"
    );
}

/// `plan --out` writes into a directory it creates (the book's steps keep `out/ctl.log` out
/// of the repository's root).
#[test]
fn plan_creates_its_output_directory() {
    if !tools_present() {
        return;
    }
    let d = dir("plan-dir");
    let log = d.join("out/ctl.log");
    let o = controller(&["plan", "--out", log.to_str().unwrap()]);
    assert!(o.status.success(), "{}", all_output(&o));
    assert!(log.is_file());
}
