//! Programs (see the test's docs in `main.rs`).

use super::*;

/// A sequence number: the next after the last accepted control command (what `DIAG` tells a
/// controller), one used before, this far after the last accepted (127, 128, 129 … to try
/// the edge of "ahead"), or any.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Seq {
    Fresh,
    Reuse(usize),
    After(u8),
    Any(u8),
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum AppendKind {
    /// The next id, the side the node requires.
    Next,
    /// The next id, the other side.
    WrongSide,
    /// The next id, 0.5 m further than asked (out of reach).
    Far,
    /// An id this much past the next.
    Skip(u8),
    /// An id already used (or, before any, a high one).
    Old(usize),
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum ModifyKind {
    /// The next version from the step book.
    Next,
    /// The next version with the side bit flipped.
    FlipSide,
    /// The version in force plus this (modulo 128).
    Jump(u8),
}

#[derive(Clone, Debug)]
pub(crate) enum Op {
    /// A `STEP_APPEND`, `forward` of the other foot, `lateral` wider, turned by `turn`;
    /// `left` picks the side when either may step.
    Append {
        kind: AppendKind,
        forward: f64,
        lateral: f64,
        turn: f64,
        left: bool,
    },
    /// A `STEP_MODIFY` of a known step (`pick`: mostly a queued one) by a small change.
    Modify {
        kind: ModifyKind,
        pick: usize,
        dx: f64,
        dy: f64,
        dyaw: f64,
    },
    /// One of the modification frames sent before (stale or duplicate, mostly).
    ResendModify(usize),
    /// One of the frames sent before, of any kind.
    Resend(usize),
    /// The append (`false`) or the modification in force (`true`) of the `k`-th last step
    /// accepted since the last reset: within the node's memory of repeats or just beyond.
    ResendStep(usize, bool),
    /// The last frame again.
    RepeatLast,
    Control(ControlOp, Seq),
    /// A control command with a fresh sequence number in another session (before or after the
    /// node's by this many epochs, halved; odd: after).
    OldSession(ControlOp, u8),
    Estop(Seq),
    /// A frame on `FOREIGN_IDS[i]` with `len` bytes of `fill`.
    Foreign(usize, u8, u8),
    /// A `MEASURED` frame against the reference `back` cycles before the last one published
    /// (fresh up to the node's 4 cycles; a large `back` is old or, wrapped, from the future),
    /// valid or not, in the node's session (`true`) or the one before.
    Measure(u32, bool, bool),
    /// A command frame sent before with one data bit flipped (`BadCrc`).
    Corrupt(usize, u8),
    /// A command frame sent before, cut short or lengthened (`BadLength`).
    Truncate(usize, u8),
    /// Cycles with a heartbeat every 20 (from the first).
    Poll(u32),
    /// Cycles without any frame.
    Silence(u32),
    /// One cycle this many milliseconds (plus 5) after the last.
    ClockJump(u32),
    /// `Stop`, heartbeats until standing, `Reset`.
    Recover,
}

pub(crate) fn seq() -> impl Strategy<Value = Seq> {
    prop_oneof![
        6 => Just(Seq::Fresh),
        2 => (0..64usize).prop_map(Seq::Reuse),
        1 => prop_oneof![Just(0u8), Just(1), Just(127), Just(128), Just(129), Just(255)]
            .prop_map(Seq::After),
        1 => any::<u8>().prop_map(Seq::Any),
    ]
}

pub(crate) fn append() -> BoxedStrategy<Op> {
    let kind = prop_oneof![
        14 => Just(AppendKind::Next),
        1 => Just(AppendKind::WrongSide),
        1 => Just(AppendKind::Far),
        1 => (1u8..4).prop_map(AppendKind::Skip),
        1 => (0..64usize).prop_map(AppendKind::Old),
    ];
    let forward = prop_oneof![4 => 0.15..0.22f64, 1 => 0.0..0.15f64, 1 => 0.22..0.26f64];
    let turn = prop_oneof![3 => Just(0.0), 1 => -0.2..0.2f64];
    (kind, forward, -0.02..0.04f64, turn, any::<bool>())
        .prop_map(|(kind, forward, lateral, turn, left)| Op::Append {
            kind,
            forward,
            lateral,
            turn,
            left,
        })
        .boxed()
}

pub(crate) fn modify() -> BoxedStrategy<Op> {
    let kind = prop_oneof![
        8 => Just(ModifyKind::Next),
        1 => Just(ModifyKind::FlipSide),
        1 => (1u8..128).prop_map(ModifyKind::Jump),
    ];
    let dyaw = prop_oneof![2 => Just(0.0), 1 => -0.05..0.05f64, 1 => -0.3..0.3f64];
    let d = || prop_oneof![3 => -0.03..0.03f64, 1 => -0.12..0.12f64];
    (kind, any::<usize>(), d(), d(), dyaw)
        .prop_map(|(kind, pick, dx, dy, dyaw)| Op::Modify {
            kind,
            pick,
            dx,
            dy,
            dyaw,
        })
        .boxed()
}

pub(crate) fn control() -> BoxedStrategy<Op> {
    let op = prop_oneof![
        4 => Just(ControlOp::Start),
        1 => Just(ControlOp::StartAdjusting),
        2 => Just(ControlOp::Stop),
        1 => Just(ControlOp::StopNow),
        1 => Just(ControlOp::Reset),
        1 => Just(ControlOp::Heartbeat),
    ];
    (op, seq()).prop_map(|(op, s)| Op::Control(op, s)).boxed()
}

pub(crate) fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        24 => append(),
        12 => modify(),
        3 => any::<usize>().prop_map(Op::ResendModify),
        3 => any::<usize>().prop_map(Op::Resend),
        2 => Just(Op::RepeatLast),
        10 => control(),
        1 => seq().prop_map(Op::Estop),
        1 => (control(), 0u8..6).prop_map(|(c, back)| match c {
            Op::Control(op, _) => Op::OldSession(op, back),
            other => other,
        }),
        2 => (0..FOREIGN_IDS.len(), 0u8..9, any::<u8>()).prop_map(|(i, n, b)| Op::Foreign(i, n, b)),
        2 => (
            prop_oneof![6 => 0u32..=6, 1 => 0u32..=40, 1 => Just(STAMPS - 1), 1 => any::<u32>()],
            prop_oneof![4 => Just(true), 1 => Just(false)],
            prop_oneof![6 => Just(true), 1 => Just(false)],
        )
            .prop_map(|(b, v, s)| Op::Measure(b, v, s)),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Op::Corrupt(p, b)),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(p, n)| Op::Truncate(p, n)),
        24 => prop_oneof![3 => 1u32..=200, 1 => 200u32..=400].prop_map(Op::Poll),
        3 => prop_oneof![1u32..=40, 60u32..=100, 80u32..=150].prop_map(Op::Silence),
        2 => prop_oneof![0u32..=300, 0u32..=2000].prop_map(Op::ClockJump),
        3 => Just(Op::Recover),
    ]
}

/// A controller that mostly walks: the next steps, heartbeats, modifications and repeats of
/// the steps' frames, rarely anything else (long walks: more steps than the node remembers).
pub(crate) fn walker_op() -> impl Strategy<Value = Op> {
    prop_oneof![
        10 => append(),
        8 => (20u32..=200).prop_map(Op::Poll),
        3 => modify(),
        3 => (0..40usize, any::<bool>()).prop_map(|(k, v)| Op::ResendStep(k, v)),
        1 => Just(Op::Control(ControlOp::Start, Seq::Fresh)),
        1 => op(),
    ]
}

/// A start time (0, just before the 32-bit millisecond counter wraps, or anywhere) and the
/// operations: random ones, or a walker's.
pub(crate) fn program() -> impl Strategy<Value = (u32, Vec<Op>)> {
    let t0 = prop_oneof![Just(0u32), (u32::MAX - 20_000)..=u32::MAX, any::<u32>()];
    let ops = prop_oneof![
        3 => prop::collection::vec(op(), 1..=120),
        1 => prop::collection::vec(walker_op(), 40..=160),
    ];
    (t0, ops)
}
