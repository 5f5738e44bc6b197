//! The hardware-free node: one call of [`Node::poll`] is one 5 ms control cycle.
//!
//! Time is passed in (`now_ms`, a free-running millisecond counter that may wrap) and the bus
//! is behind the `embedded-can` non-blocking trait, as smoltcp's `poll(timestamp, device)`:
//! the same code runs in the firmware (FDCAN), in host-sim (a virtual bus) and in tests.
//!
//! Per cycle, with bounded work:
//! 1. **receive**: drain the device, at most [`NodeConfig::max_frames`] frames of all kinds
//!    (160: more than the 106 a 1 Mbit/s bus carries in 5 ms, so nothing received waits for
//!    the next cycle), before acting on any. Frames that are not the node's
//!    ([`ids::COMMANDS`]) are counted ([`Counters::foreign`], published in `DIAG`) and never
//!    answered; of the node's, at most [`NodeConfig::max_rx`] (20) are held, whoever sent
//!    them. When more arrive, a frame of a higher class takes the place of the newest held
//!    frame of the lowest class: an `ESTOP` first, then a `StopNow`, then the controller's
//!    other commands, then the estimator's `MEASURED`; the frame left out is refused `Busy`
//!    (answered after the cycle's stream and reports, as far as the transmit backlog holds)
//!    and changes nothing;
//! 2. **act in priority order**: every `ESTOP` of the cycle first, then every `StopNow`,
//!    then the other commands in the order they arrived. Each is validated once
//!    ([`Command::decode`]), checked against the state (session, freshness, reach, side
//!    order, emergency stop, supervision) and applied to the [`Gait`], and answered with an
//!    `ACK` that carries the reason code when refused. So **a node that an `ESTOP` reaches is
//!    emergency-stopped in that cycle**, whatever arrives before or with it and from whichever
//!    sender (an `ESTOP` is left out only when `max_rx` other `ESTOP`s are held), and every
//!    `StopNow` is carried out in its cycle while fewer than `max_rx` urgent frames arrive.
//!    The controller keeps to 16 commands a cycle and the estimator to one `MEASURED`: both
//!    are then taken whole, with room for emergency stops of other senders.
//!    Commands that plan — a
//!    `Start` (the start window) and a `STEP_MODIFY` of the next swing target while walking
//!    (eq. 17 plans the re-plan it will cause) — cost a window's plan against a few hundred
//!    instructions for the others, so at most [`NodeConfig::max_plans`] of them are carried
//!    out a cycle; the rest are refused `Busy`. A modification that plans is acted on **after
//!    the cycle's other commands and the step adjustment**, its work kept from the commands
//!    that arrived after it: eq. 17 is then planned once, on the final steps (the later modifications of the steps it lands with included), and the
//!    tick's re-plan at a start of single support in the same cycle takes that plan instead
//!    of planning again; if the step adjustment planned (a capture step comes first), it is
//!    refused `Busy`. And the cycle's command work is counted against a budget in estimated
//!    instructions ([`NodeConfig::work_budget`], [`WORK_BUDGET`]: each footstep command's
//!    checks, each plan, the step adjustment): a command is taken only if its work fits what
//!    is left, else refused `Busy` with nothing changed, and only a command carried out takes
//!    its work (a refusal spends nothing: the checks of refused frames are bounded by
//!    `max_rx` instead). In a walk that adjusts its steps, the step adjustment's share
//!    ([`WORK_ADJUST`]) is kept from the commands, so no number of footstep frames defers a
//!    capture step. So the worst cycle is bounded whatever arrives. Priority keeps what arrival order
//!    means: a footstep frame that arrived before a `StopNow` carried out in the cycle was
//!    dropped by it (refused `Stale`), and a `Reset` received with an `ESTOP` in one cycle is
//!    refused `EmergencyStopped` (the stop stands, whatever the order). Modifications of one step that arrive in one cycle are
//!    coalesced, newest version first: the first one accepted is in force and the older ones
//!    are then `Stale` (a newer one that is refused leaves an older one its turn, except that
//!    a modification that planned eq. 17 and was refused `Infeasible` has spent the cycle's
//!    plan: an older one of the next swing target is then `Busy`, and taken when sent again).
//!    Because a modification that plans is acted on last, a command of the same cycle that
//!    depends on it is checked against the step as it was (an append placed from the moved
//!    next target may be refused its reach, and is sent again in the next cycle); every step
//!    as it ends up is checked against its neighbours either way;
//! 3. **supervision**: if the robot moves and the controller has not been heard (an accepted
//!    command: new by construction, see below) for more than
//!    [`NodeConfig::heartbeat_timeout_ms`], by the clock or by the count of cycles (one cycle
//!    stands for `dt`), the node enters the *controller lost* state: the queue is dropped,
//!    the swing in progress ends, the robot settles, and motion commands are refused
//!    (`ControllerLost`) until a `Reset` once standing. The clock itself is checked: if
//!    `now_ms` advances by less than half of the nominal time over [`CLOCK_WINDOW`] cycles
//!    (50 ms over 100 ms), the node latches a clock fault (`STATUS` flag) and stops as for a
//!    lost controller. A link off the bus is a lost link: when the firmware reports its CAN
//!    link bus-off ([`Node::set_link_health`]) in more than [`OFF_BUS_CYCLES`] cycles in a
//!    row (20 ms: the board's back-off after a bus-off keeps it off for 1 … 64 cycles), a
//!    moving robot stops as for a lost controller, whatever was heard. So **no foot lifts off
//!    more than `heartbeat_timeout_ms` after the controller was last heard**, for the whole
//!    walk, even with a stopped clock, **nor more than 20 ms into a loss of the link**;
//! 4. advance the gait by one tick;
//! 5. publish the reference (5 frames; none before a session is open) and, in the first
//!    cycle and every 20 cycles after it, `STATUS`, `DIAG`, `SESSION` (and `LINK`); frames that cannot be sent now wait in a transmit
//!    backlog of [`TX_BACKLOG`] frames; an unsent reference is replaced by the next one
//!    rather than sent late.
//!
//! # Sessions and freshness (see [`crate::wire`] for the frames)
//! * After start-up no session is open (state *no session*): the node streams nothing,
//!   publishes its session epoch (`SESSION`), and takes only `ESTOP` and the `Reset` that
//!   carries that epoch (the handshake); everything else is refused `NoSession`. So after a
//!   reset of the board nothing moves until a controller has heard the new start-up.
//! * A control command must carry the session's tag (else `WrongSession`) and a sequence
//!   number greater than every one accepted since start-up (else `Stale`; equal to the last:
//!   `Duplicate`). A footstep append must carry the next step number (else `SequenceGap`;
//!   equal to an accepted one: `Duplicate`), a modification a version greater than the
//!   step's version in force (else `Stale`). Numbers and versions never wrap (a start-up
//!   numbers 65,535 steps, a step has 127 versions: beyond, `Exhausted`), and step numbers
//!   run on across `Reset`s, [`SESSION_SKIP`] past the old session's, so **no frame of an earlier session, no replayed and no wrapped
//!   copy is ever taken**; only a command never seen before proves the controller alive.
//! * `Reset` (only when standing) opens a new session (epoch + 1): the queue and the step
//!   memory are dropped, the step numbers skip 256, the emergency stop, the controller-lost state and the clock fault are
//!   left, and — except for the handshake after start-up — the node's world frame is
//!   **re-based**: its origin moves to the midpoint of the feet and its x axis to their mean
//!   heading; the stream and every later footstep are in the new frame.
//! * `ESTOP` belongs to no session: any one stops the robot (a repeat while stopped is
//!   `Duplicate`), and proves nothing.
//! * `StopNow` while standing drops the queued steps, and nothing else; with none queued it
//!   is refused `WrongState`. `Stop` while standing does nothing but count as heard.
//!
//! # Answers
//! A refused command changes nothing but the refusal counters: [`Node::same_state`] holds
//! between the node before and after it (tested for every reason code, and for random
//! programs against a reference model in `planner-core/tests/protocol/`). The state machine
//! (no session, standing, walking, stopping, controller lost, emergency-stopped; for each
//! command what the node does and answers) is the table in the book's *Reliability*
//! section, which `planner-core/tests/state_table.rs` checks against this code cell by cell.
//! Steps alternate feet ([`Gait::next_side`], published in `STATUS`): a step for the foot
//! that will be supporting is refused (`SideOrder`).
//!
//! Reach limits ([`Reach`]): what the HRP-2 legs (thigh and shank 0.3 m) can follow at the
//! gait's COG height, with a margin, measured on host-sim's multi-body model
//! (`host-sim/tests/reach.rs` walks the corners of these limits and asserts the knee margin).
//! A step is measured in the frame of the previous foot of the other side (`forward` along
//! its heading, `width` across, positive on the stepping foot's own side; a negative width is
//! `Crossing`):
//! * box: forward −0.20 … +0.30 m, width 0.15 … 0.28 m, heading change at most 0.30 rad;
//! * soles: the landing sole keeps at least [`Reach::sole_gap`] (10 mm) from the support sole,
//!   both taken as their rectangles at their headings (else `Crossing`): the width limit
//!   alone is measured between sole centres, and a turned sole reaches across it;
//! * distance between the feet `hypot(forward, width)` at most 0.361 m;
//! * a turn costs reach: `forward + 0.3 m/rad · |Δyaw| ≤ 0.30 m`;
//! * stride: the swinging foot travels at most 0.43 m along that heading (steady walking up
//!   to 0.215 m steps);
//! * growth: a step is at most 0.22 m longer than the one before (from standing: than 0).
//!
//! The last two are why a box alone is not enough: a long step needs the speed built up by the
//! steps before it, and the stop after long steps needs room. A modification is checked with
//! its two successors (their rules involve the modified step). The steps the node pads in
//! (in place, at the nominal width) keep the sole gap by the configuration's check at
//! start-up.

