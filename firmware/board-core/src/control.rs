//! The board's control cycle, without hardware: one slot of the loop around `Node::poll`.
//!
//! Owns the loop ([`ControlLoop`], [`Io`], [`poll`], what a slot did: [`SlotRun`]) and the
//! small traits of the hardware it runs over ([`MicrosClock`], [`CycleCounter`],
//! [`Watchdog`], [`BusyPin`], [`Port`], [`LogSink`] with its [`SummaryLine`]). It uses
//! [`crate::cycle`] for the bookkeeping (overruns, the statistics window) and
//! [`crate::node`] for the node's contract, [`ControlNode`], re-exported here because it is
//! part of this module's interface (`board_core::control::ControlNode`).
//!
//! [`ControlLoop`] is the body of the board image's loop (`firmware/board/src/main.rs`), and
//! the QEMU image runs the same code around its replayed polls (`firmware/qemu`), as does the
//! link-time no-panic check (`firmware/nopanic`). Per slot ([`ControlLoop::step`]):
//!
//! 1. **wait** for the next slot of the [`Pacer`], calling [`Port::service`] (the CAN link
//!    adapter's upkeep) meanwhile; [`MicrosClock::idle_until`] says until when there is
//!    nothing else to do (the board spins, a simulated clock may jump);
//! 2. one cycle to the port ([`Port::cycle`]: the bus-off back-off counts in cycles), then
//!    tell the node its link health ([`ControlNode::set_link_health`]: the port's
//!    [`Health`], the reset reason and the missed slots, published in `LINK`);
//! 3. the busy pin high, **one timed poll** ([`poll`], a frame of its own) with the slot's
//!    time, the busy pin low;
//! 4. the **late** decision: the poll took more than a slot's core cycles, or the next slot
//!    has already begun ([`Pacer::behind`]); [`Stats::record`] counts it and tells the node;
//! 5. the **watchdog feed**, once, now that the cycle is complete (a poll or a wait that never
//!    returns is never followed by a feed);
//! 6. the **decision of what to log**, outside the timed part, handed to a [`LogSink`]:
//!    missed slots, an overrun, refused commands, the summary once per [`SUMMARY_EVERY`](crate::cycle::SUMMARY_EVERY)
//!    cycles.
//!
//! The hardware is behind small traits: [`MicrosClock`] (the board's TIM2, the QEMU image's
//! CMSDK timer), [`CycleCounter`] (DWT CYCCNT; the QEMU image's instruction count),
//! [`Watchdog`] (the IWDG), [`BusyPin`] (PE1), [`LogSink`] (defmt; the QEMU image counts),
//! and the node behind [`ControlNode`] (planner-core's `Node`; host tests use a stand-in
//! that can be slow or hang). Host-tested in `tests/control.rs`.

use embedded_can::nb::Can;
use planner_core::node::PollReport;

use crate::cycle::{Stats, Summary};
use crate::link::{Fdcan, Health, Link};
use crate::pace::{Pacer, Slot};
use crate::reset::ResetReason;

/// The node's contract with the cycle (defined in [`crate::node`]; this path is public API).
pub use crate::node::ControlNode;

/// The free-running microsecond counter the slots are cut from (wrapping `u32`).
pub trait MicrosClock {
    /// The present count \[µs\].
    fn now_us(&mut self) -> u32;
    /// Nothing is due before `at_us` (the next slot): the board keeps spinning (the default:
    /// nothing to do); a simulated clock may advance to it.
    fn idle_until(&mut self, at_us: u32) {
        let _ = at_us;
    }
}

/// The counter that times a poll (wrapping `u32`; only differences are used): core cycles on
/// the board (DWT CYCCNT).
pub trait CycleCounter {
    /// The present count.
    fn cycles(&mut self) -> u32;
}

/// The watchdog: fed once per completed cycle.
pub trait Watchdog {
    /// Reloads the watchdog.
    fn feed(&mut self);
}

