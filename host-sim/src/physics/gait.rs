//! What "walked" means: the gait's quality besides the fall, from the engine's ground truth.
//!
//! A robot can stay up and still not walk: its feet slide over the floor, it hops, it stands
//! on a foot that should be in the air, or it puts its feet elsewhere than planned. Every engine
//! run measures these four, each against a stated bound, and **walked** means no fall
//! ([`super::metrics`]) and all four within their bounds ([`GaitQuality::walked`]):
//!
//! | measure | definition | bound |
//! |---|---|---|
//! | **slip** | the largest horizontal displacement of a sole centre, and the largest turn of the sole about the vertical, while the reference has it on the floor, from where it was when it first touched the floor in that support (with [`FLIGHT_SHARE`] of the weight: a foot that skids under a light load is slipping, and so is one that hops and slides, or turns in place) | [`SLIP_MAX_M`] = 10 mm, [`SLIP_YAW_MAX_RAD`] = 0.05 rad |
//! | **flight** | the time with no floor contact at all (total normal force below [`FLIGHT_SHARE`] of the weight): the references of a walk never plan a flight | longest interval [`FLIGHT_MAX_S`] = 5 ms |
//! | **CoP outside the support polygon** | the engine's CoP (1 ms, all floor contacts) more than [`COP_MARGIN_M`] = 5 mm outside the planned support polygon (the convex hull of the sole rectangles the reference has on the floor) | longest interval [`COP_OUTSIDE_MAX_S`] = 50 ms |
//! | **landing error** | at each landing (the first tick at which the reference has the foot on the floor and its sole carries load, after a swing), the horizontal distance of the sole centre from the reference's, and the sole's heading from the reference's | [`LANDING_MAX_M`] = 20 mm, [`LANDING_YAW_MAX_RAD`] = 0.05 rad |
//!
//! Why these values: HRP-2's built-in walks with ideal sensors slip at most 2.0 mm, leave the
//! floor for at most one physics tick, keep the CoP in the planned polygon but for a tick and
//! land within 2.2 mm (the book's physics page gives the measurements); a
//! sole sliding a centimetre, a hop of more than a few physics ticks, or a landing two
//! centimetres off are what a roboticist reads as a slip, a flight and a misplaced step. The
//! engine's CoP cannot leave the soles it touches, so the polygon is the *planned* one: the
//! CoP outside it means the weight is on a foot that should be in the air or on a sole that
//! is not where it should be.
//!
//! Samples before the trajectory (the settle) are not judged.

use crate::robot::model::Pose;
use planner_core::gait::FootPose;

/// Share of the weight above which a sole carries load (support, landing).
pub const LOAD_SHARE: f64 = 0.1;
/// Share of the weight below which the robot has no floor contact.
pub const FLIGHT_SHARE: f64 = 0.01;
/// Largest slip of a supporting sole \[m\].
pub const SLIP_MAX_M: f64 = 0.010;
/// Longest interval without floor contact \[s\].
pub const FLIGHT_MAX_S: f64 = 0.005;
/// How far outside the planned support polygon the CoP counts as outside \[m\].
pub const COP_MARGIN_M: f64 = 0.005;
/// Longest interval with the CoP outside the planned support polygon \[s\].
pub const COP_OUTSIDE_MAX_S: f64 = 0.050;
/// Largest landing error \[m\].
pub const LANDING_MAX_M: f64 = 0.020;
/// Largest turn of a supporting sole about the vertical \[rad\] (about 3°).
pub const SLIP_YAW_MAX_RAD: f64 = 0.05;
/// Largest heading error of a landing \[rad\].
pub const LANDING_YAW_MAX_RAD: f64 = 0.05;

/// The heading of a pose (its x axis about the vertical) \[rad\].
pub fn yaw_of(p: &Pose) -> f64 {
    p.r[1][0].atan2(p.r[0][0])
}

/// `a − b` wrapped into (−π, π] \[rad\].
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d - std::f64::consts::TAU
    } else {
        d
    }
}

