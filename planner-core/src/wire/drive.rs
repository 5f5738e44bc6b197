//! The frames that let the node choose the footsteps itself: `VELOCITY` ([`WireVelocity`]:
//! walk at a velocity, changed at any time) and `GOAL` ([`WireGoal`]: walk to a pose relative
//! to where the robot stands).
//!
//! Both are control commands of the session: they carry the control sequence number (the one
//! `CONTROL` carries, shared with it: a `VELOCITY` must be numbered above every control
//! command accepted before it, and a `CONTROL` above every `VELOCITY`), so a replayed,
//! repeated or older frame is never taken.
//!
//! | bits | field | unit |
//! |---|---|---|
//! | 0–15 | the sequence number's bits 0–15 | |
//! | 16–23 | the sequence number's bits 16–23 XOR the session epoch's bits 8–15 | |
//! | 24–34 | `VELOCITY` vx i11 / `GOAL` x i11 | 1 mm/s / 1 cm |
//! | 35–45 | `VELOCITY` vy i11 / `GOAL` y i11 | 1 mm/s / 1 cm |
//! | 46–55 | `VELOCITY` ω i10 / `GOAL` θ i10 | 2 mrad/s / 2π/1024 rad |
//! | 56–63 | CRC-8 over the identifier, the session's low byte, the Gray code of the sequence number's high byte, bytes 0–6 | |
//!
//! **The sequence number.** The frame carries its low 24 bits; the node reads them as the number
//! with those bits nearest to the last one it accepted ([`seq_number`], from 2²³ below to
//! 2²³ − 1 above): exact for every number less than 2²³ (8.4 million commands) away. The high
//! byte is not sent but enters the CRC (its Gray code, so that neighbouring blocks differ in
//! one bit, as the footsteps' [`super::step_key`]): a copy 2²³ or more numbers old, read as a
//! number of another block of 2²⁴, differs from the frame its sender made in that one byte of
//! the CRC's input only, and a CRC-8 catches every error confined to 8 consecutive bits: it is
//! refused `BadCrc`, always. So within a start-up no old frame counts as new, by construction.
//!
//! **One cycle's frames.** The bus delivers the frames a controller queues at once in the
//! order of their identifiers (`CONTROL` 0x020, then `VELOCITY` 0x02F, then `GOAL` 0x046), and
//! the node takes them in the order they arrive: a controller numbers the frames it sends in
//! one cycle in that order (a heartbeat numbered after a velocity of the same cycle arrives
//! first and makes the velocity stale; the velocity proves the controller alive by itself).
//!
//! **The session.** The frame carries 16 bits of the session as `CONTROL` does, without a
//! field of their own: the low byte of the session epoch keys the CRC (as `MEASURED`'s), and
//! its second byte is XORed into the sequence number's bits 16–23. A frame whose sender knew
//! another session is read with those bits wrong, 2¹⁶ or more away from the number it was
//! sent as, and the node takes no `VELOCITY` or `GOAL` more than [`SEQ_ADVANCE`] above the
//! last accepted number (refused `WrongSession`; a controller that falls that far behind is
//! taken again after any `CONTROL`, which carries its whole number): of the 256 second bytes,
//! at most one puts a frame in that window, and a CRC-8 keyed with another low byte (an error
//! confined to one byte) always fails. A frame of an earlier start-up (another epoch drawn at
//! random) is thus taken with odds of at most 2⁻¹⁶, those of `CONTROL`. Frames of an earlier
//! session of this start-up carry older sequence numbers: refused by the rule above.
//!
//! **Not a number.** The most negative value of each field is reserved: a gateway that receives
//! a value that is not a finite number (a ROS `Twist` with a `NaN`) sends it so
//! ([`WireVelocity::from_si`]) and the node refuses the frame `OutOfRange`, changing nothing. A
//! finite value beyond a field's range is sent as the field's end (the node cuts it to what the
//! legs can take in any case, and says so).

use super::{crc8, ids, signed_range, RawFrame, Reason};
use crate::real::Real;

