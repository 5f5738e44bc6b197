//! The board's control cycle (`board_core::control`) on mock hardware: one watchdog feed per
//! completed cycle and none after a poll or a wait that does not return, a slow poll is an
//! overrun and the slots it ran over are counted, the busy pin frames the poll, and what is
//! logged when; then the whole cycle with planner-core's node over the link adapter on the
//! FDCAN model (`mock`), publishing its health in `LINK`.

#[allow(dead_code)] // shared with tests/link.rs
mod mock;

use std::cell::{Cell, RefCell};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;

use board_core::control::{
    BusyPin, ControlLoop, ControlNode, CycleCounter, Io, LogSink, MicrosClock, Port, SummaryLine,
};
use board_core::cycle::SUMMARY_EVERY;
use board_core::{Health, Link, Pacer, ResetReason, Slot};
use embedded_can::nb::Can;
use mock::MockFdcan;
use planner_core::gait::Reference;
use planner_core::node::{Node, NodeConfig, PollReport};
use planner_core::wire::{ids, LinkHealth, RawFrame};

/// Microseconds per slot, and core cycles per microsecond (the board's 480 MHz).
const PERIOD_US: u32 = 5_000;
const CYCLES_PER_US: u32 = 480;
const PERIOD_CYCLES: u32 = PERIOD_US * CYCLES_PER_US;

/// The time shared by the clock, the counter and the stand-in node.
#[derive(Default)]
struct World {
    us: Cell<u32>,
    /// Core cycles beyond `us` (a poll can burn cycles faster than the clock, see below).
    extra_cycles: Cell<u32>,
    feeds: Cell<u32>,
    /// (level, feeds so far) at each change of the busy pin.
    busy: RefCell<Vec<(bool, u32)>>,
    log: RefCell<Vec<Line>>,
}

