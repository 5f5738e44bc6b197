//! The 5 ms slots of the control loop, from a free-running 32-bit counter.
//!
//! The board's TIM2 counts microseconds from 0 to `u32::MAX` and wraps (every ~71.6 min); the
//! pacer only takes differences (`wrapping_sub`), so the wrap is invisible as long as
//! [`Pacer::due`] is called at least once per 2^31 ticks. Slot `k` begins at `start + k ·
//! period`. When the loop comes back after slot `k + 1` has already ended (a cycle that
//! overran by more than a period), the slots it missed are **counted and skipped**, so the
//! next poll runs in the slot that is current and its `now_ms` is that slot's time: `now_ms`
//! never lags the counter by a period or more, and the time lost is visible
//! ([`Pacer::missed`]).

/// A slot that has begun.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    /// Index of the slot since the start (wrapping).
    pub index: u32,
    /// The slot's start in milliseconds since the pacer started (wrapping; plus
    /// [`Pacer::with_first_ms`]'s offset): the `now_ms` of the poll.
    pub now_ms: u32,
    /// Slots skipped right before this one (0 when on time).
    pub skipped: u32,
    /// Counter ticks since the slot began (how late the loop noticed it).
    pub late_ticks: u32,
}

/// Slots of `period` counter ticks, `ms_per_slot` milliseconds each.
#[derive(Clone, Copy, Debug)]
pub struct Pacer {
    period: u32,
    ms_per_slot: u32,
    /// `now_ms` of slot 0.
    first_ms: u32,
    /// Counter value at which the next slot begins.
    next: u32,
    /// Index of the next slot.
    index: u32,
    missed: u32,
}

impl Pacer {
    /// Slot 0 begins at counter value `start`. `period` is at least 1 tick and below 2^31.
    pub fn new(start: u32, period: u32, ms_per_slot: u32) -> Self {
        Self {
            period: period.clamp(1, 1 << 30),
            ms_per_slot,
            first_ms: 0,
            next: start,
            index: 0,
            missed: 0,
        }
    }

    /// The same slots with `first_ms` as slot 0's `now_ms` (instead of 0): slot `k` is at
    /// `first_ms + k · ms_per_slot` (wrapping). The QEMU image replays a log on its grid.
    pub fn with_first_ms(mut self, first_ms: u32) -> Self {
        self.first_ms = first_ms;
        self
    }

    /// Counter value at which the next slot begins.
    pub fn next_start(&self) -> u32 {
        self.next
    }

    /// The slot that has begun at counter value `now`, if the next one has: `None` while it
    /// is still ahead (wait and call again).
    pub fn due(&mut self, now: u32) -> Option<Slot> {
        let late = now.wrapping_sub(self.next);
        if late >= 1 << 31 {
            return None; // `next` is still ahead of `now`
        }
        let skipped = late / self.period;
        self.missed = self.missed.saturating_add(skipped);
        let index = self.index.wrapping_add(skipped);
        let begun = self.next.wrapping_add(skipped.wrapping_mul(self.period));
        self.index = index.wrapping_add(1);
        self.next = begun.wrapping_add(self.period);
        Some(Slot {
            index,
            now_ms: self
                .first_ms
                .wrapping_add(index.wrapping_mul(self.ms_per_slot)),
            skipped,
            late_ticks: now.wrapping_sub(begun),
        })
    }

    /// `true` if the slot after the current one has already begun at `now` (the cycle that
    /// just ran is late).
    pub fn behind(&self, now: u32) -> bool {
        now.wrapping_sub(self.next) < 1 << 31
    }

    /// Slots skipped since the start (saturating).
    pub fn missed(&self) -> u32 {
        self.missed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_time_slots_advance_by_one_period() {
        let mut p = Pacer::new(1000, 5000, 5);
        assert_eq!(p.due(999), None);
        let s = p.due(1000).unwrap();
        assert_eq!((s.index, s.now_ms, s.skipped, s.late_ticks), (0, 0, 0, 0));
        assert_eq!(p.due(5999), None);
        assert!(!p.behind(5999));
        let s = p.due(6003).unwrap();
        assert_eq!((s.index, s.now_ms, s.skipped, s.late_ticks), (1, 5, 0, 3));
        assert_eq!(p.missed(), 0);
    }

    #[test]
    fn an_overrun_of_several_periods_counts_and_skips_the_missed_slots() {
        let mut p = Pacer::new(0, 5000, 5);
        p.due(0).unwrap();
        // The cycle of slot 0 ran until 17,500 µs: slots 1 and 2 are over, 3 has begun.
        assert!(p.behind(17_500));
        let s = p.due(17_500).unwrap();
        assert_eq!((s.index, s.now_ms, s.skipped), (3, 15, 2));
        assert_eq!(s.late_ticks, 2_500);
        assert_eq!(p.missed(), 2);
        // Back on the grid: slot 4 at 20,000 µs.
        assert_eq!(p.due(19_999), None);
        assert_eq!(p.due(20_000).unwrap().index, 4);
    }

    #[test]
    fn first_ms_offsets_every_slot_and_next_start_is_the_next_slot() {
        let mut p = Pacer::new(0, 5000, 5).with_first_ms(2);
        assert_eq!(p.next_start(), 0);
        assert_eq!(p.due(0).unwrap().now_ms, 2);
        assert_eq!(p.next_start(), 5000);
        assert_eq!(p.due(5000).unwrap().now_ms, 7);
        let s = p.due(21_000).unwrap(); // slots 2 and 3 are over, 4 has begun
        assert_eq!((s.index, s.now_ms, s.skipped), (4, 22, 2));
        assert_eq!(p.next_start(), 25_000);
    }

    #[test]
    fn the_counter_wrap_is_invisible() {
        let start = u32::MAX - 7_000;
        let mut p = Pacer::new(start, 5000, 5);
        p.due(start).unwrap();
        assert_eq!(p.due(u32::MAX - 2_001), None);
        let s = p.due(u32::MAX - 1_999).unwrap(); // start + 5,001
        assert_eq!((s.index, s.now_ms, s.skipped, s.late_ticks), (1, 5, 0, 1));
        let s = p.due(3_000).unwrap(); // start + 10,001 across the wrap
        assert_eq!((s.index, s.now_ms, s.skipped, s.late_ticks), (2, 10, 0, 1));
    }

    #[test]
    fn now_ms_never_lags_the_counter_by_a_period() {
        let mut p = Pacer::new(0, 5000, 5);
        let mut now = 0u32;
        // Irregular lateness, some of it several periods.
        for (i, extra) in [0u32, 3, 4_999, 12_345, 1, 40_000, 7]
            .iter()
            .cycle()
            .take(200)
            .enumerate()
        {
            let s = loop {
                if let Some(s) = p.due(now) {
                    break s;
                }
                now += 1;
            };
            let wall_ms = now / 1000;
            assert!(
                wall_ms >= s.now_ms && wall_ms - s.now_ms < 5,
                "slot {i}: {s:?} at {now}"
            );
            now += extra;
        }
        assert!(p.missed() > 0);
    }
}
