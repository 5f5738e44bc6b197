//! The hand-written link table: a `[multibody]` of HRP-2's shape, read into a [`Model`] with
//! the closed-form inverse kinematics.
//!
//! | key | meaning |
//! |---|---|
//! | `thigh_length`, `shank_length` | hip joint centre to knee, knee to ankle joint centre \[m\] |
//! | `hip_offset` | lateral distance of each hip joint centre from the waist origin \[m\] |
//! | `ankle_height` | ankle joint centre above the sole \[m\] |
//! | `waist_height` | waist origin above the floor while walking \[m\] |
//! | `[multibody.limits.<joint>]`, optional, for hip_yaw, hip_roll, hip_pitch, knee, ankle_pitch, ankle_roll | `range = [lower, upper]` \[rad\] of the left leg's joint (the right leg's mirrored: yaw and roll ranges change sign and swap ends), optional `effort` \[N m\]: MuJoCo limits the joint and saturates its servo there |
//! | `[multibody.<body>]` for trunk, waist, hip, thigh, shank, foot | `mass` \[kg\], `com` \[m\] in the body's link frame (below), and one of `box = [x, y, z]` (sides of a homogeneous box), `cylinder = [radius, length]` (a solid cylinder along z) or `inertia` (principal moments `[Ixx, Iyy, Izz]` about the COM, or the tensor `[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`) |
//!
//! # The shape
//!
//! Ten rigid bodies on eighteen degrees of freedom:
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
//! The **waist origin** is the midpoint of the two hip joint centres; the hip joints are at
//! `(0, ±hip_offset, 0)` in the waist frame (+ left). Each leg: hip yaw `q1` (about z), hip
//! roll `q2` (x), hip pitch `q3` (y), knee pitch `q4` (y), ankle pitch `q5` (y), ankle roll
//! `q6` (x). The three hip axes intersect at the hip joint centre and the two ankle axes at the
//! ankle joint centre, so the leg has a closed-form inverse kinematics
//! ([`super::model::closed_form_ik`]). With all angles zero the leg hangs straight down: the
//! knee is `thigh_length` below the hip, the ankle `shank_length` below the knee, and the sole
//! centre `ankle_height` below the ankle. A bent knee is `q4 > 0`. The orientation of the
//! thigh is `R_w R_z(q1) R_x(q2) R_y(q3)`, of the shank that times `R_y(q4)`, and of the foot
//! that times `R_y(q5) R_x(q6)`. Link bodies are given for the left leg; the right leg
//! mirrors them (centre-of-mass y and the products of inertia with y change sign).
//!
//! The checks, each naming its key: lengths and masses finite and positive (the hip housing
//! may be massless), inertias non-negative, and the reach limits and the swing height within
//! the legs' reach at the walking height ([`check_legs`]).
//!
//! # HRP-2's parameters and their sources
//!
//! Published HRP-2 figures (Kaneko et al., "Humanoid robot HRP-2", ICRA 2004): height 1.54 m,
//! total mass 58 kg (with batteries), thigh and shank 0.30 m. The half-sitting posture of
//! HRP-2's walking controllers bends the knee by about 50° (hip pitch −26°, knee 50°, ankle
//! pitch −24°). Everything else is an **assumption** of this model (the mass distribution of
//! HRP-2 is not in the papers cited here), chosen to be plausible for a 58 kg, 1.54 m humanoid
//! and summing to 58 kg. Inertia tensors are those of homogeneous boxes
//! (`I_xx = m (b² + c²) / 12` for a box `a × b × c` along x, y, z) and solid cylinders along
//! the link (`I_xx = I_yy = m (3 r² + l²) / 12`, `I_zz = m r² / 2`), diagonal in the body
//! frame, about the body's centre of mass (`host-sim/robots/hrp2.toml`):
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
//! | joint ranges (left leg) | hip yaw −30…45°, hip roll −20…35°, hip pitch −125…42°, knee 0…150°, ankle pitch −75…42°, ankle roll −35…20° (`[multibody.limits]`) | Kaneko 2004, movable ranges |
//! | joint torque limits | none (the servos of `physics::model` unsaturated) | assumed: not published there |
//!
//! The waist height is chosen (by bisection, rounded to 0.1 mm) so that the whole-body COG is
//! 0.814 m high standing with the feet at (0, ±0.1) and the waist between them; the knees are
//! then bent by 47.7° (hip roll 4.2°, hip and ankle pitch −23.9°): close to HRP-2's
//! half-sitting posture, which leaves the reach needed for long steps (a straighter stance
//! puts the ankle out of reach in the 0.3 m step of the `fig4` scenario).
//!
//! Other assumptions: the trunk is rigidly fixed to the waist (no chest joint moves, the arms do
//! not swing); the joints follow the references exactly (no compliance, no ankle flexibility,
//! no tracking error); the stance feet stay flat on the floor, so the ZMP formula applies
//! whenever it falls inside the support polygon.

