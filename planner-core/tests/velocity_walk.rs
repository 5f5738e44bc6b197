//! Walking at a velocity and to a goal on the node (`planner_core::node`'s `drive`): a change
//! reaches the next landing that may still move in the cycle it is accepted, cuts are
//! answered, values that are not numbers and old frames change nothing, a stream that stops
//! stops the robot, a goal is reached within its tolerance.

mod common;

use common::*;
use planner_core::gait::{Footstep, Side};
use planner_core::node::{
    Driver, NodeConfig, NodeState, Reach, GOAL_TOLERANCE, GOAL_YAW_TOLERANCE,
};
use planner_core::velocity::{Saturation, Stepping, Velocity};
use planner_core::wire::{ids, Ack, Command, Reason, WireGoal, WireVelocity};

/// Sends `c` alone in one cycle and returns its answer (a refusal checked to change nothing,
/// as `Rig::ask` does).
fn send(r: &mut Rig, c: Command) -> Ack {
    let epoch = r.session.epoch;
    let mut without = r.n.clone();
    without.poll(r.t + 5, &mut Bus::default());
    r.bus.rx.push_back(c.encode_in(epoch));
    let acks = r.cycle();
    let a = *acks
        .iter()
        .find(|a| a.command == c.code() && a.echo == c.echo_in(epoch))
        .unwrap_or_else(|| panic!("no answer to {c:?}: {acks:?}"));
    if a.reason.is_some() {
        assert!(r.n.same_state(&without), "refused {a:?} changed the node");
    }
    a
}

fn velocity(r: &mut Rig, vx: f64, vy: f64, wz: f64) -> Ack {
    r.seq += 1;
    send(
        r,
        Command::Velocity(WireVelocity::from_si(r.seq, vx, vy, wz)),
    )
}

fn goal(r: &mut Rig, x: f64, y: f64, yaw: f64) -> Ack {
    r.seq += 1;
    send(r, Command::Goal(WireGoal::from_si(r.seq, x, y, yaw)))
}

/// Cycles with a velocity every 10 cycles (50 ms), `k` cycles.
fn stream(r: &mut Rig, k: u32, v: (f64, f64, f64)) {
    for i in 0..k {
        if i % 10 == 0 {
            let a = velocity(r, v.0, v.1, v.2);
            assert_eq!(a.reason, None, "{a:?}");
        } else {
            r.cycle();
        }
    }
}

