//! The walking stabilizer: what an HRP-2-class robot runs between the pattern generator and
//! its joint servos, using only the simulated sensors.
//!
//! Source: S. Kajita, M. Morisawa, K. Miura, S. Nakaoka, K. Harada, K. Kaneko, F. Kanehiro,
//! K. Yokoi, "Biped walking stabilization based on linear inverted pendulum tracking",
//! IEEE/RSJ IROS 2010 (the HRP-2/HRP-4C stabilizer: a DCM/LIPM-tracking desired ZMP, its
//! distribution to the feet, foot damping control and foot force difference control), with
//! the desired ZMP of the divergent component of motion written as in J. Englsberger,
//! C. Ott, M. Roa, A. Albu-Schäffer, G. Hirzinger, "Bipedal walking control based on Capture
//! Point dynamics", IROS 2011, and the ZMP feedback by COG modification of K. Nagasaka et
//! al. (HRP-2's "COG compliance"). Written from the papers' equations, no code copied.
//!
//! # Symbols
//!
//! `c`, `ċ` the horizontal COG and its velocity, `p` the ZMP, `ω = √(g / z_c)`, the divergent
//! component of motion (capture point) `ξ = c + ċ / ω`; `ref` the pattern generator's values,
//! `m` measured, `d` desired.
//!
//! # Every control tick (1 ms)
//!
//! The contact phase (which foot supports) is the ankle force sensors' ([`contact_phase`]),
//! or with [`Gains::contact_from_sensors`] off the reference's.
//!
//! The soles' poses `S_k` used below are the leg odometry's ([`super::odometry`], with
//! [`Gains::foot_odometry`], the default): a sole on the ground where the encoders say it
//! landed, a swinging sole blended from where it lifted off to its planned landing; without
//! it the references'.
//!
//! 1. **State estimate** (IMU + encoders): the waist attitude `R` from the IMU, the joint
//!    angles from the encoders; forward kinematics with the waist at the origin in attitude
//!    `R` gives the COG relative to each sole; anchored at `S_k` of the support
//!    sole(s) (weighted by the measured vertical forces) that is the measured COG `c_m`;
//!    `ċ_m` its difference quotient through a first-order low-pass of time constant
//!    [`Gains::vel_filter_s`].
//! 2. **DCM feedback**: `p_d = p_ref + (1 + k_ξ / ω)(ξ_m − ξ_ref)`, clamped into the support
//!    region (the stance sole in single support, the hull of both in double support).
//! 3. **Measured ZMP** from the ankle force/torque sensors: for a flat foot with the ground
//!    force `F` (sensor force less the foot's weight) and moment `M = −τ` about the ankle,
//!    the local CoP is `r_x = (r_z F_x − M_y) / F_z`, `r_y = (M_x + r_z F_y) / F_z`,
//!    `r_z` the sole's plane in the ankle frame (less the foot's own weight and moment).
//! 4. **ZMP distribution** (Kajita 2010): `p_d` is projected onto the segment between the two
//!    sole centres: the ratio `α` gives the desired vertical forces `α M g`, `(1 − α) M g`;
//!    what is left over is each foot's desired local CoP `r_d` (clamped into the sole, 1 cm
//!    inside its edges).
//! 5. **Foot damping control**: each loaded ankle yields to the torque error,
//!    `Δθ̇_pitch = −F_z (r_x,m − r_x,d) / D − Δθ_pitch / T`,
//!    `Δθ̇_roll = F_z (r_y,m − r_y,d) / D − Δθ_roll / T`, added to the ankle joint targets.
//! 6. **Foot force difference control**: `Δż = K_f ((f_L − f_R)_d − (f_L − f_R)_m) − Δz / T_z`,
//!    the left sole lowered by `Δz / 2`, the right one raised by as much (double support).
//! 7. **COG modification** (ZMP feedback): `Δċ = −K_c (p_d − p_m) − Δc / T_c`, `|Δc|` at most
//!    [`Gains::cog_limit_m`]; the commanded COG is `c_ref + Δc`.
//! 8. **Inverse kinematics**: the waist upright, heading the mean yaw, at the waist height,
//!    placed (Newton on the whole-body COG, as the kinematic model does) so that the COG is
//!    the commanded one; the soles at `S_k` (plus `Δz`); the analytic leg IK gives
//!    the twelve joint targets, the ankle corrections are added.

