//! The node's step adjustment in closed loop with a robot: a linear inverted pendulum
//! integrated exactly over each 5 ms tick, kept on the node's reference by a divergent-component
//! stabilizer whose ZMP is held inside the support polygon, and pushed (a velocity step) in
//! single support. The robot's state estimator sends the measured DCM deviation (`MEASURED`)
//! every cycle against the reference it was tracking.
//!
//! What holds:
//! * with `Start` the node never moves a step, whatever is measured;
//! * with `StartAdjusting` every landing is where its step was commanded plus the shift the
//!   node published in `ADJUST` (the controller's book stays true), the shift points the way
//!   the robot was pushed, every landing keeps the reach limits, and the capture step's
//!   window starts from the measured state (never without a fresh one);
//! * the largest survivable push (bisection to 1/64 of 1 m/s), pushed at the start of a double
//!   support or 0.15 s into a single support, forward, backward, outward and inward, is never
//!   smaller with the adjustment than without it, and larger in some cells (printed with
//!   `--nocapture`; the book's *Step adjustment* section says where and why not more);
//! * measured states the node must not use (stale, of another session) move nothing.
//! * with the capture step re-planned from the measured state, a state measured against a
//!   reference from before that re-plan is refused `Stale` (one per re-plan with an estimator
//!   a cycle late), and none is with the re-plan from the reference's state.

#[path = "common/mod.rs"]
mod common;

use common::{y, Rig};
use planner_core::gait::{Phase, Side};
use planner_core::node::NodeConfig;
use planner_core::wire::{Ack, Adjust, Command, ControlOp, Measured, Reason};

/// The stabilizer's DCM error gain \[1/s\]: `p = p_ref + (1 + k/ω)(ξ − ξ_ref)`.
const K_DCM: f64 = 3.0;
/// A DCM error beyond this is a fall \[m\] (the pendulum has left every sole for good).
const FALLEN: f64 = 0.35;

/// One pendulum plane.
#[derive(Clone, Copy, Debug)]
struct Plane {
    x: f64,
    v: f64,
}

impl Plane {
    /// Exact over `dt` with the ZMP `p` held.
    fn step(&mut self, p: f64, w: f64, dt: f64) {
        let (c, s) = ((w * dt).cosh(), (w * dt).sinh());
        let x = p + (self.x - p) * c + self.v / w * s;
        let v = (self.x - p) * w * s + self.v * c;
        self.x = x;
        self.v = v;
    }
}

/// What a run gives.
#[derive(Debug, Default)]
struct Outcome {
    fallen: bool,
    worst: f64,
    /// The node's last shift other than 0 during the run \[0.5 mm\], its shift after the run
    /// (the walk ended: 0), and every `ADJUST` seen.
    shift: [i32; 2],
    shift_after: [i32; 2],
    adjusts: Vec<Adjust>,
    /// Landings: (commanded x, y, landed x, y).
    landings: Vec<(f64, f64, f64, f64)>,
    /// Re-plans that started from the measured state (capture steps).
    from_measured: u32,
    /// Measured states refused `Stale`.
    stale: u32,
}

/// A straight walk of `n` steps of `len`, pushed by `dv` (x, y) \[m/s\] `push_at` ticks after
/// the third lift-off; `adjusting` starts it with `StartAdjusting`; `measure` sends the
/// estimator's frames (with `stamp_back` cycles of extra age, and for `epoch_off` sessions
/// before the open one).
fn walk(rig: &Rig, adjusting: bool, dv: [f64; 2], measure: (bool, u32, u32)) -> Outcome {
    walk_pushed(rig, adjusting, dv, measure, PUSH_IN_SINGLE)
}

/// When the push comes: after the `n`-th lift-off (`true`) or landing (`false`), `delay` ticks
/// later.
#[derive(Clone, Copy, Debug)]
struct PushAt {
    liftoff: bool,
    n: u32,
    delay: u32,
}

/// 0.15 s into the third single support.
const PUSH_IN_SINGLE: PushAt = PushAt {
    liftoff: true,
    n: 3,
    delay: 30,
};
/// At the start of the double support before the third lift-off.
const PUSH_IN_DOUBLE: PushAt = PushAt {
    liftoff: false,
    n: 2,
    delay: 1,
};

