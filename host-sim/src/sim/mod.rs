//! The simulation over the virtual CAN link: a controller (the scenario's timeline) on port 0,
//! the node (the same `planner_core::node::Node` as the firmware) on port 1.
//!
//! First the handshake's cycle (bus time 0 … 5 ms): the node's first poll publishes its
//! session (`SESSION`), the controller reads it and sends the `Reset` that opens it, with the
//! commands of tick 0. Then per 5 ms tick `k` (bus time `t_k = 5(k + 1) ms`):
//! 1. the controller sends the commands due at tick `k` (and a heartbeat every 100 ms);
//! 2. the bus runs to `t_k + 2.5 ms` and the node polls (handles what arrived, advances the
//!    gait by one tick, publishes the reference and its answers);
//! 3. the bus runs to `t_{k+1}` and the controller reads the answers and the stream.
//!
//! The trajectory is the node's reference at full precision; the stream decoded by the
//! controller (1 µm units) is kept to check the link.
//!
//! What became of every command ([`outcomes`]): carried out, refused by the node (the
//! [`Reason`] of its answer), never answered, or accepted and never carried out (a footstep
//! not walked at its accepted pose: the run ended with it still queued or being swung, it was
//! dropped without the scenario's own `stop_now`, or it landed elsewhere). A footstep dropped
//! by an accepted `stop_now` of the scenario counts as carried out: that is what the scenario
//! asked for. These are the names that a scenario file's `expect` key takes ([`Failure`]).
//!
//! Step ids: a scenario's footstep ids are the node's step numbers ([`WireId`](crate::scenario::WireId), 0 …
//! [`MAX_WIRE_ID`](crate::scenario::MAX_WIRE_ID)); the TOML reader refuses an id that does not fit, naming the entry, and
//! [`simulate`] refuses one too for scenarios built in code.

pub mod bus;
pub mod entropy;
pub mod pushed;
pub mod replay;
pub mod report;
#[cfg(feature = "socketcan")]
pub mod socketcan;
pub mod worst;

use planner_core::gait::{Footstep, Reference, Side};
use planner_core::node::{Broken, Counters, Node, NodeConfig};
use planner_core::wire::{self, Ack, ControlOp, RawFrame, Reason, StepBook, Stream};

use crate::scenario::expect::{limit_text, reason_name};
use crate::scenario::wire::{encode, Controller};
use crate::scenario::{self, Adjustment, Event, Failure, Run, Scenario};
use bus::{Bus, BusStats, Faults};

use embedded_can::nb::Can;

/// Simulation settings.
#[derive(Clone, Copy, Debug)]
pub struct SimConfig {
    /// The node's configuration.
    pub node: NodeConfig,
    /// Bitrate \[bit/s\].
    pub bitrate: u32,
    /// Faults on the bus.
    pub faults: Faults,
    /// Seed of the fault generator.
    pub seed: u64,
    /// Record a candump log.
    pub record: bool,
    /// The controller sends a heartbeat every this many ticks (0: never).
    pub heartbeat_ticks: u64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            node: NodeConfig::hrp2(),
            bitrate: 1_000_000,
            faults: Faults::default(),
            seed: 1,
            record: true,
            heartbeat_ticks: 20,
        }
    }
}

/// What became of a footstep id the controller appended, as the node's gait showed it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fate {
    /// Never queued (every append of it refused or unanswered).
    Unseen,
    /// Queued when the run ended.
    Queued,
    /// Being swung when the run ended.
    Swinging,
    /// Walked: landed in control cycle `tick` at `pose` (the gait's pose of that foot).
    Landed {
        /// The control cycle of the landing.
        tick: u64,
        /// Where the foot landed.
        pose: Footstep<f64>,
    },
    /// Left the queue in control cycle `tick` without being swung.
    Dropped {
        /// The control cycle.
        tick: u64,
    },
}

