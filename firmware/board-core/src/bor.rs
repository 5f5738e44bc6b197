//! The brown-out level's option-byte change, without the hardware: whether to start it
//! ([`plan`]), what `FLASH_OPTSR_CUR` says after it ([`outcome`]), and the no-init word that
//! remembers an attempt across resets ([`attempt_mark`], [`failure_mark`]), so that a change
//! that failed or was interrupted is not tried again at every boot, only after a power-on.
//!
//! The board (`firmware/board/src/hw.rs`) runs the change before the independent watchdog
//! starts: an option-byte change stalls the core for a long time (~300 ms reported on an
//! STM32H743), and ST warns against interrupting one.

/// `FLASH_OPTSR_CUR` / `FLASH_OPTSR_PRG` fields (RM0433 §4.9.8).
pub mod optsr {
    /// An option-byte change is in progress.
    pub const OPT_BUSY: u32 = 1 << 0;
    /// The brown-out level, bits 3:2.
    pub const BOR_LEV_SHIFT: u32 = 2;
    /// The last option-byte change failed.
    pub const OPTCHANGEERR: u32 = 1 << 30;
}

/// The brown-out level (0-3) of an `OPTSR` value.
pub const fn level(optsr: u32) -> u8 {
    ((optsr >> optsr::BOR_LEV_SHIFT) & 3) as u8
}

/// Why a change of the brown-out level did not take effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BorFailure {
    /// A reset came during the change (the mark of the attempt was still there at boot).
    Interrupted = 1,
    /// `OPT_BUSY` did not clear within the bounded wait.
    Timeout = 2,
    /// `OPTCHANGEERR` was set after the change.
    ChangeError = 3,
    /// The change completed without an error, but `BOR_LEV` reads another level.
    NotApplied = 4,
}

impl BorFailure {
    fn from_code(code: u32) -> Option<Self> {
        match code {
            1 => Some(Self::Interrupted),
            2 => Some(Self::Timeout),
            3 => Some(Self::ChangeError),
            4 => Some(Self::NotApplied),
            _ => None,
        }
    }

    /// A short description for a log line.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Interrupted => "interrupted by a reset",
            Self::Timeout => "OPT_BUSY did not clear",
            Self::ChangeError => "OPTCHANGEERR",
            Self::NotApplied => "BOR_LEV unchanged",
        }
    }
}

/// What the start-up does about the brown-out level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BorPlan {
    /// The level is already the wanted one.
    Keep,
    /// Program the option byte (mark the attempt first).
    Program,
    /// An earlier attempt since the last power-on failed: do not try again, run at the
    /// current level.
    GiveUp(BorFailure),
}

/// What happened to the brown-out level at this start-up (for the log).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BorStatus {
    /// Already at the wanted level.
    Kept,
    /// Programmed now.
    Programmed,
    /// Programming failed now; the current level stays (not tried again until a power-on).
    Failed(BorFailure),
    /// Not tried: an earlier attempt since the power-on failed.
    NotRetried(BorFailure),
}

impl BorStatus {
    /// A suffix for the start-up log line ("" when nothing happened).
    pub const fn note(self) -> &'static str {
        match self {
            Self::Kept => "",
            Self::Programmed => " (programmed now)",
            Self::Failed(_) => " (programming FAILED now: current level kept)",
            Self::NotRetried(_) => " (an earlier attempt failed: not retried until power-on)",
        }
    }

    /// The failure, if any.
    pub const fn failure(self) -> Option<BorFailure> {
        match self {
            Self::Failed(f) | Self::NotRetried(f) => Some(f),
            Self::Kept | Self::Programmed => None,
        }
    }
}

/// The mark's fixed upper half (the fault handler's are `0xFA17_xxxx`).
const MAGIC: u32 = 0xB0C5_0000;
/// Mark state: an attempt was started.
const ATTEMPT: u32 = 0;

/// The no-init word written before the change is started: level `wanted` being programmed.
pub const fn attempt_mark(wanted: u8) -> u32 {
    MAGIC | (ATTEMPT << 8) | (wanted & 3) as u32
}

/// The no-init word after a failed attempt at level `wanted`.
pub const fn failure_mark(wanted: u8, why: BorFailure) -> u32 {
    MAGIC | ((why as u32) << 8) | (wanted & 3) as u32
}

/// Whether to program level `wanted`, given the level `current` in force and the no-init
/// `mark` (garbage after a power-on: only a mark of this module for `wanted` counts).
pub fn plan(current: u8, wanted: u8, mark: u32) -> BorPlan {
    let wanted = wanted & 3;
    if current == wanted {
        return BorPlan::Keep;
    }
    if mark & 0xFFFF_0000 != MAGIC || mark & 0xFF != u32::from(wanted) {
        return BorPlan::Program;
    }
    match (mark >> 8) & 0xFF {
        ATTEMPT => BorPlan::GiveUp(BorFailure::Interrupted),
        code => match BorFailure::from_code(code) {
            Some(f) => BorPlan::GiveUp(f),
            None => BorPlan::Program,
        },
    }
}

/// The result of a change to level `wanted`, from `FLASH_OPTSR_CUR` read after the wait
/// (`timed_out`: `OPT_BUSY` was still set when the wait ended).
pub fn outcome(optsr_cur: u32, timed_out: bool, wanted: u8) -> Result<(), BorFailure> {
    if timed_out || optsr_cur & optsr::OPT_BUSY != 0 {
        Err(BorFailure::Timeout)
    } else if optsr_cur & optsr::OPTCHANGEERR != 0 {
        Err(BorFailure::ChangeError)
    } else if level(optsr_cur) != wanted & 3 {
        Err(BorFailure::NotApplied)
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_in_force_is_kept_whatever_the_mark() {
        for mark in [
            0,
            0xDEAD_BEEF,
            attempt_mark(3),
            failure_mark(3, BorFailure::Timeout),
        ] {
            assert_eq!(plan(3, 3, mark), BorPlan::Keep);
        }
    }

    #[test]
    fn a_power_on_programs_and_a_failed_or_interrupted_attempt_is_not_repeated() {
        // Garbage (a power-on), another module's mark, another level's mark: program.
        for mark in [0, 0xDEAD_BEEF, 0xFA17_0001, attempt_mark(2), 0xB0C5_7703] {
            assert_eq!(plan(0, 3, mark), BorPlan::Program, "{mark:#x}");
        }
        // A reset during the change leaves the attempt's mark.
        assert_eq!(
            plan(0, 3, attempt_mark(3)),
            BorPlan::GiveUp(BorFailure::Interrupted)
        );
        for f in [
            BorFailure::Interrupted,
            BorFailure::Timeout,
            BorFailure::ChangeError,
            BorFailure::NotApplied,
        ] {
            assert_eq!(plan(1, 3, failure_mark(3, f)), BorPlan::GiveUp(f));
        }
    }

    #[test]
    fn the_outcome_checks_busy_optchangeerr_and_the_level() {
        let at = |l: u32| l << optsr::BOR_LEV_SHIFT;
        assert_eq!(outcome(at(3), false, 3), Ok(()));
        assert_eq!(outcome(at(3), true, 3), Err(BorFailure::Timeout));
        assert_eq!(
            outcome(at(3) | optsr::OPT_BUSY, false, 3),
            Err(BorFailure::Timeout)
        );
        assert_eq!(
            outcome(at(3) | optsr::OPTCHANGEERR, false, 3),
            Err(BorFailure::ChangeError)
        );
        assert_eq!(outcome(at(1), false, 3), Err(BorFailure::NotApplied));
        assert_eq!(level(at(2) | 0xFFFF_FFF3), 2);
    }
}