/// The gait measures of a run (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GaitQuality {
    /// Largest slip of a supporting sole \[m\].
    pub slip_max_m: f64,
    /// Largest turn of a supporting sole about the vertical \[rad\].
    pub slip_yaw_max_rad: f64,
    /// Time without floor contact, in all \[s\].
    pub flight_s: f64,
    /// Longest interval without floor contact \[s\].
    pub flight_max_s: f64,
    /// Time with the CoP outside the planned support polygon, in all \[s\].
    pub cop_outside_s: f64,
    /// Longest such interval \[s\].
    pub cop_outside_max_s: f64,
    /// Farthest the CoP went outside the planned support polygon \[m\].
    pub cop_outside_max_m: f64,
    /// Largest landing error \[m\].
    pub landing_err_max_m: f64,
    /// Largest heading error of a landing \[rad\].
    pub landing_yaw_err_max_rad: f64,
    /// Landings measured.
    pub landings: usize,
}

impl GaitQuality {
    /// The measures beyond their bounds, by name (empty: the gait is within every bound).
    pub fn violations(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.slipped() {
            v.push("slip");
        }
        if self.flight_max_s > FLIGHT_MAX_S + 1e-9 {
            v.push("flight");
        }
        if self.cop_outside_max_s > COP_OUTSIDE_MAX_S + 1e-9 {
            v.push("CoP outside the support polygon");
        }
        if self.landed_off() {
            v.push("landing error");
        }
        v
    }

    /// Slip beyond its bounds (distance or turn).
    pub fn slipped(&self) -> bool {
        self.slip_max_m > SLIP_MAX_M || self.slip_yaw_max_rad > SLIP_YAW_MAX_RAD
    }

    /// A landing beyond its bounds (distance or heading).
    pub fn landed_off(&self) -> bool {
        self.landing_err_max_m > LANDING_MAX_M || self.landing_yaw_err_max_rad > LANDING_YAW_MAX_RAD
    }

    /// Whether the gait is within every bound.
    pub fn within_bounds(&self) -> bool {
        self.violations().is_empty()
    }

    /// The measures as every engine command's JSON gives them: `slip_max_m`,
    /// `slip_yaw_max_rad`, `flight_s`, `flight_max_s`, `cop_outside_s`, `cop_outside_max_s`,
    /// `cop_outside_max_m`, `landing_err_max_m`, `landing_yaw_err_max_rad`, `landings`, and `gait_violations` (the names of the measures
    /// beyond their bounds).
    pub fn fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        use serde_json::json;
        vec![
            ("slip_max_m", json!(self.slip_max_m)),
            ("slip_yaw_max_rad", json!(self.slip_yaw_max_rad)),
            ("flight_s", json!(self.flight_s)),
            ("flight_max_s", json!(self.flight_max_s)),
            ("cop_outside_s", json!(self.cop_outside_s)),
            ("cop_outside_max_s", json!(self.cop_outside_max_s)),
            ("cop_outside_max_m", json!(self.cop_outside_max_m)),
            ("landing_err_max_m", json!(self.landing_err_max_m)),
            (
                "landing_yaw_err_max_rad",
                json!(self.landing_yaw_err_max_rad),
            ),
            ("landings", json!(self.landings)),
            ("gait_violations", json!(self.violations())),
        ]
    }

    /// The bounds, for the JSON (`gait_bounds`).
    pub fn bounds_json() -> serde_json::Value {
        serde_json::json!({
            "slip_max_m": SLIP_MAX_M,
            "flight_max_s": FLIGHT_MAX_S,
            "cop_margin_m": COP_MARGIN_M,
            "cop_outside_max_s": COP_OUTSIDE_MAX_S,
            "landing_err_max_m": LANDING_MAX_M,
            "slip_yaw_max_rad": SLIP_YAW_MAX_RAD,
            "landing_yaw_err_max_rad": LANDING_YAW_MAX_RAD,
            "load_share": LOAD_SHARE,
            "flight_share": FLIGHT_SHARE,
        })
    }
}

/// One engine sample as the monitor reads it.
#[derive(Clone, Copy, Debug)]
pub struct GaitSample {
    /// Physics tick \[s\].
    pub dt: f64,
    /// The reference's feet at the sample.
    pub feet_ref: [FootPose<f64>; 2],
    /// The true sole poses (forward kinematics of the engine's state).
    pub soles: [Pose; 2],
    /// The floor's normal force on each sole \[N\].
    pub sole_force: [f64; 2],
    /// The total floor normal force \[N\].
    pub normal_force: f64,
    /// The engine's CoP (NaN without contact) \[m\].
    pub cop: [f64; 2],
}