/// What a simulation produced.
#[derive(Clone, Debug)]
pub struct SimRun {
    /// Trajectory, events (the node's answers) and adjustments, as for [`scenario::run`].
    pub run: Run,
    /// The stream as the controller decoded it, one per tick (the last values received).
    pub stream: Vec<Stream>,
    /// Every answer the controller received, with its tick.
    pub acks: Vec<(u64, Ack)>,
    /// The candump log.
    pub can_log: Vec<String>,
    /// Fraction of the time the bus was busy.
    pub bus_load: f64,
    /// Bus counters.
    pub bus: BusStats,
    /// The node's counters at the end.
    pub counters: Counters,
    /// What became of every footstep id the controller appended, in the order first sent.
    pub steps: Vec<(u16, Fate)>,
    /// `true` if the run ended at the scenario's `max_ticks` rather than standing after its
    /// last command.
    pub cut: bool,
    /// For every event of `run.events`: the reach limit the node's check found broken for
    /// its footstep in the cycle it was handled (`Node::reach_broken`, asked right after that
    /// cycle), `None` for other commands and for footsteps within reach.
    pub broken: Vec<Option<Broken<f64>>>,
    /// The node's next step number when the scenario's first command was sent (its first
    /// append's number; every accepted append adds one).
    pub first_step: u16,
}

/// Ticks between two frames of a velocity stream (50 ms: five of them within the node's
/// 250 ms stream timeout).
pub const STREAM_TICKS: u64 = 10;

fn send(port: &mut crate::sim::bus::Port, f: RawFrame) {
    // The mailbox holds 64 frames; a scenario never sends that many in one tick.
    let _ = port.transmit(&f);
}

/// The session handshake on a virtual bus at time 0: the node's first cycle (at 2.5 ms)
/// publishes its session epoch, the controller reads it and sends the `Reset` that opens the
/// next session (it reaches the node with whatever the caller sends before the next poll).
/// Returns the controller in that new session; the bus stands at 5 ms.
pub(crate) fn handshake<const Q: usize>(
    bus: &Bus,
    node: &mut Node<Q>,
    ctl: &mut bus::Port,
    nport: &mut bus::Port,
) -> Controller {
    let ms = 1_000_000u64;
    bus.advance(0);
    bus.advance(5 * ms / 2);
    node.poll(2, nport);
    bus.advance(5 * ms);
    let mut c = Controller::default();
    while let Ok(f) = ctl.receive() {
        if let Some(session) = wire::Session::decode(&f) {
            c = Controller {
                epoch: session.epoch,
                seq: session.last_seq,
            };
        }
    }
    send(ctl, c.control(ControlOp::Reset).encode());
    c.epoch = c.epoch.wrapping_add(1);
    c
}

/// The node's configuration for a run of `s`: `node`, standing where the scenario's feet
/// start ([`Scenario::start_feet`]).
pub fn start_config(s: &Scenario, node: &NodeConfig) -> NodeConfig {
    let [left, right] = s.start_feet(node.params.step_width);
    NodeConfig {
        left,
        right,
        ..*node
    }
}

