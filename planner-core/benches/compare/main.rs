//! The host comparison: one re-plan of the window (build the 20×20 `Z` for a timing,
//! factorise it, solve the x and the y plane) three ways, side by side in one run:
//!
//! * **planner-core**: [`Factorized::refactor`] then [`Factorized::solve`], the two calls of
//!   the gait's re-plan (`Active::plan_into` in `planner-core/src/gait/active.rs`);
//! * **LAPACK**: [`build_z`], `dgetrf`, then `dgetrs` with the two planes' right-hand sides;
//! * **jrl-walkgen's method** (the public C++ implementation, `AnalyticalMorisawaCompact`):
//!   [`build_z`], `dgetrf` once, then the expert driver `dgesvx` with `FACT = 'F'` once per
//!   plane (solve, iterative refinement, condition estimate, error bounds).
//!
//! Every method builds the same `Z` (planner-core's [`build_z`], the planner's basis) for the
//! same timing, and the timed loop alternates between two timings so that planner-core's
//! "same timing, keep the factorisation" shortcut never applies: each re-plan factorises.
//! planner-core's figure also includes building the right-hand sides from the boundary values
//! and writing the 14 segments of the plan; the LAPACK methods are given the right-hand sides
//! ready-made (the same vectors, recovered once as `Z·y` from planner-core's plan) and write
//! the bare solution vectors, so the ratios favour LAPACK. A fourth row, planner-core's linear
//! algebra alone (refactor and two [`Factorized::solve_vector`]), is the like-for-like one.
//! jrl-walkgen also transposes a copy of `Z` and allocates its workspace at every solve; here
//! the workspace is allocated once, and only the copy of `A` into `AF` before `dgetrf` remains
//! (`dgesvx` needs both).
//!
//! Before timing, [`check`] solves the same `Z` and right-hand sides three ways for several
//! timings (single support 0.6–1.0 s, double support 0.1–0.2 s, a re-plan in the middle of a
//! single support, a long final interval) and fails unless the solutions agree to 1e-12
//! relative (to the largest unknown). Then criterion times each method (`replan/…`, wall
//! clock), and a closing summary times them again interleaved: rounds of a batch of re-plans
//! per method, the order rotated each round, every batch timed in the calling thread's CPU
//! time (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`) and in wall-clock time. It prints the
//! median per re-plan of each method and the ratios on both clocks, the share of the wall
//! clock the thread ran, and the machine: CPU model (`/proc/cpuinfo`), online CPUs and the
//! 1-minute load average (`/proc/loadavg`) at the start and at the end of the run. Thread CPU
//! time leaves out the time the thread waits for a CPU on a loaded machine, so its ratios are
//! the ones to quote; the wall-clock ones show what the load did. Run it with
//!
//! ```text
//! cargo bench -p planner-core --bench compare
//! ```
//!
//! Under `cargo test` (criterion's test mode: no `--bench` argument) the check runs, every
//! benchmark runs once and the summary takes 3 short rounds, so CI stays quick. It needs
//! Debian's `liblapack-dev` (`tests/run-all.sh` installs it).

// The FFI modules `lapack` (LAPACK) and `sys` (libc's clocks) are the only places with unsafe
// code (they allow it, with a SAFETY note per call); everything else, the timed methods
// included, is safe Rust.
#![deny(unsafe_code)]

mod lapack;

/// The calling thread's CPU clock and the number of online CPUs, from libc.
mod sys {
    // Two libc calls, each with a SAFETY note: the bench's only unsafe code besides `lapack`.
    #![allow(unsafe_code)]

    use std::time::Duration;

    /// The CPU time the calling thread has consumed (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`):
    /// it stops while the thread waits for a CPU, so other jobs on the machine do not count.
    pub fn thread_cpu_time() -> Duration {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable `timespec` that lives across the call;
        // clock_gettime writes only it and keeps no pointer.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        assert_eq!(
            rc,
            0,
            "clock_gettime(CLOCK_THREAD_CPUTIME_ID): {}",
            std::io::Error::last_os_error()
        );
        let secs = u64::try_from(ts.tv_sec).expect("a thread's CPU time is not negative");
        let nanos = u32::try_from(ts.tv_nsec).expect("tv_nsec is below 10⁹");
        Duration::new(secs, nanos)
    }

    /// The number of CPUs online (`sysconf(_SC_NPROCESSORS_ONLN)`), `None` if unknown.
    pub fn online_cpus() -> Option<u64> {
        // SAFETY: sysconf takes an integer and touches no memory of the caller.
        let n = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) };
        u64::try_from(n).ok().filter(|&n| n > 0)
    }
}

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::Criterion;
use lapack::Gesvx;
use nalgebra::SMatrix;
use planner_core::window::{build_z, Factorized, Plan, PlaneBoundary, Timing, M, N};
use planner_core::{Basis, State};