impl World {
    fn advance(&self, us: u32) {
        self.us.set(self.us.get().wrapping_add(us));
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Line {
    Missed {
        skipped: u32,
        index: u32,
        total: u32,
    },
    Overrun {
        cycle: u32,
        spent: u32,
        total: u32,
    },
    Refused {
        cycle: u32,
        refused: u8,
        received: u8,
    },
    Summary {
        cycles: u32,
        worst: u32,
        overruns: u32,
        missed: u32,
        n: u32,
    },
}

struct Clock(Rc<World>);
impl MicrosClock for Clock {
    fn now_us(&mut self) -> u32 {
        self.0.us.get()
    }
    fn idle_until(&mut self, at_us: u32) {
        self.0.us.set(at_us);
    }
}

struct Counter(Rc<World>);
impl CycleCounter for Counter {
    fn cycles(&mut self) -> u32 {
        let w = &self.0;
        w.us.get()
            .wrapping_mul(CYCLES_PER_US)
            .wrapping_add(w.extra_cycles.get())
    }
}

struct Dog(Rc<World>);
impl board_core::control::Watchdog for Dog {
    fn feed(&mut self) {
        self.0.feeds.set(self.0.feeds.get() + 1);
    }
}

struct Pin(Rc<World>);
impl BusyPin for Pin {
    fn set_busy(&mut self, busy: bool) {
        let w = &self.0;
        w.busy.borrow_mut().push((busy, w.feeds.get()));
    }
}

struct Log(Rc<World>);
impl LogSink for Log {
    fn missed_slots(&mut self, slot: &Slot, total: u32) {
        self.0.log.borrow_mut().push(Line::Missed {
            skipped: slot.skipped,
            index: slot.index,
            total,
        });
    }
    fn overrun(&mut self, cycle: u32, spent: u32, period: u32, total: u32) {
        assert_eq!(period, PERIOD_CYCLES);
        self.0.log.borrow_mut().push(Line::Overrun {
            cycle,
            spent,
            total,
        });
    }
    fn refused(&mut self, cycle: u32, refused: u8, received: u8) {
        self.0.log.borrow_mut().push(Line::Refused {
            cycle,
            refused,
            received,
        });
    }
    fn summary(&mut self, line: &SummaryLine) {
        assert_eq!(line.period_cycles, PERIOD_CYCLES);
        self.0.log.borrow_mut().push(Line::Summary {
            cycles: line.cycles,
            worst: line.window.worst,
            overruns: line.overruns,
            missed: line.missed,
            n: line.window.cycles,
        });
    }
}

type Loop = ControlLoop<Clock, Counter, Dog, Pin, Log>;

/// A loop whose slot 0 begins one period from now (as on the board).
fn control_loop(world: &Rc<World>) -> Loop {
    let pacer = Pacer::new(world.us.get().wrapping_add(PERIOD_US), PERIOD_US, 5);
    ControlLoop::new(
        Io {
            clock: Clock(world.clone()),
            counter: Counter(world.clone()),
            watchdog: Dog(world.clone()),
            busy: Pin(world.clone()),
            log: Log(world.clone()),
        },
        pacer,
        PERIOD_CYCLES,
        ResetReason::Pin,
    )
}

/// What the stand-in node does in its next polls.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Work {
    /// Takes this many microseconds.
    Takes(u32),
    /// Burns this many core cycles in 100 µs (a slow core, a stuck bus access).
    Burns(u32),
    /// Refuses `refused` of `received` frames.
    Refuses(u8, u8),
    /// Never returns (a panic stands in for the hang).
    Hangs,
}

struct StandIn {
    world: Rc<World>,
    reference: Reference<f64>,
    plan: Vec<(u32, Work)>,
    polls: u32,
    overruns: u32,
    now_ms: Vec<u32>,
    health: Vec<LinkHealth>,
}

impl StandIn {
    fn new(world: &Rc<World>, plan: &[(u32, Work)]) -> Self {
        let node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
        Self {
            world: world.clone(),
            reference: *node.gait().last(),
            plan: plan.to_vec(),
            polls: 0,
            overruns: 0,
            now_ms: vec![],
            health: vec![],
        }
    }
}

impl ControlNode for StandIn {
    type Scalar = f64;
    fn set_link_health(&mut self, link: LinkHealth) {
        self.health.push(link);
    }
    fn poll<C: Can>(&mut self, now_ms: u32, _can: &mut C) -> PollReport<f64> {
        self.polls += 1;
        self.now_ms.push(now_ms);
        let work = self
            .plan
            .iter()
            .find(|(k, _)| *k == self.polls)
            .map(|&(_, w)| w)
            .unwrap_or(Work::Takes(50));
        let (mut received, mut refused) = (0, 0);
        match work {
            Work::Takes(us) => self.world.advance(us),
            Work::Burns(cycles) => {
                self.world.advance(100);
                let w = &self.world;
                w.extra_cycles
                    .set(w.extra_cycles.get().wrapping_add(cycles));
            }
            Work::Refuses(r, n) => {
                self.world.advance(50);
                (refused, received) = (r, n);
            }
            Work::Hangs => panic!("the poll hangs"),
        }
        PollReport {
            reference: self.reference,
            received,
            refused,
            sent: 5,
        }
    }
    fn note_overrun(&mut self) {
        self.overruns += 1;
    }
    fn cycles(&self) -> u32 {
        self.polls
    }
}

/// A port that counts its services (and can hang in one).
#[derive(Default)]
struct TestPort {
    services: u32,
    hang_at_service: Option<u32>,
}

impl Can for TestPort {
    type Frame = RawFrame;
    type Error = core::convert::Infallible;
    fn transmit(&mut self, _: &RawFrame) -> nb::Result<Option<RawFrame>, Self::Error> {
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<RawFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

impl Port for TestPort {
    fn service(&mut self) {
        self.services += 1;
        if Some(self.services) == self.hang_at_service {
            panic!("the wait hangs");
        }
    }
    fn health(&self) -> Health {
        Health {
            tec: 7,
            ..Health::default()
        }
    }
}

#[test]
fn every_completed_cycle_feeds_the_watchdog_once_and_the_busy_pin_frames_the_poll() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    let mut node = StandIn::new(&world, &[]);
    let mut port = TestPort::default();
    for k in 0..50u32 {
        let run = ctl.step(&mut node, &mut port);
        assert_eq!(world.feeds.get(), k + 1, "one feed per completed cycle");
        assert_eq!(run.slot.index, k);
        assert_eq!(run.slot.now_ms, 5 * k);
        assert_eq!(run.spent, 50 * CYCLES_PER_US, "the poll alone is timed");
        assert!(run.whole >= run.spent);
        assert!(!run.overrun);
    }
    // High before each poll, low after it, and the feed only after the pin went low.
    let busy = world.busy.borrow();
    assert_eq!(busy.len(), 100);
    for (k, pair) in busy.chunks(2).enumerate() {
        assert_eq!(pair, [(true, k as u32), (false, k as u32)]);
    }
    assert_eq!(node.now_ms, (0..50).map(|k| 5 * k).collect::<Vec<_>>());
    // The link health goes to the node before every poll: the port's, the reset reason, the
    // missed slots.
    assert_eq!(node.health.len(), 50);
    assert!(node
        .health
        .iter()
        .all(|h| h.tec == 7 && h.reset == ResetReason::Pin as u8 && h.missed_slots == 0));
    assert!(world.log.borrow().is_empty(), "nothing to log");
    assert!(port.services >= 50, "the link is serviced while waiting");
}

#[test]
fn a_slow_poll_is_an_overrun_and_the_slots_it_ran_over_are_counted() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    // Poll 4 (in slot 3) takes 17 ms: slots 4 and 5 are over when the loop comes back, slot 6
    // has begun.
    let mut node = StandIn::new(&world, &[(4, Work::Takes(17_000))]);
    let mut port = TestPort::default();
    let runs: Vec<_> = (0..8).map(|_| ctl.step(&mut node, &mut port)).collect();
    assert_eq!(
        world.feeds.get(),
        8,
        "a late cycle that completes is fed too"
    );
    assert!(runs[3].overrun && runs[3].spent == 17_000 * CYCLES_PER_US);
    assert_eq!(runs.iter().filter(|r| r.overrun).count(), 1);
    assert_eq!((ctl.stats().overruns, node.overruns), (1, 1));
    // The next poll runs in the current slot, with its time: two slots skipped.
    assert_eq!(
        (
            runs[4].slot.index,
            runs[4].slot.skipped,
            runs[4].slot.now_ms
        ),
        (6, 2, 30)
    );
    assert_eq!(ctl.pacer().missed(), 2);
    // The node is told the missed slots from the next cycle on.
    assert_eq!(node.health[4].missed_slots, 2);
    assert_eq!(
        *world.log.borrow(),
        [
            Line::Overrun {
                cycle: 4,
                spent: 17_000 * CYCLES_PER_US,
                total: 1
            },
            Line::Missed {
                skipped: 2,
                index: 6,
                total: 2
            },
        ]
    );
}

#[test]
fn a_poll_over_its_cycle_budget_is_late_even_when_the_slot_is_not_over() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    let mut node = StandIn::new(&world, &[(2, Work::Burns(PERIOD_CYCLES))]);
    let mut port = TestPort::default();
    let runs: Vec<_> = (0..4).map(|_| ctl.step(&mut node, &mut port)).collect();
    assert!(runs[1].overrun, "{:?}", runs[1]);
    assert_eq!(runs.iter().filter(|r| r.overrun).count(), 1);
    assert_eq!(ctl.pacer().missed(), 0, "no slot was missed");
    assert_eq!(node.overruns, 1);
    assert_eq!(world.feeds.get(), 4);
}

