//! The seeded fault sweep (`host_sim::eval::faults`): every fault kind and rate on the `straight`
//! and `fig4` scenarios, `WALK_FAULT_SEEDS` seeds (3 by default), and the heavier mixed rows
//! with `WALK_FAULT_HEAVY_SEEDS` seeds (10 by default; more for release runs), walked as
//! written and walked with the node's step adjustment (`Walk::Adjusting`: `start_adjusting`, a
//! pushed pendulum robot whose estimator sends `MEASURED` every cycle, every fault applying to
//! `MEASURED` and `ADJUST` too). Prints the Markdown tables.
//!
//! Asserted: the fault-free runs walk every footstep once and keep the multi-body ZMP inside
//! the support polygon; under every fault no run falls (multi-body ZMP more than
//! `FALL_MARGIN` outside the polygon; in the adjusting walk, nor does the pendulum robot), no
//! accepted footstep is lost (in the adjusting walk: walked at its accepted pose plus the
//! node's shift in force at its lift-off), and the node hands one finite reference to the bus
//! in every cycle (except under a flood, where its transmit mailbox may be full: not asserted,
//! printed). Legs out of reach are printed, not asserted. Of the adjusting walk also: the node
//! adjusts without faults, takes no `MEASURED` older than its `max_age` and refuses the
//! corrupted, late and repeated ones; an estimator that falls silent moves no step after its
//! last state is `max_age` old; the runs are the same for the same seed; and with the default
//! seeds the book's tables (`docs/src/reliability.md`: the plain walk's, figure by figure, and
//! the adjusting walk's, between the `adjusting-fault-table` markers) are the ones measured.

use doc_figures::Quotes;
use host_sim::eval::faults::{
    markdown, markdown_adjusting, run_case, run_walk, run_walk_logged, sweep, sweep_walk,
    FaultKind, SweepRow, Walk, SCENARIOS,
};
use host_sim::scenario;
use planner_core::node::NodeConfig;

/// The seeds of a row and of a heavier row (`WALK_FAULT_SEEDS`, `WALK_FAULT_HEAVY_SEEDS`),
/// and whether they are the defaults (3 and 10: the figures the book quotes).
fn seeds() -> (u64, u64, bool) {
    let var = |name: &str| std::env::var(name).ok().and_then(|v| v.parse().ok());
    let (s, h) = (var("WALK_FAULT_SEEDS"), var("WALK_FAULT_HEAVY_SEEDS"));
    let default = s.is_none_or(|s| s == 3) && h.is_none_or(|h| h == 10);
    (s.unwrap_or(3), h.unwrap_or(10), default)
}

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
    let (seeds, heavy, default) = seeds();
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
    if default {
        book_quotes_the_plain_sweep(&rows);
    }
}

