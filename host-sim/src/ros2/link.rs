//! The node the gateway drives: in this process over the virtual CAN bus ([`InProcess`], the
//! default), or a real node on a Linux CAN interface ([`SocketCan`], feature `socketcan`).
//!
//! One call of [`NodeLink::cycle`] is one control cycle: the gateway's frames go on the bus,
//! the node runs its cycle, and the frames the node sent come back. In this process the cycle
//! is the simulation's (`host_sim::sim`): the controller's frames at `t_k`, the node's poll
//! at `t_k + 2.5 ms`, its answers read at `t_{k+1}`, with `t_k = 5 (k + 1)` ms; on a real bus
//! the node keeps its own clock and the cycle hands back whatever arrived since the last one.

use embedded_can::nb::Can;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::RawFrame;

use crate::sim::bus::{Bus, Faults, Port};

/// A node behind a bus, one control cycle at a time.
pub trait NodeLink {
    /// Sends `frames`, lets one control cycle pass, and returns the frames the node sent.
    fn cycle(&mut self, frames: &[RawFrame]) -> Vec<RawFrame>;
    /// The soles where the robot has them now (left, right: x, y, heading in the world frame),
    /// where the link has a robot ([`WithEngine`]); `None`: the node's reference is all there
    /// is.
    fn measured_soles(&self) -> Option<[(f64, f64, f64); 2]> {
        None
    }
    /// The bus log so far (`candump -l` lines), where the link records one.
    fn log(&self) -> Vec<String> {
        Vec::new()
    }
}

/// The node in this process, on host-sim's virtual CAN bus (1 Mbit/s, no faults), recorded, with
/// the board's queue of 16 steps.
pub struct InProcess {
    node: Node<16>,
    bus: Bus,
    ctl: Port,
    port: Port,
    k: u64,
}

impl InProcess {
    /// The node configured by `cfg` on a fresh bus.
    pub fn new(cfg: NodeConfig) -> Result<Self, String> {
        let node = Node::new(cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
        let bus = Bus::new(1_000_000, 2, Faults::default(), 1);
        bus.record();
        let (ctl, port) = (bus.port(0), bus.port(1));
        Ok(Self {
            node,
            bus,
            ctl,
            port,
            k: 0,
        })
    }

    /// The node (for tests and the engine).
    pub fn node(&self) -> &Node<16> {
        &self.node
    }
}

/// The node in this process and the robot in MuJoCo: after each node cycle the engine runs the
/// cycle's five 1 ms ticks under the stabilizer, tracking the reference (interpolated from the
/// cycle before, as in `host_sim::physics::closed_loop`), and the soles are read from the
/// engine's waist pose and leg encoders. The gateway reports those as the landings.
pub struct WithEngine {
    inner: InProcess,
    engine: crate::physics::bridge::Engine,
    stab: crate::physics::stabilizer::Stabilizer,
    sensed: crate::physics::sensors::Sensors,
    robot: crate::physics::model::Robot,
    obs: crate::physics::bridge::Observation,
    prev: planner_core::gait::Reference<f64>,
    waist_z0: f64,
    /// The first fall, if any: when (s) and why.
    pub fell: Option<(f64, String)>,
    k: u64,
}

impl WithEngine {
    /// The node configured by `cfg` and `robot` in MuJoCo (`python3 -m pip install
    /// mujoco==3.2.7`), standing in the node's first pose.
    pub fn new(cfg: NodeConfig, robot: &crate::robot::Robot) -> Result<Self, String> {
        use crate::physics::{initial_pose, PhysicsConfig, PHYSICS_DT};
        let inner = InProcess::new(cfg)?;
        let pc = PhysicsConfig::for_robot(robot);
        let r0 = *inner.node().gait().last();
        let (waist0, qpos) = initial_pose(&pc.robot, &r0)?;
        let mut engine = crate::physics::bridge::Engine::start(&pc.robot.mjcf())?;
        let obs = engine.reset(&qpos)?;
        Ok(Self {
            inner,
            engine,
            stab: crate::physics::stabilizer::Stabilizer::new(
                pc.robot.clone(),
                pc.gains,
                PHYSICS_DT,
                pc.z_c,
            ),
            sensed: crate::physics::sensors::Sensors::new(pc.sensors),
            robot: pc.robot,
            obs,
            prev: r0,
            waist_z0: waist0.p[2],
            fell: None,
            k: 0,
        })
    }
}

impl NodeLink for WithEngine {
    fn cycle(&mut self, frames: &[RawFrame]) -> Vec<RawFrame> {
        use crate::physics::{metrics::fall_check, reference_at, PHYSICS_DT};
        let out = self.inner.cycle(frames);
        let r = *self.inner.node().gait().last();
        let pair = [self.prev, r];
        let dt = self.inner.node().gait().params().dt;
        self.k += 1;
        for j in 0..5 {
            if self.fell.is_some() {
                break;
            }
            let rj = reference_at(&pair, dt, (j + 1) as f64 * PHYSICS_DT);
            let step = self
                .stab
                .step(&rj, self.sensed.read(&self.obs.sensors))
                .and_then(|ctrl| self.engine.step(1, &ctrl, [0.0; 6]));
            match step {
                Ok(obs) => self.obs = obs,
                Err(e) => {
                    self.fell = Some((self.k as f64 * dt, format!("engine: {e}")));
                    break;
                }
            }
            if let Some(cause) = fall_check(
                self.obs.base_quat,
                self.obs.base_pos[2],
                self.waist_z0,
                self.obs.other_contact,
            ) {
                self.fell = Some((self.k as f64 * dt, format!("{cause:?}")));
            }
        }
        self.prev = r;
        out
    }

