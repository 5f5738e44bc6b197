//! The bus-off back-off over the register model: the node listens in bus monitoring, so an
//! `ESTOP` sent during the back-off reaches it in the cycle it arrives; nothing is transmitted
//! until the back-off ends; the `ACK`s owed in the TX FIFO at the bus-off (whose requests
//! configuration mode resets) leave in order after the re-join, before the later ones; an
//! `ESTOP` waiting in RX FIFO1 at the bus-off is not lost. And the fallback for a core that
//! refuses configuration mode: held in `INIT`, deaf, its `ACK`s kept in the TX FIFO.

mod common;
mod regmodel;

use common::*;

use board_core::fdcan::RegFdcan;
use board_core::Link;
use planner_core::node::{Node, NodeConfig, NodeState};
use planner_core::wire::ids;
use regmodel::{FdcanModel, Verdict};

/// Bit times of a 5 ms control cycle at 1 Mbit/s.
const CYCLE_BITS: u32 = 5_000;

type ModelLink = Link<RegFdcan<FdcanModel>>;

fn link_over(m: FdcanModel) -> ModelLink {
    Link::new(RegFdcan::new(m))
}

fn model(l: &ModelLink) -> &FdcanModel {
    l.peripheral().regs()
}

/// (command byte, sequence number) of the `ACK`s on the modelled wire, in order.
fn acks(l: &ModelLink) -> Vec<(u8, u8)> {
    model(l)
        .st()
        .wire
        .iter()
        .filter(|f| f.id == u32::from(ids::ACK))
        .map(|f| (f.data[0], f.data[1]))
        .collect()
}

/// The rest of a control cycle after the poll: its bus time, the bus sending what it may
/// (`send`), services between; then `Link::cycle` (the next slot begins).
fn rest_of_cycle(l: &mut ModelLink, send: bool) {
    for _ in 0..4 {
        model(l).st().idle_bits(CYCLE_BITS / 4);
        if send {
            model(l).st().bus_sends(64);
        }
        l.service();
    }
    l.cycle();
}

/// Bus-offs with a re-join after each, until the back-off is `level` (2^(level-1) cycles).
fn back_off_to(l: &mut ModelLink, level: u8) {
    while l.health().backoff < level {
        model(l).st().bus_off();
        l.service();
        while l.backoff_remaining() > 0 {
            rest_of_cycle(l, true);
        }
        rest_of_cycle(l, true);
    }
    assert_eq!(l.backoff_remaining(), 0);
}