/// Agreement required between the three solutions, relative to the largest unknown.
const TOLERANCE: f64 = 1e-12;

/// One window to plan: its timing and the boundary values of both planes.
#[derive(Clone, Copy, Debug)]
struct Case {
    timing: Timing<f64>,
    x: PlaneBoundary<f64>,
    y: PlaneBoundary<f64>,
}

/// A walking window: the current single support (`first` seconds of it left), then double,
/// single, double, single, double and a final interval of `last`; steps of 0.2 m forward,
/// feet 0.2 m apart, the COG moving.
fn walk(first: f64, single: f64, double: f64, last: f64) -> Case {
    let timing = Timing {
        omega: (planner_core::GRAVITY / planner_core::HRP2_COG_HEIGHT).sqrt(),
        durations: [first, double, single, double, single, double, last],
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
    Case { timing, x, y }
}

/// The two windows the timed loop alternates between (single support 0.7 s and 0.8 s).
fn timed_cases() -> [Case; 2] {
    [walk(0.7, 0.7, 0.1, 0.7), walk(0.8, 0.8, 0.1, 0.8)]
}

/// The timings of the correctness check.
fn check_cases() -> Vec<(String, Case)> {
    let mut cases = Vec::new();
    for single in [0.6, 0.7, 0.8, 0.9, 1.0] {
        for double in [0.1, 0.2] {
            cases.push((
                format!("SS {single:.1} s, DS {double:.1} s"),
                walk(single, single, double, single),
            ));
        }
    }
    cases.push((
        "re-plan 0.3 s into SS 0.8 s, DS 0.1 s".into(),
        walk(0.5, 0.8, 0.1, 0.8),
    ));
    cases.push((
        "last 0.05 s of SS 0.7 s, DS 0.2 s, final 1.6 s".into(),
        walk(0.05, 0.7, 0.2, 1.6),
    ));
    cases
}

/// The unknowns of one plane read off a solved plan, in the order of `Z`'s columns
/// (`planner_core::window`'s module doc: `β¹ | P_j Q_j | β⁷`, the planner's basis).
fn unknowns(plane: &planner_core::window::PlanePlan<f64>) -> [f64; N] {
    let mut y = [0.0; N];
    y[..3].copy_from_slice(&plane[0].zmp[2..5]);
    for (j, seg) in plane.iter().enumerate() {
        y[3 + 2 * j] = seg.p;
        y[4 + 2 * j] = seg.q;
    }
    y[N - 3..].copy_from_slice(&plane[M - 1].zmp[2..5]);
    y
}

/// `Z` of a case and the right-hand sides of its two planes, `w = Z·y` with `y` the unknowns
/// of planner-core's plan (so every method solves exactly the system planner-core solved),
/// and those unknowns.
fn system(case: &Case) -> (SMatrix<f64, N, N>, [[f64; N]; 2], [[f64; N]; 2]) {
    let f = Factorized::new(&case.timing).expect("the window factorises");
    let mut plan = Plan::zeroed(case.timing);
    f.solve(&case.x, &case.y, &mut plan)
        .expect("the window solves");
    let mut z = SMatrix::<f64, N, N>::zeros();
    build_z(&case.timing, Basis::Exponential, &mut z);
    let ys = [unknowns(&plan.x), unknowns(&plan.y)];
    let ws = ys.map(|y| {
        let w = z * nalgebra::SVector::<f64, N>::from(y);
        let mut out = [0.0; N];
        out.copy_from_slice(w.as_slice());
        out
    });
    (z, ws, ys)
}

/// Largest difference between two solutions relative to the largest entry of `reference`.
fn relative(a: &[f64; N], reference: &[f64; N]) -> f64 {
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(reference)
        .fold(0.0f64, |m, (u, v)| m.max((u - v).abs()));
    diff / scale
}

/// The three methods on the same `Z` and right-hand sides, for every case of
/// [`check_cases`]: panics unless they agree (and reproduce planner-core's plan) to
/// [`TOLERANCE`].
fn check() {
    println!("check: the three solutions of Z y = w, both planes (largest difference relative to the largest unknown, tolerance {TOLERANCE:e})");
    println!(
        "  {:<48} {:>10} {:>10} {:>10} {:>9}",
        "timing", "LAPACK", "jrl", "plan", "rcond"
    );
    let mut jrl = Gesvx::default();
    for (name, case) in check_cases() {
        let (z, ws, ys) = system(&case);
        let f = Factorized::new(&case.timing).expect("the window factorises");
        // planner-core's solution of each plane (the reference).
        let ours = ws.map(|mut w| {
            f.solve_vector(&mut w);
            w
        });
        // LAPACK: dgetrf + dgetrs with both right-hand sides at once.
        let mut lu = z;
        let mut ipiv = [0; N];
        lapack::dgetrf(&mut lu, &mut ipiv).expect("dgetrf");
        let mut plain = ws;
        lapack::dgetrs(&lu, &ipiv, &mut plain).expect("dgetrs");
        // jrl-walkgen's method: the same dgetrf, then dgesvx with FACT = 'F' per plane.
        let (mut a, mut af) = (z, z);
        lapack::dgetrf(&mut af, &mut ipiv).expect("dgetrf");
        let mut expert = [[0.0; N]; 2];
        let mut rcond = f64::INFINITY;
        for (k, x) in expert.iter_mut().enumerate() {
            let mut b = ws[k];
            let rc = jrl
                .solve(&mut a, &mut af, &mut ipiv, &mut b, x)
                .expect("dgesvx");
            rcond = rcond.min(rc);
        }
        let mut worst = [0.0f64; 3];
        for k in 0..2 {
            worst[0] = worst[0].max(relative(&plain[k], &ours[k]));
            worst[1] = worst[1].max(relative(&expert[k], &ours[k]));
            worst[2] = worst[2].max(relative(&ours[k], &ys[k]));
        }
        println!(
            "  {name:<48} {:>10.1e} {:>10.1e} {:>10.1e} {rcond:>9.1e}",
            worst[0], worst[1], worst[2]
        );
        for (what, v) in ["LAPACK", "jrl-walkgen's method", "planner-core's plan"]
            .iter()
            .zip(worst)
        {
            assert!(
                v <= TOLERANCE,
                "{name}: {what} differs from planner-core's solution by {v:e} relative"
            );
        }
    }
}

/// One way of re-planning; `replan(k)` plans window `k` of [`timed_cases`] (`k` is 0 or 1).
trait Method {
    /// The benchmark id (`replan/<id>`).
    fn id(&self) -> &'static str;
    /// The row label of the summary.
    fn name(&self) -> &'static str;
    /// One re-plan of window `k`.
    fn replan(&mut self, k: usize);
}

/// (a) planner-core as the gait re-plans: `refactor` (builds `Z`) and the two-plane `solve`.
struct Planner {
    cases: [Case; 2],
    factor: Factorized<f64>,
    plan: Plan<f64>,
}

impl Method for Planner {
    fn id(&self) -> &'static str {
        "planner-core"
    }
    fn name(&self) -> &'static str {
        "planner-core (refactor + solve, as the gait)"
    }
    fn replan(&mut self, k: usize) {
        let c = black_box(&self.cases[k]);
        self.factor.refactor(&c.timing).expect("refactor");
        self.factor
            .solve(&c.x, &c.y, &mut self.plan)
            .expect("solve");
        black_box(&self.plan);
    }
}

