//! `ParkedNode` and `Node::restart`: the firmware's node is a parked `static` configured in
//! place. A start or a restart, whatever the node did before, leaves exactly the node that
//! `Node::with_gains` builds (every field: compared through `Debug`, which prints every field
//! of the node, the gait, its buffers and counters), behaves like it on the bus, and refuses
//! what `with_gains` refuses without changing anything.

mod common;

use common::{y, Bus, Rig};
use planner_core::gait::{Footstep, GaitError, Side, PREVIEW};
use planner_core::node::{Node, NodeConfig, ParkedNode};
use planner_core::shaping::{GainError, Law, PreviewGains};
use planner_core::wire::{ControlOp, LinkHealth, RawFrame};

/// A node that has walked, been modified, counted refusals and foreign frames, and been told
/// its link health: as far from a fresh node as a few seconds of walking get.
fn walked(cycles_walking: u32) -> Rig {
    let mut r = Rig::hrp2();
    for i in 0..6u16 {
        let left = i % 2 == 1;
        assert_eq!(r.append(i, left, 0.1 * f64::from(i + 1), y(left)), None);
    }
    // A refusal (a gap in the ids) and a foreign frame.
    assert!(r.append(9, true, 0.9, y(true)).is_some());
    r.bus
        .rx
        .push_back(RawFrame::new(0x555, &[1, 2, 3]).unwrap());
    r.cycle();
    assert_eq!(r.n.counters().foreign, 1);
    r.n.set_link_health(LinkHealth {
        tec: 7,
        bus_offs: 1,
        reset: 5,
        ..LinkHealth::default()
    });
    r.n.note_overrun();
    assert_eq!(r.control(ControlOp::Start), None);
    assert_eq!(r.modify(4, 0.55, y(false)), None);
    r.run(cycles_walking, true);
    r
}

/// Every field of `a` equals `b`'s.
fn assert_same_node<G: std::fmt::Debug>(a: &Node<16, G>, b: &Node<16, G>, what: &str) {
    assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}");
}

/// The frames both nodes send over `cycles` cycles of the same traffic (a walk of four
/// steps), which must be the same.
fn same_behaviour<G>(a: &mut Node<16, G>, b: &mut Node<16, G>)
where
    G: std::borrow::Borrow<PreviewGains<f64, PREVIEW>>,
{
    let mut book = planner_core::wire::StepBook::new();
    let side = a.gait().next_side() == Some(Side::Left);
    let session = a.session().tag();
    let control = |seq, op| planner_core::wire::Command::Control { session, seq, op }.encode();
    // The handshake (the session as the node publishes it), four steps, the start (the
    // session then is the next epoch).
    let mut program = vec![control(1, ControlOp::Reset)];
    let first = a.next_step();
    program.extend((0..4u16).map(|i| {
        let left = side ^ (i % 2 == 1);
        book.append(first + i, left, 0.15 * f64::from(i + 1), y(left), 0.0)
            .unwrap()
            .encode()
    }));
    let opened = planner_core::wire::Command::Control {
        session: session.wrapping_add(1),
        seq: 2,
        op: ControlOp::Start,
    };
    program.push(opened.encode());
    let (mut ba, mut bb) = (Bus::default(), Bus::default());
    for k in 0..600u32 {
        if let Some(f) = program.get(k as usize) {
            ba.rx.push_back(*f);
            bb.rx.push_back(*f);
        }
        let ra = a.poll(5 * k + 5, &mut ba);
        let rb = b.poll(5 * k + 5, &mut bb);
        assert_eq!(ra, rb, "cycle {k}");
    }
    assert!(ba.tx.len() > 3000, "the walk sent {} frames", ba.tx.len());
    assert_eq!(ba.tx, bb.tx);
    assert!(a.gait().is_standing() && a.same_state(b));
}

