//! The CAN message set (classic CAN: 11-bit identifiers, at most 8 data bytes, 1 Mbit/s).
//!
//! Every frame from the bus is validated once, here, by [`Command::decode`]: identifier, length,
//! and every field's range. What passes is a [`Command`] whose accessors cannot fail; what does
//! not is a [`Reason`] that the node sends back in an [`ids::ACK`] frame. The same message set
//! is described for CAN tools in `host-sim/can/walking.dbc` (a test checks that they agree).
//!
//! # Units (fixed point, little-endian, two's complement)
//! | quantity | unit | range |
//! |---|---|---|
//! | footstep x, y | 0.5 mm (17 bits) | −32.768 … +32.7675 m |
//! | modification dx, dy (from the appended x, y) | 0.5 mm (14 bits) | −4.096 … +4.0955 m |
//! | footstep yaw | 2π/4096 rad ≈ 1.53 mrad (12 bits) | [−π, π) (any heading, wrapped) |
//! | COG, ZMP position | 1 µm (32 bits) | ±2147 m |
//! | COG velocity | 0.1 mm/s (16 bits) | ±3.27 m/s |
//! | foot x, y | 0.1 mm (20 bits) | ±52.4 m |
//! | foot height | 0.5 mm (8 bits) | 0 … 127.5 mm |
//! | foot yaw | 1e-4 rad (16 bits) | ±3.27 rad |
//!
//! The paper's figures are given to 1 mm (positions) and 5 ms (times): footsteps travel at
//! 0.5 mm and the published references at 1 µm, far below what the robot can follow. The
//! footstep's 17-bit coordinates bound the walking area to ±32.77 m around the origin of the
//! node's world frame; a `Reset` while standing re-bases that frame (its origin moves to the
//! midpoint of the feet, its x axis to their mean heading: see `node`), so a longer walk is a
//! sequence of walks of at most that size. Every range is one definition shared by the
//! encoder ([`WireStep::from_si`]) and the decoder: what one accepts, the other does.
//!
//! # Sessions and freshness
//! Nothing old counts as new: every rule below holds by construction, with no window that a
//! wrapped or replayed copy could fall into.
//!
//! * **Session.** The node draws a 32-bit session epoch at start-up (from
//!   [`crate::node::NodeConfig::entropy`], which the firmware fills from its hardware random
//!   number generator) and adds one at every accepted `Reset`; it publishes the epoch in
//!   `SESSION` from its first cycle on. Every `CONTROL` frame carries the low 16 bits of the
//!   epoch it was sent in: another session's frame is refused [`Reason::WrongSession`]. After
//!   start-up no session is open: the node accepts only `ESTOP` and the `Reset` that opens
//!   one (the handshake), and sends no reference until then.
//! * **Control sequence.** `CONTROL` carries a 32-bit sequence number. A control command is
//!   taken only if its number is greater than that of every control command accepted since
//!   start-up (across sessions: the counter is never reset, and `SESSION` publishes the
//!   last one, so that a controller that restarts continues above it); a repeat of the last
//!   one is [`Reason::Duplicate`], an older one [`Reason::Stale`]. At one command a
//!   millisecond the counter lasts 49 days.
//! * **Step numbers.** Footsteps are numbered by the node's step counter, which runs on
//!   across `Reset`s (each skips 256 numbers, `node::SESSION_SKIP`) and restarts only with
//!   the node (at a number drawn from the entropy). A controller never sends a number 128 or
//!   more past the node's next one.
//!   A footstep frame carries the low byte of its 16-bit number; the high byte is not sent but
//!   enters the frame's CRC ([`crc8_keyed`], [`step_key`]). The node reads a footstep frame's
//!   number as the one with that low byte nearest to the next number it expects (`DIAG`
//!   publishes it; [`step_number`]): exact for every queued step. A copy of an older step whose low byte aliases
//!   (256 · k numbers earlier, k = 1 … 255) differs in the high byte only, and a CRC-8 detects
//!   every error confined to 8 consecutive bits: it is refused [`Reason::BadCrc`], always. A
//!   start-up numbers at most 65,535 steps (beyond, appends are refused
//!   [`Reason::Exhausted`]), so no two steps of a start-up share their 16 bits.
//!
//!   A number 128 or more past the node's next one (a controller's numbering bug: steps 0,
//!   then 256) is read the same way, as a number of another block, and is refused
//!   [`Reason::BadCrc`], where a gap within the window is [`Reason::SequenceGap`]. The node
//!   cannot tell that gap from a corrupted frame: for every frame exactly one high byte makes
//!   its CRC match (the key enters the CRC as one byte, and a CRC-8 maps the 256 values of a
//!   byte to 256 different CRCs), so "the CRC matches another block's key" is true of every
//!   corrupted frame as well, and answering it as a gap would tell a corrupted frame's sender
//!   its frame was numbered wrong. The answer stays [`Reason::BadCrc`]; the controller, which
//!   knows the number it sent, compares it with `DIAG`'s next step number (host-sim's `run`
//!   names such a refusal so).
//! * **Versions.** A footstep is appended once (`STEP_APPEND`, version 0) and may be modified
//!   (`STEP_MODIFY`) up to 127 times: a modification is taken only if its 7-bit version is
//!   greater than the step's version in force (no modulo: versions never wrap); an equal
//!   frame is [`Reason::Duplicate`], an older version [`Reason::Stale`]. The modification
//!   carries its position as the offset from the appended position, its heading absolute;
//!   [`StepBook`] keeps what a controller needs for that.
//! * **Measured state.** `MEASURED` names the node cycle whose reference it was measured
//!   against (24 bits: exact for a start-up's first 2²⁴ cycles, 23.3 hours; beyond, refused
//!   [`Reason::Exhausted`]) and its CRC is keyed with the session: it is taken only if it is
//!   at most [`crate::node::AdjustConfig::max_age`] cycles old, newer than the last
//!   one taken, of the open session, and (with [`crate::node::AdjustConfig::from_measured`])
//!   not from before the reference stepped to the measured state. It never proves the
//!   controller alive.
//! * **`ESTOP`** belongs to no session on purpose: any frame on its identifier with the right
//!   length stops the robot, in the cycle it is received (a stop is always safe), and proves
//!   nothing about the controller. **A controller repeats an `ESTOP` (every cycle, 5 ms)
//!   until it receives its `ACK`** (accepted, or `Duplicate`: the node was stopped already):
//!   a frame can be lost on any bus, and a node off the bus (bus-off) hears nothing until it
//!   is back; an `ESTOP` sent then is heard when it is back, and the node has stopped by
//!   then on its own (a link off the bus for more than
//!   [`crate::node::OFF_BUS_CYCLES`] cycles stops a moving robot).
//!
//! # End-to-end protection (CRC-8)
//! CAN's own CRC-15 catches errors on the wire, not a frame a faulty gateway or controller
//! corrupts before it is sent. `CONTROL`, `STEP_APPEND`, `STEP_MODIFY`, `MEASURED`, `ACK` and `ADJUST` therefore
//! end with a CRC-8 (AUTOSAR profile: polynomial 0x2F, initial value and final XOR 0xFF; Hamming
//! distance 4 up to 119 data bits, so every 1-, 2- and 3-bit error of these frames is caught)
//! computed over the identifier (two bytes, little-endian: a frame moved to another identifier
//! fails), for the footstep frames the key of the step number ([`step_key`]), then the data
//! bytes before the CRC. The key is read from the frame's low byte, so an error in that byte
//! that moves the number into the neighbouring block of 256 also changes one bit of the key:
//! such an error of three bits weighs four, and is caught except by chance (the exhaustive
//! test counts them; every error of one or two bits is caught). A command with a wrong CRC is
//! refused
//! with [`Reason::BadCrc`] and changes nothing; the controller sends it again. `ESTOP` has no
//! CRC on purpose: any frame on its identifier with the right length stops the robot (a
//! corrupted emergency stop errs on the safe side; the length is kept, so that no corrupted
//! command of another identifier can become one: see the exhaustive 3-bit test). The stream,
//! `STATUS` and `SESSION` carry none: every value is superseded 5 ms (100 ms) later.
//!
//! The `ACK` echoes the last byte of the frame it answers (the CRC, for the protected
//! commands), so the controller knows *which version* of a command was taken — a modification
//! answered while a newer one for the same step is on its way is not mistaken for the newer
//! one.
//!
//! # Frames
//! Lower identifiers win arbitration, so commands come first, then answers, then the stream.
//! The commands' identifiers differ pairwise in at least four bits, so that no error of up to
//! three bits moves a frame to another command's identifier.
//!
//! | id | name | dir | dlc | layout |
//! |---|---|---|---|---|
//! | 0x010 | `ESTOP` | in | 1 | seq u8 |
//! | 0x020 | `CONTROL` | in | 8 | session u16, seq u32, op u8 (0 heartbeat, 1 start, 2 stop, 3 stop now, 4 reset, 5 start with step adjustment), crc u8 |
//! | 0x02F | `VELOCITY` | in | 8 | seq's low 16 bits u16, seq's bits 16–23 XOR the session's second byte u8, vx i11, vy i11 (1 mm/s), ω i10 (2 mrad/s), crc u8 keyed with the session's low byte and the seq's high byte (see `drive.rs`) |
//! | 0x046 | `GOAL` | in | 8 | seq's low 24 bits as `VELOCITY`'s, x i11, y i11 (1 cm), θ i10 (2π/1024 rad), crc u8 keyed as `VELOCITY`'s |
//! | 0x100 | `STEP_APPEND` | in | 8 | step number's low byte u8, left u1, reserved u1 (0), x i17, y i17, yaw i12, crc u8 |
//! | 0x101 | `STEP_MODIFY` | in | 8 | step number's low byte u8, version u7, left u1, dx i14, dy i14, yaw i12, crc u8 |
//! | 0x0D8 | `MEASURED` | in | 8 | stamp u24 (the node cycle measured against), DCM deviation from that cycle's reference x i15, y i15 (0.1 mm), reserved u2 (0), crc u8 keyed with the session (see `measured.rs`) |
//! | 0x090 | `ADJUST` | out | 8 | first step number's low byte u8, shift x i16, y i16 (0.5 mm), adjustments u8, flags u8, crc u8 |
//! | 0x080 | `ACK` | out | 7 | command code u8, seq's or step number's low byte u8, reason u8 (0 = accepted), queue length u8, echo u8, step version in force u8 (0xFF: none), crc u8 |
//! | 0x200 | `COG` | out | 8 | x i32 µm, y i32 µm |
//! | 0x201 | `ZMP` | out | 8 | x i32 µm, y i32 µm |
//! | 0x202 | `COG_VEL` | out | 8 | vx i16, vy i16 (0.1 mm/s), phase u8, tick u24 (the low 24 bits of the node's cycle) |
//! | 0x210 | `FOOT_LEFT` | out | 8 | x i20, y i20, z u8 (0.5 mm), yaw i16 (1e-4 rad) |
//! | 0x211 | `FOOT_RIGHT` | out | 8 | as `FOOT_LEFT` |
//! | 0x300 | `STATUS` | out | 8 | state u8, queue u8, rejected u16, overruns u16, last adjustment i8 (5 ms), flags u8 (shaping u1, re-plan failed u1, tx overflow u1, next side u2, clock fault u1, velocity cut u1, at goal u1) |
//! | 0x301 | `DIAG` | out | 8 | foreign u16, bus errors u16, tx dropped u16, next step number u16 |
//! | 0x302 | `LINK` | out | 8 | TEC u8, REC u7, receive passive u1, bus state u2, reset reason u4, message RAM faults u2, bus-offs u16, error-passive episodes u12, bus-off back-off u4, missed slots u8 |
//! | 0x303 | `SESSION` | out | 8 | session epoch u32, last accepted control seq u32 (0: none) |
//!
//! `STATUS`, `DIAG`, `SESSION` (and `LINK`) go out in the node's first cycle and every 20
//! cycles after it. `LINK` is the firmware's: the node sends it (with `STATUS` and `DIAG`) only once the
//! firmware has told it the link's health ([`crate::node::Node::set_link_health`]); a node
//! without a CAN controller of its own (host-sim) never sends it.
//!
//! The node's own commands are [`ids::COMMANDS`]; a frame on any other identifier (or an
//! extended or remote frame) is not the node's: it is counted and never answered (every CAN
//! backend also filters the bus for exactly [`ids::COMMANDS`] in hardware where it can).
//!
//! Bits of a 64-bit field group are packed from the least significant bit of byte 0 upwards.
//!
//! # Files
//! * `mod.rs` (this file): the identifiers ([`ids`]), [`RawFrame`], the refusal [`Reason`]s and
//!   the CRC-8 ([`crc8`]);
//! * `step.rs`: the footstep units and field widths, [`WireStep`] (`STEP_APPEND`),
//!   [`WireModify`] (`STEP_MODIFY`) and the controller's [`StepBook`];
//! * `drive.rs`: the commands with which the node chooses the footsteps itself,
//!   [`WireVelocity`] (`VELOCITY`) and [`WireGoal`] (`GOAL`);
//! * `command.rs`: [`ControlOp`], the validated [`Command`] (decoded once, at the edge) and
//!   its answer, [`Ack`];
//! * `status.rs`: the node's periodic reports [`Status`], [`Diag`], [`LinkHealth`] and
//!   [`Session`];
//! * `stream.rs`: the 5 ms reference [`Stream`] and its fixed-point encoding;
//! * `measured.rs`: the robot's measured state from its estimator ([`Measured`]) and the
//!   node's step adjustment ([`Adjust`]);
//! * `tests.rs`: the unit tests of the message set.

