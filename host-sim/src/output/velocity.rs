//! The commanded velocity against the walked one, for a run in which the node chose the
//! footsteps (`[[velocity]]`, `[[goal]]`): `velocity.csv` and `velocity.png`.
//!
//! * **commanded**: the last `VELOCITY` the node accepted (a goal's velocity is the node's
//!   own: the columns are empty while a goal is walked);
//! * **walked**: the reference COG's displacement over the last two step cycles (`2 Tₛ`, the
//!   period of the lateral sway, which it averages out), divided by that time, in the frame
//!   of the feet's mean heading half-way through it; the turn rate is the change of that
//!   heading over the same time. So the walked velocity follows a change with a lag of about
//!   `Tₛ` plus the steps it takes to reach it.

use std::io::Write;
use std::path::Path;

use planner_core::gait::Reference;

use super::plot::{write_time_plot, Curve};
use crate::scenario::{Command, Run};

/// How near the walked velocity must stay to a commanded one for `run` to call it followed
/// (m/s for vx and vy, rad/s for ω).
pub const RESPONSE_TOL: f64 = 0.01;

/// `host-sim run`'s velocity outputs for a run with the gait `params`: nothing for a run
/// whose scenario gives no velocity or goal; else [`write_velocity_outputs`] (at
/// [`RESPONSE_TOL`]) into `out`, the figure added to `plots`, the lines to print returned.
pub fn outputs(
    out: &Path,
    name: &str,
    run: &Run,
    params: &planner_core::gait::GaitParams<f64>,
    plots: &mut Vec<std::path::PathBuf>,
) -> Result<Vec<String>, String> {
    if !drives(run) {
        return Ok(Vec::new());
    }
    let cycle = (params.single_ticks + params.double_ticks) as usize;
    let (png, lines) = write_velocity_outputs(out, name, run, params.dt, cycle, RESPONSE_TOL)?;
    plots.push(png);
    Ok(lines)
}

/// One sample: time, commanded (vx, vy, ω) (NaN: none in force) and walked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocitySample {
    /// Time \[s\].
    pub t: f64,
    /// The velocity in force \[m/s, m/s, rad/s\].
    pub commanded: [f64; 3],
    /// The velocity walked (see the module docs).
    pub walked: [f64; 3],
}

/// The mean heading of the feet of `r`.
fn heading(r: &Reference<f64>) -> f64 {
    let (s, c) = r
        .feet
        .iter()
        .fold((0.0, 0.0), |(s, c), f| (s + f.yaw.sin(), c + f.yaw.cos()));
    s.atan2(c)
}

fn wrap(a: f64) -> f64 {
    a.sin().atan2(a.cos())
}

/// `true` if the run's scenario gave a velocity or a goal.
pub fn drives(run: &Run) -> bool {
    run.events.iter().any(|e| e.command.drives())
}

/// The samples of `run` (ticks of `dt`; a step cycle of `cycle_ticks`), one per tick.
pub fn velocity_series(run: &Run, dt: f64, cycle_ticks: usize) -> Vec<VelocitySample> {
    let window = 2 * cycle_ticks.max(1);
    let nan = [f64::NAN; 3];
    let mut commanded = nan;
    let mut events = run.events.iter().filter(|e| e.result.is_ok()).peekable();
    let tr = &run.trajectory;
    (0..tr.len())
        .map(|k| {
            while let Some(e) = events.next_if(|e| e.tick as usize <= k) {
                match e.command {
                    Command::Velocity(vx, vy, wz) => commanded = [vx, vy, wz],
                    Command::Goal(..) => commanded = nan,
                    _ => {}
                }
            }
            let walked = if k >= window {
                let (a, b) = (&tr[k - window], &tr[k]);
                let span = window as f64 * dt;
                let dh = wrap(heading(b) - heading(a));
                let mid = heading(a) + dh / 2.0;
                let (dx, dy) = (b.x.cog - a.x.cog, b.y.cog - a.y.cog);
                let (s, c) = mid.sin_cos();
                [
                    (c * dx + s * dy) / span,
                    (-s * dx + c * dy) / span,
                    dh / span,
                ]
            } else {
                nan
            };
            VelocitySample {
                t: k as f64 * dt,
                commanded,
                walked,
            }
        })
        .collect()
}

/// Writes `velocity.csv` (`t,vx_cmd,vy_cmd,wz_cmd,vx_walked,vy_walked,wz_walked`, empty
/// cells where a value is not known) into `out`.
pub fn write_velocity_csv(path: &Path, samples: &[VelocitySample]) -> Result<(), String> {
    let named = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(named)?;
    let mut w = std::io::BufWriter::new(file);
    let cell = |v: f64| {
        if v.is_finite() {
            format!("{v:.5}")
        } else {
            String::new()
        }
    };
    writeln!(w, "t,vx_cmd,vy_cmd,wz_cmd,vx_walked,vy_walked,wz_walked").map_err(named)?;
    for s in samples {
        let [a, b, c] = s.commanded.map(cell);
        let [d, e, f] = s.walked.map(cell);
        writeln!(w, "{:.3},{a},{b},{c},{d},{e},{f}", s.t).map_err(named)?;
    }
    w.flush().map_err(named)
}

