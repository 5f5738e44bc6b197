//! Priority over every sender: the controller at its 16 commands a cycle, the estimator at
//! its one `MEASURED` a cycle, foreign traffic, and an `ESTOP` from another node. The node
//! takes everything the bus carried in a cycle, holds its commands by class and carries out
//! an `ESTOP` in the cycle it arrives, however much else is queued.

mod common;

use common::*;
use planner_core::node::{NodeConfig, NodeState, WORK_BUDGET, WORK_PLAN, WORK_STEP};
use planner_core::wire::{Command, ControlOp, Measured, RawFrame, Reason};

/// A walking rig.
fn walking() -> Rig {
    let mut r = Rig::hrp2();
    queue_walk(&mut r, 12);
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(3, true);
    assert_eq!(r.n.state(), NodeState::Walking);
    r
}

/// The estimator's state against the last reference published.
fn measured(r: &Rig) -> RawFrame {
    let m = Measured::from_si(r.n.cycles(), [0.0, 0.0]).unwrap();
    Command::Measured(m).encode_in(r.session.epoch)
}

/// A foreign frame (another node's traffic).
fn foreign(k: u16) -> RawFrame {
    RawFrame::new(0x400 + (k % 0x100), &[k as u8; 8]).unwrap()
}

/// The cycle: 15 heartbeats, one estimator state, then an `ESTOP` (17 command frames,
/// one more than the controller's 16): the stop is carried out in this cycle.
#[test]
fn an_estop_behind_the_controller_and_the_estimator_is_carried_out_in_its_cycle() {
    let mut r = walking();
    for _ in 0..15 {
        let h = r.heartbeat();
        r.bus.rx.push_back(h.encode());
    }
    let m = measured(&r);
    r.bus.rx.push_back(m);
    r.bus
        .rx
        .push_back(Command::EmergencyStop { seq: 1 }.encode());
    let acks = r.cycle();
    assert_eq!(r.n.state(), NodeState::EmergencyStopped);
    assert!(r.bus.rx.is_empty(), "{} frames wait", r.bus.rx.len());
    assert_eq!(acks.len(), 17, "every frame answered once: {acks:?}");
    assert!(
        acks.iter().all(|a| a.reason != Some(Reason::Busy)),
        "{acks:?}"
    );
}

/// Both senders at their stated rates for 100 cycles (16 controller commands and one
/// `MEASURED` a cycle), foreign traffic besides, then an `ESTOP` of another node: nothing
/// ever waits for the next cycle, nothing of the two senders is refused `Busy`, and the stop
/// is carried out in its cycle.
#[test]
fn an_estop_under_sustained_load_of_both_senders_never_waits() {
    let mut r = walking();
    for k in 0..=100u16 {
        for _ in 0..16 {
            let h = r.heartbeat();
            r.bus.rx.push_back(h.encode());
        }
        for j in 0..20 {
            r.bus.rx.push_back(foreign(k + j));
        }
        let m = measured(&r);
        r.bus.rx.push_back(m);
        if k == 100 {
            r.bus
                .rx
                .push_back(Command::EmergencyStop { seq: 7 }.encode());
        }
        let acks = r.cycle();
        assert!(
            r.bus.rx.is_empty(),
            "cycle {k}: {} frames wait",
            r.bus.rx.len()
        );
        assert_eq!(acks.len(), 17 + usize::from(k == 100), "cycle {k}");
        assert!(
            acks.iter().all(|a| a.reason != Some(Reason::Busy)),
            "cycle {k}: {acks:?}"
        );
        let want = if k == 100 {
            NodeState::EmergencyStopped
        } else {
            NodeState::Walking
        };
        assert_eq!(r.n.state(), want, "cycle {k}");
    }
}

/// A flood beyond every rate, as much as a 1 Mbit/s bus carries in a cycle (30 states,
/// 25 heartbeats, 50 foreign frames and the `ESTOP`: 106 frames), with the `ESTOP` last: it takes a place among the held frames, the node stops in this cycle, and the
/// frames left out are refused `Busy` (after the stream), the estimator's first.
#[test]
fn an_estop_takes_its_place_in_a_flood() {
    let mut r = walking();
    let m = measured(&r);
    for k in 0..30 {
        r.bus.rx.push_back(m);
        r.bus.rx.push_back(foreign(k));
    }
    for _ in 0..25 {
        let h = r.heartbeat();
        r.bus.rx.push_back(h.encode());
    }
    for k in 0..20 {
        r.bus.rx.push_back(foreign(k + 30));
    }
    r.bus
        .rx
        .push_back(Command::EmergencyStop { seq: 3 }.encode());
    let before = r.n.counters().by_reason[usize::from(Reason::Busy.code())];
    let acks = r.cycle();
    assert_eq!(r.n.state(), NodeState::EmergencyStopped);
    assert!(r.bus.rx.is_empty(), "{} frames wait", r.bus.rx.len());
    let max_rx = r.n.config().max_rx;
    // Held: the ESTOP and max_rx − 1 heartbeats (the states made room first); the rest
    // refused `Busy`, counted whether or not the backlog had room for the answer.
    let busy = r.n.counters().by_reason[usize::from(Reason::Busy.code())] - before;
    assert_eq!(usize::from(busy), 30 + 25 - (max_rx - 1));
    let taken: Vec<_> = acks
        .iter()
        .filter(|a| a.reason != Some(Reason::Busy))
        .collect();
    assert_eq!(taken.len(), max_rx, "{acks:?}");
    assert!(
        taken.iter().all(|a| a.command != 0xD8),
        "no state held: {taken:?}"
    );
    assert_eq!(taken[0].command, 0x10, "the ESTOP first: {taken:?}");
}

