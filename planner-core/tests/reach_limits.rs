//! The reach check names the limit it finds broken: `Reach::broken` agrees with
//! `Reach::check_with` on every step (refused exactly when a limit is named, `Crossing` for
//! the crossing limit, `Reach` for the others), every limit can be the one named, and the
//! value it reports is on the wrong side of the bound it names.

use planner_core::gait::{Footstep, GaitParams, Side};
use planner_core::node::{Limit, Reach, Soles};
use planner_core::wire::Reason;
use proptest::prelude::*;

fn hrp2() -> (Reach, Soles) {
    (Reach::default(), Soles::of(&GaitParams::hrp2()))
}

fn side(left: bool) -> Side {
    if left {
        Side::Left
    } else {
        Side::Right
    }
}

/// A support foot at the origin, the swinging foot's lift-off pose and the landing, in the
/// support frame (the landing on `side`).
fn case(
    left: bool,
    lift: (f64, f64),
    land: (f64, f64, f64),
) -> (Footstep<f64>, Footstep<f64>, Footstep<f64>) {
    let s = side(left);
    let sign = if left { 1.0 } else { -1.0 };
    let other = Footstep::new(s.other(), 0.0, 0.0, 0.0);
    let same = Footstep::new(s, lift.0, sign * lift.1, 0.0);
    let step = Footstep::new(s, land.0, sign * land.1, sign * land.2);
    (other, same, step)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    #[test]
    fn broken_agrees_with_the_check(
        left in any::<bool>(),
        from_rest in any::<bool>(),
        lift in (-0.5..0.5f64, 0.1..0.3f64),
        land in (-0.5..0.6f64, -0.1..0.45f64, -0.6..0.6f64),
    ) {
        let (r, soles) = hrp2();
        let (other, same, step) = case(left, lift, land);
        let check = r.check_with(&other, &same, &step, from_rest, &soles);
        let broken = r.broken(&other, &same, &step, from_rest, &soles);
        match broken {
            None => prop_assert_eq!(check, Ok(())),
            Some(b) => {
                let reason = if b.limit == Limit::Crossing { Reason::Crossing } else { Reason::Reach };
                prop_assert_eq!(check, Err(reason));
                prop_assert_eq!(b.reason(), reason);
                // The value is beyond its bound (`min_width`: below, the others: above;
                // crossing: either a negative width or soles nearer than the gap).
                match b.limit {
                    Limit::Crossing => {}
                    Limit::MinWidth => prop_assert!(b.value < b.bound, "{b:?}"),
                    _ => prop_assert!(b.value > b.bound, "{b:?}"),
                }
            }
        }
    }
}

/// Each limit is the one named for a step that breaks only it (or it first).
#[test]
fn every_limit_can_be_named() {
    let (r, soles) = hrp2();
    let cases = [
        (Limit::Crossing, (0.0, 0.2), (0.0, -0.05, 0.0), false),
        (Limit::Forward, (0.0, 0.2), (0.32, 0.2, 0.0), false),
        (Limit::Backward, (0.0, 0.2), (-0.22, 0.2, 0.0), false),
        // (soles staggered along the heading, so that they keep the gap)
        (Limit::MinWidth, (0.0, 0.2), (0.26, 0.14, 0.0), false),
        (Limit::MaxWidth, (0.0, 0.2), (0.0, 0.29, 0.0), false),
        (Limit::Yaw, (0.0, 0.2), (0.0, 0.2, 0.35), false),
        (Limit::FeetDistance, (0.1, 0.2), (0.25, 0.27, 0.0), false),
        (Limit::TurnCost, (0.1, 0.2), (0.25, 0.2, 0.25), false),
        (Limit::Stride, (-0.2, 0.2), (0.25, 0.2, 0.0), false),
        (Limit::Growth, (0.0, 0.2), (0.25, 0.2, 0.0), true),
    ];
    for (limit, lift, land, from_rest) in cases {
        for left in [true, false] {
            let (other, same, step) = case(left, lift, land);
            let b = r.broken(&other, &same, &step, from_rest, &soles);
            assert_eq!(b.map(|b| b.limit), Some(limit), "{limit:?} {left}: {b:?}");
        }
    }
    // Within every limit: nothing named.
    let (other, same, step) = case(true, (0.0, 0.2), (0.1, 0.2, 0.0));
    assert_eq!(r.broken(&other, &same, &step, true, &soles), None);
}
