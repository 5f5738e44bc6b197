//! The gateway's invariants over random programs of a ROS 2 peer (footstep lists in both modes
//! with moved, late and new steps, pauses, resumes, aborts, the peer vanishing and coming
//! back), against the node in this process. Whatever the program:
//!
//! * every status is about a step the peer sent, each step lifts off at most once in a walk
//!   and lands at most once, and only after it lifted off;
//! * a step lands where its last accepted pose puts it (the node's reference: within the
//!   bus's footstep grid, 0.25 mm, and the stream's rounding, 0.05 mm), and the status's
//!   desired pose is that pose;
//! * a walk starts only when none is under way and completes only after it started
//!   (ABORT_REQUESTED may come at any time);
//! * the gateway never sends a frame the node answers `bad_crc`, `bad_length`, `duplicate`,
//!   `wrong_session` or `no_session` (what a correct controller never causes);
//! * once the peer stops sending, the robot stands within a bounded time.
//!
//! `WALK_GATEWAY_CASES` sets the number of programs (default 24).

use std::collections::{BTreeMap, BTreeSet};

use host_sim::robot::Robot;
use host_sim::ros2::gateway::{Gateway, GatewayConfig, Output};
use host_sim::ros2::link::{InProcess, NodeLink};
use host_sim::ros2::msg::{
    FootstepDataListMessage, FootstepDataMessage, FOOTSTEP_STATUS_COMPLETED,
    FOOTSTEP_STATUS_STARTED, WALKING_COMPLETED, WALKING_STARTED,
};
use proptest::prelude::*;

#[derive(Clone, Debug)]
enum Act {
    /// A list: mode (0 override, 1 queue), how many steps, the first step's offset from the
    /// peer's plan, the step length, whether to reuse the ids of the plan so far.
    List {
        mode: u8,
        n: usize,
        length: f64,
        reuse: bool,
        nudge: f64,
    },
    Pause(bool, bool),
    Abort,
    /// Cycles to let pass, the peer there or not.
    Wait(u32, bool),
    /// The peer restarts: its ids start again from 1 (a walk's ids are its own).
    Restart,
    /// The next act comes in the same cycle (no cycle after this one).
    Together,
}

fn act() -> impl Strategy<Value = Act> {
    prop_oneof![
        4 => (0u8..2, 1usize..8, 0.0f64..0.2, any::<bool>(), -0.03f64..0.03).prop_map(
            |(mode, n, length, reuse, nudge)| Act::List { mode, n, length, reuse, nudge }
        ),
        1 => (any::<bool>(), any::<bool>()).prop_map(|(p, c)| Act::Pause(p, c)),
        1 => Just(Act::Abort),
        4 => (1u32..200, prop::bool::weighted(0.9)).prop_map(|(k, alive)| Act::Wait(k, alive)),
        1 => Just(Act::Restart),
        1 => Just(Act::Together),
    ]
}

struct World {
    g: Gateway,
    link: InProcess,
    /// Every output with the peer's era (restarts) it came in.
    out: Vec<(u32, Output)>,
    era: u32,
    /// The peer's ids so far, in order, with their side and pose.
    plan: Vec<(u32, u8, f64, f64)>,
    next_id: u32,
    /// The largest id ever sent (ids repeat after a restart).
    max_id: u32,
    list_id: u32,
    bad: Vec<String>,
}

impl World {
    /// HRP-2's node in this process and a gateway that has opened its session.
    fn open() -> Self {
        let robot = Robot::hrp2();
        let mut w = World {
            g: Gateway::new(GatewayConfig::default()),
            link: InProcess::new(robot.node_config()).unwrap(),
            out: Vec::new(),
            plan: Vec::new(),
            next_id: 0,
            max_id: 0,
            era: 0,
            list_id: 0,
            bad: Vec::new(),
        };
        while !w.g.is_open() {
            w.cycle(true);
        }
        w
    }

