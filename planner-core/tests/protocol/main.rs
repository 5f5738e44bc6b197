//! Random programs of frames run against the node and against a small reference model of what
//! the protocol promises (the `node` module docs, the book's *Reliability* chapter): the
//! queue, the step ids, the versions, the memory of repeats and the states.
//!
//! A program is a list of operations: footstep appends (usually the next id, the side
//! `Gait::next_side` requires and a pose near a nominal step beside the other foot, so that
//! many are accepted; sometimes the wrong side, out of reach, a skipped or an old id),
//! modifications (a known id, the next version from `wire::StepBook`, a small change; or a
//! flipped side, a version jump), re-sent frames (duplicates, stale modifications, old
//! appends), control commands and emergency stops with fresh, reused or random sequence
//! numbers, foreign frames, corrupted and truncated frames, polls with heartbeats, silences,
//! and clock jumps. Every frame is sent alone in its cycle, so that its answer can be paired
//! with it and the node compared with a clone that ran the same cycle without it.
//!
//! For every frame the model says what the answer must be. Where it cannot decide (reach,
//! crossing, eq. 17's verdict on a modification, a full queue that might also be out of
//! reach) it allows each possible answer (never `PlanFailed`: the book says a validated
//! configuration leaves none, and no re-plan may fail); otherwise it demands one: `Duplicate`, `Stale`,
//! `SequenceGap`, `SideOrder`, `WrongState`, `LiftedOff`, `UnknownStep`, `ControllerLost`,
//! `EmergencyStopped`, the decoder's `BadCrc` / `BadLength`, acceptance, and no answer at all
//! to a frame that is not the node's. When the node accepts, the model records it. The `ACK`'s
//! queue length and version in force must be the model's.
//!
//! After every poll:
//! * the state (`Node::state`) is the model's (the book's state table), `Node::last_heard`
//!   is when the model last saw a command accepted, and the gait's queue is the model's;
//! * a refused frame (and a foreign one) changed nothing: `Node::same_state` with the clone;
//! * a foot that supports in this cycle and the one before keeps exactly its pose (and stays
//!   on the floor);
//! * the swinging foot is the one the step names: an accepted step lifts off in queue order,
//!   the model's next, in single support on the other foot;
//! * an accepted step lands where its last accepted version put it (±1e-9 m, ±1e-9 rad modulo
//!   2π); a padded step (id `u16::MAX`, walking in place) lifts off only with nothing queued and
//!   no stop requested, and lands beside the other foot at the nominal width;
//! * no foot lifts off more than `heartbeat_timeout_ms` (500 ms) after the controller was last
//!   heard, and the controller-lost state starts exactly when the model says;
//! * the reference ZMP is inside the support polygon (the support sole in single support, the
//!   convex hull of both soles otherwise) within [`ZMP_TOLERANCE`].
//!
//! At the end of each program the controller stops the robot (heartbeats, a `Start` if steps
//! wait while standing, a `Stop`, until standing) and every accepted footstep must have been
//! walked exactly once, at its last accepted version, or dropped by an event the model recorded
//! (`StopNow`, `ESTOP`, controller lost, `Reset`).
//!
//! The random programs found that a step accepted while stopping could still be queued when
//! the robot stood (walked or not by that stop depending on whether its last window was
//! planned yet); appends are now refused while stopping (`WrongState`), which
//! `a_step_appended_while_stopping_is_refused` checks on its own, and the model demands.
//!
//! 64 programs by default, from a fixed seed (the same programs on every run, as in `props.rs`);
//! `WALK_PROTOCOL_CASES` sets another number. Run with `-- --nocapture` for the totals (answers
//! by reason, steps walked and dropped, the largest ZMP excursion).

#[path = "../common/mod.rs"]
mod common;
mod harness;
mod model;
mod polygons;
mod programs;

use harness::*;
use model::*;
use polygons::*;
use programs::*;

use std::cell::RefCell;
use std::collections::VecDeque;

use common::{Bus, N};
use planner_core::gait::{FootPose, Phase, Reference, Side};
use planner_core::node::{NodeConfig, NodeState, HISTORY};
use planner_core::wire::{
    Ack, Command, ControlOp, Diag, Expect, Measured, RawFrame, Reason, StepBook, WireModify,
    WireStep, STAMPS,
};
use proptest::prelude::*;
use proptest::test_runner::{RngSeed, TestCaseError, TestRunner};

