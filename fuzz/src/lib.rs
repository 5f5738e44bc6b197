//! The bodies of the fuzz targets, shared by the libFuzzer binaries (`fuzz_targets/`) and by
//! the deterministic replay test (`tests/replay.rs`, plain `cargo test`, no nightly needed).
//!
//! * [`decode_one`]: bytes `[id lo, id hi, data…]` → [`RawFrame::new`] → [`Command::decode`];
//!   an accepted command encodes to a frame that decodes to the same command, and a refusal
//!   never panics. The same frame goes through the decoders of what the node sends (`ACK`,
//!   `STATUS`, `DIAG`, `LINK`, the stream), which a controller runs on whatever is on the bus:
//!   no panic, and what they accept re-encodes (see `replies_checked`).
//! * [`node_run`]: the bytes are a program of operations on a `Node<8>` (raw frames through
//!   the bus or through [`Node::handle`], well-formed footsteps near a nominal gait so that
//!   the fuzzer reaches the walking states, control commands, time steps). Checked: no panic,
//!   every poll publishes exactly one reference (one frame of each of the five stream
//!   identifiers, with this cycle's tick counter) whose values are finite, every frame with
//!   one of the node's identifiers received is answered with one `ACK` and every other frame
//!   with none (counted as foreign), and a refused frame changes nothing
//!   ([`Node::same_state`] against a clone taken before it).
//! * [`text_one`]: the bytes as text (lossy UTF-8) through the host's text decoders: every
//!   line through host-sim's candump line reader (what it accepts, its own printer writes as a
//!   line that reads back the same; and the MCAP writer's reader accepts it with the same time,
//!   identifier and data, unless its time is beyond the nanoseconds MCAP counts) and through the MCAP writer's reader; the whole text as a candump
//!   log to replay (cycles in order), as a TOML scenario and as a robot file. No panic.
//! * [`wlog_one`]: the bytes as a file of binary CAN logs for the QEMU image
//!   (`gait_loop::binlog`): the decoder never panics, and every header and frame it gives
//!   satisfies the format's rules (name, period, feet; identifiers, lengths, times from
//!   `first_us` to `last_us` in order, no more frames than announced, the last at `last_us`).

use std::collections::VecDeque;
use std::sync::OnceLock;

use planner_core::gait::Side;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{
    ids, Ack, Command, ControlOp, RawFrame, StepBook, Stream, WireModify, WireStep,
};

/// `decode` target: see the module docs.
pub fn decode_one(data: &[u8]) {
    if data.len() < 2 {
        return;
    }
    let id = u16::from_le_bytes([data[0], data[1]]);
    let Some(frame) = RawFrame::new(id, &data[2..]) else {
        assert!(id > 0x7FF || data.len() > 10, "a valid frame was refused");
        return;
    };
    replies_checked(&frame);
    for next in NEXTS {
        decode_checked(&frame, next);
        // The same frame with its last byte made the right CRC-8: the field checks behind
        // the CRC are reached by every input, not by one in 256.
        decode_checked(&with_crc(frame, next), next);
        replies_checked(&with_crc(frame, next));
    }
}

/// The controller's side of the wire on any frame: the decoders of what the node sends
/// (`ACK`, `STATUS`, `DIAG`, `LINK`, `ADJUST`, the five stream frames) never panic; `ACK`, `STATUS` and
/// `DIAG` are canonical (what they accept re-encodes to the same frame); `LINK` re-encodes to
/// the frame with its two unused bits cleared; a stream frame decodes to finite values that
/// re-encode to a frame which decodes to the same values.
fn replies_checked(frame: &RawFrame) {
    if let Some(a) = Ack::decode(frame) {
        assert_eq!(a.encode(), *frame, "{a:?}");
    }
    if let Some(s) = planner_core::wire::Status::decode(frame) {
        assert_eq!(s.encode(), *frame, "{s:?}");
    }
    if let Some(d) = planner_core::wire::Diag::decode(frame) {
        assert_eq!(d.encode(), *frame, "{d:?}");
    }
    if let Some(l) = planner_core::wire::LinkHealth::decode(frame) {
        // Every bit of LINK is a field's: the frame encodes back exactly.
        assert_eq!(l.encode(), *frame, "{l:?}");
    }
    if let Some(a) = planner_core::wire::Adjust::decode(frame) {
        // Every bit of ADJUST is a field's (or the CRC): canonical.
        assert_eq!(a.encode(), *frame, "{a:?}");
    }
    let mut s = Stream::default();
    if s.decode_into(frame) {
        let values = s
            .cog
            .iter()
            .chain(&s.cog_vel)
            .chain(&s.zmp)
            .chain(s.feet.iter().flatten());
        assert!(values.clone().all(|v| v.is_finite()), "{frame:?}: {s:?}");
        let again = s.encode();
        let same = again
            .iter()
            .find(|f| f.id == frame.id)
            .expect("the stream encodes every identifier it decodes");
        let mut t = Stream::default();
        assert!(t.decode_into(same));
        assert_eq!(t, s, "{frame:?} -> {same:?}");
    }
}

