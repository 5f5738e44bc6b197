//! The board's FDCAN bring-up and run-time path against a register-level model of FDCAN1
//! that enforces RM0433's rules (`regmodel`): configuration only in configuration mode, the
//! read-back, the acceptance filters on frames of a modelled bus, `ESTOP` through RX FIFO1
//! before everything else, and the sequence the `fdcan` crate ran before (caught letting
//! every standard frame in).

mod common;
mod regmodel;

use common::*;

use board_core::fdcan::{self, layout, BringUpError, FdcanRegs, Reg, RegFdcan};
use board_core::link::{psr, RX_ELEMENTS, TX_FIFO, TX_SLOTS};
use board_core::{BusState, Fdcan, Link};
use embedded_can::Frame;
use planner_core::node::{Node, NodeConfig, NodeState};
use planner_core::wire::{ids, Ack, Command, RawFrame};
use regmodel::{BusFrame, FdcanModel, Verdict, Violation};

/// Frames that are not the node's commands, of every kind: a foreign data frame, remote
/// frames (foreign, and on a command's identifier), extended frames (one whose low 11 bits
/// are a command's), the extremes of the identifier range.
fn foreign_frames() -> Vec<BusFrame> {
    vec![
        BusFrame::std(0x123, &[0]),
        BusFrame::std(0x000, &[1, 2]),
        BusFrame::std(0x7FF, &[]),
        BusFrame::std(ids::ACK, &[0; 8]),
        BusFrame::std(ids::COG, &[0; 8]),
        BusFrame::std(ids::ESTOP + 1, &[0]),
        BusFrame::std_remote(0x123, 0),
        BusFrame::std_remote(ids::ESTOP, 1),
        BusFrame::std_remote(ids::CONTROL, 8),
        BusFrame::ext(0x123, &[0]),
        BusFrame::ext(u32::from(ids::CONTROL), &[0; 8]),
        BusFrame::ext(0x1FFF_FFFF, &[]),
    ]
}

/// The foreign frames (of [`foreign_frames`]) the model stores into a FIFO.
fn foreign_accepted(m: &FdcanModel) -> Vec<(BusFrame, Verdict)> {
    foreign_frames()
        .into_iter()
        .map(|f| (f, m.st().arrive(f)))
        .filter(|(_, v)| v.stored())
        .collect()
}

/// A `STEP_APPEND` / `STEP_MODIFY` identifier with 8 bytes (decoded or not, the filters
/// only look at the identifier).
fn step(id: u16) -> BusFrame {
    BusFrame::std(id, &[0; 8])
}

// --- the bring-up ---

#[test]
fn bring_up_follows_the_rules_and_reads_back() {
    assert!(TIMING.is_valid());
    assert_eq!(TIMING.bit_rate(80_000_000), 1_000_000);
    assert_eq!(TIMING.sample_point_permille(), 875);
    assert!(
        !fdcan::BitTiming { sjw: 6, ..TIMING }.is_valid(),
        "SJW above seg2"
    );
    let m = brought_up();
    let s = m.st();
    assert_eq!(
        s.peek(regmodel::GFC),
        0x3F,
        "reject non-matching and remote"
    );
    assert_eq!(s.peek(regmodel::NBTP), 0x0801_2104, "1 Mbit/s at 80 MHz");
    // One standard filter element (one word) per identifier the node receives.
    let n = ids::COMMANDS.len() as u32;
    assert_eq!(s.peek(regmodel::SIDFC), n << 16, "{n} elements at word 0");
    assert_eq!(s.peek(regmodel::XIDFC), n << 2, "no extended filter");
    assert_eq!(s.peek(regmodel::RXF0C), (64 << 16) | (n << 2));
    // FIFO0: 64 elements of 4 words; FIFO1: 16, then 16 dedicated buffers and a TX FIFO
    // (TFQM = 0) of 16.
    assert_eq!(s.peek(regmodel::RXF1C), (16 << 16) | ((n + 256) << 2));
    assert_eq!(
        s.peek(regmodel::TXBC),
        (16 << 24) | (16 << 16) | ((n + 320) << 2)
    );
    assert_eq!(s.peek(regmodel::CCCR) & regmodel::CCCR_PROTECTED, 1 << 12);
    // RM0433's standard filter element: SFT 01 (dual id), SFEC 010 (FIFO1) for ESTOP, 001
    // (FIFO0) for the others, SFID1 = SFID2 = the identifier.
    assert_eq!(s.peek_ram(0), 0x5010_0010);
    assert_eq!(s.peek_ram(1), 0x4820_0020);
    for (i, &id) in (0u32..).zip(ids::COMMANDS.iter()) {
        let sfec: u32 = if id == ids::ESTOP { 0b010 } else { 0b001 };
        let want = (0b01 << 30) | (sfec << 27) | (u32::from(id) << 16) | u32::from(id);
        assert_eq!(s.peek_ram(i), want, "filter element {i}: {id:#05x}");
    }
    drop(s);
    // The read-back passes on the bus too.
    assert_eq!(fdcan::verify(&m, &TIMING), Ok(()));
}

#[test]
fn foreign_remote_and_extended_frames_are_rejected() {
    let m = brought_up();
    assert_eq!(foreign_accepted(&m), []);
    let s = m.st();
    assert_eq!((s.fill(0), s.fill(1)), (0, 0));
    // Each for the reason RM0433 gives: remote frames by RRFS, the others by ANFS / ANFE.
    for (f, v) in &s.arrivals {
        let want = if f.remote {
            Verdict::RemoteRejected
        } else {
            Verdict::NonMatchingRejected
        };
        assert_eq!(*v, want, "{f:?}");
    }
}