/// Accumulates [`GaitQuality`] sample by sample.
#[derive(Clone, Debug)]
pub struct GaitMonitor {
    weight: f64,
    sole_half: [f64; 2],
    q: GaitQuality,
    anchor: [Option<[f64; 3]>; 2],
    swung: [bool; 2],
    flight_run: f64,
    outside_run: f64,
}

impl GaitMonitor {
    /// A monitor for a robot of weight `weight` \[N\] with soles of half-extents `sole_half`
    /// (length, width) \[m\].
    pub fn new(weight: f64, sole_half: [f64; 2]) -> Self {
        Self {
            weight,
            sole_half,
            q: GaitQuality::default(),
            anchor: [None; 2],
            swung: [false; 2],
            flight_run: 0.0,
            outside_run: 0.0,
        }
    }

    /// The measures so far.
    pub fn quality(&self) -> GaitQuality {
        self.q
    }

    /// Adds one sample.
    pub fn push(&mut self, s: &GaitSample) {
        let load = LOAD_SHARE * self.weight;
        let touch = FLIGHT_SHARE * self.weight;
        for k in 0..2 {
            let on_floor = s.feet_ref[k].z == 0.0;
            let p = [s.soles[k].p[0], s.soles[k].p[1]];
            let yaw = yaw_of(&s.soles[k]);
            if !on_floor {
                self.swung[k] = true;
            }
            let loaded = s.sole_force[k] > load;
            if !on_floor {
                self.anchor[k] = None;
                continue;
            }
            if loaded && self.swung[k] {
                self.swung[k] = false;
                let r = &s.feet_ref[k];
                let e = (p[0] - r.x).hypot(p[1] - r.y);
                self.q.landing_err_max_m = self.q.landing_err_max_m.max(e);
                let ey = angle_diff(yaw, r.yaw).abs();
                self.q.landing_yaw_err_max_rad = self.q.landing_yaw_err_max_rad.max(ey);
                self.q.landings += 1;
            }
            if s.sole_force[k] > touch && self.anchor[k].is_none() {
                self.anchor[k] = Some([p[0], p[1], yaw]);
            }
            if let Some(a) = self.anchor[k] {
                let d = (p[0] - a[0]).hypot(p[1] - a[1]);
                self.q.slip_max_m = self.q.slip_max_m.max(d);
                let t = angle_diff(yaw, a[2]).abs();
                self.q.slip_yaw_max_rad = self.q.slip_yaw_max_rad.max(t);
            }
        }
        if s.normal_force < FLIGHT_SHARE * self.weight {
            self.q.flight_s += s.dt;
            self.flight_run += s.dt;
            self.q.flight_max_s = self.q.flight_max_s.max(self.flight_run);
        } else {
            self.flight_run = 0.0;
        }
        let d = if s.cop[0].is_finite() && s.cop[1].is_finite() {
            let mut corners = Vec::with_capacity(8);
            for f in s.feet_ref.iter().filter(|f| f.z == 0.0) {
                corners.extend(sole_corners(f, self.sole_half));
            }
            outside_distance(s.cop, &corners)
        } else {
            0.0
        };
        self.q.cop_outside_max_m = self.q.cop_outside_max_m.max(d);
        if d > COP_MARGIN_M {
            self.q.cop_outside_s += s.dt;
            self.outside_run += s.dt;
            self.q.cop_outside_max_s = self.q.cop_outside_max_s.max(self.outside_run);
        } else {
            self.outside_run = 0.0;
        }
    }
}

/// The four corners of a sole rectangle of half-extents `half` at the foot pose `f`.
pub fn sole_corners(f: &FootPose<f64>, half: [f64; 2]) -> [[f64; 2]; 4] {
    let (s, c) = f.yaw.sin_cos();
    let at = |lx: f64, ly: f64| [f.x + c * lx - s * ly, f.y + s * lx + c * ly];
    [
        at(half[0], half[1]),
        at(-half[0], half[1]),
        at(-half[0], -half[1]),
        at(half[0], -half[1]),
    ]
}

fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// The convex hull of `points`, counter-clockwise (the monotone chain).
pub fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// How far `p` lies outside the convex hull of `points` \[m\] (0 inside; infinite with no
/// points).
pub fn outside_distance(p: [f64; 2], points: &[[f64; 2]]) -> f64 {
    let hull = convex_hull(points);
    let n = hull.len();
    if n == 0 {
        return f64::INFINITY;
    }
    let seg = |a: [f64; 2], b: [f64; 2]| {
        let ab = [b[0] - a[0], b[1] - a[1]];
        let l2 = ab[0] * ab[0] + ab[1] * ab[1];
        let t = if l2 > 0.0 {
            (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p[0] - a[0] - t * ab[0]).hypot(p[1] - a[1] - t * ab[1])
    };
    if n < 3 {
        return seg(hull[0], hull[n - 1]);
    }
    let inside = (0..n).all(|i| cross(hull[i], hull[(i + 1) % n], p) >= 0.0);
    if inside {
        return 0.0;
    }
    (0..n)
        .map(|i| seg(hull[i], hull[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn foot(x: f64, y: f64, z: f64, yaw: f64) -> FootPose<f64> {
        FootPose { x, y, z, yaw }
    }

    fn pose(x: f64, y: f64) -> Pose {
        Pose::upright(x, y, 0.0, 0.0)
    }

    #[test]
    fn distance_outside_the_hull_of_two_soles() {
        let half = [0.12, 0.07];
        let mut c = sole_corners(&foot(0.0, 0.1, 0.0, 0.0), half).to_vec();
        c.extend(sole_corners(&foot(0.2, -0.1, 0.0, 0.0), half));
        // Between the soles (inside the hull, outside both rectangles).
        assert_eq!(outside_distance([0.1, 0.0], &c), 0.0);
        // 3 cm ahead of the front sole's toe.
        assert!((outside_distance([0.35, -0.1], &c) - 0.03).abs() < 1e-12);
        // A rotated sole: 90° yaw, the long side along y.
        let r = sole_corners(&foot(0.0, 0.0, 0.0, std::f64::consts::FRAC_PI_2), half);
        assert_eq!(outside_distance([0.0, 0.11], &r), 0.0);
        assert!((outside_distance([0.1, 0.0], &r) - 0.03).abs() < 1e-12);
        assert!(outside_distance([0.0, 0.0], &[]).is_infinite());
    }

    fn sample(soles: [Pose; 2], feet: [FootPose<f64>; 2]) -> GaitSample {
        GaitSample {
            dt: 0.001,
            feet_ref: feet,
            soles,
            sole_force: [300.0, 300.0],
            normal_force: 600.0,
            cop: [0.0, 0.0],
        }
    }

    /// A still walk: both feet on the floor, loaded, where planned: every measure zero. Then a
    /// slide, a hop, a CoP off the soles and a misplaced landing, each seen and bounded.
    #[test]
    fn each_measure_sees_its_failure() {
        let (w, half) = (600.0, [0.12, 0.07]);
        let feet = [foot(0.0, 0.1, 0.0, 0.0), foot(0.0, -0.1, 0.0, 0.0)];
        let still = [pose(0.0, 0.1), pose(0.0, -0.1)];
        let mut m = GaitMonitor::new(w, half);
        for _ in 0..100 {
            m.push(&sample(still, feet));
        }
        assert_eq!(m.quality(), GaitQuality::default());
        assert!(m.quality().within_bounds());
        // The left sole slides 15 mm while loaded.
        m.push(&sample([pose(0.015, 0.1), pose(0.0, -0.1)], feet));
        assert!((m.quality().slip_max_m - 0.015).abs() < 1e-12);
        assert_eq!(m.quality().violations(), ["slip"]);
        // 6 ms without contact, then 3 ms: the longest is 6 ms.
        let mut m = GaitMonitor::new(w, half);
        for k in 0..12 {
            let mut s = sample(still, feet);
            if k < 6 || (8..11).contains(&k) {
                s.normal_force = 0.0;
                s.sole_force = [0.0; 2];
                s.cop = [f64::NAN; 2];
            }
            m.push(&s);
        }
        let q = m.quality();
        assert!((q.flight_max_s - 0.006).abs() < 1e-12 && (q.flight_s - 0.009).abs() < 1e-12);
        assert_eq!(q.violations(), ["flight"]);
        // The CoP 5 cm in front of the toes for 60 ms.
        let mut m = GaitMonitor::new(w, half);
        for _ in 0..60 {
            let mut s = sample(still, feet);
            s.cop = [0.17, 0.0];
            m.push(&s);
        }
        let q = m.quality();
        assert!((q.cop_outside_max_m - 0.05).abs() < 1e-12);
        assert_eq!(q.violations(), ["CoP outside the support polygon"]);
        // The left foot swings and lands 25 mm from its reference.
        let q = swing_and_land(w, half, pose(0.2, 0.125));
        assert_eq!(q.landings, 1);
        assert!((q.landing_err_max_m - 0.025).abs() < 1e-12);
        assert_eq!(q.violations(), ["landing error"]);
    }

    /// The left foot swings (its reference lifted 5 cm at x 0.1) and lands at `landed` where
    /// its reference lands at (0.2, 0.1), heading 0: the monitor's quality.
    fn swing_and_land(w: f64, half: [f64; 2], landed: Pose) -> GaitQuality {
        let still = [pose(0.0, 0.1), pose(0.0, -0.1)];
        let mut m = GaitMonitor::new(w, half);
        let up = [foot(0.1, 0.1, 0.05, 0.0), foot(0.0, -0.1, 0.0, 0.0)];
        let down = [foot(0.2, 0.1, 0.0, 0.0), foot(0.0, -0.1, 0.0, 0.0)];
        let mut s = sample(still, up);
        s.sole_force = [0.0, 600.0];
        s.cop = [0.0, -0.1];
        m.push(&s);
        let mut s = sample([landed, pose(0.0, -0.1)], down);
        s.cop = [0.1, 0.0];
        m.push(&s);
        m.quality()
    }

    fn turned(x: f64, y: f64, yaw: f64) -> Pose {
        Pose::upright(x, y, 0.0, yaw)
    }

    /// A sole turning in place, a sole skidding under a light load before it carries the
    /// weight, and a landing turned from its reference: each a violation.
    #[test]
    fn turns_and_light_skids_are_seen() {
        let (w, half) = (600.0, [0.12, 0.07]);
        let feet = [foot(0.0, 0.1, 0.0, 0.0), foot(0.0, -0.1, 0.0, 0.0)];
        let still = [pose(0.0, 0.1), pose(0.0, -0.1)];
        // The left sole turns 0.06 rad about its centre while loaded: no distance, a slip.
        let mut m = GaitMonitor::new(w, half);
        m.push(&sample(still, feet));
        m.push(&sample([turned(0.0, 0.1, 0.06), pose(0.0, -0.1)], feet));
        let q = m.quality();
        assert!(q.slip_max_m < 1e-12 && (q.slip_yaw_max_rad - 0.06).abs() < 1e-9);
        assert_eq!(q.violations(), ["slip"]);
        // Within the bound (0.04 rad): walked.
        let mut m = GaitMonitor::new(w, half);
        m.push(&sample(still, feet));
        m.push(&sample([turned(0.0, 0.1, -0.04), pose(0.0, -0.1)], feet));
        assert!(m.quality().within_bounds());
        // The left foot touches with 3 % of the weight (below the load share), slides 15 mm,
        // then takes the weight where it slid to: a slip.
        let mut m = GaitMonitor::new(w, half);
        for k in 0..16 {
            let mut s = sample([pose(0.001 * k as f64, 0.1), pose(0.0, -0.1)], feet);
            s.sole_force = [0.03 * w, 0.97 * w];
            m.push(&s);
        }
        m.push(&sample([pose(0.015, 0.1), pose(0.0, -0.1)], feet));
        let q = m.quality();
        assert!((q.slip_max_m - 0.015).abs() < 1e-12, "{q:?}");
        assert_eq!(q.violations(), ["slip"]);
        // The left foot lands where planned but turned 0.08 rad from its reference.
        let q = swing_and_land(w, half, turned(0.2, 0.1, 0.08));
        assert!(q.landing_err_max_m < 1e-12 && (q.landing_yaw_err_max_rad - 0.08).abs() < 1e-9);
        assert_eq!(q.violations(), ["landing error"]);
    }
}
