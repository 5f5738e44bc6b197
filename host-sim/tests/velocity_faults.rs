//! The velocity walk under bus faults (`host_sim::eval::faults`, `Walk::Velocity`): the
//! built-in `velocity` scenario steered by a stick that streams `VELOCITY` every 50 ms, under
//! the fault sweep's rows (each row once by default; every row with `WALK_FAULT_SEEDS` seeds, 3 by
//! default, and the heavier mixes with `WALK_FAULT_HEAVY_SEEDS`, 10 by default, under
//! `WALK_LONG=1`, which also prints the table and compares it with the book's, between the
//! `velocity-fault-table` markers of `docs/src/velocity.md`).
//!
//! Asserted of every run: no fall (the multi-body ZMP within `FALL_MARGIN` of the support
//! polygon), one finite reference in every cycle (except under a flood, as in the footstep
//! sweep), no `VELOCITY` taken after a newer one was taken, none taken once the node declared
//! the controller lost, the velocity in force the one the frame taken last carries; under
//! `silence` the node declares the controller lost within its velocity time-out (plus a
//! cycle) and the robot stands within 3 s (the swinging foot lands, the feet close).

use host_sim::eval::faults::{
    markdown_velocity, rows, run_walk, sweep_walk, CaseResult, FaultKind, Walk, VELOCITY_SCENARIO,
};
use host_sim::scenario;
use planner_core::node::NodeConfig;

fn check(kind: FaultKind, rate: f64, seed: u64, r: &CaseResult) {
    let what = format!("{} {} seed {seed}", kind.name(), kind.rate_label(rate));
    let v = r.velocity.expect("a velocity walk counts its stick");
    assert!(!r.fell, "{what}: fell, {r:?}");
    assert!(v.taken > 0, "{what}: no VELOCITY taken: {v:?}");
    if kind != FaultKind::Flood {
        assert_eq!(r.ticks_without_reference, 0, "{what}");
    }
    assert_eq!(v.old_taken, 0, "{what}: an old VELOCITY taken: {v:?}");
    assert_eq!(v.taken_after_lost, 0, "{what}: {v:?}");
    assert_eq!(v.wrong_velocity, 0, "{what}: {v:?}");
    if kind == FaultKind::Silence {
        let timeout = u64::from(NodeConfig::hrp2().velocity_timeout_ms);
        if let Some(lost) = v.lost_after {
            assert!(lost * 5 <= timeout + 10, "{what}: lost after {lost} ticks");
        }
        let standing = v
            .standing_after
            .expect("the robot stands after the silence");
        assert!(
            standing * 5 <= 3000,
            "{what}: standing after {standing} ticks"
        );
    }
}

#[test]
fn a_stick_walk_under_faults_keeps_its_feet_and_takes_no_old_velocity() {
    let s = scenario::built_in(VELOCITY_SCENARIO).unwrap();
    let free = run_walk(&s, Walk::Velocity, FaultKind::None, 0.0, 1).unwrap();
    check(FaultKind::None, 0.0, 1, &free);
    let v = free.velocity.unwrap();
    assert_eq!(v.taken, v.sent, "fault-free: every frame taken, {v:?}");
    assert!(!free.safety_stop && free.landings > 20, "{free:?}");
    // Every row once (seed 1; the silence of seed 2 falls while the robot walks).
    for (kind, rate) in rows(Walk::Velocity) {
        let seed = if kind == FaultKind::Silence { 2 } else { 1 };
        let r = run_walk(&s, Walk::Velocity, kind, rate, seed).unwrap();
        println!(
            "{} {}: {:?}",
            kind.name(),
            kind.rate_label(rate),
            r.velocity
        );
        check(kind, rate, seed, &r);
        let v = r.velocity.unwrap();
        match kind {
            // Repeats are refused, and so are late copies overtaken by newer frames (600 ms
            // late: a 30 ms delay is not overtaken by the next frame, 50 ms later).
            FaultKind::Duplicate | FaultKind::Mixed(0) => assert!(v.refused_old > 0, "{v:?}"),
            FaultKind::Silence => assert!(r.safety_stop, "silence: the node stops on its own"),
            _ => {}
        }
    }
}

#[test]
fn velocity_fault_sweep() {
    if std::env::var("WALK_LONG").is_err() {
        println!("the full velocity fault sweep runs with WALK_LONG=1");
        return;
    }
    let var = |name: &str| std::env::var(name).ok().and_then(|v| v.parse().ok());
    let (seeds, heavy) = (
        var("WALK_FAULT_SEEDS").unwrap_or(3),
        var("WALK_FAULT_HEAVY_SEEDS").unwrap_or(10),
    );
    let s = scenario::built_in(VELOCITY_SCENARIO).unwrap();
    for (kind, rate) in rows(Walk::Velocity) {
        let n = match kind {
            FaultKind::None => 1,
            FaultKind::Mixed(_) => heavy,
            _ => seeds,
        };
        for seed in 1..=n {
            let r = run_walk(&s, Walk::Velocity, kind, rate, seed).unwrap();
            check(kind, rate, seed, &r);
        }
    }
    let table = markdown_velocity(&sweep_walk(Walk::Velocity, seeds, heavy).unwrap());
    println!("{table}");
    if (seeds, heavy) == (3, 10) {
        let book = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../docs/src/velocity.md"
        ))
        .expect("docs/src/velocity.md");
        let quoted = book
            .split_once("<!-- velocity-fault-table -->\n")
            .and_then(|(_, rest)| rest.split_once("<!-- /velocity-fault-table -->"))
            .map(|(t, _)| t)
            .expect("the book's velocity fault table, between its markers");
        assert_eq!(
            quoted, table,
            "docs/src/velocity.md quotes another velocity fault table than \
             `WALK_LONG=1 cargo test -p host-sim --test velocity_faults -- --nocapture` \
             measures (printed above)"
        );
    }
}