use super::model::{sensor, Robot};
use super::odometry::Odometry;
use crate::robot::model::{mean_yaw, rot_z, LegAngles, Mat3, Pose, Vec3};
use planner_core::gait::{Phase, Reference, Side};

/// The stabilizer's gains (every one stated here; `k_dcm` ∈ {0, 1, 2}, `D` ∈ {400, 1000} and
/// `K_c` ∈ {3, 5, 8} were tried on the `fig4` scenario with the contact phase from the
/// reference: every combination walked, the mean CoP error was 6.7–9.8 mm and the worst
/// 33–51 mm; these gave 8.2 / 33.5 mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains {
    /// The feedback is on (false: open-loop playback through the IK).
    pub enabled: bool,
    /// DCM feedback gain `k_ξ` \[1/s\].
    pub k_dcm: f64,
    /// Low-pass time constant of the COG velocity \[s\].
    pub vel_filter_s: f64,
    /// Foot damping `D` \[N m s/rad\].
    pub damping: f64,
    /// Return time constant of the ankle corrections `T` \[s\].
    pub ankle_return_s: f64,
    /// Largest ankle correction \[rad\].
    pub ankle_limit_rad: f64,
    /// Foot force difference gain `K_f` \[m/(N s)\].
    pub k_force: f64,
    /// Return time constant of `Δz` \[s\].
    pub force_return_s: f64,
    /// Largest `|Δz|` \[m\].
    pub dz_limit_m: f64,
    /// COG modification gain `K_c` \[1/s\].
    pub k_cog: f64,
    /// Return time constant of `Δc` \[s\].
    pub cog_return_s: f64,
    /// Largest `|Δc|` \[m\].
    pub cog_limit_m: f64,
    /// Where the contact phase comes from: the ankle force sensors (`true`, the default,
    /// [`contact_phase`]), or the reference's phase (`false`).
    pub contact_from_sensors: bool,
    /// The loop delay the gains were designed for ([`Gains::for_delay`]) \[s\].
    pub design_delay_s: f64,
    /// Foot placement from leg odometry ([`super::odometry`]; the default): the soles where
    /// the encoders say they landed, the swing aimed at its planned landing in the world.
    /// Off: the soles at their references (a landing that falls short is never known, and
    /// the shortfalls add up over a walk). A switch rather than always on because it is
    /// feedback from the encoders: the open-loop playback ([`Gains::enabled`] off) and the
    /// stabilizer scaled to 0 ([`Gains::scaled`]) act without it, and a test measures what
    /// it changes against the walk without it.
    pub foot_odometry: bool,
}

impl Default for Gains {
    fn default() -> Self {
        Self {
            enabled: true,
            k_dcm: 1.0,
            vel_filter_s: 0.01,
            damping: 1000.0,
            ankle_return_s: 0.5,
            ankle_limit_rad: 0.15,
            k_force: 2e-4,
            force_return_s: 0.5,
            dz_limit_m: 0.02,
            k_cog: 8.0,
            cog_return_s: 1.0,
            cog_limit_m: 0.04,
            contact_from_sensors: true,
            design_delay_s: 0.0,
            foot_odometry: true,
        }
    }
}

/// The largest loop delay for which the stated gains ([`Gains::default`]) are kept \[s\]:
/// above it [`Gains::for_delay`] lowers them.
pub const FULL_GAIN_DELAY_S: f64 = 0.001;

/// A foot is on the ground when its sensor's vertical ground force is above this share of
/// the robot's weight (and off it below half of it: the hysteresis keeps a touchdown from
/// chattering).
pub const CONTACT_SHARE: f64 = 0.1;

