//! The standing height an import chooses, within the legs' torque limits and joint ranges.
//!
//! The waist is lowered from the straight-legged height by [`DROPS`] of the leg length, the
//! first (largest, HRP-2's bend first) that passes a static check of single support on either
//! foot: the whole weight on the stance sole's centre, the whole-body COM above it (the waist
//! moved sideways to put it there, the swing leg at its standing angles), every joint of the
//! stance leg holding
//!
//! `τ_j = a_j · [(p_sole − p_j) × M g ẑ − Σ_{bodies below j} (c_b − p_j) × m_b g ẑ]`
//!
//! (the moment about its axis `a_j` at `p_j` of the floor's push and of the weight of the links
//! between it and the floor) at most [`TORQUE_SHARE`] of its effort limit, and every joint
//! angle of the standing posture and of that single support at least [`RANGE_MARGIN`] inside
//! its range. The rest of the effort is left for what a static check does not see: the
//! swing's accelerations, the COM passing beside the sole, the stabilizer's corrections.
//! A straighter leg needs less knee torque but has less reach: the drop is the bend the
//! limits allow, no less. When no drop passes, the import is refused, naming the joint and
//! the limit at the straightest height tried.

use planner_core::gait::Side;

use crate::robot::model::{cross, mul_mv, side_index, sub, LegAngles, Model, Pose};

/// The waist's drops from the straight-legged height tried, as fractions of the leg length
/// (hip to ankle), largest first: HRP-2's 8.8 %, then 1 % steps.
pub const DROPS: [f64; 7] = [super::KNEE_DROP, 0.08, 0.07, 0.06, 0.05, 0.04, 0.03];
/// The share of a joint's effort limit its static single-support torque may take.
pub const TORQUE_SHARE: f64 = 0.7;
/// The margin a standing or single-support joint angle keeps from either end of its range
/// \[rad\].
pub const RANGE_MARGIN: f64 = 0.02;

/// A joint whose axis has at least this component across the walk (y) is a pitch joint,
/// loaded by the knee bend.
pub const ACROSS: f64 = 0.9;

/// The first joint outside a limit, if any: its name and angles against the range.
pub fn out_of_range(m: &Model, side: Side, q: &LegAngles, what: &str) -> Option<String> {
    let leg = &m.legs[side_index(side)];
    leg.links.iter().zip(q).find_map(|(l, &a)| {
        let [lo, hi] = l.joint.range?;
        (a < lo + RANGE_MARGIN || a > hi - RANGE_MARGIN).then(|| {
            format!(
                "<joint name=\"{}\">: {what} needs {a:.3} rad, its range {lo:.3} … {hi:.3} rad \
                 (a margin of {RANGE_MARGIN} rad kept)",
                l.joint.name
            )
        })
    })
}

/// Single support on `side`'s sole at `(0, ±step_width/2, 0)`: the stance leg's angles, with
/// the whole-body COM above the sole centre, and the static torque of each of its joints
/// \[N m\] (see the module docs).
pub fn single_support(
    m: &Model,
    step_width: f64,
    side: Side,
) -> Result<(LegAngles, [f64; 6]), String> {
    let i = side_index(side);
    let y = if i == 0 { step_width } else { -step_width } / 2.0;
    let sole = Pose::upright(0.0, y, 0.0, 0.0);
    let mut w = [0.0, 0.0];
    let mass = m.total_mass();
    let mut q = m.stance;
    for _ in 0..60 {
        let waist = Pose::upright(w[0], w[1], m.waist_height, 0.0);
        q[i] = m
            .leg_ik(side, &waist, &sole)
            .map_err(|e| format!("single support: {e}"))?;
        let mut first = [0.0; 3];
        for b in m.place_all(&waist, &q) {
            for (f, c) in first.iter_mut().zip(b.com) {
                *f += b.mass * c;
            }
        }
        let e = [sole.p[0] - first[0] / mass, sole.p[1] - first[1] / mass];
        if e[0].hypot(e[1]) < 1e-7 {
            let waist = Pose::upright(w[0], w[1], m.waist_height, 0.0);
            return Ok((q[i], torques(m, side, &waist, &q[i], &sole)));
        }
        w = [w[0] + e[0], w[1] + e[1]];
    }
    Err("single support: no waist position puts the COM above the sole".into())
}

fn torques(m: &Model, side: Side, waist: &Pose, q: &LegAngles, sole: &Pose) -> [f64; 6] {
    let g = m.gravity;
    let leg = &m.legs[side_index(side)];
    let fr = m.leg_fk(side, waist, q);
    let floor = [0.0, 0.0, m.total_mass() * g];
    let mut out = [0.0; 6];
    for (j, t) in out.iter_mut().enumerate() {
        let p = fr.links[j].p;
        let mut moment = cross(sub(sole.p, p), floor);
        for k in j..6 {
            for b in &leg.links[k].bodies {
                let c = fr.links[k].apply(b.com);
                let w = cross(sub(c, p), [0.0, 0.0, -b.mass * g]);
                moment = [moment[0] + w[0], moment[1] + w[1], moment[2] + w[2]];
            }
        }
        let a = mul_mv(&fr.links[j].r, leg.links[j].joint.axis);
        *t = (a[0] * moment[0] + a[1] * moment[1] + a[2] * moment[2]).abs();
    }
    out
}

/// Why a model at its waist height is outside its legs' limits (the first joint found), or
/// `None`: the standing angles and single support on either foot within the ranges, the
/// static single-support torques within [`TORQUE_SHARE`] of the effort limits.
pub fn outside_limits(m: &Model, step_width: f64) -> Option<String> {
    for side in [Side::Left, Side::Right] {
        let i = side_index(side);
        if let Some(why) = out_of_range(m, side, &m.stance[i], "standing") {
            return Some(why);
        }
        let (q, tau) = match single_support(m, step_width, side) {
            Ok(v) => v,
            Err(e) => return Some(e),
        };
        if let Some(why) = out_of_range(m, side, &q, "single support") {
            return Some(why);
        }
        let frames = m.leg_fk(side, &Pose::IDENTITY, &q);
        for ((l, t), f) in m.legs[i].links.iter().zip(tau).zip(frames.links) {
            let across = mul_mv(&f.r, l.joint.axis)[1].abs() > ACROSS;
            if let (Some(e), true) = (l.joint.effort, across) {
                if t > TORQUE_SHARE * e {
                    return Some(format!(
                        "<joint name=\"{}\">: single support needs {t:.1} N m, more than \
                         {TORQUE_SHARE} of its effort limit {e} N m",
                        l.joint.name
                    ));
                }
            }
        }
    }
    None
}

/// The pitch joint of the left leg in single support nearest its effort limit (by share),
/// said as `<joint name="…">: τ N m of its effort limit E N m`; `None` without limits.
pub fn heaviest(m: &Model, step_width: f64) -> Option<String> {
    let (q, tau) = single_support(m, step_width, Side::Left).ok()?;
    let frames = m.leg_fk(Side::Left, &Pose::IDENTITY, &q);
    m.legs[0]
        .links
        .iter()
        .zip(tau)
        .zip(frames.links)
        .filter(|((l, _), f)| mul_mv(&f.r, l.joint.axis)[1].abs() > ACROSS)
        .filter_map(|((l, t), _)| Some((l, t, l.joint.effort?)))
        .max_by(|a, b| (a.1 / a.2).total_cmp(&(b.1 / b.2)))
        .map(|(l, t, e)| {
            format!(
                "<joint name=\"{}\">: {t:.1} N m of its effort limit {e} N m",
                l.joint.name
            )
        })
}
