//! A capture step (the node's own move of the next landing, `Gait::place_steps`) through the
//! gait's public API:
//! * eq. 18 may shorten its single support but not lengthen it, where the same move sent as a
//!   modification gets eq. 18 as the paper has it;
//! * the re-plan that lifts its foot starts from the measured state (`Gait::set_measured`):
//!   against a twin gait told nothing, the reference at the re-plan has the same COG position
//!   (1e-12 m) and a divergent component `ξ = x + ẋ/ω` off by `e_c`, the part of the measured
//!   deviation the move captures (`capture::captured_deviation`, over the single support as
//!   eq. 18 left it; 1e-9 m), and the plan keeps the ZMP in the sole (eq. 17);
//! * a measured state whose plan would take the ZMP out of the sole is ignored (the twin's
//!   reference, bit for bit), as it is for a modification from the bus and with no move.
//! * the flag of a window planned from the measured state ends with that window: not after
//!   it, standing, or in a new walk's start window.

use planner_core::capture::captured_deviation;
use planner_core::gait::{Deviation, Footstep, Gait, GaitParams, Phase, Reference, Side};

type G = Gait<f64, 32>;

fn standing() -> G {
    let mut p = GaitParams::hrp2();
    p.shaping = false;
    Gait::new(
        p,
        Footstep::new(Side::Left, 0.0, 0.1, 0.0),
        Footstep::new(Side::Right, 0.0, -0.1, 0.0),
    )
    .expect("valid gait parameters")
}

/// `n` straight steps of `step`, then a closing step beside the last foot.
fn push_straight(g: &mut G, n: u16, step: f64) {
    let mut side = Side::Right;
    for i in 0..n {
        let y = if side == Side::Left { 0.1 } else { -0.1 };
        g.push(i, Footstep::new(side, step * (i + 1) as f64, y, 0.0))
            .unwrap();
        side = side.other();
    }
    let y = if side == Side::Left { 0.1 } else { -0.1 };
    g.push(n, Footstep::new(side, step * n as f64, y, 0.0))
        .unwrap();
}

/// A walk of 0.2 m steps in the double support before step 3 swings.
fn before_step_3() -> G {
    let mut g = standing();
    push_straight(&mut g, 8, 0.2);
    g.start().unwrap();
    let mut guard = 0;
    while g.next_target() != Some(3) || matches!(g.last().phase, Phase::Single(_)) {
        g.tick();
        guard += 1;
        assert!(guard < 2000, "step 3 never became the next target");
    }
    g
}

/// How step 3 (commanded at x = 0.8 m, on the left) is moved by `dx`.
#[derive(Clone, Copy, PartialEq)]
enum Move {
    None,
    Capture,
    Modify,
}

/// The reference at the re-plan that lifts step 3, moved by `dx` as `how`, with `measured`
/// given to the gait; and whether that re-plan started from the measured state, and its
/// single-support adjustment.
fn replan_with(dx: f64, how: Move, measured: Deviation<f64>) -> (Reference<f64>, bool, i32) {
    let mut g = before_step_3();
    let plans = g.plans();
    let to = Footstep::new(Side::Left, 0.8 + dx, 0.1, 0.0);
    match how {
        Move::None => {}
        Move::Capture => {
            g.place_steps(|id| (id == 3).then_some([to.x, to.y]));
            g.check_next_target().expect("feasible");
        }
        Move::Modify => g.modify(3, to).expect("feasible"),
    }
    g.set_measured(measured);
    while g.plans() == plans {
        g.tick();
    }
    let info = *g.last_replan().expect("a re-plan");
    let sole = (g.params().sole_half_length, g.params().sole_half_width);
    assert!(
        info.worst_zmp[0].abs() <= sole.0 && info.worst_zmp[1].abs() <= sole.1,
        "eq. 17: {:?}",
        info.worst_zmp
    );
    (*g.last(), g.replanned_from_measured(), info.adjust_ticks)
}

/// The node's own move of the next landing (a capture step, `Gait::place_steps`) is not
/// slowed down: eq. 18 may shorten its single support but not lengthen it. The same move sent
/// as a modification (`Gait::modify`) gets eq. 18 as the paper has it: lengthened forward,
/// shortened backward. Backward, both agree.
#[test]
fn a_capture_step_is_shortened_never_lengthened() {
    // (the adjustment of the re-plan that the move of step 3 by `dx` causes, as a capture
    // step or as a modification)
    let replan = |dx: f64, capture: bool| -> i32 {
        let how = if capture { Move::Capture } else { Move::Modify };
        replan_with(dx, how, Deviation::ZERO).2
    };
    let (fwd_mod, fwd_cap) = (replan(0.08, false), replan(0.08, true));
    let (back_mod, back_cap) = (replan(-0.08, false), replan(-0.08, true));
    assert!(
        fwd_mod > 0,
        "a forward modification is lengthened: {fwd_mod}"
    );
    assert_eq!(fwd_cap, 0, "a forward capture step is not: {fwd_cap}");
    assert!(
        back_mod < 0,
        "a backward modification is shortened: {back_mod}"
    );
    assert_eq!(back_cap, back_mod);
}