fn walk_pushed(
    rig: &Rig,
    adjusting: bool,
    dv: [f64; 2],
    measure: (bool, u32, u32),
    at: PushAt,
) -> Outcome {
    walk_on(&mut rig.fork(), adjusting, dv, measure, at)
}

/// [`walk_pushed`] on the rig `r` itself (left standing after the walk).
fn walk_on(
    r: &mut Rig,
    adjusting: bool,
    dv: [f64; 2],
    measure: (bool, u32, u32),
    at: PushAt,
) -> Outcome {
    let n_steps = 10u16;
    let len = 0.2;
    let mut commanded = vec![];
    for i in 0..n_steps {
        let left = i % 2 == 1;
        let x = len * f64::from(i + 1).min(f64::from(n_steps - 1));
        let id = r.n.next_step();
        assert_eq!(r.append(id, left, x, y(left)), None, "step {i}");
        commanded.push((id, x, y(left)));
    }
    let op = if adjusting {
        ControlOp::StartAdjusting
    } else {
        ControlOp::Start
    };
    assert_eq!(r.control(op), None);
    let stop = r.command(ControlOp::Stop);
    r.bus.rx.push_back(stop.encode());
    let p = *r.n.config();
    let (w, dt) = (p.params.omega, p.params.dt);
    let (hl, hw) = (p.params.sole_half_length, p.params.sole_half_width);
    let last = *r.n.gait().last();
    let mut robot = [
        Plane {
            x: last.x.cog,
            v: last.x.cog_vel,
        },
        Plane {
            x: last.y.cog,
            v: last.y.cog_vel,
        },
    ];
    let mut out = Outcome::default();
    let (mut liftoffs, mut landings, mut pushed_at) = (0, 0, None);
    let mut swinging = None;
    for k in 0..2400u32 {
        let reference = *r.n.gait().last();
        let stamp = r.n.cycles();
        // The estimator: the measured DCM less the reference's, against this reference.
        let refs = [reference.x, reference.y];
        let e = [0, 1].map(|i| (robot[i].x + robot[i].v / w) - (refs[i].cog + refs[i].cog_vel / w));
        out.worst = out.worst.max(e[0].hypot(e[1]));
        if e[0].hypot(e[1]) > FALLEN {
            out.fallen = true;
            break;
        }
        // The stabilizer: ZMP from the DCM error, inside the support polygon (the support
        // sole, or the box around both soles in double support).
        let feet = reference.feet;
        let (lo, hi) = match reference.phase {
            Phase::Single(support) => {
                let f = feet[usize::from(support == Side::Right)];
                ([f.x - hl, f.y - hw], [f.x + hl, f.y + hw])
            }
            _ => (
                [feet[0].x.min(feet[1].x) - hl, feet[0].y.min(feet[1].y) - hw],
                [feet[0].x.max(feet[1].x) + hl, feet[0].y.max(feet[1].y) + hw],
            ),
        };
        for i in 0..2 {
            let zmp = refs[i].zmp + (1.0 + K_DCM / w) * e[i];
            robot[i].step(zmp.clamp(lo[i], hi[i]), w, dt);
        }
        if measure.0 {
            let m = Measured::from_si(stamp.wrapping_sub(measure.1), e).unwrap();
            let epoch = r.session.epoch.wrapping_sub(measure.2);
            r.bus.rx.push_back(m.encode(epoch));
        }
        if k % 20 == 0 {
            let hb = r.heartbeat();
            r.bus.rx.push_back(hb.encode());
        }
        r.t += 5;
        let plans = r.n.gait().plans();
        r.n.poll(r.t, &mut r.bus);
        if r.n.shift() != [0, 0] {
            out.shift = r.n.shift();
        }
        if r.n.gait().plans() != plans && r.n.gait().replanned_from_measured() {
            out.from_measured += 1;
        }
        for f in r.bus.tx.drain(..) {
            if let Some(a) = Adjust::decode(&f) {
                out.adjusts.push(a);
            }
            if let Some(a) = Ack::decode(&f) {
                let measured = a.command == (planner_core::wire::ids::MEASURED & 0xFF) as u8;
                out.stale += u32::from(measured && a.reason == Some(Reason::Stale));
            }
        }
        // A lift-off and a landing.
        let s = r.n.gait().swinging();
        if s.is_some() && s != swinging {
            liftoffs += 1;
            if at.liftoff && liftoffs == at.n {
                pushed_at = Some(k + at.delay);
            }
        }
        if let (Some(id), None) = (swinging, s) {
            landings += 1;
            if !at.liftoff && landings == at.n {
                pushed_at = Some(k + at.delay);
            }
            let (_, cx, cy) = commanded.iter().find(|c| c.0 == id).copied().unwrap();
            let side = usize::from(commanded.iter().position(|c| c.0 == id).unwrap() % 2 == 0);
            let f = r.n.gait().feet()[side];
            out.landings.push((cx, cy, f.x, f.y));
        }
        swinging = s;
        if pushed_at == Some(k) {
            robot[0].v += dv[0];
            robot[1].v += dv[1];
        }
        if r.n.gait().is_standing() && k > 100 {
            // The stop window is the reference's own: no flag of a capture step outlives it.
            assert!(!r.n.gait().replanned_from_measured());
            break;
        }
    }
    out.shift_after = r.n.shift();
    out
}

