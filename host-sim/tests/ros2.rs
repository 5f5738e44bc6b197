//! The ROS 2 gateway (`host-sim ros2`) against a real, independent ROS 2 peer: PyPI's
//! `cyclonedds` (Eclipse Cyclone DDS), speaking IHMC's footstep interface under ROS 2's naming
//! (`host-sim/examples/ros2_peer.py`, its types declared from `host-sim/interfaces`, not from
//! the gateway's code). Skipped when `cyclonedds` is not installed, unless
//! `WALK_REQUIRE_ROS2=1` (`tests/run-all.sh` installs it and sets that).
//!
//! Each test runs on a DDS domain of its own, so that they may run at once.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use host_sim::ros2::msg::{self, MSG_FIELDS};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn have_cyclonedds() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import cyclonedds.domain"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok && std::env::var("WALK_REQUIRE_ROS2").as_deref() == Ok("1") {
        panic!("PyPI's cyclonedds is not installed (python3 -m pip install cyclonedds==11.0.1)");
    }
    if !ok {
        eprintln!("skipped: python3 -m pip install cyclonedds==11.0.1 to run this test");
    }
    ok
}

/// The `.msg` files' fields, in order, for `pkg/name`.
fn msg_file_fields(pkg: &str, name: &str) -> Vec<(String, String)> {
    let path = root().join(format!("interfaces/{pkg}/msg/{name}.msg"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    text.lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .filter_map(|l| {
            let mut w = l.split_whitespace();
            let (ty, field) = (w.next()?, w.next()?);
            // A constant: `TYPE NAME = value` (or `NAME=value`).
            let constant = field.contains('=') || w.next() == Some("=");
            (!constant).then(|| (ty.to_string(), field.to_string()))
        })
        .collect()
}

#[test]
fn the_msg_files_and_the_rust_types_list_the_same_fields() {
    let dir = root().join("interfaces");
    let mut files = 0;
    for pkg in std::fs::read_dir(&dir).unwrap() {
        let pkg = pkg.unwrap().path();
        let Ok(msgs) = std::fs::read_dir(pkg.join("msg")) else {
            continue;
        };
        for m in msgs {
            let m = m.unwrap().path();
            let (p, n) = (
                pkg.file_name().unwrap().to_str().unwrap().to_string(),
                m.file_stem().unwrap().to_str().unwrap().to_string(),
            );
            let listed = MSG_FIELDS
                .iter()
                .find(|(lp, ln, _)| *lp == p && *ln == n)
                .unwrap_or_else(|| panic!("{p}/{n} is not in MSG_FIELDS"));
            let want: Vec<(String, String)> = listed
                .2
                .iter()
                .map(|(t, f)| (t.to_string(), f.to_string()))
                .collect();
            assert_eq!(msg_file_fields(&p, &n), want, "{p}/{n}");
            files += 1;
        }
    }
    assert_eq!(files, MSG_FIELDS.len());
    // The serde order of the Rust types is the CDR order on the wire.
    let names =
        |v: serde_json::Value| -> Vec<String> { v.as_object().unwrap().keys().cloned().collect() };
    let listed = |n: &str| -> Vec<String> {
        let f = MSG_FIELDS.iter().find(|(_, ln, _)| *ln == n).unwrap().2;
        f.iter().map(|(_, f)| f.to_string()).collect()
    };
    let list = msg::FootstepDataListMessage::new(
        1,
        0,
        vec![msg::FootstepDataMessage::new(1, 0, 0.0, 0.0, 0.0)],
    );
    let step = list.footstep_data_list[0].clone();
    for (name, v) in [
        (
            "FootstepDataListMessage",
            serde_json::to_value(&list).unwrap(),
        ),
        ("FootstepDataMessage", serde_json::to_value(&step).unwrap()),
        (
            "QueueableMessage",
            serde_json::to_value(&list.queueing_properties).unwrap(),
        ),
        (
            "StepConstraintsListMessage",
            serde_json::to_value(&step.step_constraints).unwrap(),
        ),
        (
            "FootstepStatusMessage",
            serde_json::to_value(msg::FootstepStatusMessage::default()).unwrap(),
        ),
        (
            "WalkingStatusMessage",
            serde_json::to_value(msg::WalkingStatusMessage::default()).unwrap(),
        ),
        (
            "PauseWalkingMessage",
            serde_json::to_value(msg::PauseWalkingMessage::default()).unwrap(),
        ),
        (
            "AbortWalkingMessage",
            serde_json::to_value(msg::AbortWalkingMessage::default()).unwrap(),
        ),
        (
            "SE3TrajectoryPointMessage",
            serde_json::to_value(msg::Se3TrajectoryPointMessage::default()).unwrap(),
        ),
        (
            "CommandRefusal",
            serde_json::to_value(msg::CommandRefusal::default()).unwrap(),
        ),
    ] {
        let mut got = names(v);
        let mut want = listed(name);
        // serde_json's map is sorted: compare as sets here; the order is checked by the peer,
        // which decodes every message the gateway sends and encodes what the gateway reads.
        got.sort();
        want.sort();
        assert_eq!(got, want, "{name}");
    }
}

#[test]
fn the_peers_declarations_agree_with_the_msg_files() {
    if !have_cyclonedds() {
        return;
    }
    let out = Command::new("python3")
        .arg(root().join("examples/ros2_peer.py"))
        .arg("types")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("10 message types agree"), "{text}");
}

/// The gateway on `domain`, writing into `out`, for at most `seconds`.
fn gateway(domain: u16, out: &Path, seconds: u32, walks: Option<u32>) -> Child {
    let mut c = Command::new(env!("CARGO_BIN_EXE_host-sim"));
    c.args(["ros2", "--domain", &domain.to_string(), "--seconds"])
        .arg(seconds.to_string())
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(w) = walks {
        c.args(["--walks", &w.to_string()]);
    }
    c.spawn().expect("host-sim ros2 starts")
}

fn peer(mode: &str, domain: u16) -> Command {
    let mut c = Command::new("python3");
    c.arg(root().join("examples/ros2_peer.py"))
        .args([mode, "--domain", &domain.to_string()])
        // A peer killed without a word is forgotten after its lease (1 s, not Cyclone's 10 s).
        .env(
            "CYCLONEDDS_URI",
            "<CycloneDDS><Domain><Discovery><LeaseDuration>1s</LeaseDuration></Discovery></Domain></CycloneDDS>",
        );
    c
}

fn finish(mut gw: Child) -> (String, String) {
    let _ = gw.kill();
    let out = gw.wait_with_output().unwrap();
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs the peer in `mode` against a gateway on `domain` (writing to `dir`, for at most
/// `seconds`) and asserts that it passed (exit 0, its last line `ok`); the gateway's output.
fn peer_passes(mode: &str, domain: u16, dir: &Path, seconds: u32) -> (String, String) {
    let gw = gateway(domain, dir, seconds, None);
    let out = peer(mode, domain).output().unwrap();
    let (gw_out, gw_err) = finish(gw);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.ends_with("ok\n"),
        "peer:\n{text}{}\ngateway:\n{gw_out}{gw_err}",
        String::from_utf8_lossy(&out.stderr)
    );
    (gw_out, gw_err)
}

#[test]
fn a_cyclonedds_peer_walks_changes_refuses_and_aborts_through_the_gateway() {
    if !have_cyclonedds() {
        return;
    }
    let dir = std::env::temp_dir().join("host-sim-ros2-peer");
    let (gw_out, gw_err) = peer_passes("check", 61, &dir, 120);
    // The gateway logged each refusal too.
    for reason in ["lifted_off", "not_finite", "queue_full", "too_many_steps"] {
        assert!(
            gw_out.contains(reason),
            "{reason} not in the log:\n{gw_out}"
        );
    }
    assert!(
        gw_err.contains("wrong_type") || gw_err.contains("Point_"),
        "{gw_err}"
    );
    assert!(gw_err.contains("malformed"), "{gw_err}");
}

#[test]
fn a_peer_that_vanishes_mid_walk_is_stopped_by_the_nodes_supervision() {
    if !have_cyclonedds() {
        return;
    }
    let dir = std::env::temp_dir().join("host-sim-ros2-vanish");
    let _ = std::fs::remove_dir_all(&dir);
    let mut gw = gateway(62, &dir, 60, Some(1));
    let mut p = peer("vanish", 62).stdout(Stdio::piped()).spawn().unwrap();
    let mut line = String::new();
    BufReader::new(p.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert_eq!(line.trim(), "lifted off");
    p.kill().unwrap(); // SIGKILL: no goodbye on the wire
    let _ = p.wait();
    let killed = Instant::now();
    // The gateway ends once the walk has ended (`--walks 1`): the node stopped it.
    loop {
        if gw.try_wait().unwrap().is_some() {
            break;
        }
        assert!(
            killed.elapsed() < Duration::from_secs(20),
            "the walk still runs 20 s after its peer vanished"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let (out, err) = finish(gw);
    assert!(out.contains("controller_lost"), "{out}{err}");
    // The node said so on the bus: a STATUS frame in state 3 (controller lost).
    let log = std::fs::read_to_string(dir.join("can.log")).unwrap();
    assert!(
        log.lines().any(|l| l.contains(" 300#03")),
        "no STATUS 'controller lost' in can.log"
    );
}

#[test]
fn the_books_python_peer_runs_as_written() {
    if !have_cyclonedds() {
        return;
    }
    let book = std::fs::read_to_string(root().join("../docs/src/ros2.md")).unwrap();
    let section = book.split("## A Python peer").nth(1).expect("the section");
    let code = section
        .split("```python\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("a python block");
    let printed: Vec<String> = section
        .split("It prints one line per step, each landing where it was sent ")
        .nth(1)
        .expect("the expected output")
        .split(". `host-sim")
        .next()
        .unwrap()
        .replace('\n', " ")
        .replace('\u{2212}', "-")
        .split("), ")
        .map(|p| {
            p.trim()
                .trim_start_matches("and ")
                .trim_end_matches(')')
                .to_string()
                + ")"
        })
        .collect();
    let dir = std::env::temp_dir().join("host-sim-ros2-book");
    let gw = gateway(64, &dir, 60, Some(1));
    let out = Command::new("python3")
        .args(["-c", code])
        .current_dir(root().join(".."))
        .env("ROS_DOMAIN_ID", "64")
        .output()
        .unwrap();
    let (gw_out, _) = finish(gw);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}\n{gw_out}",
        String::from_utf8_lossy(&out.stderr)
    );
    let landed: Vec<String> = text
        .lines()
        .map(|l| l.split("landed at ").nth(1).unwrap_or("").to_string())
        .collect();
    assert_eq!(landed, printed, "the book says {printed:?}");
}

/// A cyclonedds peer steers by `cmd_vel` (`geometry_msgs/Twist` at 20 Hz for 5 s, then let
/// go) and sends a relative goal (`geometry_msgs/Pose2D`): the COG goes forward, stops when
/// the stick is let go (the gateway sends zero), and ends 0.4 m further at the goal; no
/// refusal (`ros2_peer.py stick`).
#[test]
fn a_cyclonedds_peer_steers_by_cmd_vel_and_a_goal() {
    if !have_cyclonedds() {
        return;
    }
    let dir = std::env::temp_dir().join("host-sim-ros2-stick");
    peer_passes("stick", 63, &dir, 90);
}