    fn log(&self) -> Vec<String> {
        self.inner.log()
    }

    fn measured_soles(&self) -> Option<[(f64, f64, f64); 2]> {
        use crate::physics::model::sensor;
        let o = &self.obs;
        let mut q = [[0.0; 6]; 2];
        for (j, leg) in q.iter_mut().enumerate() {
            leg.copy_from_slice(
                o.sensors
                    .get(sensor::QPOS + 6 * j..sensor::QPOS + 6 * j + 6)?,
            );
        }
        let base = crate::robot::model::Pose {
            p: o.base_pos,
            r: crate::physics::quat_to_mat(o.base_quat),
        };
        let (soles, _, _) = self.robot.fk(&base, &q);
        let pose = |p: &crate::robot::model::Pose| (p.p[0], p.p[1], p.r[1][0].atan2(p.r[0][0]));
        Some([pose(&soles[0]), pose(&soles[1])])
    }
}

impl NodeLink for InProcess {
    fn cycle(&mut self, frames: &[RawFrame]) -> Vec<RawFrame> {
        const MS: u64 = 1_000_000;
        let t0 = 5 * MS * (self.k + 1);
        self.k += 1;
        self.bus.advance(t0);
        for f in frames {
            // The port's mailbox holds 64 frames; the gateway sends at most 16 a cycle.
            let _ = self.ctl.transmit(f);
        }
        self.bus.advance(t0 + 5 * MS / 2);
        self.node.poll((t0 / MS) as u32 + 2, &mut self.port);
        self.bus.advance(t0 + 5 * MS);
        let mut out = Vec::new();
        while let Ok(f) = self.ctl.receive() {
            out.push(f);
        }
        out
    }

    fn log(&self) -> Vec<String> {
        self.bus.log()
    }
}

/// The identifiers the node sends: what the gateway reads from a real bus.
pub const NODE_SENDS: [u16; 11] = {
    use planner_core::wire::ids::*;
    [
        ACK, ADJUST, COG, ZMP, COG_VEL, FOOT_LEFT, FOOT_RIGHT, STATUS, DIAG, LINK, SESSION,
    ]
};

/// A real node on a Linux CAN interface (feature `socketcan`): the gateway's frames are
/// written to the socket, and every frame of the node's identifiers that arrived since the
/// last cycle is read back (the socket's filters pass only those).
#[cfg(feature = "socketcan")]
pub struct SocketCan {
    socket: socketcan::CanSocket,
}

#[cfg(feature = "socketcan")]
impl SocketCan {
    /// Opens `interface` (e.g. `can0`), non-blocking, filtered for the node's frames.
    pub fn open(interface: &str) -> Result<Self, String> {
        use socketcan::{CanFilter, Socket, SocketOptions};
        let socket = socketcan::CanSocket::open(interface)
            .map_err(|e| format!("cannot open CAN interface {interface}: {e}"))?;
        let mask =
            socketcan::id::CAN_SFF_MASK | socketcan::id::CAN_EFF_FLAG | socketcan::id::CAN_RTR_FLAG;
        let filters: Vec<CanFilter> = NODE_SENDS
            .iter()
            .map(|&id| CanFilter::new(u32::from(id), mask))
            .collect();
        socket
            .set_filters(&filters)
            .and_then(|_| socket.set_nonblocking(true))
            .map_err(|e| format!("{interface}: {e}"))?;
        Ok(Self { socket })
    }
}

#[cfg(feature = "socketcan")]
impl NodeLink for SocketCan {
    fn cycle(&mut self, frames: &[RawFrame]) -> Vec<RawFrame> {
        use socketcan::{EmbeddedFrame, Socket, StandardId};
        for f in frames {
            if let Some(frame) =
                StandardId::new(f.id).and_then(|id| socketcan::CanFrame::new(id, f.bytes()))
            {
                let _ = self.socket.write_frame(&frame);
            }
        }
        let mut out = Vec::new();
        while let Ok(frame) = self.socket.read_frame() {
            if let socketcan::Id::Standard(id) = frame.id() {
                if let Some(f) = RawFrame::new(id.as_raw(), frame.data()) {
                    out.push(f);
                }
            }
        }
        out
    }
}
