//! A seeded fault sweep of the CAN link ("Reliability": a walking robot that receives bad
//! frames must not fall, and the node must never stop publishing references).
//!
//! [`run_case`] plays a built-in scenario through the virtual bus and the node, as
//! [`crate::sim::simulate`] does, with a controller that **retransmits**: a footstep or control
//! command whose `ACK` has not arrived 20 ms (4 ticks) after it was sent, or that was refused
//! with `SequenceGap` (an earlier append was lost or overtaken) or `BadCrc` (corrupted on the
//! way), is sent again, at most [`MAX_RETRIES`] times; a repeat that the node had already applied is
//! answered `Duplicate`, which the controller takes as accepted. An answer counts for a command
//! only if it echoes that command's CRC (an answer to an older version of a modification is not
//! taken for the newer one) and its own CRC is right. A control command (`Start`, `Stop`) is
//! held back until every earlier command is answered (a `Stop` that overtakes a lost `Start`
//! would leave the robot stepping in place). `sim.rs` is unchanged (it stays the run without
//! retransmission).
//!
//! Fault kinds ([`FaultKind`]) and what their rate means:
//! * `drop`, `duplicate`, `corrupt` (one data bit flipped, a frame a faulty gateway passes on
//!   with a valid CRC), `delay` (30 ms late, overtaken by later frames): probability per frame,
//!   on the frames of **both** directions;
//! * `silence`: the controller dies (its port neither sends nor receives) at a time drawn
//!   uniformly in 0.1 … 8 s; no rate;
//! * `flood`: a third port (a babbling node) sends frames of uniformly random identifiers
//!   (0 … 0x7FF), lengths and data, one at a time, offering about `rate` of the bus time (1.0:
//!   a new frame is ready as soon as the last one is sent, the bus runs at 100 % load); a random
//!   identifier below the controller's and the node's wins arbitration over them, and frames
//!   with command identifiers are commands (a random `ESTOP` stops the robot);
//! * `burst`: `rate` modifications (each a random change of ±50 mm along, ±30 mm across,
//!   ±0.1 rad of one of the queued steps after the swinging one) sent during one single support
//!   chosen at random;
//! * `estimator silent` (adjusting walks only): the state estimator stops sending 0 … 0.3 s
//!   after the push, while the deviation still grows; no rate.
//!
//! **Two walks** ([`Walk`]): the scenario as written (`start`), and the same scenario started
//! with `start_adjusting`, with a pushed robot whose state estimator sends `MEASURED` every
//! cycle on a port of its own (see `adjusting.rs`: the pendulum robot of
//! [`crate::sim::pushed`], tracking the node's references, pushed once by 0.15 … 0.25 m/s in a
//! direction drawn from the seed). Every fault of a row applies to every frame on the bus, so
//! to `MEASURED` and `ADJUST` too, at the same rates; `silence` is the controller's.
//! A third walk, [`Walk::Velocity`], plays a velocity scenario ([`VELOCITY_SCENARIO`]): a
//! stick streams the velocity it holds every 50 ms (`stick.rs`), and [`VelocityRun`] counts
//! what the node did with its frames (none taken after a newer one, none once the controller
//! is lost, the velocity in force the one taken last carries; under `silence`, how soon the
//! node declared the controller lost and the robot stood). It has no `burst` rows.
//!
//! What is counted per run ([`CaseResult`]):
//! * **fall**: the multi-body ZMP ([`crate::eval::multibody::evaluate`] of the node's references)
//!   leaves the support polygon by more than [`FALL_MARGIN`] at some tick (ticks 2 … n−3, as
//!   [`crate::eval::multibody::max_zmp_error`]). The support polygon is the sole (0.24 × 0.14 m, centred on
//!   the foot pose and turned by its yaw) of the foot on the ground in single support, and the
//!   convex hull of both soles otherwise (the reference's phase decides);
//! * **leg out of reach**: the model cannot follow the references to the end (a knee would
//!   have to stretch beyond thigh + shank = 0.6 m); the ZMP of such a run is evaluated up to
//!   50 ms before that tick, and the run is counted in its own column, not as a fall;
//! * **lost commands**: footsteps whose final state as the controller knows it (the last
//!   append or modification of that id it saw accepted) was not walked exactly once at that
//!   pose (±0.5 mm, ±2 mrad), plus landings that match no accepted footstep. Steps left unwalked
//!   after the node's own safety stop (controller lost, emergency stop) are counted apart as
//!   **cancelled**, and so is the closing step such a stop adds. In an adjusting walk a step
//!   counts as walked at its accepted pose plus the shift the node had in force when it
//!   lifted off (the node's own book of its `ADJUST`s: the last shift made before that
//!   lift-off); a landing at neither is lost;
//! * **shift unheard** (adjusting walks): a walked step whose shift the controller's book got
//!   wrong. The controller keeps every `ADJUST` it receives by its count of adjustments (a
//!   late or repeated copy changes nothing) and lands step `id` at its accepted pose plus the
//!   newest shift whose first step is at most `id`. The node repeats `ADJUST` every 100 ms
//!   while a shift is in force, so the book converges to the shift in force; only a shift
//!   that is overtaken by the next one before any of its copies arrives stays unheard (the
//!   landing is then recognised by the node's book, and counted here, not as lost);
//! * **`MEASURED` answered** (adjusting walks, [`MeasuredCount`]): taken, or refused stale,
//!   duplicate, for a bad CRC, or otherwise (controller lost, emergency stop); a state taken
//!   older than the node's `max_age` (by its answer's stamp) is counted apart and must not
//!   happen; **adjustments**: changes of the node's shift; **pendulum fell**: the robot's DCM
//!   more than [`crate::sim::pushed::FALLEN_M`] from the reference's;
//! * **reference every tick**: the node handed one reference (five stream frames) to its bus
//!   port in every cycle, each finite; **stream gaps**: ticks whose reference the controller
//!   did not receive (a property of the bus, not of the node).
//!
//! The module's files:
//! * this one: the fault kinds, the sweep's rows ([`SWEEP`], [`HEAVY`]) and scenarios, the
//!   result of a run ([`CaseResult`]) and the entry points [`run_case`], [`run_case_with`] and
//!   [`run_case_logged`];
//! * `play.rs`: one run: the retransmitting controller, the node and the bus, tick by tick,
//!   and the evaluation of its references and landings;
//! * `ports.rs`: what the run puts on the bus besides the controller: the node's tap (what it
//!   hands to its port in a cycle), the babbling port of `flood`, the seeded random numbers;
//! * `adjusting.rs`: the adjusting walk's robot and estimator, the count of the node's answers
//!   to `MEASURED`, and the node's and the controller's books of the shift;
//! * `polygon.rs`: the support polygon (the soles' convex hull) and the distance of a ZMP
//!   outside it, and the landings of a trajectory;
//! * `stick.rs`: the velocity walk's stick and its count of the node's uptake;
//! * `sweep.rs`: the sweep over the rows, scenarios and seeds ([`sweep()`], [`SweepRow`]) and its
//!   Markdown table.

