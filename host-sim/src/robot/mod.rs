//! The robot host-sim simulates, read from a robot file (`--robot FILE`; by default HRP-2,
//! `host-sim/robots/hrp2.toml`, compiled into the binary).
//!
//! The planner's part of the file (`[pendulum]`, `[timing]`, `[adjustment]`, `[feet]`,
//! `[reach]`, `[preview]`) is read by [`planner_core::robot`], which the firmware's build
//! script also uses, so the simulated node and the board's node are configured from one file.
//! This module reads the `[multibody]` link table into a [`Model`]:
//!
//! | key | meaning |
//! |---|---|
//! | `thigh_length`, `shank_length` | hip joint centre to knee, knee to ankle joint centre \[m\] |
//! | `hip_offset` | lateral distance of each hip joint centre from the waist origin \[m\] |
//! | `ankle_height` | ankle joint centre above the sole \[m\] |
//! | `waist_height` | waist origin above the floor while walking \[m\] |
//! | `[multibody.<body>]` for trunk, waist, hip, thigh, shank, foot | `mass` \[kg\], `com` \[m\] in the body's link frame (see [`Model`]), and one of `box = [x, y, z]` (sides of a homogeneous box), `cylinder = [radius, length]` (a solid cylinder along z) or `inertia = [Ixx, Iyy, Izz]` (principal moments about the COM) |
//!
//! Checks, each naming its key: the reach limits and the swing height within the legs'
//! reach at the walking height (`check_legs`); the control period the simulator's scenarios and bus run at
//! ([`TICK_S`], 5 ms); lengths and masses finite and positive (the hip housing may be
//! massless), inertias non-negative; the stance reachable by the legs; and the stance COG of
//! the link table (feet `step_width` apart, waist at `waist_height`) within
//! [`STANCE_TOLERANCE_M`] of the pendulum's `cog_height`, since the planner's COG is the
//! multi-body model's COG.

use std::fmt;
use std::path::Path;

use planner_core::node::NodeConfig;
use planner_core::robot::{Robot as PlannerRobot, RobotError};
use serde::Deserialize;

pub mod model;

use crate::scenario::TICK_S;
use model::{Body, Model, Vec3};

/// The robot file shipped for HRP-2, compiled into the binary.
pub const HRP2_TOML: &str = include_str!("../../robots/hrp2.toml");

/// Largest difference between the link table's stance COG height and the pendulum's
/// `cog_height` \[m\].
pub const STANCE_TOLERANCE_M: f64 = 0.005;

/// A robot: the planner's part and the multi-body model.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// The planner's part (name, gait parameters, reach limits).
    pub planner: PlannerRobot,
    /// The multi-body model.
    pub model: Model,
}

/// Why a robot file was refused.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadError {
    /// The file (`None`: the built-in HRP-2 file).
    pub path: Option<String>,
    /// What is wrong.
    pub error: RobotError,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let path = self.path.as_deref().unwrap_or("(built-in hrp2.toml)");
        write!(f, "robot file {path}: {}", self.error)
    }
}

impl std::error::Error for LoadError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Links {
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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BodySpec {
    mass: f64,
    com: Vec3,
    #[serde(rename = "box")]
    cuboid: Option<Vec3>,
    cylinder: Option<[f64; 2]>,
    inertia: Option<Vec3>,
}

fn invalid(key: &'static str, message: String) -> RobotError {
    RobotError::Invalid { key, message }
}

fn length(key: &'static str, v: f64) -> Result<f64, RobotError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(key, format!("{v} m must be finite and > 0")))
    }
}

