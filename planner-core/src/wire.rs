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
//! # Versions of a footstep
//! A footstep is appended once (`STEP_APPEND`, version 0) and may be modified many times
//! (`STEP_MODIFY`); each modification carries a 7-bit version, one more (modulo 128) than the
//! one before it for that step. The node takes a modification only if its version is newer
//! than the version in force (1 … 63 ahead, modulo 128): an older modification that arrives
//! late (overtaken by a newer one for the same step) is refused with [`Reason::Stale`], so the
//! step is always walked at the newest version the node accepted. A frame equal to the version
//! in force (or to the step's append) is answered [`Reason::Duplicate`]. The modification
//! carries its position as the offset from the appended position (that makes room for the
//! version), its heading absolute; [`StepBook`] keeps what a controller needs for that.
//!
//! # End-to-end protection (CRC-8)
//! CAN's own CRC-15 catches errors on the wire, not a frame a faulty gateway or controller
//! corrupts before it is sent. `CONTROL`, `STEP_APPEND`, `STEP_MODIFY` and `ACK` therefore
//! end with a CRC-8 (AUTOSAR profile: polynomial 0x2F, initial value and final XOR 0xFF; Hamming
//! distance 4 up to 119 data bits, so every 1-, 2- and 3-bit error of these frames is caught)
//! computed over the identifier (two bytes, little-endian: a frame moved to another identifier
//! fails) followed by the data bytes before the CRC. A command with a wrong CRC is refused
//! with [`Reason::BadCrc`] and changes nothing; the controller sends it again. `ESTOP` has no
//! CRC on purpose: any frame on its identifier with the right length stops the robot (a
//! corrupted emergency stop errs on the safe side; the length is kept, so that no corrupted
//! command of another identifier can become one: see the exhaustive 3-bit test). The stream and `STATUS` carry none: every
//! value is superseded 5 ms (100 ms) later.
//!
//! The `ACK` echoes the last byte of the frame it answers (the CRC, for the protected
//! commands), so the controller knows *which version* of a command was taken — a modification
//! answered while a newer one for the same step is on its way is not mistaken for the newer
//! one.
//!
//! # Frames
//! Lower identifiers win arbitration, so commands come first, then answers, then the stream.
//!
//! | id | name | dir | dlc | layout |
//! |---|---|---|---|---|
//! | 0x010 | `ESTOP` | in | 1 | seq u8 |
//! | 0x020 | `CONTROL` | in | 3 | seq u8, op u8 (0 heartbeat, 1 start, 2 stop, 3 stop now, 4 reset), crc u8 |
//! | 0x100 | `STEP_APPEND` | in | 8 | step id u8, left u1, reserved u1 (0), x i17, y i17, yaw i12, crc u8 |
//! | 0x101 | `STEP_MODIFY` | in | 8 | step id u8, version u7, left u1, dx i14, dy i14, yaw i12, crc u8 |
//! | 0x080 | `ACK` | out | 7 | command code u8, seq/step id u8, reason u8 (0 = accepted), queue length u8, echo u8, step version in force u8 (0xFF: none), crc u8 |
//! | 0x200 | `COG` | out | 8 | x i32 µm, y i32 µm |
//! | 0x201 | `ZMP` | out | 8 | x i32 µm, y i32 µm |
//! | 0x202 | `COG_VEL` | out | 6 | vx i16, vy i16 (0.1 mm/s), phase u8, tick u8 |
//! | 0x210 | `FOOT_LEFT` | out | 8 | x i20, y i20, z u8 (0.5 mm), yaw i16 (1e-4 rad) |
//! | 0x211 | `FOOT_RIGHT` | out | 8 | as `FOOT_LEFT` |
//! | 0x300 | `STATUS` | out | 8 | state u8, queue u8, rejected u16, overruns u16, last adjustment i8 (5 ms), flags u8 |
//! | 0x301 | `DIAG` | out | 8 | foreign u16, bus errors u16, tx dropped u16, next side u8, last control seq u8 |
//! | 0x302 | `LINK` | out | 8 | TEC u8, REC u7, receive passive u1, bus state u2, reset reason u4, reserved u2 (0), bus-offs u16, error-passive episodes u16, missed slots u8 |
//!
//! `LINK` is the firmware's: the node sends it (with `STATUS` and `DIAG`) only once the
//! firmware has told it the link's health ([`crate::node::Node::set_link_health`]); a node
//! without a CAN controller of its own (host-sim) never sends it.
//!
//! The node's own commands are [`ids::COMMANDS`]; a frame on any other identifier (or an
//! extended or remote frame) is not the node's: it is counted and never answered (every CAN
//! backend also filters the bus for exactly [`ids::COMMANDS`] in hardware where it can).
//!
//! Bits of a 64-bit field group are packed from the least significant bit of byte 0 upwards.

/// The identifiers of the message set.
pub mod ids {
    /// Emergency stop (controller → node).
    pub const ESTOP: u16 = 0x010;
    /// Start, stop, heartbeat, reset (controller → node).
    pub const CONTROL: u16 = 0x020;
    /// Acknowledge or reject a command (node → controller).
    pub const ACK: u16 = 0x080;
    /// Append a footstep (controller → node).
    pub const STEP_APPEND: u16 = 0x100;
    /// Modify a queued footstep (controller → node).
    pub const STEP_MODIFY: u16 = 0x101;
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

    /// The identifiers the node receives: everything else on the bus is not its business.
    pub const COMMANDS: [u16; 4] = [ESTOP, CONTROL, STEP_APPEND, STEP_MODIFY];

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
        let mut d = [0u8; 8];
        d[..data.len()].copy_from_slice(data);
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
    /// Older than the command in force: a modification whose version is not newer than the
    /// step's version in force, or a `Start`/`Reset` whose sequence number is behind the last
    /// accepted control command (a late copy overtaken by newer commands).
    Stale = 17,
    /// The controller fell silent while the robot walked: motion commands are refused until
    /// a `Reset` once standing.
    ControllerLost = 18,
}

