//! `walk.mcap` of `host-sim run`, read back with the `mcap` crate's reader: the channel set
//! (with Foxglove's scene and pose schemas),
//! a JSON schema on every channel, one message per row of `trajectory.csv` (and per line of
//! `can.log`), non-decreasing log times, and values equal to the CSV and the log within the
//! CSV's rounding. Then read again by an independent reader, PyPI's `mcap` package, with every
//! message validated against its schema (`jsonschema`); `tests/run-all.sh` installs both and
//! sets `WALK_REQUIRE_MCAP_TOOLS=1`, without which a missing reader skips that test.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::process::Command;

use host_sim::output::mcap::{parse_log_line, SOLE_THICKNESS, TOPICS, WORLD_FRAME};
use host_sim::sim::bus::LOG_EPOCH_S;
use serde_json::Value;

/// The CSV has 6 decimals (1 µm, 1 µrad): a value read back differs by at most half a unit
/// of the last place, plus the binary rounding of the printed decimal.
const CSV_TOL: f64 = 0.5e-6 + 1e-12;

/// `host-sim run <scenario>` into a fresh directory named by `tag`.
fn run(scenario: &str, tag: &str) -> PathBuf {
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mcap-{tag}"));
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["run", scenario, "--out", out.to_str().expect("UTF-8 path")])
        .output()
        .expect("run host-sim");
    assert!(
        o.status.success(),
        "host-sim run {scenario}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn read(path: &std::path::Path) -> Csv {
        let text = std::fs::read_to_string(path).expect("trajectory.csv");
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        Csv { header, rows }
    }

    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    }

    fn num(&self, row: usize, name: &str) -> f64 {
        self.rows[row][self.col(name)]
            .parse()
            .unwrap_or_else(|_| panic!("row {row} {name}: not a number"))
    }
}

/// A message as read back: topic, log time, publish time, sequence, JSON.
struct Msg {
    topic: String,
    log_time: u64,
    publish_time: u64,
    sequence: u32,
    json: Value,
}

fn read_mcap(path: &std::path::Path) -> (Vec<Msg>, mcap::read::Summary) {
    let bytes = std::fs::read(path).expect("walk.mcap");
    let summary = mcap::read::Summary::read(&bytes)
        .expect("summary readable")
        .expect("the file has a summary section");
    let mut msgs = Vec::new();
    for m in mcap::MessageStream::new(&bytes).expect("MCAP magic and header") {
        let m = m.expect("a valid message record");
        assert_eq!(m.channel.message_encoding, "json", "{}", m.channel.topic);
        let json: Value = serde_json::from_slice(&m.data)
            .unwrap_or_else(|e| panic!("{}: message is not JSON: {e}", m.channel.topic));
        msgs.push(Msg {
            topic: m.channel.topic.clone(),
            log_time: m.log_time,
            publish_time: m.publish_time,
            sequence: m.sequence,
            json,
        });
    }
    (msgs, summary)
}

fn f(v: &Value, path: &[&str]) -> f64 {
    let mut x = v;
    for p in path {
        x = &x[*p];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("{path:?} is not a number in {v}"))
}

