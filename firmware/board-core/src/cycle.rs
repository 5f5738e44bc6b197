//! The bookkeeping of one control cycle: overruns (counted and reported to the node, which
//! publishes them in its status) and the statistics window summarised once per second.
//!
//! Owns [`Stats`] (with [`Stats::record`] and its [`Outcome`]), the window's [`Summary`] and
//! its length [`SUMMARY_EVERY`]. It tells the node of a late cycle through the node's
//! contract ([`ControlNode`], in [`crate::node`]) and depends on nothing else of the crate:
//! the board's control cycle (`crate::control`), which the board image, the link-time
//! no-panic check (`firmware/nopanic`) and the QEMU image all run, uses it, not the other way
//! round. Host-tested (`tests/cycle.rs`).

use planner_core::node::PollReport;

use crate::node::ControlNode;

/// Cycles per summary (1 s at 5 ms).
pub const SUMMARY_EVERY: u32 = 200;

/// What the statistics window gathered since the last summary.
#[derive(Clone, Copy, Debug, Default)]
pub struct Summary {
    /// Cycles in the window.
    pub cycles: u32,
    /// Most core cycles one control cycle took.
    pub worst: u32,
    /// Core cycles of all control cycles.
    pub sum: u64,
    /// Frames received.
    pub received: u32,
    /// Commands refused.
    pub refused: u32,
    /// Frames sent.
    pub sent: u32,
}

impl Summary {
    /// Mean core cycles per control cycle: `sum / cycles` rounded down (`sum` for no cycle),
    /// exactly while `sum < 2⁵³` (a window of [`Stats::record`] holds at most 200 × 2³² < 2⁴⁰),
    /// beyond that within 2⁻⁵² of it (relative) and one.
    ///
    /// In `f64`, not by a `u64` division: that is a library routine on the Cortex-M
    /// (`__aeabi_uldivmod`, 0.9 KB of flash), which the board image would link for this
    /// once-a-second figure alone; the FPU divides and converts `u32`s in hardware. Exact: for
    /// `sum < 2⁵³` both operands are exact, and the rounded quotient cannot reach the next
    /// integer, whose distance from `sum / cycles` is at least `1 / cycles`, more than the
    /// rounding (`2⁻⁵³ · sum / cycles`).
    pub fn mean(&self) -> u64 {
        const TWO_32: f64 = 4_294_967_296.0;
        let (hi, lo) = ((self.sum >> 32) as u32, self.sum as u32);
        let q = (f64::from(hi) * TWO_32 + f64::from(lo)) / f64::from(self.cycles.max(1));
        // q < 2⁶⁴ + 1: its integer part in two `u32` halves (the conversions truncate and
        // saturate; q − h·2³² is exact).
        let h = (q / TWO_32) as u32;
        let l = (q - f64::from(h) * TWO_32) as u32;
        (u64::from(h) << 32) | u64::from(l)
    }
}

/// Overruns since start-up and the current statistics window.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Control cycles that were late, since start-up (saturating).
    pub overruns: u32,
    window: Summary,
}

/// What one cycle's bookkeeping found, for the caller to log.
#[derive(Clone, Copy, Debug)]
pub struct Outcome {
    /// The cycle was late (counted, and told to the node).
    pub overrun: bool,
    /// The window closed with this cycle: its summary.
    pub summary: Option<Summary>,
}

impl Stats {
    /// Records one cycle: `spent` core cycles of `poll`, `late` if the work did not fit the
    /// slot or the next slot has already begun.
    pub fn record<N: ControlNode>(
        &mut self,
        node: &mut N,
        report: &PollReport<N::Scalar>,
        spent: u32,
        late: bool,
    ) -> Outcome {
        if late {
            self.overruns = self.overruns.saturating_add(1);
            node.note_overrun();
        }
        let w = &mut self.window;
        w.cycles = w.cycles.saturating_add(1);
        w.worst = w.worst.max(spent);
        w.sum = w.sum.saturating_add(u64::from(spent));
        w.received = w.received.saturating_add(u32::from(report.received));
        w.refused = w.refused.saturating_add(u32::from(report.refused));
        w.sent = w.sent.saturating_add(u32::from(report.sent));
        let summary = if w.cycles >= SUMMARY_EVERY {
            let s = *w;
            *w = Summary::default();
            Some(s)
        } else {
            None
        };
        Outcome {
            overrun: late,
            summary,
        }
    }
}