impl Reason {
    /// Every reason, in code order.
    pub const ALL: [Reason; 18] = [
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
    ];

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
    let c = data
        .iter()
        .fold(step(step(0xFF, lo), hi), |c, &b| step(c, b));
    c ^ 0xFF
}

/// CRC-8 of the bytes of `data` without the last one, as it is sent: a frame whose last byte
/// is this CRC is intact. `data` must not be empty.
fn crc_ok(id: u16, data: &[u8]) -> bool {
    match data.split_last() {
        Some((&c, body)) => crc8(id, body) == c,
        None => false,
    }
}

/// Control operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ControlOp {
    /// Keep-alive: the controller is there.
    Heartbeat,
    /// Start walking with the queued steps.
    Start,
    /// Walk the queued steps, then stop.
    Stop,
    /// Drop the queue and stop as soon as possible.
    StopNow,
    /// Leave the emergency-stopped state (only when standing).
    Reset,
}

impl ControlOp {
    fn code(self) -> u8 {
        match self {
            ControlOp::Heartbeat => 0,
            ControlOp::Start => 1,
            ControlOp::Stop => 2,
            ControlOp::StopNow => 3,
            ControlOp::Reset => 4,
        }
    }
    fn from_code(c: u8) -> Option<Self> {
        Some(match c {
            0 => ControlOp::Heartbeat,
            1 => ControlOp::Start,
            2 => ControlOp::Stop,
            3 => ControlOp::StopNow,
            4 => ControlOp::Reset,
            _ => return None,
        })
    }
}

/// Largest magnitude of a 20-bit field.
const I20_MAX: i32 = (1 << 19) - 1;
/// Footstep yaw unit \[rad\].
pub const YAW_UNIT: f64 = core::f64::consts::TAU / 4096.0;
/// Footstep position unit \[m\].
pub const STEP_UNIT: f64 = 5e-4;
/// Foot position unit of the stream \[m\].
pub const FOOT_UNIT: f64 = 1e-4;
/// Bits of a footstep coordinate (x, y of `STEP_APPEND`).
pub const STEP_BITS: u32 = 17;
/// Bits of a modification's offset (dx, dy of `STEP_MODIFY`).
pub const OFFSET_BITS: u32 = 14;
/// Bits of a footstep heading.
pub const YAW_BITS: u32 = 12;
/// Modification versions are counted modulo this.
pub const VERSIONS: u8 = 128;

/// The range of a signed `bits`-bit field: `(min, max)`, two's complement. The one definition
/// used by the encoders and the decoders.
pub const fn signed_range(bits: u32) -> (i32, i32) {
    (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
}

/// `v` in `unit`s, rounded, if finite and inside a signed `bits`-bit field.
fn quantise(v: f64, unit: f64, bits: u32) -> Option<i32> {
    let (min, max) = signed_range(bits);
    let r = libm::round(v / unit);
    (v.is_finite() && r >= f64::from(min) && r <= f64::from(max)).then_some(r as i32)
}

/// A heading in `YAW_UNIT`s, wrapped into the 12-bit field: every finite heading has one
/// (±π, and π − half a unit, become −2048 = −π).
fn quantise_yaw(yaw: f64) -> Option<i16> {
    if !yaw.is_finite() {
        return None;
    }
    let turns = 1i64 << YAW_BITS;
    let w = libm::remainder(yaw, core::f64::consts::TAU); // [−π, π]
    let r = libm::round(w / YAW_UNIT) as i64;
    let r = (r + turns / 2).rem_euclid(turns) - turns / 2;
    Some(r as i16)
}

/// Sign-extends the low `n` bits of `v`.
fn sign_extend(v: u64, n: u32) -> i32 {
    ((v << (64 - n)) as i64 >> (64 - n)) as i32
}

/// `v` as an `n`-bit two's complement field.
fn field(v: i32, n: u32) -> u64 {
    (v as i64 as u64) & ((1u64 << n) - 1)
}

/// A footstep as carried by `STEP_APPEND` (fixed point, see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireStep {
    /// Step id.
    pub id: u8,
    /// `true` for the left foot.
    pub left: bool,
    /// x in 0.5 mm (17 bits).
    pub x: i32,
    /// y in 0.5 mm (17 bits).
    pub y: i32,
    /// yaw in 2π/4096 rad (12 bits).
    pub yaw: i16,
}

impl WireStep {
    /// A footstep in SI units, rounded to the wire units; `None` if a coordinate is out of
    /// range or a value not finite. Any finite heading is representable (wrapped into
    /// [−π, π)).
    pub fn from_si(id: u8, left: bool, x: f64, y: f64, yaw: f64) -> Option<Self> {
        Some(Self {
            id,
            left,
            x: quantise(x, STEP_UNIT, STEP_BITS)?,
            y: quantise(y, STEP_UNIT, STEP_BITS)?,
            yaw: quantise_yaw(yaw)?,
        })
    }

    /// x, y \[m\] and yaw \[rad\].
    pub fn si(&self) -> (f64, f64, f64) {
        (
            f64::from(self.x) * STEP_UNIT,
            f64::from(self.y) * STEP_UNIT,
            f64::from(self.yaw) * YAW_UNIT,
        )
    }

    /// `true` when every field is inside its range (what the decoder produces).
    pub fn in_range(&self) -> bool {
        let (min, max) = signed_range(STEP_BITS);
        let (ymin, ymax) = signed_range(YAW_BITS);
        (min..=max).contains(&self.x)
            && (min..=max).contains(&self.y)
            && (ymin..=ymax).contains(&i32::from(self.yaw))
    }

