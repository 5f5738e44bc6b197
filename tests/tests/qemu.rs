//! The firmware's QEMU image (`firmware/qemu`, Cortex-M7 `mps2-an500`) replays host runs.
//!
//! Record and replay, as CAN engineers do with `canplayer`: this test records host-sim runs
//! (the candump log each writes), encodes them into one file of compact binary logs
//! (`host_sim::replay::binary_log`, the format of `gait_loop::binlog`), builds the image and
//! runs it twice under `qemu-system-arm -icount shift=0` on that file (one QEMU invocation per
//! image run, every log in it). The image plays each log into a fresh `Node<16>` with
//! `gait_loop::Player` (`planner_core::playback`'s rule) and prints, per log, the count and an
//! FNV-1a digest of every frame the node sent (with the cycle that sent it) and of every
//! reference, and per-poll instruction counts by kind of cycle.
//!
//! The runs: every built-in scenario (`host_sim::scenario::BUILT_IN`) and every TOML scenario
//! of `host-sim/scenarios/` through `sim::simulate`, and one fault-sweep run
//! (`faults::run_case_logged`, fig4, seed 1) per fault kind that the in-memory device can
//! replay as host-sim's bus does: none, drop, duplicate, corrupt, delay, silence, flood at
//! 20 % load, burst and the heavier mixed rows. **Not the flood at 100 % load**: it puts more
//! frames on the bus than it carries in the 2.5 ms before a poll; host-sim's replay
//! (`replay::replay_into`) sends them as the bus's transmission time allows, the in-memory
//! device has no transmission time and delivers every due frame before the poll, so the node's
//! frames cannot match (they differ from the 84th on). At 20 % load the due frames fit.
//!
//! A third QEMU run on a file whose second log is cut short checks that the image refuses it
//! (an `ERROR` line, exit code 1) after replaying the first.
//!
//! Checked, against the host (the same log, the same `Node<16>`):
//! * for every log, the target's node sent the frames that `replay::replay_into::<16>` (host-sim's
//!   replay over its virtual bus) and the target's player compiled for the host record, bit for
//!   bit with their cycles (count and digest, and a digest every 500 cycles to locate a
//!   difference); the references are bit-identical; the same cycles were run, the same frames
//!   fed, the same re-plans adjusted by the same amounts, with the same node counters;
//! * the instruction counts are repeatable: both runs print the same report, line for line;
//! * the instructions-per-timer-tick factor (40) holds, and the stack stays inside its region;
//! * the worst control cycle over every log (a whole `Node::poll`) fits 5 % of a 5 ms cycle at
//!   480 MHz (120,000 instructions).
//!
//! `WALK_QEMU_KEEP=DIR` keeps the file of logs (`DIR/replay.wlog`) and the image's report
//! (`DIR/report.txt`), e.g. to run the image on the same logs under a QEMU trace.
//!
//! `qemu-system-arm` comes from Debian's `qemu-system-arm` package, which `tests/run-all.sh`
//! installs. Without it these tests fail, unless `WALK_SKIP_QEMU=1` is set.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command as Process;
use std::sync::OnceLock;

use gait_loop::binlog::{Frames, Header, SliceBytes};
use gait_loop::{Fnv, Player};
use host_sim::faults::{run_case_logged, FaultKind, HEAVY};
use host_sim::replay;
use host_sim::scenario::{built_in, BUILT_IN};
use host_sim::sim::{simulate, start_config, SimConfig};
use host_sim::toml_scenario;
use planner_core::node::{Node, NodeConfig};
use planner_core::playback::LogClock;
use planner_core::wire::RawFrame;

