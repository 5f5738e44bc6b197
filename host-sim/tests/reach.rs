//! The node's footstep reach limits against the legs of the multi-body HRP-2 model
//! (`host_sim::eval::multibody`: thigh + shank = 0.6 m).
//!
//! A limit is followable when, for every sequence of footsteps it admits, the gait's references
//! keep every ankle joint centre at least [`MIN_MARGIN`] closer to its hip joint centre than
//! thigh + shank (the knee never gets within that much of straight). The waist is placed as
//! [`multibody::evaluate`](host_sim::eval::multibody::evaluate) places it (`Model::solve_waist`, warm
//! started tick to tick), so a positive margin means `evaluate` does not fail with
//! `MbError::OutOfReach`.
//!
//! Measured (`cargo test -p host-sim --release --test reach -- --ignored --nocapture`):
//!
//! * [`former`], the node's limits before this survey (forward −0.30 … +0.40 m, width
//!   0.15 … 0.40 m, yaw 0.6 rad, a box only), was not followable: three 0.40 m steps from standing overshoot the leg by 49 mm (width 0.15 m) to
//!   84 mm (width 0.40 m); a 0.40 m step modified into a 0.2 m walk by 35 mm; three 0.30 m
//!   steps backwards at width 0.40 m by 35 mm; the worst corner pair by 92 mm.
//! * No box alone is both followable and wide enough: three 0.30 m steps and a stop overshoot
//!   by 14 mm, while fig4 needs a 0.30 m step (after 0.1 m steps). Long steps need momentum
//!   and a stop after them needs room, hence the combined rules of `Reach::check`, which the
//!   node now applies ([`admitting`] = `Reach::default()`).
//! * [`strict`] with [`followable`]: margin ≥ 5.34 mm over the whole corner survey (2742
//!   sequences walked; the worst: a 0.228 m step at 0.28 m width, the longest the feet-distance
//!   rule admits there, after 0.2 m steps).
//! * [`admitting`] (the same with max forward 0.30 m) admits every built-in scenario; its
//!   worst surveyed sequence keeps 2.20 mm (a 0.3 m step after a 0.13 m one), and fig4 itself
//!   only **1.37 mm** (the landing of its 0.3 m step at 4.87 s): no limit that admits fig4 can
//!   promise 5 mm. [`strict`] refuses exactly fig4's modification.

use host_sim::robot::model::{mean_yaw, ClosedForm, Model, Pose};
use host_sim::scenario::{self, Command, Run, Scenario};
use planner_core::gait::{Footstep, GaitParams, Reference, Side};
use planner_core::node::{Reach, Soles};

/// The knee margin asked of [`strict`] \[m\].
const MIN_MARGIN: f64 = 0.005;

/// The margin [`admitting`] keeps: fig4 itself has 1.37 mm \[m\].
const ADMITTING_MARGIN: f64 = 0.001;

/// The node's limits with a 0.28 m forward step: 5 mm of leg left in every sequence tried
/// (fig4's 0.3 m step is refused).
fn strict() -> Reach {
    Reach {
        max_forward: 0.28,
        ..Reach::default()
    }
}

/// The node's limits (`Reach::default()`), which admit the 0.30 m forward step fig4 needs.
fn admitting() -> Reach {
    Reach::default()
}

/// The limits the node had before this survey: a box only (forward −0.30 … +0.40 m, width
/// 0.15 … 0.40 m, yaw 0.6 rad).
fn former() -> Reach {
    Reach {
        max_forward: 0.40,
        max_backward: 0.30,
        min_width: 0.15,
        max_width: 0.40,
        max_yaw: 0.6,
        ..Reach::default()
    }
}

const EPS: f64 = 1e-9;

/// A footstep relative to the previous foot of the other side, in that foot's frame (as
/// `Node::check_reach` measures it): `width` is across, positive on the stepping foot's own side.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rel {
    forward: f64,
    width: f64,
    yaw: f64,
}

const fn rel(forward: f64, width: f64, yaw: f64) -> Rel {
    Rel {
        forward,
        width,
        yaw,
    }
}

