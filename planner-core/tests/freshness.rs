//! Regression tests of the second outside review of the robot-safe node: nothing old counts as
//! new or as alive (replays, wrapped counters, frames across a `Reset` or a restart of the
//! node), an `ESTOP` never waits behind other commands, one sole never lands on the other, a
//! command changes nothing that is not published, and a stopped clock does not switch
//! supervision off. One test per finding, each failing on the node before the fix; driven
//! through the bus as a controller (or a faulty gateway) would.

mod common;

use common::{queue_walk, y, Bus, Rig, N};
use planner_core::gait::{Footstep, Phase, Side};
use planner_core::node::{NodeConfig, NodeState};
use planner_core::wire::{ids, Command, ControlOp, RawFrame, Reason, Session, Status};

/// Runs `cycles` cycles with nothing from the controller but `gateway(k)` (frames a faulty
/// gateway puts on the bus in cycle `k`).
fn dead_controller(r: &mut Rig, cycles: u32, gateway: impl Fn(u32) -> Vec<RawFrame>) {
    for k in 0..cycles {
        r.bus.rx.extend(gateway(k));
        r.cycle();
    }
}

/// Every lift-off of the rig came at most the supervision bound after the controller was last
/// heard, and the last new command was at `last_new` ms.
fn assert_supervised(r: &Rig, last_new: u32) {
    let timeout = r.n.config().heartbeat_timeout_ms;
    for &(at, heard, id) in &r.liftoffs {
        let heard = heard.expect("heard before walking");
        assert!(
            at - heard <= timeout,
            "step {id} lifted off at {at} ms, {} ms after the controller was heard",
            at - heard
        );
        assert!(
            at <= last_new + timeout,
            "step {id} lifted off at {at} ms, {} ms after the last new command",
            at - last_new
        );
    }
}

/// Item 1: a gateway that replays an old `Stop` every 100 ms (or two old heartbeats in turn)
/// after the controller died: the copies are old, prove nothing, and the robot stops within
/// the supervision bound.
#[test]
fn replays_do_not_keep_a_dead_controller_alive() {
    for replay_heartbeats in [false, true] {
        let mut r = Rig::hrp2();
        queue_walk(&mut r, 1);
        let start1 = r.command(ControlOp::Start);
        assert_eq!(r.ask(start1), None);
        let stop = r.command(ControlOp::Stop);
        assert_eq!(r.ask(stop), None);
        r.until(4000, |n| n.gait().is_standing());
        let (h1, h2) = (r.heartbeat(), r.heartbeat());
        assert_eq!(r.ask(h1), None);
        assert_eq!(r.ask(h2), None);
        queue_walk(&mut r, 16);
        assert_eq!(r.control(ControlOp::Start), None);
        let died = r.t;
        r.liftoffs.clear();
        dead_controller(&mut r, 6000, |k| {
            if k % 20 != 0 {
                vec![]
            } else if replay_heartbeats {
                vec![if k % 40 == 0 { h1 } else { h2 }.encode()]
            } else {
                vec![stop.encode()]
            }
        });
        assert_eq!(
            r.n.state(),
            NodeState::ControllerLost,
            "{replay_heartbeats}"
        );
        assert!(r.n.gait().is_standing());
        assert_supervised(&r, died);
        assert!(r.liftoffs.len() <= 2, "{} lift-offs", r.liftoffs.len());
    }
}

/// Item 2a: a modification 65 versions old is older, whatever a 7-bit counter's wrap would
/// say: refused, the step keeps the newest pose, and the controller's next version is taken.
#[test]
fn an_old_version_never_counts_as_newer() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 8);
    let mut versions = vec![];
    for k in 1..=66u32 {
        let x = 0.75 + 0.0005 * f64::from(k);
        let c = r.book.modify(4, x, y(false), 0.0).unwrap();
        assert_eq!(r.ask(c), None, "version {k}");
        versions.push(c);
    }
    let newest = r.n.gait().queued_step(4).unwrap();
    assert_eq!(r.ask(versions[0]), Some(Reason::Stale));
    assert_eq!(r.n.gait().queued_step(4), Some(newest));
    let next = r.book.modify(4, 0.76, y(false), 0.0).unwrap();
    assert_eq!(r.ask(next), None);
    // Versions never wrap: the 127th is the last a step has.
    for _ in 68..=127 {
        let c = r.book.modify(4, 0.75, y(false), 0.0).unwrap();
        assert_eq!(r.ask(c), None);
    }
    assert!(r.book.modify(4, 0.75, y(false), 0.0).is_none());
}