#[test]
fn estop_lands_in_fifo1_and_the_commands_in_fifo0() {
    let m = brought_up();
    let estop = command(Command::EmergencyStop { seq: 1 });
    assert_eq!(
        m.st().arrive(estop),
        Verdict::Fifo {
            n: 1,
            filter: Some(0)
        }
    );
    for f in [heartbeat(1), step(ids::STEP_APPEND), step(ids::STEP_MODIFY)] {
        let i = ids::COMMANDS
            .iter()
            .position(|&id| u32::from(id) == f.id)
            .unwrap();
        assert_eq!(
            m.st().arrive(f),
            Verdict::Fifo {
                n: 0,
                filter: Some(i as u32)
            }
        );
    }
    // The RX element as RM0433 lays it out, where board-core's layout says.
    let s = m.st();
    assert_eq!(s.peek_ram(layout::RX_FIFO1), u32::from(ids::ESTOP) << 18);
    assert_eq!(s.peek_ram(layout::RX_FIFO1 + 1), 1 << 16); // DLC 1, FIDX 0
    assert_eq!(s.peek_ram(layout::RX_FIFO0), u32::from(ids::CONTROL) << 18);
    assert_eq!((s.fill(0), s.fill(1)), (3, 1));
}

#[test]
fn a_configuration_write_outside_init_is_caught() {
    let mut m = brought_up();
    m.write(Reg::Gfc, 0);
    assert_eq!(
        m.violations(),
        [Violation::Protected {
            offset: 0x080,
            value: 0
        }]
    );
    // Ignored, as the hardware ignores it.
    assert_eq!(m.st().peek(regmodel::GFC), 0x3F);
    // In INIT but without CCE: still refused; CCE before INIT reads set: refused.
    let mut m = FdcanModel::after_reset();
    m.write(Reg::Nbtp, 0x0801_2104);
    m.write(Reg::Cccr, 0x3); // INIT already set at reset: CCE taken
    m.write(Reg::Cccr, 0x0); // leave: CCE cleared at once
    m.write(Reg::Txbc, 0);
    m.st().settle();
    m.write(Reg::Cccr, 0x3); // INIT requested, not yet read set: CCE refused
    assert_eq!(
        m.violations(),
        [
            Violation::Protected {
                offset: 0x01C,
                value: 0x0801_2104
            },
            Violation::Protected {
                offset: 0x0C0,
                value: 0
            },
            Violation::CceWithoutInit,
        ]
    );
    // The mode bits of CCCR likewise.
    let mut m = brought_up();
    m.write(Reg::Cccr, 1 << 8);
    assert!(matches!(
        m.violations()[..],
        [Violation::ProtectedCccrBits { .. }]
    ));
}

#[test]
fn bring_up_refuses_to_join_when_a_register_reads_back_otherwise() {
    // GFC's RRFS bit does not take a write (a stand-in for any register that reads back
    // otherwise): the bring-up names it and stays off the bus.
    let mut m = FdcanModel::after_reset();
    m.st().stuck_bits.push((regmodel::GFC, 1 << 1));
    assert_eq!(
        fdcan::bring_up(&mut m, &TIMING),
        Err(BringUpError::Register(Reg::Gfc))
    );
    m.st().settle();
    assert!(m.st().in_init(), "not on the bus");
    assert_eq!(m.st().joins, 0, "and never was");
    assert_eq!(
        m.st().arrive(BusFrame::std(ids::CONTROL, &[0])),
        Verdict::NotOnBus
    );
    assert_eq!(m.violations(), []);
    // NBTP, a FIFO's configuration, TXBC (NDTB, the TX FIFO's size), SIDFC: each named (a bit
    // the value has, stuck at 0).
    for (off, bit, reg) in [
        (regmodel::NBTP, 16, Reg::Nbtp),
        (regmodel::RXF1C, 20, Reg::Rxf1c),
        (regmodel::TXBC, 20, Reg::Txbc),
        (regmodel::TXBC, 28, Reg::Txbc),
        (regmodel::SIDFC, 18, Reg::Sidfc),
    ] {
        let mut m = FdcanModel::after_reset();
        m.st().stuck_bits.push((off, 1 << bit));
        assert_eq!(
            fdcan::bring_up(&mut m, &TIMING),
            Err(BringUpError::Register(reg))
        );
        m.st().settle();
        assert!(m.st().in_init());
        assert_eq!(m.st().joins, 0);
    }
    // TXBC in queue mode (TFQM reads 1): the ACKs would leave by identifier, not in order.
    let mut m = FdcanModel::after_reset();
    m.st().forced_bits.push((regmodel::TXBC, 1 << 30));
    assert_eq!(
        fdcan::bring_up(&mut m, &TIMING),
        Err(BringUpError::Register(Reg::Txbc))
    );
    m.st().settle();
    assert_eq!(m.st().joins, 0);
    // A filter element.
    let mut m = FdcanModel::after_reset();
    m.st().stuck_word = Some(layout::STD_FILTERS + 2);
    assert_eq!(
        fdcan::bring_up(&mut m, &TIMING),
        Err(BringUpError::StdFilter(2))
    );
    m.st().settle();
    assert!(m.st().in_init());
    assert_eq!(m.st().joins, 0);
}

#[test]
fn bring_up_is_bounded_when_init_never_changes() {
    let mut m = FdcanModel::after_reset();
    // After a reset INIT is set already; take the core out of it first.
    m.st().settle();
    m.write(Reg::Cccr, 0);
    m.st().settle();
    m.st().init_never_set = true;
    assert_eq!(
        fdcan::bring_up(&mut m, &TIMING),
        Err(BringUpError::InitTimeout)
    );
    let mut m = FdcanModel::after_reset();
    m.st().init_never_clear = true;
    assert_eq!(
        fdcan::bring_up(&mut m, &TIMING),
        Err(BringUpError::JoinTimeout)
    );
    assert_eq!(m.violations(), []);
}

