//! The multi-body model of a robot: its bodies, frames, forward and inverse kinematics, and
//! the waist placement that puts the whole-body COG on the planner's.
//! [`crate::eval::multibody`] computes the ZMP of a walk on it; [`crate::physics`] writes its
//! MuJoCo model from it.
//!
//! # The model
//!
//! A floating **waist** (the root link, 6 DoF) and two **legs** of six revolute joints each,
//! in any order and about any axes. Frames: world x forward, y left, z up, the floor at
//! z = 0. Each leg link `i` (hip first) has a joint: its origin `O_i` (a pose in the frame of
//! the link before it, the waist frame for the first) and its unit axis `a_i` in its own
//! frame, so the link's frame is
//!
//! `T_i = T_{i−1} O_i Rot(a_i, q_i)`, `T_0` = the waist pose,
//!
//! and the **sole centre** is a fixed pose `S` in the last link's frame (the ankle frame):
//! `T_sole = T_6 S`. The rest of the robot (pelvis, torso, arms, head) is rigid: its bodies
//! are fixed to the waist frame ([`Model::root`]).
//!
//! Every body has a mass, a centre of mass `c` and an inertia tensor `I` about `c`, both in
//! its link's frame; placed by a link pose `(p, R)` its centre is `p + R c` and its world
//! inertia `R I Rᵀ`.
//!
//! # Inverse kinematics
//!
//! Where the leg is HRP-2's shape (hip yaw–roll–pitch about one point, knee pitch, ankle
//! pitch–roll about one point, the sole straight below the ankle; [`ClosedForm`]) the
//! closed form of [`Model::leg_ik`] applies. Otherwise the angles are found by Newton's method
//! on the sole's pose error `e = (p* − p, log(R* Rᵀ))` with the geometric Jacobian
//! `J_i = (a_i × (p − p_i), a_i)` (world axis `a_i` through the joint's origin `p_i`),
//! damped (`(JᵀJ + λ²I) Δq = Jᵀe`, λ = [`IK_DAMPING`]) while the error is above a millimetre
//! and undamped after, from the standing posture ([`Model::stance`]); it converges to the
//! pose within [`IK_TOLERANCE`] or fails with [`IkError`]: out of reach where the ankle is
//! farther from the hip than the sum of the joint-to-joint distances, else not reached (with
//! offsets between a leg's axes its reach in a direction is shorter than that sum).

use core::fmt;

use planner_core::gait::{FootPose, Side};

pub use super::frame::*;

/// Newton iterations per tick at most in the waist search.
pub const MAX_ITERATIONS: usize = 50;
/// The waist search stops when the whole-body COG is this close to the reference \[m\].
/// Far below the 1e-9 m asked for, because the second difference multiplies position noise by
/// 4/dt² = 1.6e5 s⁻² (1e-10 m of noise would be up to 1.3e-6 m of ZMP, 1e-13 m is 1.3e-9 m).
pub const COG_TOLERANCE: f64 = 1e-13;
/// The numerical inverse kinematics stops when the sole's position and rotation errors
/// (\[m\] + \[rad\]) are below this.
pub const IK_TOLERANCE: f64 = 1e-14;
/// Damping of the numerical inverse kinematics while the error is above 1 mm.
pub const IK_DAMPING: f64 = 0.02;
/// Iterations of the numerical inverse kinematics at most.
pub const IK_ITERATIONS: usize = 60;

/// A rigid body: mass, centre of mass and inertia tensor in its link frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Mass \[kg\].
    pub mass: f64,
    /// Centre of mass in the link frame \[m\].
    pub com: Vec3,
    /// Inertia tensor about the centre of mass, in link-frame axes \[kg m²\].
    pub inertia: Mat3,
}

fn diagonal(i: Vec3) -> Mat3 {
    [[i[0], 0.0, 0.0], [0.0, i[1], 0.0], [0.0, 0.0, i[2]]]
}