mod command;
mod drive;
mod measured;
mod status;
mod step;
mod stream;
#[cfg(test)]
mod tests;

pub use command::{echo_of, step_number, Ack, Command, ControlOp, Expect};
pub use drive::{
    seq_number, WireGoal, WireVelocity, DRIVE_BITS, DRIVE_TURN_BITS, GOAL_UNIT, GOAL_YAW_UNIT,
    SEQ_ADVANCE, SEQ_WINDOW, SPEED_UNIT, TURN_UNIT,
};
pub use measured::{Adjust, Measured, DEVIATION_BITS, DEVIATION_UNIT, STAMPS};
pub use status::{Diag, LinkHealth, Session, Status};
pub use step::{
    signed_range, StepBook, WireModify, WireStep, FOOT_UNIT, OFFSET_BITS, STEP_BITS, STEP_UNIT,
    VERSIONS, YAW_BITS, YAW_UNIT,
};
pub use stream::Stream;

/// The identifiers of the message set.
pub mod ids {
    /// Emergency stop (controller → node).
    pub const ESTOP: u16 = 0x010;
    /// Start, stop, heartbeat, reset (controller → node).
    pub const CONTROL: u16 = 0x020;
    /// Walk at a velocity (controller → node), a stream: see [`super::WireVelocity`].
    pub const VELOCITY: u16 = 0x02F;
    /// Walk to a relative goal (controller → node): see [`super::WireGoal`].
    pub const GOAL: u16 = 0x046;
    /// Acknowledge or reject a command (node → controller).
    pub const ACK: u16 = 0x080;
    /// Append a footstep (controller → node).
    pub const STEP_APPEND: u16 = 0x100;
    /// Modify a queued footstep (controller → node).
    pub const STEP_MODIFY: u16 = 0x101;
    /// The robot's measured state (state estimator → node), up to every 5 ms.
    pub const MEASURED: u16 = 0x0D8;
    /// The node's step adjustment: the shift of the steps from a step number on (node →
    /// controller), when it changes and every 100 ms.
    pub const ADJUST: u16 = 0x090;
    /// COG position reference, every 5 ms.
    pub const COG: u16 = 0x200;
    /// ZMP reference, every 5 ms.
    pub const ZMP: u16 = 0x201;
    /// COG velocity, phase and tick counter, every 5 ms.
    pub const COG_VEL: u16 = 0x202;
    /// Left foot pose, every 5 ms.
    pub const FOOT_LEFT: u16 = 0x210;
    /// Right foot pose, every 5 ms.
    pub const FOOT_RIGHT: u16 = 0x211;
    /// Node status (also the node's heartbeat), every 100 ms.
    pub const STATUS: u16 = 0x300;
    /// Node diagnostics (foreign frames, bus errors, what the node expects next), every 100 ms.
    pub const DIAG: u16 = 0x301;
    /// Link health of the board (CAN error counters, bus state, reset reason), every 100 ms
    /// once the firmware reports it.
    pub const LINK: u16 = 0x302;
    /// The session epoch and the last accepted control sequence number, every 100 ms.
    pub const SESSION: u16 = 0x303;