/// Plays a scenario through the virtual bus and the node (standing, at the start, where the
/// scenario's feet are: [`start_config`]).
pub fn simulate(s: &Scenario, cfg: &SimConfig) -> Result<SimRun, String> {
    let mut node: Node<64> = Node::new(start_config(s, &cfg.node))
        .map_err(|e| format!("node start-up failed: {e:?}"))?;
    let bus = Bus::new(cfg.bitrate, 2, cfg.faults, cfg.seed);
    if cfg.record {
        bus.record();
    }
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let mut trajectory = vec![*node.gait().last()];
    let mut stream = Stream::default();
    let mut streams = vec![stream];
    let mut acks = Vec::new();
    let mut events = Vec::new();
    let mut adjustments = Vec::new();
    let mut footsteps: Vec<(u16, planner_core::gait::Footstep<f64>)> = Vec::new();
    let mut book = StepBook::new();
    let mut steps: Vec<(u16, Side, Fate)> = Vec::new();
    let mut cut = true;
    let mut broken = Vec::new();
    let mut next = 0;
    let mut last_replan = None;
    let last_command = s.timeline.last().map(|(t, _)| *t).unwrap_or(0);
    let ms = 1_000_000u64;
    // The handshake, 5 ms before the scenario's tick 0; the `Reset` goes out with tick 0's
    // commands, which are in the session it opens.
    let mut ctl_state = handshake(&bus, &mut node, &mut ctl, &mut nport);
    let first_step = node.next_step();
    // The velocity the controller streams (every `STREAM_TICKS`), and when it last sent it.
    let mut streaming: Option<(f64, f64, f64)> = None;
    let mut streamed_at = 0u64;
    let mut heartbeat_due = false;
    for k in 0..s.max_ticks {
        let t0 = (k + 1) * 5 * ms;
        bus.advance(t0);
        // A `VELOCITY` or `GOAL` sent in this tick (then no heartbeat: see below).
        let mut drove = false;
        while next < s.timeline.len() && s.timeline[next].0 <= k {
            let (_, command) = s.timeline[next];
            let wire = encode(command, &mut ctl_state, &mut book)?;
            drove |= command.drives();
            if let scenario::Command::Push(id, f) = command {
                if !steps.iter().any(|(i, _, _)| *i == id) {
                    steps.push((id, f.side, Fate::Unseen));
                }
            }
            send(&mut ctl, wire.encode_in(ctl_state.epoch));
            match command {
                scenario::Command::Velocity(vx, vy, wz) => {
                    streaming = Some((vx, vy, wz));
                    streamed_at = k;
                }
                scenario::Command::Goal(..) => streaming = None,
                _ => {}
            }
            events.push((k, command, wire));
            broken.push(None);
            next += 1;
        }
        // A stick streams: the velocity in force again, every 50 ms, with a new number (a
        // repeat proves nothing).
        if let Some((vx, vy, wz)) = streaming {
            if k >= streamed_at + STREAM_TICKS {
                let f = ctl_state.velocity(vx, vy, wz).encode_in(ctl_state.epoch);
                send(&mut ctl, f);
                streamed_at = k;
                drove = true;
            }
        }
        // (Arbitration delivers a cycle's `CONTROL` before its `VELOCITY` or `GOAL`, whatever
        // the order of sending: a heartbeat numbered after one would make it stale, so it
        // waits for the next cycle.)
        heartbeat_due |= cfg.heartbeat_ticks > 0 && k % cfg.heartbeat_ticks == 0;
        if heartbeat_due && !drove {
            heartbeat_due = false;
            // A new sequence number for every heartbeat (a repeat proves nothing).
            send(&mut ctl, ctl_state.control(ControlOp::Heartbeat).encode());
        }
        bus.advance(t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let report = node.poll(now_ms, &mut nport);
        // Which limit each footstep of this cycle breaks, in the state the node left.
        for (e, b) in events
            .iter()
            .zip(broken.iter_mut())
            .filter(|(e, _)| e.0 == k)
        {
            *b = match e.1 {
                scenario::Command::Push(_, f) => node.reach_broken(&f, None),
                scenario::Command::Modify(id, f) => node.reach_broken(&f, Some(id)),
                _ => None,
            };
        }
        trajectory.push(report.reference);
        track_steps(node.gait(), k, &mut steps);
        if let Some(info) = node.gait().last_replan() {
            if last_replan != Some(info.tick) {
                last_replan = Some(info.tick);
                if info.adjust_ticks != 0 || info.ratio != 1.0 {
                    adjustments.push(Adjustment {
                        tick: info.tick,
                        adjust_s: f64::from(info.adjust_ticks) * cfg.node.params.dt,
                        ratio: info.ratio,
                        plane: info.plane,
                    });
                }
            }
        }
        bus.advance(t0 + 5 * ms);
        while let Ok(f) = ctl.receive() {
            if let Some(a) = Ack::decode(&f) {
                acks.push((k, a));
            } else {
                stream.decode_into(&f);
            }
        }
        streams.push(stream);
        if node.gait().is_standing() && k > last_command && next >= s.timeline.len() {
            cut = false;
            break;
        }
    }
    // Pair every command with its answer (first answer with the same code and sequence).
    let mut used = vec![false; acks.len()];
    let mut out_events = Vec::new();
    for (k, command, wire) in events {
        let code = wire.code();
        let key = wire.key();
        let found = acks.iter().enumerate().find(|(i, (t, a))| {
            !used[*i]
                && *t >= k
                && a.command == code
                && a.seq == key
                && a.echo == wire.echo_in(ctl_state.epoch)
        });
        let result = match found {
            Some((i, (_, a))) => {
                used[i] = true;
                match a.reason {
                    None => Ok(()),
                    Some(r) => Err(format!("{r:?}")),
                }
            }
            None => Err("no answer".to_string()),
        };
        if let (Ok(()), scenario::Command::Push(id, f) | scenario::Command::Modify(id, f)) =
            (&result, command)
        {
            if let Some(e) = footsteps.iter_mut().find(|(i, _)| *i == id) {
                e.1 = f;
            } else {
                footsteps.push((id, f));
            }
        }
        out_events.push(Event {
            tick: k,
            command,
            result,
        });
    }
    Ok(SimRun {
        run: Run {
            trajectory,
            events: out_events,
            adjustments,
            footsteps,
        },
        stream: streams,
        acks,
        can_log: bus.log(),
        bus_load: bus.load(),
        bus: bus.stats(),
        counters: *node.counters(),
        steps: steps.into_iter().map(|(id, _, f)| (id, f)).collect(),
        cut,
        broken,
        first_step,
    })
}

/// Follows every appended footstep through the gait after control cycle `k`.
fn track_steps(g: &planner_core::gait::Gait<f64, 64>, k: u64, steps: &mut [(u16, Side, Fate)]) {
    let swinging = g.swinging();
    for (id, side, fate) in steps.iter_mut() {
        let now = if swinging == Some(*id) {
            Some(Fate::Swinging)
        } else if g.is_queued(*id) {
            Some(Fate::Queued)
        } else {
            None
        };
        *fate = match (*fate, now) {
            (_, Some(f)) => f,
            (Fate::Swinging, None) => Fate::Landed {
                tick: k,
                pose: g.feet()[usize::from(*side == Side::Right)],
            },
            (Fate::Queued, None) => Fate::Dropped { tick: k },
            (f, None) => f,
        };
    }
}

/// What became of one command of the timeline.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The control cycle it was sent in.
    pub tick: u64,
    /// The command.
    pub command: scenario::Command,
    /// `None`: accepted and carried out.
    pub failure: Option<Failure>,
    /// What happened, in words (for a failure: why; otherwise empty, or a note such as a step
    /// dropped by the scenario's `stop_now`).
    pub detail: String,
}

