//! What the node publishes of itself: `STATUS` (state, queue, refusals, overruns, the last
//! eq. 18 adjustment, flags), `DIAG` (foreign frames, bus errors, dropped frames, the next step
//! number) and the reference stream's frames (COG, COG velocity and ZMP of both planes, the
//! phase, the feet).

use super::*;

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// The status as published.
    pub fn status(&self) -> Status {
        let adjust = self
            .gait
            .last_replan()
            .map(|i| i.adjust_ticks.clamp(-128, 127) as i8)
            .unwrap_or(0);
        let mut flags = 0;
        if self.gait.params().shaping {
            flags |= 1;
        }
        if self.gait.replan_failed() {
            flags |= 2;
        }
        if self.counters.tx_dropped > 0 {
            flags |= 4;
        }
        flags |= match self.gait.next_side() {
            None => 0,
            Some(Side::Left) => 1 << 3,
            Some(Side::Right) => 2 << 3,
        };
        if self.clock_fault {
            flags |= Status::CLOCK_FAULT;
        }
        if self.drive.driver != drive::Driver::Steps && self.drive.cut.any() {
            flags |= Status::CUT;
        }
        if self.at_goal() {
            flags |= Status::AT_GOAL;
        }
        Status {
            state: self.state() as u8,
            queue: self.gait.queued().min(255) as u8,
            rejected: self.counters.refused,
            overruns: self.counters.overruns,
            last_adjust: adjust,
            flags,
        }
    }

    /// The diagnostics as published.
    pub fn diag(&self) -> Diag {
        Diag {
            foreign: self.counters.foreign,
            bus_errors: self.counters.bus_errors,
            tx_dropped: self.counters.tx_dropped,
            next_step: self.next_step(),
        }
    }

    pub(super) fn stream(&self, r: &Reference<T>) -> Stream<T> {
        let phase = match r.phase {
            Phase::Standing => 0,
            Phase::Double => 1,
            Phase::Single(Side::Left) => 2,
            Phase::Single(Side::Right) => 3,
        };
        let f = |k: usize| [r.feet[k].x, r.feet[k].y, r.feet[k].z, r.feet[k].yaw];
        Stream {
            cog: [r.x.cog, r.y.cog],
            cog_vel: [r.x.cog_vel, r.y.cog_vel],
            zmp: [r.x.zmp, r.y.zmp],
            phase,
            tick: self.cycle & (crate::wire::STAMPS - 1),
            feet: [f(0), f(1)],
        }
    }
}
