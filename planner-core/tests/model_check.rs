//! Model check of the session protocol (stateright): every interleaving, up to a bound, of an
//! honest controller, a hostile bus and **the node's own code**.
//!
//! * **Controller**: sends a script of commands in order (the handshake, footsteps, control
//!   commands, an `ESTOP`), each command once, numbered as the protocol says (sequence numbers
//!   from one counter, step numbers from the node's `DIAG`, versions one up), in the session
//!   it has opened; after a `Reset` it sends nothing until the node has accepted it (it reads
//!   `SESSION`; the node-to-controller direction is not attacked here).
//! * **Bus**: delivers, in any cycle and in any order, any frame the controller ever sent —
//!   never, once, or again and again. That is every delay, loss, duplication, reordering
//!   and replay of the controller's frames.
//! * **Node**: [`Node::poll`] once per cycle on what the bus delivered in it.
//!
//! The counters start where they wrap: the session tag runs 0xFFFF → 0x0000 at the second
//! `Reset`, the step numbers 0xFFFE, 0xFFFF, 0x0000 (16-bit wrap and a new high byte), then 256
//! on (a new session: the old numbers' low bytes come back), the sequence numbers end at
//! `u32::MAX`. So the bus can offer the node, in a later session, old frames whose low bytes,
//! tags and versions alias the new ones.
//!
//! Properties, in every state reached:
//! 1. **nothing old is taken**: an accepted control command has a sequence number above every
//!    one accepted before; an accepted append a step number never accepted; an accepted
//!    modification a version above every one accepted for its step; no frame but an `ESTOP`
//!    is accepted twice;
//! 2. **nothing from an earlier session changes anything**: every accepted frame (but an
//!    `ESTOP`, which belongs to no session) was sent in the session open when it was taken;
//! 3. **a step is walked only at a pose the controller sent for it in this session**: every
//!    queued step's pose is one the controller sent for that number in the current session;
//! 4. **alive only by something new**: the node counts the controller as heard in a cycle only
//!    if it accepted a command then (new, by 1); and a robot that moves and is not stopped by
//!    supervision heard one within the timeout (2 cycles here);
//! 5. **every `ESTOP` in its cycle**: after a cycle in which one was delivered, the node is
//!    emergency-stopped with nothing queued — with the node holding 2 commands a cycle of the
//!    3 delivered, so that a cycle can hold more frames than the node acts on: the frame left
//!    out is refused `Busy`, and an `ESTOP` is never the one;
//! 6. **a refusal changes nothing**: the node equals ([`Node::same_state`]) a copy that ran
//!    the cycle with the accepted frames only; and every frame is answered once.
//!
//! By 6, the node's state is a function of the frames it accepted and when: the checker
//! identifies states by that history (with the controller's and the bus's state), which is
//! what makes the search finite.
//!
//! Walking at a velocity has a script of its own: `VELOCITY` frames are control commands of
//! the session (properties 1, 2, 4 and 6 as for `CONTROL`), so a replayed, repeated or older
//! velocity frame keeps a robot walking no more than a replayed heartbeat does: the node
//! chooses its steps, and stops as for a lost controller when nothing new arrives (4).
//!
//! The estimator's measured states (`MEASURED`) have a script of their own: taken only at most
//! 4 cycles old and newer than every one taken before (besides 1, 2 and 6), never counted as
//! the controller heard (4).
//!
//! Bounds: 2 scripts, at most 3 frames a cycle (the node holds 2), 6 cycles (`WALK_LONG=1`: 7
//! cycles). The front
//! page's "Headline figures" quote the bounds and each script's states (in millions):
//! each check asserts that they are the measured ones (at the default bound).

mod common;

use std::hash::{Hash, Hasher};
use std::sync::OnceLock;

use common::Bus;

use planner_core::gait::PREVIEW;
use planner_core::node::{Node, NodeConfig, NodeState};
use planner_core::shaping::{Law, PreviewGains};
use planner_core::wire::{
    Ack, Command, ControlOp, Measured, RawFrame, Reason, WireModify, WireStep, WireVelocity,
};
use stateright::{Checker, Model, Property};