/// The next step numbers the decoder is tried with: the start of a block of 256, its end,
/// and one in the middle (a footstep frame's number is read against it).
const NEXTS: [u16; 3] = [0, 0x01FF, 0x5A80];

/// `frame` with its last data byte replaced by the CRC-8 of its identifier and the bytes
/// before it (unchanged if it has no data); for a footstep frame, keyed as a node whose next
/// step number is `next` reads it.
pub fn with_crc(mut frame: RawFrame, next: u16) -> RawFrame {
    use planner_core::wire::{crc8, crc8_keyed, step_key, step_number};
    let n = usize::from(frame.len.min(8));
    if n > 0 {
        let body = &frame.data[..n - 1];
        frame.data[n - 1] = if matches!(frame.id, ids::STEP_APPEND | ids::STEP_MODIFY) {
            crc8_keyed(frame.id, step_key(step_number(frame.data[0], next)), body)
        } else {
            crc8(frame.id, body)
        };
    }
    frame
}

fn decode_checked(frame: &RawFrame, next: u16) {
    let frame = *frame;
    match Command::decode(&frame, next) {
        Ok(cmd) => {
            let again = cmd.encode();
            assert_eq!(again.id, frame.id, "{cmd:?}");
            assert_eq!(Command::decode(&again, next), Ok(cmd), "{frame:?}");
            // The codec is canonical: what it accepts, it re-encodes bit for bit.
            assert_eq!(again, frame, "{cmd:?}");
            assert_eq!(u16::from(cmd.code()), frame.id & 0xFF);
        }
        Err((reason, _seq)) => {
            let r = reason.code();
            assert!((1..=planner_core::wire::Reason::ALL.len() as u8).contains(&r));
        }
    }
}

/// A frame of the in-memory bus device: the codec's own frame type.
pub type MemFrame = RawFrame;

/// An in-memory `embedded-can` device: frames to receive, frames transmitted.
#[derive(Debug, Default)]
pub struct MemCan {
    /// Frames waiting to be received by the node.
    pub rx: VecDeque<RawFrame>,
    /// Frames the node transmitted.
    pub tx: Vec<RawFrame>,
}

/// Never happens: the in-memory device does not fail.
#[derive(Debug)]
pub struct NoError;

impl embedded_can::Error for NoError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl embedded_can::nb::Can for MemCan {
    type Frame = MemFrame;
    type Error = NoError;
    fn transmit(&mut self, frame: &MemFrame) -> nb::Result<Option<MemFrame>, NoError> {
        self.tx.push(*frame);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<MemFrame, NoError> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

fn fresh_node() -> Node<8> {
    static NODE: OnceLock<Node<8>> = OnceLock::new();
    NODE.get_or_init(|| Node::new(NodeConfig::hrp2()).expect("HRP-2 node"))
        .clone()
}

/// A byte reader that yields zeros once the input is exhausted.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((b, rest)) => {
                self.0 = rest;
                *b
            }
            None => 0,
        }
    }
    fn i8(&mut self) -> i8 {
        self.u8() as i8
    }
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// Operation codes of the `node` target's program (the first byte of an operation, modulo 8).
pub mod op {
    /// `[id lo, id hi, len, data…]`: a raw frame into the receive queue (`len` modulo 9 bytes;
    /// `len` ≥ 0x80: the last byte is replaced by the right CRC-8).
    pub const RAW: u8 = 0;
    /// `[id lo, id hi, len, data…]`: a raw frame straight to `Node::handle` (as `RAW`).
    pub const HANDLE: u8 = 1;
    /// `[id delta, dx, dy, dyaw]`: append the next footstep of a nominal 0.2 m gait, perturbed.
    pub const APPEND: u8 = 2;
    /// `[back, dx, dy, dyaw]`: modify a recent footstep, perturbed.
    pub const MODIFY: u8 = 3;
    /// `[seq, op]`: a control command (op modulo 8: 0 … 4 in the node's session; 5 … 7 as
    /// `op − 5` in another session); `seq` is the next number plus `seq − 8` (below: old).
    pub const CONTROL: u8 = 4;
    /// `[seq]`: an emergency stop.
    pub const ESTOP: u8 = 5;
    /// `[n]`: poll `n + 1` cycles of 5 ms.
    pub const POLL: u8 = 6;
    /// `[ms lo, ms hi]`: poll once after a jump of the clock (it may wrap).
    pub const JUMP: u8 = 7;
}