/// The contact phase the ankle force sensors say: `Single(k)` when only foot `k` carries
/// more than [`CONTACT_SHARE`] of the weight `mg` (a foot in contact stays so until its force
/// falls below half of that), `Double` when both do; with neither (a flight phase the
/// references never plan), the reference's phase.
pub fn contact_phase(
    fz: [f64; 2],
    mg: f64,
    before: [bool; 2],
    reference: Phase,
) -> (Phase, [bool; 2]) {
    let on = |k: usize| {
        let threshold = if before[k] { 0.5 } else { 1.0 } * CONTACT_SHARE * mg;
        fz[k] > threshold
    };
    let contact = [on(0), on(1)];
    let phase = match contact {
        [true, true] => Phase::Double,
        [true, false] => Phase::Single(Side::Left),
        [false, true] => Phase::Single(Side::Right),
        [false, false] => reference,
    };
    (phase, contact)
}

impl Gains {
    /// The gains with every feedback scaled by `s` ≥ 0: the DCM gain `k_ξ`, the COG
    /// modification `K_c` and the force difference `K_f` times `s`, the foot damping `D`
    /// divided by it (its compliance `1 / D` times `s`); the filters, return times and limits
    /// unchanged. `s` = 1 is the stabilizer as stated, `s` = 0 leaves no feedback acting (the
    /// pattern through the same IK: the open-loop playback; the foot placement from the
    /// encoders, [`Gains::foot_odometry`], is feedback too and off at `s` = 0).
    pub fn scaled(self, s: f64) -> Self {
        Self {
            k_dcm: self.k_dcm * s,
            damping: self.damping / s,
            k_force: self.k_force * s,
            k_cog: self.k_cog * s,
            foot_odometry: self.foot_odometry && s > 0.0,
            ..self
        }
    }
}

impl Gains {
    /// The gains designed for the loop delay `delay_s` (sensing to actuation): every feedback
    /// gain times `min(1, τ₀ / delay)`, τ₀ = [`FULL_GAIN_DELAY_S`] ([`Gains::scaled`]), so
    /// that each loop's gain × delay product stays at most what it is with the stated gains at
    /// τ₀.
    ///
    /// Why: a feedback loop of rate `k` \[1/s\] closed through a delay `τ` loses the phase
    /// `k τ` at its crossover, so keeping `k τ` bounded keeps its phase margin. The fast loops
    /// here (the foot damping control, whose rate is the ankle's stiffness over `D`, and the
    /// COG modification) are tuned for no delay. τ₀ comes from a delay sweep of the stated
    /// gains on HRP-2's `straight` walk (the book's physics page): every gait measure within
    /// half its bound at 1 ms; at 2 ms the longest flight at 80 % of its bound and the CoP
    /// error three times that with no delay, at 3 ms five times, the feet sliding beyond the
    /// bound at 5 ms. The filters, return times and limits are unchanged.
    pub fn for_delay(self, delay_s: f64) -> Self {
        let s = if delay_s > FULL_GAIN_DELAY_S {
            FULL_GAIN_DELAY_S / delay_s
        } else {
            1.0
        };
        Self {
            design_delay_s: delay_s.max(0.0),
            ..self.scaled(s)
        }
    }
}

/// What the stabilizer computed at a tick (for the logs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Internals {
    /// Measured COG (x, y) \[m\].
    pub cog: [f64; 2],
    /// Desired ZMP \[m\].
    pub zmp_desired: [f64; 2],
    /// ZMP from the force sensors \[m\] (NaN without load).
    pub zmp_measured: [f64; 2],
    /// COG modification \[m\].
    pub dc: [f64; 2],
    /// The measured DCM less the reference's, `ξ − ξ_ref` (x, y) \[m\]: the sensor-only
    /// estimate the robot's state estimator sends to the node (`MEASURED`).
    pub dcm_error: [f64; 2],
}

/// The stabilizer's state.
#[derive(Clone, Debug)]
pub struct Stabilizer {
    robot: Robot,
    gains: Gains,
    omega: f64,
    dt: f64,
    cog_prev: Option<[f64; 2]>,
    cog_vel: [f64; 2],
    /// Ankle corrections (pitch, roll) per foot.
    ankle: [[f64; 2]; 2],
    dz: f64,
    dc: [f64; 2],
    waist_guess: Option<Pose>,
    /// The feet in contact by the force sensors (with `contact_from_sensors`).
    contact: [bool; 2],
    /// The soles' estimate from the encoders (with `foot_odometry`).
    odometry: Odometry,
    /// The last tick's internals.
    pub internals: Internals,
}

