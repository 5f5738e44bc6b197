//! The worst admissible control cycle, generated and recorded: the log that puts the most
//! work the node takes into one cycle (what its work budget, `planner_core::node::WORK_BUDGET`,
//! lets through), for the target's replay (the QEMU images), without a
//! physics engine.
//!
//! A straight walk of [`WALK_STEPS`] steps of [`STEP_M`] with HRP-2's node (`Node<16>`, the
//! images' queue), started with `start` or `start_adjusting`; the robot is the pushed walk's
//! pendulum ([`super::pushed`]), its estimator's `MEASURED` every cycle when adjusting, pushed
//! once as that walk is. In the cycle whose tick re-plans at the start of the
//! [`BURST_SUPPORT`]-th single support (found by a first run without the burst), the controller
//! sends, in one cycle:
//! * a modification of **every queued step** (distinct steps, each moved [`MOVE_M`] forward,
//!   each checked for reach against its neighbours and its two successors), the next swing
//!   target first (it plans the re-plan it causes, eq. 17: the node acts on it after the
//!   others, so that it plans once on the final landings, and the tick's re-plan, with eq. 18's
//!   adjustment, takes that plan);
//! * appends until the queue is full or the cycle holds the node's `max_rx` command frames (the
//!   estimator's `MEASURED` among them when adjusting);
//! * with the queue full, a newer version of later steps (one each), [`FAR_M`] forward: out
//!   of reach, refused after its check, and the older version then acted on;
//!
//! and the `stop` a cycle later. The paths ([`Path`]) load that cycle further: the burst in a
//! cycle that also sends the periodic reports ([`Path::Report`]); in a walk that adjusts, a
//! measured state in the burst that claims the largest plausible deviation, so that the step
//! adjustment's reach cut bisects to the footstep unit (10 halvings for the 0.30 m shift) and
//! eq. 17 checks the cut move ([`Path::Reach`]); and the same with
//! [`planner_core::node::AdjustConfig::from_measured`], the next swing target a capture step
//! (moved for a measured deviation in the cycles before), so that its lift-off plans from the
//! measured state on top of the step adjustment's eq. 17 ([`Path::Measured`]). The worst
//! admissible cycle is the worst over the paths. (Eq. 17 refusing the cut move, or the plan
//! from the measured state, which would plan once more, is not reached with HRP-2's node:
//! with claimed deviations of 0.05 to 0.9 m forward, backward, sideways and diagonally, and
//! (without the option) bursts from 1 to 150 cycles before the lift-off, eq. 17 held.)
//!
//! The burst is sent at the start of its cycle, as every
//! controller of host-sim sends (and as the replay rule, `planner_core::playback`, plays a
//! log): it holds as many frames as the bus carries before the poll (at most `max_rx`).
//! Appends go out before the modifications (the bus sends the lower identifier first). The start cycle is loaded too: the `start` comes with appends that
//! fill the queue.

mod drive;

pub use drive::{largest_change, GOAL_AHEAD, GOAL_REAIM, STREAM_CYCLES, WALK_V};

use planner_core::gait::Phase;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{ControlOp, Measured, RawFrame, StepBook};

use super::bus::{Bus, Faults};
use super::pushed::{Pendulum, PUSH_DELAY_TICKS};
use embedded_can::nb::Can;

/// The walk's steps appended before the start.
pub const WALK_STEPS: u16 = 8;
/// Their length \[m\].
pub const STEP_M: f64 = 0.1;
/// How far forward the burst moves every queued step \[m\].
pub const MOVE_M: f64 = 0.05;
/// How far forward the burst's out-of-reach versions move a step \[m\].
pub const FAR_M: f64 = 0.6;
/// The single support (counted from the first) whose start's re-plan meets the burst.
pub const BURST_SUPPORT: usize = 3;
/// The push (x, y) \[m/s\] of the adjusting walk.
pub const PUSH_DV: [f64; 2] = [0.2, 0.0];
/// The deviation \[m\] the measured state of [`Path::Reach`] and [`Path::Measured`] claims in
/// the burst: within the node's plausibility bound (`AdjustConfig::max_deviation`, 1.0 m), its
/// capture offset far beyond the largest shift (`max_shift`) and the reach.
pub const FAR_DEVIATION: [f64; 2] = [0.9, 0.0];
/// The deviation \[m\] the measured state of [`Path::Measured`] claims in the
/// [`CAPTURE_CYCLES`] cycles before the burst: the next swing target moves for it (a capture
/// step).
pub const CAPTURE_DEVIATION: [f64; 2] = [0.025, 0.0];
/// See [`CAPTURE_DEVIATION`].
pub const CAPTURE_CYCLES: u64 = 10;

