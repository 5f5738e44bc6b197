//! The safe state's order (`board_core::safe_state`): the CAN TX pin recessive first, then the
//! reset mark and the fault pin, only then the FDCAN, then the reset; a fault inside the FDCAN
//! step cannot undo what came before it.

use std::panic::{catch_unwind, AssertUnwindSafe};

use board_core::reset::{MARK_CLOCK, MARK_FAULT};
use board_core::safe_state::{fail_safe, signal, SafeStateHw};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    TxRecessive,
    Mark(u32),
    FaultPin,
    Fdcan,
    Reset,
}

/// Records every operation; optionally "faults" (panics) in the FDCAN step, as a bus fault on
/// an unclocked peripheral would re-enter the handler.
#[derive(Default)]
struct Recorder {
    ops: Vec<Op>,
    fdcan_faults: bool,
}

impl SafeStateHw for Recorder {
    fn can_tx_recessive(&mut self) {
        self.ops.push(Op::TxRecessive);
    }
    fn write_mark(&mut self, mark: u32) {
        self.ops.push(Op::Mark(mark));
    }
    fn raise_fault_pin(&mut self) {
        self.ops.push(Op::FaultPin);
    }
    fn silence_fdcan(&mut self) {
        if self.fdcan_faults {
            panic!("bus fault in an FDCAN access");
        }
        self.ops.push(Op::Fdcan);
    }
    fn reset(&mut self) -> ! {
        self.ops.push(Op::Reset);
        panic!("reset");
    }
}

#[test]
fn the_safe_state_is_pin_mark_fault_pin_fdcan_then_reset() {
    let mut hw = Recorder::default();
    let r = catch_unwind(AssertUnwindSafe(|| fail_safe(&mut hw, MARK_CLOCK)));
    assert!(r.is_err(), "fail_safe ends in the reset");
    assert_eq!(
        hw.ops,
        [
            Op::TxRecessive,
            Op::Mark(MARK_CLOCK),
            Op::FaultPin,
            Op::Fdcan,
            Op::Reset
        ]
    );
}

#[test]
fn off_the_bus_is_the_same_order_without_the_reset() {
    let mut hw = Recorder::default();
    signal(&mut hw, MARK_FAULT);
    assert_eq!(
        hw.ops,
        [
            Op::TxRecessive,
            Op::Mark(MARK_FAULT),
            Op::FaultPin,
            Op::Fdcan
        ]
    );
}

#[test]
fn a_fault_in_the_fdcan_step_leaves_the_pin_the_mark_and_the_fault_pin_done() {
    let mut hw = Recorder {
        fdcan_faults: true,
        ..Recorder::default()
    };
    let r = catch_unwind(AssertUnwindSafe(|| fail_safe(&mut hw, MARK_CLOCK)));
    assert!(r.is_err());
    // Everything that silences and reports came before the access that faulted.
    assert_eq!(
        hw.ops,
        [Op::TxRecessive, Op::Mark(MARK_CLOCK), Op::FaultPin]
    );
}