/// The largest push (in 0.025 m/s steps up to 1 m/s) along `dir` that does not fell the robot.
fn largest(rig: &Rig, adjusting: bool, dir: [f64; 2], at: PushAt) -> f64 {
    let (mut lo, mut hi) = (0.0, 1.0);
    while hi - lo > 0.025 {
        let mid = 0.5 * (lo + hi);
        let o = walk_pushed(
            rig,
            adjusting,
            [dir[0] * mid, dir[1] * mid],
            (true, 0, 0),
            at,
        );
        if o.fallen {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

#[test]
fn without_opting_in_nothing_moves() {
    let rig = Rig::new(NodeConfig::hrp2());
    let o = walk(&rig, false, [0.3, 0.0], (true, 0, 0));
    assert_eq!(o.shift, [0, 0]);
    assert_eq!(o.from_measured, 0);
    assert!(o.adjusts.iter().all(|a| a.shift == [0, 0] && a.count == 0));
    for (cx, cy, x, y) in &o.landings {
        assert!(
            (cx - x).abs() < 1e-9 && (cy - y).abs() < 1e-9,
            "{:?}",
            o.landings
        );
    }
}

/// A node whose capture steps are re-planned from the measured state
/// (`AdjustConfig::from_measured`).
fn from_measured() -> NodeConfig {
    let mut cfg = NodeConfig::hrp2();
    cfg.adjust.from_measured = true;
    cfg
}

#[test]
fn an_adjusted_walk_lands_where_adjust_says() {
    for (cfg, measured) in [(NodeConfig::hrp2(), false), (from_measured(), true)] {
        adjusted_walk_lands_where_adjust_says(&Rig::new(cfg), measured);
    }
}

fn adjusted_walk_lands_where_adjust_says(rig: &Rig, measured: bool) {
    let push = [0.35, 0.0];
    let o = walk(rig, true, push, (true, 0, 0));
    assert!(!o.fallen, "{o:?}");
    assert!(
        o.shift[0] > 0,
        "a forward push moves the steps forward: {o:?}"
    );
    // The last shift published is the one the walk had; the walk's end ends it.
    let moved = o.adjusts.iter().rev().find(|a| a.shift != [0, 0]);
    let moved = moved.expect("ADJUST frames");
    assert_eq!(
        [i32::from(moved.shift[0]), i32::from(moved.shift[1])],
        o.shift
    );
    assert!(moved.count > 0);
    let last = o.adjusts.last().unwrap();
    assert_eq!((last.shift, o.shift_after), ([0, 0], [0, 0]), "{last:?}");
    assert!(last.count > moved.count);
    // The capture step's window started from the measured state, where the node says so.
    assert_eq!(o.from_measured > 0, measured, "{o:?}");
    // Every landing is its commanded position plus a shift the node published.
    let published: Vec<[f64; 2]> = o.adjusts.iter().map(Adjust::shift_si).collect();
    for (cx, cy, x, y) in &o.landings {
        let ok = std::iter::once([0.0, 0.0])
            .chain(published.iter().copied())
            .any(|s| (cx + s[0] - x).abs() < 1e-9 && (cy + s[1] - y).abs() < 1e-9);
        assert!(
            ok,
            "landed at ({x}, {y}), commanded ({cx}, {cy}): {published:?}"
        );
    }
}

#[test]
fn stale_or_foreign_measured_states_move_nothing() {
    let rig = Rig::new(from_measured());
    // Older than the node's limit of 4 cycles.
    let o = walk(&rig, true, [0.35, 0.0], (true, 5, 0));
    assert_eq!(o.shift, [0, 0]);
    // Of the session before this one.
    let o = walk(&rig, true, [0.35, 0.0], (true, 0, 1));
    assert_eq!(o.shift, [0, 0]);
    assert_eq!(o.from_measured, 0);
    // None at all.
    let o = walk(&rig, true, [0.35, 0.0], (false, 0, 0));
    assert_eq!(o.shift, [0, 0]);
    assert_eq!(o.from_measured, 0);
}

/// A state measured against a reference from before the window that re-planned from the
/// measured state counts a deviation that window took as its own: with an estimator one cycle
/// late, the one frame of each such re-plan that names the cycle before it is refused `Stale`,
/// and no other frame is (nor any with the re-plan from the reference's state).
#[test]
fn a_state_measured_before_the_reference_stepped_is_stale() {
    let o = walk(&Rig::new(from_measured()), true, [0.3, 0.0], (true, 1, 0));
    assert!(!o.fallen, "{o:?}");
    assert!(o.from_measured > 0, "{o:?}");
    assert_eq!(o.stale, o.from_measured, "{o:?}");
    let o = walk(
        &Rig::new(NodeConfig::hrp2()),
        true,
        [0.3, 0.0],
        (true, 1, 0),
    );
    assert!(o.shift != [0, 0] && o.from_measured == 0, "{o:?}");
    assert_eq!(o.stale, 0, "{o:?}");
}

#[test]
fn the_adjustment_never_lowers_the_survivable_push() {
    let rig = Rig::new(NodeConfig::hrp2());
    let measured = Rig::new(from_measured());
    let (mut better, mut rows) = (0, vec![]);
    for (phase, at) in [
        ("at the start of a double support", PUSH_IN_DOUBLE),
        ("0.15 s into a single support", PUSH_IN_SINGLE),
    ] {
        for (k, (name, dir)) in [
            ("forward", [1.0, 0.0]),
            ("backward", [-1.0, 0.0]),
            ("outward", [0.0, 1.0]),
            ("inward", [0.0, -1.0]),
        ]
        .into_iter()
        .enumerate()
        {
            let plain = largest(&rig, false, dir, at);
            let adjusted = largest(&rig, true, dir, at);
            let from = largest(&measured, true, dir, at);
            let first = if k == 0 { phase } else { "" };
            let row = format!("| {first} | {name} | {plain:.3} | {adjusted:.3} | {from:.3} |");
            eprintln!("{row}");
            rows.push(row);
            // Never worse (to the bisection's resolution) …
            assert!(adjusted >= plain, "{phase}, {name}: {plain} → {adjusted}");
            assert!(from >= plain, "{phase}, {name}: {plain} → {from}");
            better += usize::from(adjusted > plain);
        }
    }
    // … and better somewhere.
    assert!(better > 0);
    // The book quotes this table.
    let book = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/src/adjust.md"
    ))
    .expect("the book");
    for row in rows {
        assert!(
            book.contains(&row),
            "docs/src/adjust.md lacks the row (write it there): {row}"
        );
    }
}

/// A measured state of the session before a `Reset` is refused `BadCrc` (its CRC is keyed with
/// the old session); one stamped before the session opened, re-sealed for the new session, is
/// `WrongSession`; a repeat is `Duplicate`; an older one `Stale`.
#[test]
fn measured_states_of_an_old_session_are_refused() {
    use planner_core::wire::{Command, Reason};
    let mut r = Rig::new(NodeConfig::hrp2());
    r.run(3, true);
    let old = Measured::from_si(r.n.cycles(), [0.01, 0.0]).unwrap();
    assert_eq!(r.ask(Command::Measured(old)), None);
    assert_eq!(r.ask(Command::Measured(old)), Some(Reason::Duplicate));
    let older = Measured::from_si(r.n.cycles() - 3, [0.01, 0.0]).unwrap();
    assert_eq!(r.ask(Command::Measured(older)), Some(Reason::Stale));
    let epoch = r.session.epoch;
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.session.epoch, epoch + 1);
    // The old frame as it was sent: another session's key.
    r.bus.rx.push_back(old.encode(epoch));
    let acks = r.cycle();
    assert_eq!(acks[0].reason, Some(Reason::BadCrc), "{acks:?}");
    // Stamped before the session opened, sealed with the new key.
    let before = Measured::from_si(r.n.cycles() - 3, [0.01, 0.0]).unwrap();
    assert_eq!(r.ask(Command::Measured(before)), Some(Reason::WrongSession));
}

