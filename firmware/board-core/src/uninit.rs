//! The no-init RAM words (`.uninit`: the fault handler's reset mark, the brown-out attempt
//! mark, the logger's ring) on ECC RAM.
//!
//! The STM32H743's DTCM and SRAMs have ECC: after a power-on (or a brown-out) a word holds no
//! valid code until it is written, and a read of it may report an ECC error (a bus fault).
//! So the start-up writes every no-init word before anything reads it whenever `RCC_RSR` says
//! the supply went away ([`power_lost`]); after any other reset (pin, software, watchdog)
//! the words keep what was written before it, which is what they are for.

use crate::reset::rsr::{BORRSTF, PORRSTF};

/// `true` if the reset that started the MCU followed a loss of supply (`RCC_RSR.PORRSTF` or
/// `BORRSTF`): the no-init words hold no valid data (and maybe no valid ECC) then.
pub const fn power_lost(rsr: u32) -> bool {
    rsr & (PORRSTF | BORRSTF) != 0
}

/// One no-init word.
pub trait NoInitWord {
    /// Reads the word.
    fn read(&self) -> u32;
    /// Writes the word.
    fn write(&mut self, value: u32);
}

/// Makes `word` safe to read: written 0 if the supply was lost ([`power_lost`]); untouched
/// otherwise.
pub fn prepare<W: NoInitWord>(word: &mut W, rsr: u32) {
    if power_lost(rsr) {
        word.write(0);
    }
}

/// The word's value since the last reset (0 after a loss of supply, never read then), left
/// 0.
pub fn take<W: NoInitWord>(word: &mut W, rsr: u32) -> u32 {
    prepare(word, rsr);
    let value = word.read();
    word.write(0);
    value
}