#[test]
fn fig4_mcap_reads_back_like_the_csv_and_the_can_log() {
    let out = run("fig4", "rust");
    let csv = Csv::read(&out.join("trajectory.csv"));
    let log: Vec<_> = std::fs::read_to_string(out.join("can.log"))
        .expect("can.log")
        .lines()
        .map(|l| parse_log_line(l).expect("can.log line"))
        .collect();
    let (msgs, summary) = read_mcap(&out.join("walk.mcap"));

    // Channels and schemas, from the summary section.
    let topics: BTreeSet<&str> = summary
        .channels
        .values()
        .map(|c| c.topic.as_str())
        .collect();
    assert_eq!(topics, TOPICS.iter().copied().collect::<BTreeSet<_>>());
    for c in summary.channels.values() {
        let s = c
            .schema
            .as_ref()
            .unwrap_or_else(|| panic!("{}: no schema", c.topic));
        assert_eq!(s.encoding, "jsonschema", "{}", c.topic);
        let schema: Value = serde_json::from_slice(&s.data)
            .unwrap_or_else(|e| panic!("{}: schema is not JSON: {e}", c.topic));
        assert_eq!(schema["type"], "object", "{}", c.topic);
        assert_eq!(schema["title"], s.name.as_str(), "{}", c.topic);
        assert!(
            schema["properties"]
                .as_object()
                .is_some_and(|p| !p.is_empty()),
            "{}: schema has no properties",
            c.topic
        );
    }
    let schema_of = |topic: &str| {
        summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .and_then(|c| c.schema.as_ref())
            .map(|s| s.name.clone())
    };
    assert_eq!(
        schema_of("/feet/left").as_deref(),
        Some("foxglove.PoseInFrame")
    );
    assert_eq!(
        schema_of("/feet/right").as_deref(),
        Some("foxglove.PoseInFrame")
    );
    assert_eq!(schema_of("/scene").as_deref(), Some("foxglove.SceneUpdate"));

    // Message counts: a row of the CSV is one message on every trajectory channel; every
    // row has a multi-body ZMP in a fault-free run of fig4; a line of can.log is a frame.
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    for m in &msgs {
        *count.entry(m.topic.as_str()).or_default() += 1;
    }
    let rows = csv.rows.len();
    let mb_rows = (0..rows)
        .filter(|&r| !csv.rows[r][csv.col("mb_zmp_x")].is_empty())
        .count();
    assert!(rows > 1000, "{rows} CSV rows");
    assert_eq!(count["/reference"], rows);
    assert_eq!(count["/multibody/zmp"], mb_rows);
    assert_eq!(count["/feet/left"], rows);
    assert_eq!(count["/feet/right"], rows);
    assert_eq!(count["/scene"], rows);
    assert_eq!(count["/can"], log.len());
    assert!(log.len() > 5 * rows, "{} frames for {rows} rows", log.len());
    let stats = summary.stats.as_ref().expect("statistics record");
    assert_eq!(stats.message_count, msgs.len() as u64);
    assert_eq!(stats.channel_count as usize, TOPICS.len());

    // Log times never decrease over the file; publish time = log time; sequences count up
    // per channel from 0.
    let mut next_seq: BTreeMap<&str, u32> = BTreeMap::new();
    for w in msgs.windows(2) {
        assert!(
            w[0].log_time <= w[1].log_time,
            "{} at {} before {} at {}",
            w[0].topic,
            w[0].log_time,
            w[1].topic,
            w[1].log_time
        );
    }
    for m in &msgs {
        assert_eq!(m.publish_time, m.log_time);
        let s = next_seq.entry(m.topic.as_str()).or_default();
        assert_eq!(m.sequence, *s, "{}", m.topic);
        *s += 1;
    }
    assert_eq!(stats.message_start_time, msgs[0].log_time);
    assert_eq!(stats.message_end_time, msgs[msgs.len() - 1].log_time);

    // Values against the CSV (every row of /reference, the feet and the multi-body ZMP).
    let epoch_ns = LOG_EPOCH_S * 1_000_000_000;
    let on = |topic: &'static str| msgs.iter().filter(move |m| m.topic == topic);
    for (r, m) in on("/reference").enumerate() {
        let t = csv.num(r, "t");
        // The CSV time has 3 decimals and is a whole number of ms: exact to 1 ns.
        let ns = (t * 1e9).round() as u64;
        assert_eq!(m.log_time, epoch_ns + ns, "row {r}");
        assert!((f(&m.json, &["t"]) - t).abs() <= 0.5e-3, "row {r} t");
        for (path, col) in [
            (&["cog", "x"][..], "cog_x"),
            (&["cog", "y"], "cog_y"),
            (&["cog", "vx"], "cog_vx"),
            (&["cog", "vy"], "cog_vy"),
            (&["zmp", "x"], "zmp_x"),
            (&["zmp", "y"], "zmp_y"),
            (&["left", "x"], "left_x"),
            (&["left", "z"], "left_z"),
            (&["right", "y"], "right_y"),
            (&["right", "yaw"], "right_yaw"),
        ] {
            let (a, b) = (f(&m.json, path), csv.num(r, col));
            assert!((a - b).abs() <= CSV_TOL, "row {r} {col}: mcap {a}, csv {b}");
        }
        assert_eq!(m.json["phase"], csv.rows[r][csv.col("phase")].as_str());
    }
    for (r, m) in on("/multibody/zmp").enumerate() {
        for (k, col) in [("x", "mb_zmp_x"), ("y", "mb_zmp_y")] {
            let (a, b) = (f(&m.json, &[k]), csv.num(r, col));
            assert!((a - b).abs() <= CSV_TOL, "row {r} {col}: mcap {a}, csv {b}");
        }
    }
    for (side, topic) in [("left", "/feet/left"), ("right", "/feet/right")] {
        for (r, m) in on(topic).enumerate() {
            assert_eq!(m.json["frame_id"], WORLD_FRAME);
            let ts = f(&m.json, &["timestamp", "sec"]) as u64 * 1_000_000_000
                + f(&m.json, &["timestamp", "nsec"]) as u64;
            assert_eq!(ts, m.log_time, "{topic} row {r}: timestamp");
            let p = |k| f(&m.json, &["pose", "position", k]);
            let q = |k| f(&m.json, &["pose", "orientation", k]);
            for (k, col) in [("x", "x"), ("y", "y"), ("z", "z")] {
                let b = csv.num(r, &format!("{side}_{col}"));
                assert!((p(k) - b).abs() <= CSV_TOL, "{topic} row {r} {k}");
            }
            // A rotation about z by the foot's yaw: a unit quaternion, yaw = 2·atan2(z, w).
            let norm = (q("x").powi(2) + q("y").powi(2) + q("z").powi(2) + q("w").powi(2)).sqrt();
            assert!((norm - 1.0).abs() < 1e-12, "{topic} row {r}: |q| = {norm}");
            assert_eq!((q("x"), q("y")), (0.0, 0.0));
            let yaw = 2.0 * q("z").atan2(q("w"));
            let b = csv.num(r, &format!("{side}_yaw"));
            assert!(
                (yaw - b).abs() <= CSV_TOL,
                "{topic} row {r} yaw {yaw} csv {b}"
            );
        }
    }
    // The scene: the soles at the feet (cube centres half a sole thickness above the sole),
    // the COG at the pendulum's height, the planned and the multi-body ZMP on the floor.
    let hrp2 = planner_core::gait::GaitParams::<f64>::hrp2();
    let (cog_height, sole) = (
        hrp2.cog_height,
        [2.0 * hrp2.sole_half_length, 2.0 * hrp2.sole_half_width],
    );
    for (r, m) in on("/scene").enumerate() {
        let e = &m.json["entities"][0];
        assert_eq!(e["frame_id"], WORLD_FRAME);
        assert_eq!(e["id"], "walk");
        let ts = f(e, &["timestamp", "sec"]) as u64 * 1_000_000_000
            + f(e, &["timestamp", "nsec"]) as u64;
        assert_eq!(ts, m.log_time, "/scene row {r}: timestamp");
        let at = |shape: &Value, k: &str| f(shape, &["pose", "position", k]);
        let cubes = e["cubes"].as_array().expect("cubes");
        assert_eq!(cubes.len(), 2, "/scene row {r}");
        for (cube, side) in cubes.iter().zip(["left", "right"]) {
            assert_eq!(f(cube, &["size", "x"]), sole[0]);
            assert_eq!(f(cube, &["size", "y"]), sole[1]);
            assert_eq!(f(cube, &["size", "z"]), SOLE_THICKNESS);
            for k in ["x", "y"] {
                let b = csv.num(r, &format!("{side}_{k}"));
                assert!(
                    (at(cube, k) - b).abs() <= CSV_TOL,
                    "/scene row {r} {side} {k}"
                );
            }
            let z = csv.num(r, &format!("{side}_z")) + 0.5 * SOLE_THICKNESS;
            assert!(
                (at(cube, "z") - z).abs() <= CSV_TOL,
                "/scene row {r} {side} z"
            );
        }
        let spheres = e["spheres"].as_array().expect("spheres");
        assert_eq!(spheres.len(), 3, "/scene row {r}: COG, ZMP, multi-body ZMP");
        for (sphere, (cx, cy, z)) in spheres.iter().zip([
            ("cog_x", "cog_y", cog_height),
            ("zmp_x", "zmp_y", 0.0),
            ("mb_zmp_x", "mb_zmp_y", 0.0),
        ]) {
            assert!(
                (at(sphere, "x") - csv.num(r, cx)).abs() <= CSV_TOL,
                "row {r} {cx}"
            );
            assert!(
                (at(sphere, "y") - csv.num(r, cy)).abs() <= CSV_TOL,
                "row {r} {cy}"
            );
            assert!((at(sphere, "z") - z).abs() < 1e-12, "row {r} {cx} z");
        }
    }
    // The frames equal can.log, line by line (time to the log's 1 µs, identifier, data).
    for (i, (m, l)) in on("/can").zip(&log).enumerate() {
        assert_eq!(m.log_time, l.unix_us * 1000, "frame {i}");
        assert_eq!(m.json["id"].as_u64(), Some(u64::from(l.id)), "frame {i}");
        assert_eq!(m.json["id_hex"], format!("{:03X}", l.id), "frame {i}");
        assert_eq!(
            m.json["dlc"].as_u64(),
            Some(l.data.len() as u64),
            "frame {i}"
        );
        let data: Vec<u8> = m.json["data"]
            .as_array()
            .expect("data array")
            .iter()
            .map(|b| u8::try_from(b.as_u64().expect("byte")).expect("byte"))
            .collect();
        assert_eq!(data, l.data, "frame {i}");
        let t = (l.unix_us - LOG_EPOCH_S * 1_000_000) as f64 * 1e-6;
        assert!((f(&m.json, &["t"]) - t).abs() < 1e-9, "frame {i} t");
    }
}