    /// The identifiers the node receives (its commands and the measured state): everything
    /// else on the bus is not its business.
    pub const COMMANDS: [u16; 7] = [
        ESTOP,
        CONTROL,
        VELOCITY,
        GOAL,
        MEASURED,
        STEP_APPEND,
        STEP_MODIFY,
    ];

    /// `true` for one of [`COMMANDS`].
    pub fn is_command(id: u16) -> bool {
        COMMANDS.contains(&id)
    }
}

/// A classic CAN data frame with a standard identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawFrame {
    /// 11-bit identifier.
    pub id: u16,
    /// Data length (0 … 8).
    pub len: u8,
    /// Data; bytes past `len` are zero.
    pub data: [u8; 8],
}

impl RawFrame {
    /// A frame from an identifier and up to 8 bytes; `None` if either is out of range.
    pub fn new(id: u16, data: &[u8]) -> Option<Self> {
        if id > 0x7FF || data.len() > 8 {
            return None;
        }
        // All 8 bytes, each taken or zero (a fixed-length loop: no `memcpy` call for a
        // length known only here).
        let d: [u8; 8] = core::array::from_fn(|i| data.get(i).copied().unwrap_or(0));
        Some(Self {
            id,
            len: data.len() as u8,
            data: d,
        })
    }

