//! `host-sim`: the HRP-2 simulation around the planner (the project's main job).
//!
//! ```text
//! host-sim                         the default demo (the `straight` scenario into out/demo)
//! host-sim list                    the built-in scenarios
//! host-sim run <scenario|file.toml> [--out DIR]
//! host-sim tables [--out DIR]      the paper's Table II (and Fig. 4) recomputed
//! ```

use std::error::Error;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use host_sim::multibody::{evaluate, max_zmp_error, Hrp2, MbSample};
use host_sim::paper::{
    self, cells_within, without_adjustment, PAPER_ADJUST_S, PAPER_ERROR_WITHOUT_M,
    PAPER_ERROR_WITH_M, STEP_LENGTHS,
};
use host_sim::scenario::{self, Run, BUILT_IN};
use host_sim::sim::{simulate, SimConfig};
use host_sim::{plot, toml_scenario};
use planner_core::gait::{Footstep, GaitParams, Phase, Side};
use serde_json::json;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Err(e) = dispatch(&args) {
        eprintln!("host-sim: {e}");
        std::process::exit(2);
    }
}

fn out_dir(args: &[String], default: &str) -> PathBuf {
    args.iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(default))
}

fn dispatch(args: &[String]) -> Result<(), Box<dyn Error>> {
    match args.first().map(String::as_str) {
        None => run_scenario("straight", &out_dir(args, "out/demo")),
        Some("list") => {
            for name in BUILT_IN {
                let s = scenario::built_in(name).ok_or("missing built-in")?;
                println!("{name:<10} {}", s.about);
            }
            Ok(())
        }
        Some("run") => {
            let name = args
                .get(1)
                .ok_or("usage: host-sim run <scenario> [--out DIR]")?;
            let default = format!("out/{name}");
            run_scenario(name, &out_dir(args, &default))
        }
        Some("tables") => tables(&out_dir(args, "out/tables")),
        #[cfg(feature = "socketcan")]
        Some("node") => {
            let iface = args
                .get(1)
                .ok_or("usage: host-sim node <interface> [--seconds S]")?;
            let secs = args
                .iter()
                .position(|a| a == "--seconds")
                .and_then(|i| args.get(i + 1))
                .and_then(|s| s.parse().ok());
            host_sim::socketcan_link::run_node(iface, secs)
        }
        Some("-h" | "--help" | "help") => {
            println!("usage: host-sim [list | run <scenario> [--out DIR] | tables [--out DIR]]");
            Ok(())
        }
        Some(other) => Err(format!("unknown command {other:?} (try: list, run, tables)").into()),
    }
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Standing => "standing",
        Phase::Double => "double",
        Phase::Single(planner_core::gait::Side::Left) => "single_left",
        Phase::Single(planner_core::gait::Side::Right) => "single_right",
    }
}

fn write_trajectory(
    path: &Path,
    run: &Run,
    mb: &[MbSample],
    dt: f64,
) -> Result<(), Box<dyn Error>> {
    let mut csv = std::io::BufWriter::new(fs::File::create(path)?);
    writeln!(
        csv,
        "t,cog_x,cog_y,cog_vx,cog_vy,zmp_x,zmp_y,mb_zmp_x,mb_zmp_y,phase,left_x,left_y,left_z,left_yaw,right_x,right_y,right_z,right_yaw"
    )?;
    for (k, r) in run.trajectory.iter().enumerate() {
        let (l, rt) = (&r.feet[0], &r.feet[1]);
        let (mx, my) = mb
            .get(k)
            .map(|m| (format!("{:.6}", m.mb_zmp_x), format!("{:.6}", m.mb_zmp_y)))
            .unwrap_or_default();
        writeln!(
            csv,
            "{:.3},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{mx},{my},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
            k as f64 * dt,
            r.x.cog,
            r.y.cog,
            r.x.cog_vel,
            r.y.cog_vel,
            r.x.zmp,
            r.y.zmp,
            phase_name(r.phase),
            l.x,
            l.y,
            l.z,
            l.yaw,
            rt.x,
            rt.y,
            rt.z,
            rt.yaw
        )?;
    }
    csv.flush()?;
    Ok(())
}

/// Largest ZMP deviation from the support-foot centre during single support, in the support
/// foot's frame (along, across) \[m\].
fn max_fluctuation(run: &Run) -> (f64, f64) {
    let (mut along, mut across) = (0.0_f64, 0.0_f64);
    for r in &run.trajectory {
        if let Phase::Single(side) = r.phase {
            let f = &r.feet[if side == planner_core::gait::Side::Left {
                0
            } else {
                1
            }];
            let (s, c) = f.yaw.sin_cos();
            let (dx, dy) = (r.x.zmp - f.x, r.y.zmp - f.y);
            along = along.max((c * dx + s * dy).abs());
            across = across.max((-s * dx + c * dy).abs());
        }
    }
    (along, across)
}