/// A path through the node's cycle that the generator loads (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// `worst-start`: the burst in a walk started with `start`.
    Start,
    /// `worst-adjusting`: started with `start_adjusting`, the estimator's state every cycle
    /// and a push.
    Adjusting,
    /// `worst-report`: [`Path::Start`]'s burst in a cycle that sends the periodic reports
    /// (`STATUS`, `DIAG`, `SESSION`, `LINK`).
    Report,
    /// `worst-reach`: [`Path::Adjusting`], the burst's measured state claiming
    /// [`FAR_DEVIATION`] (the reach cut's whole bisection, then eq. 17's check), in a report
    /// cycle.
    Reach,
    /// `worst-measured`: [`Path::Reach`] with `AdjustConfig::from_measured`, the next swing
    /// target a capture step: its lift-off plans from the measured state after the step
    /// adjustment's eq. 17. (The QEMU images replay a log whose name ends in `-measured` with the
    /// option on.)
    Measured,
    /// `worst-velocity`: a walk the node drives at a velocity; in a report cycle that re-plans
    /// at a start of single support, the velocity the legs cut the most re-plans every queued
    /// step, in a burst of the other drive commands and footstep frames (`drive` module).
    Velocity,
    /// `worst-velocity-start`: the start from standing by that velocity, with the burst.
    VelocityStart,
    /// `worst-goal-start`: the start from standing by a `GOAL`, with the burst.
    GoalStart,
    /// `worst-goal`: a walk toward a goal, re-aimed behind the robot in the burst.
    Goal,
    /// `worst-resume`: the drive's own stop (a zero velocity) cancelled by the burst's
    /// velocity, the queue made up again by that command in the same cycle.
    Resume,
}

impl Path {
    /// Every path, in the order of the logs.
    pub const ALL: [Path; 10] = [
        Path::Start,
        Path::Adjusting,
        Path::Report,
        Path::Reach,
        Path::Measured,
        Path::Velocity,
        Path::VelocityStart,
        Path::GoalStart,
        Path::Goal,
        Path::Resume,
    ];