/// The busy pin: high while the node works (for a scope).
pub trait BusyPin {
    /// Drives the pin high (`true`) or low.
    fn set_busy(&mut self, busy: bool);
}

/// The node's side of the CAN link: the bus for `Node::poll`, serviced while the loop waits.
pub trait Port: Can {
    /// Upkeep between polls (error state, receive FIFO, transmit queue).
    fn service(&mut self);
    /// What the board publishes about the link.
    fn health(&self) -> Health;
    /// One control cycle has passed (the bus-off back-off counts in cycles).
    fn cycle(&mut self) {}
}

impl<P: Fdcan> Port for Link<P> {
    fn service(&mut self) {
        Link::service(self);
    }
    fn cycle(&mut self) {
        Link::cycle(self);
    }
    fn health(&self) -> Health {
        Link::health(self)
    }
}

/// A summary's content: the window and the state of the loop when it closed.
#[derive(Clone, Copy, Debug)]
pub struct SummaryLine {
    /// The node's polls since start-up.
    pub cycles: u32,
    /// The window (worst, sum, frames).
    pub window: Summary,
    /// Core cycles of a slot (the budget the worst is compared with).
    pub period_cycles: u32,
    /// Late cycles since start-up.
    pub overruns: u32,
    /// Slots missed since start-up.
    pub missed: u32,
    /// The slot jitter: the most counter ticks (µs on the board) a cycle of the window began
    /// after its slot did ([`crate::pace::Slot::late_ticks`]).
    pub late_max: u32,
    /// The link's health.
    pub health: Health,
}

/// Where the cycle's log lines go (the board: defmt; the QEMU image: counters). Called after
/// the watchdog feed, outside the timed part.
pub trait LogSink {
    /// `slot.skipped` slots were missed before `slot`; `total` since start-up.
    fn missed_slots(&mut self, slot: &Slot, total: u32);
    /// Cycle `cycle` was late: its poll took `spent` core cycles of `period`; `total` late
    /// cycles since start-up.
    fn overrun(&mut self, cycle: u32, spent: u32, period: u32, total: u32);
    /// Cycle `cycle` refused `refused` of the `received` frames.
    fn refused(&mut self, cycle: u32, refused: u8, received: u8);
    /// The statistics window closed (once per [`SUMMARY_EVERY`](crate::cycle::SUMMARY_EVERY) cycles).
    fn summary(&mut self, line: &SummaryLine);
}

/// What one slot did.
#[derive(Clone, Copy, Debug)]
pub struct SlotRun<T = f64> {
    /// The slot (its index, time, the slots skipped before it).
    pub slot: Slot,
    /// The node's report.
    pub report: PollReport<T>,
    /// [`CycleCounter`] units of the poll alone.
    pub spent: u32,
    /// [`CycleCounter`] units from the slot's start (the wait's end) to the watchdog feed:
    /// the link health, the busy pin, the timed poll, the late decision, the statistics and
    /// the feed.
    pub whole: u32,
    /// The cycle was late (counted, told to the node).
    pub overrun: bool,
    /// The window closed with this cycle.
    pub summary: Option<Summary>,
}

/// The hardware a cycle uses (each behind its trait).
#[derive(Debug)]
pub struct Io<K, C, W, B, L> {
    /// The microsecond counter.
    pub clock: K,
    /// The poll's timer.
    pub counter: C,
    /// The watchdog.
    pub watchdog: W,
    /// The busy pin.
    pub busy: B,
    /// The log sink.
    pub log: L,
}

/// The board's control loop: the pacer, the statistics and the hardware of the cycle.
#[derive(Debug)]
pub struct ControlLoop<K, C, W, B, L> {
    /// The hardware.
    pub io: Io<K, C, W, B, L>,
    pacer: Pacer,
    stats: Stats,
    reset: ResetReason,
    period_cycles: u32,
    /// The most `late_ticks` of a slot in the statistics window.
    late_max: u32,
}