mod adjust;
mod commands;
mod config;
mod cycle;
mod drive;
mod feet;
mod reach;
mod report;
mod steps;
pub mod velocity;

use core::borrow::Borrow;

use heapless::Deque;

use adjust::Adjusting;
pub use adjust::{AdjustConfig, MAX_AGE, MAX_SHIFT};
pub use config::NodeConfig;
use cycle::*;
pub use drive::{Driver, AHEAD, GOAL_TOLERANCE, GOAL_YAW_TOLERANCE, WORK_DRIVE, WORK_GENERATE};
use reach::Frame;
pub(crate) use reach::Stance;
pub use reach::{Broken, Limit, Reach, Soles};
pub use steps::HISTORY;
use steps::{Record, Steps};

use crate::gait::{Footstep, Gait, GaitError, GaitParams, Phase, Reference, Side, PREVIEW};
use crate::real::Real;
use crate::shaping::PreviewGains;
use crate::wire::{
    ids, Ack, Command, ControlOp, Diag, Expect, LinkHealth, RawFrame, Reason, Session, Status,
    Stream, WireModify, WireStep,
};

/// Frames that can wait to be sent.
pub const TX_BACKLOG: usize = 32;

/// The command work a cycle may do by default ([`NodeConfig::work_budget`]), in estimated
/// Cortex-M7 instructions: every modification's checks cost [`WORK_STEP`], every append's
/// [`WORK_APPEND`], a plan it causes (a `Start`, a `STEP_MODIFY` of the next swing target
/// while walking: eq. 17) [`WORK_PLAN`] more, and the step adjustment from the measured state
/// [`WORK_ADJUST`] (kept from the commands in a walk that adjusts). A command whose work does
/// not fit what is left of the cycle's budget is refused `Busy` with nothing changed (the
/// controller sends it again in a later cycle); a refused command spends nothing. With the
/// tick, the re-plan, the frames sent and the checks of refused frames (at most
/// [`NodeConfig::max_rx`]), this bounds the worst cycle whatever is received (the firmware's
/// timing chapter states the bound and the log that reaches it).
pub const WORK_BUDGET: u32 = 33_000;
/// See [`WORK_BUDGET`]: one modification's checks (reach against the feet before it and its
/// two successors; the step records).
pub const WORK_STEP: u32 = 2_100;
/// See [`WORK_BUDGET`]: one append's checks (reach against the feet before it; the step
/// records).
pub const WORK_APPEND: u32 = 1_400;
/// See [`WORK_BUDGET`]: a plan of a window (a `Start`, eq. 17's check of a modified next
/// swing target).
pub const WORK_PLAN: u32 = 14_000;
/// See [`WORK_BUDGET`]: the step adjustment's work on a move (the reach's bisection to the
/// footstep unit and eq. 17's check).
pub const WORK_ADJUST: u32 = 23_000;

