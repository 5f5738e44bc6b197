//! `LINK` (0x302): the firmware's CAN link health, published only once the firmware reports
//! it (`Node::set_link_health`), with `STATUS`, `DIAG` and `SESSION` in the first cycle and
//! every 20 cycles after it, the latest report.

mod common;

use common::Bus;
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{ids, LinkHealth};

#[test]
fn link_is_sent_only_once_reported_with_status_and_the_latest_values() {
    let mut n = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut bus = Bus::default();
    for k in 1..=40 {
        n.poll(5 * k, &mut bus);
    }
    assert!(bus.tx.iter().any(|f| f.id == ids::STATUS));
    assert!(
        bus.tx.iter().all(|f| f.id != ids::LINK),
        "LINK without a report"
    );
    bus.tx.clear();
    for k in 41..=100u32 {
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
    // Right behind STATUS, DIAG and SESSION, with the report of that cycle (cycles 41, 61,
    // 81).
    for (&i, l) in status.iter().zip(&links) {
        assert_eq!(bus.tx[i + 1].id, ids::DIAG);
        assert_eq!(bus.tx[i + 2].id, ids::SESSION);
        assert_eq!(bus.tx[i + 3].id, ids::LINK);
        assert_eq!((l.bus_offs, l.reset), (2, 5));
    }
    assert_eq!(
        links.iter().map(|l| l.tec).collect::<Vec<_>>(),
        [41, 61, 81]
    );
}

/// The reports go out in the node's first cycle (after a reset of the board a controller sees
/// the new start-up at once), then every 20 cycles: `STATUS`, `DIAG`, `SESSION`, `LINK`.
#[test]
fn the_reports_go_out_in_the_first_cycle() {
    let mut n = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut bus = Bus::default();
    n.set_link_health(LinkHealth {
        reset: 5,
        ..LinkHealth::default()
    });
    n.poll(5, &mut bus);
    let ids: Vec<u16> = bus.tx.iter().map(|f| f.id).collect();
    // No reference before a session is open: nothing but the reports.
    assert_eq!(ids, [ids::STATUS, ids::DIAG, ids::SESSION, ids::LINK]);
    assert_eq!(LinkHealth::decode(&bus.tx[3]).map(|l| l.reset), Some(5));
}