impl Body {
    /// A massless body.
    pub const NONE: Body = Body {
        mass: 0.0,
        com: [0.0; 3],
        inertia: [[0.0; 3]; 3],
    };

    /// A body with principal moments `inertia` along the link axes.
    pub fn principal(mass: f64, com: Vec3, inertia: Vec3) -> Self {
        Self {
            mass,
            com,
            inertia: diagonal(inertia),
        }
    }

    /// A point mass at `com`.
    pub fn point(mass: f64, com: Vec3) -> Self {
        Self::principal(mass, com, [0.0; 3])
    }

    /// A homogeneous box of sides `size` (along x, y, z) centred at `com`.
    pub fn cuboid(mass: f64, com: Vec3, size: Vec3) -> Self {
        let [a, b, c] = size;
        Self::principal(
            mass,
            com,
            [
                mass * (b * b + c * c) / 12.0,
                mass * (a * a + c * c) / 12.0,
                mass * (a * a + b * b) / 12.0,
            ],
        )
    }

    /// A homogeneous solid cylinder of `radius` and `length` along z, centred at `com`.
    pub fn cylinder(mass: f64, com: Vec3, radius: f64, length: f64) -> Self {
        let t = mass * (3.0 * radius * radius + length * length) / 12.0;
        Self::principal(mass, com, [t, t, 0.5 * mass * radius * radius])
    }

    /// The same body on the right side: the y of the centre of mass and the products of
    /// inertia with y change sign.
    pub fn mirrored(&self) -> Self {
        let mut b = *self;
        b.com[1] = -b.com[1];
        for (r, c) in [(0, 1), (1, 0), (1, 2), (2, 1)] {
            b.inertia[r][c] = -b.inertia[r][c];
        }
        b
    }

    /// The body described in a frame placed at `pose` (in this body's new frame).
    pub fn moved(&self, pose: &Pose) -> Self {
        Self {
            mass: self.mass,
            com: pose.apply(self.com),
            inertia: mul_mm(&mul_mm(&pose.r, &self.inertia), &transpose(&pose.r)),
        }
    }

    /// The rigid union of two bodies in one frame: masses added, the centre of mass the
    /// weighted mean, the inertias moved to it (Steiner: `I + m (|d|² E − d dᵀ)`).
    pub fn merged(&self, other: &Body) -> Self {
        let m = self.mass + other.mass;
        if m == 0.0 {
            return Body::NONE;
        }
        let com = scale(
            1.0 / m,
            add(scale(self.mass, self.com), scale(other.mass, other.com)),
        );
        let mut inertia = [[0.0; 3]; 3];
        for b in [self, other] {
            let d = sub(b.com, com);
            let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            for (r, row) in inertia.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    let e = if r == c { dd } else { 0.0 };
                    *v += b.inertia[r][c] + b.mass * (e - d[r] * d[c]);
                }
            }
        }
        Self {
            mass: m,
            com,
            inertia,
        }
    }
}

/// A revolute joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Its name (the MuJoCo joint's).
    pub name: String,
    /// Its origin in the frame of the link before it.
    pub origin: Pose,
    /// Its unit axis in its own frame.
    pub axis: Vec3,
    /// Its range \[rad\], if it has one.
    pub range: Option<[f64; 2]>,
    /// Its actuator's largest torque \[N m\], if limited.
    pub effort: Option<f64>,
    /// Its largest speed \[rad/s\], if limited.
    pub velocity: Option<f64>,
}

impl Joint {
    /// A joint about `axis` at `origin` without limits.
    pub fn new(name: &str, origin: Pose, axis: Vec3) -> Self {
        Self {
            name: name.into(),
            origin,
            axis,
            range: None,
            effort: None,
            velocity: None,
        }
    }
}

/// A leg link: the joint before it and the bodies fixed to it.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// Its name (the MuJoCo body's).
    pub name: String,
    /// The joint that moves it.
    pub joint: Joint,
    /// Its bodies, in its frame (none: a link between two joints at one point).
    pub bodies: Vec<Body>,
}

