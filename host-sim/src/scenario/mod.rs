//! Scenarios: a timeline of footstep commands played against the gait, one tick per 5 ms of
//! simulated time, and the built-in HRP-2 scenarios.
//!
//! [`run`] drives the gait API directly (the API the node calls), without the bus;
//! [`crate::sim`] plays a scenario through the virtual CAN link and the node.
//!
//! # Rooms
//! [`file`](mod@file) reads scenario files (TOML); [`expect`] names what may become of a command (a
//! file's `expect` key); [`wire`] encodes a scenario's commands as the controller sends them.

pub mod expect;
pub mod file;
pub mod wire;

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

fn foot_y(side: Side, half_width: f64) -> f64 {
    match side {
        Side::Left => half_width,
        Side::Right => -half_width,
    }
}

/// Straight steps of `step` m from feet at x = 0, right foot first, `n` steps and a closing
/// step; ids from 0.
fn straight_steps(n: u16, step: f64) -> Vec<(u16, Footstep<f64>)> {
    let mut out = Vec::new();
    let mut side = Side::Right;
    for i in 0..n {
        out.push((
            i,
            Footstep::new(side, step * f64::from(i + 1), foot_y(side, 0.1), 0.0),
        ));
        side = side.other();
    }
    out.push((
        n,
        Footstep::new(side, step * f64::from(n), foot_y(side, 0.1), 0.0),
    ));
    out
}

fn pushes(steps: &[(u16, Footstep<f64>)]) -> Vec<(u64, Command)> {
    steps
        .iter()
        .map(|&(i, f)| (0, Command::Push(i, f)))
        .collect()
}

/// The names of the built-in scenarios.
pub const BUILT_IN: [&str; 5] = ["straight", "turn", "stop", "fig4", "lateral"];

/// A built-in scenario by name.
pub fn built_in(name: &str) -> Option<Scenario> {
    // The robot's stance: the built-in steps are HRP-2's (feet 0.2 m apart).
    let feet = None;
    let s = match name {
        "straight" => {
            let mut timeline = pushes(&straight_steps(8, 0.2));
            timeline.push((20, Command::Start));
            timeline.push((20, Command::Stop));
            Scenario {
                name: name.into(),
                about: "eight 0.2 m steps and a closing step, then stop".into(),
                feet,
                timeline,
                max_ticks: 4000,
            }
        }
        "turn" => {
            let mut steps = Vec::new();
            let mut side = Side::Right;
            let n = 8u16;
            for i in 0..=n {
                let yaw = core::f64::consts::FRAC_PI_2 * f64::from(i.min(n - 1) + 1) / f64::from(n);
                let radius = if side == Side::Left { 0.9 } else { 1.1 };
                steps.push((
                    i,
                    Footstep::new(side, radius * yaw.sin(), 1.0 - radius * yaw.cos(), yaw),
                ));
                side = side.other();
            }
            let mut timeline = pushes(&steps);
            timeline.push((20, Command::Start));
            timeline.push((20, Command::Stop));
            Scenario {
                name: name.into(),
                about: "a quarter turn to the left on a 1 m radius in nine steps, then stop".into(),
                feet,
                timeline,
                max_ticks: 4000,
            }
        }
        "stop" => {
            let mut timeline = pushes(&straight_steps(20, 0.2));
            timeline.push((20, Command::Start));
            // Stop request in the middle of the walk: the queue is dropped, the robot closes
            // its feet with a step in place and settles.
            timeline.push((600, Command::StopNow));
            Scenario {
                name: name.into(),
                about: "walking 0.2 m steps, stop-now command at 3.0 s".into(),
                feet,
                timeline,
                max_ticks: 4000,
            }
        }
        "fig4" => {
            // The paper's Fig. 4: 0.1 m steps; at the single support that begins at 4.0 s the
            // landing moves from 0.4 m to 0.6 m, the later steps keep their 0.1 m length.
            let steps = straight_steps(11, 0.1);
            let mut timeline = pushes(&steps);
            timeline.push((160, Command::Start));
            for &(i, f) in steps.iter().skip(3).rev() {
                let moved = Footstep::new(f.side, f.x + 0.2, f.y, f.yaw);
                timeline.push((799, Command::Modify(i, moved)));
            }
            timeline.push((800, Command::Stop));
            Scenario {
                name: name.into(),
                about: "paper Fig. 4: next landing 0.4 m -> 0.6 m at the start of the single support at 4.0 s"
                    .into(),
                feet,
                timeline,
                max_ticks: 4000,
            }
        }
        "lateral" => {
            // Section V: 0.2 m steps, step cycle 0.8 s; the next landing is moved 0.05 m
            // inwards, and later 0.05 m outwards, just before lift-off.
            let steps = straight_steps(12, 0.2);
            let mut timeline = pushes(&steps);
            timeline.push((160, Command::Start));
            // Single supports begin at 1.6 s + k·0.8 s; the one at 4.0 s swings step 3 (left).
            // Step 5 (left) is moved at 5.0 s, while step 4 swings: the change takes effect
            // when step 5 lifts off, wherever the first adjustment has put that moment.
            let (_, s3) = steps[3];
            timeline.push((
                799,
                Command::Modify(3, Footstep::new(s3.side, s3.x, s3.y - 0.05, 0.0)),
            ));
            let (_, s5) = steps[5];
            timeline.push((
                1000,
                Command::Modify(5, Footstep::new(s5.side, s5.x, s5.y + 0.05, 0.0)),
            ));
            timeline.push((1200, Command::Stop));
            Scenario {
                name: name.into(),
                about: "paper section V: next landing moved 0.05 m inwards at 4.0 s, the one after next outwards"
                    .into(),
                feet,
                timeline,
                max_ticks: 4000,
            }
        }
        _ => return None,
    };
    Some(s)
}