/// The book's table of the plain walk (`docs/src/reliability.md`, "Faults it survives": one
/// line per fault kind, the rates' figures joined by " / " where they differ) quotes what the
/// default seeds measure. (The fault-free row is the test above's.)
fn book_quotes_the_plain_sweep(rows: &[SweepRow]) {
    const BOOK: &str = "docs/src/reliability.md";
    let lines = [
        (FaultKind::Drop, "drop (both directions)"),
        (FaultKind::Duplicate, "| duplicate | 1 / 5 / 20 %"),
        (FaultKind::Corrupt, "corrupt (one bit, CAN CRC valid)"),
        (FaultKind::Delay, "delay 30 ms (overtaken)"),
        (FaultKind::Silence, "controller silent from a random time"),
        (FaultKind::Flood, "flood of random frames"),
        (
            FaultKind::Burst,
            "burst of modifications in one single support",
        ),
        (
            FaultKind::Mixed(0),
            "| delay 600 ms 30 % + drop 30 % + corrupt 30 % | —",
        ),
        (
            FaultKind::Mixed(1),
            "| burst 60 + drop 20 % + delay 600 ms 20 % | —",
        ),
        (FaultKind::Mixed(2), "| corrupt 50 % | —"),
    ];
    /// A column of the book's table and its figure in a row.
    type Column = (&'static str, fn(&SweepRow) -> usize);
    let columns: [Column; 9] = [
        ("runs", |r| r.runs),
        ("falls", |r| r.falls),
        ("lost", |r| r.lost),
        ("cancelled by safety stop", |r| r.cancelled),
        ("unanswered", |r| r.unanswered),
        ("controller misinformed", |r| r.misinformed),
        ("retransmissions", |r| r.retransmissions),
        ("safety stops", |r| r.safety_stops),
        ("cycles without a reference", |r| r.ticks_without_reference),
    ];
    let mut q = Quotes::new("cargo test --release -p host-sim --test faults -- --nocapture");
    for (kind, anchor) in lines {
        let of_kind: Vec<&SweepRow> = rows.iter().filter(|r| r.kind == kind).collect();
        assert!(!of_kind.is_empty(), "{kind:?}");
        for (column, value) in columns {
            let v: Vec<String> = of_kind.iter().map(|r| value(r).to_string()).collect();
            let text = if v.iter().all(|x| *x == v[0]) {
                v[0].clone()
            } else {
                v.join(" / ")
            };
            q = q.cell(BOOK, anchor, column, &text);
        }
    }
    q.assert();
}

/// The adjusting walk without faults: the node adjusts in every run (the push's deviation
/// exceeds its margin), lands some steps moved, takes every `MEASURED` (one a cycle, never
/// refused), and every step lands at its accepted pose plus the shift in force at its lift-off,
/// which the controller's book knows.
#[test]
fn fault_free_adjusting_runs_adjust_and_walk_every_step() {
    let mut shifted = 0;
    for name in SCENARIOS {
        let s = scenario::built_in(name).unwrap();
        for seed in 1..=3 {
            let r = run_walk(&s, Walk::Adjusting, FaultKind::None, 0.0, seed).unwrap();
            let what = format!(
                "{name} seed {seed}: {:?}",
                (r.lost, r.measured, r.adjustments)
            );
            assert!(
                !r.fell && !r.pendulum_fell && r.max_outside == 0.0,
                "{what}"
            );
            assert_eq!((r.lost, r.cancelled, r.shift_unheard), (0, 0, 0), "{what}");
            assert!(r.adjustments > 0, "{what}");
            let m = r.measured;
            assert_eq!(
                (m.stale, m.duplicate, m.bad_crc, m.other),
                (0, 0, 0, 0),
                "{what}"
            );
            // One a cycle from the scenario's first tick on, the first cycle's excepted.
            assert_eq!(m.taken, r.ticks - 2, "{what}");
            assert_eq!(r.ticks_without_reference, 0, "{what}");
            assert!(!r.safety_stop, "{what}");
            shifted += r.shifted_landings;
        }
    }
    assert!(
        shifted > 0,
        "no step landed moved: the adjusting walk tests nothing"
    );
}

/// An estimator that falls silent after the push: the node makes no adjustment after the
/// last state it was sent is `max_age` cycles old (no stale state moves a step), and every
/// step lands where the node's book says (`lost` 0). Not vacuous: the same seed without the
/// silence adjusts later than that in some run.
#[test]
fn a_silent_estimator_moves_no_step_once_its_last_state_is_stale() {
    let max_age = NodeConfig::hrp2().adjust.max_age;
    let mut later = 0;
    for name in SCENARIOS {
        let s = scenario::built_in(name).unwrap();
        for seed in 1..=4 {
            let r = run_walk(&s, Walk::Adjusting, FaultKind::Blind, 0.0, seed).unwrap();
            let silent = r.estimator_silent_from.expect("the estimator fell silent");
            let what = format!("{name} seed {seed}: silent from cycle {silent}, {r:?}");
            if let Some(last) = r.last_adjustment {
                assert!(last <= silent + max_age, "{what}");
            }
            assert_eq!((r.lost, r.measured_too_old), (0, 0), "{what}");
            assert!(!r.fell && !r.pendulum_fell, "{what}");
            let heard = run_walk(&s, Walk::Adjusting, FaultKind::None, 0.0, seed).unwrap();
            later += usize::from(heard.last_adjustment > Some(silent + max_age));
        }
    }
    assert!(
        later > 0,
        "the node never adjusted after the silence anyway: nothing tested"
    );
}

/// The same seed gives the same run, frame for frame (the adjusting walk's robot, push and
/// estimator draw from the seed); another seed gives another.
#[test]
fn adjusting_runs_are_deterministic_per_seed() {
    for (name, kind, rate) in [
        ("straight", FaultKind::Corrupt, 0.2),
        ("fig4", FaultKind::Mixed(1), 0.0),
    ] {
        let s = scenario::built_in(name).unwrap();
        let a = run_walk_logged(&s, Walk::Adjusting, kind, rate, 2).unwrap();
        let b = run_walk_logged(&s, Walk::Adjusting, kind, rate, 2).unwrap();
        assert!(a == b, "{name} {kind:?}: two runs of seed 2 differ");
        let c = run_walk_logged(&s, Walk::Adjusting, kind, rate, 3).unwrap();
        assert!(
            a.1 != c.1,
            "{name} {kind:?}: seeds 2 and 3 gave the same bus"
        );
    }
}

/// The sweep of the adjusting walk. Every row: no fall (multi-body ZMP or pendulum), no lost
/// footstep, a reference every cycle (but under a flood), no `MEASURED` taken older than
/// `max_age`, the node adjusted in some run. Corrupted states are refused `bad_crc`, late ones
/// `stale`, repeated ones `duplicate`. With the default seeds the book quotes its table.
#[test]
fn adjusting_fault_sweep() {
    let (seeds, heavy, default) = seeds();
    let rows = sweep_walk(Walk::Adjusting, seeds, heavy).unwrap();
    let table = markdown_adjusting(&rows);
    println!("\nFault sweep, adjusting walk ({seeds} seeds, {heavy} heavy):\n\n{table}");
    for r in &rows {
        for e in &r.model_errors {
            println!("model error ({} {}): {e}", r.kind.name(), r.rate);
        }
    }
    for r in &rows {
        let name = format!("{} {}", r.kind.name(), r.kind.rate_label(r.rate));
        assert_eq!((r.falls, r.pendulum_falls), (0, 0), "{name}: {r:?}");
        assert_eq!(r.lost, 0, "{name}: {r:?}");
        assert_eq!(r.measured_too_old, 0, "{name}: {r:?}");
        assert!(r.adjusted_runs > 0, "{name}: {r:?}");
        if r.kind != FaultKind::Flood {
            assert_eq!(r.ticks_without_reference, 0, "{name}: {r:?}");
        }
        let m = r.measured;
        match r.kind {
            FaultKind::Corrupt if r.rate >= 0.05 => assert!(m.bad_crc > 0, "{name}: {m:?}"),
            FaultKind::Delay if r.rate >= 0.05 => assert!(m.stale > 0, "{name}: {m:?}"),
            FaultKind::Duplicate if r.rate >= 0.05 => assert!(m.duplicate > 0, "{name}: {m:?}"),
            FaultKind::None | FaultKind::Drop | FaultKind::Blind | FaultKind::Burst => {
                assert_eq!(
                    (m.stale, m.duplicate, m.bad_crc),
                    (0, 0, 0),
                    "{name}: {m:?}"
                )
            }
            _ => {}
        }
    }
    if default {
        let book = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../docs/src/reliability.md"
        ))
        .expect("docs/src/reliability.md");
        let (open, close) = (
            "<!-- adjusting-fault-table -->\n",
            "<!-- /adjusting-fault-table -->",
        );
        let quoted = book
            .split_once(open)
            .and_then(|(_, rest)| rest.split_once(close))
            .map(|(t, _)| t)
            .expect("the book's adjusting fault table, between its markers");
        assert_eq!(
            quoted, table,
            "docs/src/reliability.md quotes another adjusting fault table than \
             `cargo test -p host-sim --test faults -- --nocapture` measures (printed above)"
        );
    }
}
