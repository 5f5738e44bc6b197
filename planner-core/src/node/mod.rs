//! The hardware-free node: one call of [`Node::poll`] is one 5 ms control cycle.
//!
//! Time is passed in (`now_ms`, a free-running millisecond counter that may wrap) and the bus
//! is behind the `embedded-can` non-blocking trait, as smoltcp's `poll(timestamp, device)`:
//! the same code runs in the firmware (FDCAN), in host-sim (a virtual bus) and in tests.
//!
//! Per cycle, with bounded work:
//! 1. **receive**: drain the device, at most [`NodeConfig::max_rx`] of the node's own frames
//!    ([`ids::COMMANDS`]) and [`NodeConfig::max_foreign`] others (counted in
//!    [`Counters::foreign`], published in `DIAG`, never answered), before acting on any;
//! 2. **act in priority order**: every `ESTOP` of the cycle first, then every `StopNow`,
//!    then the other commands in the order they arrived. Each is validated once
//!    ([`Command::decode`]), checked against the state (session, freshness, reach, side
//!    order, emergency stop, supervision) and applied to the [`Gait`], and answered with an
//!    `ACK` that carries the reason code when refused. So **every `ESTOP` and `StopNow` that
//!    reaches the node is carried out in the cycle in which it is received**, whatever arrives
//!    before or with it, as long as the controller keeps to `max_rx` commands a cycle (16,
//!    more than a third of what a 1 Mbit/s bus carries in 5 ms). Commands that plan — a
//!    `Start` (the start window) and a `STEP_MODIFY` of the next swing target while walking
//!    (eq. 17 plans the re-plan it will cause) — cost up to ~60,000 instructions on the
//!    Cortex-M7 against ~200 for the others, so at most [`NodeConfig::max_plans`] of them
//!    are carried out a cycle; the rest are refused `Busy`. Priority keeps what arrival order
//!    means: a footstep frame that arrived before a `StopNow` carried out in the cycle was
//!    dropped by it (refused `Stale`), and a `Reset` received with an `ESTOP` in one cycle is
//!    refused `EmergencyStopped` (the stop stands, whatever the order). Modifications of one step that arrive in one cycle are
//!    coalesced, newest version first: the first one accepted is in force and the older ones
//!    are then `Stale` (a newer one that is refused leaves an older one its turn);
//! 3. **supervision**: if the robot moves and the controller has not been heard (an accepted
//!    command: new by construction, see below) for more than
//!    [`NodeConfig::heartbeat_timeout_ms`], by the clock or by the count of cycles (one cycle
//!    stands for `dt`), the node enters the *controller lost* state: the queue is dropped,
//!    the swing in progress ends, the robot settles, and motion commands are refused
//!    (`ControllerLost`) until a `Reset` once standing. The clock itself is checked: if
//!    `now_ms` advances by less than half of the nominal time over [`CLOCK_WINDOW`] cycles
//!    (50 ms over 100 ms), the node latches a clock fault (`STATUS` flag) and stops as for a
//!    lost controller. So **no foot lifts off more than `heartbeat_timeout_ms` after the
//!    controller was last heard**, for the whole walk, even with a stopped clock;
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
//! command what the node does and answers) is the table in the README's *Reliability*
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

mod reach;
mod steps;

use core::borrow::Borrow;

use heapless::Deque;

use reach::Frame;
pub use reach::{Reach, Soles};
pub use steps::HISTORY;
use steps::{Record, Steps};

use crate::gait::{Footstep, Gait, GaitError, GaitParams, Phase, Reference, Side, PREVIEW};
use crate::real::Real;
use crate::shaping::PreviewGains;
use crate::wire::{
    ids, Ack, Command, ControlOp, Diag, LinkHealth, RawFrame, Reason, Session, Status, Stream,
    WireModify, WireStep,
};

/// Frames that can wait to be sent.
pub const TX_BACKLOG: usize = 32;

