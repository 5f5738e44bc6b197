//! The multi-body model of a robot file's `[multibody]` table (HRP-2's by default): its
//! bodies, frames, forward and inverse kinematics, and the waist placement that puts the
//! whole-body COG on the planner's. [`crate::eval::multibody`] computes the ZMP of a walk on it.
//!
//! # The model
//!
//! Eighteen degrees of freedom: a floating **waist** (pelvis, 6 DoF, of which the references
//! leave two free, see below) and two 6-DoF **legs**. Ten rigid bodies:
//!
//! | body | frame it is fixed to | origin of that frame |
//! |------|----------------------|----------------------|
//! | trunk (chest, head, both arms, backpack: one body) | waist | waist origin |
//! | waist (pelvis) | waist | waist origin |
//! | hip (yaw and roll housings), ×2 | after hip yaw and hip roll | hip joint centre |
//! | thigh, ×2 | after hip pitch | hip joint centre |
//! | shank, ×2 | after the knee | knee |
//! | foot (ankle housings and sole), ×2 | after ankle pitch and roll | ankle joint centre |
//!
//! Frames: world x forward, y left, z up, the floor at z = 0. The **waist origin** is the
//! midpoint of the two hip joint centres; the hip joints are at `(0, ±hip_offset, 0)` in the
//! waist frame (+ left). Each leg: hip yaw `q1` (about z), hip roll `q2` (x), hip pitch `q3` (y),
//! knee pitch `q4` (y), ankle pitch `q5` (y), ankle roll `q6` (x). The three hip axes intersect
//! at the hip joint centre and the two ankle axes at the ankle joint centre, so the leg has a
//! closed-form inverse kinematics. With all angles zero the leg hangs straight down: the knee is
//! `thigh_length` below the hip, the ankle `shank_length` below the knee, and the sole centre
//! `ankle_height` below the ankle. The foot frame is the frame after `q6`; the **sole centre**
//! (the point the references give) is at `(0, 0, −ankle_height)` in it: the ankle is assumed to
//! be straight above the sole centre. A bent knee is `q4 > 0`.
//!
//! Rotations: `R_x(a)`, `R_y(a)`, `R_z(a)` are the elementary rotations (right-handed), so the
//! orientation of the thigh is `R_w R_z(q1) R_x(q2) R_y(q3)`, of the shank that times `R_y(q4)`,
//! and of the foot that times `R_y(q5) R_x(q6)`.
//!
//!
//! # Parameters and their sources
//!
//! Published HRP-2 figures (Kaneko et al., "Humanoid robot HRP-2", ICRA 2004): height 1.54 m,
//! total mass 58 kg (with batteries), thigh and shank 0.30 m. The half-sitting posture of
//! HRP-2's walking controllers bends the knee by about 50° (hip pitch −26°, knee 50°, ankle
//! pitch −24°). Everything else is an **assumption** of this model (the mass distribution of
//! HRP-2 is not in the papers cited here), chosen to be plausible for a 58 kg, 1.54 m humanoid
//! and summing to 58 kg. Inertia tensors are those of homogeneous boxes
//! (`I_xx = m (b² + c²) / 12` for a box `a × b × c` along x, y, z) and solid cylinders along
//! the link (`I_xx = I_yy = m (3 r² + l²) / 12`, `I_zz = m r² / 2`), diagonal in the body
//! frame, about the body's centre of mass. [`Model::hrp2`]:
//!
//! | symbol / body | value | source |
//! |---------------|-------|--------|
//! | `thigh_length` A, `shank_length` B | 0.30 m, 0.30 m | Kaneko 2004 |
//! | `hip_offset` | 0.06 m (hips ±0.06 m from the waist origin) | assumed, HRP-2 class |
//! | `ankle_height` | 0.105 m, ankle straight above the sole centre | assumed, HRP-2 class |
//! | `waist_height` | 0.6523 m | chosen: stance COG at 0.814 m |
//! | trunk | 28.0 kg, COM (0, 0, 0.50) in the waist frame, box 0.30 × 0.50 × 0.60 | assumed |
//! | waist | 10.0 kg, COM (0, 0, 0.05), box 0.20 × 0.30 × 0.15 | assumed |
//! | hip ×2 | 1.5 kg, COM at the hip joint centre, box 0.10 × 0.10 × 0.10 | assumed |
//! | thigh ×2 | 4.5 kg, COM (0, 0, −0.15), cylinder r 0.06, l 0.30 | assumed (length published) |
//! | shank ×2 | 2.5 kg, COM (0, 0, −0.15) from the knee, cylinder r 0.05, l 0.30 | assumed (length published) |
//! | foot ×2 | 1.5 kg, COM (0, 0, −0.065) from the ankle (4 cm above the sole), box 0.24 × 0.14 × 0.08 | assumed (sole: the planner's) |
//! | total | 58.0 kg (legs 10 kg each, trunk + waist 38 kg) | Kaneko 2004 |
//!
//! The waist height is chosen (by bisection, rounded to 0.1 mm) so that the whole-body COG is
//! 0.814 m high standing with the feet at (0, ±0.1) and the waist between them; the knees are
//! then bent by 47.7° (hip roll 4.2°, hip and ankle pitch −23.9°): close to HRP-2's
//! half-sitting posture, which leaves the reach needed for long steps (a straighter stance
//! puts the ankle out of reach in the 0.3 m step of the `fig4` scenario).
//!
//! Other assumptions: the trunk is rigidly fixed to the waist (no chest joint moves, the arms do
//! not swing); the joints follow the references exactly (no compliance, no ankle flexibility,
//! no tracking error); the right leg is the mirror image of the left (centre-of-mass y
//! offsets change sign); the stance feet stay flat on the floor, so the ZMP formula applies
//! whenever it falls inside the support polygon (this module does not check that).

