//! `LINK` (0x302): the firmware's CAN link health, published only once the firmware reports
//! it (`Node::set_link_health`), with `STATUS` and `DIAG` every 20 cycles, the latest report.

mod common;

use common::Bus;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{ids, LinkHealth};

#[test]
fn link_is_sent_only_once_reported_with_status_and_the_latest_values() {
    let mut n = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut bus = Bus::default();
    for k in 0..40 {
        n.poll(5 * k, &mut bus);
    }
    assert!(bus.tx.iter().any(|f| f.id == ids::STATUS));
    assert!(
        bus.tx.iter().all(|f| f.id != ids::LINK),
        "LINK without a report"
    );
    bus.tx.clear();
    for k in 40..100u32 {
        n.set_link_health(LinkHealth {
            tec: k as u8,
            bus_offs: 2,
            reset: 5,
            ..LinkHealth::default()
        });
        n.poll(5 * k, &mut bus);
    }
    let status: Vec<usize> = (0..bus.tx.len())
        .filter(|&i| bus.tx[i].id == ids::STATUS)
        .collect();
    let links: Vec<LinkHealth> = bus.tx.iter().filter_map(LinkHealth::decode).collect();
    assert_eq!(status.len(), 3);
    assert_eq!(links.len(), status.len());
    // Right behind STATUS and DIAG, with the report of that cycle (cycles 60, 80, 100).
    for (&i, l) in status.iter().zip(&links) {
        assert_eq!(bus.tx[i + 1].id, ids::DIAG);
        assert_eq!(bus.tx[i + 2].id, ids::LINK);
        assert_eq!((l.bus_offs, l.reset), (2, 5));
    }
    assert_eq!(
        links.iter().map(|l| l.tec).collect::<Vec<_>>(),
        [59, 79, 99]
    );
}

/// The heartbeats firmware/README.md's bring-up checklist sends with `cansend`.
#[test]
fn the_bring_up_heartbeats_are_these_bytes() {
    use planner_core::wire::{Command, ControlOp};
    for (seq, bytes) in [(1, [1, 0, 0x17]), (2, [2, 0, 0x03]), (3, [3, 0, 0xEA])] {
        let f = Command::Control {
            seq,
            op: ControlOp::Heartbeat,
        }
        .encode();
        assert_eq!((f.id, f.bytes()), (ids::CONTROL, &bytes[..]));
    }
}
