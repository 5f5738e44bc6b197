//! Leg reach limits of a footstep, in the frame of the support foot (see the parent module's
//! docs for the rules and where they come from).

use crate::gait::{Footstep, Side};
use crate::real::Real;
use crate::wire::Reason;

/// Leg reach limits (see the module docs), in the node's scalar `T` (the robot file gives them
/// in `f64`; [`Reach::cast`] converts).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(
    feature = "robot",
    derive(serde::Deserialize),
    serde(
        deny_unknown_fields,
        bound(deserialize = "T: Real + serde::Deserialize<'de>")
    )
)]
pub struct Reach<T = f64> {
    /// Largest forward step \[m\].
    pub max_forward: T,
    /// Largest backward step \[m\].
    pub max_backward: T,
    /// Smallest distance across the heading between the feet \[m\].
    pub min_width: T,
    /// Largest distance across the heading between the feet \[m\].
    pub max_width: T,
    /// Largest heading change \[rad\].
    pub max_yaw: T,
    /// Largest distance between the feet \[m\].
    pub max_feet_distance: T,
    /// Forward reach lost per radian of heading change \[m/rad\].
    pub yaw_cost: T,
    /// Largest travel of the swinging foot along the other foot's heading \[m\].
    pub max_stride: T,
    /// Largest growth of the forward step over the step before it \[m\].
    pub max_growth: T,
    /// Smallest distance between the landing sole and the support sole, both rectangles at
    /// their headings \[m\] (10 mm if a robot file leaves it out).
    #[cfg_attr(feature = "robot", serde(default = "default_sole_gap"))]
    pub sole_gap: T,
}

#[cfg(feature = "robot")]
fn default_sole_gap<T: Real>() -> T {
    T::of(0.01)
}

/// The sole of a foot: a rectangle centred on the foot's pose, along its heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Soles<T = f64> {
    /// Half of the sole's length (along the heading) \[m\].
    pub half_length: T,
    /// Half of the sole's width \[m\].
    pub half_width: T,
}

impl<T: Real> Soles<T> {
    /// The soles of a gait's parameters.
    pub fn of(p: &crate::gait::GaitParams<T>) -> Self {
        Self {
            half_length: p.sole_half_length,
            half_width: p.sole_half_width,
        }
    }
}

impl<T: Real> Default for Reach<T> {
    fn default() -> Self {
        Reach {
            max_forward: 0.30,
            max_backward: 0.20,
            min_width: 0.15,
            max_width: 0.28,
            max_yaw: 0.30,
            max_feet_distance: 0.361,
            yaw_cost: 0.3,
            max_stride: 0.43,
            max_growth: 0.22,
            sole_gap: 0.01,
        }
        .cast()
    }
}

impl<T: Real> Reach<T> {
    /// Every limit zero (see `Node::parked`).
    pub(crate) const PARKED: Self = Self {
        max_forward: T::ZERO,
        max_backward: T::ZERO,
        min_width: T::ZERO,
        max_width: T::ZERO,
        max_yaw: T::ZERO,
        max_feet_distance: T::ZERO,
        yaw_cost: T::ZERO,
        max_stride: T::ZERO,
        max_growth: T::ZERO,
        sole_gap: T::ZERO,
    };
}

impl Reach<f64> {
    /// These limits in the scalar `T` (each rounded to the nearest `T`).
    pub fn cast<T: Real>(&self) -> Reach<T> {
        Reach {
            max_forward: T::of(self.max_forward),
            max_backward: T::of(self.max_backward),
            min_width: T::of(self.min_width),
            max_width: T::of(self.max_width),
            max_yaw: T::of(self.max_yaw),
            max_feet_distance: T::of(self.max_feet_distance),
            yaw_cost: T::of(self.yaw_cost),
            max_stride: T::of(self.max_stride),
            max_growth: T::of(self.max_growth),
            sole_gap: T::of(self.sole_gap),
        }
    }
}

/// The two feet a step is checked against, as frames ([`Reach::broken_in`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stance<T> {
    other: Frame<T>,
    same: Frame<T>,
}

impl<T: Real> Stance<T> {
    /// The frames of `other` (the support foot) and `same` (where the swinging foot stands).
    pub(crate) fn of(other: &Footstep<T>, same: &Footstep<T>) -> Self {
        let o = Frame::of(other);
        Self {
            other: o,
            same: Frame::like(same, &[&o]),
        }
    }
}

