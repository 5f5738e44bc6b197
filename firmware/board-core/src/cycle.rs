//! The bookkeeping of one control cycle: overruns (counted and reported to the node, which
//! publishes them in its status) and the statistics window summarised once per second.
//!
//! Part of the board's control cycle ([`crate::control`]), which the board image, the
//! link-time no-panic check (`firmware/nopanic`) and the QEMU image all run; host-tested
//! (`tests/cycle.rs`).

use planner_core::node::PollReport;

use crate::control::ControlNode;

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
    /// Mean core cycles per control cycle.
    pub fn mean(&self) -> u64 {
        self.sum / u64::from(self.cycles.max(1))
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