#[test]
fn a_hung_poll_is_never_followed_by_a_feed() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    let mut node = StandIn::new(&world, &[(5, Work::Hangs)]);
    let mut port = TestPort::default();
    let hung = catch_unwind(AssertUnwindSafe(|| {
        for _ in 0..10 {
            ctl.step(&mut node, &mut port);
        }
    }));
    assert!(hung.is_err());
    assert_eq!(
        world.feeds.get(),
        4,
        "fed for the four completed cycles only"
    );
    // The busy pin stays high: the scope shows where it hung.
    assert_eq!(world.busy.borrow().last(), Some(&(true, 4)));
    assert_eq!(node.polls, 5);
}

#[test]
fn a_hung_wait_is_never_followed_by_a_feed() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    let mut node = StandIn::new(&world, &[]);
    let mut port = TestPort::default();
    for _ in 0..3 {
        ctl.step(&mut node, &mut port);
    }
    port.hang_at_service = Some(port.services + 1);
    let hung = catch_unwind(AssertUnwindSafe(|| ctl.step(&mut node, &mut port)));
    assert!(hung.is_err());
    assert_eq!((world.feeds.get(), node.polls), (3, 3));
}

#[test]
fn refusals_and_the_summary_are_logged_after_the_feed() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    let mut node = StandIn::new(
        &world,
        &[
            (3, Work::Refuses(2, 5)),
            (7, Work::Takes(300)),
            (250, Work::Takes(11_000)),
        ],
    );
    let mut port = TestPort::default();
    let mut summaries = vec![];
    for _ in 0..(2 * SUMMARY_EVERY) {
        let before = world.log.borrow().len();
        let run = ctl.step(&mut node, &mut port);
        if world.log.borrow().len() > before {
            // Every log call comes after the cycle's feed and with the busy pin low.
            assert_eq!(
                world.busy.borrow().last(),
                Some(&(false, world.feeds.get() - 1))
            );
        }
        if let Some(s) = run.summary {
            summaries.push(s);
        }
    }
    let log = world.log.borrow();
    assert_eq!(
        *log,
        [
            Line::Refused {
                cycle: 3,
                refused: 2,
                received: 5
            },
            Line::Summary {
                cycles: SUMMARY_EVERY,
                worst: 300 * CYCLES_PER_US,
                overruns: 0,
                missed: 0,
                n: SUMMARY_EVERY
            },
            Line::Overrun {
                cycle: 250,
                spent: 11_000 * CYCLES_PER_US,
                total: 1
            },
            Line::Missed {
                skipped: 1,
                index: 251,
                total: 1
            },
            Line::Summary {
                cycles: 2 * SUMMARY_EVERY,
                worst: 11_000 * CYCLES_PER_US,
                overruns: 1,
                missed: 1,
                n: SUMMARY_EVERY
            },
        ]
    );
    assert_eq!(summaries.len(), 2);
}

#[test]
fn the_board_cycle_runs_planner_cores_node_over_the_link_and_publishes_link() {
    let world = Rc::new(World::default());
    let mut ctl = control_loop(&world);
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut link = Link::new(MockFdcan::new(board_core::link::RX_ELEMENTS));
    for _ in 0..100 {
        let run = ctl.step(&mut node, &mut link);
        assert!(!run.overrun);
        world.advance(200);
        link.peripheral_mut().bus_sends(64);
    }
    assert_eq!(world.feeds.get(), 100);
    assert_eq!(node.cycles(), 100);
    let links: Vec<LinkHealth> = link
        .peripheral()
        .wire
        .iter()
        .filter_map(RawFrame::from_frame)
        .filter(|f| f.id == ids::LINK)
        .map(|f| LinkHealth::decode(&f).unwrap())
        .collect();
    // One LINK per STATUS (every 100 ms = 20 cycles).
    assert_eq!(links.len(), 5);
    assert!(links
        .iter()
        .all(|l| l.reset == ResetReason::Pin as u8 && l.missed_slots == 0 && l.bus_state == 0));
}
