//! Independent oracles for the window solver.
//!
//! 1. The paper's *general* formulation (section IV, conditions (I)–(V)) built from scratch with
//!    a dense 44×44 `nalgebra::DMatrix` and solved by full-pivoting LU in f64: unknowns are
//!    `V_j, W_j` (the paper's `cosh/sinh` basis, local time per interval) and every ZMP
//!    coefficient `a_i^{(j)}`, with orders `N = [4,3,3,3,3,3,4]`. It shares no code with the
//!    planner (own COG polynomial recursion, own rows, std `cosh/sinh`, own interval lookup).
//! 2. A fixed-step RK4 integration of `ẍ = ω²(x − p(t))` driven by the planner's ZMP.
//! 3. Every boundary condition of the window, and the pendulum equation at sample points.
//! 4. Error cases and the "output untouched on error" contract.
//!
//! Run `cargo test -p planner-core --test oracle -- --nocapture` to see the measured figures;
//! test 1 asserts that the front page and the solver's page quote its figures as measured.

use nalgebra::{DMatrix, DVector};
use planner_core::window::{Factorized, Plan, PlanError, PlaneBoundary, Timing, M};
use planner_core::{Segment, State};

/// Number of unknowns of the general formulation: `2m + Σ(N_j + 1)` = 14 + 30.
const N_FULL: usize = 44;
/// ZMP polynomial orders of the general formulation.
const ORDERS: [usize; M] = [4, 3, 3, 3, 3, 3, 4];

fn omega() -> f64 {
    (9.8_f64 / 0.814).sqrt()
}

/// One test window: durations and both planes.
struct Window {
    name: &'static str,
    durations: [f64; M],
    x: PlaneBoundary<f64>,
    y: PlaneBoundary<f64>,
}

/// A walk of `step` metres per step: in single support the ZMP via point is the support-foot
/// centre, in double support it moves to the next foot (via velocities 0). Feet alternate at
/// `y = ±0.1` m. `first_ss` says whether interval 1 is a single support.
fn walk(
    name: &'static str,
    durations: [f64; M],
    first_ss: bool,
    step: f64,
    zmp_start: (State<f64>, State<f64>),
) -> Window {
    let mut foot = 0i32;
    let mut xv = [State::default(); M];
    let mut yv = [State::default(); M];
    for j in 0..M {
        let ss = (j % 2 == 0) == first_ss;
        if !ss {
            foot += 1;
        }
        xv[j] = State::at_rest(step * foot as f64);
        yv[j] = State::at_rest(if foot % 2 == 0 { 0.1 } else { -0.1 });
    }
    Window {
        name,
        durations,
        x: PlaneBoundary {
            cog_start: State::new(-0.03, 0.3),
            zmp_start: zmp_start.0,
            via: xv,
            cog_end: State::at_rest(xv[M - 1].pos),
        },
        y: PlaneBoundary {
            cog_start: State::new(0.05, -0.12),
            zmp_start: zmp_start.1,
            via: yv,
            cog_end: State::at_rest(yv[M - 1].pos),
        },
    }
}

fn windows() -> Vec<Window> {
    vec![
        walk(
            "HRP-2 0.7/0.1 s, 0.2 m steps",
            [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7],
            true,
            0.2,
            (State::at_rest(0.0), State::at_rest(0.1)),
        ),
        walk(
            "irregular durations, moving initial ZMP",
            [0.45, 0.1, 0.8, 0.15, 0.7, 0.12, 1.05],
            true,
            0.2,
            (State::new(0.01, 0.05), State::new(0.09, -0.03)),
        ),
        walk(
            "starting in double support",
            [0.1, 0.7, 0.1, 0.7, 0.1, 0.7, 0.1],
            false,
            0.2,
            (State::at_rest(0.0), State::at_rest(0.1)),
        ),
    ]
}

fn timing(w: &Window) -> Timing<f64> {
    Timing {
        omega: omega(),
        durations: w.durations,
    }
}