    /// The 8 data bytes of a `STEP_APPEND` frame (CRC in the last byte).
    fn pack(&self) -> [u8; 8] {
        let mut bits: u64 = u64::from(self.id);
        bits |= u64::from(self.left as u8) << 8;
        bits |= field(self.x, STEP_BITS) << 10;
        bits |= field(self.y, STEP_BITS) << 27;
        bits |= field(i32::from(self.yaw), YAW_BITS) << 44;
        let mut d = bits.to_le_bytes();
        d[7] = crc8(ids::STEP_APPEND, &d[..7]);
        d
    }

    /// Fields of a `STEP_APPEND` frame whose CRC was checked.
    fn unpack(data: &[u8; 8]) -> Result<Self, Reason> {
        let bits = u64::from_le_bytes(*data);
        if (bits >> 9) & 1 != 0 {
            return Err(Reason::OutOfRange);
        }
        Ok(Self {
            id: (bits & 0xFF) as u8,
            left: (bits >> 8) & 1 == 1,
            x: sign_extend(bits >> 10, STEP_BITS),
            y: sign_extend(bits >> 27, STEP_BITS),
            yaw: sign_extend(bits >> 44, YAW_BITS) as i16,
        })
    }
}

/// A modification as carried by `STEP_MODIFY`: the step's new version, its position as the
/// offset from where it was appended, its heading absolute (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireModify {
    /// Step id.
    pub id: u8,
    /// Version, 0 … 127 (one more than the step's previous version, modulo 128; the append
    /// is version 0).
    pub version: u8,
    /// `true` for the left foot (a modification cannot change the side).
    pub left: bool,
    /// x offset from the appended x, in 0.5 mm (14 bits).
    pub dx: i32,
    /// y offset from the appended y, in 0.5 mm (14 bits).
    pub dy: i32,
    /// yaw in 2π/4096 rad (12 bits).
    pub yaw: i16,
}

impl WireModify {
    /// The modification of the step appended as `base` to the pose `(x, y, yaw)` \[m, rad\],
    /// as version `version`; `None` if the offset is out of range or a value not finite.
    pub fn from_si(base: &WireStep, version: u8, x: f64, y: f64, yaw: f64) -> Option<Self> {
        // Offsets on the wire grid: the new position rounded, minus the appended one.
        let x = quantise(x, STEP_UNIT, STEP_BITS)?;
        let y = quantise(y, STEP_UNIT, STEP_BITS)?;
        let (min, max) = signed_range(OFFSET_BITS);
        let (dx, dy) = (x - base.x, y - base.y);
        ((min..=max).contains(&dx) && (min..=max).contains(&dy)).then_some(Self {
            id: base.id,
            version: version % VERSIONS,
            left: base.left,
            dx,
            dy,
            yaw: quantise_yaw(yaw)?,
        })
    }

    /// The footstep this modification makes of the step appended as `base`: `None` if the
    /// result leaves the footstep coordinate range.
    pub fn applied_to(&self, base: &WireStep) -> Option<WireStep> {
        let s = WireStep {
            id: self.id,
            left: self.left,
            x: base.x.checked_add(self.dx)?,
            y: base.y.checked_add(self.dy)?,
            yaw: self.yaw,
        };
        s.in_range().then_some(s)
    }

    /// `true` if `self.version` is newer than `current` (1 … 63 ahead, modulo 128).
    pub fn is_newer_than(&self, current: u8) -> bool {
        let d = self.version.wrapping_sub(current) % VERSIONS;
        (1..VERSIONS / 2).contains(&d)
    }

    fn pack(&self) -> [u8; 8] {
        let mut bits: u64 = u64::from(self.id);
        bits |= u64::from(self.version % VERSIONS) << 8;
        bits |= u64::from(self.left as u8) << 15;
        bits |= field(self.dx, OFFSET_BITS) << 16;
        bits |= field(self.dy, OFFSET_BITS) << 30;
        bits |= field(i32::from(self.yaw), YAW_BITS) << 44;
        let mut d = bits.to_le_bytes();
        d[7] = crc8(ids::STEP_MODIFY, &d[..7]);
        d
    }

    fn unpack(data: &[u8; 8]) -> Self {
        let bits = u64::from_le_bytes(*data);
        Self {
            id: (bits & 0xFF) as u8,
            version: ((bits >> 8) & 0x7F) as u8,
            left: (bits >> 15) & 1 == 1,
            dx: sign_extend(bits >> 16, OFFSET_BITS),
            dy: sign_extend(bits >> 30, OFFSET_BITS),
            yaw: sign_extend(bits >> 44, YAW_BITS) as i16,
        }
    }
}

/// What a controller keeps to speak the footstep protocol: the appended position of every
/// step id and the version of its last modification (no_std, 256 entries, about 3 KB).
#[derive(Clone, Debug)]
pub struct StepBook {
    steps: [Option<(WireStep, u8)>; 256],
}

impl Default for StepBook {
    fn default() -> Self {
        Self::new()
    }
}

impl StepBook {
    /// Knows no step.
    pub const fn new() -> Self {
        Self { steps: [None; 256] }
    }

    /// The `STEP_APPEND` of step `id` at `(x, y, yaw)`; `None` if not representable.
    pub fn append(&mut self, id: u8, left: bool, x: f64, y: f64, yaw: f64) -> Option<Command> {
        let s = WireStep::from_si(id, left, x, y, yaw)?;
        self.steps[usize::from(id)] = Some((s, 0));
        Some(Command::Append(s))
    }

    /// The next `STEP_MODIFY` of step `id` to `(x, y, yaw)` (one version newer than the last
    /// one made here); `None` if the step was never appended here or the offset from its
    /// appended position is out of range.
    pub fn modify(&mut self, id: u8, x: f64, y: f64, yaw: f64) -> Option<Command> {
        let (base, v) = self.steps[usize::from(id)]?;
        let v = (v + 1) % VERSIONS;
        let m = WireModify::from_si(&base, v, x, y, yaw)?;
        self.steps[usize::from(id)] = Some((base, v));
        Some(Command::Modify(m))
    }

