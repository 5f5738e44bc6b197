//! Why the MCU started: the reset flags of `RCC_RSR` (RM0433 §8.7.37) and the board's own
//! mark for a reset by its fault handler.

/// Reset reason, as published (4 bits in `LINK`).
///
/// The mark is read only after a reset that kept RAM: after a power-on or a brown-out the
/// start-up writes it before any read ([`crate::uninit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResetReason {
    /// No flag the board knows (or flags not read yet).
    Unknown = 0,
    /// Power-on (POR/PDR).
    PowerOn = 1,
    /// The NRST pin (a reset button, a probe).
    Pin = 2,
    /// Brown-out (supply below the BOR level) without a power-on.
    BrownOut = 3,
    /// Software reset (`SYSRESETREQ`) not from the fault handler: e.g. a probe's reset.
    Software = 4,
    /// The independent watchdog (a hung loop).
    IndependentWatchdog = 5,
    /// The window watchdog.
    WindowWatchdog = 6,
    /// The fault handler (HardFault, panic) reset the MCU after silencing the CAN output.
    Fault = 7,
    /// The clock security system saw the HSE fail (NMI); the fault handler reset the MCU.
    ClockFailure = 8,
    /// A low-power reset (illegal Stop/Standby entry).
    LowPower = 9,
    /// The HSE did not become ready at start-up within its bound; the start-up reset the MCU
    /// with the fault pin raised (instead of waiting until the watchdog bites).
    HseNotReady = 10,
    /// A second fault inside the fault path, after its first steps (the CAN TX pin
    /// recessive, the mark, the fault pin) and before its FDCAN step had ended: either the
    /// handler saw a bus fault of that step (ignored at fault priority) and reset the MCU, or
    /// the core locked up there and the independent watchdog reset it. The mark
    /// ([`MARK_UNFINISHED`]) tells both apart from a plain fault or a plain watchdog reset.
    NestedFault = 11,
}

/// `RCC_RSR` flags.
pub mod rsr {
    /// Low-power reset.
    pub const LPWRRSTF: u32 = 1 << 30;
    /// Window watchdog 1.
    pub const WWDG1RSTF: u32 = 1 << 28;
    /// Independent watchdog 1.
    pub const IWDG1RSTF: u32 = 1 << 26;
    /// Software reset (CPU1).
    pub const SFTRSTF: u32 = 1 << 24;
    /// Power-on / power-down reset.
    pub const PORRSTF: u32 = 1 << 23;
    /// NRST pin.
    pub const PINRSTF: u32 = 1 << 22;
    /// Brown-out reset.
    pub const BORRSTF: u32 = 1 << 21;
}

/// What the fault handler leaves in its no-init word before a reset (`0xFA17_xxxx`: the low
/// half says which fault).
pub const FAULT_MARK: u32 = 0xFA17_0000;
/// [`FAULT_MARK`] for a HardFault or a panic.
pub const MARK_FAULT: u32 = FAULT_MARK | 1;
/// [`FAULT_MARK`] for a clock failure (CSS NMI).
pub const MARK_CLOCK: u32 = FAULT_MARK | 2;
/// [`FAULT_MARK`] for an HSE that did not become ready at start-up.
pub const MARK_HSE: u32 = FAULT_MARK | 3;
/// Added to the mark from the fault path's second step until its FDCAN step has ended
/// cleanly (`crate::safe_state`): a reset that finds it (the handler's, or the watchdog's
/// after a lock-up) reads as [`ResetReason::NestedFault`].
pub const MARK_UNFINISHED: u32 = 0x0100;

/// `mark` is one of the fault path's marks with [`MARK_UNFINISHED`].
const fn unfinished(mark: u32) -> bool {
    let cause = mark & !MARK_UNFINISHED;
    mark & MARK_UNFINISHED != 0 && (cause == MARK_FAULT || cause == MARK_CLOCK || cause == MARK_HSE)
}

impl ResetReason {
    /// Every reason, in the order of its code (the `reset` value table of `LINK` in
    /// host-sim/can/walking.dbc is checked against it).
    pub const ALL: [ResetReason; 12] = [
        Self::Unknown,
        Self::PowerOn,
        Self::Pin,
        Self::BrownOut,
        Self::Software,
        Self::IndependentWatchdog,
        Self::WindowWatchdog,
        Self::Fault,
        Self::ClockFailure,
        Self::LowPower,
        Self::HseNotReady,
        Self::NestedFault,
    ];

