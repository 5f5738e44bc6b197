//! The simulation over the virtual CAN bus: the node behind the bus produces exactly what the
//! gait produces when driven directly, the controller decodes the stream to its units, and the
//! stream keeps to the bus.

use doc_figures::Quotes;
use host_sim::scenario::{self, BUILT_IN};
use host_sim::sim::bus::Faults;
use host_sim::sim::{simulate, SimConfig};
use planner_core::gait::{Footstep, GaitParams, Side};
use planner_core::wire::WireStep;

/// The node over the bus equals the gait driven directly; the bus load of every built-in
/// scenario is what the book quotes (`host-sim run <scenario>` prints the same figure).
#[test]
fn the_node_over_the_bus_equals_the_gait_driven_directly() {
    let mut loads = Vec::new();
    for name in BUILT_IN {
        let s = scenario::built_in(name).unwrap();
        // Footsteps travel at 0.5 mm and 1.5 mrad: the direct run is given the footsteps as
        // the node decodes them, so both runs see the same footsteps and command ticks.
        let mut on_wire = s.clone();
        for (_, c) in on_wire.timeline.iter_mut() {
            if let scenario::Command::Push(id, f) | scenario::Command::Modify(id, f) = c {
                let w = WireStep::from_si(*id, f.side == Side::Left, f.x, f.y, f.yaw);
                let (x, y, yaw) = w.expect("representable").si();
                *f = Footstep::new(f.side, x, y, yaw);
            }
        }
        let direct = scenario::run(&on_wire, GaitParams::hrp2());
        let sim = simulate(&s, &SimConfig::default()).unwrap();
        let n = direct.trajectory.len().min(sim.run.trajectory.len());
        assert!(n > 500, "{name}: {n} ticks");
        let mut worst: f64 = 0.0;
        for (a, b) in direct.trajectory[..n].iter().zip(&sim.run.trajectory[..n]) {
            worst = worst
                .max((a.x.cog - b.x.cog).abs())
                .max((a.y.cog - b.y.cog).abs())
                .max((a.x.zmp - b.x.zmp).abs())
                .max((a.y.zmp - b.y.zmp).abs());
            assert_eq!(a.phase, b.phase, "{name}");
        }
        assert!(worst < 1e-9, "{name}: {worst}");
        let adj = |r: &scenario::Run| {
            r.adjustments
                .iter()
                .map(|a| (a.tick, a.adjust_s))
                .collect::<Vec<_>>()
        };
        assert_eq!(adj(&direct), adj(&sim.run), "{name}");
        assert!(
            sim.run.events.iter().all(|e| e.result.is_ok()),
            "{name}: {:?}",
            sim.run.events
        );
        // The controller's decoded stream (one tick late) is the reference to 1 µm.
        for k in 1..n - 1 {
            let (r, st) = (&sim.run.trajectory[k], &sim.stream[k]);
            assert!(
                (st.cog[0] - r.x.cog).abs() <= 0.5e-6 + 1e-12,
                "{name} tick {k}"
            );
            assert!(
                (st.zmp[1] - r.y.zmp).abs() <= 0.5e-6 + 1e-12,
                "{name} tick {k}"
            );
        }
        // The stream and the answers keep below 20 % of 1 Mbit/s.
        assert!(
            sim.bus_load > 0.05 && sim.bus_load < 0.2,
            "{name}: {}",
            sim.bus_load
        );
        assert!(sim.can_log.len() as u64 >= sim.bus.sent / 2);
        loads.push((name, sim.bus_load * 100.0));
    }
    let straight = loads
        .iter()
        .find(|(n, _)| *n == "straight")
        .expect("straight")
        .1;
    let (lo, hi) = loads.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), l| {
        (lo.min(l.1), hi.max(l.1))
    });
    let anchor = "load the bus to";
    Quotes::new("cargo run --release -p host-sim -- run <scenario> (its load line)")
        .line(
            "docs/src/host-sim.md",
            anchor,
            &format!("**{straight:.1} %**"),
        )
        .line(
            "docs/src/host-sim.md",
            anchor,
            &format!("{lo:.1}–{hi:.1} %"),
        )
        .assert();
}

#[test]
fn lost_heartbeats_stop_the_robot() {
    let s = scenario::built_in("stop").unwrap();
    // The controller falls silent at 2 s (its frames are lost) and the scenario's own stop
    // command at 3 s never arrives: the node stops by itself.
    let cfg = SimConfig {
        faults: Faults {
            from_port: Some(0),
            silence_ns: Some((2_000_000_000, u64::MAX)),
            ..Faults::default()
        },
        ..SimConfig::default()
    };
    let sim = simulate(&s, &cfg).unwrap();
    let end = sim.run.trajectory.last().unwrap();
    assert_eq!(end.phase, planner_core::gait::Phase::Standing);
    assert!(end.x.cog_vel.abs() < 1e-9);
    // It stopped within a bounded number of steps after the silence began.
    let t_end = (sim.run.trajectory.len() - 1) as f64 * 0.005;
    assert!(t_end < 2.0 + 0.5 + 3.0, "{t_end}");
}