use std::collections::BTreeMap;

use planner_core::robot::{Robot as PlannerRobot, RobotError};
use serde::Deserialize;

use super::model::{Body, ClosedForm, Joint, Leg, Link, Model, Named, Pose, Vec3, IDENTITY};

/// The keys of a link table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Links {
    thigh_length: f64,
    shank_length: f64,
    hip_offset: f64,
    ankle_height: f64,
    waist_height: f64,
    trunk: BodySpec,
    waist: BodySpec,
    hip: BodySpec,
    thigh: BodySpec,
    shank: BodySpec,
    foot: BodySpec,
    /// Optional joint limits of the left leg by joint name (the right mirrored).
    #[serde(default)]
    limits: BTreeMap<String, LimitSpec>,
}

/// A joint's limits as a robot file gives them (`[multibody.limits.<joint>]`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LimitSpec {
    range: Option<[f64; 2]>,
    effort: Option<f64>,
}

/// The joints a `[multibody.limits]` table names.
const JOINT_NAMES: [&str; 6] = [
    "hip_yaw",
    "hip_roll",
    "hip_pitch",
    "knee",
    "ankle_pitch",
    "ankle_roll",
];

/// A body as a robot file gives it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BodySpec {
    mass: f64,
    com: Vec3,
    #[serde(rename = "box")]
    cuboid: Option<Vec3>,
    cylinder: Option<[f64; 2]>,
    inertia: Option<Vec<f64>>,
}

pub(super) fn invalid(key: &'static str, message: String) -> RobotError {
    RobotError::Invalid { key, message }
}

pub(super) fn length(key: &'static str, v: f64) -> Result<f64, RobotError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(key, format!("{v} m must be finite and > 0")))
    }
}

impl BodySpec {
    /// A body given by its inertia (`[Ixx, Iyy, Izz]` or the six components of the tensor).
    pub(super) fn of_inertia(mass: f64, com: Vec3, inertia: Vec<f64>) -> Self {
        Self {
            mass,
            com,
            cuboid: None,
            cylinder: None,
            inertia: Some(inertia),
        }
    }