    fn cycle(&mut self, alive: bool) {
        let frames = self.g.poll(alive);
        for f in self.link.cycle(&frames) {
            if let Some(a) = planner_core::wire::Ack::decode(&f) {
                if let Some(r) = a.reason {
                    use planner_core::wire::Reason::*;
                    if matches!(r, BadCrc | BadLength | Duplicate | WrongSession | NoSession) {
                        self.bad
                            .push(format!("{r:?} to command {:#04x}", a.command));
                    }
                }
            }
            self.g.on_frame(&f);
        }
        self.g.end_cycle();
        let era = self.era;
        self.out
            .extend(self.g.take_outputs().into_iter().map(|o| (era, o)));
    }

    /// The feet's x (left, right) and which foot stands ahead, from the node's feet.
    fn feet(&self) -> ([f64; 2], usize) {
        let f = self.g.frame();
        let xs: Vec<f64> = self
            .link
            .node()
            .gait()
            .feet()
            .iter()
            .map(|p| f.x + f.yaw.cos() * p.x - f.yaw.sin() * p.y)
            .collect();
        ([xs[0], xs[1]], usize::from(xs[1] > xs[0]))
    }

    fn list(&mut self, mode: u8, n: usize, length: f64, reuse: bool, nudge: f64) {
        let mut steps = Vec::new();
        let mut plan = Vec::new();
        if reuse && mode == 0 && !self.plan.is_empty() {
            // The plan so far, its last step moved: a modification (or a late change).
            plan = self.plan.clone();
            if let Some(last) = plan.last_mut() {
                last.2 += nudge;
            }
        } else {
            // After the plan so far (QUEUE while it walks), else from where the feet stand,
            // with the foot the node expects next.
            let walking = self.g.is_walking();
            let (x0, first) = match (mode, self.plan.last(), walking) {
                (1, Some(&(_, side, x, _)), true) => (x, 1 - side),
                _ => {
                    let ([xl, xr], _) = self.feet();
                    let side = match self.link.node().status().next_side() {
                        1 => 0,
                        _ => 1,
                    };
                    (xl.max(xr), side)
                }
            };
            for k in 0..n {
                let side = if k % 2 == 0 { first } else { 1 - first };
                let x = x0 + length * (k as f64 + 1.0).min((n - 1).max(1) as f64);
                let y = if side == 1 { -0.1 } else { 0.1 };
                self.next_id += 1;
                self.max_id = self.max_id.max(self.next_id);
                plan.push((self.next_id, side, x, y));
            }
            if mode == 1 {
                // QUEUE: after what was sent.
                let mut all = self.plan.clone();
                all.extend(plan.iter().copied());
                self.plan = all;
            } else {
                self.plan = plan.clone();
            }
        }
        if reuse && mode == 0 {
            self.plan = plan.clone();
        }
        for &(id, side, x, y) in &plan {
            steps.push(FootstepDataMessage::new(id, side, x, y, 0.0));
        }
        self.list_id += 1;
        self.g
            .on_footstep_list(FootstepDataListMessage::new(self.list_id, mode, steps));
    }
}

fn check(world: &World) -> Result<(), String> {
    // A step is its id within its walk: a walk's ids are its own (a peer may send a plan
    // again once it was walked, or restart and number from 1 again).
    let mut walk = 0u32;
    let mut started: BTreeSet<(u32, u32)> = BTreeSet::new();
    let mut landed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    let mut walking_open = false;
    let mut swinging: Option<(u32, u32)> = None;
    for (_, o) in &world.out {
        match o {
            Output::Footstep(s) if s.footstep_status == FOOTSTEP_STATUS_STARTED => {
                if s.sequence_id == 0 || s.sequence_id > world.max_id {
                    return Err(format!("a status for step {} never sent", s.sequence_id));
                }
                if !started.insert((walk, s.sequence_id)) {
                    return Err(format!("step {} lifted off twice in a walk", s.sequence_id));
                }
                swinging = Some((walk, s.sequence_id));
            }
            Output::Footstep(s) if s.footstep_status == FOOTSTEP_STATUS_COMPLETED => {
                // The step that lands is the one that lifted off last (its era may be the
                // previous one, when the peer restarted during its swing).
                let Some(key) = swinging.take().filter(|k| k.1 == s.sequence_id) else {
                    return Err(format!("step {} landed, never lifted off", s.sequence_id));
                };
                *landed.entry(key).or_default() += 1;
                if landed[&key] > 1 {
                    return Err(format!("step {} landed twice", s.sequence_id));
                }
                let (d, a) = (
                    &s.desired_foot_position_in_world,
                    &s.actual_foot_position_in_world,
                );
                // Half the footstep unit (0.5 mm) and half the stream's foot unit (0.1 mm).
                const TOL: f64 = 0.25e-3 + 0.05e-3 + 1e-9;
                if (d.x - a.x).abs() > TOL || (d.y - a.y).abs() > TOL {
                    return Err(format!(
                        "step {} landed at ({:.4}, {:.4}), its pose ({:.4}, {:.4})",
                        s.sequence_id, a.x, a.y, d.x, d.y
                    ));
                }
            }
            Output::Walking(w, _) => {
                // STARTED opens a walk, COMPLETED closes it; ABORT_REQUESTED (an abort, a
                // pause, a safety stop) may come at any time and closes what is open.
                match *w {
                    WALKING_STARTED if walking_open => {
                        return Err("a walk started while one was under way".into())
                    }
                    WALKING_COMPLETED if !walking_open => {
                        return Err("a walk completed that had not started".into())
                    }
                    _ => {
                        walking_open = *w == WALKING_STARTED;
                        walk += u32::from(walking_open);
                    }
                }
            }
            _ => {}
        }
    }
    if let Some(b) = world.bad.first() {
        return Err(format!("the node answered {b}"));
    }
    Ok(())
}

