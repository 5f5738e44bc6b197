//! `can.log` against the real tools: the line format of `candump -l` with an absolute time from
//! the stated epoch (`host_sim::sim::bus::LOG_EPOCH_S`), the documented offset to `trajectory.csv`,
//! can-utils' `log2asc` / `asc2log` round trip and python-can's `CanutilsLogReader`.
//!
//! The tool checks skip (and say so) when the tools are missing, unless
//! `WALK_REQUIRE_CAN_TOOLS=1`, which makes a missing tool a failure (CI sets it after
//! `apt-get install -y can-utils` and `pip install python-can`).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use host_sim::scenario::{self, BUILT_IN};
use host_sim::sim::bus::{log_line, parse_log_line, Faults, LogEntry, LOG_EPOCH_S, LOG_IFACE};
use host_sim::sim::{simulate, SimConfig};
use planner_core::wire::ids;

const REQUIRE: &str = "WALK_REQUIRE_CAN_TOOLS";
/// The scenario whose `host-sim run` output is given to the tools: walking, a modification
/// and a re-plan with an adjusted single support.
const SCENARIO: &str = "fig4";
const EPOCH_US: u64 = LOG_EPOCH_S * 1_000_000;
const TICK_US: u64 = 5_000;

fn required() -> bool {
    std::env::var(REQUIRE).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// A tool is missing: a failure under `WALK_REQUIRE_CAN_TOOLS=1`, else a skip that says so.
fn missing(what: &str) {
    assert!(
        !required(),
        "{what} is missing and {REQUIRE}=1 (Debian: apt-get install -y can-utils; \
         pip install python-can)"
    );
    eprintln!("canlog: SKIPPED the {what} check: not installed ({REQUIRE}=1 makes this a failure)");
}

fn on_path(tool: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(tool).is_file()))
}

/// `host-sim run <scenario> --out <dir>` (the binary, so the files are exactly what it writes).
fn host_sim_run(scenario: &str, tag: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("canlog-{tag}"));
    let _ = fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["run", scenario, "--out"])
        .arg(&dir)
        .output()
        .expect("run host-sim");
    assert!(
        out.status.success(),
        "host-sim run {scenario}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir
}

fn read_log(path: &Path) -> (Vec<String>, Vec<LogEntry>) {
    let text = fs::read_to_string(path).unwrap();
    assert!(
        text.ends_with('\n'),
        "{}: no final line end",
        path.display()
    );
    let lines: Vec<String> = text.lines().map(str::to_string).collect();
    let entries = lines
        .iter()
        .map(|l| parse_log_line(l).unwrap_or_else(|| panic!("not a log line: {l:?}")))
        .collect();
    (lines, entries)
}

fn hex(data: &[u8]) -> String {
    data.iter().map(|b| format!("{b:02X}")).collect()
}

/// The shape of a `candump -l` line, checked character by character (independently of
/// `parse_log_line`): `(` 10 digits `.` 6 digits `) can0 ` 3 upper-case hex digits `#` an even
/// number (at most 16) of upper-case hex digits.
fn candump_l_shape(line: &str) -> bool {
    let b = line.as_bytes();
    let digit = |c: &u8| c.is_ascii_digit();
    let uhex = |c: &u8| matches!(c, b'0'..=b'9' | b'A'..=b'F');
    let head = "(0000000000.000000) can0 000#".len();
    if b.len() < head || b.len() > head + 16 || (b.len() - head) % 2 != 0 {
        return false;
    }
    b[0] == b'('
        && b[1..11].iter().all(digit)
        && b[11] == b'.'
        && b[12..18].iter().all(digit)
        && &b[18..25] == b") can0 "
        && b[25..28].iter().all(uhex)
        && b[28] == b'#'
        && b[29..].iter().all(uhex)
}

