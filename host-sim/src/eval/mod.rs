//! Evaluation of a walk: the multi-body ZMP of the planned motion ([`multibody`]), the paper's
//! modification experiments ([`paper`]), the fault sweep over the bus ([`faults`]) and the
//! largest ZMP fluctuation of a walk ([`max_fluctuation`]).
pub mod faults;
pub mod multibody;
pub mod paper;

use planner_core::gait::{Phase, Side};

use crate::scenario::Run;

/// Largest ZMP deviation from the support-foot centre during single support, in the support
/// foot's frame (along, across) \[m\].
pub fn max_fluctuation(run: &Run) -> (f64, f64) {
    let (mut along, mut across) = (0.0_f64, 0.0_f64);
    for r in &run.trajectory {
        if let Phase::Single(side) = r.phase {
            let f = &r.feet[if side == Side::Left { 0 } else { 1 }];
            let (s, c) = f.yaw.sin_cos();
            let (dx, dy) = (r.x.zmp - f.x, r.y.zmp - f.y);
            along = along.max((c * dx + s * dy).abs());
            across = across.max((-s * dx + c * dy).abs());
        }
    }
    (along, across)
}
