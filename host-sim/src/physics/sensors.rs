//! What the stabilizer's sensors make of the engine's exact values: noise, bias and latency
//! (`--sensors ideal|realistic`, `--latency-ms N` on every engine subcommand).
//!
//! Each reading of [`super::model::sensor`]'s layout is delayed by `latency` physics ticks
//! (1 ms each; the stabilizer then acts on the state that many milliseconds old), then every
//! value gets zero-mean Gaussian noise of its standard deviation `σ`, white from tick to tick,
//! except the IMU's attitude: an estimator's output is smooth, so its error is a first-order
//! Gauss–Markov process (`e_{k+1} = a e_k + σ √(1 − a²) n_k`, `a = e^{−Δt/τ}`,
//! τ = [`ATTITUDE_TAU_S`]: standard deviation `σ`, wandering over about τ), plus a constant
//! bias (a rotation about the trunk's x and y axes: a mis-mounted or drifted estimate). The
//! noise is seeded ([`SensorModel::seed`]): a run is repeatable.
//!
//! [`SensorModel::IDEAL`], the default, is the engine's values as they are (the figures of the
//! book are measured so unless they say otherwise). [`SensorModel::REALISTIC`] states a humanoid
//! of HRP-2's class (assumed, typical values, not HRP-2's data sheets):
//!
//! | sensor | σ | bias | source of the assumption |
//! |---|---|---|---|
//! | IMU attitude (the estimator's output) | 0.002 rad (0.11°), correlated over 0.5 s | 0.005 rad about y (0.29°), 0.002 rad about x | a MEMS IMU with a complementary filter |
//! | gyro | 0.005 rad/s | – | MEMS gyro noise over a 1 kHz band |
//! | accelerometer | 0.05 m/s² | – | MEMS accelerometer |
//! | joint encoders | 1e-4 rad; velocities 0.01 rad/s | – | 16-bit absolute encoders on the joint side |
//! | ankle force / torque | 2 N / 0.2 N m | – | a 6-axis strain-gauge sensor's noise floor |
//! | latency | 2 ms | | the bus and the estimator |

use super::model::sensor;

/// Correlation time of the attitude estimate's error \[s\].
pub const ATTITUDE_TAU_S: f64 = 0.5;

/// Noise, bias and latency of the sensors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorModel {
    /// σ of the attitude (each axis of a small rotation) \[rad\].
    pub attitude_rad: f64,
    /// Bias of the attitude about the trunk's x and y axes \[rad\].
    pub attitude_bias_rad: [f64; 2],
    /// σ of the gyro \[rad/s\].
    pub gyro_rad_s: f64,
    /// σ of the accelerometer \[m/s²\].
    pub accel_m_s2: f64,
    /// σ of the joint angles \[rad\].
    pub encoder_rad: f64,
    /// σ of the joint velocities \[rad/s\].
    pub encoder_rad_s: f64,
    /// σ of the ankle forces \[N\].
    pub force_n: f64,
    /// σ of the ankle torques \[N m\].
    pub torque_nm: f64,
    /// Latency \[physics ticks of 1 ms\].
    pub latency_ticks: usize,
    /// The noise's seed.
    pub seed: u64,
}

impl SensorModel {
    /// The engine's values as they are.
    pub const IDEAL: SensorModel = SensorModel {
        attitude_rad: 0.0,
        attitude_bias_rad: [0.0; 2],
        gyro_rad_s: 0.0,
        accel_m_s2: 0.0,
        encoder_rad: 0.0,
        encoder_rad_s: 0.0,
        force_n: 0.0,
        torque_nm: 0.0,
        latency_ticks: 0,
        seed: 1,
    };

    /// A humanoid of HRP-2's class (the module's table).
    pub const REALISTIC: SensorModel = SensorModel {
        attitude_rad: 0.002,
        attitude_bias_rad: [0.002, 0.005],
        gyro_rad_s: 0.005,
        accel_m_s2: 0.05,
        encoder_rad: 1e-4,
        encoder_rad_s: 0.01,
        force_n: 2.0,
        torque_nm: 0.2,
        latency_ticks: 2,
        seed: 1,
    };

    /// Whether the readings are the engine's values.
    pub fn is_ideal(&self) -> bool {
        *self
            == Self {
                seed: self.seed,
                ..Self::IDEAL
            }
    }
}

impl Default for SensorModel {
    fn default() -> Self {
        Self::IDEAL
    }
}

/// Parses `--sensors`: `ideal` or `realistic`.
pub fn parse(s: &str) -> Result<SensorModel, String> {
    match s {
        "ideal" => Ok(SensorModel::IDEAL),
        "realistic" => Ok(SensorModel::REALISTIC),
        _ => Err(format!("--sensors {s:?}: expected ideal or realistic")),
    }
}

/// The sensors of one run: the delay line and the noise's generator.
#[derive(Clone, Debug)]
pub struct Sensors {
    model: SensorModel,
    past: std::collections::VecDeque<Vec<f64>>,
    state: u64,
    out: Vec<f64>,
    /// The attitude estimate's wandering error (rotation vector) \[rad\].
    attitude: [f64; 3],
}

