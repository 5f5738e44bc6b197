//! A planned window being executed ([`Active`]): its specification, its plan (the COG's
//! closed form per interval in both planes) and the sampling of the reference at window tick `t`.

use super::*;

/// The window being executed.
#[derive(Clone, Debug)]
pub(super) struct Active<T: Real> {
    pub(super) inputs: Inputs<T>,
    pub(super) spec: Spec<T>,
    pub(super) bounds: [PlaneBoundary<T>; 2],
    pub(super) factor: Factorized<T>,
    pub(super) plan: Plan<T>,
    /// Ticks since the window started.
    pub(super) tick: u32,
    /// Window tick of every interval start, and the window end.
    pub(super) starts: [u32; M + 1],
}

impl<T: Real> Active<T> {
    /// A parked window buffer (every byte zero: see [`Gait::parked`]).
    pub(crate) const PARKED: Self = Self {
        inputs: Inputs::PARKED,
        spec: Spec {
            ticks: [0; M],
            kinds: [Kind::Start; M],
            // `Some(Left)`, not `None`: its bytes are the zero ones (`None` is the niche).
            support: [Some(Side::Left); M],
            via: [[T::ZERO; 2]; M],
            replan: None,
        },
        bounds: [PlaneBoundary::ZERO; 2],
        factor: Factorized::empty(),
        plan: Plan::ZERO,
        tick: 0,
        starts: [0; M + 1],
    };

    /// Makes this buffer an unused one for `p` and `feet`, in place (the buffer is 6 KB: it is
    /// never built on the stack).
    pub(super) fn clear(&mut self, p: &GaitParams<T>, feet: &[Footstep<T>; 2]) {
        self.inputs = Inputs {
            kind: WindowKind::Stop,
            support: feet[0],
            other: feet[1],
            land: [feet[0]; 3],
            n_land: 0,
            first_ticks: p.settle_ticks,
        };
        self.spec = Spec {
            ticks: [1; M],
            kinds: [Kind::Stand; M],
            support: [None; M],
            via: [[T::ZERO; 2]; M],
            replan: None,
        };
        self.bounds = [PlaneBoundary::default(); 2];
        self.factor = Factorized::empty();
        self.plan.timing = Timing {
            omega: p.omega,
            durations: [T::ONE; M],
        };
        for seg in self.plan.x.iter_mut().chain(self.plan.y.iter_mut()) {
            *seg = Segment::default();
        }
        self.tick = 0;
        self.starts = [0; M + 1];
    }

    /// Plans a window in this buffer, in place (the buffer is 9 KB: never moved on the control
    /// path). On error the buffer must not be used.
    pub(super) fn plan_into(
        &mut self,
        p: &GaitParams<T>,
        inputs: &Inputs<T>,
        cog: [State<T>; 2],
        zmp: [State<T>; 2],
    ) -> Result<(), PlanError> {
        build_spec(&mut self.spec, p, inputs);
        let (timing, bounds) = boundaries(p, &self.spec, cog, zmp);
        self.bounds = bounds;
        self.factor.refactor(&timing)?;
        self.factor
            .solve(&self.bounds[0], &self.bounds[1], &mut self.plan)?;
        self.starts[0] = 0;
        for j in 0..M {
            self.starts[j + 1] = self.starts[j] + self.spec.ticks[j];
        }
        self.inputs = *inputs;
        self.tick = 0;
        Ok(())
    }

    pub(super) fn interval(&self, tick: u32) -> usize {
        (0..M).rev().find(|&j| tick >= self.starts[j]).unwrap_or(0)
    }

    pub(super) fn sample(&self, p: &GaitParams<T>, tick: u32) -> (Sample<T>, Sample<T>) {
        let j = self.interval(tick);
        let tau = p.seconds(tick - self.starts[j]);
        Segment::sample_pair(&self.plan.x[j], &self.plan.y[j], tau)
    }

    /// Worst ZMP excursion of interval 0 in the frame of its support foot (or of the via point
    /// when the interval is not a single support): `(along the foot, across the foot)`.
    pub(super) fn worst_first(&self) -> [T; 2] {
        let (s, c) = match self.inputs.kind {
            WindowKind::Walk => sin_cos(self.inputs.support.yaw),
            _ => (T::ZERO, T::ONE),
        };
        let centre = self.spec.via[0];
        let (px, py) = (&self.plan.x[0].zmp, &self.plan.y[0].zmp);
        let mut along = [T::ZERO; 5];
        let mut across = [T::ZERO; 5];
        for i in 0..5 {
            along[i] = c * px[i] + s * py[i];
            across[i] = -s * px[i] + c * py[i];
        }
        let ca = c * centre[0] + s * centre[1];
        let cb = -s * centre[0] + c * centre[1];
        let a = worst_deviation(&along, T::ONE, ca);
        let b = worst_deviation(&across, T::ONE, cb);
        [a.deviation, b.deviation]
    }
}
