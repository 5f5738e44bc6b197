//! Whether an engine command can start the walk: the robot must stand on its soles through
//! the settle before the walk ([`super::PhysicsConfig::settle_s`]). A `physics` run whose
//! robot falls there has walked nothing, and the command exits non-zero naming the fall (its
//! files are written all the same); the commands that run many walks (`physics-tables`,
//! `physics-faults`, `physics-sequence`, `push-map`) first stand a robot file's robot through
//! the settle and stop before the first walk if it falls.

use serde_json::Value;

use super::{run, PhysicsConfig, PhysicsReport};
use crate::robot::Robot;

/// Why a `physics` run, as its `physics.json` reports it, did not start the walk (`None`:
/// it did).
pub fn not_started(j: &Value) -> Option<String> {
    let t = j["fall_time_s"].as_f64()?;
    (j["fell"].as_bool() == Some(true) && t < 0.0).then(|| {
        format!(
            "{} cannot start the walk: it fell {:.3} s before the walk, during the engine's \
             settle ({}), and walked 0 s; is its robot file right (its soles, its standing \
             height)?",
            j["robot"].as_str().unwrap_or("the robot"),
            -t,
            j["fall_cause"].as_str().unwrap_or("?")
        )
    })
}

/// Why `report` is a fall before the walk or while standing, `None` if it stood.
fn fell(report: &PhysicsReport) -> Option<(f64, &'static str)> {
    if report.fell {
        Some((
            report.fall_time_s.unwrap_or(f64::NAN),
            report.fall_cause.map_or("?", |c| c.name()),
        ))
    } else if report.fell_after_end {
        Some((
            report.fall_after_end_time_s.unwrap_or(f64::NAN),
            report.fall_after_end_cause.map_or("?", |c| c.name()),
        ))
    } else {
        None
    }
}

/// Stands `robot` in MuJoCo, as [`PhysicsConfig::for_robot`] runs it, through the settle and
/// the tail on the first reference of `straight` (no step): an error naming the fall if it
/// does not stand.
pub fn stands(robot: &Robot) -> Result<(), String> {
    let (_, trajectory, dt) = crate::sim::scenario_trajectory("straight", robot)?;
    let cfg = PhysicsConfig::for_robot(robot);
    let r = run(&trajectory[..1], dt, &cfg).map_err(|e| format!("standing in MuJoCo: {e}"))?;
    match fell(&r.report) {
        None => Ok(()),
        Some((t, cause)) => Err(format!(
            "{} cannot start the walk: standing on its soles in MuJoCo before any step, it \
             fell at {t:.3} s ({cause}; the settle starts at {:.3} s); is its robot file right \
             (its soles, its standing height)?",
            robot.name(),
            -cfg.settle_s
        )),
    }
}