fn planner_plan(w: &Window) -> Plan<f64> {
    let t = timing(w);
    let f = Factorized::new(&t).expect("valid timing");
    let mut plan = Plan::zeroed(t);
    f.solve(&w.x, &w.y, &mut plan).expect("solvable window");
    plan
}

fn plane(plan: &Plan<f64>, k: usize) -> &[Segment<f64>; M] {
    if k == 0 {
        &plan.x
    } else {
        &plan.y
    }
}

fn boundary(w: &Window, k: usize) -> &PlaneBoundary<f64> {
    if k == 0 {
        &w.x
    } else {
        &w.y
    }
}

// ---------------------------------------------------------------------------------------------
// The general formulation, from scratch.
// ---------------------------------------------------------------------------------------------

/// The COG polynomial `A` of the ZMP polynomial `a` (local time): `x = Σ A_i τ^i` solves
/// `p = x − ẍ/ω²` iff `a_i = A_i − (i+1)(i+2) A_{i+2}/ω²`, so from the top down
/// `A_i = a_i + (i+1)(i+2) A_{i+2}/ω²` (with `A_{N+1} = A_{N+2} = 0`).
fn cog_coeffs(a: &[f64], w: f64) -> Vec<f64> {
    let n = a.len();
    let mut big = vec![0.0; n];
    for i in (0..n).rev() {
        let above = if i + 2 < n { big[i + 2] } else { 0.0 };
        big[i] = a[i] + ((i + 1) * (i + 2)) as f64 * above / (w * w);
    }
    big
}

/// `d^der/dτ^der τ^i` at `tau` (der ∈ {0, 1}).
fn mono(i: usize, tau: f64, der: usize) -> f64 {
    match der {
        0 => tau.powi(i as i32),
        _ => {
            if i == 0 {
                0.0
            } else {
                i as f64 * tau.powi(i as i32 - 1)
            }
        }
    }
}

/// Column layout: `[V_1 W_1 … V_7 W_7 | a^(1)_0..a^(1)_4 | a^(2)_0..a^(2)_3 | … | a^(7)_0..4]`.
fn vcol(j: usize) -> usize {
    2 * j
}
fn acol(j: usize) -> usize {
    2 * M + ORDERS[..j].iter().map(|n| n + 1).sum::<usize>()
}

/// The row of `x^{(j)}` (der = 0) or `ẋ^{(j)}` (der = 1) at local time `tau`, in terms of the
/// unknowns: `x = V cosh ωτ + W sinh ωτ + Σ_i A_i τ^i`, `A` linear in `a`.
fn cog_row(row: &mut [f64], j: usize, tau: f64, der: usize, w: f64, sign: f64) {
    let (c, s) = ((w * tau).cosh(), (w * tau).sinh());
    let (hv, hw) = if der == 0 { (c, s) } else { (w * s, w * c) };
    row[vcol(j)] += sign * hv;
    row[vcol(j) + 1] += sign * hw;
    let n = ORDERS[j] + 1;
    for k in 0..n {
        // Column of a_k: the COG polynomial of the ZMP monomial τ^k.
        let mut unit = vec![0.0; n];
        unit[k] = 1.0;
        let big = cog_coeffs(&unit, w);
        let v: f64 = (0..n).map(|i| big[i] * mono(i, tau, der)).sum();
        row[acol(j) + k] += sign * v;
    }
}

/// The row of `p^{(j)}` (der = 0) or `ṗ^{(j)}` (der = 1) at local time `tau`: `p = Σ a_i τ^i`.
fn zmp_row(row: &mut [f64], j: usize, tau: f64, der: usize) {
    for k in 0..=ORDERS[j] {
        row[acol(j) + k] += mono(k, tau, der);
    }
}

/// The solution of the general formulation for one plane.
struct Oracle {
    w: f64,
    durations: [f64; M],
    v: [f64; M],
    wc: [f64; M],
    /// ZMP coefficients `a^{(j)}` in local time.
    a: Vec<Vec<f64>>,
    /// Normwise backward error of the dense solve, `‖Z y − w‖∞ / (‖Z‖∞ ‖y‖∞ + ‖w‖∞)`.
    residual: f64,
}