/// Item 2b: a modification of step 3 delayed past 256 steps, when step 259 (the same low byte)
/// is queued: refused, step 259 unchanged. The step numbers are advanced by appending and
/// dropping (`StopNow` while standing) 16 steps at a time.
#[test]
fn a_modification_delayed_past_256_steps_is_refused() {
    let mut r = Rig::new(NodeConfig::hrp2());
    queue_walk(&mut r, 4);
    let late = r.book.modify(3, 0.62, y(true), 0.0).unwrap();
    assert_eq!(r.control(ControlOp::StopNow), None);
    while r.n.next_step() < 256 {
        let k = (256 - r.n.next_step()).min(16);
        queue_walk(&mut r, k);
        assert_eq!(r.control(ControlOp::StopNow), None);
    }
    queue_walk(&mut r, 4);
    let before = r.n.gait().queued_step(259).unwrap();
    assert_eq!(r.n.next_step(), 260);
    assert_eq!(r.ask(late), Some(Reason::BadCrc));
    assert_eq!(r.n.gait().queued_step(259), Some(before));
    assert_eq!(late.encode().data[0], 3, "the same low byte as step 259");
}

/// Item 2c: a `Start` delayed past 129 control commands is old (32-bit sequence numbers,
/// compared without a window).
#[test]
fn a_start_delayed_past_129_commands_is_old() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 2);
    let late = r.command(ControlOp::Start);
    for _ in 0..300 {
        let h = r.heartbeat();
        assert_eq!(r.ask(h), None);
    }
    assert_eq!(r.ask(late), Some(Reason::Stale));
    assert_eq!(r.n.state(), NodeState::Standing);
}

/// Item 3: frames from before a `Reset` change nothing after it: a modification and an append
/// of the old session — the append never accepted, carrying the number that was next at the
/// `Reset` — and a control command (another session). The new session numbers its steps
/// from 256 past the old session's next number, so the old frames are read as numbers of
/// another block.
#[test]
fn frames_from_before_a_reset_change_nothing() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 2);
    let next = r.n.next_step();
    let old_modify = r.book.modify(next - 2, 0.17, y(false), 0.0).unwrap();
    let old_appends: Vec<Command> = (0..3)
        .map(|k| {
            let left = k % 2 == 1;
            r.book
                .append(next + k, left, 0.3 + 0.15 * f64::from(k), y(left), 0.0)
                .expect("representable")
        })
        .collect();
    let old_start = r.command(ControlOp::Start);
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(
        r.n.next_step(),
        next + 256,
        "the new session's first number"
    );
    // The new walk: three steps.
    queue_walk(&mut r, 3);
    let ids = |r: &Rig| {
        let first = r.n.next_step() - 3;
        [0, 1, 2].map(|k| r.n.gait().queued_step(first + k))
    };
    let queued = ids(&r);
    for c in old_appends.iter().chain([&old_modify]) {
        assert_eq!(r.ask(*c), Some(Reason::BadCrc), "{c:?}");
    }
    assert_eq!(r.ask(old_start), Some(Reason::WrongSession));
    assert_eq!(ids(&r), queued);
    assert_eq!(r.n.gait().queued(), 3);
    assert_eq!(r.n.state(), NodeState::Standing);
}

/// The same, with the old session's appends delivered before the new session's own: the
/// next number is 256 past them, so none of them takes its place.
#[test]
fn an_append_never_accepted_before_a_reset_is_not_taken_after_it() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 1);
    let next = r.n.next_step();
    let lost = r.book.append(next, false, 0.3, y(false), 0.0).unwrap();
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.ask(lost), Some(Reason::BadCrc));
    assert_eq!(r.n.gait().queued(), 0);
}

