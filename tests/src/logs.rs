//! The host runs that the QEMU images replay (`tests/tests/qemu.rs` for the M7,
//! `tests/tests/qemu_m4.rs` for the M4F): every built-in scenario and every TOML scenario of
//! `host-sim/scenarios/` through `sim::simulate`, a pushed walk with the node's step
//! adjustment (`sim::pushed`: `start_adjusting` and the estimator's `MEASURED` every cycle),
//! the worst admissible cycle ([`WORST`], `sim::worst`), and one fault-sweep run (fig4, seed 1) per
//! fault kind that the in-memory device replays as host-sim's bus does (not the flood at
//! 100 % load: see `tests/tests/qemu.rs`), each with its candump log; [`binary`] encodes one
//! for the image's `replay.wlog` (a file of such logs, one after the other); [`play`] plays
//! one into a node of either scalar as the image does, [`compare`] checks the image's report
//! against that.

use std::borrow::Borrow;
use std::path::{Path, PathBuf};

use gait_loop::binlog::{Frames, Header, SliceBytes};
use gait_loop::{Fnv, Player};

use host_sim::eval::faults::{run_case_logged, FaultKind, HEAVY};
use host_sim::scenario::{self, built_in, BUILT_IN};
use host_sim::sim::pushed::pushed_walk;
use host_sim::sim::replay;
use host_sim::sim::worst::{worst_cycle, Path as WorstPath};
use host_sim::sim::{simulate, start_config, SimConfig};
use planner_core::gait::{Footstep, Reference, PREVIEW};
use planner_core::node::{Node, NodeConfig};
use planner_core::playback::LogClock;
use planner_core::shaping::PreviewGains;
use planner_core::wire::{ids, LinkHealth, RawFrame};
use planner_core::Real;

use crate::report::QemuRun;

/// The image's `CHECK` period \[cycles\].
pub const CHECK_EVERY: u64 = 500;

/// The pushed walk's steps, their length \[m\] and the push (a velocity step, x and y \[m/s\]).
pub const PUSHED_STEPS: u16 = 10;
/// See [`PUSHED_STEPS`].
pub const PUSHED_LENGTH_M: f64 = 0.2;
/// See [`PUSHED_STEPS`].
pub const PUSHED_DV: [f64; 2] = [0.35, 0.0];

/// The worst-admissible-cycle logs (`host_sim::sim::worst`), one per path; the log of
/// `Path::Measured` (`worst-measured`) runs the node with `AdjustConfig::from_measured`, as the
/// images replay a log whose name ends in `-measured`.
pub const WORST: [WorstPath; 10] = WorstPath::ALL;

/// One host run to replay on the target.
pub struct Case {
    /// The log's name (`scenario=` in the image's report).
    pub name: String,
    /// The node's configuration (the run's start feet).
    pub cfg: NodeConfig,
    /// The run's candump log.
    pub log: Vec<String>,
    /// Whether the run must contain a single-support time adjustment.
    pub adjusts: bool,
}

