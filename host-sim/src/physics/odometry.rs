//! Foot placement from leg odometry: where the stabilizer believes each sole is, from the
//! joint encoders alone (no world position is available to a real robot's stabilizer), and
//! the sole targets it gives the inverse kinematics from that belief.
//!
//! # Why
//!
//! Joint servos lag their targets (a position servo against the load and the joint's
//! damping), so a swing sole commanded to its planned landing touches down a little short of
//! it. A stabilizer that puts the soles at their references in the IK and anchors its state
//! estimate there never learns of that shortfall: the next step is commanded relative to the
//! real (short) stance foot, and the shortfalls add up over a walk. Here each landing is
//! measured, and the next swing is aimed at its planned landing in the world.
//!
//! # Symbols
//!
//! Per foot `k` the estimate `ŝ_k = (x̂_k, ŷ_k, ψ̂_k)` (sole centre and heading in the world),
//! the reference `s_k = (x_k, y_k, ψ_k)` and height `z_k` (the pattern generator's); the
//! forward kinematics of the encoder angles with the waist at the origin in the IMU's
//! attitude gives each sole's position `f_k` and heading `φ_k` (the waist's own position
//! cancels in a difference of two soles).
//!
//! # The estimate
//!
//! * At the start `ŝ_k = s_k` (the robot stands on its plan).
//! * A sole measured from the other sole `j`: `δ = ψ̂_j − φ_j`,
//!   `(x̂_k, ŷ_k) = (x̂_j, ŷ_j) + R(δ) (f_k − f_j)_xy`, `ψ̂_k = φ_k + δ` (`R(δ)` the rotation by
//!   `δ` about the vertical): the other sole's estimated pose composed with the two soles'
//!   relative pose by the encoders. This is done at each touchdown (the contact phase's change
//!   that puts foot `k` on the ground while `j` stands), and again for the landed sole in the
//!   double support that follows, while the less loaded sole carries at least [`FIRM_SHARE`]
//!   of the two soles' vertical force (a landed sole settling, measured until both stand
//!   firmly; a sole rolling onto its edge at lift-off is not measured). Always the landed sole
//!   from the other, never back: each measurement of it is a fresh one, so the encoders' noise
//!   enters once a step.
//! * Otherwise a sole keeps its estimate: a foot on the ground is taken not to move.
//!
//! A constant bias of a pitch joint's encoder enters one step with one sign and the next with
//! the other, so it does not add up; a bias whose effect on the sole does not flip with the
//! leg in front or behind (a hip yaw's, moving the sole sideways) adds up step by step, as in
//! any leg odometry (the realistic sensor model has no bias); random encoder noise adds up as a random walk (1e-4 rad on 0.6 m legs:
//! about 0.1 mm a step). What the encoders cannot see is a standing sole sliding on the floor:
//! that adds up, as it does for any leg odometry (Alexander's stance sole creeps back about
//! 0.5 mm in each single support of its `lateral` walk).
//!
//! # The sole targets
//!
//! * A foot on the ground: its last target low-passed toward `ŝ_k` with the time constant
//!   [`TARGET_FOLLOW_S`] (from where the swing aimed it to where the encoders say it landed,
//!   without a jump at touchdown), at the reference's height `z_k` (the floor is where the
//!   plan says: only the horizontal placement and the heading are estimated).
//! * A swinging foot: `s_k(t) + w(t) e_k`, `e_k` its last target less `s_k` at lift-off (so
//!   the target does not jump there), `w` the blend from the lift-off pose to the reference's
//!   landing: 1 until the reference lifts the foot and while it rises, `z_k / z_peak` while it
//!   comes down (a smooth blend over the second half of the swing, 0 at the reference's
//!   touchdown), 0 once the reference has it back on the ground. The blend needs only the
//!   reference stream, not the landing ahead or the swing's duration, so it also holds when
//!   the node adjusts a step in the middle of a swing. A swing the reference never lifts (a
//!   step height of 0) keeps `w = 1` until the reference's touchdown, where the target moves
//!   by `e_k`.
//!
//! The swing sole so lands at its reference pose in the world less only that step's own
//! servo lag: the legs' shortfalls no longer add up from step to step; a standing sole's
//! creep, which the encoders cannot see, still does (above).
//!
//! # What the stabilizer takes from it
//!
//! The sole targets (not the raw estimate): the stance sole's target in the IK, and the anchor
//! of the COG estimate (each sole's target plus the COG's offset from that sole by the
//! encoders). Just after a touchdown the landed sole's target is still on its way from the
//! planned landing to the estimate (the low-pass above, a few millimetres in 50 ms), and the
//! COG estimate follows it; that was chosen over a jump of the IK's target at touchdown.