#[test]
fn bring_up_after_a_run_starts_from_any_state() {
    // A second bring-up over a running core (a warm start without a peripheral reset).
    let mut m = brought_up();
    m.st().arrive(heartbeat(1));
    assert_eq!(fdcan::bring_up(&mut m, &TIMING), Ok(()));
    assert_eq!(m.violations(), []);
}

// --- today's sequence (the `fdcan` crate's), replayed ---

/// `reg.modify(|r, w| ..)` as the PAC does it: a read, then a write.
fn modify(r: &mut impl FdcanRegs, reg: Reg, f: impl FnOnce(u32) -> u32) {
    let v = r.read(reg);
    r.write(reg, f(v));
}

fn set(r: &mut impl FdcanRegs, reg: Reg, mask: u32, value: u32) {
    modify(r, reg, |v| (v & !mask) | (value & mask));
}

/// The register sequence of the board's start-up before this change, transcribed from the
/// sources: stm32h7xx-hal 0.16's `FDCAN1.fdcan()` (`Can::fdcan1`: `FdCan::new(..)
/// .into_config_mode()`, then `message_ram_layout!(can, 0)`), the board's calls on the
/// `fdcan` 0.2.1 driver in configuration mode (`set_protocol_exception_handling(false)`,
/// `set_frame_transmit(ClassicCanOnly)`, `set_nominal_bit_timing`, `set_standard_filters`,
/// `set_extended_filter(_0, reject_all)`, `set_global_filter(reject_all)`), the board's
/// `fdcan1::layout()`, and `into_normal()`: `set_normal_operations` and `leave_init_mode`,
/// whose `apply_config(self.control.config)` ends with `set_global_filter(config
/// .global_filter)` — the default, "accept non-matching into FIFO0", since
/// `set_global_filter` never stores what it writes — before CCE and INIT are cleared.
fn fdcan_crate_sequence(r: &mut impl FdcanRegs) {
    const INIT: u32 = 1;
    const CCE: u32 = 2;
    // into_config_mode: set_power_down_mode(false) (CSR = 0, wait for CSA = 0) ...
    set(r, Reg::Cccr, 1 << 4, 0);
    while r.read(Reg::Cccr) & (1 << 3) != 0 {}
    // ... enter_init_mode ...
    set(r, Reg::Cccr, INIT, INIT);
    while r.read(Reg::Cccr) & INIT == 0 {}
    set(r, Reg::Cccr, CCE, CCE);
    // ... reset_msg_ram (its 212 words: 28 + 2 x 8 filters, 2 x 3 RX, 3 TX events, 3 TX) ...
    for w in 0..212 {
        r.ram_write(w, 0);
    }
    assert_eq!(r.read(Reg::Crel) >> 28, 3);
    assert_eq!(r.read(Reg::Endn), 0x8765_4321);
    // ... TX buffers in queue mode, 28 standard and 8 extended filter elements, disabled.
    r.write(Reg::Txbc, 1 << 30);
    set(r, Reg::Sidfc, 0xFF << 16, 28 << 16);
    set(r, Reg::Xidfc, 0x7F << 16, 8 << 16);
    for i in 0..28 {
        r.ram_write(i, 0b11 << 30); // SFT disabled, SFEC disable
    }
    for i in 0..8 {
        r.ram_write(28 + 2 * i, 0);
        r.ram_write(28 + 2 * i + 1, 0b11 << 30);
    }
    // The HAL's message_ram_layout!(can, 0x000).
    set(r, Reg::Sidfc, 0xFFFC, 0);
    set(r, Reg::Xidfc, 0xFFFC, 28 << 2);
    set(
        r,
        Reg::Rxf0c,
        0x7F7F_FFFC,
        (3 << 24) | (3 << 16) | (44 << 2),
    );
    set(
        r,
        Reg::Rxf1c,
        0x7F7F_FFFC,
        (3 << 24) | (3 << 16) | (98 << 2),
    );
    set(
        r,
        Reg::Txefc,
        0x3F3F_FFFC,
        (3 << 24) | (3 << 16) | (152 << 2),
    );
    set(r, Reg::Txbc, 0x3F00_FFFC, (3 << 24) | (158 << 2));
    set(r, Reg::Rxbc, 0xFFFC, 212 << 2);
    set(r, Reg::Rxesc, 0x777, 0x777);
    set(r, Reg::Txesc, 0x7, 0x7);
    // The board's main.rs.
    set(r, Reg::Cccr, 1 << 12, 1 << 12); // PXHD: protocol exception handling off
    set(r, Reg::Cccr, 3 << 8, 0); // FDOE = BRSE = 0
    r.write(Reg::Nbtp, (4 << 25) | (1 << 16) | (33 << 8) | 4);
    for (i, id) in ids::COMMANDS.iter().enumerate() {
        let id = u32::from(*id);
        r.ram_write(i as u32, (0b01 << 30) | (0b001 << 27) | (id << 16) | id);
    }
    for i in ids::COMMANDS.len() as u32..28 {
        r.ram_write(i, 0b11 << 30);
    }
    r.ram_write(28, 0b011 << 29); // reject, classic filter 0 / mask 0: every extended id
    r.ram_write(29, 0b10 << 30);
    set(r, Reg::Gfc, 0x3F, 0x3F); // GlobalFilter::reject_all()
                                  // The board's fdcan1::layout().
    r.write(Reg::Rxf0c, (64 << 16) | (44 << 2));
    r.write(Reg::Rxf1c, 0);
    r.write(Reg::Txefc, 0);
    r.write(Reg::Txbc, (32 << 16) | (300 << 2));
    r.write(Reg::Rxesc, 0);
    r.write(Reg::Txesc, 0);
    // into_normal(): set_normal_operations = set_loopback_mode(None): TEST = MON = 0,
    // TEST.LBCK = 0 ...
    set(r, Reg::Cccr, 1 << 7, 0);
    set(r, Reg::Cccr, 1 << 5, 0);
    set(r, Reg::Test, 1 << 4, 0);
    // ... leave_init_mode: apply_config(self.control.config) ...
    r.write(Reg::Dbtp, 0x0000_0A33); // DataBitTiming::default()
    r.write(Reg::Nbtp, (4 << 25) | (1 << 16) | (33 << 8) | 4);
    set(r, Reg::Cccr, 1 << 6, 0); // DAR: automatic retransmission
    set(r, Reg::Cccr, 1 << 14, 0); // TXP
    set(r, Reg::Cccr, 3 << 8, 0); // ClassicCanOnly
    r.write(Reg::Ils, 0);
    set(r, Reg::Cccr, 1 << 15, 0); // NISO
    set(r, Reg::Cccr, 1 << 13, 0); // EFBI
    set(r, Reg::Cccr, 1 << 12, 1 << 12); // PXHD (stored by the driver)
    set(r, Reg::Gfc, 0x3F, 0x00); // GlobalFilter::default(): never stored, so reset here
                                  // ... then CCE and INIT cleared, and INIT waited for.
    set(r, Reg::Cccr, CCE, 0);
    set(r, Reg::Cccr, INIT, 0);
    while r.read(Reg::Cccr) & INIT != 0 {}
}

