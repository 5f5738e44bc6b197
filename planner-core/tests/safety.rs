//! Regression tests of the robot-safe node: one test per defect an outside review found, each
//! failing on the node before the fix. Driven through the bus, as a controller
//! would, with `wire::StepBook` for the footstep frames.

mod common;

use common::{y, Bus, Rig};
use planner_core::gait::{Phase, Side};
use planner_core::node::{NodeConfig, NodeState};
use planner_core::wire::{ids, Command, ControlOp, RawFrame, Reason, WireStep};

/// Item 1: a controller that sends each step just in time (one in the queue at most). In
/// every double support with nothing queued the side of the next step is fixed by the last
/// landing: the supporting foot's step is refused, and the foot that swings is always the
/// one the step names.
#[test]
fn a_step_for_the_supporting_foot_is_refused() {
    let mut r = Rig::hrp2();
    assert_eq!(r.append(0, false, 0.1, -0.1), None);
    assert_eq!(r.control(ControlOp::Start), None);
    let mut tried = 0;
    for id in 1..8u16 {
        // Wait until the previous step has landed and the queue is empty (double support).
        r.until(2000, |n| {
            n.gait().queued() == 0 && n.gait().swinging().is_none() && !n.gait().is_standing()
        });
        let expected =
            r.n.gait()
                .next_side()
                .expect("the side is fixed while walking");
        let right_side = expected == Side::Left;
        let wrong = WireStep::from_si(
            id,
            !right_side,
            0.1 * f64::from(id + 1),
            y(!right_side),
            0.0,
        )
        .unwrap();
        assert_eq!(
            r.ask(Command::Append(wrong)),
            Some(Reason::SideOrder),
            "step {id} for the supporting foot"
        );
        tried += 1;
        assert_eq!(
            r.append(id, right_side, 0.1 * f64::from(id + 1), y(right_side)),
            None
        );
        // It is swung by the foot it names.
        r.until(400, |n| n.gait().swinging() == Some(id));
        assert_eq!(
            r.n.gait().last().phase,
            Phase::Single(expected.other()),
            "step {id} swings the stance foot"
        );
    }
    assert_eq!(tried, 7);
    // Walking in place (nothing sent for a while: padded steps alternate), then a step: its
    // side follows the last padded landing.
    r.until(3000, |n| {
        n.gait().queued() == 0 && n.gait().swinging().is_none() && !n.gait().is_standing()
    });
    r.run(170, true);
    r.until(3000, |n| n.gait().swinging().is_none());
    let side = r.n.gait().next_side().unwrap();
    let wrong = WireStep::from_si(8, side == Side::Right, 0.85, y(side == Side::Right), 0.0);
    assert_eq!(
        r.ask(Command::Append(wrong.unwrap())),
        Some(Reason::SideOrder)
    );
    // STATUS publishes the side (1 left, 2 right).
    r.until(40, |n| n.cycles() % 20 == 0);
    r.run(1, false);
    let d = r.status.expect("a STATUS every 20 cycles");
    let now = r.n.gait().next_side().unwrap();
    assert_eq!(d.next_side(), if now == Side::Left { 1 } else { 2 });
}

/// Items 2 and 3: a refused `Start` records nothing: its retransmission is carried out (not
/// answered `Duplicate`), and it does not leave the controller-lost state.
#[test]
fn a_refused_start_records_nothing() {
    let mut r = Rig::hrp2();
    let start = r.command_at(5, ControlOp::Start);
    assert_eq!(r.ask(start), Some(Reason::WrongState)); // nothing queued
    assert_eq!(r.append(0, false, 0.1, -0.1), None);
    assert_eq!(r.ask(start), None, "the retransmission is a new attempt");
    assert_eq!(r.n.state(), NodeState::Walking);
    assert_eq!(r.ask(start), Some(Reason::Duplicate));

    // Lost: a refused start leaves the state as it is (3), standing or moving.
    r.run(101, false);
    assert_eq!(r.n.status().state, 3);
    let before = r.n.clone();
    let again = r.command_at(6, ControlOp::Start);
    assert_eq!(r.ask(again), Some(Reason::ControllerLost));
    assert_eq!(r.n.status().state, 3);
    let mut ghost = before;
    ghost.poll(r.t, &mut Bus::default());
    assert!(r.n.same_state(&ghost));
    r.until(2000, |n| n.gait().is_standing());
    let again = r.command(ControlOp::Start);
    assert_eq!(r.ask(again), Some(Reason::ControllerLost));
    assert_eq!(r.n.status().state, 3);
}