type Gains = PreviewGains<f64, PREVIEW>;
type M = Node<8, &'static Gains>;

/// The start-up entropy: epoch 0xFFFE_FFFE (tags 0xFFFF, then 0x0000), first step 0xFFFE.
const ENTROPY: u32 = 0xFFFE_FFFE;

/// A controller's intent; footsteps refer to the script's appends by slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Intent {
    Control(ControlOp),
    /// Append slot `slot` (the script's order), `left`, at x (mm), nominal width.
    Append {
        slot: u8,
        left: bool,
        x_mm: i16,
    },
    /// A new version of slot `slot` at x (mm).
    Modify {
        slot: u8,
        x_mm: i16,
    },
    Estop,
    /// A measured state against the last reference the node published (the estimator's).
    Measure,
    /// A `VELOCITY` forward at `vx` (mm/s), numbered with the control commands.
    Velocity {
        vx_mm: i16,
    },
}

use Intent::*;

/// A frame the controller sent, with what the properties need to know of it.
#[derive(Clone, Copy, Debug)]
struct Sent {
    frame: RawFrame,
    /// The epoch it was sent in (`None`: an `ESTOP`).
    epoch: Option<u32>,
    kind: Kind,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Control {
        seq: u32,
    },
    Append {
        number: u16,
        pose: Pose,
    },
    Modify {
        number: u16,
        version: u8,
        pose: Pose,
    },
    Estop,
    /// A measured state naming node cycle `at`.
    Measured {
        at: u32,
    },
}

/// What a search must reach: a name and a condition.
type Goal = (&'static str, fn(&S) -> bool);

/// A footstep pose as the node reads it from the wire (side, x, y, yaw).
type Pose = (bool, f64, f64, f64);

/// What the controller keeps.
#[derive(Clone, Debug, Hash)]
struct Ctl {
    /// Next intent of the script.
    pc: usize,
    seq: u32,
    /// The epoch of the session it has opened (the start-up's, until the handshake).
    epoch: u32,
    /// The next step number (from `DIAG`).
    next: u16,
    /// The `Reset` waiting to be accepted (its sequence number).
    waiting: Option<u32>,
    /// Per slot: the append (number, fields) and its last version.
    slots: Vec<Option<(WireStepKey, u8)>>,
    /// The node's cycles so far (the estimator stamps its states with the last one).
    cycle: u32,
}

/// `WireStep` with `Hash`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct WireStepKey {
    id: u16,
    left: bool,
    x: i32,
    y: i32,
    yaw: i16,
}

impl From<WireStepKey> for WireStep {
    fn from(k: WireStepKey) -> Self {
        WireStep {
            id: k.id,
            left: k.left,
            x: k.x,
            y: k.y,
            yaw: k.yaw,
        }
    }
}

#[derive(Clone)]
struct S {
    node: M,
    ctl: Ctl,
    sent: Vec<Sent>,
    /// Frames (indices into `sent`) the bus delivers in the next cycle, in order.
    pending: Vec<u8>,
    /// Frames accepted: (cycle, index into `sent`).
    accepted: Vec<(u32, u8)>,
    /// The last cycle in which a command other than an `ESTOP` was accepted.
    last_new: u32,
    cycles: u32,
    /// The first property broken, if any.
    broken: Option<String>,
}

impl Hash for S {
    fn hash<H: Hasher>(&self, h: &mut H) {
        self.ctl.hash(h);
        for s in &self.sent {
            (s.frame.id, s.frame.len, s.frame.data).hash(h);
        }
        self.pending.hash(h);
        self.accepted.hash(h);
        self.cycles.hash(h);
        self.broken.hash(h);
    }
}

impl S {
    fn key(&self) -> impl PartialEq + '_ {
        (
            &self.ctl.pc,
            &self.ctl.seq,
            &self.ctl.epoch,
            &self.ctl.next,
            &self.ctl.waiting,
            &self.ctl.slots,
            self.sent.iter().map(|s| s.frame).collect::<Vec<_>>(),
            &self.pending,
            &self.accepted,
            &self.cycles,
            &self.broken,
        )
    }
}

