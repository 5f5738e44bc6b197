//! The node through the bus: a mock CAN device, every reason code, the heartbeat rule, and the
//! published stream against the gait's own reference.

use std::collections::VecDeque;

use planner_core::gait::Phase;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{
    self, ids, Ack, Command, ControlOp, RawFrame, Reason, Status, Stream, WireModify, WireStep,
};

/// The codec's frame type is an `embedded-can` frame.
type F = RawFrame;

/// A loop-back device: what the test puts in `rx` the node receives; what it sends lands in
/// `tx`.
#[derive(Default)]
struct Bus {
    rx: VecDeque<F>,
    tx: Vec<F>,
}

#[derive(Debug)]
struct E;
impl embedded_can::Error for E {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl embedded_can::nb::Can for Bus {
    type Frame = F;
    type Error = E;
    fn transmit(&mut self, f: &F) -> nb::Result<Option<F>, E> {
        self.tx.push(*f);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<F, E> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

impl Bus {
    fn send(&mut self, c: Command) {
        self.send_raw(c.encode());
    }
    fn send_raw(&mut self, r: RawFrame) {
        self.rx.push_back(r);
    }
    fn acks(&mut self) -> Vec<Ack> {
        let acks = self.tx.iter().filter_map(Ack::decode).collect();
        self.tx.clear();
        acks
    }
}

type N = Node<8>;

fn node() -> N {
    N::new(NodeConfig::hrp2()).unwrap()
}

thread_local! {
    /// The controller's memory: appended step of each id and the last version made.
    static BOOK: std::cell::RefCell<std::collections::HashMap<u8, (WireStep, u8)>> =
        Default::default();
}

fn step(id: u8, left: bool, x: f64) -> Command {
    let y = if left { 0.1 } else { -0.1 };
    let s = WireStep::from_si(id, left, x, y, 0.0).unwrap();
    BOOK.with(|b| {
        let mut b = b.borrow_mut();
        if b.get(&id).map(|e| e.0) != Some(s) {
            b.insert(id, (s, 0));
        }
    });
    Command::Append(s)
}

/// The next version of a modification of step `id` (offsets from its append; a step never
/// appended is taken as appended at the origin).
fn modify(id: u8, left: bool, x: f64, y: f64) -> Command {
    BOOK.with(|b| {
        let mut b = b.borrow_mut();
        let e = b
            .entry(id)
            .or_insert((WireStep::from_si(id, left, 0.0, 0.0, 0.0).unwrap(), 0));
        e.1 = (e.1 + 1) % wire::VERSIONS;
        let mut m = WireModify::from_si(&e.0, e.1, x, y, 0.0).unwrap();
        m.left = left;
        Command::Modify(m)
    })
}

/// A heartbeat with a new sequence number (a repeated one proves nothing).
fn heartbeat() -> Command {
    thread_local! {
        static SEQ: std::cell::Cell<u8> = const { std::cell::Cell::new(0) };
    }
    let seq = SEQ.with(|s| {
        s.set(s.get().wrapping_add(1));
        s.get()
    });
    control(seq, ControlOp::Heartbeat)
}

fn control(seq: u8, op: ControlOp) -> Command {
    Command::Control { seq, op }
}

/// Runs `n` cycles at 5 ms and returns the acks seen.
fn run(n: &mut N, bus: &mut Bus, t: &mut u32, cycles: u32) -> Vec<Ack> {
    let mut acks = vec![];
    for _ in 0..cycles {
        *t += 5;
        n.poll(*t, bus);
        acks.extend(bus.acks());
    }
    acks
}

/// Sends one command, runs one cycle, returns its ack. A refusal must have changed nothing:
/// the node is then in the state of a clone that ran the same cycle without the frame.
fn ask(n: &mut N, bus: &mut Bus, t: &mut u32, c: Command) -> Ack {
    ask_raw(n, bus, t, c.encode())
}

fn ask_raw(n: &mut N, bus: &mut Bus, t: &mut u32, f: RawFrame) -> Ack {
    assert!(bus.rx.is_empty());
    let mut without = n.clone();
    without.poll(*t + 5, &mut Bus::default());
    bus.send_raw(f);
    let acks = run(n, bus, t, 1);
    assert_eq!(acks.len(), 1, "{acks:?}");
    if acks[0].reason.is_some() {
        assert!(
            n.same_state(&without),
            "refused {:?} changed the node",
            acks[0]
        );
    }
    acks[0]
}

fn walking_node() -> (N, Bus, u32) {
    let (mut n, mut bus, mut t) = (node(), Bus::default(), 0);
    for (i, x) in [0.2, 0.4, 0.6, 0.8, 1.0].iter().enumerate() {
        let a = ask(&mut n, &mut bus, &mut t, step(i as u8, i % 2 == 1, *x));
        assert_eq!(a.reason, None, "{a:?}");
    }
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, control(1, ControlOp::Start)).reason,
        None
    );
    (n, bus, t)
}

#[test]
fn every_reason_code_is_answered_and_changes_nothing() {
    let seen = std::cell::RefCell::new(vec![]);
    let check = |a: Ack, r: Reason| {
        assert_eq!(a.reason, Some(r), "{a:?}");
        seen.borrow_mut().push(r);
    };
    let (mut n, mut bus, mut t) = (node(), Bus::default(), 0);
    // Frame-level. A frame that is not the node's is not answered (counted in DIAG).
    bus.send_raw(RawFrame::new(0x555, &[1, 2]).unwrap());
    assert!(run(&mut n, &mut bus, &mut t, 1).is_empty());
    assert_eq!(n.counters().foreign, 1);
    seen.borrow_mut().push(Reason::UnknownId); // (the decoder's; never sent)
    let f = RawFrame::new(ids::STEP_APPEND, &[1, 2, 3]).unwrap();
    check(ask_raw(&mut n, &mut bus, &mut t, f), Reason::BadLength);
    let body = [9, 77];
    let crc = wire::crc8(ids::CONTROL, &body);
    let f = RawFrame::new(ids::CONTROL, &[9, 77, crc]).unwrap();
    check(ask_raw(&mut n, &mut bus, &mut t, f), Reason::OutOfRange);
    // A corrupted footstep (one bit of x) and a corrupted start: refused, nothing queued.
    let mut f = step(0, false, 0.2).encode();
    f.data[2] ^= 0x04;
    let a = ask_raw(&mut n, &mut bus, &mut t, f);
    assert_eq!((a.seq, a.echo), (0, f.data[7]));
    check(a, Reason::BadCrc);
    let mut f = control(1, ControlOp::Start).encode();
    f.data[1] ^= 0x02; // start (1) would read as stop now (3)
    check(ask_raw(&mut n, &mut bus, &mut t, f), Reason::BadCrc);
    assert_eq!(n.gait().queued(), 0);
    // State-level, standing.
    check(
        ask(&mut n, &mut bus, &mut t, modify(0, false, 0.2, -0.1)),
        Reason::WrongState,
    );
    check(
        ask(&mut n, &mut bus, &mut t, control(1, ControlOp::Start)),
        Reason::WrongState,
    );
    check(
        ask(&mut n, &mut bus, &mut t, step(0, false, 0.5)),
        Reason::Reach,
    );
    check(
        ask(
            &mut n,
            &mut bus,
            &mut t,
            Command::Append(WireStep::from_si(0, false, 0.1, 0.15, 0.0).unwrap()),
        ),
        Reason::Crossing,
    );
    // Step ids count from 0: a first step with another id is a gap (a lost step 0).
    check(
        ask(&mut n, &mut bus, &mut t, step(1, false, 0.2)),
        Reason::SequenceGap,
    );
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, step(0, false, 0.2)).reason,
        None
    );
    check(
        ask(&mut n, &mut bus, &mut t, step(0, false, 0.2)),
        Reason::Duplicate,
    );
    check(
        ask(&mut n, &mut bus, &mut t, step(5, true, 0.4)),
        Reason::SequenceGap,
    );
    check(
        ask(&mut n, &mut bus, &mut t, step(1, false, 0.4)),
        Reason::SideOrder,
    );
    for i in 1..8u8 {
        assert_eq!(
            ask(
                &mut n,
                &mut bus,
                &mut t,
                step(i, i % 2 == 1, 0.2 + 0.1 * f64::from(i))
            )
            .reason,
            None
        );
    }
    check(
        ask(&mut n, &mut bus, &mut t, step(8, false, 1.0)),
        Reason::QueueFull,
    );
    assert_eq!(n.gait().queued(), 8);
    // Walking.
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, control(2, ControlOp::Start)).reason,
        None
    );
    check(
        ask(&mut n, &mut bus, &mut t, control(2, ControlOp::Start)),
        Reason::Duplicate,
    );
    // A late copy of an older `Start` (sequence behind the last accepted control command).
    check(
        ask(&mut n, &mut bus, &mut t, control(1, ControlOp::Start)),
        Reason::Stale,
    );
    // A late copy of an older version of a modification.
    let older = modify(5, true, 0.7, 0.1);
    let newer = modify(5, true, 0.71, 0.1);
    assert_eq!(ask(&mut n, &mut bus, &mut t, newer).reason, None);
    check(ask(&mut n, &mut bus, &mut t, older), Reason::Stale);
    check(
        ask(&mut n, &mut bus, &mut t, modify(42, true, 0.3, 0.1)),
        Reason::UnknownStep,
    );
    for k in 0.. {
        if matches!(n.gait().last().phase, Phase::Single(_)) {
            break;
        }
        assert!(k < 1000, "never reached single support");
        if k % 20 == 0 {
            bus.send(heartbeat());
        }
        run(&mut n, &mut bus, &mut t, 1);
    }
    check(
        ask(&mut n, &mut bus, &mut t, modify(0, false, 0.25, -0.1)),
        Reason::LiftedOff,
    );
    // Eq. 17: within the HRP-2 reach limits the adjusted single support always keeps the ZMP
    // on the foot (a 2.8 m step would still pass, see tests/gait.rs); with the reach check
    // widened, a 4 m change of the next landing is refused.
    let mut wide = NodeConfig::hrp2();
    wide.reach.max_forward = 10.0;
    wide.reach.max_feet_distance = 10.0;
    wide.reach.max_stride = 10.0;
    wide.reach.max_growth = 10.0;
    wide.reach.max_backward = 10.0;
    let mut w = N::new(wide).unwrap();
    let (mut b3, mut t3) = (Bus::default(), 0);
    for (i, x) in [0.2, 0.4, 0.6].iter().enumerate() {
        assert_eq!(
            ask(&mut w, &mut b3, &mut t3, step(i as u8, i % 2 == 1, *x)).reason,
            None
        );
    }
    assert_eq!(
        ask(&mut w, &mut b3, &mut t3, control(1, ControlOp::Start)).reason,
        None
    );
    for k in 0..200 {
        if k % 20 == 0 {
            b3.send(heartbeat());
        }
        run(&mut w, &mut b3, &mut t3, 1);
    }
    check(
        ask(&mut w, &mut b3, &mut t3, modify(1, true, 4.4, 0.1)),
        Reason::Infeasible,
    );
    // Emergency stop, then motion commands are refused until reset once standing.
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, Command::EmergencyStop { seq: 1 }).reason,
        None
    );
    check(
        ask(&mut n, &mut bus, &mut t, step(8, true, 1.0)),
        Reason::EmergencyStopped,
    );
    check(
        ask(&mut n, &mut bus, &mut t, control(3, ControlOp::Reset)),
        Reason::WrongState,
    );
    run(&mut n, &mut bus, &mut t, 600);
    assert!(n.gait().is_standing());
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, control(4, ControlOp::Reset)).reason,
        None
    );
    // The controller falls silent while walking: motion commands are refused until a reset.
    let (mut l, mut bl, mut tl) = walking_node();
    run(&mut l, &mut bl, &mut tl, 101);
    assert_eq!(l.status().state, 3);
    check(
        ask(&mut l, &mut bl, &mut tl, step(5, false, 1.2)),
        Reason::ControllerLost,
    );
    // A plan that cannot be made: a configuration that would give one (a zero single-support
    // time, a standing interval of 0) is refused at start-up, so a node never answers
    // `PlanFailed` for it; what a failed re-plan does is tested in tests/gait.rs
    // (`a_failed_replan_stops_the_robot`).
    for bad in [
        |c: &mut NodeConfig| c.params.single_ticks = 0,
        |c: &mut NodeConfig| c.params.stand_ticks = 0,
        |c: &mut NodeConfig| c.params.rest_ticks = 0,
        |c: &mut NodeConfig| c.params.adjust_min_ticks = -140,
        |c: &mut NodeConfig| c.params.dt = f64::NAN,
    ] {
        let mut cfg = NodeConfig::hrp2();
        bad(&mut cfg);
        assert_eq!(
            N::new(cfg).err(),
            Some(planner_core::gait::GaitError::BadParams)
        );
    }
    seen.borrow_mut().push(Reason::PlanFailed);
    let seen = seen.into_inner();
    for r in Reason::ALL {
        assert!(seen.contains(&r), "no test for {r:?}");
    }
    // Every refusal of this node was counted (UnknownId is not a refusal, PlanFailed not
    // reached; Infeasible and ControllerLost were the other nodes').
    assert_eq!(n.counters().refused as usize, seen.len() - 4);
}