/// Item 4: supervision holds for the whole walk. A controller that sends a burst of steps and
/// a start and dies; one that walks, dies, comes back with another burst and dies again; one
/// that keeps heartbeats for a while then dies mid-walk. No foot lifts off more than the
/// timeout after the controller was last heard (an accepted command).
#[test]
fn no_lift_off_beyond_the_supervision_bound() {
    let timeout = NodeConfig::hrp2().heartbeat_timeout_ms;
    let burst = |r: &mut Rig, from: u16, n: u16| {
        let (x0, _) = (r.n.gait().feet()[0].x, 0);
        for k in 0..n {
            let id = from + k;
            let left = id % 2 == 1;
            let a = r.append(id, left, x0 + 0.15 * f64::from(k + 1), y(left));
            assert!(
                matches!(a, None | Some(Reason::ControllerLost)),
                "step {id}: {a:?}"
            );
        }
    };
    // 1. A burst of 13 steps and a start, then silence.
    let mut r = Rig::hrp2();
    burst(&mut r, 0, 13);
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(3000, false);
    assert!(r.n.gait().is_standing());
    assert_eq!(r.n.status().state, 3);
    // 2. Walks with heartbeats, dies, comes back (heartbeats and a burst: refused), dies.
    let mut r = Rig::hrp2();
    burst(&mut r, 0, 13);
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(400, true);
    r.run(300, false);
    assert_eq!(r.n.status().state, 3);
    r.run(40, true);
    for id in 13..20u16 {
        let left = id % 2 == 1;
        let c = Command::Append(WireStep::from_si(id, left, 3.0, y(left), 0.0).unwrap());
        assert_eq!(r.ask(c), Some(Reason::ControllerLost));
    }
    r.run(3000, false);
    assert!(r.n.gait().is_standing());
    // 3. The same with the return after standing: still refused until a reset.
    r.run(100, true);
    assert_eq!(r.n.status().state, 3);
    assert!(r.n.gait().is_standing(), "{:?}", r.n.state());
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.n.status().state, 0);
    r.book.clear();
    // (The robot stopped wherever the loss found it: the left foot beside the right, then
    // steps in place.)
    let rf = r.n.gait().feet()[1];
    let lf = (rf.x - 0.2 * rf.yaw.sin(), rf.y + 0.2 * rf.yaw.cos());
    // (Step numbers run on across the reset.)
    let first = r.n.next_step();
    for k in 0..6u16 {
        let id = first + k;
        let (x, y) = if k % 2 == 0 { lf } else { (rf.x, rf.y) };
        let c = r.book.append(id, k % 2 == 0, x, y, rf.yaw).unwrap();
        assert_eq!(
            r.ask(c),
            None,
            "step {id} in place: {:?}",
            r.n.gait().feet()
        );
    }
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(500, true);
    r.run(2000, false);
    for rig in [&r] {
        assert!(!rig.liftoffs.is_empty());
        for &(at, heard, id) in &rig.liftoffs {
            let heard = heard.expect("heard before walking");
            assert!(
                at.wrapping_sub(heard) <= timeout,
                "step {id} lifted off at {at} ms, {} ms after the controller was heard",
                at - heard
            );
        }
    }
}