/// A leg: six links from the hip to the ankle and the sole centre.
#[derive(Clone, Debug, PartialEq)]
pub struct Leg {
    /// The links, hip first.
    pub links: [Link; 6],
    /// The sole centre in the last link's (the ankle's) frame.
    pub sole: Pose,
}

/// A named body fixed to the waist frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    /// Its name (`waist`: the root link's own body; `trunk`: the rest of the upper body).
    pub name: String,
    /// The body, in the waist frame.
    pub body: Body,
}

impl Named {
    /// The bodies fixed to the waist frame of every robot file: the trunk (the upper body)
    /// and the waist (the root link's own body), in that order.
    pub fn root(trunk: Body, waist: Body) -> Vec<Named> {
        vec![
            Named {
                name: "trunk".into(),
                body: trunk,
            },
            Named {
                name: "waist".into(),
                body: waist,
            },
        ]
    }
}

/// The dimensions of a leg of HRP-2's shape, for the closed-form inverse kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosedForm {
    /// Hip joint centre to knee \[m\].
    pub thigh: f64,
    /// Knee to ankle joint centre \[m\].
    pub shank: f64,
    /// Lateral distance of each hip joint centre from the waist origin \[m\].
    pub hip_offset: f64,
    /// Ankle joint centre above the sole centre \[m\].
    pub ankle_height: f64,
}

/// The multi-body model of a biped.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Gravity \[m/s²\].
    pub gravity: f64,
    /// Height of the waist origin above the floor in the walking posture \[m\].
    pub waist_height: f64,
    /// The bodies fixed to the waist frame.
    pub root: Vec<Named>,
    /// The left and the right leg.
    pub legs: [Leg; 2],
    /// HRP-2's leg shape, where it applies.
    pub closed_form: Option<ClosedForm>,
    /// The standing posture (soles at `(0, ±step_width/2, 0)`, the waist at `waist_height`
    /// above their midpoint): where the numerical inverse kinematics starts.
    pub stance: [LegAngles; 2],
}

/// The frames of one leg from forward kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegFrames {
    /// The six link frames, hip first.
    pub links: [Pose; 6],
    /// The sole centre.
    pub sole: Pose,
}

impl LegFrames {
    /// The ankle frame (the last link's).
    pub fn ankle(&self) -> Pose {
        self.links[5]
    }
}

/// The inverse kinematics has no solution: the ankle is out of the leg's reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkError {
    /// The leg.
    pub side: Side,
    /// Hip (the first joint's origin) to ankle joint centre \[m\].
    pub distance: f64,
    /// The longest reach (the sum of the joint-to-joint distances) \[m\].
    pub reach: f64,
}

impl fmt::Display for IkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:?} ankle {}: {:.4} m from the hip, reach {:.4} m",
            self.side,
            if self.distance > self.reach {
                "out of reach"
            } else {
                "not reached by the inverse kinematics"
            },
            self.distance,
            self.reach
        )
    }
}

impl std::error::Error for IkError {}

/// One body placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Placed {
    pub(crate) mass: f64,
    pub(crate) com: Vec3,
    pub(crate) r: Mat3,
    pub(crate) inertia: Mat3,
}

fn place(frame: &Pose, body: &Body) -> Placed {
    Placed {
        mass: body.mass,
        com: frame.apply(body.com),
        r: frame.r,
        inertia: body.inertia,
    }
}

/// The index of a side's leg (left 0, right 1).
pub fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