    /// The append of step `id` as recorded, if any.
    pub fn appended(&self, id: u8) -> Option<WireStep> {
        self.steps[usize::from(id)].map(|(s, _)| s)
    }

    /// Forgets every step (after a `Reset`: ids count from 0 again).
    pub fn clear(&mut self) {
        self.steps = [None; 256];
    }
}

/// A validated command from the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Emergency stop with its sequence number.
    EmergencyStop {
        /// Sequence number.
        seq: u8,
    },
    /// A control operation with its sequence number.
    Control {
        /// Sequence number.
        seq: u8,
        /// Operation.
        op: ControlOp,
    },
    /// Append a footstep.
    Append(WireStep),
    /// Modify a queued footstep.
    Modify(WireModify),
}

impl Command {
    /// Validates a frame. On error, the reason and the sequence number or step id to answer
    /// with (0 when the frame is too short to carry one).
    pub fn decode(f: &RawFrame) -> Result<Self, (Reason, u8)> {
        let b = f.bytes();
        let first = b.first().copied().unwrap_or(0);
        let need = |n: usize| {
            if b.len() == n {
                Ok(())
            } else {
                Err((Reason::BadLength, first))
            }
        };
        match f.id {
            ids::ESTOP => {
                need(1)?;
                Ok(Command::EmergencyStop { seq: first })
            }
            ids::CONTROL => {
                need(3)?;
                if !crc_ok(f.id, b) {
                    return Err((Reason::BadCrc, first));
                }
                let op = ControlOp::from_code(b[1]).ok_or((Reason::OutOfRange, first))?;
                Ok(Command::Control { seq: first, op })
            }
            ids::STEP_APPEND | ids::STEP_MODIFY => {
                need(8)?;
                if !crc_ok(f.id, b) {
                    return Err((Reason::BadCrc, first));
                }
                let mut d = [0u8; 8];
                d.copy_from_slice(b);
                Ok(if f.id == ids::STEP_APPEND {
                    Command::Append(WireStep::unpack(&d).map_err(|r| (r, first))?)
                } else {
                    Command::Modify(WireModify::unpack(&d))
                })
            }
            _ => Err((Reason::UnknownId, 0)),
        }
    }

    /// The frame that carries this command.
    pub fn encode(&self) -> RawFrame {
        let (id, data, n) = match self {
            Command::EmergencyStop { seq } => (ids::ESTOP, [*seq, 0, 0, 0, 0, 0, 0, 0], 1),
            Command::Control { seq, op } => {
                let c = crc8(ids::CONTROL, &[*seq, op.code()]);
                (ids::CONTROL, [*seq, op.code(), c, 0, 0, 0, 0, 0], 3)
            }
            Command::Append(s) => (ids::STEP_APPEND, s.pack(), 8),
            Command::Modify(s) => (ids::STEP_MODIFY, s.pack(), 8),
        };
        RawFrame {
            id,
            len: n,
            data: {
                let mut d = [0u8; 8];
                d[..usize::from(n)].copy_from_slice(&data[..usize::from(n)]);
                d
            },
        }
    }

    /// The step id of a footstep command.
    pub fn step_id(&self) -> Option<u8> {
        match self {
            Command::Append(s) => Some(s.id),
            Command::Modify(m) => Some(m.id),
            _ => None,
        }
    }

    /// What an `ACK` to this command carries as `seq`: the step id or the sequence number.
    pub fn key(&self) -> u8 {
        match self {
            Command::Append(s) => s.id,
            Command::Modify(m) => m.id,
            Command::Control { seq, .. } | Command::EmergencyStop { seq } => *seq,
        }
    }

    /// The code of the command in `ACK` frames (the low byte of its identifier).
    pub fn code(&self) -> u8 {
        let id = match self {
            Command::EmergencyStop { .. } => ids::ESTOP,
            Command::Control { .. } => ids::CONTROL,
            Command::Append(_) => ids::STEP_APPEND,
            Command::Modify(_) => ids::STEP_MODIFY,
        };
        (id & 0xFF) as u8
    }

    /// What the `ACK` to this command echoes: the last byte of its frame (the CRC, except for
    /// the emergency stop, whose only byte is its sequence number).
    pub fn echo(&self) -> u8 {
        echo_of(&self.encode())
    }
}

/// The byte an `ACK` echoes of the frame it answers: its last data byte (0 if it has none).
pub fn echo_of(f: &RawFrame) -> u8 {
    f.bytes().last().copied().unwrap_or(0)
}

/// An `ACK` frame: the answer to a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ack {
    /// Low byte of the command's identifier (0x10 e-stop, 0x20 control, 0x00 append,
    /// 0x01 modify).
    pub command: u8,
    /// Sequence number or step id of the command.
    pub seq: u8,
    /// `None` when accepted.
    pub reason: Option<Reason>,
    /// Queued steps after the command.
    pub queue: u8,
    /// The last byte of the answered frame ([`echo_of`]; the command's CRC for `CONTROL` and
    /// footsteps).
    pub echo: u8,
    /// For a footstep command: the version of that step in force after the command (0 as
    /// appended), whatever the answer; `None` (0xFF on the wire) for other commands and for
    /// steps the node does not know. A controller whose newer modification was refused learns
    /// from it which of its versions the node walks.
    pub version: Option<u8>,
}

