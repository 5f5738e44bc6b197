//! What the gait puts out every tick: the [`Reference`] (COG and ZMP of both planes, the
//! [`Phase`], the feet's poses) and, per re-plan, [`ReplanInfo`] (eq. 18's `r` and `ΔT`).

use super::*;

/// The phase of the gait at the present tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Standing still in double support.
    Standing,
    /// Double support (both feet on the ground) while walking, starting or stopping.
    Double,
    /// Single support on the given foot; the other one swings.
    Single(Side),
}

/// Pose of one foot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootPose<T> {
    /// Sole centre x \[m\].
    pub x: T,
    /// Sole centre y \[m\].
    pub y: T,
    /// Sole height above the floor \[m\].
    pub z: T,
    /// Heading \[rad\].
    pub yaw: T,
}

/// The reference of one control tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference<T> {
    /// Sagittal (x) COG and ZMP.
    pub x: Sample<T>,
    /// Frontal (y) COG and ZMP.
    pub y: Sample<T>,
    /// Phase.
    pub phase: Phase,
    /// Left and right foot poses.
    pub feet: [FootPose<T>; 2],
}

impl<T: Real> Reference<T> {
    /// `true` when every COG, ZMP and foot value is finite.
    pub fn is_finite(&self) -> bool {
        let plane = |p: &Sample<T>| {
            p.cog.is_finite()
                && p.cog_vel.is_finite()
                && p.cog_acc.is_finite()
                && p.zmp.is_finite()
                && p.zmp_vel.is_finite()
        };
        plane(&self.x)
            && plane(&self.y)
            && self
                .feet
                .iter()
                .all(|f| f.x.is_finite() && f.y.is_finite() && f.z.is_finite() && f.yaw.is_finite())
    }
}

/// The measured state as the node's step adjustment gives it to the gait
/// ([`super::Gait::set_measured`]): what the re-plan that lifts a capture step's foot starts
/// from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deviation<T> {
    /// `e = ξ_meas − ξ_ref` \[m\] (x, y): the measured divergent component's deviation from
    /// the reference's.
    pub error: [T; 2],
    /// How far the capture step's landing was moved for it \[m\] (x, y).
    pub moved: [T; 2],
    /// The robot's stabilizer's ZMP margin `m` in the sole \[m\].
    pub margin: T,
}

impl<T: Real> Deviation<T> {
    /// Nothing measured: every re-plan starts from the reference's state.
    pub const ZERO: Self = Self {
        error: [T::ZERO; 2],
        moved: [T::ZERO; 2],
        margin: T::ZERO,
    };
}

/// What the last re-plan did (for reports and tests).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplanInfo<T> {
    /// Tick (since the gait was created) of the re-plan.
    pub tick: u64,
    /// Single-support adjustment applied \[ticks\].
    pub adjust_ticks: i32,
    /// `r` of eq. 18 (1 when no modification was pending).
    pub ratio: T,
    /// Plane that decided the adjustment (0 = x, 1 = y).
    pub plane: u8,
    /// Worst ZMP excursion of the first interval in the support-foot frame (x, y) \[m\].
    pub worst_zmp: [T; 2],
}
