//! The node inside the engine's loop: a straight walk commanded over the bus, the node polled
//! every 5 ms control cycle, its reference tracked by the stabilizer at 1 ms, and the robot's
//! state estimate sent back to the node as `MEASURED` frames, so that the node can move the
//! next landing when the robot is pushed.
//!
//! # The loop
//!
//! At control cycle `k` the node is polled and gives the reference `r_k`; the 1 ms physics
//! ticks of the next 5 ms track the linear interpolation from `r_{k−1}` to `r_k` (one cycle of
//! delay, as on a robot whose controller acts on the newest reference). After those ticks the
//! estimator sends the stabilizer's sensor-only DCM deviation `ξ − ξ_ref` (COG from the
//! encoders, anchored at the soles' targets of the leg odometry, velocity filtered; see [`super::stabilizer`]) against
//! `r_k`, stamped with the node cycle that produced `r_k`: one cycle old when the node reads
//! it, within its `max_age`.
//!
//! # The three configurations
//!
//! * [`Stepping::Fixed`]: `Start`: the node walks the commanded steps; the stabilizer alone
//!   keeps the robot up;
//! * [`Stepping::Plain`]: `StartAdjusting` with the plain re-plan: no single-support
//!   adjustment (eq. 18 off: `adjust_min_ticks = adjust_max_ticks = 0`) and no shaping;
//! * [`Stepping::Proposed`]: `StartAdjusting` with the paper's method (eq. 18 and the
//!   shaping, the robot file's settings).
//!
//! A run stands [`PhysicsConfig::settle_s`] before the commands, walks until the node stands
//! again (its reference then stops moving), and goes on [`PhysicsConfig::tail_s`] after that.
//! A fall ([`super::metrics::fall_check`]) counts until
//! [`super::metrics::SETTLE_AFTER_S`] after the node stands, as in every engine run
//! ([`super::metrics::fall_counts`]); a later one (with a tail longer than that) is reported
//! apart (`fell_after_end`). A walk that does not stand within the run says so (`stood_s`
//! `None`).

use std::collections::VecDeque;

use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{Adjust, ControlOp, Measured, RawFrame, Session, StepBook};

use super::bridge::Engine;
use super::metrics::{fall_check, fall_counts};
use super::model::sensor;
use super::stabilizer::Stabilizer;
use super::{initial_pose, quat_to_mat, reference_at, PhysicsConfig, PHYSICS_DT};
use crate::robot::model::Pose;
use crate::scenario::wire::Controller;

/// How the node may change the steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stepping {
    /// The commanded steps (`Start`): the stabilizer alone.
    Fixed,
    /// Step adjustment with the plain re-plan (no eq. 18, no shaping).
    Plain,
    /// Step adjustment with the proposed method (eq. 18 and the shaping).
    Proposed,
}

impl Stepping {
    /// All three, in the order of the push map.
    pub const ALL: [Stepping; 3] = [Stepping::Fixed, Stepping::Plain, Stepping::Proposed];

    /// The name in `push_map.json`.
    pub fn name(self) -> &'static str {
        match self {
            Stepping::Fixed => "stabilizer_only",
            Stepping::Plain => "plain",
            Stepping::Proposed => "proposed",
        }
    }

    /// The node's configuration for this mode, from the robot's.
    pub fn node_config(self, base: &NodeConfig) -> NodeConfig {
        let mut cfg = *base;
        if self == Stepping::Plain {
            cfg.params.adjust_min_ticks = 0;
            cfg.params.adjust_max_ticks = 0;
            cfg.params.shaping = false;
        }
        cfg
    }
}

/// When in the walk a push comes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PushPhase {
    /// At the start of the double support after the second landing.
    Double,
    /// At the third lift-off.
    SingleStart,
    /// In the middle of the third single support (the push centred on it).
    SingleMiddle,
    /// Ending with the third single support.
    SingleEnd,
}