impl Ack {
    /// The frame (with its CRC).
    pub fn encode(&self) -> RawFrame {
        let r = self.reason.map(Reason::code).unwrap_or(0);
        let v = self.version.unwrap_or(0xFF);
        let body = [self.command, self.seq, r, self.queue, self.echo, v];
        let c = crc8(ids::ACK, &body);
        RawFrame {
            id: ids::ACK,
            len: 7,
            data: [body[0], body[1], body[2], body[3], body[4], v, c, 0],
        }
    }
    /// Decodes an `ACK` frame; `None` if it is not one or its CRC is wrong.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::ACK || f.len != 7 || !crc_ok(f.id, f.bytes()) {
            return None;
        }
        let reason = match f.data[2] {
            0 => None,
            c => Some(Reason::from_code(c)?),
        };
        Some(Self {
            command: f.data[0],
            seq: f.data[1],
            reason,
            queue: f.data[3],
            echo: f.data[4],
            version: match f.data[5] {
                0xFF => None,
                v if v < VERSIONS => Some(v),
                _ => return None,
            },
        })
    }
}

/// The node's published state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// 0 standing, 1 walking, 2 emergency-stopped, 3 controller lost, 4 stopping (a `Stop`
    /// or `StopNow` is being carried out). See the state table in the node's docs.
    pub state: u8,
    /// Queued steps.
    pub queue: u8,
    /// Commands rejected since start-up (saturating).
    pub rejected: u16,
    /// Control cycles that overran their budget (saturating; reported by the firmware).
    pub overruns: u16,
    /// Last single-support adjustment \[5 ms\].
    pub last_adjust: i8,
    /// Bit 0: shaping active; bit 1: last re-plan failed; bit 2: transmit backlog overflowed.
    pub flags: u8,
}

impl Status {
    /// The frame.
    pub fn encode(&self) -> RawFrame {
        let r = self.rejected.to_le_bytes();
        let o = self.overruns.to_le_bytes();
        RawFrame {
            id: ids::STATUS,
            len: 8,
            data: [
                self.state,
                self.queue,
                r[0],
                r[1],
                o[0],
                o[1],
                self.last_adjust as u8,
                self.flags,
            ],
        }
    }
    /// Decodes a `STATUS` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::STATUS || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            state: d[0],
            queue: d[1],
            rejected: u16::from_le_bytes([d[2], d[3]]),
            overruns: u16::from_le_bytes([d[4], d[5]]),
            last_adjust: d[6] as i8,
            flags: d[7],
        })
    }
}

/// The node's diagnostics (every 100 ms, with `STATUS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diag {
    /// Frames received that are not the node's (other identifiers, extended or remote
    /// frames), saturating.
    pub foreign: u16,
    /// Bus errors on receive or transmit, saturating.
    pub bus_errors: u16,
    /// Frames dropped because the transmit backlog was full, saturating.
    pub tx_dropped: u16,
    /// The side the next appended step must have: 0 either, 1 left, 2 right.
    pub next_side: u8,
    /// Sequence number of the last accepted `Start`, `Stop`, `StopNow` or `Reset` (0 before
    /// any): a controller that restarts continues from it.
    pub last_control: u8,
}

impl Diag {
    /// The frame.
    pub fn encode(&self) -> RawFrame {
        let [f0, f1] = self.foreign.to_le_bytes();
        let [b0, b1] = self.bus_errors.to_le_bytes();
        let [t0, t1] = self.tx_dropped.to_le_bytes();
        RawFrame {
            id: ids::DIAG,
            len: 8,
            data: [f0, f1, b0, b1, t0, t1, self.next_side, self.last_control],
        }
    }
    /// Decodes a `DIAG` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::DIAG || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            foreign: u16::from_le_bytes([d[0], d[1]]),
            bus_errors: u16::from_le_bytes([d[2], d[3]]),
            tx_dropped: u16::from_le_bytes([d[4], d[5]]),
            next_side: d[6],
            last_control: d[7],
        })
    }
}

/// The CAN link's health as the board reports it (`LINK`, every 100 ms with `STATUS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkHealth {
    /// Transmit error counter.
    pub tec: u8,
    /// Receive error counter (0 … 127).
    pub rec: u8,
    /// The receive error counter has reached the error-passive level.
    pub rx_passive: bool,
    /// 0 error-active, 1 warning (a counter ≥ 96), 2 error-passive, 3 bus-off.
    pub bus_state: u8,
    /// Why the board last started: 0 unknown, 1 power-on, 2 pin, 3 brown-out, 4 software,
    /// 5 independent watchdog, 6 window watchdog, 7 fault handler, 8 clock failure,
    /// 9 low-power.
    pub reset: u8,
    /// Bus-off events since start-up (each recovered), saturating.
    pub bus_offs: u16,
    /// Entries into error-passive since start-up, saturating.
    pub passive_episodes: u16,
    /// 5 ms slots the control loop missed since start-up (an overrun longer than a period),
    /// saturating at 255.
    pub missed_slots: u8,
}

impl LinkHealth {
    /// The frame (fields beyond their widths are cut to them).
    pub fn encode(&self) -> RawFrame {
        let [b0, b1] = self.bus_offs.to_le_bytes();
        let [p0, p1] = self.passive_episodes.to_le_bytes();
        RawFrame {
            id: ids::LINK,
            len: 8,
            data: [
                self.tec,
                (self.rec & 0x7F) | (u8::from(self.rx_passive) << 7),
                (self.bus_state & 0x3) | ((self.reset & 0xF) << 2),
                b0,
                b1,
                p0,
                p1,
                self.missed_slots,
            ],
        }
    }
    /// Decodes a `LINK` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::LINK || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            tec: d[0],
            rec: d[1] & 0x7F,
            rx_passive: d[1] & 0x80 != 0,
            bus_state: d[2] & 0x3,
            reset: (d[2] >> 2) & 0xF,
            bus_offs: u16::from_le_bytes([d[3], d[4]]),
            passive_episodes: u16::from_le_bytes([d[5], d[6]]),
            missed_slots: d[7],
        })
    }
}

