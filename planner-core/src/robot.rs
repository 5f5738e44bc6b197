//! The robot file: one TOML file describes a robot for every part of the project (feature
//! `robot`, std only; the firmware reads it at compile time through its build script).
//!
//! A robot file has the sections below; every key is required, unknown keys are refused (a
//! misspelt key is an error, never a silent default). Durations are in seconds and must be
//! whole numbers of control periods (the gait counts in control ticks of `dt`).
//!
//! | section | keys | meaning |
//! |---|---|---|
//! | (top) | `name` | the robot's name |
//! | `[pendulum]` | `cog_height`, `gravity` | `z_c` \[m\] and `g` \[m/s²\]: `ω = √(g/z_c)` |
//! | `[timing]` | `control_period`, `single_support`, `double_support`, `start`, `settle`, `stand`, `rest` | `dt` and the phases of [`GaitParams`] \[s\] |
//! | `[adjustment]` | `min`, `max` | eq. 18's limits `ΔT_min ≤ 0 ≤ ΔT_max` on the single support \[s\] |
//! | `[feet]` | `sole_length`, `sole_width`, `step_width`, `step_height` | the sole (ZMP limits), the distance of the feet in a zero-length step, the swing height \[m\] |
//! | `[reach]` | the fields of [`Reach`] | the leg reach limits the node checks every footstep against |
//! | `[preview]` | `qe`, `r`, `shaping` | Kajita's preview weights `Q_e` \[1/m²\] and `R`; `shaping` on or off |
//! | `[multibody]` | free-form here | host-sim's link table (host-sim reads it; the planner ignores it) |
//!
//! [`Robot::from_toml`] checks the file's consistency and names the key at fault: values in
//! plausible ranges for a legged robot ([`RANGES`]: `z_c` 0.05 … 5 m, `g` 0.5 … 50 m/s², …),
//! durations on the control grid and in the planner's range, `ΔT_min ≤ 0 ≤ ΔT_max` with the
//! adjusted single support at least one period, positive sizes and weights, feet that do not
//! overlap (`step_width ≥ sole_width`), and a stance inside the reach limits
//! (`min_width ≤ step_width ≤ max_width`), and preview gains that the node can compute
//! (the Riccati iteration converges for `qe`, `r`). The node built from a robot
//! ([`Robot::node_config`]) stands with the feet `step_width` apart at the origin.
//!
//! [`node_config_source`] writes a [`NodeConfig`] as a Rust constant expression with every
//! float given by its bits, so that the firmware's build script compiles exactly the
//! configuration the host parsed (`tests/tests/robot.rs` compares them).
use std::fmt;
use std::format;
use std::string::{String, ToString};

use serde::Deserialize;

use std::boxed::Box;

use crate::gait::{GaitParams, Tail, PREVIEW};
pub use crate::literal::Literal;
use crate::node::{NodeConfig, Reach};
use crate::shaping::{Law, PreviewGains};

/// A robot, as read from its file.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// The robot's name.
    pub name: String,
    /// The gait parameters.
    pub params: GaitParams<f64>,
    /// The leg reach limits.
    pub reach: Reach,
    /// The `[multibody]` table, unread here (host-sim's link table).
    pub multibody: Option<toml::Table>,
}

/// Why a robot file was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum RobotError {
    /// Not TOML, a missing or unknown key, or a value of the wrong type (the TOML reader's
    /// message, which names the key and its line).
    Syntax(String),
    /// A value that does not fit the others.
    Invalid {
        /// The key, as `section.key`.
        key: &'static str,
        /// What is wrong with it.
        message: String,
    },
}

impl fmt::Display for RobotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RobotError::Syntax(m) => write!(f, "{}", m.trim_end()),
            RobotError::Invalid { key, message } => write!(f, "key `{key}`: {message}"),
        }
    }
}