struct Driver {
    node: Node<8>,
    can: MemCan,
    now_ms: u32,
    cycles: u32,
    /// The controller's last sequence number.
    seq: u32,
    side: Side,
    x: f64,
    sent: Vec<WireStep>,
    book: StepBook,
}

impl Driver {
    /// A node after the handshake (the `Reset` in the start-up's session, epoch 0).
    fn new() -> Self {
        let mut d = Self {
            node: fresh_node(),
            can: MemCan::default(),
            now_ms: 0,
            cycles: 0,
            seq: 0,
            side: Side::Right,
            x: 0.0,
            sent: Vec::new(),
            book: StepBook::new(),
        };
        d.control(ControlOp::Reset, 0, 0);
        d.poll(5);
        assert_eq!(d.node.state(), planner_core::node::NodeState::Standing);
        d
    }

    /// Queues control command `op`, `back` numbers below the next (0: the next), `other`
    /// sessions away from the node's.
    fn control(&mut self, op: ControlOp, back: u32, other: u16) {
        self.seq += 1;
        let c = Command::Control {
            session: (self.node.session().tag()).wrapping_add(other),
            seq: self.seq.saturating_sub(back),
            op,
        };
        self.queue(c.encode());
    }

    fn queue(&mut self, f: RawFrame) {
        // A controller's receive FIFO is bounded; so is the fuzz input's effect.
        if self.can.rx.len() < 256 {
            self.can.rx.push_back(f);
        }
    }

    fn poll(&mut self, dt_ms: u32) {
        self.now_ms = self.now_ms.wrapping_add(dt_ms);
        let foreign_before = self.node.counters().foreign;
        let dropped_before = self.node.counters().tx_dropped;
        self.can.tx.clear();
        let report = self.node.poll(self.now_ms, &mut self.can);
        let foreign = usize::from(self.node.counters().foreign - foreign_before);
        self.cycles = self.cycles.wrapping_add(1);
        assert!(report.reference.is_finite(), "{:?}", report.reference);
        assert_eq!(self.node.cycles(), self.cycles);
        // The first poll publishes no reference (no session yet: the handshake is in it).
        if self.cycles == 1 {
            return;
        }
        // Exactly one reference: one frame of each stream identifier, this cycle's tick.
        let mut stream = Stream::default();
        for id in [
            ids::COG,
            ids::ZMP,
            ids::COG_VEL,
            ids::FOOT_LEFT,
            ids::FOOT_RIGHT,
        ] {
            let frames: Vec<_> = self.can.tx.iter().filter(|f| f.id == id).collect();
            assert_eq!(frames.len(), 1, "stream id {id:#x}: {:?}", self.can.tx);
            assert!(stream.decode_into(frames[0]));
        }
        assert_eq!(stream.tick, self.cycles & (planner_core::wire::STAMPS - 1));
        // Every command frame taken is answered once (those held acted on, the rest refused
        // `Busy`) as far as the transmit backlog holds (an answer it could not hold is counted
        // dropped), no other frame is; the node takes frames until its bound of all kinds or
        // an empty queue (a planning command beyond the cycle's budget is answered `Busy`).
        let handled = usize::from(report.received) - foreign;
        let dropped = usize::from(self.node.counters().tx_dropped - dropped_before);
        let cfg = self.node.config();
        assert!(usize::from(report.received) <= cfg.max_frames);
        let acks: Vec<Ack> = self.can.tx.iter().filter_map(Ack::decode).collect();
        assert!(
            acks.len() <= handled && acks.len() + dropped >= handled,
            "{:?}",
            self.can.tx
        );
        if usize::from(report.received) < cfg.max_frames {
            assert!(self.can.rx.is_empty(), "stopped receiving: {acks:?}");
        }

        assert!(self
            .can
            .tx
            .iter()
            .filter(|f| f.id == ids::ACK)
            .all(|f| Ack::decode(f).is_some()));
        for id in [ids::STATUS, ids::DIAG, ids::SESSION] {
            let n = self.can.tx.iter().filter(|f| f.id == id).count();
            assert_eq!(n, usize::from(self.cycles % 20 == 1), "id {id:#x}");
        }
    }