/// `Reset` while standing drops the queue; step numbers run on, 256 past the old session's
/// (no two steps of a start-up share a number), so a modification of a dropped step and an
/// append of the number that was next are refused, and the new session's first step 258 is
/// moved by its own modification.
#[test]
fn reset_while_standing_drops_the_queue() {
    let mut r = Rig::hrp2();
    assert_eq!(r.append(0, false, 0.1, -0.1), None);
    assert_eq!(r.append(1, true, 0.2, 0.1), None);
    let old = r.book.modify(0, 0.12, -0.1, 0.0).unwrap();
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.n.gait().queued(), 0);
    assert_eq!(r.append(0, true, 0.05, 0.1), Some(Reason::BadCrc));
    assert_eq!(r.append(2, true, 0.05, 0.1), Some(Reason::BadCrc));
    r.run(20, true);
    assert_eq!(r.diag.map(|d| d.next_step), Some(258), "published");
    assert_eq!(r.append(258, true, 0.05, 0.1), None);
    assert_eq!(r.n.gait().queued(), 1);
    assert_eq!(r.ask(old), Some(Reason::BadCrc));
    assert_eq!(r.modify(258, 0.08, 0.1), None);
    let s = r.n.gait().queued_step(258).unwrap();
    assert_eq!((s.side, s.x, s.y), (Side::Left, 0.08, 0.1));
}

/// Item 6: modifications A → B → A: the third is a new version (accepted), and the step is
/// walked at A. A repeat of the version in force is `Duplicate`, an older version `Stale`.
#[test]
fn duplicate_means_equal_to_the_version_in_force() {
    let mut r = Rig::hrp2();
    for (i, x) in [0.1, 0.2, 0.3, 0.4].iter().enumerate() {
        let left = i % 2 == 1;
        assert_eq!(r.append(i as u16, left, *x, y(left)), None);
    }
    let a = r.book.modify(2, 0.32, -0.1, 0.0).unwrap();
    let b = r.book.modify(2, 0.28, -0.1, 0.0).unwrap();
    let a2 = r.book.modify(2, 0.32, -0.1, 0.0).unwrap();
    assert_eq!(r.ask(a), None);
    assert_eq!(r.ask(b), None);
    assert_eq!(r.ask(a2), None, "back to A: a new version");
    assert_eq!(r.ask(a2), Some(Reason::Duplicate));
    assert_eq!(r.ask(b), Some(Reason::Stale));
    assert_eq!(r.ask(a), Some(Reason::Stale));
    assert_eq!(r.control(ControlOp::Start), None);
    r.until(2000, |n| n.gait().swinging() == Some(2));
    r.until(400, |n| n.gait().swinging() != Some(2));
    let f = r.n.gait().feet()[1];
    assert_eq!((f.x, f.y), (0.32, -0.1), "walked at A");
}