/// A latched state is always clearable by a `Reset`, however many sessions came before: the
/// start-up's step numbers last 255 sessions, and a `Reset` beyond them still opens a session
/// and leaves the emergency stop or the lost controller, with no step numbers left (appends
/// `Exhausted`). No frame of an earlier session is taken: an append sent before the last
/// `Reset` (refused then) is refused after it.
#[test]
fn a_latched_stop_is_always_cleared_by_a_reset() {
    let mut r = Rig::hrp2();
    // A walk, then the controller falls silent: lost.
    queue_walk(&mut r, 4);
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(150, false);
    assert_eq!(r.n.state(), NodeState::ControllerLost);
    r.until(2000, |n| n.gait().is_standing());
    for k in 0..300 {
        // An append of this session, refused (latched), then delivered after the `Reset`.
        let next = r.n.next_step();
        let side = r.n.gait().next_side() == Some(Side::Left);
        let old = r.book.append(next, side, 0.1, y(side), 0.0).unwrap();
        assert!(
            r.ask(old).is_some(),
            "round {k}: a latched node took a step"
        );
        assert_eq!(r.control(ControlOp::Reset), None, "round {k}");
        assert_eq!(r.n.state(), NodeState::Standing, "round {k}");
        assert!(r.ask(old).is_some(), "round {k}: an old append taken");
        assert_eq!(r.n.gait().queued(), 0);
        assert_eq!(
            r.ask(Command::EmergencyStop { seq: k as u8 }),
            None,
            "round {k}"
        );
        assert_eq!(r.n.state(), NodeState::EmergencyStopped);
    }
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.n.state(), NodeState::Standing);
    // The numbers are used up: the robot stands.
    let next = r.n.next_step();
    let side = r.n.gait().next_side() == Some(Side::Left);
    assert_eq!(r.append(next, side, 0.1, y(side)), Some(Reason::Exhausted));
}

/// Item 4: fifteen modifications of the next target and an `ESTOP` in one cycle: the
/// emergency stop is carried out in that cycle. With the target modified at 400 Hz the
/// receive queue never grows and an `ESTOP` is carried out in its cycle.
#[test]
fn an_estop_never_waits_behind_planning_commands() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 6);
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(3, true);
    let target = r.n.gait().next_target().unwrap();
    for k in 0..15 {
        let c = r
            .book
            .modify(target, 0.15, -0.1 - 0.001 * f64::from(k), 0.0);
        r.bus.rx.push_back(c.unwrap().encode());
    }
    r.bus
        .rx
        .push_back(Command::EmergencyStop { seq: 1 }.encode());
    let acks = r.cycle();
    assert_eq!(acks.len(), 16);
    assert_eq!(
        acks[0].command, 0x10,
        "the ESTOP is answered first: {acks:?}"
    );
    assert_eq!(r.n.state(), NodeState::EmergencyStopped);
    assert!(r.bus.rx.is_empty());

    let mut r = Rig::hrp2();
    queue_walk(&mut r, 16);
    assert_eq!(r.control(ControlOp::Start), None);
    for k in 0..150u32 {
        if let Some(t) = r.n.gait().next_target() {
            // Two a cycle, 2 … 18 mm wider, while the step has versions left (127).
            for j in 0..2 {
                let dy = 0.002 * f64::from((2 * k + j) % 10);
                let (x, yy, _) = r.book.appended(t).unwrap().si();
                if let Some(c) = r.book.modify(t, x, yy + dy.copysign(yy), 0.0) {
                    r.bus.rx.push_back(c.encode());
                }
            }
        }
        if k % 20 == 0 {
            let h = r.heartbeat();
            r.bus.rx.push_back(h.encode());
        }
        if k == 120 {
            r.bus
                .rx
                .push_back(Command::EmergencyStop { seq: 2 }.encode());
        }
        r.cycle();
        assert!(
            r.bus.rx.is_empty(),
            "cycle {k}: {} frames wait",
            r.bus.rx.len()
        );
        if k == 120 {
            assert_eq!(r.n.state(), NodeState::EmergencyStopped);
        }
    }
}