    fn step(&mut self, b: &mut Bytes) {
        match b.u8() % 8 {
            op::RAW | op::HANDLE => {
                // (HANDLE is taken by `node_run` before it gets here.)
                let id = u16::from_le_bytes([b.u8(), b.u8()]) & 0x7FF;
                let l = b.u8();
                let data: Vec<u8> = (0..usize::from(l % 9)).map(|_| b.u8()).collect();
                let f = RawFrame::new(id, &data).expect("11-bit id, at most 8 bytes");
                // Length byte ≥ 0x80: the frame gets a right CRC-8 (see `with_crc`).
                let next = self.node.next_step();
                self.queue(if l >= 0x80 { with_crc(f, next) } else { f });
            }
            op::APPEND => {
                let id = self.node.next_step().wrapping_add(u16::from(b.u8() % 4));
                let (dx, dy, dyaw) = (b.i8(), b.i8(), b.i8());
                self.x += 0.2;
                let y = if self.side == Side::Left { 0.1 } else { -0.1 };
                let x = self.x + f64::from(dx) * 2e-3;
                let y = y + f64::from(dy) * 1e-3;
                let yaw = f64::from(dyaw) * 5e-3;
                if let Some(c) = self.book.append(id, self.side == Side::Left, x, y, yaw) {
                    self.queue(c.encode());
                    if let Command::Append(w) = c {
                        self.sent.push(w);
                    }
                }
                self.side = self.side.other();
            }
            op::MODIFY => {
                let back = usize::from(b.u8() % 4);
                let (dx, dy, dyaw) = (b.i8(), b.i8(), b.i8());
                if let Some(&w) = self.sent.iter().rev().nth(back) {
                    let (x, y, yaw) = w.si();
                    if let Some(m) = self.book.modify(
                        w.id,
                        x + f64::from(dx) * 1e-3,
                        y + f64::from(dy) * 5e-4,
                        yaw + f64::from(dyaw) * 2e-3,
                    ) {
                        self.queue(m.encode());
                    }
                }
            }
            op::CONTROL => {
                let back = u32::from(b.u8()).saturating_sub(8);
                let k = b.u8() % 8;
                let op = [
                    ControlOp::Heartbeat,
                    ControlOp::Start,
                    ControlOp::Stop,
                    ControlOp::StopNow,
                    ControlOp::Reset,
                ][usize::from(k % 5)];
                self.control(op, back, u16::from(k >= 5));
            }
            op::ESTOP => {
                let seq = b.u8();
                self.queue(Command::EmergencyStop { seq }.encode());
            }
            op::POLL => {
                for _ in 0..=b.u8() {
                    self.poll(5);
                }
            }
            _ => {
                let ms = u32::from(u16::from_le_bytes([b.u8(), b.u8()]));
                self.poll(ms);
            }
        }
    }
}

/// `node` target: see the module docs.
pub fn node_run(data: &[u8]) {
    let mut d = Driver::new();
    let mut b = Bytes(data);
    let mut ops = 0;
    // Bounded work per input: at most 64 operations, and a final poll.
    while !b.is_empty() && ops < 64 {
        // HANDLE is RAW given straight to `Node::handle` (no poll, no queue limit).
        if b.0[0] % 8 == op::HANDLE {
            b.u8();
            let id = u16::from_le_bytes([b.u8(), b.u8()]) & 0x7FF;
            let l = b.u8();
            let data: Vec<u8> = (0..usize::from(l % 9)).map(|_| b.u8()).collect();
            let f = RawFrame::new(id, &data).expect("11-bit id, at most 8 bytes");
            let next = d.node.next_step();
            let f = if l >= 0x80 { with_crc(f, next) } else { f };
            let before = d.node.clone();
            let Some(ack) = d.node.handle(&f, d.now_ms) else {
                assert!(!ids::is_command(f.id), "a command was not answered: {f:?}");
                assert_eq!(d.node.counters().foreign, before.counters().foreign + 1);
                assert!(d.node.same_state(&before));
                ops += 1;
                continue;
            };
            assert!(ids::is_command(f.id), "a foreign frame was answered: {f:?}");
            if ack.reason.is_some() {
                assert!(
                    d.node.same_state(&before),
                    "refused {ack:?} changed the node"
                );
            }
            assert_eq!(Ack::decode(&ack.encode()), Some(ack));
            if let Ok(cmd) = Command::decode(&f, next) {
                assert_eq!(ack.command, cmd.code());
            } else {
                assert!(
                    ack.reason.is_some(),
                    "a malformed frame was accepted: {f:?}"
                );
            }
        } else {
            d.step(&mut b);
        }
        ops += 1;
    }
    d.poll(5);
}