#[test]
fn bad_log_lines_are_refused_with_the_line_quoted() {
    for line in [
        "",
        "1767225600.000085 can0 020#00",
        "(1767225600.85) can0 020#00",
        "(1767225600.000085) can0 0200#00",
        "(1767225600.000085) can0 020#0",
        "(1767225600.000085) can0 020#000102030405060708",
        "(1767225600.000085) can0 02G#00",
        "(99999999999999999.000000) can0 020#00",
    ] {
        let e = parse_log_line(line).expect_err(line);
        assert!(e.contains(&format!("{line:?}")), "{e}");
    }
    let ok = parse_log_line("(1767225600.000085) can0 2A0#00FF").expect("valid line");
    assert_eq!(ok.unix_us, 1_767_225_600_000_085);
    assert_eq!((ok.id, ok.data), (0x2A0, vec![0x00, 0xFF]));
}

/// Set by `tests/run-all.sh`: a missing Python MCAP reader fails the test instead of skipping.
const REQUIRE: &str = "WALK_REQUIRE_MCAP_TOOLS";

/// An independent reader: PyPI's `mcap` (summary, then every message in file order), each
/// message validated against its channel's JSON schema with `jsonschema`. Prints, per topic
/// (sorted): topic, schema name, schema encoding, message encoding, count, first and last log
/// time; then the number of log times that went back, the number of schema violations, and
/// `cog.x` of /reference message 800.
const PYTHON: &str = r#"
import json, sys
import jsonschema
from mcap.reader import make_reader
with open(sys.argv[1], "rb") as f:
    reader = make_reader(f)
    summary = reader.get_summary()
    validators = {}
    for cid, ch in summary.channels.items():
        schema = summary.schemas[ch.schema_id]
        validators[ch.topic] = jsonschema.Draft202012Validator(json.loads(schema.data))
    seen = {}
    back = bad = 0
    last = -1
    cog_800 = None
    for schema, ch, msg in reader.iter_messages(log_time_order=False):
        if msg.log_time < last:
            back += 1
        last = msg.log_time
        value = json.loads(msg.data)
        if not validators[ch.topic].is_valid(value):
            bad += 1
        s = seen.setdefault(ch.topic, [schema.name, schema.encoding, ch.message_encoding, 0, msg.log_time, 0])
        if ch.topic == "/reference" and s[3] == 800:
            cog_800 = value["cog"]["x"]
        s[3] += 1
        s[5] = msg.log_time
