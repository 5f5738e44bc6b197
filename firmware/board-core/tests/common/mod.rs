//! What the register-model tests share: the board's bit timing, a model brought up by
//! board-core with no violation, and the frames they put on the modelled bus.
// Each test file uses its own part of these helpers.
#![allow(dead_code)]

use crate::regmodel::{BusFrame, FdcanModel};
use board_core::fdcan;
use embedded_can::Frame;
use planner_core::wire::{Command, ControlOp};

/// The board's nominal bit timing (its setting in `board/src/main.rs`): 1 Mbit/s from 80 MHz,
/// 40 time quanta, sample point 87.5 %.
pub const TIMING: fdcan::BitTiming = fdcan::BitTiming {
    prescaler: 2,
    seg1: 34,
    seg2: 5,
    sjw: 5,
};

/// A model brought up by board-core: no violation, out of `INIT`, joined the bus once.
pub fn brought_up() -> FdcanModel {
    let mut m = FdcanModel::after_reset();
    assert_eq!(fdcan::bring_up(&mut m, &TIMING), Ok(()));
    assert_eq!(m.violations(), []);
    assert!(!m.st().in_init());
    assert_eq!(m.st().joins, 1);
    m
}

/// A command as the modelled bus carries it.
pub fn command(c: Command) -> BusFrame {
    BusFrame::raw(&c.encode())
}

/// A controller's heartbeat of the handshake-less session 0.
pub fn heartbeat(seq: u32) -> BusFrame {
    command(Command::Control {
        session: 0,
        seq,
        op: ControlOp::Heartbeat,
    })
}

/// An `ESTOP`.
pub fn estop(seq: u8) -> BusFrame {
    command(Command::EmergencyStop { seq })
}

/// A classic frame as a TX buffer element.
pub fn element(id: u16, data: &[u8]) -> [u32; 4] {
    board_core::ClassicFrame::new(embedded_can::StandardId::new(id).unwrap(), data)
        .unwrap()
        .to_element()
}
