//! The register model's configuration-mode, bus-monitoring and fault-confinement rules
//! (`regmodel`, `regmodel/errors.rs`), and the link adapter's error paths over them: warning,
//! error-passive, bus-off and its recovery window, all read from `PSR`/`ECR` as the model
//! derives them from injected error counters.

mod common;
mod regmodel;

use common::*;

use board_core::fdcan::{layout, FdcanRegs, Reg, RegFdcan};
use board_core::link::{BACKOFF_RESET_CYCLES, TX_SLOTS};
use board_core::{BusState, Link};
use planner_core::wire::{ids, Command};
use regmodel::{BusFrame, FdcanModel, Verdict, Violation, RECOVERY_BITS};

/// Requests `INIT` and reads `CCCR` until it shows.
fn enter_init(m: &mut FdcanModel) {
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::INIT);
    m.st().settle();
    assert!(m.st().in_init());
}

/// `INIT` and `CCE`: configuration mode.
fn enter_config(m: &mut FdcanModel) {
    enter_init(m);
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::INIT | regmodel::CCE);
    assert_ne!(m.read(Reg::Cccr) & regmodel::CCE, 0);
}

fn leave_init(m: &mut FdcanModel) {
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c & !(regmodel::INIT | regmodel::CCE));
    m.st().settle();
    assert!(!m.st().in_init());
}

// --- configuration mode ---

#[test]
fn setting_cce_resets_the_fifo_statuses_and_every_tx_request() {
    let m = brought_up();
    for seq in 0..3 {
        m.st().arrive(heartbeat(seq));
    }
    m.st()
        .arrive(BusFrame::raw(&Command::EmergencyStop { seq: 1 }.encode()));
    let mut r = RegFdcan::new(m);
    board_core::Fdcan::tx_start(&mut r, 2, &element(ids::COG, &[1]));
    assert!(board_core::Fdcan::tx_fifo_put(
        &mut r,
        &element(ids::ACK, &[0x20, 1])
    ));
    let m = r.regs_mut();
    m.st().bus_sends(1); // the COG: TXBTO set
    let before = (m.read(Reg::Rxf0s), m.read(Reg::Rxf1s), m.read(Reg::Txbrp));
    assert_eq!(before.0 & 0x7F, 3);
    assert_eq!(before.1 & 0x7F, 1);
    assert_ne!(before.2, 0);
    assert_ne!(m.read(Reg::Txbto), 0);
    // INIT alone changes none of them.
    enter_init(m);
    assert_eq!(
        (m.read(Reg::Rxf0s), m.read(Reg::Rxf1s), m.read(Reg::Txbrp)),
        before
    );
    // CCE resets RXF0S, RXF1S, TXFQS, TXBRP, TXBTO, TXBCF (HPMS, TXEFS read 0 throughout).
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::CCE);
    for reg in [
        Reg::Rxf0s,
        Reg::Rxf1s,
        Reg::Txbrp,
        Reg::Txbto,
        Reg::Txbcf,
        Reg::Hpms,
        Reg::Txefs,
    ] {
        assert_eq!(m.read(reg), 0, "{reg:?}");
    }
    let q = m.read(Reg::Txfqs);
    assert_eq!(q & 0x3F, 16, "TX FIFO all free");
    assert_eq!(
        (q >> 16) & 0x1F,
        TX_SLOTS as u32,
        "put index at its first buffer"
    );
    assert_eq!(m.violations(), []);
}

#[test]
fn tx_requests_and_cancellations_are_ignored_in_configuration_mode() {
    let mut m = brought_up();
    for (k, w) in element(ids::COG, &[1]).iter().enumerate() {
        m.ram_write(layout::TX_BUFFERS + k as u32, *w);
    }
    enter_config(&mut m);
    m.write(Reg::Txbar, 1);
    assert_eq!(m.read(Reg::Txbrp), 0, "TXBAR ignored with CCE set");
    m.write(Reg::Txbcr, 1);
    assert_eq!(m.read(Reg::Txbcf), 0, "TXBCR ignored with CCE set");
    // The lost request is recorded (a frame never sent); the cancellation is harmless.
    let v = m.violations();
    assert_eq!(v.len(), 1);
    assert!(matches!(v[0], Violation::RequestIgnored { bits: 1, .. }));
    m.st().violations.clear();
    leave_init(&mut m);
    assert_eq!(m.st().bus_sends(4), 0, "nothing was requested");
    m.write(Reg::Txbar, 1);
    assert_eq!(m.st().bus_sends(4), 1);
    assert_eq!(m.violations(), []);
}

