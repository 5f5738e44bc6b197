//! Dynamic validation in a physics engine (MuJoCo): does the generated pattern keep the HRP-2
//! model walking once it has mass, contacts and servos?
//!
//! * [`model`]: the MJCF generated from the multi-body link table (the one place that reads
//!   it), 1 kHz physics, joint position servos, IMU, encoders, ankle force/torque sensors;
//! * [`bridge`]: MuJoCo behind a small Python process (the reasons are in its documentation);
//! * [`stabilizer`]: the DCM/ZMP stabilizer between the pattern and the servos (Kajita et al.
//!   2010), fed with the simulated sensors only;
//! * [`metrics`]: the definitions of a fall and of the CoP tracking;
//! * [`gait`]: what "walked" means besides no fall: slip, flight, the CoP outside the support
//!   polygon and the landing error, each within a stated bound;
//! * [`output`]: the `physics` command and its files (`physics.json` …);
//! * [`tables`]: the paper's Tables I and II in the engine (`physics-tables`);
//! * [`fault_sweep`]: the fault sweep's rows in the engine (`physics-faults`);
//! * [`probe`]: the grid with a weakened stabilizer and softer servos (`--stabilizer`,
//!   `--servo-damping`, `--open-loop`: the options of every engine command);
//! * [`sequence`]: several consecutive steps modified, plain re-plan and proposed method
//!   (`physics-sequence`);
//! * [`closed_loop`]: the node inside the engine's loop, fed the measured state (`MEASURED`),
//!   adjusting its steps when the walk was started with `StartAdjusting`;
//! * [`push_map`]: the push-recovery map over phases and directions (`push-map`).
//!
//! # A run
//!
//! The planner's references (one every `dt` = 5 ms) are linearly interpolated to the 1 ms
//! control period (COG, its velocity, ZMP, foot poses; the phase of the earlier tick). The
//! robot starts at rest in the pose of the first reference (its joint angles from the same
//! waist search and IK the stabilizer uses), stands for [`PhysicsConfig::settle_s`] on it,
//! plays the trajectory, then stands for [`PhysicsConfig::tail_s`] on the last reference. At
//! every 1 ms tick the stabilizer reads the sensors and sets the twelve servo targets, the
//! engine steps once, the evaluation reads the engine's ground truth and checks for a fall
//! ([`metrics`]); the run stops at the first fall. A fall counts (`fell`) until
//! [`metrics::SETTLE_AFTER_S`] after the reference stops moving, later it is reported as a fall
//! after the end (`fell_after_end`). Every engine command hands [`run`] a trajectory that ends
//! standing (both feet on the floor, the stop window finished: [`ends_standing`]); the report
//! says whether it did (`ended_standing`), for a walk that could not stand.

pub mod bridge;
pub mod closed_loop;
pub mod fault_sweep;
pub mod gait;
pub mod metrics;
pub mod model;
pub mod odometry;
pub mod output;
pub mod probe;
pub mod push_map;
pub mod push_scan;
pub mod sensors;
pub mod sequence;
pub mod stabilizer;
pub mod start;
pub mod tables;
mod waist;

use crate::robot::model::{mean_yaw, Pose};
use bridge::Engine;
use metrics::{fall_check, tilt_deg, FallCause, Tracking};
use model::{sensor, Robot};
use planner_core::gait::{FootPose, Phase, Reference};
use planner_core::lipm::Sample;
use stabilizer::{Gains, Stabilizer};

/// Physics (and control) period \[s\].
pub const PHYSICS_DT: f64 = 0.001;

/// A horizontal push on the trunk (for the fall tests).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Push {
    /// Start, in trajectory time \[s\].
    pub t_s: f64,
    /// Duration \[s\].
    pub duration_s: f64,
    /// Force (x, y) \[N\], world frame.
    pub force: [f64; 2],
}

