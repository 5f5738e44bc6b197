//! The live view (`--live PORT`) against an independent client of the Foxglove WebSocket
//! protocol (`tests/live/client.py`: PyPI's websockets and jsonschema): the channels it
//! advertises, their schemas (the MCAP file's), and messages of every channel decoded and
//! validated. Skipped without those packages unless `WALK_REQUIRE_LIVE=1` (`tests/run-all.sh`
//! installs them and sets it).

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};

fn have_client() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import websockets, jsonschema"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok && std::env::var("WALK_REQUIRE_LIVE").as_deref() == Ok("1") {
        panic!("the live view's test client needs python3 -m pip install websockets jsonschema");
    }
    if !ok {
        eprintln!("skipped: python3 -m pip install websockets jsonschema to run this test");
    }
    ok
}

/// Starts host-sim with `args` and reads the live view's port from its announcement.
fn start(args: &[&str]) -> (Child, u16) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    let port = loop {
        line.clear();
        if out.read_line(&mut line).unwrap_or(0) == 0 {
            break None;
        }
        if let Some(rest) = line.split("ws://127.0.0.1:").nth(1) {
            break rest
                .split(|c: char| !c.is_ascii_digit())
                .next()
                .and_then(|p| p.parse::<u16>().ok());
        }
    };
    let Some(port) = port else {
        let _ = child.kill();
        let _ = child.wait();
        panic!("no live view announced");
    };
    // Keep draining stdout so the child never blocks on a full pipe.
    std::thread::spawn(move || for _ in out.lines() {});
    (child, port)
}

/// The client's verdict (JSON) after `seconds` of listening; panics when it failed.
fn client(port: u16, seconds: f64, required: &[&str]) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/live/client.py");
    let out = Command::new("python3")
        .arg(script)
        .arg(format!("ws://127.0.0.1:{port}"))
        .arg(seconds.to_string())
        .arg(required.join(","))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "client: {text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(text.trim()).unwrap()
}

fn have_mujoco() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import mujoco"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok && std::env::var("WALK_REQUIRE_MUJOCO").as_deref() == Ok("1") {
        panic!("MuJoCo is not installed (python3 -m pip install mujoco==3.2.7)");
    }
    ok
}

const WALK_TOPICS: [&str; 6] = [
    "/reference",
    "/multibody/zmp",
    "/feet/left",
    "/feet/right",
    "/can",
    "/scene",
];

#[test]
fn run_serves_the_walk_with_the_mcap_files_channels() {
    if !have_client() {
        return;
    }
    let dir = std::env::temp_dir().join("host-sim-live-run");
    let (mut child, port) = start(&[
        "run",
        "straight",
        "--out",
        dir.to_str().unwrap(),
        "--live",
        "0",
    ]);
    let v = client(port, 3.0, &WALK_TOPICS);
    let _ = child.kill();
    let _ = child.wait();
    // Every channel of the MCAP file, with its schema's name, plus the links' transforms.
    let channels: Vec<(String, String)> = v["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c[0].as_str().unwrap().into(), c[1].as_str().unwrap().into()))
        .collect();
    let schemas = host_sim::output::mcap::schemas();
    for (topic, schema) in host_sim::output::mcap::TOPICS.iter().zip(schemas.iter()) {
        let name = schema["title"].as_str().unwrap().to_string();
        assert!(
            channels.contains(&(topic.to_string(), name.clone())),
            "{topic} ({name}) not advertised: {channels:?}"
        );
    }
    assert!(channels.iter().any(|c| c.0 == "/tf"));
    // 200 samples a second: at least a second's worth in 3 s of listening.
    assert!(v["messages"]["/reference"].as_u64().unwrap() >= 200, "{v}");
}

#[test]
fn the_gateway_serves_its_walk_live() {
    if !have_client() {
        return;
    }
    let dir = std::env::temp_dir().join("host-sim-live-ros2");
    let (mut child, port) = start(&[
        "ros2",
        "--domain",
        "63",
        "--seconds",
        "20",
        "--out",
        dir.to_str().unwrap(),
        "--live",
        "0",
    ]);
    // Standing, the node streams its reference and the bus carries it.
    let v = client(
        port,
        2.0,
        &["/reference", "/feet/left", "/feet/right", "/can", "/scene"],
    );
    let _ = child.kill();
    let _ = child.wait();
    assert!(v["messages"]["/can"].as_u64().unwrap() >= 100, "{v}");
}

#[test]
fn physics_serves_the_robots_links_from_the_engine() {
    if !have_client() || !have_mujoco() {
        return;
    }
    let dir = std::env::temp_dir().join("host-sim-live-physics");
    let (mut child, port) = start(&[
        "physics",
        "straight",
        "--out",
        dir.to_str().unwrap(),
        "--live",
        "0",
    ]);
    // The engine computes the run first (seconds), then plays it in real time.
    let v = client(port, 12.0, &["/tf", "/measured", "/reference", "/scene"]);
    let _ = child.kill();
    let _ = child.wait();
    let tf = v["first"]["/tf"]["transforms"].as_array().unwrap();
    // The waist, six links per leg and the two soles, each in `world`.
    assert_eq!(tf.len(), 15, "{tf:?}");
    let z = |name: &str| {
        tf.iter()
            .find(|t| t["child_frame_id"] == name)
            .unwrap_or_else(|| panic!("no {name}"))["translation"]["z"]
            .as_f64()
            .unwrap()
    };
    // Standing at the start: soles on the floor, the waist above them.
    assert!(z("left_sole").abs() < 0.02 && z("right_sole").abs() < 0.02);
    assert!(z("waist") > 0.4, "waist at {}", z("waist"));
    let cog = &v["first"]["/measured"]["cog"];
    assert!(cog["x"].as_f64().unwrap().abs() < 0.1, "{cog}");
}