/// planner-core's linear algebra alone: `refactor` and `solve_vector` on the two ready-made
/// right-hand sides (what the LAPACK rows do).
struct PlannerLinalg {
    cases: [Case; 2],
    rhs: [[[f64; N]; 2]; 2],
    factor: Factorized<f64>,
    out: [[f64; N]; 2],
}

impl Method for PlannerLinalg {
    fn id(&self) -> &'static str {
        "planner-core-linalg"
    }
    fn name(&self) -> &'static str {
        "planner-core, linear algebra only"
    }
    fn replan(&mut self, k: usize) {
        let timing = &black_box(&self.cases[k]).timing;
        self.factor.refactor(timing).expect("refactor");
        self.out = black_box(self.rhs[k]);
        for w in &mut self.out {
            self.factor.solve_vector(w);
        }
        black_box(&self.out);
    }
}

/// (b) plain LAPACK: `build_z`, `dgetrf`, `dgetrs` with both planes.
struct Lapack {
    cases: [Case; 2],
    rhs: [[[f64; N]; 2]; 2],
    z: SMatrix<f64, N, N>,
    ipiv: lapack::Pivots,
    out: [[f64; N]; 2],
}

impl Method for Lapack {
    fn id(&self) -> &'static str {
        "lapack"
    }
    fn name(&self) -> &'static str {
        "LAPACK dgetrf + dgetrs (2 RHS)"
    }
    fn replan(&mut self, k: usize) {
        let timing = &black_box(&self.cases[k]).timing;
        build_z(timing, Basis::Exponential, &mut self.z);
        lapack::dgetrf(&mut self.z, &mut self.ipiv).expect("dgetrf");
        self.out = black_box(self.rhs[k]);
        lapack::dgetrs(&self.z, &self.ipiv, &mut self.out).expect("dgetrs");
        black_box(&self.out);
    }
}

