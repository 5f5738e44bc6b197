//! PNG figures of a walk, in the style of the paper's:
//!
//! * `sagittal.png`, `frontal.png`: COG, planned ZMP and (when given) multi-body ZMP of one
//!   plane against time (Fig. 4, Fig. 6 a/b), over bands that shade single support (blue) and
//!   double support (orange); the sole limits (the support polygon's extent along the axis:
//!   the support sole in single support, both soles in double support) as dashed lines; the
//!   modification instants as labelled vertical lines. Under it, a zoom of the ZMP
//!   fluctuation (the planned ZMP minus the support-sole centre during single support, in mm),
//!   as the paper's Fig. 4 shows it;
//! * `footprints.png`: the walk seen from above (Fig. 6c): COG and ZMP paths and the sole
//!   rectangles (the robot's sole, HRP-2's 0.24 × 0.14 m, rotated by their yaw) with their
//!   step numbers, the same scale on both axes; a landing that a modification moved is drawn
//!   dashed at its first planned pose, with its number in brackets;
//! * `modification.png`, for a walk whose footsteps were modified (`fig4`, `lateral`): the
//!   plan as first sent (no modification), the modified walk without the single-support
//!   time adjustment (the paper's Fig. 4 a) and the walk as it went, with the adjustment
//!   (Fig. 4 b), side by side on the same axes, in the plane of the adjustment. When every
//!   modification preceded the start (the robot still stood), nothing was walked without it:
//!   the figure then shows the walk alone, planned with the modified steps from the start,
//!   and says so in its caption and title. (The first planned landings are in
//!   `footprints.png`.)
//!
//! A mark that would fall on the y axis (a modification in the first ticks) is kept inside
//! the plot area: the time axis then begins a little before 0.
//!
//! The figures are drawn with `plotters` into bitmaps (no display needed) at
//! [`SUPERSAMPLE`] times their size and averaged down, so lines and text are anti-aliased.
//! Text is rendered with a TrueType font read at run time: DejaVu Sans (Debian package
//! `fonts-dejavu-core`, which `tests/run-all.sh` installs when it is missing), or the file
//! named by the environment variable `HOST_SIM_FONT`.

mod canvas;
mod curves;
mod data;
pub mod polar;
mod time;
mod top;

use std::error::Error;
use std::fs;
use std::ops::Range;
use std::path::{Path, PathBuf};

use planner_core::gait::{Footstep, GaitParams, Reference};

use crate::eval::multibody::MbSample;
use crate::scenario::{Run, Scenario};

pub use canvas::SUPERSAMPLE;
pub use curves::{write_time_plot, Curve};
pub use data::{fluctuation, landings, modification_marks, sole_limits, walked_landings};

/// HRP-2's sole length (x in the foot frame), the default of [`Walk::sole`] \[m\].
pub const SOLE_LENGTH: f64 = 0.24;
/// HRP-2's sole width (y in the foot frame) \[m\].
pub const SOLE_WIDTH: f64 = 0.14;

/// Environment variable naming a TrueType font to use instead of DejaVu Sans.
pub const FONT_ENV: &str = "HOST_SIM_FONT";

/// Where the font is looked for when `HOST_SIM_FONT` is not set.
pub const FONT_PATHS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// The files [`write_plots`] writes for every walk, in the order it returns them.
pub const FILES: [&str; 3] = ["sagittal.png", "frontal.png", "footprints.png"];
/// The file written in addition when the walk has comparison columns.
pub const COMPARISON_FILE: &str = "modification.png";

/// A landing to draw in the footprint plot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing {
    /// The footstep id, if known (drawn beside the sole).
    pub id: Option<u16>,
    /// Where the foot landed.
    pub foot: Footstep<f64>,
    /// Where the same step was first planned, when a modification moved it.
    pub planned: Option<Footstep<f64>>,
}

/// A labelled instant (a modification) drawn as a vertical line on the time plots.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// Time \[s\].
    pub t: f64,
    /// Label.
    pub label: String,
    /// The modification was applied before the walk's start, while the robot stood: the walk
    /// is planned with it from the start (there is no walk without it to compare with).
    pub before_start: bool,
}

/// Another trajectory of the same scenario, drawn beside the walk in `modification.png`.
#[derive(Clone, Debug)]
pub struct Column {
    /// Column title.
    pub title: String,
    /// One reference per tick from tick 0.
    pub trajectory: Vec<Reference<f64>>,
}

/// One column of `modification.png` as drawn.
#[derive(Clone, Copy, Debug)]
pub struct ComparisonColumn<'a> {
    /// Column title.
    pub title: &'a str,
    /// The trajectory drawn, one reference per tick from tick 0.
    pub trajectory: &'a [Reference<f64>],
    /// The marks drawn in it.
    pub marks: &'a [Mark],
}

/// What `modification.png` shows, as [`write_plots`] draws it ([`Walk::comparison`]).
#[derive(Clone, Debug)]
pub struct Comparison<'a> {
    /// The figure's caption.
    pub caption: String,
    /// The columns, left to right: the comparison columns, then the walk itself; the walk
    /// alone when every modification preceded the start.
    pub columns: Vec<ComparisonColumn<'a>>,
    /// The time axis of the upper panels \[s\].
    pub t: Range<f64>,
    /// The time axis of the zoom panels \[s\].
    pub zoom_t: Range<f64>,
}

