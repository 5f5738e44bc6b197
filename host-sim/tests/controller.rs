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

/// The scripted stick (`controller.py stick`): a `VELOCITY` stream of 19 s (forward,
/// sideways, a turn and its reversal, zero) written from the DBC alone, replayed into the
/// node: every velocity accepted, the robot standing at the end. A stream that stops early
/// (the log cut after 3 s of walking) is caught by the same check: the node stops the robot
/// as a lost controller, and the later frames are refused.
#[test]
fn the_scripted_stick_walks_by_velocity() {
    if !tools_present() {
        return;
    }
    let d = dir("stick");
    let log = d.join("stick.log");
    let out = d.join("out");
    let o = controller(&["stick", "--out", log.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = host_sim(&[
        "replay",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let bus_log = out.join("can.log");
    let c = controller(&["check", bus_log.to_str().unwrap(), "--stick"]);
    let text = String::from_utf8_lossy(&c.stdout).to_string();
    assert_eq!(c.status.code(), Some(0), "{text}");
    // The stream falls silent for 0.5 s at 3 s: the robot is stopped, the rest refused.
    let text_log = std::fs::read_to_string(&log).unwrap();
    let cut: Vec<&str> = text_log
        .lines()
        .filter(|l| {
            let t: f64 = l[1..l.find(')').unwrap()].parse().unwrap();
            let t = t - 1_767_225_600.0;
            !(3.0..3.5).contains(&t)
        })
        .collect();
    let gap = d.join("gap.log");
    std::fs::write(&gap, cut.join("\n") + "\n").unwrap();
    let out2 = d.join("out2");
    let r = host_sim(&[
        "replay",
        gap.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    let _ = r;
    let c = controller(&["check", out2.join("can.log").to_str().unwrap(), "--stick"]);
    let text = String::from_utf8_lossy(&c.stdout).to_string();
    assert_eq!(c.status.code(), Some(1), "{text}");
    assert!(text.contains("controller_lost"), "{text}");
}
