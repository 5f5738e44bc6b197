//! Footsteps from a commanded velocity: what a stick, a policy or ROS's `cmd_vel` asks for,
//! turned into landings that the legs can take.
//!
//! A velocity `v = (vx, vy, ω)` \[m/s, m/s, rad/s\] is given in the frame of the support foot
//! (`vx` along its heading, `vy` to its left, `ω` counter-clockwise). A step lasts
//! `Tₛ = (single + double support) · dt` (one single support and one double support of the
//! gait). The swing foot's landing is placed in the support foot's frame:
//!
//! * **forward** `f = vx · Tₛ`: each step moves the walk by one step length, so the walk
//!   advances `vx` on average (the swinging foot travels `2f` in steady walking);
//! * **across**: the nominal width `w` (the gait's `step_width`), plus `2 |vy| Tₛ` on the steps
//!   whose swing foot is on the side of the motion; the closing step of the other foot comes
//!   back to `w` (so the feet never come nearer than `w`, and the walk moves `vy` on average);
//! * **heading** `Δψ = 2 ω Tₛ` on the steps whose swing foot is on the side of the turn; the
//!   other foot closes parallel to the support foot (`Δψ = 0`): `ω` on average.
//!
//! **Saturation.** A component the legs cannot take is cut to the nearest value they can, in
//! closed form and in this order, against the node's [`Reach`] limits (measured as the node
//! measures them: see [`crate::node`]): the heading change to `max_yaw`; the forward step to
//! `[−max_backward, max_forward − yaw_cost·|Δψ|]`, to the stride around where the swinging
//! foot lifts off, and to `max_growth` over the step before (from standing: over 0); the width
//! to `[min_width, max_width]`; the forward step again so that the feet stay within
//! `max_feet_distance`. The landing is then checked with [`Reach::broken`] (the limit a closed
//! form does not cover is the sole gap of turned soles); while it is refused the heading
//! change and the forward step are halved, at most [`HALVINGS`] times, and if it is still
//! refused the foot steps beside the support foot at the nominal width. Every component that
//! was cut is reported ([`Saturation`]), so the answer can say that the walk is slower than
//! commanded. The work is bounded: at most `1 + HALVINGS` reach checks a step.
//!
//! A velocity with a component that is not finite is refused ([`VelocityError::NonFinite`]):
//! nothing is planned from it.

use super::{Reach, Soles, Stance};
use crate::gait::{Footstep, GaitParams, Side};
use crate::real::Real;

/// Most halvings of the heading change and the forward step after the closed-form cut (the
/// sole gap of turned soles); beyond, the foot steps beside the support foot.
pub const HALVINGS: u32 = 6;

/// A commanded velocity in the support foot's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Velocity<T = f64> {
    /// Along the heading \[m/s\].
    pub vx: T,
    /// To the left of the heading \[m/s\].
    pub vy: T,
    /// Turn rate, counter-clockwise \[rad/s\].
    pub wz: T,
}

impl<T: Real> Velocity<T> {
    /// Standing still.
    pub const ZERO: Self = Self {
        vx: T::ZERO,
        vy: T::ZERO,
        wz: T::ZERO,
    };

    fn is_finite(&self) -> bool {
        self.vx.is_finite() && self.vy.is_finite() && self.wz.is_finite()
    }
}

/// Which components of a commanded velocity were cut to what the legs can take.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Saturation {
    /// The step along the heading was cut.
    pub forward: bool,
    /// The step across was cut.
    pub lateral: bool,
    /// The heading change was cut.
    pub turn: bool,
    /// No cut within the limits' closed forms was enough: the foot steps beside the support
    /// foot.
    pub in_place: bool,
}

impl Saturation {
    /// `true` if any component was cut.
    pub fn any(&self) -> bool {
        self.forward || self.lateral || self.turn || self.in_place
    }

    /// The cuts as the `ACK` to a `VELOCITY` or `GOAL` carries them (bit 0 forward, 1 across,
    /// 2 turn, 3 in place; see [`crate::wire::Ack::cut`]).
    pub fn mask(&self) -> u8 {
        u8::from(self.forward)
            | u8::from(self.lateral) << 1
            | u8::from(self.turn) << 2
            | u8::from(self.in_place) << 3
    }

    /// The cuts of a `mask` ([`Saturation::mask`]).
    pub fn from_mask(mask: u8) -> Self {
        Self {
            forward: mask & 1 != 0,
            lateral: mask & 2 != 0,
            turn: mask & 4 != 0,
            in_place: mask & 8 != 0,
        }
    }

    /// Both cuts together.
    pub fn or(self, other: Self) -> Self {
        Self {
            forward: self.forward || other.forward,
            lateral: self.lateral || other.lateral,
            turn: self.turn || other.turn,
            in_place: self.in_place || other.in_place,
        }
    }
}

