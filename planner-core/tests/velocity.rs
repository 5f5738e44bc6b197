//! Velocity walking's footsteps against the node's own reach check: for every finite velocity
//! and every start the node accepts, each generated landing passes `Reach::check_with` from
//! the feet before it (the node would take it), and what was asked within the limits is walked
//! uncut.

use planner_core::gait::{Footstep, GaitParams, Side};
use planner_core::node::{Reach, Soles};
use planner_core::velocity::{Stepping, Velocity};
use proptest::prelude::*;

fn hrp2() -> Stepping<f64> {
    Stepping::of(&GaitParams::hrp2(), Reach::default())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2_000))]

    #[test]
    fn every_generated_step_is_one_the_node_takes(
        vx in -3.0f64..3.0, vy in -3.0f64..3.0, wz in -6.0f64..6.0,
        x in -5.0f64..5.0, y in -5.0f64..5.0, yaw in -3.1f64..3.1,
        right_first in any::<bool>(),
        changes in proptest::collection::vec((-3.0f64..3.0, -3.0f64..3.0, -6.0f64..6.0), 0..4),
    ) {
        let s = hrp2();
        let side = if right_first { Side::Right } else { Side::Left };
        let support = Footstep::new(side, x, y, yaw);
        let same = support.beside(s.width);
        let soles = Soles::of(&GaitParams::hrp2());
        let reach = Reach::default();
        let (mut sup, mut prev, mut rest) = (support, same, true);
        let mut commands = vec![(vx, vy, wz)];
        commands.extend(changes);
        for (vx, vy, wz) in commands {
            let v = Velocity { vx, vy, wz };
            for _ in 0..4 {
                let (step, _) = s.next_step(&v, &sup, &prev, rest).unwrap();
                prop_assert!(
                    reach.check_with(&sup, &prev, &step, rest, &soles).is_ok(),
                    "{v:?}: {step:?} from {sup:?} (lifting off {prev:?}): {:?}",
                    reach.broken(&sup, &prev, &step, rest, &soles)
                );
                prop_assert_eq!(step.side, sup.side.other());
                prev = sup;
                sup = step;
                rest = false;
            }
        }
    }

    #[test]
    fn a_forward_velocity_within_the_limits_is_not_cut(vx in -0.2f64..0.25) {
        let s = hrp2();
        let right = Footstep::new(Side::Right, 0.0, -0.5 * s.width, 0.0);
        let left = right.beside(s.width);
        // From standing the first step grows from 0, so the walk reaches vx within the
        // growth limit; once there it is not cut.
        let v = Velocity { vx, vy: 0.0, wz: 0.0 };
        let (steps, _) = s.steps::<3>(&v, &right, &left, true).unwrap();
        let (later, sat) = s.steps::<4>(&v, &steps[2], &steps[1], false).unwrap();
        prop_assert!(!sat.any(), "{vx}: {sat:?} {later:?}");
    }
}
