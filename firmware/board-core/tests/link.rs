//! The board's CAN link adapter on a model of the FDCAN (`mock`): queues, replacement of stale
//! frames, bus-off recovery, error counters, a burst of commands during a node's poll and
//! `ESTOP` overtaking a full RX FIFO0, with planner-core's real node on top.

mod mock;

use board_core::link::{psr, SOFT_TX, TX_FIFO};
use board_core::{BusState, Link, RxLost};
use embedded_can::nb::Can;
use embedded_can::Frame;
use mock::{frame, MockFdcan};
use planner_core::node::{Node, NodeConfig, NodeState};
use planner_core::wire::{ids, Ack, Command, ControlOp, RawFrame};

/// A heartbeat of the start-up's session (epoch 0: the node has no entropy); before the
/// handshake the node answers it `NoSession`, which is an answer all the same.
fn heartbeat(seq: u8) -> [u32; 4] {
    let raw = Command::Control {
        session: 0,
        seq: u32::from(seq),
        op: ControlOp::Heartbeat,
    }
    .encode();
    frame(raw.id, raw.bytes()).to_element()
}

/// The handshake: the `Reset` that opens the start-up's session.
fn open() -> [u32; 4] {
    let raw = Command::Control {
        session: 0,
        seq: 1000,
        op: ControlOp::Reset,
    }
    .encode();
    frame(raw.id, raw.bytes()).to_element()
}

fn acks(wire: &[board_core::ClassicFrame]) -> Vec<u8> {
    wire.iter()
        .filter_map(RawFrame::from_frame)
        .filter_map(|r| Ack::decode(&r))
        .map(|a| a.seq)
        .collect()
}

/// Runs `cycles` node cycles: poll, then the wait loop's `service` and a bus that sends
/// everything pending.
fn run(node: &mut Node<16>, link: &mut Link<MockFdcan>, first_ms: u32, cycles: u32) {
    for k in 0..cycles {
        node.poll(first_ms + 5 * k, link);
        for _ in 0..4 {
            link.peripheral_mut().bus_sends(64);
            link.service();
        }
    }
}

#[test]
fn a_burst_of_16_commands_during_a_poll_is_not_lost() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut link = Link::new(MockFdcan::new(board_core::link::RX_ELEMENTS));
    link.peripheral_mut().burst = (1..=16).map(heartbeat).collect();
    run(&mut node, &mut link, 0, 6);
    assert_eq!(acks(&link.peripheral().wire), (1..=16).collect::<Vec<u8>>());
    assert_eq!(link.health().rx_lost, 0);
    assert_eq!(node.counters().bus_errors, 0);
}

#[test]
fn the_old_three_element_fifo_loses_that_burst_and_says_so() {
    // The layout of the `fdcan` crate (3 elements): the check above is not vacuous.
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut link = Link::new(MockFdcan::new(3));
    link.peripheral_mut().burst = (1..=16).map(heartbeat).collect();
    run(&mut node, &mut link, 0, 6);
    let got = acks(&link.peripheral().wire);
    assert!(got.len() < 16, "{got:?}");
    assert_eq!(link.health().rx_lost, 1);
    // Reported once to the node as a receive error (DIAG bus errors).
    assert_eq!(node.counters().bus_errors, 1);
}

#[test]
fn a_lost_frame_is_reported_once_then_frames_flow() {
    let mut link = Link::new(MockFdcan::new(2));
    for s in 1..=3 {
        link.peripheral_mut().arrive(heartbeat(s));
    }
    assert_eq!(link.receive(), Err(nb::Error::Other(RxLost)));
    assert!(link.receive().is_ok());
    assert!(link.receive().is_ok());
    assert_eq!(link.receive(), Err(nb::Error::WouldBlock));
    assert_eq!(link.health().rx_lost, 1);
}

#[test]
fn a_stream_frame_replaces_the_waiting_one_of_its_id() {
    let mut link = Link::new(MockFdcan::new(64));
    // Bus stalled (nothing sent) for 40 cycles of the stream.
    for v in 0..40u8 {
        for id in [ids::COG, ids::ZMP, ids::FOOT_LEFT] {
            link.transmit(&frame(id, &[v; 8])).unwrap();
        }
    }
    assert!(link.peripheral().pending_count() <= 3);
    link.peripheral_mut().bus_sends(64);
    let wire = &link.peripheral().wire;
    assert_eq!(wire.len(), 3, "{wire:?}");
    assert!(wire.iter().all(|f| f.data() == [39; 8]), "{wire:?}");
    assert_eq!(link.health().replaced, 3 * 39);
}

