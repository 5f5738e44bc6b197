//! The node's reference stream: lift-off and touchdown (from `COG_VEL.phase`), the end of a
//! walk, and the reference in the world frame with the support polygon (the convex hull of the
//! soles on the floor).

use super::*;
use planner_core::gait::{FootPose, Phase, Reference};
use planner_core::lipm::Sample;

impl Gateway {
    /// After every frame of the node's cycle: lift-offs and touchdowns, the end of a walk, the
    /// reference.
    pub fn end_cycle(&mut self) {
        if !self.have_stream {
            return;
        }
        let phase = self.stream.phase;
        let was = self.phase;
        self.phase = phase;
        let single = |p: u8| p == 2 || p == 3;
        if single(phase) && !single(was) {
            // Support on the left (2): the right foot swings.
            let swing = if phase == 2 { Side::Right } else { Side::Left };
            self.lift_off(swing);
        }
        if !single(phase) && single(was) {
            let swing = if was == 2 { Side::Right } else { Side::Left };
            self.touch_down(swing);
        }
        self.refit_frame(was == 0 && phase == 0);
        if phase != 0 {
            self.moved = true;
        }
        if phase == 0 && self.moved {
            self.moved = false;
            self.stopping = false;
            self.stop_sent = false;
            if let Some(list) = self.walking.take() {
                if !self.paused {
                    self.outputs.push(Output::Walking(WALKING_COMPLETED, list));
                    self.close_walk();
                }
            }
        }
        if phase == 0 && self.walking.is_none() {
            self.stopping = false;
        }
        self.publish_reference();
        self.run_deferred();
    }

    /// Keeps the node's frame in the world: standing, the feet do not move, so a jump of the
    /// stream's feet between two cycles is the node's frame moving (a `Reset`, the gateway's
    /// or another controller's): the frame is the one that keeps the feet where they were in
    /// the world (their midpoint and mean heading, as the node re-bases).
    pub(super) fn refit_frame(&mut self, standing: bool) {
        let f = self.stream.feet;
        let node = [
            Pose {
                x: f[0][0],
                y: f[0][1],
                yaw: f[0][3],
            },
            Pose {
                x: f[1][0],
                y: f[1][1],
                yaw: f[1][3],
            },
        ];
        if let (true, Some((world, before))) = (standing, self.last_feet) {
            let moved = node
                .iter()
                .zip(&before)
                .any(|(a, b)| (a.x - b.x).hypot(a.y - b.y) > 1e-3 || (a.yaw - b.yaw).abs() > 1e-3);
            if moved {
                let mid = |p: &[Pose; 2]| Pose {
                    x: 0.5 * (p[0].x + p[1].x),
                    y: 0.5 * (p[0].y + p[1].y),
                    yaw: (p[0].yaw.sin() + p[1].yaw.sin()).atan2(p[0].yaw.cos() + p[1].yaw.cos()),
                };
                let (w, n) = (mid(&world), mid(&node));
                self.frame = w.compose(&n.relative(&Pose::default()));
            }
        }
        let world = [self.frame.compose(&node[0]), self.frame.compose(&node[1])];
        self.last_feet = Some((world, node));
    }

    pub(super) fn foot(&self, side: Side) -> Pose {
        let f = self.stream.feet[usize::from(side == Side::Right)];
        self.frame.compose(&Pose {
            x: f[0],
            y: f[1],
            yaw: f[3],
        })
    }

    pub(super) fn status(
        &self,
        k: usize,
        status: u8,
        actual: Pose,
        swing: f64,
    ) -> FootstepStatusMessage {
        let s = &self.steps[k];
        FootstepStatusMessage {
            sequence_id: s.id,
            footstep_status: status,
            footstep_index: s.index,
            robot_side: if s.side == Side::Left {
                ROBOT_SIDE_LEFT
            } else {
                ROBOT_SIDE_RIGHT
            },
            desired_foot_position_in_world: Point {
                x: s.pose.x,
                y: s.pose.y,
                z: 0.0,
            },
            desired_foot_orientation_in_world: Quaternion::from_yaw(s.pose.yaw),
            actual_foot_position_in_world: Point {
                x: actual.x,
                y: actual.y,
                z: 0.0,
            },
            actual_foot_orientation_in_world: Quaternion::from_yaw(actual.yaw),
            swing_duration: swing,
        }
    }