/// The same across the wrap of the session counter: the session before the reset and the one
/// after it key their CRCs differently even where the epoch wraps.
#[test]
fn measured_states_of_the_session_before_a_wrap_are_refused() {
    use planner_core::wire::{Command, Reason};
    let mut cfg = NodeConfig::hrp2();
    cfg.entropy = 0xFFFE_FFFE;
    let mut r = Rig::new(cfg);
    let old = Measured::from_si(r.n.cycles(), [0.01, -0.02]).unwrap();
    let epoch = r.session.epoch;
    assert_eq!(r.ask(Command::Measured(old)), None);
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_ne!(r.session.epoch, epoch);
    r.bus.rx.push_back(old.encode(epoch));
    let acks = r.cycle();
    assert_eq!(acks[0].reason, Some(Reason::BadCrc), "{acks:?}");
}

/// The shift ends with its walk: after an adjusted walk (pushed, steps moved), `Stop` and
/// standing, with no `Reset`, a plain `Start` walk's steps commanded beside the feet are
/// taken and land where commanded; `ADJUST` said so (shift 0 from the next step on).
#[test]
fn the_shift_ends_with_its_walk() {
    let rig = Rig::new(NodeConfig::hrp2());
    for push in [[0.35, 0.0], [0.0, -0.2]] {
        let mut r = rig.fork();
        let o = walk_on(&mut r, true, push, (true, 0, 0), PUSH_IN_SINGLE);
        assert!(!o.fallen && o.shift != [0, 0], "{o:?}");
        assert!(r.n.gait().is_standing());
        assert_eq!(r.n.shift(), [0, 0]);
        let adjust = r.n.adjustment();
        assert_eq!((adjust.shift, adjust.from), ([0, 0], r.n.next_step() as u8));
        // A plain walk from where the feet stand.
        let feet = *r.n.gait().feet();
        let x0 = feet[0].x.max(feet[1].x);
        let right_first = r.n.gait().next_side() != Some(Side::Left);
        let mut commanded = vec![];
        for i in 0..4u16 {
            let left = (i % 2 == 1) == right_first;
            let (x, yy) = (x0 + 0.15 * f64::from(i + 1), feet[usize::from(!left)].y);
            let id = r.n.next_step();
            assert_eq!(r.append(id, left, x, yy), None, "push {push:?}, step {i}");
            commanded.push((id, left, x, yy));
        }
        assert_eq!(r.control(ControlOp::Start), None);
        assert_eq!(r.control(ControlOp::Stop), None);
        let mut landed = vec![];
        let mut swinging = None;
        for k in 0..1200 {
            r.run(1, k % 20 == 0);
            let s = r.n.gait().swinging();
            if let (Some(id), None) = (swinging, s) {
                let &(_, left, x, yy) = commanded.iter().find(|c| c.0 == id).unwrap();
                let f = r.n.gait().feet()[usize::from(!left)];
                landed.push(((f.x - x).abs(), (f.y - yy).abs()));
            }
            swinging = s;
        }
        assert_eq!(landed.len(), 4, "push {push:?}");
        for (dx, dy) in landed {
            assert!(dx < 1e-9 && dy < 1e-9, "push {push:?}: {dx}, {dy}");
        }
    }
}

