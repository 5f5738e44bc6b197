//! Eq. 17 and eq. 18: the re-plan a modification of the next swing target will cause,
//! predicted when it arrives (its worst ZMP excursion in the support foot's frame must stay inside
//! the sole), and the single-support adjustment `ΔT = ln(d_f / d_i) / ω` from the divergent
//! components `d = ω(x − p) + (ẋ − ṗ)` of the executed and the target pattern.

use super::*;

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    pub(super) fn inside_sole(&self, worst: [T; 2]) -> bool {
        worst[0].abs() <= self.params.sole_half_length
            && worst[1].abs() <= self.params.sole_half_width
    }

    /// The first `n ≤ 3` landings from queue position `skip`, padded with steps in place unless
    /// a stop was requested.
    pub(super) fn landings(&self, support: &Footstep<T>, skip: usize) -> ([Footstep<T>; 3], usize) {
        let mut land = [*support; 3];
        let mut n = 0;
        for q in self.queue.iter().skip(skip).take(3) {
            land[n] = q.step;
            n += 1;
        }
        if !self.stop_requested {
            while n < 3 {
                let prev = if n == 0 { *support } else { land[n - 1] };
                land[n] = prev.beside(self.params.step_width);
                n += 1;
            }
        }
        (land, n)
    }

    /// The buffer being executed, if walking: `self.cur` (always 0 or 1), masked so that
    /// indexing `wins` with it or with `1 - c` needs no bounds check (no panic path).
    pub(super) fn cur_buf(&self) -> Option<usize> {
        self.cur.map(|c| c & 1)
    }

    /// The present reference state (what the next window starts from).
    pub(super) fn state(&self) -> ([State<T>; 2], [State<T>; 2]) {
        states(&self.last.x, &self.last.y)
    }

    /// The re-plan that will happen at the next start of single support if nothing else
    /// changes: returns the worst first-interval ZMP excursion, or `None` if no re-plan is due.
    pub(super) fn predict_replan(&mut self) -> Result<Option<[T; 2]>, GaitError> {
        let Some(c) = self.cur_buf() else {
            return Ok(None);
        };
        let win = &self.wins[c];
        let Some(j) = win.spec.replan else {
            return Ok(None);
        };
        // `j` indexes an interval of `win` (always in range; `None` is never taken).
        let Some(&at) = win.starts.get(j) else {
            return Ok(None);
        };
        // The state the re-plan will start from: the plan at `at`, shaped. If the re-plan is
        // the next tick's, that is exactly what the tick will compute (the compensators'
        // next step, on a copy); further ahead the compensation is left out (it is small: a
        // few millimetres, see the `shaping` module).
        let (sx, sy) = if at == win.tick.wrapping_add(1) {
            shaped_peek(win, &self.params, self.gains.borrow(), &self.comp, at)
        } else {
            win.sample(&self.params, at)
        };
        let (cog, zmp) = states(&sx, &sy);
        let Some(next) = self.next_walk_inputs(win, j) else {
            return Ok(None);
        };
        let (adjust, _, _) = self.adjustment(c, at, cog, zmp)?;
        let mut inputs = next;
        inputs.first_ticks = adjusted(self.params.single_ticks, adjust);
        // Planned in the spare buffer, which is free between re-plans.
        let spare = 1 - c;
        self.predicted = None;
        self.walk_plans = self.walk_plans.wrapping_add(1);
        self.wins[spare].plan_into(&self.params, &inputs, cog, zmp)?;
        self.predicted = Some(self.prediction(at, inputs, cog, zmp));
        self.predicted_worst = self.wins[spare].worst_first();
        Ok(Some(self.predicted_worst))
    }

    /// The key under which a plan of `inputs` from `(cog, zmp)` at window tick `at` is kept.
    pub(super) fn prediction(
        &self,
        at: u32,
        inputs: Inputs<T>,
        cog: [State<T>; 2],
        zmp: [State<T>; 2],
    ) -> Predicted<T> {
        Predicted {
            gen: self.gen,
            serial: self.serial,
            at,
            inputs,
            cog,
            zmp,
        }
    }

    /// Inputs of the walking window that starts at interval `j` of `win` (a single support),
    /// with the footsteps as they are now.
    pub(super) fn next_walk_inputs(&self, win: &Active<T>, j: usize) -> Option<Inputs<T>> {
        let side = win.spec.support.get(j).copied().flatten()?;
        let front = self.queue.front();
        // The support foot: where it landed (in the window's plan) or stands.
        let support = if win.inputs.kind == WindowKind::Start && j == 1 {
            win.inputs.support
        } else {
            let mut f = self.feet[side.index()];
            if let Some(s) = self.swing {
                if s.step.side == side {
                    f = s.step;
                }
            }
            f
        };
        if front.is_none() && self.stop_requested {
            return None;
        }
        let (land, n) = self.landings(&support, 0);
        Some(Inputs {
            kind: WindowKind::Walk,
            support,
            other: self.feet[side.other().index()],
            land,
            n_land: n,
            first_ticks: self.params.single_ticks,
        })
    }

    /// The boundary values of `x_f` of eq. 18: the window `win` with its own initial state and
    /// the footsteps as they are now.
    pub(super) fn target_bounds(&self, win: &Active<T>) -> [PlaneBoundary<T>; 2] {
        let mut inputs = win.inputs;
        // The first landing of a walking window was its swing target: fixed since lift-off.
        let mut land = inputs.land;
        let mut n = match inputs.kind {
            WindowKind::Walk => 1,
            _ => 0,
        };
        for q in self.queue.iter().take(3 - n) {
            land[n] = q.step;
            n += 1;
        }
        if !self.stop_requested {
            while n < 3 {
                let prev = if n == 0 { inputs.support } else { land[n - 1] };
                land[n] = prev.beside(self.params.step_width);
                n += 1;
            }
        }
        inputs.land = land;
        inputs.n_land = n;
        let mut spec = Active::<T>::PARKED.spec;
        build_spec(&mut spec, &self.params, &inputs);
        let (_, bounds) = boundaries(
            &self.params,
            &spec,
            [win.bounds[0].cog_start, win.bounds[1].cog_start],
            [win.bounds[0].zmp_start, win.bounds[1].zmp_start],
        );
        bounds
    }

    /// Eq. 18 at window tick `at` of the current window `c` (index into the buffers), from the
    /// present state `(cog, zmp)`: the adjustment in ticks, `r`, and the deciding plane. The
    /// target state `x_f` is cached between the feasibility check of a modification and the
    /// re-plan it causes (same footsteps, same window), so a re-plan does not compute it twice.
    pub(super) fn adjustment(
        &mut self,
        c: usize,
        at: u32,
        cog: [State<T>; 2],
        zmp: [State<T>; 2],
    ) -> Result<(i32, T, u8), GaitError> {
        let pending = self.queue.front().map(|q| q.modified).unwrap_or(false);
        if !pending {
            return Ok((0, T::ONE, 0));
        }
        // A capture step (the node's own move) is not slowed down.
        let capture = self.queue.front().is_some_and(|q| q.capture);
        let f = match self.target {
            Some((g, w, a, f)) if g == self.gen && w == self.serial && a == at => f,
            _ => {
                let cur = &self.wins[c];
                let bounds = self.target_bounds(cur);
                // Solved with the current window's factorisation (same timing), and only the
                // interval of `at` built: no plan is written.
                let j = cur.interval(at);
                let tau = self.params.seconds(at - cur.starts[j]);
                let (fx, fy) = cur.factor.sample(&bounds[0], &bounds[1], j, tau)?;
                let f = [fx, fy];
                self.target = Some((self.gen, self.serial, at, f));
                f
            }
        };
        let w = self.params.omega;
        let mut d_i = [T::ZERO; 2];
        let mut d_f = [T::ZERO; 2];
        for k in 0..2 {
            d_i[k] = w * (cog[k].pos - zmp[k].pos) + (cog[k].vel - zmp[k].vel);
            d_f[k] = w * (f[k].cog - f[k].zmp) + (f[k].cog_vel - f[k].zmp_vel);
        }
        let plane = if (d_f[1] - d_i[1]).abs() > (d_f[0] - d_i[0]).abs() {
            1
        } else {
            0
        };
        let eps = T::of(1e-3) * w;
        let (di, df) = (d_i[plane], d_f[plane]);
        let p = &self.params;
        let ticks = if di.abs() < eps {
            0
        } else if df.abs() < eps {
            p.adjust_min_ticks
        } else {
            let r = df / di;
            if r <= T::ZERO {
                p.adjust_max_ticks
            } else {
                let dt = r.ln() / w;
                let t = libm::round((dt / p.dt).f64());
                (t.max(p.adjust_min_ticks as f64)
                    .min(p.adjust_max_ticks as f64)) as i32
            }
        };
        let ticks = if capture { ticks.min(0) } else { ticks };
        let r = if di.abs() < eps { T::ONE } else { df / di };
        Ok((ticks, r, plane as u8))
    }
}

pub(super) fn adjusted(single: u32, adjust: i32) -> u32 {
    (single as i64 + adjust as i64).max(1) as u32
}