impl PartialEq for S {
    fn eq(&self, other: &Self) -> bool {
        self.key() == other.key()
    }
}

impl std::fmt::Debug for S {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("S")
            .field("state", &self.node.state())
            .field("session", &self.node.session())
            .field("next_step", &self.node.next_step())
            .field("ctl", &self.ctl)
            .field("pending", &self.pending)
            .field("accepted", &self.accepted)
            .field("cycles", &self.cycles)
            .field("broken", &self.broken)
            .finish()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Action {
    /// The controller sends its next intent.
    Send,
    /// The bus delivers `sent[i]` in the next cycle.
    Deliver(u8),
    /// One cycle of the node.
    Cycle,
}

struct Protocol {
    script: Vec<Intent>,
    /// What the search must reach (not vacuous): a name and a condition.
    goals: Vec<Goal>,
    cfg: NodeConfig,
    gains: &'static Gains,
    per_cycle: usize,
    max_cycles: u32,
}

fn gains(cfg: &NodeConfig) -> &'static Gains {
    static G: OnceLock<&'static Gains> = OnceLock::new();
    G.get_or_init(|| {
        let g = Gains::new(&cfg.params.preview_config(), Law::FromRest).expect("gains");
        Box::leak(Box::new(g))
    })
}

fn cycle(node: &mut M, cycles: u32, frames: &[RawFrame]) -> Vec<Ack> {
    let mut bus = Bus {
        rx: frames.iter().copied().collect(),
        tx: vec![],
    }; // (the rigs' in-memory device)
    node.poll(5 * cycles, &mut bus);
    bus.tx.iter().filter_map(Ack::decode).collect()
}

impl Protocol {
    fn new(script: Vec<Intent>, goals: Vec<Goal>, long: bool) -> Self {
        let mut cfg = NodeConfig::hrp2();
        cfg.entropy = ENTROPY;
        cfg.heartbeat_timeout_ms = 10; // 2 cycles: supervision within the bound
        cfg.velocity_timeout_ms = 10; // (and the velocity stream's)
                                      // Fewer commands held a cycle than the bus delivers: the receive's ranking (an `ESTOP`
                                      // takes the place of another frame, which is refused `Busy`) is within the bound.
        cfg.max_rx = 2;
        let gains = gains(&cfg);
        Self {
            script,
            goals,
            cfg,
            gains,
            per_cycle: 3,
            max_cycles: if long { 7 } else { 6 },
        }
    }

    /// The frame of the controller's next intent, and the controller after sending it.
    fn send(&self, ctl: &Ctl) -> Option<(Ctl, Sent)> {
        let mut c = ctl.clone();
        let intent = *self.script.get(c.pc)?;
        c.pc += 1;
        let epoch = Some(c.epoch);
        let y = |left: bool| if left { 0.1 } else { -0.1 };
        let pose = |s: &WireStep| {
            let (x, y, yaw) = s.si();
            (s.left, x, y, yaw)
        };
        let sent = match intent {
            Control(op) => {
                c.seq += 1;
                if op == ControlOp::Reset {
                    c.waiting = Some(c.seq);
                }
                let cmd = Command::Control {
                    session: c.epoch as u16,
                    seq: c.seq,
                    op,
                };
                Sent {
                    frame: cmd.encode(),
                    epoch,
                    kind: Kind::Control { seq: c.seq },
                }
            }
            Append { slot, left, x_mm } => {
                let s = WireStep::from_si(c.next, left, f64::from(x_mm) / 1e3, y(left), 0.0)?;
                c.next = c.next.wrapping_add(1);
                let key = WireStepKey {
                    id: s.id,
                    left: s.left,
                    x: s.x,
                    y: s.y,
                    yaw: s.yaw,
                };
                *c.slots.get_mut(usize::from(slot))? = Some((key, 0));
                Sent {
                    frame: Command::Append(s).encode(),
                    epoch,
                    kind: Kind::Append {
                        number: s.id,
                        pose: pose(&s),
                    },
                }
            }
            Modify { slot, x_mm } => {
                let (key, v) = (*c.slots.get(usize::from(slot))?)?;
                let base = WireStep::from(key);
                let m = WireModify::from_si(&base, v + 1, f64::from(x_mm) / 1e3, y(key.left), 0.0)?;
                *c.slots.get_mut(usize::from(slot))? = Some((key, v + 1));
                let applied = m.applied_to(&base)?;
                Sent {
                    frame: Command::Modify(m).encode(),
                    epoch,
                    kind: Kind::Modify {
                        number: m.id,
                        version: m.version,
                        pose: pose(&applied),
                    },
                }
            }
            Estop => Sent {
                frame: Command::EmergencyStop { seq: 1 }.encode(),
                epoch: None,
                kind: Kind::Estop,
            },
            Velocity { vx_mm } => {
                c.seq += 1;
                let v = WireVelocity::from_si(c.seq, f64::from(vx_mm) / 1e3, 0.0, 0.0);
                Sent {
                    frame: v.encode(c.epoch),
                    epoch,
                    // (A control command of the session: properties 1, 2 and 4 as `CONTROL`.)
                    kind: Kind::Control { seq: c.seq },
                }
            }
            Measure => {
                let m = Measured::from_si(c.cycle, [0.01, -0.02])?;
                Sent {
                    frame: m.encode(c.epoch),
                    epoch,
                    kind: Kind::Measured { at: c.cycle },
                }
            }
        };
        Some((c, sent))
    }