use crate::robot::model::{wrap, Pose};
use planner_core::gait::{FootPose, Phase, Side};

/// The leg odometry's state.
#[derive(Clone, Debug, Default)]
pub struct Odometry {
    /// Estimated sole poses (x, y, yaw), left then right; `None` before the first tick.
    est: Option<[[f64; 3]; 2]>,
    /// The sole targets of the last tick (x, y, yaw).
    target: [[f64; 3]; 2],
    /// The feet on the ground at the last tick.
    contact: [bool; 2],
    /// Per foot: the swing's offset `e_k` from its reference at lift-off.
    offset: [[f64; 3]; 2],
    /// Per foot: the reference's highest swing height so far \[m\].
    peak: [f64; 2],
    /// Per foot: the reference has lifted the foot in this swing.
    started: [bool; 2],
    /// Per foot: the reference's swing has passed its peak.
    falling: [bool; 2],
    /// The target's low-pass per tick, `dt / T_r`.
    fade: f64,
    /// The sole that landed last, measured again in double support (none standing).
    newest: Option<usize>,
}

/// The time constant `T_r` with which the target of a foot on the ground follows its
/// estimate (from where the swing aimed it to where the encoders say it is) \[s\].
pub const TARGET_FOLLOW_S: f64 = 0.05;

/// In double support the less loaded sole is measured again from the more loaded one while it
/// carries at least this share of the two soles' vertical force (both then stand firmly: a
/// sole that rolls onto an edge at lift-off or skims the floor is not measured).
pub const FIRM_SHARE: f64 = 0.25;

/// The feet the phase has on the ground (left, right).
pub fn on_ground(phase: Phase) -> [bool; 2] {
    match phase {
        Phase::Single(Side::Left) => [true, false],
        Phase::Single(Side::Right) => [false, true],
        _ => [true, true],
    }
}

/// The heading of a rotation matrix (about the vertical).
fn heading(p: &Pose) -> f64 {
    p.r[1][0].atan2(p.r[0][0])
}

/// `(x, y, yaw)` of a foot pose.
fn xyyaw(f: &FootPose<f64>) -> [f64; 3] {
    [f.x, f.y, f.yaw]
}

impl Odometry {
    /// The odometry before its first tick, at the control period `dt` \[s\].
    pub fn new(dt: f64) -> Self {
        Self {
            fade: (dt / TARGET_FOLLOW_S).min(1.0),
            ..Self::default()
        }
    }

    /// The estimated sole poses (x, y, yaw), left then right (`None` before the first tick).
    pub fn estimate(&self) -> Option<[[f64; 3]; 2]> {
        self.est
    }

