//! The robot's measured state on the bus (`MEASURED`, from the state estimator) and the node's
//! step adjustment that answers it (`ADJUST`, to the controller).
//!
//! # `MEASURED` (0x0D8, 8 bytes)
//! | bits | field | unit |
//! |---|---|---|
//! | 0–23 | stamp: the low 24 bits of the node cycle `k` whose reference the state was measured against (`COG_VEL`'s tick) | cycle |
//! | 24–38 | `ξ_meas − ξ_ref(k)`, x: the measured DCM `ξ = x + ẋ/ω` less the reference's (`COG + COG_VEL/ω` of cycle `k`) | 0.1 mm (i15, ±1.6383 m) |
//! | 39–53 | the same, y | 0.1 mm (i15) |
//! | 54–55 | reserved (0) | |
//! | 56–63 | CRC-8 over the identifier, the session key, the bytes 0–6 | |
//!
//! An estimator without a valid estimate sends nothing: the node uses a state only while it is
//! fresh (at most `max_age` cycles old), and walks its planned steps otherwise.
//!
//! The deviation is what the step adjustment needs, measured against the very reference the
//! robot was tracking (the estimator has the stream and the robot's `ω`); a deviation of more
//! than 1.6 m is a fall, not a state to step for. The session key is the low byte of the session
//! epoch (`SESSION`): a frame of another session fails its CRC unless the epochs' low bytes
//! agree (within a start-up, sessions 1 … 255 apart always differ, and the node also refuses
//! any stamp older than the session's first cycle). The stamp names the reference exactly for
//! the node's first 2²⁴ cycles (23.3 hours at 5 ms) of a start-up; beyond them the node
//! refuses the frame `Exhausted`, so no wrapped stamp is ever taken for a new one.
//!
//! # `ADJUST` (0x090, 8 bytes)
//! | bits | field | unit |
//! |---|---|---|
//! | 0–7 | low byte of the first step number the shift applies to | |
//! | 8–23 | shift x (i16) | 0.5 mm (the footstep unit) |
//! | 24–39 | shift y (i16) | 0.5 mm |
//! | 40–47 | adjustments made since the session opened (saturating) | |
//! | 48–55 | flags: bit 0 the last adjustment was limited by reach, bit 1 by eq. 17 (the ZMP's room in the sole), bit 2 the measured state is fresh | |
//! | 56–63 | CRC-8 over the identifier and bytes 0–6 | |
//!
//! Every step from that number on lands at its commanded position (the appended one, moved by
//! its modifications) plus the shift; steps before it keep the shift they landed with. The
//! node sends `ADJUST` when the shift changes and every 100 ms (half-way between two `STATUS`).

use super::{crc8, crc8_keyed, crc_ok, crc_ok_over, ids, signed_range, RawFrame, Reason};

/// The unit of `MEASURED`'s DCM deviation \[m\].
pub const DEVIATION_UNIT: f64 = 1e-4;
/// The width of `MEASURED`'s DCM deviation fields \[bits\].
pub const DEVIATION_BITS: u32 = 15;
/// Stamps are the low 24 bits of the node's cycle: the node takes measured states for its
/// first `STAMPS` cycles of a start-up.
pub const STAMPS: u32 = 1 << 24;

fn sign_extend(v: u64, n: u32) -> i32 {
    ((v << (64 - n)) as i64 >> (64 - n)) as i32
}

/// A measured state as `MEASURED` carries it (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Measured {
    /// The low 24 bits of the node cycle whose reference the state was measured against.
    pub stamp: u32,
    /// The measured DCM less the reference's of that cycle, x and y in [`DEVIATION_UNIT`].
    pub deviation: [i32; 2],
}

impl Measured {
    /// The measured DCM's deviation `deviation` \[m\] from the reference of node cycle `cycle`
    /// (its low 24 bits are sent); `None` if a coordinate is out of range or not finite.
    pub fn from_si(cycle: u32, deviation: [f64; 2]) -> Option<Self> {
        let (min, max) = signed_range(DEVIATION_BITS);
        let q = |v: f64| {
            let r = libm::round(v / DEVIATION_UNIT);
            (v.is_finite() && r >= f64::from(min) && r <= f64::from(max)).then_some(r as i32)
        };
        let deviation = [q(deviation[0])?, q(deviation[1])?];
        Some(Self {
            stamp: cycle & (STAMPS - 1),
            deviation,
        })
    }