#[test]
fn a_deferred_cancellation_keeps_its_buffer_and_the_newest_frame_is_sent() {
    let mut link = Link::new(MockFdcan::new(64));
    link.peripheral_mut().defer_cancel = true;
    link.transmit(&frame(ids::COG, &[1])).unwrap(); // buffer 0
    link.transmit(&frame(ids::COG, &[2])).unwrap(); // cancels 0, buffer 1
    link.transmit(&frame(ids::COG, &[3])).unwrap(); // cancels 1, buffer 2
    assert_eq!(link.peripheral().cancel_requested, 0b11);
    assert_eq!(link.tx_waiting(), 0);
    // Buffers being cancelled are not written again (the model asserts it) until done.
    link.transmit(&frame(ids::ZMP, &[4])).unwrap();
    assert!(link.peripheral().slots[3].is_some());
    link.peripheral_mut().complete_cancels();
    link.service();
    link.peripheral_mut().bus_sends(64);
    let p = link.peripheral();
    assert_eq!(p.cancelled, [frame(ids::COG, &[1]), frame(ids::COG, &[2])]);
    assert_eq!(p.wire, [frame(ids::COG, &[3]), frame(ids::ZMP, &[4])]);
    assert_eq!(link.health().replaced, 2);
}

#[test]
fn acks_are_never_replaced_and_block_only_when_everything_is_full() {
    let mut link = Link::new(MockFdcan::new(64));
    for seq in 0..(TX_FIFO + SOFT_TX) {
        let f = frame(ids::ACK, &[0x20, seq as u8]);
        assert_eq!(link.transmit(&f), Ok(None), "ACK {seq}");
    }
    assert_eq!(
        link.transmit(&frame(ids::ACK, &[0x20, 0xFF])),
        Err(nb::Error::WouldBlock)
    );
    link.peripheral_mut().bus_sends(TX_FIFO);
    link.service();
    link.peripheral_mut().bus_sends(TX_FIFO);
    link.service();
    link.peripheral_mut().bus_sends(TX_FIFO);
    let seqs: Vec<u8> = link.peripheral().wire.iter().map(|f| f.data()[1]).collect();
    assert_eq!(seqs, (0..(TX_FIFO + SOFT_TX) as u8).collect::<Vec<_>>());
    assert_eq!(link.health().replaced, 0);
}

#[test]
fn bus_off_is_counted_and_recovered_and_old_frames_are_dropped() {
    let mut link = Link::new(MockFdcan::new(64));
    link.transmit(&frame(ids::ACK, &[1])).unwrap();
    link.transmit(&frame(ids::COG, &[1])).unwrap();
    // The core goes bus-off: it sets INIT by itself.
    let hw = link.peripheral_mut();
    hw.psr = psr::BO | psr::EP | psr::EW;
    hw.ecr = 0xFF;
    hw.init = true;
    link.service();
    let h = link.health();
    assert_eq!((h.state, h.bus_offs, h.tec), (BusState::BusOff, 1, 255));
    // Off the bus for the back-off (1 cycle the first time): INIT not cleared yet.
    assert_eq!(h.backoff, 1);
    assert_eq!(link.backoff_remaining(), 1);
    assert_eq!(link.peripheral().leave_init_calls, 0);
    // The stream frame cancelled; the ACK, owed, stays in the TX FIFO.
    assert_eq!(link.peripheral().cancelled, [frame(ids::COG, &[1])]);
    assert_eq!(link.peripheral().fifo.len(), 1);
    assert_eq!(link.peripheral().pending_count(), 1);
    // While off: frames wait in software (and stream frames still replace); servicing during
    // the back-off counts nothing again.
    link.transmit(&frame(ids::COG, &[2])).unwrap();
    link.transmit(&frame(ids::COG, &[3])).unwrap();
    link.service();
    assert_eq!(link.health().bus_offs, 1);
    // The cycle ends the back-off: INIT cleared, recovery begins.
    link.cycle();
    assert_eq!(link.peripheral().leave_init_calls, 1);
    assert!(!link.peripheral().init);
    link.service(); // still bus-off (recovery sequence running): not counted again
    assert_eq!(link.health().bus_offs, 1);
    assert_eq!(link.peripheral().pending_count(), 1);
    // Recovered: error-active, counters reset by the core.
    let hw = link.peripheral_mut();
    hw.psr = 0;
    hw.ecr = 0;
    link.service();
    link.peripheral_mut().bus_sends(64);
    assert_eq!(link.health().state, BusState::Active);
    assert_eq!(
        link.peripheral().wire,
        [frame(ids::ACK, &[1]), frame(ids::COG, &[3])]
    );
    // A second bus-off is a second count, with twice the back-off.
    let hw = link.peripheral_mut();
    hw.psr = psr::BO;
    hw.init = true;
    link.service();
    assert_eq!(link.health().bus_offs, 2);
    assert_eq!(link.backoff_remaining(), 2);
    link.cycle();
    link.service();
    assert_eq!(link.peripheral().leave_init_calls, 1, "still backing off");
    link.cycle();
    assert_eq!(link.peripheral().leave_init_calls, 2);
    // A third one before the adapter saw the recovery end (INIT set again, BO never cleared
    // in between): counted and backed off too.
    link.service();
    assert_eq!(link.health().bus_offs, 2, "recovering: not a new event");
    link.peripheral_mut().init = true;
    link.service();
    assert_eq!(link.health().bus_offs, 3);
    assert_eq!(link.backoff_remaining(), 4);
}