/// The capture step's re-plan starts from the measured state: the COG where the reference
/// was, its divergent component moved by the captured part of the measurement, whole when the
/// move accounts for all of it and cut when the move was smaller.
#[test]
fn a_capture_steps_window_starts_from_the_measured_state() {
    let p = GaitParams::<f64>::hrp2();
    let dx = 0.08;
    for (error, margin) in [
        ([0.03, 0.004], 0.02),
        ([0.06, -0.01], 0.02),
        ([0.05, 0.0], 0.0),
    ] {
        let measured = Deviation {
            error,
            moved: [dx, 0.0],
            margin,
        };
        let (twin, twin_measured, twin_adjust) = replan_with(dx, Move::Capture, Deviation::ZERO);
        let (r, from_measured, adjust) = replan_with(dx, Move::Capture, measured);
        assert!(!twin_measured);
        assert!(
            from_measured,
            "{error:?}: the window starts from the measured state"
        );
        assert_eq!(
            adjust, twin_adjust,
            "eq. 18 is taken from the reference's state"
        );
        let single = p.dt * f64::from(p.single_ticks as i32 + adjust);
        let e_c = captured_deviation(error, [dx, 0.0], margin, p.omega, single);
        for (k, (a, b)) in [(r.x, twin.x), (r.y, twin.y)].into_iter().enumerate() {
            assert!(
                (a.cog - b.cog).abs() < 1e-12,
                "COG {k}: {} vs {}",
                a.cog,
                b.cog
            );
            let xi = |s: planner_core::lipm::Sample<f64>| s.cog + s.cog_vel / p.omega;
            let d = xi(a) - xi(b);
            assert!((d - e_c[k]).abs() < 1e-9, "ξ {k}: {d} vs {}", e_c[k]);
        }
        let len = e_c[0].hypot(e_c[1]);
        assert!(len <= error[0].hypot(error[1]) + 1e-15);
        assert!(len > 0.0);
    }
}

/// A measurement is ignored where it must be: a plan from it that breaks eq. 17, a modification
/// from the bus (not a capture step), no move at all.
#[test]
fn the_measured_state_is_ignored_where_it_must_be() {
    let dx = 0.08;
    let (capture_twin, _, _) = replan_with(dx, Move::Capture, Deviation::ZERO);
    // 1.6 m/s more of COG velocity: no single support keeps that ZMP in the sole.
    let huge = Deviation {
        error: [0.46, 0.0],
        moved: [10.0, 0.0],
        margin: 0.02,
    };
    let (r, from_measured, _) = replan_with(dx, Move::Capture, huge);
    assert!(!from_measured);
    assert_eq!(
        r, capture_twin,
        "falls back to the reference's state, bit for bit"
    );
    let small = Deviation {
        error: [0.03, 0.0],
        moved: [dx, 0.0],
        margin: 0.02,
    };
    for how in [Move::Modify, Move::None] {
        let (twin, _, _) = replan_with(dx, how, Deviation::ZERO);
        let (r, from_measured, _) = replan_with(dx, how, small);
        assert!(!from_measured);
        assert_eq!(r, twin);
    }
}

/// The flag of a window planned from the measured state belongs to that window: the stop
/// window after it, and a new walk's start window, are the reference's own.
#[test]
fn the_measured_start_ends_with_its_window() {
    let dx = 0.05;
    // Three steps and the closing one (step 3), which the capture moves.
    let mut g = standing();
    push_straight(&mut g, 3, 0.2);
    g.start().unwrap();
    let mut guard = 0;
    let mut tick = |g: &mut G| {
        g.tick();
        guard += 1;
        assert!(guard < 4000, "the walk never got there");
    };
    while g.next_target() != Some(3) || matches!(g.last().phase, Phase::Single(_)) {
        tick(&mut g);
    }
    g.place_steps(|id| (id == 3).then_some([0.6 + dx, 0.1]));
    g.check_next_target().expect("feasible");
    g.set_measured(Deviation {
        error: [0.03, 0.0],
        moved: [dx, 0.0],
        margin: 0.02,
    });
    g.stop();
    let plans = g.plans();
    while g.plans() == plans {
        tick(&mut g);
    }
    assert!(g.replanned_from_measured(), "the capture step's window");
    // What follows it (the stop window, or standing at its end) is not.
    let plans = g.plans();
    while g.plans() == plans && !g.is_standing() {
        tick(&mut g);
    }
    assert!(
        !g.replanned_from_measured(),
        "after the capture step's window"
    );
    while !g.is_standing() {
        tick(&mut g);
    }
    assert!(!g.replanned_from_measured(), "standing");
    // A new walk's start window.
    g.push(4, Footstep::new(Side::Right, 0.8, -0.1, 0.0))
        .unwrap();
    g.start().unwrap();
    assert!(!g.replanned_from_measured(), "the start window");
}