/// The seed corpus: a few valid inputs of every message type, per target, by file name.
pub fn seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let mut out = Vec::new();
    let frame = |f: RawFrame| {
        let mut v = f.id.to_le_bytes().to_vec();
        v.extend_from_slice(f.bytes());
        v
    };
    let step = |id, left, x, y, yaw| WireStep::from_si(id, left, x, y, yaw).unwrap();
    let change = |id, left, x, y, yaw| {
        WireModify::from_si(&step(id, left, 0.0, 0.0, 0.0), 1, x, y, yaw).unwrap()
    };
    let commands = [
        ("estop", Command::EmergencyStop { seq: 7 }),
        (
            "heartbeat",
            Command::Control {
                session: 0,
                seq: 1,
                op: ControlOp::Heartbeat,
            },
        ),
        (
            "start",
            Command::Control {
                session: 0,
                seq: 2,
                op: ControlOp::Start,
            },
        ),
        (
            "stop",
            Command::Control {
                session: 0,
                seq: 3,
                op: ControlOp::Stop,
            },
        ),
        (
            "stopnow",
            Command::Control {
                session: 0,
                seq: 4,
                op: ControlOp::StopNow,
            },
        ),
        (
            "reset",
            Command::Control {
                session: 0,
                seq: 5,
                op: ControlOp::Reset,
            },
        ),
        ("append", Command::Append(step(0, false, 0.2, -0.1, 0.0))),
        ("modify", Command::Modify(change(3, true, 0.6, 0.1, 0.1))),
    ];
    for (name, c) in commands {
        out.push(("decode", format!("seed-{name}"), frame(c.encode())));
    }
    // Answers and the stream: not commands, refused as unknown identifiers.
    let ack = Ack {
        command: 0,
        seq: 1,
        reason: None,
        queue: 2,
        echo: 0x5A,
        version: None,
    };
    out.push(("decode", "seed-ack".into(), frame(ack.encode())));
    let st = Stream {
        cog: [0.1, -0.05],
        cog_vel: [0.2, 0.0],
        zmp: [0.1, -0.1],
        phase: 2,
        tick: 9,
        feet: [[0.2, 0.1, 0.01, 0.0], [0.0, -0.1, 0.0, 0.0]],
    };
    for (i, f) in st.encode().into_iter().enumerate() {
        out.push(("decode", format!("seed-stream{i}"), frame(f)));
    }
    out.push((
        "decode",
        "seed-status".into(),
        frame(planner_core::wire::Status::default().encode()),
    ));
    let diag = planner_core::wire::Diag {
        foreign: 3,
        bus_errors: 0,
        tx_dropped: 1,
        next_step: 5,
    };
    out.push(("decode", "seed-diag".into(), frame(diag.encode())));
    let link = planner_core::wire::LinkHealth {
        tec: 8,
        rec: 3,
        bus_state: 1,
        reset: 5,
        bus_offs: 1,
        ..planner_core::wire::LinkHealth::ZERO
    };
    out.push(("decode", "seed-link".into(), frame(link.encode())));
    // `text`: host-sim's own log lines, a candump log of another interface in lower case, the
    // TOML scenarios and a robot file.
    let own: Vec<String> = commands
        .iter()
        .enumerate()
        .map(|(i, (_, c))| host_sim::sim::bus::log_line(5_000_000 * i as u64, &c.encode()))
        .collect();
    out.push(("text", "seed-canlog".into(), own.join("\n").into_bytes()));
    out.push((
        "text",
        "seed-candump".into(),
        b"(1767225600.002500) vcan0 010#0140\n(1767225600.007500) vcan0 1a0#0102\n".to_vec(),
    ));
    for (name, toml) in [
        (
            "seed-fig4",
            include_str!("../../host-sim/scenarios/fig4.toml"),
        ),
        (
            "seed-lateral",
            include_str!("../../host-sim/scenarios/lateral.toml"),
        ),
        (
            "seed-robot",
            include_str!("../../host-sim/robots/hrp2.toml"),
        ),
    ] {
        out.push(("text", name.into(), toml.as_bytes().to_vec()));
    }
    // `wlog`: a log of a heartbeat, a start and a stop; two logs in one file; an empty log.
    let heartbeat = frame(
        Command::Control {
            session: 0,
            seq: 1,
            op: ControlOp::Heartbeat,
        }
        .encode(),
    );
    let start = frame(
        Command::Control {
            session: 0,
            seq: 2,
            op: ControlOp::Start,
        }
        .encode(),
    );
    let (hb_id, hb) = (
        u16::from_le_bytes([heartbeat[0], heartbeat[1]]),
        &heartbeat[2..],
    );
    let (st_id, st) = (u16::from_le_bytes([start[0], start[1]]), &start[2..]);
    let one = wlog_seed(
        "walk",
        3,
        &[(120, hb_id, hb), (100_000, st_id, st), (300, 0x123, &[])],
    );
    out.push(("wlog", "seed-one".into(), one.clone()));
    let mut two = one.clone();
    two.extend(wlog_seed("second", 1, &[(9_000_000_000, hb_id, hb)]));
    out.push(("wlog", "seed-two".into(), two));
    out.push(("wlog", "seed-empty".into(), wlog_seed("empty", 0, &[])));
    // `node`: a walk of four steps, a modification, a stop; an emergency stop and reset; a
    // silent controller; raw frames of every command identifier.
    let walk = vec![
        op::APPEND,
        0,
        0,
        0,
        0,
        op::APPEND,
        0,
        0,
        0,
        0,
        op::APPEND,
        0,
        0,
        0,
        0,
        op::APPEND,
        0,
        0,
        0,
        0,
        op::CONTROL,
        1,
        1,
        op::POLL,
        200,
        op::MODIFY,
        1,
        10,
        0,
        0,
        op::POLL,
        200,
        op::CONTROL,
        2,
        2,
        op::POLL,
        255,
        op::POLL,
        255,
    ];
    out.push(("node", "seed-walk".into(), walk.clone()));
    let mut estop = walk[..25].to_vec();
    estop.extend_from_slice(&[
        op::ESTOP,
        9,
        op::POLL,
        255,
        op::CONTROL,
        3,
        4,
        op::POLL,
        255,
        op::POLL,
        255,
        op::CONTROL,
        4,
        4,
        op::POLL,
        1,
    ]);
    out.push(("node", "seed-estop".into(), estop));
    let mut silent = walk[..25].to_vec();
    silent.extend_from_slice(&[op::JUMP, 0x20, 0x03, op::POLL, 255, op::POLL, 255]);
    out.push(("node", "seed-silent".into(), silent));
    let mut raw = Vec::new();
    for (_, c) in commands {
        let f = c.encode();
        raw.push(op::RAW);
        raw.extend_from_slice(&f.id.to_le_bytes());
        raw.push(f.len | 0x80);
        raw.extend_from_slice(f.bytes());
        raw.extend_from_slice(&[op::POLL, 3]);
    }
    raw.extend_from_slice(&[op::HANDLE, 0x10, 0x00, 1, 5, op::HANDLE, 0x23, 0x01, 0]);
    out.push(("node", "seed-raw".into(), raw));
    out
}