impl PushPhase {
    /// All four, in the order of the push map.
    pub const ALL: [PushPhase; 4] = [
        PushPhase::Double,
        PushPhase::SingleStart,
        PushPhase::SingleMiddle,
        PushPhase::SingleEnd,
    ];

    /// The name in `push_map.json` and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PushPhase::Double => "double",
            PushPhase::SingleStart => "single_start",
            PushPhase::SingleMiddle => "single_middle",
            PushPhase::SingleEnd => "single_end",
        }
    }

    /// The phase named `s`.
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == s)
    }
}

/// A horizontal push: when, in which direction, and what it does ([`PushKind`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PushSpec {
    /// When.
    pub phase: PushPhase,
    /// Direction in the walking frame \[deg\]: 0 forward, 90 to the left.
    pub direction_deg: f64,
    /// The push.
    pub kind: PushKind,
}

/// What a push does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PushKind {
    /// A force on the trunk's centre of mass for a time (the convention of push-recovery
    /// tests on hardware, IHMC's Atlas among them).
    Force {
        /// Force \[N\].
        force_n: f64,
        /// Duration \[s\].
        duration_s: f64,
    },
    /// The base's horizontal velocity set, at one instant, to `v_mps` in the push's direction,
    /// everything else of the state unchanged (the convention of learning-based locomotion
    /// benchmarks: the floating base's linear velocity overwritten).
    Velocity {
        /// The base's horizontal speed after the push \[m/s\].
        v_mps: f64,
    },
}

impl PushKind {
    /// How long the push acts \[s\] (0 for a velocity set at one instant).
    pub fn duration_s(&self) -> f64 {
        match self {
            PushKind::Force { duration_s, .. } => *duration_s,
            PushKind::Velocity { .. } => 0.0,
        }
    }
}

/// The commanded walk: `steps` straight steps of `length` \[m\] from the robot's stance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walk {
    /// Number of steps (the last one closes the stance).
    pub steps: u16,
    /// Step length \[m\].
    pub length: f64,
}

impl Default for Walk {
    fn default() -> Self {
        Self {
            steps: 8,
            length: 0.15,
        }
    }
}

/// What a closed-loop run gives.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClosedOutcome {
    /// The robot fell (while walking or within [`super::metrics::SETTLE_AFTER_S`] after the
    /// node stood).
    pub fell: bool,
    /// When, from the first command \[s\].
    pub fall_time_s: Option<f64>,
    /// Why ([`super::metrics::FallCause::name`]).
    pub fall_cause: Option<&'static str>,
    /// Steps that landed away from where they were commanded (the node moved them).
    pub steps_adjusted: usize,
    /// The largest distance between a landing and its commanded position \[m\].
    pub max_shift_m: f64,
    /// Re-plans that started from the measured state (capture steps, with
    /// `AdjustConfig::from_measured`).
    pub replans_from_measured: usize,
    /// Every `ADJUST` the node sent.
    pub adjusts: Vec<Adjust>,
    /// Whether the push was applied (the walk reached its phase).
    pub pushed: bool,
    /// When the push began, from the first command \[s\].
    pub push_at_s: Option<f64>,
    /// The landings: time from the first command \[s\], commanded and landed (x, y) \[m\].
    pub landings: Vec<(f64, [f64; 2], [f64; 2])>,
    /// Simulated time from the first command \[s\].
    pub simulated_s: f64,
    /// When the engine reached the node's first standing reference after the walk (the
    /// reference stops there), from the first command \[s\] (`None`: the node did not stand
    /// within the run).
    pub stood_s: Option<f64>,
    /// The robot fell later than [`super::metrics::SETTLE_AFTER_S`] after the node stood (not
    /// counted in `fell`).
    pub fell_after_end: bool,
    /// When, from the first command \[s\].
    pub fall_after_end_time_s: Option<f64>,
    /// Every control cycle of the walk: time from the first command \[s\], the measured DCM
    /// deviation sent \[m\], and the node's shift \[m\].
    pub trace: Vec<(f64, [f64; 2], [f64; 2])>,
    /// Slip, flight, the CoP outside the support polygon and the landing error from the first
    /// command to the end of the run ([`super::gait`]).
    pub gait: super::gait::GaitQuality,
}