impl Oracle {
    fn solve(durations: [f64; M], w: f64, b: &PlaneBoundary<f64>) -> Self {
        let mut z = DMatrix::<f64>::zeros(N_FULL, N_FULL);
        let mut rhs = DVector::<f64>::zeros(N_FULL);
        let mut r = 0;
        let mut push = |z: &mut DMatrix<f64>, f: &dyn Fn(&mut [f64]), value: f64| {
            let mut row = vec![0.0; N_FULL];
            f(&mut row);
            for (c, v) in row.iter().enumerate() {
                z[(r, c)] = *v;
            }
            rhs[r] = value;
            r += 1;
        };
        let d = durations;
        // (I) initial COG position and velocity.
        push(
            &mut z,
            &|row| cog_row(row, 0, 0.0, 0, w, 1.0),
            b.cog_start.pos,
        );
        push(
            &mut z,
            &|row| cog_row(row, 0, 0.0, 1, w, 1.0),
            b.cog_start.vel,
        );
        // (II) COG position and velocity continuous at T_1 … T_6.
        for (j, &dj) in d.iter().enumerate().take(M - 1) {
            for der in 0..2 {
                push(
                    &mut z,
                    &|row| {
                        cog_row(row, j, dj, der, w, 1.0);
                        cog_row(row, j + 1, 0.0, der, w, -1.0);
                    },
                    0.0,
                );
            }
        }
        // (III) terminal COG position and velocity.
        push(
            &mut z,
            &|row| cog_row(row, M - 1, d[M - 1], 0, w, 1.0),
            b.cog_end.pos,
        );
        push(
            &mut z,
            &|row| cog_row(row, M - 1, d[M - 1], 1, w, 1.0),
            b.cog_end.vel,
        );
        // (IV) ZMP position and velocity at the start of every interval: the initial ZMP for
        // interval 1, the via point at the end of the previous interval otherwise.
        for j in 0..M {
            let s = if j == 0 { b.zmp_start } else { b.via[j - 1] };
            push(&mut z, &|row| zmp_row(row, j, 0.0, 0), s.pos);
            push(&mut z, &|row| zmp_row(row, j, 0.0, 1), s.vel);
        }
        // (V) ZMP position and velocity at the end of every interval: the via point.
        for (j, (&dj, via)) in d.iter().zip(&b.via).enumerate() {
            push(&mut z, &|row| zmp_row(row, j, dj, 0), via.pos);
            push(&mut z, &|row| zmp_row(row, j, dj, 1), via.vel);
        }
        assert_eq!(r, N_FULL, "6m + 2 = 44 conditions");
        let lu = z.clone().full_piv_lu();
        let y = lu.solve(&rhs).expect("the 44×44 system is non-singular");
        let z_norm = z
            .row_iter()
            .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let residual = (&z * &y - &rhs).amax() / (z_norm * y.amax() + rhs.amax());
        let mut v = [0.0; M];
        let mut wc = [0.0; M];
        let mut a = Vec::new();
        for j in 0..M {
            v[j] = y[vcol(j)];
            wc[j] = y[vcol(j) + 1];
            a.push((0..=ORDERS[j]).map(|k| y[acol(j) + k]).collect::<Vec<_>>());
        }
        Oracle {
            w,
            durations,
            v,
            wc,
            a,
            residual,
        }
    }

    /// Interval containing window time `t` and the local time in it (own implementation).
    fn locate(&self, t: f64) -> (usize, f64) {
        let mut start = 0.0;
        for j in 0..M {
            if t < start + self.durations[j] || j == M - 1 {
                return (j, (t - start).min(self.durations[j]));
            }
            start += self.durations[j];
        }
        unreachable!()
    }

