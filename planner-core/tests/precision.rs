//! f32 against f64: how much COG the single-precision planner loses, in both homogeneous bases.
//!
//! The f64 solve in the exponential basis is the reference (it agrees with the 44-unknown oracle
//! to 1e-9 m, see `oracle.rs`). Requirement: the shipped f32 planner stays within
//! 0.1 mm of COG on every test window. The paper's `V cosh + W sinh` basis is measured too, to
//! show what the better-conditioned basis buys; it is reported, not required.
//!
//! Run `cargo test -p planner-core --test precision -- --nocapture` to see the figures.

use planner_core::window::{Banded, Basis, Factorized, Plan, PlaneBoundary, Timing, M};
use planner_core::{Real, State};

/// A test window: timing plus both planes, in f64.
struct Case {
    name: &'static str,
    durations: [f64; M],
    x: PlaneBoundary<f64>,
    y: PlaneBoundary<f64>,
}

fn walk(name: &'static str, durations: [f64; M], x0: f64, step: f64, lateral: f64) -> Case {
    // Via points: SS ends on the support foot, DS moves to the next foot (zero velocities).
    let mut xv = [State::default(); M];
    let mut yv = [State::default(); M];
    let mut foot_x = x0;
    let mut side = 1.0;
    for j in 0..M {
        if j % 2 == 1 {
            foot_x += step;
            side = -side;
        }
        xv[j] = State::at_rest(foot_x);
        yv[j] = State::at_rest(side * lateral);
    }
    Case {
        name,
        durations,
        x: PlaneBoundary {
            cog_start: State::new(x0 - 0.02, 0.25),
            zmp_start: State::at_rest(x0),
            via: xv,
            cog_end: State::at_rest(xv[M - 1].pos),
        },
        y: PlaneBoundary {
            cog_start: State::new(0.06, -0.15),
            zmp_start: State::at_rest(lateral),
            via: yv,
            cog_end: State::at_rest(yv[M - 1].pos),
        },
    }
}

fn cases() -> [Case; 5] {
    [
        walk(
            "HRP-2 walk 0.2 m",
            [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7],
            0.0,
            0.2,
            0.1,
        ),
        walk(
            "walk far from origin (x = 25 m)",
            [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7],
            25.0,
            0.3,
            0.1,
        ),
        walk(
            "SS stretched +0.35 s",
            [1.05, 0.1, 1.05, 0.1, 1.05, 0.1, 1.05],
            0.0,
            0.3,
            0.1,
        ),
        walk(
            "SS shortened -0.2 s",
            [0.5, 0.1, 0.5, 0.1, 0.5, 0.1, 0.5],
            0.0,
            -0.3,
            0.1,
        ),
        walk(
            "start from double support",
            [0.1, 0.7, 0.1, 0.7, 0.1, 0.7, 0.1],
            0.0,
            0.2,
            0.1,
        ),
    ]
}

fn to32(b: &PlaneBoundary<f64>) -> PlaneBoundary<f32> {
    let s = |s: State<f64>| State::new(s.pos as f32, s.vel as f32);
    PlaneBoundary {
        cog_start: s(b.cog_start),
        zmp_start: s(b.zmp_start),
        via: b.via.map(s),
        cog_end: s(b.cog_end),
    }
}

/// Largest COG-position difference of an f32 plan from the f64 reference over 2000 samples.
fn max_cog_error<T>(case: &Case, basis: Basis, reference: &Plan<f64>) -> f64
where
    T: Real + From<f32>,
{
    let timing = Timing {
        omega: T::of(libm::sqrt(9.8 / 0.814)),
        durations: case.durations.map(T::of),
    };
    // The planner's structured elimination in its own basis; the banded LU of the dense `Z`
    // for the paper's.
    let solve = |x: &PlaneBoundary<T>, y: &PlaneBoundary<T>, plan: &mut Plan<T>| match basis {
        Basis::Exponential => Factorized::new(&timing).and_then(|f| f.solve(x, y, plan)),
        Basis::Hyperbolic => Banded::with_basis(&timing, basis).and_then(|f| f.solve(x, y, plan)),
    };
    let (x, y) = (to32(&case.x), to32(&case.y));
    let conv = |b: &PlaneBoundary<f32>| {
        let s = |s: State<f32>| State::new(T::from(s.pos), T::from(s.vel));
        PlaneBoundary {
            cog_start: s(b.cog_start),
            zmp_start: s(b.zmp_start),
            via: b.via.map(s),
            cog_end: s(b.cog_end),
        }
    };
    let mut plan = Plan::zeroed(timing);
    solve(&conv(&x), &conv(&y), &mut plan).expect("solvable");
    let total = reference.timing.total();
    let mut worst = 0.0_f64;
    for i in 0..=2000 {
        let t = total * i as f64 / 2000.0;
        let (rx, ry) = reference.sample(t);
        let (px, py) = plan.sample(T::of(t));
        worst = worst
            .max((px.cog.f64() - rx.cog).abs())
            .max((py.cog.f64() - ry.cog).abs());
    }
    worst
}

fn reference(case: &Case) -> Plan<f64> {
    let timing = Timing {
        omega: libm::sqrt(9.8 / 0.814),
        durations: case.durations,
    };
    let f = Factorized::new(&timing).expect("timing is valid");
    // The f64 reference is solved from the same f32-rounded inputs, so that only the
    // arithmetic differs.
    let up = |b: &PlaneBoundary<f32>| {
        let s = |s: State<f32>| State::new(s.pos as f64, s.vel as f64);
        PlaneBoundary {
            cog_start: s(b.cog_start),
            zmp_start: s(b.zmp_start),
            via: b.via.map(s),
            cog_end: s(b.cog_end),
        }
    };
    let mut plan = Plan::zeroed(timing);
    f.solve(&up(&to32(&case.x)), &up(&to32(&case.y)), &mut plan)
        .expect("solvable");
    plan
}

#[test]
fn f32_planner_stays_within_a_tenth_of_a_millimetre() {
    let mut worst_exp = 0.0_f64;
    let mut worst_hyp = 0.0_f64;
    for case in &cases() {
        let r = reference(case);
        let e32 = max_cog_error::<f32>(case, Basis::Exponential, &r);
        let h32 = max_cog_error::<f32>(case, Basis::Hyperbolic, &r);
        let h64 = max_cog_error::<f64>(case, Basis::Hyperbolic, &r);
        eprintln!(
            "{:<34} f32 exp basis {:>9.3} µm | f32 cosh/sinh basis {:>9.3} µm | f64 cosh/sinh vs exp {:.1e} m",
            case.name,
            e32 * 1e6,
            h32 * 1e6,
            h64
        );
        // Both bases are exact in exact arithmetic: in f64 they agree to rounding.
        assert!(h64 < 1e-9, "{}: f64 bases disagree by {h64}", case.name);
        worst_exp = worst_exp.max(e32);
        worst_hyp = worst_hyp.max(h32);
    }
    eprintln!(
        "worst COG deviation of f32 from f64: exponential basis {:.3} µm, cosh/sinh basis {:.3} µm",
        worst_exp * 1e6,
        worst_hyp * 1e6
    );
    assert!(
        worst_exp < 1e-4,
        "f32 planner loses {worst_exp} m of COG (limit 1e-4 m)"
    );
}
