//! The model's fault confinement (ISO 11898-1 as RM0433's FDCAN implements it): error
//! counters injected by a test, `PSR.EW`/`EP`/`BO` derived from them, bus-off setting `INIT`,
//! and the bus-off recovery that takes modelled bus time.
//!
//! RM0433 (FDCAN, "Bus-off recovery"; Bosch M_CAN user's manual, `CCCR.INIT`): after a
//! bus-off the core has set `INIT` itself; once software clears it, the core waits for 129
//! occurrences of bus idle (11 consecutive recessive bits), counting them in `ECR.REC` and
//! writing `PSR.LEC` = 5 (bit0 error) at each, and only then resets its error counters and is
//! error-active again. Until then it is bus-off: it neither receives nor sends. The sequence
//! cannot be shortened by setting or clearing `INIT` (the model restarts it at the next clear).

use super::*;

/// Recessive bit times a bus-off recovery takes at least: 129 × 11 (≈1.42 ms at 1 Mbit/s).
pub const RECOVERY_BITS: u32 = 129 * 11;

/// `ECR.RP`: the receive error counter reached the error-passive level (128).
const ECR_RP: u32 = 1 << 15;
/// `PSR.LEC` code 5: bit0 error (written at each 11 recessive bits of the recovery).
const LEC_BIT0: u32 = 5;

impl State {
    /// The error counters become `tec` and `rec` (ISO 11898-1 fault confinement): `ECR` (TEC
    /// 7:0, REC 14:8 up to 127, `RP` at 128 or more), `PSR.EW` (a counter at 96 or more),
    /// `PSR.EP` (a counter at 128 or more); a `tec` above 255 is a bus-off ([`State::bus_off`]).
    pub fn set_error_counters(&mut self, tec: u16, rec: u8) {
        if tec > 255 {
            self.bus_off();
            return;
        }
        self.ecr =
            u32::from(tec) | u32::from(rec.min(127)) << 8 | if rec >= 128 { ECR_RP } else { 0 };
        let (tec, rec) = (u32::from(tec), u32::from(rec));
        self.psr &= !(PSR_EW | PSR_EP);
        if tec >= 96 || rec >= 96 {
            self.psr |= PSR_EW;
        }
        if tec >= 128 || rec >= 128 {
            self.psr |= PSR_EP;
        }
    }

    /// The core goes bus-off (TEC above 255): `PSR.BO` with `EP` and `EW`, `ECR.TEC` at its
    /// limit, `CCCR.INIT` set by the core itself; any recovery under way is abandoned.
    pub fn bus_off(&mut self) {
        self.psr |= PSR_BO | PSR_EP | PSR_EW;
        self.ecr = (self.ecr & !0xFF) | 0xFF;
        self.regs[idx(CCCR)] |= INIT;
        self.pending_init = None;
        self.recovery = None;
    }

    /// `bits` bit times of recessive bus pass: a bus-off recovery under way (`INIT` cleared
    /// in bus-off) counts them; at [`RECOVERY_BITS`] the core resets its error counters and is
    /// error-active again.
    pub fn idle_bits(&mut self, bits: u32) {
        let Some(counted) = self.recovery else {
            return;
        };
        if self.in_init() {
            return;
        }
        let counted = counted.saturating_add(bits);
        let sequences = counted / 11;
        if sequences > 0 {
            self.psr = (self.psr & !PSR_LEC) | LEC_BIT0;
        }
        if counted >= RECOVERY_BITS {
            self.recovery = None;
            self.psr &= !(PSR_BO | PSR_EP | PSR_EW);
            self.ecr = 0;
        } else {
            self.recovery = Some(counted);
            // REC counts the sequences (7 bits).
            self.ecr = (self.ecr & !(0x7F << 8)) | (sequences.min(127) << 8);
        }
    }

    /// A bus-off recovery is under way (`INIT` cleared, the recessive bits not all counted).
    pub fn recovering(&self) -> bool {
        self.recovery.is_some() && !self.in_init()
    }
}