/// A foot as a frame: its pose with the sine and cosine of its yaw (computed once per foot:
/// the reach check runs on the Cortex-M for every footstep frame).
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame<T> {
    x: T,
    y: T,
    yaw: T,
    sin: T,
    cos: T,
}

impl<T: Real> Frame<T> {
    /// Every field zero (a frame not computed: see `feet`).
    pub(super) const ZERO: Self = Self {
        x: T::ZERO,
        y: T::ZERO,
        yaw: T::ZERO,
        sin: T::ZERO,
        cos: T::ZERO,
    };

    /// This frame moved by `d` (the heading kept): the frame of the footstep moved by `d`.
    pub(super) fn shifted(&self, d: [T; 2]) -> Self {
        Self {
            x: self.x + d[0],
            y: self.y + d[1],
            ..*self
        }
    }

    pub(super) fn of(f: &Footstep<T>) -> Self {
        Self::like(f, &[])
    }

    /// [`Frame::of`], taking the sine and cosine from a frame in `known` of the same yaw (bit
    /// for bit) if there is one: the feet of a reach check often share their heading.
    pub(super) fn like(f: &Footstep<T>, known: &[&Frame<T>]) -> Self {
        let (sin, cos) = match known.iter().find(|k| k.yaw.bits() == f.yaw.bits()) {
            Some(k) => (k.sin, k.cos),
            None => f.yaw.sin_cos(),
        };
        Self {
            x: f.x,
            y: f.y,
            yaw: f.yaw,
            sin,
            cos,
        }
    }

    /// `true` if the soles of `self` and `other` (rectangles of the same size at their poses)
    /// keep at least `gap` apart (less `eps`). In `self`'s frame, with `other` at `(dx, dy)`
    /// turned by `Δ` (`c = cos Δ`, `s = sin Δ`, from the frames' sines and cosines): `other`
    /// reaches `ex = l|c| + w|s|` along and `ey = l|s| + w|c|` across, and so does `self` in
    /// `other`'s frame. If the separation along one of `self`'s axes is at least `gap` the soles
    /// are that far apart (the distance of two convex sets is at least their separation along
    /// any axis): the common case, side by side. If they overlap along all four edge normals
    /// they intersect (the separating axis theorem). Otherwise their distance is attained at a
    /// corner of one of them: the smallest distance of the four corners of each to the other.
    fn soles_apart(&self, other: &Frame<T>, soles: &Soles<T>, gap: T, eps: T) -> bool {
        let (l, w) = (soles.half_length, soles.half_width);
        let g = (gap - eps).max(T::ZERO);
        let (x, y) = (other.x - self.x, other.y - self.y);
        let (dx, dy) = (self.cos * x + self.sin * y, -self.sin * x + self.cos * y);
        let c = self.cos * other.cos + self.sin * other.sin;
        let s = self.cos * other.sin - self.sin * other.cos;
        let (ex, ey) = (l * c.abs() + w * s.abs(), l * s.abs() + w * c.abs());
        let (sx, sy) = (dx.abs() - l - ex, dy.abs() - w - ey);
        if sx.max(sy) >= g {
            return true;
        }
        // `self`'s centre in `other`'s frame.
        let (bx, by) = (-(c * dx + s * dy), s * dx - c * dy);
        let (tx, ty) = (bx.abs() - l - ex, by.abs() - w - ey);
        if sx.max(sy).max(tx).max(ty) < T::ZERO {
            return false;
        }
        // The corners of a rectangle centred at `(px, py)` turned by (`c`, `s`), against the
        // rectangle of the frame it is expressed in: the smallest squared distance.
        let nearest = |px: T, py: T, c: T, s: T| {
            // Half the sole along and across its heading.
            let (ax, ay) = (l * c, l * s);
            let (bx, by) = (-w * s, w * c);
            let corner = |u: T, v: T| {
                let (cx, cy) = (px + u * ax + v * bx, py + u * ay + v * by);
                let ox = (cx.abs() - l).max(T::ZERO);
                let oy = (cy.abs() - w).max(T::ZERO);
                square(ox) + square(oy)
            };
            let (p, m) = (T::ONE, -T::ONE);
            corner(p, p)
                .min(corner(p, m))
                .min(corner(m, p))
                .min(corner(m, m))
        };
        let g2 = g * g;
        nearest(dx, dy, c, s) >= g2 && nearest(bx, by, c, -s) >= g2
    }

