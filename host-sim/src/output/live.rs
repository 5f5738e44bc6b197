//! The live view: a walk served over the Foxglove WebSocket protocol (the `foxglove` crate,
//! Foxglove's SDK), so that Foxglove (or any client of the protocol) shows it as it happens.
//!
//! The channels and their schemas are the MCAP file's ([`super::mcap::TOPICS`],
//! [`super::mcap::schemas`]: JSON messages, JSON Schema), so a recording and the live view
//! look alike in a viewer; the live view adds `/tf` (`foxglove.FrameTransforms`: the robot's
//! links from the engine state, in `physics`) and `/measured` (the engine's COG and CoP). Every message carries its log time
//! on the clock of the MCAP file ([`super::mcap::log_time_ns`]).
//!
//! Connect Foxglove (or Lichtblick) to `ws://localhost:<port>` ("Open connection" →
//! "Foxglove WebSocket"); the 3D panel shows `/scene` in frame `world`.

use std::sync::Arc;
use std::time::{Duration, Instant};

use foxglove::websocket::Capability;
use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};
use planner_core::gait::Reference;
use serde_json::{json, Value};

use super::mcap::{frame_json, log_time_ns, sample_messages, schemas, LogFrame, CAN, TOPICS};
use crate::eval::multibody::MbSample;

/// The topic of the links' transforms.
pub const TF_TOPIC: &str = "/tf";
/// The topic of the measured COG and CoP (engine runs).
pub const MEASURED_TOPIC: &str = "/measured";

fn measured_schema() -> Value {
    let xy = json!({ "type": "object", "properties": {
        "x": { "type": "number" }, "y": { "type": "number" } } });
    json!({
        "title": "host_sim.Measured",
        "description": "The robot as the engine has it: whole-body COG and floor CoP [m]",
        "type": "object",
        "properties": {
            "t": { "type": "number", "description": "trajectory time [s]" },
            "cog": xy.clone(),
            "cop": xy,
        },
    })
}

/// The unit quaternion (x, y, z, w) of a rotation matrix (rows: `r[i][j]`).
pub fn quaternion_of(r: &[[f64; 3]; 3]) -> [f64; 4] {
    let tr = r[0][0] + r[1][1] + r[2][2];
    let (x, y, z, w) = if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        (
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
            0.25 * s,
        )
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        (
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[2][1] - r[1][2]) / s,
        )
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        (
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
            (r[0][2] - r[2][0]) / s,
        )
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        (
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
            (r[1][0] - r[0][1]) / s,
        )
    };
    [x, y, z, w]
}

/// One link's pose in its parent's frame: name, parent, position \[m\], orientation (x, y, z,
/// w).
#[derive(Clone, Debug, PartialEq)]
pub struct LinkPose {
    /// The link's frame.
    pub child: String,
    /// Its parent's frame (`world` for the root).
    pub parent: String,
    /// Position \[m\].
    pub position: [f64; 3],
    /// Orientation as a unit quaternion (x, y, z, w).
    pub orientation: [f64; 4],
}

fn tf_schema() -> Value {
    json!({
        "title": "foxglove.FrameTransforms",
        "description": "Transforms between frames (Foxglove's well-known schema)",
        "type": "object",
        "properties": {
            "transforms": { "type": "array", "items": {
                "type": "object",
                "properties": {
                    "timestamp": { "type": "object", "properties": {
                        "sec": { "type": "integer" }, "nsec": { "type": "integer" } } },
                    "parent_frame_id": { "type": "string" },
                    "child_frame_id": { "type": "string" },
                    "translation": { "type": "object", "properties": {
                        "x": { "type": "number" }, "y": { "type": "number" }, "z": { "type": "number" } } },
                    "rotation": { "type": "object", "properties": {
                        "x": { "type": "number" }, "y": { "type": "number" },
                        "z": { "type": "number" }, "w": { "type": "number" } } },
                },
            } },
        },
    })
}

/// A running live view.
pub struct LiveView {
    /// The context the channels and the server live in (the server does not keep it alive).
    _ctx: Arc<Context>,
    server: Option<foxglove::WebSocketServerHandle>,
    channels: Vec<Arc<RawChannel>>,
    tf: Arc<RawChannel>,
    measured: Arc<RawChannel>,
    cog_height: f64,
    sole: [f64; 2],
}

