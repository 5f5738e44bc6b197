//! The firmware's QEMU image (`firmware/qemu`, Cortex-M7 `mps2-an500`) against the host.
//!
//! The image runs planner-core's CAN node (`Node::poll`, as the board does) fed through an
//! in-memory CAN device with the scenario's command frames, at the ticks host-sim's
//! `sim::simulate` sends them. This test builds the image, runs it twice under
//! `qemu-system-arm -icount shift=0` and checks, against `sim::simulate` on a fault-free bus
//! (the same node fed the same frames):
//! * the frames it sent (`CMD` lines) are host-sim's timeline through `wire::StepBook` and
//!   `Command::encode`, command for command, and the node answered each the same way in the
//!   same cycle;
//! * every reference is bit-identical (FNV-1a digest over all ticks), the sampled `REF` values
//!   agree (to 1e-9 m and m/s, printed as max difference), the same single supports were
//!   adjusted by the same amounts, and the node transmitted the same frames (count and digest
//!   over identifier and data, against the bus's candump log) with the same counters;
//! * the instruction counts are repeatable: both runs print the same report, line for line;
//! * the instructions-per-timer-tick factor (40) holds, and the stack stays inside its region;
//! * the worst control cycle (a whole `Node::poll`) fits 5 % of a 5 ms cycle at 480 MHz
//!   (120,000 instructions).
//!
//! `qemu-system-arm` comes from Debian's `qemu-system-arm` package, which `tests/run-all.sh`
//! installs. Without it these tests fail, unless `WALK_SKIP_QEMU=1` is set.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command as Process;
use std::sync::OnceLock;

use host_sim::scenario::{built_in, Command};
use host_sim::sim::{simulate, SimConfig, SimRun};
use planner_core::gait::{Reference, Side};
use planner_core::wire::{ids, Command as Wire, ControlOp, RawFrame, StepBook};

/// 5 % of a 5 ms control cycle at 480 MHz, in cycles (compared with instruction counts).
const BUDGET: u64 = 120_000;
/// Host vs target, per REF value \[m, m/s\].
const TOLERANCE: f64 = 1e-9;
const SCENARIOS: [&str; 2] = ["fig4", "lateral"];
/// `firmware/qemu`'s report: instructions per CMSDK timer tick under `-icount shift=0`.
const INSTRUCTIONS_PER_TICK: u64 = 40;

/// One output line: its keyword and `key=value` fields.
#[derive(Debug, Clone)]
struct Record {
    kind: String,
    fields: BTreeMap<String, String>,
}

impl Record {
    fn parse(line: &str) -> Option<Record> {
        let mut words = line.split_whitespace();
        let kind = words.next()?.to_string();
        let fields = words
            .filter_map(|w| w.split_once('='))
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Some(Record { kind, fields })
    }

    fn get(&self, key: &str) -> &str {
        self.fields
            .get(key)
            .unwrap_or_else(|| panic!("{} line without `{key}`: {:?}", self.kind, self.fields))
    }

    fn num<T: std::str::FromStr>(&self, key: &str) -> T {
        let v = self.get(key);
        v.parse()
            .unwrap_or_else(|_| panic!("{} line: `{key}={v}` is not a number", self.kind))
    }
}

/// What one QEMU run printed.
struct QemuRun {
    stdout: String,
    records: Vec<Record>,
}

impl QemuRun {
    fn all<'a>(&'a self, kind: &'a str) -> impl Iterator<Item = &'a Record> + 'a {
        self.records.iter().filter(move |r| r.kind == kind)
    }

    fn one<'a>(&'a self, kind: &'a str) -> &'a Record {
        let mut it = self.all(kind);
        let r = it
            .next()
            .unwrap_or_else(|| panic!("no {kind} line in the QEMU output"));
        assert!(it.next().is_none(), "more than one {kind} line");
        r
    }

    fn timing<'a>(&'a self, scenario: &'a str, kind: &'a str) -> Option<&'a Record> {
        self.all("TIMING")
            .find(|r| r.get("scenario") == scenario && r.get("kind") == kind)
    }
}

fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("firmware")
        .join("qemu")
}

