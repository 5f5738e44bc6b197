//! Scenarios as TOML files.
//!
//! ```toml
//! name = "my-walk"                 # required, non-empty
//! about = "one line"               # optional (default: empty)
//! max_time_s = 20.0                # optional (default: 20 s): run at most this long
//!
//! [feet]                           # optional (default: left at (0, 0.1), right at (0, -0.1))
//! left = { x = 0.0, y = 0.1, yaw = 0.0 }
//! right = { x = 0.0, y = -0.1 }    # yaw is optional everywhere (default 0)
//!
//! [[step]]                         # append footstep `id` to the queue
//! id = 0                           # 0 … 65535, unique among the [[step]] entries
//! side = "right"                   # "left" | "right"
//! x = 0.2                          # sole centre [m]
//! y = -0.1                         # sole centre [m]
//! yaw = 0.0                        # heading [rad] (default 0)
//! at_s = 0.0                       # when [s] (default 0)
//!
//! [[command]]
//! at_s = 0.1                       # when [s] (required)
//! kind = "start"                   # "start" | "stop" (walk the queue, then stop)
//!                                  # | "stop_now" (drop the queue and stop)
//!
//! [[modify]]                       # move the queued footstep `id`
//! at_s = 3.995                     # when [s] (required)
//! id = 3
//! x = 0.6                          # new sole centre [m] (required)
//! y = 0.1                          # (required)
//! yaw = 0.0                        # (default 0)
//! side = "left"                    # optional: defaults to the side of [[step]] `id`; required
//!                                  # when the file has no such step
//! ```
//!
//! Times are converted to control ticks of [`TICK_S`] (5 ms), rounded to the nearest tick.
//! The timeline is ordered by tick; commands that fall on the same tick are applied in this
//! order: the `[[step]]` entries, then the `[[modify]]` entries, then the `[[command]]`
//! entries, each kind in file order. (So pushing steps and starting at the same instant works,
//! and several modifications at one tick keep the order written, which matters for the
//! feasibility check of each.)
//!
//! Rejected, with a message naming the entry: TOML syntax errors, unknown keys, missing
//! required keys, wrong types, unknown sides or command kinds, negative, non-finite or huge
//! times, non-finite coordinates, duplicate step ids, a `[[modify]]` of an id that no
//! `[[step]]` defines and without a `side`, an empty name and a non-positive `max_time_s`.
//! Whether a command makes sense for the gait (alternating feet, reachable steps, …) is left to
//! the gait: it answers every command when the scenario runs.

use std::collections::HashMap;
use std::path::Path;

use planner_core::gait::{Footstep, Side};
use serde::Deserialize;

use crate::scenario::{Command, Scenario};

/// The scenario tick \[s\] (the HRP-2 control period).
pub const TICK_S: f64 = 0.005;

/// `max_time_s` when the file does not give it \[s\].
pub const DEFAULT_MAX_TIME_S: f64 = 20.0;

