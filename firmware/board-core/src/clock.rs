//! The system clock the silicon allows: 480 MHz needs voltage scale 0 (VOS0), which only the
//! STM32H743's revision V supports (`DBGMCU_IDC.REV_ID` = 0x2003); earlier revisions (Y:
//! 0x1003) run at most 400 MHz at VOS1. Decided from the revision read at start-up, before
//! the power and clock configuration.

/// `DBGMCU_IDC.REV_ID` of revision V.
pub const REV_V: u16 = 0x2003;

/// The voltage scale and system clock chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClockPlan {
    /// Voltage scale 0 (else 1).
    pub vos0: bool,
    /// System clock \[Hz\].
    pub sysclk_hz: u32,
}

impl ClockPlan {
    /// Revision V: VOS0, 480 MHz.
    pub const REV_V: ClockPlan = ClockPlan {
        vos0: true,
        sysclk_hz: 480_000_000,
    };
    /// Any other revision: VOS1, 400 MHz.
    pub const OTHER: ClockPlan = ClockPlan {
        vos0: false,
        sysclk_hz: 400_000_000,
    };

    /// The plan for the revision `rev_id` (`DBGMCU_IDC` bits 31:16).
    pub const fn for_revision(rev_id: u16) -> ClockPlan {
        if rev_id == REV_V {
            Self::REV_V
        } else {
            Self::OTHER
        }
    }

    /// `DBGMCU_IDC`'s `REV_ID` field.
    pub const fn rev_id(idc: u32) -> u16 {
        (idc >> 16) as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_revision_v_runs_480_mhz_at_vos0() {
        // DBGMCU_IDC of a revision V STM32H743: REV_ID 0x2003, DEV_ID 0x450.
        let v = ClockPlan::for_revision(ClockPlan::rev_id(0x2003_6450));
        assert_eq!(
            v,
            ClockPlan {
                vos0: true,
                sysclk_hz: 480_000_000
            }
        );
        for rev in [0x1003, 0x1001, 0x2001, 0x0000, 0xFFFF, 0x2004] {
            let p = ClockPlan::for_revision(rev);
            assert!(!p.vos0, "{rev:#x}");
            assert_eq!(p.sysclk_hz, 400_000_000, "{rev:#x}");
        }
    }
}