mod adjusting;
mod play;
mod polygon;
mod ports;
mod stick;
mod sweep;

use planner_core::gait::Reference;
use planner_core::node::NodeConfig;

use crate::robot::model::Model;
use crate::scenario::Scenario;

pub use adjusting::{BLIND_AFTER, PUSH_DV};
pub use polygon::{landings, support_polygon};
pub use sweep::{
    markdown, markdown_adjusting, markdown_velocity, sweep, sweep_markdown, sweep_walk, SweepRow,
};

/// How far the multi-body ZMP may leave the support polygon before the run counts as a fall
/// \[m\]. The fault-free runs of the built-in scenarios stay inside (see the test); 20 mm is
/// less than the smallest multi-body ZMP error of those runs (41 mm): a run only falls if
/// the faults push the ZMP clearly further out than modelling error does.
pub const FALL_MARGIN: f64 = 0.02;
/// Half the sole length and width \[m\].
pub const SOLE_HALF: [f64; 2] = [0.12, 0.07];
/// Ticks (5 ms) without an answer before a command is sent again (20 ms).
pub const RETRY_TICKS: u64 = 4;
/// Retransmissions of one command at most (40 × 20 ms: a command is given up 0.8 s after it
/// was first sent). Repeats are safe — the node answers a repeat of what it applied with
/// `Duplicate` — so the controller can afford to insist: with 20 % of the frames of each
/// direction lost, one attempt fails with probability 0.36 and 41 in a row with 6e-19; with
/// 50 % corrupted, 0.75 and 7.5e-6 (at 20 retries it was 2.4e-3, and the sweep's heavier rows
/// saw a walked step whose every answer was corrupted).
pub const MAX_RETRIES: u8 = 40;
/// Latency of a delayed frame \[ns\] (30 ms: beyond the retransmission time-out).
pub const DELAY_NS: u64 = 30_000_000;

