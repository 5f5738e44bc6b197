//! The paper's figures reproduced end to end through the gait API (Fig. 4, Table II and the
//! lateral change of section V), and the book's table of them (`docs/src/gait.md`, "Figures")
//! quotes each as measured (`walk_tests::figures`).
//!
//! Run with `-- --nocapture` to see the grids side by side.

use host_sim::eval::paper::{
    cells_within, modification, table, without_adjustment, PAPER_ADJUST_S, STEP_LENGTHS,
};
use planner_core::gait::{GaitParams, Tail};
use walk_tests::figures::Quotes;

/// The command that measures the figures of this file.
const COMMAND: &str = "cargo test -p walk-tests --test paper -- --nocapture";
/// The book's chapter on the gait, whose "Figures" table quotes them.
const GAIT: &str = "docs/src/gait.md";
/// The column of that table with our figures.
const OURS: &str = "ours";

/// `x` with its sign as the book writes it: `+0.065`, `−0.085` (a minus sign, U+2212).
fn signed(x: f64, decimals: usize) -> String {
    if x < 0.0 {
        format!("\u{2212}{:.*}", decimals, -x)
    } else {
        format!("+{x:.decimals$}")
    }
}

#[test]
fn fig4_adjustment_removes_the_backward_fluctuation() {
    let p = GaitParams::<f64>::hrp2();
    let without = modification(without_adjustment(p), 0.1, 0.3);
    let mut bare = without_adjustment(p);
    bare.shaping = false;
    let bare = modification(bare, 0.1, 0.3);
    let with = modification(p, 0.1, 0.3);
    eprintln!(
        "Fig. 4 (0.1 -> 0.3 m at 4.0 s): without adjustment {:.1} mm, and {:.1} mm without shaping \
         either (paper: 26 mm backward); with dT = {:+.3} s (paper: +0.31 s) {:.2} mm (paper: about 1 mm)",
        without.sagittal_m * 1e3,
        bare.sagittal_m * 1e3,
        with.adjust_s,
        with.sagittal_m * 1e3
    );
    // Backward (negative) and large without adjustment, as in the paper.
    assert!(without.sagittal_m < -0.02, "{}", without.sagittal_m);
    assert!(
        bare.sagittal_m < without.sagittal_m,
        "shaping should reduce it"
    );
    // The paper's 0.31 s within two control cycles.
    assert!(
        (with.adjust_s - 0.31).abs() <= 0.010 + 1e-9,
        "{}",
        with.adjust_s
    );
    // Nearly flat with the adjustment (paper: about 1 mm).
    assert!(with.sagittal_m.abs() < 0.002, "{}", with.sagittal_m);
    Quotes::new(COMMAND)
        .cell(
            GAIT,
            "Fig. 4, 0.1 → 0.3 m at 4.0 s: ΔT",
            OURS,
            &format!("{} s", signed(with.adjust_s, 3)),
        )
        .cell(
            GAIT,
            "no adjustment, no shaping",
            OURS,
            &format!("{:.1} mm", bare.sagittal_m.abs() * 1e3),
        )
        .cell(
            GAIT,
            "Fig. 4: the same with shaping",
            OURS,
            &format!("{:.1} mm", without.sagittal_m.abs() * 1e3),
        )
        .cell(
            GAIT,
            "Fig. 4: with adjustment",
            OURS,
            &format!("{:.2} mm", with.sagittal_m.abs() * 1e3),
        )
        .assert();
}

fn print_grid(name: &str, grid: &[Vec<host_sim::eval::paper::Modification>]) {
    eprintln!("{name}: adjustment [s], ours / paper (rows: after, columns: before)");
    eprint!("{:>7}", "");
    for b in STEP_LENGTHS {
        eprint!("{b:>15.1}");
    }
    eprintln!();
    for (r, row) in grid.iter().enumerate() {
        eprint!("{:>7.1}", STEP_LENGTHS[r]);
        for (c, m) in row.iter().enumerate() {
            eprint!("{:>8.3}/{:<6.3}", m.adjust_s, PAPER_ADJUST_S[r][c]);
        }
        eprintln!();
    }
}

