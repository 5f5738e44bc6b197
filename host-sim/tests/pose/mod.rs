//! What the multi-body model's tests share: a small deterministic generator and the distance
//! between two poses.

use host_sim::robot::model::Pose;

/// A small deterministic generator (64-bit LCG), uniform in [lo, hi).
pub struct Lcg(pub u64);

impl Lcg {
    /// The next value, uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// The largest difference of two poses' positions \[m\] and rotation matrices' entries.
pub fn pose_error(a: &Pose, b: &Pose) -> f64 {
    let mut e = 0.0f64;
    for i in 0..3 {
        e = e.max((a.p[i] - b.p[i]).abs());
        for j in 0..3 {
            e = e.max((a.r[i][j] - b.r[i][j]).abs());
        }
    }
    e
}
