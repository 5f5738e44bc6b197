//! The 5 ms reference stream (`COG`, `ZMP`, `COG_VEL`, `FOOT_LEFT`, `FOOT_RIGHT`) and its
//! saturating fixed-point encoding.

use super::{ids, RawFrame, FOOT_UNIT};
use crate::real::Real;

/// Largest magnitude of a 20-bit field.
const I20_MAX: i32 = (1 << 19) - 1;

/// `libm::round(x)` (halves away from zero; `libm::roundf` for `f32`) as an `i32`, saturated
/// at the `i32` range, `NaN` to 0: one hardware conversion (`vcvt`, truncating) and an exact
/// correction, instead of libm's bit manipulation. `x − trunc(x)` is exact for every `x` whose
/// truncation fits an `i32` (below 2⁵² for `f64`, 2²³ for `f32`, it keeps the fraction's bits;
/// above, `x` is an integer and the difference is 0); beyond the range the truncation
/// saturates and the correction saturates too.
pub(super) fn round_to_i32<T: Real>(x: T) -> i32 {
    let t = x.trunc_i32();
    let frac = x - T::of_i32(t);
    let half = T::of(0.5);
    if frac >= half {
        t.saturating_add(1)
    } else if frac <= -half {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Saturating conversion to a fixed-point integer of `unit` (`v / unit` in `T`).
fn fixed<T: Real>(v: T, unit: f64, min: i32, max: i32) -> i32 {
    if !v.is_finite() {
        return 0;
    }
    round_to_i32(v / T::of(unit)).clamp(min, max)
}

/// The 5 ms reference stream (what the node publishes every control cycle), in the node's
/// scalar `T`; the frames are the same fixed-point integers for both scalars (each value
/// divided by its unit and rounded in `T`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stream<T = f64> {
    /// COG x, y \[m\].
    pub cog: [T; 2],
    /// COG velocity \[m/s\].
    pub cog_vel: [T; 2],
    /// ZMP x, y \[m\].
    pub zmp: [T; 2],
    /// Phase: 0 standing, 1 double support, 2 single support on the left foot, 3 on the right.
    pub phase: u8,
    /// The low 24 bits of the node's cycle counter (the stamp a measured state names).
    pub tick: u32,
    /// Left and right foot: x, y, z \[m\], yaw \[rad\].
    pub feet: [[T; 4]; 2],
}

impl<T: Real> Stream<T> {
    /// The five frames of one cycle, in identifier order.
    pub fn encode(&self) -> [RawFrame; 5] {
        let um = |v: T| fixed(v, 1e-6, i32::MIN, i32::MAX);
        let pos = |id: u16, p: [T; 2]| {
            let (a, b) = (um(p[0]).to_le_bytes(), um(p[1]).to_le_bytes());
            RawFrame {
                id,
                len: 8,
                data: [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]],
            }
        };
        let vel = |v: T| fixed(v, 1e-4, i16::MIN.into(), i16::MAX.into()) as i16;
        let (vx, vy) = (
            vel(self.cog_vel[0]).to_le_bytes(),
            vel(self.cog_vel[1]).to_le_bytes(),
        );
        let foot = |id: u16, f: [T; 4]| {
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
            {
                let [t0, t1, t2, _] = self.tick.to_le_bytes();
                RawFrame {
                    id: ids::COG_VEL,
                    len: 8,
                    data: [vx[0], vx[1], vy[0], vy[1], self.phase, t0, t1, t2],
                }
            },
            foot(ids::FOOT_LEFT, self.feet[0]),
            foot(ids::FOOT_RIGHT, self.feet[1]),
        ]
    }
}

impl Stream<f64> {
    /// Updates the fields carried by one stream frame; `false` if it is not a stream frame.
    /// Every value it gives encodes ([`Stream::encode`]) to a frame that decodes to it again.
    pub fn decode_into(&mut self, f: &RawFrame) -> bool {
        let d = &f.data;
        let i32at = |i: usize| i32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        match (f.id, f.len) {
            (ids::COG, 8) => self.cog = [f64::from(i32at(0)) * 1e-6, f64::from(i32at(4)) * 1e-6],
            (ids::ZMP, 8) => self.zmp = [f64::from(i32at(0)) * 1e-6, f64::from(i32at(4)) * 1e-6],
            (ids::COG_VEL, 8) => {
                self.cog_vel = [
                    f64::from(i16::from_le_bytes([d[0], d[1]])) * 1e-4,
                    f64::from(i16::from_le_bytes([d[2], d[3]])) * 1e-4,
                ];
                self.phase = d[4];
                self.tick = u32::from_le_bytes([d[5], d[6], d[7], 0]);
            }
            (ids::FOOT_LEFT | ids::FOOT_RIGHT, 8) => {
                let bits = u64::from_le_bytes(*d);
                let sx = |v: u64, n: u32| -> i64 { (v << (64 - n)) as i64 >> (64 - n) };
                // The one 20-bit code below the documented range (−2¹⁹; the encoder saturates
                // at ±(2¹⁹ − 1), as the DBC's [−52.4287, 52.4287] m) reads as the range's end.
                let x20 = |v: u64| sx(v, 20).max(-i64::from(I20_MAX)) as f64 * FOOT_UNIT;
                let k = usize::from(f.id == ids::FOOT_RIGHT);
                self.feet[k] = [
                    x20(bits & 0xF_FFFF),
                    x20((bits >> 20) & 0xF_FFFF),
                    ((bits >> 40) & 0xFF) as f64 * 5e-4,
                    sx((bits >> 48) & 0xFFFF, 16) as f64 * 1e-4,
                ];
            }
            _ => return false,
        }
        true
    }
}