/// The most command frames the node receives in one cycle (the bound of
/// [`NodeConfig::max_rx`]): they are held for the cycle, so that every `ESTOP` and `StopNow`
/// among them is carried out first.
pub const MAX_RX: usize = 32;
const _: () = assert!(
    MAX_RX <= 64,
    "a cycle's frames are numbered in a byte and deferred by a 64-bit mask"
);

/// Control cycles in a row that the firmware may report its link bus-off (off the bus: it
/// neither sends nor takes part) before a moving robot stops as for a lost controller: more
/// than this many (20 ms) is a link loss, not a glitch.
pub const OFF_BUS_CYCLES: u32 = 4;

/// Cycles over which the clock is checked: it must advance by at least half of their nominal
/// time (see the module docs).
pub const CLOCK_WINDOW: u32 = 20;

/// Step numbers a start-up can give: 2¹⁶ − 1, so that no two steps of a start-up share the 16
/// bits of their number (the frames carry the low byte, their CRC the high byte).
pub const STEP_NUMBERS: u32 = 0xFFFF;

/// Step numbers a `Reset` (after the handshake) skips: the new session's first number is the
/// old session's next number + 256. A controller never sends a number 128 or more beyond the
/// node's next one (the frame would be read as a number 256 lower: `BadCrc`), so every
/// footstep frame of the old session, accepted or not, carries a number below the new
/// session's first: read against the new numbers it is one already past, or one of another
/// block (`BadCrc`). So a start-up's numbers last 255 sessions, fewer as steps use numbers;
/// a `Reset` after that still opens a session and leaves every latched state, with no step
/// numbers (appends `Exhausted`: the robot stands until the node restarts).
pub const SESSION_SKIP: u32 = 256;

