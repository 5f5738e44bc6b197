//! PNG plots of a walk, in the style of the paper's figures:
//!
//! * `sagittal.png`: COG x and ZMP x against time (Fig. 4 and Fig. 6a), with the multi-body
//!   ZMP x when it is given;
//! * `frontal.png`: the same for y (Fig. 6b);
//! * `footprints.png`: the walk seen from above (Fig. 6c): COG and ZMP paths and the sole
//!   rectangles (0.24 × 0.14 m, rotated by their yaw), with the same scale on both axes.
//!
//! The plots are drawn with `plotters` into bitmaps (no display needed). Text is rendered with
//! a TrueType font read at run time: DejaVu Sans (Debian package `fonts-dejavu-core`, which
//! `tests/run-all.sh` installs when it is missing), or the file named by the environment
//! variable `HOST_SIM_FONT`.

use std::error::Error;
use std::fs;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::multibody::MbSample;
use planner_core::gait::{Footstep, Reference, Side};

/// Sole length (x in the foot frame) \[m\].
pub const SOLE_LENGTH: f64 = 0.24;
/// Sole width (y in the foot frame) \[m\].
pub const SOLE_WIDTH: f64 = 0.14;

/// Environment variable naming a TrueType font to use instead of DejaVu Sans.
pub const FONT_ENV: &str = "HOST_SIM_FONT";

/// Where the font is looked for when `HOST_SIM_FONT` is not set.
pub const FONT_PATHS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

const FONT: &str = "sans-serif";
const TIME_SIZE: (u32, u32) = (1200, 600);
const COG_COLOR: RGBColor = RGBColor(0x1f, 0x5f, 0xbf);
const ZMP_COLOR: RGBColor = RGBColor(0xd6, 0x27, 0x28);
const MB_COLOR: RGBColor = RGBColor(0x2c, 0xa0, 0x2c);
const LEFT_COLOR: RGBColor = RGBColor(0x30, 0x30, 0x90);
const RIGHT_COLOR: RGBColor = RGBColor(0x90, 0x30, 0x30);
const START_COLOR: RGBColor = RGBColor(0x80, 0x80, 0x80);