/// `false` when QEMU is missing and `WALK_SKIP_QEMU=1`; panics when it is missing otherwise.
fn qemu_available() -> bool {
    let found = Process::new("qemu-system-arm")
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

/// `cargo build --release` in firmware/qemu (its own workspace and target dir); the ELF.
fn build_image() -> PathBuf {
    let dir = firmware_dir();
    let mut cmd = walk_tests::firmware_cargo(&dir);
    cmd.args(["build", "--release"]);
    let out = cmd.output().expect("cannot run cargo");
    assert!(
        out.status.success(),
        "building the QEMU image failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let elf = dir.join("target/thumbv7em-none-eabihf/release/qemu");
    assert!(elf.is_file(), "no image at {}", elf.display());
    elf
}

fn run_qemu(elf: &Path) -> QemuRun {
    let out = Process::new("timeout")
        .arg("120")
        .args(["qemu-system-arm", "-M", "mps2-an500", "-nographic"])
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
    let records = stdout.lines().filter_map(Record::parse).collect();
    let run = QemuRun { stdout, records };
    assert!(run.all("DONE").next().is_some(), "no DONE line");
    run
}

fn tail(s: &str, n: usize) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

/// The image built once and run twice (shared by the tests of this file); `None` if skipped.
fn runs() -> Option<&'static (QemuRun, QemuRun)> {
    static RUNS: OnceLock<Option<(QemuRun, QemuRun)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        if !qemu_available() {
            return None;
        }
        let elf = build_image();
        Some((run_qemu(&elf), run_qemu(&elf)))
    })
    .as_ref()
}

/// FNV-1a 64, as the image computes it.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    fn hex(&self) -> String {
        format!("{:#018x}", self.0)
    }
}

/// The image's reference digest: over the bits of (cog, cog_vel, cog_acc, zmp, zmp_vel) of x
/// then y, every tick from 0.
fn digest(trajectory: &[Reference<f64>]) -> String {
    let mut h = Fnv::new();
    for r in trajectory {
        for s in [&r.x, &r.y] {
            for v in [s.cog, s.cog_vel, s.cog_acc, s.zmp, s.zmp_vel] {
                h.add(&v.to_bits().to_le_bytes());
            }
        }
    }
    h.hex()
}

/// The frames the node transmitted on the host's bus (from the candump log: the node's
/// identifiers, ACK and the stream and status from COG up), and the image's digest over them (identifier as 2 bytes little
/// endian, then the data).
fn node_frames(sim: &SimRun) -> (usize, String) {
    let mut h = Fnv::new();
    let mut n = 0;
    for line in &sim.can_log {
        let frame = line.rsplit(' ').next().unwrap_or_default();
        let (id, data) = frame
            .split_once('#')
            .unwrap_or_else(|| panic!("log line {line}"));
        let id = u16::from_str_radix(id, 16).unwrap_or_else(|_| panic!("log line {line}"));
        if id != ids::ACK && id < ids::COG {
            continue; // the controller's frames (ESTOP, CONTROL, STEP_APPEND, STEP_MODIFY)
        }
        let bytes: Vec<u8> = (0..data.len() / 2)
            .map(|i| u8::from_str_radix(&data[2 * i..2 * i + 2], 16).expect("hex data"))
            .collect();
        h.add(&id.to_le_bytes());
        h.add(&bytes);
        n += 1;
    }
    (n, h.hex())
}

/// The frame host-sim's controller sends for a command (`seq`: its CONTROL sequence number so
/// far), candump style.
fn wire_frame(command: &Command, seq: &mut u8, book: &mut StepBook) -> String {
    let wire = match *command {
        Command::Push(id, f) => book
            .append(id as u8, f.side == Side::Left, f.x, f.y, f.yaw)
            .expect("representable footstep"),
        Command::Modify(id, f) => book
            .modify(id as u8, f.x, f.y, f.yaw)
            .expect("representable modification"),
        Command::Start | Command::Stop | Command::StopNow => {
            *seq = seq.wrapping_add(1);
            let op = match command {
                Command::Start => ControlOp::Start,
                Command::Stop => ControlOp::Stop,
                _ => ControlOp::StopNow,
            };
            Wire::Control { seq: *seq, op }
        }
    };
    let f: RawFrame = wire.encode();
    let data: String = f.bytes().iter().map(|b| format!("{b:02X}")).collect();
    format!("{:03X}#{data}", f.id)
}

