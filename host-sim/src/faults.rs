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
//!   chosen at random.
//!
//! What is counted per run ([`CaseResult`]):
//! * **fall**: the multi-body ZMP ([`crate::multibody::evaluate`] of the node's references)
//!   leaves the support polygon by more than [`FALL_MARGIN`] at some tick (ticks 2 … n−3, as
//!   [`crate::multibody::max_zmp_error`]). The support polygon is the sole (0.24 × 0.14 m, centred on
//!   the foot pose and turned by its yaw) of the foot on the ground in single support, and the
//!   convex hull of both soles otherwise (the reference's phase decides);
//! * **leg out of reach**: the model cannot follow the references to the end (a knee would
//!   have to stretch beyond thigh + shank = 0.6 m); the ZMP of such a run is evaluated up to
//!   50 ms before that tick, and the run is counted in its own column, not as a fall;
//! * **lost commands**: footsteps whose final state as the controller knows it (the last
//!   append or modification of that id it saw accepted) was not walked exactly once at that
//!   pose (±0.5 mm, ±2 mrad), plus landings that match no accepted footstep. Steps left unwalked
//!   after the node's own safety stop (controller lost, emergency stop) are counted apart as
//!   **cancelled**, and so is the closing step such a stop adds;
//! * **reference every tick**: the node handed one reference (five stream frames) to its bus
//!   port in every cycle, each finite; **stream gaps**: ticks whose reference the controller
//!   did not receive (a property of the bus, not of the node).

use std::fmt::Write as _;

use embedded_can::nb::Can;
use planner_core::gait::{FootPose, Footstep, Phase, Reference, Side};
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{ids, Ack, Command, ControlOp, RawFrame, Reason, StepBook, Stream};

use crate::bus::{Bus, BusError, Faults, Port, VFrame};
use crate::multibody::{evaluate, max_zmp_error, MbError, Model};
use crate::scenario::{self, Scenario};

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
    /// A combination of faults: the index of its row in [`HEAVY`].
    Mixed(usize),
}

/// One of the heavier combinations of faults (issue 10, item 8).
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
            FaultKind::Mixed(_) => "mixed",
        }
    }

    /// The rate as printed.
    pub fn rate_label(self, rate: f64) -> String {
        match self {
            FaultKind::None | FaultKind::Silence => "—".into(),
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

/// The scenarios of the sweep.
pub const SCENARIOS: [&str; 2] = ["straight", "fig4"];

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
    /// The references the node published, one per tick (for the physics engine run).
    pub trajectory: Vec<Reference<f64>>,
}

/// The node's port, recording what the node hands to the bus in a cycle.
struct Tap<'a> {
    port: &'a mut Port,
    sent: Vec<RawFrame>,
}

impl Can for Tap<'_> {
    type Frame = VFrame;
    type Error = BusError;
    fn transmit(&mut self, frame: &VFrame) -> nb::Result<Option<VFrame>, BusError> {
        let r = self.port.transmit(frame);
        if r.is_ok() {
            self.sent.push(*frame);
        }
        r
    }
    fn receive(&mut self) -> nb::Result<VFrame, BusError> {
        self.port.receive()
    }
}

struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }
}

/// The babbling port: one frame at a time, the next one ready as soon as the previous one
/// has been on the bus (a listener port sees it), so that with `rate` 1 it takes every
/// arbitration its random identifier wins. With a lower rate, a new frame is ready after each
/// 50 µs step with a probability that offers about `rate` of the bus time.
struct Flood {
    on: bool,
    rate: f64,
    port: Port,
    listener: Port,
    waiting: Option<RawFrame>,
    rng: Rng,
}

impl Flood {
    /// Runs the bus from `from` to `t` \[ns\], the babbler included.
    fn run(&mut self, bus: &Bus, from: u64, t: u64) {
        if !self.on {
            bus.advance(t);
            return;
        }
        const STEP: u64 = 50_000;
        // A frame of random length (0 … 8 bytes) takes about 95 µs on average.
        let p = (self.rate * STEP as f64 / 95_000.0).min(1.0);
        let mut now = from;
        while now < t {
            if self.waiting.is_none() && (self.rate >= 1.0 || self.rng.unit() < p) {
                let r = self.rng.next();
                let len = ((r >> 11) % 9) as usize;
                let data = self.rng.next().to_le_bytes();
                if let Some(f) = RawFrame::new((r & 0x7FF) as u16, &data[..len]) {
                    if self.port.transmit(&f).is_ok() {
                        self.waiting = Some(f);
                    }
                }
            }
            now = (now + STEP).min(t);
            bus.advance(now);
            while let Ok(f) = self.listener.receive() {
                if Some(f) == self.waiting {
                    self.waiting = None;
                }
            }
        }
    }
}

