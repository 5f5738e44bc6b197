//! The seeded fault sweep (`host_sim::eval::faults`): every fault kind and rate on the `straight`
//! and `fig4` scenarios, `WALK_FAULT_SEEDS` seeds (3 by default), and the heavier mixed rows
//! with `WALK_FAULT_HEAVY_SEEDS` seeds (10 by default; more for release runs). Prints the
//! Markdown table.
//!
//! Asserted: the fault-free runs walk every footstep once and keep the multi-body ZMP inside
//! the support polygon; under every fault no run falls (multi-body ZMP more than
//! `FALL_MARGIN` outside the polygon) and the node hands one finite reference to the bus in
//! every cycle (except under a flood, where its transmit mailbox may be full: not asserted,
//! printed). Lost commands and legs out of reach are printed, not asserted.

use host_sim::eval::faults::{markdown, run_case, sweep, FaultKind};
use host_sim::scenario;

#[test]
fn fault_free_runs_walk_every_step_once_inside_the_polygon() {
    for name in host_sim::eval::faults::SCENARIOS {
        let s = scenario::built_in(name).unwrap();
        let r = run_case(&s, FaultKind::None, 0.0, 1).unwrap();
        println!("{name}: {r:?}");
        assert!(!r.fell && r.max_outside == 0.0, "{name}: {r:?}");
        assert!(r.model_error.is_none(), "{name}: {r:?}");
        assert_eq!(
            (r.lost, r.cancelled, r.unanswered, r.retransmissions),
            (0, 0, 0, 0),
            "{name}: {r:?}"
        );
        assert_eq!(r.ticks_without_reference, 0, "{name}");
        assert_eq!(r.stream_gaps, 0, "{name}");
        assert!(!r.safety_stop, "{name}");
    }
}

#[test]
fn fault_sweep() {
    let seeds = std::env::var("WALK_FAULT_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let heavy = std::env::var("WALK_FAULT_HEAVY_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10);
    let t = std::time::Instant::now();
    let rows = sweep(seeds, heavy).unwrap();
    println!(
        "\nFault sweep ({seeds} seeds, {:.1} s):\n\n{}",
        t.elapsed().as_secs_f64(),
        markdown(&rows)
    );
    for r in &rows {
        for e in &r.model_errors {
            println!("model error ({} {}): {e}", r.kind.name(), r.rate);
        }
    }
    for r in &rows {
        let name = format!("{} {}", r.kind.name(), r.kind.rate_label(r.rate));
        assert_eq!(r.falls, 0, "{name}: {r:?}");
        // No accepted footstep lost or walked twice (the CRC refuses corrupted commands, the
        // controller retransmits, repeats are answered `Duplicate`).
        assert_eq!(r.lost, 0, "{name}: {r:?}");
        if r.kind != FaultKind::Flood {
            assert_eq!(r.ticks_without_reference, 0, "{name}: {r:?}");
        }
    }
}
