//! Feet: [`Side`] and [`Footstep`] (a foot's position `x, y` \[m\] and heading `yaw` \[rad\] in the
//! world frame), and the angle helpers (headings wrapped to (−π, π]).

use super::*;

/// Left or right foot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Side {
    /// Left foot (+y of the walking line at zero yaw).
    Left,
    /// Right foot.
    Right,
}

impl Side {
    /// The other foot.
    pub fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
    pub(crate) fn index(self) -> usize {
        match self {
            Side::Left => 0,
            Side::Right => 1,
        }
    }
    /// +1 for the left foot, −1 for the right foot.
    pub(super) fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }
}

/// A footstep: which foot, and where its sole centre lands in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footstep<T> {
    /// The foot that lands.
    pub side: Side,
    /// Sole centre x \[m\].
    pub x: T,
    /// Sole centre y \[m\].
    pub y: T,
    /// Heading \[rad\].
    pub yaw: T,
}

impl<T: Real> Footstep<T> {
    /// The left foot at the origin (every byte zero: see [`Gait::parked`]).
    pub(crate) const PARKED: Self = Self {
        side: Side::Left,
        x: T::ZERO,
        y: T::ZERO,
        yaw: T::ZERO,
    };

    /// A footstep.
    pub fn new(side: Side, x: T, y: T, yaw: T) -> Self {
        Self { side, x, y, yaw }
    }
    pub(super) fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.yaw.is_finite()
    }
    pub(super) fn centre(&self) -> [T; 2] {
        [self.x, self.y]
    }
    /// The zero-length step of the other foot: it lands beside this one, `width` apart.
    pub fn beside(&self, width: T) -> Self {
        let side = self.side.other();
        let (s, c) = sin_cos(self.yaw);
        let off = width * T::of(side.sign());
        Self {
            side,
            x: self.x - s * off,
            y: self.y + c * off,
            yaw: self.yaw,
        }
    }
}

/// `a` wrapped into [−π, π] (unchanged, and no libm call, when it is already inside: the
/// usual case, on every tick for every foot).
pub(super) fn wrap_angle<T: Real>(a: T) -> T {
    // In the scalar itself (no software double on a single-precision FPU) while inside.
    if a.abs() <= T::of(core::f64::consts::PI) {
        a
    } else {
        T::of(libm::remainder(a.f64(), core::f64::consts::TAU))
    }
}

/// In the scalar itself ([`Real::sin_cos`]).
pub(super) fn sin_cos<T: Real>(a: T) -> (T, T) {
    a.sin_cos()
}

pub(super) fn midpoint<T: Real>(a: [T; 2], b: [T; 2]) -> [T; 2] {
    let h = T::of(0.5);
    [h * (a[0] + b[0]), h * (a[1] + b[1])]
}