/// The most command frames the node receives in one cycle (the bound of
/// [`NodeConfig::max_rx`]): they are held for the cycle, so that every `ESTOP` and `StopNow`
/// among them is carried out first.
pub const MAX_RX: usize = 32;
const _: () = assert!(MAX_RX < 64, "a cycle's frames are a 64-bit mask");

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
/// block (`BadCrc`). So a start-up opens at most 255 sessions (beyond, `Reset` is refused
/// `Exhausted`), fewer as steps use numbers.
pub const SESSION_SKIP: u32 = 256;

/// Node configuration, in the node's scalar `T` ([`NodeConfig::cast`] converts the `f64`
/// configuration that a robot file gives).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeConfig<T = f64> {
    /// Gait parameters.
    pub params: GaitParams<T>,
    /// Where the left foot stands at start-up.
    pub left: Footstep<T>,
    /// Where the right foot stands at start-up.
    pub right: Footstep<T>,
    /// Silence of the controller after which a moving robot stops \[ms\] (see the module
    /// docs: the supervision bound).
    pub heartbeat_timeout_ms: u32,
    /// Command frames received per cycle at most (the rest wait in the controller's
    /// mailbox), at most [`MAX_RX`].
    pub max_rx: usize,
    /// Frames that are not the node's drained per cycle at most (apart from `max_rx`).
    pub max_foreign: usize,
    /// Planning commands (`Start`, `STEP_MODIFY` of the next swing target while walking)
    /// handled per cycle at most (see the module docs).
    pub max_plans: usize,
    /// Reach limits.
    pub reach: Reach<T>,
    /// A value that differs at every start-up (the firmware takes it from its hardware random
    /// number generator): the start-up's session epoch, and (its high half) the number of its
    /// first step. Frames of an earlier start-up are then refused except by chance (2⁻¹⁶ for
    /// a control command); within a start-up, by construction.
    pub entropy: u32,
}

impl NodeConfig {
    /// HRP-2 defaults: [`GaitParams::hrp2`], [`Reach::default`] and
    /// [`NodeConfig::for_robot`]'s node settings.
    pub fn hrp2() -> Self {
        Self::for_robot(GaitParams::hrp2(), Reach::default())
    }

    /// The node for a robot's gait parameters and reach limits (a robot file gives both: see
    /// `planner_core::robot`, feature `robot`), with the node settings that do not depend on
    /// the robot: the feet `step_width` apart at the origin, heading along x; 500 ms
    /// heartbeat timeout; 16 command frames and 128 foreign frames per cycle (more than a
    /// 1 Mbit/s bus carries in 5 ms); one planning command per cycle.
    pub fn for_robot(params: GaitParams<f64>, reach: Reach) -> Self {
        let half = params.step_width / 2.0;
        Self {
            params,
            left: Footstep::new(Side::Left, 0.0, half, 0.0),
            right: Footstep::new(Side::Right, 0.0, -half, 0.0),
            heartbeat_timeout_ms: 500,
            max_rx: 16,
            max_foreign: 128,
            max_plans: 1,
            reach,
            entropy: 0,
        }
    }

    /// This configuration in the scalar `T` (every real rounded to the nearest `T`; exact for
    /// `f64`): how the `f32` node is configured from a robot file.
    pub fn cast<T: Real>(&self) -> NodeConfig<T> {
        let foot = |f: &Footstep<f64>| Footstep::new(f.side, T::of(f.x), T::of(f.y), T::of(f.yaw));
        let p = &self.params;
        NodeConfig {
            params: GaitParams {
                omega: T::of(p.omega),
                dt: T::of(p.dt),
                single_ticks: p.single_ticks,
                double_ticks: p.double_ticks,
                start_ticks: p.start_ticks,
                settle_ticks: p.settle_ticks,
                stand_ticks: p.stand_ticks,
                rest_ticks: p.rest_ticks,
                adjust_min_ticks: p.adjust_min_ticks,
                adjust_max_ticks: p.adjust_max_ticks,
                step_width: T::of(p.step_width),
                sole_half_length: T::of(p.sole_half_length),
                sole_half_width: T::of(p.sole_half_width),
                step_height: T::of(p.step_height),
                tail: p.tail,
                shaping: p.shaping,
                cog_height: p.cog_height,
                gravity: p.gravity,
                preview_qe: p.preview_qe,
                preview_r: p.preview_r,
            },
            left: foot(&self.left),
            right: foot(&self.right),
            heartbeat_timeout_ms: self.heartbeat_timeout_ms,
            max_rx: self.max_rx,
            max_foreign: self.max_foreign,
            max_plans: self.max_plans,
            reach: self.reach.cast(),
            entropy: self.entropy,
        }
    }
}

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