#[test]
fn error_counters_and_passive_episodes() {
    let mut link = Link::new(MockFdcan::new(64));
    let hw = link.peripheral_mut();
    hw.ecr = 100 | (12 << 8);
    hw.psr = psr::EW;
    link.service();
    let h = link.health();
    assert_eq!(
        (h.tec, h.rec, h.rx_passive, h.state),
        (100, 12, false, BusState::Warning)
    );
    let hw = link.peripheral_mut();
    hw.ecr = 130 | (127 << 8) | (1 << 15);
    hw.psr = psr::EP | psr::EW;
    for _ in 0..3 {
        link.service();
    }
    let h = link.health();
    assert_eq!((h.tec, h.rec, h.rx_passive), (130, 127, true));
    assert_eq!((h.state, h.passive_episodes), (BusState::Passive, 1));
    link.peripheral_mut().psr = 0;
    link.service();
    link.peripheral_mut().psr = psr::EP;
    link.service();
    assert_eq!(link.health().passive_episodes, 2);
    assert_eq!(link.health().bus_offs, 0);
}

#[test]
fn foreign_elements_are_dropped_and_counted() {
    let mut link = Link::new(MockFdcan::new(64));
    let mut ext = heartbeat(1);
    ext[0] |= 1 << 30;
    link.peripheral_mut().arrive(ext);
    link.peripheral_mut().arrive(heartbeat(2));
    let got = link.receive().unwrap();
    assert_eq!(got.raw_id(), ids::CONTROL);
    assert_eq!(got.data()[2], 2); // (the sequence number's low byte)
    assert_eq!(link.health().rx_foreign, 1);
    assert_eq!(link.receive(), Err(nb::Error::WouldBlock));
}

#[test]
fn a_node_keeps_publishing_through_a_bus_off() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut link = Link::new(MockFdcan::new(64));
    link.peripheral_mut().arrive(open());
    run(&mut node, &mut link, 0, 20);
    let before = link.peripheral().wire.len();
    assert!(before >= 20 * 5, "{before}");
    let hw = link.peripheral_mut();
    hw.psr = psr::BO;
    hw.init = true;
    // 10 cycles off the bus (the back-off, then a recovery that lasts): nothing sent, the
    // software queue stays bounded by replacement.
    for k in 20..30 {
        link.cycle();
        node.poll(5 * k, &mut link);
        link.service();
        assert!(link.tx_waiting() <= 8, "cycle {k}: {}", link.tx_waiting());
    }
    assert_eq!(link.peripheral().wire.len(), before);
    link.peripheral_mut().psr = 0;
    run(&mut node, &mut link, 150, 1);
    let after: Vec<u16> = link.peripheral().wire[before..]
        .iter()
        .map(|f| f.raw_id())
        .collect();
    // One frame per stream id (the newest), not ten cycles' worth.
    for id in [
        ids::COG,
        ids::ZMP,
        ids::COG_VEL,
        ids::FOOT_LEFT,
        ids::FOOT_RIGHT,
    ] {
        assert_eq!(
            after.iter().filter(|&&i| i == id).count(),
            1,
            "{id:#x}: {after:x?}"
        );
    }
    assert_eq!(link.health().bus_offs, 1);
}

#[test]
fn health_goes_into_link_as_published() {
    let mut link = Link::new(MockFdcan::new(64));
    let hw = link.peripheral_mut();
    hw.ecr = 140 | (3 << 8);
    hw.psr = psr::EP;
    link.service();
    let w = link
        .health()
        .to_wire(board_core::ResetReason::IndependentWatchdog, 300);
    let back = planner_core::wire::LinkHealth::decode(&w.encode()).unwrap();
    assert_eq!((back.tec, back.rec, back.bus_state), (140, 3, 2));
    assert_eq!(
        (back.reset, back.missed_slots, back.passive_episodes),
        (5, 255, 1)
    );
}

