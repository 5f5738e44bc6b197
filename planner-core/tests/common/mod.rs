//! A controller rig for the node tests: an in-memory CAN device, the step book, the control
//! sequence, the session, the stream and `DIAG` as received, and every lift-off with the time
//! the controller was last heard before it. A refused command is checked to change nothing:
//! the node is then in the state of a clone that ran the same cycle without the frame. The
//! rig opens a session (the handshake) before the test begins.

#![allow(dead_code)] // (each test file uses a part)

use std::collections::VecDeque;

use planner_core::node::{Driver, Node, NodeConfig, NodeState};
use planner_core::wire::{
    Ack, Command, ControlOp, Diag, Measured, RawFrame, Reason, Session, Status, StepBook, Stream,
};

/// The in-memory device.
#[derive(Default)]
pub struct Bus {
    /// To the node.
    pub rx: VecDeque<RawFrame>,
    /// From the node.
    pub tx: Vec<RawFrame>,
}

/// Never happens.
#[derive(Debug)]
pub struct E;
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

/// The node of the rigs.
pub type N = Node<16>;

/// A controller with its node: time, the bus, the step book, the control sequence, and every
/// lift-off seen with the time the controller was last heard before it.
pub struct Rig {
    #[allow(missing_docs)]
    pub n: N,
    #[allow(missing_docs)]
    pub bus: Bus,
    #[allow(missing_docs)]
    pub t: u32,
    #[allow(missing_docs)]
    pub book: StepBook,
    /// The last sequence number sent (one counter for every control command).
    pub seq: u32,
    /// The session as last published.
    pub session: Session,
    #[allow(missing_docs)]
    pub swinging: Option<u16>,
    #[allow(missing_docs)]
    pub liftoffs: Vec<(u32, Option<u32>, u16)>,
    #[allow(missing_docs)]
    pub stream: Stream,
    #[allow(missing_docs)]
    pub diag: Option<Diag>,
    #[allow(missing_docs)]
    pub status: Option<Status>,
}

impl Rig {
    /// A node of `cfg`, after the handshake: the first cycle publishes the session, the
    /// second takes the `Reset` that opens it.
    pub fn new(cfg: NodeConfig) -> Self {
        let mut r = Self::unopened(cfg);
        r.cycle();
        let reset = r.command(ControlOp::Reset);
        r.bus.rx.push_back(reset.encode());
        let acks = r.cycle();
        assert!(
            acks.iter().any(|a| a.command == 0x20 && a.reason.is_none()),
            "handshake refused: {acks:?}"
        );
        r.session.epoch += 1; // an accepted reset opens the next session
        assert_eq!(r.n.state(), NodeState::Standing);
        r
    }
    /// A rig with a copy of this rig's node (its session, time and sequence), an empty bus and
    /// book: cheaper than a new node, whose gains are computed afresh.
    pub fn fork(&self) -> Self {
        Self {
            n: self.n.clone(),
            bus: Bus::default(),
            t: self.t,
            book: StepBook::new(),
            seq: self.seq,
            session: self.session,
            swinging: None,
            liftoffs: vec![],
            stream: self.stream,
            diag: self.diag,
            status: self.status,
        }
    }
    /// A node of `cfg` just started: no cycle run, no session open.
    pub fn unopened(cfg: NodeConfig) -> Self {
        Self {
            n: N::new(cfg).unwrap(),
            bus: Bus::default(),
            t: 0,
            book: StepBook::new(),
            seq: 0,
            session: Session::default(),
            swinging: None,
            liftoffs: vec![],
            stream: Stream::default(),
            diag: None,
            status: None,
        }
    }
    /// The next control command `op` (the next sequence number, the session as published).
    pub fn command(&mut self, op: ControlOp) -> Command {
        self.seq += 1;
        self.command_at(self.seq, op)
    }
    /// Control command `op` with sequence number `seq`, in the session as published.
    pub fn command_at(&self, seq: u32, op: ControlOp) -> Command {
        Command::Control {
            session: self.session.tag(),
            seq,
            op,
        }
    }
    pub fn hrp2() -> Self {
        Self::new(NodeConfig::hrp2())
    }
    /// One cycle; returns the ACKs.
    pub fn cycle(&mut self) -> Vec<Ack> {
        self.t += 5;
        self.n.poll(self.t, &mut self.bus);
        let s = self.n.gait().swinging();
        if s.is_some() && s != self.swinging {
            self.liftoffs
                .push((self.t, self.n.last_heard(), s.unwrap_or(u16::MAX)));
        }
        self.swinging = s;
        let mut acks = vec![];
        for f in self.bus.tx.drain(..) {
            if let Some(a) = Ack::decode(&f) {
                acks.push(a);
            } else if let Some(d) = Diag::decode(&f) {
                self.diag = Some(d);
            } else if let Some(s) = Session::decode(&f) {
                self.session = s;
            } else if let Some(s) = Status::decode(&f) {
                self.status = Some(s);
            } else {
                self.stream.decode_into(&f);
            }
        }
        acks
    }
    /// The next heartbeat (each with a new sequence number).
    pub fn heartbeat(&mut self) -> Command {
        self.command(ControlOp::Heartbeat)
    }

