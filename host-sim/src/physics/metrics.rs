//! What "fell" and "tracked" mean: the definitions the physics command reports.
//!
//! # Fall
//!
//! The robot has **fallen** at the first engine sample (1 ms) where one of these holds:
//!
//! * **tilt**: the angle between the waist's z axis and the world's vertical exceeds
//!   [`FALL_TILT_DEG`] = 20°. With the waist quaternion `(w, x, y, z)` the waist z axis has
//!   the world z component `1 − 2 (x² + y²)`, so `tilt = acos(1 − 2 (x² + y²))`;
//! * **contact**: a geom other than the two soles touches the floor (a knee, a hip, the trunk);
//! * **height**: the waist is more than [`FALL_DROP_M`] = 0.15 m below its reference height.
//!
//! # When a fall counts
//!
//! A fall counts for the walk (`fell`) while the reference moves, and until [`SETTLE_AFTER_S`]
//! = 1 s after it stops: the reference **stops** at the last tick at which it differs from
//! the tick before ([`reference_stop_s`]; every engine command's trajectory ends standing,
//! both feet down and the stop window finished, so that is where the robot stands still).
//! A fall later than that is reported apart (`fell_after_end`, with its time and cause),
//! never dropped, and is not the walk's fall: by then the robot has stood on a still reference
//! for 1 s. Why 1 s: it is 3.5 time constants of the pendulum (`√(z_c/g)` = 0.29 s for
//! HRP-2's 0.814 m), so a divergent component of motion the walk left uncorrected has grown
//! e^3.5 ≈ 33-fold and tipped the robot over within it; it is the standing time after the walk
//! that the engine runs by default ([`super::PhysicsConfig::tail_s`]); and it is the window
//! the closed-loop runs of the push map use after the node stands ([`super::closed_loop`]).
//! The same rule ([`fall_counts`]) judges every engine run.
//!
//! # Tracking
//!
//! The measured **centre of pressure** (CoP) is that of all floor contact forces of the engine
//! (`p = Σ f_z,i p_i / Σ f_z,i` over the contact points `p_i` with normal forces `f_z,i`).
//! It and the reference ZMP are both smoothed by the same **50 ms moving average** (the mean
//! of the last [`COP_WINDOW`] samples, so the comparison carries no filter lag), and the
//! tracking error at each sample is the horizontal distance between the two; the report gives
//! its **mean** and its **worst** value over the samples after the first full window until
//! the fall (or the end). Samples without floor contact are skipped.
//!
//! The **COG drift** is the largest horizontal distance between the whole-body COG (forward
//! kinematics of the engine's true waist pose and joint angles) and the reference COG; the
//! **foot drift** the largest distance between a true sole centre and its reference while
//! that foot is in support.

/// Tilt of the waist beyond which the robot has fallen \[deg\].
pub const FALL_TILT_DEG: f64 = 20.0;
/// Drop of the waist below its reference height beyond which the robot has fallen \[m\].
pub const FALL_DROP_M: f64 = 0.15;
/// Samples (of 1 ms) of the CoP moving average: 50 ms.
pub const COP_WINDOW: usize = 50;
/// How long after the reference stops moving a fall still counts as the walk's \[s\] (see
/// "When a fall counts" above for the reason of the value).
pub const SETTLE_AFTER_S: f64 = 1.0;

/// The trajectory time at which the references (one every `dt`) stop moving: that of the last
/// one that differs from the one before it (0 for a trajectory that never moves) \[s\].
pub fn reference_stop_s<T: PartialEq>(trajectory: &[T], dt: f64) -> f64 {
    let last_change = (1..trajectory.len())
        .rev()
        .find(|&k| trajectory[k] != trajectory[k - 1])
        .unwrap_or(0);
    last_change as f64 * dt
}

/// Whether a fall at trajectory time `fall_s` counts as the walk's when the reference stopped
/// at `stop_s`: at most [`SETTLE_AFTER_S`] after it (otherwise it is a fall after the end).
pub fn fall_counts(fall_s: f64, stop_s: f64) -> bool {
    fall_s <= stop_s + SETTLE_AFTER_S + 1e-9
}

/// Why the robot was judged fallen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FallCause {
    /// Waist tilt above [`FALL_TILT_DEG`].
    Tilt,
    /// A contact other than the soles.
    Contact,
    /// Waist more than [`FALL_DROP_M`] below the reference.
    Height,
}

