//! One run of the fault sweep ([`play`]): the retransmitting controller (see the module docs
//! of [`crate::eval::faults`]), the node and the virtual bus with the faults, tick by tick; then the
//! evaluation of the node's references (the multi-body ZMP against the support polygon) and
//! of its landings against the footsteps the controller saw accepted.

use embedded_can::nb::Can;
use planner_core::gait::{FootPose, Footstep, Phase, Side};
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{ids, Ack, Adjust, Command, ControlOp, Reason, StepBook, Stream};

use super::adjusting::{count_measured, shifted, Estimator, Shifts};
use super::polygon::{landings, outside, support_polygon};
use super::ports::{Flood, Rng};
use super::stick::Stick;
use super::{
    CaseResult, FaultKind, MeasuredCount, Walk, DELAY_NS, FALL_MARGIN, HEAVY, MAX_RETRIES,
    RETRY_TICKS,
};
use crate::eval::multibody::{evaluate, max_zmp_error, MbError};
use crate::robot::model::Model;
use crate::scenario::{self, Scenario};
use crate::sim::bus::{Bus, Faults, Tap};

/// A command of the controller, with the footstep (id, pose) it carries if any, and whether it
/// pins a step (see [`super::run_case`]).
type Outgoing = (Command, Option<(u16, Footstep<f64>)>, bool);

/// A command of the controller waiting for its answer.
struct Pending {
    cmd: Command,
    /// The footstep (id, pose) for appends and modifications.
    step: Option<(u16, Footstep<f64>)>,
    last_sent: u64,
    retries: u8,
    /// Waiting for an answer (or for a retry after `SequenceGap` or `BadCrc`).
    open: bool,
    /// A newer modification of the same step was sent: do not retry this one.
    superseded: bool,
    /// Sent to pin a step after a refused modification (not pinned again if refused).
    pin: bool,
}

fn key(c: &Command) -> u8 {
    c.key()
}

/// The step number an `ACK`'s low byte names: the latest of the controller's steps with it.
fn step_of(plan: &[(u16, Footstep<f64>)], low: u8) -> u16 {
    let next = plan.iter().map(|(id, _)| id + 1).max().unwrap_or(0);
    planner_core::wire::step_number(low, next)
}

/// The version a footstep command carries (0 for an append).
fn version(c: &Command) -> u8 {
    match c {
        Command::Modify(m) => m.version,
        _ => 0,
    }
}

/// The frame of footstep `id` at `f`: its append, or its next modification.
fn wire_step(
    book: &mut StepBook,
    append: bool,
    id: u16,
    f: &Footstep<f64>,
) -> Result<Command, String> {
    let wid = crate::scenario::wire::wire_id(id)
        .ok_or(format!("footstep id {id} does not fit the bus"))?;
    let c = if append {
        book.append(wid, f.side == Side::Left, f.x, f.y, f.yaw)
    } else {
        book.modify(wid, f.x, f.y, f.yaw)
    };
    c.ok_or_else(|| {
        format!(
            "footstep {id} at ({}, {}) is not representable on the bus",
            f.x, f.y
        )
    })
}

/// One run's settings: the walk, the fault kind at its rate, the seed.
#[derive(Clone, Copy, Debug)]
pub(super) struct Case {
    pub(super) walk: Walk,
    pub(super) kind: FaultKind,
    pub(super) rate: f64,
    pub(super) seed: u64,
}