    /// The data bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.len.min(8))]
    }

    /// From any `embedded-can` frame: `None` for extended or remote frames.
    pub fn from_frame<F: embedded_can::Frame>(f: &F) -> Option<Self> {
        match f.id() {
            embedded_can::Id::Standard(id) if f.is_data_frame() => Self::new(id.as_raw(), f.data()),
            _ => None,
        }
    }

    /// Into any `embedded-can` frame type.
    pub fn to_frame<F: embedded_can::Frame>(&self) -> Option<F> {
        let id = embedded_can::StandardId::new(self.id)?;
        F::new(id, self.bytes())
    }

    /// Worst-case length on the wire in bits, with bit stuffing (classic CAN, standard id):
    /// `47 + 8n` bits of frame plus at most `⌊(34 + 8n − 1)/4⌋` stuff bits.
    pub fn wire_bits(&self) -> u32 {
        let n = u32::from(self.len);
        47 + 8 * n + (34 + 8 * n - 1) / 4
    }
}

/// `RawFrame` is itself an `embedded-can` frame (standard identifiers, data frames only), so
/// test devices, the virtual bus and the fuzzers need no frame type of their own.
impl embedded_can::Frame for RawFrame {
    fn new(id: impl Into<embedded_can::Id>, data: &[u8]) -> Option<Self> {
        match id.into() {
            embedded_can::Id::Standard(s) => RawFrame::new(s.as_raw(), data),
            embedded_can::Id::Extended(_) => None,
        }
    }
    fn new_remote(_: impl Into<embedded_can::Id>, _: usize) -> Option<Self> {
        None
    }
    fn is_extended(&self) -> bool {
        false
    }
    fn is_remote_frame(&self) -> bool {
        false
    }
    fn id(&self) -> embedded_can::Id {
        let id = embedded_can::StandardId::new(self.id).unwrap_or(embedded_can::StandardId::ZERO);
        embedded_can::Id::Standard(id)
    }
    fn dlc(&self) -> usize {
        usize::from(self.len.min(8))
    }
    fn data(&self) -> &[u8] {
        self.bytes()
    }
}