fn side(s: Side) -> &'static str {
    match s {
        Side::Left => "L",
        Side::Right => "R",
    }
}

/// Timeline, answers, references, adjustments and transmitted frames of one scenario against
/// host-sim's simulation; returns the max |difference| of the REF values.
fn compare_scenario(q: &QemuRun, name: &str) -> f64 {
    let scenario = built_in(name).unwrap_or_else(|| panic!("host-sim has no scenario {name}"));
    let cfg = SimConfig::default();
    let host = simulate(&scenario, &cfg).unwrap_or_else(|e| panic!("{name}: simulate: {e}"));
    let params = cfg.node.params;

    // The tick of the host's answer to each command, paired as `simulate` pairs them.
    let mut used = vec![false; host.acks.len()];
    let mut seq = 0u8;
    let mut book = StepBook::new();

    // The timeline: the firmware's copy of the scenario is host-sim's, sent as the same frames.
    let cmds: Vec<&Record> = q.all("CMD").filter(|r| r.get("scenario") == name).collect();
    assert_eq!(
        cmds.len(),
        scenario.timeline.len(),
        "{name}: the firmware sent {} commands, host-sim's timeline has {}",
        cmds.len(),
        scenario.timeline.len()
    );
    for (i, (rec, ((tick, command), event))) in cmds
        .iter()
        .zip(scenario.timeline.iter().zip(host.run.events.iter()))
        .enumerate()
    {
        let ctx = format!("{name}: command {i} ({command:?} at tick {tick})");
        assert_eq!(rec.num::<u64>("tick"), event.tick, "{ctx}: sent at");
        let (op, step) = match command {
            Command::Push(id, f) => ("push", Some((id, f))),
            Command::Start => ("start", None),
            Command::Stop => ("stop", None),
            Command::StopNow => ("stop-now", None),
            Command::Modify(id, f) => ("modify", Some((id, f))),
        };
        assert_eq!(rec.get("op"), op, "{ctx}: operation");
        if let Some((id, f)) = step {
            assert_eq!(rec.num::<u16>("id"), *id, "{ctx}: id");
            assert_eq!(rec.get("side"), side(f.side), "{ctx}: side");
            // `{:e}` prints the shortest string that parses back to the same f64.
            assert_eq!(rec.num::<f64>("x"), f.x, "{ctx}: x");
            assert_eq!(rec.num::<f64>("y"), f.y, "{ctx}: y");
            assert_eq!(rec.num::<f64>("yaw"), f.yaw, "{ctx}: yaw");
        }
        let frame = wire_frame(command, &mut seq, &mut book);
        assert_eq!(rec.get("frame"), frame, "{ctx}: frame");
        let want = match &event.result {
            Ok(()) => "Ok".to_string(),
            Err(e) if e == "no answer" => "NoAnswer".to_string(),
            Err(e) => e.clone(),
        };
        assert_eq!(rec.get("result"), want, "{ctx}: the node's answer");
        // When the host's node answered it.
        let (code, key) = (
            u8::from_str_radix(&frame[1..3], 16).expect("id"),
            u8::from_str_radix(&frame[4..6], 16).expect("first byte"),
        );
        let answered = host
            .acks
            .iter()
            .enumerate()
            .find(|(j, (t, a))| !used[*j] && *t >= event.tick && a.command == code && a.seq == key)
            .map(|(j, (t, _))| {
                used[j] = true;
                t.to_string()
            })
            .unwrap_or_else(|| "none".to_string());
        assert_eq!(rec.get("answered"), answered, "{ctx}: answered in cycle");
    }

    // The length of the run and the whole trajectory's bits.
    let end = q
        .all("END")
        .find(|r| r.get("scenario") == name)
        .unwrap_or_else(|| panic!("no END line for {name}"));
    let trajectory = &host.run.trajectory;
    let ticks: usize = end.num("ticks");
    assert_eq!(
        ticks + 1,
        trajectory.len(),
        "{name}: the firmware ran {ticks} ticks, the host {}",
        trajectory.len() - 1
    );
    assert_eq!(
        end.get("digest"),
        digest(trajectory),
        "{name}: the references of the target and the host are not bit-identical"
    );

    // The frames the node sent, and its counters.
    let (n_frames, frames_digest) = node_frames(&host);
    assert_eq!(
        (end.num::<usize>("tx_frames"), end.get("tx_digest")),
        (n_frames, frames_digest.as_str()),
        "{name}: the frames the node transmitted (count, digest)"
    );
    let heartbeats: usize = end.num("heartbeats");
    assert_eq!(
        end.num::<usize>("heartbeat_acks"),
        heartbeats,
        "{name}: heartbeats answered"
    );
    assert_eq!(
        heartbeats + host.run.events.len(),
        host.acks.len(),
        "{name}: answers on the host"
    );
    // The board's bookkeeping ran around every poll: a summary per 200 cycles, no overrun
    // (the worst cycle is far below a 5 ms slot), and the node was told none.
    let board = q
        .all("BOARD")
        .find(|r| r.get("scenario") == name)
        .unwrap_or_else(|| panic!("no BOARD line for {name}"));
    assert_eq!(
        board.num::<usize>("summaries"),
        ticks / 200,
        "{name}: summaries"
    );
    assert_eq!(
        (
            board.num::<u32>("overruns"),
            board.num::<u16>("status_overruns")
        ),
        (0, 0),
        "{name}: overruns"
    );
    assert!(board.num::<u32>("worst") > 0, "{name}: worst cycle");
    let node = q
        .all("NODE")
        .find(|r| r.get("scenario") == name)
        .unwrap_or_else(|| panic!("no NODE line for {name}"));
    assert_eq!(
        node.num::<u16>("refused"),
        host.counters.refused,
        "{name}: refused"
    );
    assert_eq!(
        node.num::<u16>("tx_dropped"),
        host.counters.tx_dropped,
        "{name}: tx_dropped"
    );
    assert_eq!(
        node.num::<u16>("bus_errors"),
        host.counters.bus_errors,
        "{name}: bus_errors"
    );
    assert_eq!(
        node.num::<u32>("rx_overflow"),
        0,
        "{name}: frames lost by the device"
    );

    // The references at the sampled ticks.
    let mut max_diff: f64 = 0.0;
    let mut n = 0;
    for rec in q.all("REF").filter(|r| r.get("scenario") == name) {
        let tick: usize = rec.num("tick");
        let h = &trajectory[tick];
        for (key, want) in [
            ("cog_x", h.x.cog),
            ("cog_y", h.y.cog),
            ("zmp_x", h.x.zmp),
            ("zmp_y", h.y.zmp),
            ("cogv_x", h.x.cog_vel),
            ("cogv_y", h.y.cog_vel),
        ] {
            let got: f64 = rec.num(key);
            let d = (got - want).abs();
            assert!(
                d <= TOLERANCE,
                "{name} tick {tick}: {key} = {got:e} on the target, {want:e} on the host (|d| = {d:e})"
            );
            max_diff = max_diff.max(d);
        }
        n += 1;
    }
    assert!(n > 100, "{name}: only {n} REF lines");

    // The single supports that were adjusted, and by how much.
    let target: Vec<(u64, i64)> = q
        .all("REPLAN")
        .filter(|r| r.get("scenario") == name && r.num::<i64>("adjust_ticks") != 0)
        .map(|r| (r.num("tick"), r.num("adjust_ticks")))
        .collect();
    let expected: Vec<(u64, i64)> = host
        .run
        .adjustments
        .iter()
        .filter(|a| a.adjust_s != 0.0)
        .map(|a| (a.tick, (a.adjust_s / params.dt).round() as i64))
        .collect();
    assert_eq!(target, expected, "{name}: adjusted single supports");
    assert!(!target.is_empty(), "{name}: no adjustment at all");

    println!(
        "{name}: {ticks} ticks, {n} REF samples, max |target - host| = {max_diff:e}, all ticks \
         bit-identical, {n_frames} node frames identical"
    );
    max_diff
}