    /// One tick: the contact `phase`, the vertical forces on the feet `fz` \[N\], the
    /// reference `r_phase` and `feet`, and the soles by forward kinematics of the encoders
    /// `fk` (waist at the origin, IMU attitude). Returns the sole targets for the IK (left,
    /// right; see the module docs).
    pub fn update(
        &mut self,
        phase: Phase,
        fz: [f64; 2],
        r_phase: Phase,
        feet: &[FootPose<f64>; 2],
        fk: &[Pose; 2],
    ) -> [FootPose<f64>; 2] {
        let on = on_ground(phase);
        let mut est = self.est.unwrap_or_else(|| {
            self.contact = on;
            self.target = [xyyaw(&feet[0]), xyyaw(&feet[1])];
            self.target
        });
        // The sole measured from the other: at a touchdown the landed one from the stance
        // one, and in double support, while both soles are firmly loaded, the one that landed
        // last again from the other (never the other way round: each measurement of it is
        // then a fresh one, and the encoders' noise does not add up in a double support).
        let landed = |k: usize| on[k] && !self.contact[k] && self.contact[1 - k];
        let light = fz[0].min(fz[1]);
        let firm = light >= FIRM_SHARE * (fz[0] + fz[1]).max(f64::MIN_POSITIVE);
        let measured = if landed(0) {
            Some(0)
        } else if landed(1) {
            Some(1)
        } else if on == [true, true] && firm {
            self.newest
        } else {
            None
        };
        if let Some(k) = measured {
            self.newest = Some(k);
        }
        if on != [true, true] {
            // Single support: nothing is measured again until the next touchdown.
            self.newest = None;
        }
        if let Some(k) = measured {
            let j = 1 - k;
            let d = wrap(est[j][2] - heading(&fk[j]));
            let (s, c) = d.sin_cos();
            let (dx, dy) = (fk[k].p[0] - fk[j].p[0], fk[k].p[1] - fk[j].p[1]);
            est[k] = [
                est[j][0] + c * dx - s * dy,
                est[j][1] + s * dx + c * dy,
                wrap(heading(&fk[k]) + d),
            ];
        }
        for k in 0..2 {
            if !on[k] && self.contact[k] {
                // Lift-off: the swing starts from the last target.
                let t = self.target[k];
                self.offset[k] = [t[0] - feet[k].x, t[1] - feet[k].y, wrap(t[2] - feet[k].yaw)];
                self.peak[k] = 0.0;
                self.started[k] = false;
                self.falling[k] = false;
            }
        }
        self.est = Some(est);
        self.contact = on;
        let mut out = *feet;
        for k in 0..2 {
            let f = &feet[k];
            if on[k] {
                let t = &mut self.target[k];
                for i in 0..3 {
                    let e = if i == 2 {
                        wrap(est[k][i] - t[i])
                    } else {
                        est[k][i] - t[i]
                    };
                    t[i] += self.fade * e;
                }
                out[k] = FootPose {
                    x: t[0],
                    y: t[1],
                    z: f.z,
                    yaw: wrap(t[2]),
                };
                continue;
            }
            let ref_swinging = !on_ground(r_phase)[k];
            let w = if !self.started[k] {
                if ref_swinging {
                    self.started[k] = true;
                    self.peak[k] = f.z;
                }
                1.0
            } else if !ref_swinging {
                0.0
            } else {
                if f.z >= self.peak[k] && !self.falling[k] {
                    self.peak[k] = f.z;
                } else if self.peak[k] > 0.0 {
                    self.falling[k] = true;
                }
                if self.falling[k] {
                    (f.z / self.peak[k]).clamp(0.0, 1.0)
                } else {
                    1.0
                }
            };
            let e = self.offset[k];
            out[k] = FootPose {
                x: f.x + w * e[0],
                y: f.y + w * e[1],
                z: f.z,
                yaw: wrap(f.yaw + w * e[2]),
            };
        }
        for k in 0..2 {
            if !on[k] {
                self.target[k] = xyyaw(&out[k]);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f64, y: f64, z: f64, yaw: f64) -> FootPose<f64> {
        FootPose { x, y, z, yaw }
    }

    /// The soles by "forward kinematics" with the waist at `w` (a frame that moves with the
    /// robot: only differences count).
    fn fk(w: [f64; 2], l: [f64; 2], r: [f64; 2]) -> [Pose; 2] {
        [
            Pose::upright(l[0] - w[0], l[1] - w[1], -0.6, 0.0),
            Pose::upright(r[0] - w[0], r[1] - w[1], -0.6, 0.0),
        ]
    }

    /// A swing of the reference from `from` to `to` over `n` ticks (quintic in x, lifted 5 cm).
    fn swing_at(from: f64, to: f64, y: f64, i: usize, n: usize) -> FootPose<f64> {
        let s = i as f64 / n as f64;
        let q = s * (1.0 - s);
        let b = s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
        pose(from + (to - from) * b, y, 0.05 * 64.0 * q * q * q, 0.0)
    }

    const N: usize = 400;
    /// Double support ticks: ten times the target's time constant.
    const DOUBLE: usize = 500;

    #[test]
    fn a_short_landing_is_estimated_and_the_next_step_aims_at_the_plan() {
        let mut o = Odometry::new(0.001);
        let (short, len) = (0.0013, 0.2);
        let (left, right) = ([500.0, 100.0], [100.0, 500.0]);
        // Standing on the plan, then the right foot swings from x = 0 to x = len.
        let start = [pose(0.0, 0.1, 0.0, 0.0), pose(0.0, -0.1, 0.0, 0.0)];
        let at = fk([0.0; 2], [0.0, 0.1], [0.0, -0.1]);
        let out = o.update(Phase::Double, left, Phase::Double, &start, &at);
        assert_eq!(out, start);
        let swing = Phase::Single(Side::Left);
        for i in 0..=N {
            let feet = [start[0], swing_at(0.0, len, -0.1, i, N)];
            let out = o.update(swing, [600.0, 0.0], swing, &feet, &at);
            // The stance sole stays; the swing target is the reference (no offset yet).
            assert_eq!(out[0], start[0]);
            assert!((out[1].x - feet[1].x).abs() < 1e-12);
        }
        // Touchdown 1.3 mm short by the encoders, the waist somewhere else.
        let planned = [pose(0.0, 0.1, 0.0, 0.0), pose(len, -0.1, 0.0, 0.0)];
        let w = [0.37, 0.05];
        let at = fk(w, [0.0, 0.1], [len - short, -0.1]);
        let mut out = [planned[0]; 2];
        let mut last = planned[1];
        for i in 0..DOUBLE {
            out = o.update(Phase::Double, left, Phase::Double, &planned, &at);
            // The landed sole's target moves smoothly from the planned landing to the
            // measured one.
            assert!((out[1].x - last.x).abs() < short * 0.03, "{i}: {out:?}");
            last = out[1];
        }
        let est = o.estimate().expect("estimated");
        assert!((est[1][0] - (len - short)).abs() < 1e-12, "{est:?}");
        assert!((est[1][1] + 0.1).abs() < 1e-12 && est[1][2].abs() < 1e-12);
        assert!((out[1].x - (len - short)).abs() < 1e-6, "{out:?}");
        // The weight onto the right foot, then the left foot swings from x = 0 to 2 len: its
        // target starts where it stood (no jump) and ends at its planned landing in the world,
        // a step of len + short from the real stance foot.
        o.update(Phase::Double, right, Phase::Double, &planned, &at);
        let swing = Phase::Single(Side::Right);
        let mut last = planned[0];
        for i in 0..=N {
            let feet = [swing_at(0.0, 2.0 * len, 0.1, i, N), planned[1]];
            let out = o.update(swing, [0.0, 600.0], swing, &feet, &at);
            assert!((out[1].x - (len - short)).abs() < 1e-6, "stance target");
            assert!(
                (out[0].x - last.x).abs() < 2e-3,
                "a jump of the swing target: {last:?} → {:?}",
                out[0]
            );
            last = out[0];
        }
        assert!((last.x - 2.0 * len).abs() < 1e-12, "{last:?}");
        // The left foot lands on its plan; the right one swings from its short estimate to
        // 3 len: its target starts where the foot is and blends to the planned landing.
        let planned = [pose(2.0 * len, 0.1, 0.0, 0.0), pose(len, -0.1, 0.0, 0.0)];
        let at = fk(w, [2.0 * len, 0.1], [len - short, -0.1]);
        for _ in 0..DOUBLE {
            o.update(Phase::Double, right, Phase::Double, &planned, &at);
        }
        let est = o.estimate().expect("estimated");
        assert!((est[0][0] - 2.0 * len).abs() < 1e-12, "{est:?}");
        o.update(Phase::Double, left, Phase::Double, &planned, &at);
        let swing = Phase::Single(Side::Left);
        let mut first = None;
        for i in 0..=N {
            let feet = [planned[0], swing_at(len, 3.0 * len, -0.1, i, N)];
            let out = o.update(swing, [600.0, 0.0], swing, &feet, &at);
            first.get_or_insert(out[1]);
            if i <= N / 2 {
                // Rising: the whole offset.
                assert!((out[1].x - (feet[1].x - short)).abs() < 1e-6, "{out:?}");
            }
            last = out[1];
        }
        let first = first.expect("a tick");
        assert!((first.x - (len - short)).abs() < 1e-6, "{first:?}");
        assert!((last.x - 3.0 * len).abs() < 1e-12, "{last:?}");
    }

    #[test]
    fn a_turned_stance_turns_the_measured_step() {
        // The stance sole estimated at heading 0.1 rad while the encoders' frame has it at 0:
        // the measured step is turned by 0.1 rad into the world.
        let mut o = Odometry::new(0.001);
        let (s, c) = 0.1f64.sin_cos();
        let start = [
            pose(1.0, 2.0, 0.0, 0.1),
            pose(1.0 + 0.2 * s, 2.0 - 0.2 * c, 0.0, 0.1),
        ];
        let level = [
            Pose::upright(0.0, 0.1, -0.6, 0.0),
            Pose::upright(0.0, -0.1, -0.6, 0.0),
        ];
        let left = [500.0, 100.0];
        o.update(Phase::Double, left, Phase::Double, &start, &level);
        let swing = Phase::Single(Side::Left);
        o.update(swing, [600.0, 0.0], swing, &start, &level);
        let landed = [level[0], Pose::upright(0.2, -0.1, -0.6, 0.05)];
        o.update(Phase::Double, left, Phase::Double, &start, &landed);
        let est = o.estimate().expect("estimated");
        let want = [1.0 + c * 0.2 + s * 0.2, 2.0 + s * 0.2 - c * 0.2, 0.15];
        for i in 0..3 {
            assert!((est[1][i] - want[i]).abs() < 1e-12, "{est:?} {want:?}");
        }
    }

    /// Standing, a right step of `len` from x = 0 to its touchdown, `fk_right` the encoders'
    /// right sole there (the left one at its plan): the odometry and the planned feet after it.
    fn step_right(len: f64, fk_right: [f64; 2]) -> (Odometry, [FootPose<f64>; 2]) {
        let mut o = Odometry::new(0.001);
        let start = [pose(0.0, 0.1, 0.0, 0.0), pose(0.0, -0.1, 0.0, 0.0)];
        let at = fk([0.0; 2], [0.0, 0.1], [0.0, -0.1]);
        o.update(Phase::Double, [500.0, 100.0], Phase::Double, &start, &at);
        let swing = Phase::Single(Side::Left);
        for i in 0..=N {
            let feet = [start[0], swing_at(0.0, len, -0.1, i, N)];
            o.update(swing, [600.0, 0.0], swing, &feet, &at);
        }
        let planned = [start[0], pose(len, -0.1, 0.0, 0.0)];
        let at = fk([0.2, 0.0], [0.0, 0.1], fk_right);
        // The touchdown itself, the landed sole lightly loaded.
        o.update(Phase::Double, [550.0, 50.0], Phase::Double, &planned, &at);
        (o, planned)
    }

    #[test]
    fn a_landed_sole_is_measured_again_only_while_both_stand_firmly() {
        let len = 0.2;
        let (mut o, planned) = step_right(len, [len - 0.002, -0.1]);
        let est = |o: &Odometry| o.estimate().expect("estimated");
        assert!(
            (est(&o)[1][0] - (len - 0.002)).abs() < 1e-12,
            "{:?}",
            est(&o)
        );
        // The sole settles 1 mm further back while it carries less than FIRM_SHARE of the
        // load: not measured again.
        let settled = fk([0.2, 0.0], [0.0, 0.1], [len - 0.003, -0.1]);
        let light = 0.9 * FIRM_SHARE * 600.0;
        for _ in 0..10 {
            o.update(
                Phase::Double,
                [600.0 - light, light],
                Phase::Double,
                &planned,
                &settled,
            );
            assert!(
                (est(&o)[1][0] - (len - 0.002)).abs() < 1e-12,
                "{:?}",
                est(&o)
            );
        }
        // Both firmly loaded: measured again, from the stance sole, whose estimate stays.
        let firm = 1.1 * FIRM_SHARE * 600.0;
        o.update(
            Phase::Double,
            [600.0 - firm, firm],
            Phase::Double,
            &planned,
            &settled,
        );
        let e = est(&o);
        assert!((e[1][0] - (len - 0.003)).abs() < 1e-12, "{e:?}");
        assert_eq!(
            e[0],
            [0.0, 0.1, 0.0],
            "the stance sole is never measured back"
        );
        // The encoders now put the left sole 1 mm forward (the relative pose changed): still
        // the landed sole is measured from the left one, never the left one from it.
        let moved = fk([0.2, 0.0], [0.001, 0.1], [len - 0.003, -0.1]);
        o.update(
            Phase::Double,
            [firm, 600.0 - firm],
            Phase::Double,
            &planned,
            &moved,
        );
        let e = est(&o);
        assert_eq!(e[0], [0.0, 0.1, 0.0]);
        assert!((e[1][0] - (len - 0.004)).abs() < 1e-12, "{e:?}");
        // Single support on the right sole: nothing is measured, whatever the encoders say.
        let swing = Phase::Single(Side::Right);
        let wild = fk([0.0; 2], [0.3, 0.2], [0.5, -0.4]);
        let before = est(&o);
        for i in 0..N / 4 {
            let feet = [swing_at(0.0, 2.0 * len, 0.1, i, N), planned[1]];
            o.update(swing, [0.0, 600.0], swing, &feet, &wild);
            assert_eq!(est(&o), before);
        }
        // A firm double support that follows no touchdown (standing from the start) measures
        // nothing either.
        let mut o = Odometry::new(0.001);
        let start = [pose(0.0, 0.1, 0.0, 0.0), pose(0.0, -0.1, 0.0, 0.0)];
        let off = fk([0.0; 2], [0.0, 0.1], [0.01, -0.1]);
        for _ in 0..10 {
            o.update(Phase::Double, [300.0, 300.0], Phase::Double, &start, &off);
        }
        assert_eq!(est(&o), [[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]]);
    }

    #[test]
    fn a_yaw_offset_blends_out_through_a_turning_swing_across_pi() {
        // Both soles at heading 3.1 rad, the encoders' frame aligned with the world. The right
        // sole lands turned 0.01 rad from its plan; its next swing turns 0.0832 rad, across ±π.
        let h = 3.1;
        let stand = [pose(0.0, 0.1, 0.0, h), pose(0.0, -0.1, 0.0, h)];
        let level = [
            Pose::upright(0.0, 0.1, -0.6, h),
            Pose::upright(0.0, -0.1, -0.6, h),
        ];
        let turned = [level[0], Pose::upright(0.0, -0.1, -0.6, h + 0.01)];
        let mut o = Odometry::new(0.001);
        let left = [500.0, 100.0];
        o.update(Phase::Double, left, Phase::Double, &stand, &level);
        let swing = Phase::Single(Side::Left);
        o.update(swing, [600.0, 0.0], swing, &stand, &level);
        for _ in 0..DOUBLE {
            o.update(Phase::Double, left, Phase::Double, &stand, &turned);
        }
        let e = o.estimate().expect("estimated");
        assert!((e[1][2] - (h + 0.01)).abs() < 1e-12, "{e:?}");
        // The turning swing: its target starts at the landed heading and ends at the
        // reference's, without a jump, every heading in (−π, π].
        let turn = 0.0832;
        let mut last: Option<FootPose<f64>> = None;
        for i in 0..=N {
            let mut f = swing_at(0.0, 0.0, -0.1, i, N);
            let s = i as f64 / N as f64;
            f.yaw = wrap(h + turn * s * s * s * (10.0 + s * (-15.0 + 6.0 * s)));
            let feet = [stand[0], f];
            let out = o.update(swing, [600.0, 0.0], swing, &feet, &turned);
            let y = out[1].yaw;
            assert!(
                y > -core::f64::consts::PI && y <= core::f64::consts::PI,
                "{y}"
            );
            match last {
                None => assert!(wrap(y - (h + 0.01)).abs() < 1e-6, "a jump at lift-off: {y}"),
                Some(l) => assert!(wrap(y - l.yaw).abs() < 2e-3, "a jump: {} → {y}", l.yaw),
            }
            last = Some(out[1]);
        }
        let end = last.expect("a tick");
        assert!(wrap(end.yaw - wrap(h + turn)).abs() < 1e-12, "{end:?}");
        assert!(end.yaw < 0.0, "across π: {end:?}");
    }

    #[test]
    fn a_contact_flickering_mid_swing_is_overwritten_by_the_landing() {
        let (len, short) = (0.2, 0.0013);
        let mut o = Odometry::new(0.001);
        let start = [pose(0.0, 0.1, 0.0, 0.0), pose(0.0, -0.1, 0.0, 0.0)];
        let at = fk([0.0; 2], [0.0, 0.1], [0.0, -0.1]);
        o.update(Phase::Double, [500.0, 100.0], Phase::Double, &start, &at);
        let swing = Phase::Single(Side::Left);
        let flicker = 3 * N / 4;
        let mut last: Option<FootPose<f64>> = None;
        for i in 0..=N {
            let feet = [start[0], swing_at(0.0, len, -0.1, i, N)];
            // One tick of contact while the reference descends; the encoders put the sole
            // 30 mm behind its reference there (a servo lagging mid-swing).
            let (phase, fz, enc) = if i == flicker {
                let x = feet[1].x - 0.03;
                (
                    Phase::Double,
                    [590.0, 10.0],
                    fk([0.0; 2], [0.0, 0.1], [x, -0.1]),
                )
            } else {
                (swing, [600.0, 0.0], at)
            };
            let out = o.update(phase, fz, swing, &feet, &enc);
            assert_eq!(out[0], start[0], "the stance sole's target stays");
            if let Some(l) = last {
                assert!(
                    (out[1].x - l.x).abs() < 2e-3,
                    "a jump: {l:?} → {:?}",
                    out[1]
                );
            }
            last = Some(out[1]);
            let e = o.estimate().expect("estimated");
            assert_eq!(e[0], [0.0, 0.1, 0.0], "the stance sole's estimate stays");
        }
        // The swing still ends on its reference, and the landing replaces the flicker's
        // measurement.
        let end = last.expect("a tick");
        assert!((end.x - len).abs() < 1e-12, "{end:?}");
        let planned = [start[0], pose(len, -0.1, 0.0, 0.0)];
        let landed = fk([0.1, 0.0], [0.0, 0.1], [len - short, -0.1]);
        o.update(
            Phase::Double,
            [550.0, 50.0],
            Phase::Double,
            &planned,
            &landed,
        );
        let e = o.estimate().expect("estimated");
        assert!((e[1][0] - (len - short)).abs() < 1e-12, "{e:?}");
    }
}