fn quat_to_mat(q: &[f64]) -> Mat3 {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Return time constant of the ankle corrections of the swing foot \[s\]: level before landing.
const SWING_RETURN_S: f64 = 0.05;

/// Margin inside the sole rectangle of the desired local CoPs \[m\].
const SOLE_CLAMP_MARGIN_M: f64 = 0.01;

/// The ground's vertical force on a flat foot \[N\] and its centre of pressure in the sole
/// frame (x, y from the sole centre) \[m\], from the ankle sensor `ft` (force then torque),
/// the foot's weight `foot_weight` \[N\] and centre of mass `foot_com`, and the sole centre
/// `sole`, both in the ankle frame \[m\].
///
/// MuJoCo's force/torque sensors give the action of the parent (the shank) on the foot, at the
/// ankle, in the foot frame. A foot at rest is balanced by the ground: ground force
/// `F = −f + (0, 0, W)`, ground moment about the ankle `M = −τ + c × (0, 0, W)`; the CoP `r`
/// on the sole plane (`r_z = s_z`) solves `M = r × F`: `r_x = (r_z F_x − M_y) / F_z`,
/// `r_y = (M_x + r_z F_y) / F_z`, less the sole centre's `s_x`, `s_y`. No CoP below
/// [`MIN_LOAD_N`].
pub fn sole_cop(
    ft: &[f64; 6],
    foot_weight: f64,
    foot_com: Vec3,
    sole: Vec3,
) -> (f64, Option<[f64; 2]>) {
    let gf = [-ft[0], -ft[1], -ft[2] + foot_weight];
    let m = [
        -ft[3] + foot_com[1] * foot_weight,
        -ft[4] - foot_com[0] * foot_weight,
    ];
    let rz = sole[2];
    let cop = (gf[2] > MIN_LOAD_N).then(|| {
        [
            (rz * gf[0] - m[1]) / gf[2] - sole[0],
            (m[0] + rz * gf[1]) / gf[2] - sole[1],
        ]
    });
    (gf[2], cop)
}

/// Smallest vertical force with which a foot's CoP is computed \[N\].
pub const MIN_LOAD_N: f64 = 20.0;

impl Stabilizer {
    /// A stabilizer for `robot` at the control period `dt` with the LIPM height `z_c`.
    pub fn new(robot: Robot, gains: Gains, dt: f64, z_c: f64) -> Self {
        Self {
            omega: (robot.gravity() / z_c).sqrt(),
            robot,
            gains,
            dt,
            cog_prev: None,
            cog_vel: [0.0; 2],
            ankle: [[0.0; 2]; 2],
            dz: 0.0,
            dc: [0.0; 2],
            waist_guess: None,
            contact: [true; 2],
            odometry: Odometry::new(dt),
            internals: Internals::default(),
        }
    }

    /// The joint targets (left leg then right leg) for the reference `r` and the sensors.
    pub fn step(&mut self, r: &Reference<f64>, sensors: &[f64]) -> Result<[f64; 12], String> {
        let g = self.gains;
        let mut q_meas: [LegAngles; 2] = [[0.0; 6]; 2];
        for k in 0..2 {
            q_meas[k].copy_from_slice(&sensors[sensor::QPOS + 6 * k..sensor::QPOS + 6 * k + 6]);
        }
        // 3. Force sensors: local CoP and vertical force per foot.
        let mut fz = [0.0; 2];
        let mut local = [[f64::NAN; 2]; 2];
        for k in 0..2 {
            let o = sensor::FT + 6 * k;
            let side = [Side::Left, Side::Right][k];
            // The sensor's force and torque in the sole's axes.
            let rf = self
                .robot
                .to_sole(side, [sensors[o], sensors[o + 1], sensors[o + 2]]);
            let rt = self
                .robot
                .to_sole(side, [sensors[o + 3], sensors[o + 4], sensors[o + 5]]);
            let ft = [rf[0], rf[1], rf[2], rt[0], rt[1], rt[2]];
            let (f, cop) = sole_cop(
                &ft,
                self.robot.foot_mass(side) * self.robot.gravity(),
                self.robot.to_sole(side, self.robot.foot_com(side)),
                self.robot.to_sole(side, self.robot.sole_offset(side)),
            );
            fz[k] = f;
            if let Some(c) = cop {
                local[k] = c;
            }
        }
        let phase = if g.contact_from_sensors {
            let mg = self.robot.total_mass() * self.robot.gravity();
            let (phase, contact) = contact_phase(fz, mg, self.contact, r.phase);
            self.contact = contact;
            phase
        } else {
            r.phase
        };
        // 1. State estimate.
        let att = quat_to_mat(&sensors[sensor::QUAT..sensor::QUAT + 4]);
        let origin = Pose {
            p: [0.0; 3],
            r: att,
        };
        let (soles_rel, _, cog_rel) = self.robot.fk(&origin, &q_meas);
        // The soles' targets: from the leg odometry, or the references.
        let feet = if g.enabled && g.foot_odometry {
            self.odometry
                .update(phase, fz, r.phase, &r.feet, &soles_rel)
        } else {
            r.feet
        };
        let sole_targets = [Pose::sole(&feet[0]), Pose::sole(&feet[1])];
        let weights = match phase {
            Phase::Single(s) => {
                let i = s as usize;
                let mut w = [0.0; 2];
                w[i] = 1.0;
                w
            }
            _ => {
                let (a, b) = (fz[0].max(1.0), fz[1].max(1.0));
                [a / (a + b), b / (a + b)]
            }
        };
        let mut cog = [0.0; 2];
        for k in 0..2 {
            for i in 0..2 {
                cog[i] += weights[k] * (sole_targets[k].p[i] + cog_rel[i] - soles_rel[k].p[i]);
            }
        }
        if let Some(prev) = self.cog_prev {
            let a = self.dt / (g.vel_filter_s + self.dt);
            for i in 0..2 {
                let v = (cog[i] - prev[i]) / self.dt;
                self.cog_vel[i] += a * (v - self.cog_vel[i]);
            }
        } else {
            self.cog_vel = [r.x.cog_vel, r.y.cog_vel];
        }
        self.cog_prev = Some(cog);
        // 2. DCM feedback.
        let w = self.omega;
        let c_ref = [r.x.cog, r.y.cog];
        let v_ref = [r.x.cog_vel, r.y.cog_vel];
        let p_ref = [r.x.zmp, r.y.zmp];
        let mut p_d = [0.0; 2];
        let mut dcm_error = [0.0; 2];
        for i in 0..2 {
            let xi = cog[i] + self.cog_vel[i] / w;
            let xi_ref = c_ref[i] + v_ref[i] / w;
            dcm_error[i] = xi - xi_ref;
            p_d[i] = p_ref[i] + (1.0 + g.k_dcm / w) * dcm_error[i];
        }
        // 4. Distribution.
        let (a, b) = (sole_targets[0].p, sole_targets[1].p);
        let (alpha, rest) = match phase {
            Phase::Single(s) => {
                let i = s as usize;
                let sp = sole_targets[i].p;
                (
                    if i == 0 { 1.0 } else { 0.0 },
                    [p_d[0] - sp[0], p_d[1] - sp[1]],
                )
            }
            _ => {
                let ab = [a[0] - b[0], a[1] - b[1]];
                let l2 = (ab[0] * ab[0] + ab[1] * ab[1]).max(1e-9);
                let lam =
                    (((p_d[0] - b[0]) * ab[0] + (p_d[1] - b[1]) * ab[1]) / l2).clamp(0.0, 1.0);
                (
                    lam,
                    [p_d[0] - b[0] - lam * ab[0], p_d[1] - b[1] - lam * ab[1]],
                )
            }
        };
        let half = self.robot.sole_half();
        let clamp = [
            (half[0] - SOLE_CLAMP_MARGIN_M).max(0.0),
            (half[1] - SOLE_CLAMP_MARGIN_M).max(0.0),
        ];
        let mut r_d = [[0.0; 2]; 2];
        let mut clamped_pd = [0.0; 2];
        for k in 0..2 {
            let yaw = feet[k].yaw;
            let (s, c) = yaw.sin_cos();
            let lx = (c * rest[0] + s * rest[1]).clamp(-clamp[0], clamp[0]);
            let ly = (-s * rest[0] + c * rest[1]).clamp(-clamp[1], clamp[1]);
            r_d[k] = [lx, ly];
            let share = if k == 0 { alpha } else { 1.0 - alpha };
            clamped_pd[0] += share * (sole_targets[k].p[0] + c * lx - s * ly);
            clamped_pd[1] += share * (sole_targets[k].p[1] + s * lx + c * ly);
        }
        // Measured ZMP (world) from the loaded feet.
        let mut zm = [0.0; 2];
        let mut fsum = 0.0;
        for k in 0..2 {
            if local[k][0].is_finite() {
                let (s, c) = feet[k].yaw.sin_cos();
                let [lx, ly] = local[k];
                zm[0] += fz[k] * (sole_targets[k].p[0] + c * lx - s * ly);
                zm[1] += fz[k] * (sole_targets[k].p[1] + s * lx + c * ly);
                fsum += fz[k];
            }
        }
        let zmp_measured = if fsum > 0.0 {
            [zm[0] / fsum, zm[1] / fsum]
        } else {
            [f64::NAN; 2]
        };
        let dt = self.dt;
        if g.enabled {
            // 5. Foot damping control.
            for k in 0..2 {
                let [pitch, roll] = &mut self.ankle[k];
                let swing = matches!(phase, Phase::Single(s) if s as usize != k);
                let ret = if swing {
                    SWING_RETURN_S
                } else {
                    g.ankle_return_s
                };
                let (dp, dr) = if !swing && local[k][0].is_finite() && fz[k] > 50.0 {
                    // Local errors in the sole frame.
                    (
                        -fz[k] * (local[k][0] - r_d[k][0]) / g.damping,
                        fz[k] * (local[k][1] - r_d[k][1]) / g.damping,
                    )
                } else {
                    (0.0, 0.0)
                };
                *pitch += dt * (dp - *pitch / ret);
                *roll += dt * (dr - *roll / ret);
                *pitch = pitch.clamp(-g.ankle_limit_rad, g.ankle_limit_rad);
                *roll = roll.clamp(-g.ankle_limit_rad, g.ankle_limit_rad);
            }
            // 6. Foot force difference control (double support only).
            let double = !matches!(phase, Phase::Single(_));
            let mg = self.robot.total_mass() * self.robot.gravity();
            let diff_d = (2.0 * alpha - 1.0) * mg;
            let diff_m = fz[0] - fz[1];
            let vz = if double {
                g.k_force * (diff_d - diff_m)
            } else {
                0.0
            };
            self.dz += dt * (vz - self.dz / g.force_return_s);
            self.dz = self.dz.clamp(-g.dz_limit_m, g.dz_limit_m);
            // 7. COG modification.
            if zmp_measured[0].is_finite() {
                for i in 0..2 {
                    let v =
                        -g.k_cog * (clamped_pd[i] - zmp_measured[i]) - self.dc[i] / g.cog_return_s;
                    self.dc[i] = (self.dc[i] + dt * v).clamp(-g.cog_limit_m, g.cog_limit_m);
                }
            }
        }
        self.internals = Internals {
            cog,
            zmp_desired: clamped_pd,
            zmp_measured,
            dc: self.dc,
            dcm_error,
        };
        // 8. Inverse kinematics.
        let yaw = mean_yaw(&feet);
        let mut soles = sole_targets;
        soles[0].p[2] -= 0.5 * self.dz;
        soles[1].p[2] += 0.5 * self.dz;
        let target = [c_ref[0] + self.dc[0], c_ref[1] + self.dc[1]];
        let start = self
            .waist_guess
            .unwrap_or_else(|| Pose::upright(target[0], target[1], self.robot.waist_height(), yaw));
        let start = Pose {
            p: [start.p[0], start.p[1], self.robot.waist_height()],
            r: rot_z(yaw),
        };
        let (waist, q) = self.robot.solve_waist(start, &soles, target)?;
        self.waist_guess = Some(waist);
        let mut out = [0.0; 12];
        for k in 0..2 {
            let mut qk = q[k];
            let [(ip, sp), (ir, sr)] = self.robot.ankle_joints([Side::Left, Side::Right][k]);
            qk[ip] += sp * self.ankle[k][0];
            qk[ir] += sr * self.ankle[k][1];
            out[6 * k..6 * k + 6].copy_from_slice(&qk);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sensor reading of a foot at rest on the ground force `fg` at `r` (from the ankle,
    /// foot frame), with the foot weight `w` at `c` (the inverse of [`sole_cop`]'s balance).
    fn reading_at(fg: [f64; 3], r: [f64; 3], w: f64, c: [f64; 3]) -> [f64; 6] {
        let m = [
            r[1] * fg[2] - r[2] * fg[1],
            r[2] * fg[0] - r[0] * fg[2],
            r[0] * fg[1] - r[1] * fg[0],
        ];
        [
            -fg[0],
            -fg[1],
            -(fg[2] - w),
            c[1] * w - m[0],
            -c[0] * w - m[1],
            -m[2],
        ]
    }

    /// [`reading_at`] with the foot's centre of mass below the ankle.
    fn reading(fg: [f64; 3], r: [f64; 3], w: f64) -> [f64; 6] {
        reading_at(fg, r, w, [0.0, 0.0, -0.06])
    }

    #[test]
    fn cop_from_the_ankle_sensor() {
        let (h, w) = (0.105, 14.7);
        for (fg, r) in [
            ([0.0, 0.0, 300.0], [0.03, -0.02, -h]),
            ([25.0, -10.0, 500.0], [-0.08, 0.05, -h]),
        ] {
            let below = [0.0, 0.0, -0.06];
            let (fz, cop) = sole_cop(&reading(fg, r, w), w, below, [0.0, 0.0, -h]);
            let cop = cop.expect("loaded");
            assert!((fz - fg[2]).abs() < 1e-9);
            assert!(
                (cop[0] - r[0]).abs() < 1e-12 && (cop[1] - r[1]).abs() < 1e-12,
                "{cop:?}"
            );
            // A sole centre ahead of the ankle and a foot's centre of mass off its axis
            // (a G1-like foot): the CoP is given from the sole centre.
            let (sole, c) = ([0.035, 0.01, -0.035], [0.026, 0.0, -0.016]);
            let at = [r[0], r[1], sole[2]];
            let (_, cop) = sole_cop(&reading_at(fg, at, w, c), w, c, sole);
            let cop = cop.expect("loaded");
            assert!(
                (cop[0] - (r[0] - sole[0])).abs() < 1e-12
                    && (cop[1] - (r[1] - sole[1])).abs() < 1e-12,
                "{cop:?}"
            );
        }
        // Unloaded (a swing foot: the sensor carries only the foot's weight).
        let (fz, cop) = sole_cop(&[0.0, 0.0, w, 0.0, 0.0, 0.0], w, [0.0; 3], [0.0, 0.0, -h]);
        assert!(fz.abs() < 1e-12 && cop.is_none());
    }

    #[test]
    fn standing_still_leaves_the_pattern_alone() {
        // Sensors of a robot standing exactly on its reference: the DCM error is zero only if
        // the measured COG equals the reference; the commanded pose is then the IK of the
        // reference (no ankle, height or COG correction in the first tick).
        use planner_core::gait::{FootPose, Reference};
        let robot = Robot::default();
        let feet = [
            FootPose {
                x: 0.0,
                y: 0.1,
                z: 0.0,
                yaw: 0.0,
            },
            FootPose {
                x: 0.0,
                y: -0.1,
                z: 0.0,
                yaw: 0.0,
            },
        ];
        let soles = [Pose::sole(&feet[0]), Pose::sole(&feet[1])];
        let (_, q) = robot
            .solve_waist(
                Pose::upright(0.0, 0.0, robot.waist_height(), 0.0),
                &soles,
                [0.0, 0.0],
            )
            .unwrap();
        let mut r = Reference {
            x: Default::default(),
            y: Default::default(),
            phase: Phase::Double,
            feet,
        };
        r.x.cog = 0.0;
        let mut s = vec![0.0; sensor::LEN];
        s[sensor::QUAT] = 1.0;
        for k in 0..2 {
            s[sensor::QPOS + 6 * k..sensor::QPOS + 6 * k + 6].copy_from_slice(&q[k]);
            // Half the weight on each sole centre.
            let half = 0.5 * robot.total_mass() * robot.gravity();
            let ft = reading([0.0, 0.0, half], [0.0, 0.0, -robot.ankle_height()], 14.7);
            s[sensor::FT + 6 * k..sensor::FT + 6 * k + 6].copy_from_slice(&ft);
        }
        let mut st = Stabilizer::new(robot, Gains::default(), 0.001, 0.814);
        let out = st.step(&r, &s).unwrap();
        for k in 0..2 {
            for j in 0..6 {
                assert!((out[6 * k + j] - q[k][j]).abs() < 1e-6, "{out:?} {q:?}");
            }
        }
        let i = st.internals;
        assert!(
            i.zmp_measured[0].abs() < 1e-9 && i.zmp_measured[1].abs() < 1e-9,
            "{i:?}"
        );
        assert!(i.cog[0].abs() < 1e-9 && i.cog[1].abs() < 1e-9, "{i:?}");
    }

    #[test]
    fn damping_control_moves_the_ankle_against_a_toe_load() {
        // The measured CoP 5 cm ahead of the desired one: the ankle pitch target goes toe up
        // (negative pitch), and back to zero when the load goes.
        let robot = Robot::default();
        let feet = [
            planner_core::gait::FootPose {
                x: 0.0,
                y: 0.1,
                z: 0.0,
                yaw: 0.0,
            },
            planner_core::gait::FootPose {
                x: 0.0,
                y: -0.1,
                z: 0.0,
                yaw: 0.0,
            },
        ];
        let soles = [Pose::sole(&feet[0]), Pose::sole(&feet[1])];
        let (_, q) = robot
            .solve_waist(
                Pose::upright(0.0, 0.0, robot.waist_height(), 0.0),
                &soles,
                [0.0, 0.0],
            )
            .unwrap();
        let mut r = Reference {
            x: Default::default(),
            y: Default::default(),
            phase: Phase::Single(planner_core::gait::Side::Left),
            feet,
        };
        // The reference ZMP at the left sole centre.
        r.y.zmp = 0.1;
        let mut s = vec![0.0; sensor::LEN];
        s[sensor::QUAT] = 1.0;
        for k in 0..2 {
            s[sensor::QPOS + 6 * k..sensor::QPOS + 6 * k + 6].copy_from_slice(&q[k]);
        }
        let weight = robot.total_mass() * robot.gravity();
        let ft = reading([0.0, 0.0, weight], [0.05, 0.0, -robot.ankle_height()], 14.7);
        s[sensor::FT..sensor::FT + 6].copy_from_slice(&ft);
        s[sensor::FT + 6..sensor::FT + 12].copy_from_slice(&[0.0, 0.0, 14.7, 0.0, 0.0, 0.0]);
        let mut st = Stabilizer::new(robot, Gains::default(), 0.001, 0.814);
        for _ in 0..20 {
            st.step(&r, &s).unwrap();
        }
        let [pitch, roll] = st.ankle[0];
        // 20 ms at F_z (x_m − x_d) / D = 570 N × 0.05 m / 1000 = 0.028 rad/s.
        assert!(pitch < -4e-4 && pitch > -6e-4, "{pitch}");
        assert!(roll.abs() < 1e-9, "{roll}");
        // The swing (right) foot has no correction.
        assert_eq!(st.ankle[1], [0.0, 0.0]);
    }
}