impl BodySpec {
    fn body(&self, key: &'static str, massless: bool) -> Result<Body, RobotError> {
        let m = self.mass;
        if !(m.is_finite() && (m > 0.0 || (massless && m == 0.0))) {
            return Err(invalid(key, format!("mass {m} kg must be finite and > 0")));
        }
        if !self.com.iter().all(|c| c.is_finite()) {
            return Err(invalid(key, "com must be finite".into()));
        }
        let non_negative = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x >= 0.0);
        match (self.cuboid, self.cylinder, self.inertia) {
            (Some(size), None, None) if non_negative(&size) => Ok(Body::cuboid(m, self.com, size)),
            (None, Some([r, l]), None) if non_negative(&[r, l]) => {
                Ok(Body::cylinder(m, self.com, r, l))
            }
            (None, None, Some(i)) if non_negative(&i) => Ok(Body {
                mass: m,
                com: self.com,
                inertia: i,
            }),
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

/// What the legs can reach at the walking height: the feet at most
/// `2 √(L² − h²)` apart (each ankle `√(L² − h²)` from below its hip, `L` the leg length, `h`
/// the hip-to-ankle height while walking), and a swing height that leaves the knee a tenth of
/// the leg length before it folds completely (`h − step_height ≥ |thigh − shank| + L/10`).
fn check_legs(planner: &PlannerRobot, m: &Model) -> Result<(), RobotError> {
    let leg = m.thigh_length + m.shank_length;
    let h = m.waist_height - m.ankle_height;
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
    let lift = h - (m.thigh_length - m.shank_length).abs() - leg / 10.0;
    let sh = planner.params.step_height;
    if sh > lift {
        return Err(invalid(
            "feet.step_height",
            format!("{sh} m: the legs lift the foot at most {lift:.4} m at the walking height"),
        ));
    }
    Ok(())
}

impl Robot {
    /// HRP-2 from the file shipped in the repository.
    pub fn hrp2() -> Self {
        // Read once per process (the check computes the preview gains).
        static HRP2: std::sync::OnceLock<Robot> = std::sync::OnceLock::new();
        HRP2.get_or_init(|| match Self::from_toml(HRP2_TOML) {
            Ok(r) => r,
            // The shipped file is checked by the tests (host-sim/tests/robot.rs).
            Err(e) => unreachable!("the built-in robot file is invalid: {e}"),
        })
        .clone()
    }

    /// Reads a robot file.
    pub fn load(path: &Path) -> Result<Self, LoadError> {
        let name = Some(path.display().to_string());
        let text = std::fs::read_to_string(path).map_err(|e| LoadError {
            path: name.clone(),
            error: RobotError::Syntax(format!("cannot be read: {e}")),
        })?;
        Self::from_toml(&text).map_err(|error| LoadError { path: name, error })
    }

    /// Reads the text of a robot file (see the module docs).
    pub fn from_toml(text: &str) -> Result<Self, RobotError> {
        let planner = PlannerRobot::from_toml(text)?;
        let dt = planner.params.dt;
        if (dt - TICK_S).abs() > 1e-12 {
            return Err(invalid(
                "timing.control_period",
                format!(
                    "{dt} s: host-sim simulates a {TICK_S} s control cycle (its scenarios, bus \
                     timing and the firmware's loop); only the planner takes other periods"
                ),
            ));
        }
        let table = planner.multibody.clone().ok_or_else(|| {
            RobotError::Syntax("missing table `[multibody]` (host-sim's link table)".into())
        })?;
        let links: Links = table
            .try_into()
            .map_err(|e: toml::de::Error| RobotError::Syntax(format!("in [multibody]: {e}")))?;
        let model = Model {
            thigh_length: length("multibody.thigh_length", links.thigh_length)?,
            shank_length: length("multibody.shank_length", links.shank_length)?,
            hip_offset: length("multibody.hip_offset", links.hip_offset)?,
            ankle_height: length("multibody.ankle_height", links.ankle_height)?,
            waist_height: length("multibody.waist_height", links.waist_height)?,
            gravity: planner.params.gravity,
            trunk: links.trunk.body("multibody.trunk", false)?,
            waist: links.waist.body("multibody.waist", false)?,
            hip: links.hip.body("multibody.hip", true)?,
            thigh: links.thigh.body("multibody.thigh", false)?,
            shank: links.shank.body("multibody.shank", false)?,
            foot: links.foot.body("multibody.foot", false)?,
        };
        check_legs(&planner, &model)?;
        let width = planner.params.step_width;
        let z = model.stance_cog_height(width).map_err(|e| {
            invalid(
                "multibody.waist_height",
                format!("the legs cannot stand with the feet {width} m apart: {e}"),
            )
        })?;
        let z_c = planner.params.cog_height;
        if (z - z_c).abs() > STANCE_TOLERANCE_M {
            return Err(invalid(
                "multibody.waist_height",
                format!(
                    "puts the stance COG of the link table at {z:.4} m, but pendulum.cog_height \
                     is {z_c} m (at most {STANCE_TOLERANCE_M} m apart)"
                ),
            ));
        }
        Ok(Self { planner, model })
    }

    /// The robot's name.
    pub fn name(&self) -> &str {
        &self.planner.name
    }

    /// The node for this robot.
    pub fn node_config(&self) -> NodeConfig {
        self.planner.node_config()
    }

    /// Whether this robot can walk HRP-2's footsteps (the built-in scenarios, the fault
    /// sweep's and the paper's grid are written for feet `step_width` = 0.2 m apart): an error
    /// naming `what` and the robot's width if its feet stand otherwise.
    pub fn check_hrp2_footsteps(&self, what: &str) -> Result<(), String> {
        let hrp2_width = Self::hrp2().planner.params.step_width;
        let width = self.planner.params.step_width;
        if width == hrp2_width {
            Ok(())
        } else {
            Err(format!(
                "{what}: the built-in scenarios are HRP-2's footsteps (feet {hrp2_width} m \
                 apart), and {} stands {width} m apart: write a scenario file for it",
                self.name()
            ))
        }
    }
}

impl Model {
    /// HRP-2, from the robot file shipped in the repository (`host-sim/robots/hrp2.toml`).
    pub fn hrp2() -> Self {
        Robot::hrp2().model
    }
}