#[test]
fn old_fdcan_crate_sequence_is_caught_letting_every_standard_frame_in() {
    let mut m = FdcanModel::after_reset();
    fdcan_crate_sequence(&mut m);
    // The driver kept RM0433's rules (and its layout was sound) ...
    assert_eq!(m.violations(), []);
    assert!(!m.st().in_init());
    // ... but GFC is back at "accept non-matching into FIFO0, filter remote frames": the
    // read-back names it, and the bus is open to every standard frame.
    assert_eq!(m.st().peek(regmodel::GFC), 0);
    assert_eq!(
        fdcan::verify(&m, &TIMING),
        Err(BringUpError::Register(Reg::Gfc))
    );
    let accepted = foreign_accepted(&m);
    let ids: Vec<_> = accepted.iter().map(|(f, _)| (f.id, f.remote)).collect();
    // Every standard data frame and every standard remote frame; the extended frames only
    // because of the extended reject-all element.
    assert_eq!(
        ids,
        [
            (0x123, false),
            (0x000, false),
            (0x7FF, false),
            (u32::from(ids::ACK), false),
            (u32::from(ids::COG), false),
            (u32::from(ids::ESTOP) + 1, false),
            (0x123, true),
            (u32::from(ids::ESTOP), true),
            (u32::from(ids::CONTROL), true),
        ]
    );
    for (_, v) in &accepted {
        assert!(matches!(v, Verdict::Fifo { n: 0, .. }), "{v:?}");
    }
    // And ESTOP shared FIFO0 with everything else.
    assert_eq!(
        m.st().arrive(command(Command::EmergencyStop { seq: 1 })),
        Verdict::Fifo {
            n: 0,
            filter: Some(0)
        }
    );
}

// --- the model's own rules ---

#[test]
fn interrupt_flags_are_write_one_to_clear() {
    let mut m = brought_up();
    for i in 0..=RX_ELEMENTS as u32 {
        m.st().arrive(heartbeat(i));
    }
    let ir = m.read(Reg::Ir);
    assert_ne!(ir & regmodel::IR_RF0L, 0, "the 65th frame was lost");
    m.write(Reg::Ir, 0);
    assert_eq!(m.read(Reg::Ir), ir, "a 0 clears nothing");
    m.write(Reg::Ir, regmodel::IR_RF0L);
    assert_eq!(m.read(Reg::Ir), ir & !regmodel::IR_RF0L);
    assert_eq!(
        (m.read(Reg::Rxf0s) >> 25) & 1,
        0,
        "RXF0S.RF0L follows IR.RF0L"
    );
    assert_eq!(m.violations(), []);
}

#[test]
fn fifo_indices_and_acknowledgements_follow_rm0433() {
    let mut m = brought_up();
    for i in 0..5 {
        m.st().arrive(heartbeat(i));
    }
    let s = m.read(Reg::Rxf0s);
    assert_eq!((s & 0x7F, (s >> 8) & 0x3F, (s >> 16) & 0x3F), (5, 0, 5));
    // Acknowledging index 2 releases elements 0, 1 and 2.
    m.write(Reg::Rxf0a, 2);
    let s = m.read(Reg::Rxf0s);
    assert_eq!((s & 0x7F, (s >> 8) & 0x3F), (2, 3));
    assert_eq!(m.violations(), []);
    // An index outside the fill (element 1 is free again), of an empty FIFO: caught.
    m.write(Reg::Rxf0a, 1);
    m.write(Reg::Rxf1a, 0);
    assert_eq!(
        m.violations(),
        [
            Violation::AckOutsideFill { fifo: 0, index: 1 },
            Violation::AckOutsideFill { fifo: 1, index: 0 },
        ]
    );
}

