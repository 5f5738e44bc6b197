//! The footstep frames: units and field widths, `STEP_APPEND` ([`WireStep`]), `STEP_MODIFY`
//! ([`WireModify`]) and the controller's [`StepBook`].

use super::{crc8_keyed, ids, Command, Reason};
use crate::real::Real;

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
/// Versions of a footstep: 0 (as appended) … `VERSIONS − 1` (its 127th modification).
/// Versions never wrap: a step is modified at most 127 times.
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
    /// Step number (the frame carries its low byte, its CRC the high byte).
    pub id: u16,
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
    pub fn from_si(id: u16, left: bool, x: f64, y: f64, yaw: f64) -> Option<Self> {
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

    /// [`WireStep::si`] in the scalar `T`, computed in `T` (`x · STEP_UNIT` with both rounded
    /// to `T`: for `f64` exactly `si`; for `f32` no double-precision operation).
    pub fn si_in<T: Real>(&self) -> (T, T, T) {
        (
            T::of_i32(self.x) * T::of(STEP_UNIT),
            T::of_i32(self.y) * T::of(STEP_UNIT),
            T::of_i32(i32::from(self.yaw)) * T::of(YAW_UNIT),
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
    pub(super) fn pack(&self) -> [u8; 8] {
        let mut bits: u64 = u64::from(self.id & 0xFF);
        bits |= u64::from(self.left as u8) << 8;
        bits |= field(self.x, STEP_BITS) << 10;
        bits |= field(self.y, STEP_BITS) << 27;
        bits |= field(i32::from(self.yaw), YAW_BITS) << 44;
        let mut d = bits.to_le_bytes();
        d[7] = crc8_keyed(ids::STEP_APPEND, super::step_key(self.id), &d[..7]);
        d
    }

    /// Fields of a `STEP_APPEND` frame whose CRC was checked, as step number `id` (whose low
    /// byte the frame carries).
    pub(super) fn unpack(data: &[u8; 8], id: u16) -> Result<Self, Reason> {
        let bits = u64::from_le_bytes(*data);
        if (bits >> 9) & 1 != 0 {
            return Err(Reason::OutOfRange);
        }
        Ok(Self {
            id,
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
    /// Step number (the frame carries its low byte, its CRC the high byte).
    pub id: u16,
    /// Version, 1 … 127: greater than every version of the step before it (the append is
    /// version 0).
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
    /// as version `version`; `None` if the version is not 1 … 127, the offset out of range or
    /// a value not finite.
    pub fn from_si(base: &WireStep, version: u8, x: f64, y: f64, yaw: f64) -> Option<Self> {
        if version == 0 || version >= VERSIONS {
            return None;
        }
        // Offsets on the wire grid: the new position rounded, minus the appended one.
        let x = quantise(x, STEP_UNIT, STEP_BITS)?;
        let y = quantise(y, STEP_UNIT, STEP_BITS)?;
        let (min, max) = signed_range(OFFSET_BITS);
        let (dx, dy) = (x - base.x, y - base.y);
        ((min..=max).contains(&dx) && (min..=max).contains(&dy)).then_some(Self {
            id: base.id,
            version,
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

    /// `true` if `self.version` is newer than `current` (greater: versions never wrap).
    pub fn is_newer_than(&self, current: u8) -> bool {
        self.version > current
    }

    pub(super) fn pack(&self) -> [u8; 8] {
        let mut bits: u64 = u64::from(self.id & 0xFF);
        bits |= u64::from(self.version % VERSIONS) << 8;
        bits |= u64::from(self.left as u8) << 15;
        bits |= field(self.dx, OFFSET_BITS) << 16;
        bits |= field(self.dy, OFFSET_BITS) << 30;
        bits |= field(i32::from(self.yaw), YAW_BITS) << 44;
        let mut d = bits.to_le_bytes();
        d[7] = crc8_keyed(ids::STEP_MODIFY, super::step_key(self.id), &d[..7]);
        d
    }

    /// Fields of a `STEP_MODIFY` frame whose CRC was checked, as step number `id`.
    pub(super) fn unpack(data: &[u8; 8], id: u16) -> Self {
        let bits = u64::from_le_bytes(*data);
        Self {
            id,
            version: ((bits >> 8) & 0x7F) as u8,
            left: (bits >> 15) & 1 == 1,
            dx: sign_extend(bits >> 16, OFFSET_BITS),
            dy: sign_extend(bits >> 30, OFFSET_BITS),
            yaw: sign_extend(bits >> 44, YAW_BITS) as i16,
        }
    }
}

/// What a controller keeps to speak the footstep protocol: the appended position and the
/// version of the last modification of the last 256 step numbers (no_std, about 4 KB).
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

    fn slot(&self, id: u16) -> Option<(WireStep, u8)> {
        self.steps[usize::from(id & 0xFF)].filter(|(s, _)| s.id == id)
    }

    /// The `STEP_APPEND` of step number `id` at `(x, y, yaw)`; `None` if not representable.
    pub fn append(&mut self, id: u16, left: bool, x: f64, y: f64, yaw: f64) -> Option<Command> {
        let s = WireStep::from_si(id, left, x, y, yaw)?;
        self.steps[usize::from(id & 0xFF)] = Some((s, 0));
        Some(Command::Append(s))
    }

    /// The next `STEP_MODIFY` of step `id` to `(x, y, yaw)` (one version newer than the last
    /// one made here); `None` if the step was not appended here (or has been overwritten by
    /// a step 256 numbers later), if it has had its 127 versions, or if the offset from its
    /// appended position is out of range.
    pub fn modify(&mut self, id: u16, x: f64, y: f64, yaw: f64) -> Option<Command> {
        let (base, v) = self.slot(id)?;
        let m = WireModify::from_si(&base, v.checked_add(1)?, x, y, yaw)?;
        self.steps[usize::from(id & 0xFF)] = Some((base, m.version));
        Some(Command::Modify(m))
    }

    /// The append of step `id` as recorded, if any.
    pub fn appended(&self, id: u16) -> Option<WireStep> {
        self.slot(id).map(|(s, _)| s)
    }

    /// The version of the last modification of step `id` made here (0: none), if known.
    pub fn version(&self, id: u16) -> Option<u8> {
        self.slot(id).map(|(_, v)| v)
    }

    /// Forgets every step.
    pub fn clear(&mut self) {
        self.steps = [None; 256];
    }
}
