//! The engine's waist search ([`Robot::solve_waist`]): where to put the waist so that the
//! whole-body COG follows its target with the soles where the reference has them.

use planner_core::gait::Side;

use super::model::Robot;
use crate::robot::model::{LegAngles, Pose, Vec3};

/// The waist search's step tries: the whole Newton step and four halvings of it.
const WAIST_HALVINGS: usize = 5;

impl Robot {
    /// Finds the waist position (orientation `r`, at height `z`) that puts the whole-body COG
    /// at `target` (x, y) with the soles at `soles`: Newton's method as in
    /// [`crate::robot::model::Model::solve_waist`], but for any waist orientation, each step
    /// taken only as far as it brings the COG nearer the target (so that a saturated leg,
    /// whose COG Jacobian is rough, never throws the waist away from the feet). Returns the
    /// waist pose and the joint angles.
    pub fn solve_waist(
        &self,
        waist: Pose,
        soles: &[Pose; 2],
        target: [f64; 2],
    ) -> Result<(Pose, [LegAngles; 2]), String> {
        const H: f64 = 1e-6;
        let cog = |w: &Pose| -> Result<(Vec3, [LegAngles; 2]), String> {
            let q = [
                self.leg_ik(Side::Left, w, &soles[0])?,
                self.leg_ik(Side::Right, w, &soles[1])?,
            ];
            Ok((self.fk(w, &q).2, q))
        };
        let mut w = waist;
        let (mut c, mut q) = cog(&w)?;
        for _ in 0..8 {
            let e = [target[0] - c[0], target[1] - c[1]];
            let err = e[0].hypot(e[1]);
            if err < 1e-9 {
                return Ok((w, q));
            }
            let mut wx = w;
            wx.p[0] += H;
            let mut wy = w;
            wy.p[1] += H;
            let (cx, _) = cog(&wx)?;
            let (cy, _) = cog(&wy)?;
            let j = [
                [(cx[0] - c[0]) / H, (cy[0] - c[0]) / H],
                [(cx[1] - c[1]) / H, (cy[1] - c[1]) / H],
            ];
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det.abs() < 1e-9 || !det.is_finite() {
                return Err("waist search: singular COG Jacobian".into());
            }
            let d = [
                (j[1][1] * e[0] - j[0][1] * e[1]) / det,
                (-j[1][0] * e[0] + j[0][0] * e[1]) / det,
            ];
            // The whole Newton step where it brings the COG nearer the target (near the
            // solution, always), else half of it, down to 1/16; where none does (a leg at the
            // end of its reach, its inverse kinematics saturated), the search stops here.
            let mut t = 1.0;
            let mut moved = false;
            for _ in 0..WAIST_HALVINGS {
                let mut wt = w;
                wt.p[0] += t * d[0];
                wt.p[1] += t * d[1];
                if let Ok((ct, qt)) = cog(&wt) {
                    if (target[0] - ct[0]).hypot(target[1] - ct[1]) < err {
                        (w, c, q, moved) = (wt, ct, qt, true);
                        break;
                    }
                }
                t *= 0.5;
            }
            if !moved {
                break;
            }
        }
        Ok((w, q))
    }
}
