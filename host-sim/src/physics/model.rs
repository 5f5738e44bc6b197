//! The MuJoCo model (MJCF) generated from a robot's multi-body model
//! ([`crate::robot::model::Model`]), and the kinematics the stabilizer needs from it.
//!
//! This is the **only** place of the physics module that reads the link table: the rest goes
//! through [`Robot`].
//!
//! # The MJCF
//!
//! One MuJoCo body per body of the model, with exactly its mass, centre of mass and inertia
//! tensor (an explicit `<inertial>`, so the collision shapes carry no mass): `waist` (floating,
//! a free joint) with `trunk` welded to it, and per leg one body per link. A link without
//! bodies whose next joint sits at the same origin (HRP-2's hip yaw before hip roll, ankle
//! pitch before ankle roll) is one MuJoCo body with both joints: MuJoCo composes the joints of
//! a body in the order written, so the frames are those of the model:
//! `T_i = T_{i−1} O_i Rot(a_i, q_i)`.
//!
//! Collision shapes: the **soles** are boxes of the robot file's `[feet]` `sole_length` ×
//! `sole_width` (HRP-2: 0.24 × 0.14 m), [`SOLE_BOX_HEIGHT`] = 0.08 m high or the ankle's
//! height above the sole if that is less, their bottom face on the sole centre's plane, in the
//! ankle's frame; every other body (but the last two links of a leg, at the ankle, and a
//! body lighter than [`NO_BOX_BELOW_KG`]) has the box
//! of equal principal moments
//! (`a² = 6 (I_y + I_z − I_x) / m`, and so on, from the diagonal of its tensor), so that a fall
//! can touch the floor with a knee, a hip or the trunk. Robot geoms collide with the floor only
//! (`contype 2, conaffinity 1` against the floor's `1, 2`): no self collision.
//!
//! Contact (stated): friction 1.0 (sliding), condim 3, `solref 0.004 1` (a 4 ms time
//! constant, critically damped), `solimp 0.95 0.99 0.001`: standing, the soles sink about
//! 0.01 mm into the floor.
//!
//! Physics: `timestep` 1 ms, the `implicitfast` integrator, gravity `−g` of the link table.
//!
//! Joint servos: a `position` actuator per joint, `τ = kp (q_target − q)` with `kp` =
//! [`SERVO_KP`] N m/rad, a viscous joint damping `−kd q̇` with `kd` = [`SERVO_KD`] N m s/rad,
//! and a reflected rotor inertia (`armature`) of [`ARMATURE`] kg m² (stated assumptions of an
//! HRP-2-class harmonic-drive joint). With `kd` = 150 the ankle mode of the standing robot
//! (about 4 Hz) is barely damped and the open-loop playback rocks; 600 damps it. For another
//! robot ([`Robot::of`]) `kp` and `kd` scale with its total mass against HRP-2's (the gravity
//! torques its joints hold scale with it), the armature stays: with HRP-2's servos the 17.4 kg
//! test robot (`host-sim/tests/robots/small.toml`) walked but rocked on its sole edges (CoP
//! error mean 25.6 mm), scaled (× 0.30) 5.7 mm. A joint with a range in the robot file is
//! limited to it (`range`), and an actuator with an effort limit saturates at it
//! (`forcerange`), its damping then inside the actuator (`kv`, so that the limit bounds the
//! servo's whole torque `kp (q_target − q) − kd q̇`) instead of on the joint; the hand-written
//! HRP-2 table gives neither.
//!
//! Sensors (what the real robot measures, nothing else reaches the controller): a trunk IMU
//! (site `imu` at the waist origin: `framequat` as the attitude estimate, `gyro`,
//! `accelerometer`), the twelve joint encoders (`jointpos`, `jointvel`), and a 6-axis
//! force/torque sensor at each ankle (`force`, `torque` at the site at the ankle frame's
//! origin, in the ankle frame).

use std::fmt::Write;
use std::sync::Arc;

use crate::robot::model::{
    mul_mv, norm, side_index, sub, transpose, Body, LegAngles, Link, Mat3, Model, Pose, Vec3,
    IDENTITY,
};
use planner_core::gait::Side;

