//! The general link table: a `[multibody]` that lists each leg's six joints and links, as
//! `host-sim robot import` writes it from a URDF (any order of revolute joints, any axes,
//! full inertia tensors, a sole centre anywhere in the ankle's frame).
//!
//! | key | meaning |
//! |---|---|
//! | `waist_height` | the waist (root link) origin above the floor while walking \[m\] |
//! | `[multibody.waist]` | the root link's own body, in its frame: `mass`, `com`, `inertia` (as in the hand-written table) |
//! | `[multibody.trunk]` | the rest of the upper body (torso, arms, head) at its stated pose, merged into one body in the waist frame |
//! | `[[multibody.left]]`, `[[multibody.right]]` | six entries, hip first: `joint` and `link` (names), `origin` \[m\] and `rpy` \[rad\] of the joint in the previous link's frame (the waist's for the first), its unit `axis`; optional `range` \[rad\], `effort` \[N m\], `velocity` \[rad/s\]; the link's `mass`, `com`, `inertia` (a mass of 0 is allowed) |
//! | `[multibody.sole]` | `left`, `right`: the sole centre in the last link's frame \[m\]; optional `left_rpy`, `right_rpy`: the sole's orientation in it \[rad\] (default: the sole is flat in that frame) |
//!
//! The checks, each naming its key: six entries per leg, unit axes, ranges with
//! `lower < upper`, positive limits, bodies as in the hand-written table, and the standing
//! posture within reach (the numerical inverse kinematics converges from a bent knee: the
//! joint about the y axis nearest the middle between hip and ankle, bent forward by 0.5 rad).

use planner_core::gait::Side;
use planner_core::robot::RobotError;
use serde::Deserialize;

use super::model::{
    mul_mv, norm, rot_rpy, side_index, Joint, LegAngles, Link, Model, Named, Pose, Vec3,
};
use super::table::{invalid, length, BodySpec};

/// The keys of a general link table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Tree {
    waist_height: f64,
    waist: BodySpec,
    trunk: BodySpec,
    left: Vec<LinkSpec>,
    right: Vec<LinkSpec>,
    sole: Soles,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Soles {
    left: Vec3,
    right: Vec3,
    #[serde(default)]
    left_rpy: Option<Vec3>,
    #[serde(default)]
    right_rpy: Option<Vec3>,
}

/// One leg link as the file gives it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LinkSpec {
    joint: String,
    link: String,
    origin: Vec3,
    rpy: Vec3,
    axis: Vec3,
    range: Option<[f64; 2]>,
    effort: Option<f64>,
    velocity: Option<f64>,
    mass: f64,
    com: Vec3,
    inertia: Vec<f64>,
}

const LEFT: &str = "multibody.left";
const RIGHT: &str = "multibody.right";

impl LinkSpec {
    fn link(&self, key: &'static str) -> Result<Link, RobotError> {
        let named = |m: &str| invalid(key, format!("joint `{}`: {m}", self.joint));
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.origin) || !finite(&self.rpy) {
            return Err(named("origin and rpy must be finite"));
        }
        let n = norm(self.axis);
        if !(n.is_finite() && (n - 1.0).abs() < 1e-6) {
            return Err(named("axis must be a unit vector"));
        }
        if let Some([lo, hi]) = self.range {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(named("range must be [lower, upper] with lower < upper"));
            }
        }
        for (what, v) in [("effort", self.effort), ("velocity", self.velocity)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(named(&format!("{what} must be finite and > 0")));
                }
            }
        }
        Ok(Link {
            name: self.link.clone(),
            joint: Joint {
                name: self.joint.clone(),
                origin: Pose {
                    p: self.origin,
                    r: rot_rpy(self.rpy),
                },
                axis: self.axis,
                range: self.range,
                effort: self.effort,
                velocity: self.velocity,
            },
            bodies: {
                let b = BodySpec::of_inertia(self.mass, self.com, self.inertia.clone())
                    .body(key, true)?;
                if b.mass > 0.0 {
                    vec![b]
                } else {
                    vec![]
                }
            },
        })
    }
}