/// A kind of fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultKind {
    /// None (the reference run).
    None,
    /// Frames lost.
    Drop,
    /// Frames delivered twice.
    Duplicate,
    /// One data bit flipped.
    Corrupt,
    /// Frames delivered 30 ms late.
    Delay,
    /// The controller dies at a random time.
    Silence,
    /// A babbling port floods the bus with random identifiers.
    Flood,
    /// Many modifications within one single support.
    Burst,
    /// The state estimator stops sending after the push (adjusting walks only).
    Blind,
    /// A combination of faults: the index of its row in [`HEAVY`].
    Mixed(usize),
}

/// One of the heavier combinations of faults (the last rows of the fault table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mix {
    /// As printed in the table.
    pub label: &'static str,
    /// Drop probability per frame (both directions).
    pub drop: f64,
    /// Corruption probability per frame.
    pub corrupt: f64,
    /// Delay probability per frame.
    pub delay: f64,
    /// Latency of a delayed frame \[ns\].
    pub delay_ns: u64,
    /// Modifications in one single support (as `burst`).
    pub burst: usize,
}

/// The heavier rows: what lost footsteps before modifications carried a version.
pub const HEAVY: [Mix; 3] = [
    Mix {
        label: "delay 600 ms 30 % + drop 30 % + corrupt 30 %",
        drop: 0.3,
        corrupt: 0.3,
        delay: 0.3,
        delay_ns: 600_000_000,
        burst: 0,
    },
    Mix {
        label: "burst 60 + drop 20 % + delay 600 ms 20 %",
        drop: 0.2,
        corrupt: 0.0,
        delay: 0.2,
        delay_ns: 600_000_000,
        burst: 60,
    },
    Mix {
        label: "corrupt 50 %",
        drop: 0.0,
        corrupt: 0.5,
        delay: 0.0,
        delay_ns: 0,
        burst: 0,
    },
];

impl FaultKind {
    /// Name in the table.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::None => "none",
            FaultKind::Drop => "drop",
            FaultKind::Duplicate => "duplicate",
            FaultKind::Corrupt => "corrupt",
            FaultKind::Delay => "delay",
            FaultKind::Silence => "silence",
            FaultKind::Flood => "flood",
            FaultKind::Burst => "burst",
            FaultKind::Blind => "estimator silent",
            FaultKind::Mixed(_) => "mixed",
        }
    }

    /// The rate as printed.
    pub fn rate_label(self, rate: f64) -> String {
        match self {
            FaultKind::None | FaultKind::Silence | FaultKind::Blind => "—".into(),
            FaultKind::Flood => format!("{:.0} % load", rate * 100.0),
            FaultKind::Burst => format!("{rate:.0} / support"),
            FaultKind::Mixed(i) => HEAVY.get(i).map_or("?", |m| m.label).into(),
            _ => format!("{:.0} %", rate * 100.0),
        }
    }
}

/// The sweep: every kind with its rates.
pub const SWEEP: [(FaultKind, &[f64]); 8] = [
    (FaultKind::None, &[0.0]),
    (FaultKind::Drop, &[0.01, 0.05, 0.20]),
    (FaultKind::Duplicate, &[0.01, 0.05, 0.20]),
    (FaultKind::Corrupt, &[0.01, 0.05, 0.20]),
    (FaultKind::Delay, &[0.01, 0.05, 0.20]),
    (FaultKind::Silence, &[0.0]),
    (FaultKind::Flood, &[0.2, 1.0]),
    (FaultKind::Burst, &[5.0, 20.0, 60.0]),
];

/// The rows only the adjusting walk has.
pub const ADJUSTING_ONLY: [(FaultKind, &[f64]); 1] = [(FaultKind::Blind, &[0.0])];

/// The scenarios of the sweep.
pub const SCENARIOS: [&str; 2] = ["straight", "fig4"];

/// The scenario of the velocity walk ([`Walk::Velocity`]).
pub const VELOCITY_SCENARIO: &str = "velocity";

/// The `ACK`'s command code of a `VELOCITY`.
pub const VELOCITY_CODE: u8 = (planner_core::wire::ids::VELOCITY & 0xFF) as u8;

