//! `trajectory.csv`: the reference of every tick (COG, ZMP, phase, feet) and the multi-body
//! ZMP beside it, as `host-sim run` and `host-sim replay` write it.

use std::fs;
use std::io::Write;
use std::path::Path;

use planner_core::gait::Phase;

use crate::eval::multibody::MbSample;
use crate::scenario::Run;

/// The `phase` column: `standing`, `double`, `single_left`, `single_right`.
pub fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Standing => "standing",
        Phase::Double => "double",
        Phase::Single(planner_core::gait::Side::Left) => "single_left",
        Phase::Single(planner_core::gait::Side::Right) => "single_right",
    }
}

/// Writes the CSV of `run` (with the multi-body ZMP of `mb` where it has a sample, empty
/// columns where not; ticks of `dt` seconds) to `path`; the error names it.
pub fn write_trajectory(path: &Path, run: &Run, mb: &[MbSample], dt: f64) -> Result<(), String> {
    let named = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = fs::File::create(path).map_err(named)?;
    write_csv(std::io::BufWriter::new(file), run, mb, dt).map_err(named)
}

/// The CSV of `run` into `csv`: a header line, then one row per tick.
pub fn write_csv(mut csv: impl Write, run: &Run, mb: &[MbSample], dt: f64) -> std::io::Result<()> {
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
