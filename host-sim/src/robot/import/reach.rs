//! The imported reach limits against the legs: every corner of the region the node's
//! [`Reach`] admits is checked with the leg's inverse kinematics, with a stated margin.
//!
//! The corners are the steps at the edges of the limits (in the support foot's frame: the
//! forward step `max_forward` less the turn's cost and the backward step `max_backward`, each
//! at the width `min_width` and `max_width`, and the widest step with none forward; where the pair is farther apart than
//! `max_feet_distance`, the two points where that circle meets the box), each with no turn and
//! with `±max_yaw`, for a left and a right step. A corner is reached when both legs' inverse
//! kinematics converges with
//!
//! * the feet [`STRETCH_M`] farther apart than the corner (along the line between them), and
//! * the waist at its standing height and the feet's mean heading, anywhere from
//!   `0.5 − WAIST_SPREAD` to `0.5 + WAIST_SPREAD` of the way from one sole centre to the other
//!   (checked at both ends and midway): at a step's lift-off and touchdown the centre of mass
//!   is not midway between the feet. In a steady walk of the longest steps it is about 8 % of
//!   the step off (the LIPM's sway over half of HRP-2's 0.1 s double support), and the
//!   stabilizer moves the commanded COG by up to 0.04 m more (about 12 % of a 0.33 m step);
//!   a capture step after a push landed G1's waist 71 % of the way to the front foot (a
//!   0.335 m step, the reach of the limits before this check). A leg whose hip axes are offset
//!   reaches less far in some directions than the sum of its joint distances, and the
//!   engine's waist search fails where a leg's inverse kinematics does not converge;
//!
//! and, with the waist midway, every joint is inside its range ([`posture::out_of_range`]).
//! A raised swing foot is nearer its hip than the same foot on the floor, so the floor poses
//! are the swing's worst.

use planner_core::gait::Side;
use planner_core::node::Reach;

use super::posture;
use crate::robot::model::{side_index, Model, Pose};

/// The feet this much farther apart than each corner \[m\].
pub const STRETCH_M: f64 = 0.01;

/// The waist from `0.5 − WAIST_SPREAD` to `0.5 + WAIST_SPREAD` of the way between the feet.
pub const WAIST_SPREAD: f64 = 0.2;

/// A step at a corner of the limits: forward and width in the support foot's frame (width
/// positive away from the support foot, on the stepping side) \[m\], and the heading change
/// \[rad\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// Forward \[m\].
    pub forward: f64,
    /// Across \[m\].
    pub width: f64,
    /// Heading change \[rad\].
    pub yaw: f64,
}

/// The corners of the region `r` admits (see the module docs).
pub fn corners(r: &Reach) -> Vec<Corner> {
    let d = r.max_feet_distance;
    let mut out = Vec::new();
    for yaw in [0.0, r.max_yaw, -r.max_yaw] {
        let front = r.max_forward - r.yaw_cost * yaw.abs();
        for (forward, widths) in [
            (front, &[r.min_width, r.max_width][..]),
            (-r.max_backward, &[r.min_width, r.max_width][..]),
            (0.0, &[r.max_width][..]),
        ] {
            for &width in widths {
                let mut push = |forward: f64, width: f64| {
                    out.push(Corner {
                        forward,
                        width,
                        yaw,
                    })
                };
                if forward.hypot(width) <= d {
                    push(forward, width);
                    continue;
                }
                // The feet-distance circle: where it crosses the box's edges.
                if width < d {
                    push(forward.signum() * (d * d - width * width).sqrt(), width);
                }
                let across = (d * d - forward * forward).max(0.0).sqrt();
                if (r.min_width..=r.max_width).contains(&across) {
                    push(forward, across);
                }
            }
        }
    }
    out
}

/// The feet for a step `c` of the `side` foot from the other foot at the origin (the step
/// stretched by `stretch` metres along the line between the sole centres), left first.
pub fn feet(c: &Corner, side: Side, stretch: f64) -> [Pose; 2] {
    let sign = if side == Side::Left { 1.0 } else { -1.0 };
    let (x, y) = (c.forward, sign * c.width);
    let k = 1.0 + stretch / x.hypot(y);
    let step = Pose::upright(k * x, k * y, 0.0, c.yaw);
    let support = Pose::upright(0.0, 0.0, 0.0, 0.0);
    let mut f = [support; 2];
    f[side_index(side)] = step;
    f
}

/// The first corner of `r` the legs of `m` do not reach with the margins of the module docs,
/// described; `None` when every one is reached.
pub fn unreached(m: &Model, r: &Reach) -> Option<String> {
    for c in corners(r) {
        for side in [Side::Left, Side::Right] {
            let soles = feet(&c, side, STRETCH_M);
            let (a, b) = (soles[0].p, soles[1].p);
            for t in [0.5, 0.5 - WAIST_SPREAD, 0.5 + WAIST_SPREAD] {
                let waist = Pose::upright(
                    a[0] + t * (b[0] - a[0]),
                    a[1] + t * (b[1] - a[1]),
                    m.waist_height,
                    0.5 * c.yaw,
                );
                let what = format!(
                    "a {side:?} step {:.3} m forward, {:.3} m across, turned {:.2} rad \
                     (+{STRETCH_M} m), the waist {t} of the way from the left sole to the right",
                    c.forward, c.width, c.yaw
                );
                match m.cog(&waist, &soles) {
                    Err(e) => return Some(format!("{what}: {e}")),
                    Ok((_, q)) if t == 0.5 => {
                        for s in [Side::Left, Side::Right] {
                            if let Some(why) = posture::out_of_range(m, s, &q[side_index(s)], &what)
                            {
                                return Some(why);
                            }
                        }
                    }
                    Ok(_) => {}
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::gait::Footstep;

    #[test]
    fn corners_are_admitted_by_the_node_and_on_its_edges() {
        let r = Reach::default();
        let soles = planner_core::node::Soles {
            half_length: 0.1,
            half_width: 0.05,
        };
        let cs = corners(&r);
        // No turn: forward 0.30 m at 0.15 m across, where the feet-distance circle (0.361 m)
        // meets the box at 0.28 m across and at 0.30 m forward (two), backward at both widths,
        // the widest step; turned either way (0.21 m forward left), the box's four and the
        // widest step.
        assert_eq!(cs.len(), 6 + 5 + 5, "{cs:?}");
        for c in &cs {
            let step = |k: f64| Footstep {
                side: Side::Left,
                x: k * c.forward,
                y: k * c.width,
                yaw: c.yaw,
            };
            let other = Footstep {
                side: Side::Right,
                x: 0.0,
                y: 0.0,
                yaw: 0.0,
            };
            // The step before: 0.1 m (the stride and growth limits leave the corners alone).
            let same = Footstep {
                side: Side::Left,
                x: -0.1,
                y: 0.2,
                yaw: 0.0,
            };
            let broken = |k| r.broken(&other, &same, &step(k), false, &soles);
            assert_eq!(broken(1.0 - 1e-9).map(|b| b.limit), None, "{c:?}");
            // A little farther out, a limit breaks (growth and stride aside, the region's edge).
            assert!(broken(1.02).is_some(), "{c:?}");
        }
    }
}