/// `step` in the frame of `prev` (the computation of `Node::check_reach`).
fn relative(prev: &Footstep<f64>, step: &Footstep<f64>) -> Rel {
    let (s, c) = prev.yaw.sin_cos();
    let (dx, dy) = (step.x - prev.x, step.y - prev.y);
    let forward = c * dx + s * dy;
    let mut width = -s * dx + c * dy;
    if step.side == Side::Right {
        width = -width;
    }
    let d = step.yaw - prev.yaw;
    rel(forward, width, d.sin().atan2(d.cos()))
}

/// The box of `Reach`: the present `Node::check_reach`.
fn in_box(r: &Reach, s: Rel) -> bool {
    s.forward <= r.max_forward + EPS
        && s.forward >= -r.max_backward - EPS
        && s.width >= r.min_width - EPS
        && s.width <= r.max_width + EPS
        && s.yaw.abs() <= r.max_yaw + EPS
}

/// The box and the single-step combined rules (for generating corners).
fn in_reach(r: &Reach, s: Rel) -> bool {
    in_box(r, s)
        && s.forward.hypot(s.width) <= r.max_feet_distance + EPS
        && s.forward + r.yaw_cost * s.yaw.abs() <= r.max_forward + EPS
}

/// The node's check (`Reach::check`): `other` is the previous foot of the other side, `same`
/// the previous foot of the same side (where the swinging foot lifts off).
fn followable(
    r: &Reach,
    other: &Footstep<f64>,
    same: &Footstep<f64>,
    step: &Footstep<f64>,
) -> bool {
    r.check(other, same, step, &Soles::of(&GaitParams::hrp2()))
        .is_ok()
}

/// Limits under test: a box, with or without the combined rules.
#[derive(Clone, Copy, Debug)]
struct Limits {
    reach: Reach,
    combined: bool,
}

impl Limits {
    fn admits(&self, other: &Footstep<f64>, same: &Footstep<f64>, step: &Footstep<f64>) -> bool {
        if self.combined {
            followable(&self.reach, other, same, step)
        } else {
            in_box(&self.reach, relative(other, step))
        }
    }

    fn single(&self, s: Rel) -> bool {
        if self.combined {
            in_reach(&self.reach, s)
        } else {
            in_box(&self.reach, s)
        }
    }
}

fn place(prev: &Footstep<f64>, side: Side, r: Rel) -> Footstep<f64> {
    let (s, c) = prev.yaw.sin_cos();
    let across = if side == Side::Left {
        r.width
    } else {
        -r.width
    };
    Footstep::new(
        side,
        prev.x + c * r.forward - s * across,
        prev.y + s * r.forward + c * across,
        prev.yaw + r.yaw,
    )
}

fn index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

fn standing() -> [Footstep<f64>; 2] {
    [
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    ]
}

/// World footsteps of a relative sequence, right foot first, from standing.
fn world(rels: &[Rel]) -> Vec<Footstep<f64>> {
    let mut last = standing();
    let mut side = Side::Right;
    let mut out = Vec::new();
    for &r in rels {
        let f = place(&last[index(side.other())], side, r);
        last[index(side)] = f;
        out.push(f);
        side = side.other();
    }
    out
}

/// How many of `steps` (alternating, from standing) `followable` admits before the first
/// refusal.
fn admitted(l: &Limits, steps: &[Footstep<f64>]) -> usize {
    let mut last = standing();
    for (i, f) in steps.iter().enumerate() {
        if !l.admits(&last[index(f.side.other())], &last[index(f.side)], f) {
            return i;
        }
        last[index(f.side)] = *f;
    }
    steps.len()
}

const START: u64 = 20;