#[test]
fn tx_requests_pend_until_sent_or_cancelled() {
    let mut m = brought_up();
    let e = RawFrame::new(ids::STATUS, &[1; 8]).unwrap();
    let el = board_core::ClassicFrame::new(embedded_can::StandardId::new(e.id).unwrap(), e.bytes())
        .unwrap()
        .to_element();
    for (k, w) in el.iter().enumerate() {
        m.ram_write(layout::TX_BUFFERS + 4 + k as u32, *w);
    }
    m.write(Reg::Txbar, 1 << 1);
    assert_eq!(m.read(Reg::Txbrp), 1 << 1);
    // Writing a pending buffer, requesting a buffer TXBC does not configure: caught.
    m.ram_write(layout::TX_BUFFERS + 4, 0);
    assert_eq!(
        m.violations(),
        [Violation::BufferWrittenWhilePending { slot: 1 }]
    );
    m.st().violations.clear();
    m.write(Reg::Txbcr, 1 << 1);
    assert_eq!(m.read(Reg::Txbrp), 0);
    assert_eq!(m.read(Reg::Txbcf), 1 << 1);
    assert_eq!(m.st().bus_sends(8), 0);
    let mut m = FdcanModel::after_reset();
    m.st().settle();
    m.write(Reg::Txbar, 1);
    assert_eq!(m.violations(), [Violation::UnconfiguredBuffer { bits: 1 }]);
}

#[test]
fn the_message_ram_is_bounded_and_its_layout_checked_when_leaving_init() {
    let mut m = brought_up();
    m.ram_write(1024, 0);
    assert_eq!(m.ram_read(2000), 0);
    assert_eq!(
        m.violations(),
        [
            Violation::RamBounds { word: 1024 },
            Violation::RamBounds { word: 2000 }
        ]
    );
    // RX FIFO1 over RX FIFO0, and the TX buffers past the end.
    let mut m = FdcanModel::after_reset();
    fdcan::configure(&mut m, &TIMING).unwrap();
    m.write(Reg::Rxf1c, (16 << 16) | ((layout::RX_FIFO0 + 8) << 2));
    m.write(Reg::Txbc, (32 << 16) | (1000 << 2));
    assert_eq!(fdcan::join(&mut m), Ok(()));
    let v = m.violations();
    assert!(
        v.contains(&Violation::LayoutOverlap("RX FIFO0", "RX FIFO1")),
        "{v:?}"
    );
    assert!(v.contains(&Violation::Layout {
        section: "TX buffers",
        problem: "beyond FDCAN1's 1,024 words"
    }));
}

#[test]
fn the_filter_engine_follows_rm0433() {
    // Hand-written elements, one of each kind, and GFC sending non-matching frames to FIFO1.
    let mut m = FdcanModel::after_reset();
    fdcan::configure(&mut m, &TIMING).unwrap();
    let sfe =
        |sft: u32, sfec: u32, id1: u32, id2: u32| (sft << 30) | (sfec << 27) | (id1 << 16) | id2;
    let elements = [
        sfe(0b00, 0b001, 0x200, 0x20F), // range 0x200-0x20F -> FIFO0
        sfe(0b10, 0b010, 0x300, 0x7F0), // classic: 0x30x -> FIFO1
        sfe(0b11, 0b001, 0x400, 0x400), // SFT disabled
        sfe(0b01, 0b000, 0x401, 0x401), // SFEC disabled
        sfe(0b01, 0b011, 0x402, 0x403), // dual: reject 0x402 and 0x403
        sfe(0b01, 0b001, 0x403, 0x403), // never reached for 0x403 (first match wins)
        sfe(0b00, 0b111, 0x404, 0x000), // RX buffer: SFT ignored, SFID1 the id
    ];
    // The lists after board-core's layout (words 600 and 620, free).
    for (w, e) in (600..).zip(elements) {
        m.ram_write(w, e);
    }
    m.write(Reg::Sidfc, ((elements.len() as u32) << 16) | (600 << 2));
    // One extended element: classic filter 0x100 / mask 0x1FF, XIDAM clearing bit 12.
    m.ram_write(620, (0b001 << 29) | 0x100);
    m.ram_write(621, (0b10 << 30) | 0x1FF);
    m.write(Reg::Xidfc, (1 << 16) | (620 << 2));
    m.write(Reg::Xidam, 0x1FFF_EFFF);
    m.write(Reg::Gfc, (0b01 << 4) | (0b11 << 2)); // non-matching std -> FIFO1, ext rejected
    fdcan::join(&mut m).unwrap();
    assert_eq!(m.violations(), []);
    let fifo = |n, filter| Verdict::Fifo { n, filter };
    let cases = [
        (BusFrame::std(0x205, &[]), fifo(0, Some(0))),
        (BusFrame::std(0x210, &[]), fifo(1, None)),
        (BusFrame::std(0x30A, &[]), fifo(1, Some(1))),
        (BusFrame::std(0x400, &[]), fifo(1, None)),
        (BusFrame::std(0x401, &[]), fifo(1, None)),
        (BusFrame::std(0x402, &[]), Verdict::FilterRejected(4)),
        (BusFrame::std(0x403, &[]), Verdict::FilterRejected(4)),
        (BusFrame::std(0x404, &[]), Verdict::RxBuffer(6)),
        // RRFS = 0: remote frames are filtered like data frames.
        (BusFrame::std_remote(0x205, 0), fifo(0, Some(0))),
        // 0x1100 & XIDAM = 0x0100, & 0x1FF = 0x100: matches; 0x300 too, 0x200 not.
        (BusFrame::ext(0x1100, &[]), fifo(0, Some(0))),
        (BusFrame::ext(0x0300, &[]), fifo(0, Some(0))),
        (BusFrame::ext(0x0200, &[]), Verdict::NonMatchingRejected),
    ];
    for (f, want) in cases {
        assert_eq!(m.st().arrive(f), want, "{f:x?}");
    }
    // The stored elements: R1 with ANMF for a non-matching frame, R0 with XTD and the
    // identifier as received (FIFO0's third element).
    let s = m.st();
    assert_eq!(s.peek_ram(layout::RX_FIFO1), 0x210 << 18);
    assert_eq!(s.peek_ram(layout::RX_FIFO1 + 1) >> 31, 1);
    assert_eq!(s.peek_ram(layout::RX_FIFO0 + 8), (1 << 30) | 0x1100);
}

