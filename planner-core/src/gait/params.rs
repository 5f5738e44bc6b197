//! The gait's parameters ([`GaitParams`]: `dt` the control period, `T_ss`/`T_ds` the single- and
//! double-support durations, `z_c` the COG height with `ω = √(g/z_c)`, the step width and sole,
//! eq. 18's clamp `[ΔT_min, ΔT_max]`, the swing, shaping and the window tail) with their checks, and
//! [`GaitError`].

use super::*;

/// How a window ends (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tail {
    /// The ZMP settles to the midpoint of the last two footholds.
    Settle,
    /// A single support on the last landing, ending over its centre.
    Single,
}

/// Gait parameters. Durations are in control ticks, so every phase is on the control grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitParams<T> {
    /// ω = √(g/z_c) \[1/s\].
    pub omega: T,
    /// Control period \[s\].
    pub dt: T,
    /// Single support \[ticks\].
    pub single_ticks: u32,
    /// Double support \[ticks\].
    pub double_ticks: u32,
    /// The double support that starts walking from standing \[ticks\].
    pub start_ticks: u32,
    /// The settling interval of a stop \[ticks\].
    pub settle_ticks: u32,
    /// Each padding interval of a stop window (a window always has 7 intervals) \[ticks\].
    pub stand_ticks: u32,
    /// The final resting interval of a stop window \[ticks\].
    pub rest_ticks: u32,
    /// Shortest single-support adjustment `ΔT_min` \[ticks\] (negative).
    pub adjust_min_ticks: i32,
    /// Longest single-support adjustment `ΔT_max` \[ticks\].
    pub adjust_max_ticks: i32,
    /// Distance between the foot centres of a zero-length step \[m\].
    pub step_width: T,
    /// Half the sole length (x in the foot frame) \[m\].
    pub sole_half_length: T,
    /// Half the sole width (y in the foot frame) \[m\].
    pub sole_half_width: T,
    /// Swing-foot height at mid-swing \[m\].
    pub step_height: T,
    /// How a window ends.
    pub tail: Tail,
    /// Shape the ZMP fluctuation of the first interval of every window with preview control
    /// (section IV.B).
    pub shaping: bool,
    /// COG height for the preview controller's cart-table model \[m\].
    pub cog_height: f64,
    /// Gravity \[m/s²\].
    pub gravity: f64,
    /// Weight `Q_e` of the squared ZMP error in the preview controller \[1/m²\].
    pub preview_qe: f64,
    /// Weight `R` of the squared COG jerk in the preview controller.
    pub preview_r: f64,
}

impl<T: Real> GaitParams<T> {
    /// Every value zero, `false` and the first variant (not parameters to walk with: see
    /// [`Gait::parked`]).
    pub(crate) const PARKED: Self = Self {
        omega: T::ZERO,
        dt: T::ZERO,
        single_ticks: 0,
        double_ticks: 0,
        start_ticks: 0,
        settle_ticks: 0,
        stand_ticks: 0,
        rest_ticks: 0,
        adjust_min_ticks: 0,
        adjust_max_ticks: 0,
        step_width: T::ZERO,
        sole_half_length: T::ZERO,
        sole_half_width: T::ZERO,
        step_height: T::ZERO,
        tail: Tail::Settle,
        shaping: false,
        cog_height: 0.0,
        gravity: 0.0,
        preview_qe: 0.0,
        preview_r: 0.0,
    };

    /// The HRP-2 defaults: z_c 0.814 m, g 9.8 m/s², 5 ms cycle, single support 0.7 s, double
    /// support 0.1 s, start 0.8 s, stop: settle 0.7 s and rest 0.5 s, adjustments
    /// −0.2 … +0.35 s, feet 0.2 m apart, sole
    /// 0.24 × 0.14 m, step height 0.05 m, preview weights `Q_e = 1`, `R = 1e-6`. The same
    /// values as the robot file `host-sim/robots/hrp2.toml` (a test compares them).
    pub fn hrp2() -> Self {
        Self {
            omega: T::of(libm::sqrt(crate::GRAVITY / crate::HRP2_COG_HEIGHT)),
            dt: T::of(0.005),
            single_ticks: 140,
            double_ticks: 20,
            start_ticks: 160,
            settle_ticks: 140,
            stand_ticks: 1,
            rest_ticks: 100,
            adjust_min_ticks: -40,
            adjust_max_ticks: 70,
            step_width: T::of(0.2),
            sole_half_length: T::of(0.12),
            sole_half_width: T::of(0.07),
            step_height: T::of(0.05),
            tail: Tail::Settle,
            shaping: true,
            cog_height: crate::HRP2_COG_HEIGHT,
            gravity: crate::GRAVITY,
            preview_qe: crate::shaping::DEFAULT_QE,
            preview_r: crate::shaping::DEFAULT_R,
        }
    }