/// A retransmitted footstep command (its answer was lost) is answered `Duplicate` and changes
/// nothing, even once its step has lifted off; the answer echoes the frame's CRC, so the
/// controller can tell an answer to an older version of a modification from one to the newer.
#[test]
fn repeats_are_duplicates_whatever_happened_since() {
    let (mut n, mut bus, mut t) = walking_node();
    let first = modify(2, false, 0.61, -0.1);
    let second = modify(2, false, 0.62, -0.1);
    let a = ask(&mut n, &mut bus, &mut t, first);
    assert_eq!((a.reason, a.echo), (None, first.echo()));
    let a = ask(&mut n, &mut bus, &mut t, second);
    assert_eq!((a.reason, a.echo), (None, second.echo()));
    assert_ne!(first.echo(), second.echo());
    // A late copy of the first modification does not undo the second: it is stale; a repeat
    // of the second (the version in force) is a duplicate.
    let a = ask(&mut n, &mut bus, &mut t, first);
    assert_eq!((a.reason, a.echo), (Some(Reason::Stale), first.echo()));
    let a = ask(&mut n, &mut bus, &mut t, second);
    assert_eq!((a.reason, a.echo), (Some(Reason::Duplicate), second.echo()));
    let landing = |n: &N| n.gait().queued_step(2).map(|f| (f.x, f.y));
    assert_eq!(landing(&n), Some((0.62, -0.1)));
    // Walk until step 2 is in the air: repeats of its append and of its modification are
    // still duplicates, not `LiftedOff`; a new modification is `LiftedOff`.
    for k in 0.. {
        assert!(k < 2000, "step 2 never lifted off");
        if k % 20 == 0 {
            bus.send(heartbeat());
        }
        run(&mut n, &mut bus, &mut t, 1);
        if n.gait().swinging() == Some(2) {
            break;
        }
    }
    for (c, r) in [
        (step(2, false, 0.6), Reason::Duplicate),
        (second, Reason::Duplicate),
        (modify(2, false, 0.615, -0.1), Reason::LiftedOff),
    ] {
        assert_eq!(ask(&mut n, &mut bus, &mut t, c).reason, Some(r), "{c:?}");
    }
    // An append that reuses an old id with another pose is a sequence error, not a repeat.
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, step(1, true, 0.45)).reason,
        Some(Reason::SequenceGap)
    );
}

