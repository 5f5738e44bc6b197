//! The paper's figures reproduced end to end through the gait API (Fig. 4 and Table II).
//!
//! Run with `-- --nocapture` to see the grids side by side.

use host_sim::eval::paper::{
    cells_within, modification, table, without_adjustment, PAPER_ADJUST_S, STEP_LENGTHS,
};
use planner_core::gait::{GaitParams, Tail};

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
    eprintln!(
        "Fig. 4 frontal fluctuation in the stretched single support: without shaping peak {:.1} mm \
         RMS {:.1} mm; with shaping peak {:.1} mm RMS {:.1} mm (x{:.2} peak, x{:.2} RMS)",
        plain.frontal_m.abs() * 1e3,
        plain.frontal_rms_m * 1e3,
        shaped.frontal_m.abs() * 1e3,
        shaped.frontal_rms_m * 1e3,
        plain.frontal_m.abs() / shaped.frontal_m.abs(),
        plain.frontal_rms_m / shaped.frontal_rms_m
    );
    // Shaping may not change the sagittal result nor the adjustment.
    assert_eq!(shaped.adjust_s, plain.adjust_s);
    // It reduces the frontal peak by at least 20 % (measured: see the print).
    assert!(shaped.frontal_m.abs() < 0.8 * plain.frontal_m.abs());
    assert!(shaped.frontal_rms_m < plain.frontal_rms_m);
}