/// What one cycle did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PollReport<T = f64> {
    /// The reference of this cycle.
    pub reference: Reference<T>,
    /// Frames received (the node's and foreign ones).
    pub received: u8,
    /// Commands refused.
    pub refused: u8,
    /// Frames handed to the bus.
    pub sent: u8,
}

/// Counters kept by the node (all saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Commands refused, total.
    pub refused: u16,
    /// Refusals per reason code (index = code; 0 unused).
    pub by_reason: [u16; Reason::CODES],
    /// Frames received that are not the node's (never answered).
    pub foreign: u16,
    /// Frames dropped because the transmit backlog was full.
    pub tx_dropped: u16,
    /// Cycles reported late by the firmware.
    pub overruns: u16,
    /// Bus errors on receive or transmit.
    pub bus_errors: u16,
}

impl Counters {
    /// Every counter zero.
    pub const ZERO: Self = Self {
        refused: 0,
        by_reason: [0; Reason::CODES],
        foreign: 0,
        tx_dropped: 0,
        overruns: 0,
        bus_errors: 0,
    };
}

/// The published state (the `state` field of `STATUS`; the book's state table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NodeState {
    /// Standing still.
    Standing = 0,
    /// Walking (the queue, padded with steps in place).
    Walking = 1,
    /// Emergency-stopped (latched until a `Reset` once standing).
    EmergencyStopped = 2,
    /// The controller fell silent while the robot moved (latched until a `Reset` once
    /// standing).
    ControllerLost = 3,
    /// Walking out the queue after `Stop` or `StopNow`, then settling.
    Stopping = 4,
    /// After start-up, before the handshake (a `Reset` carrying the start-up's session):
    /// standing, no reference streamed.
    NoSession = 5,
}

