//! The `f32` node (`Node<16, PreviewGains<f32, _>, f32>`, the Cortex-M4F's) against the `f64`
//! node (`Node<16>`) on the same command frames, for every built-in scenario.
//!
//! The frames are host-sim's: `sim::simulate` runs the scenario (its controller, the `f64`
//! node, the virtual bus) and writes the candump log; the controller's frames of that log are
//! fed to both nodes here at the cycles `planner_core::playback`'s rule gives them (as
//! `host-sim replay` and the target's player do), through one in-memory CAN device per node
//! (`gait_loop::ScriptedBus`). Both nodes are configured from the same `f64` configuration
//! (`NodeConfig::cast` rounds it for `f32`). Over the whole walks this checks:
//! * **COG**: the `f32` node's COG (x and y, every tick) is within 0.1 mm of the `f64` node's
//!   (the required bound; the worst difference per scenario is printed);
//! * **decisions**: both nodes answer every command the same way, in the same cycle (the whole
//!   `ACK`: command, sequence or step id, reason code, queue length, echo, version in force);
//! * **adjustment times**: the same single supports are re-planned, in the same ticks, with
//!   the same adjustment (`ReplanInfo::adjust_ticks`). No scenario needs an exception today:
//!   the eq. 17 adjustment is chosen on the 5 ms grid (`libm::round` of the optimal `ΔT` in
//!   ticks), and the `f32` error of `ΔT` (≈ 1e-6 s) is far below half a tick, so the two
//!   scalars round to the same tick unless the optimum falls within ≈ 1e-6 s of a half-tick
//!   boundary. If one ever does, the assertion names the scenario and tick;
//! * both walks have the same length (the same tick at which the node stands again).
//!
//! Of the built-in scenarios only `stop` has refusals (5); so that more refusals are compared,
//! [`faulty_runs_refuse_alike`] does the same on logs of host-sim's fault sweep (fig4 and
//! lateral with frames lost, repeated, corrupted, delayed, and bursts of modifications: the
//! nodes refuse gaps, repeats, bad CRCs, stale versions and infeasible modifications).

use gait_loop::ScriptedBus;
use host_sim::eval::faults::{run_case_logged, FaultKind};
use host_sim::scenario::{built_in, BUILT_IN};
use host_sim::sim::replay;
use host_sim::sim::{references, simulate, start_config, SimConfig};
use planner_core::gait::{Reference, PREVIEW};
use planner_core::node::{Node, NodeConfig};
use planner_core::playback;
use planner_core::real::Real;
use planner_core::shaping::PreviewGains;
use planner_core::wire::{ids, Ack};

/// The required bound on the COG of the `f32` node against the `f64` node \[m\].
const COG_TOLERANCE: f64 = 1e-4;

/// What one node did over a replay.
struct Walk {
    /// The reference of every tick (tick 0: standing, before the first poll).
    trajectory: Vec<Reference<f64>>,
    /// Every `ACK`, with the cycle that sent it.
    acks: Vec<(u64, Ack)>,
    /// Every re-plan: (tick, adjustment in ticks).
    replans: Vec<(u64, i32)>,
}

fn widen<T: Real>(r: &Reference<T>) -> Reference<f64> {
    let s = |p: &planner_core::Sample<T>| planner_core::Sample {
        cog: p.cog.f64(),
        cog_vel: p.cog_vel.f64(),
        cog_acc: p.cog_acc.f64(),
        zmp: p.zmp.f64(),
        zmp_vel: p.zmp_vel.f64(),
    };
    let foot = |f: &planner_core::gait::FootPose<T>| planner_core::gait::FootPose {
        x: f.x.f64(),
        y: f.y.f64(),
        z: f.z.f64(),
        yaw: f.yaw.f64(),
    };
    Reference {
        x: s(&r.x),
        y: s(&r.y),
        phase: r.phase,
        feet: [foot(&r.feet[0]), foot(&r.feet[1])],
    }
}