#[test]
fn table2_adjustment_times_agree_with_the_paper() {
    let mut p = GaitParams::<f64>::hrp2();
    let grid = table(p);
    let within1 = cells_within(&grid, p.dt, 1.0);
    let exact = cells_within(&grid, p.dt, 0.0);
    print_grid("tail = settle (default)", &grid);
    eprintln!("{exact}/49 cells equal to the paper, {within1}/49 within one control cycle");
    p.tail = Tail::Single;
    let single = table(p);
    print_grid("tail = single support", &single);
    eprintln!(
        "tail = single support: {}/49 equal, {}/49 within one control cycle",
        cells_within(&single, p.dt, 0.0),
        cells_within(&single, p.dt, 1.0)
    );
    assert!(
        within1 >= 47,
        "only {within1}/49 cells within one control cycle"
    );
    Quotes::new(COMMAND)
        .cell(
            GAIT,
            "Table II: adjustment times within one control cycle",
            OURS,
            &format!("{within1}/49 ({exact} equal)"),
        )
        .cell(
            GAIT,
            "Table II with `Tail::Single`",
            OURS,
            &format!(
                "{}/49 ({} equal)",
                cells_within(&single, p.dt, 1.0),
                cells_within(&single, p.dt, 0.0)
            ),
        )
        .line(
            "docs/src/host-sim.md",
            "adjustment times, ",
            &format!("{within1}/49 cells"),
        )
        .assert();
    // Every cell on the 5 ms grid and inside the limits.
    for m in grid.iter().flatten() {
        let ticks = m.adjust_s / p.dt;
        assert!((ticks - ticks.round()).abs() < 1e-9);
        assert!(m.adjust_s >= -0.2 - 1e-12 && m.adjust_s <= 0.35 + 1e-12);
    }
}

#[test]
fn shaping_reduces_the_frontal_fluctuation_of_fig4() {
    let p = GaitParams::<f64>::hrp2();
    let mut off = p;
    off.shaping = false;
    let shaped = modification(p, 0.1, 0.3);
    let plain = modification(off, 0.1, 0.3);
    // Peak / RMS without shaping → with it, and the factors (as the gait page quotes them).
    let figure = format!(
        "{:.1} / {:.1} mm → {:.1} / {:.1} mm with shaping (×{:.2} / ×{:.2})",
        plain.frontal_m.abs() * 1e3,
        plain.frontal_rms_m * 1e3,
        shaped.frontal_m.abs() * 1e3,
        shaped.frontal_rms_m * 1e3,
        plain.frontal_m.abs() / shaped.frontal_m.abs(),
        plain.frontal_rms_m / shaped.frontal_rms_m
    );
    eprintln!("Fig. 4 frontal fluctuation in the stretched single support: {figure}");
    // Shaping may not change the sagittal result nor the adjustment.
    assert_eq!(shaped.adjust_s, plain.adjust_s);
    // It reduces the frontal peak by at least 20 % (measured: see the print).
    assert!(shaped.frontal_m.abs() < 0.8 * plain.frontal_m.abs());
    assert!(shaped.frontal_rms_m < plain.frontal_rms_m);
    Quotes::new(COMMAND)
        .cell(
            GAIT,
            "Fig. 4 frontal fluctuation in the stretched single support",
            OURS,
            &figure,
        )
        .assert();
}

/// Section V: the `lateral` scenario moves the next landing 0.05 m inwards at 4.0 s and a later
/// one 0.05 m outwards; the single supports they take effect in are adjusted, inwards shorter
/// and outwards longer (the paper's signs), by the times the book quotes.
#[test]
fn the_lateral_changes_of_section_v() {
    let p = GaitParams::<f64>::hrp2();
    let s = host_sim::scenario::built_in("lateral").expect("the lateral scenario");
    let run = host_sim::scenario::run(&s, p);
    let adjusted: Vec<f64> = run
        .adjustments
        .iter()
        .map(|a| a.adjust_s)
        .filter(|a| *a != 0.0)
        .collect();
    eprintln!(
        "section V, lateral change of 0.05 m: adjustments {adjusted:?} s (paper: -0.2 / +0.28 s)"
    );
    assert_eq!(adjusted.len(), 2, "{adjusted:?}");
    let (inwards, outwards) = (adjusted[0], adjusted[1]);
    assert!(inwards < 0.0 && outwards > 0.0, "{adjusted:?}");
    Quotes::new(COMMAND)
        .cell(
            GAIT,
            "Section V lateral change of 0.05 m",
            OURS,
            &format!("{} s / {} s", signed(inwards, 3), signed(outwards, 3)),
        )
        .assert();
}