// --- bus monitoring ---

#[test]
fn mon_is_set_only_in_configuration_mode() {
    let mut m = brought_up();
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::CCCR_MON);
    assert!(!m.st().monitoring());
    assert!(matches!(
        m.violations()[..],
        [Violation::ProtectedCccrBits { .. }]
    ));
    m.st().violations.clear();
    // INIT alone is not enough either.
    enter_init(&mut m);
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::CCCR_MON);
    assert!(!m.st().monitoring());
    assert_eq!(m.violations().len(), 1);
    m.st().violations.clear();
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::CCE);
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::CCCR_MON);
    assert!(m.st().monitoring());
    assert_eq!(m.violations(), []);
}

#[test]
fn in_bus_monitoring_the_core_receives_and_never_transmits() {
    let mut m = brought_up();
    enter_config(&mut m);
    let c = m.read(Reg::Cccr);
    m.write(Reg::Cccr, c | regmodel::CCCR_MON);
    leave_init(&mut m);
    assert!(m.st().monitoring());
    // Received and filtered as in normal operation.
    assert!(matches!(
        m.st()
            .arrive(BusFrame::raw(&Command::EmergencyStop { seq: 3 }.encode())),
        Verdict::Fifo { n: 1, .. }
    ));
    assert!(m.st().arrive(heartbeat(1)).stored());
    // A request: TXBRP held in reset, nothing sent, the lost request recorded.
    for (k, w) in element(ids::COG, &[1]).iter().enumerate() {
        m.ram_write(layout::TX_BUFFERS + k as u32, *w);
    }
    m.write(Reg::Txbar, 1);
    assert_eq!(m.read(Reg::Txbrp), 0);
    assert_eq!(m.st().bus_sends(8), 0);
    assert!(m.st().wire.is_empty());
    assert!(matches!(
        m.violations()[..],
        [Violation::RequestIgnored { bits: 1, .. }]
    ));
}

// --- fault confinement ---

#[test]
fn ew_and_ep_follow_the_injected_error_counters() {
    let m = brought_up();
    let cases: [(u16, u8, bool, bool); 7] = [
        (0, 0, false, false),
        (95, 95, false, false),
        (96, 0, true, false),
        (0, 96, true, false),
        (127, 127, true, false),
        (128, 0, true, true),
        (0, 200, true, true),
    ];
    for (tec, rec, ew, ep) in cases {
        m.st().set_error_counters(tec, rec);
        let psr = m.read(Reg::Psr);
        assert_eq!(psr & regmodel::PSR_EW != 0, ew, "{tec} {rec}");
        assert_eq!(psr & regmodel::PSR_EP != 0, ep, "{tec} {rec}");
        assert_eq!(psr & regmodel::PSR_BO, 0);
        let ecr = m.read(Reg::Ecr);
        assert_eq!(ecr & 0xFF, u32::from(tec));
        assert_eq!((ecr >> 8) & 0x7F, u32::from(rec.min(127)));
        assert_eq!(ecr >> 15 & 1 != 0, rec >= 128, "RP");
    }
    // Above 255: bus-off, INIT set by the core.
    m.st().set_error_counters(256, 0);
    assert_ne!(m.read(Reg::Psr) & regmodel::PSR_BO, 0);
    assert!(m.st().in_init());
}