/// `Node::poll` (through [`ControlNode::poll`]) in a frame of its own: the timed part of the
/// cycle, and the function the QEMU image's instruction attribution cuts its trace by.
#[inline(never)]
pub fn poll<N: ControlNode, P: Port>(
    node: &mut N,
    now_ms: u32,
    port: &mut P,
) -> PollReport<N::Scalar> {
    node.poll(now_ms, port)
}

impl<K, C, W, B, L> ControlLoop<K, C, W, B, L>
where
    K: MicrosClock,
    C: CycleCounter,
    W: Watchdog,
    B: BusyPin,
    L: LogSink,
{
    /// A loop whose slots are `pacer`'s; a poll of more than `period_cycles` counter units is
    /// late; `reset` is published in `LINK`.
    pub fn new(
        io: Io<K, C, W, B, L>,
        pacer: Pacer,
        period_cycles: u32,
        reset: ResetReason,
    ) -> Self {
        Self {
            io,
            pacer,
            stats: Stats::default(),
            reset,
            period_cycles,
            late_max: 0,
        }
    }

    /// The pacer (missed slots).
    pub fn pacer(&self) -> &Pacer {
        &self.pacer
    }

    /// The cycle statistics (overruns since start-up).
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Waits for the next slot, servicing `port` meanwhile.
    pub fn wait<P: Port>(&mut self, port: &mut P) -> Slot {
        loop {
            port.service();
            if let Some(slot) = self.pacer.due(self.io.clock.now_us()) {
                return slot;
            }
            self.io.clock.idle_until(self.pacer.next_start());
        }
    }

    /// One whole slot: [`ControlLoop::wait`], then [`ControlLoop::run`].
    pub fn step<N: ControlNode, P: Port>(
        &mut self,
        node: &mut N,
        port: &mut P,
    ) -> SlotRun<N::Scalar> {
        let slot = self.wait(port);
        self.run(slot, node, port)
    }

    /// The cycle of `slot` (just begun): link health, the timed poll, the late decision, the
    /// statistics, the watchdog feed, then the log calls (module docs).
    pub fn run<N: ControlNode, P: Port>(
        &mut self,
        slot: Slot,
        node: &mut N,
        port: &mut P,
    ) -> SlotRun<N::Scalar> {
        let begun = self.io.counter.cycles();
        self.late_max = self.late_max.max(slot.late_ticks);
        port.cycle();
        node.set_link_health(port.health().to_wire(self.reset, self.pacer.missed()));

        self.io.busy.set_busy(true);
        let t0 = self.io.counter.cycles();
        let report = poll(node, slot.now_ms, port);
        let spent = self.io.counter.cycles().wrapping_sub(t0);
        self.io.busy.set_busy(false);

        // Late: the work did not fit the slot, or the next slot has already begun.
        let late = spent > self.period_cycles || self.pacer.behind(self.io.clock.now_us());
        let outcome = self.stats.record(node, &report, spent, late);
        // The cycle is complete.
        self.io.watchdog.feed();
        let whole = self.io.counter.cycles().wrapping_sub(begun);

        // What to log, outside the timed part.
        if slot.skipped > 0 {
            self.io.log.missed_slots(&slot, self.pacer.missed());
        }
        if outcome.overrun {
            self.io.log.overrun(
                node.cycles(),
                spent,
                self.period_cycles,
                self.stats.overruns,
            );
        }
        if report.refused > 0 {
            self.io
                .log
                .refused(node.cycles(), report.refused, report.received);
        }
        if let Some(window) = outcome.summary {
            self.io.log.summary(&SummaryLine {
                cycles: node.cycles(),
                window,
                period_cycles: self.period_cycles,
                overruns: self.stats.overruns,
                missed: self.pacer.missed(),
                late_max: self.late_max,
                health: port.health(),
            });
            self.late_max = 0;
        }
        SlotRun {
            slot,
            report,
            spent,
            whole,
            overrun: outcome.overrun,
            summary: outcome.summary,
        }
    }
}