    /// `(x, ẋ, p)` at window time `t`.
    fn sample(&self, t: f64) -> (f64, f64, f64) {
        let (j, tau) = self.locate(t);
        let w = self.w;
        let big = cog_coeffs(&self.a[j], w);
        let (c, s) = ((w * tau).cosh(), (w * tau).sinh());
        let x = self.v[j] * c
            + self.wc[j] * s
            + (0..big.len())
                .map(|i| big[i] * mono(i, tau, 0))
                .sum::<f64>();
        let xd = w * (self.v[j] * s + self.wc[j] * c)
            + (0..big.len())
                .map(|i| big[i] * mono(i, tau, 1))
                .sum::<f64>();
        let p = (0..self.a[j].len())
            .map(|i| self.a[j][i] * mono(i, tau, 0))
            .sum();
        (x, xd, p)
    }
}

/// Test 1: the planner's 20×20 reduced solve equals the paper's 44×44 general formulation.
///
/// Tolerances: COG and ZMP positions agree to 1e-9 m at 2001 sample times per window and
/// plane; COG velocity to 1e-8 m/s; `V, W` to `1e-9·(1 + |V|)` (resp. `|W|`) m; the ZMP
/// coefficients `a_i` (local time) to `1e-9·(1 + |a_i|)·max(1, D^{-i})` (m/s^i, the `D^{-i}`
/// because a coefficient error δ of the normalised polynomial shows as `δ/D^i` in `a_i`).
#[test]
fn planner_matches_the_general_44_unknown_formulation() {
    let mut worst_cog = 0.0_f64;
    let mut worst_zmp = 0.0_f64;
    let mut worst_vel = 0.0_f64;
    let mut worst_vw = 0.0_f64;
    let mut worst_a = 0.0_f64;
    let mut worst_res = 0.0_f64;
    for win in &windows() {
        let plan = planner_plan(win);
        let total: f64 = win.durations.iter().sum();
        for k in 0..2 {
            let oracle = Oracle::solve(win.durations, omega(), boundary(win, k));
            worst_res = worst_res.max(oracle.residual);
            // A backward-stable solve: backward error a small multiple of ε = 2.2e-16.
            assert!(
                oracle.residual < 1e-14,
                "oracle backward error {}",
                oracle.residual
            );
            let segs = plane(&plan, k);
            let (mut e_cog, mut e_zmp, mut e_vel) = (0.0_f64, 0.0_f64, 0.0_f64);
            const SAMPLES: usize = 2000;
            for i in 0..=SAMPLES {
                let t = total * i as f64 / SAMPLES as f64;
                let (sx, sy) = plan.sample(t);
                let s = if k == 0 { sx } else { sy };
                let (x, xd, p) = oracle.sample(t);
                e_cog = e_cog.max((s.cog - x).abs());
                e_vel = e_vel.max((s.cog_vel - xd).abs());
                e_zmp = e_zmp.max((s.zmp - p).abs());
            }
            // The paper's V, W and a_i of every interval.
            let mut e_vw = 0.0_f64;
            let mut e_a = 0.0_f64;
            for (j, seg) in segs.iter().enumerate() {
                let (v, w) = seg.vw();
                e_vw = e_vw
                    .max((v - oracle.v[j]).abs() / (1.0 + oracle.v[j].abs()))
                    .max((w - oracle.wc[j]).abs() / (1.0 + oracle.wc[j].abs()));
                let a = seg.zmp_tau();
                for (i, &ai) in a.iter().enumerate() {
                    let o = oracle.a[j].get(i).copied().unwrap_or(0.0);
                    let scale = (1.0 + o.abs()) * win.durations[j].powi(-(i as i32)).max(1.0);
                    e_a = e_a.max((ai - o).abs() / scale);
                }
            }
            eprintln!(
                "{:<42} plane {}: COG {:.2e} m, COG vel {:.2e} m/s, ZMP {:.2e} m, V/W rel {:.2e}, a_i rel {:.2e}, 44×44 backward error {:.1e}",
                win.name,
                ["x", "y"][k],
                e_cog,
                e_vel,
                e_zmp,
                e_vw,
                e_a,
                oracle.residual
            );
            assert!(e_cog <= 1e-9, "{}: COG differs by {e_cog} m", win.name);
            assert!(e_zmp <= 1e-9, "{}: ZMP differs by {e_zmp} m", win.name);
            assert!(e_vel <= 1e-8, "{}: COG vel differs by {e_vel}", win.name);
            assert!(e_vw <= 1e-9, "{}: V/W differ by {e_vw} (rel)", win.name);
            assert!(e_a <= 1e-9, "{}: a_i differ by {e_a} (rel)", win.name);
            worst_cog = worst_cog.max(e_cog);
            worst_zmp = worst_zmp.max(e_zmp);
            worst_vel = worst_vel.max(e_vel);
            worst_vw = worst_vw.max(e_vw);
            worst_a = worst_a.max(e_a);
        }
    }
    eprintln!(
        "oracle (44×44 full-pivot LU) vs planner, worst: COG {worst_cog:.2e} m, COG vel {worst_vel:.2e} m/s, ZMP {worst_zmp:.2e} m, V/W rel {worst_vw:.2e}, a_i rel {worst_a:.2e}, backward error {worst_res:.1e}"
    );
    // The front page and the solver's page quote these figures (two significant digits) and
    // the tolerance of the COG and ZMP assertions above.
    let figure = format!(
        "COG {:.1e} m, ZMP {:.1e} m (tolerance {:e})",
        worst_cog, worst_zmp, 1e-9
    );
    // (the documents are files: not read under Miri, whose isolation forbids it)
    if !cfg!(miri) {
        doc_figures::assert_quoted(
            "README.md",
            "paper's general 44-unknown formulation",
            &figure,
            COMMAND,
        );
    }
    // (the documents are files: not read under Miri, whose isolation forbids it)
    if !cfg!(miri) {
        doc_figures::assert_quoted(
            "docs/src/solver.md",
            "the general 44-unknown formulation",
            &figure,
            COMMAND,
        );
    }
}

