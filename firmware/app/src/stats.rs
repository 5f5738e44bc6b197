//! Timing statistics per kind of work: count, maximum (and where), sum.
//!
//! Units are whatever the image's [`Clock`](crate::Clock) counts (QEMU: CMSDK timer ticks,
//! 40 instructions each under `-icount shift=0`; board: core cycles).

/// A kind of timed work: `New` is the node's start-up, every other kind is a whole
/// `Node::poll` (one control cycle), classified by what it did, first match wins:
/// a cycle that received a `VELOCITY` or `GOAL` or in which the node chose steps itself is
/// `Drive`, one that received a `STEP_MODIFY` is `Modify`, one that received a `Start` is
/// `Start`, then by its tick (`Adjust`, `Replan`), then `StopCommand`, `Push`, `Standing`, then by
/// whether its tick planned a window (`Settle`), the node's state changed (`Transition`) or it
/// took more than a heartbeat (`Traffic`), else `Steady`. One heartbeat does not count as a command. Every cycle is also recorded as
/// `Cycle`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `Node::new` (the preview-control gains: about 1100 Riccati iterations), moved into its
    /// `static`.
    New,
    /// A cycle that received `STEP_APPEND` frames (and no other command).
    Push,
    /// A cycle that received a `Start`: plans the start window.
    Start,
    /// A cycle that received `STEP_MODIFY` frames: a modification of the next swing target
    /// plans the re-plan it will cause (eq. 17); the cycle's tick may re-plan too.
    Modify,
    /// A cycle that received a `VELOCITY` or a `GOAL` (a start from standing or a re-plan of
    /// the queued steps), or in which the node chose steps itself (a walk it drives: the queue
    /// topped up after a lift-off, no footstep append received); footstep frames in the same
    /// cycle are refused (`WrongState`).
    Drive,
    /// A cycle that received a `Stop`, `StopNow` or emergency stop (and did not re-plan).
    StopCommand,
    /// A cycle standing, no command.
    Standing,
    /// A walking cycle that planned no window and took no frame but at most one heartbeat (and
    /// the estimator's measured state).
    Steady,
    /// A walking cycle whose tick planned a window other than a re-plan at the start of a
    /// single support: the stop window (the robot settles after a `Stop`, a supervision stop
    /// or a failed re-plan).
    Settle,
    /// A walking cycle without plan and without command in which the node's published state
    /// changed: a supervision stop (the controller fell silent: the queue is dropped), the end
    /// of a walk.
    Transition,
    /// A walking cycle without plan and without planning command that took more than one
    /// frame, or a reset, an invalid frame or another node's frame (duplicates, floods).
    Traffic,
    /// A cycle whose tick re-plans at the start of a single support, no time adjustment.
    Replan,
    /// A cycle whose tick re-plans with a single-support time adjustment
    /// (`adjust_ticks != 0`: eq. 18 solves the target pattern too).
    Adjust,
    /// A cycle in which the node worked on moving the steps from the measured state (its step
    /// adjustment: the reach's bisection and eq. 17's check, carried out or not), no command
    /// planned.
    StepAdjust,
    /// Every control cycle.
    Cycle,
}

impl Kind {
    /// Every kind, in report order.
    pub const ALL: [Kind; 15] = [
        Kind::New,
        Kind::Push,
        Kind::Start,
        Kind::Modify,
        Kind::Drive,
        Kind::StopCommand,
        Kind::Standing,
        Kind::Steady,
        Kind::Settle,
        Kind::Transition,
        Kind::Traffic,
        Kind::Replan,
        Kind::Adjust,
        Kind::StepAdjust,
        Kind::Cycle,
    ];

    /// The name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Kind::New => "new",
            Kind::Push => "push",
            Kind::Start => "start",
            Kind::Modify => "modify",
            Kind::Drive => "drive",
            Kind::StopCommand => "stop-command",
            Kind::Standing => "standing",
            Kind::Steady => "steady",
            Kind::Settle => "settle",
            Kind::Transition => "transition",
            Kind::Traffic => "traffic",
            Kind::Replan => "replan",
            Kind::Adjust => "adjust",
            Kind::StepAdjust => "step-adjust",
            Kind::Cycle => "cycle",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Statistics of one kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stat {
    /// Number of samples.
    pub n: u32,
    /// Largest sample.
    pub max: u32,
    /// Control tick of the largest sample (the gait's tick count when it was taken).
    pub max_tick: u64,
    /// Sum of the samples.
    pub sum: u64,
}

impl Stat {
    fn record(&mut self, units: u32, tick: u64) {
        if self.n == 0 || units > self.max {
            self.max = units;
            self.max_tick = tick;
        }
        self.n += 1;
        self.sum += u64::from(units);
    }
}

/// Statistics of every kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    by_kind: [Stat; Kind::ALL.len()],
}

impl Stats {
    /// Nothing recorded.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records one sample of `kind` taken at control tick `tick`.
    pub fn record(&mut self, kind: Kind, units: u32, tick: u64) {
        self.by_kind[kind.index()].record(units, tick);
    }

    /// The statistics of `kind`.
    pub fn get(&self, kind: Kind) -> &Stat {
        &self.by_kind[kind.index()]
    }

    /// Adds the samples of `other` (the tick of a maximum is kept as recorded).
    pub fn merge(&mut self, other: &Stats) {
        for (mine, theirs) in self.by_kind.iter_mut().zip(other.by_kind.iter()) {
            if theirs.n == 0 {
                continue;
            }
            if mine.n == 0 || theirs.max > mine.max {
                mine.max = theirs.max;
                mine.max_tick = theirs.max_tick;
            }
            mine.n += theirs.n;
            mine.sum += theirs.sum;
        }
    }
}
