//! The order of the safe state: what the fault handlers do, step by step, over a small trait
//! of the hardware ([`SafeStateHw`]), so that the order is written once and host-tested.
//!
//! 1. **the CAN TX pin recessive, as a GPIO** ([`SafeStateHw::can_tx_recessive`]: on the
//!    board PD1, FDCAN1's TX, taken from its alternate function as a push-pull output driven
//!    high). This needs only the GPIO port, so it silences the node even when the FDCAN
//!    cannot be reached: after a clock-security failure its kernel clock (PLL1Q) is gone and
//!    an `INIT` or `TXBCR` write never takes effect;
//! 2. **the reset mark** ([`SafeStateHw::write_mark`]: one no-init RAM word saying why),
//!    with [`MARK_UNFINISHED`] added;
//! 3. **the fault pin** high ([`SafeStateHw::raise_fault_pin`]);
//! 4. only then **the FDCAN** ([`SafeStateHw::silence_fdcan`]: `CCCR.INIT`, every TX request
//!    cancelled): if an access to it faults again, the output is already recessive, the mark
//!    written and the pin high. Only when the step ends cleanly is the mark rewritten without
//!    [`MARK_UNFINISHED`]. A second fault there thus always ends in a reset whose reason says
//!    so ([`crate::ResetReason::NestedFault`]): the board ignores a data bus fault in this
//!    step (it runs at fault priority with `CCR.BFHFNMIGN`), notices it and resets at once
//!    with the flag kept; any other fault there locks the core up until the independent
//!    watchdog resets it, and the flag, still in the mark, turns that watchdog reset into a
//!    nested fault;
//! 5. **a reset at once** ([`SafeStateHw::reset`], [`fail_safe`] only): no hold delay, so that
//!    after a clock-security failure (the core on the 64 MHz HSI) the reset comes from the
//!    handler, long before the independent watchdog, and the reason reads as what it was.
//!
//! [`signal`] runs steps 1-4 (the board's "off the bus" state also uses it, without the
//! reset); [`fail_safe`] all five.

use crate::reset::MARK_UNFINISHED;

/// The safe state's hardware operations, in the order [`signal`] calls them.
pub trait SafeStateHw {
    /// Takes the CAN TX pin from the FDCAN: a push-pull output driven recessive (high).
    fn can_tx_recessive(&mut self);
    /// Writes `mark` into the no-init word the next start-up reads.
    fn write_mark(&mut self, mark: u32);
    /// Drives the fault pin high.
    fn raise_fault_pin(&mut self);
    /// Puts the FDCAN into its initialisation state and cancels every TX request; `true` if
    /// that ended without a fault (a board that survives a bus fault here returns `false`
    /// when it saw one, or when the FDCAN did not answer).
    fn silence_fdcan(&mut self) -> bool;
    /// Resets the MCU (never returns).
    fn reset(&mut self) -> !;
}

/// Steps 1-4 of the safe state (see the [module docs](self)): the TX pin recessive, the mark
/// (flagged [`MARK_UNFINISHED`]), the fault pin, then the FDCAN, and the mark unflagged if
/// that ended cleanly.
pub fn signal<H: SafeStateHw>(hw: &mut H, mark: u32) {
    hw.can_tx_recessive();
    hw.write_mark(mark | MARK_UNFINISHED);
    hw.raise_fault_pin();
    if hw.silence_fdcan() {
        hw.write_mark(mark);
    }
}

/// The whole safe state: [`signal`], then a reset at once.
pub fn fail_safe<H: SafeStateHw>(hw: &mut H, mark: u32) -> ! {
    signal(hw, mark);
    hw.reset()
}
