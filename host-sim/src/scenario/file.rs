//! Scenarios as TOML files.
//!
//! ```toml
//! name = "my-walk"                 # required, non-empty
//! about = "one line"               # optional (default: empty)
//! max_time_s = 20.0                # optional (default: 20 s): run at most this long
//!
//! [feet]                           # optional (default: the robot's stance, the feet
//!                                  # `step_width` apart at the origin: HRP-2 (0, ±0.1))
//! left = { x = 0.0, y = 0.1, yaw = 0.0 }
//! right = { x = 0.0, y = -0.1 }    # yaw is optional everywhere (default 0)
//!
//! [[step]]                         # append footstep `id` to the queue
//! id = 0                           # 0 … 255 (the bus's one-byte step id), unique among
//!                                  # the [[step]] entries
//! side = "right"                   # "left" | "right"
//! x = 0.2                          # sole centre [m]
//! y = -0.1                         # sole centre [m]
//! yaw = 0.0                        # heading [rad] (default 0)
//! at_s = 0.0                       # when [s] (default 0)
//! expect = "reach"                 # optional, on any entry: see "Expected failures"
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
//!
//! [[velocity]]                     # walk at a velocity: the node chooses the footsteps
//! at_s = 0.5                       # when [s] (required)
//! vx = 0.15                        # forward [m/s] (default 0), in the support foot's frame
//! vy = 0.0                         # to the left [m/s] (default 0)
//! wz = 0.0                         # turn, counter-clockwise [rad/s] (default 0)
//!                                  # all 0: stop and stand
//!
//! [[goal]]                         # walk to a pose, then stand
//! at_s = 0.5                       # when [s] (required)
//! x = 1.0                          # forward [m], relative to the midpoint of the feet
//! y = 0.2                          # to the left [m] (default 0)
//! yaw = 0.5                        # heading change [rad] (default 0)
//! ```
//!
//! A run through the bus (`host-sim run`) streams the last `[[velocity]]` every 50 ms, as a
//! stick does, until the next `[[velocity]]` or `[[goal]]`: the node stops a robot whose
//! velocity stream falls silent. While the node chooses the footsteps, the file's
//! `[[step]]` and `[[modify]]` entries are refused (`wrong_state`).
//!
//! Times are converted to control ticks of [`TICK_S`] (5 ms), rounded to the nearest tick.
//! The timeline is ordered by tick; commands that fall on the same tick are applied in this
//! order: the `[[step]]` entries, then the `[[modify]]` entries, then the `[[command]]`
//! entries, each kind in file order. (So pushing steps and starting at the same instant works,
//! and several modifications at one tick keep the order written, which matters for the
//! feasibility check of each.)
//!
//! ## Expected failures
//!
//! `host-sim run` reports every command that failed, with its time, step id and reason, and
//! exits with status 1 when one failed that its entry did not expect. An entry expects a
//! failure with `expect = "NAME"`, and then that failure must happen (a command that succeeds
//! against its expectation is reported too). The names:
//!
//! * a refusal: the node's reason, as in the DBC's `VAL_ 128 reason` table
//!   (`host-sim/can/walking.dbc`): `unknown_id`, `bad_length`, `out_of_range`, `queue_full`,
//!   `side_order`, `unknown_step`, `lifted_off`, `infeasible`, `wrong_state`,
//!   `sequence_gap` (ids must count from 0), `duplicate`, `reach` (alias `out_of_reach`),
//!   `crossing`, `emergency_stopped`, `plan_failed`, `bad_crc`, `stale`, `controller_lost`;
//! * `no_answer`: the node never answered the command;
//! * `not_walked` (`[[step]]` and `[[modify]]` only): the node accepted the footstep but never
//!   walked it at that pose: the run ended with it queued (no `start`, or `max_time_s` cut the
//!   walk) or being swung, it left the queue without a `stop_now` of the scenario, or it
//!   landed elsewhere. Every accepted entry about that step fails so (its `[[step]]` and its
//!   accepted `[[modify]]` entries). Steps that the scenario's own accepted `stop_now` drops
//!   are carried out: that is what it asked for.
//!
//! Rejected, with a message naming the entry (and its line): TOML syntax errors, unknown keys, missing
//! required keys, wrong types, unknown sides or command kinds, negative, non-finite or huge
//! times, non-finite coordinates, step ids outside 0 … 65,534 (the node's step numbers:
//! [`WireId`]), duplicate step ids, a `[[modify]]` of an id that no `[[step]]`
//! defines and without a `side`, unknown `expect` names and `not_walked` on a `[[command]]`,
//! an empty name and a non-positive `max_time_s`. ([`load_file`] also refuses an entry that
//! cannot be put on the bus, e.g. a modification more than 4.096 m from its append.)
//! Whether a command makes sense for the gait (alternating feet, reachable steps, …) is left to
//! the gait: it answers every command when the scenario runs.