/// Why an append numbered `id` is refused `bad_crc` by a node whose next step number is
/// `next` when `id` is not within −128 … +127 of it: the frame carries the number's low byte
/// only, the node reads it as the number with that low byte nearest its next one, and the
/// frame's CRC, keyed with the true number's high byte, does not match that one. The node
/// cannot tell this from a corrupted frame (`planner_core::wire`: every frame's CRC matches
/// exactly one high byte); the controller that numbered the step can.
pub fn out_of_window_text(id: u16, next: u16) -> String {
    format!(
        "step {id} is not the node's next step number ({next}): a footstep frame carries its \
         number's low byte, read within -128 … +127 of the next number (here as step {}), so \
         the CRC keyed with step {id}'s high byte fails; number the steps on from the next \
         one (DIAG next_step)",
        wire::step_number(id as u8, next)
    )
}

/// Same pose within the wire's resolution (0.5 mm, 2π/4096 rad) and some rounding.
fn same_pose(a: &Footstep<f64>, b: &Footstep<f64>) -> bool {
    let dyaw = (a.yaw - b.yaw + core::f64::consts::PI).rem_euclid(core::f64::consts::TAU)
        - core::f64::consts::PI;
    a.side == b.side && (a.x - b.x).abs() <= 5e-4 && (a.y - b.y).abs() <= 5e-4 && dyaw.abs() <= 2e-3
}

/// What became of every command of a run of `s` ([`simulate`]), in timeline order.
pub fn outcomes(s: &Scenario, sim: &SimRun) -> Vec<Outcome> {
    let dt = crate::scenario::TICK_S;
    let end_s = (sim.run.trajectory.len() - 1) as f64 * dt;
    let stop_now_at: Vec<u64> = sim
        .run
        .events
        .iter()
        .filter(|e| e.result.is_ok() && e.command == scenario::Command::StopNow)
        .map(|e| e.tick)
        .collect();
    // The node's next step number as each command reaches it: appends are numbered one after
    // another, so it is the first one plus the appends accepted before.
    let mut next_step = sim.first_step;
    sim.run
        .events
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let expected_step = next_step;
            if let (Ok(()), scenario::Command::Push(..)) = (&e.result, e.command) {
                next_step = next_step.wrapping_add(1);
            }
            let (failure, detail) = match (&e.result, e.command) {
                (Err(r), _) => match Reason::ALL.into_iter().find(|x| format!("{x:?}") == *r) {
                    Some(reason) => (
                        Some(Failure::Refused(reason)),
                        match (sim.broken.get(i).copied().flatten(), e.command) {
                            (Some(b), _) if matches!(reason, Reason::Reach | Reason::Crossing) => {
                                format!(
                                    "refused: {} (code {}): {}",
                                    reason_name(reason),
                                    reason.code(),
                                    limit_text(&b)
                                )
                            }
                            (_, scenario::Command::Push(id, _))
                                if reason == Reason::BadCrc
                                    && wire::step_number(id as u8, expected_step) != id =>
                            {
                                format!(
                                    "refused: {} (code {}): {}",
                                    reason_name(reason),
                                    reason.code(),
                                    out_of_window_text(id, expected_step)
                                )
                            }
                            _ => {
                                format!("refused: {} (code {})", reason_name(reason), reason.code())
                            }
                        },
                    ),
                    None => (
                        Some(Failure::NoAnswer),
                        format!("{r}: the node never answered"),
                    ),
                },
                (Ok(()), scenario::Command::Push(id, _) | scenario::Command::Modify(id, _)) => {
                    let wanted = sim
                        .run
                        .footsteps
                        .iter()
                        .find(|(i, _)| *i == id)
                        .map(|p| p.1);
                    let fate = sim
                        .steps
                        .iter()
                        .find(|(i, _)| *i == id)
                        .map_or(Fate::Unseen, |p| p.1);
                    step_outcome(fate, wanted, &stop_now_at, sim.cut, end_s, s.max_ticks, dt)
                }
                (Ok(()), _) => (None, String::new()),
            };
            Outcome {
                tick: e.tick,
                command: e.command,
                failure,
                detail,
            }
        })
        .collect()
}

