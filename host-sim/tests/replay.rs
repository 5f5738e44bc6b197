//! Record and replay (`host_sim::replay`): the candump log of a run, played back into a fresh
//! node, gives the run again bit for bit; the log reader takes candump's variants and refuses
//! what it cannot place, naming the line.

use host_sim::replay::{self, node_sends};
use host_sim::scenario::{self, BUILT_IN};
use host_sim::sim::{simulate, SimConfig};
use planner_core::wire::ids;

#[test]
fn every_built_in_run_replays_bit_for_bit() {
    for name in BUILT_IN {
        let s = scenario::built_in(name).unwrap();
        let cfg = SimConfig::default();
        let sim = simulate(&s, &cfg).unwrap();
        let frames = replay::parse(&(sim.can_log.join("\n") + "\n"), cfg.node.params.dt).unwrap();
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
        // Every frame on the bus, at the same time and in the same order.
        let m = sim.can_log.len().min(r.can_log.len());
        assert!(m > 1000, "{name}");
        assert_eq!(sim.can_log[..m], r.can_log[..m], "{name}");
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
    // not replayed; 12.5 ms after the epoch is cycle 2.
    let text = "\n(1767225600.012500) vcan0 020#0a01b3\n(1767225600.013000) can1 080#00\n";
    let f = replay::parse(text, dt).unwrap();
    assert_eq!(f.len(), 1);
    assert_eq!((f[0].tick, f[0].frame.id), (2, ids::CONTROL));
    assert_eq!(f[0].frame.bytes(), &[0x0A, 0x01, 0xB3]);
    for (text, line) in [
        ("(1767225600.000000) can0 020#0A\nnonsense\n", "line 2"),
        ("(1767225600.000000) can0 12345678#00\n", "line 1"),
        ("(1767225600.000000) can0 020#0A0\n", "line 1"),
        (
            "(1767225600.000000) can0 020#001122334455667788\n",
            "line 1",
        ),
        ("(1767225600.000000) can0 020#0A extra\n", "line 1"),
        ("(1767225599.999999) can0 020#0A\n", "before the epoch"),
        (
            "(1767225600.010000) can0 020#0A\n(1767225600.005000) can0 020#0B\n",
            "line 2",
        ),
    ] {
        let e = replay::parse(text, dt).unwrap_err();
        assert!(e.contains(line), "{text:?}: {e}");
    }
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