/// At most one planning command per cycle: five modifications of the next swing target sent
/// at once are answered one per cycle, in order; cheap commands before the first (a heartbeat,
/// modifications of later steps) are answered at once.
#[test]
fn one_planning_command_per_cycle() {
    let (mut n, mut bus, mut t) = walking_node();
    assert_eq!(n.gait().next_target(), Some(0));
    for k in 0..3 {
        bus.send(modify(3, true, 0.8 + 0.01 * f64::from(k), 0.1));
    }
    assert_eq!(run(&mut n, &mut bus, &mut t, 1).len(), 3);
    bus.send(heartbeat());
    let mods: Vec<Command> = (0..5)
        .map(|k| modify(0, false, 0.2, -0.11 - 0.01 * f64::from(k)))
        .collect();
    for m in &mods {
        bus.send(*m);
    }
    let first = run(&mut n, &mut bus, &mut t, 1);
    assert_eq!(first.len(), 2, "{first:?}"); // the heartbeat and one modification
    assert_eq!((first[1].reason, first[1].echo), (None, mods[0].echo()));
    for m in &mods[1..] {
        let acks = run(&mut n, &mut bus, &mut t, 1);
        assert_eq!(acks.len(), 1, "{acks:?}");
        assert_eq!((acks[0].reason, acks[0].echo), (None, m.echo()));
    }
    assert!(run(&mut n, &mut bus, &mut t, 1).is_empty());
    // With the limit lifted, all in one cycle.
    let mut cfg = NodeConfig::hrp2();
    cfg.max_plans = usize::MAX;
    let (mut m, mut b2, mut t2) = (N::new(cfg).unwrap(), Bus::default(), 0);
    for (i, x) in [0.2, 0.4, 0.6, 0.8].iter().enumerate() {
        ask(&mut m, &mut b2, &mut t2, step(i as u8, i % 2 == 1, *x));
    }
    ask(&mut m, &mut b2, &mut t2, control(1, ControlOp::Start));
    for k in 0..3 {
        b2.send(modify(0, false, 0.2, -0.11 - 0.01 * f64::from(k)));
    }
    assert_eq!(run(&mut m, &mut b2, &mut t2, 1).len(), 3);
}

