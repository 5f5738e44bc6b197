//! Host timings of the window solver: `cargo bench -p planner-core --bench window`.
//!
//! * `replan`: build Z for a timing, factorise it, solve the x and y planes (what the planner
//!   does at every start of single support).
//! * `solve_both_planes`: the two solves with an existing factorisation.
//! * `sample`: one sample of both planes (what every 5 ms cycle does).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use planner_core::window::{Factorized, Plan, PlaneBoundary, Timing, M};
use planner_core::State;

fn window() -> (Timing<f64>, PlaneBoundary<f64>, PlaneBoundary<f64>) {
    let timing = Timing {
        omega: libm::sqrt(9.8 / 0.814),
        durations: [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7],
    };
    let mut xv = [State::default(); M];
    let mut yv = [State::default(); M];
    let (mut fx, mut side) = (0.0, 0.1);
    for j in 0..M {
        if j % 2 == 1 {
            fx += 0.2;
            side = -side;
        }
        xv[j] = State::at_rest(fx);
        yv[j] = State::at_rest(side);
    }
    let x = PlaneBoundary {
        cog_start: State::new(-0.02, 0.25),
        zmp_start: State::at_rest(0.0),
        via: xv,
        cog_end: State::at_rest(fx),
    };
    let y = PlaneBoundary {
        cog_start: State::new(0.05, -0.1),
        zmp_start: State::at_rest(0.1),
        via: yv,
        cog_end: State::at_rest(side),
    };
    (timing, x, y)
}

fn bench(c: &mut Criterion) {
    let (timing, x, y) = window();
    let mut plan = Plan::zeroed(timing);
    c.bench_function("replan (build Z, LU, solve x and y)", |b| {
        b.iter(|| {
            let f = Factorized::new(black_box(&timing)).unwrap();
            f.solve(black_box(&x), black_box(&y), &mut plan).unwrap();
            black_box(&plan);
        })
    });
    let mut z = nalgebra::SMatrix::<f64, 20, 20>::from_element(0.0);
    c.bench_function("build_z", |b| {
        b.iter(|| {
            planner_core::window::build_z(
                black_box(&timing),
                planner_core::Basis::Exponential,
                &mut z,
            );
            black_box(&z);
        })
    });
    let f = Factorized::new(&timing).unwrap();
    c.bench_function("solve_both_planes", |b| {
        b.iter(|| {
            f.solve(black_box(&x), black_box(&y), &mut plan).unwrap();
            black_box(&plan);
        })
    });
    f.solve(&x, &y, &mut plan).unwrap();
    c.bench_function("sample (both planes)", |b| {
        b.iter(|| black_box(plan.sample(black_box(1.234))))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