    /// The deviation \[m\] in the scalar `T`.
    pub fn deviation_in<T: crate::Real>(&self) -> [T; 2] {
        let u = T::of(DEVIATION_UNIT);
        self.deviation.map(|v| T::of_i32(v) * u)
    }

    /// The frame, for the session whose epoch is `epoch` (its low byte keys the CRC).
    pub fn encode(&self, epoch: u32) -> RawFrame {
        let field = |v: i32| (v as i64 as u64) & ((1u64 << DEVIATION_BITS) - 1);
        let [x, y] = self.deviation;
        let bits = u64::from(self.stamp & (STAMPS - 1)) | field(x) << 24 | field(y) << 39;
        let b = bits.to_le_bytes();
        let body = [b[0], b[1], b[2], b[3], b[4], b[5], b[6]];
        let c = crc8_keyed(ids::MEASURED, epoch as u8, &body);
        RawFrame {
            id: ids::MEASURED,
            len: 8,
            data: [b[0], b[1], b[2], b[3], b[4], b[5], b[6], c],
        }
    }

    /// Validates the 8 data bytes of a `MEASURED` frame for the session `epoch`; on error the
    /// reason (the answer carries the stamp's low byte).
    pub(super) fn decode(b: &[u8], epoch: u32) -> Result<Self, Reason> {
        if !crc_ok_over(ids::MEASURED, Some(epoch as u8), b) {
            return Err(Reason::BadCrc);
        }
        let mut d = [0u8; 8];
        d.copy_from_slice(b);
        let bits = u64::from_le_bytes(d) & ((1u64 << 56) - 1);
        if bits >> 54 != 0 {
            return Err(Reason::OutOfRange);
        }
        Ok(Self {
            stamp: (bits & u64::from(STAMPS - 1)) as u32,
            deviation: [
                sign_extend(bits >> 24, DEVIATION_BITS),
                sign_extend(bits >> 39, DEVIATION_BITS),
            ],
        })
    }
}

/// The node's step adjustment as `ADJUST` reports it (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Adjust {
    /// The low byte of the first step number the shift applies to.
    pub from: u8,
    /// The shift x, y in the footstep unit (0.5 mm).
    pub shift: [i16; 2],
    /// Adjustments made since the session opened (saturating).
    pub count: u8,
    /// Bit 0: the last adjustment was limited by reach; bit 1: by eq. 17; bit 2: the measured
    /// state is fresh.
    pub flags: u8,
}

impl Adjust {
    /// The last adjustment was limited by the reach limits.
    pub const REACH_LIMITED: u8 = 1;
    /// The last adjustment was limited by eq. 17 (the ZMP's room in the support sole).
    pub const ZMP_LIMITED: u8 = 2;
    /// The measured state is fresh (the node can adjust).
    pub const FRESH: u8 = 4;

    /// The frame.
    pub fn encode(&self) -> RawFrame {
        let [x0, x1] = self.shift[0].to_le_bytes();
        let [y0, y1] = self.shift[1].to_le_bytes();
        let body = [self.from, x0, x1, y0, y1, self.count, self.flags];
        let c = crc8(ids::ADJUST, &body);
        RawFrame {
            id: ids::ADJUST,
            len: 8,
            data: [body[0], x0, x1, y0, y1, self.count, self.flags, c],
        }
    }

    /// Decodes an `ADJUST` frame; `None` if it is not one or its CRC is wrong.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::ADJUST || f.len != 8 || !crc_ok(f.id, f.bytes()) {
            return None;
        }
        let d = &f.data;
        Some(Self {
            from: d[0],
            shift: [
                i16::from_le_bytes([d[1], d[2]]),
                i16::from_le_bytes([d[3], d[4]]),
            ],
            count: d[5],
            flags: d[6],
        })
    }

    /// The shift \[m\].
    pub fn shift_si(&self) -> [f64; 2] {
        [
            f64::from(self.shift[0]) * super::STEP_UNIT,
            f64::from(self.shift[1]) * super::STEP_UNIT,
        ]
    }
}