    /// One cycle and the properties it must keep (the first broken one, if any).
    fn run_cycle(&self, s: &mut S) -> Result<(), String> {
        let before = s.node.clone();
        let batch: Vec<RawFrame> = s
            .pending
            .iter()
            .map(|&i| s.sent[usize::from(i)].frame)
            .collect();
        s.cycles += 1;
        let acks = cycle(&mut s.node, s.cycles, &batch);
        // 6: every frame answered once; which were accepted.
        if acks.len() != batch.len() {
            return Err(format!("{} frames, {} answers", batch.len(), acks.len()));
        }
        let mut taken: Vec<u8> = vec![];
        for a in acks.iter().filter(|a| a.reason.is_none()) {
            let mut matching = s.pending.iter().filter(|&&i| {
                let f = &s.sent[usize::from(i)].frame;
                a.command == (f.id & 0xFF) as u8
                    && a.echo == planner_core::wire::echo_of(f)
                    && answer_key(&s.sent[usize::from(i)]) == a.seq
            });
            let Some(&i) = matching.next() else {
                return Err(format!("an acceptance of no frame delivered: {a:?}"));
            };
            if matching.any(|&j| s.sent[usize::from(j)].frame != s.sent[usize::from(i)].frame) {
                return Err("two delivered frames share an answer: widen the script".into());
            }
            taken.push(i);
        }
        // The accepted frames in the order the node answered them (its order of acting).
        let mut only = before.clone();
        let dedup: Vec<RawFrame> = taken
            .iter()
            .map(|&i| s.sent[usize::from(i)].frame)
            .collect();
        let _ = cycle(&mut only, s.cycles, &dedup);
        if !only.same_state(&s.node) {
            return Err("the refused frames of the cycle changed the node".into());
        }
        // 1, 2: nothing old, nothing of another session.
        let epoch = before.session().epoch;
        for &i in &taken {
            let sent = s.sent[usize::from(i)];
            if sent.kind == Kind::Estop {
                continue;
            }
            if sent.epoch != Some(epoch) {
                return Err(format!(
                    "frame {i} of epoch {:?} taken in epoch {epoch:#x}",
                    sent.epoch
                ));
            }
            if s.accepted.iter().any(|&(_, j)| j == i) {
                return Err(format!("frame {i} accepted twice"));
            }
            let earlier = s.accepted.iter().map(|&(_, j)| s.sent[usize::from(j)].kind);
            match sent.kind {
                Kind::Control { seq } => {
                    if earlier
                        .clone()
                        .any(|k| matches!(k, Kind::Control { seq: q } if q >= seq))
                    {
                        return Err(format!("control seq {seq} not above an accepted one"));
                    }
                }
                Kind::Append { number, .. } => {
                    if earlier
                        .clone()
                        .any(|k| matches!(k, Kind::Append { number: n, .. } if n == number))
                    {
                        return Err(format!("step number {number:#x} appended twice"));
                    }
                }
                Kind::Modify {
                    number, version, ..
                } => {
                    if earlier.clone().any(|k| {
                        matches!(k, Kind::Modify { number: n, version: v, .. }
                            if n == number && v >= version)
                    }) {
                        return Err(format!("version {version} of {number:#x} not newer"));
                    }
                }
                Kind::Estop => {}
                Kind::Measured { at } => {
                    // Fresh: at most the node's 4 cycles old; newer than every one taken.
                    let age = s.cycles - 1 - at;
                    if age > 4 {
                        return Err(format!("a measured state {age} cycles old taken"));
                    }
                    if earlier
                        .clone()
                        .any(|k| matches!(k, Kind::Measured { at: a } if a >= at))
                    {
                        return Err(format!("a measured state of cycle {at} not newer"));
                    }
                }
            }
        }
        // A command proves the controller alive; an emergency stop or a measured state not.
        let proves = |k: Kind| !matches!(k, Kind::Estop | Kind::Measured { .. });
        for &i in &taken {
            s.accepted.push((s.cycles, i));
            if proves(s.sent[usize::from(i)].kind) {
                s.last_new = s.cycles;
            }
        }
        // 3: every queued step at a pose sent for it in this session.
        let now = s.node.session().epoch;
        let first = (ENTROPY >> 16) as u16;
        for sent in &s.sent {
            let Kind::Append { number, .. } = sent.kind else {
                continue;
            };
            let Some(step) = s.node.gait().queued_step(number.wrapping_sub(first)) else {
                continue;
            };
            let walked = (
                step.side == planner_core::gait::Side::Left,
                step.x,
                step.y,
                step.yaw,
            );
            let sent_now = s.sent.iter().any(|o| {
                o.epoch == Some(now)
                    && matches!(o.kind,
                        Kind::Append { number: n, pose } | Kind::Modify { number: n, pose, .. }
                        if n == number && pose == walked)
            });
            if !sent_now {
                return Err(format!(
                    "step {number:#x} queued at {walked:?}, not a pose sent in epoch {now:#x}"
                ));
            }
        }
        // 4: heard only by something accepted; a moving robot heard within the timeout.
        let heard =
            s.node.last_heard() == Some(5 * s.cycles) && before.last_heard() != s.node.last_heard();
        if heard && !taken.iter().any(|&i| proves(s.sent[usize::from(i)].kind)) {
            return Err("heard without a new command".into());
        }
        let moving = !s.node.gait().is_standing();
        if moving && s.node.state() == NodeState::Walking && s.cycles.saturating_sub(s.last_new) > 2
        {
            return Err(format!(
                "walking {} cycles after the last new command",
                s.cycles - s.last_new
            ));
        }
        // 5: every ESTOP in its cycle.
        let estop = batch.iter().any(|f| f.id == planner_core::wire::ids::ESTOP);
        if estop && (s.node.state() != NodeState::EmergencyStopped || s.node.gait().queued() != 0) {
            return Err(format!("an ESTOP delivered, the node {:?}", s.node.state()));
        }
        s.pending.clear();
        s.ctl.cycle = s.cycles;
        // The controller reads SESSION and DIAG: a reset accepted opens its session.
        if let Some(q) = s.ctl.waiting {
            if s.node.session().last_seq == q {
                s.ctl.epoch = s.node.session().epoch;
                s.ctl.next = s.node.next_step();
                s.ctl.waiting = None;
            }
        }
        Ok(())
    }
}