fn step_outcome(
    fate: Fate,
    wanted: Option<Footstep<f64>>,
    stop_now_at: &[u64],
    cut: bool,
    end_s: f64,
    max_ticks: u64,
    dt: f64,
) -> (Option<Failure>, String) {
    let not = |why: String| {
        (
            Some(Failure::NotWalked),
            format!("accepted, never walked: {why}"),
        )
    };
    let pose = |f: &Footstep<f64>| format!("({:.4}, {:.4}) m, {:.4} rad", f.x, f.y, f.yaw);
    match fate {
        Fate::Landed { tick, pose: p } => match wanted {
            Some(w) if !same_pose(&p, &w) => (
                Some(Failure::NotWalked),
                format!(
                    "accepted, walked elsewhere: landed at {} at {:.3} s, the accepted pose is {}",
                    pose(&p),
                    tick as f64 * dt,
                    pose(&w)
                ),
            ),
            _ => (None, String::new()),
        },
        Fate::Dropped { tick } => match stop_now_at
            .iter()
            .rev()
            .find(|&&t| t <= tick && tick - t <= 1)
        {
            Some(&t) => (
                None,
                format!(
                    "dropped by the scenario's stop_now at {:.3} s",
                    t as f64 * dt
                ),
            ),
            None => not(format!(
                "dropped from the queue at {:.3} s without a stop_now of the scenario",
                tick as f64 * dt
            )),
        },
        Fate::Queued | Fate::Swinging if cut => not(format!(
            "{} when max_time_s ({:.3} s) ended the run",
            if fate == Fate::Queued {
                "still queued"
            } else {
                "still being swung"
            },
            max_ticks as f64 * dt
        )),
        Fate::Queued | Fate::Swinging => not(format!(
            "still queued when the run ended at {end_s:.3} s with the robot standing (no start \
             after it?)"
        )),
        Fate::Unseen => not("the node never queued it".into()),
    }
}

/// The reference trajectory a run published.
pub fn references(run: &SimRun) -> &[Reference<f64>] {
    &run.run.trajectory
}

/// The planner's trajectory for a scenario (built-in name or `.toml` file) through the virtual
/// CAN bus and `robot`'s node, and its tick \[s\]. A built-in scenario is drawn in the
/// robot's proportions ([`crate::robot::Robot::built_in`]).
pub fn scenario_trajectory(
    name: &str,
    robot: &crate::robot::Robot,
) -> Result<(String, Vec<planner_core::gait::Reference<f64>>, f64), String> {
    let s = if name.ends_with(".toml") {
        crate::scenario::file::load_file(std::path::Path::new(name))?.scenario
    } else {
        robot.built_in(name).ok_or_else(|| {
            format!(
                "unknown scenario {name:?}; built-in: {} (or a .toml file)",
                crate::scenario::BUILT_IN.join(", ")
            )
        })?
    };
    let cfg = SimConfig {
        node: robot.node_config(),
        ..SimConfig::default()
    };
    let dt = cfg.node.params.dt;
    let sim = simulate(&s, &cfg).map_err(|e| format!("{}: {e}", s.name))?;
    Ok((s.name.clone(), sim.run.trajectory, dt))
}
