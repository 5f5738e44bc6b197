//! One control cycle of the scripted gait loop, timed and classified.
//!
//! [`Player`] replays a [`Scenario`] exactly as `host_sim::scenario::run` does (same order of
//! commands and ticks, same end condition), so the references of every tick can be compared
//! with the host's one for one.

use planner_core::gait::{Footstep, Gait, GaitError, GaitParams, Reference, ReplanInfo};

use crate::script::{Command, Scenario};
use crate::stats::{Kind, Stats};
use crate::QUEUE;

/// A free-running up-counter provided by the image (wrapping `u32`; only differences are
/// used).
pub trait Clock {
    /// The present count.
    fn now(&mut self) -> u32;
}

/// A command that was applied, and what it cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommandRecord {
    /// Tick at which it was applied (the gait's tick count before the cycle's tick).
    pub tick: u64,
    /// The command.
    pub command: Command,
    /// The gait's answer.
    pub result: Result<(), GaitError>,
    /// Clock units spent in the gait call.
    pub units: u32,
}

/// What one control cycle did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleRecord {
    /// The gait's tick count after the cycle (the index of `reference` in host-sim's
    /// trajectory).
    pub tick: u64,
    /// The kind of the cycle's tick.
    pub kind: Kind,
    /// Clock units spent in `Gait::tick`.
    pub tick_units: u32,
    /// Clock units spent in the gait calls of the whole cycle (commands and tick).
    pub cycle_units: u32,
    /// The reference of this tick.
    pub reference: Reference<f64>,
    /// The re-plan done by this tick, if any.
    pub replan: Option<ReplanInfo<f64>>,
}

/// Replays a scenario, one control cycle per call of [`Player::cycle`].
#[derive(Clone, Debug)]
pub struct Player<'s> {
    scenario: &'s Scenario,
    next: usize,
    last_command: u64,
    finished: bool,
}

impl<'s> Player<'s> {
    /// Replays `scenario` against a gait that was just created with `scenario.feet`.
    pub fn new(scenario: &'s Scenario) -> Self {
        Self {
            scenario,
            next: 0,
            last_command: scenario.timeline.last().map(|(t, _)| *t).unwrap_or(0),
            finished: false,
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> &'s Scenario {
        self.scenario
    }

    /// `true` once the scenario has ended: standing after its last command, or `max_ticks`
    /// elapsed.
    pub fn done<const Q: usize>(&self, gait: &Gait<f64, Q>) -> bool {
        self.finished || gait.ticks() >= self.scenario.max_ticks
    }

    /// One control cycle: applies the commands that are due (in timeline order), then ticks
    /// the gait. Each gait call is timed with `clock` and recorded in `stats`; `on_command`
    /// sees every applied command. The cycle's time is the sum of its gait calls: what
    /// `on_command` and the bookkeeping cost is not counted.
    pub fn cycle<C: Clock, const Q: usize>(
        &mut self,
        gait: &mut Gait<f64, Q>,
        clock: &mut C,
        stats: &mut Stats,
        mut on_command: impl FnMut(&CommandRecord),
    ) -> CycleRecord {
        let timeline = &self.scenario.timeline;
        let mut cycle_units: u32 = 0;
        while self.next < timeline.len() && timeline[self.next].0 <= gait.ticks() {
            let (_, command) = timeline[self.next];
            let t0 = clock.now();
            let result = apply(gait, command);
            let units = clock.now().wrapping_sub(t0);
            let kind = match command {
                Command::Push(..) => Kind::Push,
                Command::Start => Kind::Start,
                Command::Stop | Command::StopNow => Kind::StopCommand,
                Command::Modify(..) => Kind::Modify,
            };
            stats.record(kind, units, gait.ticks());
            cycle_units = cycle_units.saturating_add(units);
            on_command(&CommandRecord {
                tick: gait.ticks(),
                command,
                result,
                units,
            });
            self.next += 1;
        }

        let was_standing = gait.is_standing();
        let t0 = clock.now();
        let reference = tick(gait);
        let tick_units = clock.now().wrapping_sub(t0);
        cycle_units = cycle_units.saturating_add(tick_units);
        let tick = gait.ticks();

        let replan = gait.last_replan().filter(|i| i.tick == tick).copied();
        let kind = if was_standing && gait.is_standing() {
            Kind::Standing
        } else if let Some(info) = replan {
            if info.adjust_ticks != 0 {
                Kind::Adjust
            } else {
                Kind::Replan
            }
        } else {
            Kind::Steady
        };
        stats.record(kind, tick_units, tick);
        stats.record(Kind::Cycle, cycle_units, tick);

        if gait.is_standing() && tick > self.last_command && self.next >= timeline.len() {
            self.finished = true;
        }
        CycleRecord {
            tick,
            kind,
            tick_units,
            cycle_units,
            reference,
            replan,
        }
    }
}

/// `Gait::new` with the HRP-2 feet of `scenario`, in a frame of its own.
///
/// Inlined into its caller, `new`'s local copy of the gait (~38 KB) and the returned one would
/// both stay reserved in the caller's frame for as long as the caller runs. Keep the result
/// where it was returned and borrow the gait from it (`match &mut result`): moving it out
/// copies it into yet another slot.
#[inline(never)]
pub fn new_gait(
    params: GaitParams<f64>,
    scenario: &Scenario,
) -> Result<Gait<f64, QUEUE>, GaitError> {
    Gait::new(params, scenario.feet[0], scenario.feet[1])
}

// The gait calls, each in a frame of its own. Inlined into `Player::cycle`, the temporaries of
// `start`, `modify` and `tick` (plan windows of ~9 KB each, the 20×20 factorisation) would
// all be reserved at once in one frame: 40 KB of stack instead of the largest of them.

#[inline(never)]
fn apply<const Q: usize>(gait: &mut Gait<f64, Q>, command: Command) -> Result<(), GaitError> {
    match command {
        Command::Push(id, f) => gait.push(id, f).map_err(|(e, _)| e),
        Command::Start => start(gait),
        Command::Stop => {
            gait.stop();
            Ok(())
        }
        Command::StopNow => {
            gait.clear_and_stop();
            Ok(())
        }
        Command::Modify(id, f) => modify(gait, id, f),
    }
}

#[inline(never)]
fn start<const Q: usize>(gait: &mut Gait<f64, Q>) -> Result<(), GaitError> {
    gait.start()
}

#[inline(never)]
fn modify<const Q: usize>(
    gait: &mut Gait<f64, Q>,
    id: u16,
    step: Footstep<f64>,
) -> Result<(), GaitError> {
    gait.modify(id, step)
}

#[inline(never)]
fn tick<const Q: usize>(gait: &mut Gait<f64, Q>) -> Reference<f64> {
    gait.tick()
}