#[test]
fn the_stream_carries_the_gaits_reference() {
    let (mut n, mut bus, mut t) = walking_node();
    let mut stream = Stream::default();
    let mut worst: f64 = 0.0;
    let mut status = None;
    for k in 0..400 {
        if k % 20 == 0 {
            bus.send(heartbeat());
        }
        t += 5;
        let rep = n.poll(t, &mut bus);
        for f in bus.tx.drain(..) {
            stream.decode_into(&f);
            if let Some(s) = Status::decode(&f) {
                status = Some(s);
            }
        }
        let r = rep.reference;
        worst = worst
            .max((stream.cog[0] - r.x.cog).abs())
            .max((stream.cog[1] - r.y.cog).abs())
            .max((stream.zmp[0] - r.x.zmp).abs())
            .max((stream.zmp[1] - r.y.zmp).abs());
    }
    // 1 µm units: half a unit of rounding.
    assert!(worst <= 0.5e-6 + 1e-12, "{worst}");
    let s = status.expect("a status every 20 cycles");
    assert_eq!(s.state, 1);
}

#[test]
fn a_silent_controller_stops_the_robot() {
    let (mut n, mut bus, mut t) = walking_node();
    // Heartbeats keep it walking.
    for k in 0..100u32 {
        if k % 20 == 0 {
            bus.send(heartbeat());
        }
        run(&mut n, &mut bus, &mut t, 1);
    }
    assert!(!n.gait().is_standing());
    assert_eq!(n.status().state, 1);
    // Then silence: after 500 ms the queue is dropped and the robot stops.
    run(&mut n, &mut bus, &mut t, 101);
    assert_eq!(n.status().state, 3);
    assert_eq!(n.gait().queued(), 0);
    run(&mut n, &mut bus, &mut t, 800);
    assert!(n.gait().is_standing());
    // The state is latched until a reset once standing.
    assert_eq!(n.status().state, 3);
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, control(2, ControlOp::Start)).reason,
        Some(Reason::ControllerLost)
    );
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, control(3, ControlOp::Reset)).reason,
        None
    );
    assert_eq!(n.status().state, 0);
}