impl LiveView {
    /// Serves on `host:port` (port 0: any free port, see [`LiveView::port`]); `cog_height` and
    /// `sole` draw the scene as the MCAP file does.
    pub fn start(host: &str, port: u16, cog_height: f64, sole: [f64; 2]) -> Result<Self, String> {
        let ctx = Context::new();
        let schema = |v: &Value| {
            let name = v["title"].as_str().unwrap_or("unnamed").to_string();
            Schema::new(
                name,
                "jsonschema",
                serde_json::to_vec(v).unwrap_or_default(),
            )
        };
        let mut channels = Vec::new();
        for (topic, s) in TOPICS.iter().zip(schemas().iter()) {
            let c = ChannelBuilder::new(*topic)
                .context(&ctx)
                .message_encoding("json")
                .schema(schema(s))
                .build_raw()
                .map_err(|e| format!("live view channel {topic}: {e}"))?;
            channels.push(c);
        }
        let tf = ChannelBuilder::new(TF_TOPIC)
            .context(&ctx)
            .message_encoding("json")
            .schema(schema(&tf_schema()))
            .build_raw()
            .map_err(|e| format!("live view channel {TF_TOPIC}: {e}"))?;
        let measured = ChannelBuilder::new(MEASURED_TOPIC)
            .context(&ctx)
            .message_encoding("json")
            .schema(schema(&measured_schema()))
            .build_raw()
            .map_err(|e| format!("live view channel {MEASURED_TOPIC}: {e}"))?;
        let server = WebSocketServer::new()
            .name("host-sim")
            .context(&ctx)
            .capabilities([Capability::Time])
            .bind(host, port)
            .start_blocking()
            .map_err(|e| format!("live view on {host}:{port}: {e}"))?;
        Ok(Self {
            _ctx: ctx,
            server: Some(server),
            channels,
            tf,
            measured,
            cog_height,
            sole,
        })
    }

    /// The live view for `robot` on `127.0.0.1:port`, its address printed for the user.
    pub fn announce(port: u16, robot: &crate::robot::Robot) -> Result<Self, String> {
        let p = robot.node_config().params;
        let view = Self::start(
            "127.0.0.1",
            port,
            p.cog_height,
            [2.0 * p.sole_half_length, 2.0 * p.sole_half_width],
        )?;
        crate::outln!(
            "live view: ws://127.0.0.1:{} (Foxglove: Open connection, Foxglove WebSocket)",
            view.port()
        );
        Ok(view)
    }

    /// The port the view listens on.
    pub fn port(&self) -> u16 {
        self.server.as_ref().map(|s| s.port()).unwrap_or(0)
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.server.as_ref().map(|s| s.client_count()).unwrap_or(0)
    }

    fn put(&self, ch: &RawChannel, ns: u64, v: &Value) {
        if let Ok(bytes) = serde_json::to_vec(v) {
            ch.log_with_meta(&bytes, PartialMetadata::with_log_time(ns));
        }
    }

    /// One reference sample at trajectory time `t` \[s\] (and its multi-body ZMP, if any).
    pub fn sample(&self, t: f64, r: &Reference<f64>, mb: Option<&MbSample>) {
        let ns = log_time_ns(t);
        if let Some(s) = &self.server {
            s.broadcast_time(ns);
        }
        for (ch, v) in sample_messages(t, r, mb, self.cog_height, self.sole) {
            self.put(&self.channels[ch], ns, &v);
        }
    }

    /// One CAN frame.
    pub fn can(&self, f: &LogFrame) {
        self.put(&self.channels[CAN], f.unix_us * 1000, &frame_json(f));
    }