/// 5 % of a 5 ms control cycle at 480 MHz, in cycles (compared with instruction counts).
const BUDGET: u64 = 120_000;
/// `firmware/qemu`'s report: instructions per CMSDK timer tick under `-icount shift=0`.
const INSTRUCTIONS_PER_TICK: u64 = 40;
/// The image's `CHECK` period \[cycles\].
const CHECK_EVERY: u64 = 500;

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

    fn of<'a>(&'a self, kind: &'a str, scenario: &'a str) -> impl Iterator<Item = &'a Record> + 'a {
        self.all(kind)
            .filter(move |r| r.get("scenario") == scenario)
    }

    fn one<'a>(&'a self, kind: &'a str) -> &'a Record {
        let mut it = self.all(kind);
        let r = it
            .next()
            .unwrap_or_else(|| panic!("no {kind} line in the QEMU output"));
        assert!(it.next().is_none(), "more than one {kind} line");
        r
    }

    fn one_of<'a>(&'a self, kind: &'a str, scenario: &'a str) -> &'a Record {
        let mut it = self.of(kind, scenario);
        let r = it
            .next()
            .unwrap_or_else(|| panic!("no {kind} line for {scenario}"));
        assert!(
            it.next().is_none(),
            "more than one {kind} line for {scenario}"
        );
        r
    }

    fn timing<'a>(&'a self, scenario: &'a str, kind: &'a str) -> Option<&'a Record> {
        self.of("TIMING", scenario).find(|r| r.get("kind") == kind)
    }
}

/// One host run to replay on the target.
struct Case {
    /// The log's name (`scenario=` in the image's report).
    name: String,
    /// The node's configuration (the run's start feet).
    cfg: NodeConfig,
    /// The run's candump log.
    log: Vec<String>,
    /// Whether the run must contain a single-support time adjustment.
    adjusts: bool,
}

/// The fault-sweep runs (fig4, seed 1): one per kind, the flood excepted (module docs).
fn fault_runs() -> Vec<(String, FaultKind, f64)> {
    let mut v: Vec<(String, FaultKind, f64)> = [
        (FaultKind::None, 0.0),
        (FaultKind::Drop, 0.05),
        (FaultKind::Duplicate, 0.05),
        (FaultKind::Corrupt, 0.05),
        (FaultKind::Delay, 0.05),
        (FaultKind::Silence, 0.0),
        (FaultKind::Flood, 0.2),
        (FaultKind::Burst, 20.0),
    ]
    .into_iter()
    .map(|(k, r)| (format!("fault-{}-{r}", k.name()), k, r))
    .collect();
    for i in 0..HEAVY.len() {
        v.push((format!("fault-mixed-{i}"), FaultKind::Mixed(i), 0.0));
    }
    v
}