/// How to run the engine.
#[derive(Clone, Debug, PartialEq)]
pub struct PhysicsConfig {
    /// The stabilizer's gains (`enabled = false`: open-loop playback).
    pub gains: Gains,
    /// Standing time before the trajectory \[s\].
    pub settle_s: f64,
    /// Standing time after it \[s\]: the engine holds the last reference this long (a fall
    /// counts until [`metrics::SETTLE_AFTER_S`] after the reference stops, a later one is
    /// reported as a fall after the end).
    pub tail_s: f64,
    /// An optional push.
    pub push: Option<Push>,
    /// LIPM height z_c \[m\].
    pub z_c: f64,
    /// The robot (its MJCF, kinematics and soles).
    pub robot: Robot,
    /// The sensors' noise, bias and latency ([`sensors`]; default: ideal).
    pub sensors: sensors::SensorModel,
}

impl Default for PhysicsConfig {
    fn default() -> Self {
        Self {
            gains: Gains::default(),
            settle_s: 1.0,
            tail_s: 1.0,
            push: None,
            z_c: planner_core::HRP2_COG_HEIGHT,
            robot: Robot::default(),
            sensors: sensors::SensorModel::IDEAL,
        }
    }
}

impl PhysicsConfig {
    /// The default run of a robot file's robot: its link table and soles ([`Robot::of`]) and
    /// its pendulum height.
    pub fn for_robot(robot: &crate::robot::Robot) -> Self {
        Self {
            z_c: robot.planner.params.cog_height,
            robot: Robot::of(robot),
            ..Self::default()
        }
    }
}

/// One logged sample (every 5 ms).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhysicsSample {
    /// Trajectory time \[s\] (negative while settling).
    pub t: f64,
    /// Waist tilt \[deg\].
    pub tilt_deg: f64,
    /// Measured CoP of the floor contacts (x, y) \[m\] (NaN when airborne).
    pub cop: [f64; 2],
    /// Reference ZMP \[m\].
    pub zmp_ref: [f64; 2],
    /// Desired ZMP of the stabilizer \[m\].
    pub zmp_desired: [f64; 2],
    /// ZMP the stabilizer measured with the ankle force sensors \[m\].
    pub zmp_sensed: [f64; 2],
    /// The 50 ms CoP tracking error \[m\] (NaN before the first full window).
    pub cop_err: f64,
    /// True whole-body COG (x, y) \[m\].
    pub cog: [f64; 2],
    /// Reference COG \[m\].
    pub cog_ref: [f64; 2],
    /// Waist height \[m\].
    pub base_z: f64,
    /// The waist's pose from the engine: position \[m\] and orientation (w, x, y, z).
    pub base: ([f64; 3], [f64; 4]),
    /// The leg joints' angles from the encoders (left, right; hip first) \[rad\].
    pub legs: [[f64; 6]; 2],
}

/// The outcome of a run (the figures of `physics.json`).
#[derive(Clone, Debug, PartialEq)]
pub struct PhysicsReport {
    /// The robot fell.
    pub fell: bool,
    /// When, in trajectory time \[s\].
    pub fall_time_s: Option<f64>,
    /// Why.
    pub fall_cause: Option<FallCause>,
    /// The robot fell later than [`metrics::SETTLE_AFTER_S`] after the reference stopped (not
    /// counted in `fell`).
    pub fell_after_end: bool,
    /// When, in trajectory time \[s\].
    pub fall_after_end_time_s: Option<f64>,
    /// Why.
    pub fall_after_end_cause: Option<FallCause>,
    /// When the reference stopped moving, in trajectory time \[s\] ([`metrics::reference_stop_s`]).
    pub reference_stop_s: f64,
    /// The trajectory ended standing ([`ends_standing`]).
    pub ended_standing: bool,
    /// Largest waist tilt \[deg\].
    pub max_tilt_deg: f64,
    /// Mean 50 ms CoP tracking error \[m\].
    pub cop_err_mean_m: f64,
    /// Worst 50 ms CoP tracking error \[m\].
    pub cop_err_max_m: f64,
    /// When the worst error happened \[s\].
    pub cop_err_max_t_s: f64,
    /// Largest horizontal COG error against the reference \[m\].
    pub cog_drift_max_m: f64,
    /// Largest distance of a supporting sole from its reference \[m\].
    pub foot_drift_max_m: f64,
    /// Simulated trajectory time \[s\].
    pub simulated_s: f64,
    /// Slip, flight, the CoP outside the support polygon and the landing error ([`gait`]).
    pub gait: gait::GaitQuality,
    /// The MuJoCo version.
    pub engine: String,
}