/// The four corners of a sole.
fn corners(f: &Footstep<f64>, hl: f64, hw: f64) -> [(f64, f64); 4] {
    let (s, c) = f.yaw.sin_cos();
    [(hl, hw), (hl, -hw), (-hl, -hw), (-hl, hw)]
        .map(|(a, b)| (f.x + c * a - s * b, f.y + s * a + c * b))
}

/// An oracle of the distance between two soles, independent of the node's (separating axes
/// and corners): each outline sampled every 0.5 mm, the smallest distance from a sample to
/// the other outline's edges (exact, point to segment), 0 if a sample is inside the other.
fn sampled_gap(a: &Footstep<f64>, b: &Footstep<f64>, hl: f64, hw: f64) -> f64 {
    let samples = |f: &Footstep<f64>| {
        let c = corners(f, hl, hw);
        let mut pts = vec![];
        for i in 0..4 {
            let (p, q) = (c[i], c[(i + 1) % 4]);
            let n = ((q.0 - p.0).hypot(q.1 - p.1) / 5e-4).ceil() as usize;
            for k in 0..n {
                let t = k as f64 / n as f64;
                pts.push((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)));
            }
        }
        pts
    };
    let inside = |f: &Footstep<f64>, (x, y): (f64, f64)| {
        let (s, c) = f.yaw.sin_cos();
        let (dx, dy) = (x - f.x, y - f.y);
        (c * dx + s * dy).abs() <= hl && (-s * dx + c * dy).abs() <= hw
    };
    let to_edges = |f: &Footstep<f64>, (x, y): (f64, f64)| {
        let c = corners(f, hl, hw);
        (0..4)
            .map(|i| {
                let (p, q) = (c[i], c[(i + 1) % 4]);
                let (ex, ey) = (q.0 - p.0, q.1 - p.1);
                let t = (((x - p.0) * ex + (y - p.1) * ey) / (ex * ex + ey * ey)).clamp(0.0, 1.0);
                (x - p.0 - t * ex).hypot(y - p.1 - t * ey)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let (pa, pb) = (samples(a), samples(b));
    if pa.iter().any(|&p| inside(b, p)) || pb.iter().any(|&p| inside(a, p)) {
        return 0.0;
    }
    let ab = pa
        .iter()
        .map(|&p| to_edges(b, p))
        .fold(f64::INFINITY, f64::min);
    let ba = pb
        .iter()
        .map(|&p| to_edges(a, p))
        .fold(f64::INFINITY, f64::min);
    ab.min(ba)
}

/// Item 5: a right step at forward 0, width 0.15 m, turned by +0.299 rad (and 0.15 rad)
/// passed every reach limit and put its sole 22.3 mm (7.2 mm) into the other; refused now.
/// And over a grid of steps from standing, every step the node takes keeps the soles 10 mm
/// apart by the sampled oracle (to its 0.5 mm sampling), and every step it refuses for
/// `Crossing` while the centres are on the right side comes closer than that.
#[test]
fn one_sole_never_lands_on_the_other() {
    let cfg = NodeConfig::hrp2();
    let (hl, hw) = (cfg.params.sole_half_length, cfg.params.sole_half_width);
    for turn in [0.299, 0.15] {
        let mut r = Rig::hrp2();
        let left = r.n.gait().feet()[0];
        let (s, c) = left.yaw.sin_cos();
        let (x, yy) = (left.x + 0.15 * s, left.y - 0.15 * c);
        let step = r.book.append(0, false, x, yy, turn).unwrap();
        let land = Footstep::new(Side::Right, x, yy, turn);
        assert!(sampled_gap(&left, &land, hl, hw) < 0.01);
        assert_eq!(r.ask(step), Some(Reason::Crossing), "turned by {turn}");
    }
    let (mut taken, mut refused) = (0, 0);
    let base = Rig::hrp2();
    for i in 0..=12 {
        for j in 0..=8 {
            let forward = -0.1 + 0.025 * f64::from(i);
            let width = 0.15 + 0.01 * f64::from(j);
            for turn in [-0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3] {
                let mut r = base.fork();
                let left = r.n.gait().feet()[0];
                let (x, yy) = (left.x + forward, left.y - width);
                let c = r.book.append(0, false, x, yy, turn).unwrap();
                let land = Footstep::new(Side::Right, x, yy, turn);
                let gap = sampled_gap(&left, &land, hl, hw);
                match r.ask(c) {
                    None => {
                        taken += 1;
                        assert!(gap >= 0.01 - 5e-4, "{forward} {width} {turn}: {gap}");
                    }
                    Some(Reason::Crossing) => {
                        refused += 1;
                        assert!(gap < 0.01 + 5e-4, "{forward} {width} {turn}: {gap}");
                    }
                    Some(_) => {}
                }
            }
        }
    }
    assert!(
        taken > 100 && refused > 20,
        "{taken} taken, {refused} refused"
    );
}

/// Item 6: `StopNow` while standing with nothing queued is refused and changes nothing; with
/// steps queued it drops them and nothing else: the walk started afterwards is the walk of a
/// node that never had them.
#[test]
fn stop_now_while_standing_leaves_nothing_behind() {
    let mut a = Rig::hrp2();
    let mut b = Rig::hrp2();
    assert_eq!(a.control(ControlOp::StopNow), Some(Reason::WrongState));
    queue_walk(&mut a, 2);
    assert_eq!(a.control(ControlOp::StopNow), None);
    assert_eq!(a.n.gait().queued(), 0);
    // The same single step on both (`b` numbers it 0, `a` 2), then a start.
    let ya = a.n.next_step();
    assert_eq!(a.append(ya, false, 0.15, y(false)), None);
    assert_eq!(b.append(0, false, 0.15, y(false)), None);
    b.run(3, true); // the same number of cycles as `a` took
    assert_eq!(a.control(ControlOp::Start), None);
    assert_eq!(b.control(ControlOp::Start), None);
    for k in 0..400 {
        a.run(1, k % 20 == 0);
        b.run(1, k % 20 == 0);
        let (ra, rb) = (a.n.gait().last(), b.n.gait().last());
        assert_eq!((ra.x, ra.y, ra.feet), (rb.x, rb.y, rb.feet), "cycle {k}");
    }
}

/// Item 7: with `now_ms` stuck (a timer fault) and the controller silent, the robot stops
/// within the supervision bound counted in cycles, and `STATUS` reports the clock fault.
#[test]
fn a_frozen_clock_does_not_disable_supervision() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 16);
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(60, true);
    let stuck = r.t;
    let (mut liftoffs, mut last) = (vec![], r.n.gait().swinging());
    let mut bus = Bus::default();
    for k in 1..=4000u32 {
        r.n.poll(stuck, &mut bus);
        let s = r.n.gait().swinging();
        if s.is_some() && s != last {
            liftoffs.push(k);
        }
        last = s;
        for f in bus.tx.drain(..) {
            if let Some(st) = Status::decode(&f) {
                r.status = Some(st);
            }
        }
    }
    assert!(r.n.gait().is_standing());
    assert_eq!(r.n.state(), NodeState::ControllerLost);
    assert!(r.n.clock_fault());
    assert!(r.status.unwrap().flags & Status::CLOCK_FAULT != 0);
    // The controller was last heard at most 20 cycles before the clock stopped, so no lift-off
    // comes later than the timeout's 100 cycles after that.
    assert!(liftoffs.iter().all(|&k| k <= 100), "{liftoffs:?}");
}