/// Servo stiffness of every joint \[N m/rad\].
pub const SERVO_KP: f64 = 20_000.0;
/// Joint damping \[N m s/rad\].
pub const SERVO_KD: f64 = 600.0;
/// Reflected rotor inertia per joint \[kg m²\].
pub const ARMATURE: f64 = 0.3;
/// Largest hip–ankle distance the IK is asked for, as a fraction of the leg's reach.
pub const REACH_FRACTION: f64 = 0.9995;

/// Half-extents of HRP-2's sole box \[m\]: 0.24 × 0.14 × 0.08 (the robot of
/// [`Robot::new`]; [`Robot::of`] takes the robot file's).
pub const SOLE_HALF: Vec3 = [0.12, 0.07, 0.04];
/// Height of the sole box \[m\], at most the ankle height.
pub const SOLE_BOX_HEIGHT: f64 = 0.08;

/// The joints of HRP-2's legs, in actuator (and qpos) order: hip yaw, hip roll, hip pitch,
/// knee, ankle pitch, ankle roll (`l_` and `r_` prefixed in the MJCF).
pub const JOINTS: [&str; 6] = [
    "hip_yaw",
    "hip_roll",
    "hip_pitch",
    "knee",
    "ankle_pitch",
    "ankle_roll",
];

/// Layout of the sensor data the MJCF declares, in order.
pub mod sensor {
    /// IMU orientation quaternion (w, x, y, z).
    pub const QUAT: usize = 0;
    /// IMU angular velocity (body frame).
    pub const GYRO: usize = 4;
    /// IMU linear acceleration (body frame).
    pub const ACC: usize = 7;
    /// Twelve joint angles.
    pub const QPOS: usize = 10;
    /// Twelve joint velocities.
    pub const QVEL: usize = 22;
    /// Left ankle force (3) and torque (3), then the right ones.
    pub const FT: usize = 34;
    /// Number of values.
    pub const LEN: usize = 46;
}

/// The robot as the physics module sees it: the link table and what follows from it.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    model: Arc<Model>,
    sole_half: Vec3,
    /// Servo stiffness and joint damping.
    servo: [f64; 2],
}

impl Default for Robot {
    fn default() -> Self {
        Self::new(link_table())
    }
}

/// The link table the physics module uses (host-sim's HRP-2 model; the kinematic evaluation
/// of [`super::tables`] takes the same one from here).
pub fn link_table() -> Model {
    Model::hrp2()
}

fn f(v: f64) -> String {
    format!("{v:.6}")
}

fn v3(v: Vec3) -> String {
    format!("{} {} {}", f(v[0]), f(v[1]), f(v[2]))
}

fn g(v: f64) -> String {
    format!("{v:.9}")
}

/// Half-extents of the box with the principal moments of the diagonal of `b`'s tensor.
fn equivalent_box(b: &Body) -> Vec3 {
    let [ix, iy, iz] = [b.inertia[0][0], b.inertia[1][1], b.inertia[2][2]];
    let side = |s: f64| (6.0 * s / b.mass).max(1e-6).sqrt() / 2.0;
    [side(iy + iz - ix), side(ix + iz - iy), side(ix + iy - iz)]
}

fn inertial(b: &Body) -> String {
    let i = &b.inertia;
    if i[0][1] == 0.0 && i[0][2] == 0.0 && i[1][2] == 0.0 {
        format!(
            "<inertial pos=\"{}\" mass=\"{}\" diaginertia=\"{}\"/>",
            v3(b.com),
            f(b.mass),
            v3([i[0][0].max(1e-6), i[1][1].max(1e-6), i[2][2].max(1e-6)])
        )
    } else {
        format!(
            "<inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{} {} {} {} {} {}\"/>",
            v3(b.com),
            f(b.mass),
            g(i[0][0].max(1e-6)),
            g(i[1][1].max(1e-6)),
            g(i[2][2].max(1e-6)),
            g(i[0][1]),
            g(i[0][2]),
            g(i[1][2])
        )
    }
}

/// A body lighter than this has no collision box: its equivalent box says nothing of its
/// shape (a URDF's placeholder base of 1 mg with a unit tensor would be metres wide) \[kg\].
pub const NO_BOX_BELOW_KG: f64 = 1e-3;

fn collision_box(name: &str, b: &Body) -> String {
    collision_box_within(name, b, None)
}