/// Velocity unit of `VELOCITY`'s vx and vy \[m/s\].
pub const SPEED_UNIT: f64 = 1e-3;
/// Turn rate unit of `VELOCITY`'s ω \[rad/s\].
pub const TURN_UNIT: f64 = 2e-3;
/// Position unit of `GOAL`'s x and y \[m\].
pub const GOAL_UNIT: f64 = 1e-2;
/// Heading unit of `GOAL`'s θ \[rad\].
pub const GOAL_YAW_UNIT: f64 = core::f64::consts::TAU / 1024.0;
/// Bits of the first two fields (vx, vy; x, y).
pub const DRIVE_BITS: u32 = 11;
/// Bits of the third field (ω; θ).
pub const DRIVE_TURN_BITS: u32 = 10;
/// Sequence numbers a frame tells apart (it carries the low 24 bits).
pub const SEQ_WINDOW: u32 = 1 << 24;
/// The most one `VELOCITY` or `GOAL` may advance the control sequence number (see the module
/// docs: below 2¹⁶, the step by which a wrong session byte moves it).
pub const SEQ_ADVANCE: u32 = 1 << 15;

/// The session epoch's second byte, where it is XORed into the carried sequence number.
fn session_bits(epoch: u32) -> u32 {
    ((epoch >> 8) & 0xFF) << 16
}

/// The control sequence number whose low 24 bits are `low` nearest to `last` (the last
/// accepted one): from 2²³ below `last` to 2²³ − 1 above it, wrapping.
pub fn seq_number(low: u32, last: u32) -> u32 {
    let low = low & (SEQ_WINDOW - 1);
    let d = low.wrapping_sub(last) & (SEQ_WINDOW - 1);
    // Sign-extend the 24-bit difference.
    let d = ((d << 8) as i32) >> 8;
    last.wrapping_add(d as u32)
}

/// `v` in `unit`s in a signed `bits`-bit field: rounded, the ends for finite values beyond
/// them, the reserved most negative value when `v` is not finite.
fn code(v: f64, unit: f64, bits: u32) -> i32 {
    let (min, max) = signed_range(bits);
    if !v.is_finite() {
        return min;
    }
    let r = libm::round(v / unit);
    r.max(f64::from(min + 1)).min(f64::from(max)) as i32
}

fn sign_extend(v: u64, n: u32) -> i32 {
    ((v << (64 - n)) as i64 >> (64 - n)) as i32
}

fn field(v: i32, n: u32) -> u64 {
    (v as i64 as u64) & ((1u64 << n) - 1)
}

/// The three fields and the sequence number of both frames.
fn pack(id: u16, seq: u32, f: [i32; 3], epoch: u32) -> RawFrame {
    let bits = u64::from((seq & (SEQ_WINDOW - 1)) ^ session_bits(epoch))
        | field(f[0], DRIVE_BITS) << 24
        | field(f[1], DRIVE_BITS) << 35
        | field(f[2], DRIVE_TURN_BITS) << 46;
    let b = bits.to_le_bytes();
    let c = crc(id, epoch, seq, &b);
    RawFrame {
        id,
        len: 8,
        data: [b[0], b[1], b[2], b[3], b[4], b[5], b[6], c],
    }
}

fn crc(id: u16, epoch: u32, seq: u32, b: &[u8; 8]) -> u8 {
    let keyed = [
        epoch as u8,
        gray((seq >> 24) as u8),
        b[0],
        b[1],
        b[2],
        b[3],
        b[4],
        b[5],
        b[6],
    ];
    crc8(id, &keyed)
}

fn gray(h: u8) -> u8 {
    h ^ (h >> 1)
}

/// Reads a frame of `id` whose length was checked: the sequence number (read against `last`)
/// and the three fields; the reserved values are `OutOfRange`.
fn unpack(id: u16, b: &[u8], epoch: u32, last: u32) -> Result<(u32, [i32; 3]), Reason> {
    let mut d = [0u8; 8];
    d.copy_from_slice(b);
    let bits = u64::from_le_bytes(d);
    let seq = seq_number((bits as u32 ^ session_bits(epoch)) & (SEQ_WINDOW - 1), last);
    if crc(id, epoch, seq, &d) != d[7] {
        return Err(Reason::BadCrc);
    }
    let f = [
        sign_extend(bits >> 24, DRIVE_BITS),
        sign_extend(bits >> 35, DRIVE_BITS),
        sign_extend(bits >> 46, DRIVE_TURN_BITS),
    ];
    let reserved = [
        signed_range(DRIVE_BITS).0,
        signed_range(DRIVE_BITS).0,
        signed_range(DRIVE_TURN_BITS).0,
    ];
    if f.iter().zip(reserved).any(|(v, r)| *v == r) {
        return Err(Reason::OutOfRange);
    }
    Ok((seq, f))
}

