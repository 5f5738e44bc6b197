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

/// A link loss is a loss: a link reported bus-off in more than `OFF_BUS_CYCLES` cycles in a row
/// stops a walking robot as a lost controller does (motion refused until a `Reset` standing),
/// although the controller was heard a moment before; a shorter bus-off (the first back-off,
/// one cycle; or `OFF_BUS_CYCLES` in a row) leaves the walk going; a standing robot is not
/// latched by it.
#[test]
fn a_link_off_the_bus_for_a_few_cycles_stops_the_walk() {
    use common::{y, Rig};
    use planner_core::node::{NodeState, OFF_BUS_CYCLES};
    use planner_core::wire::{ControlOp, Reason};
    let off = LinkHealth {
        bus_state: 3,
        ..LinkHealth::default()
    };
    let on = LinkHealth::default();
    let walking = || {
        let mut r = Rig::hrp2();
        for i in 0..8u16 {
            let left = i % 2 == 1;
            let x = 0.15 * f64::from(i + 1);
            assert_eq!(r.append(i, left, x, y(left)), None);
        }
        assert_eq!(r.control(ControlOp::Start), None);
        r.run(5, true);
        r
    };
    // Off for OFF_BUS_CYCLES in a row, back, off again: a glitch each time.
    let mut r = walking();
    for _ in 0..3 {
        for _ in 0..OFF_BUS_CYCLES {
            r.n.set_link_health(off);
            r.run(1, false);
        }
        r.n.set_link_health(on);
        r.run(1, true);
        assert_eq!(r.n.state(), NodeState::Walking);
    }
    // One cycle more: lost, in that cycle.
    let mut r = walking();
    for k in 0..=OFF_BUS_CYCLES {
        r.n.set_link_health(off);
        assert_eq!(r.n.state(), NodeState::Walking, "cycle {k}");
        r.run(1, false);
    }
    assert_eq!(r.n.state(), NodeState::ControllerLost);
    r.n.set_link_health(on);
    assert_eq!(
        r.append(8, false, 1.35, y(false)),
        Some(Reason::ControllerLost)
    );
    r.until(2000, |n| n.gait().is_standing());
    assert_eq!(r.control(ControlOp::Reset), None);
    assert_eq!(r.n.state(), NodeState::Standing);
    // Standing: nothing to stop, nothing latched.
    for _ in 0..3 * OFF_BUS_CYCLES {
        r.n.set_link_health(off);
        r.run(1, false);
    }
    assert_eq!(r.n.state(), NodeState::Standing);
}
