//! The safe state's order (`board_core::safe_state`): the CAN TX pin recessive first, then the
//! reset mark (flagged unfinished) and the fault pin, only then the FDCAN, the mark unflagged
//! once that step has ended cleanly, then the reset; a fault inside the FDCAN step cannot undo
//! what came before it, and the reset that follows it (the handler's or the watchdog's) reads
//! as a nested fault.

use std::panic::{catch_unwind, AssertUnwindSafe};

use board_core::reset::{rsr, MARK_CLOCK, MARK_FAULT, MARK_UNFINISHED};
use board_core::safe_state::{fail_safe, signal, SafeStateHw};
use board_core::ResetReason;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    TxRecessive,
    Mark(u32),
    FaultPin,
    Fdcan,
    Reset,
}

/// How the FDCAN step ends.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum FdcanStep {
    /// Cleanly.
    #[default]
    Clean,
    /// A bus fault, ignored at fault priority and seen afterwards (the step returns `false`).
    FaultIgnored,
    /// A fault that never returns (a lock-up: here a panic).
    LockUp,
}

/// Records every operation; the FDCAN step ends as `fdcan` says.
#[derive(Default)]
struct Recorder {
    ops: Vec<Op>,
    fdcan: FdcanStep,
    /// The no-init word.
    mark: u32,
}

impl SafeStateHw for Recorder {
    fn can_tx_recessive(&mut self) {
        self.ops.push(Op::TxRecessive);
    }
    fn write_mark(&mut self, mark: u32) {
        self.mark = mark;
        self.ops.push(Op::Mark(mark));
    }
    fn raise_fault_pin(&mut self) {
        self.ops.push(Op::FaultPin);
    }
    fn silence_fdcan(&mut self) -> bool {
        if self.fdcan == FdcanStep::LockUp {
            panic!("bus fault in an FDCAN access at HardFault priority");
        }
        self.ops.push(Op::Fdcan);
        self.fdcan == FdcanStep::Clean
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
            Op::Mark(MARK_CLOCK | MARK_UNFINISHED),
            Op::FaultPin,
            Op::Fdcan,
            Op::Mark(MARK_CLOCK),
            Op::Reset
        ]
    );
    // The handler's reset: a software reset with the plain mark.
    let rsr = rsr::SFTRSTF | rsr::PINRSTF;
    assert_eq!(ResetReason::decode(rsr, hw.mark), ResetReason::ClockFailure);
}

#[test]
fn off_the_bus_is_the_same_order_without_the_reset() {
    let mut hw = Recorder::default();
    signal(&mut hw, MARK_FAULT);
    assert_eq!(
        hw.ops,
        [
            Op::TxRecessive,
            Op::Mark(MARK_FAULT | MARK_UNFINISHED),
            Op::FaultPin,
            Op::Fdcan,
            Op::Mark(MARK_FAULT)
        ]
    );
    // Off the bus for ever; should the loop hang later, the watchdog's reset reads as one.
    let rsr = rsr::IWDG1RSTF | rsr::PINRSTF;
    assert_eq!(
        ResetReason::decode(rsr, hw.mark),
        ResetReason::IndependentWatchdog
    );
}

#[test]
fn a_lock_up_in_the_fdcan_step_leaves_its_mark_and_the_watchdog_reset_reads_nested() {
    let mut hw = Recorder {
        fdcan: FdcanStep::LockUp,
        ..Recorder::default()
    };
    let r = catch_unwind(AssertUnwindSafe(|| fail_safe(&mut hw, MARK_CLOCK)));
    assert!(r.is_err());
    // Everything that silences and reports came before the access that faulted.
    assert_eq!(
        hw.ops,
        [
            Op::TxRecessive,
            Op::Mark(MARK_CLOCK | MARK_UNFINISHED),
            Op::FaultPin
        ]
    );
    // The core locked up; the independent watchdog resets it; the start-up reads the mark.
    let rsr = rsr::IWDG1RSTF | rsr::PINRSTF;
    assert_eq!(ResetReason::decode(rsr, hw.mark), ResetReason::NestedFault);
}

#[test]
fn a_bus_fault_seen_in_the_fdcan_step_resets_at_once_as_a_nested_fault() {
    let mut hw = Recorder {
        fdcan: FdcanStep::FaultIgnored,
        ..Recorder::default()
    };
    let r = catch_unwind(AssertUnwindSafe(|| fail_safe(&mut hw, MARK_FAULT)));
    assert!(r.is_err());
    assert_eq!(
        hw.ops,
        [
            Op::TxRecessive,
            Op::Mark(MARK_FAULT | MARK_UNFINISHED),
            Op::FaultPin,
            Op::Fdcan,
            Op::Reset
        ]
    );
    let rsr = rsr::SFTRSTF | rsr::PINRSTF;
    assert_eq!(ResetReason::decode(rsr, hw.mark), ResetReason::NestedFault);
}
