//! Leg reach limits of a footstep, in the frame of the support foot (see the parent module's
//! docs for the rules and where they come from).

use crate::gait::{Footstep, Side};
use crate::wire::Reason;

/// Leg reach limits (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(
    feature = "robot",
    derive(serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct Reach {
    /// Largest forward step \[m\].
    pub max_forward: f64,
    /// Largest backward step \[m\].
    pub max_backward: f64,
    /// Smallest distance across the heading between the feet \[m\].
    pub min_width: f64,
    /// Largest distance across the heading between the feet \[m\].
    pub max_width: f64,
    /// Largest heading change \[rad\].
    pub max_yaw: f64,
    /// Largest distance between the feet \[m\].
    pub max_feet_distance: f64,
    /// Forward reach lost per radian of heading change \[m/rad\].
    pub yaw_cost: f64,
    /// Largest travel of the swinging foot along the other foot's heading \[m\].
    pub max_stride: f64,
    /// Largest growth of the forward step over the step before it \[m\].
    pub max_growth: f64,
}

impl Default for Reach {
    fn default() -> Self {
        Self {
            max_forward: 0.30,
            max_backward: 0.20,
            min_width: 0.15,
            max_width: 0.28,
            max_yaw: 0.30,
            max_feet_distance: 0.361,
            yaw_cost: 0.3,
            max_stride: 0.43,
            max_growth: 0.22,
        }
    }
}

/// A foot as a frame: its pose with the sine and cosine of its yaw (computed once per foot:
/// the reach check runs on the Cortex-M for every footstep frame).
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame {
    x: f64,
    y: f64,
    yaw: f64,
    sin: f64,
    cos: f64,
}

impl Frame {
    pub(super) fn of(f: &Footstep<f64>) -> Self {
        Self {
            x: f.x,
            y: f.y,
            yaw: f.yaw,
            sin: libm::sin(f.yaw),
            cos: libm::cos(f.yaw),
        }
    }

    /// `to` in this frame: forward and width (positive on `to_side`'s own side).
    fn forward_width(&self, to: &Frame, to_side: Side) -> (f64, f64) {
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
/// and they differ from `hypot` only within a few ulps of the limit, inside its `EPS`.
fn square(v: f64) -> f64 {
    v * v
}

impl Reach {
    /// Whether the legs can take `step`, where `other` is the previous foot of the other side
    /// (the support foot of this step) and `same` the previous foot of the same side (where
    /// the swinging foot lifts off). `Crossing` or `Reach` if not.
    pub fn check(
        &self,
        other: &Footstep<f64>,
        same: &Footstep<f64>,
        step: &Footstep<f64>,
    ) -> Result<(), Reason> {
        self.check_with(other, same, step, false)
    }

    /// [`Reach::check`]; `from_rest`: the step is the first swing of a walk from standing, so
    /// its growth is measured from a step of 0 (whatever the stagger of the feet).
    pub fn check_with(
        &self,
        other: &Footstep<f64>,
        same: &Footstep<f64>,
        step: &Footstep<f64>,
        from_rest: bool,
    ) -> Result<(), Reason> {
        self.check_frames(
            &Frame::of(other),
            &Frame::of(same),
            &Frame::of(step),
            step.side,
            from_rest,
        )
    }

    pub(super) fn check_frames(
        &self,
        other: &Frame,
        same: &Frame,
        step: &Frame,
        side: Side,
        from_rest: bool,
    ) -> Result<(), Reason> {
        const EPS: f64 = 1e-9; // values on the limits pass
        let (forward, width) = other.forward_width(step, side);
        if width < 0.0 {
            return Err(Reason::Crossing);
        }
        // Heading change wrapped into [−π, π] (without a libm call when it is inside: the
        // wrap of an angle within ±π is itself, so both branches agree to the bit).
        let d = step.yaw - other.yaw;
        let dyaw = if libm::fabs(d) <= core::f64::consts::PI {
            libm::fabs(d)
        } else {
            libm::fabs(d - core::f64::consts::TAU * libm::round(d / core::f64::consts::TAU))
        };
        // The step before this one (`other` from `same`; none from rest), and where the
        // swinging foot was.
        let before = if from_rest {
            0.0
        } else {
            same.forward_width(other, side.other()).0
        };
        let lift = other.forward_width(same, side).0;
        let ok = forward <= self.max_forward + EPS
            && forward >= -self.max_backward - EPS
            && width >= self.min_width - EPS
            && width <= self.max_width + EPS
            && dyaw <= self.max_yaw + EPS
            && forward * forward + width * width <= square(self.max_feet_distance + EPS)
            && forward + self.yaw_cost * dyaw <= self.max_forward + EPS
            && libm::fabs(forward - lift) <= self.max_stride + EPS
            && forward - before <= self.max_growth + EPS;
        if ok {
            Ok(())
        } else {
            Err(Reason::Reach)
        }
    }
}