// --- the run-time path over the registers ---

type ModelLink = Link<RegFdcan<FdcanModel>>;

fn link() -> ModelLink {
    Link::new(RegFdcan::new(brought_up()))
}

fn model(l: &ModelLink) -> &FdcanModel {
    l.peripheral().regs()
}

/// The node's `ACK`s on the modelled wire: (identifier of the command, sequence number).
fn acks(l: &ModelLink) -> Vec<Ack> {
    model(l)
        .st()
        .wire
        .iter()
        .filter(|f| u32::from(ids::ACK) == f.id)
        .filter_map(|f| RawFrame::new(f.id as u16, &f.data[..usize::from(f.dlc)]))
        .filter_map(|r| Ack::decode(&r))
        .collect()
}

fn run(node: &mut Node<16>, l: &mut ModelLink, first_ms: u32, cycles: u32) {
    for k in 0..cycles {
        node.poll(first_ms + 5 * k, l);
        for _ in 0..4 {
            model(l).st().bus_sends(64);
            l.service();
        }
    }
}

#[test]
fn commands_reach_the_node_and_its_frames_the_bus_over_the_registers() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link();
    for f in foreign_frames() {
        model(&l).st().arrive(f);
    }
    for seq in 1..=16 {
        model(&l).st().arrive(heartbeat(seq));
    }
    run(&mut node, &mut l, 0, 6);
    let seqs: Vec<u8> = acks(&l).iter().map(|a| a.seq).collect();
    assert_eq!(seqs, (1..=16).collect::<Vec<u8>>());
    // The filters kept the foreign frames out: the node never saw one.
    assert_eq!(node.counters().foreign, 0);
    assert_eq!(l.health().rx_foreign, 0);
    // STATUS, DIAG, SESSION went out too, through the TX buffers.
    assert!(model(&l)
        .st()
        .wire
        .iter()
        .any(|f| f.id == u32::from(ids::STATUS)));
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn an_estop_behind_a_full_fifo0_stops_the_node_in_its_cycle() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link();
    // 48 commands fill the node's receive budget of three cycles (16 a cycle); the ESTOP
    // arrives last.
    for seq in 1..=48 {
        model(&l).st().arrive(heartbeat(seq));
    }
    l.service(); // 32 of them into the software queue already
    model(&l)
        .st()
        .arrive(command(Command::EmergencyStop { seq: 7 }));
    node.poll(0, &mut l);
    assert_eq!(node.state(), NodeState::EmergencyStopped);
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn overflow_bus_off_and_silence_over_the_registers() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link();
    // An RX FIFO1 overflow (17 ESTOPs into 16 elements) is reported once, the flag cleared
    // by writing 1.
    for seq in 0..17 {
        model(&l)
            .st()
            .arrive(command(Command::EmergencyStop { seq }));
    }
    assert_eq!(
        model(&l).st().peek(regmodel::IR) & regmodel::IR_RF1L,
        regmodel::IR_RF1L
    );
    l.service();
    assert_eq!(l.health().rx_lost, 1);
    assert_eq!(model(&l).st().peek(regmodel::IR) & regmodel::IR_RF1L, 0);
    // The 16 ESTOPs first, then the loss, in the same cycle (the node takes what waits, and
    // stops receiving for the cycle at the loss); nothing more in the next.
    node.poll(0, &mut l);
    assert_eq!(node.state(), NodeState::EmergencyStopped);
    assert_eq!(node.counters().bus_errors, 1);
    node.poll(5, &mut l);
    assert_eq!(node.counters().bus_errors, 1);
    // Bus-off: the core sets INIT itself; the adapter cancels the pending dedicated buffers
    // (stream frames), copies the ACKs owed in the TX FIFO (buffers 16 … 31) and listens in
    // bus monitoring (configuration mode resets TXBRP): the ACKs wait in software.
    let dedicated = (1u32 << TX_SLOTS) - 1;
    assert_ne!(
        model(&l).st().pending() & dedicated,
        0,
        "frames wait in the TX buffers"
    );
    let acks_waiting = (model(&l).st().pending() & !dedicated).count_ones() as usize;
    assert_ne!(acks_waiting, 0, "ACKs in the FIFO");
    model(&l).st().bus_off();
    assert_eq!(l.peripheral().protocol_status() & psr::BO, psr::BO);
    l.service();
    assert_eq!(l.health().state, BusState::BusOff);
    assert!(l.listening());
    assert_eq!(model(&l).st().pending(), 0);
    assert_eq!(l.tx_waiting(), acks_waiting);
    // The recovery (129 × 11 recessive bits) runs during the back-off (one cycle the first
    // time); bus-off is published throughout.
    model(&l).st().settle();
    assert!(!model(&l).st().in_init(), "recovery started");
    model(&l).st().idle_bits(regmodel::RECOVERY_BITS - 1);
    l.service();
    assert!(model(&l).st().recovering());
    model(&l).st().idle_bits(1);
    l.service();
    assert!(!model(&l).st().recovering());
    assert_eq!(l.health().state, BusState::BusOff, "backing off, listening");
    l.cycle();
    model(&l).st().settle();
    assert!(!model(&l).st().monitoring() && !model(&l).st().in_init());
    l.service();
    assert_eq!(l.health().bus_offs, 1);
    assert_eq!(l.health().state, BusState::Active);
    assert_eq!(l.tx_waiting(), 0, "the owed ACKs back in the TX FIFO");
    assert_eq!(
        (model(&l).st().pending() & !dedicated).count_ones() as usize,
        acks_waiting
    );
    // The fault path: off the bus, every request cancelled, nothing sent.
    model(&l).st().arrive(heartbeat(1)); // answered: a frame waits in a TX buffer
    node.poll(10, &mut l);
    assert_ne!(model(&l).st().pending(), 0);
    assert!(
        fdcan::silence(l.peripheral_mut().regs_mut()),
        "ENDN answered"
    );
    model(&l).st().settle();
    assert!(model(&l).st().in_init());
    assert_eq!(model(&l).st().pending(), 0);
    assert_eq!(model(&l).st().bus_sends(TX_SLOTS), 0);
    assert_eq!(model(&l).violations(), []);
}

