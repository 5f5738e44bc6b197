//! The node on a real Linux CAN interface (feature `socketcan`).
//!
//! `host-sim node <interface>` runs the same `planner_core::node::Node` as the firmware on a
//! SocketCAN socket, polled every 5 ms of wall-clock time: a host PC can stand in for the
//! microcontroller on a bench bus (`ip link set can0 up type can bitrate 1000000`). The
//! sandbox this project is built in has no CAN (not even vcan), so this backend is only
//! compile-tested.
//!
//! The socket's receive filters are the node's command identifiers, [`ids::COMMANDS`], and
//! nothing else ([`command_filters`]): the kernel drops every other standard identifier, every
//! extended frame and every remote frame before they reach the node (which would count and
//! ignore them anyway, as it does on the virtual bus).

use std::error::Error;
use std::time::{Duration, Instant};

use planner_core::node::{Node, NodeConfig};
use planner_core::wire::ids;
use socketcan::id::{CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_SFF_MASK};
use socketcan::{CanFilter, CanSocket, Socket, SocketOptions};

/// The filter mask of [`command_filters`]: all 11 identifier bits, and the extended-frame and
/// remote-request flags, so that a filter whose identifier has both flags clear matches only
/// standard data frames.
const COMMAND_MASK: u32 = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;

/// The socket's receive filters: one per command identifier of [`ids::COMMANDS`], each
/// matching exactly that standard identifier in a data frame (the kernel accepts a frame when
/// `can_id & mask == filter_id & mask` for one of the filters).
pub fn command_filters() -> [CanFilter; ids::COMMANDS.len()] {
    ids::COMMANDS.map(|id| CanFilter::new(u32::from(id), COMMAND_MASK))
}

/// Runs the node configured by `cfg` on `interface` for `seconds` (forever if `None`), one
/// poll per control period of its gait, printing the status every 200 cycles. The entropy of
/// `cfg` is replaced by the operating system's ([`super::entropy::start_up`]).
pub fn run_node(
    interface: &str,
    seconds: Option<f64>,
    cfg: NodeConfig,
) -> Result<(), Box<dyn Error>> {
    let mut socket = CanSocket::open(interface)?;
    // Frames that arrived between `open` and here are still queued; the node ignores those
    // that are not its own.
    socket.set_filters(&command_filters())?;
    socket.set_nonblocking(true)?;
    // A session epoch and first step number of this start-up's own (`super::entropy`).
    let cfg = super::entropy::start_up(cfg)
        .map_err(|e| format!("no entropy for the session epoch (/dev/urandom): {e}"))?;
    let mut node: Node<64> = Node::new(cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let period = Duration::from_secs_f64(cfg.params.dt);
    let start = Instant::now();
    let mut next = start;
    let mut cycles: u64 = 0;
    loop {
        next += period;
        let now = Instant::now();
        if now < next {
            std::thread::sleep(next - now);
        } else if now - next > period {
            node.note_overrun();
        }
        let ms = start.elapsed().as_millis() as u32;
        node.poll(ms, &mut socket);
        cycles += 1;
        if cycles % 200 == 0 {
            crate::outln!(
                "{:.1} s: {:?}",
                start.elapsed().as_secs_f64(),
                node.status()
            );
        }
        if seconds.is_some_and(|s| start.elapsed().as_secs_f64() >= s) {
            return Ok(());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernel's rule (`can_id & mask == filter_id & mask`, no inverted filters here).
    fn accepted(can_id: u32) -> bool {
        command_filters().iter().any(|f| {
            let f = f.as_ref();
            can_id & f.can_mask == f.can_id & f.can_mask
        })
    }

    #[test]
    fn one_exact_filter_per_command() {
        let filters = command_filters();
        assert_eq!(filters.len(), ids::COMMANDS.len());
        for (f, &id) in filters.iter().zip(ids::COMMANDS.iter()) {
            let f = f.as_ref();
            assert_eq!(f.can_id, u32::from(id), "filter id of {id:#05x}");
            assert_eq!(f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG), 0);
            assert_eq!(f.can_mask, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG);
        }
    }

    #[test]
    fn only_standard_data_frames_of_the_commands_pass() {
        for id in 0..=CAN_SFF_MASK {
            let command = ids::is_command(id as u16);
            assert_eq!(accepted(id), command, "standard data frame {id:#05x}");
            assert!(!accepted(id | CAN_RTR_FLAG), "remote frame {id:#05x}");
            // Extended frames whose low bits (or whole identifier) equal a command's.
            assert!(!accepted(id | CAN_EFF_FLAG), "extended frame {id:#010x}");
            assert!(!accepted(id | CAN_EFF_FLAG | CAN_RTR_FLAG));
            assert!(
                !accepted((id << 18) | CAN_EFF_FLAG),
                "extended frame with base id {id:#05x}"
            );
        }
    }
}