/// The node's identifiers (ESTOP, CONTROL, MEASURED, STEP_APPEND, STEP_MODIFY); every other
/// frame is not its business and must get no answer.
const COMMAND_IDS: [u16; 5] = [0x010, 0x020, 0x0D8, 0x100, 0x101];
/// Frames on other identifiers: random ones, the node's own output identifiers, neighbours of
/// its command identifiers.
const FOREIGN_IDS: [u16; 9] = [
    0x555, 0x7FF, 0x000, 0x080, 0x090, 0x201, 0x300, 0x102, 0x011,
];
/// The queue capacity of the rig's node.
const Q: usize = 16;
/// How far the reference ZMP may be outside the support polygon \[m\]. Measured (release
/// build, `WALK_PROTOCOL_CASES=4096`, 15.5 million cycles): the ZMP never left the polygon; it
/// came no closer than 29.3 mm to the sole's edge in single support and 38.3 mm to the hull's
/// in double support (the totals printed with `--nocapture`). The 2 mm allowed for the shaped
/// ZMP were never used.
const ZMP_TOLERANCE: f64 = 2e-3;
/// Footstep poses compared to \[m, rad\].
const POSE_TOLERANCE: f64 = 1e-9;

/// 64 programs from a fixed seed, as in `props.rs` (`PROPTEST_RNG_SEED` does not apply; set
/// `rng_seed` here to explore others); `WALK_PROTOCOL_CASES` sets the number. Failures are
/// not persisted; the shrunk program is printed in the failure message.
fn config() -> ProptestConfig {
    let cases = std::env::var("WALK_PROTOCOL_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64);
    ProptestConfig {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(0x5EED_0010),
        max_shrink_iters: 2000,
        max_shrink_time: 120_000,
        ..ProptestConfig::default()
    }
}

fn run(t0: u32, ops: &[Op], stats: &mut Stats) -> Result<(), String> {
    let mut h = Harness::new(t0, stats);
    // Most programs open the session first (one cycle to publish it, then the `Reset`); one
    // in eight starts without, and stays so until a `Reset` of its own.
    if ops.len() % 8 != 0 {
        h.cycle(None, 5)
            .map_err(|e| format!("before the handshake: {e}"))?;
        let reset = h.control(h.fresh_seq(), ControlOp::Reset);
        let a = h.send(reset).map_err(|e| format!("handshake: {e}"))?;
        if a.is_some() {
            return Err(format!("handshake refused: {a:?}"));
        }
    }
    for (k, op) in ops.iter().enumerate() {
        h.op(op)
            .map_err(|e| format!("op {k} ({op:?}), cycle {}: {e}", h.cycles))?;
    }
    h.drain()
        .map_err(|e| format!("drain, cycle {}: {e}", h.cycles))?;
    h.stats.programs += 1;
    Ok(())
}

#[test]
fn random_programs_keep_the_protocol() {
    let config = config();
    let cases = config.cases;
    let stats = RefCell::new(Stats::new());
    let mut runner = TestRunner::new(config);
    let result = runner.run(&program(), |(t0, ops)| {
        let mut s = Stats::new();
        run(t0, &ops, &mut s).map_err(TestCaseError::fail)?;
        let mut all = stats.borrow_mut();
        all.programs += s.programs;
        all.cycles += s.cycles;
        all.frames += s.frames;
        all.foreign += s.foreign;
        all.accepted += s.accepted;
        for k in 0..Reason::CODES {
            all.refused[k] += s.refused[k];
            all.demanded[k] += s.demanded[k];
        }
        all.appends += s.appends;
        all.modifications += s.modifications;
        all.measured += s.measured;
        all.walked += s.walked;
        all.walked_modified += s.walked_modified;
        all.padded += s.padded;
        for k in 0..4 {
            all.dropped[k] += s.dropped[k];
        }
        all.lost += s.lost;
        all.resets += s.resets;
        all.clock_jumps += s.clock_jumps;
        all.left_queued += s.left_queued;
        all.liftoff_silence = all.liftoff_silence.max(s.liftoff_silence);
        all.zmp_single = all.zmp_single.max(s.zmp_single);
        all.zmp_double = all.zmp_double.max(s.zmp_double);
        all.zmp_margin_single = all.zmp_margin_single.max(s.zmp_margin_single);
        all.zmp_margin_double = all.zmp_margin_double.max(s.zmp_margin_double);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    let s = stats.into_inner();
    eprintln!("{s:#?}");
    let by = |r: Reason| s.demanded[usize::from(r.code())];
    eprintln!(
        "{} programs, {} cycles, {} frames ({} foreign): {} accepted ({} appends, {} \
         modifications), refused: {:?}; walked {} steps ({} modified), {} padded; dropped \
         (StopNow, ESTOP, lost, Reset) {:?}; {} controller losses, {} resets; largest ZMP \
         excursion outside the support polygon: single support {:.4} mm, double {:.4} mm; \
         closest approach to the edge from inside: single {:.2} mm, double {:.2} mm; {} steps \
         appended while stopping left queued by the stop; longest silence before a lift-off {} ms",
        s.programs,
        s.cycles,
        s.frames,
        s.foreign,
        s.accepted,
        s.appends,
        s.modifications,
        Reason::ALL
            .iter()
            .filter(|r| s.refused[usize::from(r.code())] > 0)
            .map(|r| (r, s.refused[usize::from(r.code())]))
            .collect::<Vec<_>>(),
        s.walked,
        s.walked_modified,
        s.padded,
        s.dropped,
        s.lost,
        s.resets,
        s.zmp_single * 1e3,
        s.zmp_double * 1e3,
        -s.zmp_margin_single * 1e3,
        -s.zmp_margin_double * 1e3,
        s.left_queued,
        s.liftoff_silence,
    );
    // The programs must exercise what they check (at the default number or more).
    if cases >= 64 {
        use Reason::*;
        for r in [
            Duplicate,
            Stale,
            SequenceGap,
            SideOrder,
            WrongState,
            LiftedOff,
            UnknownStep,
            ControllerLost,
            EmergencyStopped,
            BadCrc,
            BadLength,
        ] {
            assert!(by(r) > 0, "no refusal {r:?} demanded by the model: {s:#?}");
        }
        assert!(
            s.walked >= 100 && s.walked_modified > 0 && s.padded > 0,
            "{s:#?}"
        );
        assert!(s.dropped.iter().all(|&d| d > 0), "{s:#?}");
        assert!(s.lost > 0 && s.resets > 0 && s.foreign > 0, "{s:#?}");
        // Measured states are taken as well as refused.
        assert!(s.measured > 0, "no measured state was taken: {s:#?}");
        // Lift-offs close to the supervision bound.
        assert!(s.liftoff_silence > 400, "{s:#?}");
    }
}

/// The signed distance to a support polygon is right (the ZMP check is not vacuous): inside a
/// sole it is minus the distance to the nearest edge, outside the distance to the polygon.
#[test]
fn support_polygon_distances() {
    let foot = |x: f64, y: f64, yaw: f64| FootPose { x, y, z: 0.0, yaw };
    let square = hull(sole(&foot(1.0, 2.0, 0.0), 0.12, 0.07).to_vec());
    assert_eq!(square.len(), 4);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(outside(&square, (1.0, 2.0)), -0.07));
    assert!(close(outside(&square, (1.1, 2.0)), -0.02));
    assert!(close(outside(&square, (1.0, 2.1)), 0.03));
    assert!(close(outside(&square, (1.15, 2.11)), 0.05));
    // Turned by 90°: 0.24 m along y.
    let turned = hull(sole(&foot(0.0, 0.0, std::f64::consts::FRAC_PI_2), 0.12, 0.07).to_vec());
    assert!(close(outside(&turned, (0.0, 0.11)), -0.01));
    assert!(close(outside(&turned, (0.08, 0.0)), 0.01));
    // Two soles side by side: the hull spans the gap between them.
    let mut both = sole(&foot(0.0, 0.1, 0.0), 0.12, 0.07).to_vec();
    both.extend(sole(&foot(0.2, -0.1, 0.0), 0.12, 0.07));
    let h = hull(both);
    assert_eq!(h.len(), 6);
    assert!(outside(&h, (0.1, 0.0)) < 0.0);
    assert!(outside(&h, (-0.1, -0.15)) > 0.0);
}

/// Found by the random programs: a step appended while stopping was accepted, and then walked
/// by that stop or left queued when the robot stood, depending on whether the stop's last window
/// was planned yet. It is refused now (`WrongState`), and taken once standing.
#[test]
fn a_step_appended_while_stopping_is_refused() {
    let mut r = common::Rig::hrp2();
    assert_eq!(r.append(0, false, 0.15, -0.1), None);
    assert_eq!(r.control(ControlOp::Start), None);
    assert_eq!(r.control(ControlOp::Stop), None);
    r.until(400, |n| n.gait().swinging() == Some(0));
    assert_eq!(r.n.state(), NodeState::Stopping);
    assert_eq!(r.append(1, true, 0.3, 0.1), Some(Reason::WrongState));
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(r.n.gait().queued(), 0);
    // Once standing the step is taken, and walked by the next start.
    assert_eq!(r.append(1, true, 0.3, 0.1), None);
}
