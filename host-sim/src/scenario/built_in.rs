//! The built-in scenarios, drawn in a robot's proportions ([`Stance`]).
//!
//! They are written for HRP-2 (feet 0.2 m apart, 0.2 m steps, reach 0.30 m forward, a 0.8 s
//! step cycle started 0.8 s after `start`) and scaled for another robot: lateral positions
//! by its stance (`y = ±step_width/2`), lengths along the walk (step lengths, the turn's
//! radius, the modifications' offsets) by `s = max_forward / 0.30` (the lateral offsets at
//! most what `min_width` allows), and the modification
//! times by its timing (the `k`-th single support begins `start + k (T_ss + T_ds)` after the
//! start command). For HRP-2 the scaled scenarios are the written ones exactly.

use planner_core::gait::{Footstep, GaitParams, Side};
use planner_core::node::Reach;

use super::{Command, Scenario, TICK_S};

/// HRP-2's forward reach, the unit of the built-in scenarios' lengths \[m\].
pub const HRP2_FORWARD: f64 = 0.30;

/// A robot's proportions for the built-in scenarios.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stance {
    /// Half the distance between the feet \[m\].
    pub half_width: f64,
    /// Lengths along the walk, against HRP-2's.
    pub scale: f64,
    /// Ticks from the start command to the first single support.
    pub start_ticks: u64,
    /// Ticks of a step cycle (single plus double support).
    pub cycle_ticks: u64,
    /// How far a foot may move inwards from the stance (`step_width − min_width`) \[m\].
    pub inward: f64,
}

impl Stance {
    /// HRP-2's.
    pub const HRP2: Stance = Stance {
        half_width: 0.1,
        scale: 1.0,
        start_ticks: 160,
        cycle_ticks: 160,
        inward: 0.05,
    };

    /// A robot's, from its gait parameters and reach limits.
    pub fn of(params: &GaitParams<f64>, reach: &Reach) -> Self {
        Self {
            half_width: params.step_width / 2.0,
            scale: reach.max_forward / HRP2_FORWARD,
            start_ticks: u64::from(params.start_ticks),
            cycle_ticks: u64::from(params.single_ticks) + u64::from(params.double_ticks),
            inward: params.step_width - reach.min_width,
        }
    }

    /// The tick at which the `k`-th single support begins, for a start command at `start`.
    fn single_support(&self, start: u64, k: u64) -> u64 {
        start + self.start_ticks + k * self.cycle_ticks
    }

    fn y(&self, side: Side) -> f64 {
        match side {
            Side::Left => self.half_width,
            Side::Right => -self.half_width,
        }
    }

    /// A length along the walk, scaled.
    fn l(&self, hrp2: f64) -> f64 {
        hrp2 * self.scale
    }
}

/// Straight steps of `step` m from feet at x = 0, right foot first, `n` steps and a closing
/// step; ids from 0.
fn straight_steps(st: &Stance, n: u16, step: f64) -> Vec<(u16, Footstep<f64>)> {
    let mut out = Vec::new();
    let mut side = Side::Right;
    for i in 0..n {
        out.push((
            i,
            Footstep::new(side, step * f64::from(i + 1), st.y(side), 0.0),
        ));
        side = side.other();
    }
    out.push((n, Footstep::new(side, step * f64::from(n), st.y(side), 0.0)));
    out
}

fn pushes(steps: &[(u16, Footstep<f64>)]) -> Vec<(u64, Command)> {
    steps
        .iter()
        .map(|&(i, f)| (0, Command::Push(i, f)))
        .collect()
}

/// A length for a description, to the millimetre.
fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// The names of the built-in scenarios.
pub const BUILT_IN: [&str; 5] = ["straight", "turn", "stop", "fig4", "lateral"];

/// The built-in scenarios in which the node chooses the footsteps (a velocity, a goal): played
/// by `run` through the bus and the node (the gait alone, [`super::run`], has no step
/// generator), so they are not among [`BUILT_IN`], which every footstep tool plays.
pub const DRIVEN: [&str; 1] = ["velocity"];

/// A built-in scenario by name, as written (HRP-2's proportions).
pub fn built_in(name: &str) -> Option<Scenario> {
    built_in_for(name, &Stance::HRP2)
}