/// The low byte an `ACK` carries of the command it answers (`Ack::seq`).
fn answer_key(s: &Sent) -> u8 {
    match s.kind {
        Kind::Control { seq } => seq as u8,
        Kind::Append { number, .. } | Kind::Modify { number, .. } => number as u8,
        Kind::Estop => 1,
        Kind::Measured { at } => at as u8,
    }
}

impl Protocol {
    /// Goal `k` holds in `s` (a script with fewer goals: trivially).
    fn goal(&self, k: usize, s: &S) -> bool {
        self.goals.get(k).is_none_or(|g| (g.1)(s))
    }
}

impl Model for Protocol {
    type State = S;
    type Action = Action;

    fn init_states(&self) -> Vec<S> {
        let node = M::with_gains(self.cfg, self.gains).expect("node");
        let controls = self
            .script
            .iter()
            .filter(|i| matches!(i, Control(_) | Velocity { .. }))
            .count() as u32;
        let slots = self
            .script
            .iter()
            .filter(|i| matches!(i, Append { .. }))
            .count();
        vec![S {
            ctl: Ctl {
                pc: 0,
                // The last control command of the script has sequence number u32::MAX.
                seq: u32::MAX - controls,
                epoch: node.session().epoch,
                next: node.next_step(),
                waiting: None,
                slots: vec![None; slots],
                cycle: 0,
            },
            node,
            sent: vec![],
            pending: vec![],
            accepted: vec![],
            last_new: 0,
            cycles: 0,
            broken: None,
        }]
    }