/// `libm::round(x)` (halves away from zero) as an `i32`, saturated at the `i32` range, `NaN`
/// to 0: one hardware conversion (`vcvt`, truncating) and an exact correction, instead of
/// libm's bit manipulation. `x − trunc(x)` is exact for every `f64` whose truncation fits an
/// `i32`; beyond the range the truncation saturates and the correction saturates too.
fn round_to_i32(x: f64) -> i32 {
    let t = x as i32;
    let frac = x - f64::from(t);
    if frac >= 0.5 {
        t.saturating_add(1)
    } else if frac <= -0.5 {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Saturating conversion to a fixed-point integer of `unit`.
fn fixed(v: f64, unit: f64, min: i32, max: i32) -> i32 {
    if !v.is_finite() {
        return 0;
    }
    round_to_i32(v / unit).clamp(min, max)
}

/// The 5 ms reference stream (what the node publishes every control cycle).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stream {
    /// COG x, y \[m\].
    pub cog: [f64; 2],
    /// COG velocity \[m/s\].
    pub cog_vel: [f64; 2],
    /// ZMP x, y \[m\].
    pub zmp: [f64; 2],
    /// Phase: 0 standing, 1 double support, 2 single support on the left foot, 3 on the right.
    pub phase: u8,
    /// Low byte of the tick counter.
    pub tick: u8,
    /// Left and right foot: x, y, z \[m\], yaw \[rad\].
    pub feet: [[f64; 4]; 2],
}

impl Stream {
    /// The five frames of one cycle, in identifier order.
    pub fn encode(&self) -> [RawFrame; 5] {
        let um = |v: f64| fixed(v, 1e-6, i32::MIN, i32::MAX);
        let pos = |id: u16, p: [f64; 2]| {
            let (a, b) = (um(p[0]).to_le_bytes(), um(p[1]).to_le_bytes());
            RawFrame {
                id,
                len: 8,
                data: [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]],
            }
        };
        let vel = |v: f64| fixed(v, 1e-4, i16::MIN.into(), i16::MAX.into()) as i16;
        let (vx, vy) = (
            vel(self.cog_vel[0]).to_le_bytes(),
            vel(self.cog_vel[1]).to_le_bytes(),
        );
        let foot = |id: u16, f: [f64; 4]| {
            let x = fixed(f[0], FOOT_UNIT, -I20_MAX, I20_MAX) as u64;
            let y = fixed(f[1], FOOT_UNIT, -I20_MAX, I20_MAX) as u64;
            let z = fixed(f[2], 5e-4, 0, 255) as u64;
            let yaw = fixed(f[3], 1e-4, i16::MIN.into(), i16::MAX.into()) as u64;
            let bits =
                (x & 0xF_FFFF) | (y & 0xF_FFFF) << 20 | (z & 0xFF) << 40 | (yaw & 0xFFFF) << 48;
            RawFrame {
                id,
                len: 8,
                data: bits.to_le_bytes(),
            }
        };
        [
            pos(ids::COG, self.cog),
            pos(ids::ZMP, self.zmp),
            RawFrame {
                id: ids::COG_VEL,
                len: 6,
                data: [vx[0], vx[1], vy[0], vy[1], self.phase, self.tick, 0, 0],
            },
            foot(ids::FOOT_LEFT, self.feet[0]),
            foot(ids::FOOT_RIGHT, self.feet[1]),
        ]
    }

    /// Updates the fields carried by one stream frame; `false` if it is not a stream frame.
    pub fn decode_into(&mut self, f: &RawFrame) -> bool {
        let d = &f.data;
        let i32at = |i: usize| i32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        match (f.id, f.len) {
            (ids::COG, 8) => self.cog = [f64::from(i32at(0)) * 1e-6, f64::from(i32at(4)) * 1e-6],
            (ids::ZMP, 8) => self.zmp = [f64::from(i32at(0)) * 1e-6, f64::from(i32at(4)) * 1e-6],
            (ids::COG_VEL, 6) => {
                self.cog_vel = [
                    f64::from(i16::from_le_bytes([d[0], d[1]])) * 1e-4,
                    f64::from(i16::from_le_bytes([d[2], d[3]])) * 1e-4,
                ];
                self.phase = d[4];
                self.tick = d[5];
            }
            (ids::FOOT_LEFT | ids::FOOT_RIGHT, 8) => {
                let bits = u64::from_le_bytes(*d);
                let sx = |v: u64, n: u32| -> i64 { (v << (64 - n)) as i64 >> (64 - n) };
                let k = usize::from(f.id == ids::FOOT_RIGHT);
                self.feet[k] = [
                    sx(bits & 0xF_FFFF, 20) as f64 * FOOT_UNIT,
                    sx((bits >> 20) & 0xF_FFFF, 20) as f64 * FOOT_UNIT,
                    ((bits >> 40) & 0xFF) as f64 * 5e-4,
                    sx((bits >> 48) & 0xFFFF, 16) as f64 * 1e-4,
                ];
            }
            _ => return false,
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_to_i32_is_libm_round_saturated() {
        let mut cases = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            1e-300,
            -1e-300,
            2147483646.5,
            2147483647.4,
            2147483647.5,
            -2147483648.4,
            -2147483648.5,
            -2147483649.0,
            1e12,
            -1e12,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            4503599627370495.5,
            -4503599627370495.5,
        ];
        let mut x = 0x1234_5678_9abc_def0_u64;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            // Spread over ±2^33, with many exact halves.
            cases.push((u - 0.5) * 2f64.powi(34));
            cases.push(((x % 20_001) as f64 - 10_000.0) * 0.5);
        }
        for &c in &cases {
            let want = libm::round(c).clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
            assert_eq!(round_to_i32(c), want, "{c:e}");
        }
        assert_eq!(round_to_i32(f64::NAN), 0);
    }

    #[test]
    fn steps_round_trip_at_wire_precision() {
        for &(x, y, yaw) in &[
            (0.0, 0.0, 0.0),
            (1.2345, -0.1, 0.3),
            (-32.0, 32.7, -3.1),
            (0.0002, 0.0003, 3.1),
        ] {
            let s = WireStep::from_si(7, true, x, y, yaw).unwrap();
            let f = Command::Append(s).encode();
            let Command::Append(back) = Command::decode(&f).unwrap() else {
                panic!("not an append")
            };
            assert_eq!(back, s);
            let (bx, by, byaw) = back.si();
            let half = STEP_UNIT / 2.0 + 1e-12;
            assert!((bx - x).abs() <= half && (by - y).abs() <= half);
            let dyaw = libm::remainder(byaw - yaw, core::f64::consts::TAU);
            assert!(dyaw.abs() <= YAW_UNIT / 2.0 + 1e-12, "{yaw} -> {byaw}");
        }
        assert!(WireStep::from_si(0, false, 33.0, 0.0, 0.0).is_none());
        assert!(WireStep::from_si(0, false, f64::NAN, 0.0, 0.0).is_none());
    }

    /// Every heading is representable: ±π, π − half a unit, several turns (issue 10, item 7).
    #[test]
    fn every_finite_heading_is_representable() {
        use core::f64::consts::{PI, TAU};
        for yaw in [PI, -PI, PI - 5e-4, -PI + 5e-4, 3.0 * PI, 100.0, -7.0, 0.0] {
            let s = WireStep::from_si(0, true, 0.0, 0.0, yaw).expect("representable");
            let Ok(Command::Append(back)) = Command::decode(&Command::Append(s).encode()) else {
                panic!("decodes");
            };
            let d = libm::remainder(back.si().2 - yaw, TAU);
            assert!(d.abs() <= YAW_UNIT / 2.0 + 1e-9, "{yaw}: {}", back.si().2);
        }
        assert!(WireStep::from_si(0, true, 0.0, 0.0, f64::INFINITY).is_none());
    }

    /// Encoder and decoder agree on every range: the extreme values the decoder accepts are
    /// produced by the encoder, and one unit beyond is refused by it (issue 10, item 7).
    #[test]
    fn encoder_and_decoder_agree_on_the_ranges() {
        let (min, max) = signed_range(STEP_BITS);
        for v in [min, max] {
            let m = f64::from(v) * STEP_UNIT;
            let s = WireStep::from_si(1, false, m, m, 0.0).expect("extreme encodable");
            assert_eq!((s.x, s.y), (v, v));
            let Ok(Command::Append(back)) = Command::decode(&Command::Append(s).encode()) else {
                panic!("decodes");
            };
            assert_eq!(back, s);
        }
        let beyond = f64::from(max + 1) * STEP_UNIT;
        assert!(WireStep::from_si(1, false, beyond, 0.0, 0.0).is_none());
        let below = f64::from(min - 1) * STEP_UNIT;
        assert!(WireStep::from_si(1, false, 0.0, below, 0.0).is_none());
        // Every 17-bit pattern decodes to a value in range, and re-encodes to itself.
        for raw in [0u64, 1, 0xFFFF, 0x1_0000, 0x1_FFFF] {
            let bits = raw << 10 | raw << 27;
            let mut d = bits.to_le_bytes();
            d[7] = crc8(ids::STEP_APPEND, &d[..7]);
            let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
            let Ok(Command::Append(s)) = Command::decode(&f) else {
                panic!("decodes");
            };
            assert!(s.in_range());
            assert_eq!(Command::Append(s).encode(), f);
        }
    }

    #[test]
    fn modifications_carry_a_version_and_an_offset() {
        let base = WireStep::from_si(5, true, 10.0, 0.1, 0.0).unwrap();
        let m = WireModify::from_si(&base, 3, 10.25, 0.05, -0.2).unwrap();
        assert_eq!(
            (m.id, m.version, m.left, m.dx, m.dy),
            (5, 3, true, 500, -100)
        );
        let f = Command::Modify(m).encode();
        assert_eq!(Command::decode(&f), Ok(Command::Modify(m)));
        let s = m.applied_to(&base).unwrap();
        let (x, y, yaw) = s.si();
        assert!((x - 10.25).abs() < 1e-12 && (y - 0.05).abs() < 1e-12);
        assert!((yaw + 0.2).abs() <= YAW_UNIT / 2.0);
        // The offset's range: ±4.096 m.
        assert!(WireModify::from_si(&base, 1, 14.0955, 0.1, 0.0).is_some());
        assert!(WireModify::from_si(&base, 1, 14.1, 0.1, 0.0).is_none());
        // Newer: 1 … 63 ahead modulo 128.
        let v = |version| WireModify { version, ..m };
        assert!(v(4).is_newer_than(3) && v(66).is_newer_than(3) && v(0).is_newer_than(127));
        assert!(!v(3).is_newer_than(3) && !v(2).is_newer_than(3) && !v(67).is_newer_than(3));
        // The controller's book counts versions per step.
        let mut book = StepBook::new();
        assert!(book.modify(9, 0.0, 0.0, 0.0).is_none(), "never appended");
        assert!(book.append(9, false, 0.2, -0.1, 0.0).is_some());
        for want in 1..=130u32 {
            let Some(Command::Modify(m)) = book.modify(9, 0.25, -0.1, 0.0) else {
                panic!("modify");
            };
            assert_eq!(u32::from(m.version), want % 128);
        }
    }

    #[test]
    fn bad_frames_are_rejected_with_a_reason() {
        let f = RawFrame::new(ids::CONTROL, &[3, 9, crc8(ids::CONTROL, &[3, 9])]).unwrap();
        assert_eq!(Command::decode(&f), Err((Reason::OutOfRange, 3)));
        let f = RawFrame::new(ids::CONTROL, &[3, 1]).unwrap();
        assert_eq!(Command::decode(&f), Err((Reason::BadLength, 3)));
        let f = RawFrame::new(0x123, &[]).unwrap();
        assert_eq!(Command::decode(&f), Err((Reason::UnknownId, 0)));
        let mut d = Command::Append(WireStep::from_si(1, false, 0.1, -0.1, 0.0).unwrap())
            .encode()
            .data;
        d[1] |= 0x02; // the reserved bit, CRC not updated
        let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
        assert_eq!(Command::decode(&f), Err((Reason::BadCrc, 1)));
        d[7] = crc8(ids::STEP_APPEND, &d[..7]); // a sender that sets it on purpose
        let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
        assert_eq!(Command::decode(&f), Err((Reason::OutOfRange, 1)));
        let f = RawFrame::new(ids::CONTROL, &[3, 1, 0]).unwrap();
        assert_eq!(Command::decode(&f), Err((Reason::BadCrc, 3)));
    }

    /// The catalogue check value of CRC-8/AUTOSAR ("123456789" → 0xDF) is an oracle
    /// independent of this implementation; the identifier is prepended as two bytes.
    #[test]
    fn crc8_matches_the_autosar_check_value() {
        // The identifier's two bytes are the first two of the message: "12" + "3456789".
        assert_eq!(crc8(u16::from_le_bytes(*b"12"), b"3456789"), 0xDF);
        // The identifier enters the CRC: a frame moved to another identifier fails.
        assert_ne!(crc8(0x100, &[0; 7]), crc8(0x101, &[0; 7]));
    }

    /// Every error of up to three bits in a protected command (identifier bits included) is
    /// refused, never accepted as another command.
    #[test]
    fn every_one_two_and_three_bit_error_is_caught() {
        let step = WireStep::from_si(9, true, 1.2345, -0.2, 0.25).unwrap();
        let change = WireModify::from_si(&step, 77, 1.3, -0.25, 0.2).unwrap();
        for cmd in [
            Command::Append(step),
            Command::Modify(change),
            Command::Control {
                seq: 77,
                op: ControlOp::Stop,
            },
        ] {
            let f = cmd.encode();
            let n = 8 * usize::from(f.len) + 11; // data bits, then the identifier's
            let flip = |f: &mut RawFrame, k: usize| {
                if k < 8 * usize::from(f.len) {
                    f.data[k / 8] ^= 1 << (k % 8);
                } else {
                    f.id ^= 1 << (k - 8 * usize::from(f.len));
                }
            };
            let mut tried = 0;
            for a in 0..n {
                for b in a..n {
                    for c in b..n {
                        let mut g = f;
                        flip(&mut g, a);
                        if b > a {
                            flip(&mut g, b);
                        }
                        if c > b {
                            flip(&mut g, c);
                        }
                        if g == f {
                            continue;
                        }
                        tried += 1;
                        // Another identifier may be a command too: still refused.
                        assert!(Command::decode(&g).is_err(), "{cmd:?}: bits {a} {b} {c}");
                    }
                }
            }
            // Single flips, pairs (each twice: (a, a, c) and (a, c, c)), triples.
            assert_eq!(tried, n + n * (n - 1) + n * (n - 1) * (n - 2) / 6);
        }
    }

    #[test]
    fn acks_status_and_stream_round_trip() {
        for r in [None, Some(Reason::Infeasible), Some(Reason::PlanFailed)] {
            let a = Ack {
                command: 0x01,
                seq: 42,
                reason: r,
                queue: 3,
                echo: 0xA5,
                version: r.map(|_| 17),
            };
            assert_eq!(Ack::decode(&a.encode()), Some(a));
            let mut bad = a.encode();
            bad.data[3] ^= 0x10;
            assert_eq!(Ack::decode(&bad), None);
        }
        let d = Diag {
            foreign: 700,
            bus_errors: 3,
            tx_dropped: 1,
            next_side: 2,
            last_control: 9,
        };
        assert_eq!(Diag::decode(&d.encode()), Some(d));
        let l = LinkHealth {
            tec: 200,
            rec: 127,
            rx_passive: true,
            bus_state: 3,
            reset: 9,
            bus_offs: 513,
            passive_episodes: 40_000,
            missed_slots: 255,
        };
        assert_eq!(LinkHealth::decode(&l.encode()), Some(l));
        assert_eq!(l.encode().data[2], 3 | 9 << 2);
        assert_eq!(l.encode().data[1], 0xFF);
        let s = Status {
            state: 1,
            queue: 4,
            rejected: 300,
            overruns: 2,
            last_adjust: -40,
            flags: 5,
        };
        assert_eq!(Status::decode(&s.encode()), Some(s));
        let st = Stream {
            cog: [12.345678, -0.1],
            cog_vel: [0.3, -0.25],
            zmp: [12.3, -0.09],
            phase: 2,
            tick: 77,
            feet: [[12.4, 0.1, 0.0321, 0.5], [12.2, -0.1, 0.0, -0.25]],
        };
        let mut back = Stream::default();
        for f in st.encode() {
            assert!(back.decode_into(&f));
        }
        for k in 0..2 {
            assert!((back.cog[k] - st.cog[k]).abs() <= 0.5e-6 + 1e-12);
            assert!((back.zmp[k] - st.zmp[k]).abs() <= 0.5e-6 + 1e-12);
            assert!((back.cog_vel[k] - st.cog_vel[k]).abs() <= 0.5e-4 + 1e-12);
            for i in 0..4 {
                let unit = [1e-4, 1e-4, 5e-4, 1e-4][i];
                assert!((back.feet[k][i] - st.feet[k][i]).abs() <= unit / 2.0 + 1e-12);
            }
        }
        assert_eq!((back.phase, back.tick), (2, 77));
    }
}