/// The command that measures this file's figures (the documents name it).
const COMMAND: &str = "cargo test -p planner-core --test oracle -- --nocapture";

/// The oracle really is a different computation: it must notice a wrong boundary value.
#[test]
fn oracle_detects_a_perturbed_boundary() {
    let win = &windows()[0];
    let plan = planner_plan(win);
    let mut b = win.x;
    b.via[3].pos += 1e-6;
    let oracle = Oracle::solve(win.durations, omega(), &b);
    let total: f64 = win.durations.iter().sum();
    let mut e = 0.0_f64;
    for i in 0..=1000 {
        let t = total * i as f64 / 1000.0;
        e = e.max((plan.sample(t).0.zmp - oracle.sample(t).2).abs());
    }
    assert!(e > 5e-7, "a 1 µm via-point change went unnoticed ({e})");
}

// ---------------------------------------------------------------------------------------------
// RK4 integration of the pendulum driven by the planner's ZMP.
// ---------------------------------------------------------------------------------------------

/// Test 2: integrate `ẍ = ω²(x − p(t))` from the initial COG state with fixed-step RK4 (at most
/// 1e-4 s, each interval split into equal steps so that the boundaries are hit exactly), the
/// ZMP being the planner's piecewise polynomial, and compare with the planner's closed-form COG
/// at every step. Tolerances: position 1e-6 m, velocity 1e-5 m/s. (The unstable mode grows
/// like e^{ωt} ≈ 1e5 over a 3.4 s window, which amplifies rounding and truncation; the RK4
/// truncation error itself is O((ωh)⁴) ≈ 1e-14 per unit time.)
#[test]
fn rk4_integration_matches_the_closed_form_cog() {
    const DT: f64 = 1e-4;
    let w = omega();
    let mut worst_pos = 0.0_f64;
    let mut worst_vel = 0.0_f64;
    for win in &windows() {
        let plan = planner_plan(win);
        for k in 0..2 {
            let segs = plane(&plan, k);
            let start = boundary(win, k).cog_start;
            let (mut x, mut v) = (start.pos, start.vel);
            let (mut e_pos, mut e_vel) = (0.0_f64, 0.0_f64);
            let mut steps = 0usize;
            for (j, seg) in segs.iter().enumerate() {
                let d = win.durations[j];
                let n = (d / DT).ceil() as usize;
                let h = d / n as f64;
                let p = |tau: f64| seg.sample(tau).zmp;
                let acc = |x: f64, tau: f64| w * w * (x - p(tau));
                for i in 0..n {
                    let tau = i as f64 * h;
                    let (k1x, k1v) = (v, acc(x, tau));
                    let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, tau + 0.5 * h));
                    let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, tau + 0.5 * h));
                    let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, tau + h));
                    x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
                    v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
                    // Compare at the end of the step (the last step lands on τ = D exactly).
                    let tau1 = if i + 1 == n { d } else { (i + 1) as f64 * h };
                    let s = seg.sample(tau1);
                    e_pos = e_pos.max((s.cog - x).abs());
                    e_vel = e_vel.max((s.cog_vel - v).abs());
                    assert!(
                        (s.cog - x).abs() <= 1e-6 && (s.cog_vel - v).abs() <= 1e-5,
                        "{} plane {k} interval {j} τ={tau1}: RK4 ({x}, {v}) vs planner ({}, {})",
                        win.name,
                        s.cog,
                        s.cog_vel
                    );
                    steps += 1;
                }
            }
            eprintln!(
                "{:<42} plane {}: RK4 ({} steps) vs closed form: pos {:.2e} m, vel {:.2e} m/s",
                win.name,
                ["x", "y"][k],
                steps,
                e_pos,
                e_vel
            );
            worst_pos = worst_pos.max(e_pos);
            worst_vel = worst_vel.max(e_vel);
        }
    }
    eprintln!("RK4 (h ≤ 1e-4 s) vs planner, worst: pos {worst_pos:.2e} m, vel {worst_vel:.2e} m/s");
    // (the documents are files: not read under Miri, whose isolation forbids it)
    if !cfg!(miri) {
        doc_figures::assert_quoted(
            "docs/src/solver.md",
            "RK4 integration of",
            &format!("{worst_pos:.1e} m, {worst_vel:.1e} m/s (tolerance 1e-6 m)"),
            COMMAND,
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Boundary conditions and the pendulum equation.
// ---------------------------------------------------------------------------------------------

/// Test 3: every condition of the window holds to 1e-9 (m for positions, m/s for velocities,
/// m/s² for the pendulum residual `ẍ − ω²(x − p)`), evaluating segment j at τ = D_j and
/// segment j+1 at τ = 0.
#[test]
fn boundary_conditions_hold() {
    const TOL: f64 = 1e-9;
    let w = omega();
    let mut worst = 0.0_f64;
    let mut worst_ode = 0.0_f64;
    for win in &windows() {
        let plan = planner_plan(win);
        for k in 0..2 {
            let segs = plane(&plan, k);
            let b = boundary(win, k);
            let mut check = |what: &str, got: f64, want: f64| {
                let e = (got - want).abs();
                worst = worst.max(e);
                assert!(
                    e <= TOL,
                    "{} plane {k}: {what}: {got} vs {want} (error {e})",
                    win.name
                );
            };
            let first = segs[0].sample(0.0);
            check("initial COG position", first.cog, b.cog_start.pos);
            check("initial COG velocity", first.cog_vel, b.cog_start.vel);
            check("initial ZMP position", first.zmp, b.zmp_start.pos);
            check("initial ZMP velocity", first.zmp_vel, b.zmp_start.vel);
            for j in 0..M {
                let end = segs[j].sample(win.durations[j]);
                let via = b.via[j];
                check(&format!("ZMP position at T_{}", j + 1), end.zmp, via.pos);
                check(
                    &format!("ZMP velocity at T_{}", j + 1),
                    end.zmp_vel,
                    via.vel,
                );
                if j + 1 < M {
                    let next = segs[j + 1].sample(0.0);
                    check(&format!("COG position at T_{}", j + 1), next.cog, end.cog);
                    check(
                        &format!("COG velocity at T_{}", j + 1),
                        next.cog_vel,
                        end.cog_vel,
                    );
                    check(&format!("ZMP position at T_{}+", j + 1), next.zmp, via.pos);
                    check(
                        &format!("ZMP velocity at T_{}+", j + 1),
                        next.zmp_vel,
                        via.vel,
                    );
                } else {
                    check("terminal COG position", end.cog, b.cog_end.pos);
                    check("terminal COG velocity", end.cog_vel, b.cog_end.vel);
                }
                for i in 0..=50 {
                    let s = segs[j].sample(win.durations[j] * i as f64 / 50.0);
                    let r = (s.cog_acc - w * w * (s.cog - s.zmp)).abs();
                    worst_ode = worst_ode.max(r);
                    assert!(
                        r <= TOL,
                        "{} plane {k} interval {j} sample {i}: ẍ − ω²(x − p) = {r}",
                        win.name
                    );
                }
            }
        }
    }
    eprintln!(
        "boundary conditions: worst error {worst:.2e}; pendulum residual {worst_ode:.2e} m/s²"
    );
    // (the documents are files: not read under Miri, whose isolation forbids it)
    if !cfg!(miri) {
        doc_figures::assert_quoted(
            "docs/src/solver.md",
            "every boundary condition of a window",
            &format!("{worst:.1e}, pendulum residual {worst_ode:.1e} m/s² (tolerance 1e-9)"),
            COMMAND,
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Errors.
// ---------------------------------------------------------------------------------------------

/// Test 4a: a zero, negative, NaN or infinite duration is `BadDuration` with its index.
#[test]
fn bad_durations_are_rejected_with_their_index() {
    let base = timing(&windows()[0]);
    for index in 0..M {
        for bad in [0.0, -0.0, -0.1, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut t = base;
            t.durations[index] = bad;
            assert_eq!(
                Factorized::new(&t).unwrap_err(),
                PlanError::BadDuration { index: index as u8 },
                "duration {bad} at {index}"
            );
        }
    }
    // The first bad interval is the one reported.
    let mut t = base;
    t.durations[2] = f64::NAN;
    t.durations[5] = -1.0;
    assert_eq!(
        Factorized::new(&t).unwrap_err(),
        PlanError::BadDuration { index: 2 }
    );
}

/// Test 4b: a NaN (or infinite) boundary value in either plane is `NonFinite`, and the output
/// plan is left exactly as it was (bit for bit: the plan holds no NaN, so `==` is exact).
#[test]
fn non_finite_boundaries_are_rejected_and_leave_the_plan_untouched() {
    let win = &windows()[1];
    let t = timing(win);
    let f = Factorized::new(&t).expect("valid timing");
    let mut plan = Plan::zeroed(t);
    f.solve(&win.x, &win.y, &mut plan).expect("solvable");
    let before = plan;
    type Poke = fn(&mut PlaneBoundary<f64>, f64);
    let pokes: [(&str, Poke); 7] = [
        ("via[0].pos", |b, v| b.via[0].pos = v),
        ("via[4].pos", |b, v| b.via[4].pos = v),
        ("via[6].vel", |b, v| b.via[6].vel = v),
        ("cog_start.pos", |b, v| b.cog_start.pos = v),
        ("cog_start.vel", |b, v| b.cog_start.vel = v),
        ("zmp_start.vel", |b, v| b.zmp_start.vel = v),
        ("cog_end.pos", |b, v| b.cog_end.pos = v),
    ];
    for (name, poke) in pokes {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for k in 0..2 {
                let (mut x, mut y) = (win.x, win.y);
                poke(if k == 0 { &mut x } else { &mut y }, bad);
                assert_eq!(
                    f.solve(&x, &y, &mut plan),
                    Err(PlanError::NonFinite),
                    "{name} = {bad} in plane {k}"
                );
                assert!(
                    plan == before,
                    "{name} = {bad} in plane {k}: plan was modified"
                );
            }
        }
    }
    // A different, valid plan is still accepted afterwards and does change the output.
    let mut x = win.x;
    x.via[3].pos += 0.05;
    f.solve(&x, &win.y, &mut plan).expect("solvable");
    assert!(plan != before);
}