/// Replays `frames` into a node of scalar `T` (its gains computed by `Node::new`).
fn walk<T: Real>(frames: &[replay::Timed], cfg: NodeConfig<T>, period_us: u64) -> Walk {
    let mut node: Node<16, PreviewGains<T, PREVIEW>, T> = Node::new(cfg).expect("node");
    let mut bus = ScriptedBus::new();
    let last = frames.last().map_or(0, |f| f.tick);
    let mut next = 0;
    let mut w = Walk {
        trajectory: vec![widen(node.gait().last())],
        acks: Vec::new(),
        replans: Vec::new(),
    };
    for k in 0..playback::max_cycles(last, period_us) {
        while next < frames.len() && frames[next].tick <= k {
            bus.deliver(frames[next].frame);
            next += 1;
        }
        let report = node.poll(playback::poll_ms(k, period_us), &mut bus);
        // From the session's first cycle (the node does not tick before), as host-sim's run.
        if node.session_open() {
            w.trajectory.push(widen(&report.reference));
        }
        let tick = node.gait().ticks();
        if let Some(i) = node.gait().last_replan().filter(|i| i.tick == tick) {
            w.replans.push((tick, i.adjust_ticks));
        }
        while let Some(f) = bus.take_sent() {
            if f.id == ids::ACK {
                w.acks
                    .push((k, Ack::decode(&f).expect("the node's ACK decodes")));
            }
        }
        let idle = next >= frames.len() && bus.pending_len() == 0;
        if playback::finished(k, last, idle, node.gait().is_standing()) {
            break;
        }
    }
    assert_eq!(bus.rx_overflow(), 0);
    w
}

/// Both nodes replayed on one candump log: the worst COG difference \[m\] and the number of
/// refusals, after asserting the same answers, re-plans and walk length.
fn compare(name: &str, log: &[String], cfg: NodeConfig, period_us: u64) -> (f64, usize, Walk) {
    let frames = replay::parse(&(log.join("\n") + "\n"), cfg.params.dt)
        .expect("host-sim's log parses")
        .frames;
    let wide = walk::<f64>(&frames, cfg, period_us);
    let narrow = walk::<f32>(&frames, cfg.cast::<f32>(), period_us);
    assert!(wide.acks.len() > 5, "{name}: {} answers", wide.acks.len());
    assert_eq!(narrow.acks, wide.acks, "{name}: answers (ACK frames)");
    assert_eq!(
        narrow.replans, wide.replans,
        "{name}: re-plans and adjustments"
    );
    assert_eq!(
        narrow.trajectory.len(),
        wide.trajectory.len(),
        "{name}: walk length"
    );
    let (mut worst, mut at) = (0.0_f64, 0);
    for (k, (a, b)) in narrow.trajectory.iter().zip(&wide.trajectory).enumerate() {
        let d = (a.x.cog - b.x.cog).abs().max((a.y.cog - b.y.cog).abs());
        if d > worst {
            (worst, at) = (d, k);
        }
    }
    let refused = wide.acks.iter().filter(|(_, a)| a.reason.is_some()).count();
    println!(
        "F32 run={name} ticks={} acks={} refused={refused} replans={} worst_cog_diff_m={worst:.3e} at_tick={at}",
        wide.trajectory.len() - 1,
        wide.acks.len(),
        wide.replans.len()
    );
    assert!(
        worst <= COG_TOLERANCE,
        "{name}: COG of the f32 node {worst:e} m from the f64 node's at tick {at}"
    );
    (worst, refused, wide)
}

#[test]
fn faulty_runs_refuse_alike() {
    let sim_cfg = SimConfig::default();
    let period_us = (sim_cfg.node.params.dt * 1e6).round() as u64;
    let mut refused = 0;
    for name in ["fig4", "lateral"] {
        let s = built_in(name).expect("built-in scenario");
        for (kind, rate) in [
            (FaultKind::Drop, 0.05),
            (FaultKind::Duplicate, 0.1),
            (FaultKind::Corrupt, 0.05),
            (FaultKind::Delay, 0.1),
            (FaultKind::Burst, 1.0),
        ] {
            for seed in 1..=2 {
                let (_, log) = run_case_logged(&s, kind, rate, seed).expect("fault run");
                let label = format!("{name}/{kind:?}/{rate}/seed{seed}");
                let cfg = start_config(&s, &sim_cfg.node);
                refused += compare(&label, &log, cfg, period_us).1;
            }
        }
    }
    assert!(
        refused > 0,
        "no refusal in the fault runs: nothing compared"
    );
}

#[test]
fn the_f32_node_walks_as_the_f64_node() {
    let sim_cfg = SimConfig::default();
    let period_us = (sim_cfg.node.params.dt * 1e6).round() as u64;
    for name in BUILT_IN {
        let s = built_in(name).expect("built-in scenario");
        let sim = simulate(&s, &sim_cfg).expect("simulate");
        let cfg = start_config(&s, &sim_cfg.node);
        let (_, _, wide) = compare(name, &sim.can_log, cfg, period_us);
        // The f64 replay is host-sim's own walk (a check of this driver).
        assert_eq!(
            wide.trajectory.len(),
            references(&sim).len(),
            "{name}: f64 replay length against host-sim's run"
        );
    }
}