/// The node. `G` holds the preview-control gains, as in [`Gait`]: by value (the default,
/// computed by [`Node::new`]) or lent, e.g. by a reference to gains in flash
/// ([`Node::with_gains`]). `T` is the scalar of the gait, the reach checks and the stream's
/// encoding: `f64` (the default, for double-precision FPUs) or `f32` (single-precision
/// FPUs: `Node<Q, PreviewGains<f32, PREVIEW>, f32>`, or lent gains of `f32`). The bus is the
/// same for both: its fixed-point fields are decoded once ([`Command::decode`]) and
/// converted to `T` at the edge, and the stream is rounded to the same integer units.
#[derive(Clone, Debug)]
pub struct Node<const Q: usize, G = PreviewGains<f64, PREVIEW>, T: Real = f64> {
    cfg: NodeConfig<T>,
    gait: Gait<T, Q, G>,
    tx: Deque<RawFrame, TX_BACKLOG>,
    steps: Steps<Q>,
    /// The session epoch (see the module docs).
    epoch: u32,
    /// A session is open (the handshake after start-up was taken).
    open: bool,
    /// Sequence number of the last accepted control command (0: none since start-up).
    last_seq: u32,
    /// The number of the start-up's first step.
    first: u16,
    /// Step numbers used since start-up: every step appended, and [`SESSION_SKIP`] per
    /// `Reset` (the next number is `first + appended`; gait ids are `appended` at the time).
    appended: u32,
    estopped: bool,
    lost: bool,
    /// The clock did not advance with the cycles (latched until a `Reset`).
    clock_fault: bool,
    /// Planning commands that may still plan in this cycle ([`NodeConfig::max_plans`] at
    /// the start of each cycle's acting).
    plans_left: usize,
    /// What is left of the cycle's [`NodeConfig::work_budget`] (the whole budget at the start
    /// of each cycle's acting).
    work_left: u32,
    /// An emergency stop was received in the cycle being acted on: no `Reset` leaves it (set
    /// and cleared within [`Node::poll`]).
    estop_now: bool,
    last_heard: Option<u32>,
    /// The cycle in which the controller was last heard.
    heard_cycle: u32,
    /// The start of the clock check's window: cycle and `now_ms`.
    window: (u32, u32),
    /// Supervision's timeout in cycles (from the timeout and `dt`).
    timeout_cycles: u32,
    /// The nominal time of [`CLOCK_WINDOW`] cycles \[ms\].
    window_ms: u32,
    counters: Counters,
    cycle: u32,
    /// The firmware's CAN link health, published in `LINK` once set.
    link: Option<LinkHealth>,
    /// Cycles in a row that the link reported bus-off (up to the supervision's).
    off_bus: u32,
    /// The step adjustment (see `adjust`).
    adj: Adjusting<T>,
    /// The frames of the queued steps kept for the reach checks (see `feet`).
    feet: feet::FeetFrames<T, Q>,
    /// Who chooses the footsteps: the controller, or the node from a velocity or a goal (see
    /// `drive`).
    drive: drive::Drive<T>,
}

/// A node that is not configured yet, as a `static` holds it before start-up: every byte zero
/// (with gains named by a zero-sized type, such as the firmware's `walk_robot::Gains`), so the
/// `static` is in .bss (no flash, nothing copied at reset). `G` lends gains computed
/// beforehand ([`PreviewGains::are_for`] the configuration; nothing computes them in place).
/// [`ParkedNode::start`] configures it in place and only then hands out the [`Node`]: nothing
/// of the node's 14 KB is built on the stack (a node built by value and moved into place needs
/// that much stack and more), and a node that was never configured cannot be polled.
///
/// ```
/// use planner_core::gait::PREVIEW;
/// use planner_core::node::{NodeConfig, ParkedNode};
/// use planner_core::shaping::{Law, PreviewGains};
///
/// let cfg = NodeConfig::hrp2();
/// let gains = PreviewGains::<f64, PREVIEW>::new(&cfg.params.preview_config(), Law::FromRest)?;
/// let mut parked = ParkedNode::<16, _>::new(&gains); // a `static` in the firmware
/// let node = parked.start(cfg).expect("the gains are the robot's");
/// assert!(node.gait().is_standing());
/// # Ok::<(), planner_core::shaping::GainError>(())
/// ```
#[derive(Debug)]
pub struct ParkedNode<const Q: usize, G, T: Real = f64>(Node<Q, G, T>);