    fn actions(&self, s: &S, actions: &mut Vec<Action>) {
        if s.broken.is_some() || s.cycles >= self.max_cycles {
            return;
        }
        actions.push(Action::Cycle);
        if s.pending.len() < self.per_cycle {
            for i in 0..s.sent.len() {
                actions.push(Action::Deliver(i as u8));
            }
        }
        if s.ctl.waiting.is_none() && s.ctl.pc < self.script.len() {
            actions.push(Action::Send);
        }
    }

    fn next_state(&self, s: &S, a: Action) -> Option<S> {
        let mut n = s.clone();
        match a {
            Action::Send => {
                let (c, sent) = self.send(&s.ctl)?;
                n.ctl = c;
                n.sent.push(sent);
            }
            Action::Deliver(i) => n.pending.push(i),
            Action::Cycle => {
                if let Err(e) = self.run_cycle(&mut n) {
                    n.broken = Some(e);
                }
            }
        }
        Some(n)
    }

    fn properties(&self) -> Vec<Property<Self>> {
        vec![
            Property::always("the protocol's properties hold", |_, s: &S| {
                s.broken.is_none()
            }),
            // Not vacuous: the search reaches each goal of the script (at most 4).
            Property::sometimes("goal 1", |m: &Protocol, s: &S| m.goal(0, s)),
            Property::sometimes("goal 2", |m: &Protocol, s: &S| m.goal(1, s)),
            Property::sometimes("goal 3", |m: &Protocol, s: &S| m.goal(2, s)),
            Property::sometimes("goal 4", |m: &Protocol, s: &S| m.goal(3, s)),
        ]
    }
}

/// Checks the model of `script`; `quoted`: what the front page's model-check row and the
/// book's sentence on the bound (`docs/src/reliability.md`) must say of its state count (given
/// the states generated in millions with one decimal, `9.2`), checked at the default bound
/// (not with `WALK_LONG=1`).
fn check(name: &str, script: Vec<Intent>, goals: Vec<Goal>, quoted: Option<Quoted>) {
    let long = std::env::var("WALK_LONG").as_deref() == Ok("1");
    let names: Vec<&str> = goals.iter().map(|g| g.0).collect();
    let model = Protocol::new(script, goals, long);
    let (per, cycles) = (model.per_cycle, model.max_cycles);
    let checker = model.checker().threads(2).spawn_dfs().join();
    eprintln!(
        "{name}: {} states ({} unique), depth {}, {per} frames a cycle, {cycles} cycles; goals {names:?}",
        checker.state_count(),
        checker.unique_state_count(),
        checker.max_depth(),
    );
    checker.assert_properties();
    if let (false, Some(quoted)) = (long, quoted) {
        // The front page and the book quote the bounds and the states generated ("9.2 M",
        // "9.2 million").
        let millions = format!("{:.1}", checker.state_count() as f64 / 1e6);
        let row = "| protocol model check (";
        let bounds = format!("{per} frames a cycle, {cycles} cycles");
        doc_figures::Quotes::new(COMMAND)
            .line("README.md", row, &bounds)
            .line("README.md", row, &(quoted.readme)(&millions))
            .line(BOOK, BOOK_ANCHOR, &bounds)
            .line(BOOK, BOOK_ANCHOR, &(quoted.book)(&millions))
            .assert();
    }
}