/// The index of `side` in `[left, right]`.
fn ix(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

fn stepping(r: &Rig) -> Stepping<f64> {
    Stepping::of(&r.n.config().params, r.n.config().reach)
}

/// The next movable landing (the next swing target) and the feet before it.
fn next_landing(r: &Rig) -> (Footstep<f64>, [Footstep<f64>; 2]) {
    let g = r.n.gait();
    let id = g.next_target().expect("a step queued");
    (g.queued_step(id).unwrap(), g.previous_feet(Some(id)))
}

#[test]
fn a_velocity_change_reaches_the_next_movable_landing_in_the_cycle_it_is_accepted() {
    let mut r = Rig::hrp2();
    stream(&mut r, 400, (0.15, 0.0, 0.0));
    assert_eq!(r.n.state(), NodeState::Walking);
    assert_eq!(r.n.driver(), Driver::Velocity);
    assert_eq!(r.n.gait().queued(), planner_core::node::AHEAD);
    for (k, v) in [(0.0, 0.04, 0.0), (0.05, 0.0, -0.15), (0.05, 0.0, 0.15)]
        .into_iter()
        .enumerate()
    {
        // Mid-swing: the next target has not lifted off.
        r.until(400, |n| n.gait().swinging().is_some());
        stream(&mut r, 30, (0.15, 0.0, 0.0));
        let (before, feet) = next_landing(&r);
        let a = velocity(&mut r, v.0, v.1, v.2);
        assert_eq!(a.reason, None, "change {k}: {a:?}");
        let (after, _) = next_landing(&r);
        assert_ne!(before, after, "change {k}: the next landing did not move");
        // It is the landing the new velocity gives from the feet before it.
        let side = after.side;
        let want = stepping(&r)
            .next_step(
                &Velocity {
                    vx: v.0,
                    vy: v.1,
                    wz: v.2,
                },
                &feet[ix(side.other())],
                &feet[ix(side)],
                false,
            )
            .unwrap()
            .0;
        assert!((after.x - want.x).abs() < 2e-3 && (after.y - want.y).abs() < 2e-3);
        assert!((after.yaw - want.yaw).abs() < 4e-3, "{after:?} {want:?}");
        stream(&mut r, 200, v);
    }
    assert_ne!(r.n.state(), NodeState::ControllerLost);
}

#[test]
fn a_velocity_beyond_the_legs_is_walked_cut_and_the_answer_says_so() {
    let mut r = Rig::hrp2();
    let a = velocity(&mut r, 0.1, 0.0, 0.0);
    assert_eq!(a.reason, None);
    assert_eq!(a.cut(), Some(0), "{a:?}");
    stream(&mut r, 200, (0.1, 0.0, 0.0));
    for (v, forward, lateral, turn) in [
        ((0.9, 0.0, 0.0), true, false, false),
        ((0.0, 0.5, 0.0), false, true, false),
        ((0.0, 0.0, 0.9), false, false, true),
    ] {
        r.until(400, |n| n.gait().swinging().is_some());
        let a = velocity(&mut r, v.0, v.1, v.2);
        assert_eq!(a.reason, None, "{v:?}");
        let cut = Saturation::from_mask(a.cut().expect("a cut mask"));
        assert_eq!(
            (cut.forward, cut.lateral, cut.turn),
            (forward, lateral, turn),
            "{v:?}"
        );
        // Every landing planned passes the node's reach check.
        for pos in 0..r.n.gait().queued() {
            let id = r.n.gait().next_target().unwrap().wrapping_add(pos as u16);
            let s = r.n.gait().queued_step(id).unwrap();
            let feet = r.n.gait().previous_feet(Some(id));
            let reach = Reach::default();
            let soles = planner_core::node::Soles::of(&r.n.config().params);
            assert_eq!(
                reach.broken(
                    &feet[ix(s.side.other())],
                    &feet[ix(s.side)],
                    &s,
                    false,
                    &soles
                ),
                None,
                "{v:?} {s:?}"
            );
        }
        stream(&mut r, 100, v);
    }
}

#[test]
fn a_velocity_that_is_not_a_number_is_refused_and_changes_nothing() {
    let mut r = Rig::hrp2();
    for v in [
        (f64::NAN, 0.0, 0.0),
        (0.0, f64::INFINITY, 0.0),
        (0.0, 0.0, f64::NEG_INFINITY),
    ] {
        let a = velocity(&mut r, v.0, v.1, v.2);
        assert_eq!(a.reason, Some(Reason::OutOfRange), "{v:?}");
    }
    assert_eq!(r.n.state(), NodeState::Standing);
    // Walking, too.
    stream(&mut r, 300, (0.1, 0.0, 0.0));
    let a = velocity(&mut r, f64::NAN, 0.0, 0.0);
    assert_eq!(a.reason, Some(Reason::OutOfRange));
    assert_eq!(r.n.drive_velocity().unwrap().0.vx, 0.1);
}

#[test]
fn a_zero_velocity_brings_the_robot_to_a_stand_with_its_feet_together() {
    let mut r = Rig::hrp2();
    stream(&mut r, 300, (0.1, 0.0, 0.1));
    let a = velocity(&mut r, 0.0, 0.0, 0.0);
    assert_eq!(a.reason, None);
    assert!(r.n.gait().is_stopping());
    // A stick held at zero keeps streaming it: taken, nothing changes (the controller is
    // heard).
    let queued = r.n.gait().queued();
    assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
    assert!(r.n.gait().is_stopping() && r.n.gait().queued() == queued);
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(r.n.state(), NodeState::Standing);
    assert_eq!(r.n.driver(), Driver::Steps);
    let [l, rt] = *r.n.gait().feet();
    assert!((l.yaw - rt.yaw).abs() < 1e-9, "{l:?} {rt:?}");
    let (s, c) = rt.yaw.sin_cos();
    let across = -s * (l.x - rt.x) + c * (l.y - rt.y);
    let along = c * (l.x - rt.x) + s * (l.y - rt.y);
    let w = r.n.config().params.step_width;
    assert!(
        (across - w).abs() < 1e-9 && along.abs() < 1e-9,
        "{across} {along}"
    );
    // Standing, velocity walking starts again.
    assert_eq!(velocity(&mut r, 0.1, 0.0, 0.0).reason, None);
    assert_eq!(r.n.state(), NodeState::Walking);
}

/// A controller that sends nothing but a `VELOCITY` every 50 ms, and releases its stick to
/// zero, stops the robot and is never declared lost: every frame of the stream is taken.
#[test]
fn a_velocity_only_stream_released_to_zero_stands_and_stays_alive() {
    let mut r = Rig::hrp2();
    stream(&mut r, 300, (0.1, 0.0, 0.0));
    let mut k = 0;
    while !r.n.gait().is_standing() {
        assert!(k < 4000, "not standing after {k} cycles");
        if k % 10 == 0 {
            let a = velocity(&mut r, 0.0, 0.0, 0.0);
            assert_eq!(a.reason, None, "cycle {k}: {a:?}");
        } else {
            r.cycle();
        }
        k += 1;
    }
    // The stream goes on at zero while standing, past every timeout.
    stream(&mut r, 300, (0.0, 0.0, 0.0));
    assert_eq!(r.n.state(), NodeState::Standing);
    assert_eq!(velocity(&mut r, 0.1, 0.0, 0.0).reason, None);
}

/// The stop a zero velocity asks for is the drive's own: while a step queued after the one
/// being swung has not lifted off, a new velocity cancels it and re-plans the queued steps (the
/// next swing target is the new velocity's step from the feet before it); once no step is
/// left to change, the velocity is refused `WrongState` and taken again once standing.
#[test]
fn a_velocity_cancels_the_drives_own_stop_while_its_steps_have_not_lifted_off() {
    let mut r = Rig::hrp2();
    stream(&mut r, 300, (0.1, 0.0, 0.0));
    assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
    assert!(r.n.gait().is_stopping());
    r.cycle();
    let (before, feet) = next_landing(&r);
    let from_rest = r.n.gait().next_swing_from_rest();
    let v = Velocity {
        vx: 0.12,
        vy: 0.0,
        wz: 0.0,
    };
    assert_eq!(velocity(&mut r, v.vx, v.vy, v.wz).reason, None);
    assert!(!r.n.gait().is_stopping());
    let (after, _) = next_landing(&r);
    assert_ne!(before, after);
    let side = after.side;
    let want = stepping(&r)
        .next_step(&v, &feet[ix(side.other())], &feet[ix(side)], from_rest)
        .unwrap()
        .0;
    assert!((after.x - want.x).abs() < 2e-3 && (after.y - want.y).abs() < 2e-3);
    // It walks on at that velocity (the queue topped up again).
    stream(&mut r, 400, (0.12, 0.0, 0.0));
    assert_eq!(r.n.state(), NodeState::Walking);
    assert_eq!(r.n.gait().queued(), planner_core::node::AHEAD);
    // Stopped again, and held at zero until nothing queued is left to change: then a velocity
    // is refused (its steps could not be walked) and nothing changes.
    assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
    let mut k = 0;
    while r.n.gait().queued() > 0 {
        assert!(k < 4000);
        if k % 10 == 0 {
            assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
        } else {
            r.cycle();
        }
        k += 1;
    }
    assert!(r.n.gait().is_stopping());
    assert_eq!(
        velocity(&mut r, 0.1, 0.0, 0.0).reason,
        Some(Reason::WrongState)
    );
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(velocity(&mut r, 0.1, 0.0, 0.0).reason, None);
}

/// The controller's own `Stop` during a velocity walk is not cancelled by a velocity (only a
/// stop the drive asked for is); a zero velocity is still taken (the stick streams it).
#[test]
fn a_velocity_does_not_cancel_the_controllers_stop() {
    let mut r = Rig::hrp2();
    stream(&mut r, 300, (0.1, 0.0, 0.0));
    assert_eq!(r.control(planner_core::wire::ControlOp::Stop), None);
    assert!(r.n.gait().is_stopping());
    assert_eq!(
        velocity(&mut r, 0.1, 0.0, 0.0).reason,
        Some(Reason::WrongState)
    );
    assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
    assert!(r.n.gait().is_stopping());
}

/// A goal walk that has queued its closing step (and asked for its stop) is replaced at once
/// by a new goal or a velocity while the queued steps have not lifted off.
#[test]
fn a_goal_is_replaced_at_once_in_its_last_steps() {
    for by_goal in [true, false] {
        let mut r = Rig::hrp2();
        assert_eq!(goal(&mut r, 1.0, 0.0, 0.0).reason, None);
        r.until(20_000, |n| n.gait().is_stopping());
        assert!(r.n.gait().queued() > 0);
        let a = if by_goal {
            goal(&mut r, -1.0, 0.0, 0.0)
        } else {
            velocity(&mut r, 0.0, 0.1, 0.0)
        };
        assert_eq!(a.reason, None, "by goal {by_goal}: {a:?}");
        assert!(!r.n.gait().is_stopping());
        let want = if by_goal {
            Driver::Goal
        } else {
            Driver::Velocity
        };
        assert_eq!(r.n.driver(), want);
        assert!(!r.n.at_goal());
    }
}

#[test]
fn a_stream_that_stops_stops_the_robot_as_a_lost_controller_does() {
    let cfg = NodeConfig::hrp2();
    let mut r = Rig::new(cfg);
    // (The last velocity in the last cycle.)
    stream(&mut r, 301, (0.1, 0.0, 0.0));
    let last = r.t;
    // Heartbeats keep the controller alive, not the stream.
    let mut lost_at = None;
    for i in 0..200 {
        if i % 10 == 0 {
            let hb = r.heartbeat();
            assert_eq!(send(&mut r, hb).reason, None);
        } else {
            r.cycle();
        }
        if r.n.state() == NodeState::ControllerLost && lost_at.is_none() {
            lost_at = Some(r.t);
        }
    }
    let lost_at = lost_at.expect("the robot did not stop");
    assert!(
        lost_at - last <= cfg.velocity_timeout_ms + 5,
        "{lost_at} {last}"
    );
    assert!(lost_at - last > cfg.velocity_timeout_ms, "{lost_at} {last}");
    // No foot lifts off after the timeout.
    assert!(r
        .liftoffs
        .iter()
        .all(|&(t, _, _)| t <= last + cfg.velocity_timeout_ms + 5));
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(
        velocity(&mut r, 0.1, 0.0, 0.0).reason,
        Some(Reason::ControllerLost)
    );
}

#[test]
fn a_replayed_or_older_velocity_frame_does_not_keep_the_stream_alive() {
    let cfg = NodeConfig::hrp2();
    let mut r = Rig::new(cfg);
    stream(&mut r, 301, (0.1, 0.0, 0.0));
    let last = r.seq;
    let epoch = r.session.epoch;
    let t0 = r.t;
    let replay = Command::Velocity(WireVelocity::from_si(last, 0.1, 0.0, 0.0));
    let older = Command::Velocity(WireVelocity::from_si(last - 1, 0.1, 0.0, 0.0));
    // Another session's frame (the session keys the CRC) and one 2²⁴ numbers back (its
    // low bits read as new, its high byte in the CRC).
    let other = WireVelocity::from_si(last + 1, 0.1, 0.0, 0.0).encode(epoch ^ 1);
    let wrapped = Command::Velocity(WireVelocity::from_si(
        (last + 1).wrapping_sub(1 << 24),
        0.1,
        0.0,
        0.0,
    ));
    let mut answers = vec![];
    while r.n.state() == NodeState::Walking && r.t < t0 + 1000 {
        let i = ((r.t - t0) / 5) % 4;
        let f = match i {
            0 => replay.encode_in(epoch),
            1 => older.encode_in(epoch),
            2 => other,
            _ => wrapped.encode_in(epoch),
        };
        // (The first replay before any newer command: a repeat of the last one taken.)
        if r.t > t0 {
            let hb = r.heartbeat();
            r.bus.rx.push_back(hb.encode());
        }
        r.bus.rx.push_back(f);
        for a in r.cycle() {
            if a.command == (ids::VELOCITY & 0xFF) as u8 {
                answers.push(a.reason);
            }
        }
    }
    assert_eq!(r.n.state(), NodeState::ControllerLost);
    assert!(r.t - t0 <= cfg.velocity_timeout_ms + 5);
    assert!(answers.contains(&Some(Reason::Duplicate)));
    assert!(answers.contains(&Some(Reason::Stale)));
    assert!(answers.contains(&Some(Reason::BadCrc)));
    assert!(answers.iter().all(|a| a.is_some()), "{answers:?}");
}

#[test]
fn footsteps_are_refused_while_the_node_chooses_them_and_taken_once_standing() {
    let mut r = Rig::hrp2();
    stream(&mut r, 200, (0.1, 0.0, 0.0));
    let next = r.n.next_step();
    let left = r.n.gait().next_side() == Some(Side::Left);
    assert_eq!(r.append(next, left, 1.0, y(left)), Some(Reason::WrongState));
    // A walk of footsteps is not steered by velocity.
    let mut s = Rig::hrp2();
    queue_walk(&mut s, 4);
    s.control(planner_core::wire::ControlOp::Start);
    assert_eq!(
        velocity(&mut s, 0.1, 0.0, 0.0).reason,
        Some(Reason::WrongState)
    );
}

#[test]
fn two_velocities_in_one_cycle_the_second_is_busy() {
    let mut r = Rig::hrp2();
    stream(&mut r, 300, (0.1, 0.0, 0.0));
    let epoch = r.session.epoch;
    let a = Command::Velocity(WireVelocity::from_si(r.seq + 1, 0.0, 0.03, 0.0));
    let b = Command::Velocity(WireVelocity::from_si(r.seq + 2, 0.1, 0.0, 0.0));
    r.seq += 2;
    r.bus.rx.push_back(a.encode_in(epoch));
    r.bus.rx.push_back(b.encode_in(epoch));
    let acks = r.cycle();
    let reasons: Vec<_> = acks
        .iter()
        .filter(|a| a.command == (ids::VELOCITY & 0xFF) as u8)
        .map(|a| a.reason)
        .collect();
    assert_eq!(reasons, vec![None, Some(Reason::Busy)]);
    assert_eq!(r.n.drive_velocity().unwrap().0.vy, 0.03);
}

#[test]
fn a_goal_is_walked_to_within_its_tolerance_and_its_arrival_reported() {
    for (x, y_, yaw) in [
        (0.8, 0.0, 0.0),
        (0.5, 0.2, 0.4),
        (-0.2, -0.1, -0.3),
        (0.3, 0.0, 1.2),
    ] {
        let mut r = Rig::hrp2();
        let a = goal(&mut r, x, y_, yaw);
        assert_eq!(a.reason, None, "{a:?}");
        r.until(20_000, |n| n.gait().is_standing());
        assert!(r.n.at_goal(), "goal {x} {y_} {yaw}");
        let [l, rt] = *r.n.gait().feet();
        let (mx, my) = (0.5 * (l.x + rt.x), 0.5 * (l.y + rt.y));
        let h = (l.yaw.sin() + rt.yaw.sin()).atan2(l.yaw.cos() + rt.yaw.cos());
        // The goal as the wire carries it (1 cm, 2π/1024).
        let g = WireGoal::from_si(0, x, y_, yaw).si_in::<f64>();
        let tol = GOAL_TOLERANCE * std::f64::consts::SQRT_2 + 1e-3;
        assert!(
            (mx - g.0).hypot(my - g.1) <= tol,
            "goal {g:?}: at {mx} {my}"
        );
        assert!(
            (h - g.2).abs() <= GOAL_YAW_TOLERANCE + 1e-3,
            "goal {g:?}: heading {h}"
        );
        // A new command clears the arrival.
        assert_eq!(velocity(&mut r, 0.1, 0.0, 0.0).reason, None);
        assert!(!r.n.at_goal());
    }
}

#[test]
fn a_velocity_replaces_a_goal_at_once() {
    let mut r = Rig::hrp2();
    assert_eq!(goal(&mut r, 2.0, 0.0, 0.0).reason, None);
    r.until(400, |n| n.gait().swinging().is_some());
    r.run(10, true);
    let (before, _) = next_landing(&r);
    assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
    let (after, _) = next_landing(&r);
    assert_ne!(before, after);
    assert_eq!(r.n.driver(), Driver::Velocity);
    r.until(2000, |n| n.gait().is_standing());
    assert!(!r.n.at_goal());
}

/// The midpoint of the feet.
fn midpoint(r: &Rig) -> (f64, f64) {
    let [l, rt] = *r.n.gait().feet();
    (0.5 * (l.x + rt.x), 0.5 * (l.y + rt.y))
}

/// `STATUS`'s `AT_GOAL` flag after a few cycles (a `STATUS` among them).
fn flagged(r: &mut Rig) -> bool {
    r.run(40, true);
    r.status.unwrap().flags & planner_core::wire::Status::AT_GOAL != 0
}

/// The arrival is reported only while standing at the goal: a `StopNow` after the goal walk
/// has queued its closing step stands short of it, and neither `at_goal()` nor `STATUS` says
/// it arrived.
#[test]
fn a_goal_walk_stopped_short_of_its_goal_is_not_at_it() {
    use planner_core::wire::ControlOp;
    let mut r = Rig::hrp2();
    assert_eq!(goal(&mut r, 1.0, 0.0, 0.0).reason, None);
    r.until(20_000, |n| n.gait().is_stopping());
    assert_eq!(r.control(ControlOp::StopNow), None);
    r.until(2000, |n| n.gait().is_standing());
    let (mx, my) = midpoint(&r);
    assert!((mx - 1.0).hypot(my) > 2.0 * GOAL_TOLERANCE, "{mx} {my}");
    assert!(!r.n.at_goal());
    assert!(!flagged(&mut r));
}

/// The arrival belongs to the goal given in this session with no walk since: a `Reset` ends
/// it, and so does a walk of the controller's footsteps.
#[test]
fn a_goals_arrival_ends_with_a_new_session_or_a_footstep_walk() {
    use planner_core::wire::ControlOp;
    let mut r = Rig::hrp2();
    assert_eq!(goal(&mut r, 0.3, 0.0, 0.0).reason, None);
    r.until(20_000, |n| n.gait().is_standing());
    assert!(r.n.at_goal());
    assert!(flagged(&mut r));
    let mut s = r.fork();
    assert_eq!(s.control(ControlOp::Reset), None);
    assert!(!s.n.at_goal());
    assert!(!flagged(&mut s));
    // A footstep walk (in the same session) from the goal, ending elsewhere.
    queue_walk(&mut r, 4);
    assert!(!r.n.at_goal());
    assert_eq!(r.control(ControlOp::Start), None);
    assert_eq!(r.control(ControlOp::Stop), None);
    r.until(4000, |n| n.gait().is_standing());
    assert!(!r.n.at_goal());
    assert!(!flagged(&mut r));
}

/// A `VELOCITY` of another start-up (another session epoch) is taken with odds of at most
/// 2⁻¹⁶, those of a `CONTROL`: of the 256 epochs that share this one's low byte, at most one
/// gets a frame through (whatever its sequence number), and none of the others' (a frame keyed
/// with another low byte fails its CRC).
#[test]
fn another_sessions_velocity_is_taken_no_more_often_than_its_control() {
    let r = Rig::hrp2();
    let epoch = r.session.epoch;
    let last = r.n.session().last_seq;
    for seq in [last + 1, last + 200, last + 70_000, last + (1 << 20), 3] {
        let taken = (0u32..256)
            .filter(|&k| {
                let other = epoch ^ (k << 8);
                let f = Command::Velocity(WireVelocity::from_si(seq, 0.2, 0.0, 0.0));
                let a = r.n.clone().handle(&f.encode_in(other), r.t).unwrap();
                a.reason.is_none()
            })
            .count();
        assert!(taken <= 1, "seq {seq}: {taken} of 256 epochs taken");
        // Another low byte: never.
        for k in 1u32..256 {
            let f = Command::Velocity(WireVelocity::from_si(seq, 0.2, 0.0, 0.0));
            let a = r.n.clone().handle(&f.encode_in(epoch ^ k), r.t).unwrap();
            assert!(a.reason.is_some(), "seq {seq}, low byte ^ {k}");
        }
    }
}

/// The frame of an earlier start-up whose session differs in its second byte only is refused,
/// and the live controller keeps its sequence numbers (its `Stop` is taken).
#[test]
fn an_earlier_start_ups_velocity_does_not_lock_the_controller_out() {
    use planner_core::wire::ControlOp;
    let mut old_cfg = NodeConfig::hrp2();
    old_cfg.entropy = 0x1234_5600;
    let mut cfg = NodeConfig::hrp2();
    cfg.entropy = 0x1234_5700;
    let mut old = Rig::new(old_cfg);
    for _ in 0..200 {
        old.heartbeat();
    }
    old.seq += 1;
    let stale = Command::Velocity(WireVelocity::from_si(old.seq, 0.2, 0.0, 0.0))
        .encode_in(old.session.epoch);
    let mut r = Rig::new(cfg);
    assert_ne!(r.session.tag(), old.session.tag());
    r.bus.rx.push_back(stale);
    let a = r.cycle();
    assert!(a[0].reason.is_some(), "{a:?}");
    assert_eq!(r.n.state(), NodeState::Standing);
    assert_eq!(velocity(&mut r, 0.1, 0.0, 0.0).reason, None);
    r.run(3, true);
    assert_eq!(r.control(ControlOp::Stop), None);
}

/// A zero velocity queues what the stop needs and no more: the next swing target closes the
/// feet and the steps after it are dropped (their numbers given to the next steps), so the
/// robot stands after landing the foot it swings and one step more.
#[test]
fn a_zero_velocity_keeps_only_the_closing_step() {
    let mut r = Rig::hrp2();
    stream(&mut r, 300, (0.1, 0.0, 0.0));
    r.until(400, |n| n.gait().swinging().is_some());
    r.cycle(); // (the queue topped up after the lift-off)
    let queued = r.n.gait().queued();
    assert_eq!(queued, planner_core::node::AHEAD);
    let next = r.n.next_step();
    let lifted = r.liftoffs.len();
    assert_eq!(velocity(&mut r, 0.0, 0.0, 0.0).reason, None);
    assert_eq!(r.n.gait().queued(), 1);
    assert_eq!(r.n.next_step(), next - (queued as u16 - 1));
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(r.n.state(), NodeState::Standing);
    assert_eq!(r.liftoffs.len() - lifted, 1, "{:?}", &r.liftoffs[lifted..]);
    // The next walk numbers its steps from there on.
    assert_eq!(velocity(&mut r, 0.1, 0.0, 0.0).reason, None);
    assert_eq!(r.n.next_step(), next - (queued as u16 - 1) + queued as u16);
}

/// With the start-up's step numbers all but spent, a drive's stop is still taken: a zero
/// velocity appends no step (it keeps the closing one), while a change that needs a new step
/// is refused `Exhausted` with nothing changed.
#[test]
fn a_stop_is_taken_when_the_step_numbers_are_spent() {
    use planner_core::node::AHEAD;
    use planner_core::wire::ControlOp;
    let mut r = Rig::hrp2();
    let first = r.n.next_step();
    for _ in 0..255 {
        assert_eq!(r.control(ControlOp::Reset), None);
    }
    let used = |r: &Rig| u32::from(r.n.next_step().wrapping_sub(first));
    while used(&r) < 65_532 {
        let k = (65_532 - used(&r)).min(14) as u16;
        queue_walk(&mut r, k);
        assert_eq!(r.control(ControlOp::StopNow), None);
    }
    // The last three numbers start a walk at 0.2 m/s; after its first lift-off two steps
    // are queued and no number is left to make the queue up.
    assert_eq!(velocity(&mut r, 0.2, 0.0, 0.0).reason, None);
    assert_eq!(used(&r), 65_535);
    for k in 0..400 {
        if r.n.gait().queued() < AHEAD {
            break;
        }
        if k % 10 == 0 {
            assert_eq!(velocity(&mut r, 0.2, 0.0, 0.0).reason, None);
        } else {
            r.cycle();
        }
    }
    let queued = r.n.gait().queued();
    assert!(queued < AHEAD);
    let change = velocity(&mut r.fork(), 0.25, 0.0, 0.0);
    assert_eq!(change.reason, Some(Reason::Exhausted), "{change:?}");
    let stop = velocity(&mut r, 0.0, 0.0, 0.0);
    assert_eq!(stop.reason, None, "{stop:?}");
    assert!(r.n.gait().is_stopping());
    assert!(r.n.gait().queued() <= queued, "no step appended");
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(r.n.state(), NodeState::Standing);
}