use core::fmt;

use planner_core::gait::{FootPose, Side};

/// A 3-vector.
pub type Vec3 = [f64; 3];
/// A 3×3 matrix, row-major (`m[row][column]`).
pub type Mat3 = [[f64; 3]; 3];
/// The six joint angles of one leg \[rad\]: hip yaw, hip roll, hip pitch, knee, ankle pitch,
/// ankle roll.
pub type LegAngles = [f64; 6];

/// Newton iterations per tick at most in the waist search.
pub const MAX_ITERATIONS: usize = 50;
/// The waist search stops when the whole-body COG is this close to the reference \[m\].
/// Far below the 1e-9 m asked for, because the second difference multiplies position noise by
/// 4/dt² = 1.6e5 s⁻² (1e-10 m of noise would be up to 1.3e-6 m of ZMP, 1e-13 m is 1.3e-9 m).
pub const COG_TOLERANCE: f64 = 1e-13;

pub(crate) fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(crate) fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn scale(s: f64, a: Vec3) -> Vec3 {
    [s * a[0], s * a[1], s * a[2]]
}

pub(crate) fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: Vec3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

pub(crate) fn mul_mv(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

pub(crate) fn mul_mm(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

pub(crate) fn transpose(m: &Mat3) -> Mat3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

/// Rotation about x by `a` \[rad\].
pub fn rot_x(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Rotation about y by `a` \[rad\].
pub fn rot_y(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Rotation about z by `a` \[rad\].
pub fn rot_z(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// The rotation vector of a rotation matrix (axis × angle, angle in \[0, π)); accurate for
/// the small rotations between two ticks.
pub(crate) fn log_so3(r: &Mat3) -> Vec3 {
    let v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let s = 0.5 * norm(v); // sin θ
    let c = 0.5 * (r[0][0] + r[1][1] + r[2][2] - 1.0); // cos θ
    let theta = s.atan2(c);
    let k = if s > 1e-9 {
        theta / (2.0 * s)
    } else {
        // θ / (2 sin θ) = 1/2 + θ²/12 + O(θ⁴)
        0.5 + theta * theta / 12.0
    };
    scale(k, v)
}

/// Wraps an angle to (−π, π].
pub(crate) fn wrap(a: f64) -> f64 {
    let w = a.sin().atan2(a.cos());
    if w <= -core::f64::consts::PI {
        w + 2.0 * core::f64::consts::PI
    } else {
        w
    }
}

/// A rigid-body pose: position and orientation (body-to-world rotation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position \[m\].
    pub p: Vec3,
    /// Orientation: columns are the body axes in the world frame.
    pub r: Mat3,
}

impl Pose {
    /// An upright pose (roll = pitch = 0) at `(x, y, z)` with heading `yaw`.
    pub fn upright(x: f64, y: f64, z: f64, yaw: f64) -> Self {
        Self {
            p: [x, y, z],
            r: rot_z(yaw),
        }
    }

    /// The pose of a sole centre from a reference foot pose (flat sole).
    pub fn sole(f: &FootPose<f64>) -> Self {
        Self::upright(f.x, f.y, f.z, f.yaw)
    }

    /// A point given in this frame, in the world frame.
    pub fn apply(&self, v: Vec3) -> Vec3 {
        add(self.p, mul_mv(&self.r, v))
    }
}

/// A rigid body: mass, centre of mass and principal moments of inertia in its link frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Mass \[kg\].
    pub mass: f64,
    /// Centre of mass in the link frame (left leg for leg links) \[m\].
    pub com: Vec3,
    /// Moments of inertia about the centre of mass along the link-frame axes \[kg m²\]
    /// (the products of inertia are zero).
    pub inertia: Vec3,
}

impl Body {
    /// A massless body.
    pub const NONE: Body = Body {
        mass: 0.0,
        com: [0.0; 3],
        inertia: [0.0; 3],
    };

    /// A point mass at `com`.
    pub fn point(mass: f64, com: Vec3) -> Self {
        Self {
            mass,
            com,
            inertia: [0.0; 3],
        }
    }

    /// A homogeneous box of sides `size` (along x, y, z) centred at `com`.
    pub fn cuboid(mass: f64, com: Vec3, size: Vec3) -> Self {
        let [a, b, c] = size;
        Self {
            mass,
            com,
            inertia: [
                mass * (b * b + c * c) / 12.0,
                mass * (a * a + c * c) / 12.0,
                mass * (a * a + b * b) / 12.0,
            ],
        }
    }

    /// A homogeneous solid cylinder of `radius` and `length` along z, centred at `com`.
    pub fn cylinder(mass: f64, com: Vec3, radius: f64, length: f64) -> Self {
        let t = mass * (3.0 * radius * radius + length * length) / 12.0;
        Self {
            mass,
            com,
            inertia: [t, t, 0.5 * mass * radius * radius],
        }
    }

    /// The same body on the right side: the y of the centre of mass changes sign.
    fn mirrored(&self, side: Side) -> Self {
        let mut b = *self;
        if side == Side::Right {
            b.com[1] = -b.com[1];
        }
        b
    }
}

/// The multi-body model of a biped (read from the robot file's `[multibody]` table,
/// [`crate::robot`]). Link bodies are given for the left leg; the right leg mirrors them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    /// Hip joint centre to knee \[m\].
    pub thigh_length: f64,
    /// Knee to ankle joint centre \[m\].
    pub shank_length: f64,
    /// Lateral distance of each hip joint centre from the waist origin \[m\].
    pub hip_offset: f64,
    /// Height of the ankle joint centre above the sole \[m\].
    pub ankle_height: f64,
    /// Height of the waist origin (the hip joint centres) above the floor \[m\].
    pub waist_height: f64,
    /// Gravity \[m/s²\].
    pub gravity: f64,
    /// Trunk: chest, head, arms and backpack as one body, in the waist frame.
    pub trunk: Body,
    /// Waist (pelvis), in the waist frame.
    pub waist: Body,
    /// Hip yaw and roll housings, in the frame after hip roll (origin: hip joint centre).
    pub hip: Body,
    /// Thigh, in the frame after hip pitch (origin: hip joint centre).
    pub thigh: Body,
    /// Shank, in the frame after the knee (origin: knee).
    pub shank: Body,
    /// Foot with the ankle housings, in the foot frame (origin: ankle joint centre).
    pub foot: Body,
}

/// The frames of one leg from forward kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegFrames {
    /// After hip yaw and roll, at the hip joint centre.
    pub hip: Pose,
    /// After hip pitch (the thigh), at the hip joint centre.
    pub thigh: Pose,
    /// After the knee (the shank), at the knee.
    pub shank: Pose,
    /// After the ankle roll (the foot), at the ankle joint centre.
    pub foot: Pose,
    /// The sole centre (foot orientation).
    pub sole: Pose,
}

/// The inverse kinematics has no solution: the ankle is out of the leg's reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkError {
    /// The leg.
    pub side: Side,
    /// Hip joint centre to ankle joint centre \[m\].
    pub distance: f64,
    /// The longest reach, `thigh_length + shank_length` \[m\].
    pub reach: f64,
}