/// How the documents quote one model's state count, given in millions with one decimal.
struct Quoted {
    /// In the front page's row: `| 9.2 M + `.
    readme: fn(&str) -> String,
    /// In the book's sentence: `cycles: 9.2, `.
    book: fn(&str) -> String,
}

/// The book's page that states the model check's bound and its state counts.
const BOOK: &str = "docs/src/reliability.md";
/// The line of that page with them.
const BOOK_ANCHOR: &str = "supervision at 2 cycles), at most";

/// The command that measures this file's figures (the front page names it).
const COMMAND: &str = "cargo test --release -p planner-core --test model_check -- --nocapture";

/// Two sessions: appends and a modification in the first, one append possibly still in flight
/// at the `Reset`, an emergency stop that the `Reset` leaves (the bus may deliver both in one
/// cycle), then appends and a modification in the second whose numbers' low bytes and
/// versions are the old ones'.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: tests/run-all.sh runs it with --release"
)]
fn across_a_reset_nothing_old_is_taken() {
    check(
        "across a reset",
        vec![
            Control(ControlOp::Reset),
            Append {
                slot: 0,
                left: false,
                x_mm: 100,
            },
            Append {
                slot: 1,
                left: true,
                x_mm: 200,
            },
            Modify { slot: 1, x_mm: 220 },
            Append {
                slot: 2,
                left: false,
                x_mm: 300,
            },
            Estop,
            Control(ControlOp::Reset),
            Append {
                slot: 3,
                left: false,
                x_mm: 120,
            },
            Modify { slot: 3, x_mm: 140 },
            Append {
                slot: 4,
                left: true,
                x_mm: 240,
            },
        ],
        vec![
            ("the first session queues two steps", |s| {
                s.node.session().epoch == ENTROPY + 1 && s.node.gait().queued() >= 2
            }),
            ("the second session queues a step", |s| {
                s.node.session().epoch == ENTROPY + 2 && s.node.gait().queued() > 0
            }),
            ("an old footstep frame refused in the second session", |s| {
                s.node.session().epoch == ENTROPY + 2
                    && s.node.counters().by_reason[usize::from(Reason::BadCrc.code())] > 0
            }),
        ],
        // The first of the documents' two counts.
        Some(Quoted {
            readme: |m| format!("| {m} M + "),
            book: |m| format!("cycles: {m}, "),
        }),
    );
}

/// One session walking: a start, a modification, a heartbeat, a stop now and an emergency stop;
/// supervision at 2 cycles.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: tests/run-all.sh runs it with --release"
)]
fn walking_only_new_commands_keep_it_going_and_an_estop_never_waits() {
    check(
        "walking",
        vec![
            Control(ControlOp::Reset),
            Append {
                slot: 0,
                left: false,
                x_mm: 100,
            },
            Append {
                slot: 1,
                left: true,
                x_mm: 200,
            },
            Control(ControlOp::Start),
            Modify { slot: 1, x_mm: 210 },
            Control(ControlOp::Heartbeat),
            Control(ControlOp::StopNow),
            Estop,
        ],
        vec![
            ("walking", |s| s.node.state() == NodeState::Walking),
            ("supervision stops it", |s| {
                s.node.state() == NodeState::ControllerLost && !s.node.gait().is_standing()
            }),
            ("a modification taken while walking", |s| {
                s.node.state() == NodeState::Walking
                    && s.accepted
                        .iter()
                        .any(|&(_, i)| matches!(s.sent[usize::from(i)].kind, Kind::Modify { .. }))
            }),
            ("emergency-stopped while walking", |s| {
                s.node.state() == NodeState::EmergencyStopped && !s.node.gait().is_standing()
            }),
        ],
        // The second of the documents' two counts.
        Some(Quoted {
            readme: |m| format!("+ {m} M + "),
            book: |m| format!(", {m} and "),
        }),
    );
}