/// Every run this test replays (module docs), recorded on the host.
fn cases() -> Vec<Case> {
    let sim = SimConfig::default();
    let mut out = Vec::new();
    for name in BUILT_IN {
        let s = built_in(name).unwrap();
        let run = simulate(&s, &sim).unwrap_or_else(|e| panic!("{name}: {e}"));
        out.push(Case {
            name: name.to_string(),
            cfg: start_config(&s, &sim.node),
            log: run.can_log,
            adjusts: matches!(name, "fig4" | "lateral"),
        });
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no TOML scenario in {}", dir.display());
    for path in files {
        let s = toml_scenario::load(&path).unwrap();
        let run = simulate(&s, &sim).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let stem = path.file_stem().unwrap().to_string_lossy();
        out.push(Case {
            name: format!("toml-{stem}"),
            cfg: start_config(&s, &sim.node),
            log: run.can_log,
            adjusts: true,
        });
    }
    let fig4 = built_in("fig4").unwrap();
    for (name, kind, rate) in fault_runs() {
        let (_, log) =
            run_case_logged(&fig4, kind, rate, 1).unwrap_or_else(|e| panic!("{name}: {e}"));
        out.push(Case {
            name,
            // `faults::run_case_logged` runs `NodeConfig::hrp2()` as it is.
            cfg: NodeConfig::hrp2(),
            log,
            adjusts: false,
        });
    }
    out
}

/// What the host computed for one log.
struct Expected {
    cycles: u64,
    fed: u32,
    cut: bool,
    tx_frames: usize,
    tx_digest: String,
    ref_digest: String,
    /// (cycle, frames so far, frame digest, reference digest) after every CHECK_EVERY-th cycle.
    checks: Vec<(u64, usize, String, String)>,
    /// (tick, adjust_ticks) of every re-plan.
    replans: Vec<(u64, i32)>,
    counters: (u16, u16, u16),
    rx_overflow: u32,
}

fn hex(h: &Fnv) -> String {
    format!("{:#018x}", h.0)
}

/// The log replayed on the host twice: by host-sim (`replay_into::<16>`, its virtual bus) and
/// by the target's player compiled for the host, reading the binary log through the target's
/// decoder; both must agree bit for bit (frames with their cycles, references).
fn expected(case: &Case, bytes: &[u8]) -> Expected {
    let name = &case.name;
    let sim = SimConfig::default();
    let text = case.log.join("\n") + "\n";
    let host = replay::replay_into::<16>(
        &replay::parse(&text, case.cfg.params.dt).unwrap(),
        &case.cfg,
        sim.bitrate,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));

    let mut src = SliceBytes::new(bytes);
    let header = Header::read(&mut src).unwrap().expect("a header");
    assert_eq!(header.name(), name);
    assert_eq!(header.feet, [case.cfg.left, case.cfg.right], "{name}: feet");
    let mut frames = Frames::new(&header, &mut src);
    let clock = LogClock::new(header.first_us, u64::from(header.period_us)).unwrap();
    let mut player = Player::new(clock, header.count, header.last_us);
    let mut node: Node<16> = Node::new(case.cfg).unwrap();
    let mut trajectory = vec![*node.gait().last()];
    let mut sent: Vec<(u64, RawFrame)> = Vec::new();
    let (mut tx, mut refs) = (Fnv::default(), Fnv::default());
    refs.add_reference(node.gait().last());
    let mut checks = Vec::new();
    let mut replans = Vec::new();
    while !player.done() {
        let k = player.next_cycle();
        let report = player
            .cycle(
                &mut node,
                &mut frames,
                |n, ms, bus| n.poll(ms, bus),
                |c, f| {
                    sent.push((c, *f));
                    tx.add_sent(c, f);
                },
            )
            .unwrap_or_else(|_| panic!("{name}: log truncated: {:?}", frames.error()));
        trajectory.push(report.reference);
        refs.add_reference(&report.reference);
        let tick = node.gait().ticks();
        if let Some(info) = node.gait().last_replan().filter(|i| i.tick == tick) {
            replans.push((tick, info.adjust_ticks));
        }
        if (k + 1) % CHECK_EVERY == 0 {
            checks.push((k, sent.len(), hex(&tx), hex(&refs)));
        }
    }
    assert_eq!(frames.remaining(), 0, "{name}: frames left");
    assert_eq!(frames.error(), None, "{name}: decoder");
    assert_eq!(src.remaining(), 0, "{name}: bytes after the log");
    assert_eq!(player.fed() as usize, host.replayed, "{name}: frames fed");
    assert_eq!(player.cut(), host.cut, "{name}: cut");
    assert_eq!(
        sent, host.node_frames,
        "{name}: the node's frames, target player (host build) vs host-sim replay"
    );
    assert_eq!(trajectory, host.trajectory, "{name}: references");
    assert!(sent.len() > 1000, "{name}: only {} node frames", sent.len());
    let c = node.counters();
    Expected {
        cycles: player.next_cycle(),
        fed: player.fed(),
        cut: player.cut(),
        tx_frames: sent.len(),
        tx_digest: hex(&tx),
        ref_digest: hex(&refs),
        checks,
        replans,
        counters: (c.refused, c.tx_dropped, c.bus_errors),
        rx_overflow: player.bus().rx_overflow(),
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

/// Runs the image in `dir` (which holds its `replay.wlog`): its exit code and output.
fn qemu(elf: &Path, dir: &Path) -> std::process::Output {
    Process::new("timeout")
        .arg("300")
        .args(["qemu-system-arm", "-M", "mps2-an500", "-nographic"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", "shift=0"])
        .arg("-kernel")
        .arg(elf)
        .current_dir(dir)
        .output()
        .expect("cannot run timeout/qemu-system-arm")
}

/// Runs the image in `dir` (which holds its `replay.wlog`); it must succeed.
fn run_qemu(elf: &Path, dir: &Path) -> QemuRun {
    let out = qemu(elf, dir);
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

/// The cases, what the host expects of each, and the image's two runs on their logs (shared
/// by the tests of this file); `None` if skipped.
struct Runs {
    cases: Vec<(Case, Expected)>,
    first: QemuRun,
    second: QemuRun,
    /// The run on a file whose second log is cut short: exit code, output.
    broken: (Option<i32>, String),
}

fn runs() -> Option<&'static Runs> {
    static RUNS: OnceLock<Option<Runs>> = OnceLock::new();
    RUNS.get_or_init(|| {
        if !qemu_available() {
            return None;
        }
        let elf = build_image();
        let mut file = Vec::new();
        let mut cases = Vec::new();
        for case in self::cases() {
            let bytes = replay::binary_log(&case.name, &case.log, &case.cfg)
                .unwrap_or_else(|e| panic!("{}: {e}", case.name));
            let want = expected(&case, &bytes);
            file.extend_from_slice(&bytes);
            cases.push((case, want));
        }
        let dir = std::env::temp_dir().join(format!("walk-qemu-replay-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("replay.wlog"), &file).unwrap();
        let first = run_qemu(&elf, &dir);
        let second = run_qemu(&elf, &dir);
        // The smallest log, whole, then the same cut in the middle of its frames.
        let (stop, _) = cases.iter().find(|(c, _)| c.name == "stop").unwrap();
        let whole = replay::binary_log(&stop.name, &stop.log, &stop.cfg).unwrap();
        let mut broken = whole.clone();
        broken.extend_from_slice(&whole[..whole.len() * 2 / 3]);
        std::fs::write(dir.join("replay.wlog"), &broken).unwrap();
        let out = qemu(&elf, &dir);
        let broken = (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        );
        let _ = std::fs::remove_dir_all(&dir);
        // WALK_QEMU_KEEP=DIR keeps the file and the first run's report (e.g. to run the image
        // under a QEMU trace on the same logs).
        if let Some(keep) = std::env::var_os("WALK_QEMU_KEEP") {
            let keep = PathBuf::from(keep);
            std::fs::create_dir_all(&keep).unwrap();
            std::fs::write(keep.join("replay.wlog"), &file).unwrap();
            std::fs::write(keep.join("report.txt"), &first.stdout).unwrap();
        }
        println!(
            "{} logs ({} bytes) replayed on the target in one QEMU run",
            cases.len(),
            file.len()
        );
        Some(Runs {
            cases,
            first,
            second,
            broken,
        })
    })
    .as_ref()
}

/// The target's report on one log against the host's replay of it.
fn compare(q: &QemuRun, case: &Case, want: &Expected) {
    let name = case.name.as_str();
    let end = q.one_of("END", name);
    assert_eq!(
        (
            end.num::<u64>("cycles"),
            end.num::<u32>("fed"),
            end.get("cut") == "1"
        ),
        (want.cycles, want.fed, want.cut),
        "{name}: cycles run, frames fed, cut"
    );
    let checks: Vec<(u64, usize, String, String)> = q
        .of("CHECK", name)
        .map(|r| {
            (
                r.num("cycle"),
                r.num("tx_frames"),
                r.get("tx_digest").to_string(),
                r.get("ref_digest").to_string(),
            )
        })
        .collect();
    if let Some((t, h)) = checks.iter().zip(&want.checks).find(|(t, h)| t != h) {
        panic!(
            "{name}: the target and the host differ by cycle {}: {t:?} vs {h:?}",
            h.0
        );
    }
    assert_eq!(checks.len(), want.checks.len(), "{name}: CHECK lines");
    assert_eq!(
        (end.num::<usize>("tx_frames"), end.get("tx_digest")),
        (want.tx_frames, want.tx_digest.as_str()),
        "{name}: the frames the node sent (count, digest with their cycles)"
    );
    assert_eq!(
        end.get("ref_digest"),
        want.ref_digest,
        "{name}: the references of the target and the host are not bit-identical"
    );
    let replans: Vec<(u64, i32)> = q
        .of("REPLAN", name)
        .map(|r| (r.num("tick"), r.num("adjust_ticks")))
        .collect();
    assert_eq!(
        replans, want.replans,
        "{name}: re-plans and their adjustments"
    );
    if case.adjusts {
        assert!(
            replans.iter().any(|&(_, a)| a != 0),
            "{name}: no adjustment at all"
        );
    }
    let node = q.one_of("NODE", name);
    assert_eq!(
        (
            node.num::<u16>("refused"),
            node.num::<u16>("tx_dropped"),
            node.num::<u16>("bus_errors")
        ),
        want.counters,
        "{name}: the node's counters (refused, tx_dropped, bus_errors)"
    );
    assert_eq!(
        node.num::<u32>("rx_overflow"),
        want.rx_overflow,
        "{name}: frames lost by the device"
    );
    // The board's bookkeeping ran around every poll: a summary per 200 cycles, no overrun
    // (the worst cycle is far below a 5 ms slot), and the node was told none.
    let board = q.one_of("BOARD", name);
    assert_eq!(
        board.num::<u64>("summaries"),
        want.cycles / 200,
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
    println!(
        "{name}: {} cycles, {} frames fed, {} node frames and every reference bit-identical, {} \
         re-plans{}",
        want.cycles,
        want.fed,
        want.tx_frames,
        replans.len(),
        if want.cut {
            " (cut at its longest)"
        } else {
            ""
        }
    );
}

fn print_table(q: &QemuRun) {
    let runs = q.one("RUNS").get("count").to_string();
    println!(
        "instructions per Node::poll, by kind of cycle, worst over {runs} replayed logs (`new`: \
         Node::new; QEMU mps2-an500, -icount shift=0, resolution {INSTRUCTIONS_PER_TICK}); budget \
         {BUDGET} = 5 % of 5 ms at 480 MHz"
    );
    println!(
        "{:<14} {:>6} {:>10} {:>10} {:>8}  worst in",
        "kind", "n", "max", "mean", "max/budget"
    );
    for r in q.of("TIMING", "all") {
        let max: u64 = r.num("max");
        // The log whose maximum it is: the first with the same maximum of that kind.
        let worst_in = q
            .all("TIMING")
            .find(|x| {
                x.get("scenario") != "all"
                    && x.get("kind") == r.get("kind")
                    && x.get("max") == r.get("max")
            })
            .map_or("?", |x| x.get("scenario"));
        println!(
            "{:<14} {:>6} {:>10} {:>10} {:>8.2}  {} (tick {})",
            r.get("kind"),
            r.get("n"),
            max,
            r.get("mean"),
            max as f64 / BUDGET as f64,
            worst_in,
            r.get("max_tick")
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
fn qemu_image_replays_host_runs_and_is_repeatable() {
    let Some(runs) = runs() else {
        return;
    };
    let (first, second) = (&runs.first, &runs.second);

    // Repeatable: the second run printed exactly the same report, counts included.
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
    assert!(first.all("ERROR").next().is_none(), "ERROR lines");

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

    // Every log, in file order, replayed as on the host.
    let names: Vec<&str> = first.all("RUN").map(|r| r.get("scenario")).collect();
    let want: Vec<&str> = runs.cases.iter().map(|(c, _)| c.name.as_str()).collect();
    assert_eq!(names, want, "the logs the image replayed");
    assert_eq!(first.one("RUNS").num::<usize>("count"), want.len());
    for (case, expected) in &runs.cases {
        compare(first, case, expected);
    }
    print_table(first);
}

/// The worst control cycle over every replayed log (a whole `Node::poll`: its frames, its
/// tick, its stream) within 5 % of the 5 ms cycle at 480 MHz. The worst has been the `modify`
/// cycle of `fig4`, where the feasibility check of the modified next landing and the adjusted
/// re-plan fall together (history: 391,480 instructions for the gait calls alone before the
/// planner stopped moving its 9 KB windows and zeroing Z through nalgebra's iterator; 105,560
/// after; 112,800 for the node's whole poll).
#[test]
fn worst_cycle_within_budget() {
    let Some(runs) = runs() else {
        return;
    };
    let q = &runs.first;
    print_table(q);
    let cycle = q
        .timing("all", "cycle")
        .expect("no TIMING line for the whole cycle");
    let worst: u64 = cycle.num("max");
    let over: Vec<String> = q
        .all("TIMING")
        .filter(|r| r.get("kind") != "new")
        .filter(|r| r.num::<u64>("max") > BUDGET)
        .map(|r| {
            format!(
                "{} {} {} (tick {})",
                r.get("scenario"),
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

/// The image refuses a log cut short (the decoder's `Truncated`) after replaying the whole log
/// before it, and fails the run.
#[test]
fn a_log_cut_short_fails_the_run() {
    let Some(runs) = runs() else {
        return;
    };
    let (code, stdout) = &runs.broken;
    assert_eq!(
        *code,
        Some(1),
        "exit code on a broken file:\n{}",
        tail(stdout, 10)
    );
    let records: Vec<Record> = stdout.lines().filter_map(Record::parse).collect();
    let ends = records.iter().filter(|r| r.kind == "END").count();
    let errors: Vec<&Record> = records.iter().filter(|r| r.kind == "ERROR").collect();
    assert_eq!(ends, 1, "the whole log is replayed:\n{}", tail(stdout, 10));
    assert_eq!(errors.len(), 1, "{}", tail(stdout, 10));
    assert_eq!(
        errors[0].get("log"),
        "Some(Truncated)",
        "{}",
        tail(stdout, 10)
    );
    assert!(stdout.contains("RUNS count=1"), "{}", tail(stdout, 10));
}

/// Issue 12's instruction and stack targets, over every replayed log. Met, and asserted:
/// `Node::new` ≤ 100,000 instructions, the re-plan at the start of single support ≤ 20,000, the
/// control loop's stack ≤ 12 KiB, the steady cycle's mean ≤ 3,000. Not met yet, asserted as
/// ceilings against regression (the issue's target in brackets): the worst cycle ≤ 46,000
/// (40,000), the adjusted re-plan ≤ 23,000 (20,000), the start-up stack ≤ 24,000 B (16 KiB).
#[test]
fn issue_12_targets() {
    let Some(runs) = runs() else {
        return;
    };
    let q = &runs.first;
    let max = |kind: &str| -> u64 {
        q.timing("all", kind)
            .unwrap_or_else(|| panic!("no TIMING line for {kind}"))
            .num("max")
    };
    let steady_mean: f64 = q.timing("all", "steady").expect("steady").num("mean");
    let stack = q.one("STACK");
    let (startup, control): (u64, u64) = (stack.num("startup"), stack.num("control"));
    let checks: [(&str, f64, f64, f64); 7] = [
        ("Node::new", max("new") as f64, 100_000.0, 100_000.0),
        ("re-plan (max)", max("replan") as f64, 20_000.0, 20_000.0),
        ("control-loop stack [B]", control as f64, 12_288.0, 12_288.0),
        ("steady (mean)", steady_mean, 3_000.0, 3_000.0),
        ("worst cycle", max("cycle") as f64, 40_000.0, 46_000.0),
        (
            "adjusted re-plan (max)",
            max("adjust") as f64,
            20_000.0,
            23_000.0,
        ),
        ("start-up stack [B]", startup as f64, 16_384.0, 24_000.0),
    ];
    for (name, value, target, ceiling) in checks {
        let met = if value <= target { "met" } else { "NOT met" };
        println!(
            "issue 12: {name:<24} {value:>9.0}  target {target:>7.0} ({met}), ceiling {ceiling:.0}"
        );
        assert!(value <= ceiling, "{name}: {value} above {ceiling}");
    }
}