/// `text` target: see the module docs.
pub fn text_one(data: &[u8]) {
    use host_sim::sim::bus::{log_line, parse_log_line, LOG_EPOCH_S};
    let text = String::from_utf8_lossy(data);
    for line in text.lines() {
        let mcap = host_sim::output::mcap::parse_log_line(line);
        let Some(e) = parse_log_line(line) else {
            continue;
        };
        assert!(e.frame.id <= 0x7FF && e.frame.len <= 8, "{line:?}");
        // (The printer takes bus time in nanoseconds: from the epoch on, to 584 years.)
        let ns = e
            .unix_us
            .checked_sub(LOG_EPOCH_S * 1_000_000)
            .and_then(|us| us.checked_mul(1000));
        if let Some(ns) = ns {
            // The printer's line reads back as the same entry (the line itself, but for
            // leading zeros of the seconds beyond the printer's ten digits).
            assert_eq!(parse_log_line(&log_line(ns, &e.frame)), Some(e), "{line:?}");
        }
        // The MCAP reader refuses only times beyond its nanoseconds.
        if e.unix_us.checked_mul(1000).is_none() {
            assert!(mcap.is_err(), "{line:?}");
            continue;
        }
        let m = mcap.unwrap_or_else(|err| panic!("{line:?}: the MCAP reader refuses it: {err}"));
        assert_eq!(
            (m.unix_us, m.id, &m.data[..]),
            (e.unix_us, e.frame.id, e.frame.bytes()),
            "{line:?}"
        );
    }
    if let Ok(parsed) = host_sim::sim::replay::parse(&text, 0.005) {
        let frames = &parsed.frames;
        assert!(frames.windows(2).all(|w| w[0].tick <= w[1].tick));
        assert!(frames
            .iter()
            .all(|f| f.frame.id <= 0x7FF && f.frame.len <= 8));
    }
    let _ = host_sim::scenario::file::parse(&text);
    let _ = planner_core::robot::Robot::from_toml(&text);
}