/// (c) jrl-walkgen's method: `build_z`, a copy into `AF`, `dgetrf` once, `dgesvx` with
/// `FACT = 'F'` per plane.
struct Jrl {
    cases: [Case; 2],
    rhs: [[[f64; N]; 2]; 2],
    a: SMatrix<f64, N, N>,
    af: SMatrix<f64, N, N>,
    ipiv: lapack::Pivots,
    b: [f64; N],
    out: [[f64; N]; 2],
    work: Gesvx,
}

impl Method for Jrl {
    fn id(&self) -> &'static str {
        "jrl-walkgen"
    }
    fn name(&self) -> &'static str {
        "jrl-walkgen: dgetrf + 2 x dgesvx FACT='F'"
    }
    fn replan(&mut self, k: usize) {
        let timing = &black_box(&self.cases[k]).timing;
        build_z(timing, Basis::Exponential, &mut self.a);
        self.af.copy_from(&self.a);
        lapack::dgetrf(&mut self.af, &mut self.ipiv).expect("dgetrf");
        for (plane, x) in self.out.iter_mut().enumerate() {
            self.b = black_box(self.rhs[k][plane]);
            self.work
                .solve(&mut self.a, &mut self.af, &mut self.ipiv, &mut self.b, x)
                .expect("dgesvx");
        }
        black_box(&self.out);
    }
}

/// The four methods, in the order of the summary (planner-core first: the ratios' base).
fn methods() -> Vec<Box<dyn Method>> {
    let cases = timed_cases();
    let rhs = cases.map(|c| system(&c).1);
    let zero = SMatrix::<f64, N, N>::zeros();
    vec![
        Box::new(Planner {
            cases,
            factor: Factorized::empty(),
            plan: Plan::zeroed(cases[0].timing),
        }),
        Box::new(PlannerLinalg {
            cases,
            rhs,
            factor: Factorized::empty(),
            out: [[0.0; N]; 2],
        }),
        Box::new(Lapack {
            cases,
            rhs,
            z: zero,
            ipiv: [0; N],
            out: [[0.0; N]; 2],
        }),
        Box::new(Jrl {
            cases,
            rhs,
            a: zero,
            af: zero,
            ipiv: [0; N],
            b: [0.0; N],
            out: [[0.0; N]; 2],
            work: Gesvx::default(),
        }),
    ]
}

/// Criterion's timings, one benchmark per method (`replan/<method>`).
fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("replan");
    for mut m in methods() {
        let mut k = 0;
        group.bench_function(m.id(), |b| {
            b.iter(|| {
                m.replan(k);
                k ^= 1;
            })
        });
    }
    group.finish();
}

/// The CPU model, from the first `model name` line of `/proc/cpuinfo` (or, on machines that
/// have none, `Hardware`, `cpu model` or `cpu`); "unknown" without the file or the line.
fn cpu_model() -> String {
    let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") else {
        return "unknown".into();
    };
    let field = |key: &str| {
        info.lines().find_map(|line| {
            let (k, v) = line.split_once(':')?;
            (k.trim() == key && !v.trim().is_empty()).then(|| v.trim().to_string())
        })
    };
    ["model name", "Hardware", "cpu model", "cpu"]
        .into_iter()
        .find_map(field)
        .unwrap_or_else(|| "unknown".into())
}

/// The 1-minute load average, the first field of `/proc/loadavg`; "unknown" without it.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

/// The machine in one line: CPU model and online CPUs.
fn machine() -> String {
    let cpus = sys::online_cpus().map_or_else(|| "unknown".into(), |n| n.to_string());
    format!("{}, {cpus} online CPUs", cpu_model())
}

/// One batch's time on both clocks.
#[derive(Clone, Copy, Debug, Default)]
struct Sample {
    /// The calling thread's CPU time.
    cpu: Duration,
    /// Wall-clock time.
    wall: Duration,
}

/// Runs `work` once and times it on both clocks (wall clock outside, thread CPU inside).
fn timed(work: impl FnOnce()) -> Sample {
    let wall = Instant::now();
    let cpu = sys::thread_cpu_time();
    work();
    let cpu = sys::thread_cpu_time() - cpu;
    Sample {
        cpu,
        wall: wall.elapsed(),
    }
}