/// Always runs: every line of every built-in scenario's log (and of a faulty bus) has the
/// format, the log starts at the epoch plus the first frame's delivery and never goes back.
#[test]
fn the_log_is_candump_l_from_the_stated_epoch() {
    assert_eq!(LOG_EPOCH_S, 1_767_225_600, "2026-01-01T00:00:00Z");
    assert_eq!(LOG_IFACE, "can0");
    let faulty = SimConfig {
        // The node's frames are delayed, duplicated and lost (the controller's arrive, so the
        // scenario runs to its end).
        faults: Faults {
            from_port: Some(1),
            delay: 0.05,
            delay_ns: 3_000_000,
            duplicate: 0.05,
            drop: 0.01,
            ..Faults::default()
        },
        ..SimConfig::default()
    };
    for name in BUILT_IN {
        let s = scenario::built_in(name).unwrap();
        for (what, cfg) in [("clean", SimConfig::default()), ("faulty", faulty)] {
            let sim = simulate(&s, &cfg).unwrap();
            let log = &sim.can_log;
            assert!(log.len() > 1000, "{name} {what}: {} lines", log.len());
            let mut last = 0;
            for line in log {
                assert!(candump_l_shape(line), "{name} {what}: {line:?}");
                let e = parse_log_line(line).unwrap();
                assert_eq!(log_line(e.sim_us().unwrap() * 1000, &e.frame), *line);
                assert!(e.unix_us >= last, "{name} {what}: time goes back at {line}");
                last = e.unix_us;
            }
            if what == "faulty" {
                assert!(
                    sim.bus.delayed > 0 && sim.bus.duplicated > 0,
                    "{:?}",
                    sim.bus
                );
                continue;
            }
            // The first frame leaves at the handshake cycle's poll (simulated time 2.5 ms) and
            // is logged when its transmission ends (1 µs a bit at 1 Mbit/s); the last one
            // within the simulated time (the handshake's cycle and the ticks).
            let first = parse_log_line(&log[0]).unwrap();
            let bit_us = 1_000_000 / u64::from(cfg.bitrate);
            assert_eq!(
                first.unix_us,
                EPOCH_US + TICK_US / 2 + u64::from(first.frame.wire_bits()) * bit_us,
                "{name}: {}",
                log[0]
            );
            let ticks = sim.run.trajectory.len() as u64;
            assert!(last - EPOCH_US <= ticks * TICK_US, "{name}");
            assert_eq!(
                log.len() as u64,
                sim.bus.sent,
                "{name}: a clean bus logs every frame"
            );
        }
    }
    // What `host-sim run` writes is this log, one line each, with a final line end.
    let dir = host_sim_run("straight", "format");
    let (lines, _) = read_log(&dir.join("can.log"));
    let sim = simulate(
        &scenario::built_in("straight").unwrap(),
        &SimConfig::default(),
    )
    .unwrap();
    assert_eq!(lines, sim.can_log);
}