#[test]
fn a_restarted_node_is_the_node_built_afresh() {
    let cfg = NodeConfig::hrp2();
    // Standing after start-up traffic, mid-walk in double and single support, stopping.
    for cycles in [0, 37, 90, 161, 400] {
        let mut r = walked(cycles);
        r.n.restart(cfg).unwrap();
        let mut fresh = Node::<16>::new(cfg).unwrap();
        assert_same_node(&r.n, &fresh, &format!("after {cycles} cycles of walking"));
        same_behaviour(&mut r.n, &mut fresh);
    }
}

#[test]
fn a_started_parked_node_is_with_gains() {
    let cfg = NodeConfig::hrp2();
    let gains =
        PreviewGains::<f64, PREVIEW>::new(&cfg.params.preview_config(), Law::FromRest).unwrap();
    let mut parked = ParkedNode::<16, _>::new(&gains);
    let mut built = Node::<16, _>::with_gains(cfg, &gains).unwrap();
    let node = parked.start(cfg).unwrap();
    assert_same_node(node, &built, "parked, then started");
    same_behaviour(node, &mut built);

    // In another stance (turned, away from the origin): as built there.
    let mut turned = cfg;
    let (s, c) = (0.7f64.sin(), 0.7f64.cos());
    let half = cfg.params.step_width / 2.0;
    turned.left = Footstep::new(Side::Left, 3.0 - s * half, -2.0 + c * half, 0.7);
    turned.right = Footstep::new(Side::Right, 3.0 + s * half, -2.0 - c * half, 0.7);
    let mut parked = ParkedNode::<16, _>::new(&gains);
    let built = Node::<16, _>::with_gains(turned, &gains).unwrap();
    assert_same_node(
        parked.start(turned).unwrap(),
        &built,
        "started in another stance",
    );
    node.restart(turned).unwrap();
    assert_same_node(node, &built, "restarted in another stance");
}

#[test]
fn a_failed_start_leaves_the_node_parked() {
    let cfg = NodeConfig::hrp2();
    let gains =
        PreviewGains::<f64, PREVIEW>::new(&cfg.params.preview_config(), Law::FromRest).unwrap();
    let mut parked = ParkedNode::<16, _>::new(&gains);
    let before = format!("{parked:?}");
    let mut other_robot = cfg;
    other_robot.params.cog_height += 0.05;
    assert_eq!(
        parked.start(other_robot).map(|_| ()),
        Err(GaitError::Gains(GainError::BadConfig))
    );
    assert_eq!(format!("{parked:?}"), before);
    let built = Node::<16, _>::with_gains(cfg, &gains).unwrap();
    assert_same_node(
        parked.start(cfg).unwrap(),
        &built,
        "started after a refusal",
    );
}

#[test]
fn a_refused_restart_changes_nothing() {
    let cfg = NodeConfig::hrp2();
    let mut r = walked(120);
    let before = format!("{:?}", r.n);
    let gains =
        PreviewGains::<f64, PREVIEW>::new(&cfg.params.preview_config(), Law::FromRest).unwrap();

    let mut bad_foot = cfg;
    bad_foot.left.x = f64::NAN;
    let mut bad_params = cfg;
    bad_params.params.single_ticks = 0;
    // Gains that are not this node's: a robot with another COG height.
    let mut other_robot = cfg;
    other_robot.params.cog_height += 0.05;
    for (what, c, want) in [
        ("a foot not finite", bad_foot, Some(GaitError::NonFinite)),
        ("no single support", bad_params, None),
        (
            "another robot's gains",
            other_robot,
            Some(GaitError::Gains(GainError::BadConfig)),
        ),
    ] {
        // `with_gains` with the node's own gains refuses it too, with the same error.
        let built = Node::<16, _>::with_gains(c, &gains).map(|_| ());
        let e = r.n.restart(c).expect_err(what);
        assert_eq!(built, Err(e), "{what}");
        if let Some(want) = want {
            assert_eq!(e, want, "{what}");
        }
        assert_eq!(format!("{:?}", r.n), before, "{what} changed the node");
    }
    // It still walks on as it was.
    r.run(200, true);
}
