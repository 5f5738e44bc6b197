//! The shaping glue: the window's ZMP minus Kajita's preview-control compensation of its
//! fluctuation (the quartic's difference from the cubic Hermite with the same ends), per plane,
//! with the preview gains `G` shared by both planes.

use super::*;

/// COG and ZMP states of both planes from their samples.
pub(super) fn states<T: Real>(x: &Sample<T>, y: &Sample<T>) -> ([State<T>; 2], [State<T>; 2]) {
    (
        [State::new(x.cog, x.cog_vel), State::new(y.cog, y.cog_vel)],
        [State::new(x.zmp, x.zmp_vel), State::new(y.zmp, y.zmp_vel)],
    )
}

/// `p − c`, sample by sample.
/// The plan of `win` at window tick `t` minus the compensation of the next step of `comp`
/// (which it advances), or the plan alone without shaping.
pub(super) fn shaped_sample<T: Real>(
    win: &Active<T>,
    params: &GaitParams<T>,
    gains: &PreviewGains<T, PREVIEW>,
    comp: &mut [Compensator<T>; 2],
    t: u32,
) -> (Sample<T>, Sample<T>) {
    shaped_by(win, params, gains, t, |k| comp[k & 1].step(gains))
}

/// What [`shaped_sample`] returns, without advancing the compensators.
pub(super) fn shaped_peek<T: Real>(
    win: &Active<T>,
    params: &GaitParams<T>,
    gains: &PreviewGains<T, PREVIEW>,
    comp: &[Compensator<T>; 2],
    t: u32,
) -> (Sample<T>, Sample<T>) {
    shaped_by(win, params, gains, t, |k| comp[k & 1].peek(gains))
}

/// The window's sample at `t` minus the compensation of plane `k` that `compensation(k)`
/// gives (x first), if shaping is on.
pub(super) fn shaped_by<T: Real>(
    win: &Active<T>,
    params: &GaitParams<T>,
    gains: &PreviewGains<T, PREVIEW>,
    t: u32,
    mut compensation: impl FnMut(usize) -> Compensation<T>,
) -> (Sample<T>, Sample<T>) {
    let (sx, sy) = win.sample(params, t);
    if !params.shaping {
        return (sx, sy);
    }
    let zf = gains.zmp_factor();
    let cx = compensation(0).sample(zf);
    let cy = compensation(1).sample(zf);
    (minus(sx, cx), minus(sy, cy))
}

pub(super) fn minus<T: Real>(p: Sample<T>, c: Sample<T>) -> Sample<T> {
    Sample {
        cog: p.cog - c.cog,
        cog_vel: p.cog_vel - c.cog_vel,
        cog_acc: p.cog_acc - c.cog_acc,
        zmp: p.zmp - c.zmp,
        zmp_vel: p.zmp_vel - c.zmp_vel,
    }
}

/// The ZMP fluctuation of a quartic interval: its difference from the cubic Hermite with the
/// same end positions and velocities (normalised time).
pub(super) fn fluctuation<T: Real>(c: &Poly<T>) -> Poly<T> {
    let (two, three) = (T::of(2.0), T::of(3.0));
    let p1 = c[0] + c[1] + c[2] + c[3] + c[4];
    let v1 = c[1] + two * c[2] + three * c[3] + T::of(4.0) * c[4];
    let dp = p1 - c[0];
    let h2 = three * dp - two * c[1] - v1;
    let h3 = -two * dp + c[1] + v1;
    [T::ZERO, T::ZERO, c[2] - h2, c[3] - h3, c[4]]
}

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    /// The current window's analytic plan at window tick `t` minus the compensation of this
    /// tick (the compensators advance by one tick: call once per tick).
    pub(super) fn shaped(&mut self, t: u32) -> (Sample<T>, Sample<T>) {
        let Some(c) = self.cur_buf() else {
            return (self.last.x, self.last.y);
        };
        shaped_sample(
            &self.wins[c],
            &self.params,
            self.gains.borrow(),
            &mut self.comp,
            t,
        )
    }

    /// Restarts the compensators from rest with the fluctuation of the first interval of the
    /// current window as their reference.
    pub(super) fn start_shaping(&mut self) {
        let Some(c) = self.cur_buf() else {
            return;
        };
        let win = &self.wins[c];
        for (k, comp) in self.comp.iter_mut().enumerate() {
            comp.reset();
            // Only a window that is followed by a re-plan is shaped: the re-plan starts from
            // the shaped state and so absorbs what is left of the compensation, while the last
            // window must end exactly at rest. The start and stop windows begin with a double
            // support, where the fluctuation is harmless (the polygon spans both feet) and
            // shaping would only carry it into the following single support: they are not
            // shaped.
            let walking = win.inputs.kind == WindowKind::Walk;
            if self.params.shaping && walking && win.spec.replan.is_some() {
                let seg = if k == 0 {
                    &win.plan.x[0]
                } else {
                    &win.plan.y[0]
                };
                let piece = Piece::new(0, win.spec.ticks[0], fluctuation(&seg.zmp));
                // A non-finite fluctuation cannot come from a solved plan; without shaping the
                // analytic pattern is still exact.
                let _ = comp.set_pieces(&[piece]);
            }
        }
    }
}