    /// The preview controller of these parameters: the cart-table model (`dt`, `z_c`, `g`)
    /// and the weights, with the default solver settings.
    pub fn preview_config(&self) -> PreviewConfig {
        PreviewConfig {
            model: CartTable {
                dt: self.dt.f64(),
                z_c: self.cog_height,
                g: self.gravity,
            },
            qe: self.preview_qe,
            r: self.preview_r,
            ..PreviewConfig::default()
        }
    }

    pub(super) fn seconds(&self, ticks: u32) -> T {
        T::of(ticks as f64) * self.dt
    }

    /// Checks that every window this gait can build is one the planner accepts: the control
    /// period, ω, COG height, gravity and the preview weights finite and positive; every interval (single, double,
    /// start, settle, standing, rest, and the single support with either adjustment limit) on
    /// the planner's range of 5 ms … 10 s; `ΔT_min ≤ 0 ≤ ΔT_max`; the sole, the step width and
    /// height finite and positive (the height non-negative). `BadParams` otherwise.
    pub fn validate(&self) -> Result<(), GaitError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let dt = self.dt.f64();
        // In `T`, as the window computes and checks its intervals (for `f32`, 1 tick of the
        // rounded 5 ms is 4.99999989 ms in `f64`, but exactly the window's 5 ms in `f32`).
        let span = |ticks: i64| {
            let d = (T::of(ticks as f64) * self.dt).f64();
            (T::of(0.005).f64() - 1e-12..=T::of(10.0).f64() + 1e-12).contains(&d)
        };
        let single = i64::from(self.single_ticks);
        let ok = pos(dt)
            && pos(self.omega.f64())
            && pos(self.cog_height)
            && pos(self.gravity)
            && pos(self.preview_qe)
            && pos(self.preview_r)
            && [
                single,
                i64::from(self.double_ticks),
                i64::from(self.start_ticks),
                i64::from(self.settle_ticks),
                i64::from(self.stand_ticks),
                i64::from(self.rest_ticks),
                single + i64::from(self.adjust_min_ticks),
                single + i64::from(self.adjust_max_ticks),
            ]
            .iter()
            .all(|&t| span(t))
            && self.adjust_min_ticks <= 0
            && self.adjust_max_ticks >= 0
            && pos(self.sole_half_length.f64())
            && pos(self.sole_half_width.f64())
            && pos(self.step_width.f64())
            && self.step_height.f64().is_finite()
            && self.step_height.f64() >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(GaitError::BadParams)
        }
    }
}

/// Why the gait refused a command. The gait's plan is unchanged after any of these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum GaitError {
    /// The footstep queue is full.
    QueueFull,
    /// A coordinate is not finite.
    NonFinite,
    /// Steps must alternate feet: this one has the same side as the step before it.
    SideOrder,
    /// No queued step has this id (never queued, or already executed).
    UnknownStep,
    /// The step is being swung: its foot has lifted off.
    LiftedOff,
    /// Even with the adjusted single support, the ZMP would leave the support foot.
    Infeasible,
    /// The command is not valid in the present state (e.g. start while walking).
    WrongState,
    /// The window could not be planned.
    Plan(PlanError),
    /// The preview-control gains could not be computed.
    Gains(GainError),
    /// The parameters fail [`GaitParams::validate`].
    BadParams,
}

impl From<PlanError> for GaitError {
    fn from(e: PlanError) -> Self {
        GaitError::Plan(e)
    }
}