impl fmt::Display for IkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:?} ankle out of reach: {:.4} m from the hip, reach {:.4} m",
            self.side, self.distance, self.reach
        )
    }
}

impl std::error::Error for IkError {}

/// Number of bodies of the model.
pub const BODIES: usize = 10;

/// One body placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Placed {
    pub(crate) mass: f64,
    pub(crate) com: Vec3,
    pub(crate) r: Mat3,
    pub(crate) inertia: Vec3,
}

fn place(frame: &Pose, body: &Body) -> Placed {
    Placed {
        mass: body.mass,
        com: frame.apply(body.com),
        r: frame.r,
        inertia: body.inertia,
    }
}

fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

fn side_sign(side: Side) -> f64 {
    match side {
        Side::Left => 1.0,
        Side::Right => -1.0,
    }
}

impl Model {
    /// Total mass \[kg\].
    pub fn total_mass(&self) -> f64 {
        self.trunk.mass
            + self.waist.mass
            + 2.0 * (self.hip.mass + self.thigh.mass + self.shank.mass + self.foot.mass)
    }

    /// The hip joint centre of a leg, in the world frame.
    pub fn hip_joint(&self, side: Side, waist: &Pose) -> Vec3 {
        waist.apply([0.0, side_sign(side) * self.hip_offset, 0.0])
    }

