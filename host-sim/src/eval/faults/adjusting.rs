//! The adjusting walk of the fault sweep ([`super::Walk::Adjusting`]): the robot and its state
//! estimator on their own port ([`Estimator`]), what the node took of the estimator's frames
//! ([`super::MeasuredCount`], from its answers), and the two books of the node's shift
//! ([`Shifts`]): the node's own, and the controller's, built from the `ADJUST` frames it
//! received.
//!
//! The robot is [`crate::sim::pushed`]'s pendulum under its DCM stabilizer, tracking the node's
//! references as the node hands them to the bus; the estimator sends `ξ − ξ_ref` against the
//! reference of the cycle the robot tracked, every cycle, keyed with the session. The robot is
//! pushed once, [`PUSH_DELAY_TICKS`] after the third lift-off, by a velocity step drawn from
//! the seed: 0.15 … 0.25 m/s in any direction. That puts the DCM about 43 … 72 mm (Δv/ω) off
//! the reference's, beyond the node's 20 mm margin, so the node adjusts; and it is small enough
//! that a run in which the faults keep the node from adjusting need not fall (the sweep's test
//! asserts that no pendulum falls, adjusted or not). Under [`super::FaultKind::Blind`] the
//! estimator stops sending 0 … 0.3 s after the push (it has no estimate any more), while the
//! deviation still grows.

use embedded_can::nb::Can;
use planner_core::gait::{Footstep, GaitParams, Reference};
use planner_core::wire::{ids, Ack, Measured, Reason, STEP_UNIT};

use super::ports::Rng;
use super::MeasuredCount;
use crate::sim::bus::Port;
use crate::sim::pushed::{Pendulum, FALLEN_M, PUSH_DELAY_TICKS};

/// The push's speed, least and greatest \[m/s\].
pub const PUSH_DV: [f64; 2] = [0.15, 0.25];
/// Under `Blind`, the estimator stops this many cycles after the push at most (0.3 s).
pub const BLIND_AFTER: u64 = 60;

/// The robot and its state estimator (see the module docs).
pub(super) struct Estimator {
    /// The estimator's port.
    pub(super) port: Port,
    robot: Pendulum,
    /// The cycle the robot tracked last and its DCM's deviation from that cycle's reference.
    tracked: Option<(u32, [f64; 2])>,
    dv: [f64; 2],
    swinging: Option<u16>,
    liftoffs: u32,
    push_at: Option<u64>,
    /// Cycles after the push at which the estimator stops (`Blind`).
    blind_after: Option<u64>,
    /// The first node cycle whose `MEASURED` was not sent (`Blind`).
    pub(super) silent_from: Option<u32>,
    /// The robot's DCM left the reference's by more than [`FALLEN_M`].
    pub(super) fell: bool,
}

impl Estimator {
    /// The robot at rest at `r0`; its push and, with `blind`, its estimator's silence drawn
    /// from `seed`.
    pub(super) fn new(port: Port, r0: &Reference<f64>, seed: u64, blind: bool) -> Self {
        let mut rng = Rng::new(seed ^ 0x0090_54ED);
        let speed = rng.range(PUSH_DV[0], PUSH_DV[1]);
        let (s, c) = rng.range(0.0, std::f64::consts::TAU).sin_cos();
        let after = rng.next() % (BLIND_AFTER + 1);
        Estimator {
            port,
            robot: Pendulum::at(r0),
            tracked: None,
            dv: [speed * c, speed * s],
            swinging: None,
            liftoffs: 0,
            push_at: None,
            blind_after: blind.then_some(after),
            silent_from: None,
            fell: false,
        }
    }

    /// Before the node's cycle `k`: sends what the robot measured in the last one (`epoch`:
    /// the session's); nothing once silent.
    pub(super) fn send(&mut self, k: u64, epoch: u32) {
        while self.port.receive().is_ok() {}
        let silent = match (self.push_at, self.blind_after) {
            (Some(p), Some(a)) => k >= p + a,
            _ => false,
        };
        let Some((stamp, e)) = self.tracked else {
            return;
        };
        if silent {
            self.silent_from.get_or_insert(stamp);
            return;
        }
        if let Some(m) = Measured::from_si(stamp, e) {
            let _ = self.port.transmit(&m.encode(epoch));
        }
    }

