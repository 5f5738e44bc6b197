//! Freshness across a restart of `host-sim node`: its start-up draws the session epoch and the
//! first step number from the operating system (`host_sim::sim::entropy::start_up`), so a
//! controller's log recorded before a restart and replayed after it moves nothing.

use std::collections::VecDeque;

use host_sim::robot::Robot;
use host_sim::sim::entropy::start_up;
use planner_core::node::{Node, NodeConfig, NodeState};
use planner_core::wire::{Ack, Command, ControlOp, Diag, RawFrame, Session, StepBook};

#[derive(Default)]
struct Bus {
    rx: VecDeque<RawFrame>,
    tx: Vec<RawFrame>,
}

#[derive(Debug)]
struct E;
impl embedded_can::Error for E {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl embedded_can::nb::Can for Bus {
    type Frame = RawFrame;
    type Error = E;
    fn transmit(&mut self, f: &RawFrame) -> nb::Result<Option<RawFrame>, E> {
        self.tx.push(*f);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<RawFrame, E> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

/// One cycle of `node` with `frames` delivered: its answers, and what it published.
fn cycle(
    node: &mut Node<16>,
    t: &mut u32,
    frames: &[RawFrame],
) -> (Vec<Ack>, Option<Session>, Option<Diag>) {
    let mut bus = Bus::default();
    bus.rx.extend(frames.iter().copied());
    *t += 5;
    node.poll(*t, &mut bus);
    let acks = bus.tx.iter().filter_map(Ack::decode).collect();
    let session = bus.tx.iter().find_map(Session::decode);
    let diag = bus.tx.iter().find_map(Diag::decode);
    (acks, session, diag)
}

/// An honest controller's walk on a node started as `host-sim node` starts it: the frames
/// of each cycle (the log), and the number of lift-offs.
fn walk(cfg: NodeConfig) -> (Vec<Vec<RawFrame>>, usize) {
    let mut node = Node::<16>::new(cfg).unwrap();
    let mut t = 0;
    let (_, session, diag) = cycle(&mut node, &mut t, &[]);
    let (session, diag) = (session.unwrap(), diag.unwrap());
    let mut seq = session.last_seq;
    let mut control = |op| {
        seq += 1;
        Command::Control {
            session: session
                .tag()
                .wrapping_add(u16::from(op != ControlOp::Reset)),
            seq,
            op,
        }
        .encode()
    };
    let mut log = vec![vec![control(ControlOp::Reset)]];
    let mut book = StepBook::new();
    let first = diag.next_step;
    let steps: Vec<RawFrame> = (0..6u16)
        .map(|i| {
            let left = i % 2 == 1;
            let y = if left { 0.1 } else { -0.1 };
            let x = 0.15 * f64::from(i + 1);
            book.append(first.wrapping_add(i), left, x, y, 0.0)
                .unwrap()
                .encode()
        })
        .collect();
    log.push(steps);
    log.push(vec![control(ControlOp::Start)]);
    for k in 0..600 {
        log.push(if k % 20 == 0 {
            vec![control(ControlOp::Heartbeat)]
        } else {
            vec![]
        });
    }
    let lift_offs = play(&mut node, &mut t, &log);
    (log, lift_offs)
}

/// Plays `log` to `node` a cycle at a time: the lift-offs it made.
fn play(node: &mut Node<16>, t: &mut u32, log: &[Vec<RawFrame>]) -> usize {
    let mut lift_offs = 0;
    let mut swinging = None;
    for frames in log {
        cycle(node, t, frames);
        let s = node.gait().swinging();
        if s.is_some() && s != swinging {
            lift_offs += 1;
        }
        swinging = s;
    }
    lift_offs
}

#[test]
fn a_log_replayed_after_a_restart_moves_nothing() {
    let robot = Robot::hrp2();
    let before = start_up(robot.node_config()).expect("the host's entropy");
    let (log, lift_offs) = walk(before);
    assert!(lift_offs >= 3, "the log walks: {lift_offs} lift-offs");
    // The restart: another start-up of the same node, the log replayed cycle for cycle.
    let after = start_up(robot.node_config()).expect("the host's entropy");
    assert_ne!(before.entropy, after.entropy, "a start-up of its own");
    let mut node = Node::<16>::new(after).unwrap();
    let mut t = 0;
    cycle(&mut node, &mut t, &[]);
    let mut taken = vec![];
    for frames in &log {
        let (acks, _, _) = cycle(&mut node, &mut t, frames);
        taken.extend(acks.into_iter().filter(|a| a.reason.is_none()));
        assert!(node.gait().swinging().is_none());
    }
    // Every frame refused, but by chance: a control command of the earlier start-up passes
    // only if the two epochs' low 16 bits agree (2⁻¹⁶).
    assert_eq!(taken, vec![], "frames of the earlier start-up taken");
    assert_eq!(node.state(), NodeState::NoSession);
}
