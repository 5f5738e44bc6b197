//! Moving queued steps together (the node's step adjustment: the next landing and the ones
//! after it by one shift), the check of the next swing target's move by eq. 17, and the time
//! left until the next swing target lands.
//!
//! A move of the next swing target is a modification in the paper's sense: it is marked
//! modified, so the re-plan at the next start of single support adjusts the single support by
//! eq. 18 and shapes the fluctuation, as for a modification from the bus, with one
//! difference: a capture step must come early, so eq. 18 may shorten its single support but
//! not lengthen it (`ΔT ≤ 0`; Khadiv et al., Humanoids 2016, adapt the step time the same
//! way). A modification from the bus after the move makes it an ordinary modification again.
//!
//! # A capture step's window starts from the measured state
//! The robot that needed the capture step is not where the reference is: its divergent
//! component `ξ = x + ẋ/ω` is off the reference's by the measured `e`
//! ([`Gait::set_measured`]). The re-plan that lifts the capture step's foot therefore starts
//! from the reference's COG position with the velocity `ẋ + ω e_c` (the COG continuous), `e_c`
//! the part of `e` that the landing's move captures (all of it unless the reach cut the move:
//! [`captured_deviation`]), so that the new window brings the robot's own divergent component to the
//! moved landings instead of the reference's, which the robot's stabilizer would otherwise
//! chase with its ZMP at the sole's edge. That window is taken if eq. 17 holds for it (the
//! ZMP stays in the sole); otherwise the re-plan starts from the reference's state, as every
//! other re-plan does. A window not started by a capture step ignores the measurement.

use super::*;
use crate::capture::captured_deviation;

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    /// Moves queued steps: `place(id)` gives the new position `[x, y]` of queued step `id`, or
    /// `None` to leave it where it is (headings are kept). Nothing is checked here: the caller
    /// checks the reach and then [`Gait::check_next_target`], and puts the steps back with a
    /// second call if either refuses. A step whose position changes is marked modified.
    pub fn place_steps(&mut self, place: impl Fn(u16) -> Option<[T; 2]>) {
        let mut moved = false;
        for q in self.queue.iter_mut() {
            if let Some([x, y]) = place(q.id) {
                if q.step.x != x || q.step.y != y {
                    q.step.x = x;
                    q.step.y = y;
                    q.modified = true;
                    q.capture = true;
                    moved = true;
                }
            }
        }
        if moved {
            self.predicted = None;
            self.gen = self.gen.wrapping_add(1);
        }
    }

    /// The measured state that the next re-plan of a capture step starts from (see the module
    /// docs); [`Deviation::ZERO`], the default, leaves every re-plan on the reference's state.
    /// The node's step adjustment sets it every cycle from a fresh measured state, and to zero
    /// without one.
    pub fn set_measured(&mut self, measured: Deviation<T>) {
        self.measured = measured;
    }

    /// The next tick re-plans at a start of single support (the re-plan that lifts the next
    /// swing target's foot, and that a capture step's may start from the measured state).
    pub fn replans_next_tick(&self) -> bool {
        let Some(c) = self.cur_buf() else {
            return false;
        };
        let w = &self.wins[c];
        w.spec
            .replan
            .is_some_and(|j| w.starts.get(j) == Some(&w.tick.wrapping_add(1)))
    }

    /// The window being executed was planned from the measured state (a capture step's window
    /// whose plan kept the ZMP in the sole; see the module docs); `false` after the start and
    /// the stop windows.
    pub fn replanned_from_measured(&self) -> bool {
        self.from_measured
    }

    /// The window of a capture step planned into the buffer `spare` from the measured state:
    /// the reference's COG position, its velocity moved by `ω e_c`, with `e_c` the part of the
    /// measured deviation that the landing's move captures over the single support
    /// ([`captured_deviation`]). Its worst first-interval ZMP excursion if the plan exists and
    /// keeps the ZMP in the sole (eq. 17), else `None` (the buffer then holds nothing to use).
    /// Kept out of line, so that a re-plan that does not call it stays as it was.
    #[inline(never)]
    pub(super) fn plan_from_measured(
        &mut self,
        spare: usize,
        inputs: &Inputs<T>,
        cog: [State<T>; 2],
        zmp: [State<T>; 2],
    ) -> Option<[T; 2]> {
        let p = &self.params;
        let d = self.measured;
        let e = captured_deviation(
            d.error,
            d.moved,
            d.margin,
            p.omega,
            p.seconds(inputs.first_ticks),
        );
        let mut from = cog;
        for (s, e) in from.iter_mut().zip(e) {
            s.vel += p.omega * e;
        }
        let win = &mut self.wins[spare & 1];
        win.plan_into(&self.params, inputs, from, zmp).ok()?;
        let worst = win.worst_first();
        self.inside_sole(worst).then_some(worst)
    }

    /// Eq. 17 for the next swing target as it is queued now (see the module docs of
    /// [`crate::gait`]): `Infeasible` if the re-plan it will cause takes the ZMP outside the
    /// support sole. Plans (the cost of a modification's check); `Ok` with nothing to check
    /// (standing, or no re-plan due).
    pub fn check_next_target(&mut self) -> Result<(), GaitError> {
        if self.mode != Mode::Walking {
            return Ok(());
        }
        match self.predict_replan() {
            Ok(Some(worst)) if !self.inside_sole(worst) => {
                self.predicted = None;
                Err(GaitError::Infeasible)
            }
            Err(e) => {
                self.predicted = None;
                Err(e)
            }
            _ => Ok(()),
        }
    }

    /// Ticks from now until the next swing target (the first queued step) lands, by the window
    /// being executed: the end of the first single support that swings it (the one after the
    /// swing in progress, if any). `None` when standing or when the window does not swing it
    /// (a stop window without it, or beyond the window).
    pub fn ticks_to_next_landing(&self) -> Option<u32> {
        self.queue.front()?;
        let c = self.cur_buf()?;
        let win = &self.wins[c];
        let t = win.tick;
        let now = win.interval(t);
        let mut skip = self.swing.is_some() && win.spec.kinds[now] == Kind::Single;
        for j in now..M {
            if win.spec.kinds[j] != Kind::Single {
                continue;
            }
            if skip {
                skip = false;
                continue;
            }
            return win.starts.get(j + 1).map(|&end| end.saturating_sub(t));
        }
        None
    }
}
