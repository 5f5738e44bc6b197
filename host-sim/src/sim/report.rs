//! The report of a run: what became of each command of a scenario, in words, as `host-sim
//! run` prints it and writes it into `summary.json` (`refused_commands`).
//!
//! A command that failed (refused by the node, never answered, accepted and never carried out)
//! or did not go as the scenario's entry expected is a line; a refusal that follows from the
//! refused append of an earlier step (later appends refused `sequence_gap`, modifications
//! refused `unknown_step`, a `start` refused `wrong_state` with no step taken) is marked so and counts as expected; notes on commands carried out
//! (steps dropped by the scenario's `stop_now`) are grouped by note.

use planner_core::gait::Side;
use planner_core::wire::Reason;
use serde_json::{json, Value};

use super::Outcome;
use crate::scenario::file::Entry;
use crate::scenario::{Command, Failure};

/// The report of a run's commands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// One printed line per command that failed or did not go as expected, in order.
    pub lines: Vec<String>,
    /// Notes on commands carried out, by note: the note and the steps (or commands) it is on.
    pub notes: Vec<(String, Vec<String>)>,
    /// How many commands did not go as the scenario expected.
    pub unexpected: usize,
    /// The commands of [`Report::lines`] as `summary.json`'s `refused_commands` entries.
    pub failed: Vec<Value>,
}

/// The report of `results`, the outcomes of a scenario's commands, against `entries`, the
/// scenario's entry behind each (its label and `expect`); ticks of `dt` seconds.
pub fn report(results: &[Outcome], entries: &[Entry], dt: f64) -> Report {
    let mut lines = Vec::new();
    // Notes on commands carried out (steps dropped by the scenario's stop_now), by note.
    let mut notes: Vec<(String, Vec<String>)> = Vec::new();
    let mut unexpected = 0;
    let mut failed = Vec::new();
    // The first append the node refused: later appends refused `sequence_gap` and
    // modifications of its step or later ones refused `unknown_step` follow from it.
    let mut first_refused: Option<u64> = None;
    // Appends the node took: a `start` refused `wrong_state` before any follows from the
    // refused first append (the queue it would walk is empty).
    let mut taken = 0;
    for (o, entry) in results.iter().zip(entries) {
        let follows = consequence_of(o, first_refused, taken).filter(|_| entry.expect.is_none());
        if let (Command::Push(..), None | Some(Failure::NotWalked)) = (o.command, o.failure) {
            taken += 1;
        }
        if let (Command::Push(id, _), Some(Failure::Refused(_)), None) =
            (o.command, o.failure, first_refused)
        {
            first_refused = Some(u64::from(id));
        }
        let (expected, line) = outcome_line(o, entry, follows, dt);
        unexpected += usize::from(!expected);
        if o.failure.is_some() || !expected {
            lines.push(line);
        } else if !o.detail.is_empty() {
            let what = match o.command {
                Command::Push(id, _) | Command::Modify(id, _) => id.to_string(),
                c => describe(&c),
            };
            match notes.iter_mut().find(|(d, _)| *d == o.detail) {
                Some((_, ids)) => ids.push(what),
                None => notes.push((o.detail.clone(), vec![what])),
            }
        }
        if o.failure.is_some() || !expected {
            let step_id = match o.command {
                Command::Push(id, _) | Command::Modify(id, _) => Some(id),
                _ => None,
            };
            failed.push(json!({
                "t_s": o.tick as f64 * dt,
                "command": describe(&o.command),
                "step_id": step_id,
                "failure": o.failure.map(|f| f.name()),
                "error": o.detail,
                "expected": entry.expect.map(|f| f.name()),
                "as_expected": expected,
                "follows_from_step": follows,
                "entry": entry.label,
            }));
        }
    }
    Report {
        lines,
        notes,
        unexpected,
        failed,
    }
}

/// A command in words: `step 3 (append, left at (0.4000, 0.1000) m)`, `start`.
pub fn describe(c: &Command) -> String {
    let side = |s: Side| if s == Side::Left { "left" } else { "right" };
    match c {
        Command::Push(id, f) => format!(
            "step {id} (append, {} at ({:.4}, {:.4}) m, {:.4} rad)",
            side(f.side),
            f.x,
            f.y,
            f.yaw
        ),
        Command::Modify(id, f) => format!(
            "step {id} (modify, {} to ({:.4}, {:.4}) m, {:.4} rad)",
            side(f.side),
            f.x,
            f.y,
            f.yaw
        ),
        Command::Start => "start".into(),
        Command::Stop => "stop".into(),
        Command::StopNow => "stop_now".into(),
        Command::Velocity(vx, vy, wz) => {
            format!("velocity ({vx:.3} m/s, {vy:.3} m/s, {wz:.3} rad/s)")
        }
        Command::Goal(x, y, yaw) => format!("goal ({x:.3} m, {y:.3} m, {yaw:.3} rad)"),
    }
}

/// One outcome as printed: whether it was as the scenario expected (a refusal that `follows`
/// from the refused append of that step counts as expected), and the line.
fn outcome_line(o: &Outcome, entry: &Entry, follows: Option<u64>, dt: f64) -> (bool, String) {
    let expected = o.failure == entry.expect || follows.is_some();
    let what = match (o.failure, entry.expect) {
        _ if follows.is_some() => format!(
            "{} (follows from the refusal of step {})",
            o.detail,
            follows.map_or(String::new(), |k| k.to_string())
        ),
        (Some(f), _) if expected => format!("{} (expected {})", o.detail, f.name()),
        (Some(_), None) => o.detail.clone(),
        (Some(_), Some(x)) => format!("{} (but expected {})", o.detail, x.name()),
        (None, Some(x)) if o.detail.is_empty() => {
            format!("carried out, but expected {}", x.name())
        }
        (None, Some(x)) => format!("{}, but expected {}", o.detail, x.name()),
        (None, None) => o.detail.clone(),
    };
    let mark = if expected { "" } else { "UNEXPECTED " };
    (
        expected,
        format!(
            "  {mark}{:.3} s, {}: {}: {what}",
            o.tick as f64 * dt,
            entry.label,
            describe(&o.command),
        ),
    )
}

/// The step whose refused append `o` follows from, if it does: an append refused
/// `sequence_gap` after it, a modification of it or a later step refused `unknown_step`, or a
/// `start` refused `wrong_state` while no append was taken (`taken`: appends taken before).
fn consequence_of(o: &Outcome, first_refused: Option<u64>, taken: usize) -> Option<u64> {
    let k = first_refused?;
    match (o.command, o.failure) {
        (Command::Start, Some(Failure::Refused(Reason::WrongState))) if taken == 0 => Some(k),
        (Command::Push(id, _), Some(Failure::Refused(Reason::SequenceGap)))
            if u64::from(id) > k =>
        {
            Some(k)
        }
        (Command::Modify(id, _), Some(Failure::Refused(Reason::UnknownStep)))
            if u64::from(id) >= k =>
        {
            Some(k)
        }
        _ => None,
    }
}