    /// Forward kinematics of one leg.
    pub fn leg_fk(&self, side: Side, waist: &Pose, q: &LegAngles) -> LegFrames {
        let hip_p = self.hip_joint(side, waist);
        let r_hip = mul_mm(&mul_mm(&waist.r, &rot_z(q[0])), &rot_x(q[1]));
        let r_thigh = mul_mm(&r_hip, &rot_y(q[2]));
        let knee = add(hip_p, mul_mv(&r_thigh, [0.0, 0.0, -self.thigh_length]));
        let r_shank = mul_mm(&r_thigh, &rot_y(q[3]));
        let ankle = add(knee, mul_mv(&r_shank, [0.0, 0.0, -self.shank_length]));
        let r_foot = mul_mm(&mul_mm(&r_shank, &rot_y(q[4])), &rot_x(q[5]));
        let sole = add(ankle, mul_mv(&r_foot, [0.0, 0.0, -self.ankle_height]));
        LegFrames {
            hip: Pose { p: hip_p, r: r_hip },
            thigh: Pose {
                p: hip_p,
                r: r_thigh,
            },
            shank: Pose {
                p: knee,
                r: r_shank,
            },
            foot: Pose {
                p: ankle,
                r: r_foot,
            },
            sole: Pose { p: sole, r: r_foot },
        }
    }

    /// Analytic inverse kinematics of one leg: the joint angles that put the sole centre at
    /// `sole` (position and orientation) with the waist at `waist`.
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
    pub fn leg_ik(&self, side: Side, waist: &Pose, sole: &Pose) -> Result<LegAngles, IkError> {
        let (a, b) = (self.thigh_length, self.shank_length);
        let hip_p = self.hip_joint(side, waist);
        let ankle = add(sole.p, mul_mv(&sole.r, [0.0, 0.0, self.ankle_height]));
        let rt = transpose(&sole.r);
        let r = mul_mv(&rt, sub(hip_p, ankle));
        let c = norm(r);
        let reach = a + b;
        if c > reach || c < (a - b).abs() || !c.is_finite() {
            return Err(IkError {
                side,
                distance: c,
                reach,
            });
        }
        let cos_knee = ((c * c - a * a - b * b) / (2.0 * a * b)).clamp(-1.0, 1.0);
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

    /// The ten bodies in the world for a waist pose and joint angles; order: trunk, waist,
    /// then hip, thigh, shank, foot of the left and of the right leg.
    pub(crate) fn place_all(&self, waist: &Pose, q: &[LegAngles; 2]) -> [Placed; BODIES] {
        let mut out = [place(waist, &self.trunk); BODIES];
        out[1] = place(waist, &self.waist);
        for side in [Side::Left, Side::Right] {
            let f = self.leg_fk(side, waist, &q[side_index(side)]);
            let o = 2 + 4 * side_index(side);
            out[o] = place(&f.hip, &self.hip.mirrored(side));
            out[o + 1] = place(&f.thigh, &self.thigh.mirrored(side));
            out[o + 2] = place(&f.shank, &self.shank.mirrored(side));
            out[o + 3] = place(&f.foot, &self.foot.mirrored(side));
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

    /// The whole-body COG height in the standing pose: soles at `(0, ±step_width/2, 0)`,
    /// waist at `(0, 0, waist_height)` \[m\].
    pub fn stance_cog_height(&self, step_width: f64) -> Result<f64, IkError> {
        let half = step_width / 2.0;
        let soles = [
            Pose::upright(0.0, half, 0.0, 0.0),
            Pose::upright(0.0, -half, 0.0, 0.0),
        ];
        let waist = Pose::upright(0.0, 0.0, self.waist_height, 0.0);
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

    const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn identity_log() {
        assert_eq!(log_so3(&IDENTITY), [0.0; 3]);
        let v = log_so3(&rot_z(0.3));
        assert!((v[2] - 0.3).abs() < 1e-15 && v[0] == 0.0 && v[1] == 0.0);
    }
}
