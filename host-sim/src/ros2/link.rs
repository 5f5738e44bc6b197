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

    /// The node (for tests).
    pub fn node(&self) -> &Node<16> {
        &self.node
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
