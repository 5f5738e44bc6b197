//! Survival that is not monotonic in the force: a scan above a push-map cell's bisected
//! threshold.
//!
//! A bisection assumes that a robot which survives a push survives every smaller one. Where
//! the robot steps, that fails: a larger push can bring a capture step that a smaller one does
//! not, and survive where the smaller one fell (and the bisection, having seen a survival
//! above them, reports a threshold above falls). The scan pushes at [`SCAN_FORCES`] forces
//! above the bisected threshold and as many below it, [`SCAN_STEP_BW`] of body weight apart
//! ([`scan_with`]), and reports, over every tried push (the bisection's and the scan's):
//!
//! * `sure_bw`: the largest force below which every tried push was survived (the largest
//!   survived force below the smallest fall);
//! * `survived_above`: the fraction of the tried pushes above `sure_bw` that were survived
//!   (0: monotonic as far as tried);
//! * `spread_bw`: the cell's own spread, the span of forces where survivals and falls mix
//!   (the largest survived force minus the smallest fall, 0 if every survival lies below
//!   every fall).
//!
//! Two configurations compare in a cell only where their `sure_bw` differ by more than the
//! larger of their spreads (and of the resolution): [`beyond_spread`]. The engine's side, a
//! cell's bisection and its scan, is `super::push_map::scan_cell`.

use std::cmp::Ordering;

/// Forces tried above the bisected threshold.
pub const SCAN_FORCES: usize = 4;
/// Their spacing \[fraction of body weight\].
pub const SCAN_STEP_BW: f64 = 0.05;

/// A cell's pushes and what they tell (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Scan {
    /// Every tried push: its force \[fraction of body weight\] and whether it was survived,
    /// by force.
    pub tried: Vec<(f64, bool)>,
    /// The largest force below which every tried push was survived \[fraction of body
    /// weight\].
    pub sure_bw: f64,
    /// The fraction of the tried pushes above `sure_bw` that were survived.
    pub survived_above: f64,
    /// The span of forces where survivals and falls mix \[fraction of body weight\].
    pub spread_bw: f64,
}

impl Scan {
    /// What the tried pushes `(force, survived)` tell.
    pub fn of(mut tried: Vec<(f64, bool)>) -> Self {
        tried.sort_by(|a, b| a.0.total_cmp(&b.0));
        let first_fall = tried.iter().find(|t| !t.1).map_or(f64::INFINITY, |t| t.0);
        let sure_bw = tried
            .iter()
            .filter(|t| t.1 && t.0 < first_fall)
            .map(|t| t.0)
            .fold(0.0, f64::max);
        let above: Vec<&(f64, bool)> = tried.iter().filter(|t| t.0 > sure_bw).collect();
        let survived_above = if above.is_empty() {
            0.0
        } else {
            above.iter().filter(|t| t.1).count() as f64 / above.len() as f64
        };
        let last_survival = tried
            .iter()
            .filter(|t| t.1)
            .map(|t| t.0)
            .fold(0.0, f64::max);
        let spread_bw = if first_fall.is_finite() {
            (last_survival - first_fall).max(0.0)
        } else {
            0.0
        };
        Self {
            tried,
            sure_bw,
            survived_above,
            spread_bw,
        }
    }

    /// The scan as JSON: `sure_bw`, `survived_above`, `spread_bw`, `tried` (`[force, survived]`).
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "sure_bw": self.sure_bw,
            "survived_above": self.survived_above,
            "spread_bw": self.spread_bw,
            "tried": self.tried,
        })
    }
}

/// `a` against `b` in one cell: `Some(Greater)` when `a` survives surely to a larger force by
/// more than either cell's spread and `resolution_bw`, `Some(Less)` the other way, `None`
/// inside the noise.
pub fn beyond_spread(a: &Scan, b: &Scan, resolution_bw: f64) -> Option<Ordering> {
    let noise = a.spread_bw.max(b.spread_bw).max(resolution_bw);
    let d = a.sure_bw - b.sure_bw;
    if d > noise {
        Some(Ordering::Greater)
    } else if -d > noise {
        Some(Ordering::Less)
    } else {
        None
    }
}