/// The documented offset: CSV row `j` (t = 5j ms) is the poll that runs at bus time
/// t + 2.5 ms (the first 5 ms are the handshake's cycle); the frames it publishes are logged
/// at EPOCH + t + 2.5 ms + d, 0 < d ≤ 2.5 ms, and the controller's commands of tick k at
/// EPOCH + 5(k + 1) ms + d, 0 < d < 2.5 ms (the handshake's `Reset` with those of tick 0).
#[test]
fn the_log_and_trajectory_csv_are_offset_as_documented() {
    for name in ["straight", SCENARIO] {
        let dir = host_sim_run(name, &format!("offset-{name}"));
        let (_, log) = read_log(&dir.join("can.log"));
        let csv = fs::read_to_string(dir.join("trajectory.csv")).unwrap();
        let mut rows = csv.lines();
        assert!(rows.next().unwrap().starts_with("t,cog_x,cog_y,"));
        let rows: Vec<(f64, f64, f64)> = rows
            .map(|r| {
                let v: Vec<f64> = r.split(',').take(3).map(|x| x.parse().unwrap()).collect();
                (v[0], v[1], v[2])
            })
            .collect();
        for (j, r) in rows.iter().enumerate() {
            assert!(
                (r.0 - j as f64 * 0.005).abs() < 1e-9,
                "{name}: row {j} t = {}",
                r.0
            );
        }
        let mut cog_frames = vec![0usize; rows.len()];
        for e in &log {
            let t = e.sim_us().unwrap();
            let id = e.frame.id;
            if ids::is_command(id) {
                // Sent at the start of tick k, delivered within its first half.
                let d = t % TICK_US;
                assert!(
                    d > 0 && d < TICK_US / 2,
                    "{name}: command {id:03X} at {t} µs"
                );
                continue;
            }
            // A node frame: published by the poll of CSV row j = ceil(t / 5 ms) − 1 (the
            // handshake cycle's frames before row 0's time: no row).
            let Some(j) = (t.div_ceil(TICK_US) as usize).checked_sub(1) else {
                continue;
            };
            let t_csv = j as u64 * TICK_US;
            let d = t - TICK_US / 2 - t_csv;
            assert!(
                d > 0 && d <= TICK_US / 2,
                "{name}: node frame {id:03X} at {t} µs"
            );
            if id == ids::COG {
                let f = &e.frame.data;
                let um = |i: usize| i32::from_le_bytes([f[i], f[i + 1], f[i + 2], f[i + 3]]);
                let (x, y) = (f64::from(um(0)) * 1e-6, f64::from(um(4)) * 1e-6);
                let r = rows[j];
                assert!(
                    (x - r.1).abs() < 1.5e-6 && (y - r.2).abs() < 1.5e-6,
                    "{name}: COG frame at {t} µs ({x}, {y}) is not CSV row {j} at {} s ({}, {})",
                    r.0,
                    r.1,
                    r.2
                );
                cog_frames[j] += 1;
            }
        }
        // Every row after the first has exactly one COG frame, row 0 none.
        assert_eq!(cog_frames[0], 0, "{name}");
        assert!(
            cog_frames[1..].iter().all(|&n| n == 1),
            "{name}: {cog_frames:?}"
        );
    }
}

/// One frame line of an ASC file (`log2asc`, classic CAN): time relative to the first frame
/// \[µs\], channel, identifier, data.
fn parse_asc_frame(line: &str) -> Option<(u64, u32, u16, Vec<u8>)> {
    let w: Vec<&str> = line.split_whitespace().collect();
    let (s, us) = w.first()?.split_once('.')?;
    if us.len() != 6 {
        return None;
    }
    let t = s.parse::<u64>().ok()? * 1_000_000 + us.parse::<u64>().ok()?;
    if w.len() < 6 || w[3] != "Rx" || w[4] != "d" {
        return None;
    }
    let channel = w[1].parse().ok()?;
    let id = u16::from_str_radix(w[2], 16).ok()?;
    let dlc = usize::from_str_radix(w[5], 16).ok()?;
    let data: Vec<u8> = w[6..]
        .iter()
        .map(|b| u8::from_str_radix(b, 16))
        .collect::<Result<_, _>>()
        .ok()?;
    (data.len() == dlc).then_some((t, channel, id, data))
}

