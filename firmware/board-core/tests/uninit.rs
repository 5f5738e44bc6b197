//! The no-init words on ECC RAM (`board_core::uninit`): written before any read after a loss
//! of supply, kept through every other reset.

use board_core::reset::rsr::{BORRSTF, IWDG1RSTF, PINRSTF, PORRSTF, SFTRSTF};
use board_core::reset::{ResetReason, MARK_CLOCK};
use board_core::uninit::{power_lost, prepare, take, NoInitWord};

/// A word of ECC RAM: `None` until written; reading it then is an ECC error (a panic here).
struct EccWord(Option<u32>);

impl NoInitWord for EccWord {
    fn read(&self) -> u32 {
        self.0.expect("read of an unwritten ECC word")
    }
    fn write(&mut self, value: u32) {
        self.0 = Some(value);
    }
}

#[test]
fn power_on_and_brown_out_count_as_a_loss_of_supply() {
    assert!(power_lost(PORRSTF | BORRSTF | PINRSTF));
    assert!(power_lost(BORRSTF | PINRSTF));
    assert!(!power_lost(SFTRSTF | PINRSTF));
    assert!(!power_lost(IWDG1RSTF | PINRSTF));
    assert!(!power_lost(PINRSTF));
}

#[test]
fn after_a_power_on_the_mark_is_written_before_it_is_read() {
    // Unwritten ECC RAM after a power-on: `take` does not read it first.
    let mut w = EccWord(None);
    let rsr = PORRSTF | BORRSTF | PINRSTF;
    assert_eq!(take(&mut w, rsr), 0);
    assert_eq!(w.0, Some(0));
    // A word read later (the BOR mark): prepared, then readable.
    let mut bor = EccWord(None);
    prepare(&mut bor, BORRSTF | PINRSTF);
    assert_eq!(bor.read(), 0);
}

#[test]
fn after_a_software_reset_the_mark_is_kept_read_and_cleared() {
    // The fault handler left the clock-failure mark before its reset.
    let mut w = EccWord(Some(MARK_CLOCK));
    let rsr = SFTRSTF | PINRSTF;
    let mark = take(&mut w, rsr);
    assert_eq!(ResetReason::decode(rsr, mark), ResetReason::ClockFailure);
    assert_eq!(w.0, Some(0));
    // Untouched by `prepare` when the supply stayed.
    let mut kept = EccWord(Some(7));
    prepare(&mut kept, IWDG1RSTF | PINRSTF);
    assert_eq!(kept.0, Some(7));
}

#[test]
fn an_unwritten_word_read_without_the_rule_is_an_ecc_error() {
    // What the rule prevents: a read first.
    let w = EccWord(None);
    assert!(std::panic::catch_unwind(|| w.read()).is_err());
}
