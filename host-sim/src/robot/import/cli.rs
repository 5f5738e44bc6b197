//! The `robot import` command: the import of [`super::import`] written as a robot file.

use std::error::Error;
use std::fs;
use std::path::Path;

use crate::{errln, outln};

/// `host-sim robot import URDF [--sole LEFT,RIGHT] --out FILE`: imports `urdf`, prints the
/// warnings and a one-line summary, and writes the robot file `out`.
pub fn command(urdf: &Path, sole: Option<&str>, out: &Path) -> Result<(), Box<dyn Error>> {
    let soles = match sole {
        None => None,
        Some(s) => match s.split_once(',') {
            Some((l, r)) if !l.is_empty() && !r.is_empty() && !r.contains(',') => Some([l, r]),
            _ => return Err(format!("--sole {s:?}: give LEFT,RIGHT").into()),
        },
    };
    let imported = super::import(urdf, soles)?;
    for w in &imported.warnings {
        errln!("warning: {w}");
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    fs::write(out, &imported.toml).map_err(|e| format!("{}: {e}", out.display()))?;
    let r = &imported.robot;
    let p = &r.planner.params;
    outln!(
        "{}: {:.2} kg, COG {:.3} m standing, feet {:.3} m apart, soles {:.3} × {:.3} m, \
         steps up to {:.3} m forward; wrote {}",
        r.name(),
        r.model.total_mass(),
        p.cog_height,
        p.step_width,
        2.0 * p.sole_half_length,
        2.0 * p.sole_half_width,
        r.planner.reach.max_forward,
        out.display()
    );
    Ok(())
}
