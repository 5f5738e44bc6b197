//! The footstep queue's commands: re-basing the frame, appending, starting, stopping, dropping
//! and modifying a queued step (a modification of the next swing target checked by eq. 17 and
//! put back if refused).

use super::*;

/// The most steps [`Gait::replace_front`] makes the queue at once.
pub const MODIFY_FRONT: usize = 4;

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    /// Moves the world frame while standing: the new origin is `(x, y)` of the old frame and
    /// the new x axis has the old heading `yaw`. Every pose the gait holds (feet, the resting
    /// reference) is expressed in the new frame; the queue is dropped, and the side of the
    /// next step is free again. `WrongState` unless standing.
    pub fn rebase(&mut self, x: T, y: T, yaw: T) -> Result<(), GaitError> {
        if self.mode != Mode::Standing {
            return Err(GaitError::WrongState);
        }
        if !(x.is_finite() && y.is_finite() && yaw.is_finite()) {
            return Err(GaitError::NonFinite);
        }
        let (s, c) = sin_cos(yaw);
        let to = |px: T, py: T| {
            let (dx, dy) = (px - x, py - y);
            (c * dx + s * dy, -s * dx + c * dy)
        };
        for f in self.feet.iter_mut() {
            let (nx, ny) = to(f.x, f.y);
            f.x = nx;
            f.y = ny;
            f.yaw = wrap_angle(f.yaw - yaw);
        }
        let (cx, cy) = to(self.last.x.cog, self.last.y.cog);
        let (zx, zy) = to(self.last.x.zmp, self.last.y.zmp);
        let rot = |a: T, b: T| (c * a + s * b, -s * a + c * b);
        let (vx, vy) = rot(self.last.x.cog_vel, self.last.y.cog_vel);
        let (ax, ay) = rot(self.last.x.cog_acc, self.last.y.cog_acc);
        let (wx, wy) = rot(self.last.x.zmp_vel, self.last.y.zmp_vel);
        self.last.x = Sample {
            cog: cx,
            cog_vel: vx,
            cog_acc: ax,
            zmp: zx,
            zmp_vel: wx,
        };
        self.last.y = Sample {
            cog: cy,
            cog_vel: vy,
            cog_acc: ay,
            zmp: zy,
            zmp_vel: wy,
        };
        self.last.feet = self.ground_poses();
        self.queue.clear();
        self.consecutive = false;
        self.landed = None;
        self.stop_requested = false;
        self.target = None;
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Where each foot stands (left, right); the swinging foot where it lifted off.
    pub fn feet(&self) -> &[Footstep<T>; 2] {
        &self.feet
    }

    /// Appends a footstep. A full queue hands the step back.
    pub fn push(&mut self, id: u16, step: Footstep<T>) -> Result<(), (GaitError, Footstep<T>)> {
        if !step.is_finite() {
            return Err((GaitError::NonFinite, step));
        }
        if let Some(side) = self.next_side() {
            if side != step.side {
                return Err((GaitError::SideOrder, step));
            }
        }
        let consecutive = match self.queue.back() {
            None => true,
            Some(b) => self.consecutive && id == b.id.wrapping_add(1),
        };
        self.queue
            .push_back(Queued {
                id,
                step,
                modified: false,
                capture: false,
            })
            .map_err(|q| (GaitError::QueueFull, q.step))?;
        self.consecutive = consecutive;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Starts walking (from standing) with the queued steps.
    pub fn start(&mut self) -> Result<(), GaitError> {
        if self.mode != Mode::Standing {
            return Err(GaitError::WrongState);
        }
        let Some(first) = self.queue.front() else {
            return Err(GaitError::WrongState);
        };
        // A stop requested while standing (an emergency stop before the walk) is not this
        // walk's: the start window is planned as for a node that never had it.
        self.stop_requested = false;
        let support = self.feet[first.step.side.other().index()];
        let other = self.feet[first.step.side.index()];
        let (land, n) = self.landings(&support, 0);
        let inputs = Inputs {
            kind: WindowKind::Start,
            support,
            other,
            land,
            n_land: n,
            first_ticks: self.params.start_ticks,
        };
        let (cog, zmp) = self.state();
        self.wins[0].plan_into(&self.params, &inputs, cog, zmp)?;
        self.cur = Some(0);
        self.serial = self.serial.wrapping_add(1);
        self.from_measured = false;
        self.start_shaping();
        // The reference of this instant becomes the window's tick 0 (the same position, with
        // the velocities the pattern starts with), and the compensators take their tick 0.
        let (sx, sy) = self.shaped(0);
        self.last.x = sx;
        self.last.y = sy;
        self.mode = Mode::Walking;
        self.stop_requested = false;
        self.failed = false;
        for q in self.queue.iter_mut() {
            q.modified = false;
            q.capture = false;
        }
        Ok(())
    }

    /// Requests a stop: the queued steps are walked, then the robot settles between its feet.
    /// Steps that are not given are no longer padded with steps in place.
    /// A stop already requested changes nothing (the plan stays valid).
    pub fn stop(&mut self) {
        if !self.stop_requested {
            self.stop_requested = true;
            self.gen = self.gen.wrapping_add(1);
        }
    }

    /// Cancels a requested stop while it can still be undone: walking, with a step queued
    /// after the one being swung (its foot has not lifted off) and the re-plan at the next
    /// single support still ahead in the window being walked. The walk goes on as before the
    /// stop (the landings padded with steps in place). The caller checks the re-plan this
    /// causes as for a modification ([`Gait::modify`], eq. 17) and requests the stop
    /// again if it is refused. `WrongState` (nothing changed) when no stop can be cancelled.
    pub fn resume(&mut self) -> Result<(), GaitError> {
        if !self.resumable() {
            return Err(GaitError::WrongState);
        }
        self.stop_requested = false;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Drops the queued steps after the first `keep` (none of them has lifted off: the step
    /// being swung is not queued), and nothing else: how the node shortens its own steps to
    /// what a stop needs (the stop is requested apart, [`Gait::stop`]).
    pub fn truncate(&mut self, keep: usize) {
        if self.queue.len() <= keep {
            return;
        }
        while self.queue.len() > keep {
            self.queue.pop_back();
        }
        self.consecutive &= !self.queue.is_empty();
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
    }

    /// `true` if [`Gait::resume`] would cancel the stop under way.
    pub fn resumable(&self) -> bool {
        self.is_stopping()
            && !self.queue.is_empty()
            && self.cur_buf().is_some_and(|c| {
                let w = &self.wins[c];
                w.spec
                    .replan
                    .and_then(|j| w.starts.get(j))
                    .is_some_and(|&at| at > w.tick)
            })
    }

    /// Drops every queued step while standing, and nothing else (no stop is requested: a
    /// later `start` walks what is queued then exactly as if nothing had been dropped).
    pub fn drop_queue(&mut self) -> Result<(), GaitError> {
        if self.mode != Mode::Standing {
            return Err(GaitError::WrongState);
        }
        self.queue.clear();
        self.consecutive = false;
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Drops every queued step (not the one being swung) and stops after the present swing.
    pub fn clear_and_stop(&mut self) {
        self.queue.clear();
        self.consecutive = false;
        self.stop_requested = true;
        self.gen = self.gen.wrapping_add(1);
    }

    /// Modifies the queued step `id`. Refused when its foot has lifted off, when it is unknown,
    /// or when the re-plan it would cause is infeasible (eq. 17); the queue is unchanged then.
    pub fn modify(&mut self, id: u16, step: Footstep<T>) -> Result<(), GaitError> {
        if !step.is_finite() {
            return Err(GaitError::NonFinite);
        }
        if self.swing.map(|s| s.id) == Some(id) {
            return Err(GaitError::LiftedOff);
        }
        let Some(pos) = self.index_of(id) else {
            return Err(GaitError::UnknownStep);
        };
        if self.queue.get(pos).map(|q| q.step.side) != Some(step.side) {
            return Err(GaitError::SideOrder);
        }
        let old = self.queue.get(pos).copied();
        if let Some(q) = self.queue.get_mut(pos) {
            q.step = step;
            q.modified = true;
            q.capture = false;
        }
        self.gen = self.gen.wrapping_add(1);
        if pos == 0 && self.mode == Mode::Walking {
            // This is the next swing target: check the re-plan it will cause.
            match self.predict_replan() {
                Ok(Some(worst)) if !self.inside_sole(worst) => {
                    self.undo_modify(pos, old);
                    return Err(GaitError::Infeasible);
                }
                Err(e) => {
                    self.undo_modify(pos, old);
                    return Err(e);
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Makes the queue `steps` (at most [`MODIFY_FRONT`], from the next swing target on) at
    /// once, and requests a stop after them if `stop` (else cancels one that was requested):
    /// how the node re-plans the steps it chooses itself when the commanded velocity changes.
    /// The queued steps are replaced in place (each with its side and number kept), those
    /// beyond `steps` dropped, and the steps beyond the queue appended, numbered from `id`.
    /// While walking, the re-plan the new queue causes at the next start of single support is
    /// checked once, with every step and the stop in place (eq. 17, as [`Gait::modify`]): it
    /// is the plan that re-plan takes. If it is refused, the queue and the stop request are
    /// put back as they were and the error returned (`Infeasible`; `WrongState` when more
    /// than [`MODIFY_FRONT`] steps are given or queued, `SideOrder` when a side differs from
    /// the queued step's or the steps do not alternate, `NonFinite`).
    #[inline(never)]
    pub fn replace_front(
        &mut self,
        steps: &[Footstep<T>],
        id: u16,
        stop: bool,
    ) -> Result<(), GaitError> {
        let queued = self.queue.len();
        if steps.len() > MODIFY_FRONT || queued > MODIFY_FRONT {
            return Err(GaitError::WrongState);
        }
        if steps.iter().any(|s| !s.is_finite()) {
            return Err(GaitError::NonFinite);
        }
        let mut side = self.queue.front().map(|q| q.step.side);
        if queued == 0 {
            side = self.next_side();
        }
        for (i, s) in steps.iter().enumerate() {
            let want = match self.queue.get(i) {
                Some(q) => Some(q.step.side),
                None => side,
            };
            if want.is_some_and(|w| w != s.side) {
                return Err(GaitError::SideOrder);
            }
            side = Some(s.side.other());
        }
        let mut old: [Option<Queued<T>>; MODIFY_FRONT] = [None; MODIFY_FRONT];
        for (slot, q) in old.iter_mut().zip(self.queue.iter()) {
            *slot = Some(*q);
        }
        let (old_stop, old_consecutive) = (self.stop_requested, self.consecutive);
        while self.queue.len() > steps.len() {
            self.queue.pop_back();
        }
        for (i, s) in steps.iter().enumerate() {
            if let Some(q) = self.queue.get_mut(i) {
                q.step = *s;
                q.modified = true;
                q.capture = false;
                continue;
            }
            let n = id.wrapping_add((i - queued) as u16);
            let consecutive = match self.queue.back() {
                None => true,
                Some(b) => self.consecutive && n == b.id.wrapping_add(1),
            };
            let q = Queued {
                id: n,
                step: *s,
                modified: false,
                capture: false,
            };
            if self.queue.push_back(q).is_err() {
                self.put_back(&old, old_stop, old_consecutive);
                return Err(GaitError::QueueFull);
            }
            self.consecutive = consecutive;
        }
        self.consecutive &= !self.queue.is_empty();
        self.stop_requested = stop;
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
        if self.mode == Mode::Walking {
            let refused = match self.predict_replan() {
                Ok(Some(worst)) if !self.inside_sole(worst) => Some(GaitError::Infeasible),
                Err(e) => Some(e),
                _ => None,
            };
            if let Some(e) = refused {
                self.put_back(&old, old_stop, old_consecutive);
                return Err(e);
            }
        }
        Ok(())
    }

    /// Puts back the queue and the stop request a refused [`Gait::replace_front`] replaced
    /// (the prediction dropped, `gen` moved on: see [`Gait::undo_modify`]).
    fn put_back(&mut self, old: &[Option<Queued<T>>; MODIFY_FRONT], stop: bool, consecutive: bool) {
        self.queue.clear();
        for q in old.iter().flatten() {
            let _ = self.queue.push_back(*q);
        }
        self.stop_requested = stop;
        self.consecutive = consecutive;
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
    }

    /// Puts back the step a refused modification replaced. The spare buffer now holds the
    /// refused plan: the prediction is dropped (a cache: the re-plan computes it again, bit
    /// for bit the same), and `gen` moves on so that no cache keyed on it is taken.
    pub(super) fn undo_modify(&mut self, pos: usize, old: Option<Queued<T>>) {
        if let (Some(q), Some(o)) = (self.queue.get_mut(pos), old) {
            *q = o;
        }
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
    }

    /// `true` if `other` walks on exactly as `self` does: every field that decides a future
    /// reference is equal (queue, feet, swing, phase, the window being executed and its
    /// compensators, the last reference). Not compared: the caches (the spare window buffer,
    /// the eq. 18 target, the prediction of a modification's re-plan, the generation counter
    /// that keys them), which only save work, and the preview gains, which never change.
    pub fn same_state<H: Borrow<PreviewGains<T, PREVIEW>>>(&self, other: &Gait<T, Q, H>) -> bool {
        let mine = self.cur_buf().map(|c| {
            let w = &self.wins[c];
            (w.inputs, w.spec, w.bounds, w.plan, w.tick, w.starts)
        });
        let theirs = other.cur_buf().map(|c| {
            let w = &other.wins[c];
            (w.inputs, w.spec, w.bounds, w.plan, w.tick, w.starts)
        });
        self.params == other.params
            && self.queue.iter().eq(other.queue.iter())
            && self.feet == other.feet
            && self.swing == other.swing
            && self.landed == other.landed
            && self.failed == other.failed
            && self.mode == other.mode
            && self.stop_requested == other.stop_requested
            && self.serial == other.serial
            && self.measured == other.measured
            && self.from_measured == other.from_measured
            && self.tick == other.tick
            && self.last == other.last
            && self.info == other.info
            && self.comp == other.comp
            && mine == theirs
    }

    /// `true` while a requested stop is being carried out (the queue is walked without
    /// padding, then the robot settles).
    pub fn is_stopping(&self) -> bool {
        self.mode == Mode::Walking && self.stop_requested
    }
}