impl FallCause {
    /// A short name for the reports.
    pub fn name(self) -> &'static str {
        match self {
            FallCause::Tilt => "tilt",
            FallCause::Contact => "non-sole contact",
            FallCause::Height => "waist below reference",
        }
    }
}

/// The tilt of a body from its orientation quaternion (w, x, y, z) \[deg\].
pub fn tilt_deg(q: [f64; 4]) -> f64 {
    let n2 = q.iter().map(|v| v * v).sum::<f64>();
    let zz = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]) / n2.max(1e-300);
    zz.clamp(-1.0, 1.0).acos().to_degrees()
}

/// The fall test of one sample.
pub fn fall_check(
    base_quat: [f64; 4],
    base_z: f64,
    reference_z: f64,
    other_contact: bool,
) -> Option<FallCause> {
    if tilt_deg(base_quat) > FALL_TILT_DEG {
        Some(FallCause::Tilt)
    } else if other_contact {
        Some(FallCause::Contact)
    } else if base_z < reference_z - FALL_DROP_M {
        Some(FallCause::Height)
    } else {
        None
    }
}

/// Moving average of 2-vectors over a fixed window.
#[derive(Clone, Debug)]
pub struct MovingAverage {
    buf: Vec<[f64; 2]>,
    next: usize,
    full: bool,
    sum: [f64; 2],
}

impl MovingAverage {
    /// A window of `n` samples (at least 1).
    pub fn new(n: usize) -> Self {
        Self {
            buf: vec![[0.0; 2]; n.max(1)],
            next: 0,
            full: false,
            sum: [0.0; 2],
        }
    }

    /// Adds a sample; the mean of the window once it is full.
    pub fn push(&mut self, v: [f64; 2]) -> Option<[f64; 2]> {
        let old = self.buf[self.next];
        self.sum = [self.sum[0] + v[0] - old[0], self.sum[1] + v[1] - old[1]];
        self.buf[self.next] = v;
        self.next = (self.next + 1) % self.buf.len();
        if self.next == 0 {
            self.full = true;
            // Recompute to keep the rounding from accumulating.
            self.sum = self
                .buf
                .iter()
                .fold([0.0; 2], |s, b| [s[0] + b[0], s[1] + b[1]]);
        }
        let n = self.buf.len() as f64;
        self.full.then(|| [self.sum[0] / n, self.sum[1] / n])
    }
}

/// The CoP tracking statistics (see the module documentation).
#[derive(Clone, Debug)]
pub struct Tracking {
    cop: MovingAverage,
    zmp: MovingAverage,
    n: usize,
    sum: f64,
    /// Worst error so far \[m\].
    pub max: f64,
    /// Time of the worst error \[s\].
    pub max_t: f64,
}

impl Default for Tracking {
    fn default() -> Self {
        Self {
            cop: MovingAverage::new(COP_WINDOW),
            zmp: MovingAverage::new(COP_WINDOW),
            n: 0,
            sum: 0.0,
            max: 0.0,
            max_t: 0.0,
        }
    }
}

impl Tracking {
    /// Adds one sample: the measured CoP (NaN when airborne) and the reference ZMP at `t`.
    /// Returns the current error, if any.
    pub fn push(&mut self, t: f64, cop: [f64; 2], zmp: [f64; 2]) -> Option<f64> {
        if !(cop[0].is_finite() && cop[1].is_finite()) {
            return None;
        }
        let c = self.cop.push(cop);
        let z = self.zmp.push(zmp);
        let (c, z) = (c?, z?);
        let e = (c[0] - z[0]).hypot(c[1] - z[1]);
        self.n += 1;
        self.sum += e;
        if e > self.max {
            self.max = e;
            self.max_t = t;
        }
        Some(e)
    }