/// The median of `t` (sorts it).
fn median(t: &mut [Duration]) -> Duration {
    t.sort();
    t[t.len() / 2]
}

/// Times the methods interleaved: `rounds` rounds, each timing a batch of `batch` re-plans of
/// every method (the order rotated by one each round), every batch in thread CPU time and in
/// wall-clock time; prints the median time per re-plan of each method and the ratios to
/// planner-core on both clocks, and the machine (`load_at_start`: the 1-minute load average
/// when the run began).
fn summary(rounds: usize, batch: usize, note: &str, load_at_start: &str) {
    let mut methods = methods();
    let mut samples: Vec<Vec<Sample>> = vec![Vec::with_capacity(rounds); methods.len()];
    // Warm-up: caches, branch predictors, the CPU's clock.
    for m in methods.iter_mut() {
        for i in 0..batch {
            m.replan(i & 1);
        }
    }
    let per = u32::try_from(batch).expect("batch fits in u32");
    for round in 0..rounds {
        for step in 0..methods.len() {
            let index = (round + step) % methods.len();
            let m = &mut methods[index];
            let s = timed(|| {
                for i in 0..batch {
                    m.replan(i & 1);
                }
            });
            samples[index].push(Sample {
                cpu: s.cpu / per,
                wall: s.wall / per,
            });
        }
    }
    // What reading the two clocks costs (an empty batch), included in every batch above.
    let empty: Vec<Sample> = (0..rounds).map(|_| timed(|| ())).collect();
    let clock_cpu = median(&mut empty.iter().map(|s| s.cpu).collect::<Vec<_>>());
    let clock_wall = median(&mut empty.iter().map(|s| s.wall).collect::<Vec<_>>());
    let (total_cpu, total_wall) = samples
        .iter()
        .flatten()
        .fold((Duration::ZERO, Duration::ZERO), |(c, w), s| {
            (c + s.cpu, w + s.wall)
        });
    let cpu: Vec<f64> = samples
        .iter()
        .map(|t| median(&mut t.iter().map(|s| s.cpu).collect::<Vec<_>>()).as_secs_f64())
        .collect();
    let wall: Vec<f64> = samples
        .iter()
        .map(|t| median(&mut t.iter().map(|s| s.wall).collect::<Vec<_>>()).as_secs_f64())
        .collect();
    let load_at_end = load_average();

    println!(
        "\nper re-plan (build Z, factorise, solve x and y): median of {rounds} interleaved rounds of {batch} re-plans per method, each batch timed in the thread's CPU time and in wall-clock time{note}"
    );
    println!(
        "  {:<44} {:>10} {:>16}   {:>10} {:>16}",
        "", "thread CPU", "× planner-core", "wall clock", "× planner-core"
    );
    for (i, m) in methods.iter().enumerate() {
        println!(
            "  {:<44} {:>7.2} µs {:>16.2}   {:>7.2} µs {:>16.2}",
            m.name(),
            cpu[i] * 1e6,
            cpu[i] / cpu[0],
            wall[i] * 1e6,
            wall[i] / wall[0],
        );
    }
    for (clock, t) in [("thread CPU", &cpu), ("wall clock", &wall)] {
        println!(
            "  ratios, {clock}: LAPACK/planner-core {:.2}, jrl/planner-core {:.2} (planner-core linear algebra only: {:.2}, {:.2})",
            t[2] / t[0],
            t[3] / t[0],
            t[2] / t[1],
            t[3] / t[1],
        );
    }
    println!(
        "  thread CPU / wall clock over all timed batches: {:.1} %; reading both clocks: {:.2} µs thread CPU, {:.2} µs wall per batch (included, not subtracted)",
        100.0 * total_cpu.as_secs_f64() / total_wall.as_secs_f64(),
        clock_cpu.as_secs_f64() * 1e6,
        clock_wall.as_secs_f64() * 1e6,
    );
    println!(
        "  machine: {}; 1-minute load average {load_at_start} at the start of the run, {load_at_end} at the end",
        machine()
    );
}

fn main() {
    let load_at_start = load_average();
    println!(
        "machine: {}; 1-minute load average {load_at_start}",
        machine()
    );
    check();
    let bench_mode = std::env::args().any(|a| a == "--bench");
    let mut criterion = Criterion::default().configure_from_args();
    bench(&mut criterion);
    criterion.final_summary();
    if bench_mode {
        summary(101, 200, "", &load_at_start);
    } else {
        summary(
            3,
            10,
            " (test mode: a quick run of the code, not a measurement)",
            &load_at_start,
        );
    }
}
