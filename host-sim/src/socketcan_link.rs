//! The node on a real Linux CAN interface (feature `socketcan`).
//!
//! `host-sim node <interface>` runs the same `planner_core::node::Node` as the firmware on a
//! SocketCAN socket, polled every 5 ms of wall-clock time: a host PC can stand in for the
//! microcontroller on a bench bus (`ip link set can0 up type can bitrate 1000000`). The
//! sandbox this project is built in has no CAN (not even vcan), so this backend is only
//! compile-tested.

use std::error::Error;
use std::time::{Duration, Instant};

use planner_core::node::{Node, NodeConfig};
use socketcan::{CanSocket, Socket};

/// Runs the node on `interface` for `seconds` (forever if `None`), printing the status every
/// second.
pub fn run_node(interface: &str, seconds: Option<f64>) -> Result<(), Box<dyn Error>> {
    let mut socket = CanSocket::open(interface)?;
    socket.set_nonblocking(true)?;
    let mut node: Node<64> =
        Node::new(NodeConfig::hrp2()).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let period = Duration::from_millis(5);
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
            println!(
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
