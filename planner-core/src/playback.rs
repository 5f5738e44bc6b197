//! The timing rule of a replayed CAN log: which control cycle a logged frame is for.
//!
//! One definition for the two players of a candump log, `host-sim replay` (over host-sim's
//! virtual bus) and the QEMU image's (over its in-memory CAN device), so that the rule
//! cannot diverge between host and target:
//!
//! * times count from the start of the control cycle of the log's **first** frame, on the grid
//!   of the control period ([`LogClock::new`]);
//! * the node polls in the middle of each cycle (`k·dt + dt/2`, [`poll_ms`]); a frame logged at
//!   `t` is for the first poll at or after `t`: cycle `k = ⌈(t − dt/2) / dt⌉`, 0 if
//!   `t ≤ dt/2` ([`LogClock::cycle`]);
//! * the player runs until every frame has been fed and read by the node and the node stands
//!   still, from the cycle of the last frame on ([`finished`]), or for at most
//!   [`MAX_AFTER_US`] after the last frame's cycle ([`max_cycles`]).
//!
//! All arithmetic is in integer microseconds.

/// Longest replay after the cycle of the log's last frame \[µs\] (60 s).
pub const MAX_AFTER_US: u64 = 60_000_000;

/// The cycle grid of one log (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogClock {
    base_us: u64,
    period_us: u64,
}

impl LogClock {
    /// The grid of a log whose first frame is at `first_us`, for a control period of
    /// `period_us`; `None` if the period is below 2 µs.
    pub fn new(first_us: u64, period_us: u64) -> Option<Self> {
        if period_us < 2 {
            return None;
        }
        Some(Self {
            base_us: first_us - first_us % period_us,
            period_us,
        })
    }

    /// The start of cycle 0 \[µs, in the log's time\].
    pub fn base_us(&self) -> u64 {
        self.base_us
    }

    /// The control period \[µs\].
    pub fn period_us(&self) -> u64 {
        self.period_us
    }

    /// The cycle whose poll a frame logged at `t_us` is for (a time before cycle 0 is for
    /// cycle 0).
    pub fn cycle(&self, t_us: u64) -> u64 {
        let x = t_us.saturating_sub(self.base_us);
        let half = self.period_us / 2;
        if x <= half {
            0
        } else {
            (x - half).div_ceil(self.period_us)
        }
    }
}

/// The `now_ms` of the node's poll in cycle `k` (the middle of the cycle, rounded down).
pub fn poll_ms(k: u64, period_us: u64) -> u32 {
    ((k * period_us + period_us / 2) / 1000) as u32
}

/// Cycles a replay runs at most when its last frame is for cycle `last`.
pub fn max_cycles(last: u64, period_us: u64) -> u64 {
    last + MAX_AFTER_US.div_ceil(period_us.max(1))
}

/// Whether a replay ends after cycle `k`: every frame fed and read by the node (`idle`), the
/// node `standing`, and `k` at or after `last`, the cycle of the last frame.
pub fn finished(k: u64, last: u64, idle: bool, standing: bool) -> bool {
    k >= last && idle && standing
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_is_for_the_first_poll_at_or_after_it() {
        // 5 ms cycles; the first frame at 10.2 ms puts cycle 0 at 10 ms, its poll at 12.5 ms.
        let c = LogClock::new(10_200, 5_000).unwrap();
        assert_eq!(c.base_us(), 10_000);
        assert_eq!(c.cycle(12_500), 0);
        assert_eq!(c.cycle(12_501), 1);
        assert_eq!(c.cycle(17_500), 1);
        assert_eq!(c.cycle(23_000), 3);
        assert_eq!(c.cycle(9_000), 0);
        assert_eq!(poll_ms(0, 5_000), 2);
        assert_eq!(poll_ms(3, 5_000), 17);
        assert_eq!(max_cycles(10, 5_000), 12_010);
        assert!(LogClock::new(0, 1).is_none());
        assert!(finished(10, 10, true, true));
        assert!(!finished(9, 10, true, true));
        assert!(!finished(10, 10, false, true));
        assert!(!finished(10, 10, true, false));
    }
}
