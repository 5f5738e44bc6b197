//! The QEMU image's hardware behind board-core's control-cycle traits
//! (`board_core::control`), so that the image runs the board's own cycle (`ControlLoop`)
//! around every replayed poll:
//!
//! * [`ReplayClock`]: the microseconds of the CMSDK timer (25 ticks per µs of QEMU's virtual
//!   time, i.e. 1,000 instructions per µs under `-icount shift=0`) plus the idle time the
//!   waits skip: the board spins until its next slot, the image jumps there
//!   ([`MicrosClock::idle_until`]), so that a replay does not execute 5 ms of spinning per
//!   cycle;
//! * [`Instructions`]: the poll's timer, the CMSDK timer in instructions (40 per tick);
//! * [`CountingWatchdog`], [`CountingBusy`], [`CountingLog`]: the feeds, the busy pulses and
//!   the log lines the cycle asks for, counted (reported in the `BOARD` line).

use board_core::control::{BusyPin, CycleCounter, LogSink, MicrosClock, SummaryLine, Watchdog};
use board_core::Slot;

use crate::hw::{Timer0, TIMER_HZ};

/// Timer ticks per microsecond.
const TICKS_PER_US: u64 = TIMER_HZ as u64 / 1_000_000;
/// Instructions per timer tick under `-icount shift=0` (1 ns per instruction).
pub const INSTRUCTIONS_PER_TICK: u32 = 1_000_000_000 / TIMER_HZ;

/// Microseconds of virtual time, idle waits skipped (module docs).
pub struct ReplayClock<'a> {
    timer: &'a Timer0,
    last: u32,
    ticks: u64,
    skipped_us: u64,
}

impl<'a> ReplayClock<'a> {
    /// From the timer's present count.
    pub fn new(timer: &'a Timer0) -> Self {
        Self {
            timer,
            last: timer.count(),
            ticks: 0,
            skipped_us: 0,
        }
    }

    fn us(&mut self) -> u64 {
        let now = self.timer.count();
        self.ticks += u64::from(now.wrapping_sub(self.last));
        self.last = now;
        self.ticks / TICKS_PER_US + self.skipped_us
    }
}

impl MicrosClock for ReplayClock<'_> {
    fn now_us(&mut self) -> u32 {
        self.us() as u32
    }
    fn idle_until(&mut self, at_us: u32) {
        let now = self.us();
        let ahead = at_us.wrapping_sub(now as u32);
        if ahead < 1 << 31 {
            self.skipped_us += u64::from(ahead);
        }
    }
}

/// The CMSDK timer in instructions (wrapping; only differences are used).
pub struct Instructions<'a>(pub &'a Timer0);

impl CycleCounter for Instructions<'_> {
    fn cycles(&mut self) -> u32 {
        self.0.count().wrapping_mul(INSTRUCTIONS_PER_TICK)
    }
}

/// Counts the feeds.
#[derive(Default)]
pub struct CountingWatchdog {
    /// Feeds so far.
    pub feeds: u32,
}

impl Watchdog for CountingWatchdog {
    fn feed(&mut self) {
        self.feeds += 1;
    }
}

/// Counts the busy pulses (rising edges); `high` is the pin's level.
#[derive(Default)]
pub struct CountingBusy {
    /// Rising edges so far.
    pub pulses: u32,
    /// The level.
    pub high: bool,
}

impl BusyPin for CountingBusy {
    fn set_busy(&mut self, busy: bool) {
        if busy && !self.high {
            self.pulses += 1;
        }
        self.high = busy;
    }
}

/// Counts the log lines the cycle asks for (the board's would go to defmt).
#[derive(Default)]
pub struct CountingLog {
    /// "slot(s) missed" warnings.
    pub missed: u32,
    /// "overrun" warnings.
    pub overruns: u32,
    /// "commands refused" warnings.
    pub refused: u32,
    /// Summaries.
    pub summaries: u32,
    /// The worst poll of any summary's window \[instructions\].
    pub worst: u32,
}

impl LogSink for CountingLog {
    fn missed_slots(&mut self, _slot: &Slot, _total: u32) {
        self.missed += 1;
    }
    fn overrun(&mut self, _cycle: u32, _spent: u32, _period: u32, _total: u32) {
        self.overruns += 1;
    }
    fn refused(&mut self, _cycle: u32, _refused: u8, _received: u8) {
        self.refused += 1;
    }
    fn summary(&mut self, line: &SummaryLine) {
        self.summaries += 1;
        self.worst = self.worst.max(line.window.worst);
    }
}