/// Why a velocity cannot be walked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VelocityError {
    /// A component is not a finite number.
    NonFinite,
}

/// The gait's figures the generator needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stepping<T = f64> {
    /// The time of one step, `(single + double support) · dt` \[s\].
    pub period: T,
    /// The nominal distance across between the feet \[m\].
    pub width: T,
    /// The legs' limits.
    pub reach: Reach<T>,
    /// The soles.
    pub soles: Soles<T>,
}

impl<T: Real> Stepping<T> {
    /// The step period, width and soles of `params`, with the legs' limits `reach`.
    pub fn of(params: &GaitParams<T>, reach: Reach<T>) -> Self {
        let ticks = params.single_ticks.saturating_add(params.double_ticks);
        Self {
            period: params.dt * T::of(f64::from(ticks)),
            width: params.step_width,
            reach,
            soles: Soles::of(params),
        }
    }

    /// The next landing of the foot that is not `support`, which lifts off from `same`;
    /// `from_rest`: the first step of a walk from standing (its growth is measured from a
    /// step of 0, as the node measures it).
    #[inline(never)] // (one copy for its callers: the firmware's flash)
    pub fn next_step(
        &self,
        v: &Velocity<T>,
        support: &Footstep<T>,
        same: &Footstep<T>,
        from_rest: bool,
    ) -> Result<(Footstep<T>, Saturation), VelocityError> {
        if !v.is_finite() {
            return Err(VelocityError::NonFinite);
        }
        let r = &self.reach;
        let side = support.side.other();
        let toward = |c: T| match side {
            Side::Left => c > T::ZERO,
            Side::Right => c < T::ZERO,
        };
        let two = T::of(2.0);
        let mut sat = Saturation::default();
        // What was asked.
        let want_yaw = if toward(v.wz) {
            two * v.wz * self.period
        } else {
            T::ZERO
        };
        let want_width = if toward(v.vy) {
            self.width + two * v.vy.abs() * self.period
        } else {
            self.width
        };
        let want_forward = v.vx * self.period;
        // Where the swinging foot lifts off and the step before, in the support foot's frame.
        let (lift, _) = frame_of(support, same, side);
        let before = if from_rest {
            T::ZERO
        } else {
            frame_of(same, support, support.side).0
        };
        // The heading change.
        let dyaw = clamp(want_yaw, -r.max_yaw, r.max_yaw);
        sat.turn |= dyaw != want_yaw;
        // The width.
        let width = clamp(want_width, r.min_width, r.max_width);
        sat.lateral |= width != want_width;
        // The forward step: the box less the turn's cost, the stride, the growth, the
        // distance between the feet.
        let mut hi = (r.max_forward - r.yaw_cost * dyaw.abs())
            .min(lift + r.max_stride)
            .min(before + r.max_growth);
        let reach_left = r.max_feet_distance * r.max_feet_distance - width * width;
        let along = if reach_left > T::ZERO {
            reach_left.sqrt()
        } else {
            T::ZERO
        };
        hi = hi.min(along);
        let lo = (-r.max_backward).max(lift - r.max_stride).max(-along);
        let mut forward = if lo <= hi {
            clamp(want_forward, lo, hi)
        } else {
            T::ZERO
        };
        sat.forward |= forward != want_forward;
        // The check the node makes; the halvings for what the closed forms leave out.
        let mut dyaw = dyaw;
        let half = T::of(0.5);
        // (The feet's frames once, for every try.)
        let stance = Stance::of(support, same);
        for _ in 0..=HALVINGS {
            let step = place(support, side, forward, width, dyaw);
            if r.broken_in(&stance, &step, from_rest, &self.soles)
                .is_none()
            {
                return Ok((step, sat));
            }
            sat.turn |= dyaw != T::ZERO;
            sat.forward |= forward != T::ZERO;
            dyaw *= half;
            forward *= half;
        }
        sat.in_place = true;
        Ok((place(support, side, T::ZERO, self.width, T::ZERO), sat))
    }

    /// The next `N` landings from standing or walking: the first from `support` (the foot
    /// that stays) and `same` (where the first swinging foot stands), each later one from the
    /// one before; the cuts of all of them together.
    pub fn steps<const N: usize>(
        &self,
        v: &Velocity<T>,
        support: &Footstep<T>,
        same: &Footstep<T>,
        from_rest: bool,
    ) -> Result<([Footstep<T>; N], Saturation), VelocityError> {
        let mut out = [*support; N];
        let (mut s, mut o) = (*support, *same);
        let mut sat = Saturation::default();
        for (i, slot) in out.iter_mut().enumerate() {
            let (step, cut) = self.next_step(v, &s, &o, from_rest && i == 0)?;
            sat = sat.or(cut);
            *slot = step;
            o = s;
            s = step;
        }
        Ok((out, sat))
    }
}