/// Walks `rels` from standing through the gait (HRP-2 parameters) and stops after the last
/// step; the sequence is cut at the first step the limits refuse, as the node would. With
/// `modify = Some((k, new))`, one tick before the single support that swings step k, steps k..
/// become `new` (placed from the steps before k; the later ones are modified first). `None`
/// when the limits or the gait (eq. 17) refuse the modification.
fn walk(l: &Limits, rels: &[Rel], modify: Option<(usize, &[Rel])>) -> Option<Run> {
    let mut steps = world(rels);
    steps.truncate(admitted(l, &steps));
    let mut timeline: Vec<(u64, Command)> = steps
        .iter()
        .enumerate()
        .map(|(i, &f)| (0, Command::Push(i as u16, f)))
        .collect();
    timeline.push((START, Command::Start));
    if let Some((k, new)) = modify {
        let mut all = rels[..k].to_vec();
        all.extend_from_slice(new);
        let moved = world(&all);
        if k >= steps.len() || admitted(l, &moved) < moved.len() || moved.len() != steps.len() {
            return None;
        }
        let at = START + 160 + 160 * k as u64 - 1;
        for i in (k..moved.len()).rev() {
            timeline.push((at, Command::Modify(i as u16, moved[i])));
        }
    }
    let last = timeline.last().map_or(START, |(t, _)| *t);
    timeline.push((last, Command::Stop));
    let s = Scenario {
        name: "reach".into(),
        about: String::new(),
        feet: Some(standing()),
        timeline,
        max_ticks: 6000,
    };
    let run = scenario::run(&s, GaitParams::hrp2());
    run.events.iter().all(|e| e.result.is_ok()).then_some(run)
}

