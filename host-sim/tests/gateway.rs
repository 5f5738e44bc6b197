//! The ROS 2 gateway's state machine against the node in this process (no DDS): footstep
//! lists in, the node's frames through the virtual bus, IHMC's statuses out.

use host_sim::robot::Robot;
use host_sim::ros2::gateway::{Gateway, GatewayConfig, Output};
use host_sim::ros2::link::{InProcess, NodeLink};
use host_sim::ros2::msg::{
    FootstepDataListMessage, FootstepDataMessage, FOOTSTEP_STATUS_COMPLETED,
    FOOTSTEP_STATUS_STARTED, WALKING_ABORT_REQUESTED, WALKING_COMPLETED, WALKING_STARTED,
};

struct Rig {
    g: Gateway,
    link: InProcess,
    out: Vec<(u64, Output)>,
    k: u64,
}

impl Rig {
    fn new() -> Self {
        let robot = Robot::hrp2();
        let link = InProcess::new(robot.node_config()).unwrap();
        let mut rig = Rig {
            g: Gateway::new(GatewayConfig::default()),
            link,
            out: Vec::new(),
            k: 0,
        };
        rig.run_until(|r| r.g.is_open(), 10);
        rig
    }

    fn cycle(&mut self, alive: bool) {
        let frames = self.g.poll(alive);
        for f in self.link.cycle(&frames) {
            self.g.on_frame(&f);
        }
        self.g.end_cycle();
        self.k += 1;
        let k = self.k;
        self.out
            .extend(self.g.take_outputs().into_iter().map(|o| (k, o)));
    }

    fn run_until(&mut self, done: impl Fn(&Rig) -> bool, max: u64) {
        for _ in 0..max {
            if done(self) {
                return;
            }
            self.cycle(true);
        }
        panic!("not reached in {max} cycles; outputs: {:?}", self.logs());
    }