/// Each rule of the reach limits, just inside and just outside, the others kept satisfied:
/// the right foot at the origin is the support (`other`), the left foot lifts off from
/// `(sx, 0.2)` (`same`) and lands at `(fx, w)` turned by `yaw`.
#[test]
fn reach_rules_one_by_one() {
    use planner_core::gait::{Footstep, Side};
    use planner_core::node::Reach;
    let r = Reach::default();
    let other = Footstep::new(Side::Right, 0.0, 0.0, 0.0);
    let check = |sx: f64, fx: f64, w: f64, yaw: f64| {
        let same = Footstep::new(Side::Left, sx, 0.2, 0.0);
        r.check(&other, &same, &Footstep::new(Side::Left, fx, w, yaw))
    };
    let reach = Err(Reason::Reach);
    for (what, inside, outside) in [
        (
            "forward",
            check(-0.1, 0.30, 0.2, 0.0),
            check(-0.1, 0.305, 0.2, 0.0),
        ),
        (
            "yaw cost",
            check(-0.1, 0.285, 0.2, 0.05),
            check(-0.1, 0.30, 0.2, 0.05),
        ),
        (
            "yaw",
            check(0.0, 0.0, 0.2, 0.30),
            check(0.0, 0.0, 0.2, 0.31),
        ),
        (
            "width",
            check(0.0, 0.0, 0.28, 0.0),
            check(0.0, 0.0, 0.29, 0.0),
        ),
        (
            "narrow",
            check(0.0, 0.0, 0.15, 0.0),
            check(0.0, 0.0, 0.14, 0.0),
        ),
        (
            "backward",
            check(0.0, -0.2, 0.2, 0.0),
            check(0.0, -0.21, 0.2, 0.0),
        ),
        (
            "stride",
            check(-0.23, 0.2, 0.2, 0.0),
            check(-0.24, 0.2, 0.2, 0.0),
        ),
        (
            "growth",
            check(0.0, 0.22, 0.2, 0.0),
            check(0.0, 0.23, 0.2, 0.0),
        ),
        (
            "feet distance",
            check(-0.1, 0.25, 0.26, 0.0),
            check(-0.1, 0.25, 0.27, 0.0),
        ),
    ] {
        assert_eq!(inside, Ok(()), "{what} inside");
        assert_eq!(outside, reach, "{what} outside");
    }
    assert_eq!(check(0.0, 0.1, -0.01, 0.0), Err(Reason::Crossing));
}

/// A modification is checked with its successors: moving step 2 back makes step 4's stride
/// too long, so it is refused although step 2 alone would be in reach.
#[test]
fn a_modification_is_checked_with_its_successors() {
    let (mut n, mut bus, mut t) = walking_node();
    // Step 2 (right) at 0.6 → 0.5: from step 1 (left, 0.4) a 0.1 m step, fine on its own; but
    // step 3 (left, 0.8) becomes a 0.3 m step after a 0.1 m one (growth 0.2, fine), and step 4
    // (right, 1.0) then travels 0.5 m from 0.5 (stride > 0.43).
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, modify(2, false, 0.5, -0.1)).reason,
        Some(Reason::Reach)
    );
    assert_eq!(n.gait().queued_step(2).map(|f| f.x), Some(0.6));
    assert_eq!(
        ask(&mut n, &mut bus, &mut t, modify(2, false, 0.58, -0.1)).reason,
        None
    );
}
