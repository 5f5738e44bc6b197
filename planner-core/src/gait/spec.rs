//! Window specifications: from the support foot `S₀`, the next landings `L₁, L₂, L₃` and the
//! timing, the 7 intervals of a window (start, walk or stop; see the parent module's docs)
//! with their ZMP via points (foot centres, zero ZMP velocity) and the boundary conditions of
//! both planes that `window` solves (`y = Z⁻¹ w`).

use super::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Start,
    Single,
    Double,
    Settle,
    Stand,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum WindowKind {
    Start,
    Walk,
    Stop,
}

/// What [`Gait::predict_replan`] planned into the spare buffer (see `Gait::predicted`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Predicted<T> {
    pub(super) gen: u32,
    pub(super) serial: u32,
    pub(super) at: u32,
    pub(super) inputs: Inputs<T>,
    pub(super) cog: [State<T>; 2],
    pub(super) zmp: [State<T>; 2],
}

/// Everything needed to build a window, kept so that eq. 18 can solve it again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Inputs<T> {
    pub(super) kind: WindowKind,
    /// Support foot of the first single support.
    pub(super) support: Footstep<T>,
    /// The other foot where it stands (start and stop windows).
    pub(super) other: Footstep<T>,
    /// Landings (only the first `n_land` are used).
    pub(super) land: [Footstep<T>; 3],
    pub(super) n_land: usize,
    /// Duration of the first interval \[ticks\].
    pub(super) first_ticks: u32,
}

impl<T: Real> Inputs<T> {
    /// Every byte zero (see [`Gait::parked`]).
    pub(crate) const PARKED: Self = Self {
        kind: WindowKind::Start,
        support: Footstep::PARKED,
        other: Footstep::PARKED,
        land: [Footstep::PARKED; 3],
        n_land: 0,
        first_ticks: 0,
    };
}

/// A window's intervals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Spec<T> {
    pub(super) ticks: [u32; M],
    pub(super) kinds: [Kind; M],
    pub(super) support: [Option<Side>; M],
    pub(super) via: [[T; 2]; M],
    /// Interval at whose start the next re-plan happens.
    pub(super) replan: Option<usize>,
}

/// Writes the window's intervals into `spec` (in place: a `Spec` returned by value costs two
/// copies of its 180 bytes on the Cortex-M).
pub(super) fn build_spec<T: Real>(spec: &mut Spec<T>, p: &GaitParams<T>, inp: &Inputs<T>) {
    spec.ticks = [p.stand_ticks; M];
    spec.kinds = [Kind::Stand; M];
    spec.support = [None; M];
    spec.via = [[T::ZERO; 2]; M];
    spec.replan = None;
    let mut n = 0;
    pub(super) fn push<T: Copy>(
        spec: &mut Spec<T>,
        n: &mut usize,
        kind: Kind,
        ticks: u32,
        via: [T; 2],
        sup: Option<Side>,
    ) {
        if *n < M {
            spec.kinds[*n] = kind;
            spec.ticks[*n] = ticks;
            spec.via[*n] = via;
            spec.support[*n] = sup;
            *n += 1;
        }
    }
    let s0 = inp.support;
    // Footholds before the landings: (previous, last) for the settle midpoint.
    let (mut prev, mut last) = (inp.other.centre(), s0.centre());
    match inp.kind {
        WindowKind::Stop => {
            push(
                spec,
                &mut n,
                Kind::Settle,
                inp.first_ticks,
                midpoint(prev, last),
                None,
            );
        }
        WindowKind::Start | WindowKind::Walk => {
            // A start window shifts the ZMP onto the support foot first; a walking window
            // begins with the (possibly adjusted) single support itself.
            let single = if inp.kind == WindowKind::Start {
                push(spec, &mut n, Kind::Start, inp.first_ticks, last, None);
                p.single_ticks
            } else {
                inp.first_ticks
            };
            push(spec, &mut n, Kind::Single, single, last, Some(s0.side));
            let mut last_side = s0.side;
            for (i, l) in inp.land.iter().take(inp.n_land).enumerate() {
                if n >= M - 1 {
                    break;
                }
                push(spec, &mut n, Kind::Double, p.double_ticks, l.centre(), None);
                prev = last;
                last = l.centre();
                last_side = l.side;
                // The last landing of a walking window is followed by the tail.
                if n >= M - 1 {
                    break;
                }
                let more = i + 1 < inp.n_land;
                if more {
                    push(
                        spec,
                        &mut n,
                        Kind::Single,
                        p.single_ticks,
                        last,
                        Some(l.side),
                    );
                } else {
                    break;
                }
            }
            let walking_on = inp.n_land == 3 && n == M - 1;
            if walking_on && p.tail == Tail::Single {
                push(
                    spec,
                    &mut n,
                    Kind::Single,
                    p.single_ticks,
                    last,
                    Some(last_side),
                );
            } else {
                push(
                    spec,
                    &mut n,
                    Kind::Settle,
                    p.settle_ticks,
                    midpoint(prev, last),
                    None,
                );
            }
        }
    }
    // Fill with one-tick standing intervals at the last via point, and end with a resting
    // interval long enough for the final quartic to bring the COG to rest gently.
    // `n ≥ 1` here (the first interval is always pushed); `via[0]` only keeps this panic-free.
    let rest = match n.checked_sub(1).and_then(|i| spec.via.get(i)) {
        Some(&v) => v,
        None => spec.via[0],
    };
    while n < M - 1 {
        push(spec, &mut n, Kind::Stand, p.stand_ticks, rest, None);
    }
    if n < M {
        push(spec, &mut n, Kind::Stand, p.rest_ticks, rest, None);
    }
    spec.replan = (1..M).find(|&j| spec.kinds[j] == Kind::Single);
}

/// Timing and boundary values of a window from its spec and the initial state.
pub(super) fn boundaries<T: Real>(
    p: &GaitParams<T>,
    spec: &Spec<T>,
    cog: [State<T>; 2],
    zmp: [State<T>; 2],
) -> (Timing<T>, [PlaneBoundary<T>; 2]) {
    let mut durations = [T::ZERO; M];
    for (d, &t) in durations.iter_mut().zip(spec.ticks.iter()) {
        *d = p.seconds(t);
    }
    let timing = Timing {
        omega: p.omega,
        durations,
    };
    let plane = |k: usize| {
        let mut via = [State::default(); M];
        for (v, pt) in via.iter_mut().zip(spec.via.iter()) {
            *v = State::at_rest(pt[k]);
        }
        PlaneBoundary {
            cog_start: cog[k],
            zmp_start: zmp[k],
            via,
            cog_end: State::at_rest(spec.via[M - 1][k]),
        }
    };
    (timing, [plane(0), plane(1)])
}