/// The mark of a fall after the end in the tables' verdicts ([`PhysicsReport::verdict`]).
pub const AFTER_END_MARK: &str = "†";

/// The footnote the tables give [`AFTER_END_MARK`].
pub const AFTER_END_NOTE: &str =
    "†: fell more than 1 s (`SETTLE_AFTER_S`) after the reference stopped: not counted as a fall";

impl PhysicsReport {
    /// The robot walked: no fall and every gait measure within its bound ([`gait`]).
    pub fn walked(&self) -> bool {
        !self.fell && self.gait.within_bounds()
    }

    /// The verdict as the tables write it: `**fell**`; `**slip**`, `**flight**`, `**cop**`,
    /// `**landing**` (joined by `+`) for a run that stayed up with a gait measure beyond its
    /// bound; `ok` for a walk, `ok†` for a walk followed by a fall after the end.
    pub fn verdict(&self) -> String {
        if self.fell {
            "**fell**".into()
        } else if !self.gait.within_bounds() {
            format!("**{}**", self.gait_short())
        } else if self.fell_after_end {
            format!("ok{AFTER_END_MARK}")
        } else {
            "ok".into()
        }
    }

    /// The gait measures beyond their bounds in short: `slip+flight` (empty within bounds).
    pub fn gait_short(&self) -> String {
        let q = &self.gait;
        let mut v = Vec::new();
        if q.slipped() {
            v.push("slip");
        }
        if q.flight_max_s > gait::FLIGHT_MAX_S + 1e-9 {
            v.push("flight");
        }
        if q.cop_outside_max_s > gait::COP_OUTSIDE_MAX_S + 1e-9 {
            v.push("cop");
        }
        if q.landed_off() {
            v.push("landing");
        }
        v.join("+")
    }

    /// The verdict in words: `walked`, `fell (tilt)`, `did not walk (slip, flight)`.
    pub fn verdict_words(&self) -> String {
        if self.fell {
            format!("fell ({})", self.fall_cause.map_or("?", |c| c.name()))
        } else if self.walked() {
            "walked".into()
        } else {
            format!("did not walk ({})", self.gait.violations().join(", "))
        }
    }

    /// "Fell" as the sequence and fault tables write it: `**yes** (6.41 s)`, `no`, or
    /// `no (fell after the end, 9.80 s)`.
    pub fn fell_text(&self) -> String {
        match (self.fall_time_s, self.fall_after_end_time_s) {
            (Some(t), _) => format!("**yes** ({t:.2} s)"),
            (None, Some(t)) => format!("no (fell after the end, {t:.2} s)"),
            (None, None) => "no".into(),
        }
    }

    /// "Walked" as the sequence and fault tables write it: `yes`, `**no** (fell)`, or
    /// `**no** (slip 23.1 mm, flight 12 ms)` with the measures beyond their bounds.
    pub fn walked_text(&self) -> String {
        let q = &self.gait;
        if self.fell {
            return "**no** (fell)".into();
        }
        if self.walked() {
            return "yes".into();
        }
        let mut v = Vec::new();
        if q.slip_max_m > gait::SLIP_MAX_M {
            v.push(format!("slip {:.1} mm", q.slip_max_m * 1e3));
        }
        if q.slip_yaw_max_rad > gait::SLIP_YAW_MAX_RAD {
            v.push(format!("sole turned {:.3} rad", q.slip_yaw_max_rad));
        }
        if q.flight_max_s > gait::FLIGHT_MAX_S + 1e-9 {
            v.push(format!("flight {:.0} ms", q.flight_max_s * 1e3));
        }
        if q.cop_outside_max_s > gait::COP_OUTSIDE_MAX_S + 1e-9 {
            v.push(format!("CoP outside {:.0} ms", q.cop_outside_max_s * 1e3));
        }
        if q.landing_err_max_m > gait::LANDING_MAX_M {
            v.push(format!("landing {:.1} mm", q.landing_err_max_m * 1e3));
        }
        if q.landing_yaw_err_max_rad > gait::LANDING_YAW_MAX_RAD {
            v.push(format!(
                "landing heading {:.3} rad",
                q.landing_yaw_err_max_rad
            ));
        }
        format!("**no** ({})", v.join(", "))
    }