impl std::error::Error for RobotError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    name: String,
    pendulum: Pendulum,
    timing: Timing,
    adjustment: Adjustment,
    feet: Feet,
    reach: Reach,
    preview: Preview,
    multibody: Option<toml::Table>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Pendulum {
    cog_height: f64,
    gravity: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Timing {
    control_period: f64,
    single_support: f64,
    double_support: f64,
    start: f64,
    settle: f64,
    stand: f64,
    rest: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Adjustment {
    min: f64,
    max: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Feet {
    sole_length: f64,
    sole_width: f64,
    step_width: f64,
    step_height: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Preview {
    qe: f64,
    r: f64,
    shaping: bool,
}

fn invalid(key: &'static str, message: String) -> RobotError {
    RobotError::Invalid { key, message }
}

/// A finite value `> 0` (or `≥ 0` when `zero` is allowed).
fn positive(key: &'static str, v: f64, zero: bool) -> Result<f64, RobotError> {
    if v.is_finite() && (v > 0.0 || (zero && v == 0.0)) {
        Ok(v)
    } else {
        let what = if zero { "≥ 0" } else { "> 0" };
        Err(invalid(key, format!("{v} must be finite and {what}")))
    }
}

/// Shortest and longest interval the planner takes \[s\].
const SPAN: (f64, f64) = (0.005, 10.0);

/// Plausible ranges for a legged robot (a value outside is a unit error or a typo, and would
/// drive the planner far outside what it is tested on): `(key, min, max)`.
pub const RANGES: [(&str, f64, f64); 8] = [
    ("pendulum.cog_height", 0.05, 5.0),
    ("pendulum.gravity", 0.5, 50.0),
    ("timing.control_period", 1e-4, 0.1),
    ("feet.sole_length", 0.01, 2.0),
    ("feet.sole_width", 0.01, 2.0),
    ("feet.step_width", 0.01, 2.0),
    ("feet.step_height", 0.0, 1.0),
    ("reach.max_feet_distance", 0.01, 5.0),
];

/// `v` inside its plausible range ([`RANGES`]).
fn plausible(key: &'static str, v: f64) -> Result<f64, RobotError> {
    match RANGES.iter().find(|r| r.0 == key) {
        Some(&(_, lo, hi)) if !(lo..=hi).contains(&v) => Err(invalid(
            key,
            format!("{v} is outside the plausible {lo} … {hi} (SI units)"),
        )),
        _ => Ok(v),
    }
}

/// A duration as a whole number of control periods.
fn ticks(key: &'static str, seconds: f64, dt: f64, signed: bool) -> Result<i64, RobotError> {
    if !seconds.is_finite() {
        return Err(invalid(
            key,
            format!("{seconds} s is not a finite duration"),
        ));
    }
    let n = (seconds / dt).round();
    if (n * dt - seconds).abs() > 1e-9 * seconds.abs().max(1.0) {
        return Err(invalid(
            key,
            format!("{seconds} s is not a whole number of control periods ({dt} s)"),
        ));
    }
    if !signed && n <= 0.0 {
        return Err(invalid(
            key,
            format!("{seconds} s must be at least one control period"),
        ));
    }
    if n.abs() > f64::from(i32::MAX) {
        return Err(invalid(key, format!("{seconds} s is too long")));
    }
    Ok(n as i64)
}

/// A phase duration in the planner's range.
fn phase(key: &'static str, seconds: f64, dt: f64) -> Result<u32, RobotError> {
    let n = ticks(key, seconds, dt, false)?;
    let d = n as f64 * dt;
    if d < SPAN.0 - 1e-12 || d > SPAN.1 + 1e-12 {
        return Err(invalid(
            key,
            format!(
                "{seconds} s is outside the planner's {} … {} s",
                SPAN.0, SPAN.1
            ),
        ));
    }
    // In range: at most 10 s of at least 1 µs periods, far below u32::MAX.
    u32::try_from(n).map_err(|_| invalid(key, format!("{seconds} s is too long")))
}

impl Robot {
    /// Reads and checks a robot file (see the module docs).
    pub fn from_toml(text: &str) -> Result<Self, RobotError> {
        let f: File = toml::from_str(text).map_err(|e| RobotError::Syntax(e.to_string()))?;
        let z_c = positive("pendulum.cog_height", f.pendulum.cog_height, false)?;
        let z_c = plausible("pendulum.cog_height", z_c)?;
        let g = positive("pendulum.gravity", f.pendulum.gravity, false)?;
        let g = plausible("pendulum.gravity", g)?;
        let t = &f.timing;
        let dt = positive("timing.control_period", t.control_period, false)?;
        let dt = plausible("timing.control_period", dt)?;
        if dt > SPAN.1 {
            return Err(invalid(
                "timing.control_period",
                format!("{dt} s is longer than the planner's longest interval"),
            ));
        }
        let single = phase("timing.single_support", t.single_support, dt)?;
        let double = phase("timing.double_support", t.double_support, dt)?;
        let start = phase("timing.start", t.start, dt)?;
        let settle = phase("timing.settle", t.settle, dt)?;
        let stand = phase("timing.stand", t.stand, dt)?;
        let rest = phase("timing.rest", t.rest, dt)?;
        let adj_min = ticks("adjustment.min", f.adjustment.min, dt, true)?;
        let adj_max = ticks("adjustment.max", f.adjustment.max, dt, true)?;
        if adj_min > 0 {
            return Err(invalid(
                "adjustment.min",
                format!("{} s must be ≤ 0", f.adjustment.min),
            ));
        }
        if adj_max < 0 {
            return Err(invalid(
                "adjustment.max",
                format!("{} s must be ≥ 0", f.adjustment.max),
            ));
        }
        let shortest = i64::from(single) + adj_min;
        if (shortest as f64) * dt < SPAN.0 - 1e-12 {
            return Err(invalid(
                "adjustment.min",
                format!(
                    "{} s leaves a single support of {} s, shorter than {} s",
                    f.adjustment.min,
                    shortest as f64 * dt,
                    SPAN.0
                ),
            ));
        }
        let longest = i64::from(single) + adj_max;
        if (longest as f64) * dt > SPAN.1 + 1e-12 {
            return Err(invalid(
                "adjustment.max",
                format!(
                    "{} s makes a single support of {} s, longer than {} s",
                    f.adjustment.max,
                    longest as f64 * dt,
                    SPAN.1
                ),
            ));
        }
        let feet = &f.feet;
        let sole_length = plausible(
            "feet.sole_length",
            positive("feet.sole_length", feet.sole_length, false)?,
        )?;
        let sole_width = plausible(
            "feet.sole_width",
            positive("feet.sole_width", feet.sole_width, false)?,
        )?;
        let step_width = plausible(
            "feet.step_width",
            positive("feet.step_width", feet.step_width, false)?,
        )?;
        let step_height = plausible(
            "feet.step_height",
            positive("feet.step_height", feet.step_height, true)?,
        )?;
        if step_width < sole_width {
            return Err(invalid(
                "feet.step_width",
                format!(
                    "{step_width} m is less than the sole width {sole_width} m: the feet overlap"
                ),
            ));
        }
        let reach = check_reach(&f.reach, step_width, sole_width)?;
        let qe = positive("preview.qe", f.preview.qe, false)?;
        let r = positive("preview.r", f.preview.r, false)?;
        let params = GaitParams {
            omega: crate::omega(g, z_c),
            dt,
            single_ticks: single,
            double_ticks: double,
            start_ticks: start,
            settle_ticks: settle,
            stand_ticks: stand,
            rest_ticks: rest,
            // |adj| ≤ 10 s of periods, checked above against the planner's span.
            adjust_min_ticks: i32::try_from(adj_min)
                .map_err(|_| invalid("adjustment.min", "too long".into()))?,
            adjust_max_ticks: i32::try_from(adj_max)
                .map_err(|_| invalid("adjustment.max", "too long".into()))?,
            step_width,
            sole_half_length: sole_length / 2.0,
            sole_half_width: sole_width / 2.0,
            step_height,
            tail: Tail::Settle,
            shaping: f.preview.shaping,
            cog_height: z_c,
            gravity: g,
            preview_qe: qe,
            preview_r: r,
        };
        // Everything validate() checks has been checked above with the key named (ω from
        // z_c and g in their plausible ranges is finite); this is the planner's own word.
        params.validate().map_err(|_| {
            invalid(
                "pendulum.cog_height",
                "the gait parameters are not accepted by the planner".into(),
            )
        })?;
        // The preview controller's gains exist for these weights (the node computes them at
        // start-up: a file that passes here starts a node).
        if params.shaping {
            let config = params.preview_config();
            let mut gains = Box::new(PreviewGains::<f64, PREVIEW>::zeroed());
            gains.compute(&config, Law::FromRest).map_err(|e| {
                invalid(
                    "preview.r",
                    format!(
                        "the preview gains cannot be computed for qe = {qe}, r = {r} ({e:?}): \
                         the ratio qe / r is out of the Riccati iteration's reach"
                    ),
                )
            })?;
        }
        Ok(Self {
            name: f.name,
            params,
            reach,
            multibody: f.multibody,
        })
    }

    /// The node for this robot ([`NodeConfig::for_robot`]).
    pub fn node_config(&self) -> NodeConfig {
        NodeConfig::for_robot(self.params, self.reach)
    }
}

fn check_reach(r: &Reach, step_width: f64, sole_width: f64) -> Result<Reach, RobotError> {
    positive("reach.max_forward", r.max_forward, false)?;
    positive("reach.max_backward", r.max_backward, true)?;
    positive("reach.min_width", r.min_width, false)?;
    positive("reach.max_width", r.max_width, false)?;
    positive("reach.max_yaw", r.max_yaw, true)?;
    positive("reach.max_feet_distance", r.max_feet_distance, false)?;
    plausible("reach.max_feet_distance", r.max_feet_distance)?;
    positive("reach.yaw_cost", r.yaw_cost, true)?;
    positive("reach.max_stride", r.max_stride, false)?;
    positive("reach.max_growth", r.max_growth, false)?;
    if r.min_width < sole_width {
        return Err(invalid(
            "reach.min_width",
            format!(
                "{} m is less than the sole width {sole_width} m: steps could overlap the other foot",
                r.min_width
            ),
        ));
    }
    if !(r.min_width..=r.max_width).contains(&step_width) {
        return Err(invalid(
            "feet.step_width",
            format!(
                "{step_width} m is outside the reach limits' width {} … {} m: the robot could not stand",
                r.min_width, r.max_width
            ),
        ));
    }
    if r.max_feet_distance < step_width {
        return Err(invalid(
            "reach.max_feet_distance",
            format!(
                "{} m is less than the stance width {step_width} m",
                r.max_feet_distance
            ),
        ));
    }
    Ok(*r)
}

/// A float as a constant expression with exactly its bits.
fn bits(v: f64) -> String {
    format!("f64::from_bits({:#018x})", v.to_bits())
}

/// `cfg` as a Rust constant expression of type `planner_core::node::NodeConfig` (every float by
/// its bits): what the firmware's build script writes for the robot file it compiles in.
pub fn node_config_source<T: Literal>(cfg: &NodeConfig<T>) -> String {
    let p = &cfg.params;
    let r = &cfg.reach;
    let tail = match p.tail {
        Tail::Settle => "Settle",
        Tail::Single => "Single",
    };
    let foot = |f: &crate::gait::Footstep<T>| {
        let side = match f.side {
            crate::gait::Side::Left => "Left",
            crate::gait::Side::Right => "Right",
        };
        format!(
            "::planner_core::gait::Footstep {{ side: ::planner_core::gait::Side::{side}, x: {}, y: {}, yaw: {} }}",
            f.x.literal(),
            f.y.literal(),
            f.yaw.literal()
        )
    };
    format!(
        "::planner_core::node::NodeConfig {{
    params: ::planner_core::gait::GaitParams {{
        omega: {omega},
        dt: {dt},
        single_ticks: {single},
        double_ticks: {double},
        start_ticks: {start},
        settle_ticks: {settle},
        stand_ticks: {stand},
        rest_ticks: {rest},
        adjust_min_ticks: {amin},
        adjust_max_ticks: {amax},
        step_width: {sw},
        sole_half_length: {shl},
        sole_half_width: {shw},
        step_height: {sh},
        tail: ::planner_core::gait::Tail::{tail},
        shaping: {shaping},
        cog_height: {zc},
        gravity: {g},
        preview_qe: {qe},
        preview_r: {pr},
    }},
    left: {left},
    right: {right},
    heartbeat_timeout_ms: {hb},
    velocity_timeout_ms: {vt},
    max_rx: {max_rx},
    max_frames: {max_frames},
    max_plans: {max_plans},
    work_budget: {work_budget},
    reach: ::planner_core::node::Reach {{
        max_forward: {mf},
        max_backward: {mb},
        min_width: {minw},
        max_width: {maxw},
        max_yaw: {my},
        max_feet_distance: {mfd},
        yaw_cost: {yc},
        max_stride: {ms},
        max_growth: {mg},
        sole_gap: {sg},
    }},
    adjust: ::planner_core::node::AdjustConfig {{
        max_age: {age},
        margin: {db},
        min_change: {mc},
        max_shift: {msh},
        max_deviation: {mdv},
        from_measured: {fm},
    }},
    entropy: 0,
}}",
        omega = p.omega.literal(),
        dt = p.dt.literal(),
        single = p.single_ticks,
        double = p.double_ticks,
        start = p.start_ticks,
        settle = p.settle_ticks,
        stand = p.stand_ticks,
        rest = p.rest_ticks,
        amin = p.adjust_min_ticks,
        amax = p.adjust_max_ticks,
        sw = p.step_width.literal(),
        shl = p.sole_half_length.literal(),
        shw = p.sole_half_width.literal(),
        sh = p.step_height.literal(),
        shaping = p.shaping,
        zc = bits(p.cog_height),
        g = bits(p.gravity),
        qe = bits(p.preview_qe),
        pr = bits(p.preview_r),
        left = foot(&cfg.left),
        right = foot(&cfg.right),
        hb = cfg.heartbeat_timeout_ms,
        vt = cfg.velocity_timeout_ms,
        max_rx = cfg.max_rx,
        max_frames = cfg.max_frames,
        max_plans = cfg.max_plans,
        work_budget = cfg.work_budget,
        mf = r.max_forward.literal(),
        mb = r.max_backward.literal(),
        minw = r.min_width.literal(),
        maxw = r.max_width.literal(),
        my = r.max_yaw.literal(),
        mfd = r.max_feet_distance.literal(),
        yc = r.yaw_cost.literal(),
        ms = r.max_stride.literal(),
        mg = r.max_growth.literal(),
        sg = r.sole_gap.literal(),
        age = cfg.adjust.max_age,
        db = cfg.adjust.margin.literal(),
        mc = cfg.adjust.min_change.literal(),
        msh = cfg.adjust.max_shift.literal(),
        mdv = cfg.adjust.max_deviation.literal(),
        fm = cfg.adjust.from_measured,
    )
}