    /// The log's name.
    pub fn name(self) -> &'static str {
        match self {
            Path::Start => "worst-start",
            Path::Adjusting => "worst-adjusting",
            Path::Report => "worst-report",
            Path::Reach => "worst-reach",
            Path::Measured => "worst-measured",
            Path::Velocity => "worst-velocity",
            Path::VelocityStart => "worst-velocity-start",
            Path::GoalStart => "worst-goal-start",
            Path::Goal => "worst-goal",
            Path::Resume => "worst-resume",
        }
    }

    /// The path of the log `name`.
    pub fn named(name: &str) -> Option<Path> {
        Path::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The walk is started with `start_adjusting` (the estimator's state every cycle).
    pub fn adjusting(self) -> bool {
        matches!(self, Path::Adjusting | Path::Reach | Path::Measured)
    }

    /// The burst comes in a cycle that sends the periodic reports.
    pub fn report(self) -> bool {
        !matches!(self, Path::Start | Path::Adjusting)
    }

    /// The node drives the walk (`VELOCITY`, `GOAL`): the footstep frames are refused.
    pub fn drives(self) -> bool {
        matches!(
            self,
            Path::Velocity | Path::VelocityStart | Path::GoalStart | Path::Goal | Path::Resume
        )
    }

    /// The node's configuration for the path: `base`, with `from_measured` for
    /// [`Path::Measured`].
    pub fn config(self, base: &NodeConfig) -> NodeConfig {
        let mut cfg = *base;
        cfg.adjust.from_measured = self == Path::Measured;
        cfg
    }
}

/// What a worst-cycle run gave.
#[derive(Clone, Debug)]
pub struct WorstRun {
    /// The path generated.
    pub path: Path,
    /// The node's configuration.
    pub cfg: NodeConfig,
    /// The bus, as candump lines (`sim::bus::log_line`).
    pub can_log: Vec<String>,
    /// The cycle of the burst (counted from the scenario's tick 0).
    pub burst_tick: u64,
    /// Command frames sent for that cycle: modifications of distinct steps, newer
    /// out-of-reach versions, appends, the measured state (a drive path: the drive command
    /// accepted, the drive commands refused, the footstep frames, the others).
    pub burst: (usize, usize, usize, usize),
    /// Whether the node re-planned in the burst cycle.
    pub replanned: bool,
    /// Whether that re-plan started from the measured state (`from_measured`).
    pub from_measured: bool,
    /// Walking windows the node planned in the burst cycle (`Gait::walk_plans`: eq. 17's
    /// check and the re-plan, which takes the checked plan when nothing changed after it).
    pub plans: u32,
    /// Frames of the burst the node refused (the out-of-reach versions, and `Busy` what its
    /// work budget leaves out).
    pub refused: u8,
    /// Frames the node received in the burst cycle.
    pub received: u8,
    /// The burst cycle sent the periodic reports.
    pub report: bool,
    /// `ADJUST`'s flags after the burst cycle (reach limited, ZMP limited, fresh); a drive
    /// path: the cut mask of the velocity in force (`Saturation::mask`).
    pub adjust_flags: u8,
    /// Moves of the steps the step adjustment worked on in the burst cycle.
    pub adjust_attempts: u32,
    /// The pendulum fell.
    pub fallen: bool,
}

impl WorstRun {
    /// A run of `path` with the node `cfg` and its burst at cycle `burst` (if any), before
    /// anything is recorded.
    fn new(path: Path, cfg: &NodeConfig, burst: Option<u64>) -> Self {
        Self {
            path,
            cfg: *cfg,
            can_log: Vec::new(),
            burst_tick: burst.unwrap_or(0),
            burst: (0, 0, 0, 0),
            replanned: false,
            from_measured: false,
            plans: 0,
            refused: 0,
            received: 0,
            report: false,
            adjust_flags: 0,
            adjust_attempts: 0,
            fallen: false,
        }
    }
}

/// The generator of the module docs, for the path `path` with the node `base` (its
/// configuration [`Path::config`]).
pub fn worst_cycle(base: &NodeConfig, path: Path) -> Result<WorstRun, String> {
    let cfg = &path.config(base);
    if path.drives() {
        return drive::worst_drive(cfg, path);
    }
    let (at, lead) = burst_cycle(cfg, path, run, path.report())?;
    largest_burst(cfg, path, at, lead, run)
}

/// The cycle of the burst: the poll that re-plans at the start of single support
/// [`BURST_SUPPORT`], found by a first run without the burst (and the node's count of cycles
/// then); in a report cycle if `report`, the walk started as many cycles later (`lead`) as
/// that takes. Returns the cycle and the lead.
fn burst_cycle(cfg: &NodeConfig, path: Path, run: Run, report: bool) -> Result<(u64, u64), String> {
    let replan = |lead: u64| -> Result<(u64, u32), String> {
        let probe = run(cfg, path, None, 0, lead)?;
        probe
            .1
            .get(BURST_SUPPORT.saturating_sub(1))
            .copied()
            .ok_or_else(|| "the walk has too few single supports".into())
    };
    let (mut at, cycle) = replan(0)?;
    let lead = if report {
        u64::from((21 - cycle % 20) % 20)
    } else {
        0
    };
    if lead > 0 {
        at = replan(lead)?.0;
    }
    Ok((at, lead))
}

/// One run of a path: `burst` the cycle of the burst, `cap` its frames, `lead` the cycles by
/// which the start is delayed; the run and the cycles whose poll re-planned at a start of
/// single support.
type Run =
    fn(&NodeConfig, Path, Option<u64>, usize, u64) -> Result<(WorstRun, Vec<(u64, u32)>), String>;

/// The run with as many command frames in the burst at cycle `at` as reach the poll (the
/// node's `max_rx` at most).
fn largest_burst(
    cfg: &NodeConfig,
    path: Path,
    at: u64,
    lead: u64,
    run: Run,
) -> Result<WorstRun, String> {
    for cap in (1..=cfg.max_rx).rev() {
        let (out, _) = run(cfg, path, Some(at), cap, lead)?;
        let (m, v, a, e) = out.burst;
        if usize::from(out.received) == m + v + a + e {
            return Ok(out);
        }
    }
    Err("no burst reaches the poll".into())
}

/// The node of a run (HRP-2's 16-step queue) on a recorded 1 Mbit/s bus of two ports.
fn open(cfg: &NodeConfig) -> Result<(Node<16>, Bus), String> {
    let node = Node::new(*cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let bus = Bus::new(1_000_000, 2, Faults::default(), 1);
    bus.record();
    Ok((node, bus))
}

/// One run; `burst`: the cycle of the burst, `lead`: cycles by which the start is delayed.
/// Returns the run and the cycles whose poll re-planned at the start of a single support
/// (with the node's count of cycles after it).
fn run(
    cfg: &NodeConfig,
    path: Path,
    burst: Option<u64>,
    cap: usize,
    lead: u64,
) -> Result<(WorstRun, Vec<(u64, u32)>), String> {
    let adjusting = path.adjusting();
    let (mut node, bus) = open(cfg)?;
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let ms = 1_000_000u64;
    let mut c = crate::sim::handshake(&bus, &mut node, &mut ctl, &mut nport);
    let mut book = StepBook::new();
    // The controller's steps: (wire id, left, x, y), in order.
    let mut steps: Vec<(u16, bool, f64, f64)> = Vec::new();
    let first_id = node.next_step();
    let epoch = c.epoch;
    let append = |book: &mut StepBook, steps: &mut Vec<(u16, bool, f64, f64)>, dx: f64| {
        let i = steps.len() as u16;
        let left = i % 2 == 1;
        let foot = if left { cfg.left } else { cfg.right };
        let x = steps.last().map_or(foot.x, |s| s.2) + STEP_M + dx;
        let id = first_id.wrapping_add(i);
        let command = book.append(id, left, x, foot.y, 0.0)?;
        steps.push((id, left, x, foot.y));
        Some(command.encode_in(epoch))
    };
    let mut first = Vec::new();
    for _ in 0..WALK_STEPS {
        first.push(append(&mut book, &mut steps, 0.0).ok_or("a step does not fit the bus")?);
    }
    let op = if adjusting {
        ControlOp::StartAdjusting
    } else {
        ControlOp::Start
    };
    let p = cfg.params;
    let mut robot = Pendulum::at(node.gait().last());
    let mut out = WorstRun::new(path, cfg, burst);
    let mut replans = Vec::new();
    let mut last_replan = None;
    let (mut swinging, mut liftoffs, mut push_at) = (None, 0u32, None);
    let mut tracked: Option<(u32, [f64; 2])> = None;
    // The gait's id of the controller's first step (known once it is queued).
    let mut gid0: Option<u16> = None;
    for k in 0..4000u64 {
        let t0 = (k + 1) * 5 * ms;
        bus.advance(t0);
        let mut frames: Vec<RawFrame> = Vec::new();
        if k == 0 {
            frames.extend(first.iter().copied());
        }
        if k == 1 + lead {
            // The start, with appends that fill the queue.
            frames.push(c.control(op).encode());
            let room = 16usize
                .saturating_sub(node.gait().queued())
                .min(cfg.max_rx - 1);
            for _ in 0..room {
                frames.push(append(&mut book, &mut steps, 0.0).ok_or("append")?);
            }
        }
        if k % 20 == 0 && Some(k) != burst {
            frames.push(c.control(ControlOp::Heartbeat).encode());
        }
        if burst.is_some_and(|b| k == b + 1) {
            frames.push(c.control(ControlOp::Stop).encode());
        }
        // The estimator's state: the robot's, or what the path claims.
        let claimed = match burst {
            Some(b) if k == b && matches!(path, Path::Reach | Path::Measured) => {
                Some(FAR_DEVIATION)
            }
            Some(b) if path == Path::Measured && k < b && k + CAPTURE_CYCLES >= b => {
                Some(CAPTURE_DEVIATION)
            }
            _ => None,
        };
        let measured = if adjusting {
            tracked.and_then(|(stamp, e)| Measured::from_si(stamp, claimed.unwrap_or(e)))
        } else {
            None
        };
        if let Some(m) = measured {
            frames.push(m.encode(c.epoch));
        }
        if Some(k) == burst {
            let g = node.gait();
            let (Some(front), Some(g0)) = (g.next_target(), gid0) else {
                return Err("nothing queued at the burst".into());
            };
            let queued = g.queued();
            let mut burst_frames = Vec::new();
            let slots = cap.min(cfg.max_rx) - usize::from(adjusting);
            let from = usize::from(front.wrapping_sub(g0));
            let mods: Vec<usize> = (from..steps.len()).take(queued.min(slots)).collect();
            let room = 16usize.saturating_sub(queued).min(slots - mods.len());
            // Every step from the front on moves forward, the appends after them too.
            for _ in 0..room {
                burst_frames.push(append(&mut book, &mut steps, MOVE_M).ok_or("append")?);
            }
            for &i in &mods {
                let (id, _, x, y) = steps[i];
                let m = book.modify(id, x + MOVE_M, y, 0.0).ok_or("modify")?;
                burst_frames.push(m.encode_in(c.epoch));
            }
            // The frames left: a newer version of a later step, out of reach (refused after
            // its reach check; the older one then has its turn).
            let extra = slots - mods.len() - room;
            for &i in mods.iter().skip(1).cycle().take(extra) {
                let (id, _, x, y) = steps[i];
                let m = book.modify(id, x + FAR_M, y, 0.0).ok_or("modify")?;
                burst_frames.push(m.encode_in(c.epoch));
            }
            out.burst = (mods.len(), extra, room, usize::from(adjusting));
            frames.extend(burst_frames);
        }
        for f in &frames {
            let _ = ctl.transmit(f);
        }
        bus.advance(t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let plans = node.gait().walk_plans();
        let attempts = node.adjustment_attempts();
        let report = node.poll(now_ms, &mut nport);
        if gid0.is_none() {
            gid0 = node.gait().next_target();
        }
        let replan = node.gait().last_replan().map(|r| r.tick);
        if replan != last_replan {
            last_replan = replan;
            if matches!(report.reference.phase, Phase::Single(_)) {
                replans.push((k, node.cycles()));
            }
        }
        if Some(k) == burst {
            out.replanned = replans.last().map(|r| r.0) == Some(k);
            out.report = node.cycles() % 20 == 1;
            out.adjust_flags = node.adjustment().flags;
            out.adjust_attempts = node.adjustment_attempts().wrapping_sub(attempts);
            out.from_measured = node.gait().replanned_from_measured();
            out.plans = node.gait().walk_plans().wrapping_sub(plans);
            out.refused = report.refused;
            out.received = report.received;
        }
        let reference = report.reference;
        let stamp = node.cycles();
        let e = robot.deviation(&reference, p.omega);
        if e[0].hypot(e[1]) > super::pushed::FALLEN_M {
            out.fallen = true;
        }
        robot.track(&reference, e, &p);
        tracked = Some((stamp, e));
        let s = node.gait().swinging();
        if s.is_some() && s != swinging {
            liftoffs += 1;
            if liftoffs == 2 && adjusting {
                push_at = Some(k + PUSH_DELAY_TICKS);
            }
        }
        swinging = s;
        if push_at == Some(k) {
            robot.push(PUSH_DV);
        }
        bus.advance(t0 + 5 * ms);
        while ctl.receive().is_ok() {}
        let done = burst.map_or(liftoffs as usize > BURST_SUPPORT + 1, |b| {
            k > b + 1 && node.gait().is_standing()
        });
        if out.fallen || done {
            break;
        }
    }
    out.can_log = bus.log();
    Ok((out, replans))
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::wire::Adjust;

    /// Every path fills the half cycle before the poll with footstep commands (every queued
    /// step modified, out-of-reach versions), in a cycle that re-plans at a start of single
    /// support, and the robot walks on; each loads what its name says.
    #[test]
    fn the_burst_is_all_accepted_work_in_a_replanning_cycle() {
        let cfg = NodeConfig::hrp2();
        for path in Path::ALL.into_iter().filter(|p| !p.drives()) {
            let w = worst_cycle(&cfg, path).unwrap();
            let adjusting = path.adjusting();
            let (mods, versions, appends, measured) = w.burst;
            let sent = mods + versions + appends + measured;
            assert_eq!(usize::from(w.received), sent, "{path:?}");
            // At 1 Mbit/s the half cycle before the poll carries 17 or more frames.
            assert!((17..=cfg.max_rx).contains(&sent), "{path:?}: {sent} frames");
            assert!(mods >= 5, "{path:?}: {mods} modifications");
            assert_eq!(measured, usize::from(adjusting));
            assert!(w.replanned, "{path:?}: no re-plan in the burst cycle");
            // The out-of-reach versions, and what the node's work budget leaves out (`Busy`).
            assert!(usize::from(w.refused) >= versions, "{path:?}: {w:?}");
            assert!(!w.fallen, "{path:?}");
            let w = WorstRun {
                can_log: vec![],
                ..w
            };
            assert_eq!(w.report, path.report(), "{path:?}");
            assert_eq!(w.cfg.adjust.from_measured, path == Path::Measured);
            if matches!(path, Path::Reach | Path::Measured) {
                // The reach cut, then eq. 17's check.
                assert_ne!(w.adjust_flags & Adjust::REACH_LIMITED, 0, "{path:?}: {w:?}");
                assert_eq!(w.adjust_attempts, 1, "{path:?}");
            }
            if path == Path::Measured {
                // Eq. 17's check of the move, which the lift-off's re-plan takes: the step
                // adjustment planned, so the tick does not plan from the measured state (the
                // budget's charge of that try; without it, it plans a second time).
                assert_eq!(w.plans, 1, "{w:?}");
                assert!(!w.from_measured, "{w:?}");
            }
        }
    }
}