/// The estimator's measured states across a `Reset`: taken only while fresh (at most 4 cycles
/// old, newer than the last), only in the session they were stamped in, never twice, and never
/// as a sign of the controller alive; any delay, loss, repeat or reordering by the bus.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: tests/run-all.sh runs it with --release"
)]
fn measured_states_only_fresh_and_of_their_session() {
    check(
        "measured states",
        vec![
            Control(ControlOp::Reset),
            Measure,
            Measure,
            Control(ControlOp::Reset),
            Measure,
        ],
        vec![
            ("a measured state taken in the first session", |s| {
                s.node.session().epoch == ENTROPY + 1
                    && s.accepted
                        .iter()
                        .any(|&(_, i)| matches!(s.sent[usize::from(i)].kind, Kind::Measured { .. }))
            }),
            // (Delivered: property 2 says that it is not taken.)
            ("one of the first session delivered in the second", |s| {
                s.node.session().epoch == ENTROPY + 2
                    && s.pending.iter().any(|&i| {
                        let sent = &s.sent[usize::from(i)];
                        matches!(sent.kind, Kind::Measured { .. })
                            && sent.epoch == Some(ENTROPY + 1)
                    })
            }),
            ("a measured state taken in the second session", |s| {
                s.node.session().epoch == ENTROPY + 2
                    && s.accepted.iter().any(|&(_, i)| {
                        matches!(s.sent[usize::from(i)].kind, Kind::Measured { .. })
                            && s.sent[usize::from(i)].epoch == Some(ENTROPY + 2)
                    })
            }),
            // (Delivered: property 1 says that it is not taken.)
            ("an older one delivered after a newer one was taken", |s| {
                let taken =
                    s.accepted
                        .iter()
                        .filter_map(|&(_, i)| match s.sent[usize::from(i)].kind {
                            Kind::Measured { at } => Some(at),
                            _ => None,
                        });
                let newest = taken.max();
                s.pending.iter().any(|&i| {
                    matches!(s.sent[usize::from(i)].kind, Kind::Measured { at }
                        if newest.is_some_and(|n| at < n))
                })
            }),
        ],
        // The third count.
        Some(Quoted {
            readme: |m| format!("+ {m} M states"),
            book: |m| format!(" and {m} million"),
        }),
    );
}

/// Walking at a velocity: a stream of three `VELOCITY` frames (a start, a change, a stop) and
/// an emergency stop; the bus replays, repeats and reorders them at will, and no replay keeps
/// the robot walking past the supervision's 2 cycles (property 4).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: tests/run-all.sh runs it with --release"
)]
fn a_velocity_stream_keeps_it_walking_only_by_new_frames() {
    check(
        "velocity",
        vec![
            Control(ControlOp::Reset),
            Velocity { vx_mm: 100 },
            Velocity { vx_mm: 150 },
            Velocity { vx_mm: 0 },
            Estop,
        ],
        vec![
            ("walking at a velocity", |s| {
                s.node.state() == NodeState::Walking
                    && s.node.driver() == planner_core::node::Driver::Velocity
            }),
            ("supervision stops it", |s| {
                s.node.state() == NodeState::ControllerLost && !s.node.gait().is_standing()
            }),
            // (Delivered and refused: property 4 says that it keeps nothing alive.)
            ("an old velocity frame refused while walking", |s| {
                !s.node.gait().is_standing()
                    && (s.node.counters().by_reason[usize::from(Reason::Stale.code())] > 0
                        || s.node.counters().by_reason[usize::from(Reason::Duplicate.code())] > 0)
            }),
            ("a change taken while walking", |s| {
                s.node.state() == NodeState::Walking
                    && s.node.drive_velocity().is_some_and(|(v, _)| v.vx > 0.12)
            }),
        ],
        None,
    );
}