/// What a velocity walk's node did with the stick's `VELOCITY` frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VelocityRun {
    /// Frames the stick sent.
    pub sent: usize,
    /// Answered accepted.
    pub taken: usize,
    /// Refused stale or duplicate (a late or repeated copy).
    pub refused_old: usize,
    /// Refused for a bad CRC.
    pub refused_crc: usize,
    /// Refused otherwise (controller lost, emergency stop, wrong state).
    pub refused_other: usize,
    /// Frames taken although a newer one had been taken before (must be 0).
    pub old_taken: usize,
    /// Frames taken after the node had declared the controller lost (must be 0).
    pub taken_after_lost: usize,
    /// Frames taken whose velocity the node then did not hold (uncut; must be 0).
    pub wrong_velocity: usize,
    /// The oldest frame taken: ticks between its sending and the cycle that took it.
    pub max_age_taken: u64,
    /// `silence`: ticks from the controller's silence to the node's *controller lost*.
    pub lost_after: Option<u64>,
    /// `silence`: ticks from the controller's silence to the robot standing.
    pub standing_after: Option<u64>,
}

/// How a scenario of the sweep is walked (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// As written: `start`, no estimator.
    Plain,
    /// `start_adjusting`, a pushed robot and its estimator's `MEASURED` every cycle.
    Adjusting,
    /// A stick: the scenario's velocities streamed every 50 ms (see `stick.rs`).
    Velocity,
}

impl Walk {
    /// As printed and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Walk::Plain => "plain",
            Walk::Adjusting => "adjusting",
            Walk::Velocity => "velocity",
        }
    }
}

/// Every row of the sweep of `walk` in its order: the [`SWEEP`] rates, then (adjusting)
/// [`ADJUSTING_ONLY`], then the [`HEAVY`] mixes.
pub fn rows(walk: Walk) -> Vec<(FaultKind, f64)> {
    let extra: &[(FaultKind, &[f64])] = match walk {
        Walk::Plain | Walk::Velocity => &[],
        Walk::Adjusting => &ADJUSTING_ONLY,
    };
    // A velocity walk has no footsteps of the controller's to modify: no burst.
    let velocity = walk == Walk::Velocity;
    let mut v: Vec<(FaultKind, f64)> = SWEEP
        .iter()
        .chain(extra)
        .filter(|(k, _)| !(velocity && *k == FaultKind::Burst))
        .flat_map(|(k, rates)| rates.iter().map(move |r| (*k, *r)))
        .collect();
    v.extend(
        (0..HEAVY.len())
            .filter(|&i| !(velocity && HEAVY[i].burst > 0))
            .map(|i| (FaultKind::Mixed(i), 0.0)),
    );
    v
}

/// How a run's node answered the estimator's `MEASURED` frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeasuredCount {
    /// Taken.
    pub taken: usize,
    /// Refused `stale` (older than the node's `max_age`, or not newer than one taken).
    pub stale: usize,
    /// Refused `duplicate` (the state taken last, again).
    pub duplicate: usize,
    /// Refused `bad_crc` (corrupted, or keyed with another session).
    pub bad_crc: usize,
    /// Refused otherwise (controller lost, emergency-stopped, another session's stamp).
    pub other: usize,
}

impl std::ops::AddAssign for MeasuredCount {
    fn add_assign(&mut self, o: Self) {
        self.taken += o.taken;
        self.stale += o.stale;
        self.duplicate += o.duplicate;
        self.bad_crc += o.bad_crc;
        self.other += o.other;
    }
}

