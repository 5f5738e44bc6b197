//! A harder probe of the paper's claim: the Tables I/II grid with a weakened stabilizer and
//! softer servos.
//!
//! Under the stabilizer of [`super::stabilizer`] (and even open loop, with the servos of
//! [`super::model`]) no cell of the grid falls, plain re-plan or proposed method. That
//! stabilizer is ours (Kajita et al. 2010); the paper's dynamic simulation (2007) ran HRP-2
//! with HRP-2's own stabilizer and servo model, neither described in the paper, so how much
//! feedback its pattern had behind it is not known. This probe asks how the verdict changes
//! with less of it:
//!
//! * **stabilizer scale** `s` ([`Gains::scaled`]): every feedback gain of the stabilizer times
//!   `s` (`full` = 1, `off` = 0, or a number ≥ 0);
//! * **servo damping** `kd` (`--servo-damping`): the joint damping of every servo, in place of
//!   the robot's (HRP-2: [`super::model::SERVO_KD`] = 600 N m s/rad); softer joints let the
//!   feet and the trunk rock, as the compliant ankles of a real HRP-2 do;
//! * **`weakest`**: the smallest `s` of [`LADDER`] with which no built-in scenario falls
//!   through in the engine (0 falls) with that servo damping ([`weakest`]): the stabilizer
//!   just strong enough for ordinary walking, so that a modification the pattern handles
//!   badly is the first thing to fall. The search goes up the ladder and stops at the first
//!   scale that walks every scenario; the scenarios are tried in [`BUILT_IN`] order and a scale
//!   is abandoned at its first fall.
//!
//! The options are one definition, [`ProbeArgs`], flattened into every engine subcommand
//! (`physics`, `physics-tables`, `physics-faults`, `physics-sequence`); [`ProbeArgs::resolve`]
//! turns them into the configuration to run, and [`Probe::record`] writes the settings into
//! the command's JSON (`stabilizer`, `stabilizer_scale`, `servo_damping` and, for `weakest`,
//! `weakest_ladder`).
//!
//! What it models, and what not: a robot whose balance depends more on the pattern, the more
//! the feedback is weakened. It does not model HRP-2's stabilizer, its servo electronics or
//! its flexible ankle bushings; a fall or its absence here is a statement about this model.

use serde_json::{json, Value};

use super::sensors::SensorModel;
use super::stabilizer::Gains;
use super::{run, PhysicsConfig, PhysicsReport};
use crate::robot::Robot;
use crate::scenario::BUILT_IN;
use crate::sim::scenario_trajectory;

/// The stabilizer scales [`weakest`] tries, weakest first.
pub const LADDER: [f64; 8] = [0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0];

/// How the stabilizer is set (`--stabilizer`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// Every feedback gain times this scale.
    Scale(f64),
    /// The smallest scale of [`LADDER`] with which no built-in scenario falls.
    Weakest,
}

/// Parses `--stabilizer`: `full` (1), `off` (0), `weakest`, or a scale ≥ 0.
pub fn parse_setting(s: &str) -> Result<Setting, String> {
    match s {
        "full" => Ok(Setting::Scale(1.0)),
        "off" => Ok(Setting::Scale(0.0)),
        "weakest" => Ok(Setting::Weakest),
        _ => match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v >= 0.0 => Ok(Setting::Scale(v)),
            _ => Err(format!(
                "--stabilizer {s:?}: expected full, off, weakest or a scale ≥ 0"
            )),
        },
    }
}

/// The probe options of the engine subcommands (one definition, flattened into each).
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct ProbeArgs {
    /// Play the patterns open loop (the stabilizer off).
    #[arg(long)]
    pub open_loop: bool,
    /// The stabilizer: `full`, `off` (no feedback acts), a scale S ≥ 0 of every feedback gain,
    /// or `weakest` (the smallest scale with which no built-in scenario falls).
    #[arg(long, value_name = "full|off|weakest|S", default_value = "full", value_parser = parse_setting)]
    pub stabilizer: Setting,
    /// The joint damping of every servo [N m s/rad] [default: the robot's].
    #[arg(long, value_name = "KD")]
    pub servo_damping: Option<f64>,
    /// The sensors: `ideal` (the engine's values) or `realistic` (noise, bias and 2 ms of
    /// latency of a humanoid of HRP-2's class; see the book's physics page).
    #[arg(long, value_name = "ideal|realistic", default_value = "ideal", value_parser = super::sensors::parse)]
    pub sensors: SensorModel,
    /// The sensors' latency [ms] [default: the `--sensors` model's].
    #[arg(long, value_name = "MS")]
    pub latency_ms: Option<usize>,
    /// Where the stabilizer takes the contact phase from: the ankle force sensors, or the
    /// reference's phase.
    #[arg(long, value_name = "reference|sensors", default_value = "sensors", value_parser = parse_contact)]
    pub contact: Contact,
    /// The loop delay the stabilizer's gains are designed for [ms] [default: the sensors'
    /// latency].
    #[arg(long, value_name = "MS")]
    pub design_delay_ms: Option<f64>,
    /// The seed of the sensors' noise [default: 1].
    #[arg(long, value_name = "N")]
    pub noise_seed: Option<u64>,
}