    /// The verdict and the end of the run as every command's JSON gives them: `walked`
    /// ([`Self::walked`]), `verdict` ([`Self::verdict_words`]), the gait measures
    /// ([`gait::GaitQuality::fields`]), `fell_after_end`, `fall_after_end_time_s`,
    /// `fall_after_end_cause`, `reference_stop_s`, `fall_window_end_s` (until when a fall
    /// counts) and `ended_standing`.
    pub fn end_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        use serde_json::json;
        let mut v = vec![
            ("walked", json!(self.walked())),
            ("verdict", json!(self.verdict_words())),
        ];
        v.extend(self.gait.fields());
        v.extend([
            ("fell_after_end", json!(self.fell_after_end)),
            ("fall_after_end_time_s", json!(self.fall_after_end_time_s)),
            (
                "fall_after_end_cause",
                json!(self.fall_after_end_cause.map(|c| c.name())),
            ),
            ("reference_stop_s", json!(self.reference_stop_s)),
            (
                "fall_window_end_s",
                json!(self.reference_stop_s + metrics::SETTLE_AFTER_S),
            ),
            ("ended_standing", json!(self.ended_standing)),
        ]);
        v
    }

    /// Adds [`Self::end_fields`] to the JSON object `j`.
    pub fn add_end_fields(&self, j: &mut serde_json::Value) {
        for (k, v) in self.end_fields() {
            j[k] = v;
        }
    }
}

/// A run: the report and the log.
#[derive(Clone, Debug)]
pub struct PhysicsRun {
    /// The figures.
    pub report: PhysicsReport,
    /// Every 5 ms.
    pub samples: Vec<PhysicsSample>,
}

fn lerp(a: f64, b: f64, s: f64) -> f64 {
    a + (b - a) * s
}

fn lerp_sample(a: &Sample<f64>, b: &Sample<f64>, s: f64) -> Sample<f64> {
    Sample {
        cog: lerp(a.cog, b.cog, s),
        cog_vel: lerp(a.cog_vel, b.cog_vel, s),
        cog_acc: lerp(a.cog_acc, b.cog_acc, s),
        zmp: lerp(a.zmp, b.zmp, s),
        zmp_vel: lerp(a.zmp_vel, b.zmp_vel, s),
    }
}

fn lerp_foot(a: &FootPose<f64>, b: &FootPose<f64>, s: f64) -> FootPose<f64> {
    let mut f = *a;
    f.x = lerp(a.x, b.x, s);
    f.y = lerp(a.y, b.y, s);
    f.z = lerp(a.z, b.z, s);
    let dy = (b.yaw - a.yaw).sin().atan2((b.yaw - a.yaw).cos());
    f.yaw = a.yaw + dy * s;
    f
}

/// Whether a trajectory ends standing: its last reference in the phase
/// [`Phase::Standing`] (the stop window finished) with both feet on the floor.
pub fn ends_standing(trajectory: &[Reference<f64>]) -> bool {
    trajectory
        .last()
        .is_some_and(|r| r.phase == Phase::Standing && r.feet.iter().all(|f| f.z == 0.0))
}

/// The reference at trajectory time `t` (held before the start and after the end).
pub fn reference_at(trajectory: &[Reference<f64>], dt: f64, t: f64) -> Reference<f64> {
    let n = trajectory.len();
    let u = (t / dt).max(0.0);
    let k = (u.floor() as usize).min(n - 1);
    if k + 1 >= n {
        return trajectory[n - 1];
    }
    let s = u - k as f64;
    let (a, b) = (&trajectory[k], &trajectory[k + 1]);
    Reference {
        x: lerp_sample(&a.x, &b.x, s),
        y: lerp_sample(&a.y, &b.y, s),
        phase: a.phase,
        feet: [
            lerp_foot(&a.feet[0], &b.feet[0], s),
            lerp_foot(&a.feet[1], &b.feet[1], s),
        ],
    }
}