#[test]
fn bus_off_recovery_takes_129_times_11_recessive_bits_after_init_is_cleared() {
    let mut m = brought_up();
    m.st().bus_off();
    // Time in INIT does not count.
    m.st().idle_bits(10 * RECOVERY_BITS);
    assert_ne!(m.read(Reg::Psr) & regmodel::PSR_BO, 0);
    leave_init(&mut m);
    assert!(m.st().recovering());
    m.st().idle_bits(RECOVERY_BITS - 1);
    assert_ne!(m.read(Reg::Psr) & regmodel::PSR_BO, 0, "not yet");
    assert_eq!(
        (m.read(Reg::Ecr) >> 8) & 0x7F,
        127,
        "REC counts the sequences"
    );
    assert_eq!(m.read(Reg::Psr) & regmodel::PSR_LEC, 5, "bit0 error");
    // Not on the bus while recovering.
    assert_eq!(m.st().arrive(heartbeat(1)), Verdict::NotOnBus);
    m.st().idle_bits(1);
    assert_eq!(
        m.read(Reg::Psr) & (regmodel::PSR_BO | regmodel::PSR_EP | regmodel::PSR_EW),
        0
    );
    assert_eq!(m.read(Reg::Ecr), 0);
    assert!(m.st().arrive(heartbeat(2)).stored());
    // 1,419 bits: ≈1.42 ms at 1 Mbit/s.
    assert_eq!(RECOVERY_BITS, 1419);
    // INIT set again during a recovery: it starts over at the next clear.
    m.st().bus_off();
    leave_init(&mut m);
    m.st().idle_bits(RECOVERY_BITS - 11);
    enter_init(&mut m);
    leave_init(&mut m);
    m.st().idle_bits(11);
    assert_ne!(m.read(Reg::Psr) & regmodel::PSR_BO, 0);
    m.st().idle_bits(RECOVERY_BITS);
    assert_eq!(m.read(Reg::Psr) & regmodel::PSR_BO, 0);
    assert_eq!(m.violations(), []);
}

// --- the adapter's error paths over the registers ---

type ModelLink = Link<RegFdcan<FdcanModel>>;

fn model(l: &ModelLink) -> &FdcanModel {
    l.peripheral().regs()
}

#[test]
fn warning_and_passive_are_read_from_the_registers() {
    let mut l = Link::new(RegFdcan::new(brought_up()));
    model(&l).st().set_error_counters(100, 12);
    l.service();
    let h = l.health();
    assert_eq!(
        (h.tec, h.rec, h.rx_passive, h.state),
        (100, 12, false, BusState::Warning)
    );
    model(&l).st().set_error_counters(130, 140);
    l.service();
    l.service();
    let h = l.health();
    assert_eq!((h.tec, h.rec, h.rx_passive), (130, 127, true));
    assert_eq!((h.state, h.passive_episodes), (BusState::Passive, 1));
    // Back to warning, passive again: a second episode.
    model(&l).st().set_error_counters(100, 0);
    l.service();
    assert_eq!(l.health().state, BusState::Warning);
    model(&l).st().set_error_counters(0, 128);
    l.service();
    assert_eq!(l.health().passive_episodes, 2);
    model(&l).st().set_error_counters(0, 0);
    l.service();
    assert_eq!(l.health().state, BusState::Active);
    assert_eq!(l.health().bus_offs, 0);
    assert_eq!(model(&l).violations(), []);
}

#[test]
fn a_warning_keeps_the_back_off_from_resetting() {
    let mut l = Link::new(RegFdcan::new(brought_up()));
    model(&l).st().bus_off();
    l.service();
    assert_eq!(l.health().backoff, 1);
    // Whole quiet stretches, but with a counter at the warning level for one cycle in each:
    // the back-off level stays.
    for _ in 0..3 {
        for k in 0..BACKOFF_RESET_CYCLES {
            l.cycle();
            let warn = if k == BACKOFF_RESET_CYCLES / 2 { 96 } else { 0 };
            model(&l).st().idle_bits(5_000);
            if model(&l).st().on_bus() || model(&l).st().monitoring() {
                model(&l).st().set_error_counters(warn, 0);
            }
            l.service();
        }
    }
    assert_eq!(l.health().backoff, 1, "never a whole quiet stretch");
    // A whole one: reset.
    for _ in 0..BACKOFF_RESET_CYCLES {
        l.cycle();
        model(&l).st().idle_bits(5_000);
        l.service();
    }
    assert_eq!(l.health().backoff, 0);
    assert_eq!(model(&l).violations(), []);
}