/// The receive bound is checked at start-up: the frames of all kinds a cycle takes must cover
/// the commands it holds.
#[test]
fn a_receive_bound_below_the_commands_held_is_refused() {
    let mut cfg = NodeConfig::hrp2();
    cfg.max_frames = cfg.max_rx - 1;
    assert!(N::new(cfg).is_err());
}

/// The cycle's command work is counted against its budget (`NodeConfig::work_budget`): a
/// modification of every queued step in one cycle, the next swing target first, is taken as
/// far as the budget goes: the one that plans keeps its work when it arrives (it is acted on
/// at the end of the command phase, eq. 17 on the final steps), the later ones take what is
/// left in their order; the rest are refused `Busy` with nothing changed, and taken when sent
/// again in the next cycle.
#[test]
fn the_cycles_command_work_stays_within_its_budget() {
    let mut r = walking();
    let budget = r.n.config().work_budget;
    assert_eq!(budget, WORK_BUDGET);
    let g = r.n.gait();
    let front = g.next_target().unwrap();
    let queued = g.queued() as u16;
    assert!(queued >= 12, "{queued} steps queued");
    let first = r.n.next_step().wrapping_sub(queued);
    let moved: Vec<(u16, f64, f64)> = (0..queued)
        .map(|i| {
            let s = g.queued_step(front.wrapping_add(i)).unwrap();
            (first.wrapping_add(i), s.x + 0.02, s.y)
        })
        .collect();
    let epoch = r.session.epoch;
    let frames: Vec<(u16, Command)> = moved
        .iter()
        .map(|&(id, x, y)| (id, r.book.modify(id, x, y, 0.0).unwrap()))
        .collect();
    for (_, c) in &frames {
        r.bus.rx.push_back(c.encode_in(epoch));
    }
    let before = r.n.clone();
    let acks = r.cycle();
    let answer = |id: u16, acks: &[planner_core::wire::Ack]| {
        let a = acks
            .iter()
            .find(|a| a.command == 0x01 && a.seq == id as u8)
            .unwrap_or_else(|| panic!("no answer for step {id}: {acks:?}"));
        a.reason
    };
    // The next swing target's work is kept when it arrives (first), the later steps take
    // what is left as far as it goes.
    let plans = budget >= WORK_STEP + WORK_PLAN;
    let others = (u32::from(queued) - 1).min((budget - WORK_STEP - WORK_PLAN) / WORK_STEP);
    let taken = others + u32::from(plans);
    let reasons: Vec<Option<Reason>> = frames.iter().map(|(id, _)| answer(*id, &acks)).collect();
    let accepted = reasons.iter().filter(|a| a.is_none()).count() as u32;
    assert_eq!(accepted, taken, "{reasons:?}");
    assert!(taken < u32::from(queued), "the budget must leave some out");
    let is_taken = |i: usize| {
        if i == 0 {
            plans
        } else {
            i as u32 <= others
        }
    };
    for (i, reason) in reasons.iter().enumerate() {
        let id = front.wrapping_add(i as u16);
        if is_taken(i) {
            assert_eq!(*reason, None, "step {i}");
        } else {
            // Refused `Busy`: the step is where it was.
            assert_eq!(*reason, Some(Reason::Busy), "step {i}");
            assert_eq!(
                r.n.gait().queued_step(id),
                before.gait().queued_step(id),
                "step {i}"
            );
        }
    }
    // Sent again in the next cycle: taken.
    for (i, (_, c)) in frames.iter().enumerate() {
        if !is_taken(i) {
            r.bus.rx.push_back(c.encode_in(epoch));
        }
    }
    let acks = r.cycle();
    for (i, (id, _)) in frames.iter().enumerate() {
        if !is_taken(i) {
            assert_eq!(answer(*id, &acks), None, "step {id} sent again");
        }
    }
}
