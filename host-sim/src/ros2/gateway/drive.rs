//! Velocity and goal walking through the gateway: ROS's `cmd_vel` convention
//! (`geometry_msgs/Twist`: `linear.x` forward, `linear.y` to the left \[m/s\], `angular.z`
//! counter-clockwise \[rad/s\], in the robot's frame) becomes the node's `VELOCITY`, and a
//! relative goal (`geometry_msgs/Pose2D`: x, y \[m\], theta \[rad\] from the midpoint of the
//! feet and their mean heading) its `GOAL`; the node then chooses the footsteps.
//!
//! * **The stream.** A new `Twist` goes out in the next cycle; the velocity in force is sent
//!   again every [`STREAM_CYCLES`] (50 ms), each with a new sequence number, while `Twist`s
//!   keep coming. A `Twist` stream silent for [`CMD_VEL_TIMEOUT_CYCLES`] (0.5 s, ROS's usual
//!   `cmd_vel` timeout) is taken as a stick let go: the gateway sends a zero velocity (the
//!   robot stops and stands) and stops streaming. If the gateway itself stops, the node's own
//!   stream timeout stops the robot (as a lost controller).
//! * **Numbering.** The bus delivers a cycle's `CONTROL` before its `VELOCITY`: in a cycle
//!   that sends one, no heartbeat goes out (the velocity proves the controller alive).
//! * **Answers.** A refusal is published on `command_refusal` (`cmd_vel` or `goal`, the
//!   node's reason), once per reason while the refusals last; a cut (the velocity beyond what
//!   the legs can take) is logged once per change of the cut.

use planner_core::wire::{Command, WireGoal, WireVelocity};

use super::*;

/// Cycles between two frames of the velocity stream (50 ms).
pub const STREAM_CYCLES: u64 = 10;
/// Cycles without a `Twist` after which the gateway stops the robot (0.5 s).
pub const CMD_VEL_TIMEOUT_CYCLES: u64 = 100;

/// The gateway's velocity stream and goal.
#[derive(Clone, Debug, Default)]
pub(super) struct DriveLink {
    /// The velocity in force and the cycle of the last `Twist`, while streaming.
    twist: Option<([f64; 3], u64)>,
    /// A new `Twist` to send at once.
    changed: bool,
    /// The cycle the stream last went out.
    sent_at: u64,
    /// A goal to send.
    goal: Option<[f64; 3]>,
    /// Frames on their way: (code, key, echo, what).
    inflight: Vec<(u8, u8, u8, &'static str)>,
    /// The last refusal reported, and the last cut logged.
    last_refusal: Option<u8>,
    last_cut: Option<u8>,
}

impl Gateway {
    /// A `Twist` from the peer (see the module docs).
    pub fn on_cmd_vel(&mut self, vx: f64, vy: f64, wz: f64) {
        self.drive.twist = Some(([vx, vy, wz], self.cycle));
        self.drive.changed = true;
        self.drive.goal = None;
    }

    /// A relative goal from the peer (see the module docs): replaces the velocity stream.
    pub fn on_goal(&mut self, x: f64, y: f64, theta: f64) {
        self.drive.goal = Some([x, y, theta]);
        self.drive.twist = None;
    }

    /// `true` while a velocity or a goal waits to be sent or streams: the session is opened
    /// for it as for a footstep list.
    pub(super) fn drive_wanted(&self) -> bool {
        self.drive.twist.is_some() || self.drive.goal.is_some()
    }

    /// The cycle's `VELOCITY` or `GOAL`, if one is due; `true` if one went out.
    pub(super) fn drive_frames(&mut self, frames: &mut Vec<RawFrame>) -> bool {
        if self.link != Link::Open {
            return false;
        }
        if let Some(g) = self.drive.goal.take() {
            self.seq += 1;
            let c = Command::Goal(WireGoal::from_si(self.seq, g[0], g[1], g[2]));
            self.drive_send(c, "goal", frames);
            return true;
        }
        let Some((v, heard)) = self.drive.twist else {
            return false;
        };
        let silent = self.cycle.saturating_sub(heard) > CMD_VEL_TIMEOUT_CYCLES;
        let due = self.drive.changed || self.cycle >= self.drive.sent_at + STREAM_CYCLES;
        if !(due || silent) {
            return false;
        }
        let v = if silent {
            // The stick was let go: stop and stand, and stream no more.
            self.drive.twist = None;
            self.outputs.push(Output::Log(format!(
                "cmd_vel silent for {:.1} s: zero velocity, the robot stops",
                CMD_VEL_TIMEOUT_CYCLES as f64 * self.cfg.dt
            )));
            [0.0; 3]
        } else {
            v
        };
        self.seq += 1;
        let c = Command::Velocity(WireVelocity::from_si(self.seq, v[0], v[1], v[2]));
        self.drive_send(c, "cmd_vel", frames);
        self.drive.changed = false;
        self.drive.sent_at = self.cycle;
        true
    }

    fn drive_send(&mut self, c: Command, what: &'static str, frames: &mut Vec<RawFrame>) {
        self.drive
            .inflight
            .push((c.code(), c.key(), c.echo_in(self.epoch), what));
        // (At most the node's answer time: older entries are forgotten.)
        if self.drive.inflight.len() > 64 {
            self.drive.inflight.remove(0);
        }
        frames.push(c.encode_in(self.epoch));
    }

    /// The node's answer to a `VELOCITY` or `GOAL`: `true` if it was one.
    pub(super) fn on_drive_ack(&mut self, a: &Ack) -> bool {
        let Some(pos) = self
            .drive
            .inflight
            .iter()
            .position(|f| f.0 == a.command && f.1 == a.seq && f.2 == a.echo)
        else {
            return false;
        };
        let (_, _, _, what) = self.drive.inflight.remove(pos);
        match a.reason {
            Some(r) => {
                if self.drive.last_refusal != Some(r.code()) {
                    self.drive.last_refusal = Some(r.code());
                    let detail = format!("the node refused the {what} command");
                    self.refusal(0, 0, -1, what, Ok(r), detail);
                }
            }
            None => {
                self.drive.last_refusal = None;
                let cut = a.cut().unwrap_or(0);
                if self.drive.last_cut != Some(cut) {
                    self.drive.last_cut = Some(cut);
                    if cut != 0 {
                        self.outputs.push(Output::Log(format!(
                            "{what}: walked slower than commanded (cut {cut:#06b}: bit 0 \
                             forward, 1 across, 2 turn, 3 in place)"
                        )));
                    }
                }
            }
        }
        true
    }
}
