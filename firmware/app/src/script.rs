//! The scripted controller's timeline: gait commands at given control ticks.
//!
//! The two scenarios are `host-sim`'s built-in `fig4` and `lateral`
//! (`host-sim/src/scenario.rs`), DUPLICATED here as data: host-sim builds them with `Vec` and
//! `String` (std), and this crate must stay `no_std`. The footstep coordinates are computed
//! with the same expressions in the same order, so they are the same `f64` values bit for bit
//! (and the same frames once quantised by `WireStep::from_si`); the QEMU image prints its
//! timeline (`CMD` lines, with the frames) and `tests/tests/qemu.rs` compares it with
//! host-sim's, so the copies cannot drift apart unnoticed. The [`Controller`](crate::Controller)
//! turns the timeline into CAN frames.

use heapless::Vec;
use planner_core::gait::{Footstep, Side};

/// Longest timeline of a scenario.
pub const MAX_COMMANDS: usize = 32;

/// One command of a scenario (host-sim's `Command`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// Append a footstep with this id.
    Push(u16, Footstep<f64>),
    /// Start walking.
    Start,
    /// Walk the queued steps, then stop.
    Stop,
    /// Drop the queued steps and stop.
    StopNow,
    /// Modify the queued step with this id.
    Modify(u16, Footstep<f64>),
}

impl Command {
    /// A short name (`push`, `start`, `stop`, `stop-now`, `modify`).
    pub fn name(&self) -> &'static str {
        match self {
            Command::Push(..) => "push",
            Command::Start => "start",
            Command::Stop => "stop",
            Command::StopNow => "stop-now",
            Command::Modify(..) => "modify",
        }
    }
}

/// A scenario: where the feet start, and commands at given ticks.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Name (host-sim's built-in name).
    pub name: &'static str,
    /// Left and right foot at the start.
    pub feet: [Footstep<f64>; 2],
    /// `(tick, command)`: applied, in order, once `tick` control periods have elapsed, before
    /// the next reference is computed.
    pub timeline: Vec<(u64, Command), MAX_COMMANDS>,
    /// Ticks to run at most (the run ends earlier once standing after the last command).
    pub max_ticks: u64,
}

impl Scenario {
    /// The built-in scenarios by name: `fig4` or `lateral`.
    pub fn by_name(name: &str) -> Option<Scenario> {
        match name {
            "fig4" => Some(fig4()),
            "lateral" => Some(lateral()),
            _ => None,
        }
    }
}

/// The names of the scenarios of this module.
pub const NAMES: [&str; 2] = ["fig4", "lateral"];

fn put<T, const N: usize>(v: &mut Vec<T, N>, item: T) {
    // The scenarios below are fixed data that fit: a failure here is a programming error.
    assert!(v.push(item).is_ok(), "scenario timeline capacity exceeded");
}

fn foot_y(side: Side, half_width: f64) -> f64 {
    match side {
        Side::Left => half_width,
        Side::Right => -half_width,
    }
}

/// Straight steps of `step` m from feet at x = 0, right foot first, `n` steps and a closing
/// step; ids from 0 (host-sim's `straight_steps`).
fn straight_steps(n: u16, step: f64) -> Vec<(u16, Footstep<f64>), MAX_COMMANDS> {
    let mut out = Vec::new();
    let mut side = Side::Right;
    for i in 0..n {
        put(
            &mut out,
            (
                i,
                Footstep::new(side, step * f64::from(i + 1), foot_y(side, 0.1), 0.0),
            ),
        );
        side = side.other();
    }
    put(
        &mut out,
        (
            n,
            Footstep::new(side, step * f64::from(n), foot_y(side, 0.1), 0.0),
        ),
    );
    out
}

fn standing_feet() -> [Footstep<f64>; 2] {
    [
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    ]
}

fn pushes(steps: &[(u16, Footstep<f64>)]) -> Vec<(u64, Command), MAX_COMMANDS> {
    let mut out = Vec::new();
    for &(i, f) in steps {
        put(&mut out, (0, Command::Push(i, f)));
    }
    out
}

/// The paper's Fig. 4: 0.1 m steps; at the single support that begins at 4.0 s the landing
/// moves from 0.4 m to 0.6 m, the later steps keep their 0.1 m length.
pub fn fig4() -> Scenario {
    let steps = straight_steps(11, 0.1);
    let mut timeline = pushes(&steps);
    put(&mut timeline, (160, Command::Start));
    for &(i, f) in steps.iter().skip(3).rev() {
        let moved = Footstep::new(f.side, f.x + 0.2, f.y, f.yaw);
        put(&mut timeline, (799, Command::Modify(i, moved)));
    }
    put(&mut timeline, (800, Command::Stop));
    Scenario {
        name: "fig4",
        feet: standing_feet(),
        timeline,
        max_ticks: 4000,
    }
}

/// Section V of the paper: 0.2 m steps, step cycle 0.8 s; the next landing is moved 0.05 m
/// inwards at 4.0 s, and the one after next 0.05 m outwards at 5.0 s.
pub fn lateral() -> Scenario {
    let steps = straight_steps(12, 0.2);
    let mut timeline = pushes(&steps);
    put(&mut timeline, (160, Command::Start));
    let (_, s3) = steps[3];
    put(
        &mut timeline,
        (
            799,
            Command::Modify(3, Footstep::new(s3.side, s3.x, s3.y - 0.05, 0.0)),
        ),
    );
    let (_, s5) = steps[5];
    put(
        &mut timeline,
        (
            1000,
            Command::Modify(5, Footstep::new(s5.side, s5.x, s5.y + 0.05, 0.0)),
        ),
    );
    put(&mut timeline, (1200, Command::Stop));
    Scenario {
        name: "lateral",
        feet: standing_feet(),
        timeline,
        max_ticks: 4000,
    }
}