/// Registers the font with plotters once (plotters' `ab_glyph` backend keeps a global table
/// of `'static` font data: the file is read and leaked once per process).
fn ensure_font() -> Result<(), String> {
    static FONT_STATE: OnceLock<Result<(), String>> = OnceLock::new();
    FONT_STATE
        .get_or_init(|| {
            let candidates: Vec<PathBuf> = match std::env::var_os(FONT_ENV) {
                Some(p) => vec![PathBuf::from(p)],
                None => FONT_PATHS.iter().map(PathBuf::from).collect(),
            };
            let (path, bytes) = candidates
                .iter()
                .find_map(|p| fs::read(p).ok().map(|b| (p.clone(), b)))
                .ok_or_else(|| {
                    format!(
                        "no font found for the plots (tried {}): install the Debian package \
                         fonts-dejavu-core, or set {FONT_ENV} to a TrueType font file",
                        candidates
                            .iter()
                            .map(|p| p.display().to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })?;
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font(FONT, FontStyle::Normal, bytes)
                .map_err(|_| format!("{} is not a usable TrueType font", path.display()))
        })
        .clone()
}

/// `lo..hi` widened by `pad` of its length on each side (and to at least `min_span`).
fn padded(lo: f64, hi: f64, pad: f64, min_span: f64) -> Range<f64> {
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (-1.0, 1.0) };
    let span = (hi - lo).max(min_span);
    let mid = 0.5 * (lo + hi);
    let half = 0.5 * span * (1.0 + 2.0 * pad);
    (mid - half)..(mid + half)
}

fn bounds(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// Corners of a sole centred at (x, y) with heading `yaw`, closed (5 points).
fn sole_outline(x: f64, y: f64, yaw: f64) -> Vec<(f64, f64)> {
    let (s, c) = yaw.sin_cos();
    let (a, b) = (0.5 * SOLE_LENGTH, 0.5 * SOLE_WIDTH);
    [(a, b), (-a, b), (-a, -b), (a, -b), (a, b)]
        .iter()
        .map(|&(u, v)| (x + c * u - s * v, y + s * u + c * v))
        .collect()
}

/// Width of the legend strip on the right of every plot \[px\].
const LEGEND_W: u32 = 230;

type Area<DB> = DrawingArea<DB, Shift>;

/// How a legend entry is marked.
#[derive(Clone, Copy)]
enum Mark {
    /// A line of this colour.
    Line(RGBColor),
    /// A sole outline of this colour.
    Sole(RGBColor),
}

/// The layout shared by all plots: caption on top, the chart on the left, the legend strip on
/// the right (so that the legend never hides data). Returns the chart builder and the legend
/// area.
fn layout<DB: DrawingBackend>(
    root: &Area<DB>,
    caption: &str,
) -> Result<(Area<DB>, Area<DB>), Box<dyn Error>>
where
    DB::ErrorType: 'static,
{
    let body = root.margin(8, 0, 0, 0).titled(caption, (FONT, 26))?;
    let w = body.dim_in_pixel().0;
    Ok(body.split_horizontally(w.saturating_sub(LEGEND_W)))
}

fn chart_builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(12)
        .margin_right(20)
        .x_label_area_size(56)
        .y_label_area_size(84);
    b
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, Mark)],
) -> Result<(), Box<dyn Error>>
where
    DB::ErrorType: 'static,
{
    let style = TextStyle::from((FONT, 18)).pos(Pos::new(HPos::Left, VPos::Center));
    for (i, (label, mark)) in entries.iter().enumerate() {
        let y = 40 + 28 * i as i32;
        match *mark {
            Mark::Line(c) => {
                area.draw(&PathElement::new(vec![(6, y), (36, y)], c.stroke_width(3)))?
            }
            Mark::Sole(c) => {
                area.draw(&Rectangle::new(
                    [(6, y - 7), (36, y + 7)],
                    c.mix(0.08).filled(),
                ))?;
                area.draw(&Rectangle::new(
                    [(6, y - 7), (36, y + 7)],
                    c.stroke_width(2),
                ))?;
            }
        }
        area.draw(&Text::new(label.clone(), (46, y), style.clone()))?;
    }
    Ok(())
}

/// A tick label with `digits` decimals (and no "-0.00").
fn tick_label(v: f64, digits: usize) -> String {
    let s = format!("{v:.digits$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

struct Series {
    label: String,
    color: RGBColor,
    width: u32,
    points: Vec<(f64, f64)>,
}

fn draw_series<DB: DrawingBackend, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    s: &Series,
) -> Result<(), Box<dyn Error>>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    DB::ErrorType: 'static,
{
    let points = s
        .points
        .iter()
        .copied()
        .filter(|(a, b)| a.is_finite() && b.is_finite());
    chart.draw_series(LineSeries::new(points, s.color.stroke_width(s.width)))?;
    Ok(())
}

fn configure_mesh<DB: DrawingBackend, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    x_desc: &str,
    y_desc: &str,
    x_digits: usize,
    y_digits: usize,
) -> Result<(), Box<dyn Error>>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>
        + plotters::coord::ranged1d::ValueFormatter<f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>
        + plotters::coord::ranged1d::ValueFormatter<f64>,
    DB::ErrorType: 'static,
{
    let xf = move |v: &f64| tick_label(*v, x_digits);
    let yf = move |v: &f64| tick_label(*v, y_digits);
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FONT, 20))
        .label_style((FONT, 16))
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.12))
        .draw()?;
    Ok(())
}