/// A built-in scenario by name, drawn in the proportions `st`.
pub fn built_in_for(name: &str, st: &Stance) -> Option<Scenario> {
    // The robot's stance: where the feet start.
    let feet = None;
    let scenario = |about: String, timeline| Scenario {
        name: name.into(),
        about,
        feet,
        timeline,
        max_ticks: 4000,
    };
    let step = st.l(0.2);
    let s = match name {
        "straight" => {
            let mut timeline = pushes(&straight_steps(st, 8, step));
            timeline.push((20, Command::Start));
            timeline.push((20, Command::Stop));
            scenario(
                format!("eight {} m steps and a closing step, then stop", mm(step)),
                timeline,
            )
        }
        "turn" => {
            let mut steps = Vec::new();
            let mut side = Side::Right;
            let n = 8u16;
            let r = st.l(1.0);
            for i in 0..=n {
                let yaw = core::f64::consts::FRAC_PI_2 * f64::from(i.min(n - 1) + 1) / f64::from(n);
                let radius = r - st.y(side);
                steps.push((
                    i,
                    Footstep::new(side, radius * yaw.sin(), r - radius * yaw.cos(), yaw),
                ));
                side = side.other();
            }
            let mut timeline = pushes(&steps);
            timeline.push((20, Command::Start));
            timeline.push((20, Command::Stop));
            scenario(
                format!(
                    "a quarter turn to the left on a {} m radius in nine steps, then stop",
                    mm(r)
                ),
                timeline,
            )
        }
        "stop" => {
            let mut timeline = pushes(&straight_steps(st, 20, step));
            timeline.push((20, Command::Start));
            // Stop request in the middle of the walk: the queue is dropped, the robot closes
            // its feet with a step in place and settles.
            timeline.push((600, Command::StopNow));
            scenario(
                format!("walking {} m steps, stop-now command at 3.0 s", mm(step)),
                timeline,
            )
        }
        "fig4" => {
            // The paper's Fig. 4: 0.1 m steps; at the single support that begins at 4.0 s the
            // landing moves from 0.4 m to 0.6 m, the later steps keep their 0.1 m length.
            let short = st.l(0.1);
            let steps = straight_steps(st, 11, short);
            let mut timeline = pushes(&steps);
            timeline.push((160, Command::Start));
            let at = st.single_support(160, 3);
            for &(i, f) in steps.iter().skip(3).rev() {
                let moved = Footstep::new(f.side, f.x + st.l(0.2), f.y, f.yaw);
                timeline.push((at - 1, Command::Modify(i, moved)));
            }
            timeline.push((at, Command::Stop));
            scenario(
                format!(
                    "paper Fig. 4: next landing {} m -> {} m at the start of the single support \
                     at {:.1} s",
                    mm(st.l(0.4)),
                    mm(st.l(0.6)),
                    at as f64 * TICK_S
                ),
                timeline,
            )
        }
        "lateral" => {
            // Section V: 0.2 m steps, step cycle 0.8 s; the next landing is moved 0.05 m
            // inwards, and later 0.05 m outwards, just before lift-off.
            let steps = straight_steps(st, 12, step);
            let mut timeline = pushes(&steps);
            timeline.push((160, Command::Start));
            // Single supports begin at 1.6 s + k·0.8 s; the one at 4.0 s swings step 3 (left).
            // Step 5 (left) is moved at 5.0 s, while step 4 swings: the change takes effect
            // when step 5 lifts off, wherever the first adjustment has put that moment.
            let at = st.single_support(160, 3);
            let d = st.l(0.05).min(st.inward);
            let (_, s3) = steps[3];
            timeline.push((
                at - 1,
                Command::Modify(3, Footstep::new(s3.side, s3.x, s3.y - d, 0.0)),
            ));
            let (_, s5) = steps[5];
            timeline.push((
                st.single_support(160, 4) + 40,
                Command::Modify(5, Footstep::new(s5.side, s5.x, s5.y + d, 0.0)),
            ));
            timeline.push((st.single_support(160, 5) + 80, Command::Stop));
            scenario(
                format!(
                    "paper section V: next landing moved {} m inwards at {:.1} s, the one after \
                     next outwards",
                    mm(d),
                    at as f64 * TICK_S
                ),
                timeline,
            )
        }
        "velocity" => {
            // A stick: forward, then a step change to sideways, a turn to the left and its
            // reversal to the right, then zero (the robot stops and stands).
            let v = |vx: f64, vy: f64, wz: f64| Command::Velocity(st.l(vx), st.l(vy), wz);
            let timeline = vec![
                (20, v(0.15, 0.0, 0.0)),
                (1200, v(0.0, 0.04, 0.0)),
                (2200, v(0.05, 0.0, 0.15)),
                (3000, v(0.05, 0.0, -0.15)),
                (3800, v(0.0, 0.0, 0.0)),
            ];
            let mut s = scenario(
                format!(
                    "velocity walking: {} m/s forward, at 6 s {} m/s sideways, at 11 s a turn of \
                     0.15 rad/s and at 15 s its reversal, at 19 s zero",
                    mm(st.l(0.15)),
                    mm(st.l(0.04))
                ),
                timeline,
            );
            s.max_ticks = 5000;
            s
        }
        _ => return None,
    };
    Some(s)
}