use std::collections::HashMap;
use std::path::Path;

use planner_core::gait::{Footstep, Side};
use serde::Deserialize;
use toml::Spanned;

use super::expect::Failure;
use super::wire::{WireId, MAX_WIRE_ID};
use super::{Command, Scenario, TICK_S};

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
    step: Vec<Spanned<StepEntry>>,
    #[serde(default)]
    command: Vec<Spanned<CommandEntry>>,
    #[serde(default)]
    modify: Vec<Spanned<ModifyEntry>>,
    #[serde(default)]
    velocity: Vec<Spanned<VelocityEntry>>,
    #[serde(default)]
    goal: Vec<Spanned<GoalEntry>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VelocityEntry {
    at_s: f64,
    #[serde(default)]
    vx: f64,
    #[serde(default)]
    vy: f64,
    #[serde(default)]
    wz: f64,
    expect: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GoalEntry {
    at_s: f64,
    x: f64,
    #[serde(default)]
    y: f64,
    #[serde(default)]
    yaw: f64,
    expect: Option<String>,
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
    id: i64,
    side: SideName,
    x: f64,
    y: f64,
    #[serde(default)]
    yaw: f64,
    at_s: Option<f64>,
    expect: Option<String>,
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
    expect: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModifyEntry {
    at_s: f64,
    id: i64,
    side: Option<SideName>,
    x: f64,
    y: f64,
    #[serde(default)]
    yaw: f64,
    expect: Option<String>,
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

/// The line (from 1) of byte `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    1 + text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// A step id as the bus carries it ([`WireId`]: the node's step numbers).
fn step_id(what: &str, id: i64) -> Result<u16, String> {
    WireId::try_from(id)
        .ok()
        .filter(|&i| i <= MAX_WIRE_ID)
        .ok_or_else(|| {
            format!(
                "{what}: step id {id} does not fit the bus (the node numbers a start-up's \
                 steps 0 … {MAX_WIRE_ID})"
            )
        })
}

/// The `expect` key of an entry.
fn expectation(what: &str, name: Option<&str>, footstep: bool) -> Result<Option<Failure>, String> {
    let Some(name) = name else { return Ok(None) };
    let f = Failure::from_name(name).ok_or_else(|| {
        format!(
            "{what}: unknown expect = {name:?}; one of: {} (or out_of_reach for reach)",
            Failure::all()
                .map(Failure::name)
                .collect::<Vec<_>>()
                .join(", ")
        )
    })?;
    if f == Failure::NotWalked && !footstep {
        return Err(format!(
            "{what}: expect = \"not_walked\" is for [[step]] and [[modify]] entries"
        ));
    }
    Ok(Some(f))
}

/// One entry of a scenario file, as [`ScenarioFile::entries`] lists them.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The entry named as in error messages: `[[step]] #3 (id 2) at line 14`.
    pub label: String,
    /// The failure it expects (`expect`), if any.
    pub expect: Option<Failure>,
}

/// A scenario file: the scenario, and the entry behind each command of its timeline.
#[derive(Clone, Debug)]
pub struct ScenarioFile {
    /// The scenario.
    pub scenario: Scenario,
    /// `entries[i]` is the file's entry for `scenario.timeline[i]`.
    pub entries: Vec<Entry>,
}

/// Parses a scenario from TOML text (format in the module documentation).
pub fn parse(text: &str) -> Result<Scenario, String> {
    parse_file(text).map(|f| f.scenario)
}

/// Parses a scenario from TOML text, with the entry behind each command.
pub fn parse_file(text: &str) -> Result<ScenarioFile, String> {
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
        Some(f) => Some([
            footstep("feet.left", Side::Left, f.left.x, f.left.y, f.left.yaw)?,
            footstep("feet.right", Side::Right, f.right.x, f.right.y, f.right.yaw)?,
        ]),
        None => None,
    };

    // (tick, class, command, entry): class orders the kinds of entries within a tick.
    let mut timeline: Vec<(u64, u8, Command, Entry)> = Vec::new();
    let mut sides: HashMap<u16, (usize, Side)> = HashMap::new();
    for (i, spanned) in file.step.iter().enumerate() {
        let s = spanned.get_ref();
        let line = line_of(text, spanned.span().start);
        let what = format!("[[step]] #{} (id {}) at line {line}", i + 1, s.id);
        let id = step_id(&what, s.id)?;
        if let Some((first, _)) = sides.get(&id) {
            return Err(format!(
                "{what}: duplicate step id {id} (already used by [[step]] #{})",
                first + 1
            ));
        }
        let tick = ticks(&format!("{what}: at_s"), s.at_s.unwrap_or(0.0))?;
        let f = footstep(&what, s.side.into(), s.x, s.y, s.yaw)?;
        let expect = expectation(&what, s.expect.as_deref(), true)?;
        sides.insert(id, (i, f.side));
        let entry = Entry {
            label: what,
            expect,
        };
        timeline.push((tick, 0, Command::Push(id, f), entry));
    }
    for (i, spanned) in file.modify.iter().enumerate() {
        let m = spanned.get_ref();
        let line = line_of(text, spanned.span().start);
        let what = format!("[[modify]] #{} (id {}) at line {line}", i + 1, m.id);
        let id = step_id(&what, m.id)?;
        let side = match (m.side, sides.get(&id)) {
            (Some(s), _) => s.into(),
            (None, Some(&(_, s))) => s,
            (None, None) => {
                return Err(format!(
                    "{what}: no [[step]] has id {id}: give `side` to modify a step that this \
                     file does not define"
                ))
            }
        };
        let tick = ticks(&format!("{what}: at_s"), m.at_s)?;
        let f = footstep(&what, side, m.x, m.y, m.yaw)?;
        let expect = expectation(&what, m.expect.as_deref(), true)?;
        let entry = Entry {
            label: what,
            expect,
        };
        timeline.push((tick, 1, Command::Modify(id, f), entry));
    }
    for (i, spanned) in file.command.iter().enumerate() {
        let c = spanned.get_ref();
        let line = line_of(text, spanned.span().start);
        let what = format!("[[command]] #{} at line {line}", i + 1);
        let tick = ticks(&format!("{what}: at_s"), c.at_s)?;
        let command = match c.kind {
            Kind::Start => Command::Start,
            Kind::Stop => Command::Stop,
            Kind::StopNow => Command::StopNow,
        };
        let expect = expectation(&what, c.expect.as_deref(), false)?;
        let entry = Entry {
            label: what,
            expect,
        };
        timeline.push((tick, 2, command, entry));
    }
    let drives = file
        .velocity
        .iter()
        .map(|v| {
            let e = v.get_ref();
            (
                v.span().start,
                "velocity",
                e.at_s,
                [e.vx, e.vy, e.wz],
                e.expect.as_deref(),
            )
        })
        .chain(file.goal.iter().map(|g| {
            let e = g.get_ref();
            (
                g.span().start,
                "goal",
                e.at_s,
                [e.x, e.y, e.yaw],
                e.expect.as_deref(),
            )
        }));
    let mut counts = [0usize; 2];
    for (start, kind, at_s, v, expect) in drives {
        let n = &mut counts[usize::from(kind == "goal")];
        *n += 1;
        let line = line_of(text, start);
        let what = format!("[[{kind}]] #{n} at line {line}");
        let tick = ticks(&format!("{what}: at_s"), at_s)?;
        for x in v {
            if !x.is_finite() {
                return Err(format!("{what}: values must be finite, got {x}"));
            }
        }
        let command = if kind == "goal" {
            Command::Goal(v[0], v[1], v[2])
        } else {
            Command::Velocity(v[0], v[1], v[2])
        };
        let expect = expectation(&what, expect, false)?;
        let entry = Entry {
            label: what,
            expect,
        };
        timeline.push((tick, 2, command, entry));
    }
    // Stable: file order is kept within a tick and a class.
    timeline.sort_by_key(|&(tick, class, _, _)| (tick, class));
    let mut entries = Vec::with_capacity(timeline.len());
    let timeline = timeline
        .into_iter()
        .map(|(t, _, c, e)| {
            entries.push(e);
            (t, c)
        })
        .collect();
    Ok(ScenarioFile {
        scenario: Scenario {
            name: file.name,
            about: file.about,
            feet,
            timeline,
            max_ticks,
        },
        entries,
    })
}

/// Reads and parses a scenario file; errors name the file.
pub fn load(path: &Path) -> Result<Scenario, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads and parses a scenario file, with the entry behind each command, and checks that
/// every command can be put on the bus ([`super::wire::wire_check`]); errors name the file
/// and the entry.
pub fn load_file(path: &Path) -> Result<ScenarioFile, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let file = parse_file(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    super::wire::wire_check(&file.scenario)
        .map_err(|(i, e)| format!("{}: {}: {e}", path.display(), file.entries[i].label))?;
    Ok(file)
}