    /// Mean error \[m\] (0 with no sample).
    pub fn mean(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.sum / self.n as f64
        }
    }

    /// Number of samples compared.
    pub fn samples(&self) -> usize {
        self.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quat_about_x(deg: f64) -> [f64; 4] {
        let h = deg.to_radians() / 2.0;
        [h.cos(), h.sin(), 0.0, 0.0]
    }

    #[test]
    fn tilt_of_rotations() {
        assert!(tilt_deg([1.0, 0.0, 0.0, 0.0]).abs() < 1e-12);
        assert!((tilt_deg(quat_about_x(12.5)) - 12.5).abs() < 1e-9);
        // About y and unnormalised.
        let h = 30f64.to_radians() / 2.0;
        assert!((tilt_deg([2.0 * h.cos(), 0.0, 2.0 * h.sin(), 0.0]) - 30.0).abs() < 1e-9);
        // Yaw is no tilt.
        assert!(tilt_deg([h.cos(), 0.0, 0.0, h.sin()]).abs() < 1e-6);
    }

    #[test]
    fn fall_thresholds() {
        let up = [1.0, 0.0, 0.0, 0.0];
        assert_eq!(fall_check(up, 0.65, 0.65, false), None);
        assert_eq!(fall_check(quat_about_x(19.9), 0.65, 0.65, false), None);
        assert_eq!(
            fall_check(quat_about_x(20.1), 0.65, 0.65, false),
            Some(FallCause::Tilt)
        );
        assert_eq!(fall_check(up, 0.65, 0.65, true), Some(FallCause::Contact));
        assert_eq!(fall_check(up, 0.51, 0.65, false), None);
        assert_eq!(fall_check(up, 0.49, 0.65, false), Some(FallCause::Height));
    }

    /// The reference stops at its last change; a fall within 1 s of that counts, a later
    /// one does not (a synthetic run: a walk that stands still from 2.0 s, held to 5.0 s).
    #[test]
    fn a_fall_counts_until_the_settle_time_after_the_reference_stops() {
        let dt = 0.005;
        // Moving (a ramp) for 400 ticks, then the same value to the end.
        let series: Vec<f64> = (0..1000).map(|k| (k.min(400) as f64) * 1e-3).collect();
        let stop = reference_stop_s(&series, dt);
        assert!((stop - 2.0).abs() < 1e-12, "{stop}");
        assert_eq!(reference_stop_s(&[1.0, 1.0, 1.0], dt), 0.0);
        assert_eq!(reference_stop_s::<f64>(&[], dt), 0.0);
        assert!(fall_counts(0.5, stop));
        assert!(fall_counts(2.5, stop));
        assert!(fall_counts(stop + SETTLE_AFTER_S, stop));
        assert!(!fall_counts(stop + SETTLE_AFTER_S + 0.001, stop));
        assert!(!fall_counts(4.9, stop));
    }

    #[test]
    fn moving_average_window() {
        let mut m = MovingAverage::new(4);
        assert_eq!(m.push([1.0, 0.0]), None);
        assert_eq!(m.push([2.0, 0.0]), None);
        assert_eq!(m.push([3.0, 0.0]), None);
        assert_eq!(m.push([4.0, 8.0]), Some([2.5, 2.0]));
        assert_eq!(m.push([5.0, 0.0]), Some([3.5, 2.0]));
    }

    #[test]
    fn tracking_constant_offset_and_lag_free() {
        let mut t = Tracking::default();
        // A ramp measured exactly: no error although the average lags the ramp.
        for k in 0..200 {
            let x = k as f64 * 1e-3;
            t.push(k as f64 * 1e-3, [x, 0.0], [x, 0.0]);
        }
        assert!(t.max < 1e-12 && t.samples() == 151);
        // A 1 cm offset in y.
        let mut t = Tracking::default();
        for k in 0..100 {
            t.push(k as f64 * 1e-3, [0.0, 0.01], [0.0, 0.0]);
        }
        assert!((t.mean() - 0.01).abs() < 1e-12 && (t.max - 0.01).abs() < 1e-12);
        // Airborne samples are skipped.
        assert_eq!(t.push(0.2, [f64::NAN, 0.0], [0.0, 0.0]), None);
        assert_eq!(t.samples(), 51);
    }

    #[test]
    fn tracking_worst_case_is_the_filtered_peak() {
        let mut t = Tracking::default();
        // A 1 ms spike of 0.5 m is 1 cm after the 50 ms average.
        for k in 0..120 {
            let y = if k == 80 { 0.5 } else { 0.0 };
            t.push(k as f64 * 1e-3, [0.0, y], [0.0, 0.0]);
        }
        assert!((t.max - 0.01).abs() < 1e-12, "{}", t.max);
        assert!((t.max_t - 0.08).abs() < 1e-12);
    }
}