fn print_table(q: &QemuRun) {
    println!(
        "instructions per Node::poll, by kind of cycle (`new`: Node::new; QEMU mps2-an500, \
         -icount shift=0, resolution {INSTRUCTIONS_PER_TICK}); budget {BUDGET} = 5 % of 5 ms at 480 MHz"
    );
    println!(
        "{:<14} {:>6} {:>10} {:>10} {:>8}",
        "kind", "n", "max", "mean", "max/budget"
    );
    for r in q.all("TIMING").filter(|r| r.get("scenario") == "all") {
        let max: u64 = r.num("max");
        println!(
            "{:<14} {:>6} {:>10} {:>10} {:>8.2}",
            r.get("kind"),
            r.get("n"),
            max,
            r.get("mean"),
            max as f64 / BUDGET as f64
        );
    }
    let stack = q.one("STACK");
    println!(
        "stack high-water: {} of {} bytes (building the node {}, control loop {})",
        stack.get("used"),
        stack.get("size"),
        stack.get("startup"),
        stack.get("control")
    );
}

#[test]
fn qemu_image_matches_host_and_is_repeatable() {
    let Some((first, second)) = runs() else {
        return;
    };

    // (c) Repeatable: the second run printed exactly the same report, counts included.
    let differing: Vec<(&str, &str)> = first
        .stdout
        .lines()
        .zip(second.stdout.lines())
        .filter(|(a, b)| a != b)
        .take(5)
        .collect();
    assert!(
        differing.is_empty() && first.stdout.lines().count() == second.stdout.lines().count(),
        "two runs of the same image differ: {differing:#?}"
    );
    assert!(
        first.timing("all", "cycle").is_some(),
        "no TIMING line for the whole cycle"
    );

    // The counting method: a loop of known length took exactly 1/40 as many timer ticks
    // (± the few instructions around the loop).
    let calib = first.one("CALIB");
    let loop_instructions: u64 = calib.num("loop_instructions");
    let timer_ticks: u64 = calib.num("timer_ticks");
    assert_eq!(
        calib.num::<u64>("instructions_per_tick"),
        INSTRUCTIONS_PER_TICK
    );
    assert!(
        timer_ticks.abs_diff(loop_instructions / INSTRUCTIONS_PER_TICK) <= 1,
        "{loop_instructions} instructions took {timer_ticks} timer ticks: not 40 per tick \
         (is QEMU running with -icount shift=0?)"
    );

    // The stack stayed inside its region (its own, as on the board: an overflow would have
    // run below the start of SSRAM2 and faulted).
    let stack = first.one("STACK");
    let (used, size): (u64, u64) = (stack.num("used"), stack.num("size"));
    let (startup, control): (u64, u64) = (stack.num("startup"), stack.num("control"));
    assert!(used > 0 && used < size, "stack: {used} of {size} bytes");
    assert!(
        control > 0 && control <= used && startup <= used,
        "stack: control loop {control}, start-up {startup}, high-water {used} bytes"
    );

    // (b) The same node run as on the host.
    let mut max_diff: f64 = 0.0;
    for name in SCENARIOS {
        max_diff = max_diff.max(compare_scenario(first, name));
    }
    println!("max |target - host| over both scenarios: {max_diff:e} (tolerance {TOLERANCE:e})");
    print_table(first);
}