    /// The reason from `RCC_RSR` and the fault handler's `mark` (the no-init word, garbage
    /// after a power-on). The watchdogs come first (a pin reset flag accompanies every reset
    /// on the STM32H7: the reset circuit drives NRST), then a software reset marked by the
    /// fault handler, power-on, brown-out, software, pin. A watchdog or software reset whose
    /// mark says the fault path did not finish its FDCAN step is a nested fault.
    pub fn decode(rsr: u32, mark: u32) -> Self {
        use rsr::*;
        let nested = unfinished(mark) && rsr & (PORRSTF | BORRSTF) == 0;
        if rsr & (IWDG1RSTF | SFTRSTF) != 0 && nested {
            Self::NestedFault
        } else if rsr & IWDG1RSTF != 0 {
            Self::IndependentWatchdog
        } else if rsr & WWDG1RSTF != 0 {
            Self::WindowWatchdog
        } else if rsr & LPWRRSTF != 0 {
            Self::LowPower
        } else if rsr & PORRSTF != 0 {
            Self::PowerOn
        } else if rsr & SFTRSTF != 0 && mark == MARK_FAULT {
            Self::Fault
        } else if rsr & SFTRSTF != 0 && mark == MARK_CLOCK {
            Self::ClockFailure
        } else if rsr & SFTRSTF != 0 && mark == MARK_HSE {
            Self::HseNotReady
        } else if rsr & BORRSTF != 0 {
            Self::BrownOut
        } else if rsr & SFTRSTF != 0 {
            Self::Software
        } else if rsr & PINRSTF != 0 {
            Self::Pin
        } else {
            Self::Unknown
        }
    }
}

#[cfg(test)]
mod tests {
    use super::rsr::*;
    use super::*;

    #[test]
    fn each_reset_is_told_apart() {
        let cases = [
            (PORRSTF | BORRSTF | PINRSTF, 0x1234, ResetReason::PowerOn),
            (BORRSTF | PINRSTF, 0, ResetReason::BrownOut),
            (PINRSTF, MARK_FAULT, ResetReason::Pin),
            (SFTRSTF | PINRSTF, 0, ResetReason::Software),
            (SFTRSTF | PINRSTF, MARK_FAULT, ResetReason::Fault),
            (SFTRSTF | PINRSTF, MARK_CLOCK, ResetReason::ClockFailure),
            (SFTRSTF | PINRSTF, MARK_HSE, ResetReason::HseNotReady),
            (
                IWDG1RSTF | PINRSTF,
                MARK_FAULT,
                ResetReason::IndependentWatchdog,
            ),
            (WWDG1RSTF | PINRSTF, 0, ResetReason::WindowWatchdog),
            (LPWRRSTF | PINRSTF, 0, ResetReason::LowPower),
            (0, 0, ResetReason::Unknown),
            // The fault path did not end its FDCAN step: locked up (the watchdog) or a bus
            // fault there seen and ignored (the handler's reset).
            (
                IWDG1RSTF | PINRSTF,
                MARK_FAULT | MARK_UNFINISHED,
                ResetReason::NestedFault,
            ),
            (
                IWDG1RSTF | PINRSTF,
                MARK_CLOCK | MARK_UNFINISHED,
                ResetReason::NestedFault,
            ),
            (
                SFTRSTF | PINRSTF,
                MARK_FAULT | MARK_UNFINISHED,
                ResetReason::NestedFault,
            ),
            // The flag on anything but a fault mark is not one; a pin reset stays a pin reset.
            (
                IWDG1RSTF | PINRSTF,
                MARK_UNFINISHED,
                ResetReason::IndependentWatchdog,
            ),
            (
                IWDG1RSTF | PINRSTF,
                0x1234_0101,
                ResetReason::IndependentWatchdog,
            ),
            (PINRSTF, MARK_FAULT | MARK_UNFINISHED, ResetReason::Pin),
        ];
        for (rsr, mark, want) in cases {
            assert_eq!(
                ResetReason::decode(rsr, mark),
                want,
                "rsr {rsr:#x} mark {mark:#x}"
            );
        }
        for (code, r) in ResetReason::ALL.iter().enumerate() {
            assert_eq!(*r as usize, code);
        }
        // A power-on leaves garbage in the mark's word: never read as a fault.
        assert_eq!(
            ResetReason::decode(PORRSTF | SFTRSTF, MARK_FAULT),
            ResetReason::PowerOn
        );
    }
}