#[test]
fn an_estop_during_the_back_off_is_heard_in_its_cycle_and_owed_acks_leave_in_order() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link_over(brought_up());
    back_off_to(&mut l, 4);
    // Three commands answered; the bus takes none of the ACKs before the bus-off.
    for seq in 1..=3 {
        model(&l).st().arrive(heartbeat(seq));
    }
    node.poll(0, &mut l);
    l.service();
    model(&l).st().bus_off();
    l.service();
    assert!(l.listening());
    let back_off = l.backoff_remaining();
    assert_eq!(back_off, 16, "the fifth bus-off: 16 cycles");
    let sent_before = model(&l).st().wire.len();
    // The back-off: commands and an ESTOP arrive in its fourth cycle (long after the 1.42 ms
    // recovery); the ESTOP is carried out in the poll of the cycle it arrived in.
    let mut cycle = 0;
    let mut stopped_in = None;
    rest_of_cycle(&mut l, true);
    while l.backoff_remaining() > 0 {
        cycle += 1;
        if cycle == 3 {
            assert!(model(&l).st().arrive(heartbeat(4)).stored());
        }
        if cycle == 4 {
            let v = model(&l).st().arrive(estop(9));
            assert!(matches!(v, Verdict::Fifo { n: 1, .. }), "{v:?}");
            assert!(model(&l).st().arrive(heartbeat(5)).stored());
        }
        node.poll(5 * cycle, &mut l);
        if node.state() == NodeState::EmergencyStopped && stopped_in.is_none() {
            stopped_in = Some(cycle);
        }
        assert_eq!(l.health().state, board_core::BusState::BusOff);
        rest_of_cycle(&mut l, true);
    }
    assert_eq!(stopped_in, Some(4));
    assert_eq!(
        model(&l).st().wire.len(),
        sent_before,
        "nothing transmitted during the back-off"
    );
    // Back on the bus: the owed ACKs first, in order, then those of the back-off.
    for k in 0..3 {
        node.poll(5 * (cycle + 1 + k), &mut l);
        rest_of_cycle(&mut l, true);
    }
    assert!(!l.listening());
    let control = ids::CONTROL as u8;
    let estop_byte = ids::ESTOP as u8;
    assert_eq!(
        acks(&l),
        [
            (control, 1),
            (control, 2),
            (control, 3),
            (control, 4),
            (estop_byte, 9),
            (control, 5)
        ]
    );
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn an_estop_waiting_in_fifo1_at_the_bus_off_is_not_lost() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link_over(brought_up());
    model(&l).st().arrive(estop(1));
    for seq in 1..=40 {
        model(&l).st().arrive(heartbeat(seq));
    }
    // Bus-off before the poll: configuration mode resets RXF1S and RXF0S, after the drain.
    model(&l).st().bus_off();
    l.service();
    assert!(l.listening());
    assert_eq!(model(&l).st().fill(1), 0);
    assert_eq!(model(&l).st().fill(0), 0);
    node.poll(0, &mut l);
    assert_eq!(node.state(), NodeState::EmergencyStopped);
    // 40 commands waited in RX FIFO0; the software queue holds 32: the rest counted lost and
    // reported to the node once.
    assert_eq!(l.health().rx_lost, 1);
    assert_eq!(node.counters().bus_errors, 1);
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn a_core_refusing_configuration_mode_is_held_in_init_with_its_acks_kept() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let m = brought_up();
    // CCE never takes (stuck at 0): the adapter cannot enter bus monitoring.
    m.st().stuck_bits.push((regmodel::CCCR, regmodel::CCE));
    let mut l = link_over(m);
    for seq in 1..=2 {
        model(&l).st().arrive(heartbeat(seq));
    }
    node.poll(0, &mut l);
    l.service();
    model(&l).st().bus_off();
    l.service();
    assert!(!l.listening());
    assert!(
        model(&l).st().in_init(),
        "held in INIT: deaf for the back-off"
    );
    assert_eq!(model(&l).st().arrive(estop(3)), Verdict::NotOnBus);
    assert_eq!(model(&l).st().pending().count_ones(), 2, "the ACKs stay");
    rest_of_cycle(&mut l, true);
    for k in 1..4 {
        node.poll(5 * k, &mut l);
        rest_of_cycle(&mut l, true);
    }
    let control = ids::CONTROL as u8;
    assert_eq!(acks(&l), [(control, 1), (control, 2)]);
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn owed_acks_that_do_not_fit_the_software_queue_keep_the_core_in_init() {
    use embedded_can::nb::Can;
    use embedded_can::{Frame, StandardId};
    let mut l = link_over(brought_up());
    let ack = |seq: u8| {
        board_core::ClassicFrame::new(StandardId::new(ids::ACK).unwrap(), &[0x20, seq]).unwrap()
    };
    // 16 ACKs in the TX FIFO, 20 more waiting in software (the bus takes none).
    for seq in 0..36 {
        l.transmit(&ack(seq)).unwrap();
    }
    assert_eq!(l.tx_waiting(), 20);
    model(&l).st().bus_off();
    l.service();
    // 16 owed, room for 12: no configuration mode, nothing reset, nothing dropped.
    assert!(!l.listening());
    assert!(model(&l).st().in_init());
    assert_eq!(model(&l).st().pending().count_ones(), 16);
    assert_eq!(l.tx_waiting(), 20);
    for _ in 0..4 {
        rest_of_cycle(&mut l, true);
    }
    let seqs: Vec<u8> = acks(&l).iter().map(|a| a.1).collect();
    assert_eq!(seqs, (0..36).collect::<Vec<u8>>());
    assert_eq!(model(&l).violations(), []);
}

/// Leaving bus monitoring clears `MON` directly (no `INIT`, no configuration mode: a frame
/// being received is not cut off and the FIFOs keep what they hold). A `MON` that does not
/// clear keeps the link reported bus-off, cycle after cycle, with nothing transmitted: never
/// mute while reported on the bus; once it clears, the owed `ACK`s leave.
#[test]
fn a_monitoring_mode_that_does_not_clear_keeps_the_link_reported_off_the_bus() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link_over(brought_up());
    model(&l).st().arrive(heartbeat(1));
    node.poll(0, &mut l);
    l.service();
    model(&l).st().bus_off();
    l.service();
    assert!(l.listening());
    // MON stuck at 1 from here on.
    model(&l)
        .st()
        .stuck_bits
        .push((regmodel::CCCR, regmodel::CCCR_MON));
    let sent_before = model(&l).st().wire.len();
    for k in 1..=10 {
        node.poll(5 * k, &mut l);
        rest_of_cycle(&mut l, true);
        assert_eq!(l.health().state, board_core::BusState::BusOff, "cycle {k}");
        assert!(l.listening(), "cycle {k}");
    }
    assert_eq!(model(&l).st().wire.len(), sent_before, "nothing sent");
    // A frame heard while the adapter retries is still delivered (the FIFOs were never reset).
    assert!(model(&l).st().arrive(heartbeat(2)).stored());
    model(&l).st().stuck_bits.clear();
    for k in 11..=14 {
        node.poll(5 * k, &mut l);
        rest_of_cycle(&mut l, true);
    }
    assert!(!l.listening());
    assert_ne!(l.health().state, board_core::BusState::BusOff);
    let control = ids::CONTROL as u8;
    assert_eq!(acks(&l), [(control, 1), (control, 2)]);
    assert_eq!(model(&l).violations(), []);
}