/// Solves `a x = b` for a 6×6 `a` by Gaussian elimination with partial pivoting; `None` when
/// singular.
fn solve6(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for c in 0..6 {
        let p = (c..6).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[p][c].abs() <= 1e-300 || a[p][c].is_nan() {
            return None;
        }
        a.swap(c, p);
        b.swap(c, p);
        let pivot = a[c];
        for r in c + 1..6 {
            let f = a[r][c] / pivot[c];
            for (x, y) in a[r][c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * y;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 6];
    for r in (0..6).rev() {
        let s: f64 = (r + 1..6).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

impl Model {
    /// Total mass \[kg\].
    pub fn total_mass(&self) -> f64 {
        let root: f64 = self.root.iter().map(|n| n.body.mass).sum();
        root + self
            .legs
            .iter()
            .flat_map(|l| l.links.iter())
            .flat_map(|l| l.bodies.iter())
            .map(|b| b.mass)
            .sum::<f64>()
    }

    /// The mass below a leg's ankle joint (its last link's bodies) \[kg\].
    pub fn foot_mass(&self, side: Side) -> f64 {
        self.legs[side_index(side)].links[5]
            .bodies
            .iter()
            .map(|b| b.mass)
            .sum()
    }

    /// The hip of a leg (its first joint's origin), in the world frame.
    pub fn hip_joint(&self, side: Side, waist: &Pose) -> Vec3 {
        waist.apply(self.legs[side_index(side)].links[0].joint.origin.p)
    }

    /// The longest reach of a leg: the sum of its joint-to-joint distances, hip to ankle \[m\].
    pub fn reach(&self, side: Side) -> f64 {
        if let Some(c) = self.closed_form {
            return c.thigh + c.shank;
        }
        self.legs[side_index(side)].links[1..]
            .iter()
            .map(|l| norm(l.joint.origin.p))
            .sum()
    }

    /// Forward kinematics of one leg.
    pub fn leg_fk(&self, side: Side, waist: &Pose, q: &LegAngles) -> LegFrames {
        let leg = &self.legs[side_index(side)];
        let mut links = [*waist; 6];
        let mut f = *waist;
        for (i, link) in leg.links.iter().enumerate() {
            let o = f.then(&link.joint.origin);
            f = Pose {
                p: o.p,
                r: mul_mm(&o.r, &rot_axis(link.joint.axis, q[i])),
            };
            links[i] = f;
        }
        LegFrames {
            links,
            sole: f.then(&leg.sole),
        }
    }

    /// Inverse kinematics of one leg: the joint angles that put the sole centre at `sole`
    /// (position and orientation) with the waist at `waist`; the closed form where it applies
    /// ([`Model::closed_form`]), Newton's method otherwise (see the module docs).
    pub fn leg_ik(&self, side: Side, waist: &Pose, sole: &Pose) -> Result<LegAngles, IkError> {
        match self.closed_form {
            Some(c) => closed_form_ik(&c, side, waist, sole),
            None => self.numerical_ik(side, waist, sole, self.stance[side_index(side)]),
        }
    }

    fn out_of_reach(&self, side: Side, waist: &Pose, sole: &Pose) -> IkError {
        let leg = &self.legs[side_index(side)];
        let ankle = sole.then(&leg.sole.inverse()).p;
        IkError {
            side,
            distance: norm(sub(ankle, self.hip_joint(side, waist))),
            reach: self.reach(side),
        }
    }

    /// Newton's method from `start` (see the module docs).
    pub fn numerical_ik(
        &self,
        side: Side,
        waist: &Pose,
        sole: &Pose,
        start: LegAngles,
    ) -> Result<LegAngles, IkError> {
        let leg = &self.legs[side_index(side)];
        let mut q = start;
        let mut best = f64::INFINITY;
        for _ in 0..IK_ITERATIONS {
            let fr = self.leg_fk(side, waist, &q);
            let ep = sub(sole.p, fr.sole.p);
            let er = log_so3(&mul_mm(&sole.r, &transpose(&fr.sole.r)));
            let err = norm(ep) + norm(er);
            if !err.is_finite() {
                break;
            }
            if err <= IK_TOLERANCE || (err < 1e-9 && err >= best) {
                return Ok(q);
            }
            best = best.min(err);
            let e = [ep[0], ep[1], ep[2], er[0], er[1], er[2]];
            let mut j = [[0.0; 6]; 6];
            for (i, (f, l)) in fr.links.iter().zip(&leg.links).enumerate() {
                let a = mul_mv(&f.r, l.joint.axis);
                let v = cross(a, sub(fr.sole.p, f.p));
                for k in 0..3 {
                    j[k][i] = v[k];
                    j[k + 3][i] = a[k];
                }
            }
            let lambda2 = if err > 1e-3 {
                IK_DAMPING * IK_DAMPING
            } else {
                0.0
            };
            let mut a = [[0.0; 6]; 6];
            let mut b = [0.0; 6];
            for r in 0..6 {
                for c in 0..6 {
                    a[r][c] = (0..6).map(|k| j[k][r] * j[k][c]).sum::<f64>();
                }
                a[r][r] += lambda2;
                b[r] = (0..6).map(|k| j[k][r] * e[k]).sum();
            }
            let Some(dq) = solve6(a, b) else { break };
            let big = dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let s = if big > 0.3 { 0.3 / big } else { 1.0 };
            for (qi, d) in q.iter_mut().zip(dq) {
                *qi += s * d;
            }
        }
        Err(self.out_of_reach(side, waist, sole))
    }

    /// The bodies in the world for a waist pose and joint angles; order: the root's, then the
    /// left leg's links', then the right leg's.
    pub(crate) fn place_all(&self, waist: &Pose, q: &[LegAngles; 2]) -> Vec<Placed> {
        let mut out: Vec<Placed> = self.root.iter().map(|n| place(waist, &n.body)).collect();
        for side in [Side::Left, Side::Right] {
            let f = self.leg_fk(side, waist, &q[side_index(side)]);
            for (frame, link) in f.links.iter().zip(&self.legs[side_index(side)].links) {
                out.extend(link.bodies.iter().map(|b| place(frame, b)));
            }
        }
        out
    }

    /// The whole-body COG for a waist pose and the two sole poses (left, right), with the
    /// joint angles from the inverse kinematics.
    pub fn cog(&self, waist: &Pose, soles: &[Pose; 2]) -> Result<(Vec3, [LegAngles; 2]), IkError> {
        let q = [
            self.leg_ik(Side::Left, waist, &soles[0])?,
            self.leg_ik(Side::Right, waist, &soles[1])?,
        ];
        Ok((cog_of(&self.place_all(waist, &q)), q))
    }

    /// The standing pose: soles at `(0, ±step_width/2, 0)`, the waist upright at
    /// `(0, 0, waist_height)`.
    pub fn stance_pose(&self, step_width: f64) -> (Pose, [Pose; 2]) {
        let half = step_width / 2.0;
        (
            Pose::upright(0.0, 0.0, self.waist_height, 0.0),
            [
                Pose::upright(0.0, half, 0.0, 0.0),
                Pose::upright(0.0, -half, 0.0, 0.0),
            ],
        )
    }

    /// The whole-body COG height in the standing pose ([`Model::stance_pose`]) \[m\].
    pub fn stance_cog_height(&self, step_width: f64) -> Result<f64, IkError> {
        let (waist, soles) = self.stance_pose(step_width);
        Ok(self.cog(&waist, &soles)?.0[2])
    }

    /// Finds the waist's horizontal position (upright, at `waist_height`, heading `yaw`) that
    /// puts the whole-body COG at `target` (x, y), starting from `start`. Returns the waist
    /// pose, the COG and the joint angles.
    pub fn solve_waist(
        &self,
        yaw: f64,
        soles: &[Pose; 2],
        target: [f64; 2],
        start: [f64; 2],
    ) -> Result<(Pose, Vec3, [LegAngles; 2]), WaistError> {
        const H: f64 = 1e-7;
        let at = |w: [f64; 2]| Pose::upright(w[0], w[1], self.waist_height, yaw);
        let mut w = start;
        let (mut c, mut q) = self.cog(&at(w), soles).map_err(WaistError::Ik)?;
        let mut e = [target[0] - c[0], target[1] - c[1]];
        let mut inverse: Option<[[f64; 2]; 2]> = None;
        let mut polish = true;
        for _ in 0..MAX_ITERATIONS {
            let err = e[0].hypot(e[1]);
            let converged = err <= COG_TOLERANCE;
            if converged && !polish {
                return Ok((at(w), c, q));
            }
            let ji = match (converged, inverse) {
                // Converged: one more step with the last Jacobian, kept only if it helps
                // (it usually brings the residual down to rounding, ~1e-16 m).
                (true, Some(ji)) => ji,
                (true, None) => return Ok((at(w), c, q)),
                _ => {
                    // Jacobian ∂COG/∂waist by forward differences.
                    let (cx, _) = self
                        .cog(&at([w[0] + H, w[1]]), soles)
                        .map_err(WaistError::Ik)?;
                    let (cy, _) = self
                        .cog(&at([w[0], w[1] + H]), soles)
                        .map_err(WaistError::Ik)?;
                    let j = [
                        [(cx[0] - c[0]) / H, (cy[0] - c[0]) / H],
                        [(cx[1] - c[1]) / H, (cy[1] - c[1]) / H],
                    ];
                    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                    if det.is_nan() || det.abs() <= 1e-12 {
                        return Err(WaistError::NoConvergence(err));
                    }
                    let ji = [
                        [j[1][1] / det, -j[0][1] / det],
                        [-j[1][0] / det, j[0][0] / det],
                    ];
                    inverse = Some(ji);
                    ji
                }
            };
            let wn = [
                w[0] + ji[0][0] * e[0] + ji[0][1] * e[1],
                w[1] + ji[1][0] * e[0] + ji[1][1] * e[1],
            ];
            let (cn, qn) = self.cog(&at(wn), soles).map_err(WaistError::Ik)?;
            let en = [target[0] - cn[0], target[1] - cn[1]];
            if converged {
                polish = false;
                if en[0].hypot(en[1]) >= err {
                    return Ok((at(w), c, q));
                }
            }
            (w, c, q, e) = (wn, cn, qn, en);
        }
        let err = e[0].hypot(e[1]);
        if err <= COG_TOLERANCE {
            Ok((at(w), c, q))
        } else {
            Err(WaistError::NoConvergence(err))
        }
    }
}

/// Analytic inverse kinematics of a leg of HRP-2's shape: the joint angles that put the sole
/// centre at `sole` (position and orientation) with the waist at `waist`.
///
/// Derivation (r is the hip joint centre seen from the ankle joint centre, in the foot
/// frame; A, B the thigh and shank lengths):
/// `r = R_x(−q6) R_y(−q5) [R_y(−q4) (0, 0, A) + (0, 0, B)]`. Hence
/// `|r|² = A² + B² + 2AB cos q4` (knee, taken ≥ 0); `R_x(−q6)` maps `(v_x, 0, v_z)` to
/// `(v_x, v_z sin q6, v_z cos q6)`, so `q6 = atan2(r_y, r_z)` and `v_z = √(r_y² + r_z²)`
/// (hip above the ankle); `R_y(−q5)` subtracts `q5` from the angle `atan2(x, z)` of
/// `u = (−A sin q4, 0, A cos q4 + B)`, so `q5 = atan2(u_x, u_z) − atan2(r_x, v_z)`. Then
/// `R_z(q1) R_x(q2) R_y(q3) = R_wᵀ R_foot R_x(−q6) R_y(−q4 − q5) =: M`, and from the
/// product of the three elementary rotations `q1 = atan2(−M01, M11)`,
/// `q2 = atan2(M21, −sin q1 M01 + cos q1 M11)`, `q3 = atan2(−M20, M22)`.
///
/// The branch returned: knee `q4 ≥ 0`, hip above the ankle in the foot frame
/// (`A cos(q4 + q5) + B cos q5 > 0`) and `|q2| < π/2`, which covers walking. Fails when the
/// ankle is farther from the hip than `A + B` (or closer than `|A − B|`).
pub fn closed_form_ik(
    c: &ClosedForm,
    side: Side,
    waist: &Pose,
    sole: &Pose,
) -> Result<LegAngles, IkError> {
    let (a, b) = (c.thigh, c.shank);
    let sign = match side {
        Side::Left => 1.0,
        Side::Right => -1.0,
    };
    let hip_p = waist.apply([0.0, sign * c.hip_offset, 0.0]);
    let ankle = add(sole.p, mul_mv(&sole.r, [0.0, 0.0, c.ankle_height]));
    let rt = transpose(&sole.r);
    let r = mul_mv(&rt, sub(hip_p, ankle));
    let dist = norm(r);
    let reach = a + b;
    if dist > reach || dist < (a - b).abs() || !dist.is_finite() {
        return Err(IkError {
            side,
            distance: dist,
            reach,
        });
    }
    let cos_knee = ((dist * dist - a * a - b * b) / (2.0 * a * b)).clamp(-1.0, 1.0);
    let q4 = cos_knee.acos();
    let q6 = r[1].atan2(r[2]);
    let vz = (r[1] * r[1] + r[2] * r[2]).sqrt();
    let (s4, c4) = q4.sin_cos();
    let q5 = wrap((-a * s4).atan2(a * c4 + b) - r[0].atan2(vz));
    let m = mul_mm(
        &mul_mm(&mul_mm(&transpose(&waist.r), &sole.r), &rot_x(-q6)),
        &rot_y(-q4 - q5),
    );
    let q1 = (-m[0][1]).atan2(m[1][1]);
    let (s1, c1) = q1.sin_cos();
    let q2 = m[2][1].atan2(-s1 * m[0][1] + c1 * m[1][1]);
    let q3 = (-m[2][0]).atan2(m[2][2]);
    Ok([q1, q2, q3, q4, q5, q6])
}

/// Why [`Model::solve_waist`] failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WaistError {
    /// A foot is out of reach.
    Ik(IkError),
    /// No convergence; the remaining COG error \[m\].
    NoConvergence(f64),
}

fn cog_of(bodies: &[Placed]) -> Vec3 {
    let mut m = 0.0;
    let mut s = [0.0; 3];
    for b in bodies {
        m += b.mass;
        s = add(s, scale(b.mass, b.com));
    }
    scale(1.0 / m, s)
}

/// The mean heading of the two feet (the bisector of their yaws).
pub fn mean_yaw(feet: &[FootPose<f64>; 2]) -> f64 {
    feet[0].yaw + 0.5 * wrap(feet[1].yaw - feet[0].yaw)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_log() {
        assert_eq!(log_so3(&IDENTITY), [0.0; 3]);
        let v = log_so3(&rot_z(0.3));
        assert!((v[2] - 0.3).abs() < 1e-15 && v[0] == 0.0 && v[1] == 0.0);
    }

    #[test]
    fn merged_bodies_keep_mass_and_first_moment() {
        let a = Body::cuboid(2.0, [0.1, 0.0, 0.0], [0.1, 0.2, 0.3]);
        let b = Body::cuboid(2.0, [-0.1, 0.0, 0.0], [0.1, 0.2, 0.3]);
        let m = a.merged(&b);
        assert_eq!(m.mass, 4.0);
        assert_eq!(m.com, [0.0; 3]);
        // Two boxes side by side along x: the union 0.3 × 0.2 × 0.3 minus a 0.1 gap: Ixx
        // unchanged by the shift, Iyy and Izz each up by m d² = 2 × 0.01 per body.
        assert!((m.inertia[0][0] - 2.0 * a.inertia[0][0]).abs() < 1e-15);
        assert!((m.inertia[1][1] - 2.0 * (a.inertia[1][1] + 0.02)).abs() < 1e-15);
        assert_eq!(m.inertia[0][1], 0.0);
    }
}