for topic in sorted(seen):
    print(topic, *seen[topic])
print(back)
print(bad)
print(repr(cog_800))
"#;

#[test]
fn python_mcap_reads_the_file_and_every_message_fits_its_schema() {
    let has = Command::new("python3")
        .args(["-c", "import mcap.reader, zstandard, jsonschema"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has {
        assert!(
            !std::env::var(REQUIRE).is_ok_and(|v| !v.is_empty() && v != "0"),
            "the Python MCAP reader is missing and {REQUIRE}=1 (pip install mcap zstandard \
             jsonschema)"
        );
        eprintln!("mcap: SKIPPED the Python reader check: not installed ({REQUIRE}=1 makes this a failure)");
        return;
    }
    let out = run("fig4", "python");
    let path = out.join("walk.mcap");
    let o = Command::new("python3")
        .args(["-c", PYTHON])
        .arg(&path)
        .output()
        .expect("run python3");
    assert!(
        o.status.success(),
        "python mcap: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8(o.stdout).expect("UTF-8");
    let lines: Vec<&str> = text.lines().collect();
    // What the Rust reader sees, in the same form.
    let (msgs, summary) = read_mcap(&path);
    let mut want: Vec<String> = Vec::new();
    let mut topics: Vec<&str> = TOPICS.to_vec();
    topics.sort_unstable();
    for topic in &topics {
        let ch = summary
            .channels
            .values()
            .find(|c| c.topic == *topic)
            .expect("channel");
        let schema = ch.schema.as_ref().expect("schema");
        let on: Vec<&Msg> = msgs.iter().filter(|m| m.topic == *topic).collect();
        want.push(format!(
            "{topic} {} {} {} {} {} {}",
            schema.name,
            schema.encoding,
            ch.message_encoding,
            on.len(),
            on[0].log_time,
            on[on.len() - 1].log_time
        ));
    }
    assert_eq!(
        lines[..topics.len()],
        want,
        "python mcap against the Rust reader"
    );
    assert_eq!(lines[topics.len()], "0", "log times that went back");
    assert_eq!(
        lines[topics.len() + 1],
        "0",
        "messages that do not fit their schema"
    );
    let csv = Csv::read(&out.join("trajectory.csv"));
    let cog: f64 = lines[topics.len() + 2]
        .parse()
        .expect("cog.x of message 800");
    assert!((cog - csv.num(800, "cog_x")).abs() <= CSV_TOL, "{cog}");
    eprintln!("mcap: Python reader: {}", want.join("; "));
}