fn cases() -> u32 {
    std::env::var("WALK_GATEWAY_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(24)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn the_gateway_keeps_its_promises_for_any_program(acts in prop::collection::vec(act(), 1..14)) {
        let mut w = World::open();
        let mut together = false;
        for a in &acts {
            match *a {
                Act::List { mode, n, length, reuse, nudge } => w.list(mode, n, length, reuse, nudge),
                Act::Pause(p, c) => { w.list_id += 1; w.g.on_pause(w.list_id, p, c) }
                Act::Abort => { w.list_id += 1; w.g.on_abort(w.list_id) }
                Act::Wait(k, alive) => for _ in 0..k { w.cycle(alive) },
                Act::Restart => {
                    // A new peer: it knows nothing of the old plan and numbers from 1.
                    w.era += 1;
                    w.next_id = 0;
                    w.plan.clear();
                    w.list_id += 1;
                    w.g.on_abort(w.list_id);
                }
                Act::Together => { together = true; continue }
            }
            if !together {
                w.cycle(true);
            }
            together = false;
        }
        // The peer falls silent, then leaves: the walk ends by itself or by the node's
        // supervision, within the time of a full queue.
        let mut quiet = 0;
        loop {
            w.cycle(quiet < 4000);
            quiet += 1;
            let standing = w.link.node().gait().is_standing();
            if standing && quiet > 200 {
                break;
            }
            prop_assert!(quiet < 8000, "still moving 40 s after the peer's last message");
        }
        if let Err(e) = check(&w) {
            let logs: Vec<String> = w.out.iter().filter_map(|(_, o)| match o {
                Output::Log(l) => Some(l.clone()),
                Output::Refusal(r) => Some(format!("{} {} {}: {}", r.command, r.footstep_sequence_id, r.reason, r.detail)),
                _ => None,
            }).collect();
            prop_assert!(false, "{e}\n{}", logs.join("\n"));
        }
    }
}

#[test]
fn the_random_programs_walk() {
    // The programs' lists walk: a list from standing and a QUEUE list while it walks, built
    // as the property test builds them, land every step.
    let mut w = World::open();
    w.list(0, 6, 0.1, false, 0.0);
    for _ in 0..50 {
        w.cycle(true);
    }
    w.list(1, 4, 0.1, false, 0.0);
    for _ in 0..3000 {
        w.cycle(true);
    }
    let landed = w
        .out
        .iter()
        .filter(
            |(_, o)| matches!(o, Output::Footstep(s) if s.footstep_status == FOOTSTEP_STATUS_COMPLETED),
        )
        .count();
    assert_eq!(
        landed,
        10,
        "{:?}",
        w.out
            .iter()
            .filter(|(_, o)| matches!(o, Output::Log(_) | Output::Refusal(_)))
            .collect::<Vec<_>>()
    );
    check(&w).unwrap();
}