    /// `k` cycles, with a heartbeat every 100 ms if `alive`.
    pub fn run(&mut self, k: u32, alive: bool) {
        for i in 0..k {
            if alive && i % 20 == 0 {
                let hb = self.heartbeat();
                self.bus.rx.push_back(hb.encode());
            }
            self.cycle();
        }
    }
    pub fn ask(&mut self, c: Command) -> Option<Reason> {
        assert!(self.bus.rx.is_empty());
        let epoch = self.session.epoch;
        let mut without = self.n.clone();
        without.poll(self.t + 5, &mut Bus::default());
        self.bus.rx.push_back(c.encode_in(epoch));
        let acks = self.cycle();
        let a = acks
            .iter()
            .find(|a| a.command == c.code() && a.echo == c.echo_in(epoch))
            .unwrap_or_else(|| panic!("no answer to {c:?}: {acks:?}"));
        if a.reason.is_some() {
            assert!(
                self.n.same_state(&without),
                "refused {a:?} changed the node"
            );
        }
        if let (
            Command::Control {
                op: ControlOp::Reset,
                ..
            },
            None,
        ) = (c, a.reason)
        {
            // An accepted reset opens the next session (whatever `SESSION` of this cycle
            // said).
            self.session.epoch = epoch + 1;
        }
        a.reason
    }
    pub fn append(&mut self, id: u16, left: bool, x: f64, y: f64) -> Option<Reason> {
        let c = self.book.append(id, left, x, y, 0.0).unwrap();
        self.ask(c)
    }
    pub fn modify(&mut self, id: u16, x: f64, y: f64) -> Option<Reason> {
        let c = self.book.modify(id, x, y, 0.0).unwrap();
        self.ask(c)
    }
    /// A measured state (the DCM's deviation `deviation` from the reference) against the last
    /// reference published.
    pub fn measure(&mut self, deviation: [f64; 2]) -> Option<Reason> {
        let m = Measured::from_si(self.n.cycles(), deviation).expect("representable");
        self.ask(Command::Measured(m))
    }
    pub fn control(&mut self, op: ControlOp) -> Option<Reason> {
        let c = self.command(op);
        self.ask(c)
    }
    /// Runs (alive) until `f` holds, at most `limit` cycles.
    pub fn until(&mut self, limit: u32, f: impl Fn(&N) -> bool) {
        for k in 0.. {
            assert!(k < limit, "condition not reached in {limit} cycles");
            if f(&self.n) {
                return;
            }
            self.run(1, k % 20 == 0);
        }
    }
}

/// The name of the node's state in the book's table (walking by footsteps, at a velocity or
/// to a goal are rows of their own).
pub fn state_name(n: &N) -> &'static str {
    let standing = n.gait().is_standing();
    match (n.state(), standing) {
        (NodeState::Standing, _) => "standing",
        (NodeState::Walking, _) => match n.driver() {
            Driver::Steps => "walking",
            Driver::Velocity => "walking (velocity)",
            Driver::Goal => "walking (goal)",
        },
        (NodeState::Stopping, _) => "stopping",
        (NodeState::ControllerLost, false) => "lost (moving)",
        (NodeState::ControllerLost, true) => "lost (standing)",
        (NodeState::EmergencyStopped, false) => "e-stopped (moving)",
        (NodeState::EmergencyStopped, true) => "e-stopped (standing)",
        (NodeState::NoSession, _) => "no session",
    }
}

/// ±0.1 m: the y of a foot of a straight walk along x.
pub fn y(left: bool) -> f64 {
    if left {
        0.1
    } else {
        -0.1
    }
}

/// `k` steps forward from standing (0.15 m each, from the foot ahead), numbered from the
/// node's next, the first on the side the node expects (the right from parallel feet).
pub fn queue_walk(r: &mut Rig, k: u16) {
    let first = r.n.next_step();
    let feet = r.n.gait().feet();
    let x0 = feet[0].x.max(feet[1].x);
    let right_first = r.n.gait().next_side() != Some(planner_core::gait::Side::Left);
    for i in 0..k {
        let left = (i % 2 == 1) == right_first;
        let x = x0 + 0.15 * f64::from(i + 1);
        assert_eq!(r.append(first + i, left, x, y(left)), None, "step {i}");
    }
}