// --- the TX FIFO and the order of the ACKs ---

/// The sequence numbers of the ACKs on the modelled wire, in order.
fn ack_seqs(m: &FdcanModel) -> Vec<u8> {
    m.st()
        .wire
        .iter()
        .filter(|f| f.id == u32::from(ids::ACK))
        .map(|f| f.data[1])
        .collect()
}

/// Writes `e` into the lowest free dedicated buffer and requests it: how every frame, ACKs
/// included, was sent before the TX FIFO.
fn start_lowest_free(m: &mut FdcanModel, e: [u32; 4]) -> u32 {
    let slot = (!m.read(Reg::Txbrp)).trailing_zeros();
    assert!(slot < TX_SLOTS as u32);
    for (k, w) in e.iter().enumerate() {
        m.ram_write(layout::TX_BUFFERS + 4 * slot + k as u32, *w);
    }
    m.write(Reg::Txbar, 1 << slot);
    slot
}

#[test]
fn acks_in_dedicated_buffers_leave_out_of_order_and_through_the_tx_fifo_in_order() {
    // The old way, over the model: ACK 0, a COG, ACK 1, ACK 2; the COG superseded (its
    // buffer's cancellation completing after the new COG took another buffer); ACK 3 takes
    // the lowest free buffer, the COG's old one. Equal identifiers: lowest buffer first.
    let mut m = brought_up();
    m.st().defer_cancel = true;
    let ack = |seq: u8| element(ids::ACK, &[0x20, seq]);
    assert_eq!(start_lowest_free(&mut m, ack(0)), 0);
    assert_eq!(start_lowest_free(&mut m, element(ids::COG, &[1])), 1);
    assert_eq!(start_lowest_free(&mut m, ack(1)), 2);
    assert_eq!(start_lowest_free(&mut m, ack(2)), 3);
    m.write(Reg::Txbcr, 1 << 1);
    assert_eq!(start_lowest_free(&mut m, element(ids::COG, &[2])), 4);
    m.st().complete_cancels();
    assert_eq!(start_lowest_free(&mut m, ack(3)), 1);
    m.st().bus_sends(16);
    assert_eq!(ack_seqs(&m), [0, 3, 1, 2]);
    assert_eq!(m.violations(), []);

    // The adapter, the same sends: the ACKs through the TX FIFO, in order.
    let mut l = link();
    model(&l).st().defer_cancel = true;
    let f = |id: u16, data: &[u8]| {
        board_core::ClassicFrame::new(embedded_can::StandardId::new(id).unwrap(), data).unwrap()
    };
    use embedded_can::nb::Can;
    for (id, data) in [
        (ids::ACK, [0x20, 0]),
        (ids::COG, [1, 0]),
        (ids::ACK, [0x20, 1]),
        (ids::ACK, [0x20, 2]),
        (ids::COG, [2, 0]),
    ] {
        l.transmit(&f(id, &data)).unwrap();
    }
    model(&l).st().complete_cancels();
    l.transmit(&f(ids::ACK, &[0x20, 3])).unwrap();
    model(&l).st().bus_sends(16);
    assert_eq!(ack_seqs(model(&l)), [0, 1, 2, 3]);
    // The superseded COG never went out.
    let cogs: Vec<u8> = model(&l)
        .st()
        .wire
        .iter()
        .filter(|w| w.id == u32::from(ids::COG))
        .map(|w| w.data[0])
        .collect();
    assert_eq!(cogs, [2]);
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn the_tx_fifo_follows_its_put_index_and_full_flag() {
    let mut r = RegFdcan::new(brought_up());
    let fifo0 = TX_SLOTS as u32;
    let st = r.regs().read(Reg::Txfqs);
    assert_eq!(st & 0x3F, TX_FIFO as u32, "all free");
    assert_eq!((st >> 16) & 0x1F, fifo0, "put index: the first FIFO buffer");
    // A request of a FIFO buffer other than the put index: caught.
    r.regs_mut().write(Reg::Txbar, 1 << (fifo0 + 3));
    assert_eq!(
        r.regs().violations(),
        [Violation::FifoNotAtPutIndex {
            bits: 1 << (fifo0 + 3),
            put: fifo0
        }]
    );
    r.regs().st().violations.clear();
    // The FIFO keeps put order whatever the identifiers: a high one first, then ACKs.
    assert!(r.tx_fifo_put(&element(ids::LINK, &[9; 8])));
    for seq in 0..TX_FIFO as u8 - 1 {
        assert!(r.tx_fifo_put(&element(ids::ACK, &[0x20, seq])));
    }
    let st = r.regs().read(Reg::Txfqs);
    assert_eq!(st & 0x3F, 0, "no free element");
    assert_ne!(st & (1 << 21), 0, "TFQF");
    // Full: the adapter's put refuses (nothing written), a raw request is caught.
    assert!(!r.tx_fifo_put(&element(ids::ACK, &[0x20, 99])));
    assert_eq!(r.regs().violations(), []);
    r.regs_mut().write(Reg::Txbar, 1 << fifo0);
    assert_eq!(r.regs().violations(), [Violation::FifoFull]);
    r.regs().st().violations.clear();
    // A dedicated buffer with a lower identifier than the FIFO's oldest goes first; the FIFO
    // then leaves in put order (LINK before the ACKs, though its identifier is higher).
    r.tx_start(0, &element(ids::COG, &[1]));
    assert_eq!(r.regs().st().bus_sends(3), 3);
    let ids_sent: Vec<u32> = r.regs().st().wire.iter().map(|w| w.id).collect();
    assert_eq!(
        ids_sent,
        [
            u32::from(ids::COG),
            u32::from(ids::LINK),
            u32::from(ids::ACK)
        ]
    );
    // Room again: the put index wrapped past the elements sent.
    let st = r.regs().read(Reg::Txfqs);
    assert_eq!(st & 0x3F, 2);
    assert_eq!((st >> 16) & 0x1F, fifo0);
    assert!(r.tx_fifo_put(&element(ids::ACK, &[0x20, 100])));
    r.regs().st().bus_sends(64);
    let seqs = ack_seqs(r.regs());
    assert_eq!(
        seqs,
        (0..TX_FIFO as u8 - 1).chain([100]).collect::<Vec<_>>()
    );
    assert_eq!(r.regs().violations(), []);
}

// --- bus-off back-off and message RAM access failures ---

/// Bit times of a 5 ms control cycle at 1 Mbit/s.
const CYCLE_BITS: u32 = 5_000;

/// One control cycle of a quiet bus: the cycle's bus time with services between (the loop's
/// wait), then `Link::cycle` and a service.
fn quiet_cycle(l: &mut ModelLink) {
    for _ in 0..4 {
        model(l).st().idle_bits(CYCLE_BITS / 4);
        l.service();
    }
    l.cycle();
    l.service();
}

/// The core takes part in the bus as a sender: on the bus, not monitoring (a pending `INIT`
/// change applied).
fn sending(l: &ModelLink) -> bool {
    let mut s = model(l).st();
    s.settle();
    s.on_bus() && !s.monitoring()
}

/// Control cycles ([`quiet_cycle`]) until the core sends again after a bus-off; `None` if it
/// has not within 1,000.
fn cycles_to_rejoin(l: &mut ModelLink) -> Option<u32> {
    for k in 1..=1000 {
        quiet_cycle(l);
        if sending(l) {
            return Some(k);
        }
    }
    None
}

#[test]
fn bus_off_recovery_backs_off_doubling_to_a_cap_and_resets_after_a_quiet_stretch() {
    use board_core::link::{BACKOFF_CAP, BACKOFF_RESET_CYCLES};
    let mut l = link();
    let mut waits = Vec::new();
    let mut published = Vec::new();
    for _ in 0..9 {
        model(&l).st().bus_off();
        l.service();
        assert_eq!(l.health().state, BusState::BusOff);
        published.push(
            l.health()
                .to_wire(board_core::ResetReason::PowerOn, 0)
                .backoff,
        );
        waits.push(cycles_to_rejoin(&mut l).expect("re-joins"));
        assert!(!model(&l).st().in_init());
    }
    // 1, 2, 4, … cycles, capped at 64 (320 ms); one bus-off counted each time.
    assert_eq!(waits, [1, 2, 4, 8, 16, 32, 64, 64, 64]);
    assert_eq!(*waits.iter().max().unwrap(), u32::from(BACKOFF_CAP));
    assert_eq!(published, [1, 2, 3, 4, 5, 6, 7, 7, 7]);
    assert_eq!(l.health().bus_offs, 9);
    // Error-active on the bus for a while, but not long enough: the back-off stays.
    for _ in 0..BACKOFF_RESET_CYCLES - 2 {
        quiet_cycle(&mut l);
    }
    model(&l).st().bus_off();
    l.service();
    assert_eq!(cycles_to_rejoin(&mut l), Some(64));
    // A whole quiet stretch: back to 1 cycle (and published as none meanwhile).
    for _ in 0..BACKOFF_RESET_CYCLES {
        quiet_cycle(&mut l);
    }
    assert_eq!(l.health().backoff, 0);
    model(&l).st().bus_off();
    l.service();
    assert_eq!(cycles_to_rejoin(&mut l), Some(1));
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn a_message_ram_access_failure_is_counted_and_restricted_operation_left() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut l = link();
    model(&l).st().arrive(heartbeat(1));
    node.poll(0, &mut l);
    assert_ne!(model(&l).st().pending(), 0, "the node's frames wait");
    // The TX handler could not read an element in time: restricted operation, nothing sent.
    model(&l).st().ram_access_failure(true);
    assert_eq!(model(&l).st().bus_sends(64), 0);
    l.service();
    assert_eq!(l.health().ram_faults, 1);
    let s = model(&l).st().peek(regmodel::CCCR);
    assert_eq!(s & regmodel::CCCR_ASM, 0, "restricted operation left");
    assert_eq!(model(&l).st().peek(regmodel::IR) & regmodel::IR_MRAF, 0);
    assert!(model(&l).st().bus_sends(64) > 0, "sending again");
    assert_eq!(acks(&l).len(), 1);
    // An RX handler failure: counted (no restricted operation); published in LINK.
    model(&l).st().ram_access_failure(false);
    l.service();
    l.service();
    assert_eq!(l.health().ram_faults, 2, "counted once");
    let w = l.health().to_wire(board_core::ResetReason::PowerOn, 0);
    assert_eq!(w.encode().data[2] >> 6, 2);
    assert_eq!(model(&l).violations(), []);
}