/// A `VELOCITY` command: walk at (vx, vy, ω) in the support foot's frame (see
/// `planner_core::velocity`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireVelocity {
    /// The control sequence number.
    pub seq: u32,
    /// Along the heading, 1 mm/s.
    pub vx: i32,
    /// To the left, 1 mm/s.
    pub vy: i32,
    /// Turn rate, counter-clockwise, 2 mrad/s.
    pub wz: i32,
}

impl WireVelocity {
    /// A velocity \[m/s, m/s, rad/s\] in the wire's units (see the module docs for values
    /// beyond the range and values that are not finite).
    pub fn from_si(seq: u32, vx: f64, vy: f64, wz: f64) -> Self {
        Self {
            seq,
            vx: code(vx, SPEED_UNIT, DRIVE_BITS),
            vy: code(vy, SPEED_UNIT, DRIVE_BITS),
            wz: code(wz, TURN_UNIT, DRIVE_TURN_BITS),
        }
    }

    /// (vx, vy, ω) in the scalar `T`.
    pub fn si_in<T: Real>(&self) -> (T, T, T) {
        (
            T::of_i32(self.vx) * T::of(SPEED_UNIT),
            T::of_i32(self.vy) * T::of(SPEED_UNIT),
            T::of_i32(self.wz) * T::of(TURN_UNIT),
        )
    }

    /// The frame, for the session whose epoch is `epoch`.
    pub fn encode(&self, epoch: u32) -> RawFrame {
        pack(ids::VELOCITY, self.seq, [self.vx, self.vy, self.wz], epoch)
    }

    /// Validates the data bytes of a `VELOCITY` frame of length 8 for the session `epoch`
    /// and the last accepted sequence number `last`.
    pub(super) fn decode(b: &[u8], epoch: u32, last: u32) -> Result<Self, Reason> {
        let (seq, [vx, vy, wz]) = unpack(ids::VELOCITY, b, epoch, last)?;
        Ok(Self { seq, vx, vy, wz })
    }
}

/// A `GOAL` command: walk to the pose (x, y, θ) relative to the midpoint of the feet and
/// their mean heading when it is accepted, then stand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireGoal {
    /// The control sequence number.
    pub seq: u32,
    /// Forward, 1 cm.
    pub x: i32,
    /// To the left, 1 cm.
    pub y: i32,
    /// Heading change, counter-clockwise, 2π/1024 rad.
    pub yaw: i32,
}

impl WireGoal {
    /// A relative goal \[m, m, rad\] in the wire's units (the heading wrapped into [−π, π)).
    pub fn from_si(seq: u32, x: f64, y: f64, yaw: f64) -> Self {
        let yaw = if yaw.is_finite() {
            libm::remainder(yaw, core::f64::consts::TAU)
        } else {
            yaw
        };
        Self {
            seq,
            x: code(x, GOAL_UNIT, DRIVE_BITS),
            y: code(y, GOAL_UNIT, DRIVE_BITS),
            yaw: code(yaw, GOAL_YAW_UNIT, DRIVE_TURN_BITS),
        }
    }

    /// (x, y, θ) in the scalar `T`.
    pub fn si_in<T: Real>(&self) -> (T, T, T) {
        (
            T::of_i32(self.x) * T::of(GOAL_UNIT),
            T::of_i32(self.y) * T::of(GOAL_UNIT),
            T::of_i32(self.yaw) * T::of(GOAL_YAW_UNIT),
        )
    }

    /// The frame, for the session whose epoch is `epoch`.
    pub fn encode(&self, epoch: u32) -> RawFrame {
        pack(ids::GOAL, self.seq, [self.x, self.y, self.yaw], epoch)
    }

    /// Validates the data bytes of a `GOAL` frame of length 8 (see [`WireVelocity::decode`]).
    pub(super) fn decode(b: &[u8], epoch: u32, last: u32) -> Result<Self, Reason> {
        let (seq, [x, y, yaw]) = unpack(ids::GOAL, b, epoch, last)?;
        Ok(Self { seq, x, y, yaw })
    }
}