/// The footprints actually stood on: every new ground pose of a foot in the trajectory.
fn footprints(run: &Run) -> Vec<Footstep<f64>> {
    let mut out: Vec<Footstep<f64>> = Vec::new();
    let mut last: [Option<(f64, f64, f64)>; 2] = [None, None];
    for r in &run.trajectory {
        for (k, f) in r.feet.iter().enumerate() {
            if f.z != 0.0 {
                continue;
            }
            let pose = (f.x, f.y, f.yaw);
            if last[k] != Some(pose) {
                last[k] = Some(pose);
                let side = if k == 0 { Side::Left } else { Side::Right };
                out.push(Footstep::new(side, f.x, f.y, f.yaw));
            }
        }
    }
    out
}

fn run_scenario(name: &str, out: &Path) -> Result<(), Box<dyn Error>> {
    let s = if name.ends_with(".toml") {
        toml_scenario::load(Path::new(name))?
    } else {
        scenario::built_in(name).ok_or_else(|| {
            format!(
                "unknown scenario {name:?}; built-in: {} (or a .toml file)",
                BUILT_IN.join(", ")
            )
        })?
    };
    let name = s.name.as_str();
    let cfg = SimConfig::default();
    let dt = cfg.node.params.dt;
    let sim = simulate(&s, &cfg)?;
    let run = &sim.run;
    let mb = evaluate(&Hrp2::default(), &run.trajectory, dt)
        .map_err(|e| format!("multi-body model: {e:?}"))?;
    let mb_error = max_zmp_error(&run.trajectory, &mb);
    fs::create_dir_all(out)?;
    let traj = out.join("trajectory.csv");
    write_trajectory(&traj, run, &mb, dt)?;
    fs::write(out.join("can.log"), sim.can_log.join("\n") + "\n")?;
    let (along, across) = max_fluctuation(run);
    let refused: Vec<_> = run
        .events
        .iter()
        .filter_map(|e| {
            e.result
                .as_ref()
                .err()
                .map(|err| json!({"t_s": e.tick as f64 * dt, "error": err}))
        })
        .collect();
    let summary = json!({
        "scenario": name,
        "about": s.about,
        "duration_s": (run.trajectory.len() - 1) as f64 * dt,
        "adjust_s": run.adjustments.iter().map(|a| a.adjust_s).collect::<Vec<_>>(),
        "adjustments": run.adjustments.iter().map(|a| json!({
            "t_s": a.tick as f64 * dt, "adjust_s": a.adjust_s, "ratio": a.ratio,
            "plane": if a.plane == 0 { "x" } else { "y" }})).collect::<Vec<_>>(),
        "max_zmp_fluctuation_m": along.max(across),
        "max_zmp_fluctuation_along_m": along,
        "max_zmp_fluctuation_across_m": across,
        "max_mb_zmp_error_m": mb_error,
        "bus_load": sim.bus_load,
        "bus_bitrate": cfg.bitrate,
        "frames_sent": sim.bus.sent,
        "refused_commands": refused,
    });
    fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    let plots = plot::write_plots(out, name, &run.trajectory, dt, &footprints(run), Some(&mb))?;
    println!("{name}: {}", s.about);
    println!(
        "  {:.2} s simulated in {} ticks of 5 ms, over a virtual CAN bus at {} kbit/s (load {:.1} %)",
        (run.trajectory.len() - 1) as f64 * dt,
        run.trajectory.len() - 1,
        cfg.bitrate / 1000,
        sim.bus_load * 100.0
    );
    for a in &run.adjustments {
        println!(
            "  re-plan at {:.3} s: single support adjusted by {:+.3} s (r = {:.3}, plane {})",
            a.tick as f64 * dt,
            a.adjust_s,
            a.ratio,
            if a.plane == 0 { "x" } else { "y" }
        );
    }
    println!(
        "  largest ZMP fluctuation in single support: {:.1} mm along the foot, {:.1} mm across",
        along * 1e3,
        across * 1e3
    );
    println!(
        "  largest multi-body ZMP error (HRP-2 model): {:.1} mm",
        mb_error * 1e3
    );
    println!(
        "  results: {}, summary.json, can.log and {} plots in {}",
        traj.display(),
        plots.len(),
        out.display()
    );
    Ok(())
}

/// Largest distance between the multi-body ZMP and the support-foot centre during the single
/// support in which the modification takes effect \[m\] (the paper's "maximum ZMP error");
/// `None` when the model's legs cannot reach the footsteps.
fn modified_support_error(m: &paper::Modification, dt: f64) -> Option<f64> {
    let mb = evaluate(&Hrp2::default(), &m.trajectory, dt).ok()?;
    let start = paper::MODIFICATION_TICK as usize;
    let support = (m.before * 3.0, -0.1);
    let mut worst: f64 = 0.0;
    for (r, s) in m.trajectory.iter().zip(&mb).skip(start) {
        if r.phase != Phase::Single(Side::Right) {
            break;
        }
        worst = worst.max((s.mb_zmp_x - support.0).hypot(s.mb_zmp_y - support.1));
    }
    Some(worst)
}