/// Plays `s` as the `case` says through `cfg`'s node, evaluates it with `model`; with
/// `record`, also the candump log of the bus.
pub(super) fn play(
    s: &Scenario,
    case: Case,
    cfg: NodeConfig,
    model: &Model,
    record: bool,
) -> Result<(CaseResult, Vec<String>), String> {
    let Case {
        walk,
        kind,
        rate,
        seed,
    } = case;
    let adjusting = walk == Walk::Adjusting;
    let driven = walk == Walk::Velocity;
    let mut silent_at_ns = None;
    let mut node: Node<64> = Node::new(cfg).map_err(|e| format!("node start-up: {e:?}"))?;
    let mut rng = Rng::new(seed ^ 0xFA17);
    let ms = 1_000_000u64;
    let mut faults = Faults::default();
    match kind {
        FaultKind::Drop => faults.drop = rate,
        FaultKind::Duplicate => faults.duplicate = rate,
        FaultKind::Corrupt => faults.corrupt = rate,
        FaultKind::Delay => {
            faults.delay = rate;
            faults.delay_ns = DELAY_NS;
        }
        FaultKind::Silence => {
            faults.from_port = Some(0);
            let at = (rng.range(0.1, 8.0) * 1e9) as u64;
            silent_at_ns = Some(at);
            faults.silence_ns = Some((at, u64::MAX));
        }
        FaultKind::Mixed(i) => {
            let m = HEAVY.get(i).ok_or("no such mixed row")?;
            faults.drop = m.drop;
            faults.corrupt = m.corrupt;
            faults.delay = m.delay;
            faults.delay_ns = m.delay_ns;
        }
        FaultKind::None | FaultKind::Flood | FaultKind::Burst | FaultKind::Blind => {}
    }
    // Ports: the controller, the node, the babbler and its listener, (adjusting) the estimator.
    let ports = if adjusting { 5 } else { 4 };
    let bus = Bus::new(
        1_000_000,
        ports,
        faults,
        seed.wrapping_mul(2).wrapping_add(1),
    );
    if record {
        bus.record();
    }
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let mut flood = Flood {
        on: kind == FaultKind::Flood,
        rate,
        port: bus.port(2),
        listener: bus.port(3),
        waiting: None,
        rng: Rng::new(seed ^ 0xF100D),
    };
    // The burst: which single support (counted from the first), how many modifications.
    let burst_support = 1 + rng.next() % 6;
    let mut supports_seen = 0u64;
    let mut burst_left = match kind {
        FaultKind::Burst => rate as usize,
        FaultKind::Mixed(i) => HEAVY.get(i).map_or(0, |m| m.burst),
        _ => 0,
    };
    let mut plan: Vec<(u16, Footstep<f64>)> = Vec::new(); // the controller's intended steps

    let mut trajectory = vec![*node.gait().last()];
    let mut pending: Vec<Pending> = Vec::new();
    let mut book = StepBook::new();
    // What the node has as the controller knows it: (id, pose, order of that version among
    // the controller's versions of the step: 0 for the append, then 1, 2, … unwrapped).
    let mut accepted: Vec<(u16, Footstep<f64>, u64)> = Vec::new();
    // Every version sent: (id, wire version) → (pose, order); a later send of the same wire
    // version (after 128 modifications) replaces it.
    let mut node_accepted: Vec<(u16, Footstep<f64>, u64)> = Vec::new();
    let mut versions: std::collections::HashMap<(u16, u8), (Footstep<f64>, u64)> =
        Default::default();
    let mut made: std::collections::HashMap<u16, u64> = Default::default();
    // Takes an acceptance: a newer version than the one known replaces it (answers may
    // arrive out of order; the node never takes an older version after a newer one).
    let take =
        |accepted: &mut Vec<(u16, Footstep<f64>, u64)>, id: u16, f: Footstep<f64>, u: u64| {
            match accepted.iter_mut().find(|(i, _, _)| *i == id) {
                Some(e) if u > e.2 => {
                    e.1 = f;
                    e.2 = u;
                }
                Some(_) => {}
                None => accepted.push((id, f, u)),
            }
        };
    // The handshake before the scenario's tick 0: the controller waits for the node's
    // `SESSION` (its first cycle and every 100 ms after), sends the `Reset` that opens it and
    // sends it again, with a new sequence number, until it is answered accepted or a `SESSION`
    // names one of its resets as the last accepted command (the answer lost). `SESSION` has no
    // CRC: the latest one read counts. The node does not tick before (nothing moves), so the
    // scenario's timing is unchanged.
    let mut ctl_state = crate::scenario::wire::Controller::default();
    let mut pre = 0u64;
    let mut heard: Option<u32> = None;
    // (sequence number, echo, session) of each reset sent: the session opened is one more than
    // the accepted one's (a corrupted `SESSION` may have given a wrong one to another).
    let mut resets: Vec<(u32, u8, u32)> = Vec::new();
    let mut opened = false;
    while !opened && pre < 2000 {
        let t0 = pre * 5 * ms;
        bus.advance(t0);
        if let Some(epoch) = heard {
            if pre % RETRY_TICKS == 0 {
                ctl_state.epoch = epoch;
                let c = ctl_state.control(ControlOp::Reset);
                resets.push((ctl_state.seq, c.echo(), epoch));
                let _ = ctl.transmit(&c.encode());
            }
        }
        bus.advance(t0 + 5 * ms / 2);
        node.poll((t0 / ms) as u32 + 2, &mut nport);
        bus.advance(t0 + 5 * ms);
        while let Ok(f) = ctl.receive() {
            if let Some(sn) = planner_core::wire::Session::decode(&f) {
                if let Some(&(_, _, e)) = resets.iter().find(|&&(q, _, _)| q == sn.last_seq) {
                    opened = true;
                    ctl_state.epoch = e;
                } else if !opened {
                    heard = Some(sn.epoch);
                }
                ctl_state.seq = ctl_state.seq.max(sn.last_seq);
            } else if let Some(a) = Ack::decode(&f) {
                let ours = resets
                    .iter()
                    .find(|&&(q, e, _)| q as u8 == a.seq && e == a.echo);
                if let (0x20, None, Some(&(_, _, e))) = (a.command, a.reason, ours) {
                    opened = true;
                    ctl_state.epoch = e;
                }
            }
        }
        pre += 1;
    }
    if !opened {
        return Err("the handshake did not complete in 10 s".into());
    }
    ctl_state.epoch = ctl_state.epoch.wrapping_add(1);
    let mut estimator = adjusting.then(|| {
        Estimator::new(
            bus.port(4),
            node.gait().last(),
            seed,
            kind == FaultKind::Blind,
        )
    });
    let mut shifts = Shifts::default();
    let mut stick = Stick::new(silent_at_ns.map(|at| (at / (5 * ms)).saturating_sub(pre)));
    let mut measured = MeasuredCount::default();
    let mut measured_too_old = 0;
    let max_age = cfg.adjust.max_age;
    let mut next = 0;
    // Commands not sent yet: a control command waits until every earlier command is answered
    // (a `Stop` overtaking a lost `Start` would leave the robot walking in place), and what
    // follows it waits behind it.
    let mut outbox: std::collections::VecDeque<Outgoing> = std::collections::VecDeque::new();
    let mut retransmissions = 0;
    let mut ticks_without_reference = 0;
    let mut stream = Stream::default();
    let mut stream_gaps = 0;
    let mut safety_stop = false;
    let last_command = s.timeline.last().map(|(t, _)| *t).unwrap_or(0);
    let mut k = 0u64;
    while k < s.max_ticks {
        let t0 = (k + pre) * 5 * ms;
        bus.advance(t0);
        // 1. The scenario's commands due now.
        let mut issue: Vec<Outgoing> = Vec::new();
        // (A `VELOCITY` is sent at once, outside the retransmitted commands: the stream
        // replaces a lost frame with the next one.)
        let mut drove = false;
        while next < s.timeline.len() && s.timeline[next].0 <= k {
            let (_, command) = s.timeline[next];
            next += 1;
            // (Numbered when sent: see below.)
            let control = |op| Command::Control {
                session: 0,
                seq: 0,
                op,
            };
            match command {
                scenario::Command::Push(id, f) => {
                    plan.push((id, f));
                    issue.push((wire_step(&mut book, true, id, &f)?, Some((id, f)), false));
                }
                scenario::Command::Modify(id, f) => {
                    if let Some(e) = plan.iter_mut().find(|(i, _)| *i == id) {
                        e.1 = f;
                    }
                    issue.push((wire_step(&mut book, false, id, &f)?, Some((id, f)), false));
                }
                scenario::Command::Start if adjusting => {
                    issue.push((control(ControlOp::StartAdjusting), None, false))
                }
                scenario::Command::Start => issue.push((control(ControlOp::Start), None, false)),
                scenario::Command::Stop => issue.push((control(ControlOp::Stop), None, false)),
                scenario::Command::StopNow => {
                    issue.push((control(ControlOp::StopNow), None, false))
                }
                scenario::Command::Velocity(vx, vy, wz) if driven => {
                    let c = stick.hold((vx, vy, wz), k, &mut ctl_state);
                    let _ = ctl.transmit(&c.encode_in(ctl_state.epoch));
                    drove = true;
                }
                scenario::Command::Velocity(..) | scenario::Command::Goal(..) => {
                    return Err(
                        "the fault sweep plays footstep scenarios and (walked as `velocity`) \
                         velocity scenarios: a goal is played by `run`"
                            .into(),
                    );
                }
            }
        }
        if !drove {
            if let Some(c) = stick.due(k, &mut ctl_state) {
                let _ = ctl.transmit(&c.encode_in(ctl_state.epoch));
                drove = true;
            }
        }
        // 2. The burst of modifications, spread over the chosen single support.
        let phase = node.gait().last().phase;
        if let Phase::Single(_) = phase {
            if trajectory.len() >= 2
                && !matches!(trajectory[trajectory.len() - 2].phase, Phase::Single(_))
            {
                supports_seen += 1;
            }
            if supports_seen == burst_support && burst_left > 0 {
                let per_tick = burst_left.div_ceil(100).max(1);
                for _ in 0..per_tick.min(burst_left) {
                    burst_left -= 1;
                    let swinging = node.gait().swinging();
                    let later: Vec<_> = plan
                        .iter()
                        .filter(|(id, _)| node.gait().is_queued(*id) && Some(*id) != swinging)
                        .copied()
                        .collect();
                    if later.is_empty() {
                        continue;
                    }
                    let (id, f) = later[(rng.next() as usize) % later.len().min(3)];
                    let (sy, cy) = f.yaw.sin_cos();
                    let (da, dc) = (rng.range(-0.05, 0.05), rng.range(-0.03, 0.03));
                    let m = Footstep::new(
                        f.side,
                        f.x + cy * da - sy * dc,
                        f.y + sy * da + cy * dc,
                        f.yaw + rng.range(-0.1, 0.1),
                    );
                    issue.push((wire_step(&mut book, false, id, &m)?, Some((id, m)), false));
                }
            }
        }
        outbox.extend(issue);
        while let Some(&(cmd, step, pin)) = outbox.front() {
            let busy = pending
                .iter()
                .any(|p| p.open && !p.superseded && p.retries < MAX_RETRIES);
            if matches!(cmd, Command::Control { .. }) && busy {
                break;
            }
            outbox.pop_front();
            // A control command takes its sequence number as it is sent (greater than every
            // one before it, heartbeats included).
            let cmd = match cmd {
                Command::Control { op, .. } => ctl_state.control(op),
                c => c,
            };
            if let (Command::Modify(_), Some((id, _))) = (&cmd, step) {
                for p in pending.iter_mut() {
                    if matches!(p.cmd, Command::Modify(_)) && p.step.map(|s| s.0) == Some(id) {
                        p.superseded = true;
                    }
                }
            }
            if let (Some(id), Some((_, f))) = (cmd.step_id(), step) {
                let u = match cmd {
                    Command::Modify(_) => {
                        let e = made.entry(id).or_insert(0);
                        *e += 1;
                        *e
                    }
                    _ => {
                        made.insert(id, 0);
                        0
                    }
                };
                versions.insert((id, version(&cmd)), (f, u));
            }
            let _ = ctl.transmit(&cmd.encode());
            pending.push(Pending {
                cmd,
                step,
                last_sent: k,
                retries: 0,
                open: true,
                superseded: false,
                pin,
            });
        }
        // 3. Retransmissions of what is still unanswered (in the order first sent).
        for p in pending.iter_mut() {
            if p.open && !p.superseded && k >= p.last_sent + RETRY_TICKS && p.retries < MAX_RETRIES
            {
                p.retries += 1;
                p.last_sent = k;
                retransmissions += 1;
                // A control command is sent again as a new one (a new sequence number: the
                // old one may be below a heartbeat's taken since).
                if let Command::Control { op, .. } = p.cmd {
                    p.cmd = ctl_state.control(op);
                }
                let _ = ctl.transmit(&p.cmd.encode());
            }
        }
        // (Not in a cycle with a `VELOCITY`: arbitration delivers the `CONTROL` first, and a
        // heartbeat numbered after the velocity would make it stale.)
        if k % 20 == 0 && !drove {
            let hb = ctl_state.control(ControlOp::Heartbeat);
            let _ = ctl.transmit(&hb.encode());
        }
        // The estimator's state of the last cycle.
        if let Some(e) = estimator.as_mut() {
            e.send(k, ctl_state.epoch);
        }
        // 4. The node's cycle (the babbling port runs with the bus).
        flood.run(&bus, t0, t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let mut tap = Tap::new(&mut nport, k + pre);
        let report = node.poll(now_ms, &mut tap);
        // What the node accepted, from its own answers as it sent them (before the bus).
        for a in tap.frames().filter_map(Ack::decode) {
            if let (0x00 | 0x01, None, Some(v)) = (a.command, a.reason, a.version) {
                let id = step_of(&plan, a.seq);
                if let Some(&(f, u)) = versions.get(&(id, v)) {
                    take(&mut node_accepted, id, f, u);
                }
            }
        }
        for a in tap.frames().filter_map(Ack::decode) {
            if count_measured(&mut measured, &a, node.cycles(), max_age) {
                measured_too_old += 1;
            }
        }
        if driven {
            stick.observe(k, &node, tap.frames().filter_map(Ack::decode));
        }
        let a = node.adjustment();
        let from = step_of(&plan, a.from);
        let standing = node.gait().is_standing();
        shifts.note(node.cycles(), (from, a.shift.map(i32::from)), standing);
        if let Some(e) = estimator.as_mut() {
            let swinging = node.gait().swinging();
            e.track(k, node.cycles(), &report.reference, swinging, &cfg.params);
        }
        let stream_ids = [
            ids::COG,
            ids::ZMP,
            ids::COG_VEL,
            ids::FOOT_LEFT,
            ids::FOOT_RIGHT,
        ];
        let one_each = stream_ids
            .iter()
            .all(|id| tap.frames().filter(|f| f.id == *id).count() == 1);
        if !one_each || !report.reference.is_finite() {
            ticks_without_reference += 1;
        }
        trajectory.push(report.reference);
        let st = node.status().state;
        if (st == 2 || st == 3) && !safety_stop {
            safety_stop = true;
        }
        // 5. The controller reads the answers and the stream.
        flood.run(&bus, t0 + 5 * ms / 2, t0 + 5 * ms);
        while let Ok(f) = ctl.receive() {
            if let Some(a) = Adjust::decode(&f) {
                let shift = (step_of(&plan, a.from), a.shift.map(i32::from));
                shifts.heard.insert(a.count, shift);
            } else if let Some(a) = Ack::decode(&f) {
                // Every answer about a footstep tells its version in force, whatever the
                // answer (a refused newer modification leaves an older one in force).
                if let (0x00 | 0x01, Some(v)) = (a.command, a.version) {
                    let id = step_of(&plan, a.seq);
                    if let Some(&(f, u)) = versions.get(&(id, v)) {
                        take(&mut accepted, id, f, u);
                    }
                }
                let same = |p: &Pending| {
                    p.cmd.code() == a.command && key(&p.cmd) == a.seq && p.cmd.echo() == a.echo
                };
                // The open command this answers (the newest, if it was sent more than once);
                // else a closed one: an acceptance that arrives after a refusal of the same
                // frame (a delayed copy taken once the steps around it had changed) still
                // tells what the node now has.
                let Some(i) = pending.iter().rposition(|p| p.open && same(p)) else {
                    if a.reason.is_none() {
                        if let Some(p) = pending.iter().rev().find(|p| same(p)) {
                            if let Some((id, f)) = p.step {
                                let u = versions.get(&(id, version(&p.cmd))).map_or(0, |e| e.1);
                                take(&mut accepted, id, f, u);
                            }
                        }
                    }
                    continue;
                };
                let mut confirm = vec![];
                let p = &mut pending[i];
                match a.reason {
                    Some(Reason::SequenceGap | Reason::BadCrc) if p.retries < MAX_RETRIES => {} // retry later
                    // A control command overtaken by a newer one (a delayed frame): sent again
                    // as a new one.
                    Some(Reason::Stale)
                        if matches!(p.cmd, Command::Control { .. }) && p.retries < MAX_RETRIES => {}
                    None | Some(Reason::Duplicate) => confirm.push(i),
                    Some(r) => {
                        p.open = false;
                        // A refused modification leaves an older version in force, and older
                        // versions still in flight (superseded, their answers lost) could be
                        // taken after it: pin the step with a new version at the pose in force,
                        // which makes every older one stale.
                        let (pin, cmd) = (p.pin, p.cmd);
                        if let (false, Command::Modify(m), Some(v)) = (pin, cmd, a.version) {
                            let id = m.id;
                            let in_flight = pending
                                .iter()
                                .any(|q| q.superseded && q.cmd.step_id() == Some(m.id));
                            if in_flight && r != Reason::Stale && r != Reason::LiftedOff {
                                if let Some(&(f, _)) = versions.get(&(id, v)) {
                                    let c = wire_step(&mut book, false, id, &f)?;
                                    outbox.push_back((c, Some((id, f)), true));
                                }
                            }
                        }
                    }
                }
                for j in confirm {
                    let p = &mut pending[j];
                    p.open = false;
                    if let Some((id, f)) = p.step {
                        let u = versions.get(&(id, version(&p.cmd))).map_or(0, |e| e.1);
                        take(&mut accepted, id, f, u);
                    }
                }
            } else {
                stream.decode_into(&f);
            }
        }
        if stream.tick != node.cycles() & (planner_core::wire::STAMPS - 1) {
            stream_gaps += 1;
        }
        k += 1;
        let quiet = pending
            .iter()
            .all(|p| !p.open || p.superseded || p.retries >= MAX_RETRIES);
        if node.gait().is_standing()
            && k > last_command + 1
            && next >= s.timeline.len()
            && quiet
            && outbox.is_empty()
        {
            break;
        }
    }
    let unanswered = pending
        .iter()
        .filter(|p| {
            p.open
                && !p.superseded
                && !matches!(
                    p.cmd,
                    Command::Control {
                        op: ControlOp::Heartbeat,
                        ..
                    }
                )
        })
        .count();

    // Footsteps: what the controller believes the node took, against what it took.
    node_accepted.sort_by_key(|(id, _, _)| *id);
    accepted.sort_by_key(|(id, _, _)| *id);
    let misinformed = node_accepted
        .iter()
        .filter(|(id, _, u)| !accepted.iter().any(|(j, _, w)| j == id && w == u))
        .count()
        + accepted
            .iter()
            .filter(|(id, _, _)| !node_accepted.iter().any(|(j, _, _)| j == id))
            .count();
    // Footsteps: accepted (as the node answered) against walked.
    let accepted = node_accepted;
    let walked = landings(&trajectory);
    let mut used = vec![false; walked.len()];
    let (mut lost, mut cancelled, mut shift_unheard, mut shifted_landings) = (0, 0, 0, 0);
    let matches = |f: &Footstep<f64>, (side, p): &(Side, FootPose<f64>)| {
        *side == f.side
            && (p.x - f.x).abs() <= 5e-4
            && (p.y - f.y).abs() <= 5e-4
            && ((p.yaw - f.yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI)
                .abs()
                <= 2e-3
    };
    // Steps are walked in id order: each accepted step (in id order) is matched to the first
    // unused landing after the previous match, so two steps at the same pose (a multi-step
    // change applied in part) are told apart; a step walked twice leaves a stray landing.
    // An adjusting walk's step is walked at its accepted pose plus the shift the node had in
    // force when it lifted off; the controller's book should say the same.
    let mut from = 0;
    for (id, f, _) in &accepted {
        let shift = shifts.of(*id);
        let f = shifted(f, shift);
        match (from..walked.len()).find(|&i| !used[i] && matches(&f, &walked[i])) {
            Some(i) => {
                used[i] = true;
                from = i + 1;
                shift_unheard += usize::from(shifts.heard_of(*id) != shift);
                shifted_landings += usize::from(shift != [0, 0]);
            }
            None if safety_stop => cancelled += 1,
            None => lost += 1,
        }
    }
    // Landings nobody asked for: a safety stop's closing step is expected (one).
    // (A velocity walk's landings are the node's own steps: none is asked for.)
    let stray = if driven {
        0
    } else {
        used.iter().filter(|u| !**u).count()
    };
    let stray = if safety_stop {
        cancelled += stray.min(1);
        stray.saturating_sub(1)
    } else {
        stray
    };
    lost += stray;
    let dt = cfg.params.dt;
    // If the model cannot follow from tick `e` on (a leg out of reach), the ZMP is evaluated
    // on the ticks up to 50 ms before it.
    let mut model_error = None;
    let mut evaluated = evaluate(model, &trajectory, dt);
    if let Err(MbError::OutOfReach(e, _) | MbError::NoConvergence(e, _) | MbError::NonFinite(e)) =
        evaluated
    {
        model_error = Some(format!("{:?}", evaluated.as_ref().err()));
        // Up to 50 ms before it: at the stretched knee itself the waist search is singular.
        evaluated = evaluate(model, &trajectory[..e.saturating_sub(10)], dt);
    }
    let (fell, max_outside, max_err) = match evaluated {
        Ok(mb) => {
            let n = mb.len().min(trajectory.len());
            let mut worst = 0.0f64;
            for kk in 2..n.saturating_sub(2) {
                let poly = support_polygon(&trajectory[kk]);
                worst = worst.max(outside(&poly, [mb[kk].mb_zmp_x, mb[kk].mb_zmp_y]));
            }
            let err = max_zmp_error(&trajectory[..n], &mb);
            (worst > FALL_MARGIN || !worst.is_finite(), worst, err)
        }
        Err(e) => {
            model_error = Some(format!("{model_error:?} then {e:?}"));
            (false, f64::NAN, f64::NAN)
        }
    };
    let result = CaseResult {
        ticks: trajectory.len(),
        fell,
        model_error,
        max_outside,
        max_zmp_error: max_err,
        lost,
        cancelled,
        unanswered,
        misinformed,
        retransmissions,
        safety_stop,
        ticks_without_reference,
        stream_gaps,
        landings: walked.len(),
        bus_load: bus.load(),
        walk,
        pendulum_fell: estimator.as_ref().is_some_and(|e| e.fell),
        measured,
        measured_too_old,
        adjustments: shifts.adjustments().count(),
        last_adjustment: shifts.adjustments().last().map(|e| e.0),
        shift_unheard,
        shifted_landings,
        estimator_silent_from: estimator.as_ref().and_then(|e| e.silent_from),
        velocity: driven.then(|| stick.finish()),
        trajectory,
    };
    Ok((result, bus.log()))
}