/// One quantity of the walk against time: COG, ZMP and (if given) multi-body ZMP.
fn time_plot(
    path: &Path,
    caption: &str,
    axis: &str,
    series: &[Series],
) -> Result<(), Box<dyn Error>> {
    let (t_lo, t_hi) = bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let (v_lo, v_hi) = bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    let root = BitMapBackend::new(path, TIME_SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let (plot, legend) = layout(&root, caption)?;
    let mut chart = chart_builder(&plot)
        .build_cartesian_2d(padded(t_lo, t_hi, 0.0, 0.1), padded(v_lo, v_hi, 0.06, 0.05))?;
    configure_mesh(&mut chart, "time [s]", axis, 1, 2)?;
    for s in series {
        draw_series(&mut chart, s)?;
    }
    let entries: Vec<_> = series
        .iter()
        .map(|s| (s.label.clone(), Mark::Line(s.color)))
        .collect();
    draw_legend(&legend, &entries)?;
    root.present()?;
    Ok(())
}

/// Pixel size of the decorations around the plotting area (caption, label areas, margins,
/// legend strip) of the shared layout, measured on a scratch bitmap.
fn decorations(caption: &str) -> Result<(u32, u32), Box<dyn Error>> {
    let (w, h) = (1000u32, 800u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
    let (plot, _) = layout(&root, caption)?;
    let chart = chart_builder(&plot).build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    Ok((w - pw, h - ph))
}

fn footprint_plot(
    path: &Path,
    caption: &str,
    trajectory: &[Reference<f64>],
    footsteps: &[Footstep<f64>],
    mb: Option<&[MbSample]>,
) -> Result<(), Box<dyn Error>> {
    let start = &trajectory[0].feet;
    let mut soles: Vec<(Vec<(f64, f64)>, RGBColor)> = start
        .iter()
        .map(|f| (sole_outline(f.x, f.y, f.yaw), START_COLOR))
        .collect();
    soles.extend(footsteps.iter().map(|f| {
        let color = match f.side {
            Side::Left => LEFT_COLOR,
            Side::Right => RIGHT_COLOR,
        };
        (sole_outline(f.x, f.y, f.yaw), color)
    }));
    let mut series = vec![
        Series {
            label: "COG".into(),
            color: COG_COLOR,
            width: 2,
            points: trajectory.iter().map(|r| (r.x.cog, r.y.cog)).collect(),
        },
        Series {
            label: "ZMP (planned)".into(),
            color: ZMP_COLOR,
            width: 2,
            points: trajectory.iter().map(|r| (r.x.zmp, r.y.zmp)).collect(),
        },
    ];
    if let Some(mb) = mb {
        series.push(Series {
            label: "ZMP (multi-body)".into(),
            color: MB_COLOR,
            width: 1,
            points: mb.iter().map(|s| (s.mb_zmp_x, s.mb_zmp_y)).collect(),
        });
    }
    // The multi-body ZMP is left out of the bounds: its finite-difference ends may jump.
    let all = || {
        soles
            .iter()
            .flat_map(|(o, _)| o.iter())
            .chain(series[..2].iter().flat_map(|s| s.points.iter()))
            .copied()
    };
    let (x_lo, x_hi) = bounds(all().map(|p| p.0));
    let (y_lo, y_hi) = bounds(all().map(|p| p.1));
    let margin = 0.05;
    let (x_lo, x_hi, y_lo, y_hi) = (x_lo - margin, x_hi + margin, y_lo - margin, y_hi + margin);
    // Equal scaling: fit the data into at most 1100 × 800 px of plotting area (and at least
    // 600 × 300), widening the shorter range around its centre.
    let (span_x, span_y) = (x_hi - x_lo, y_hi - y_lo);
    let scale = (1100.0 / span_x).min(800.0 / span_y); // px per m
    let pw = (span_x * scale).max(600.0).round() as u32;
    let ph = (span_y * scale).max(300.0).round() as u32;
    let (half_x, half_y) = (0.5 * f64::from(pw) / scale, 0.5 * f64::from(ph) / scale);
    let (cx, cy) = (0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi));
    let (dw, dh) = decorations(caption)?;

    let root = BitMapBackend::new(path, (pw + dw, ph + dh)).into_drawing_area();
    root.fill(&WHITE)?;
    let (plot, legend) = layout(&root, caption)?;
    let mut chart = chart_builder(&plot)
        .build_cartesian_2d((cx - half_x)..(cx + half_x), (cy - half_y)..(cy + half_y))?;
    debug_assert_eq!(chart.plotting_area().dim_in_pixel(), (pw, ph));
    configure_mesh(&mut chart, "x [m]", "y [m]", 1, 2)?;
    // Soles: the initial stance in grey, then every footstep by side; then the paths.
    for (o, color) in &soles {
        chart.draw_series(std::iter::once(Polygon::new(o.clone(), color.mix(0.08))))?;
        chart.draw_series(std::iter::once(PathElement::new(
            o.clone(),
            color.stroke_width(2),
        )))?;
    }
    for s in &series {
        draw_series(&mut chart, s)?;
    }
    let mut entries = vec![
        ("initial stance".to_string(), Mark::Sole(START_COLOR)),
        ("left sole".to_string(), Mark::Sole(LEFT_COLOR)),
        ("right sole".to_string(), Mark::Sole(RIGHT_COLOR)),
    ];
    entries.extend(
        series
            .iter()
            .map(|s| (s.label.clone(), Mark::Line(s.color))),
    );
    draw_legend(&legend, &entries)?;
    root.present()?;
    Ok(())
}

/// Writes `sagittal.png`, `frontal.png` and `footprints.png` into `out` (created if needed)
/// and returns their paths.
///
/// * `trajectory`: one reference per tick from tick 0 ([`crate::scenario::Run::trajectory`]);
///   its first entry also gives the initial stance drawn in the footprint plot;
/// * `dt`: the tick \[s\];
/// * `footsteps`: the landings to draw (e.g. the steps of [`crate::scenario::Run::footsteps`]);
/// * `mb`: the multi-body evaluation of the same trajectory, if any (its ZMP is added to every
///   plot);
/// * `name`: used in the captions.
///
/// Errors: an empty trajectory, a `dt` that is not positive and finite, no usable font (see the
/// module documentation), or an I/O or drawing error.
pub fn write_plots(
    out: &Path,
    name: &str,
    trajectory: &[Reference<f64>],
    dt: f64,
    footsteps: &[Footstep<f64>],
    mb: Option<&[MbSample]>,
) -> Result<Vec<PathBuf>, Box<dyn Error>> {
    if trajectory.is_empty() {
        return Err("write_plots: empty trajectory".into());
    }
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(format!("write_plots: dt must be positive and finite, got {dt}").into());
    }
    ensure_font()?;
    fs::create_dir_all(out)?;
    let t = |k: usize| k as f64 * dt;
    let mut written = Vec::new();
    for (file, plane, q) in [
        ("sagittal.png", "sagittal plane", 0),
        ("frontal.png", "frontal plane", 1),
    ] {
        let axis = ["x", "y"][q];
        let plane_of = |r: &Reference<f64>| if q == 0 { r.x } else { r.y };
        let mut series = vec![
            Series {
                label: format!("COG {axis}"),
                color: COG_COLOR,
                width: 2,
                points: trajectory
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (t(k), plane_of(r).cog))
                    .collect(),
            },
            Series {
                label: format!("ZMP {axis} (planned)"),
                color: ZMP_COLOR,
                width: 2,
                points: trajectory
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (t(k), plane_of(r).zmp))
                    .collect(),
            },
        ];
        if let Some(mb) = mb {
            series.push(Series {
                label: format!("ZMP {axis} (multi-body)"),
                color: MB_COLOR,
                width: 1,
                points: mb
                    .iter()
                    .map(|s| (s.t, if q == 0 { s.mb_zmp_x } else { s.mb_zmp_y }))
                    .collect(),
            });
        }
        let path = out.join(file);
        time_plot(
            &path,
            &format!("{name}: {plane}"),
            &format!("{axis} [m]"),
            &series,
        )?;
        written.push(path);
    }
    let path = out.join("footprints.png");
    footprint_plot(
        &path,
        &format!("{name}: footprints (top view)"),
        trajectory,
        footsteps,
        mb,
    )?;
    written.push(path);
    Ok(written)
}

/// One curve of [`write_time_plot`]: a label, an RGB colour and the (t, value) points.
pub type Curve = (String, (u8, u8, u8), Vec<(f64, f64)>);

/// Writes a time plot of `curves` (in the style of the other plots) to `path`; `axis` labels
/// the value axis. Errors: no usable font, an I/O or drawing error.
pub fn write_time_plot(
    path: &Path,
    caption: &str,
    axis: &str,
    curves: &[Curve],
) -> Result<(), Box<dyn Error>> {
    ensure_font()?;
    let series: Vec<Series> = curves
        .iter()
        .map(|(label, (r, g, b), points)| Series {
            label: label.clone(),
            color: RGBColor(*r, *g, *b),
            width: 2,
            points: points.clone(),
        })
        .collect();
    time_plot(path, caption, axis, &series)
}