/// The published state (the `state` field of `STATUS`; the README's state table).
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

/// The priority class of a command frame: 0 an emergency stop, 1 a stop now (by its op byte;
/// validated when it is handled), 2 the rest.
fn rank(f: &RawFrame) -> u8 {
    match f.id {
        ids::ESTOP => 0,
        ids::CONTROL if f.len == 8 && f.data[6] == 3 => 1,
        _ => 2,
    }
}

/// Bit `i` of a mask over a cycle's frames (at most [`MAX_RX`] ≤ 64 of them).
const fn bit(i: usize) -> u64 {
    1u64 << (i & 63)
}

/// What the acting of a cycle keeps (see [`Node::poll`]).
struct Acting {
    /// Commands refused.
    refused: u8,
    /// The last `StopNow` of the batch carried out.
    stop_at: Option<usize>,
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
                max_rx: 0,
                max_foreign: 0,
                max_plans: 0,
                reach: Reach::PARKED,
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
            last_heard: None,
            heard_cycle: 0,
            window: (0, 0),
            timeout_cycles: 0,
            window_ms: 0,
            counters: Counters::ZERO,
            cycle: 0,
            link: Some(LinkHealth::ZERO),
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
        if !gap_ok || cfg.max_rx > MAX_RX || cfg.max_rx == 0 {
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
        self.window_ms = dt_us.saturating_mul(CLOCK_WINDOW) / 1000;
        self.counters = Counters::ZERO;
        self.cycle = 0;
        self.link = None;
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
    /// per cycle, before [`Node::poll`].
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

    /// The state of the state machine (the README's table).
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

    /// The status as published.
    pub fn status(&self) -> Status {
        let adjust = self
            .gait
            .last_replan()
            .map(|i| i.adjust_ticks.clamp(-128, 127) as i8)
            .unwrap_or(0);
        let mut flags = 0;
        if self.gait.params().shaping {
            flags |= 1;
        }
        if self.gait.replan_failed() {
            flags |= 2;
        }
        if self.counters.tx_dropped > 0 {
            flags |= 4;
        }
        flags |= match self.gait.next_side() {
            None => 0,
            Some(Side::Left) => 1 << 3,
            Some(Side::Right) => 2 << 3,
        };
        if self.clock_fault {
            flags |= Status::CLOCK_FAULT;
        }
        Status {
            state: self.state() as u8,
            queue: self.gait.queued().min(255) as u8,
            rejected: self.counters.refused,
            overruns: self.counters.overruns,
            last_adjust: adjust,
            flags,
        }
    }

    /// The diagnostics as published.
    pub fn diag(&self) -> Diag {
        Diag {
            foreign: self.counters.foreign,
            bus_errors: self.counters.bus_errors,
            tx_dropped: self.counters.tx_dropped,
            next_step: self.next_step(),
        }
    }

    /// The answer refusing `frame` with `reason` without handling it (nothing changes).
    fn refusal(
        &self,
        frame: &RawFrame,
        decoded: &Result<Command, (Reason, u8)>,
        reason: Reason,
    ) -> Ack {
        let (command, seq, version) = match decoded {
            Ok(c) => (
                c.code(),
                c.key(),
                c.step_id().and_then(|id| self.steps.version(id)),
            ),
            Err((_, seq)) => ((frame.id & 0xFF) as u8, *seq, None),
        };
        Ack {
            command,
            seq,
            reason: Some(reason),
            queue: self.gait.queued().min(255) as u8,
            echo: crate::wire::echo_of(frame),
            version,
        }
    }

    fn refuse(&mut self, reason: Reason) {
        self.counters.refused = self.counters.refused.saturating_add(1);
        if let Some(n) = self.counters.by_reason.get_mut(usize::from(reason.code())) {
            *n = n.saturating_add(1);
        }
    }

    /// Reach and crossing check of a footstep: appended (`before` = `None`), or replacing the
    /// queued step `before`, with its two successors then checked against it.
    fn check_reach(&self, step: &Footstep<T>, before: Option<u16>) -> Result<(), Reason> {
        let r = &self.cfg.reach;
        let feet = self.gait.previous_feet(before);
        let other = Frame::of(&feet[step.side.other().index()]);
        let same = Frame::like(&feet[step.side.index()], &[&other]);
        let f = Frame::like(step, &[&other, &same]);
        // The first swing of a walk from standing: its growth counts from a step of 0.
        let position = match before {
            Some(id) => self.gait.position(id),
            None => Some(self.gait.queued()),
        };
        let from_rest = position == Some(0) && self.gait.next_swing_from_rest();
        let soles = Soles::of(&self.cfg.params);
        r.check_frames(&other, &same, &f, step.side, from_rest, &soles)?;
        if let Some(id) = before {
            let next = |k: u16| self.gait.queued_step(id.wrapping_add(k));
            if let Some(s1) = next(1) {
                let f1 = Frame::like(&s1, &[&f, &other]);
                r.check_frames(&f, &other, &f1, s1.side, false, &soles)?;
                if let Some(s2) = next(2) {
                    let f2 = Frame::like(&s2, &[&f1, &f]);
                    r.check_frames(&f1, &f, &f2, s2.side, false, &soles)?;
                }
            }
        }
        Ok(())
    }

    /// The footstep of a validated frame in `T`: the wire's integers in SI units (`f64`, as
    /// [`WireStep::si`]), each rounded to the nearest `T` (exact for `f64`).
    fn footstep(s: &WireStep) -> Footstep<T> {
        let (x, y, yaw) = s.si_in::<T>();
        let side = if s.left { Side::Left } else { Side::Right };
        Footstep::new(side, x, y, yaw)
    }

    /// Handles one frame from the bus (validation, state checks, application) and returns the
    /// answer to send: `None` for a frame that is not the node's (counted, not answered).
    /// [`Node::poll`] receives a cycle's frames first and hands them here in priority order.
    pub fn handle(&mut self, frame: &RawFrame, now_ms: u32) -> Option<Ack> {
        if !ids::is_command(frame.id) {
            self.counters.foreign = self.counters.foreign.saturating_add(1);
            return None;
        }
        let decoded = Command::decode(frame, self.next_step());
        Some(self.handle_command(frame, decoded, now_ms))
    }

    fn handle_command(
        &mut self,
        frame: &RawFrame,
        decoded: Result<Command, (Reason, u8)>,
        now_ms: u32,
    ) -> Ack {
        let echo = crate::wire::echo_of(frame);
        let (command, seq, result) = match decoded {
            Ok(cmd) => {
                let result = match cmd {
                    Command::EmergencyStop { .. } => self.estop(),
                    Command::Control { session, seq, op } => self.control(session, seq, op),
                    Command::Append(s) => self.append(frame, &s),
                    Command::Modify(m) => self.modify(frame, &m),
                };
                (cmd.code(), cmd.key(), result)
            }
            Err((reason, seq)) => ((frame.id & 0xFF) as u8, seq, Err(reason)),
        };
        match result {
            // Only an accepted command proves the controller alive, and every accepted one is
            // new (a greater sequence number, the next step number, a greater version); an
            // emergency stop proves nothing.
            Ok(()) if frame.id != ids::ESTOP => {
                self.last_heard = Some(now_ms);
                self.heard_cycle = self.cycle;
            }
            Ok(()) => {}
            Err(reason) => self.refuse(reason),
        }
        // Steps the command dropped (emergency stop, stop now) leave the step records. A
        // footstep command drops none (an append adds its record with its step, a modification
        // changes a queued step in place, or nothing if refused), and a heartbeat does not
        // touch the gait.
        if !matches!(
            decoded,
            Ok(Command::Append(_)
                | Command::Modify(_)
                | Command::Control {
                    op: ControlOp::Heartbeat,
                    ..
                })
        ) {
            self.steps.sync(&self.gait, self.first);
        }
        let version = match decoded {
            Ok(Command::Append(s)) => self.steps.version(s.id),
            Ok(Command::Modify(m)) => self.steps.version(m.id),
            _ => None,
        };
        Ack {
            command,
            seq,
            reason: result.err(),
            queue: self.gait.queued().min(255) as u8,
            echo,
            version,
        }
    }

    /// `Busy` if this cycle has planned [`NodeConfig::max_plans`] times already.
    fn plan(&self) -> Result<(), Reason> {
        if self.plans_left == 0 {
            return Err(Reason::Busy);
        }
        Ok(())
    }

    fn estop(&mut self) -> Result<(), Reason> {
        if self.estopped {
            return Err(Reason::Duplicate);
        }
        self.estopped = true;
        self.gait.clear_and_stop();
        Ok(())
    }

    fn control(&mut self, session: u16, seq: u32, op: ControlOp) -> Result<(), Reason> {
        if session != self.epoch as u16 {
            return Err(Reason::WrongSession);
        }
        if seq == self.last_seq && self.last_seq != 0 {
            return Err(Reason::Duplicate);
        }
        if seq <= self.last_seq {
            return Err(Reason::Stale);
        }
        if !self.open && op != ControlOp::Reset {
            return Err(Reason::NoSession);
        }
        let standing = self.gait.is_standing();
        match op {
            ControlOp::Heartbeat => {}
            ControlOp::Start => {
                if self.estopped {
                    return Err(Reason::EmergencyStopped);
                }
                if self.lost {
                    return Err(Reason::ControllerLost);
                }
                if !standing || self.gait.queued() == 0 {
                    return Err(Reason::WrongState);
                }
                self.plan()?;
                let started = self.gait.start().map_err(reason_of);
                self.plans_left = self.plans_left.saturating_sub(1);
                started?;
            }
            ControlOp::Reset => {
                if !standing {
                    return Err(Reason::WrongState);
                }
                // An emergency stop received in the same cycle stands, whatever the order.
                if self.estop_now {
                    return Err(Reason::EmergencyStopped);
                }
                self.reset()?;
            }
            ControlOp::Stop => {
                if !standing {
                    self.gait.stop();
                }
            }
            ControlOp::StopNow => {
                if standing {
                    // Standing: drop what is queued, and nothing else (no stop request for a
                    // later `Start` to find); with nothing queued there is nothing to do.
                    if self.gait.queued() == 0 {
                        return Err(Reason::WrongState);
                    }
                    self.gait.drop_queue().map_err(reason_of)?;
                } else {
                    self.gait.clear_and_stop();
                }
            }
        }
        self.last_seq = seq;
        Ok(())
    }

    /// Opens a new session while standing (see the module docs): the frame is re-based on the
    /// feet, except at the handshake after start-up.
    fn reset(&mut self) -> Result<(), Reason> {
        let epoch = self.epoch.checked_add(1).ok_or(Reason::Exhausted)?;
        // The new session numbers its steps past every number the old one could have sent.
        let skip = if self.open { SESSION_SKIP } else { 0 };
        let numbers = self
            .appended
            .checked_add(skip)
            .filter(|&n| n <= STEP_NUMBERS)
            .ok_or(Reason::Exhausted)?;
        if self.open {
            let [l, r] = *self.gait.feet();
            let half = T::of(0.5);
            let (x, y) = (half * (l.x + r.x), half * (l.y + r.y));
            let yaw = (l.yaw.sin() + r.yaw.sin()).atan2(l.yaw.cos() + r.yaw.cos());
            self.gait.rebase(x, y, yaw).map_err(reason_of)?;
        } else {
            // Nothing was accepted before the handshake but emergency stops: the queue is
            // empty already.
            let _ = self.gait.drop_queue();
        }
        self.epoch = epoch;
        self.appended = numbers;
        self.open = true;
        self.estopped = false;
        self.lost = false;
        self.clock_fault = false;
        self.steps.clear();
        Ok(())
    }

    /// What refuses any footstep frame first: no session, a repeat of what is in force, then
    /// the two latched states.
    fn footstep_gate(&self, frame: &RawFrame) -> Result<(), Reason> {
        if !self.open {
            return Err(Reason::NoSession);
        }
        if self.steps.is_repeat(frame) {
            return Err(Reason::Duplicate);
        }
        if self.estopped {
            return Err(Reason::EmergencyStopped);
        }
        if self.lost {
            return Err(Reason::ControllerLost);
        }
        Ok(())
    }

    fn append(&mut self, frame: &RawFrame, s: &WireStep) -> Result<(), Reason> {
        self.footstep_gate(frame)?;
        // A stop walks the queue it has: a step appended now might or might not be walked
        // before the robot stands (it depends on whether the last window is planned yet), so
        // it is refused, and the controller appends it once standing.
        if self.gait.is_stopping() {
            return Err(Reason::WrongState);
        }
        if self.appended >= STEP_NUMBERS {
            return Err(Reason::Exhausted);
        }
        // Step numbers run on from the start-up's first: a lost step must not let the next
        // one take its place (from standing, a stride twice as long).
        if s.id != self.next_step() {
            return Err(Reason::SequenceGap);
        }
        let step = Self::footstep(s);
        if self.gait.next_side().is_some_and(|side| side != step.side) {
            return Err(Reason::SideOrder); // (before the reach check: the clearer reason)
        }
        self.check_reach(&step, None)?;
        let gid = self.appended as u16;
        self.gait.push(gid, step).map_err(|(e, _)| reason_of(e))?;
        self.steps.push(Record {
            append: *s,
            append_frame: *frame,
            version: 0,
            in_force: None,
        });
        self.appended += 1;
        Ok(())
    }

    fn modify(&mut self, frame: &RawFrame, m: &WireModify) -> Result<(), Reason> {
        self.footstep_gate(frame)?;
        if self.gait.is_standing() && self.gait.queued() == 0 {
            return Err(Reason::WrongState);
        }
        if self.steps.swinging() == Some(m.id) {
            return Err(Reason::LiftedOff);
        }
        let Some((at, rec)) = self.steps.queued_find(m.id) else {
            return Err(Reason::UnknownStep);
        };
        if !m.is_newer_than(rec.version) {
            return Err(Reason::Stale);
        }
        if m.left != rec.append.left {
            return Err(Reason::SideOrder);
        }
        let s = m.applied_to(&rec.append).ok_or(Reason::OutOfRange)?;
        let step = Self::footstep(&s);
        let id = self.gait_id(m.id);
        self.check_reach(&step, Some(id))?;
        // A modification of the next swing target while walking plans (eq. 17).
        let plans = !self.gait.is_standing() && self.gait.next_target() == Some(id);
        if plans {
            self.plan()?;
        }
        let modified = self.gait.modify(id, step).map_err(reason_of);
        if plans {
            self.plans_left = self.plans_left.saturating_sub(1);
        }
        modified?;
        if let Some(r) = self.steps.queued_at_mut(at, m.id) {
            r.version = m.version;
            r.in_force = Some(*frame);
        }
        Ok(())
    }

    /// The clock check and the supervision rule (module docs, step 3): a moving robot whose
    /// controller has not been heard for longer than the timeout (by the clock or by the
    /// cycles), or whose clock has stopped, stops, and stays "controller lost". Checked in
    /// every cycle, so it holds for the whole walk.
    fn supervise(&mut self, now_ms: u32) {
        if self.cycle == 1 {
            self.window = (self.cycle, now_ms);
        } else if self.cycle.wrapping_sub(self.window.0) >= CLOCK_WINDOW {
            // At least half of the window's nominal time.
            let elapsed = now_ms.wrapping_sub(self.window.1);
            if elapsed < self.window_ms / 2 {
                self.clock_fault = true;
            }
            self.window = (self.cycle, now_ms);
        }
        if self.clock_fault && self.open {
            self.lost = true;
        }
        if self.gait.is_standing() {
            return;
        }
        let silent = match self.last_heard {
            Some(heard) => {
                now_ms.wrapping_sub(heard) > self.cfg.heartbeat_timeout_ms
                    || self.cycle.wrapping_sub(self.heard_cycle) > self.timeout_cycles
            }
            None => true,
        };
        if silent && !self.lost {
            self.lost = true;
        }
        if self.lost && (self.gait.queued() > 0 || !self.gait.is_stopping()) {
            self.gait.clear_and_stop();
            self.steps.sync(&self.gait, self.first);
        }
    }

    fn stream(&self, r: &Reference<T>) -> Stream<T> {
        let phase = match r.phase {
            Phase::Standing => 0,
            Phase::Double => 1,
            Phase::Single(Side::Left) => 2,
            Phase::Single(Side::Right) => 3,
        };
        let f = |k: usize| [r.feet[k].x, r.feet[k].y, r.feet[k].z, r.feet[k].yaw];
        Stream {
            cog: [r.x.cog, r.y.cog],
            cog_vel: [r.x.cog_vel, r.y.cog_vel],
            zmp: [r.x.zmp, r.y.zmp],
            phase,
            tick: (self.cycle & 0xFF) as u8,
            feet: [f(0), f(1)],
        }
    }

    /// Carries out (or refuses) the `i`-th command frame of the cycle, `decoded`, and queues
    /// its answer (`true`: accepted): a footstep command that arrived before a `StopNow`
    /// carried out in this cycle is refused `Stale` (the stop dropped it).
    fn act(
        &mut self,
        i: usize,
        f: &RawFrame,
        decoded: Result<Command, (Reason, u8)>,
        act: &mut Acting,
        now_ms: u32,
    ) -> bool {
        let footstep = matches!(decoded, Ok(Command::Append(_) | Command::Modify(_)));
        let ack = if footstep && act.stop_at.is_some_and(|s| i < s) {
            self.refuse(Reason::Stale);
            self.refusal(f, &decoded, Reason::Stale)
        } else {
            self.handle_command(f, decoded, now_ms)
        };
        if ack.reason.is_some() {
            act.refused = act.refused.saturating_add(1);
        }
        self.enqueue(ack.encode());
        ack.reason.is_none()
    }

    fn enqueue(&mut self, f: RawFrame) {
        if self.tx.push_back(f).is_err() {
            self.counters.tx_dropped = self.counters.tx_dropped.saturating_add(1);
        }
    }

    /// One control cycle (see the module docs).
    pub fn poll<C>(&mut self, now_ms: u32, can: &mut C) -> PollReport<T>
    where
        C: embedded_can::nb::Can,
    {
        self.cycle = self.cycle.wrapping_add(1);
        // 1. Receive: the node's frames of this cycle are held, the others counted.
        let mut batch: heapless::Vec<RawFrame, MAX_RX> = heapless::Vec::new();
        let (mut foreign, mut received) = (0usize, 0u8);
        let max_rx = self.cfg.max_rx.min(MAX_RX);
        while batch.len() < max_rx && foreign < self.cfg.max_foreign {
            match can.receive() {
                Ok(f) => {
                    received = received.saturating_add(1);
                    // Extended and remote frames are not ours either.
                    match RawFrame::from_frame(&f).filter(|r| ids::is_command(r.id)) {
                        Some(raw) => {
                            let _ = batch.push(raw);
                        }
                        None => {
                            self.counters.foreign = self.counters.foreign.saturating_add(1);
                            foreign += 1;
                        }
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    self.counters.bus_errors = self.counters.bus_errors.saturating_add(1);
                    break;
                }
            }
        }
        // 2. Act in priority order: emergency stops, stops now, then the rest as they came,
        // with the modifications of one step together, newest version first (the first one
        // accepted is in force, the older ones are then `Stale` by the version rule; a newer
        // one refused leaves an older one its turn). The order is read from the frames' bytes
        // (class, step number's low byte, version), each frame is read when it is acted on.
        let mut order: heapless::Vec<u8, MAX_RX> = heapless::Vec::new();
        let mut placed: u64 = 0;
        for pass in 0..3u8 {
            for (i, f) in batch.iter().enumerate() {
                if rank(f) != pass || placed & bit(i) != 0 {
                    continue;
                }
                let same_step = |g: &RawFrame| g.id == ids::STEP_MODIFY && g.data[0] == f.data[0];
                if f.id != ids::STEP_MODIFY || !batch.iter().skip(i + 1).any(same_step) {
                    placed |= bit(i);
                    let _ = order.push(i as u8);
                    continue;
                }
                loop {
                    let mut newest: Option<(usize, u8)> = None;
                    for (j, g) in batch.iter().enumerate().skip(i) {
                        let version = g.data[1] & 0x7F;
                        if placed & bit(j) == 0
                            && same_step(g)
                            && newest.is_none_or(|(_, v)| version > v)
                        {
                            newest = Some((j, version));
                        }
                    }
                    let Some((j, _)) = newest else {
                        break;
                    };
                    placed |= bit(j);
                    let _ = order.push(j as u8);
                }
            }
        }
        self.plans_left = self.cfg.max_plans;
        let mut act = Acting {
            refused: 0,
            stop_at: None,
        };
        for &i in &order {
            let i = usize::from(i);
            let Some(f) = batch.get(i) else {
                continue;
            };
            let decoded = Command::decode(f, self.next_step());
            if matches!(decoded, Ok(Command::EmergencyStop { .. })) {
                self.estop_now = true;
            }
            let stop_now = rank(f) == 1;
            let accepted = self.act(i, f, decoded, &mut act, now_ms);
            if stop_now && accepted {
                act.stop_at = Some(i);
            }
        }
        let refused = act.refused;
        self.estop_now = false;
        // (`Node::handle` outside a cycle: the budget of one.)
        self.plans_left = self.cfg.max_plans;
        // 3. Supervision, 4. the gait's tick (only in a session: nothing moves before it).
        self.supervise(now_ms);
        let streaming = self.open;
        let reference = if streaming {
            let r = self.gait.tick();
            self.steps.sync(&self.gait, self.first);
            r
        } else {
            *self.gait.last()
        };
        // A stale reference in the backlog is dropped: the new one supersedes it. (One pass
        // of pop and push rather than `Deque::retain`, whose heapless implementation keeps
        // panicking branches the optimiser cannot remove: see firmware/nopanic.)
        for _ in 0..self.tx.len() {
            if let Some(f) = self.tx.pop_front() {
                if matches!(
                    f.id,
                    ids::ACK | ids::STATUS | ids::DIAG | ids::LINK | ids::SESSION
                ) {
                    let _ = self.tx.push_back(f);
                }
            }
        }
        if streaming {
            for f in self.stream(&reference).encode() {
                self.enqueue(f);
            }
        }
        if self.cycle % 20 == 1 {
            let s = self.status().encode();
            self.enqueue(s);
            let d = self.diag().encode();
            self.enqueue(d);
            let e = self.session().encode();
            self.enqueue(e);
            if let Some(l) = self.link {
                self.enqueue(l.encode());
            }
        }
        let mut sent = 0u8;
        while let Some(raw) = self.tx.pop_front() {
            let Some(frame) = raw.to_frame::<C::Frame>() else {
                continue;
            };
            match can.transmit(&frame) {
                Ok(displaced) => {
                    sent = sent.saturating_add(1);
                    if let Some(d) = displaced.as_ref().and_then(RawFrame::from_frame) {
                        let _ = self.tx.push_front(d);
                        break;
                    }
                }
                Err(nb::Error::WouldBlock) => {
                    let _ = self.tx.push_front(raw);
                    break;
                }
                Err(nb::Error::Other(_)) => {
                    self.counters.bus_errors = self.counters.bus_errors.saturating_add(1);
                    let _ = self.tx.push_front(raw);
                    break;
                }
            }
        }
        PollReport {
            reference,
            received,
            refused,
            sent,
        }
    }
}
