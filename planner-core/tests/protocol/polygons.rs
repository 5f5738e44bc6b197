//! Support polygons (see the test's docs in `main.rs`).

use super::*;

pub(crate) fn sole(p: &FootPose<f64>, hl: f64, hw: f64) -> [(f64, f64); 4] {
    let (s, c) = p.yaw.sin_cos();
    let at = |u: f64, v: f64| (p.x + c * u - s * v, p.y + s * u + c * v);
    [at(hl, hw), at(-hl, hw), at(-hl, -hw), at(hl, -hw)]
}

/// The convex hull, counter-clockwise (Andrew's monotone chain).
pub(crate) fn hull(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut h: Vec<(f64, f64)> = vec![];
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in it {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

/// The signed distance of `p` from the boundary of the convex polygon `poly`
/// (counter-clockwise): positive outside, negative inside.
pub(crate) fn outside(poly: &[(f64, f64)], p: (f64, f64)) -> f64 {
    let n = poly.len();
    let edge = |k: usize| (poly[k], poly[(k + 1) % n]);
    let inside = (0..n).all(|k| {
        let (a, b) = edge(k);
        (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0) >= 0.0
    });
    let d = (0..n)
        .map(|k| {
            let (a, b) = edge(k);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let t = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
        })
        .fold(f64::INFINITY, f64::min);
    if inside {
        -d
    } else {
        d
    }
}

pub(crate) fn wrapped(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}