/// `wlog` target: see the module docs.
pub fn wlog_one(data: &[u8]) {
    use gait_loop::binlog::{Frames, Header, SliceBytes, NAME_MAX};
    use gait_loop::player::Source;

    let mut src = SliceBytes::new(data);
    // Every log of the file, until the end or the first refusal.
    while let Ok(Some(h)) = Header::read(&mut src) {
        assert!(h.name().len() <= NAME_MAX && h.name().bytes().all(|b| b.is_ascii_graphic()));
        assert!(h.period_us >= 2 && h.last_us >= h.first_us);
        assert!(h.count > 0 || h.last_us == h.first_us);
        for f in h.feet {
            assert!(f.x.is_finite() && f.y.is_finite() && f.yaw.is_finite());
        }
        let before = src.remaining();
        let mut frames = Frames::new(&h, &mut src);
        let (mut n, mut t) = (0u32, h.first_us);
        while let Some(f) = frames.next_frame() {
            n += 1;
            assert!(n <= h.count, "more frames than announced");
            assert!(f.us >= t && f.us <= h.last_us, "time {} after {t}", f.us);
            assert!(f.frame.id <= 0x7FF && f.frame.len <= 8);
            t = f.us;
        }
        assert_eq!(frames.remaining(), h.count - n);
        match frames.error() {
            None => {
                assert_eq!(n, h.count);
                assert!(n == 0 || t == h.last_us, "the last frame not at last_us");
            }
            Some(_) => {
                assert!(n < h.count);
                // A refused log stays refused and gives nothing more.
                assert!(frames.next_frame().is_none());
                assert!(matches!(frames.skip_rest(), Err(e) if Some(e) == frames.error()));
                break;
            }
        }
        // Each frame takes at least 4 bytes.
        assert!(before - src.remaining() >= 4 * n as usize);
    }
}

/// A binary log for the `wlog` seeds: `frames` as (time increment, identifier, data).
fn wlog_seed(name: &str, count: u32, frames: &[(u64, u16, &[u8])]) -> Vec<u8> {
    let mut v = b"WLOG".to_vec();
    v.push(1);
    v.push(name.len() as u8);
    v.extend_from_slice(name.as_bytes());
    v.extend_from_slice(&5000u32.to_le_bytes());
    let first = 1_767_225_600_000_000u64;
    let last = first + frames.iter().map(|f| f.0).sum::<u64>();
    v.extend_from_slice(&first.to_le_bytes());
    v.extend_from_slice(&last.to_le_bytes());
    v.extend_from_slice(&count.to_le_bytes());
    for x in [0.0f64, 0.1, 0.0, 0.0, -0.1, 0.0] {
        v.extend_from_slice(&x.to_le_bytes());
    }
    for &(mut dt, id, data) in frames {
        loop {
            let low = (dt & 0x7F) as u8;
            dt >>= 7;
            if dt == 0 {
                v.push(low);
                break;
            }
            v.push(low | 0x80);
        }
        v.extend_from_slice(&id.to_le_bytes());
        v.push(data.len() as u8);
        v.extend_from_slice(data);
    }
    v
}