/// Item 8: after a reset of the board mid-walk the node comes up without a session: it sends
/// no reference, publishes `STATUS`, `DIAG`, `SESSION` (and `LINK`) in its first cycle, and
/// takes no command of the session before the reset — not even once a new one is open.
#[test]
fn after_a_restart_nothing_moves_before_the_handshake() {
    let mut before = NodeConfig::hrp2();
    before.entropy = 0x1234_0042;
    let mut r = Rig::new(before);
    queue_walk(&mut r, 4);
    let old_start = r.command(ControlOp::Start);
    let old_append = r
        .book
        .append(r.n.next_step(), false, 0.75, y(false), 0.0)
        .unwrap();
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(100, true);
    // The watchdog resets the board: a new start-up, another entropy.
    let mut after = NodeConfig::hrp2();
    after.entropy = 0x9876_0017;
    let mut n = N::new(after).unwrap();
    let mut bus = Bus::default();
    n.poll(5, &mut bus);
    let first: Vec<u16> = bus.tx.iter().map(|f| f.id).collect();
    assert_eq!(first, [ids::STATUS, ids::DIAG, ids::SESSION]);
    let session = Session::decode(&bus.tx[2]).unwrap();
    assert_eq!(
        Status::decode(&bus.tx[0]).unwrap().state,
        NodeState::NoSession as u8
    );
    bus.tx.clear();
    // The late frames of the old start-up: refused (no session), nothing streamed.
    for (k, f) in [old_start.encode(), old_append.encode()].iter().enumerate() {
        bus.rx.push_back(*f);
        n.poll(10 + 5 * k as u32, &mut bus);
    }
    let acks: Vec<_> = bus
        .tx
        .iter()
        .filter_map(planner_core::wire::Ack::decode)
        .collect();
    assert_eq!(acks[0].reason, Some(Reason::WrongSession));
    // (The old append's step number is not one of this start-up: its CRC fails.)
    assert!(matches!(
        acks[1].reason,
        Some(Reason::BadCrc | Reason::NoSession)
    ));
    assert!(
        bus.tx.iter().all(|f| !(0x200..0x300).contains(&f.id)),
        "a reference streamed"
    );
    assert_eq!(n.state(), NodeState::NoSession);
    // The handshake with the new session; then the old start is still refused.
    let open = Command::Control {
        session: session.tag(),
        seq: 1,
        op: ControlOp::Reset,
    };
    bus.rx.push_back(open.encode());
    bus.rx.push_back(old_start.encode());
    n.poll(30, &mut bus);
    let acks: Vec<_> = bus
        .tx
        .iter()
        .filter_map(planner_core::wire::Ack::decode)
        .collect();
    assert_eq!(acks[2].reason, None);
    assert_eq!(acks[3].reason, Some(Reason::WrongSession));
    assert_eq!(n.state(), NodeState::Standing);
    assert_eq!(
        n.next_step(),
        0x9876,
        "numbered from the new start-up's entropy"
    );
    assert!(
        bus.tx.iter().any(|f| f.id == ids::COG),
        "streaming once open"
    );
    assert!(matches!(n.gait().last().phase, Phase::Standing));
}