impl<const Q: usize, G, T: Real> ParkedNode<Q, G, T> {
    /// The parked node, holding `gains` (see the type's docs).
    pub const fn new(gains: G) -> Self {
        Self(Node::parked(gains))
    }
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> ParkedNode<Q, G, T> {
    /// Configures the node in place for `cfg` ([`Node::restart`]: it is then the node
    /// [`Node::with_gains`] would build) and hands it out. On error the node stays parked.
    pub fn start(&mut self, cfg: NodeConfig<T>) -> Result<&mut Node<Q, G, T>, GaitError> {
        self.0.restart(cfg)?;
        Ok(&mut self.0)
    }
}

fn reason_of(e: GaitError) -> Reason {
    match e {
        GaitError::QueueFull => Reason::QueueFull,
        GaitError::NonFinite => Reason::OutOfRange,
        GaitError::SideOrder => Reason::SideOrder,
        GaitError::UnknownStep => Reason::UnknownStep,
        GaitError::LiftedOff => Reason::LiftedOff,
        GaitError::Infeasible => Reason::Infeasible,
        GaitError::WrongState => Reason::WrongState,
        _ => Reason::PlanFailed,
    }
}

impl<const Q: usize, T: Real> Node<Q, PreviewGains<T, PREVIEW>, T> {
    /// A node standing still (computes the preview gains).
    pub fn new(cfg: NodeConfig<T>) -> Result<Self, GaitError> {
        let gains = Gait::<T, Q>::gains_for(&cfg.params, &cfg.left, &cfg.right)?;
        Self::with_gains(cfg, gains)
    }
}

impl<const Q: usize, G, T: Real> Node<Q, G, T> {
    /// Step ids are 8 bits: every queued step must have its own.
    const CAPACITY_OK: () = assert!(Q >= 1 && Q <= 128, "queue capacity 1 … 128");

    /// A node that is not configured yet, holding `gains` ([`Gait::parked`]): every byte zero
    /// when `G` is zero-sized (see [`ParkedNode`], which holds it until [`Node::restart`]
    /// has configured it).
    const fn parked(gains: G) -> Self {
        let () = Self::CAPACITY_OK;
        Self {
            cfg: NodeConfig {
                params: GaitParams::PARKED,
                left: Footstep::PARKED,
                right: Footstep::PARKED,
                heartbeat_timeout_ms: 0,
                velocity_timeout_ms: 0,
                max_rx: 0,
                max_frames: 0,
                max_plans: 0,
                work_budget: 0,
                reach: Reach::PARKED,
                adjust: AdjustConfig {
                    max_age: 0,
                    margin: T::ZERO,
                    min_change: T::ZERO,
                    max_shift: T::ZERO,
                    max_deviation: T::ZERO,
                    from_measured: false,
                },
                entropy: 0,
            },
            gait: Gait::parked(gains),
            tx: Deque::new(),
            steps: Steps::PARKED,
            epoch: 0,
            open: false,
            last_seq: 0,
            first: 0,
            appended: 0,
            estopped: false,
            lost: false,
            clock_fault: false,
            estop_now: false,
            plans_left: 0,
            work_left: 0,
            last_heard: None,
            heard_cycle: 0,
            window: (0, 0),
            timeout_cycles: 0,
            window_ms: 0,
            counters: Counters::ZERO,
            cycle: 0,
            link: Some(LinkHealth::ZERO),
            off_bus: 0,
            adj: Adjusting::ZERO,
            feet: feet::FeetFrames::EMPTY,
            drive: drive::Drive::ZERO,
        }
    }
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// [`Node::new`] with the preview gains computed beforehand and lent by `gains`
    /// ([`Gait::with_gains`]: the firmware compiles them into flash from the robot file and
    /// passes a reference or a type that names them, so they are neither computed nor copied
    /// at start-up).
    pub fn with_gains(cfg: NodeConfig<T>, gains: G) -> Result<Self, GaitError> {
        let mut node = Self::parked(gains);
        node.restart(cfg)?;
        Ok(node)
    }

