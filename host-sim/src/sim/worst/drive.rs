//! The worst admissible cycle of a walk the node drives itself (`VELOCITY`, `GOAL`:
//! `planner_core::node`'s module `drive`): the paths [`Path::Velocity`],
//! [`Path::VelocityStart`], [`Path::GoalStart`], [`Path::Goal`] and [`Path::Resume`].
//!
//! A walk of HRP-2's node (`Node<16>`, the images' queue) driven at [`WALK_V`] (a `VELOCITY`
//! streamed every [`STREAM_CYCLES`] cycles) or toward [`GOAL_AHEAD`]. The burst comes in a
//! report cycle (the four periodic reports) that, for the walking paths, re-plans at the start
//! of the [`BURST_SUPPORT`]-th single support (found by a first run without the burst), and
//! holds as many command frames as reach the poll (the node's `max_rx` at most):
//! * the drive command of the path: the velocity the legs cut the most ([`largest_change`]:
//!   the reach's halvings longest over the steps it re-plans, then the most components cut)
//!   or a goal re-aimed behind the robot ([`GOAL_REAIM`]), accepted, re-planning every queued
//!   step. (From the stances of a walk the node drives, HRP-2's limits leave the halvings
//!   unreached: the closed-form cuts place every step; the search cuts all three components.
//!   Stances turned out of what the drive generates, or a sole gap of 0.12 m, do reach them.)
//! * the rest of a bus's burst, each answered: the same frame again (`Duplicate`), an older
//!   velocity (`Stale`), newer goals and velocities (fresh, refused `Busy`: the cycle's plan is
//!   taken), a heartbeat, a measured state, and footstep frames, appends and modifications
//!   of the queued steps (`WrongState`: the steps are the node's).
//!
//! [`Path::Resume`] sends a zero velocity during the single support before: the next swing
//! target becomes the step that closes the feet and the walk stops after it (the drive's own
//! stop); the burst's velocity cancels that stop, re-plans the closing step and makes the
//! queue up with [`AHEAD`] − 1 new steps before its one eq. 17 plan, which the tick's re-plan
//! in the same cycle takes. A walk the node drives does not adjust its steps (a drive from standing turns the
//! step adjustment off; a velocity is refused while the controller's steps are walked), so no
//! drive path combines with the step adjustment.

use planner_core::gait::{Footstep, Phase, Side};
use planner_core::node::velocity::{Stepping, Velocity, HALVINGS};
use planner_core::node::Limit;
use planner_core::node::{Node, NodeConfig, AHEAD};
use planner_core::wire::{
    Command, ControlOp, Measured, RawFrame, StepBook, WireGoal, WireVelocity,
};

use super::{Path, WorstRun, BURST_SUPPORT};
use crate::scenario::wire::Controller;
use embedded_can::nb::Can;

/// The velocity the walk is driven at before the burst (vx, vy, ω) \[m/s, m/s, rad/s\].
pub const WALK_V: [f64; 3] = [0.2, 0.0, 0.0];
/// Cycles between two frames of the velocity stream.
pub const STREAM_CYCLES: u64 = 10;
/// The goal of [`Path::Goal`] and [`Path::GoalStart`] (x, y, θ relative to the stance)
/// \[m, m, rad\].
pub const GOAL_AHEAD: [f64; 3] = [3.0, 0.5, 0.5];
/// The goal the burst of [`Path::Goal`] re-aims at, relative to the stance then: behind and
/// to the left, turned (every component of the velocity it asks for cut).
pub const GOAL_REAIM: [f64; 3] = [-2.0, 2.5, 3.0];
/// The velocities [`largest_change`] searches: each component at `GRID` + 1 values evenly
/// from minus to plus the largest searched.
const GRID: i32 = 40;
/// The wire's largest speed \[m/s\] and turn rate \[rad/s\] searched.
const V_MAX: [f64; 3] = [1.0, 1.0, 2.0];

/// The velocity of `v` as the wire carries it (the node's value).
fn on_wire(v: [f64; 3]) -> Velocity<f64> {
    let (vx, vy, wz) = WireVelocity::from_si(1, v[0], v[1], v[2]).si_in::<f64>();
    Velocity { vx, vy, wz }
}

