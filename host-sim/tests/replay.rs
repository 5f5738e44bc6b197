//! Record and replay (`host_sim::sim::replay`): the candump log of a run, played back into a fresh
//! node, gives the run again bit for bit; the log reader takes candump's variants and refuses
//! what it cannot place, naming the line.

use host_sim::scenario::{self, BUILT_IN};
use host_sim::sim::replay::{self, node_sends};
use host_sim::sim::{simulate, SimConfig};
use planner_core::wire::ids;

#[test]
fn every_built_in_run_replays_bit_for_bit() {
    for name in BUILT_IN {
        let s = scenario::built_in(name).unwrap();
        let cfg = SimConfig::default();
        let sim = simulate(&s, &cfg).unwrap();
        let frames = replay::parse(&(sim.can_log.join("\n") + "\n"), cfg.node.params.dt)
            .unwrap()
            .frames;
        assert!(frames.iter().all(|f| !node_sends(f.frame.id)));
        let r = replay::replay(&frames, &cfg.node, cfg.bitrate).unwrap();
        assert!(!r.cut, "{name}");
        // The reference of every cycle, float for float (the run may end a cycle apart: it
        // stops once standing after its last command, the replay after its last frame).
        let n = sim.run.trajectory.len().min(r.trajectory.len());
        assert!(
            n + 2 >= sim.run.trajectory.len().max(r.trajectory.len()),
            "{name}"
        );
        assert_eq!(sim.run.trajectory[..n], r.trajectory[..n], "{name}");
        // Every frame the node sent, in the same order (their times may differ by the bus
        // time of a frame: a controller frame that was delivered after a poll is replayed
        // at the start of the next cycle, for the same poll).
        let sent = |log: &[String]| -> Vec<String> {
            log.iter()
                .filter_map(|l| l.split_whitespace().nth(2).map(str::to_string))
                .filter(|f| u16::from_str_radix(&f[..3], 16).is_ok_and(node_sends))
                .collect()
        };
        let (a, b) = (sent(&sim.can_log), sent(&r.can_log));
        let m = a.len().min(b.len());
        assert!(m > 1000, "{name}");
        assert_eq!(a[..m], b[..m], "{name}");
        // The answers.
        let acks: Vec<_> = sim.acks.iter().map(|(_, a)| *a).collect();
        let again: Vec<_> = r.acks.iter().map(|(_, a)| *a).collect();
        assert_eq!(acks, again, "{name}");
    }
}

#[test]
fn the_reader_takes_candump_variants_and_names_bad_lines() {
    let dt = 0.005;
    // Another interface name, lower-case hexadecimal, blank lines; a frame the node sends is
    // not replayed. Cycles count from the first frame's (10 … 15 ms after the epoch); a frame
    // is for the first poll (the middle of a cycle) at or after it: 12.5 ms → cycle 0,
    // 12.6 ms → 1, 23 ms → 3. A time before host-sim's epoch is a time like any other.
    let text = "\n(1767225600.012500) vcan0 020#0a01b3\n(1767225600.013000) can1 080#00\n\
                (1767225600.012600) can0 010#00\n(1767225600.023000) can0 010#01\n";
    let e = replay::parse(text, dt).unwrap_err();
    assert!(e.contains("line 4") && e.contains("backwards"), "{e}");
    let text = "\n(1767225600.012500) vcan0 020#0a01b3\n(1767225600.012500) can1 080#00\n\
                (1767225600.012600) can0 010#00\n(1767225600.023000) can0 010#01\n";
    let f = replay::parse(text, dt).unwrap().frames;
    let got: Vec<_> = f.iter().map(|t| (t.tick, t.frame.id)).collect();
    assert_eq!(got, [(0, ids::CONTROL), (1, ids::ESTOP), (3, ids::ESTOP)]);
    assert_eq!(f[0].frame.bytes(), &[0x0A, 0x01, 0xB3]);
    assert!(replay::parse("(1000000000.000000) can0 010#00\n", dt).is_ok());
    for (text, line) in [
        ("(1767225600.000000) can0 020#0A\nnonsense\n", "line 2"),
        ("(1767225600.000000) can0 2345678A#00\n", "line 1"),
        ("(1767225600.000000) can0 020#Rx\n", "line 1"),
        ("(1767225600.000000) can0 020#0A0\n", "line 1"),
        (
            "(1767225600.000000) can0 020#001122334455667788\n",
            "line 1",
        ),
        ("(1767225600.000000) can0 020#0A extra\n", "line 1"),
        (
            "(1767225600.010000) can0 020#0A\n(1767225600.005000) can0 020#0B\n",
            "line 2",
        ),
    ] {
        let e = replay::parse(text, dt).unwrap_err();
        assert!(e.contains(line), "{text:?}: {e}");
    }
}