    /// Makes this node, in place, the one [`Node::with_gains`] would build for `cfg` with its
    /// own gains: standing on `cfg`'s feet, nothing queued or remembered, every counter and
    /// the cycle count zero, no link health. This is how the firmware configures its node in
    /// its `static` ([`ParkedNode::start`]) without building 14 KB on the stack, and how it
    /// starts afresh. On error (the checks of [`Gait::restart`]) nothing changes.
    pub fn restart(&mut self, cfg: NodeConfig<T>) -> Result<(), GaitError> {
        // The steps the node pads in (in place, at the nominal width, the same heading) must
        // keep the sole gap; and the receive bound is the node's buffer.
        let p = &cfg.params;
        let gap = p.step_width - (p.sole_half_width + p.sole_half_width);
        // (`NaN` fails too.)
        let gap_ok = gap
            .partial_cmp(&cfg.reach.sole_gap)
            .is_some_and(|o| o.is_ge());
        let a = &cfg.adjust;
        // (`NaN` fails too.)
        let within = |v: T, lo: T, hi: T| v >= lo && v <= hi;
        let age_ok = a.max_age <= MAX_AGE
            && within(a.max_shift, T::ZERO, T::of(MAX_SHIFT))
            && within(a.max_deviation, T::ZERO, T::of(1e3));
        if !gap_ok
            || !age_ok
            || cfg.max_rx > MAX_RX
            || cfg.max_rx == 0
            || cfg.max_frames < cfg.max_rx
            // The budget bounds the cycle only up to the default (the bound measured), and
            // below a plan with its checks, the step adjustment's share or a drive command's
            // start, something that plans could never be carried out.
            || cfg.work_budget > WORK_BUDGET
            || cfg.work_budget < WORK_ADJUST.max(WORK_STEP + WORK_PLAN).max(WORK_DRIVE)
            || cfg.max_plans == 0
        {
            return Err(GaitError::BadParams);
        }
        // Supervision in cycles: the timeout in whole cycles of `dt` (rounded up).
        let dt_us = (p.dt * T::of(1e6)).round().trunc_i32();
        if dt_us <= 0 {
            return Err(GaitError::BadParams);
        }
        let dt_us = dt_us as u32;
        let timeout_cycles = cfg
            .heartbeat_timeout_ms
            .saturating_mul(1000)
            .div_ceil(dt_us);
        self.gait.restart(cfg.params, cfg.left, cfg.right)?;
        self.cfg = cfg;
        self.tx.clear();
        self.steps.clear();
        self.open = false;
        self.last_seq = 0;
        self.cycle = 0;
        let _ = self.set_entropy(cfg.entropy);
        self.appended = 0;
        self.estopped = false;
        self.lost = false;
        self.clock_fault = false;
        self.last_heard = None;
        self.heard_cycle = 0;
        self.window = (0, 0);
        self.timeout_cycles = timeout_cycles;
        self.plans_left = cfg.max_plans;
        self.work_left = cfg.work_budget;
        self.window_ms = dt_us.saturating_mul(CLOCK_WINDOW) / 1000;
        self.counters = Counters::ZERO;
        self.cycle = 0;
        self.link = None;
        self.off_bus = 0;
        self.adj = Adjusting::ZERO;
        self.feet = feet::FeetFrames::EMPTY;
        self.drive = drive::Drive::ZERO;
        Ok(())
    }

    /// The gait.
    pub fn gait(&self) -> &Gait<T, Q, G> {
        &self.gait
    }

    /// The configuration.
    pub fn config(&self) -> &NodeConfig<T> {
        &self.cfg
    }

    /// The counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// What is left of the budget of the cycle being acted on ([`NodeConfig::work_budget`]),
    /// or, between cycles, of the budget [`Node::handle`] spends from (renewed by every
    /// [`Node::poll`]).
    pub fn work_left(&self) -> u32 {
        self.work_left
    }

    /// Cycles run.
    pub fn cycles(&self) -> u32 {
        self.cycle
    }

