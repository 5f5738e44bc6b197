//! The ZMP the planner's references would really produce on the multi-body model of
//! [`crate::robot::model`] (the paper's section IV.C, Tables I and II: "the maximum ZMP errors
//! which are calculated by using a multi-body model of humanoid robot HRP-2").
//!
//! # From the references to the link motion
//!
//! The references give, every `dt` = 5 ms, the COG `(x, y)` of the linear inverted pendulum
//! (at the constant height z_c = 0.814 m) and the poses of both soles (`x, y, z`, yaw; the
//! swing foot is kept flat). The robot is commanded as the usual HRP-2 walking controllers
//! command it:
//!
//! * the **feet** follow the references exactly, soles flat (roll = pitch = 0);
//! * the **waist** is kept upright (roll = pitch = 0) at the constant height
//!   [`Model::waist_height`], with yaw = the mean of the two feet yaws;
//! * its **horizontal position** is found at every tick so that the whole-body COG (all ten
//!   bodies) equals the reference COG `(x, y)`: Newton's method on the two unknowns, Jacobian by
//!   forward differences (step 1e-7 m), warm-started from the previous tick, iterated until the
//!   COG residual is below 1e-13 m (at most [`MAX_ITERATIONS`](crate::robot::model::MAX_ITERATIONS) iterations), then one more step
//!   with the same Jacobian if it reduces the residual further (usually to ~1e-16 m);
//! * the **joint angles** follow from the analytic inverse kinematics ([`Model::leg_ik`]).
//!
//! The whole-body COG **height** is not controlled: it is about z_c in the initial stance
//! ([`Model::hrp2`] chooses the waist height for that) and varies by a few millimetres as the
//! legs bend and the swing foot lifts. This, the leg masses swinging, and the angular momentum
//! of the links are what the linear inverted pendulum ignores, and what the multi-body ZMP sees.
//!
//! # Multi-body ZMP
//!
//! With `m_i` the mass of body `i`, `(x_i, y_i, z_i)` its centre of mass in the world frame,
//! dots time derivatives, `g` = 9.8 m/s², and `L_i` the angular momentum of body `i` about its
//! own centre of mass (`L̇_i = I_i ω̇_i + ω_i × I_i ω_i`, `I_i = R_i I_i^body R_iᵀ` the inertia
//! tensor in the world frame, `ω_i` the angular velocity in the world frame), the ZMP on the
//! floor z = 0 is (Kajita's textbook form, derived by setting the horizontal components of the
//! moment of the gravity and inertia forces about the ZMP to zero):
//!
//! ```text
//! p_x = (Σ m_i (z̈_i + g) x_i − Σ m_i ẍ_i z_i − Σ L̇_y,i) / Σ m_i (z̈_i + g)
//! p_y = (Σ m_i (z̈_i + g) y_i − Σ m_i ÿ_i z_i + Σ L̇_x,i) / Σ m_i (z̈_i + g)
//! ```
//!
//! **Derivatives** are central finite differences over the ticks (no analytic derivatives):
//! `c̈_k = (c_{k+1} − 2 c_k + c_{k−1}) / dt²` for every centre of mass; for the rotations,
//! the angular velocity over each tick interval is `ω_{k+½} = log(R_{k+1} R_kᵀ) / dt` (the world
//! frame rotation vector), `ω_k = (ω_{k−½} + ω_{k+½}) / 2`, `ω̇_k = (ω_{k+½} − ω_{k−½}) / dt`.
//! These are second-order accurate: the truncation error of `c̈` is `dt² c⁗ / 12` (for a
//! 1 Hz, 5 cm sinusoid 1.6e-4 m/s², i.e. 1.3e-5 m of ZMP at z = 0.814 m). The first and the
//! last tick have no central difference: they take the derivatives of their neighbour (tick 1,
//! tick n−2); [`max_zmp_error`] skips the first and last two ticks.
//!

use core::fmt;

use planner_core::gait::Reference;

use crate::robot::model::{
    add, cross, log_so3, mean_yaw, mul_mm, mul_mv, scale, sub, transpose, IkError, LegAngles,
    Model, Placed, Pose, Vec3, WaistError,
};

/// Why [`evaluate`] failed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum MbError {
    /// Fewer than three ticks: no central difference.
    TooShort(usize),
    /// `dt` is not a positive finite number.
    BadStep,
    /// A reference value is not finite at this tick.
    NonFinite(usize),
    /// A foot is out of reach at this tick.
    OutOfReach(usize, IkError),
    /// The waist search did not converge at this tick; the remaining COG error \[m\].
    NoConvergence(usize, f64),
}

impl fmt::Display for MbError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MbError::TooShort(n) => write!(f, "trajectory of {n} ticks: at least 3 needed"),
            MbError::BadStep => write!(f, "the time step must be positive and finite"),
            MbError::NonFinite(k) => write!(f, "tick {k}: reference value not finite"),
            MbError::OutOfReach(k, e) => write!(f, "tick {k}: {e}"),
            MbError::NoConvergence(k, r) => {
                write!(
                    f,
                    "tick {k}: waist search did not converge (COG error {r:.3e} m)"
                )
            }
        }
    }
}

impl std::error::Error for MbError {}