/// Writes `velocity.png`: the commanded and walked vx, vy \[m/s\] and ω \[rad/s\] against
/// time.
pub fn write_velocity_plot(
    path: &Path,
    name: &str,
    samples: &[VelocitySample],
) -> Result<(), Box<dyn std::error::Error>> {
    let pick = |f: fn(&VelocitySample) -> f64| -> Vec<(f64, f64)> {
        samples
            .iter()
            .map(|s| (s.t, f(s)))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let curves: Vec<Curve> = vec![
        (
            "vx commanded".into(),
            (150, 180, 240),
            pick(|s| s.commanded[0]),
        ),
        ("vx walked".into(), (20, 60, 200), pick(|s| s.walked[0])),
        (
            "vy commanded".into(),
            (150, 220, 150),
            pick(|s| s.commanded[1]),
        ),
        ("vy walked".into(), (20, 140, 40), pick(|s| s.walked[1])),
        (
            "ω commanded".into(),
            (240, 170, 150),
            pick(|s| s.commanded[2]),
        ),
        ("ω walked".into(), (200, 40, 20), pick(|s| s.walked[2])),
    ];
    write_time_plot(
        path,
        &format!("{name}: commanded and walked velocity"),
        "vx, vy [m/s]; ω [rad/s]",
        &curves,
    )
}

/// How long the walk took to follow each change of the commanded velocity: for every change
/// (at `t` \[s\], to `v`, from `before`), per component, the time after it from which the
/// walked component stays within `tol` (m/s for vx and vy, rad/s for ω) of the commanded one
/// until the next change (`None`: it never settled before the next change or the end).
pub fn responses(samples: &[VelocitySample], tol: f64) -> Vec<Response> {
    let mut changes: Vec<(usize, [f64; 3])> = Vec::new();
    for (i, s) in samples.iter().enumerate() {
        let c = s.commanded;
        if c.iter().all(|v| v.is_finite()) && changes.last().is_none_or(|l| l.1 != c) {
            changes.push((i, c));
        }
    }
    changes
        .iter()
        .enumerate()
        .map(|(n, &(i, v))| {
            let end = changes.get(n + 1).map_or(samples.len(), |c| c.0);
            let settled = core::array::from_fn(|j| {
                let near = |s: &VelocitySample| {
                    s.walked[j].is_finite() && (s.walked[j] - v[j]).abs() <= tol
                };
                let mut from = None;
                for k in (i..end).rev() {
                    if near(&samples[k]) {
                        from = Some(k);
                    } else {
                        break;
                    }
                }
                from.map(|k| samples[k].t - samples[i].t)
            });
            Response {
                t: samples[i].t,
                before: n.checked_sub(1).map_or([0.0; 3], |p| changes[p].1),
                v,
                settled,
            }
        })
        .collect()
}

/// One change of the commanded velocity and how the walk followed it ([`responses`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response {
    /// When \[s\].
    pub t: f64,
    /// The velocity before (zero for the first).
    pub before: [f64; 3],
    /// The velocity commanded.
    pub v: [f64; 3],
    /// Per component, how long until the walked one stayed within the tolerance \[s\].
    pub settled: [Option<f64>; 3],
}

/// The lines `host-sim run` prints of [`responses`]: per change, the components that changed
/// and when each was followed, in seconds and in step cycles of `cycle_s`.
pub fn response_lines(samples: &[VelocitySample], tol: f64, cycle_s: f64) -> Vec<String> {
    const NAMES: [&str; 3] = ["vx", "vy", "ω"];
    responses(samples, tol)
        .into_iter()
        .map(|r| {
            let parts: Vec<String> = (0..3)
                .filter(|&j| r.v[j] != r.before[j])
                .map(|j| match r.settled[j] {
                    Some(s) => format!(
                        "{} within {tol} after {s:.2} s ({:.1} step cycles)",
                        NAMES[j],
                        s / cycle_s
                    ),
                    None => format!("{} not within {tol} before the next change", NAMES[j]),
                })
                .collect();
            format!(
                "  velocity ({:.3} m/s, {:.3} m/s, {:.3} rad/s) at {:.2} s: {}",
                r.v[0],
                r.v[1],
                r.v[2],
                r.t,
                parts.join("; ")
            )
        })
        .collect()
}

/// For a run whose scenario drives: writes `velocity.csv` and `velocity.png` into `out`;
/// returns the figure's path and the lines of [`response_lines`] (tolerance `tol`).
pub fn write_velocity_outputs(
    out: &Path,
    name: &str,
    run: &Run,
    dt: f64,
    cycle_ticks: usize,
    tol: f64,
) -> Result<(std::path::PathBuf, Vec<String>), String> {
    let samples = velocity_series(run, dt, cycle_ticks);
    write_velocity_csv(&out.join("velocity.csv"), &samples)?;
    let png = out.join("velocity.png");
    write_velocity_plot(&png, name, &samples)
        .map_err(|e| format!("plot {}: {e}", png.display()))?;
    let lines = response_lines(&samples, tol, cycle_ticks as f64 * dt);
    Ok((png, lines))
}