    pub(super) fn lift_off(&mut self, swing: Side) {
        let Some(k) = self.steps.iter().position(|s| s.unlifted()) else {
            return;
        };
        if self.steps[k].side != swing || self.steps[k].state != State::Queued {
            return;
        }
        let from = self.foot(swing);
        self.steps[k].state = State::Swinging;
        self.steps[k].lift = Some((self.cycle, from));
        let out = self.status(k, FOOTSTEP_STATUS_STARTED, from, 0.0);
        self.outputs.push(Output::Footstep(out));
    }

    pub(super) fn touch_down(&mut self, swing: Side) {
        let Some(k) = self.steps.iter().position(|s| s.state == State::Swinging) else {
            return;
        };
        if self.steps[k].side != swing {
            return;
        }
        let landed = match self.measured {
            Some(m) => m[usize::from(swing == Side::Right)],
            None => self.foot(swing),
        };
        let swing_s = self.steps[k]
            .lift
            .map(|(c, _)| (self.cycle - c) as f64 * self.cfg.dt)
            .unwrap_or(0.0);
        self.steps[k].state = State::Landed;
        let out = self.status(k, FOOTSTEP_STATUS_COMPLETED, landed, swing_s);
        self.outputs.push(Output::Footstep(out));
    }

    pub(super) fn publish_reference(&mut self) {
        let st = self.stream;
        let w = |x: f64, y: f64| self.frame.compose(&Pose { x, y, yaw: 0.0 });
        let cog = w(st.cog[0], st.cog[1]);
        let zmp = w(st.zmp[0], st.zmp[1]);
        let (s, c) = self.frame.yaw.sin_cos();
        let vel = [
            c * st.cog_vel[0] - s * st.cog_vel[1],
            s * st.cog_vel[0] + c * st.cog_vel[1],
        ];
        let mut corners = Vec::with_capacity(8);
        let mut feet = [FootPose::default(); 2];
        for side in [Side::Left, Side::Right] {
            let i = usize::from(side == Side::Right);
            let f = self.foot(side);
            feet[i] = FootPose {
                x: f.x,
                y: f.y,
                z: st.feet[i][2],
                yaw: f.yaw,
            };
            let on_floor = match st.phase {
                2 => side == Side::Left,
                3 => side == Side::Right,
                _ => true,
            };
            if !on_floor {
                continue;
            }
            let (s, c) = f.yaw.sin_cos();
            let (hl, hw) = (self.cfg.sole[0] / 2.0, self.cfg.sole[1] / 2.0);
            for (dx, dy) in [(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)] {
                corners.push((f.x + c * dx - s * dy, f.y + s * dx + c * dy));
            }
        }
        let support = convex_hull(corners)
            .into_iter()
            .map(|(x, y)| Point32 {
                x: x as f32,
                y: y as f32,
                z: 0.0,
            })
            .collect();
        let plane = |cog: f64, cog_vel: f64, zmp: f64| Sample {
            cog,
            cog_vel,
            cog_acc: 0.0,
            zmp,
            zmp_vel: 0.0,
        };
        let phase = match st.phase {
            0 => Phase::Standing,
            2 => Phase::Single(Side::Left),
            3 => Phase::Single(Side::Right),
            _ => Phase::Double,
        };
        self.outputs.push(Output::Reference {
            reference: Reference {
                x: plane(cog.x, vel[0], zmp.x),
                y: plane(cog.y, vel[1], zmp.y),
                phase,
                feet,
            },
            support,
            tick: st.tick,
        });
    }
}

/// The convex hull of `pts`, counter-clockwise (Andrew's monotone chain).
pub fn convex_hull(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(pts.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    pub(super) fn hull_of_two_soles_is_their_outline() {
        let h = convex_hull(vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.5, 0.5),
        ]);
        assert_eq!(h.len(), 4);
        // Counter-clockwise: positive area.
        let area: f64 = (0..h.len())
            .map(|i| {
                let (a, b) = (h[i], h[(i + 1) % h.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0;
        assert!((area - 1.0).abs() < 1e-12);
    }

    #[test]
    pub(super) fn nothing_is_sent_before_the_node_is_heard() {
        let mut g = Gateway::new(GatewayConfig::default());
        assert!(g.poll(true).is_empty());
        assert!(!g.is_open());
    }
}