/// (a) The worst control cycle (a whole `Node::poll`: its frames, its tick, its stream) within
/// 5 % of the 5 ms cycle at 480 MHz. The worst is the `modify` cycle of `fig4`, where the
/// feasibility check of the modified next landing and the adjusted re-plan fall together
/// (history: 391,480 instructions for the gait calls alone before the planner stopped moving
/// its 9 KB windows and zeroing Z through nalgebra's iterator; 105,560 after; 112,800 for the
/// node's whole poll).
#[test]
fn worst_cycle_within_budget() {
    let Some((q, _)) = runs() else {
        return;
    };
    print_table(q);
    let cycle = q
        .timing("all", "cycle")
        .expect("no TIMING line for the whole cycle");
    let worst: u64 = cycle.num("max");
    let over: Vec<String> = q
        .all("TIMING")
        .filter(|r| r.get("scenario") == "all" && r.get("kind") != "new")
        .filter(|r| r.num::<u64>("max") > BUDGET)
        .map(|r| {
            format!(
                "{} {} (tick {})",
                r.get("kind"),
                r.get("max"),
                r.get("max_tick")
            )
        })
        .collect();
    assert!(
        worst <= BUDGET,
        "worst control cycle: {worst} instructions at tick {} (budget {BUDGET}); over the budget: {over:?}",
        cycle.get("max_tick")
    );
}
