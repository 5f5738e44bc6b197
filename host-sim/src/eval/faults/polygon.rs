//! The geometry of the fault sweep's fall verdict: the support polygon of a reference (the
//! sole of the foot on the ground, or the convex hull of both soles) and how far a ZMP lies
//! outside it; and the landings of a trajectory (for the lost-command count).

use planner_core::gait::{FootPose, Phase, Reference, Side};

use super::SOLE_HALF;

/// Distance of `p` outside the convex polygon `hull` (counter-clockwise); 0 inside.
pub(super) fn outside(hull: &[[f64; 2]], p: [f64; 2]) -> f64 {
    let n = hull.len();
    let mut inside = true;
    let mut best = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (hull[i], hull[(i + 1) % n]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let (px, py) = (p[0] - a[0], p[1] - a[1]);
        if ex * py - ey * px < 0.0 {
            inside = false;
        }
        let len2 = ex * ex + ey * ey;
        let t = if len2 > 0.0 {
            ((px * ex + py * ey) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((px - t * ex).hypot(py - t * ey));
    }
    if inside {
        0.0
    } else {
        best
    }
}

/// Convex hull (counter-clockwise, monotone chain).
fn hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut h: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

fn sole(f: &FootPose<f64>) -> [[f64; 2]; 4] {
    let (s, c) = f.yaw.sin_cos();
    let [a, b] = SOLE_HALF;
    [[a, b], [-a, b], [-a, -b], [a, -b]].map(|[u, v]| [f.x + c * u - s * v, f.y + s * u + c * v])
}

/// The support polygon of a reference (see the module docs).
pub fn support_polygon(r: &Reference<f64>) -> Vec<[f64; 2]> {
    match r.phase {
        Phase::Single(side) => {
            let i = usize::from(side == Side::Right);
            hull(sole(&r.feet[i]).to_vec())
        }
        _ => {
            let mut pts = sole(&r.feet[0]).to_vec();
            pts.extend_from_slice(&sole(&r.feet[1]));
            hull(pts)
        }
    }
}

/// Footsteps walked: the pose of the swing foot where each single support ends.
pub fn landings(traj: &[Reference<f64>]) -> Vec<(Side, FootPose<f64>)> {
    let mut out = Vec::new();
    for w in traj.windows(2) {
        if let (Phase::Single(support), next) = (w[0].phase, w[1].phase) {
            if !matches!(next, Phase::Single(s) if s == support) {
                let swing = support.other();
                let i = usize::from(swing == Side::Right);
                out.push((swing, w[1].feet[i]));
            }
        }
    }
    out
}