/// Why a command was refused. `0` on the wire means accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Reason {
    /// The identifier is not a command of this node. [`Command::decode`] says so; the node
    /// never answers such a frame (it is not its business: counted in `DIAG`).
    UnknownId = 1,
    /// The data length does not match the message.
    BadLength = 2,
    /// A field has a value outside its range (e.g. an unknown control operation, reserved bits
    /// set).
    OutOfRange = 3,
    /// The footstep queue is full.
    QueueFull = 4,
    /// The footstep has the same side as the one before it.
    SideOrder = 5,
    /// No queued step has this id (never queued, or already executed).
    UnknownStep = 6,
    /// The step is being swung: its foot has lifted off.
    LiftedOff = 7,
    /// The modification would put the ZMP outside the support foot even after adjustment.
    Infeasible = 8,
    /// The command is not valid in the present state.
    WrongState = 9,
    /// The step id is not the one after the last appended id.
    SequenceGap = 10,
    /// The frame equals the command in force (a repeat of the last accepted control
    /// command, of an accepted append, of a step's version in force): nothing to do.
    Duplicate = 11,
    /// The footstep is out of the leg's reach from the previous one.
    Reach = 12,
    /// The footstep crosses the other foot.
    Crossing = 13,
    /// Emergency-stopped: only a reset is accepted once standing.
    EmergencyStopped = 14,
    /// The planner could not plan (numerically); the previous plan goes on.
    PlanFailed = 15,
    /// The frame's CRC-8 does not match its identifier and data (see the module docs).
    BadCrc = 16,
    /// Older than what is in force: a modification whose version is below the step's
    /// version in force (or a newer modification of the same step received in the same cycle
    /// was accepted), a footstep frame that arrived before a `StopNow` carried out in the same
    /// cycle, a control command whose sequence number is below the last accepted one, a
    /// measured state older than the node's limit or than the last one taken (or measured
    /// against a reference from before the window re-planned from the measured state).
    Stale = 17,
    /// The controller fell silent while the robot walked (or the node's clock stopped):
    /// motion commands are refused until a `Reset` once standing.
    ControllerLost = 18,
    /// The `CONTROL` frame belongs to another session (before the last `Reset`, or another
    /// start-up of the node); a `VELOCITY` or `GOAL` read more than [`SEQ_ADVANCE`] above the
    /// last accepted sequence number (sent for another session); a measured state stamped
    /// before the session opened.
    WrongSession = 19,
    /// No session is open (after start-up): only a `Reset` (the handshake) and `ESTOP` are
    /// taken.
    NoSession = 20,
    /// A counter would run out: the start-up's 65,535 step numbers, a step's 127 versions,
    /// the 2³² sessions or sequence numbers, the 2²⁴ cycles whose measured states a start-up
    /// takes.
    Exhausted = 21,
    /// The cycle's planning budget is spent (one `Start` or modification of the next swing
    /// target a cycle), or a `Stop` would change the plan of a cycle whose re-plan a command
    /// has already planned: send it again.
    Busy = 22,
}