/// Where the stabilizer takes the contact phase from (`--contact`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Contact {
    /// The reference's phase.
    Reference,
    /// The ankle force sensors ([`super::stabilizer::contact_phase`]).
    Sensors,
}

/// Parses `--contact`: `reference` or `sensors`.
pub fn parse_contact(s: &str) -> Result<Contact, String> {
    match s {
        "reference" => Ok(Contact::Reference),
        "sensors" => Ok(Contact::Sensors),
        _ => Err(format!("--contact {s:?}: expected reference or sensors")),
    }
}

impl Default for ProbeArgs {
    /// The robot as stated: the full stabilizer, the robot's servos, the contact phase from
    /// the force sensors.
    fn default() -> Self {
        Self {
            open_loop: false,
            stabilizer: Setting::Scale(1.0),
            servo_damping: None,
            sensors: SensorModel::IDEAL,
            latency_ms: None,
            contact: Contact::Sensors,
            design_delay_ms: None,
            noise_seed: None,
        }
    }
}

/// The probe settings resolved for a robot: the configuration to run and what to record.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// The engine configuration (gains scaled, servos damped, open loop or not).
    pub cfg: PhysicsConfig,
    /// The stabilizer scale.
    pub scale: f64,
    /// The stabilizer off altogether (`--open-loop`).
    pub open_loop: bool,
    /// For `weakest`: the rungs tried.
    pub ladder: Option<Vec<Rung>>,
}

impl ProbeArgs {
    /// The configuration of `robot` with these options; `weakest` runs the ladder
    /// ([`weakest`]). Errors: the engine failed, or with every scale a built-in scenario falls.
    pub fn resolve(&self, robot: &Robot) -> Result<Probe, String> {
        let (scale, ladder) = match self.stabilizer {
            Setting::Scale(s) => (s, None),
            Setting::Weakest => match weakest(robot, self.servo_damping)? {
                (Some(s), rungs) => (s, Some(rungs)),
                (None, _) => {
                    return Err(
                        "--stabilizer weakest: not even the full stabilizer walks every \
                                built-in scenario with this servo damping"
                            .into(),
                    )
                }
            },
        };
        let mut cfg = weakened(robot, scale, self.servo_damping);
        cfg.gains.enabled = !self.open_loop;
        cfg.gains.contact_from_sensors = self.contact == Contact::Sensors;
        cfg.sensors = self.sensors;
        if let Some(ms) = self.latency_ms {
            cfg.sensors.latency_ticks = ms;
        }
        if let Some(seed) = self.noise_seed {
            cfg.sensors.seed = seed;
        }
        let design_ms = match self.design_delay_ms {
            Some(ms) if ms.is_finite() && ms >= 0.0 => ms,
            Some(ms) => return Err(format!("--design-delay-ms {ms}: expected a delay ≥ 0")),
            None => cfg.sensors.latency_ticks as f64,
        };
        cfg.gains = cfg.gains.for_delay(design_ms * 1e-3);
        Ok(Probe {
            cfg,
            scale,
            open_loop: self.open_loop,
            ladder,
        })
    }
}

impl Probe {
    /// The servo damping run \[N m s/rad\].
    pub fn servo_damping(&self) -> f64 {
        self.cfg.robot.servo()[1]
    }

    /// The settings in words, for the tables' titles: `stabilizer × 1, servo damping 600 N m
    /// s/rad` or `open loop, servo damping 600 N m s/rad`.
    pub fn mode(&self) -> String {
        let kd = self.servo_damping();
        let mut m = if self.open_loop {
            format!("open loop, servo damping {kd} N m s/rad")
        } else {
            format!("stabilizer × {}, servo damping {kd} N m s/rad", self.scale)
        };
        let s = self.cfg.sensors;
        if !s.is_ideal() {
            m += &format!(", noisy sensors {} ms late", s.latency_ticks);
        }
        if !self.cfg.gains.contact_from_sensors {
            m += ", contact from the reference";
        }
        let d = self.cfg.gains.design_delay_s;
        if d > 0.0 {
            m += &format!(", gains designed for {} ms", d * 1e3);
        }
        m
    }