    /// When the controller was last heard (an accepted command), if ever \[ms\].
    pub fn last_heard(&self) -> Option<u32> {
        self.last_heard
    }

    /// Tells the node that the last cycle overran its time budget (counted and published).
    pub fn note_overrun(&mut self) {
        self.counters.overruns = self.counters.overruns.saturating_add(1);
    }

    /// The firmware's report of its CAN link (error counters, bus state, reset reason, missed
    /// slots): from now on the node publishes it in `LINK` with every `STATUS`. Call it once
    /// per cycle, before [`Node::poll`]: a link reported bus-off (`bus_state` 3: the node
    /// neither sends nor takes part) in more than [`OFF_BUS_CYCLES`] polls in a row stops a
    /// moving robot as a lost controller does (supervision, see the module docs).
    pub fn set_link_health(&mut self, link: LinkHealth) {
        self.link = Some(link);
    }

    /// `true` if `other` is in the same state as `self`: everything but the counters (see
    /// [`Gait::same_state`] for what the gait compares). A refused command keeps it.
    pub fn same_state<H: Borrow<PreviewGains<T, PREVIEW>>>(&self, other: &Node<Q, H, T>) -> bool {
        self.gait.same_state(&other.gait)
            && self.cfg == other.cfg
            && self.tx.iter().eq(other.tx.iter())
            && self.steps == other.steps
            && self.epoch == other.epoch
            && self.open == other.open
            && self.last_seq == other.last_seq
            && self.first == other.first
            && self.appended == other.appended
            && self.estopped == other.estopped
            && self.lost == other.lost
            && self.clock_fault == other.clock_fault
            && self.last_heard == other.last_heard
            && self.heard_cycle == other.heard_cycle
            && self.window == other.window
            && self.cycle == other.cycle
            && self.off_bus == other.off_bus
            && self.adj == other.adj
            && self.drive == other.drive
    }

    /// The session as published in `SESSION`.
    pub fn session(&self) -> Session {
        Session {
            epoch: self.epoch,
            last_seq: self.last_seq,
        }
    }

    /// The number of the next step to append (published in `DIAG`).
    pub fn next_step(&self) -> u16 {
        self.first.wrapping_add(self.appended as u16)
    }

    /// What the validation of a frame depends on now ([`Command::decode`]): the next step
    /// number, the session epoch and the last accepted control sequence number.
    pub fn expect(&self) -> Expect {
        Expect {
            next_step: self.next_step(),
            epoch: self.epoch,
            last_seq: self.last_seq,
        }
    }

    /// Draws the start-up's session from `entropy` (as [`NodeConfig::entropy`] does at
    /// [`Node::restart`]): for a firmware whose configuration is a constant, which it keeps
    /// as it is (so that the compiler folds it) and reads its random number generator for this
    /// after start-up. Taken only before the first poll; later (a session may be open) it
    /// changes nothing and returns `false`.
    pub fn set_entropy(&mut self, entropy: u32) -> bool {
        if self.cycle != 0 || self.open {
            return false;
        }
        self.cfg.entropy = entropy;
        self.epoch = entropy;
        self.first = (entropy >> 16) as u16;
        true
    }

    /// `true` once a session is open (the handshake after start-up was taken): the node ticks
    /// and streams its reference.
    pub fn session_open(&self) -> bool {
        self.open
    }

    /// `true` once the clock was found not to advance with the cycles (until a `Reset`).
    pub fn clock_fault(&self) -> bool {
        self.clock_fault
    }

    /// The gait's id of step number `number` (the steps since start-up before it).
    fn gait_id(&self, number: u16) -> u16 {
        number.wrapping_sub(self.first)
    }

    /// The state of the state machine (the book's table, `docs/src/reliability.md`).
    pub fn state(&self) -> NodeState {
        if !self.open && !self.estopped {
            NodeState::NoSession
        } else if self.estopped {
            NodeState::EmergencyStopped
        } else if self.lost {
            NodeState::ControllerLost
        } else if self.gait.is_standing() {
            NodeState::Standing
        } else if self.gait.is_stopping() {
            NodeState::Stopping
        } else {
            NodeState::Walking
        }
    }
}