impl Reason {
    /// Every reason, in code order.
    pub const ALL: [Reason; 22] = [
        Reason::UnknownId,
        Reason::BadLength,
        Reason::OutOfRange,
        Reason::QueueFull,
        Reason::SideOrder,
        Reason::UnknownStep,
        Reason::LiftedOff,
        Reason::Infeasible,
        Reason::WrongState,
        Reason::SequenceGap,
        Reason::Duplicate,
        Reason::Reach,
        Reason::Crossing,
        Reason::EmergencyStopped,
        Reason::PlanFailed,
        Reason::BadCrc,
        Reason::Stale,
        Reason::ControllerLost,
        Reason::WrongSession,
        Reason::NoSession,
        Reason::Exhausted,
        Reason::Busy,
    ];

    /// One more than the largest code (the size of a table indexed by code).
    pub const CODES: usize = 23;

    /// The wire code.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// From a wire code (`None` for 0 = accepted, and unknown codes).
    pub fn from_code(c: u8) -> Option<Self> {
        Self::ALL.iter().copied().find(|r| r.code() == c)
    }
}

/// CRC-8 of a frame's identifier and data (AUTOSAR profile: polynomial 0x2F, initial value
/// 0xFF, no reflection, final XOR 0xFF). The identifier enters as two little-endian bytes.
pub fn crc8(id: u16, data: &[u8]) -> u8 {
    crc8_over(id, None, data)
}

/// CRC-8 of a footstep or measured-state frame: [`crc8`] with `key` ([`step_key`] of the step number, not sent)
/// between the identifier and the data. A copy that differs from the expected frame only in
/// the key differs in 8 consecutive bits of the CRC's input, and a CRC with 8 check bits
/// detects every such error: it never passes.
pub fn crc8_keyed(id: u16, key: u8, data: &[u8]) -> u8 {
    crc8_over(id, Some(key), data)
}

/// The CRC key of step number `number`: the Gray code of its high byte. Neighbouring blocks of
/// 256 numbers differ in one bit of their key, so that a bit error in a frame's low byte that
/// moves it into the neighbouring block costs the error one bit more, not up to eight.
pub fn step_key(number: u16) -> u8 {
    let h = (number >> 8) as u8;
    h ^ (h >> 1)
}

fn crc8_over(id: u16, key: Option<u8>, data: &[u8]) -> u8 {
    let step = |mut c: u8, b: u8| {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0x2F
            } else {
                c << 1
            };
        }
        c
    };
    let [lo, hi] = id.to_le_bytes();
    let mut c = step(step(0xFF, lo), hi);
    if let Some(k) = key {
        c = step(c, k);
    }
    let c = data.iter().fold(c, |c, &b| step(c, b));
    c ^ 0xFF
}

/// CRC-8 of the bytes of `data` without the last one, as it is sent: a frame whose last byte
/// is this CRC is intact. `data` must not be empty.
fn crc_ok(id: u16, data: &[u8]) -> bool {
    crc_ok_over(id, None, data)
}

fn crc_ok_over(id: u16, key: Option<u8>, data: &[u8]) -> bool {
    match data.split_last() {
        Some((&c, body)) => crc8_over(id, key, body) == c,
        None => false,
    }
}