/// The product of two quaternions (w, x, y, z).
fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The quaternion of the small rotation vector `v` (exact for any angle).
fn quat_of(v: [f64; 3]) -> [f64; 4] {
    let a = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if a == 0.0 {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let (s, c) = (0.5 * a).sin_cos();
    [c, s * v[0] / a, s * v[1] / a, s * v[2] / a]
}

impl Sensors {
    /// The sensors of a run.
    pub fn new(model: SensorModel) -> Self {
        Self {
            model,
            past: std::collections::VecDeque::new(),
            state: model.seed.max(1),
            out: Vec::new(),
            attitude: [0.0; 3],
        }
    }

    /// A standard normal number (xorshift64*, Box–Muller).
    fn normal(&mut self) -> f64 {
        let mut next = || {
            self.state ^= self.state >> 12;
            self.state ^= self.state << 25;
            self.state ^= self.state >> 27;
            let x = self.state.wrapping_mul(0x2545_F491_4F6C_DD1D);
            ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (u, v) = (next(), next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    /// What the stabilizer reads this tick, given the engine's exact values `exact`.
    pub fn read(&mut self, exact: &[f64]) -> &[f64] {
        let m = self.model;
        if m.is_ideal() {
            self.out.clear();
            self.out.extend_from_slice(exact);
            return &self.out;
        }
        self.past.push_back(exact.to_vec());
        while self.past.len() > m.latency_ticks + 1 {
            self.past.pop_front();
        }
        let mut s = self.past.front().cloned().unwrap_or_else(|| exact.to_vec());
        // Attitude: the bias and the wandering error, small rotations about the trunk's axes.
        let a = (-1e-3 / ATTITUDE_TAU_S).exp();
        let kick = m.attitude_rad * (1.0 - a * a).sqrt();
        for i in 0..3 {
            self.attitude[i] = a * self.attitude[i] + kick * self.normal();
        }
        let v = [
            m.attitude_bias_rad[0] + self.attitude[0],
            m.attitude_bias_rad[1] + self.attitude[1],
            self.attitude[2],
        ];
        let q0 = [
            s[sensor::QUAT],
            s[sensor::QUAT + 1],
            s[sensor::QUAT + 2],
            s[sensor::QUAT + 3],
        ];
        let q = qmul(q0, quat_of(v));
        s[sensor::QUAT..sensor::QUAT + 4].copy_from_slice(&q);
        let bands = [
            (sensor::GYRO, 3, m.gyro_rad_s),
            (sensor::ACC, 3, m.accel_m_s2),
            (sensor::QPOS, 12, m.encoder_rad),
            (sensor::QVEL, 12, m.encoder_rad_s),
        ];
        for (at, n, sigma) in bands {
            for x in &mut s[at..at + n] {
                *x += sigma * self.normal();
            }
        }
        for k in 0..2 {
            let o = sensor::FT + 6 * k;
            for i in 0..6 {
                let sigma = if i < 3 { m.force_n } else { m.torque_nm };
                s[o + i] += sigma * self.normal();
            }
        }
        self.out = s;
        &self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(t: f64) -> Vec<f64> {
        let mut s = vec![t; sensor::LEN];
        s[sensor::QUAT..sensor::QUAT + 4].copy_from_slice(&[1.0, 0.0, 0.0, 0.0]);
        s
    }

    #[test]
    fn ideal_is_the_engine() {
        let mut s = Sensors::new(SensorModel::IDEAL);
        for t in [0.0, 1.0, 2.0] {
            assert_eq!(s.read(&reading(t)), reading(t).as_slice());
        }
    }

    #[test]
    fn realistic_is_late_noisy_and_biased_as_stated() {
        let mut m = SensorModel::REALISTIC;
        m.latency_ticks = 3;
        let mut s = Sensors::new(m);
        let n: usize = 200_000;
        let (mut sum, mut sum2, mut pitch) = (0.0, 0.0, 0.0);
        for k in 0..n {
            let r = s.read(&reading(k as f64)).to_vec();
            // Three ticks late (the first readings repeat the first one).
            let e = r[sensor::FT] - (k.saturating_sub(3)) as f64;
            sum += e;
            sum2 += e * e;
            // The attitude's rotation about y: 2 asin(q_y) for a small rotation.
            pitch += 2.0 * r[sensor::QUAT + 2].asin();
        }
        let mean = sum / n as f64;
        let sd = (sum2 / n as f64 - mean * mean).sqrt();
        assert!(mean.abs() < 0.02, "{mean}");
        assert!((sd - m.force_n).abs() < 0.02, "{sd}");
        // The wandering error averages out: over 200 s its mean's standard error is
        // σ √(2τ/T) = 1.4e-4 rad.
        let bias = pitch / n as f64;
        assert!((bias - m.attitude_bias_rad[1]).abs() < 5e-4, "{bias}");
        // The same seed, the same readings.
        let mut a = Sensors::new(m);
        let mut b = Sensors::new(m);
        assert_eq!(
            a.read(&reading(1.0)).to_vec(),
            b.read(&reading(1.0)).to_vec()
        );
    }
}