/// The fault-sweep runs (fig4, seed 1): one per kind, the flood excepted (module docs).
pub fn fault_runs() -> Vec<(String, FaultKind, f64)> {
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

/// Every run the QEMU tests replay (module docs), recorded on the host, in file order.
pub fn cases() -> Vec<Case> {
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
        let s = scenario::file::load(&path).unwrap();
        let run = simulate(&s, &sim).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let stem = path.file_stem().unwrap().to_string_lossy();
        out.push(Case {
            name: format!("toml-{stem}"),
            cfg: start_config(&s, &sim.node),
            log: run.can_log,
            adjusts: true,
        });
    }
    // The node's step adjustment from the measured state: a walk started with
    // `start_adjusting`, pushed, with the estimator's `MEASURED` every cycle.
    let cfg = NodeConfig::hrp2();
    let pushed = pushed_walk(&cfg, PUSHED_STEPS, PUSHED_LENGTH_M, PUSHED_DV, true)
        .unwrap_or_else(|e| panic!("pushed: {e}"));
    assert!(
        pushed.shift != [0, 0] && !pushed.fallen,
        "pushed: {pushed:?}"
    );
    out.push(Case {
        name: "pushed-adjusting".to_string(),
        cfg,
        log: pushed.can_log,
        adjusts: false,
    });
    // The worst admissible cycle (`sim::worst`): every queued step modified, the queue
    // filled, the node's command frames all used, in a cycle that re-plans; one log per path
    // (started with `start`, or with `start_adjusting`: the estimator's state every cycle, a
    // push; in a report cycle; the step adjustment's reach cut; `from_measured`; the drive
    // commands).
    for path in WORST {
        let name = path.name();
        let w = worst_cycle(&cfg, path).unwrap_or_else(|e| panic!("{name}: {e}"));
        // (A start from standing by a drive command plans the start window, not a re-plan.)
        let start = matches!(path, WorstPath::VelocityStart | WorstPath::GoalStart);
        assert!((w.replanned || start) && !w.fallen, "{name}: {:?}", w.burst);
        // What the burst held, then how the node answered it.
        let (held, flags) = if path.drives() {
            (
                format!(
                    "{} drive command accepted, {} drive commands refused (repeated, stale, \
                     fresh ones over the cycle's plan), {} footstep frames, {} others \
                     (heartbeat, measured state)",
                    w.burst.0, w.burst.1, w.burst.2, w.burst.3
                ),
                format!("cut mask {:#x}", w.adjust_flags),
            )
        } else {
            (
                format!(
                    "{} modifications, {} newer versions, {} appends, {} measured",
                    w.burst.0, w.burst.1, w.burst.2, w.burst.3
                ),
                format!("step adjustment flags {}", w.adjust_flags),
            )
        };
        let measured = if path.drives() {
            String::new()
        } else {
            format!(", from the measured state {}", w.from_measured)
        };
        println!(
            "{name}: burst of {held}; {} refused, {} walking windows planned, {flags}, report \
             cycle {}{measured}",
            w.refused, w.plans, w.report
        );
        out.push(Case {
            name: name.to_string(),
            cfg: w.cfg,
            log: w.can_log,
            adjusts: false,
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

/// `case`'s log in the image's binary format (`host_sim::sim::replay::binary_log`).
pub fn binary(case: &Case) -> Vec<u8> {
    replay::binary_log(&case.name, &case.log, &case.cfg)
        .unwrap_or_else(|e| panic!("{}: {e}", case.name))
}

/// What the host computed for one log.
pub struct Expected {
    /// Cycles run.
    pub cycles: u64,
    /// Frames fed to the node.
    pub fed: u32,
    /// Whether the replay was cut at its longest.
    pub cut: bool,
    /// Frames the node sent.
    pub tx_frames: usize,
    /// Their digest (`Fnv::add_sent`), as the image prints it.
    pub tx_digest: String,
    /// The digest of every reference (`Fnv::add_reference`), as the image prints it.
    pub ref_digest: String,
    /// (cycle, frames so far, frame digest, reference digest) after every CHECK_EVERY-th cycle.
    pub checks: Vec<(u64, usize, String, String)>,
    /// (tick, adjust_ticks) of every re-plan.
    pub replans: Vec<(u64, i32)>,
    /// The node's counters: refused, tx_dropped, bus_errors.
    pub counters: (u16, u16, u16),
    /// Frames the device lost.
    pub rx_overflow: u32,
    /// Cycles that refused a command (each one a log line of the board's cycle).
    pub refusing_cycles: u64,
    /// The `LINK` frames the board's cycle makes the node send: one with every `STATUS`, as
    /// (count, digest with their cycles, `Fnv::add_sent`), for the QEMU image's link health
    /// (the in-memory FDCAN's: no errors, reset reason unknown, no missed slot).
    pub link: (usize, String),
}

/// The `LINK` frame of the QEMU image's board cycle: the in-memory FDCAN's health (error
/// counters 0, error-active, no bus-off), reset reason unknown, no missed slot.
pub fn qemu_link_frame() -> RawFrame {
    LinkHealth::default().encode()
}

/// A digest as the image prints it.
pub fn hex(h: &Fnv) -> String {
    format!("{:#018x}", h.0)
}

/// What the target's player, compiled for the host, did with one log.
pub struct Played<T> {
    /// What the image must print of it.
    pub expected: Expected,
    /// The log's start feet.
    pub feet: [Footstep<f64>; 2],
    /// The frames the node sent, with their cycles.
    pub sent: Vec<(u64, RawFrame)>,
    /// Every reference, the start-up one first, then one per cycle from the session's first.
    pub trajectory: Vec<Reference<T>>,
}

/// Plays the binary log `bytes` (one log, named `name`) into `node` (just created) with the
/// target's player and decoder compiled for the host, as the image does (with `Node::poll`
/// untimed), and what the image must print of it.
pub fn play<const Q: usize, G, T>(name: &str, bytes: &[u8], node: &mut Node<Q, G, T>) -> Played<T>
where
    G: Borrow<PreviewGains<T, PREVIEW>>,
    T: Real,
{
    let mut src = SliceBytes::new(bytes);
    let header = Header::read(&mut src).unwrap().expect("a header");
    assert_eq!(header.name(), name);
    let mut frames = Frames::new(&header, &mut src);
    let clock = LogClock::new(header.first_us, u64::from(header.period_us)).unwrap();
    let mut player = Player::new(clock, header.count, header.last_us);
    let mut trajectory = vec![*node.gait().last()];
    let mut sent: Vec<(u64, RawFrame)> = Vec::new();
    let (mut tx, mut refs) = (Fnv::default(), Fnv::default());
    refs.add_reference(node.gait().last());
    let mut checks = Vec::new();
    let mut replans = Vec::new();
    let mut refusing_cycles = 0;
    while !player.done() {
        let k = player.next_cycle();
        let report = player
            .cycle(
                node,
                &mut frames,
                |n, ms, bus| n.poll(ms, bus),
                |c, f| {
                    sent.push((c, *f));
                    tx.add_sent(c, f);
                },
            )
            .unwrap_or_else(|_| panic!("{name}: log truncated: {:?}", frames.error()));
        // The trajectory from the session's first cycle, as the host's replay records it; the
        // digest of every poll's reference, as the image computes it.
        if node.session_open() {
            trajectory.push(report.reference);
        }
        refs.add_reference(&report.reference);
        refusing_cycles += u64::from(report.refused > 0);
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
    assert!(sent.len() > 1000, "{name}: only {} node frames", sent.len());
    let c = node.counters();
    let link_frame = qemu_link_frame();
    let mut link = Fnv::default();
    let mut links = 0;
    for (cycle, _) in sent.iter().filter(|(_, f)| f.id == ids::STATUS) {
        link.add_sent(*cycle, &link_frame);
        links += 1;
    }
    Played {
        expected: Expected {
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
            refusing_cycles,
            link: (links, hex(&link)),
        },
        feet: header.feet,
        sent,
        trajectory,
    }
}

/// The target's report on one log against the host's replay of it.
pub fn compare(q: &QemuRun, case: &Case, want: &Expected) {
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
    // The board's control cycle ran around every poll (board-core's `ControlLoop`): a summary
    // per 200 cycles, no overrun (the worst cycle is far below a 5 ms slot) and the node told
    // none, one watchdog feed and one busy pulse per cycle, no missed slot, a refusal line per
    // refusing cycle; the link adapter lost, replaced and dropped nothing (so the frames on
    // the in-memory wire are the node's, in its order: compared above), and the node
    // published the link's health in `LINK` with every `STATUS`.
    let board = q.one_of("BOARD", name);
    let num = |k: &str| board.num::<u64>(k);
    assert_eq!(num("summaries"), want.cycles / 200, "{name}: summaries");
    assert_eq!(
        (num("overruns"), num("status_overruns"), num("log_overruns")),
        (0, 0, 0),
        "{name}: overruns"
    );
    assert_eq!(
        (num("feeds"), num("busy_pulses"), num("busy_high")),
        (want.cycles, want.cycles, 0),
        "{name}: watchdog feeds and busy pulses"
    );
    assert_eq!(
        (num("missed_slots"), num("log_missed")),
        (0, 0),
        "{name}: missed slots"
    );
    assert_eq!(
        num("log_refused"),
        want.refusing_cycles,
        "{name}: refusal log lines"
    );
    assert_eq!(
        (
            num("rx_lost"),
            num("replaced"),
            num("rx_foreign"),
            num("wire_lost")
        ),
        (0, 0, 0, 0),
        "{name}: the link adapter"
    );
    assert_eq!(
        (num("link_frames") as usize, board.get("link_digest")),
        (want.link.0, want.link.1.as_str()),
        "{name}: LINK frames (count, digest with their cycles)"
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

/// The log replayed on the host twice: by host-sim (`replay_into::<16>`, its virtual bus) and
/// by the target's player compiled for the host, reading the binary log through the target's
/// decoder; both must agree bit for bit (frames with their cycles, references).
pub fn expected(case: &Case, bytes: &[u8]) -> Expected {
    let name = &case.name;
    let sim = SimConfig::default();
    let text = case.log.join("\n") + "\n";
    let host = replay::replay_into::<16>(
        &replay::parse(&text, case.cfg.params.dt).unwrap().frames,
        &case.cfg,
        sim.bitrate,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));

    let mut node: Node<16> = Node::new(case.cfg).unwrap();
    let played = play(name, bytes, &mut node);
    assert_eq!(played.feet, [case.cfg.left, case.cfg.right], "{name}: feet");
    let want = &played.expected;
    assert_eq!(want.fed as usize, host.replayed, "{name}: frames fed");
    assert_eq!(want.cut, host.cut, "{name}: cut");
    assert_eq!(
        played.sent, host.node_frames,
        "{name}: the node's frames, target player (host build) vs host-sim replay"
    );
    assert_eq!(played.trajectory, host.trajectory, "{name}: references");
    played.expected
}