    /// The body; `massless`: a mass of zero is allowed.
    pub(super) fn body(&self, key: &'static str, massless: bool) -> Result<Body, RobotError> {
        let m = self.mass;
        if !(m.is_finite() && (m > 0.0 || (massless && m == 0.0))) {
            return Err(invalid(key, format!("mass {m} kg must be finite and > 0")));
        }
        if !self.com.iter().all(|c| c.is_finite()) {
            return Err(invalid(key, "com must be finite".into()));
        }
        let non_negative = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x >= 0.0);
        match (self.cuboid, self.cylinder, &self.inertia) {
            (Some(size), None, None) if non_negative(&size) => Ok(Body::cuboid(m, self.com, size)),
            (None, Some([r, l]), None) if non_negative(&[r, l]) => {
                Ok(Body::cylinder(m, self.com, r, l))
            }
            (None, None, Some(i)) if i.len() == 3 && non_negative(i) => {
                Ok(Body::principal(m, self.com, [i[0], i[1], i[2]]))
            }
            (None, None, Some(i)) if i.len() == 6 => tensor(key, m, self.com, i),
            (None, None, Some(_)) => Err(invalid(
                key,
                "inertia is [Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], finite, \
                 moments ≥ 0"
                    .into(),
            )),
            (None, None, None) => Err(invalid(key, "give one of box, cylinder or inertia".into())),
            (a, b, c)
                if [a.is_some(), b.is_some(), c.is_some()]
                    .iter()
                    .filter(|x| **x)
                    .count()
                    > 1 =>
            {
                Err(invalid(
                    key,
                    "give only one of box, cylinder or inertia".into(),
                ))
            }
            _ => Err(invalid(
                key,
                "sizes and moments of inertia must be finite and ≥ 0".into(),
            )),
        }
    }
}

/// A full inertia tensor: finite, moments ≥ 0 and the triangle inequalities of a physical
/// body (each moment at most the sum of the other two, with a relative slack of 1e-6 for the
/// rounding of published tables).
fn tensor(key: &'static str, m: f64, com: Vec3, i: &[f64]) -> Result<Body, RobotError> {
    let [xx, yy, zz, xy, xz, yz] = [i[0], i[1], i[2], i[3], i[4], i[5]];
    if !i.iter().all(|v| v.is_finite()) || xx < 0.0 || yy < 0.0 || zz < 0.0 {
        return Err(invalid(
            key,
            "inertia must be finite with moments ≥ 0".into(),
        ));
    }
    let slack = 1e-6 * (xx + yy + zz);
    if xx > yy + zz + slack || yy > xx + zz + slack || zz > xx + yy + slack {
        return Err(invalid(
            key,
            format!("inertia [{xx}, {yy}, {zz}] breaks the triangle inequality of a body"),
        ));
    }
    Ok(Body {
        mass: m,
        com,
        inertia: [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]],
    })
}

fn at(p: Vec3) -> Pose {
    Pose { p, r: IDENTITY }
}