/// The velocity of the grid whose [`AHEAD`] steps from `support` and `same` (the feet before
/// the next swing target) take the reach's halvings the most (counted on the steps that turn:
/// the heading change is halved with the forward step; a step placed beside the support foot
/// took them all), then the most components cut.
pub fn largest_change(
    cfg: &NodeConfig,
    support: Footstep<f64>,
    same: Footstep<f64>,
) -> ([f64; 3], u32) {
    let stepping = Stepping::of(&cfg.params, cfg.reach);
    let mut best = ([0.0; 3], 0u32);
    let at = |i: i32, max: f64| max * f64::from(2 * i - GRID) / f64::from(GRID);
    for a in 0..=GRID {
        for b in 0..=GRID {
            for c in 0..=GRID {
                let v = [at(a, V_MAX[0]), at(b, V_MAX[1]), at(c, V_MAX[2])];
                let score = halvings(&stepping, &on_wire(v), support, same);
                if score > best.1 {
                    best = (v, score);
                }
            }
        }
    }
    best
}

/// The score of [`largest_change`]: 8 × the halvings the steps took plus the cuts. A step
/// halved `j` times was tried at `2^i` times its heading change and forward step (`i` ≤ `j`),
/// each refused for the sole gap (the limit the closed forms leave out): counted back from
/// the step taken (a step beside the support foot: all of them).
fn halvings(
    s: &Stepping<f64>,
    v: &Velocity<f64>,
    support: Footstep<f64>,
    same: Footstep<f64>,
) -> u32 {
    let (mut sup, mut o) = (support, same);
    let mut score = 0;
    for _ in 0..AHEAD {
        let Ok((step, cut)) = s.next_step(v, &sup, &o, false) else {
            return 0;
        };
        let n = if cut.in_place {
            HALVINGS + 1
        } else {
            let (sn, cs) = sup.yaw.sin_cos();
            let (dx, dy) = (step.x - sup.x, step.y - sup.y);
            let (f, a) = (cs * dx + sn * dy, -sn * dx + cs * dy);
            let d = step.yaw - sup.yaw;
            // The heading change first tried (the closed form's cut of what was asked).
            let toward = match step.side {
                Side::Left => v.wz > 0.0,
                Side::Right => v.wz < 0.0,
            };
            let r = &s.reach;
            let first = if toward {
                (2.0 * v.wz * s.period).clamp(-r.max_yaw, r.max_yaw)
            } else {
                0.0
            };
            let mut n = 0;
            for j in 1..=HALVINGS {
                let m = f64::from(1u32 << j);
                // (Beyond the closed forms' cut: not a try the generator made.)
                if (m * d).abs() > first.abs() + 1e-12
                    || m * f > r.max_forward
                    || m * f < -r.max_backward
                {
                    break;
                }
                let tried = Footstep::new(
                    step.side,
                    sup.x + cs * m * f - sn * a,
                    sup.y + sn * m * f + cs * a,
                    sup.yaw + m * d,
                );
                match s.reach.broken(&sup, &o, &tried, false, &s.soles) {
                    Some(b) if b.limit == Limit::Crossing => n = j,
                    _ => break,
                }
            }
            n
        };
        score += 8 * n + cut.mask().count_ones();
        o = sup;
        sup = step;
    }
    score
}

/// The generator for a drive path (module docs).
pub(super) fn worst_drive(cfg: &NodeConfig, path: Path) -> Result<WorstRun, String> {
    let start = matches!(path, Path::VelocityStart | Path::GoalStart);
    // The start cycle's poll is the node's cycle k + 2: a report cycle when it is 1 mod 20.
    let (at, lead) = if start {
        (19, 18)
    } else {
        super::burst_cycle(cfg, path, run, true)?
    };
    super::largest_burst(cfg, path, at, lead, run)
}