/// The rotation of the unit quaternion `q` (w, x, y, z) as a matrix.
pub fn quat_to_mat(q: [f64; 4]) -> crate::robot::model::Mat3 {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
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

/// The robot at rest in the pose of the reference `r0`: its waist (from the same waist search
/// and IK the stabilizer uses) and the engine's `qpos` (the floating base, then the joints).
pub fn initial_pose(robot: &Robot, r0: &Reference<f64>) -> Result<(Pose, Vec<f64>), String> {
    let yaw0 = mean_yaw(&r0.feet);
    let soles0 = [Pose::sole(&r0.feet[0]), Pose::sole(&r0.feet[1])];
    let (waist0, q0) = robot.solve_waist(
        Pose::upright(r0.x.cog, r0.y.cog, robot.waist_height(), yaw0),
        &soles0,
        [r0.x.cog, r0.y.cog],
    )?;
    let mut qpos = vec![
        waist0.p[0],
        waist0.p[1],
        waist0.p[2],
        (yaw0 / 2.0).cos(),
        0.0,
        0.0,
        (yaw0 / 2.0).sin(),
    ];
    qpos.extend(q0.iter().flatten());
    Ok((waist0, qpos))
}

/// Runs a trajectory of references (period `dt`) in MuJoCo. Errors: the engine could not be
/// started (the message names what to install), the bridge ended, or the IK failed.
pub fn run(
    trajectory: &[Reference<f64>],
    dt: f64,
    cfg: &PhysicsConfig,
) -> Result<PhysicsRun, String> {
    if trajectory.is_empty() {
        return Err("empty trajectory".into());
    }
    let robot = cfg.robot.clone();
    let mut engine = Engine::start(&robot.mjcf())?;
    let mut stab = Stabilizer::new(robot.clone(), cfg.gains, PHYSICS_DT, cfg.z_c);
    let (waist0, qpos) = initial_pose(&robot, &trajectory[0])?;
    let mut obs = engine.reset(&qpos)?;
    let mut sensed = sensors::Sensors::new(cfg.sensors);
    let end_t = (trajectory.len() - 1) as f64 * dt;
    let steps = ((cfg.settle_s + end_t + cfg.tail_s) / PHYSICS_DT).round() as usize;
    let mut tracking = Tracking::default();
    let mut samples = Vec::new();
    let mut report = PhysicsReport {
        fell: false,
        fall_time_s: None,
        fall_cause: None,
        fell_after_end: false,
        fall_after_end_time_s: None,
        fall_after_end_cause: None,
        reference_stop_s: metrics::reference_stop_s(trajectory, dt),
        ended_standing: ends_standing(trajectory),
        max_tilt_deg: 0.0,
        cop_err_mean_m: 0.0,
        cop_err_max_m: 0.0,
        cop_err_max_t_s: 0.0,
        cog_drift_max_m: 0.0,
        foot_drift_max_m: 0.0,
        simulated_s: 0.0,
        gait: gait::GaitQuality::default(),
        engine: engine.version.clone(),
    };
    let mut monitor = gait::GaitMonitor::new(
        robot.total_mass() * robot.gravity(),
        [robot.sole_half()[0], robot.sole_half()[1]],
    );
    for k in 0..steps {
        let t = k as f64 * PHYSICS_DT - cfg.settle_s;
        let r = reference_at(trajectory, dt, t);
        let ctrl = stab.step(&r, sensed.read(&obs.sensors))?;
        let mut wrench = [0.0; 6];
        if let Some(p) = cfg.push {
            if t >= p.t_s && t < p.t_s + p.duration_s {
                wrench[0] = p.force[0];
                wrench[1] = p.force[1];
            }
        }
        obs = engine.step(1, &ctrl, wrench)?;
        // Evaluation at the time the engine reached.
        let t1 = t + PHYSICS_DT;
        let r1 = reference_at(trajectory, dt, t1);
        let tilt = tilt_deg(obs.base_quat);
        report.max_tilt_deg = report.max_tilt_deg.max(tilt);
        let err = tracking.push(t1, obs.cop, [r1.x.zmp, r1.y.zmp]);
        let mut q = [[0.0; 6]; 2];
        for (j, leg) in q.iter_mut().enumerate() {
            leg.copy_from_slice(&obs.sensors[sensor::QPOS + 6 * j..sensor::QPOS + 6 * j + 6]);
        }
        let base = Pose {
            p: obs.base_pos,
            r: quat_to_mat(obs.base_quat),
        };
        let (soles, _, cog) = robot.fk(&base, &q);
        let cog_err = (cog[0] - r1.x.cog).hypot(cog[1] - r1.y.cog);
        report.cog_drift_max_m = report.cog_drift_max_m.max(cog_err);
        for (s, f) in soles.iter().zip(&r1.feet) {
            if f.z == 0.0 {
                let d = (s.p[0] - f.x).hypot(s.p[1] - f.y);
                report.foot_drift_max_m = report.foot_drift_max_m.max(d);
            }
        }
        if t1 > 0.0 {
            monitor.push(&gait::GaitSample {
                dt: PHYSICS_DT,
                feet_ref: r1.feet,
                soles,
                sole_force: obs.sole_force,
                normal_force: obs.normal_force,
                cop: obs.cop,
            });
        }
        if (k + 1) % 5 == 0 {
            samples.push(PhysicsSample {
                t: t1,
                tilt_deg: tilt,
                cop: obs.cop,
                zmp_ref: [r1.x.zmp, r1.y.zmp],
                zmp_desired: stab.internals.zmp_desired,
                zmp_sensed: stab.internals.zmp_measured,
                cop_err: err.unwrap_or(f64::NAN),
                cog: [cog[0], cog[1]],
                cog_ref: [r1.x.cog, r1.y.cog],
                base_z: obs.base_pos[2],
                base: (obs.base_pos, obs.base_quat),
                legs: q,
            });
        }
        report.simulated_s = t1.max(0.0);
        if let Some(cause) = fall_check(
            obs.base_quat,
            obs.base_pos[2],
            waist0.p[2],
            obs.other_contact,
        ) {
            if metrics::fall_counts(t1, report.reference_stop_s) {
                report.fell = true;
                report.fall_time_s = Some(t1);
                report.fall_cause = Some(cause);
            } else {
                report.fell_after_end = true;
                report.fall_after_end_time_s = Some(t1);
                report.fall_after_end_cause = Some(cause);
            }
            break;
        }
    }
    report.gait = monitor.quality();
    report.cop_err_mean_m = tracking.mean();
    report.cop_err_max_m = tracking.max;
    report.cop_err_max_t_s = tracking.max_t;
    Ok(PhysicsRun { report, samples })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(fell: bool, gait: gait::GaitQuality) -> PhysicsReport {
        PhysicsReport {
            fell,
            fall_time_s: fell.then_some(3.0),
            fall_cause: fell.then_some(FallCause::Tilt),
            fell_after_end: false,
            fall_after_end_time_s: None,
            fall_after_end_cause: None,
            reference_stop_s: 9.0,
            ended_standing: true,
            max_tilt_deg: 0.2,
            cop_err_mean_m: 0.01,
            cop_err_max_m: 0.03,
            cop_err_max_t_s: 1.0,
            cog_drift_max_m: 0.01,
            foot_drift_max_m: 0.004,
            simulated_s: 10.0,
            gait,
            engine: "3.2.7".into(),
        }
    }

    /// A run that stayed up with a slide and a hop did not walk, and every verdict says why.
    #[test]
    fn verdicts_of_a_walk_a_slide_and_a_fall() {
        let good = report(false, gait::GaitQuality::default());
        assert!(good.walked());
        assert_eq!(
            (good.verdict(), good.verdict_words(), good.walked_text()),
            ("ok".into(), "walked".into(), "yes".into())
        );
        let slid = report(
            false,
            gait::GaitQuality {
                slip_max_m: 0.0231,
                flight_max_s: 0.012,
                ..Default::default()
            },
        );
        assert!(!slid.walked() && !slid.fell);
        assert_eq!(slid.verdict(), "**slip+flight**");
        assert_eq!(slid.verdict_words(), "did not walk (slip, flight)");
        assert_eq!(slid.walked_text(), "**no** (slip 23.1 mm, flight 12 ms)");
        let j = serde_json::Value::Object(
            slid.end_fields()
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
        );
        assert_eq!(j["walked"], false);
        assert_eq!(j["gait_violations"], serde_json::json!(["slip", "flight"]));
        let fell = report(true, gait::GaitQuality::default());
        assert!(!fell.walked());
        assert_eq!(
            (fell.verdict(), fell.verdict_words()),
            ("**fell**".into(), "fell (tilt)".into())
        );
    }
}