/// What an estimator claiming the constant deviation `dev` \[m\] every cycle does to an
/// adjusting straight walk of `n_steps`: the first shift's length, the largest shift's
/// length, and the farthest landing from its commanded position \[m\].
fn constant_claim(rig: &Rig, dev: [f64; 2], n_steps: u16) -> (f64, f64, f64) {
    let mut r = rig.fork();
    let mut commanded = vec![];
    for i in 0..n_steps {
        let left = i % 2 == 1;
        let x = 0.2 * f64::from(i + 1).min(f64::from(n_steps - 1));
        let id = r.n.next_step();
        assert_eq!(r.append(id, left, x, y(left)), None, "step {i}");
        commanded.push((id, left, x, y(left)));
    }
    assert_eq!(r.control(ControlOp::StartAdjusting), None);
    let stop = r.command(ControlOp::Stop);
    r.bus.rx.push_back(stop.encode());
    let (mut first, mut largest, mut farthest) = (None, 0.0f64, 0.0f64);
    let mut swinging = None;
    for k in 0..4000u32 {
        let m = Measured::from_si(r.n.cycles(), dev).unwrap();
        r.bus.rx.push_back(m.encode(r.session.epoch));
        if k % 20 == 0 {
            let hb = r.heartbeat();
            r.bus.rx.push_back(hb.encode());
        }
        r.cycle();
        let s = r.n.shift();
        let length = f64::from(s[0]).hypot(f64::from(s[1])) * 5e-4;
        if length > 0.0 && first.is_none() {
            first = Some(length);
        }
        largest = largest.max(length);
        let now = r.n.gait().swinging();
        if let (Some(id), None) = (swinging, now) {
            let &(_, left, x, yy) = commanded.iter().find(|c| c.0 == id).unwrap();
            let f = r.n.gait().feet()[usize::from(!left)];
            farthest = farthest.max((f.x - x).hypot(f.y - yy));
        }
        swinging = now;
        if r.n.gait().is_standing() && k > 100 {
            break;
        }
    }
    (first.unwrap_or(0.0), largest, farthest)
}

