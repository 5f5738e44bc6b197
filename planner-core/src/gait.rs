//! The gait: footstep queue, phases, re-planning at every start of single support, and the
//! immediate modification of the next landing with the single-support adjustment of eq. 18.
//!
//! # Windows
//! The gait re-plans a 7-interval [window](crate::window) at every start of single support
//! (Fig. 2 of the paper): with `S₀` the support foot and `L₁, L₂, L₃` the next three landings,
//!
//! ```text
//! SS on S₀ (T_ss + ΔT) | DS → L₁ | SS on L₁ | DS → L₂ | SS on L₂ | DS → L₃ | tail
//! ```
//!
//! The ZMP via points are the foot centres: the support-foot centre in single support, the
//! next foot's centre at the end of double support, zero ZMP velocity at every via point.
//! Steps not given yet have zero length (the swing foot lands beside the support foot at the
//! nominal step width, the paper's rule), and the window ends with the COG at rest over its
//! last via point. The *tail* is a settling interval that brings the ZMP to the midpoint of the
//! last two footholds ([`Tail::Settle`], the default) or a single support on `L₃`
//! ([`Tail::Single`]); which of the two the paper used is not stated, and the Table II test
//! measures both.
//!
//! Walking starts from standing with a start window whose first interval is a double support
//! that shifts the ZMP from between the feet to the first support foot; it stops with a stop
//! window (the last landing, a settle to the midpoint of the feet, then standing intervals).
//! Only the first interval(s) of every window are executed: the next re-plan replaces the rest.
//!
//! # Immediate modification (section IV.A, eq. 18)
//! A queued footstep may be modified until its swing starts (the swing foot lifts off at the
//! start of single support); the step being swung and executed steps are refused with a reason.
//! When the swing target `L₁` was modified after the current window was planned, the re-plan
//! compares, at that instant, the executed pattern (`x_i`, the present reference state) with the
//! pattern that the previous re-plan would have produced had it known the footsteps as they are
//! now (`x_f`: the previous window solved again from its own initial state with the current
//! footsteps), through their divergent components `d = ω(x − p) + (ẋ − ṗ)`:
//!
//! ```text
//! r = d_f / d_i,     ΔT = ln(r) / ω  clamped to [ΔT_min, ΔT_max] and rounded to the 5 ms grid.
//! ```
//!
//! Choices where the paper is silent (each measured in the Table II test):
//! * the plane that decides is the one in which the modification moves the divergent component
//!   most (`|d_f − d_i|` larger); the other plane keeps the shaped fluctuation;
//! * a vanishing denominator (`|d_i|` below 1 mm/s·ω: the COG is not moving in that plane, e.g.
//!   walking in place) gives `ΔT = 0`: there is no motion to slow down or speed up (Table II's
//!   "before 0" column is all zeros);
//! * `r ≤ 0` (the modification reverses the motion) gives `ΔT_max` as eq. 18 says, except when
//!   `|d_f|` is itself below the threshold: the target pattern is at rest, `r → 0⁺`, and
//!   `ln r → −∞` gives `ΔT_min` (Table II's "after 0" row).
//!
//! # Feasibility (eq. 17)
//! A modification of the next swing target is checked when it arrives: the re-plan it would
//! cause is computed and the worst ZMP excursion of the first interval, in the support foot's
//! frame (the ZMP polynomials rotated into the foot frame are quartics, so
//! [`worst_deviation`] gives their exact extrema), must stay inside the sole. Otherwise the
//! modification is refused with [`GaitError::Infeasible`] and the queue is unchanged.

use core::borrow::Borrow;

use heapless::Deque;

