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