impl Links {
    /// The model of the table (gravity from the planner's part).
    pub(super) fn model(&self, gravity: f64) -> Result<Model, RobotError> {
        let c = ClosedForm {
            thigh: length("multibody.thigh_length", self.thigh_length)?,
            shank: length("multibody.shank_length", self.shank_length)?,
            hip_offset: length("multibody.hip_offset", self.hip_offset)?,
            ankle_height: length("multibody.ankle_height", self.ankle_height)?,
        };
        let waist_height = length("multibody.waist_height", self.waist_height)?;
        let hip = self.hip.body("multibody.hip", true)?;
        let thigh = self.thigh.body("multibody.thigh", false)?;
        let shank = self.shank.body("multibody.shank", false)?;
        let foot = self.foot.body("multibody.foot", false)?;
        for (name, l) in &self.limits {
            if !JOINT_NAMES.contains(&name.as_str()) {
                return Err(invalid(
                    "multibody.limits",
                    format!("{name:?}: not a joint (one of {})", JOINT_NAMES.join(", ")),
                ));
            }
            if l.range
                .is_some_and(|[lo, hi]| !(lo.is_finite() && hi.is_finite() && lo < hi))
            {
                return Err(invalid(
                    "multibody.limits",
                    format!("{name}: range must be [lower, upper] with lower < upper [rad]"),
                ));
            }
            if l.effort.is_some_and(|e| !(e.is_finite() && e > 0.0)) {
                return Err(invalid(
                    "multibody.limits",
                    format!("{name}: effort must be finite and > 0 [N m]"),
                ));
            }
        }
        let leg = |p: &str, sign: f64, mirror: fn(&Body) -> Body| {
            let j = |name: &str, origin: Vec3, axis: Vec3| {
                let mut joint = Joint::new(&format!("{p}_{name}"), at(origin), axis);
                if let Some(l) = self.limits.get(name) {
                    // The right leg mirrors the left: rotations about x and z change sign.
                    joint.range = l.range.map(|[lo, hi]| {
                        if sign < 0.0 && axis[1] == 0.0 {
                            [-hi, -lo]
                        } else {
                            [lo, hi]
                        }
                    });
                    joint.effort = l.effort;
                }
                joint
            };
            let link = |name: &str, joint: Joint, bodies: Vec<Body>| Link {
                name: format!("{p}_{name}"),
                joint,
                bodies,
            };
            Leg {
                links: [
                    link(
                        "hip_yaw_link",
                        j("hip_yaw", [0.0, sign * c.hip_offset, 0.0], [0.0, 0.0, 1.0]),
                        vec![],
                    ),
                    link(
                        "hip",
                        j("hip_roll", [0.0; 3], [1.0, 0.0, 0.0]),
                        vec![mirror(&hip)],
                    ),
                    link(
                        "thigh",
                        j("hip_pitch", [0.0; 3], [0.0, 1.0, 0.0]),
                        vec![mirror(&thigh)],
                    ),
                    link(
                        "shank",
                        j("knee", [0.0, 0.0, -c.thigh], [0.0, 1.0, 0.0]),
                        vec![mirror(&shank)],
                    ),
                    link(
                        "ankle_pitch_link",
                        j("ankle_pitch", [0.0, 0.0, -c.shank], [0.0, 1.0, 0.0]),
                        vec![],
                    ),
                    link(
                        "foot",
                        j("ankle_roll", [0.0; 3], [1.0, 0.0, 0.0]),
                        vec![mirror(&foot)],
                    ),
                ],
                sole: at([0.0, 0.0, -c.ankle_height]),
            }
        };
        Ok(Model {
            gravity,
            waist_height,
            root: Named::root(
                self.trunk.body("multibody.trunk", false)?,
                self.waist.body("multibody.waist", false)?,
            ),
            legs: [leg("l", 1.0, |b| *b), leg("r", -1.0, Body::mirrored)],
            closed_form: Some(c),
            stance: [[0.0; 6]; 2],
        })
    }
}

/// What the legs can reach at the walking height: the feet at most
/// `2 √(L² − h²)` apart (each ankle `√(L² − h²)` from below its hip, `L` the leg length, `h`
/// the hip-to-ankle height while walking), and a swing height that leaves the knee a tenth of
/// the leg length before it folds completely (`h − step_height ≥ |thigh − shank| + L/10`).
pub(super) fn check_legs(planner: &PlannerRobot, m: &Model) -> Result<(), RobotError> {
    let Some(c) = m.closed_form else {
        return Ok(());
    };
    let leg = c.thigh + c.shank;
    let h = m.waist_height - c.ankle_height;
    if !(h > 0.0 && h < leg) {
        return Err(invalid(
            "multibody.waist_height",
            format!(
                "{} m puts the ankles {h:.4} m below the hips: the legs ({leg} m) cannot reach",
                m.waist_height
            ),
        ));
    }
    let across = 2.0 * (leg * leg - h * h).sqrt();
    let d = planner.reach.max_feet_distance;
    if d > across {
        return Err(invalid(
            "reach.max_feet_distance",
            format!(
                "{d} m: the legs reach feet at most {across:.4} m apart at the walking height \
                 (multibody.waist_height)"
            ),
        ));
    }
    let lift = h - (c.thigh - c.shank).abs() - leg / 10.0;
    let sh = planner.params.step_height;
    if sh > lift {
        return Err(invalid(
            "feet.step_height",
            format!("{sh} m: the legs lift the foot at most {lift:.4} m at the walking height"),
        ));
    }
    Ok(())
}
