//! The robot host-sim simulates, read from a robot file (`--robot FILE`; by default HRP-2,
//! `host-sim/robots/hrp2.toml`, compiled into the binary).
//!
//! The planner's part of the file (`[pendulum]`, `[timing]`, `[adjustment]`, `[feet]`,
//! `[reach]`, `[preview]`) is read by [`planner_core::robot`], which the firmware's build
//! script also uses, so the simulated node and the board's node are configured from one file.
//! This module reads the `[multibody]` link table into a [`Model`], in one of two forms:
//! the hand-written table of HRP-2's leg shape (`table.rs`: thigh and shank lengths, hip offset,
//! ankle height and ten bodies; closed-form inverse kinematics), or the general table that
//! `host-sim robot import` writes from a URDF (`tree.rs`: each leg's six joints in any order
//! and about any axes, full inertia tensors, the sole anywhere in the ankle's frame; numerical
//! inverse kinematics). A `[multibody]` with `left` and `right` link lists is the general form.
//!
//! Checks, each naming its key: each form's own (in its module); the control period the
//! simulator's scenarios and bus run at ([`TICK_S`], 5 ms); the stance reachable by the legs;
//! and the stance COG of
//! the link table (feet `step_width` apart, waist at `waist_height`) within
//! [`STANCE_TOLERANCE_M`] of the pendulum's `cog_height`, since the planner's COG is the
//! multi-body model's COG.

use std::fmt;
use std::path::Path;

use planner_core::node::NodeConfig;
use planner_core::robot::{Robot as PlannerRobot, RobotError};

pub mod frame;
pub mod import;
pub mod model;
mod table;
mod tree;

use crate::scenario::TICK_S;
use model::Model;
use table::invalid;

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
        let model = if table.contains_key("left") {
            let tree: tree::Tree = table
                .try_into()
                .map_err(|e: toml::de::Error| RobotError::Syntax(format!("in [multibody]: {e}")))?;
            tree.model(planner.params.gravity, planner.params.step_width)?
        } else {
            let links: table::Links = table
                .try_into()
                .map_err(|e: toml::de::Error| RobotError::Syntax(format!("in [multibody]: {e}")))?;
            links.model(planner.params.gravity)?
        };
        table::check_legs(&planner, &model)?;
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

    /// The proportions the built-in scenarios are drawn in for this robot.
    pub fn stance(&self) -> crate::scenario::Stance {
        crate::scenario::Stance::of(&self.planner.params, &self.planner.reach)
    }

    /// A built-in scenario drawn for this robot ([`crate::scenario::built_in_for`]).
    pub fn built_in(&self, name: &str) -> Option<crate::scenario::Scenario> {
        crate::scenario::built_in_for(name, &self.stance())
    }

    /// Whether this robot can walk HRP-2's footsteps (the built-in scenarios, the fault
    /// sweep's and the paper's grid are written for feet `step_width` = 0.2 m apart): an error
    /// naming `what` and the robot's width if its feet stand otherwise. (The built-in
    /// scenarios are drawn for every robot, [`Robot::built_in`]; the paper's grids are not.)
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