    /// After the node's cycle `k` (its count `cycle`, its reference `r`, the step it swings):
    /// the robot over the cycle, and the push.
    pub(super) fn track(
        &mut self,
        k: u64,
        cycle: u32,
        r: &Reference<f64>,
        swinging: Option<u16>,
        p: &GaitParams<f64>,
    ) {
        let e = self.robot.deviation(r, p.omega);
        if e[0].hypot(e[1]) > FALLEN_M {
            self.fell = true;
        }
        self.robot.track(r, e, p);
        self.tracked = Some((cycle, e));
        if swinging.is_some() && swinging != self.swinging {
            self.liftoffs += 1;
            if self.liftoffs == 3 {
                self.push_at = Some(k + PUSH_DELAY_TICKS);
            }
        }
        self.swinging = swinging;
        if self.push_at == Some(k) {
            self.robot.push(self.dv);
        }
    }
}

/// Counts the node's answer `a` to a `MEASURED` frame, handed to the bus in the cycle after
/// which the node's count is `cycle`; `max_age`: the node's. Returns whether a state older
/// than `max_age` was taken (the answer's stamp byte against the cycle).
pub(super) fn count_measured(n: &mut MeasuredCount, a: &Ack, cycle: u32, max_age: u32) -> bool {
    if a.command != (ids::MEASURED & 0xFF) as u8 {
        return false;
    }
    match a.reason {
        None => {
            n.taken += 1;
            // The last reference published before the cycle that took it is `cycle − 1`.
            let age = (cycle.wrapping_sub(1) as u8).wrapping_sub(a.seq);
            return u32::from(age) > max_age;
        }
        Some(Reason::Stale) => n.stale += 1,
        Some(Reason::BadCrc) => n.bad_crc += 1,
        Some(Reason::Duplicate) => n.duplicate += 1,
        Some(_) => n.other += 1,
    }
    false
}

/// One shift of the steps: the first step number it applies to and the shift \[0.5 mm\].
type Shift = (u16, [i32; 2]);

/// The books of the node's shift.
#[derive(Default)]
pub(super) struct Shifts {
    /// The node's own, every change in order, with the node cycle it was made in and whether
    /// it was the end of the shift with its walk (the robot standing: not an adjustment).
    pub(super) node: Vec<(u32, Shift, bool)>,
    /// The controller's, from the `ADJUST` frames it received (by their count of adjustments:
    /// a late or repeated copy changes nothing; from 255 on, the count saturates and the
    /// latest frame received counts).
    pub(super) heard: std::collections::BTreeMap<u8, Shift>,
}

impl Shifts {
    /// Records the node's shift after a cycle (`cycle`: its count), if it changed;
    /// `standing`: the robot stands after the cycle (a change then is the shift's end with
    /// its walk).
    pub(super) fn note(&mut self, cycle: u32, now: Shift, standing: bool) {
        // (Every adjustment changes the shift: by the node's least change, 5 mm.)
        if self.node.last().map_or([0, 0], |e| e.1 .1) != now.1 {
            self.node.push((cycle, now, standing));
        }
    }

    /// The adjustments (the changes made walking), in order, with their node cycles.
    pub(super) fn adjustments(&self) -> impl Iterator<Item = (u32, Shift)> + '_ {
        self.node.iter().filter(|e| !e.2).map(|e| (e.0, e.1))
    }

    /// The shift step `id` landed with, by the node's book: the last one made while it was
    /// not yet lifted off (the node shifts the next swing target and the steps after it).
    pub(super) fn of(&self, id: u16) -> [i32; 2] {
        last_from(self.node.iter().map(|e| e.1), id)
    }

    /// The same by the controller's book.
    pub(super) fn heard_of(&self, id: u16) -> [i32; 2] {
        last_from(self.heard.values().copied(), id)
    }
}

fn last_from(shifts: impl Iterator<Item = Shift>, id: u16) -> [i32; 2] {
    shifts
        .filter(|(from, _)| *from <= id)
        .last()
        .map_or([0, 0], |(_, s)| s)
}

/// `f` moved by `shift` \[0.5 mm\].
pub(super) fn shifted(f: &Footstep<f64>, shift: [i32; 2]) -> Footstep<f64> {
    Footstep::new(
        f.side,
        f.x + f64::from(shift[0]) * STEP_UNIT,
        f.y + f64::from(shift[1]) * STEP_UNIT,
        f.yaw,
    )
}