/// Scans `survives` (a push of a fraction of body weight survived or not) at [`SCAN_FORCES`]
/// forces [`SCAN_STEP_BW`] apart above `threshold_bw` and as many below it, adding the pushes
/// `tried` before (the bisection's); then, while no tried push below the smallest fall was
/// survived, one more [`SCAN_STEP_BW`] below that fall, so that `sure_bw` rests on a survived
/// push (0 if none above 0 is).
pub fn scan_with(
    threshold_bw: f64,
    mut tried: Vec<(f64, bool)>,
    mut survives: impl FnMut(f64) -> Result<bool, String>,
) -> Result<Scan, String> {
    for k in 1..=SCAN_FORCES {
        for f in [
            threshold_bw + SCAN_STEP_BW * k as f64,
            threshold_bw - SCAN_STEP_BW * k as f64,
        ] {
            if f > 0.0 {
                tried.push((f, survives(f)?));
            }
        }
    }
    loop {
        let first_fall = tried
            .iter()
            .filter(|t| !t.1)
            .map(|t| t.0)
            .fold(f64::INFINITY, f64::min);
        let below = first_fall - SCAN_STEP_BW;
        if !first_fall.is_finite() || below <= 0.0 || tried.iter().any(|t| t.1 && t.0 < first_fall)
        {
            break;
        }
        tried.push((below, survives(below)?));
    }
    Ok(Scan::of(tried))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small cell whose robot survives below 0.30 of its weight, falls at 0.30–0.40 and
    /// survives 0.40–0.55 (a capture step), falling again above. The bisection (to 0.02)
    /// reports 0.547, above the falls; the scan finds them, rests the sure threshold on a
    /// survived push below the first fall, and the spread covers the mixed band.
    #[test]
    fn a_cell_that_survives_above_a_fall() {
        let survives = |bw: f64| bw < 0.30 || (0.40..=0.55).contains(&bw);
        // The bisection as push_map::bisect runs it.
        let (mut lo, mut hi, mut tried) = (0.0f64, 1.0f64, Vec::new());
        while hi - lo > 0.02 {
            let mid = 0.5 * (lo + hi);
            tried.push((mid, survives(mid)));
            if survives(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        assert!((lo - 0.546875).abs() < 1e-12, "{lo}");
        let mut calls = 0;
        let s = scan_with(lo, tried.clone(), |bw| {
            calls += 1;
            Ok(survives(bw))
        })
        .expect("scanned");
        // 4 above, 4 below, then one step below the first fall (0.346875): 0.296875.
        assert_eq!(calls, 2 * SCAN_FORCES + 1);
        assert_eq!(s.tried.len(), tried.len() + calls);
        assert!((s.sure_bw - 0.296875).abs() < 1e-12, "{s:?}");
        // Above it, survived: 0.446875, 0.496875 (scan), 0.5, 0.53125, 0.546875 (bisection)
        // of 14 pushes.
        assert!((s.survived_above - 5.0 / 14.0).abs() < 1e-12, "{s:?}");
        // The spread: the last survival (0.546875) minus the first fall (0.346875).
        assert!((s.spread_bw - 0.2).abs() < 1e-12, "{s:?}");
        // A monotonic cell: nothing survives above, no spread.
        let m = Scan::of(vec![(0.2, true), (0.3, false), (0.35, false)]);
        assert_eq!((m.sure_bw, m.survived_above, m.spread_bw), (0.2, 0.0, 0.0));
        // Compared: a difference inside the spread is no difference.
        let better = Scan::of(vec![(0.45, true), (0.5, false)]);
        assert_eq!(beyond_spread(&better, &s, 0.02), None);
        assert_eq!(beyond_spread(&better, &m, 0.02), Some(Ordering::Greater));
        assert_eq!(beyond_spread(&m, &better, 0.02), Some(Ordering::Less));
    }
}
