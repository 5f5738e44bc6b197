//! host-sim: the HRP-2 simulation around the planner (main job of the project).
//!
//! This first version plans one 7-interval window for an HRP-2 straight walk with the
//! planner-core window solver and writes the reference trajectory, sampled every 5 ms, to
//! `out/demo/trajectory.csv`. The virtual CAN link, the node, the multi-body model and the
//! scenarios come with the host-sim issue; the command stays the same.

use std::error::Error;
use std::fs;
use std::io::Write;
use std::path::PathBuf;

use planner_core::window::{Factorized, Plan, PlaneBoundary, Timing, M};
use planner_core::{omega, State, GRAVITY, HRP2_COG_HEIGHT};

/// Control period \[s\].
const DT: f64 = 0.005;

fn main() -> Result<(), Box<dyn Error>> {
    let out = std::env::args()
        .skip_while(|a| a != "--out")
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("out/demo"));
    fs::create_dir_all(&out)?;

    // HRP-2 defaults: single support 0.7 s, double support 0.1 s; the window starts at the
    // beginning of a single support on the right foot, the COG above the left/right midpoint
    // moving forward, and plans three 0.2 m steps ending at rest over the last foot.
    let timing = Timing {
        omega: omega(GRAVITY, HRP2_COG_HEIGHT),
        durations: [0.7, 0.1, 0.7, 0.1, 0.7, 0.1, 0.7],
    };
    let (step, half_width) = (0.2, 0.1);
    let mut xv = [State::default(); M];
    let mut yv = [State::default(); M];
    let (mut foot_x, mut foot_y) = (0.0, -half_width);
    for j in 0..M {
        if j % 2 == 1 {
            foot_x += step;
            foot_y = -foot_y;
        }
        xv[j] = State::at_rest(foot_x);
        yv[j] = State::at_rest(foot_y);
    }
    let x = PlaneBoundary {
        cog_start: State::new(-0.05, 0.3),
        zmp_start: State::at_rest(0.0),
        via: xv,
        cog_end: State::at_rest(foot_x),
    };
    let y = PlaneBoundary {
        cog_start: State::new(-0.03, -0.15),
        zmp_start: State::at_rest(-half_width),
        via: yv,
        cog_end: State::at_rest(foot_y),
    };
    let f = Factorized::new(&timing).map_err(|e| format!("planning failed: {e:?}"))?;
    let mut plan = Plan::zeroed(timing);
    f.solve(&x, &y, &mut plan)
        .map_err(|e| format!("planning failed: {e:?}"))?;

    let path = out.join("trajectory.csv");
    let mut csv = std::io::BufWriter::new(fs::File::create(&path)?);
    writeln!(csv, "t,cog_x,cog_y,cog_vx,cog_vy,zmp_x,zmp_y,phase")?;
    let n = (timing.total() / DT).round() as usize;
    let mut max_dev: f64 = 0.0;
    for i in 0..=n {
        let t = i as f64 * DT;
        let (sx, sy) = plan.sample(t);
        let (interval, _) = plan.locate(t);
        let phase = if interval % 2 == 0 {
            "single"
        } else {
            "double"
        };
        if interval == 0 {
            max_dev = max_dev.max((sx.zmp - xv[0].pos).abs());
        }
        writeln!(
            csv,
            "{t:.3},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{phase}",
            sx.cog, sy.cog, sx.cog_vel, sy.cog_vel, sx.zmp, sy.zmp
        )?;
    }
    csv.flush()?;
    println!(
        "HRP-2 straight walk: {} samples every {:.0} ms over {:.2} s",
        n + 1,
        DT * 1e3,
        timing.total()
    );
    println!(
        "largest sagittal ZMP fluctuation in the first single support: {:.1} mm",
        max_dev * 1e3
    );
    println!("results: {}", path.display());
    Ok(())
}