/// A `Reset` that arrives before an `ESTOP` in the same cycle (carried out after it, in the
/// priority order) does not leave the emergency stop: the node ends the cycle stopped.
#[test]
fn a_reset_with_an_estop_in_one_cycle_leaves_it_stopped() {
    let mut r = Rig::hrp2();
    let estop = Command::EmergencyStop { seq: 1 };
    let reset = r.command(ControlOp::Reset);
    r.bus.rx.extend([reset.encode(), estop.encode()]);
    let acks = r.cycle();
    assert_eq!(r.n.state(), NodeState::EmergencyStopped);
    assert_eq!(answer(&acks, &estop), None);
    assert_eq!(answer(&acks, &reset), Some(Reason::EmergencyStopped));
    // Already stopped: a repeated ESTOP (`Duplicate`, a refusal: it changes nothing) with a
    // Reset in one cycle, either order: the Reset is refused too, and the node is as before.
    for first_estop in [true, false] {
        let before = r.n.clone();
        let reset = r.command(ControlOp::Reset);
        let frames = if first_estop {
            [estop.encode(), reset.encode()]
        } else {
            [reset.encode(), estop.encode()]
        };
        r.bus.rx.extend(frames);
        let acks = r.cycle();
        assert_eq!(answer(&acks, &estop), Some(Reason::Duplicate));
        assert_eq!(answer(&acks, &reset), Some(Reason::EmergencyStopped));
        assert_eq!(r.n.state(), NodeState::EmergencyStopped);
        let mut idle = before;
        idle.poll(r.t, &mut Bus::default());
        assert!(idle.same_state(&r.n), "the two refusals changed the node");
    }
    // Alone, the Reset leaves the emergency stop.
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.n.state(), NodeState::Standing);
}