    /// The x of the rear foot in the world frame (the node's feet through the gateway's frame).
    fn rear_x(&self) -> f64 {
        let f = self.g.frame();
        self.link
            .node()
            .gait()
            .feet()
            .iter()
            .map(|p| {
                f.compose(&host_sim::ros2::plan::Pose {
                    x: p.x,
                    y: p.y,
                    yaw: p.yaw,
                })
                .x
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn logs(&self) -> Vec<String> {
        self.out
            .iter()
            .filter_map(|(_, o)| match o {
                Output::Log(l) => Some(l.clone()),
                Output::Refusal(r) => Some(format!("{r:?}")),
                _ => None,
            })
            .collect()
    }

    fn statuses(&self, status: u8) -> Vec<(u32, [f64; 2], [f64; 2])> {
        self.out
            .iter()
            .filter_map(|(_, o)| match o {
                Output::Footstep(s) if s.footstep_status == status => Some((
                    s.sequence_id,
                    [
                        s.desired_foot_position_in_world.x,
                        s.desired_foot_position_in_world.y,
                    ],
                    [
                        s.actual_foot_position_in_world.x,
                        s.actual_foot_position_in_world.y,
                    ],
                )),
                _ => None,
            })
            .collect()
    }

    fn walking(&self) -> Vec<u8> {
        self.out
            .iter()
            .filter_map(|(_, o)| match o {
                Output::Walking(w, _) => Some(*w),
                _ => None,
            })
            .collect()
    }

    fn refusals(&self) -> Vec<(u32, String)> {
        self.out
            .iter()
            .filter_map(|(_, o)| match o {
                Output::Refusal(r) => Some((r.footstep_sequence_id, r.reason.clone())),
                _ => None,
            })
            .collect()
    }
}

/// HRP-2 walking forward 0.15 m a step from feet at (0, ±0.1), ids from `first`.
fn forward(list: u32, first: u32, n: usize, x0: f64) -> FootstepDataListMessage {
    let steps = (0..n)
        .map(|k| {
            let right = k % 2 == 0;
            let x = if k + 1 == n {
                x0 + 0.15 * k as f64
            } else {
                x0 + 0.15 * (k + 1) as f64
            };
            let y = if right { -0.1 } else { 0.1 };
            FootstepDataMessage::new(first + k as u32, u8::from(right), x, y, 0.0)
        })
        .collect();
    FootstepDataListMessage::new(list, 0, steps)
}

#[test]
fn a_list_walks_each_step_lands_where_sent_and_a_change_before_lift_off_moves_it() {
    let mut rig = Rig::new();
    let list = forward(1, 101, 6, 0.0);
    rig.g.on_footstep_list(list.clone());
    rig.run_until(|r| !r.statuses(FOOTSTEP_STATUS_STARTED).is_empty(), 200);
    // Step 104 (index 3) 5 cm further, and step 101 (lifted off) moved too: a late change.
    let mut changed = list.clone();
    changed.sequence_id = 2;
    changed.footstep_data_list[3].location.x += 0.05;
    changed.footstep_data_list[0].location.x += 0.05;
    rig.g.on_footstep_list(changed.clone());
    rig.run_until(|r| r.walking().contains(&WALKING_COMPLETED), 2000);
    assert_eq!(rig.walking(), [WALKING_STARTED, WALKING_COMPLETED]);
    let done = rig.statuses(FOOTSTEP_STATUS_COMPLETED);
    assert_eq!(
        done.iter().map(|d| d.0).collect::<Vec<_>>(),
        [101, 102, 103, 104, 105, 106],
        "{:?}",
        rig.logs()
    );
    for (k, (id, desired, actual)) in done.iter().enumerate() {
        let f = &changed.footstep_data_list[k];
        let expect = if *id == 101 {
            // The late change was refused: the step landed where the first list put it.
            [list.footstep_data_list[0].location.x, -0.1]
        } else {
            [f.location.x, f.location.y]
        };
        assert!(
            (actual[0] - expect[0]).abs() < 2e-4 && (actual[1] - expect[1]).abs() < 2e-4,
            "step {id}: landed at {actual:?}, expected {expect:?} (desired {desired:?})"
        );
    }
    assert_eq!(rig.refusals(), [(101, "lifted_off".to_string())]);
}

#[test]
fn a_refused_step_walks_nothing_of_its_list_from_standing() {
    let mut rig = Rig::new();
    let mut list = forward(1, 1, 4, 0.0);
    list.footstep_data_list[2].location.x = 2.0; // out of reach
    rig.g.on_footstep_list(list);
    for _ in 0..300 {
        rig.cycle(true);
    }
    assert!(rig.statuses(FOOTSTEP_STATUS_STARTED).is_empty());
    let r = rig.refusals();
    assert!(r.contains(&(3, "reach".to_string())), "{r:?}");
    assert!(r.contains(&(4, "after_refused_step".to_string())), "{r:?}");
    assert!(r.contains(&(1, "list_not_walked".to_string())), "{r:?}");
    assert!(rig.walking().is_empty());
    // The node stands with an empty queue, and the next list walks.
    rig.g.on_footstep_list(forward(2, 11, 4, 0.0));
    rig.run_until(|r| r.walking().contains(&WALKING_COMPLETED), 2000);
    assert_eq!(rig.statuses(FOOTSTEP_STATUS_COMPLETED).len(), 4);
}

#[test]
fn abort_stops_after_the_swing_and_the_node_stops_a_vanished_peer() {
    let mut rig = Rig::new();
    rig.g.on_footstep_list(forward(1, 1, 8, 0.0));
    rig.run_until(|r| r.statuses(FOOTSTEP_STATUS_STARTED).len() == 2, 400);
    rig.g.on_abort(77);
    rig.run_until(|r| r.link.node().gait().is_standing(), 1000);
    let done = rig.statuses(FOOTSTEP_STATUS_COMPLETED).len();
    assert!(done <= 2, "{done} steps completed after the abort");
    assert!(rig.walking().contains(&WALKING_ABORT_REQUESTED));
    // A new walk, then the peer vanishes: no heartbeat, the node's supervision stops it.
    let x0 = rig.rear_x();
    rig.g.on_footstep_list(forward(2, 11, 10, x0));
    rig.run_until(|r| r.statuses(FOOTSTEP_STATUS_STARTED).len() > 3, 600);
    let mut quiet = 0;
    while !rig.link.node().gait().is_standing() {
        rig.cycle(false);
        quiet += 1;
        assert!(quiet < 1000, "still moving 5 s after the peer vanished");
    }
    assert_eq!(rig.link.node().status().state, 3, "controller lost");
    let lost = rig
        .refusals()
        .iter()
        .filter(|r| r.1 == "controller_lost")
        .count();
    assert!(lost > 0, "{:?}", rig.refusals());
    // The peer is back: the next list opens the session again and walks.
    let before = rig.statuses(FOOTSTEP_STATUS_COMPLETED).len();
    let x0 = rig.rear_x();
    rig.g.on_footstep_list(forward(3, 31, 4, x0));
    rig.run_until(
        |r| r.statuses(FOOTSTEP_STATUS_COMPLETED).len() == before + 4,
        3000,
    );
}

#[test]
fn a_pause_stops_after_the_swing_and_the_resume_walks_the_rest_where_sent() {
    let mut rig = Rig::new();
    let list = forward(1, 1, 8, 0.0);
    rig.g.on_footstep_list(list.clone());
    rig.run_until(|r| r.statuses(FOOTSTEP_STATUS_STARTED).len() == 2, 400);
    rig.g.on_pause(5, true, false);
    rig.run_until(|r| r.link.node().gait().is_standing(), 1000);
    let paused_at = rig.statuses(FOOTSTEP_STATUS_COMPLETED).len();
    assert!(
        paused_at <= 3,
        "{paused_at} steps walked before the pause took effect"
    );
    for _ in 0..100 {
        rig.cycle(true);
    }
    assert_eq!(rig.statuses(FOOTSTEP_STATUS_COMPLETED).len(), paused_at);
    rig.g.on_pause(6, false, false);
    rig.run_until(|r| r.walking().contains(&WALKING_COMPLETED), 3000);
    let done = rig.statuses(FOOTSTEP_STATUS_COMPLETED);
    assert_eq!(
        done.iter().map(|d| d.0).collect::<Vec<_>>(),
        (1..=8).collect::<Vec<u32>>(),
        "{:?}",
        rig.logs()
    );
    for (k, (_, _, actual)) in done.iter().enumerate() {
        let f = &list.footstep_data_list[k].location;
        assert!((actual[0] - f.x).abs() < 2e-4 && (actual[1] - f.y).abs() < 2e-4);
    }
    // The pause's stop was reported, and the walk started again.
    let w = rig.walking();
    assert_eq!(
        w,
        [
            WALKING_STARTED,
            WALKING_ABORT_REQUESTED,
            WALKING_STARTED,
            WALKING_COMPLETED
        ]
    );
}

#[test]
fn with_mujoco_the_landings_reported_are_the_engines_soles() {
    use host_sim::ros2::link::WithEngine;
    let have = std::process::Command::new("python3")
        .args(["-c", "import mujoco"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        assert_ne!(
            std::env::var("WALK_REQUIRE_MUJOCO").as_deref(),
            Ok("1"),
            "MuJoCo is not installed (python3 -m pip install mujoco==3.2.7)"
        );
        eprintln!("skipped: python3 -m pip install mujoco==3.2.7 to run this test");
        return;
    }
    let robot = Robot::hrp2();
    let mut link = WithEngine::new(robot.node_config(), &robot).unwrap();
    let mut g = Gateway::new(host_sim::ros2::gateway_config(&robot));
    let mut out = Vec::new();
    let cycle = |g: &mut Gateway, link: &mut WithEngine, out: &mut Vec<Output>| {
        let frames = g.poll(true);
        for f in link.cycle(&frames) {
            g.on_frame(&f);
        }
        g.set_measured_soles(link.measured_soles());
        g.end_cycle();
        out.extend(g.take_outputs());
    };
    while !g.is_open() {
        cycle(&mut g, &mut link, &mut out);
    }
    let list = forward(1, 1, 4, 0.0);
    g.on_footstep_list(list.clone());
    for _ in 0..1500 {
        cycle(&mut g, &mut link, &mut out);
        if out
            .iter()
            .any(|o| matches!(o, Output::Walking(w, _) if *w == WALKING_COMPLETED))
        {
            break;
        }
    }
    assert!(link.fell.is_none(), "fell: {:?}", link.fell);
    let done: Vec<_> = out
        .iter()
        .filter_map(|o| match o {
            Output::Footstep(s) if s.footstep_status == FOOTSTEP_STATUS_COMPLETED => Some(s),
            _ => None,
        })
        .collect();
    assert_eq!(done.len(), 4);
    let mut off_reference = 0;
    for s in &done {
        let (d, a) = (
            &s.desired_foot_position_in_world,
            &s.actual_foot_position_in_world,
        );
        let err = (a.x - d.x).hypot(a.y - d.y);
        // The robot follows its reference within the stabilizer's tracking, and the report is
        // the engine's sole, not the reference (which lands exactly on the 0.5 mm grid).
        assert!(
            err < 0.02,
            "step {}: landed {err} m from its pose",
            s.sequence_id
        );
        off_reference += usize::from(err > 1e-5);
    }
    assert!(off_reference > 0, "every landing equals the reference");
}

#[test]
fn an_override_before_the_walk_started_replaces_the_plan_and_walks_once() {
    let mut rig = Rig::new();
    rig.g.on_footstep_list(forward(1, 1, 4, 0.0));
    // The next cycle's override names other steps: while standing, it replaces the first.
    rig.cycle(true);
    rig.g.on_footstep_list(forward(2, 11, 6, 0.0));
    rig.run_until(|r| r.walking().contains(&WALKING_COMPLETED), 3000);
    let done: Vec<u32> = rig
        .statuses(FOOTSTEP_STATUS_COMPLETED)
        .iter()
        .map(|d| d.0)
        .collect();
    assert_eq!(done, (11..=16).collect::<Vec<u32>>(), "{:?}", rig.logs());
    assert_eq!(rig.walking(), [WALKING_STARTED, WALKING_COMPLETED]);
    assert!(rig.refusals().is_empty(), "{:?}", rig.logs());
}