/// [`collision_box`], its extent along the link's z axis kept within `[lo, hi]` (the bone
/// between a joint and the next, with a margin) when given: a slender link whose mass is
/// spread unevenly has an equivalent box longer than the link, which would reach the floor.
fn collision_box_within(name: &str, b: &Body, z: Option<[f64; 2]>) -> String {
    if b.mass < NO_BOX_BELOW_KG {
        return String::new();
    }
    let mut c = b.com;
    let mut h = equivalent_box(b);
    if let Some([lo, hi]) = z {
        let (a, top) = ((c[2] - h[2]).max(lo), (c[2] + h[2]).min(hi));
        if top > a {
            c[2] = 0.5 * (a + top);
            h[2] = 0.5 * (top - a);
        }
    }
    format!(
        "<geom name=\"{name}\" type=\"box\" pos=\"{}\" size=\"{}\" class=\"robot\"/>",
        v3(c),
        v3(h)
    )
}

/// The unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method).
fn quat(r: &Mat3) -> [f64; 4] {
    let t = r[0][0] + r[1][1] + r[2][2];
    if t > 0.0 {
        let s = 2.0 * (1.0 + t).sqrt();
        [
            0.25 * s,
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
        ]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = 2.0 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        [
            (r[2][1] - r[1][2]) / s,
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
        ]
    } else if r[1][1] > r[2][2] {
        let s = 2.0 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
        [
            (r[0][2] - r[2][0]) / s,
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
        [
            (r[1][0] - r[0][1]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
        ]
    }
}

/// The merged body of a link (`None`: massless).
fn link_body(l: &Link) -> Option<Body> {
    let mut it = l.bodies.iter();
    let first = *it.next()?;
    Some(it.fold(first, |a, b| a.merged(b)))
}

impl Robot {
    /// The robot of a link table, with HRP-2's soles ([`SOLE_HALF`]).
    pub fn new(model: Model) -> Self {
        Self {
            model: Arc::new(model),
            sole_half: SOLE_HALF,
            servo: [SERVO_KP, SERVO_KD],
        }
    }

    /// The robot of a robot file: its `[multibody]` link table, its `[feet]` soles
    /// (`sole_length` × `sole_width`, [`SOLE_BOX_HEIGHT`] high or the ankle height if less)
    /// and servos scaled by its mass (see the module docs).
    pub fn of(robot: &crate::robot::Robot) -> Self {
        let p = &robot.planner.params;
        let scale = robot.model.total_mass() / link_table().total_mass();
        // The ankle's height above the sole, in the sole's axes (at least a centimetre of box).
        let sole = &robot.model.legs[0].sole;
        let ankle = -mul_mv(&transpose(&sole.r), sole.p)[2];
        Self {
            servo: [SERVO_KP * scale, SERVO_KD * scale],
            model: Arc::new(robot.model.clone()),
            sole_half: [
                p.sole_half_length,
                p.sole_half_width,
                0.5 * SOLE_BOX_HEIGHT.min(ankle).max(0.01),
            ],
        }
    }

    /// The same robot with the joint damping `kd` \[N m s/rad\] (the stiffness unchanged).
    pub fn with_servo_damping(mut self, kd: f64) -> Self {
        self.servo[1] = kd;
        self
    }

    /// Servo stiffness \[N m/rad\] and joint damping \[N m s/rad\].
    pub fn servo(&self) -> [f64; 2] {
        self.servo
    }

    /// Half-extents of the sole box (length, width, height) \[m\].
    pub fn sole_half(&self) -> Vec3 {
        self.sole_half
    }

    /// The link table.
    pub fn link_table(&self) -> &Model {
        &self.model
    }

    /// Gravity \[m/s²\].
    pub fn gravity(&self) -> f64 {
        self.model.gravity
    }

    /// Total mass \[kg\].
    pub fn total_mass(&self) -> f64 {
        self.model.total_mass()
    }

    /// Mass below a leg's ankle sensor \[kg\].
    pub fn foot_mass(&self, side: Side) -> f64 {
        self.model.foot_mass(side)
    }

    /// Centre of mass of a foot (below the ankle sensor) in the ankle frame \[m\].
    pub fn foot_com(&self, side: Side) -> Vec3 {
        link_body(&self.model.legs[side_index(side)].links[5]).map_or([0.0; 3], |b| b.com)
    }

    /// The sole centre of a leg in its ankle frame \[m\].
    pub fn sole_offset(&self, side: Side) -> Vec3 {
        self.model.legs[side_index(side)].sole.p
    }

    /// A vector given in a leg's ankle frame, in its sole's axes (the same vector where the
    /// sole is flat in the ankle frame, as HRP-2's).
    pub fn to_sole(&self, side: Side, v: Vec3) -> Vec3 {
        let r = &self.model.legs[side_index(side)].sole.r;
        if *r == IDENTITY {
            v
        } else {
            mul_mv(&transpose(r), v)
        }
    }

    /// The ankle's pitch and roll joints of a leg: each the index (of the last two) and the
    /// sign that turns a positive angle into a positive rotation about the ankle frame's y
    /// (pitch) and x (roll) axis. HRP-2's: `[(4, 1), (5, 1)]`.
    pub fn ankle_joints(&self, side: Side) -> [(usize, f64); 2] {
        let links = &self.model.legs[side_index(side)].links;
        // Link 4's axis in the ankle frame (joint 5 at zero), both in the sole's axes.
        let a4 = self.to_sole(
            side,
            mul_mv(&transpose(&links[5].joint.origin.r), links[4].joint.axis),
        );
        let a5 = self.to_sole(side, links[5].joint.axis);
        let sign = |v: f64| if v < 0.0 { -1.0 } else { 1.0 };
        if a4[1].abs() >= a5[1].abs() {
            [(4, sign(a4[1])), (5, sign(a5[0]))]
        } else {
            [(5, sign(a5[1])), (4, sign(a4[0]))]
        }
    }

    /// Ankle (frame origin) above the sole centre \[m\].
    pub fn ankle_height(&self) -> f64 {
        -self.to_sole(Side::Left, self.model.legs[0].sole.p)[2]
    }

    /// Height of the waist origin in the walking posture \[m\].
    pub fn waist_height(&self) -> f64 {
        self.model.waist_height
    }

    fn leg_mjcf(&self, x: &mut String, side: Side) {
        let leg = &self.model.legs[side_index(side)];
        let p = match side {
            Side::Left => "l",
            Side::Right => "r",
        };
        let mut depth = 0;
        let mut i = 0;
        while i < 6 {
            // A massless link whose next joint is at its origin shares the next one's body.
            let start = i;
            while i < 5
                && leg.links[i].bodies.is_empty()
                && leg.links[i + 1].joint.origin == Pose::IDENTITY
            {
                i += 1;
            }
            let link = &leg.links[i];
            let o = &leg.links[start].joint.origin;
            let mut pos = format!(" pos=\"{}\"", v3(o.p));
            if o.r != IDENTITY {
                let q = quat(&o.r);
                let _ = write!(
                    pos,
                    " quat=\"{} {} {} {}\"",
                    g(q[0]),
                    g(q[1]),
                    g(q[2]),
                    g(q[3])
                );
            }
            let indent = "  ".repeat(3 + depth);
            let _ = write!(x, "{indent}<body name=\"{}\"{pos}>", link.name);
            for l in &leg.links[start..=i] {
                let j = &l.joint;
                let _ = write!(
                    x,
                    "<joint name=\"{}\" type=\"hinge\" axis=\"{} {} {}\"",
                    j.name,
                    g(j.axis[0]),
                    g(j.axis[1]),
                    g(j.axis[2])
                );
                if let Some([lo, hi]) = j.range {
                    let _ = write!(x, " range=\"{} {}\"", g(lo), g(hi));
                }
                if j.effort.is_some() {
                    // The servo's damping is the motor's: inside the actuator, under its limit.
                    x.push_str(" damping=\"0\"");
                }
                x.push_str("/>");
            }
            if let Some(b) = link_body(link) {
                x.push_str(&inertial(&b));
                // The links at the ankle (the last two) touch the floor with the sole only.
                if i < 4 {
                    // An imported link's box stays on its bone (HRP-2's boxes are its bones).
                    let bone = (self.model.closed_form.is_none()).then(|| {
                        let o = leg.links[i + 1].joint.origin.p[2];
                        [o.min(0.0) - 0.02, o.max(0.0) + 0.02]
                    });
                    x.push_str(&collision_box_within(
                        &format!("{}_geom", link.name),
                        &b,
                        bone,
                    ));
                }
            }
            if i == 5 {
                let mut c = leg.sole.p;
                let mut turn = String::new();
                if leg.sole.r == IDENTITY {
                    c[2] += self.sole_half[2];
                } else {
                    // The box's bottom on the sole's plane, in the sole's axes.
                    let up = mul_mv(&leg.sole.r, [0.0, 0.0, self.sole_half[2]]);
                    c = [c[0] + up[0], c[1] + up[1], c[2] + up[2]];
                    let q = quat(&leg.sole.r);
                    turn = format!(" quat=\"{} {} {} {}\"", g(q[0]), g(q[1]), g(q[2]), g(q[3]));
                }
                let _ = write!(
                    x,
                    "<geom name=\"{p}_sole\" type=\"box\" pos=\"{}\"{turn} size=\"{}\" class=\"robot\"/>\
                     <site name=\"{p}_ankle\" pos=\"0 0 0\"/></body>",
                    v3(c),
                    v3(self.sole_half)
                );
            } else {
                x.push('\n');
                depth += 1;
            }
            i += 1;
        }
        let _ = writeln!(x, "{}", "</body>".repeat(depth));
    }

    fn joints(&self) -> impl Iterator<Item = &crate::robot::model::Joint> {
        self.model
            .legs
            .iter()
            .flat_map(|l| l.links.iter().map(|l| &l.joint))
    }

    /// The MJCF document.
    pub fn mjcf(&self) -> String {
        let h = &self.model;
        let mut x = String::new();
        let _ = writeln!(x, "<mujoco model=\"host-sim\">");
        let _ = writeln!(x, "  <compiler angle=\"radian\"/>");
        let _ = writeln!(
            x,
            "  <option timestep=\"0.001\" integrator=\"implicitfast\" gravity=\"0 0 {}\"/>",
            f(-h.gravity)
        );
        let _ = writeln!(
            x,
            "  <default><joint damping=\"{}\" armature=\"{}\"/><position kp=\"{}\"/>\
             <default class=\"robot\"><geom contype=\"2\" conaffinity=\"1\" condim=\"3\" \
             friction=\"1 0.005 0.0001\" solref=\"0.004 1\" solimp=\"0.95 0.99 0.001\"/></default>\
             </default>",
            f(self.servo[1]),
            f(ARMATURE),
            f(self.servo[0])
        );
        let _ = writeln!(x, "  <worldbody>");
        let _ = writeln!(
            x,
            "    <geom name=\"floor\" type=\"plane\" size=\"50 50 0.1\" contype=\"1\" \
             conaffinity=\"2\" condim=\"3\" friction=\"1 0.005 0.0001\" solref=\"0.004 1\" \
             solimp=\"0.95 0.99 0.001\"/>"
        );
        let root = |name: &str| h.root.iter().find(|n| n.name == name).map(|n| n.body);
        let mut waist = format!(
            "    <body name=\"waist\" pos=\"0 0 {}\"><freejoint name=\"root\"/>",
            f(h.waist_height)
        );
        if let Some(b) = root("waist").filter(|b| b.mass > 0.0) {
            waist.push_str(&inertial(&b));
            waist.push_str(&collision_box("waist_geom", &b));
        }
        let _ = writeln!(x, "{waist}<site name=\"imu\" pos=\"0 0 0\"/>");
        match root("trunk").filter(|b| b.mass > 0.0) {
            Some(b) => {
                let _ = writeln!(
                    x,
                    "      <body name=\"trunk\">{}{}</body>",
                    inertial(&b),
                    collision_box("trunk_geom", &b)
                );
            }
            None => {
                let _ = writeln!(x, "      <body name=\"trunk\"/>");
            }
        }
        for side in [Side::Left, Side::Right] {
            self.leg_mjcf(&mut x, side);
        }
        let _ = writeln!(x, "    </body>\n  </worldbody>\n  <actuator>");
        for j in self.joints() {
            let _ = write!(
                x,
                "    <position name=\"{}_servo\" joint=\"{}\"",
                j.name, j.name
            );
            if let Some(e) = j.effort {
                let _ = write!(
                    x,
                    " kv=\"{}\" forcerange=\"{} {}\"",
                    f(self.servo[1]),
                    g(-e),
                    g(e)
                );
            }
            let _ = writeln!(x, "/>");
        }
        let _ = writeln!(x, "  </actuator>\n  <sensor>");
        let _ = writeln!(
            x,
            "    <framequat name=\"imu_quat\" objtype=\"site\" objname=\"imu\"/>\n    \
             <gyro name=\"imu_gyro\" site=\"imu\"/>\n    \
             <accelerometer name=\"imu_acc\" site=\"imu\"/>"
        );
        for kind in ["jointpos", "jointvel"] {
            for j in self.joints() {
                let _ = writeln!(x, "    <{kind} joint=\"{}\"/>", j.name);
            }
        }
        for p in ["l", "r"] {
            let _ = writeln!(
                x,
                "    <force site=\"{p}_ankle\"/>\n    <torque site=\"{p}_ankle\"/>"
            );
        }
        let _ = writeln!(x, "  </sensor>\n</mujoco>");
        x
    }

    /// Inverse kinematics of one leg (see [`Model::leg_ik`]); a sole beyond the leg's reach
    /// is pulled towards the hip along the hip–ankle line until the ankle is at
    /// [`REACH_FRACTION`] of the reach (the knee nearly stretched; for a leg solved
    /// numerically, further until it converges), as a joint-space servo of a real robot would
    /// saturate, instead of failing.
    pub fn leg_ik(&self, side: Side, waist: &Pose, sole: &Pose) -> Result<LegAngles, String> {
        let h = &self.model;
        let reach = REACH_FRACTION * h.reach(side);
        let s = h.legs[side_index(side)].sole;
        let ankle = sole.then(&s.inverse()).p;
        let hip = h.hip_joint(side, waist);
        let d = sub(ankle, hip);
        let dist = norm(d);
        let mut target = *sole;
        let pulled = |k: f64| Pose {
            p: core::array::from_fn(|i| sole.p[i] - d[i] * (1.0 - k)),
            r: sole.r,
        };
        if dist > reach {
            if h.closed_form.is_some() {
                let lift = [sole.r[0][2], sole.r[1][2], sole.r[2][2]];
                let ah = -s.p[2];
                for i in 0..3 {
                    target.p[i] = hip[i] + d[i] * reach / dist - ah * lift[i];
                }
            } else {
                target = pulled(reach / dist);
            }
        }
        match h.leg_ik(side, waist, &target) {
            Ok(q) => Ok(q),
            Err(e) if h.closed_form.is_some() => Err(e.to_string()),
            Err(e) => {
                // Bisect the pull between the hip and the target for the farthest that converges.
                let (mut lo, mut hi) = (0.5, (reach / dist).min(1.0));
                let mut best = h
                    .leg_ik(side, waist, &pulled(lo))
                    .map_err(|_| e.to_string())?;
                for _ in 0..20 {
                    let mid = 0.5 * (lo + hi);
                    match h.leg_ik(side, waist, &pulled(mid)) {
                        Ok(q) => {
                            best = q;
                            lo = mid;
                        }
                        Err(_) => hi = mid,
                    }
                }
                Ok(best)
            }
        }
    }

    /// Forward kinematics: the sole centres and the ankle frames (left, right) and the
    /// whole-body COG for a waist pose and the joint angles.
    pub fn fk(&self, waist: &Pose, q: &[LegAngles; 2]) -> ([Pose; 2], [Pose; 2], Vec3) {
        let h = &self.model;
        let mut m = 0.0;
        let mut s = [0.0; 3];
        let mut acc = |mass: f64, p: Vec3| {
            m += mass;
            for (a, b) in s.iter_mut().zip(p) {
                *a += mass * b;
            }
        };
        for n in &h.root {
            acc(n.body.mass, waist.apply(n.body.com));
        }
        let mut soles = [*waist; 2];
        let mut ankles = [*waist; 2];
        for (k, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            let fr = h.leg_fk(side, waist, &q[k]);
            for (frame, link) in fr.links.iter().zip(&h.legs[k].links) {
                for b in &link.bodies {
                    acc(b.mass, frame.apply(b.com));
                }
            }
            soles[k] = fr.sole;
            ankles[k] = fr.ankle();
        }
        (soles, ankles, [s[0] / m, s[1] / m, s[2] / m])
    }

    /// Every link's frame in the world for a waist pose and the joint angles, by the MuJoCo
    /// body's name: the waist (`waist`), each leg's six links, and the soles (`left_sole`,
    /// `right_sole`).
    pub fn link_frames(&self, waist: &Pose, q: &[LegAngles; 2]) -> Vec<(String, Pose)> {
        let h = &self.model;
        let mut out = vec![("waist".to_string(), *waist)];
        for (k, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            let fr = h.leg_fk(side, waist, &q[k]);
            for (frame, link) in fr.links.iter().zip(&h.legs[k].links) {
                out.push((link.name.clone(), *frame));
            }
            let sole = if k == 0 { "left_sole" } else { "right_sole" };
            out.push((sole.to_string(), fr.sole));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equivalent_box_of_a_box_is_the_box() {
        let b = Body::cuboid(28.0, [0.0; 3], [0.30, 0.50, 0.60]);
        let h = equivalent_box(&b);
        for (got, want) in h.iter().zip([0.15, 0.25, 0.30]) {
            assert!((got - want).abs() < 1e-12, "{h:?}");
        }
    }

    #[test]
    fn fk_cog_matches_the_multibody_model() {
        let hrp2 = Model::hrp2();
        let robot = Robot::new(hrp2.clone());
        let soles = [
            Pose::upright(0.0, 0.1, 0.0, 0.0),
            Pose::upright(0.0, -0.1, 0.0, 0.0),
        ];
        let waist = Pose::upright(0.01, 0.02, hrp2.waist_height, 0.0);
        let (c, q) = hrp2.cog(&waist, &soles).unwrap();
        let (s, _, c2) = robot.fk(&waist, &q);
        for i in 0..3 {
            assert!((c[i] - c2[i]).abs() < 1e-12);
            assert!((s[0].p[i] - soles[0].p[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn ik_beyond_reach_saturates() {
        let hrp2 = Model::hrp2();
        let robot = Robot::new(hrp2.clone());
        let waist = Pose::upright(0.0, 0.0, hrp2.waist_height, 0.0);
        // 0.45 m ahead: beyond the 0.6 m reach at this waist height.
        let far = Pose::upright(0.45, 0.06, 0.0, 0.0);
        assert!(hrp2.leg_ik(Side::Left, &waist, &far).is_err());
        let q = robot.leg_ik(Side::Left, &waist, &far).expect("saturated");
        let fk = hrp2.leg_fk(Side::Left, &waist, &q);
        let hip = hrp2.hip_joint(Side::Left, &waist);
        let d = (0..3)
            .map(|i| (fk.ankle().p[i] - hip[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((d - REACH_FRACTION * 0.6).abs() < 1e-9, "{d}");
        // Within reach: unchanged.
        let near = Pose::upright(0.1, 0.06, 0.0, 0.0);
        assert_eq!(
            robot.leg_ik(Side::Left, &waist, &near).unwrap(),
            hrp2.leg_ik(Side::Left, &waist, &near).unwrap()
        );
    }

    #[test]
    fn mjcf_names_every_joint_and_sensor() {
        let x = Robot::default().mjcf();
        assert_eq!(x.matches("<position name=").count(), 12);
        assert_eq!(x.matches("<jointpos ").count(), 12);
        assert_eq!(x.matches("type=\"hinge\"").count(), 12);
        assert!(x.contains("size=\"0.120000 0.070000 0.040000\""));
        assert!(x.contains("timestep=\"0.001\""));
    }

    #[test]
    fn the_robot_files_soles_make_the_sole_boxes() {
        let small = crate::robot::Robot::from_toml(include_str!("../../tests/robots/small.toml"))
            .expect("small.toml");
        let r = Robot::of(&small);
        // [feet] 0.16 × 0.09; ankle_height 0.06 < 0.08: the box is 0.06 high.
        assert_eq!(r.sole_half(), [0.08, 0.045, 0.03]);
        let x = r.mjcf();
        assert_eq!(x.matches("size=\"0.080000 0.045000 0.030000\"").count(), 2);
        assert!(!x.contains("0.120000 0.070000"));
        // The bottom face 0.06 below the ankle: the box centre 0.03 below it.
        assert!(x.contains("pos=\"0.000000 0.000000 -0.030000\" size=\"0.080000"));
        // Servos scaled by the mass, 17.4 kg against HRP-2's.
        let scale = small.model.total_mass() / link_table().total_mass();
        assert!((small.model.total_mass() - 17.4).abs() < 1e-9);
        assert!(scale > 0.25 && scale < 0.4, "{scale}");
        assert_eq!(r.servo(), [SERVO_KP * scale, SERVO_KD * scale]);
        assert!(x.contains(&format!("kp=\"{:.6}\"", SERVO_KP * scale)));
        // HRP-2's file gives the default robot's soles.
        let h = Robot::of(&crate::robot::Robot::hrp2());
        assert_eq!(h.sole_half(), SOLE_HALF);
        assert_eq!(h.mjcf(), Robot::default().mjcf());
    }
}
