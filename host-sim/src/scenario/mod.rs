//! Scenarios: a timeline of footstep commands played against the gait, one tick per 5 ms of
//! simulated time, and the built-in HRP-2 scenarios.
//!
//! [`run`] drives the gait API directly (the API the node calls), without the bus;
//! [`crate::sim`] plays a scenario through the virtual CAN link and the node.
//!
//! # Rooms
//! `built_in.rs` draws the built-in scenarios in a robot's proportions ([`Stance`]);
//! [`file`](mod@file) reads scenario files (TOML); [`expect`] names what may become of a command (a
//! file's `expect` key); [`wire`] encodes a scenario's commands as the controller sends them.

mod built_in;
pub mod expect;
pub mod file;
pub mod wire;

pub use built_in::{built_in, built_in_for, Stance, BUILT_IN, DRIVEN};

pub use expect::Failure;
pub use wire::{wire_check, WireId, MAX_WIRE_ID};

/// The scenario tick \[s\] (the HRP-2 control period): scenario times are counted in it.
pub const TICK_S: f64 = 0.005;

use planner_core::gait::{Footstep, Gait, GaitError, GaitParams, Reference, Side};

/// One command of a scenario.
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
    /// Walk at (vx, vy, ω) \[m/s, m/s, rad/s\] in the support foot's frame: the node chooses
    /// the footsteps (`VELOCITY`; a run through the bus streams it every 50 ms until the next
    /// velocity or goal).
    Velocity(f64, f64, f64),
    /// Walk to (x, y, θ) \[m, m, rad\] relative to the midpoint of the feet and their mean
    /// heading, then stand (`GOAL`).
    Goal(f64, f64, f64),
}

impl Command {
    /// `true` for a command with which the node chooses the footsteps (a velocity, a goal).
    pub fn drives(&self) -> bool {
        matches!(self, Command::Velocity(..) | Command::Goal(..))
    }
}

/// A scenario: where the feet start, and commands at given ticks.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Name.
    pub name: String,
    /// One-line description.
    pub about: String,
    /// Left and right foot at the start; `None`: the robot's stance ([`Scenario::start_feet`]).
    pub feet: Option<[Footstep<f64>; 2]>,
    /// `(tick, command)`: applied, in order, once `tick` control periods have elapsed (at
    /// `tick · 5 ms`), before the next reference is computed.
    pub timeline: Vec<(u64, Command)>,
    /// Ticks to run at most (the run ends earlier once standing after the last command).
    pub max_ticks: u64,
}

impl Scenario {
    /// Where the feet start: [`Scenario::feet`], or the robot's stance (`step_width` apart
    /// at the origin, heading along x, as [`planner_core::node::NodeConfig::for_robot`]).
    pub fn start_feet(&self, step_width: f64) -> [Footstep<f64>; 2] {
        self.feet.unwrap_or([
            Footstep::new(Side::Left, 0.0, step_width / 2.0, 0.0),
            Footstep::new(Side::Right, 0.0, -step_width / 2.0, 0.0),
        ])
    }
}

/// What happened to a command.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// Tick at which the command was applied.
    pub tick: u64,
    /// The command.
    pub command: Command,
    /// The answer: accepted, or the reason of the refusal.
    pub result: Result<(), String>,
}

/// A re-plan that changed the single-support time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adjustment {
    /// Tick of the re-plan.
    pub tick: u64,
    /// ΔT \[s\].
    pub adjust_s: f64,
    /// `r` of eq. 18.
    pub ratio: f64,
    /// Deciding plane (0 = x, 1 = y).
    pub plane: u8,
}

/// The result of a run.
#[derive(Clone, Debug)]
pub struct Run {
    /// One reference per tick, starting with the initial standing state at tick 0.
    pub trajectory: Vec<Reference<f64>>,
    /// Every command and its answer.
    pub events: Vec<Event>,
    /// Every re-plan with a non-zero adjustment, or following a modification.
    pub adjustments: Vec<Adjustment>,
    /// Every footstep as finally queued (by id).
    pub footsteps: Vec<(u16, Footstep<f64>)>,
}

/// Plays a scenario against a gait with the given parameters.
pub fn run(s: &Scenario, params: GaitParams<f64>) -> Run {
    let [left, right] = s.start_feet(params.step_width);
    let mut g: Gait<f64, 64> = Gait::new(params, left, right).expect("valid gait parameters");
    let mut trajectory = vec![*g.last()];
    let mut events = Vec::new();
    let mut adjustments = Vec::new();
    let mut footsteps: Vec<(u16, Footstep<f64>)> = Vec::new();
    let mut next = 0;
    let mut last_replan = None;
    let last_command = s.timeline.last().map(|(t, _)| *t).unwrap_or(0);
    while g.ticks() < s.max_ticks {
        while next < s.timeline.len() && s.timeline[next].0 <= g.ticks() {
            let (_, command) = s.timeline[next];
            let result = match command {
                Command::Push(id, f) => g.push(id, f).map_err(|(e, _)| e),
                Command::Start => g.start(),
                Command::Stop => {
                    g.stop();
                    Ok(())
                }
                Command::StopNow => {
                    g.clear_and_stop();
                    Ok(())
                }
                Command::Modify(id, f) => g.modify(id, f),
                // The gait alone has no step generator: the node's (a run through the bus).
                Command::Velocity(..) | Command::Goal(..) => Err(GaitError::WrongState),
            };
            match (command, result) {
                (Command::Push(id, f), Ok(())) | (Command::Modify(id, f), Ok(())) => {
                    if let Some(e) = footsteps.iter_mut().find(|(i, _)| *i == id) {
                        e.1 = f;
                    } else {
                        footsteps.push((id, f));
                    }
                    if matches!(command, Command::Modify(..)) {}
                }
                _ => {}
            }
            events.push(Event {
                tick: g.ticks(),
                command,
                result: result.map_err(|e: GaitError| format!("{e:?}")),
            });
            next += 1;
        }
        trajectory.push(g.tick());
        if let Some(info) = g.last_replan() {
            if last_replan != Some(info.tick) {
                last_replan = Some(info.tick);
                if info.adjust_ticks != 0 || info.ratio != 1.0 {
                    adjustments.push(Adjustment {
                        tick: info.tick,
                        adjust_s: f64::from(info.adjust_ticks) * params.dt,
                        ratio: info.ratio,
                        plane: info.plane,
                    });
                }
            }
        }
        if g.is_standing() && g.ticks() > last_command && next >= s.timeline.len() {
            break;
        }
    }
    Run {
        trajectory,
        events,
        adjustments,
        footsteps,
    }
}