/// One run of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseResult {
    /// Ticks run.
    pub ticks: usize,
    /// The multi-body ZMP left the support polygon by more than [`FALL_MARGIN`] (on the ticks
    /// the model could follow).
    pub fell: bool,
    /// Why the model could not follow the references to the end, if so (then the ZMP is
    /// evaluated up to that tick).
    pub model_error: Option<String>,
    /// Largest distance of the multi-body ZMP outside the support polygon \[m\].
    pub max_outside: f64,
    /// Largest distance between the planned and the multi-body ZMP \[m\].
    pub max_zmp_error: f64,
    /// Lost commands (see the module docs).
    pub lost: usize,
    /// Footsteps cancelled by the node's safety stop.
    pub cancelled: usize,
    /// Commands never answered after every retransmission.
    pub unanswered: usize,
    /// Footsteps whose version in force the controller got wrong.
    pub misinformed: usize,
    /// Retransmissions sent.
    pub retransmissions: usize,
    /// The node stopped on its own (controller lost or emergency stop).
    pub safety_stop: bool,
    /// Cycles in which the node did not hand exactly one finite reference to the bus.
    pub ticks_without_reference: usize,
    /// Ticks whose reference the controller did not receive.
    pub stream_gaps: usize,
    /// Footsteps walked (landings).
    pub landings: usize,
    /// Fraction of the time the bus was busy.
    pub bus_load: f64,
    /// The walk.
    pub walk: Walk,
    /// The pendulum robot fell (adjusting walks).
    pub pendulum_fell: bool,
    /// The node's answers to `MEASURED`.
    pub measured: MeasuredCount,
    /// `MEASURED` states taken older than the node's `max_age` (by the answers' stamps).
    pub measured_too_old: usize,
    /// Changes of the node's shift.
    pub adjustments: usize,
    /// The node cycle of the last change of the shift.
    pub last_adjustment: Option<u32>,
    /// Walked steps whose shift the controller's book got wrong.
    pub shift_unheard: usize,
    /// Steps walked at a shift other than zero.
    pub shifted_landings: usize,
    /// `estimator silent`: the node cycle of the first state the estimator did not send.
    pub estimator_silent_from: Option<u32>,
    /// The velocity walk's stick and the node's uptake of its frames.
    pub velocity: Option<VelocityRun>,
    /// The references the node published, one per tick (for the physics engine run).
    pub trajectory: Vec<Reference<f64>>,
}

impl std::ops::AddAssign for VelocityRun {
    /// Sums the counts; the ages and delays: the largest.
    fn add_assign(&mut self, o: Self) {
        self.sent += o.sent;
        self.taken += o.taken;
        self.refused_old += o.refused_old;
        self.refused_crc += o.refused_crc;
        self.refused_other += o.refused_other;
        self.old_taken += o.old_taken;
        self.taken_after_lost += o.taken_after_lost;
        self.wrong_velocity += o.wrong_velocity;
        self.max_age_taken = self.max_age_taken.max(o.max_age_taken);
        self.lost_after = self.lost_after.max(o.lost_after);
        self.standing_after = self.standing_after.max(o.standing_after);
    }
}

/// Plays `scenario` with one fault kind at one rate and one seed, and evaluates the outcome.
pub fn run_case(s: &Scenario, kind: FaultKind, rate: f64, seed: u64) -> Result<CaseResult, String> {
    run_case_with(s, kind, rate, seed, NodeConfig::hrp2(), &Model::hrp2())
}

/// [`run_case`] with another robot: its node `cfg` and its link table `model` (for the
/// kinematic verdict).
pub fn run_case_with(
    s: &Scenario,
    kind: FaultKind,
    rate: f64,
    seed: u64,
    cfg: NodeConfig,
    model: &Model,
) -> Result<CaseResult, String> {
    run_walk_with(s, Walk::Plain, kind, rate, seed, cfg, model)
}

/// [`run_case`] walked as `walk`.
pub fn run_walk(
    s: &Scenario,
    walk: Walk,
    kind: FaultKind,
    rate: f64,
    seed: u64,
) -> Result<CaseResult, String> {
    run_walk_with(
        s,
        walk,
        kind,
        rate,
        seed,
        NodeConfig::hrp2(),
        &Model::hrp2(),
    )
}

/// [`run_case_with`] walked as `walk`.
pub fn run_walk_with(
    s: &Scenario,
    walk: Walk,
    kind: FaultKind,
    rate: f64,
    seed: u64,
    cfg: NodeConfig,
    model: &Model,
) -> Result<CaseResult, String> {
    let case = play::Case {
        walk,
        kind,
        rate,
        seed,
    };
    play::play(s, case, cfg, model, false).map(|(r, _)| r)
}

/// [`run_case`], and the candump log of every frame the bus delivered (the controller's, the
/// node's, a flood's), for `host-sim replay` or the QEMU image's player.
pub fn run_case_logged(
    s: &Scenario,
    kind: FaultKind,
    rate: f64,
    seed: u64,
) -> Result<(CaseResult, Vec<String>), String> {
    run_walk_logged(s, Walk::Plain, kind, rate, seed)
}

/// [`run_case_logged`] walked as `walk`.
pub fn run_walk_logged(
    s: &Scenario,
    walk: Walk,
    kind: FaultKind,
    rate: f64,
    seed: u64,
) -> Result<(CaseResult, Vec<String>), String> {
    let case = play::Case {
        walk,
        kind,
        rate,
        seed,
    };
    play::play(s, case, NodeConfig::hrp2(), &Model::hrp2(), true)
}