/// One run (as `worst`'s): `burst` the cycle of the burst, `cap` its frames, `lead` the cycles
/// by which the start is delayed.
fn run(
    cfg: &NodeConfig,
    path: Path,
    burst: Option<u64>,
    cap: usize,
    lead: u64,
) -> Result<(WorstRun, Vec<(u64, u32)>), String> {
    let goal_walk = matches!(path, Path::Goal | Path::GoalStart);
    let (mut node, bus) = super::open(cfg)?;
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let ms = 1_000_000u64;
    let mut c = crate::sim::handshake(&bus, &mut node, &mut ctl, &mut nport);
    let mut book = StepBook::new();
    let mut out = WorstRun::new(path, cfg, burst);
    let mut replans = Vec::new();
    let mut last_replan = None;
    let mut v_now = WALK_V;
    let start_at = 1 + lead;
    let mut stopped_at = None;
    for k in 0..4000u64 {
        let t0 = (k + 1) * 5 * ms;
        bus.advance(t0);
        let mut frames: Vec<RawFrame> = Vec::new();
        let is_burst = Some(k) == burst;
        if k % 20 == 0 && !is_burst {
            frames.push(c.control(ControlOp::Heartbeat).encode());
        }
        // The walk's command (not in a start path's burst cycle: the burst sends it).
        if k == start_at && !(is_burst && matches!(path, Path::VelocityStart | Path::GoalStart)) {
            frames.push(drive_frame(&mut c, goal_walk, v_now, GOAL_AHEAD));
        } else if !goal_walk
            && k > start_at
            && (k - start_at) % STREAM_CYCLES == 0
            && !is_burst
            && stopped_at.is_none()
            && burst.is_none_or(|b| k < b)
        {
            frames.push(drive_frame(&mut c, false, v_now, [0.0; 3]));
        }
        // The resumed walk's stop: a zero velocity a few cycles into the single support
        // before the burst's.
        if path == Path::Resume && burst.is_some_and(|b| k + 40 == b) {
            v_now = [0.0; 3];
            frames.push(drive_frame(&mut c, false, v_now, [0.0; 3]));
        }
        if burst.is_some_and(|b| k == b + 1) {
            stopped_at = Some(k);
            frames.push(c.control(ControlOp::Stop).encode());
        }
        if is_burst {
            let f = burst_frames(&mut c, &mut book, &node, cfg, path, cap)?;
            out.burst = f.1;
            frames.extend(f.0);
        }
        for f in &frames {
            let _ = ctl.transmit(f);
        }
        bus.advance(t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let plans = node.gait().walk_plans();
        let report = node.poll(now_ms, &mut nport);
        let replan = node.gait().last_replan().map(|r| r.tick);
        if replan != last_replan {
            last_replan = replan;
            if matches!(report.reference.phase, Phase::Single(_)) {
                replans.push((k, node.cycles()));
            }
        }
        if is_burst {
            out.replanned = replans.last().map(|r| r.0) == Some(k);
            out.report = node.cycles() % 20 == 1;
            out.plans = node.gait().walk_plans().wrapping_sub(plans);
            out.refused = report.refused;
            out.received = report.received;
            out.adjust_flags = node.drive_velocity().map_or(0, |(_, cut)| cut.mask());
        }
        bus.advance(t0 + 5 * ms);
        while ctl.receive().is_ok() {}
        let done = match burst {
            None => replans.len() > BURST_SUPPORT + 1 || k > 3000,
            Some(b) => k > b + 1 && node.gait().is_standing(),
        };
        if done {
            break;
        }
    }
    out.can_log = bus.log();
    Ok((out, replans))
}

/// The `VELOCITY` `v` or the `GOAL` `g` with the controller's next number.
fn drive_frame(c: &mut Controller, goal: bool, v: [f64; 3], g: [f64; 3]) -> RawFrame {
    c.seq += 1;
    if goal {
        Command::Goal(WireGoal::from_si(c.seq, g[0], g[1], g[2])).encode_in(c.epoch)
    } else {
        Command::Velocity(WireVelocity::from_si(c.seq, v[0], v[1], v[2])).encode_in(c.epoch)
    }
}

/// The burst of `path` for `node` before its poll, at most `cap` frames: the frames and their
/// count as (drive commands accepted, drive commands refused, footstep frames refused,
/// other frames).
#[allow(clippy::type_complexity)]
fn burst_frames(
    c: &mut Controller,
    book: &mut StepBook,
    node: &Node<16>,
    cfg: &NodeConfig,
    path: Path,
    cap: usize,
) -> Result<(Vec<RawFrame>, (usize, usize, usize, usize)), String> {
    let g = node.gait();
    let feet = g.previous_feet(g.next_target());
    let side = match g.next_target().and_then(|id| g.queued_step(id)) {
        Some(s) => s.side,
        None => Side::Right,
    };
    // (The gait's feet: left, right.)
    let (support, same) = match side {
        Side::Left => (feet[1], feet[0]),
        Side::Right => (feet[0], feet[1]),
    };
    let (v, _) = largest_change(cfg, support, same);
    let goal = matches!(path, Path::Goal | Path::GoalStart);
    // (frame, class): 0 the drive command, 1 a drive command refused, 2 a footstep frame,
    // 3 another.
    let mut frames: Vec<(RawFrame, usize)> = Vec::new();
    // A heartbeat, then the drive command, accepted.
    frames.push((c.control(ControlOp::Heartbeat).encode(), 3));
    let stale = c.seq;
    let target = if path == Path::GoalStart {
        GOAL_AHEAD
    } else {
        GOAL_REAIM
    };
    let command = drive_frame(c, goal, v, target);
    frames.push((command, 0));
    // The same frame again, an older velocity, then fresh ones refused `Busy`.
    frames.push((command, 1));
    let old = Command::Velocity(WireVelocity::from_si(stale, v[0], v[1], v[2]));
    frames.push((old.encode_in(c.epoch), 1));
    for i in 0..3 {
        let w = [v[0] * 0.5, -v[1], v[2] * 0.5];
        frames.push((drive_frame(c, i % 2 == 0, w, GOAL_REAIM), 1));
    }
    // A measured state.
    if let Some(m) = Measured::from_si(node.cycles(), [0.01, 0.0]) {
        frames.push((m.encode(c.epoch), 3));
    }
    // Footstep frames for the rest: appends of the next numbers, modifications of the queued.
    let next = node.next_step();
    let queued = g.queued() as u16;
    let mut i = 0u16;
    let max = cap.min(cfg.max_rx);
    while frames.len() < max {
        let id = next.wrapping_add(i);
        let left = i % 2 == 0;
        let f = book
            .append(id, left, 0.1 * f64::from(i), 0.1, 0.0)
            .ok_or("append")?;
        if i < queued && i % 2 == 1 {
            let q = next.wrapping_sub(queued).wrapping_add(i);
            book.append(q, left, 0.0, 0.0, 0.0).ok_or("append")?;
            let m = book.modify(q, 0.05, 0.0, 0.0).ok_or("modify")?;
            frames.push((m.encode_in(c.epoch), 2));
        } else {
            frames.push((f.encode_in(c.epoch), 2));
        }
        i += 1;
    }
    frames.truncate(max);
    let mut n = [0usize; 4];
    for (_, class) in &frames {
        n[*class] += 1;
    }
    Ok((
        frames.into_iter().map(|(f, _)| f).collect(),
        (n[0], n[1], n[2], n[3]),
    ))
}

#[cfg(test)]
mod tests {
    use super::super::worst_cycle;
    use super::*;

    /// Every drive path sends its burst in a report cycle (a walking one re-planning at a
    /// start of single support), the drive command accepted with its components cut and the
    /// other frames refused; the robot then stops and stands.
    #[test]
    fn the_drive_bursts_are_taken_in_a_report_cycle() {
        let cfg = NodeConfig::hrp2();
        for path in Path::ALL.into_iter().filter(|p| p.drives()) {
            let w = worst_cycle(&cfg, path).unwrap();
            let (accepted, drive_refused, footsteps, other) = w.burst;
            let sent = accepted + drive_refused + footsteps + other;
            assert_eq!(usize::from(w.received), sent, "{path:?}");
            assert!((17..=cfg.max_rx).contains(&sent), "{path:?}: {sent} frames");
            assert!(w.report, "{path:?}");
            // Everything but the drive command, the heartbeat and the measured state refused.
            assert_eq!(
                usize::from(w.refused),
                drive_refused + footsteps,
                "{path:?}"
            );
            if !matches!(path, Path::VelocityStart | Path::GoalStart) {
                assert!(w.replanned, "{path:?}: no re-plan in the burst cycle");
            }
            // The velocity in force was cut.
            assert_ne!(w.adjust_flags, 0, "{path:?}");
            // At most one walking window planned (the drive command's eq. 17, which the
            // re-plan takes: nothing is appended after it).
            assert!(
                w.plans <= 1,
                "{path:?}: {} walking windows planned",
                w.plans
            );
        }
    }

    /// From a walking stance, the largest change cuts every component over the steps it
    /// re-plans; with soles that need a wider gap when turned, it takes the reach's halvings
    /// (the count sees them: HRP-2's stances from its own drive do not reach them).
    #[test]
    fn the_largest_change_cuts_and_counts_the_halvings() {
        let mut cfg = NodeConfig::hrp2();
        let right = Footstep::new(Side::Right, 0.0, cfg.right.y, 0.0);
        let left = Footstep::new(Side::Left, 0.1, cfg.left.y, 0.0);
        let (v, score) = largest_change(&cfg, right, left);
        let stepping = Stepping::of(&cfg.params, cfg.reach);
        let (_, cut) = stepping
            .steps::<AHEAD>(&on_wire(v), &right, &left, false)
            .unwrap();
        assert!(cut.forward && cut.lateral && cut.turn, "{v:?}: {cut:?}");
        assert!(score < 8, "{v:?}: {score}");
        cfg.reach.sole_gap = 0.12;
        let (v, score) = largest_change(&cfg, right, left);
        assert!(score >= 8, "{v:?}: {score}");
    }
}
