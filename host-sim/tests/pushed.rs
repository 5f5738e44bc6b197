//! The recorded pushed walk (`host_sim::sim::pushed`): with `start_adjusting` the node moves
//! the steps the way the robot was pushed and the pendulum stays up; with `start` nothing
//! moves; and the recorded log, replayed into a fresh node, gives the same frames (the log is
//! what the QEMU test replays on the target).

use host_sim::sim::pushed::pushed_walk;
use host_sim::sim::replay;
use planner_core::node::NodeConfig;
use planner_core::wire::Adjust;

#[test]
fn a_pushed_adjusting_walk_moves_its_steps_and_replays_the_same() {
    let cfg = NodeConfig::hrp2();
    let run = pushed_walk(&cfg, 10, 0.2, [0.35, 0.0], true).unwrap();
    assert!(!run.fallen, "{run:?}");
    assert!(
        run.shift[0] > 0,
        "a forward push moves the steps forward: {:?}",
        run.shift
    );
    assert!(run.adjusts.iter().any(|a| a.count > 0));
    // Replayed as a controller's log (as the QEMU test replays it on the target): every
    // measured state and command accepted, and the node publishes the same adjustments.
    let frames = replay::parse(&run.can_log.join("\n"), cfg.params.dt)
        .unwrap()
        .frames;
    let replayed = replay::replay(&frames, &cfg, 1_000_000).unwrap();
    assert!(
        replayed.acks.iter().all(|(_, a)| a.reason.is_none()),
        "{:?}",
        replayed.acks
    );
    assert_eq!(replayed.lost, 0);
    let adjusts: Vec<Adjust> = replayed
        .node_frames
        .iter()
        .filter_map(|(_, f)| Adjust::decode(f))
        .collect();
    assert_eq!(adjusts, run.adjusts);
}

#[test]
fn without_adjusting_nothing_moves() {
    let run = pushed_walk(&NodeConfig::hrp2(), 10, 0.2, [0.35, 0.0], false).unwrap();
    assert_eq!(run.shift, [0, 0]);
    assert!(run.adjusts.is_empty(), "{:?}", run.adjusts);
}
