//! The target's log player (`gait_loop::player::Player`), compiled for the host, against
//! `host-sim replay` (`host_sim::sim::replay::replay_into::<16>`) of the same candump log: both
//! use `planner_core::playback`'s timing rule, so the node's frames (with the cycle that sent
//! them) and its references must agree bit for bit. The built-in scenarios and one fault-sweep
//! run (fig4, 5 % of the frames dropped, seed 1).

use gait_loop::player::{LogFrame, Player, Source};
use host_sim::eval::faults::{run_case_logged, FaultKind};
use host_sim::scenario::{built_in, BUILT_IN};
use host_sim::sim::bus::parse_log_line;
use host_sim::sim::replay::{self, node_sends};
use host_sim::sim::{simulate, SimConfig};
use planner_core::node::Node;
use planner_core::playback::LogClock;
use planner_core::wire::RawFrame;

struct Frames(std::vec::IntoIter<LogFrame>);

impl Source for Frames {
    fn next_frame(&mut self) -> Option<LogFrame> {
        self.0.next()
    }
}

fn compare(name: &str, log: &[String]) {
    let cfg = SimConfig::default();
    let period_us = (cfg.node.params.dt * 1e6).round() as u64;
    let host = replay::replay_into::<16>(
        &replay::parse(&(log.join("\n") + "\n"), cfg.node.params.dt)
            .unwrap()
            .frames,
        &cfg.node,
        cfg.bitrate,
    )
    .unwrap();

    let entries: Vec<_> = log.iter().map(|l| parse_log_line(l).unwrap()).collect();
    let first_us = entries[0].unix_us;
    let frames: Vec<LogFrame> = entries
        .iter()
        .filter(|e| !node_sends(e.frame.id))
        .map(|e| LogFrame {
            us: e.unix_us,
            frame: e.frame,
        })
        .collect();
    let last_us = frames.last().map_or(first_us, |f| f.us);
    let mut player = Player::new(
        LogClock::new(first_us, period_us).unwrap(),
        frames.len() as u32,
        last_us,
    );
    let mut source = Frames(frames.clone().into_iter());
    let mut node: Node<16> = Node::new(cfg.node).unwrap();
    let mut trajectory = vec![*node.gait().last()];
    let mut sent: Vec<(u64, RawFrame)> = Vec::new();
    while !player.done() {
        let report = player
            .cycle(
                &mut node,
                &mut source,
                |n, ms, bus| n.poll(ms, bus),
                |k, f| sent.push((k, *f)),
            )
            .unwrap();
        // From the session's first cycle, as the host's replay records it.
        if node.session_open() {
            trajectory.push(report.reference);
        }
    }
    assert!(!player.cut(), "{name}: cut");
    assert_eq!(player.fed() as usize, frames.len(), "{name}: frames fed");
    assert_eq!(player.bus().rx_overflow(), 0, "{name}");
    assert_eq!(host.replayed, frames.len(), "{name}: host frames replayed");
    assert!(sent.len() > 1000, "{name}: {} frames", sent.len());
    assert_eq!(sent, host.node_frames, "{name}: the node's frames");
    assert_eq!(trajectory, host.trajectory, "{name}: references");
}

#[test]
fn the_target_player_replays_as_host_sim_does() {
    for name in BUILT_IN {
        let s = built_in(name).unwrap();
        let sim = simulate(&s, &SimConfig::default()).unwrap();
        compare(name, &sim.can_log);
    }
    let s = built_in("fig4").unwrap();
    let (_, log) = run_case_logged(&s, FaultKind::Drop, 0.05, 1).unwrap();
    compare("fig4 drop 5 % seed 1", &log);
}