    /// Writes the settings into the JSON object `json`: `stabilizer` (false when open loop),
    /// `stabilizer_scale`, `servo_damping` and, for `weakest`, `weakest_ladder` (each rung's
    /// scale, whether it walked, and its runs).
    pub fn record(&self, json: &mut Value) {
        json["stabilizer"] = Value::Bool(!self.open_loop);
        json["stabilizer_scale"] = self.scale.into();
        json["servo_damping"] = self.servo_damping().into();
        let m = self.cfg.sensors;
        json["sensors"] = json!({
            "ideal": m.is_ideal(),
            "attitude_rad": m.attitude_rad,
            "attitude_bias_rad": m.attitude_bias_rad,
            "gyro_rad_s": m.gyro_rad_s,
            "accel_m_s2": m.accel_m_s2,
            "encoder_rad": m.encoder_rad,
            "encoder_rad_s": m.encoder_rad_s,
            "force_n": m.force_n,
            "torque_nm": m.torque_nm,
            "latency_ms": m.latency_ticks,
            "seed": m.seed,
        });
        json["design_delay_ms"] = (self.cfg.gains.design_delay_s * 1e3).into();
        json["contact"] = if self.cfg.gains.contact_from_sensors {
            "sensors"
        } else {
            "reference"
        }
        .into();
        if let Some(rungs) = &self.ladder {
            json["weakest_ladder"] = rungs
                .iter()
                .map(|r| {
                    json!({
                        "scale": r.scale,
                        "walked": r.walked(),
                        "runs": r.runs.iter().map(|(n, p)| json!({
                            "scenario": n, "fell": p.fell, "fall_time_s": p.fall_time_s,
                            "max_tilt_deg": p.max_tilt_deg, "cop_err_max_m": p.cop_err_max_m,
                        })).collect::<Vec<_>>(),
                    })
                })
                .collect::<Vec<_>>()
                .into();
        }
    }

    /// The ladder in words (Markdown), for `weakest`; empty otherwise.
    pub fn ladder_markdown(&self) -> String {
        let Some(rungs) = &self.ladder else {
            return String::new();
        };
        let mut md = String::from(
            "\nThe weakest stabilizer: scales tried on the built-in scenarios (up to the first fall):",
        );
        for r in rungs {
            md += &format!(
                " × {}: {};",
                r.scale,
                if r.walked() {
                    "all walk".to_string()
                } else {
                    let (n, p) = &r.runs[r.runs.len() - 1];
                    format!("{n} fell at {:.2} s", p.fall_time_s.unwrap_or(f64::NAN))
                }
            );
        }
        md + "\n"
    }
}

/// The configuration of `robot` with the stabilizer scaled by `scale` and the servo damping
/// `kd` (`None`: the robot's).
pub fn weakened(robot: &Robot, scale: f64, kd: Option<f64>) -> PhysicsConfig {
    let mut cfg = PhysicsConfig::for_robot(robot);
    cfg.gains = Gains::default().scaled(scale);
    if let Some(kd) = kd {
        cfg.robot = cfg.robot.with_servo_damping(kd);
    }
    cfg
}

/// One rung of the ladder: the scale and the built-in scenarios run with it (up to the first
/// fall).
#[derive(Clone, Debug, PartialEq)]
pub struct Rung {
    /// The stabilizer scale.
    pub scale: f64,
    /// Scenario and report, in [`BUILT_IN`] order, up to the first that fell.
    pub runs: Vec<(String, PhysicsReport)>,
}

impl Rung {
    /// Every built-in scenario run without a fall (the ladder's criterion; the gait measures
    /// are the grid's).
    pub fn walked(&self) -> bool {
        self.runs.len() == BUILT_IN.len() && self.runs.iter().all(|(_, r)| !r.fell)
    }
}