/// Everything the figures show.
#[derive(Clone, Debug)]
pub struct Walk<'a> {
    /// Used in the captions.
    pub name: &'a str,
    /// One reference per tick from tick 0; its first entry also gives the initial stance.
    pub trajectory: &'a [Reference<f64>],
    /// The tick \[s\].
    pub dt: f64,
    /// The landings of the footprint plot.
    pub landings: Vec<Landing>,
    /// The multi-body evaluation of the same trajectory, if any (its ZMP is added to the
    /// sagittal, frontal and footprint plots).
    pub mb: Option<&'a [MbSample]>,
    /// Instants marked on the time plots.
    pub marks: Vec<Mark>,
    /// Columns drawn before the walk itself in `modification.png` (none: no such file,
    /// unless every mark precedes the start: see [`Walk::comparison`]).
    pub columns: Vec<Column>,
    /// Title of the walk's own column in `modification.png`.
    pub title: String,
    /// The plane of `modification.png` (0: x, 1: y).
    pub plane: usize,
    /// The sole: length (x in the foot frame) and width \[m\].
    pub sole: [f64; 2],
}

impl<'a> Walk<'a> {
    /// A walk with nothing but its trajectory: the landings found in it (without step
    /// numbers), no multi-body ZMP, no marks, no comparison, HRP-2's sole.
    pub fn new(name: &'a str, trajectory: &'a [Reference<f64>], dt: f64) -> Self {
        Walk {
            name,
            trajectory,
            dt,
            landings: walked_landings(trajectory)
                .into_iter()
                .map(|foot| Landing {
                    id: None,
                    foot,
                    planned: None,
                })
                .collect(),
            mb: None,
            marks: Vec::new(),
            columns: Vec::new(),
            title: "as walked".into(),
            plane: 0,
            sole: [SOLE_LENGTH, SOLE_WIDTH],
        }
    }

    /// The walk of a run of scenario `s` (its trajectory in `run`): the landings with their
    /// step numbers and first planned poses, the modification instants, and, if a
    /// modification was accepted, the comparison columns of `modification.png` (the scenario
    /// without its modifications, and with them but without the time adjustment, both played
    /// against the gait with `params`); the sole of `params`.
    ///
    /// Errors: `params` that the gait refuses.
    pub fn from_run(
        name: &'a str,
        s: &Scenario,
        run: &'a Run,
        dt: f64,
        params: GaitParams<f64>,
        mb: Option<&'a [MbSample]>,
    ) -> Result<Self, String> {
        let mut w = Walk::new(name, &run.trajectory, dt);
        w.landings = landings(run);
        w.marks = modification_marks(run, dt);
        w.mb = mb;
        w.sole = [2.0 * params.sole_half_length, 2.0 * params.sole_half_width];
        let (columns, plane) = data::comparison(s, run, params)?;
        if !columns.is_empty() {
            w.columns = columns;
            w.plane = plane;
            w.title = "(c) modified, with the time adjustment: as walked".into();
        } else if w.marks.iter().any(|m| m.before_start) {
            w.plane = plane;
            w.title = PRE_START_TITLE.into();
        }
        Ok(w)
    }

    /// The time axis of `sagittal.png` and `frontal.png` \[s\]: 0 to the end of the walk,
    /// begun a little before 0 when a mark would otherwise sit on the y axis.
    pub fn time_axis(&self) -> Range<f64> {
        time::plane_time_axis(self)
    }

    /// What `modification.png` shows, or `None` when it is not written: the comparison
    /// columns and the walk itself when the walk has comparison columns; else, when it has
    /// marks and every one of them precedes the start, the walk alone (planned with the
    /// modifications from the start, nothing to compare it with), marked.
    pub fn comparison(&self) -> Option<Comparison<'_>> {
        time::comparison_layout(self)
    }
}

/// The title of the walk's column in `modification.png` when every modification preceded the
/// start.
pub const PRE_START_TITLE: &str =
    "as walked: planned with the modified steps from the start (nothing walked without them)";

/// Writes `sagittal.png`, `frontal.png`, `footprints.png` and, when the walk has comparison
/// columns or only modifications before its start ([`Walk::comparison`]), `modification.png`
/// into `out` (created if needed) and returns their paths.
///
/// Errors: an empty trajectory (or comparison column), a `dt` that is not positive and finite,
/// a plane other than 0 or 1, a sole size that is not positive and finite, no usable font (see the module documentation), or an I/O or
/// drawing error.
pub fn write_plots(out: &Path, walk: &Walk<'_>) -> Result<Vec<PathBuf>, Box<dyn Error>> {
    if walk.trajectory.is_empty() || walk.columns.iter().any(|c| c.trajectory.is_empty()) {
        return Err("write_plots: empty trajectory".into());
    }
    if !(walk.dt > 0.0 && walk.dt.is_finite()) {
        return Err(format!(
            "write_plots: dt must be positive and finite, got {}",
            walk.dt
        )
        .into());
    }
    if walk.plane > 1 {
        return Err(format!(
            "write_plots: plane {} is neither 0 (x) nor 1 (y)",
            walk.plane
        )
        .into());
    }
    if !walk.sole.iter().all(|v| *v > 0.0 && v.is_finite()) {
        return Err(format!(
            "write_plots: sole size {:?} is not positive and finite",
            walk.sole
        )
        .into());
    }
    canvas::ensure_font()?;
    fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let mut written = Vec::new();
    for (plane, file) in FILES[..2].iter().enumerate() {
        let path = out.join(file);
        time::plane_figure(&path, walk, plane)?;
        written.push(path);
    }
    let path = out.join(FILES[2]);
    top::footprint_figure(&path, walk)?;
    written.push(path);
    if let Some(c) = walk.comparison() {
        let path = out.join(COMPARISON_FILE);
        time::comparison_figure(&path, walk, &c)?;
        written.push(path);
    }
    Ok(written)
}