/// A command of the controller, with the footstep (id, pose) it carries if any, and whether it
/// pins a step (see [`run_case`]).
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
    let wid = u8::try_from(id).map_err(|_| format!("footstep id {id} does not fit the bus"))?;
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

/// Distance of `p` outside the convex polygon `hull` (counter-clockwise); 0 inside.
fn outside(hull: &[[f64; 2]], p: [f64; 2]) -> f64 {
    let n = hull.len();
    let mut inside = true;
    let mut best = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (hull[i], hull[(i + 1) % n]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let (px, py) = (p[0] - a[0], p[1] - a[1]);
        if ex * py - ey * px < 0.0 {
            inside = false;
        }
        let len2 = ex * ex + ey * ey;
        let t = if len2 > 0.0 {
            ((px * ex + py * ey) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((px - t * ex).hypot(py - t * ey));
    }
    if inside {
        0.0
    } else {
        best
    }
}

/// Convex hull (counter-clockwise, monotone chain).
fn hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut h: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

fn sole(f: &FootPose<f64>) -> [[f64; 2]; 4] {
    let (s, c) = f.yaw.sin_cos();
    let [a, b] = SOLE_HALF;
    [[a, b], [-a, b], [-a, -b], [a, -b]].map(|[u, v]| [f.x + c * u - s * v, f.y + s * u + c * v])
}

/// The support polygon of a reference (see the module docs).
pub fn support_polygon(r: &Reference<f64>) -> Vec<[f64; 2]> {
    match r.phase {
        Phase::Single(side) => {
            let i = usize::from(side == Side::Right);
            hull(sole(&r.feet[i]).to_vec())
        }
        _ => {
            let mut pts = sole(&r.feet[0]).to_vec();
            pts.extend_from_slice(&sole(&r.feet[1]));
            hull(pts)
        }
    }
}

/// Footsteps walked: the pose of the swing foot where each single support ends.
pub fn landings(traj: &[Reference<f64>]) -> Vec<(Side, FootPose<f64>)> {
    let mut out = Vec::new();
    for w in traj.windows(2) {
        if let (Phase::Single(support), next) = (w[0].phase, w[1].phase) {
            if !matches!(next, Phase::Single(s) if s == support) {
                let swing = support.other();
                let i = usize::from(swing == Side::Right);
                out.push((swing, w[1].feet[i]));
            }
        }
    }
    out
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
    play(s, kind, rate, seed, cfg, model, false).map(|(r, _)| r)
}

/// [`run_case`], and the candump log of every frame the bus delivered (the controller's, the
/// node's, a flood's), for `host-sim replay` or the QEMU image's player.
pub fn run_case_logged(
    s: &Scenario,
    kind: FaultKind,
    rate: f64,
    seed: u64,
) -> Result<(CaseResult, Vec<String>), String> {
    play(
        s,
        kind,
        rate,
        seed,
        NodeConfig::hrp2(),
        &Model::hrp2(),
        true,
    )
}

fn play(
    s: &Scenario,
    kind: FaultKind,
    rate: f64,
    seed: u64,
    cfg: NodeConfig,
    model: &Model,
    record: bool,
) -> Result<(CaseResult, Vec<String>), String> {
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
            faults.silence_ns = Some((at, u64::MAX));
        }
        FaultKind::Mixed(i) => {
            let m = HEAVY.get(i).ok_or("no such mixed row")?;
            faults.drop = m.drop;
            faults.corrupt = m.corrupt;
            faults.delay = m.delay;
            faults.delay_ns = m.delay_ns;
        }
        FaultKind::None | FaultKind::Flood | FaultKind::Burst => {}
    }
    let bus = Bus::new(1_000_000, 4, faults, seed.wrapping_mul(2).wrapping_add(1));
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
    let mut seq: u8 = 0;
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
        let t0 = k * 5 * ms;
        bus.advance(t0);
        // 1. The scenario's commands due now.
        let mut issue: Vec<Outgoing> = Vec::new();
        while next < s.timeline.len() && s.timeline[next].0 <= k {
            let (_, command) = s.timeline[next];
            next += 1;
            let mut control = |op| {
                seq = seq.wrapping_add(1);
                Command::Control { seq, op }
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
                scenario::Command::Start => issue.push((control(ControlOp::Start), None, false)),
                scenario::Command::Stop => issue.push((control(ControlOp::Stop), None, false)),
                scenario::Command::StopNow => {
                    issue.push((control(ControlOp::StopNow), None, false))
                }
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
            if let (Command::Modify(_), Some((id, _))) = (&cmd, step) {
                for p in pending.iter_mut() {
                    if matches!(p.cmd, Command::Modify(_)) && p.step.map(|s| s.0) == Some(id) {
                        p.superseded = true;
                    }
                }
            }
            if let (Some(id), Some((_, f))) = (cmd.step_id(), step) {
                let id = u16::from(id);
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
                let _ = ctl.transmit(&p.cmd.encode());
            }
        }
        if k % 20 == 0 {
            let hb = Command::Control {
                seq: (k / 20) as u8,
                op: ControlOp::Heartbeat,
            };
            let _ = ctl.transmit(&hb.encode());
        }
        // 4. The node's cycle (the babbling port runs with the bus).
        flood.run(&bus, t0, t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let mut tap = Tap {
            port: &mut nport,
            sent: Vec::new(),
        };
        let report = node.poll(now_ms, &mut tap);
        // What the node accepted, from its own answers as it sent them (before the bus).
        for a in tap.sent.iter().filter_map(Ack::decode) {
            if let (0x00 | 0x01, None, Some(v)) = (a.command, a.reason, a.version) {
                let id = u16::from(a.seq);
                if let Some(&(f, u)) = versions.get(&(id, v)) {
                    take(&mut node_accepted, id, f, u);
                }
            }
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
            .all(|id| tap.sent.iter().filter(|f| f.id == *id).count() == 1);
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
            if let Some(a) = Ack::decode(&f) {
                // Every answer about a footstep tells its version in force, whatever the
                // answer (a refused newer modification leaves an older one in force).
                if let (0x00 | 0x01, Some(v)) = (a.command, a.version) {
                    let id = u16::from(a.seq);
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
                    None | Some(Reason::Duplicate) => confirm.push(i),
                    Some(r) => {
                        p.open = false;
                        // A refused modification leaves an older version in force, and older
                        // versions still in flight (superseded, their answers lost) could be
                        // taken after it: pin the step with a new version at the pose in force,
                        // which makes every older one stale.
                        let (pin, cmd) = (p.pin, p.cmd);
                        if let (false, Command::Modify(m), Some(v)) = (pin, cmd, a.version) {
                            let id = u16::from(m.id);
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
        if stream.tick != (node.cycles() & 0xFF) as u8 {
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
    let (mut lost, mut cancelled) = (0, 0);
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
    let mut from = 0;
    for (_, f, _) in &accepted {
        match (from..walked.len()).find(|&i| !used[i] && matches(f, &walked[i])) {
            Some(i) => {
                used[i] = true;
                from = i + 1;
            }
            None if safety_stop => cancelled += 1,
            None => lost += 1,
        }
    }
    // Landings nobody asked for: a safety stop's closing step is expected (one).
    let stray = used.iter().filter(|u| !**u).count();
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
        trajectory,
    };
    Ok((result, bus.log()))
}

/// One row of the table: one fault kind at one rate over scenarios and seeds.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// Fault kind.
    pub kind: FaultKind,
    /// Rate.
    pub rate: f64,
    /// Runs.
    pub runs: usize,
    /// Runs that fell.
    pub falls: usize,
    /// Lost commands, summed.
    pub lost: usize,
    /// Footsteps cancelled by a safety stop, summed.
    pub cancelled: usize,
    /// Footsteps whose version in force the controller got wrong (it believed another version
    /// taken, or one taken that was not), summed: what an unlucky controller would not know.
    pub misinformed: usize,
    /// Commands unanswered after every retransmission, summed.
    pub unanswered: usize,
    /// Retransmissions, summed.
    pub retransmissions: usize,
    /// Runs with a safety stop of the node.
    pub safety_stops: usize,
    /// Largest multi-body ZMP error \[m\].
    pub max_zmp_error: f64,
    /// Largest distance of the multi-body ZMP outside the support polygon \[m\].
    pub max_outside: f64,
    /// Node cycles without exactly one finite reference, summed.
    pub ticks_without_reference: usize,
    /// Ticks whose reference the controller did not receive, summed.
    pub stream_gaps: usize,
    /// Ticks run, summed.
    pub ticks: usize,
    /// Runs the model could not follow to the end (a leg out of reach).
    pub out_of_reach: usize,
    /// Largest bus load of a run.
    pub max_bus_load: f64,
    /// Model errors seen.
    pub model_errors: Vec<String>,
}

/// Runs the sweep over [`SWEEP`] × [`SCENARIOS`] × `seeds` seeds (1 … seeds), then the
/// [`HEAVY`] rows with `heavy_seeds` seeds.
pub fn sweep(seeds: u64, heavy_seeds: u64) -> Result<Vec<SweepRow>, String> {
    let scenarios: Vec<Scenario> = SCENARIOS
        .iter()
        .map(|n| scenario::built_in(n).ok_or_else(|| format!("no scenario {n}")))
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::new();
    let heavy: Vec<(FaultKind, &[f64])> = (0..HEAVY.len())
        .map(|i| (FaultKind::Mixed(i), &[0.0][..]))
        .collect();
    for (kind, rates) in SWEEP.iter().copied().chain(heavy) {
        for &rate in rates {
            let mut row = SweepRow {
                kind,
                rate,
                runs: 0,
                falls: 0,
                lost: 0,
                cancelled: 0,
                unanswered: 0,
                misinformed: 0,
                retransmissions: 0,
                safety_stops: 0,
                max_zmp_error: 0.0,
                max_outside: 0.0,
                ticks_without_reference: 0,
                stream_gaps: 0,
                ticks: 0,
                out_of_reach: 0,
                max_bus_load: 0.0,
                model_errors: Vec::new(),
            };
            let seeds_here = match kind {
                FaultKind::None => 1,
                FaultKind::Mixed(_) => heavy_seeds,
                _ => seeds,
            };
            for s in &scenarios {
                for seed in 1..=seeds_here {
                    let r = run_case(s, kind, rate, seed)?;
                    row.runs += 1;
                    row.falls += usize::from(r.fell);
                    row.lost += r.lost;
                    row.cancelled += r.cancelled;
                    row.unanswered += r.unanswered;
                    row.misinformed += r.misinformed;
                    row.retransmissions += r.retransmissions;
                    row.safety_stops += usize::from(r.safety_stop);
                    row.max_zmp_error = row.max_zmp_error.max(r.max_zmp_error);
                    row.max_outside = row.max_outside.max(r.max_outside);
                    row.ticks_without_reference += r.ticks_without_reference;
                    row.stream_gaps += r.stream_gaps;
                    row.ticks += r.ticks;
                    row.out_of_reach += usize::from(r.model_error.is_some());
                    row.max_bus_load = row.max_bus_load.max(r.bus_load);
                    if let Some(e) = r.model_error {
                        row.model_errors
                            .push(format!("{} seed {seed}: {e}", s.name));
                    }
                }
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

/// The table of [`sweep`] rows as Markdown.
pub fn markdown(rows: &[SweepRow]) -> String {
    let mut out = String::from(
        "| fault | rate | runs | falls | lost commands | max multi-body ZMP error (mm) | \
         max ZMP outside polygon (mm) | leg out of reach (runs) | cancelled by safety stop | \
         unanswered | controller misinformed | retransmissions | safety stops | \
         cycles without reference | stream ticks missed by controller | max bus load |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {:.0} % |",
            r.kind.name(),
            r.kind.rate_label(r.rate),
            r.runs,
            r.falls,
            r.lost,
            r.max_zmp_error * 1e3,
            r.max_outside * 1e3,
            r.out_of_reach,
            r.cancelled,
            r.unanswered,
            r.misinformed,
            r.retransmissions,
            r.safety_stops,
            r.ticks_without_reference,
            r.stream_gaps,
            r.ticks,
            r.max_bus_load * 100.0,
        );
    }
    out
}

/// The sweep with 3 seeds, as Markdown (or the error).
pub fn sweep_markdown() -> String {
    match sweep(3, 10) {
        Ok(rows) => markdown(&rows),
        Err(e) => format!("sweep failed: {e}\n"),
    }
}