/// can-utils: `log2asc` gives one header, the log's timestamps (relative to the first frame, to
/// the microsecond) and every frame; `asc2log` gives the frames back.
#[test]
fn log2asc_and_asc2log_round_trip() {
    if !(on_path("log2asc") && on_path("asc2log")) {
        missing("can-utils (log2asc, asc2log)");
        return;
    }
    let dir = host_sim_run(SCENARIO, "can-utils");
    let log_path = dir.join("can.log");
    let (_, log) = read_log(&log_path);
    let asc_path = dir.join("can.asc");
    let out = Command::new("log2asc")
        .env("TZ", "UTC")
        .env("LC_ALL", "C")
        .arg("-I")
        .arg(&log_path)
        .arg("-O")
        .arg(&asc_path)
        .arg(LOG_IFACE)
        .output()
        .expect("run log2asc");
    assert!(
        out.status.success(),
        "log2asc: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let asc = fs::read_to_string(&asc_path).unwrap();
    let mut frames = Vec::new();
    let (mut dates, mut bases) = (Vec::new(), 0);
    for line in asc.lines() {
        if let Some(f) = parse_asc_frame(line) {
            frames.push(f);
        } else if line.starts_with("date ") {
            assert!(frames.is_empty(), "a header after the frames: {line}");
            dates.push(line.to_string());
        } else if line.starts_with("base ") {
            assert!(frames.is_empty(), "a header after the frames: {line}");
            bases += 1;
        } else {
            assert!(
                line == "no internal events logged" || line.starts_with("//"),
                "unexpected ASC line {line:?}"
            );
        }
    }
    // One header, dated by the first frame's second: the epoch.
    assert_eq!(dates, ["date Thu Jan  1 00:00:00 2026"], "{}", dates.len());
    assert_eq!(bases, 1);
    assert_eq!(frames.len(), log.len(), "every frame");
    let t0 = log[0].unix_us;
    for (k, ((t, channel, id, data), e)) in frames.iter().zip(&log).enumerate() {
        assert_eq!(*t, e.unix_us - t0, "frame {k}: time");
        assert!(k == 0 || *t > 0, "frame {k}: zero timestamp");
        assert_eq!(*channel, 1);
        assert_eq!(*id, e.frame.id, "frame {k}");
        assert_eq!(data.as_slice(), e.frame.bytes(), "frame {k}");
    }
    assert!(
        frames.windows(2).all(|w| w[0].0 <= w[1].0),
        "timestamps increase"
    );

    // And back: asc2log re-bases the times (2020.11 on the current time, its date parser
    // failing; later versions on the date line), so compare relative to the first frame.
    let back_path = dir.join("back.log");
    let out = Command::new("asc2log")
        .env("TZ", "UTC")
        .env("LC_ALL", "C")
        .arg("-I")
        .arg(&asc_path)
        .arg("-O")
        .arg(&back_path)
        .output()
        .expect("run asc2log");
    assert!(
        out.status.success(),
        "asc2log: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let back = fs::read_to_string(&back_path).unwrap();
    let back: Vec<&str> = back.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(back.len(), log.len(), "asc2log: every frame");
    let mut base = None;
    for (k, (line, e)) in back.iter().zip(&log).enumerate() {
        // `(s.us) can0 ID#DATA` with an optional direction (` R`).
        let w: Vec<&str> = line.split_whitespace().collect();
        assert!(
            w.len() == 3 || (w.len() == 4 && (w[3] == "R" || w[3] == "T")),
            "{line}"
        );
        let direct = format!("(0.000000) {} {}", w[1], w[2]);
        let parsed = parse_log_line(&direct).unwrap_or_else(|| panic!("asc2log line {line}"));
        assert_eq!(parsed.frame, e.frame, "asc2log frame {k}: {line}");
        let (s, us) = w[0]
            .strip_prefix('(')
            .and_then(|t| t.strip_suffix(')'))
            .and_then(|t| t.split_once('.'))
            .unwrap_or_else(|| panic!("asc2log time {line}"));
        assert_eq!(us.len(), 6, "{line}");
        let t: u64 = s.parse::<u64>().unwrap() * 1_000_000 + us.parse::<u64>().unwrap();
        let base = *base.get_or_insert(t);
        assert_eq!(t - base, e.unix_us - t0, "asc2log frame {k}: time");
    }
    eprintln!(
        "canlog: log2asc/asc2log: {} frames over {:.6} s, one header ({}), round trip exact to 1 µs \
         (asc2log's first time {})",
        log.len(),
        (log.last().unwrap().unix_us - t0) as f64 * 1e-6,
        dates[0],
        back[0].split_whitespace().next().unwrap()
    );
}

/// The canonical text of one frame, for the digest: `µs ID#DATA\n`.
fn canonical(unix_us: u64, id: u16, data: &[u8]) -> String {
    format!("{unix_us} {id:03X}#{}\n", hex(data))
}

/// FNV-1a 64, as the Python snippet computes it.
fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

const PYTHON: &str = r#"
import sys, can
msgs = list(can.CanutilsLogReader(sys.argv[1]))
h = 0xcbf29ce484222325
for m in msgs:
    s = "%d %03X#%s\n" % (round(m.timestamp * 1e6), m.arbitration_id, bytes(m.data).hex().upper())
    for b in s.encode():
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
print(len(msgs))
print(round(msgs[0].timestamp * 1e6))
print(round(msgs[-1].timestamp * 1e6))
print("%016x" % h)
print(",".join(sorted({str(m.channel) for m in msgs})))
print(sum(1 for m in msgs if m.is_extended_id or m.is_remote_frame or m.is_error_frame or m.is_fd or not m.is_rx))
print(can.__version__)
"#;

/// python-can's `CanutilsLogReader` reads the log as Rust does: count, first and last time,
/// a digest over every frame (time to the microsecond, identifier, data).
#[test]
fn python_can_reads_the_log() {
    let has = Command::new("python3")
        .args(["-c", "import can"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has {
        missing("python-can (python3 -c 'import can')");
        return;
    }
    let dir = host_sim_run(SCENARIO, "python-can");
    let log_path = dir.join("can.log");
    let (_, log) = read_log(&log_path);
    let out = Command::new("python3")
        .args(["-c", PYTHON])
        .arg(&log_path)
        .output()
        .expect("run python3");
    assert!(
        out.status.success(),
        "python-can: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let got: Vec<&str> = text.lines().collect();
    let digest: String = log
        .iter()
        .map(|e| canonical(e.unix_us, e.frame.id, e.frame.bytes()))
        .collect();
    let want = [
        log.len().to_string(),
        log[0].unix_us.to_string(),
        log.last().unwrap().unix_us.to_string(),
        format!("{:016x}", fnv(&digest)),
        LOG_IFACE.to_string(),
        "0".to_string(),
    ];
    assert_eq!(got[..6], want, "python-can against Rust");
    eprintln!(
        "canlog: python-can {} read {} frames, {} µs … {} µs, digest {}",
        got[6], want[0], want[1], want[2], want[3]
    );
}

/// The readers of candump text (`bus::parse_candump_line`, used by replays and by the MCAP
/// writer's `mcap_log::parse_log_line`) refuse, without panicking, what is not a line with a
/// standard identifier: non-ASCII text where hexadecimal is expected (the MCAP reader used to
/// slice it at byte offsets and panicked: found by the fuzz target `text`), identifiers above
/// 0x7FF, signs, odd data lengths; and accept any interface and either case.
#[test]
fn candump_readers_refuse_what_is_not_a_frame() {
    use host_sim::output::mcap::parse_log_line as mcap_line;
    use host_sim::sim::bus::parse_candump_line;
    for bad in [
        "(1767225600.000000) can0 010#0000\u{fffd}E",
        "(1767225600.000000) can0 01\u{e9}#00",
        "(1767225600.000000) can0 800#00",
        "(1767225600.000000) can0 +10#00",
        "(1767225600.000000) can0 010#+1",
        "(1767225600.000000) can0 010#012",
        "(1767225600.00000) can0 010#01",
        "(1767225600.000000)",
    ] {
        assert_eq!(parse_candump_line(bad), None, "{bad:?}");
        assert!(mcap_line(bad).is_err(), "{bad:?}");
    }
    let e = parse_candump_line("(1767225600.002500) vcan1 1a0#0aFf").expect("a frame");
    assert_eq!(
        (e.unix_us, e.frame.id, e.frame.bytes()),
        (1_767_225_600_002_500, 0x1A0, &[0x0A, 0xFF][..])
    );
    let m = mcap_line("(1767225600.002500) vcan1 1a0#0aFf").expect("a frame");
    assert_eq!(
        (m.unix_us, m.id, &m.data[..]),
        (e.unix_us, e.frame.id, e.frame.bytes())
    );
}