/// Item 7: a turn across ±π. The swinging foot turns the short way (0.29 rad, not 5.99), and
/// every published heading is within [−π, π].
#[test]
fn a_turn_across_pi_turns_the_short_way() {
    let mut cfg = NodeConfig::hrp2();
    let h = std::f64::consts::PI - 0.1;
    // Feet 0.2 m apart across the heading h (left of the walking direction).
    let (s, c) = h.sin_cos();
    cfg.left = planner_core::gait::Footstep::new(Side::Left, -s * 0.1, c * 0.1, h);
    cfg.right = planner_core::gait::Footstep::new(Side::Right, s * 0.1, -c * 0.1, h);
    let mut r = Rig::new(cfg);
    // Step in place while turning by +0.29 rad per step: across +π into −π.
    let mut heading = h;
    for id in 0..3u16 {
        heading += 0.145;
        let left = id % 2 == 1;
        let off = if left { 0.1 } else { -0.1 };
        let (s, c) = heading.sin_cos();
        let c = r
            .book
            .append(id, left, -s * off, c * off, heading)
            .expect("representable");
        assert_eq!(r.ask(c), None, "step {id}");
    }
    assert_eq!(r.control(ControlOp::Start), None);
    let mut last = [h, h];
    let mut travel = [0.0f64; 2];
    for k in 0..1000 {
        r.run(1, k % 20 == 0);
        let feet = r.n.gait().last().feet;
        for i in 0..2 {
            let y = feet[i].yaw;
            assert!(y.abs() <= std::f64::consts::PI + 1e-12, "{y}");
            let d = (y - last[i] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            travel[i] += d.abs();
            last[i] = y;
        }
    }
    // Each foot turned by what its steps ask (two steps of 0.29 and one, up to rounding).
    for t in travel {
        assert!(t < 0.62, "a foot turned by {t} rad in all");
    }
    assert!(travel.iter().sum::<f64>() > 0.4, "{travel:?}");
}

/// Item 9: `Reset` while standing re-bases the frame on the feet: after walking to x = 1.0,
/// the stream reports the feet about the new origin and a step at x = 0.2 is in reach.
#[test]
fn reset_rebases_the_frame() {
    let mut r = Rig::hrp2();
    let xs = [0.2, 0.4, 0.6, 0.8, 1.0, 1.0];
    for (i, x) in xs.iter().enumerate() {
        let left = i % 2 == 1;
        assert_eq!(r.append(i as u16, left, *x, y(left)), None, "step {i}");
    }
    assert_eq!(r.control(ControlOp::Start), None);
    assert_eq!(r.control(ControlOp::Stop), None);
    r.until(4000, |n| n.gait().is_standing());
    r.run(2, true);
    assert!((r.stream.feet[0][0] - 1.0).abs() < 1e-4);
    let far = WireStep::from_si(6, false, 0.2, -0.1, 0.0).unwrap();
    assert_eq!(r.ask(Command::Append(far)), Some(Reason::Reach));
    assert_eq!(r.control(ControlOp::Reset), None);
    r.run(2, true);
    for k in 0..2 {
        assert!(r.stream.feet[k][0].abs() < 1e-4, "{:?}", r.stream.feet);
        assert!((r.stream.feet[k][1].abs() - 0.1).abs() < 1e-4);
        assert!(r.stream.feet[k][3].abs() < 1e-4);
    }
    assert!(r.stream.cog[0].abs() < 1e-6 && r.stream.cog[1].abs() < 1e-6);
    assert_eq!(
        r.append(6 + 256, true, 0.2, 0.1),
        None,
        "in reach in the new frame"
    );
    // And it walks there.
    assert_eq!(r.control(ControlOp::Start), None);
    assert_eq!(r.control(ControlOp::Stop), None);
    r.until(4000, |n| n.gait().is_standing());
    let left = r.n.gait().feet()[0];
    assert_eq!((left.x, left.y), (0.2, 0.1));
}

/// Item 10: frames that are not the node's are never answered and do not take the command
/// budget; frames with the node's ids are still refused with their reason.
#[test]
fn foreign_frames_are_ignored() {
    let mut r = Rig::hrp2();
    // 100 foreign frames (every non-command id class: other standard ids, the node's own
    // output ids), then a command, in one cycle.
    for k in 0..100u16 {
        let id = [0x555, 0x7FF, 0x000, ids::ACK, ids::COG, ids::STATUS, 0x102][usize::from(k % 7)];
        r.bus
            .rx
            .push_back(RawFrame::new(id, &[k as u8; 3]).unwrap());
    }
    let c = r.book.append(0, false, 0.1, -0.1, 0.0).unwrap();
    r.bus.rx.push_back(c.encode());
    let acks = r.cycle();
    assert_eq!(acks.len(), 1, "{acks:?}");
    assert_eq!((acks[0].reason, acks[0].echo), (None, c.echo()));
    assert_eq!(r.n.counters().foreign, 100);
    assert_eq!(r.n.counters().refused, 0);
    r.run(20, true);
    assert_eq!(r.diag.map(|d| d.foreign), Some(100));
    // Our identifiers with a bad length or CRC: refused with the reason.
    let short = RawFrame::new(ids::STEP_MODIFY, &[1, 2]).unwrap();
    r.bus.rx.push_back(short);
    let mut bad = r.command(ControlOp::Stop).encode();
    bad.data[2] ^= 1;
    r.bus.rx.push_back(bad);
    let acks = r.cycle();
    let reasons: Vec<_> = acks.iter().map(|a| a.reason).collect();
    assert_eq!(reasons, [Some(Reason::BadLength), Some(Reason::BadCrc)]);
    // A flood beyond the per-cycle foreign budget is drained over cycles, never answered.
    for _ in 0..1000 {
        r.bus.rx.push_back(RawFrame::new(0x400, &[]).unwrap());
    }
    let mut answered = 0;
    for _ in 0..10 {
        answered += r.cycle().len();
    }
    assert_eq!(answered, 0);
    assert!(r.bus.rx.is_empty());
}

/// Review finding: the growth rule from standing ("a step at most 0.22 m longer than the one
/// before, from standing: than 0") held only for parallel feet. With the feet staggered after
/// a walk, a 0.30 m first step was accepted from rest.
#[test]
fn the_first_step_from_standing_grows_from_zero_whatever_the_stagger() {
    let mut r = Rig::hrp2();
    assert_eq!(r.append(0, false, 0.1, -0.1), None);
    assert_eq!(r.append(1, true, 0.2, 0.1), None); // the left foot ends 0.1 m ahead
    assert_eq!(r.control(ControlOp::Start), None);
    assert_eq!(r.control(ControlOp::Stop), None);
    r.until(4000, |n| n.gait().is_standing());
    let too_long = WireStep::from_si(2, false, 0.5, -0.1, 0.0).unwrap();
    assert_eq!(r.ask(Command::Append(too_long)), Some(Reason::Reach));
    // 0.22 m ahead of the support foot is the limit from rest.
    assert_eq!(r.append(2, false, 0.42, -0.1), None);
    // A modification of that first step is held to the same rule.
    let c = r.book.modify(2, 0.5, -0.1, 0.0).unwrap();
    assert_eq!(r.ask(c), Some(Reason::Reach));
}

/// Review finding: a late copy of a `Stop` moved the last accepted sequence number back, so a
/// late copy of a `Start` after it counted as new again and started the robot. Now every
/// control command is taken only with a sequence number greater than every one before it: a
/// late `Stop` is `Stale` like any other, and so is the late `Start`.
#[test]
fn a_late_stop_does_not_make_a_late_start_new() {
    let mut r = Rig::hrp2();
    assert_eq!(r.append(0, false, 0.1, -0.1), None);
    // Each command with the next number; `late` keeps a copy to send again later.
    let next = |r: &mut Rig, op| r.command(op);
    let start1 = next(&mut r, ControlOp::Start);
    assert_eq!(r.ask(start1), None);
    let stop = next(&mut r, ControlOp::Stop);
    assert_eq!(r.ask(stop), None);
    r.until(4000, |n| n.gait().is_standing());
    assert_eq!(r.append(1, true, 0.2, 0.1), None);
    let start2 = next(&mut r, ControlOp::Start);
    assert_eq!(r.ask(start2), None);
    assert_eq!(
        r.ask(stop),
        Some(Reason::Stale),
        "a late stop is old like any command"
    );
    let stop2 = next(&mut r, ControlOp::Stop);
    assert_eq!(r.ask(stop2), None);
    r.until(4000, |n| n.gait().is_standing());
    assert_eq!(r.append(2, false, 0.3, -0.1), None);
    assert_eq!(r.ask(start2), Some(Reason::Stale));
    assert_eq!(r.ask(start1), Some(Reason::Stale));
    assert_eq!(r.n.state(), NodeState::Standing);
    let start3 = next(&mut r, ControlOp::Start);
    assert_eq!(r.ask(start3), None);
    assert_eq!(r.ask(start3), Some(Reason::Duplicate));
}

/// Review finding: a heartbeat repeated for ever (a stuck gateway) kept supervision satisfied.
/// A heartbeat with the previous heartbeat's sequence number proves nothing (`Duplicate`):
/// the robot stops as if the controller were silent.
#[test]
fn a_repeated_heartbeat_proves_nothing() {
    let mut r = Rig::hrp2();
    for i in 0..6u16 {
        let left = i % 2 == 1;
        assert_eq!(r.append(i, left, 0.15 * f64::from(i + 1), y(left)), None);
    }
    assert_eq!(r.control(ControlOp::Start), None);
    let stuck = r.heartbeat();
    assert_eq!(r.ask(stuck), None);
    for k in 0..120u32 {
        if k % 20 == 0 {
            r.bus.rx.push_back(stuck.encode());
        }
        r.cycle();
    }
    assert_eq!(r.n.state(), NodeState::ControllerLost);
    assert_eq!(r.n.gait().queued(), 0);
    // New heartbeats are accepted (the state stays latched until a reset once standing).
    let fresh = r.heartbeat();
    assert_eq!(r.ask(fresh), None);
    assert_eq!(r.ask(fresh), Some(Reason::Duplicate));
}
