//! The ROS 2 gateway's `cmd_vel` and relative goal against the node in this process (no DDS):
//! a `Twist` stream walks the robot at that velocity, a stream that stops stops and stands the
//! robot (not as a lost controller: the gateway sends zero), a goal is walked to.

use host_sim::robot::Robot;
use host_sim::ros2::gateway::{Gateway, GatewayConfig, Output};
use host_sim::ros2::link::{InProcess, NodeLink};
use planner_core::node::{Driver, NodeState};

struct Rig {
    g: Gateway,
    link: InProcess,
    out: Vec<Output>,
}

impl Rig {
    fn new() -> Self {
        let link = InProcess::new(Robot::hrp2().node_config()).unwrap();
        let mut r = Rig {
            g: Gateway::new(GatewayConfig::default()),
            link,
            out: vec![],
        };
        for _ in 0..10 {
            r.cycle();
        }
        r
    }

    fn cycle(&mut self) {
        let frames = self.g.poll(true);
        for f in self.link.cycle(&frames) {
            self.g.on_frame(&f);
        }
        self.g.end_cycle();
        self.out.extend(self.g.take_outputs());
    }

    fn refusals(&self) -> Vec<&Output> {
        self.out
            .iter()
            .filter(|o| matches!(o, Output::Refusal(_)))
            .collect()
    }
}

#[test]
fn a_twist_stream_walks_the_robot_and_its_end_stands_it() {
    let mut r = Rig::new();
    // A teleoperation stick publishing at 20 Hz for 6 s: 0.15 m/s forward.
    for k in 0..1200 {
        if k % 10 == 0 {
            r.g.on_cmd_vel(0.15, 0.0, 0.0);
        }
        r.cycle();
    }
    let n = r.link.node();
    assert_eq!(n.state(), NodeState::Walking, "{:?}", r.out);
    assert_eq!(n.driver(), Driver::Velocity);
    let x = n.gait().feet().iter().map(|f| f.x).fold(f64::MAX, f64::min);
    assert!(x > 0.5, "the rear foot at {x} m after 6 s at 0.15 m/s");
    assert!(r.refusals().is_empty(), "{:?}", r.refusals());
    // The stick let go: the gateway sends zero after 0.5 s; the robot stands, its controller
    // not lost.
    for _ in 0..1200 {
        r.cycle();
    }
    let n = r.link.node();
    assert_eq!(n.state(), NodeState::Standing, "{:?}", r.out);
    assert!(r.refusals().is_empty(), "{:?}", r.refusals());
}

#[test]
fn a_relative_goal_is_walked_to() {
    let mut r = Rig::new();
    r.g.on_goal(0.6, 0.1, 0.3);
    for _ in 0..4000 {
        r.cycle();
        if r.link.node().at_goal() {
            break;
        }
    }
    let n = r.link.node();
    assert!(n.at_goal(), "{:?}", r.out);
    let [l, rt] = *n.gait().feet();
    let (mx, my) = (0.5 * (l.x + rt.x), 0.5 * (l.y + rt.y));
    assert!((mx - 0.6).hypot(my - 0.1) < 0.035, "at {mx} {my}");
}