/// Largest accepted time \[s\] (about 11.6 days: far beyond any walk, and exact in ticks).
pub const MAX_TIME_S: f64 = 1.0e6;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    name: String,
    #[serde(default)]
    about: String,
    max_time_s: Option<f64>,
    feet: Option<Feet>,
    #[serde(default)]
    step: Vec<StepEntry>,
    #[serde(default)]
    command: Vec<CommandEntry>,
    #[serde(default)]
    modify: Vec<ModifyEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Pose {
    x: f64,
    y: f64,
    #[serde(default)]
    yaw: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Feet {
    left: Pose,
    right: Pose,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum SideName {
    Left,
    Right,
}

impl From<SideName> for Side {
    fn from(s: SideName) -> Side {
        match s {
            SideName::Left => Side::Left,
            SideName::Right => Side::Right,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepEntry {
    id: u16,
    side: SideName,
    x: f64,
    y: f64,
    #[serde(default)]
    yaw: f64,
    at_s: Option<f64>,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Kind {
    Start,
    Stop,
    StopNow,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandEntry {
    at_s: f64,
    kind: Kind,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModifyEntry {
    at_s: f64,
    id: u16,
    side: Option<SideName>,
    x: f64,
    y: f64,
    #[serde(default)]
    yaw: f64,
}

/// A time in seconds as a tick count (rounded to the nearest tick).
fn ticks(what: &str, seconds: f64) -> Result<u64, String> {
    if !seconds.is_finite() {
        return Err(format!("{what}: time must be finite, got {seconds}"));
    }
    if seconds < 0.0 {
        return Err(format!(
            "{what}: time must not be negative, got {seconds} s"
        ));
    }
    if seconds > MAX_TIME_S {
        return Err(format!(
            "{what}: time {seconds} s is too large (at most {MAX_TIME_S} s)"
        ));
    }
    Ok((seconds / TICK_S).round() as u64)
}

fn footstep(what: &str, side: Side, x: f64, y: f64, yaw: f64) -> Result<Footstep<f64>, String> {
    for (key, v) in [("x", x), ("y", y), ("yaw", yaw)] {
        if !v.is_finite() {
            return Err(format!("{what}: {key} must be finite, got {v}"));
        }
    }
    Ok(Footstep::new(side, x, y, yaw))
}

/// Parses a scenario from TOML text (format in the module documentation).
pub fn parse(text: &str) -> Result<Scenario, String> {
    let file: File = toml::from_str(text).map_err(|e| format!("invalid scenario TOML: {e}"))?;
    if file.name.trim().is_empty() {
        return Err("`name` must not be empty".into());
    }
    let max_time_s = file.max_time_s.unwrap_or(DEFAULT_MAX_TIME_S);
    let max_ticks = ticks("max_time_s", max_time_s)?;
    if max_ticks == 0 {
        return Err(format!(
            "max_time_s: must be at least one tick ({TICK_S} s), got {max_time_s} s"
        ));
    }
    let feet = match &file.feet {
        Some(f) => [
            footstep("feet.left", Side::Left, f.left.x, f.left.y, f.left.yaw)?,
            footstep("feet.right", Side::Right, f.right.x, f.right.y, f.right.yaw)?,
        ],
        None => [
            Footstep::new(Side::Left, 0.0, 0.1, 0.0),
            Footstep::new(Side::Right, 0.0, -0.1, 0.0),
        ],
    };

    // (tick, class, command): class orders the kinds of entries within a tick.
    let mut timeline: Vec<(u64, u8, Command)> = Vec::new();
    let mut sides: HashMap<u16, (usize, Side)> = HashMap::new();
    for (i, s) in file.step.iter().enumerate() {
        let what = format!("[[step]] #{} (id {})", i + 1, s.id);
        if let Some((first, _)) = sides.get(&s.id) {
            return Err(format!(
                "{what}: duplicate step id {} (already used by [[step]] #{})",
                s.id,
                first + 1
            ));
        }
        let tick = ticks(&format!("{what}: at_s"), s.at_s.unwrap_or(0.0))?;
        let f = footstep(&what, s.side.into(), s.x, s.y, s.yaw)?;
        sides.insert(s.id, (i, f.side));
        timeline.push((tick, 0, Command::Push(s.id, f)));
    }
    for (i, m) in file.modify.iter().enumerate() {
        let what = format!("[[modify]] #{} (id {})", i + 1, m.id);
        let side = match (m.side, sides.get(&m.id)) {
            (Some(s), _) => s.into(),
            (None, Some(&(_, s))) => s,
            (None, None) => {
                return Err(format!(
                    "{what}: no [[step]] has id {}: give `side` to modify a step that this \
                     file does not define",
                    m.id
                ))
            }
        };
        let tick = ticks(&format!("{what}: at_s"), m.at_s)?;
        let f = footstep(&what, side, m.x, m.y, m.yaw)?;
        timeline.push((tick, 1, Command::Modify(m.id, f)));
    }
    for (i, c) in file.command.iter().enumerate() {
        let tick = ticks(&format!("[[command]] #{}: at_s", i + 1), c.at_s)?;
        let command = match c.kind {
            Kind::Start => Command::Start,
            Kind::Stop => Command::Stop,
            Kind::StopNow => Command::StopNow,
        };
        timeline.push((tick, 2, command));
    }
    // Stable: file order is kept within a tick and a class.
    timeline.sort_by_key(|&(tick, class, _)| (tick, class));
    Ok(Scenario {
        name: file.name,
        about: file.about,
        feet,
        timeline: timeline.into_iter().map(|(t, _, c)| (t, c)).collect(),
        max_ticks,
    })
}

/// Reads and parses a scenario file; errors name the file.
pub fn load(path: &Path) -> Result<Scenario, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}