/// The joint of a leg about the y axis (at zero angles, in the waist frame) whose origin is
/// nearest the middle between hip and ankle: the knee; its angle that bends it forward.
fn knee_seed(leg: &[Link; 6]) -> LegAngles {
    let mut pose = Pose::IDENTITY;
    let mut frames = [Pose::IDENTITY; 6];
    for (f, l) in frames.iter_mut().zip(leg) {
        pose = pose.then(&l.joint.origin);
        *f = pose;
    }
    let mid = 0.5 * (frames[0].p[2] + frames[5].p[2]);
    let mut q = [0.0; 6];
    let knee = (1..5)
        .filter_map(|i| {
            let a = mul_mv(&frames[i].r, leg[i].joint.axis);
            (a[1].abs() > 0.9).then_some((i, a[1], (frames[i].p[2] - mid).abs()))
        })
        .min_by(|a, b| a.2.total_cmp(&b.2));
    if let Some((i, ay, _)) = knee {
        q[i] = 0.5 * ay.signum();
    }
    q
}

impl Tree {
    /// The model of the table (gravity from the planner's part), its standing posture not yet
    /// solved (the knees bent by the seed).
    pub(super) fn raw_model(&self, gravity: f64) -> Result<Model, RobotError> {
        let waist_height = length("multibody.waist_height", self.waist_height)?;
        let leg = |key: &'static str, specs: &[LinkSpec], sole: Vec3, rpy: Option<Vec3>| {
            let links: Vec<Link> = specs
                .iter()
                .map(|s| s.link(key))
                .collect::<Result<_, _>>()?;
            let n = links.len();
            let links: [Link; 6] = links.try_into().map_err(|_| {
                invalid(
                    key,
                    format!("{n} joints: a leg has six revolute joints, hip to ankle"),
                )
            })?;
            let rpy = rpy.unwrap_or([0.0; 3]);
            if !sole.iter().chain(&rpy).all(|v| v.is_finite()) {
                return Err(invalid("multibody.sole", "must be finite".into()));
            }
            Ok(super::model::Leg {
                links,
                sole: Pose {
                    p: sole,
                    r: rot_rpy(rpy),
                },
            })
        };
        let legs = [
            leg(LEFT, &self.left, self.sole.left, self.sole.left_rpy)?,
            leg(RIGHT, &self.right, self.sole.right, self.sole.right_rpy)?,
        ];
        let stance = [knee_seed(&legs[0].links), knee_seed(&legs[1].links)];
        Ok(Model {
            gravity,
            waist_height,
            root: Named::root(
                self.trunk.body("multibody.trunk", true)?,
                self.waist.body("multibody.waist", false)?,
            ),
            legs,
            closed_form: None,
            stance,
        })
    }

    /// The model of the table (gravity from the planner's part), standing with the feet
    /// `step_width` apart.
    pub(super) fn model(&self, gravity: f64, step_width: f64) -> Result<Model, RobotError> {
        let mut model = self.raw_model(gravity)?;
        let (waist, soles) = model.stance_pose(step_width);
        for side in [Side::Left, Side::Right] {
            let i = side_index(side);
            let q = model
                .numerical_ik(side, &waist, &soles[i], model.stance[i])
                .map_err(|e| {
                    invalid(
                        "multibody.waist_height",
                        format!("the legs cannot stand with the feet {step_width} m apart: {e}"),
                    )
                })?;
            model.stance[i] = q;
        }
        // The knee must bend forward in the standing posture (the other branch is a
        // backward knee).
        for (i, key) in [LEFT, RIGHT].into_iter().enumerate() {
            let seed = knee_seed(&model.legs[i].links);
            if let Some(k) = seed.iter().position(|v| *v != 0.0) {
                if model.stance[i][k] * seed[k] <= 0.0 {
                    return Err(invalid(
                        key,
                        format!(
                            "joint `{}` (the knee) does not bend forward standing",
                            model.legs[i].links[k].joint.name
                        ),
                    ));
                }
            }
        }
        Ok(model)
    }
}