fn estop() -> [u32; 4] {
    let raw = Command::EmergencyStop { seq: 9 }.encode();
    frame(raw.id, raw.bytes()).to_element()
}

/// 48 commands (three cycles of the node's receive budget) wait, 32 of them already in the
/// software queue, when an `ESTOP` arrives; the cycles until the node is emergency-stopped.
fn cycles_to_estop(estop_fifo1: bool, max_frames: usize) -> u32 {
    let mut cfg = NodeConfig::hrp2();
    cfg.max_frames = max_frames;
    cfg.max_rx = cfg.max_rx.min(max_frames);
    let mut node = Node::<16>::new(cfg).unwrap();
    let mut mock = MockFdcan::new(board_core::link::RX_ELEMENTS);
    mock.estop_fifo1 = estop_fifo1;
    let mut link = Link::new(mock);
    for seq in 1..=48 {
        link.peripheral_mut().arrive(heartbeat(seq));
    }
    link.service();
    link.peripheral_mut().arrive(estop());
    for cycle in 1..=10 {
        node.poll(5 * cycle, &mut link);
        if node.state() == NodeState::EmergencyStopped {
            return cycle;
        }
    }
    panic!("never stopped");
}

#[test]
fn an_estop_in_fifo1_overtakes_a_full_fifo0() {
    let max_frames = NodeConfig::hrp2().max_frames;
    assert_eq!(cycles_to_estop(true, max_frames), 1);
    // The node takes everything waiting (up to `max_frames` a cycle): with every command in
    // FIFO0, the ESTOP behind 48 commands is carried out in its cycle all the same.
    assert_eq!(cycles_to_estop(false, max_frames), 1);
    // A node that took 16 frames a cycle needs FIFO1's routing.
    assert_eq!(cycles_to_estop(true, 16), 1);
}

#[test]
fn an_estop_behind_commands_in_fifo0_waits_cycles() {
    // Every command into FIFO0 and a node that takes 16 frames a cycle: the ESTOP waits
    // behind 48 commands; the checks above are not vacuous.
    assert_eq!(cycles_to_estop(false, 16), 4);
}

#[test]
fn fifo1_comes_before_the_software_queue_and_a_loss_report() {
    let mut mock = MockFdcan::new(board_core::link::RX_ELEMENTS);
    mock.estop_fifo1 = true;
    let mut link = Link::new(mock);
    link.peripheral_mut().arrive(heartbeat(1));
    link.service(); // the heartbeat into the software queue; FIFO1 is left to `receive`
    link.peripheral_mut().arrive(estop());
    link.peripheral_mut().rx_lost_flag = true;
    assert_eq!(link.receive().unwrap().raw_id(), ids::ESTOP);
    assert!(matches!(link.receive(), Err(nb::Error::Other(RxLost))));
    assert_eq!(link.receive().unwrap().raw_id(), ids::CONTROL);
    assert!(matches!(link.receive(), Err(nb::Error::WouldBlock)));
}

#[test]
fn a_foreign_element_in_fifo1_is_dropped_without_reordering() {
    // An ESTOP element that is no classic frame (an FD frame), then a real one; FIFO0 and
    // the software queue hold commands.
    let mut mock = MockFdcan::new(board_core::link::RX_ELEMENTS);
    mock.estop_fifo1 = true;
    let mut link = Link::new(mock);
    link.peripheral_mut().arrive(heartbeat(1));
    link.service(); // heartbeat 1 into the software queue
    link.peripheral_mut().arrive(heartbeat(2)); // FIFO0
    let mut bad = estop();
    bad[1] |= 1 << 21;
    link.peripheral_mut().arrive(bad);
    link.peripheral_mut().arrive(estop());
    let seqs: Vec<(u16, u8)> = std::iter::from_fn(|| link.receive().ok())
        .map(|f| (f.raw_id(), f.data()[0]))
        .collect();
    // The bad element dropped (counted); the call it was read in goes on in order (the
    // software queue first); the real ESTOP comes at the next call, before FIFO0.
    let hb = |seq: u8| {
        let raw = Command::Control {
            session: 0,
            seq: u32::from(seq),
            op: ControlOp::Heartbeat,
        }
        .encode();
        (raw.id, raw.bytes()[0])
    };
    assert_eq!(seqs, [hb(1), (ids::ESTOP, 9), hb(2)]);
    assert_eq!(link.health().rx_foreign, 1);
}