use crate::lipm::{Poly, Sample, Segment, State};
use crate::real::Real;
use crate::shaping::{
    CartTable, Compensation, Compensator, GainError, Law, Piece, PreviewConfig, PreviewGains,
};
use crate::timing::worst_deviation;
use crate::window::{Factorized, Plan, PlanError, PlaneBoundary, Timing, M};

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
    fn sign(self) -> f64 {
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
    fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.yaw.is_finite()
    }
    fn centre(&self) -> [T; 2] {
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
fn wrap_angle<T: Real>(a: T) -> T {
    // In the scalar itself (no software double on a single-precision FPU) while inside.
    if a.abs() <= T::of(core::f64::consts::PI) {
        a
    } else {
        T::of(libm::remainder(a.f64(), core::f64::consts::TAU))
    }
}

/// In the scalar itself ([`Real::sin_cos`]).
fn sin_cos<T: Real>(a: T) -> (T, T) {
    a.sin_cos()
}

fn midpoint<T: Real>(a: [T; 2], b: [T; 2]) -> [T; 2] {
    let h = T::of(0.5);
    [h * (a[0] + b[0]), h * (a[1] + b[1])]
}

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

    fn seconds(&self, ticks: u32) -> T {
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Start,
    Single,
    Double,
    Settle,
    Stand,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum WindowKind {
    Start,
    Walk,
    Stop,
}

/// What [`Gait::predict_replan`] planned into the spare buffer (see `Gait::predicted`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Predicted<T> {
    gen: u32,
    serial: u32,
    at: u32,
    inputs: Inputs<T>,
    cog: [State<T>; 2],
    zmp: [State<T>; 2],
}

/// Everything needed to build a window, kept so that eq. 18 can solve it again.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Inputs<T> {
    kind: WindowKind,
    /// Support foot of the first single support.
    support: Footstep<T>,
    /// The other foot where it stands (start and stop windows).
    other: Footstep<T>,
    /// Landings (only the first `n_land` are used).
    land: [Footstep<T>; 3],
    n_land: usize,
    /// Duration of the first interval \[ticks\].
    first_ticks: u32,
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
struct Spec<T> {
    ticks: [u32; M],
    kinds: [Kind; M],
    support: [Option<Side>; M],
    via: [[T; 2]; M],
    /// Interval at whose start the next re-plan happens.
    replan: Option<usize>,
}

/// Writes the window's intervals into `spec` (in place: a `Spec` returned by value costs two
/// copies of its 180 bytes on the Cortex-M).
fn build_spec<T: Real>(spec: &mut Spec<T>, p: &GaitParams<T>, inp: &Inputs<T>) {
    spec.ticks = [p.stand_ticks; M];
    spec.kinds = [Kind::Stand; M];
    spec.support = [None; M];
    spec.via = [[T::ZERO; 2]; M];
    spec.replan = None;
    let mut n = 0;
    fn push<T: Copy>(
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
fn boundaries<T: Real>(
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

/// The window being executed.
#[derive(Clone, Debug)]
struct Active<T: Real> {
    inputs: Inputs<T>,
    spec: Spec<T>,
    bounds: [PlaneBoundary<T>; 2],
    factor: Factorized<T>,
    plan: Plan<T>,
    /// Ticks since the window started.
    tick: u32,
    /// Window tick of every interval start, and the window end.
    starts: [u32; M + 1],
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
    fn clear(&mut self, p: &GaitParams<T>, feet: &[Footstep<T>; 2]) {
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
    fn plan_into(
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

    fn interval(&self, tick: u32) -> usize {
        (0..M).rev().find(|&j| tick >= self.starts[j]).unwrap_or(0)
    }

    fn sample(&self, p: &GaitParams<T>, tick: u32) -> (Sample<T>, Sample<T>) {
        let j = self.interval(tick);
        let tau = p.seconds(tick - self.starts[j]);
        Segment::sample_pair(&self.plan.x[j], &self.plan.y[j], tau)
    }

    /// Worst ZMP excursion of interval 0 in the frame of its support foot (or of the via point
    /// when the interval is not a single support): `(along the foot, across the foot)`.
    fn worst_first(&self) -> [T; 2] {
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

/// A queued footstep.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Queued<T> {
    id: u16,
    step: Footstep<T>,
    /// Modified after the current window was planned.
    modified: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Standing,
    Walking,
}

/// The gait generator: a footstep queue of capacity `Q` and the window being executed.
///
/// `G` holds the preview-control gains: by value (the default, computed by [`Gait::new`]) or
/// anything that lends them ([`Borrow`]), such as a reference to gains in flash or a
/// zero-sized type that names them (the firmware keeps its 22 KB of gains out of RAM this way:
/// [`Gait::with_gains`]).
#[derive(Clone, Debug)]
pub struct Gait<T: Real, const Q: usize, G = PreviewGains<T, PREVIEW>> {
    params: GaitParams<T>,
    queue: Deque<Queued<T>, Q>,
    /// Where each foot stands (the swing foot: where it lifted off).
    feet: [Footstep<T>; 2],
    /// The step being swung, with its id.
    swing: Option<Queued<T>>,
    /// The side of the last step that landed (none since start-up or a re-basing).
    landed: Option<Side>,
    /// The last re-plan failed (see [`Gait::replan_failed`]).
    failed: bool,
    /// The queued ids are consecutive (each the successor of the one before it, `+1` modulo
    /// 2¹⁶), so they are distinct and a lookup by id is arithmetic ([`Gait::index_of`]). A lookup hint (set by `push`), always `false` while
    /// the queue is empty, so that a gait emptied and a fresh one compare equal.
    consecutive: bool,
    mode: Mode,
    stop_requested: bool,
    /// Two window buffers: the one being executed and the one the next re-plan is built in.
    wins: [Active<T>; 2],
    /// The buffer being executed, if walking.
    cur: Option<usize>,
    /// Changes whenever the footsteps or the stop request change.
    gen: u32,
    /// Changes whenever a new window becomes the current one.
    serial: u32,
    /// Cached `x_f` of eq. 18: (gen, serial, window tick, state).
    target: Option<(u32, u32, u32, [Sample<T>; 2])>,
    /// The re-plan that the feasibility check of a modification planned into the spare
    /// buffer: (gen, serial, window tick, its inputs and initial state). The re-plan at that
    /// tick takes the spare buffer as it is if all of these are still the same (the plan is a
    /// function of them: bit for bit what it would compute again).
    predicted: Option<Predicted<T>>,
    /// The worst first-interval excursion (eq. 17) of the predicted plan, for the re-plan
    /// that takes it (valid while `predicted` is `Some`).
    predicted_worst: [T; 2],
    tick: u64,
    last: Reference<T>,
    info: Option<ReplanInfo<T>>,
    /// Preview-control gains (shared by both planes) and the two compensators.
    gains: G,
    comp: [Compensator<T>; 2],
}

/// Preview length of the shaping compensator \[ticks\] (1.6 s at 5 ms).
pub const PREVIEW: usize = 320;

/// COG and ZMP states of both planes from their samples.
fn states<T: Real>(x: &Sample<T>, y: &Sample<T>) -> ([State<T>; 2], [State<T>; 2]) {
    (
        [State::new(x.cog, x.cog_vel), State::new(y.cog, y.cog_vel)],
        [State::new(x.zmp, x.zmp_vel), State::new(y.zmp, y.zmp_vel)],
    )
}

/// `p − c`, sample by sample.
/// The plan of `win` at window tick `t` minus the compensation of the next step of `comp`
/// (which it advances), or the plan alone without shaping.
fn shaped_sample<T: Real>(
    win: &Active<T>,
    params: &GaitParams<T>,
    gains: &PreviewGains<T, PREVIEW>,
    comp: &mut [Compensator<T>; 2],
    t: u32,
) -> (Sample<T>, Sample<T>) {
    shaped_by(win, params, gains, t, |k| comp[k & 1].step(gains))
}

/// What [`shaped_sample`] returns, without advancing the compensators.
fn shaped_peek<T: Real>(
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
fn shaped_by<T: Real>(
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

fn minus<T: Real>(p: Sample<T>, c: Sample<T>) -> Sample<T> {
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
fn fluctuation<T: Real>(c: &Poly<T>) -> Poly<T> {
    let (two, three) = (T::of(2.0), T::of(3.0));
    let p1 = c[0] + c[1] + c[2] + c[3] + c[4];
    let v1 = c[1] + two * c[2] + three * c[3] + T::of(4.0) * c[4];
    let dp = p1 - c[0];
    let h2 = three * dp - two * c[1] - v1;
    let h3 = -two * dp + c[1] + v1;
    [T::ZERO, T::ZERO, c[2] - h2, c[3] - h3, c[4]]
}

impl<T: Real, const Q: usize> Gait<T, Q> {
    /// A robot standing on `left` and `right`, its COG at rest above their midpoint. Computes
    /// the preview-control gains (once; about 1100 Riccati iterations).
    pub fn new(
        params: GaitParams<T>,
        left: Footstep<T>,
        right: Footstep<T>,
    ) -> Result<Self, GaitError> {
        let gains = Self::gains_for(&params, &left, &right)?;
        Self::with_gains(params, left, right, gains)
    }

    /// The preview gains [`Gait::new`] computes for `params` (all zero when it does not shape),
    /// after the checks of [`Gait::restart`] (whose errors come first).
    pub(crate) fn gains_for(
        params: &GaitParams<T>,
        left: &Footstep<T>,
        right: &Footstep<T>,
    ) -> Result<PreviewGains<T, PREVIEW>, GaitError> {
        Self::check(params, left, right)?;
        let mut gains = PreviewGains::zeroed();
        if params.shaping {
            gains
                .compute(&params.preview_config(), Law::FromRest)
                .map_err(GaitError::Gains)?;
        }
        Ok(gains)
    }
}

impl<T: Real, const Q: usize, G> Gait<T, Q, G> {
    /// A gait that is not configured yet, holding `gains`: zero parameters, both feet at the
    /// origin, empty buffers. Its one use is to be configured in place by
    /// [`Gait::restart`] (the node's [`ParkedNode`](crate::node::ParkedNode)): a `static`
    /// initialised with it needs no start-up stack, and, when `G` is zero-sized (gains named
    /// by a type, not a reference), no flash either, because every byte of it is zero (the
    /// fields with a niche hold the value whose bytes are zero, e.g. `Some(Side::Left)`; the
    /// firmware's size check fails if the node's static leaves .bss). Not a gait to tick.
    pub(crate) const fn parked(gains: G) -> Self {
        Self {
            params: GaitParams::PARKED,
            queue: Deque::new(),
            feet: [Footstep::PARKED; 2],
            swing: Some(Queued {
                id: 0,
                step: Footstep::PARKED,
                modified: false,
            }),
            landed: Some(Side::Left),
            failed: false,
            consecutive: false,
            mode: Mode::Standing,
            stop_requested: false,
            wins: [Active::PARKED, Active::PARKED],
            cur: None,
            gen: 0,
            serial: 0,
            predicted: Some(Predicted {
                gen: 0,
                serial: 0,
                at: 0,
                inputs: Inputs::PARKED,
                cog: [State::ZERO; 2],
                zmp: [State::ZERO; 2],
            }),
            predicted_worst: [T::ZERO; 2],
            target: None,
            tick: 0,
            last: Reference {
                x: Sample::ZERO,
                y: Sample::ZERO,
                phase: Phase::Single(Side::Left),
                feet: [FootPose {
                    x: T::ZERO,
                    y: T::ZERO,
                    z: T::ZERO,
                    yaw: T::ZERO,
                }; 2],
            },
            info: None,
            gains,
            comp: [Compensator::new(), Compensator::new()],
        }
    }

    /// Why `params`, `left` and `right` start no gait (in [`Gait::restart`]'s order), if they
    /// do not.
    fn check(
        params: &GaitParams<T>,
        left: &Footstep<T>,
        right: &Footstep<T>,
    ) -> Result<(), GaitError> {
        if !(left.is_finite() && right.is_finite()) {
            return Err(GaitError::NonFinite);
        }
        params.validate()
    }
}

impl<T: Real, const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>> Gait<T, Q, G> {
    /// [`Gait::new`] with preview gains computed beforehand (the firmware compiles them into
    /// flash from the robot file) and lent by `gains` (a reference, or a type that names
    /// them: nothing is copied). `Gains(BadConfig)` unless they are the gains [`Gait::new`]
    /// would compute for `params` ([`PreviewGains::are_for`]); not used when `params.shaping`
    /// is off.
    pub fn with_gains(
        params: GaitParams<T>,
        left: Footstep<T>,
        right: Footstep<T>,
        gains: G,
    ) -> Result<Self, GaitError> {
        let mut g = Self::parked(gains);
        g.restart(params, left, right)?;
        Ok(g)
    }

    /// Makes this gait, in place, the one [`Gait::with_gains`] would build for `params`,
    /// `left` and `right` with its own gains: standing, the queue empty, the buffers unused,
    /// tick 0. Nothing is built on the stack (the gait is 12 KB; a `static` parked gait, inside
    /// a [`ParkedNode`](crate::node::ParkedNode), is configured this way). On error (the same checks and the same
    /// errors as [`Gait::with_gains`]) nothing changes.
    pub fn restart(
        &mut self,
        params: GaitParams<T>,
        left: Footstep<T>,
        right: Footstep<T>,
    ) -> Result<(), GaitError> {
        Self::check(&params, &left, &right)?;
        if params.shaping
            && !self
                .gains
                .borrow()
                .are_for(&params.preview_config(), Law::FromRest)
        {
            return Err(GaitError::Gains(GainError::BadConfig));
        }
        let mut left = left;
        let mut right = right;
        left.side = Side::Left;
        right.side = Side::Right;
        let feet = [left, right];
        let mid = midpoint(left.centre(), right.centre());
        let at = |v: T| Sample {
            cog: v,
            zmp: v,
            ..Sample::default()
        };
        self.params = params;
        self.queue.clear();
        self.consecutive = false;
        self.feet = feet;
        self.swing = None;
        self.landed = None;
        self.failed = false;
        self.mode = Mode::Standing;
        self.stop_requested = false;
        for w in &mut self.wins {
            w.clear(&params, &feet);
        }
        self.cur = None;
        self.gen = 0;
        self.serial = 0;
        self.predicted = None;
        self.predicted_worst = [T::ZERO; 2];
        self.target = None;
        self.tick = 0;
        self.last = Reference {
            x: at(mid[0]),
            y: at(mid[1]),
            phase: Phase::Standing,
            feet: [FootPose::default(); 2],
        };
        self.info = None;
        self.comp = [Compensator::new(), Compensator::new()];
        self.last.feet = self.ground_poses();
        Ok(())
    }

    /// The parameters.
    pub fn params(&self) -> &GaitParams<T> {
        &self.params
    }

    /// The reference of the last tick.
    pub fn last(&self) -> &Reference<T> {
        &self.last
    }

    /// What the last re-plan did.
    pub fn last_replan(&self) -> Option<&ReplanInfo<T>> {
        self.info.as_ref()
    }

    /// How many windows have been planned and made current since the last (re)start,
    /// wrapping: the start window, every re-plan and every stop window. A change between two
    /// ticks means the tick in between planned one.
    pub fn plans(&self) -> u32 {
        self.serial
    }

    /// Where the foot of the other side than `side` will be just before a step of `side` is
    /// taken: the last such step queued before the step `before` (or before the end of the
    /// queue), else the one being swung, else where that foot stands. Used to check reach.
    pub fn previous_other(&self, side: Side, before: Option<u16>) -> Footstep<T> {
        self.previous_feet(before)[side.other().index()]
    }

    /// Where each foot will stand just before the queued step `before` is taken (or after the
    /// whole queue, for `None`), indexed by side (`[left, right]`): the last queued step of that
    /// side before it, else the swing target of that side, else where the foot stands. One
    /// pass over the queue for both feet ([`previous_other`](Self::previous_other) is one of
    /// them).
    pub fn previous_feet(&self, before: Option<u16>) -> [Footstep<T>; 2] {
        let mut last: [Option<&Footstep<T>>; 2] = [None, None];
        // Backwards from the step before `before`: the queue alternates sides, so two steps
        // settle both (the first of each side met is the last before `before`).
        let end = before
            .and_then(|id| self.index_of(id))
            .unwrap_or(self.queue.len());
        for i in (0..end).rev() {
            if let Some(q) = self.queue.get(i) {
                let l = &mut last[q.step.side.index()];
                if l.is_none() {
                    *l = Some(&q.step);
                }
            }
            if last[0].is_some() && last[1].is_some() {
                break;
            }
        }
        let resolve = |side: Side| match (last[side.index()], self.swing) {
            (Some(step), _) => *step,
            (None, Some(s)) if s.step.side == side => s.step,
            (None, _) => self.feet[side.index()],
        };
        [resolve(Side::Left), resolve(Side::Right)]
    }

    /// `true` if the step `id` is queued (not yet swung).
    pub fn is_queued(&self, id: u16) -> bool {
        self.index_of(id).is_some()
    }

    /// The position of the first queued step `id`. With consecutive ids (every walk the node
    /// drives) the position is `id − front` (modulo 2¹⁶), checked; otherwise a search of the
    /// queue.
    fn index_of(&self, id: u16) -> Option<usize> {
        let front = self.queue.front()?.id;
        if self.consecutive && Q <= 256 {
            // At most 256 consecutive ids are distinct: the one match is there, if anywhere.
            let i = usize::from(id.wrapping_sub(front));
            return self.queue.get(i).is_some_and(|q| q.id == id).then_some(i);
        }
        self.queue.iter().position(|q| q.id == id)
    }

    /// The id of the next swing target (the first queued step), if any. While walking, a
    /// modification of this step plans the re-plan it will cause (eq. 17).
    pub fn next_target(&self) -> Option<u16> {
        self.queue.front().map(|q| q.id)
    }

    /// The footstep queued as `id` (not yet swung), if any.
    pub fn queued_step(&self, id: u16) -> Option<Footstep<T>> {
        self.index_of(id)
            .and_then(|i| self.queue.get(i))
            .map(|q| q.step)
    }

    /// The id of the step being swung, if any.
    pub fn swinging(&self) -> Option<u16> {
        self.swing.map(|s| s.id)
    }

    /// Number of queued steps (not counting the one being swung).
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// `true` while standing still.
    pub fn is_standing(&self) -> bool {
        self.mode == Mode::Standing
    }

    /// Ticks since the gait was created.
    pub fn ticks(&self) -> u64 {
        self.tick
    }

    /// The side the next appended step must have; `None` only when either foot may step
    /// (standing, with nothing queued, and no step landed since start-up or the last
    /// [`Gait::rebase`]). Steps always alternate: the other side than the last queued step,
    /// else than the step being swung, else than the support foot of the current window's
    /// next single support (while walking, the foot that will swing next is fixed by the
    /// plan), else than the last step that landed.
    pub fn next_side(&self) -> Option<Side> {
        if let Some(b) = self.queue.back() {
            return Some(b.step.side.other());
        }
        if let Some(s) = self.swing {
            return Some(s.step.side.other());
        }
        if let Some(c) = self.cur_buf() {
            let w = &self.wins[c];
            if let Some(side) = w
                .spec
                .replan
                .and_then(|j| w.spec.support.get(j).copied().flatten())
            {
                return Some(side.other());
            }
        }
        self.landed.map(Side::other)
    }

    /// Moves the world frame while standing: the new origin is `(x, y)` of the old frame and
    /// the new x axis has the old heading `yaw`. Every pose the gait holds (feet, the resting
    /// reference) is expressed in the new frame; the queue is dropped, and the side of the
    /// next step is free again. `WrongState` unless standing.
    pub fn rebase(&mut self, x: T, y: T, yaw: T) -> Result<(), GaitError> {
        if self.mode != Mode::Standing {
            return Err(GaitError::WrongState);
        }
        if !(x.is_finite() && y.is_finite() && yaw.is_finite()) {
            return Err(GaitError::NonFinite);
        }
        let (s, c) = sin_cos(yaw);
        let to = |px: T, py: T| {
            let (dx, dy) = (px - x, py - y);
            (c * dx + s * dy, -s * dx + c * dy)
        };
        for f in self.feet.iter_mut() {
            let (nx, ny) = to(f.x, f.y);
            f.x = nx;
            f.y = ny;
            f.yaw = wrap_angle(f.yaw - yaw);
        }
        let (cx, cy) = to(self.last.x.cog, self.last.y.cog);
        let (zx, zy) = to(self.last.x.zmp, self.last.y.zmp);
        let rot = |a: T, b: T| (c * a + s * b, -s * a + c * b);
        let (vx, vy) = rot(self.last.x.cog_vel, self.last.y.cog_vel);
        let (ax, ay) = rot(self.last.x.cog_acc, self.last.y.cog_acc);
        let (wx, wy) = rot(self.last.x.zmp_vel, self.last.y.zmp_vel);
        self.last.x = Sample {
            cog: cx,
            cog_vel: vx,
            cog_acc: ax,
            zmp: zx,
            zmp_vel: wx,
        };
        self.last.y = Sample {
            cog: cy,
            cog_vel: vy,
            cog_acc: ay,
            zmp: zy,
            zmp_vel: wy,
        };
        self.last.feet = self.ground_poses();
        self.queue.clear();
        self.consecutive = false;
        self.landed = None;
        self.stop_requested = false;
        self.target = None;
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Where each foot stands (left, right); the swinging foot where it lifted off.
    pub fn feet(&self) -> &[Footstep<T>; 2] {
        &self.feet
    }

    /// Appends a footstep. A full queue hands the step back.
    pub fn push(&mut self, id: u16, step: Footstep<T>) -> Result<(), (GaitError, Footstep<T>)> {
        if !step.is_finite() {
            return Err((GaitError::NonFinite, step));
        }
        if let Some(side) = self.next_side() {
            if side != step.side {
                return Err((GaitError::SideOrder, step));
            }
        }
        let consecutive = match self.queue.back() {
            None => true,
            Some(b) => self.consecutive && id == b.id.wrapping_add(1),
        };
        self.queue
            .push_back(Queued {
                id,
                step,
                modified: false,
            })
            .map_err(|q| (GaitError::QueueFull, q.step))?;
        self.consecutive = consecutive;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Starts walking (from standing) with the queued steps.
    pub fn start(&mut self) -> Result<(), GaitError> {
        if self.mode != Mode::Standing {
            return Err(GaitError::WrongState);
        }
        let Some(first) = self.queue.front() else {
            return Err(GaitError::WrongState);
        };
        // A stop requested while standing (an emergency stop before the walk) is not this
        // walk's: the start window is planned as for a node that never had it.
        self.stop_requested = false;
        let support = self.feet[first.step.side.other().index()];
        let other = self.feet[first.step.side.index()];
        let (land, n) = self.landings(&support, 0);
        let inputs = Inputs {
            kind: WindowKind::Start,
            support,
            other,
            land,
            n_land: n,
            first_ticks: self.params.start_ticks,
        };
        let (cog, zmp) = self.state();
        self.wins[0].plan_into(&self.params, &inputs, cog, zmp)?;
        self.cur = Some(0);
        self.serial = self.serial.wrapping_add(1);
        self.start_shaping();
        // The reference of this instant becomes the window's tick 0 (the same position, with
        // the velocities the pattern starts with), and the compensators take their tick 0.
        let (sx, sy) = self.shaped(0);
        self.last.x = sx;
        self.last.y = sy;
        self.mode = Mode::Walking;
        self.stop_requested = false;
        self.failed = false;
        for q in self.queue.iter_mut() {
            q.modified = false;
        }
        Ok(())
    }

    /// Requests a stop: the queued steps are walked, then the robot settles between its feet.
    /// Steps that are not given are no longer padded with steps in place.
    pub fn stop(&mut self) {
        self.stop_requested = true;
        self.gen = self.gen.wrapping_add(1);
    }

    /// Drops every queued step while standing, and nothing else (no stop is requested: a
    /// later `start` walks what is queued then exactly as if nothing had been dropped).
    pub fn drop_queue(&mut self) -> Result<(), GaitError> {
        if self.mode != Mode::Standing {
            return Err(GaitError::WrongState);
        }
        self.queue.clear();
        self.consecutive = false;
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
        Ok(())
    }

    /// Drops every queued step (not the one being swung) and stops after the present swing.
    pub fn clear_and_stop(&mut self) {
        self.queue.clear();
        self.consecutive = false;
        self.stop_requested = true;
        self.gen = self.gen.wrapping_add(1);
    }

    /// Modifies the queued step `id`. Refused when its foot has lifted off, when it is unknown,
    /// or when the re-plan it would cause is infeasible (eq. 17); the queue is unchanged then.
    pub fn modify(&mut self, id: u16, step: Footstep<T>) -> Result<(), GaitError> {
        if !step.is_finite() {
            return Err(GaitError::NonFinite);
        }
        if self.swing.map(|s| s.id) == Some(id) {
            return Err(GaitError::LiftedOff);
        }
        let Some(pos) = self.index_of(id) else {
            return Err(GaitError::UnknownStep);
        };
        if self.queue.get(pos).map(|q| q.step.side) != Some(step.side) {
            return Err(GaitError::SideOrder);
        }
        let old = self.queue.get(pos).copied();
        if let Some(q) = self.queue.get_mut(pos) {
            q.step = step;
            q.modified = true;
        }
        self.gen = self.gen.wrapping_add(1);
        if pos == 0 && self.mode == Mode::Walking {
            // This is the next swing target: check the re-plan it will cause.
            match self.predict_replan() {
                Ok(Some(worst)) if !self.inside_sole(worst) => {
                    self.undo_modify(pos, old);
                    return Err(GaitError::Infeasible);
                }
                Err(e) => {
                    self.undo_modify(pos, old);
                    return Err(e);
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Puts back the step a refused modification replaced. The spare buffer now holds the
    /// refused plan: the prediction is dropped (a cache: the re-plan computes it again, bit
    /// for bit the same), and `gen` moves on so that no cache keyed on it is taken.
    fn undo_modify(&mut self, pos: usize, old: Option<Queued<T>>) {
        if let (Some(q), Some(o)) = (self.queue.get_mut(pos), old) {
            *q = o;
        }
        self.predicted = None;
        self.gen = self.gen.wrapping_add(1);
    }

    /// `true` if `other` walks on exactly as `self` does: every field that decides a future
    /// reference is equal (queue, feet, swing, phase, the window being executed and its
    /// compensators, the last reference). Not compared: the caches (the spare window buffer,
    /// the eq. 18 target, the prediction of a modification's re-plan, the generation counter
    /// that keys them), which only save work, and the preview gains, which never change.
    pub fn same_state<H: Borrow<PreviewGains<T, PREVIEW>>>(&self, other: &Gait<T, Q, H>) -> bool {
        let mine = self.cur_buf().map(|c| {
            let w = &self.wins[c];
            (w.inputs, w.spec, w.bounds, w.plan, w.tick, w.starts)
        });
        let theirs = other.cur_buf().map(|c| {
            let w = &other.wins[c];
            (w.inputs, w.spec, w.bounds, w.plan, w.tick, w.starts)
        });
        self.params == other.params
            && self.queue.iter().eq(other.queue.iter())
            && self.feet == other.feet
            && self.swing == other.swing
            && self.landed == other.landed
            && self.failed == other.failed
            && self.mode == other.mode
            && self.stop_requested == other.stop_requested
            && self.serial == other.serial
            && self.tick == other.tick
            && self.last == other.last
            && self.info == other.info
            && self.comp == other.comp
            && mine == theirs
    }

    /// `true` while a requested stop is being carried out (the queue is walked without
    /// padding, then the robot settles).
    pub fn is_stopping(&self) -> bool {
        self.mode == Mode::Walking && self.stop_requested
    }

    fn inside_sole(&self, worst: [T; 2]) -> bool {
        worst[0].abs() <= self.params.sole_half_length
            && worst[1].abs() <= self.params.sole_half_width
    }

    /// The first `n ≤ 3` landings from queue position `skip`, padded with steps in place unless
    /// a stop was requested.
    fn landings(&self, support: &Footstep<T>, skip: usize) -> ([Footstep<T>; 3], usize) {
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
    fn cur_buf(&self) -> Option<usize> {
        self.cur.map(|c| c & 1)
    }

    /// The present reference state (what the next window starts from).
    fn state(&self) -> ([State<T>; 2], [State<T>; 2]) {
        states(&self.last.x, &self.last.y)
    }

    /// The re-plan that will happen at the next start of single support if nothing else
    /// changes: returns the worst first-interval ZMP excursion, or `None` if no re-plan is due.
    fn predict_replan(&mut self) -> Result<Option<[T; 2]>, GaitError> {
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
        // few millimetres, see shaping.rs).
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
        self.wins[spare].plan_into(&self.params, &inputs, cog, zmp)?;
        self.predicted = Some(self.prediction(at, inputs, cog, zmp));
        self.predicted_worst = self.wins[spare].worst_first();
        Ok(Some(self.predicted_worst))
    }

    /// The key under which a plan of `inputs` from `(cog, zmp)` at window tick `at` is kept.
    fn prediction(
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
    fn next_walk_inputs(&self, win: &Active<T>, j: usize) -> Option<Inputs<T>> {
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
    fn target_bounds(&self, win: &Active<T>) -> [PlaneBoundary<T>; 2] {
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
    fn adjustment(
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
        let f = match self.target {
            Some((g, w, a, f)) if g == self.gen && w == self.serial && a == at => f,
            _ => {
                let bounds = self.target_bounds(&self.wins[c]);
                // Solved with the current window's factorisation (same timing) into the spare
                // buffer's plan, which the re-plan overwrites anyway: nothing large is copied.
                let (w0, w1) = self.wins.split_at_mut(1);
                let (cur, spare) = if c == 0 {
                    (&w0[0], &mut w1[0])
                } else {
                    (&w1[0], &mut w0[0])
                };
                cur.factor.solve(&bounds[0], &bounds[1], &mut spare.plan)?;
                let j = cur.interval(at);
                let tau = self.params.seconds(at - cur.starts[j]);
                let (fx, fy) = Segment::sample_pair(&spare.plan.x[j], &spare.plan.y[j], tau);
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
        let r = if di.abs() < eps { T::ONE } else { df / di };
        Ok((ticks, r, plane as u8))
    }

    /// Advances one control period and returns its reference.
    pub fn tick(&mut self) -> Reference<T> {
        self.tick += 1;
        let Some(c) = self.cur_buf() else {
            self.last.phase = Phase::Standing;
            self.last.feet = self.ground_poses();
            return self.last;
        };
        self.wins[c].tick += 1;
        let wt = self.wins[c].tick;
        let mut kept = None;
        if let Some(j) = self.wins[c].spec.replan {
            if self.wins[c].starts.get(j) == Some(&wt) {
                // The state at this instant, from the window being left (shaped).
                let (sx, sy) = self.shaped(wt);
                let (cog, zmp) = states(&sx, &sy);
                if self.replan(j, cog, zmp) {
                    self.start_shaping();
                } else {
                    kept = Some((sx, sy));
                }
            }
        }
        let c = self.cur_buf().unwrap_or(c);
        let end = self.wins[c].starts[M];
        if self.wins[c].tick >= end && self.wins[c].spec.replan.is_none() {
            // The stop window has ended: standing (it is never shaped, so the analytic end,
            // at rest, is the reference).
            let (sx, sy) = self.wins[c].sample(&self.params, end);
            self.last.x = sx;
            self.last.y = sy;
            self.mode = Mode::Standing;
            self.stop_requested = false;
            self.last.phase = Phase::Standing;
            self.last.feet = self.ground_poses();
            self.cur = None;
            return self.last;
        }
        let t = self.wins[c].tick.min(end);
        let (sx, sy) = match kept {
            Some(k) => k,
            None => self.shaped(t),
        };
        let win = &self.wins[c];
        let j = win.interval(t);
        let phase = match win.spec.support[j] {
            Some(s) if win.spec.kinds[j] == Kind::Single => Phase::Single(s),
            _ => Phase::Double,
        };
        // The swing ends with the double support that follows it: land it before the poses
        // of this tick are taken.
        if let Some(s) = self.swing {
            if phase == Phase::Double && win.spec.kinds[j] == Kind::Double {
                self.feet[s.step.side.index()] = s.step;
                self.landed = Some(s.step.side);
                self.swing = None;
            }
        }
        // Field by field (small copies the compiler does in registers, not one 150-byte
        // `memcpy` of a whole `Reference` built aside).
        self.last.feet = self.foot_poses(&self.wins[c], j, t);
        self.last.x = sx;
        self.last.y = sy;
        self.last.phase = phase;
        self.last
    }

    /// Re-plans at the start of the single support `j` of the current window, into the spare
    /// buffer; `true` if the new window is now the current one. If the walking window cannot
    /// be planned, the queue is dropped and the stop window planned instead (flagged); only if
    /// that fails too does the old window go on.
    fn replan(&mut self, j: usize, cog: [State<T>; 2], zmp: [State<T>; 2]) -> bool {
        let Some(c) = self.cur_buf() else {
            return false;
        };
        let spare = 1 - c;
        // Land the swing that just ended (the double support before this single support).
        if let Some(s) = self.swing.take() {
            self.feet[s.step.side.index()] = s.step;
            self.landed = Some(s.step.side);
        }
        let Some(mut inputs) = self.next_walk_inputs(&self.wins[c], j) else {
            // Stopping with nothing left to swing: settle.
            return self.plan_stop(c, j, cog, zmp);
        };
        let at = self.wins[c].tick;
        let (adjust, ratio, plane) = self.adjustment(c, at, cog, zmp).unwrap_or((0, T::ONE, 0));
        inputs.first_ticks = adjusted(self.params.single_ticks, adjust);
        // The swing target is the queue front; if there is none (walking in place), the
        // padded zero-length step.
        let swing = match self.queue.pop_front() {
            Some(q) => q,
            None => Queued {
                id: u16::MAX,
                step: inputs.land[0],
                modified: false,
            },
        };
        // The hint is false whenever the queue is empty (as after every `clear`).
        self.consecutive &= !self.queue.is_empty();
        // Planned already by the feasibility check of a modification, with the same inputs
        // from the same state? Then the spare buffer holds this very plan.
        let this = self.prediction(at, inputs, cog, zmp);
        let planned = self.predicted.take() == Some(this);
        if !planned
            && self.wins[spare]
                .plan_into(&self.params, &inputs, cog, zmp)
                .is_err()
        {
            // The walking window cannot be planned (a validated configuration never gets
            // here): do not walk on a plan the feet no longer follow. Drop the queue and settle
            // between the feet where they stand; flagged until a walking plan succeeds.
            self.failed = true;
            self.queue.clear();
            self.consecutive = false;
            self.stop_requested = true;
            self.gen = self.gen.wrapping_add(1);
            return self.plan_stop(c, j, cog, zmp);
        }
        self.failed = false;
        // Eq. 17 of this plan: computed already if it is the predicted one.
        let worst_zmp = if planned {
            self.predicted_worst
        } else {
            self.wins[spare].worst_first()
        };
        self.cur = Some(spare);
        self.serial = self.serial.wrapping_add(1);
        self.swing = Some(swing);
        for q in self.queue.iter_mut() {
            q.modified = false;
        }
        self.info = Some(ReplanInfo {
            tick: self.tick,
            adjust_ticks: adjust,
            ratio,
            plane,
            worst_zmp,
        });
        true
    }

    /// Plans the stop window at the single support `j` of the current window `c` (the robot
    /// settles between its feet); `true` if it is now the current one. On failure the old
    /// window goes on (flagged: [`Gait::replan_failed`]).
    fn plan_stop(&mut self, c: usize, j: usize, cog: [State<T>; 2], zmp: [State<T>; 2]) -> bool {
        let spare = 1 - (c & 1);
        let side = self.wins[c & 1]
            .spec
            .support
            .get(j)
            .copied()
            .flatten()
            .unwrap_or(Side::Left);
        let support = self.feet[side.index()];
        let other = self.feet[side.other().index()];
        let inputs = Inputs {
            kind: WindowKind::Stop,
            support,
            other,
            land: [support; 3],
            n_land: 0,
            first_ticks: self.params.settle_ticks,
        };
        if self.wins[spare]
            .plan_into(&self.params, &inputs, cog, zmp)
            .is_err()
        {
            self.failed = true;
            return false;
        }
        self.cur = Some(spare);
        self.serial = self.serial.wrapping_add(1);
        true
    }

    /// `true` if the last re-plan failed (the gait then stops: see the module docs); cleared by
    /// the next walking plan that succeeds.
    pub fn replan_failed(&self) -> bool {
        self.failed
    }

    /// `true` if the next swing (the front of the queue) starts from rest: standing, in the
    /// start window before its first swing, or in a stop window (a new `Start` is needed).
    pub fn next_swing_from_rest(&self) -> bool {
        match self.cur_buf() {
            None => true,
            Some(c) => match self.wins[c].inputs.kind {
                WindowKind::Start => self.swing.is_none(),
                WindowKind::Stop => true,
                WindowKind::Walk => false,
            },
        }
    }

    /// The position of the queued step `id` in the queue (0: the next swing target).
    pub fn position(&self, id: u16) -> Option<usize> {
        self.index_of(id)
    }

    /// The current window's analytic plan at window tick `t` minus the compensation of this
    /// tick (the compensators advance by one tick: call once per tick).
    fn shaped(&mut self, t: u32) -> (Sample<T>, Sample<T>) {
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
    fn start_shaping(&mut self) {
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

    fn ground_poses(&self) -> [FootPose<T>; 2] {
        let pose = |f: &Footstep<T>| FootPose {
            x: f.x,
            y: f.y,
            z: T::ZERO,
            yaw: wrap_angle(f.yaw),
        };
        [pose(&self.feet[0]), pose(&self.feet[1])]
    }

    fn foot_poses(&self, win: &Active<T>, j: usize, t: u32) -> [FootPose<T>; 2] {
        let mut poses = self.ground_poses();
        if let (Some(s), Kind::Single) = (self.swing, win.spec.kinds[j]) {
            let from = self.feet[s.step.side.index()];
            let to = s.step;
            let len = win.spec.ticks[j].max(1);
            let sn = T::of((t - win.starts[j]) as f64 / len as f64);
            // Quintic smoothstep: zero velocity and acceleration at lift-off and touch-down.
            let b = sn * sn * sn * (T::of(10.0) + sn * (T::of(-15.0) + T::of(6.0) * sn));
            // Height 64 s³(1−s)³: peak 1 at mid-swing, zero velocity and acceleration at
            // lift-off and touch-down (no jerk into the multi-body ZMP).
            let q = sn * (T::ONE - sn);
            let lift = T::of(64.0) * q * q * q;
            poses[s.step.side.index()] = FootPose {
                x: from.x + b * (to.x - from.x),
                y: from.y + b * (to.y - from.y),
                z: self.params.step_height * lift,
                // Along the shorter way round (a turn across ±π), in [−π, π].
                yaw: wrap_angle(from.yaw + b * wrap_angle(to.yaw - from.yaw)),
            };
        }
        poses
    }
}

fn adjusted(single: u32, adjust: i32) -> u32 {
    (single as i64 + adjust as i64).max(1) as u32
}