/// Goes up [`LADDER`] with the servo damping `kd` until a scale with which no built-in
/// scenario falls; returns that scale (`None`: not even the full stabilizer did) and the rungs
/// tried. Errors: the engine failed.
pub fn weakest(robot: &Robot, kd: Option<f64>) -> Result<(Option<f64>, Vec<Rung>), String> {
    let mut rungs = Vec::new();
    for &scale in &LADDER {
        let cfg = weakened(robot, scale, kd);
        let mut rung = Rung {
            scale,
            runs: Vec::new(),
        };
        for name in BUILT_IN {
            let (_, trajectory, dt) = scenario_trajectory(name, robot)?;
            let r = run(&trajectory, dt, &cfg).map_err(|e| format!("{name}: {e}"))?;
            let fell = r.report.fell;
            rung.runs.push((name.to_string(), r.report));
            if fell {
                break;
            }
        }
        let walked = rung.walked();
        crate::errln!(
            "stabilizer scale {scale}: {}",
            if walked {
                "no built-in scenario falls".to_string()
            } else {
                format!("{} fell", rung.runs.last().map_or("?", |r| r.0.as_str()))
            }
        );
        rungs.push(rung);
        if walked {
            return Ok((Some(scale), rungs));
        }
    }
    Ok((None, rungs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_parse() {
        assert_eq!(parse_setting("full"), Ok(Setting::Scale(1.0)));
        assert_eq!(parse_setting("off"), Ok(Setting::Scale(0.0)));
        assert_eq!(parse_setting("weakest"), Ok(Setting::Weakest));
        assert_eq!(parse_setting("0.25"), Ok(Setting::Scale(0.25)));
        assert!(parse_setting("-1").is_err());
        assert!(parse_setting("weak").is_err());
        assert!(parse_setting("inf").is_err());
    }

    #[test]
    fn probe_records_its_settings() {
        let args = ProbeArgs {
            open_loop: false,
            stabilizer: Setting::Scale(0.3),
            servo_damping: Some(150.0),
            ..ProbeArgs::default()
        };
        let p = args.resolve(&Robot::hrp2()).unwrap();
        assert_eq!(p.cfg, weakened(&Robot::hrp2(), 0.3, Some(150.0)));
        let mut j = json!({});
        p.record(&mut j);
        assert_eq!(
            (
                &j["stabilizer"],
                &j["stabilizer_scale"],
                &j["servo_damping"]
            ),
            (&json!(true), &json!(0.3), &json!(150.0))
        );
        assert_eq!(
            (&j["sensors"]["ideal"], &j["contact"]),
            (&json!(true), &json!("sensors"))
        );
        assert!(p.cfg.gains.contact_from_sensors);
        // Noisy sensors with their latency replaced, the contact from the reference.
        let args = ProbeArgs {
            sensors: SensorModel::REALISTIC,
            latency_ms: Some(7),
            contact: Contact::Reference,
            ..ProbeArgs::default()
        };
        let noisy = args.resolve(&Robot::hrp2()).unwrap();
        assert!(!noisy.cfg.gains.contact_from_sensors);
        assert_eq!(noisy.cfg.sensors.latency_ticks, 7);
        assert_eq!(noisy.cfg.sensors.force_n, SensorModel::REALISTIC.force_n);
        let mut j = json!({});
        noisy.record(&mut j);
        assert_eq!(
            (&j["sensors"]["latency_ms"], &j["contact"]),
            (&json!(7), &json!("reference"))
        );
        assert_eq!(p.mode(), "stabilizer × 0.3, servo damping 150 N m s/rad");
        assert_eq!(
            noisy.mode(),
            "stabilizer × 1, servo damping 600 N m s/rad, noisy sensors 7 ms late, \
             contact from the reference, gains designed for 7 ms"
        );
        // The gains designed for the sensors' 7 ms (every feedback gain × 1 / 7), or for a
        // delay stated apart; the noise's seed recorded.
        let full = Gains::default();
        let k = noisy.cfg.gains.k_cog / full.k_cog;
        assert!((k - super::super::stabilizer::FULL_GAIN_DELAY_S / 0.007).abs() < 1e-12);
        assert_eq!(j["design_delay_ms"], json!(7.0));
        assert_eq!(j["sensors"]["seed"], json!(1));
        let stated = ProbeArgs {
            latency_ms: Some(7),
            design_delay_ms: Some(0.0),
            noise_seed: Some(9),
            ..ProbeArgs::default()
        }
        .resolve(&Robot::hrp2())
        .unwrap();
        assert_eq!(stated.cfg.gains.k_cog, full.k_cog);
        assert_eq!(stated.cfg.sensors.seed, 9);
        let open = ProbeArgs {
            open_loop: true,
            ..ProbeArgs::default()
        }
        .resolve(&Robot::hrp2())
        .unwrap();
        assert!(!open.cfg.gains.enabled);
        let mut j = json!({});
        open.record(&mut j);
        assert_eq!(j["stabilizer"], false);
        assert_eq!(j["servo_damping"], 600.0);
        assert!(open.ladder_markdown().is_empty());
    }

    #[test]
    fn scaling_weakens_every_feedback() {
        let g = Gains::default();
        let h = g.scaled(0.5);
        assert_eq!(h.k_dcm, 0.5 * g.k_dcm);
        assert_eq!(h.k_cog, 0.5 * g.k_cog);
        assert_eq!(h.k_force, 0.5 * g.k_force);
        assert_eq!(h.damping, 2.0 * g.damping);
        assert_eq!((h.cog_limit_m, h.enabled), (g.cog_limit_m, true));
        assert_eq!(g.scaled(1.0), g);
        let off = g.scaled(0.0);
        assert_eq!((off.k_dcm, off.k_cog, off.k_force), (0.0, 0.0, 0.0));
        assert!(off.damping.is_infinite());
        let cfg = weakened(&Robot::hrp2(), 0.3, Some(150.0));
        assert_eq!(cfg.robot.servo()[1], 150.0);
        assert_eq!(cfg.gains, g.scaled(0.3));
    }
}