    /// `to` in this frame: forward and width (positive on `to_side`'s own side).
    fn forward_width(&self, to: &Frame<T>, to_side: Side) -> (T, T) {
        let (dx, dy) = (to.x - self.x, to.y - self.y);
        let forward = self.cos * dx + self.sin * dy;
        let width = -self.sin * dx + self.cos * dy;
        match to_side {
            Side::Left => (forward, width),
            Side::Right => (forward, -width),
        }
    }
}

/// `v²`. The feet distance is compared squared (no `hypot` on the Cortex-M): for the
/// reach's sizes (≤ 1e3 m) the squares neither overflow nor underflow to a different decision,
/// and they differ from `hypot` only within a few ulps of the limit, inside its margin.
fn square<T: Real>(v: T) -> T {
    v * v
}

/// The margin by which values on the limits pass: 1 nm in `f64` (as before the node was
/// generic); in `f32`, 80 ε ≈ 9.5 µm, a few roundings of coordinates of the ±32 m walking area
/// (an `f32` ulp at 32 m is 3.8 µm), so that a step on a limit is taken by both scalars.
#[inline]
fn eps<T: Real>() -> T {
    T::of(1e-9).max(T::EPSILON * T::of(80.0))
}

impl<T: Real> Reach<T> {
    /// Whether the legs can take `step`, where `other` is the previous foot of the other side
    /// (the support foot of this step) and `same` the previous foot of the same side (where
    /// the swinging foot lifts off), with feet of `soles`. `Crossing` or `Reach` if not.
    pub fn check(
        &self,
        other: &Footstep<T>,
        same: &Footstep<T>,
        step: &Footstep<T>,
        soles: &Soles<T>,
    ) -> Result<(), Reason> {
        self.check_with(other, same, step, false, soles)
    }

    /// [`Reach::check`]; `from_rest`: the step is the first swing of a walk from standing, so
    /// its growth is measured from a step of 0 (whatever the stagger of the feet).
    pub fn check_with(
        &self,
        other: &Footstep<T>,
        same: &Footstep<T>,
        step: &Footstep<T>,
        from_rest: bool,
        soles: &Soles<T>,
    ) -> Result<(), Reason> {
        self.broken(other, same, step, from_rest, soles)
            .map_or(Ok(()), |b| Err(b.reason()))
    }

    /// The first limit that [`Reach::check_with`] finds broken ([`Limit`] order), with the
    /// measured value and the bound; `None` when it accepts the step. `check_with` is this,
    /// by reason (`Crossing` for [`Limit::Crossing`], `Reach` for the others).
    pub fn broken(
        &self,
        other: &Footstep<T>,
        same: &Footstep<T>,
        step: &Footstep<T>,
        from_rest: bool,
        soles: &Soles<T>,
    ) -> Option<Broken<T>> {
        self.broken_frames(
            &Frame::of(other),
            &Frame::of(same),
            &Frame::of(step),
            step.side,
            from_rest,
            soles,
        )
    }

    /// [`Reach::broken`] of `step` against two feet whose frames were computed once
    /// ([`Stance::of`]): the velocity stepping tries up to 1 + `HALVINGS` steps against the
    /// same feet, each try computing only the step's frame (none when it keeps a foot's
    /// heading), as a footstep command's checks with the node's kept frames do.
    pub(crate) fn broken_in(
        &self,
        stance: &Stance<T>,
        step: &Footstep<T>,
        from_rest: bool,
        soles: &Soles<T>,
    ) -> Option<Broken<T>> {
        let frame = Frame::like(step, &[&stance.other, &stance.same]);
        self.broken_frames(
            &stance.other,
            &stance.same,
            &frame,
            step.side,
            from_rest,
            soles,
        )
    }

