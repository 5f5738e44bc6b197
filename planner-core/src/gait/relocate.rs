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

use super::*;

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