/// The largest admissible capture step for any deviation: a constant measured deviation of
/// 0.05 … 0.9 m forward, outward or backward moves the first capture step, never less for a
/// larger deviation (the reach cut finds the largest part of the move that keeps the limits,
/// to the footstep unit, however small a part that is; before, a move of which even 1/64
/// broke a limit was given up). A deviation whose move is beyond `ADJUST`'s fields (1.6 m
/// backward: an offset of about 26 m) is cut to the shift bound along its direction, not
/// dropped.
#[test]
fn a_larger_push_gets_the_largest_capture_step() {
    let rig = Rig::new(NodeConfig::hrp2());
    for dir in [[1.0, 0.0], [0.0, -1.0], [-1.0, 0.0]] {
        let mut last = 0.0;
        for e in [0.05, 0.2, 0.4, 0.6, 0.9] {
            let (first, _, _) = constant_claim(&rig, [dir[0] * e, dir[1] * e], 6);
            assert!(first > 0.0, "{dir:?} × {e} m: no capture step");
            assert!(first >= last - 1e-9, "{dir:?} × {e} m: {first} < {last}");
            last = first;
        }
    }
    let mut cfg = NodeConfig::hrp2();
    cfg.adjust.max_deviation = 1.6;
    let rig = Rig::new(cfg);
    let (first, largest, _) = constant_claim(&rig, [-1.6, 0.0], 6);
    assert!(first > 0.0, "1.6 m backward: no capture step");
    assert!(largest <= cfg.adjust.max_shift + 1e-9, "{largest}");
}

/// Nothing walks the robot farther than the shift bound from its commanded path, whatever
/// the estimator claims: a constant 0.3 m claim to the side for a 12-step walk keeps every
/// landing within `max_shift` (0.30 m) of where it was commanded (before: 0.47 m); a claim
/// beyond `max_deviation` (1.0 m) is refused `OutOfRange` and changes nothing.
#[test]
fn a_lying_estimator_moves_the_path_at_most_the_shift_bound() {
    let cfg = NodeConfig::hrp2();
    let rig = Rig::new(cfg);
    for dev in [[0.0, 0.3], [0.0, -0.3], [0.3, 0.3], [-0.3, 0.0]] {
        let (_, largest, farthest) = constant_claim(&rig, dev, 12);
        let bound = cfg.adjust.max_shift + 1e-9;
        assert!(
            largest > 0.0 && largest <= bound,
            "{dev:?}: shift {largest}"
        );
        assert!(farthest <= bound, "{dev:?}: landed {farthest} m off");
    }
    let mut r = rig.fork();
    for dev in [[1.2, 0.0], [0.0, -1.4], [0.75, 0.75]] {
        let m = Measured::from_si(r.n.cycles(), dev).unwrap();
        assert_eq!(
            r.ask(Command::Measured(m)),
            Some(Reason::OutOfRange),
            "{dev:?}"
        );
    }
    let m = Measured::from_si(r.n.cycles(), [0.7, 0.7]).unwrap();
    assert_eq!(r.ask(Command::Measured(m)), None, "0.99 m is a state");
}