/// A log recorded on a robot's bus carries other nodes' frames: extended identifiers, remote
/// and CAN FD frames are skipped and counted (the node never receives them), lower or upper
/// case, with or without a remote frame's length; their times still may not go backwards.
#[test]
fn other_nodes_frames_are_skipped_and_counted() {
    let dt = 0.005;
    let text = "(1767225600.000000) can0 020#0A\n(1767225600.001000) can0 12345678#00\n\
                (1767225600.002000) can0 1FFFFFFF#R\n(1767225600.003000) can0 123#R\n\
                (1767225600.004000) can0 123#r8\n(1767225600.005000) can0 0000abcd#\n\
                (1767225600.006000) can0 123##1001122\n(1767225600.007000) can0 010#00\n";
    let p = replay::parse(text, dt).unwrap();
    assert_eq!(p.skipped, 6);
    let ids: Vec<_> = p.frames.iter().map(|t| t.frame.id).collect();
    assert_eq!(ids, [ids::CONTROL, ids::ESTOP]);
    let e = replay::parse(
        "(1767225600.010000) can0 020#0A\n(1767225600.005000) can0 12345678#00\n",
        dt,
    )
    .unwrap_err();
    assert!(e.contains("line 2") && e.contains("backwards"), "{e}");
}

#[test]
fn the_command_line_replays_a_log_and_reports_refusals() {
    let dir = std::env::temp_dir().join(format!("host-sim-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let s = scenario::built_in("fig4").unwrap();
    let sim = simulate(&s, &SimConfig::default()).unwrap();
    let log = dir.join("fig4.log");
    std::fs::write(&log, sim.can_log.join("\n") + "\n").unwrap();
    let out = dir.join("out");
    let run = |log: &std::path::Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args([
                "replay",
                log.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap()
    };
    let o = run(&log);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let replayed = std::fs::read_to_string(out.join("can.log")).unwrap();
    assert!(replayed.starts_with(&sim.can_log[..100].join("\n")));
    // The same log with its first footstep append dropped: the next is a sequence gap.
    let first = sim
        .can_log
        .iter()
        .position(|l| l.contains(" can0 100#"))
        .unwrap();
    let mut cut = sim.can_log.clone();
    cut.remove(first);
    let log = dir.join("gap.log");
    std::fs::write(&log, cut.join("\n") + "\n").unwrap();
    let o = run(&log);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(
        text.contains("refused at") && text.contains("sequence_gap"),
        "{text}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(!summary["refused"].as_array().unwrap().is_empty());
}

/// A CONTROL frame of `session`, encoded with the codec.
fn control(session: u16, seq: u32, op: planner_core::wire::ControlOp) -> String {
    let f = planner_core::wire::Command::Control { session, seq, op }.encode();
    let data: String = f.bytes().iter().map(|b| format!("{b:02X}")).collect();
    format!("020#{data}")
}

/// A log line `us` µs after `start_s` (Unix seconds).
fn line(start_s: u64, us: u64, frame: &str) -> String {
    let t = start_s * 1_000_000 + us;
    format!("({}.{:06}) can0 {frame}\n", t / 1_000_000, t % 1_000_000)
}

/// The append frames of the built-in straight walk, as its controller sent them.
fn appends() -> Vec<String> {
    let s = scenario::built_in("straight").unwrap();
    let sim = simulate(&s, &SimConfig::default()).unwrap();
    sim.can_log
        .iter()
        .filter_map(|l| l.split_whitespace().nth(2))
        .filter(|f| f.starts_with("100#"))
        .map(str::to_string)
        .collect()
}

#[test]
fn frames_are_played_in_log_order_and_for_the_poll_after_them() {
    use planner_core::wire::ControlOp;
    // The appends early in a cycle, the start later in the same cycle (after the node's
    // poll): in log order the start comes after the appends (arbitration alone would send the
    // CONTROL frame, the lower identifier, first, and the start would be refused), and the
    // node reads it in the next cycle's poll. Heartbeats keep the controller alive. The log
    // is from a wall clock (December 2026), not host-sim's epoch: it replays from its first
    // frame.
    // The handshake first: the node's start-up session (epoch 0: the replay's node has no
    // entropy) opened by a `Reset`; then session 1.
    let start_s = 1_796_000_000;
    let mut log = line(start_s, 50, &control(0, 1, ControlOp::Reset));
    for (i, f) in appends().iter().enumerate() {
        log += &line(start_s, 100 * (i as u64 + 1), f);
    }
    log += &line(start_s, 4_000, &control(1, 2, ControlOp::Start));
    for k in 0..60u64 {
        log += &line(
            start_s,
            100_000 * k + 4_900,
            &control(1, 10 + k as u32, ControlOp::Heartbeat),
        );
    }
    let cfg = SimConfig::default();
    let frames = replay::parse(&log, cfg.node.params.dt).unwrap().frames;
    assert_eq!(frames[0].tick, 0);
    let start = frames
        .iter()
        .filter(|f| f.frame.id == ids::CONTROL)
        .nth(1)
        .unwrap();
    assert_eq!(
        start.tick, 1,
        "logged after the poll of cycle 0: for the poll of cycle 1"
    );
    let r = replay::replay(&frames, &cfg.node, cfg.bitrate).unwrap();
    let refused: Vec<_> = r.acks.iter().filter(|(_, a)| a.reason.is_some()).collect();
    assert!(refused.is_empty(), "refused: {refused:?}");
    assert_eq!(r.acks.len(), frames.len());
    assert!(r.trajectory.len() < 2_000, "{} cycles", r.trajectory.len());
    assert!(r
        .trajectory
        .iter()
        .any(|t| t.phase != planner_core::gait::Phase::Standing));
}

#[test]
fn a_burst_in_the_last_cycle_is_read_and_answered_in_full() {
    use planner_core::wire::ControlOp;
    // More frames in one cycle than fit on the bus before the poll, and more than the node
    // reads per poll (16): the rest wait; every one is answered, none lost.
    for n in [40u8, 70, 100] {
        let mut log = String::new();
        for i in 0..n {
            log += &line(
                host_sim::sim::bus::LOG_EPOCH_S,
                0,
                &control(0, u32::from(i) + 1, ControlOp::Heartbeat),
            );
        }
        let cfg = SimConfig::default();
        let frames = replay::parse(&log, cfg.node.params.dt).unwrap().frames;
        let r = replay::replay(&frames, &cfg.node, cfg.bitrate).unwrap();
        assert!(!r.cut);
        assert_eq!(
            (r.replayed, r.acks.len(), r.lost),
            (n as usize, n as usize, 0),
            "{n}"
        );
    }
}

/// A fault-sweep run (`faults::run_case_logged`) replays into the firmware's `Node<16>`: every
/// frame is fed, the replay ends standing, and the node's frames recorded per cycle
/// (`Replayed::node_frames`, what the QEMU image's player writes back) are the node's frames
/// of the replay's own bus log, in order.
#[test]
fn a_fault_run_replays_into_the_firmware_node_with_its_frames_per_cycle() {
    use host_sim::eval::faults::{run_case_logged, FaultKind};
    let s = scenario::built_in("fig4").unwrap();
    let (_, log) = run_case_logged(&s, FaultKind::Drop, 0.05, 1).unwrap();
    assert!(log.len() > 1000);
    let cfg = SimConfig::default();
    let frames = replay::parse(&(log.join("\n") + "\n"), cfg.node.params.dt)
        .unwrap()
        .frames;
    let r = replay::replay_into::<16>(&frames, &cfg.node, cfg.bitrate).unwrap();
    assert!(!r.cut);
    assert_eq!(r.replayed, frames.len());
    let on_bus: Vec<String> = r
        .can_log
        .iter()
        .filter_map(|l| l.split_whitespace().nth(2).map(str::to_string))
        .filter(|f| u16::from_str_radix(&f[..3], 16).is_ok_and(node_sends))
        .collect();
    let tapped: Vec<String> = r
        .node_frames
        .iter()
        .map(|(_, f)| {
            let data: String = f.bytes().iter().map(|b| format!("{b:02X}")).collect();
            format!("{:03X}#{data}", f.id)
        })
        .collect();
    assert_eq!(tapped, on_bus);
    // One cycle per poll, non-decreasing, within the polls (those of the trajectory and the
    // ones before the session opened).
    assert!(r.node_frames.windows(2).all(|w| w[0].0 <= w[1].0));
    assert!(r.before_session >= 1);
    assert!(r.node_frames.last().unwrap().0 < r.trajectory.len() as u64 + r.before_session);
}