/// One tick of the multi-body evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MbSample {
    /// Time \[s\] (tick index × dt).
    pub t: f64,
    /// Multi-body ZMP x \[m\].
    pub mb_zmp_x: f64,
    /// Multi-body ZMP y \[m\].
    pub mb_zmp_y: f64,
    /// Whole-body COG (x, y, z) \[m\].
    pub mb_cog: Vec3,
    /// Waist origin (x, y, z) \[m\].
    pub waist: Vec3,
    /// Waist yaw \[rad\].
    pub waist_yaw: f64,
    /// Joint angles of the left and the right leg \[rad\].
    pub q: [LegAngles; 2],
}

fn finite(r: &Reference<f64>) -> bool {
    r.x.cog.is_finite()
        && r.y.cog.is_finite()
        && r.feet
            .iter()
            .all(|f| [f.x, f.y, f.z, f.yaw].iter().all(|v| v.is_finite()))
}

/// Evaluates a trajectory of references on the multi-body model: one [`MbSample`] per
/// reference (see the module documentation for the method).
pub fn evaluate(
    model: &Model,
    trajectory: &[Reference<f64>],
    dt: f64,
) -> Result<Vec<MbSample>, MbError> {
    let n = trajectory.len();
    if n < 3 {
        return Err(MbError::TooShort(n));
    }
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(MbError::BadStep);
    }
    // 1. Kinematics at every tick.
    let mut samples = Vec::with_capacity(n);
    let mut placed: Vec<Vec<Placed>> = Vec::with_capacity(n);
    let mut w = [trajectory[0].x.cog, trajectory[0].y.cog];
    for (k, r) in trajectory.iter().enumerate() {
        if !finite(r) {
            return Err(MbError::NonFinite(k));
        }
        let soles = [Pose::sole(&r.feet[0]), Pose::sole(&r.feet[1])];
        let yaw = mean_yaw(&r.feet);
        let (waist, cog, q) = model
            .solve_waist(yaw, &soles, [r.x.cog, r.y.cog], w)
            .map_err(|e| match e {
                WaistError::Ik(e) => MbError::OutOfReach(k, e),
                WaistError::NoConvergence(e) => MbError::NoConvergence(k, e),
            })?;
        w = [waist.p[0], waist.p[1]];
        placed.push(model.place_all(&waist, &q));
        samples.push(MbSample {
            t: k as f64 * dt,
            mb_zmp_x: f64::NAN,
            mb_zmp_y: f64::NAN,
            mb_cog: cog,
            waist: waist.p,
            waist_yaw: yaw,
            q,
        });
    }
    // 2. Derivatives by central differences and the ZMP.
    let g = model.gravity;
    for k in 0..n {
        let kc = k.clamp(1, n - 2);
        let (prev, cur, next) = (&placed[kc - 1], &placed[kc], &placed[kc + 1]);
        let mut den = 0.0;
        let mut num_x = 0.0;
        let mut num_y = 0.0;
        for i in 0..placed[k].len() {
            let b = &placed[k][i];
            if b.mass == 0.0 {
                continue;
            }
            let acc = scale(
                1.0 / (dt * dt),
                add(sub(next[i].com, scale(2.0, cur[i].com)), prev[i].com),
            );
            let w_next = scale(
                1.0 / dt,
                log_so3(&mul_mm(&next[i].r, &transpose(&cur[i].r))),
            );
            let w_prev = scale(
                1.0 / dt,
                log_so3(&mul_mm(&cur[i].r, &transpose(&prev[i].r))),
            );
            let omega = scale(0.5, add(w_next, w_prev));
            let omega_dot = scale(1.0 / dt, sub(w_next, w_prev));
            // World inertia R I Rᵀ of the body at tick k.
            let rr = &b.r;
            let mut iw = [[0.0; 3]; 3];
            for (a, row) in iw.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    *v = (0..3)
                        .flat_map(|j| (0..3).map(move |l| (j, l)))
                        .map(|(j, l)| rr[a][j] * b.inertia[j][l] * rr[c][l])
                        .sum();
                }
            }
            let l_dot = add(mul_mv(&iw, omega_dot), cross(omega, mul_mv(&iw, omega)));
            let f = b.mass * (acc[2] + g);
            den += f;
            num_x += f * b.com[0] - b.mass * acc[0] * b.com[2] - l_dot[1];
            num_y += f * b.com[1] - b.mass * acc[1] * b.com[2] + l_dot[0];
        }
        samples[k].mb_zmp_x = num_x / den;
        samples[k].mb_zmp_y = num_y / den;
    }
    Ok(samples)
}

/// The largest horizontal distance between the planned ZMP and the multi-body ZMP \[m\],
/// over all ticks but the first two and the last two (finite differences).
pub fn max_zmp_error(trajectory: &[Reference<f64>], mb: &[MbSample]) -> f64 {
    let n = trajectory.len().min(mb.len());
    let mut worst = 0.0f64;
    for k in 2..n.saturating_sub(2) {
        let e = (trajectory[k].x.zmp - mb[k].mb_zmp_x).hypot(trajectory[k].y.zmp - mb[k].mb_zmp_y);
        worst = worst.max(e);
    }
    worst
}