/// The answer to `c` among `acks` (exactly one).
fn answer(acks: &[planner_core::wire::Ack], c: &Command) -> Option<Reason> {
    let mut a = acks
        .iter()
        .filter(|a| a.command == c.code() && a.echo == c.echo());
    let first = a
        .next()
        .unwrap_or_else(|| panic!("{c:?} not answered: {acks:?}"));
    assert!(a.next().is_none(), "{c:?} answered twice");
    first.reason
}

/// Priority keeps what arrival order means: an append that arrived before a `StopNow` of the
/// same cycle is dropped by it (answered `Stale`), standing or walking, and one that arrived
/// after it is taken as it would be alone.
#[test]
fn footsteps_before_a_stop_now_of_the_cycle_are_dropped_by_it() {
    // Standing, one step queued: [append, StopNow] leaves the queue empty.
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 1);
    let next = r.n.next_step();
    let early = r.book.append(next, true, 0.3, y(true), 0.0).unwrap();
    let stop = r.command(ControlOp::StopNow);
    r.bus.rx.extend([early.encode(), stop.encode()]);
    let acks = r.cycle();
    assert_eq!(answer(&acks, &stop), None);
    assert_eq!(answer(&acks, &early), Some(Reason::Stale));
    assert_eq!(r.n.gait().queued(), 0);
    assert_eq!(r.n.next_step(), next, "the dropped append took no number");
    // [StopNow, append] with one step queued: the append is the only step left.
    queue_walk(&mut r, 1);
    let next = r.n.next_step();
    let stop = r.command(ControlOp::StopNow);
    let late = r.book.append(next, true, 0.15, y(true), 0.0).unwrap();
    r.bus.rx.extend([stop.encode(), late.encode()]);
    let acks = r.cycle();
    assert_eq!((answer(&acks, &stop), answer(&acks, &late)), (None, None));
    assert_eq!(r.n.gait().queued(), 1);
    // Walking: an append before the StopNow is not taken.
    let mut w = Rig::hrp2();
    queue_walk(&mut w, 4);
    assert_eq!(w.control(ControlOp::Start), None);
    w.run(3, true);
    let next = w.n.next_step();
    let left = w.n.gait().queued_step(next - 1).map(|s| s.side) == Some(Side::Right);
    let early = w.book.append(next, left, 0.75, y(left), 0.0).unwrap();
    let stop = w.command(ControlOp::StopNow);
    w.bus.rx.extend([early.encode(), stop.encode()]);
    let acks = w.cycle();
    assert_eq!(answer(&acks, &stop), None);
    assert_eq!(answer(&acks, &early), Some(Reason::Stale));
    assert_eq!(w.n.gait().queued(), 0);
}

/// Coalescing keeps what arrival order means: of two modifications of one step in a cycle,
/// a newer one that is refused (out of reach) leaves the older, valid one in force.
#[test]
fn a_refused_newer_modification_leaves_the_older_one_its_turn() {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 2);
    let id = r.n.next_step() - 1;
    let good = r.book.modify(id, 0.32, y(true), 0.0).unwrap();
    let far = r.book.modify(id, 0.95, y(true), 0.0).unwrap();
    r.bus.rx.extend([good.encode(), far.encode()]);
    let acks = r.cycle();
    assert_eq!(answer(&acks, &far), Some(Reason::Reach));
    assert_eq!(answer(&acks, &good), None);
    let s = r.n.gait().queued_step(id).unwrap();
    assert_eq!((s.x, s.y), (0.32, y(true)));
    // And the other way round: the newer valid one is in force, the older one `Stale`.
    let a = r.book.modify(id, 0.31, y(true), 0.0).unwrap();
    let b = r.book.modify(id, 0.33, y(true), 0.0).unwrap();
    r.bus.rx.extend([a.encode(), b.encode()]);
    let acks = r.cycle();
    assert_eq!(
        (answer(&acks, &a), answer(&acks, &b)),
        (Some(Reason::Stale), None)
    );
    assert_eq!(r.n.gait().queued_step(id).map(|s| s.x), Some(0.33));
}