fn clamp<T: Real>(v: T, lo: T, hi: T) -> T {
    v.max(lo).min(hi)
}

/// `to` in the frame of `from`: (forward, width), the width positive toward `to_side`.
fn frame_of<T: Real>(from: &Footstep<T>, to: &Footstep<T>, to_side: Side) -> (T, T) {
    let (s, c) = from.yaw.sin_cos();
    let (dx, dy) = (to.x - from.x, to.y - from.y);
    let forward = c * dx + s * dy;
    let width = -s * dx + c * dy;
    match to_side {
        Side::Left => (forward, width),
        Side::Right => (forward, -width),
    }
}

/// The landing of `side` at `forward` and `width` (toward its own side) in `support`'s frame,
/// turned by `dyaw` from `support`'s heading.
fn place<T: Real>(support: &Footstep<T>, side: Side, forward: T, width: T, dyaw: T) -> Footstep<T> {
    let (s, c) = support.yaw.sin_cos();
    let across = match side {
        Side::Left => width,
        Side::Right => -width,
    };
    Footstep::new(
        side,
        support.x + c * forward - s * across,
        support.y + s * forward + c * across,
        support.yaw + dyaw,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hrp2() -> Stepping<f64> {
        Stepping::of(&GaitParams::hrp2(), Reach::default())
    }

    fn standing(s: &Stepping<f64>) -> (Footstep<f64>, Footstep<f64>) {
        let right = Footstep::new(Side::Right, 0.0, -0.5 * s.width, 0.0);
        (right, right.beside(s.width))
    }

    #[test]
    fn a_velocity_within_the_limits_is_walked_as_commanded() {
        let s = hrp2();
        let (right, left) = standing(&s);
        let v = Velocity {
            vx: 0.1,
            vy: 0.0,
            wz: 0.0,
        };
        let (steps, sat) = s.steps::<6>(&v, &right, &left, true).unwrap();
        assert!(!sat.any(), "{sat:?}");
        // Each step moves the walk by vx·Tₛ along x, at the nominal width.
        let mut x = 0.0;
        for (i, step) in steps.iter().enumerate() {
            x += v.vx * s.period;
            assert!((step.x - x).abs() < 1e-12, "step {i}: {step:?}");
            let y = if i % 2 == 0 { 0.5 } else { -0.5 } * s.width;
            assert!((step.y - y).abs() < 1e-12, "step {i}: {step:?}");
        }
    }

    #[test]
    fn a_turn_and_a_side_step_average_the_command() {
        let s = hrp2();
        let (right, left) = standing(&s);
        let v = Velocity {
            vx: 0.0,
            vy: 0.05,
            wz: 0.1,
        };
        let (steps, sat) = s.steps::<4>(&v, &right, &left, true).unwrap();
        assert!(!sat.any(), "{sat:?}");
        // Two steps (a left and a right) turn 2 ω Tₛ and move the feet' midpoint about
        // 2 vy Tₛ to the left.
        let yaw = steps[3].yaw;
        assert!((yaw - 4.0 * v.wz * s.period).abs() < 1e-12, "{steps:?}");
        assert!((steps[3].yaw - steps[2].yaw).abs() < 1e-12);
    }

    #[test]
    fn a_velocity_beyond_the_legs_is_cut_and_said() {
        let s = hrp2();
        let (right, left) = standing(&s);
        for (v, forward, lateral, turn) in [
            ((5.0, 0.0, 0.0), true, false, false),
            ((-5.0, 0.0, 0.0), true, false, false),
            ((0.0, 5.0, 0.0), false, true, false),
            ((0.0, 0.0, 5.0), false, false, true),
        ] {
            let v = Velocity {
                vx: v.0,
                vy: v.1,
                wz: v.2,
            };
            let (_, sat) = s.steps::<4>(&v, &right, &left, true).unwrap();
            assert_eq!(
                (sat.forward, sat.lateral, sat.turn),
                (forward, lateral, turn),
                "{v:?}"
            );
        }
    }

    #[test]
    fn a_velocity_that_is_not_a_number_plans_nothing() {
        let s = hrp2();
        let (right, left) = standing(&s);
        for v in [
            Velocity {
                vx: f64::NAN,
                ..Velocity::ZERO
            },
            Velocity {
                vy: f64::INFINITY,
                ..Velocity::ZERO
            },
            Velocity {
                wz: f64::NEG_INFINITY,
                ..Velocity::ZERO
            },
        ] {
            assert_eq!(
                s.steps::<3>(&v, &right, &left, false),
                Err(VelocityError::NonFinite)
            );
        }
    }
}