    /// The links' poses at trajectory time `t` \[s\].
    pub fn transforms(&self, t: f64, links: &[LinkPose]) {
        let ns = log_time_ns(t);
        let stamp = json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 });
        let tfs: Vec<Value> = links
            .iter()
            .map(|l| {
                json!({
                    "timestamp": stamp,
                    "parent_frame_id": l.parent,
                    "child_frame_id": l.child,
                    "translation": { "x": l.position[0], "y": l.position[1], "z": l.position[2] },
                    "rotation": { "x": l.orientation[0], "y": l.orientation[1],
                                  "z": l.orientation[2], "w": l.orientation[3] },
                })
            })
            .collect();
        self.put(&self.tf, ns, &json!({ "transforms": tfs }));
    }

    /// The robot as the engine has it at trajectory time `t` \[s\]: whole-body COG and floor CoP.
    pub fn measured(&self, t: f64, cog: [f64; 2], cop: [f64; 2]) {
        let v = json!({ "t": t, "cog": { "x": cog[0], "y": cog[1] },
                        "cop": { "x": cop[0], "y": cop[1] } });
        self.put(&self.measured, log_time_ns(t), &v);
    }

    /// Waits up to `timeout` for a first client, then `settle` more for its subscriptions.
    pub fn wait_for_client(&self, timeout: Duration, settle: Duration) -> bool {
        let start = Instant::now();
        while self.clients() == 0 {
            if start.elapsed() >= timeout {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(settle);
        true
    }

    /// Plays a computed walk in real time: every trajectory row at its time (`dt` apart), the
    /// CAN frames of `can_log` as their times pass.
    pub fn play(
        &self,
        trajectory: &[Reference<f64>],
        dt: f64,
        mb: &[MbSample],
        can_log: &[LogFrame],
    ) {
        let start = Instant::now();
        let mut frames = can_log.iter().peekable();
        for (k, r) in trajectory.iter().enumerate() {
            let t = k as f64 * dt;
            let due = Duration::from_secs_f64(t);
            if let Some(wait) = due.checked_sub(start.elapsed()) {
                std::thread::sleep(wait);
            }
            let ns = log_time_ns(t);
            while let Some(f) = frames.next_if(|f| f.unix_us * 1000 < ns) {
                self.can(f);
            }
            self.sample(t, r, mb.get(k));
        }
        for f in frames {
            self.can(f);
        }
    }
}

/// `run --live PORT`: the computed walk served on `port`, once a client has connected (within
/// 60 s), in real time.
pub fn serve_walk(
    port: u16,
    robot: &crate::robot::Robot,
    trajectory: &[Reference<f64>],
    dt: f64,
    mb: &[MbSample],
    can_log: &[String],
) -> Result<(), String> {
    let view = LiveView::announce(port, robot)?;
    if view.wait_for_client(Duration::from_secs(60), Duration::from_millis(500)) {
        let frames = can_log
            .iter()
            .filter(|l| !l.trim().is_empty())
            .map(|l| super::mcap::parse_log_line(l))
            .collect::<Result<Vec<_>, _>>()?;
        view.play(trajectory, dt, mb, &frames);
        crate::outln!("live view: played the walk");
    } else {
        crate::outln!("live view: no client within 60 s");
    }
    Ok(())
}

impl Drop for LiveView {
    fn drop(&mut self) {
        if let Some(s) = self.server.take() {
            s.stop().wait_blocking();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternions_of_rotations_round_trip() {
        // Rotations about each axis and a general one, each branch of the conversion.
        for (axis, angle) in [(0, 0.3), (1, -2.9), (2, 3.0), (0, 3.1), (1, 1.0), (2, -0.2)] {
            let (s, c) = f64::sin_cos(angle);
            let mut r = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            let (i, j) = [(1, 2), (2, 0), (0, 1)][axis];
            r[i][i] = c;
            r[j][j] = c;
            r[i][j] = -s;
            r[j][i] = s;
            let q = quaternion_of(&r);
            let mut want = [0.0, 0.0, 0.0, (angle / 2.0).cos()];
            want[axis] = (angle / 2.0).sin();
            let sign = if q[3] * want[3] + q[axis] * want[axis] < 0.0 {
                -1.0
            } else {
                1.0
            };
            for k in 0..4 {
                assert!(
                    (sign * q[k] - want[k]).abs() < 1e-12,
                    "axis {axis} angle {angle}: {q:?}"
                );
            }
        }
    }
}