impl ClosedOutcome {
    /// The robot walked: no fall and the gait within its bounds ([`super::gait`]).
    pub fn walked(&self) -> bool {
        !self.fell && self.gait.within_bounds()
    }
}

/// An in-memory CAN device between the loop and the node.
#[derive(Default)]
struct Wire {
    rx: VecDeque<RawFrame>,
    tx: Vec<RawFrame>,
}

/// The in-memory device never fails.
#[derive(Debug)]
struct Never;

impl embedded_can::Error for Never {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl embedded_can::nb::Can for Wire {
    type Frame = RawFrame;
    type Error = Never;
    fn transmit(&mut self, f: &RawFrame) -> nb::Result<Option<RawFrame>, Never> {
        self.tx.push(*f);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<RawFrame, Never> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

/// The control cycle \[ms\].
const CYCLE_MS: u32 = 5;
/// Heartbeats every this many cycles (100 ms).
const HEARTBEAT_CYCLES: u32 = 20;
/// Which lift-off the single-support pushes follow (and which landing the double-support one).
const PUSHED_STEP: u32 = 3;

/// Runs `walk` of `robot` in MuJoCo with the node in the loop, stepping as `stepping` says,
/// pushed by `push`. Errors: the engine, the IK, or a command the node refused.
pub fn run(
    node_cfg: &NodeConfig,
    cfg: &PhysicsConfig,
    walk: Walk,
    stepping: Stepping,
    push: Option<PushSpec>,
) -> Result<ClosedOutcome, String> {
    let node_cfg = stepping.node_config(node_cfg);
    let mut node: Node<16> =
        Node::new(node_cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let p = node_cfg.params;
    let dt = p.dt;
    let mut wire = Wire::default();
    // The handshake: the node publishes its session, the controller opens it.
    let mut now = 0u32;
    node.poll(now, &mut wire);
    let session = wire
        .tx
        .drain(..)
        .find_map(|f| Session::decode(&f))
        .ok_or("the node published no session")?;
    let mut ctl = Controller {
        epoch: session.epoch,
        seq: session.last_seq,
    };
    wire.rx.push_back(ctl.control(ControlOp::Reset).encode());
    now += CYCLE_MS;
    node.poll(now, &mut wire);
    wire.tx.clear();
    ctl.epoch = ctl.epoch.wrapping_add(1);

    // The engine in the node's standing pose.
    let robot = cfg.robot.clone();
    let mut engine = Engine::start(&robot.mjcf())?;
    let mut stab = Stabilizer::new(robot.clone(), cfg.gains, PHYSICS_DT, cfg.z_c);
    let r0 = *node.gait().last();
    let (waist0, qpos) = initial_pose(&robot, &r0)?;
    let mut obs = engine.reset(&qpos)?;
    let mut sensed = super::sensors::Sensors::new(cfg.sensors);
    let mut monitor = super::gait::GaitMonitor::new(
        robot.total_mass() * robot.gravity(),
        [robot.sole_half()[0], robot.sole_half()[1]],
    );

    let settle_cycles = (cfg.settle_s / (f64::from(CYCLE_MS) * 1e-3)).round() as u32;
    let tail_cycles = (cfg.tail_s / (f64::from(CYCLE_MS) * 1e-3)).round() as u32;
    // Generous: the walk, the start and the stop, and the tail.
    let max_cycles = settle_cycles
        + tail_cycles
        + (u32::from(walk.steps) + 4) * (p.single_ticks + p.double_ticks)
        + p.start_ticks
        + p.settle_ticks
        + p.stand_ticks
        + 400;
    let mut commanded: Vec<(u16, [f64; 2])> = Vec::new();
    let mut out = ClosedOutcome::default();
    let (mut prev, mut swinging) = (r0, None);
    let (mut liftoffs, mut landings) = (0u32, 0u32);
    let mut push_start: Option<f64> = None;
    let mut walking_since: Option<u32> = None;
    let mut standing_since: Option<u32> = None;
    let t_ss = f64::from(p.single_ticks) * dt;
    for k in 0..max_cycles {
        if k == settle_cycles {
            // The walk: appends, then Start (or StartAdjusting) and Stop.
            let mut book = StepBook::new();
            let [left0, right0] = [node_cfg.left, node_cfg.right];
            for i in 0..walk.steps {
                let left = i % 2 == 1;
                let x0 = if left { left0.x } else { right0.x };
                let y = if left { left0.y } else { right0.y };
                let along = walk.length * f64::from(i + 1).min(f64::from(walk.steps - 1));
                let id = node.next_step().wrapping_add(i);
                let c = book
                    .append(id, left, x0 + along, y, 0.0)
                    .ok_or("a step of the walk does not fit the bus")?;
                wire.rx.push_back(c.encode_in(ctl.epoch));
                commanded.push((id, [x0 + along, y]));
            }
            let op = match stepping {
                Stepping::Fixed => ControlOp::Start,
                Stepping::Plain | Stepping::Proposed => ControlOp::StartAdjusting,
            };
            wire.rx.push_back(ctl.control(op).encode());
            wire.rx.push_back(ctl.control(ControlOp::Stop).encode());
            walking_since = Some(k);
        }
        if k % HEARTBEAT_CYCLES == 0 {
            wire.rx
                .push_back(ctl.control(ControlOp::Heartbeat).encode());
        }
        now += CYCLE_MS;
        let plans = node.gait().plans();
        node.poll(now, &mut wire);
        if node.gait().plans() != plans && node.gait().replanned_from_measured() {
            out.replans_from_measured += 1;
        }
        for f in wire.tx.drain(..) {
            if let Some(a) = Adjust::decode(&f) {
                out.adjusts.push(a);
            } else if let Some(a) = planner_core::wire::Ack::decode(&f) {
                if let Some(reason) = a.reason {
                    return Err(format!(
                        "the node refused command 0x{:02x}: {reason:?}",
                        a.command
                    ));
                }
            }
        }
        let reference = *node.gait().last();
        let stamp = node.cycles();
        let t_walk = walking_since.map(|s| f64::from(k - s) * f64::from(CYCLE_MS) * 1e-3);
        // Lift-offs and landings: where the push goes, and where each step landed.
        let s = node.gait().swinging();
        if s.is_some() && s != swinging {
            liftoffs += 1;
            if liftoffs == PUSHED_STEP {
                if let (Some(push), Some(t)) = (push, t_walk) {
                    let offset = match push.phase {
                        PushPhase::SingleStart => Some(0.0),
                        PushPhase::SingleMiddle => Some(0.5 * (t_ss - push.kind.duration_s())),
                        PushPhase::SingleEnd => Some(t_ss - push.kind.duration_s()),
                        PushPhase::Double => None,
                    };
                    if let Some(o) = offset {
                        push_start = Some(t + o.max(0.0));
                    }
                }
            }
        }
        if let (Some(id), None) = (swinging, s) {
            landings += 1;
            if landings == PUSHED_STEP - 1 {
                if let (Some(push), Some(t)) = (push, t_walk) {
                    if push.phase == PushPhase::Double {
                        push_start = Some(t);
                    }
                }
            }
            if let Some(&(_, c)) = commanded.iter().find(|c| c.0 == id) {
                let side = usize::from(c[1] < 0.5 * (node_cfg.left.y + node_cfg.right.y));
                let f = node.gait().feet()[side];
                let d = (f.x - c[0]).hypot(f.y - c[1]);
                out.max_shift_m = out.max_shift_m.max(d);
                out.steps_adjusted += usize::from(d > 1e-6);
                out.landings.push((t_walk.unwrap_or(0.0), c, [f.x, f.y]));
            }
        }
        swinging = s;
        // Five physics ticks toward the new reference.
        let pair = [prev, reference];
        for j in 0..5 {
            let r = reference_at(
                &pair,
                f64::from(CYCLE_MS) * 1e-3,
                (j + 1) as f64 * PHYSICS_DT,
            );
            let ctrl = stab.step(&r, sensed.read(&obs.sensors))?;
            let mut wrench = [0.0; 6];
            if let (Some(push), Some(t0), Some(t)) = (push, push_start, t_walk) {
                let t = t + (j as f64) * PHYSICS_DT;
                let a = push.direction_deg.to_radians();
                match push.kind {
                    PushKind::Force {
                        force_n,
                        duration_s,
                    } if t >= t0 && t < t0 + duration_s => {
                        wrench[0] = force_n * a.cos();
                        wrench[1] = force_n * a.sin();
                        out.pushed = true;
                        out.push_at_s.get_or_insert(t0);
                    }
                    PushKind::Velocity { v_mps } if t >= t0 && !out.pushed => {
                        engine.set_base_velocity([v_mps * a.cos(), v_mps * a.sin()])?;
                        out.pushed = true;
                        out.push_at_s.get_or_insert(t0);
                    }
                    _ => {}
                }
            }
            obs = engine.step(1, &ctrl, wrench)?;
            if t_walk.is_some() {
                let mut q = [[0.0; 6]; 2];
                for (i, leg) in q.iter_mut().enumerate() {
                    leg.copy_from_slice(
                        &obs.sensors[sensor::QPOS + 6 * i..sensor::QPOS + 6 * i + 6],
                    );
                }
                let base = Pose {
                    p: obs.base_pos,
                    r: quat_to_mat(obs.base_quat),
                };
                let (soles, _, _) = robot.fk(&base, &q);
                monitor.push(&super::gait::GaitSample {
                    dt: PHYSICS_DT,
                    feet_ref: r.feet,
                    soles,
                    sole_force: obs.sole_force,
                    normal_force: obs.normal_force,
                    cop: obs.cop,
                });
                out.gait = monitor.quality();
            }
            if let Some(cause) = fall_check(
                obs.base_quat,
                obs.base_pos[2],
                waist0.p[2],
                obs.other_contact,
            ) {
                let t = t_walk.map(|t| t + (j + 1) as f64 * PHYSICS_DT);
                out.simulated_s = t.unwrap_or(0.0);
                match (out.stood_s, t) {
                    (Some(stood), Some(t)) if !fall_counts(t, stood) => {
                        out.fell_after_end = true;
                        out.fall_after_end_time_s = Some(t);
                    }
                    _ => {
                        out.fall_cause = Some(cause.name());
                        out.fell = true;
                        out.fall_time_s = t;
                    }
                }
                return Ok(out);
            }
        }
        prev = reference;
        // The estimator: the DCM deviation against the reference just tracked; beyond the
        // node's plausible deviation the robot has fallen, and the estimator sends nothing.
        let e = stab.internals.dcm_error;
        let plausible = e[0].hypot(e[1]) <= node.config().adjust.max_deviation;
        if let Some(m) = Measured::from_si(stamp, e).filter(|_| plausible) {
            wire.rx.push_back(m.encode(ctl.epoch));
        }
        out.simulated_s = t_walk.unwrap_or(0.0) + f64::from(CYCLE_MS) * 1e-3;
        if let Some(t) = t_walk {
            let shift = node
                .shift()
                .map(|v| f64::from(v) * planner_core::wire::STEP_UNIT);
            out.trace.push((t, e, shift));
        }
        // The end: standing again for the tail.
        if walking_since.is_some() && liftoffs > 0 && node.gait().is_standing() {
            let since = *standing_since.get_or_insert(k);
            // The engine reached the first standing reference at the end of this cycle.
            if let Some(t) = t_walk {
                out.stood_s.get_or_insert(t + f64::from(CYCLE_MS) * 1e-3);
            }
            if k - since >= tail_cycles {
                break;
            }
        } else {
            standing_since = None;
            out.stood_s = None;
        }
    }
    Ok(out)
}