/// A 7×7 grid over the step lengths as a Markdown table (rows: after, columns: before).
fn grid_markdown(title: &str, cell: impl Fn(usize, usize) -> String) -> String {
    let mut md = format!("{title}\n\n| after \\ before |");
    for b in STEP_LENGTHS {
        md += &format!(" {b:+.1} |");
    }
    md += "\n|---|";
    for _ in STEP_LENGTHS {
        md += "---|";
    }
    md += "\n";
    for (r, after) in STEP_LENGTHS.iter().enumerate() {
        md += &format!("| {after:+.1} |");
        for c in 0..STEP_LENGTHS.len() {
            md += &format!(" {} |", cell(r, c));
        }
        md += "\n";
    }
    md
}

fn tables(out: &Path) -> Result<(), Box<dyn Error>> {
    let params = GaitParams::<f64>::hrp2();
    fs::create_dir_all(out)?;
    let n = STEP_LENGTHS.len();
    let mut adjust = vec![vec![0.0; n]; n];
    let mut with = vec![vec![0.0; n]; n];
    let mut without = vec![vec![0.0; n]; n];
    let mut lipm_with = vec![vec![0.0; n]; n];
    let mut lipm_without = vec![vec![0.0; n]; n];
    let mut grid = Vec::new();
    // Table I: no adjustment of the COG and ZMP at all (no eq. 18, no shaping).
    let mut bare = without_adjustment(params);
    bare.shaping = false;
    for (r, &after) in STEP_LENGTHS.iter().enumerate() {
        let mut row = Vec::new();
        for (c, &before) in STEP_LENGTHS.iter().enumerate() {
            eprint!("\rtables: cell {:>2}/49", r * n + c + 1);
            let m = paper::modification(params, before, after);
            let w = paper::modification(bare, before, after);
            adjust[r][c] = m.adjust_s;
            lipm_with[r][c] = m.sagittal_m.abs().max(m.frontal_m.abs());
            lipm_without[r][c] = w.sagittal_m.abs().max(w.frontal_m.abs());
            with[r][c] = modified_support_error(&m, params.dt).unwrap_or(f64::NAN);
            without[r][c] = modified_support_error(&w, params.dt).unwrap_or(f64::NAN);
            let mut m = m;
            m.trajectory.clear();
            row.push(m);
        }
        grid.push(row);
    }
    eprintln!();
    let within = cells_within(&grid, params.dt, 1.0);
    let json = json!({
        "step_lengths_m": STEP_LENGTHS,
        "rows": "length after the modification",
        "columns": "length before the modification",
        "adjust_s": adjust,
        "paper_adjust_s": PAPER_ADJUST_S,
        "cells_within_one_cycle": within,
        "zmp_error_model": "multi-body HRP-2 model (host-sim/src/multibody.rs): largest distance between its ZMP and the support-foot centre in the single support where the modification takes effect",
        "max_zmp_error_without_m": without,
        "max_zmp_error_with_m": with,
        "lipm_zmp_fluctuation_without_m": lipm_without,
        "lipm_zmp_fluctuation_with_m": lipm_with,
        "paper_max_zmp_error_without_m": PAPER_ERROR_WITHOUT_M,
        "paper_max_zmp_error_with_m": PAPER_ERROR_WITH_M,
    });
    fs::write(
        out.join("tables.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let mut md = grid_markdown(
        "Adjustment time [s], ours / paper's Table II (rows: after, columns: before)",
        |r, c| format!("{:.3} / {:.3}", adjust[r][c], PAPER_ADJUST_S[r][c]),
    );
    md += &format!("\n{within}/49 cells within one control cycle (5 ms) of the paper.\n");
    let cell = |v: f64| {
        if v.is_finite() {
            format!("{:.1}", v * 100.0)
        } else {
            "n/a".to_string()
        }
    };
    for (title, ours, theirs) in [
        (
            "Table I: maximum ZMP error without any adjustment [cm], ours (multi-body) / paper",
            &without,
            &PAPER_ERROR_WITHOUT_M,
        ),
        (
            "Table II: maximum ZMP error with the proposed method [cm], ours (multi-body) / paper",
            &with,
            &PAPER_ERROR_WITH_M,
        ),
    ] {
        md += "\n";
        md += &grid_markdown(title, |r, c| {
            format!("{} / {:.1}", cell(ours[r][c]), theirs[r][c] * 100.0)
        });
    }
    md += "\nn/a: the model's legs (thigh and shank 0.3 m) cannot reach the footsteps.\n";
    fs::write(out.join("tables.md"), &md)?;
    println!("{md}");
    println!(
        "results: {} and {}",
        out.join("tables.json").display(),
        out.join("tables.md").display()
    );
    Ok(())
}