/// The smallest knee margin of a trajectory: thigh + shank minus the hip–ankle distance \[m\],
/// both legs, every tick, and the tick where it occurs. Ticks where the model's legs do not
/// reach are measured with a long-legged copy (the negative margins are then approximate:
/// the waist moves a little with the leg masses).
fn leg_margin(traj: &[Reference<f64>]) -> (f64, usize) {
    let model = Model::hrp2();
    let c = model.closed_form.expect("HRP-2's leg shape");
    let mut long = model.clone();
    long.closed_form = Some(ClosedForm {
        thigh: 0.4,
        shank: 0.4,
        ..c
    });
    for leg in &mut long.legs {
        leg.links[3].joint.origin.p[2] = -0.4;
        leg.links[4].joint.origin.p[2] = -0.4;
    }
    let reach = c.thigh + c.shank;
    let mut w = [traj[0].x.cog, traj[0].y.cog];
    let mut worst = (f64::INFINITY, 0);
    for (k, r) in traj.iter().enumerate() {
        let soles = [Pose::sole(&r.feet[0]), Pose::sole(&r.feet[1])];
        let yaw = mean_yaw(&r.feet);
        let target = [r.x.cog, r.y.cog];
        let waist = match model.solve_waist(yaw, &soles, target, w) {
            Ok((p, _, _)) => p,
            Err(_) => {
                long.solve_waist(yaw, &soles, target, w)
                    .expect("the long legs reach")
                    .0
            }
        };
        w = [waist.p[0], waist.p[1]];
        for side in [Side::Left, Side::Right] {
            let hip = model.hip_joint(side, &waist);
            let ankle = soles[index(side)].apply([0.0, 0.0, c.ankle_height]);
            let d = (0..3)
                .map(|i| (hip[i] - ankle[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            if reach - d < worst.0 {
                worst = (reach - d, k);
            }
        }
    }
    worst
}

/// The largest admitted forward (towards `limit`) at this width and yaw, by bisection from 0.
fn extreme(l: &Limits, width: f64, yaw: f64, limit: f64) -> f64 {
    let ok = |f: f64| l.single(rel(f, width, yaw));
    if ok(limit) {
        return limit;
    }
    let (mut lo, mut hi) = (0.0, limit);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The corners of the admitted region: for both widths and the given yaws, the forward
/// extremes (backward, forward), 0, the longest steady step (`max_stride / 2`), the longest
/// step before a maximal one (`max_stride − max_forward`) and the step `max_growth` shorter
/// than the maximal one.
fn corners(l: &Limits, yaws: &[f64]) -> Vec<Rel> {
    let r = &l.reach;
    let mut out = Vec::new();
    for w in [r.min_width, r.max_width] {
        for &y in yaws {
            let fmax = extreme(l, w, y, r.max_forward);
            for f in [
                extreme(l, w, y, -r.max_backward),
                0.0,
                extreme(l, w, y, 0.5 * r.max_stride),
                extreme(l, w, y, r.max_stride - r.max_forward),
                extreme(l, w, y, r.max_forward - r.max_growth),
                fmax,
            ] {
                let c = rel(f, w, y);
                if l.single(c) && !out.contains(&c) {
                    out.push(c);
                }
            }
        }
    }
    out
}

/// One walk of the survey.
#[derive(Clone, Debug)]
enum Sequence {
    /// Three steps at the corner from standing, then stop.
    Steady(Rel),
    /// Three 0.2 m steps, then `a`, `b`, two 0.2 m steps, stop (all queued in advance).
    Pair(Rel, Rel),
    /// 0.2 m steps; at the lift-off of step 3, steps 3 and 4 become `a`, `b`.
    Modified(Rel, Rel),
    /// Three steps at `a`, then 0.2 m steps; at the lift-off of step 3 it becomes `b`.
    SteadyModified(Rel, Rel),
}

const NOMINAL: Rel = rel(0.2, 0.2, 0.0);

fn run_sequence(r: &Limits, s: &Sequence) -> Option<Run> {
    let n = NOMINAL;
    match *s {
        Sequence::Steady(c) => walk(r, &[c, c, c], None),
        Sequence::Pair(a, b) => walk(r, &[n, n, n, a, b, n, n], None),
        Sequence::Modified(a, b) => walk(r, &[n; 7], Some((3, &[a, b, n, n]))),
        Sequence::SteadyModified(a, b) => walk(r, &[a, a, a, n, n, n], Some((3, &[b, n, n]))),
    }
}

/// Runs the sequences (on all cores) and returns `(margin, tick, sequence)` of each walked one,
/// worst first, and how many were refused (by the limits or by eq. 17).
fn survey(r: &Limits, seqs: &[Sequence]) -> (Vec<(f64, usize, Sequence)>, usize) {
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let chunk = seqs.len().div_ceil(threads).max(1);
    let mut out = Vec::new();
    let mut refused = 0;
    std::thread::scope(|scope| {
        let handles: Vec<_> = seqs
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .map(|s| {
                            run_sequence(r, s).map(|run| {
                                let (m, k) = leg_margin(&run.trajectory);
                                (m, k, s.clone())
                            })
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            for res in h.join().expect("survey thread") {
                match res {
                    Some(x) => out.push(x),
                    None => refused += 1,
                }
            }
        }
    });
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    (out, refused)
}

/// The sequences of the quick check (debug build, a few seconds): with `steady`, every corner
/// walked steadily from standing; then every corner (yaw 0 or −max) followed by the longest
/// steps (maximal forward at both widths, at yaw 0 and, with `steady`, at −max yaw): the
/// pairs that the full survey finds worst.
fn quick_sequences(l: &Limits, steady: bool) -> Vec<Sequence> {
    let r = &l.reach;
    let mut seqs = Vec::new();
    if steady {
        let all = corners(l, &[-r.max_yaw, 0.0, r.max_yaw]);
        seqs.extend(all.iter().map(|&c| Sequence::Steady(c)));
    }
    let firsts = corners(l, &[-r.max_yaw, 0.0]);
    let mut longest = Vec::new();
    for w in [r.min_width, r.max_width] {
        for y in [0.0, -r.max_yaw] {
            if y == 0.0 || steady {
                longest.push(rel(extreme(l, w, y, r.max_forward), w, y));
            }
        }
    }
    for &a in &firsts {
        for &b in &longest {
            seqs.push(Sequence::Pair(a, b));
        }
    }
    seqs
}

/// Every corner pair, four ways (`Steady`, `Pair`, `Modified`, `SteadyModified`).
fn full_sequences(l: &Limits) -> Vec<Sequence> {
    let r = &l.reach;
    let all = corners(l, &[-r.max_yaw, 0.0, r.max_yaw]);
    let mut seqs: Vec<Sequence> = all.iter().map(|&c| Sequence::Steady(c)).collect();
    for &a in &all {
        for &b in &all {
            seqs.push(Sequence::Pair(a, b));
            seqs.push(Sequence::Modified(a, b));
            seqs.push(Sequence::SteadyModified(a, b));
        }
    }
    seqs
}

fn report(name: &str, r: &Limits, results: &[(f64, usize, Sequence)], refused: usize) {
    println!(
        "{name}: {r:?}: {} sequences walked, {refused} refused; worst margins:",
        results.len()
    );
    for (m, k, s) in results.iter().take(5) {
        println!("  {:7.2} mm at tick {k:4}: {s:?}", m * 1e3);
    }
}

/// The corner sequences keep at least 5 mm of leg with the strict limits, and 1 mm with the
/// limits that admit fig4.
#[test]
fn corner_sequences_keep_the_knee_margin() {
    for (name, r, need, steady) in [
        ("strict", strict(), MIN_MARGIN, true),
        ("admitting", admitting(), ADMITTING_MARGIN, false),
    ] {
        let l = Limits {
            reach: r,
            combined: true,
        };
        let seqs = quick_sequences(&l, steady);
        let (results, refused) = survey(&l, &seqs);
        report(name, &l, &results, refused);
        assert!(results.len() > seqs.len() / 2, "{name}: too many refused");
        let (m, k, s) = &results[0];
        assert!(
            *m >= need,
            "{name}: knee margin {:.2} mm at tick {k} in {s:?}",
            m * 1e3
        );
    }
}

/// The former limits were not followable: three 0.40 m steps at the widest width overshoot
/// the leg by far (the margin is measured, and `evaluate` agrees).
#[test]
fn former_limits_were_too_wide() {
    let r = former();
    assert!(in_box(&r, rel(0.4, 0.4, 0.0)));
    assert!(!followable(
        &admitting(),
        &standing()[0],
        &standing()[1],
        &world(&[rel(0.4, 0.4, 0.0)])[0]
    ));
    // Only the box: the present check.
    let steps = world(&[rel(0.4, 0.4, 0.0); 3]);
    let mut timeline: Vec<(u64, Command)> = steps
        .iter()
        .enumerate()
        .map(|(i, &f)| (0, Command::Push(i as u16, f)))
        .collect();
    timeline.push((START, Command::Start));
    timeline.push((START, Command::Stop));
    let s = Scenario {
        name: "corner".into(),
        about: String::new(),
        feet: Some(standing()),
        timeline,
        max_ticks: 6000,
    };
    let run = scenario::run(&s, GaitParams::hrp2());
    let (m, k) = leg_margin(&run.trajectory);
    println!(
        "{r:?}: three 0.40 m steps, width 0.40 m: margin {:.1} mm at tick {k}",
        m * 1e3
    );
    assert!(m < -0.05, "{m}");
    let model = Model::hrp2();
    assert!(matches!(
        host_sim::eval::multibody::evaluate(&model, &run.trajectory, 0.005),
        Err(host_sim::eval::multibody::MbError::OutOfReach(..))
    ));
}

/// Every footstep command of a scenario (as the node would check it, at the moment it is
/// applied): `(what, previous other-side foot, previous same-side foot, step)`.
type Checked = (String, Footstep<f64>, Footstep<f64>, Footstep<f64>);

fn scenario_steps(s: &Scenario) -> Vec<Checked> {
    let run = scenario::run(s, GaitParams::hrp2());
    let mut list: Vec<(u16, Footstep<f64>)> = Vec::new();
    let mut out = Vec::new();
    let prev = |list: &[(u16, Footstep<f64>)], i: usize, side: Side| {
        list[..i]
            .iter()
            .rev()
            .find(|(_, f)| f.side == side)
            .map_or(s.start_feet(0.2)[index(side)], |&(_, f)| f)
    };
    for e in run.events.iter().filter(|e| e.result.is_ok()) {
        let (id, f, what) = match e.command {
            Command::Push(id, f) => (id, f, "push"),
            Command::Modify(id, f) => (id, f, "modify"),
            _ => continue,
        };
        let i = list
            .iter()
            .position(|(j, _)| *j == id)
            .unwrap_or(list.len());
        if i == list.len() {
            list.push((id, f));
        } else {
            list[i].1 = f;
        }
        let other = prev(&list, i, f.side.other());
        let same = prev(&list, i, f.side);
        out.push((
            format!("{} {what} {id} at tick {}", s.name, e.tick),
            other,
            same,
            f,
        ));
    }
    out
}

/// The built-in scenarios, the TOML files and the paper's Fig. 4 (`paper::modification(0.1,
/// 0.3)`, its steps before and after the modification).
fn all_checked() -> Vec<(String, Vec<Checked>)> {
    let mut scenarios: Vec<Scenario> = scenario::BUILT_IN
        .iter()
        .map(|n| scenario::built_in(n).expect("built-in scenario"))
        .collect();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("host-sim/scenarios")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    for p in files {
        let mut s = host_sim::scenario::file::load(&p).expect("scenario file");
        s.name = format!("{}.toml", s.name);
        scenarios.push(s);
    }
    let mut out: Vec<(String, Vec<Checked>)> = scenarios
        .iter()
        .map(|s| (s.name.clone(), scenario_steps(s)))
        .collect();
    let m = host_sim::eval::paper::modification(GaitParams::hrp2(), 0.1, 0.3);
    let mut original = m.footsteps.clone();
    let closing = original.len() - 1;
    for (i, f) in original.iter_mut().enumerate().skip(3) {
        f.x -= 0.2;
        // The last step closes the stance, beside the one before it.
        let along = (i + 1).min(closing);
        assert!((f.x - 0.1 * along as f64).abs() < 1e-12);
    }
    for (what, steps) in [
        ("paper fig4 before", original),
        ("paper fig4 after", m.footsteps),
    ] {
        let mut last = standing();
        let mut checked = Vec::new();
        for (i, f) in steps.iter().enumerate() {
            let (o, s) = (last[index(f.side.other())], last[index(f.side)]);
            checked.push((format!("{what} step {i}"), o, s, *f));
            last[index(f.side)] = *f;
        }
        out.push((what.to_string(), checked));
    }
    out
}

/// Every footstep of every built-in scenario is admitted by [`admitting`]; [`strict`] refuses
/// only fig4's 0.3 m steps. Prints the extremes of each scenario.
#[test]
fn scenarios_lie_within_the_limits() {
    let (adm, strict) = (admitting(), strict());
    let mut refused_by_strict = Vec::new();
    for (name, steps) in all_checked() {
        let (mut f, mut w, mut y, mut stride, mut dist, mut growth) = (
            [f64::INFINITY, f64::NEG_INFINITY],
            [f64::INFINITY, f64::NEG_INFINITY],
            0.0f64,
            0.0f64,
            0.0f64,
            f64::NEG_INFINITY,
        );
        for (what, other, same, step) in &steps {
            let s = relative(other, step);
            f = [f[0].min(s.forward), f[1].max(s.forward)];
            w = [w[0].min(s.width), w[1].max(s.width)];
            y = y.max(s.yaw.abs());
            stride = stride.max((s.forward - relative(other, same).forward).abs());
            dist = dist.max(s.forward.hypot(s.width));
            growth = growth.max(s.forward - relative(same, other).forward);
            assert!(
                followable(&adm, other, same, step),
                "{what}: {s:?} refused by {adm:?}"
            );
            if !followable(&strict, other, same, step) {
                refused_by_strict.push(what.clone());
            }
        }
        println!(
            "{name}: forward {:.3} … {:.3} m, width {:.3} … {:.3} m, |yaw| ≤ {y:.3} rad, \
             stride ≤ {stride:.3} m, feet distance ≤ {dist:.4} m, growth ≤ {growth:.3} m",
            f[0], f[1], w[0], w[1]
        );
    }
    println!("refused by strict(): {refused_by_strict:#?}");
    assert!(!refused_by_strict.is_empty());
    assert!(
        refused_by_strict
            .iter()
            .all(|w| w.starts_with("fig4") || w.starts_with("paper fig4 after")),
        "{refused_by_strict:?}"
    );
}

/// The knee margin of the scenarios themselves (fig4's 0.3 m step: 1.37 mm).
#[test]
fn scenario_margins() {
    let scenarios: Vec<Scenario> = scenario::BUILT_IN
        .iter()
        .map(|n| scenario::built_in(n).expect("built-in scenario"))
        .collect();
    for s in &scenarios {
        let run = scenario::run(s, GaitParams::hrp2());
        let (m, k) = leg_margin(&run.trajectory);
        println!("{}: knee margin {:.2} mm at tick {k}", s.name, m * 1e3);
        assert!(m >= ADMITTING_MARGIN, "{}: {m}", s.name);
        if s.name != "fig4" {
            assert!(m >= MIN_MARGIN, "{}: {m}", s.name);
        }
    }
}

/// The full survey (every corner pair, four ways; about 2 minutes in release).
#[test]
#[ignore]
fn full_survey() {
    for (name, reach, combined) in [
        ("former", former(), false),
        ("strict", strict(), true),
        ("admitting", admitting(), true),
    ] {
        let l = Limits { reach, combined };
        let (results, refused) = survey(&l, &full_sequences(&l));
        report(name, &l, &results, refused);
    }
}
