//! The control cycle's log lines (board-core's `control::LogSink`) in defmt through the
//! board's never-blocking logger (`logger.rs`): what to log is decided by board-core's
//! `ControlLoop::run`, after the watchdog feed and outside the timed part; the format strings
//! are here. The no-panic check (`firmware/nopanic`) compiles this file too.

use board_core::control::{LogSink, SummaryLine};
use board_core::Slot;

/// The loop's log lines in defmt.
#[derive(Clone, Copy, Debug, Default)]
pub struct DefmtLog;

impl LogSink for DefmtLog {
    fn missed_slots(&mut self, slot: &Slot, total: u32) {
        defmt::warn!(
            "{=u32} slot(s) missed before slot {=u32} ({=u32} so far)",
            slot.skipped,
            slot.index,
            total
        );
    }

    fn overrun(&mut self, cycle: u32, spent: u32, period: u32, total: u32) {
        defmt::warn!(
            "overrun: cycle {=u32} took {=u32} cycles (slot {=u32}), {=u32} so far",
            cycle,
            spent,
            period,
            total
        );
    }

    fn refused(&mut self, cycle: u32, refused: u8, received: u8) {
        defmt::warn!(
            "cycle {=u32}: {=u8} of {=u8} commands refused",
            cycle,
            refused,
            received
        );
    }

    fn summary(&mut self, s: &SummaryLine) {
        let (w, h) = (&s.window, &s.health);
        defmt::info!(
            "cycles {=u32}: worst {=u32} mean {=u64} of {=u32}; rx {=u32} refused {=u32} tx {=u32}; overruns {=u32} missed {=u32} slot jitter {=u32} us; TEC {=u8} REC {=u8} state {=u8} bus-offs {=u16} passive {=u16} rx lost {=u16} replaced {=u16}; log dropped {=u32}; loop stack {=u32} B",
            s.cycles,
            w.worst,
            w.mean(),
            s.period_cycles,
            w.received,
            w.refused,
            w.sent,
            s.overruns,
            s.missed,
            s.late_max,
            h.tec,
            h.rec,
            h.state as u8,
            h.bus_offs,
            h.passive_episodes,
            h.rx_lost,
            h.replaced,
            crate::logger::dropped(),
            crate::stack::high_water()
        );
    }
}
