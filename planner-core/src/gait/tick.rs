//! One tick of the gait: the phase machine (standing, start, double and single support, stop),
//! the re-plan at every start of single support (with eq. 18's adjustment when the swing target
//! was modified), the stop window, and the swing foot's trajectory.

use super::*;

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    /// Advances one control period and returns its reference.
    pub fn tick(&mut self) -> Reference<T> {
        self.tick += 1;
        let Some(c) = self.cur_buf() else {
            self.last.phase = Phase::Standing;
            self.last.feet = self.ground_poses();
            return self.last;
        };
        self.wins[c].tick += 1;
        let wt = self.wins[c].tick;
        let mut kept = None;
        if let Some(j) = self.wins[c].spec.replan {
            if self.wins[c].starts.get(j) == Some(&wt) {
                // The state at this instant, from the window being left (shaped).
                let (sx, sy) = self.shaped(wt);
                let (cog, zmp) = states(&sx, &sy);
                if self.replan(j, cog, zmp) {
                    self.start_shaping();
                } else {
                    kept = Some((sx, sy));
                }
            }
        }
        let c = self.cur_buf().unwrap_or(c);
        let end = self.wins[c].starts[M];
        if self.wins[c].tick >= end && self.wins[c].spec.replan.is_none() {
            // The stop window has ended: standing (it is never shaped, so the analytic end,
            // at rest, is the reference).
            let (sx, sy) = self.wins[c].sample(&self.params, end);
            self.last.x = sx;
            self.last.y = sy;
            self.mode = Mode::Standing;
            self.stop_requested = false;
            self.last.phase = Phase::Standing;
            self.last.feet = self.ground_poses();
            self.cur = None;
            self.from_measured = false;
            return self.last;
        }
        let t = self.wins[c].tick.min(end);
        let (sx, sy) = match kept {
            Some(k) => k,
            None => self.shaped(t),
        };
        let win = &self.wins[c];
        let j = win.interval(t);
        let phase = match win.spec.support[j] {
            Some(s) if win.spec.kinds[j] == Kind::Single => Phase::Single(s),
            _ => Phase::Double,
        };
        // The swing ends with the double support that follows it: land it before the poses
        // of this tick are taken.
        if let Some(s) = self.swing {
            if phase == Phase::Double && win.spec.kinds[j] == Kind::Double {
                self.feet[s.step.side.index()] = s.step;
                self.landed = Some(s.step.side);
                self.swing = None;
            }
        }
        // Field by field (small copies the compiler does in registers, not one 150-byte
        // `memcpy` of a whole `Reference` built aside).
        self.last.feet = self.foot_poses(&self.wins[c], j, t);
        self.last.x = sx;
        self.last.y = sy;
        self.last.phase = phase;
        self.last
    }

    /// Re-plans at the start of the single support `j` of the current window, into the spare
    /// buffer; `true` if the new window is now the current one. If the walking window cannot
    /// be planned, the queue is dropped and the stop window planned instead (flagged); only if
    /// that fails too does the old window go on.
    pub(super) fn replan(&mut self, j: usize, cog: [State<T>; 2], zmp: [State<T>; 2]) -> bool {
        let Some(c) = self.cur_buf() else {
            return false;
        };
        let spare = 1 - c;
        // Land the swing that just ended (the double support before this single support).
        if let Some(s) = self.swing.take() {
            self.feet[s.step.side.index()] = s.step;
            self.landed = Some(s.step.side);
        }
        let Some(mut inputs) = self.next_walk_inputs(&self.wins[c], j) else {
            // Stopping with nothing left to swing: settle.
            return self.plan_stop(c, j, cog, zmp);
        };
        let at = self.wins[c].tick;
        let (adjust, ratio, plane) = self.adjustment(c, at, cog, zmp).unwrap_or((0, T::ONE, 0));
        inputs.first_ticks = adjusted(self.params.single_ticks, adjust);
        // The swing target is the queue front; if there is none (walking in place), the
        // padded zero-length step.
        let swing = match self.queue.pop_front() {
            Some(q) => q,
            None => Queued {
                id: u16::MAX,
                step: inputs.land[0],
                modified: false,
                capture: false,
            },
        };
        // The hint is false whenever the queue is empty (as after every `clear`).
        self.consecutive &= !self.queue.is_empty();
        // Planned already by the feasibility check of a modification, with the same inputs
        // from the same state? Then the spare buffer holds this very plan.
        let this = self.prediction(at, inputs, cog, zmp);
        let cached = self.predicted.take() == Some(this);
        // A capture step's window starts from the measured state if that plan keeps the ZMP in
        // the sole (eq. 17), else from the reference's as every other window. The try plans
        // into the spare buffer: a predicted plan is gone then.
        let tried = swing.capture && self.measured.error != [T::ZERO; 2];
        let measured_worst = if tried {
            self.plan_from_measured(spare, &inputs, cog, zmp)
        } else {
            None
        };
        let from_measured = measured_worst.is_some();
        let cached = cached && !tried;
        let planned = cached || from_measured;
        let count = u32::from(tried) + u32::from(!planned);
        self.walk_plans = self.walk_plans.wrapping_add(count);
        if !planned
            && self.wins[spare]
                .plan_into(&self.params, &inputs, cog, zmp)
                .is_err()
        {
            // The walking window cannot be planned (a validated configuration never gets
            // here): do not walk on a plan the feet no longer follow. Drop the queue and settle
            // between the feet where they stand; flagged until a walking plan succeeds.
            self.failed = true;
            self.queue.clear();
            self.consecutive = false;
            self.stop_requested = true;
            self.gen = self.gen.wrapping_add(1);
            return self.plan_stop(c, j, cog, zmp);
        }
        self.failed = false;
        self.from_measured = from_measured;
        // Eq. 17 of this plan: computed already if it is the predicted one.
        let worst_zmp = match measured_worst {
            Some(w) => w,
            None if cached => self.predicted_worst,
            None => self.wins[spare].worst_first(),
        };
        self.cur = Some(spare);
        self.serial = self.serial.wrapping_add(1);
        self.swing = Some(swing);
        for q in self.queue.iter_mut() {
            q.modified = false;
            q.capture = false;
        }
        self.info = Some(ReplanInfo {
            tick: self.tick,
            adjust_ticks: adjust,
            ratio,
            plane,
            worst_zmp,
        });
        true
    }

    /// Plans the stop window at the single support `j` of the current window `c` (the robot
    /// settles between its feet); `true` if it is now the current one. On failure the old
    /// window goes on (flagged: [`Gait::replan_failed`]).
    pub(super) fn plan_stop(
        &mut self,
        c: usize,
        j: usize,
        cog: [State<T>; 2],
        zmp: [State<T>; 2],
    ) -> bool {
        let spare = 1 - (c & 1);
        let side = self.wins[c & 1]
            .spec
            .support
            .get(j)
            .copied()
            .flatten()
            .unwrap_or(Side::Left);
        let support = self.feet[side.index()];
        let other = self.feet[side.other().index()];
        let inputs = Inputs {
            kind: WindowKind::Stop,
            support,
            other,
            land: [support; 3],
            n_land: 0,
            first_ticks: self.params.settle_ticks,
        };
        if self.wins[spare]
            .plan_into(&self.params, &inputs, cog, zmp)
            .is_err()
        {
            self.failed = true;
            return false;
        }
        self.cur = Some(spare);
        self.serial = self.serial.wrapping_add(1);
        self.from_measured = false;
        true
    }

    /// `true` if the last re-plan failed (the gait then stops: see the module docs); cleared by
    /// the next walking plan that succeeds.
    pub fn replan_failed(&self) -> bool {
        self.failed
    }

    /// `true` if the next swing (the front of the queue) starts from rest: standing, in the
    /// start window before its first swing, or in a stop window (a new `Start` is needed).
    pub fn next_swing_from_rest(&self) -> bool {
        match self.cur_buf() {
            None => true,
            Some(c) => match self.wins[c].inputs.kind {
                WindowKind::Start => self.swing.is_none(),
                WindowKind::Stop => true,
                WindowKind::Walk => false,
            },
        }
    }

    /// The position of the queued step `id` in the queue (0: the next swing target).
    pub fn position(&self, id: u16) -> Option<usize> {
        self.index_of(id)
    }

    pub(super) fn ground_poses(&self) -> [FootPose<T>; 2] {
        let pose = |f: &Footstep<T>| FootPose {
            x: f.x,
            y: f.y,
            z: T::ZERO,
            yaw: wrap_angle(f.yaw),
        };
        [pose(&self.feet[0]), pose(&self.feet[1])]
    }

    pub(super) fn foot_poses(&self, win: &Active<T>, j: usize, t: u32) -> [FootPose<T>; 2] {
        let mut poses = self.ground_poses();
        if let (Some(s), Kind::Single) = (self.swing, win.spec.kinds[j]) {
            let from = self.feet[s.step.side.index()];
            let to = s.step;
            let len = win.spec.ticks[j].max(1);
            let sn = T::of((t - win.starts[j]) as f64 / len as f64);
            // Quintic smoothstep: zero velocity and acceleration at lift-off and touch-down.
            let b = sn * sn * sn * (T::of(10.0) + sn * (T::of(-15.0) + T::of(6.0) * sn));
            // Height 64 s³(1−s)³: peak 1 at mid-swing, zero velocity and acceleration at
            // lift-off and touch-down (no jerk into the multi-body ZMP).
            let q = sn * (T::ONE - sn);
            let lift = T::of(64.0) * q * q * q;
            poses[s.step.side.index()] = FootPose {
                x: from.x + b * (to.x - from.x),
                y: from.y + b * (to.y - from.y),
                z: self.params.step_height * lift,
                // Along the shorter way round (a turn across ±π), in [−π, π].
                yaw: wrap_angle(from.yaw + b * wrap_angle(to.yaw - from.yaw)),
            };
        }
        poses
    }
}