    /// The first limit `step` breaks ([`Limit`] order), with the measured value and the
    /// bound; `None` if the legs can take it.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must break a limit
    pub(super) fn broken_frames(
        &self,
        other: &Frame<T>,
        same: &Frame<T>,
        step: &Frame<T>,
        side: Side,
        from_rest: bool,
        soles: &Soles<T>,
    ) -> Option<Broken<T>> {
        let eps = eps::<T>(); // values on the limits pass
        let (forward, width) = other.forward_width(step, side);
        if width < T::ZERO || !other.soles_apart(step, soles, self.sole_gap, eps) {
            return Some(Broken::new(Limit::Crossing, width, self.sole_gap));
        }
        // Heading change wrapped into [−π, π] (without a libm call when it is inside: the
        // wrap of an angle within ±π is itself, so both branches agree to the bit).
        let d = step.yaw - other.yaw;
        let (pi, tau) = (T::of(core::f64::consts::PI), T::of(core::f64::consts::TAU));
        let dyaw = if d.abs() <= pi {
            d.abs()
        } else {
            (d - tau * (d / tau).round()).abs()
        };
        // The step before this one (`other` from `same`; none from rest), and where the
        // swinging foot was.
        let before = if from_rest {
            T::ZERO
        } else {
            same.forward_width(other, side.other()).0
        };
        let lift = other.forward_width(same, side).0;
        // In the order of [`Limit`], the first broken limit returns. Each test is written as
        // "not within", so that a value that is not a number breaks the limit.
        let broken = |limit, value, bound| Some(Broken::new(limit, value, bound));
        if !(forward <= self.max_forward + eps) {
            return broken(Limit::Forward, forward, self.max_forward);
        }
        if !(forward >= -self.max_backward - eps) {
            return broken(Limit::Backward, -forward, self.max_backward);
        }
        if !(width >= self.min_width - eps) {
            return broken(Limit::MinWidth, width, self.min_width);
        }
        if !(width <= self.max_width + eps) {
            return broken(Limit::MaxWidth, width, self.max_width);
        }
        if !(dyaw <= self.max_yaw + eps) {
            return broken(Limit::Yaw, dyaw, self.max_yaw);
        }
        let distance2 = forward * forward + width * width;
        if !(distance2 <= square(self.max_feet_distance + eps)) {
            let d = distance2.sqrt();
            return broken(Limit::FeetDistance, d, self.max_feet_distance);
        }
        let turned = forward + self.yaw_cost * dyaw;
        if !(turned <= self.max_forward + eps) {
            return broken(Limit::TurnCost, turned, self.max_forward);
        }
        let stride = (forward - lift).abs();
        if !(stride <= self.max_stride + eps) {
            return broken(Limit::Stride, stride, self.max_stride);
        }
        if !(forward - before <= self.max_growth + eps) {
            return broken(Limit::Growth, forward - before, self.max_growth);
        }
        None
    }
}

/// A reach limit of [`Reach`], in the order the node checks them (the first broken one is
/// the one reported).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Limit {
    /// The landing sole crosses the support foot's midline or comes nearer to the support
    /// sole than `sole_gap` (refused with `Crossing`; the value is the width across).
    Crossing,
    /// `max_forward`: the step forward in the support foot's frame.
    Forward,
    /// `max_backward`: the step backward.
    Backward,
    /// `min_width`: the distance across the heading between the feet.
    MinWidth,
    /// `max_width`: the same, its largest value.
    MaxWidth,
    /// `max_yaw`: the heading change.
    Yaw,
    /// `max_feet_distance`: the distance between the sole centres.
    FeetDistance,
    /// `max_forward` less `yaw_cost · |Δyaw|`: the forward step a turn leaves (the value is
    /// `forward + yaw_cost · |Δyaw|`).
    TurnCost,
    /// `max_stride`: the swinging foot's travel along the support foot's heading.
    Stride,
    /// `max_growth`: the growth of the forward step over the step before it.
    Growth,
}

impl Limit {
    /// The robot file's key of the bound (`[reach]` section).
    pub fn key(self) -> &'static str {
        match self {
            Limit::Crossing => "sole_gap",
            Limit::Forward | Limit::TurnCost => "max_forward",
            Limit::Backward => "max_backward",
            Limit::MinWidth => "min_width",
            Limit::MaxWidth => "max_width",
            Limit::Yaw => "max_yaw",
            Limit::FeetDistance => "max_feet_distance",
            Limit::Stride => "max_stride",
            Limit::Growth => "max_growth",
        }
    }
}

/// A broken reach limit: which, the measured value and the bound (metres, or radians for
/// [`Limit::Yaw`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Broken<T = f64> {
    /// The limit.
    pub limit: Limit,
    /// What the step measures.
    pub value: T,
    /// The robot's bound.
    pub bound: T,
}

impl<T> Broken<T> {
    /// The refusal's reason: `Crossing` for [`Limit::Crossing`], `Reach` for the others.
    pub fn reason(&self) -> Reason {
        if self.limit == Limit::Crossing {
            Reason::Crossing
        } else {
            Reason::Reach
        }
    }

    fn new(limit: Limit, value: T, bound: T) -> Self {
        Self {
            limit,
            value,
            bound,
        }
    }
}
