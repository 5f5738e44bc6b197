//! What can become of a command, by the names a scenario file's `expect` key takes: refused
//! by the node with a reason (the DBC's `VAL_ 128 reason` names, `reach`, `sequence_gap`, …),
//! never answered (`no_answer`), or accepted and never carried out (`not_walked`).

use planner_core::node::{Broken, Limit};
use planner_core::wire::Reason;

/// A way a command can fail: the names a scenario file's `expect` key takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The node refused it: `ACK` with this reason (name: the reason's, as in the DBC's
    /// `VAL_ 128 reason` table, e.g. `reach`).
    Refused(Reason),
    /// No answer came (`no_answer`).
    NoAnswer,
    /// Accepted, never carried out: a footstep not walked at its accepted pose
    /// (`not_walked`).
    NotWalked,
}

/// The name of a refusal reason: the snake case of the variant, as in the DBC's value table
/// (`Reason::SequenceGap` is `sequence_gap`).
pub fn reason_name(r: Reason) -> String {
    let mut out = String::new();
    for (i, c) in format!("{r:?}").chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

impl Failure {
    /// Every failure, in the order of their names' documentation.
    pub fn all() -> impl Iterator<Item = Failure> {
        Reason::ALL
            .into_iter()
            .map(Failure::Refused)
            .chain([Failure::NoAnswer, Failure::NotWalked])
    }

    /// The name (`reach`, `sequence_gap`, …, `no_answer`, `not_walked`).
    pub fn name(self) -> String {
        match self {
            Failure::Refused(r) => reason_name(r),
            Failure::NoAnswer => "no_answer".into(),
            Failure::NotWalked => "not_walked".into(),
        }
    }

    /// From a name ([`Failure::name`]; `out_of_reach` is also `reach`).
    pub fn from_name(name: &str) -> Option<Failure> {
        if name == "out_of_reach" {
            return Some(Failure::Refused(Reason::Reach));
        }
        Failure::all().find(|f| f.name() == name)
    }
}

/// The reach limit a footstep broke, in words with the measured value and the robot file's
/// bound (`[reach]` key): for example "forward step 0.452 m > max_forward 0.400 m".
pub fn limit_text(b: &Broken<f64>) -> String {
    let (what, unit, below) = match b.limit {
        Limit::Crossing => {
            return if b.value < 0.0 {
                format!(
                    "the landing sole crosses the support foot's midline (width {:.3} m < 0)",
                    b.value
                )
            } else {
                format!(
                    "the landing sole comes nearer to the support sole than sole_gap {:.3} m",
                    b.bound
                )
            };
        }
        Limit::Forward => ("forward step", "m", false),
        Limit::Backward => ("backward step", "m", false),
        Limit::MinWidth => ("width between the feet", "m", true),
        Limit::MaxWidth => ("width between the feet", "m", false),
        Limit::Yaw => ("heading change", "rad", false),
        Limit::FeetDistance => ("distance between the sole centres", "m", false),
        Limit::TurnCost => ("forward step + yaw_cost × heading change", "m", false),
        Limit::Stride => ("travel of the swinging foot", "m", false),
        Limit::Growth => ("growth over the step before", "m", false),
    };
    format!(
        "{what} {:.3} {unit} {} {} {:.3} {unit}",
        b.value,
        if below { "<" } else { ">" },
        b.limit.key(),
        b.bound
    )
}
