//! The figures against time: one plane of the walk (`sagittal.png`, `frontal.png`) and the
//! side-by-side comparison of `modification.png`.

use std::error::Error;
use std::ops::Range;
use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{
    bounds, configure_mesh, draw_legend, draw_series, padded, render, Area, Key, Px, Series,
};
use super::data::{cog, fluctuation, phase_spans, sole_limits, zmp, Span};
use super::{Comparison, ComparisonColumn, Mark, Walk};
use planner_core::gait::{Phase, Reference};

pub(super) const COG_COLOR: RGBColor = RGBColor(0x1f, 0x5f, 0xbf);
pub(super) const ZMP_COLOR: RGBColor = RGBColor(0xd6, 0x27, 0x28);
pub(super) const MB_COLOR: RGBColor = RGBColor(0x2c, 0xa0, 0x2c);
const LIMIT_COLOR: RGBColor = RGBColor(0x40, 0x40, 0x40);
const MARK_COLOR: RGBColor = RGBColor(0x7b, 0x2d, 0x8e);
/// Shade of single support.
pub(super) const SINGLE_SHADE: RGBColor = RGBColor(0xe4, 0xec, 0xf7);
/// Shade of double support (while walking).
pub(super) const DOUBLE_SHADE: RGBColor = RGBColor(0xfb, 0xed, 0xd2);

/// Width of the legend strip on the right \[px\].
pub(super) const LEGEND_W: u32 = 250;
/// Size of a plane figure \[px\].
const PLANE_SIZE: (u32, u32) = (1200, 880);
/// Width of one column of the comparison figure \[px\].
const COLUMN_W: u32 = 560;
/// Fraction of a figure's height for the upper panel.
const UPPER: f64 = 0.6;
/// The comparison's zoom panels start this long before the modification \[s\].
const ZOOM_BEFORE_S: f64 = 1.0;
/// … and end this long after it \[s\].
const ZOOM_AFTER_S: f64 = 2.5;
/// The zoom panel spans at least ± this \[mm\].
const MIN_ZOOM_MM: f64 = 2.0;
/// A mark lies at least this fraction of its time axis right of the axis' left end (where
/// the y axis would hide it).
const MARK_INSET: f64 = 0.03;

/// A polyline in chart coordinates.
type Line = Vec<(f64, f64)>;
/// The sole limits: the lower and the upper polyline.
type Limits = (Line, Line);

/// One panel against time.
struct Panel<'a> {
    t: Range<f64>,
    y: Range<f64>,
    x_desc: &'a str,
    y_desc: &'a str,
    y_digits: usize,
    spans: &'a [Span],
    /// The sole limits: lower and upper polylines.
    limits: Option<Limits>,
    series: &'a [Series],
    marks: &'a [Mark],
    /// Label the marks (upper panel) or only draw their lines.
    mark_labels: bool,
    /// A note in the panel's upper left corner.
    note: Option<String>,
}

fn draw_panel(area: &Area<'_>, px: Px, p: &Panel<'_>) -> Result<(), Box<dyn Error>> {
    let mut chart = ChartBuilder::on(area)
        .margin(px.u(8))
        .margin_right(px.u(18))
        .x_label_area_size(px.u(50))
        .y_label_area_size(px.u(80))
        .build_cartesian_2d(p.t.clone(), p.y.clone())?;
    for &(t0, t1, phase) in p.spans {
        let (t0, t1) = (t0.max(p.t.start), t1.min(p.t.end));
        if t0 >= t1 {
            continue;
        }
        let shade = match phase {
            Phase::Single(_) => SINGLE_SHADE,
            Phase::Double => DOUBLE_SHADE,
            Phase::Standing => continue,
        };
        chart.draw_series(std::iter::once(Rectangle::new(
            [(t0, p.y.start), (t1, p.y.end)],
            shade.filled(),
        )))?;
    }
    configure_mesh(&mut chart, px, p.x_desc, p.y_desc, (1, p.y_digits))?;
    if let Some((lo, hi)) = &p.limits {
        for line in [lo, hi] {
            let s = Series {
                label: String::new(),
                color: LIMIT_COLOR,
                width: 1,
                points: line.clone(),
                dashed: true,
            };
            draw_series(&mut chart, px, &s, (&p.t, &p.y))?;
        }
    }
    for s in p.series {
        draw_series(&mut chart, px, s, (&p.t, &p.y))?;
    }
    let label_style = px
        .font(15)
        .color(&MARK_COLOR)
        .pos(Pos::new(HPos::Left, VPos::Top));
    let marks: Vec<&Mark> = p.marks.iter().filter(|m| p.t.contains(&m.t)).collect();
    for m in &marks {
        chart.draw_series(std::iter::once(DashedPathElement::new(
            vec![(m.t, p.y.start), (m.t, p.y.end)],
            px.i(6),
            px.i(4),
            MARK_COLOR.stroke_width(px.u(2)),
        )))?;
    }
    if p.mark_labels {
        let plot = chart.plotting_area().strip_coord_spec();
        let (ox, oy) = plot.get_base_pixel();
        let (w, _) = plot.dim_in_pixel();
        let gap = px.i(5);
        // Placed label boxes (x0, y0, x1, y1): a label that would overlap one goes a line
        // lower.
        let mut placed: Vec<(i32, i32, i32, i32)> = Vec::new();
        for m in &marks {
            let (x, y) = chart.backend_coord(&(m.t, p.y.end));
            let (tw, th) = plot.estimate_text_size(&m.label, &label_style)?;
            let (tw, th) = (tw as i32, th as i32);
            // Right of the line, or left of it when the label would leave the panel.
            let lx = if x - ox + gap + tw < w as i32 {
                x - ox + gap
            } else {
                x - ox - gap - tw
            };
            let mut ly = y - oy + gap;
            while placed
                .iter()
                .any(|b| lx < b.2 && lx + tw > b.0 && ly < b.3 && ly + th > b.1)
            {
                ly += th + gap;
            }
            placed.push((lx - gap, ly - gap, lx + tw + gap, ly + th + gap));
            boxed_text(&plot, px, &m.label, (lx, ly), &label_style)?;
        }
    }
    if let Some(note) = &p.note {
        let plot = chart.plotting_area().strip_coord_spec();
        let style = px.font(14).pos(Pos::new(HPos::Left, VPos::Top));
        let (_, th) = plot.estimate_text_size(note, &style)?;
        let (_, h) = plot.dim_in_pixel();
        let at = (px.i(6), h as i32 - px.i(6) - th as i32);
        boxed_text(&plot, px, note, at, &style)?;
    }
    Ok(())
}

/// `text` with its top left corner at `at` (pixels of `area`), on a white box.
fn boxed_text(
    area: &Area<'_>,
    px: Px,
    text: &str,
    at: (i32, i32),
    style: &TextStyle<'_>,
) -> Result<(), Box<dyn Error>> {
    let (w, h) = area.estimate_text_size(text, style)?;
    let (m, (x, y)) = (px.i(3), at);
    area.draw(&Rectangle::new(
        [(x - m, y - m), (x + w as i32 + m, y + h as i32 + m)],
        WHITE.mix(0.85).filled(),
    ))?;
    area.draw(&Text::new(text.to_string(), at, style.clone()))?;
    Ok(())
}

fn time_of(k: usize, dt: f64) -> f64 {
    k as f64 * dt
}

/// The time axis `t`, begun earlier when a mark within it lies less than [`MARK_INSET`] of
/// its span from its start (a modification in the first ticks, before the walk's start), so
/// that the mark is drawn inside the plot area and not on the y axis; `t` itself otherwise.
fn inset_marks(t: Range<f64>, marks: &[Mark]) -> Range<f64> {
    let edge = t.start + MARK_INSET * (t.end - t.start);
    let first = marks
        .iter()
        .map(|m| m.t)
        .filter(|&x| x >= t.start && x < edge)
        .fold(f64::INFINITY, f64::min);
    if !first.is_finite() {
        return t;
    }
    // first − start = MARK_INSET · (end − start).
    let start = (first - MARK_INSET * t.end) / (1.0 - MARK_INSET);
    start..t.end
}

/// The time axis of the plane figures.
pub(super) fn plane_time_axis(walk: &Walk<'_>) -> Range<f64> {
    let t_end = time_of(walk.trajectory.len().saturating_sub(1), walk.dt).max(0.1);
    inset_marks(0.0..t_end, &walk.marks)
}

/// The upper panel's lines of one trajectory in one plane.
fn plane_series(tr: &[Reference<f64>], dt: f64, plane: usize, axis: &str) -> Vec<Series> {
    let line = |label: String, color, f: &dyn Fn(&Reference<f64>) -> f64| Series {
        label,
        color,
        width: 2,
        points: tr
            .iter()
            .enumerate()
            .map(|(k, r)| (time_of(k, dt), f(r)))
            .collect(),
        dashed: false,
    };
    vec![
        line(format!("COG {axis}"), COG_COLOR, &|r| cog(r, plane)),
        line(format!("ZMP {axis} (planned)"), ZMP_COLOR, &|r| {
            zmp(r, plane)
        }),
    ]
}

fn limit_lines(tr: &[Reference<f64>], dt: f64, plane: usize, sole: [f64; 2]) -> Limits {
    let l: Vec<(f64, (f64, f64))> = tr
        .iter()
        .enumerate()
        .map(|(k, r)| (time_of(k, dt), sole_limits(r, plane, sole)))
        .collect();
    (
        l.iter().map(|&(t, (lo, _))| (t, lo)).collect(),
        l.iter().map(|&(t, (_, hi))| (t, hi)).collect(),
    )
}

/// The zoom panel's line (mm; NaN in double support).
fn fluctuation_series(tr: &[Reference<f64>], dt: f64, plane: usize, axis: &str) -> Series {
    Series {
        label: format!("ZMP {axis} − sole centre"),
        color: ZMP_COLOR,
        width: 2,
        points: tr
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let v = fluctuation(r, plane).map_or(f64::NAN, |v| v * 1e3);
                (time_of(k, dt), v)
            })
            .collect(),
        dashed: false,
    }
}

/// The symmetric zoom range covering `lines` (at least ± [`MIN_ZOOM_MM`]).
fn zoom_range<'a>(lines: impl IntoIterator<Item = &'a Series>) -> Range<f64> {
    let m = lines
        .into_iter()
        .flat_map(|s| s.points.iter().map(|p| p.1.abs()))
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    let half = (1.2 * m).max(MIN_ZOOM_MM);
    -half..half
}

fn upper_range<'a>(series: impl IntoIterator<Item = &'a Series>, limits: &[&Limits]) -> Range<f64> {
    let vals = series
        .into_iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(
            limits
                .iter()
                .flat_map(|(lo, hi)| lo.iter().chain(hi.iter()).map(|p| p.1)),
        );
    let (lo, hi) = bounds(vals);
    padded(lo, hi, 0.04, 0.05)
}

fn legend_entries(series: &[Series], zoom: &Series, marks: bool) -> Vec<(String, Key)> {
    let mut e: Vec<(String, Key)> = series
        .iter()
        .map(|s| (s.label.clone(), Key::Line(s.color, s.width.max(2))))
        .collect();
    e.push(("sole limits".into(), Key::Dashed(LIMIT_COLOR)));
    e.push(("single support".into(), Key::Fill(SINGLE_SHADE)));
    e.push(("double support".into(), Key::Fill(DOUBLE_SHADE)));
    if marks {
        e.push(("modification".into(), Key::Dashed(MARK_COLOR)));
    }
    e.push((String::new(), Key::None));
    e.push(("lower panel (zoom, mm):".into(), Key::None));
    e.push((zoom.label.clone(), Key::Line(zoom.color, 2)));
    e
}

/// `sagittal.png` (plane 0) or `frontal.png` (plane 1).
pub(super) fn plane_figure(
    path: &Path,
    walk: &Walk<'_>,
    plane: usize,
) -> Result<(), Box<dyn Error>> {
    let (axis, name) = [("x", "sagittal plane"), ("y", "frontal plane")][plane];
    let tr = walk.trajectory;
    let dt = walk.dt;
    let mut series = plane_series(tr, dt, plane, axis);
    if let Some(mb) = walk.mb {
        series.push(Series {
            label: format!("ZMP {axis} (multi-body)"),
            color: MB_COLOR,
            width: 1,
            points: mb
                .iter()
                .map(|s| (s.t, if plane == 0 { s.mb_zmp_x } else { s.mb_zmp_y }))
                .collect(),
            dashed: false,
        });
    }
    let limits = limit_lines(tr, dt, plane, walk.sole);
    // The multi-body ZMP is left out of the range (its finite-difference ends may jump); it
    // is cut where it leaves the panel.
    let y = upper_range(&series[..2], &[&limits]);
    let zoom = fluctuation_series(tr, dt, plane, axis);
    let zy = zoom_range([&zoom]);
    let t = plane_time_axis(walk);
    let spans = phase_spans(tr, dt);
    let caption = format!("{}: {name}", walk.name);
    render(path, PLANE_SIZE, |root, px| {
        let body = root
            .margin(px.u(8), 0, 0, 0)
            .titled(&caption, px.font(25))?;
        let w = body.dim_in_pixel().0;
        let (plot, legend) = body.split_horizontally(w.saturating_sub(px.u(LEGEND_W)));
        let h = plot.dim_in_pixel().1;
        let (upper, lower) = plot.split_vertically((f64::from(h) * UPPER) as u32);
        draw_panel(
            &upper,
            px,
            &Panel {
                t: t.clone(),
                y: y.clone(),
                x_desc: "",
                y_desc: &format!("{axis} [m]"),
                y_digits: 2,
                spans: &spans,
                limits: Some(limits.clone()),
                series: &series,
                marks: &walk.marks,
                mark_labels: true,
                note: None,
            },
        )?;
        draw_panel(
            &lower,
            px,
            &Panel {
                t: t.clone(),
                y: zy.clone(),
                x_desc: "time [s]",
                y_desc: "fluctuation [mm]",
                y_digits: 1,
                spans: &spans,
                limits: None,
                series: std::slice::from_ref(&zoom),
                marks: &walk.marks,
                mark_labels: false,
                note: Some(format!(
                    "single support: planned ZMP {axis} − support-sole centre (sole {:.0} × {:.0} mm)",
                    walk.sole[0] * 1e3,
                    walk.sole[1] * 1e3
                )),
            },
        )?;
        draw_legend(
            &legend,
            px,
            &legend_entries(&series, &zoom, !walk.marks.is_empty()),
        )?;
        Ok(())
    })
}

/// What `modification.png` shows (see [`Walk::comparison`]).
pub(super) fn comparison_layout<'a>(walk: &'a Walk<'_>) -> Option<Comparison<'a>> {
    let pre_start = walk.columns.is_empty()
        && !walk.marks.is_empty()
        && walk.marks.iter().all(|m| m.before_start);
    if walk.columns.is_empty() && !pre_start {
        return None;
    }
    let (_, name) = [("x", "sagittal plane"), ("y", "frontal plane")][walk.plane.min(1)];
    let dt = walk.dt;
    // The first planned column shows no mark: the modifications had not been made in it.
    let columns: Vec<ComparisonColumn<'a>> = walk
        .columns
        .iter()
        .enumerate()
        .map(|(i, c)| ComparisonColumn {
            title: c.title.as_str(),
            trajectory: c.trajectory.as_slice(),
            marks: if i == 0 { &[] } else { &walk.marks },
        })
        .chain(std::iter::once(ComparisonColumn {
            title: walk.title.as_str(),
            trajectory: walk.trajectory,
            marks: &walk.marks,
        }))
        .collect();
    let t_end = columns
        .iter()
        .map(|c| time_of(c.trajectory.len().saturating_sub(1), dt))
        .fold(0.1, f64::max);
    let t = inset_marks(0.0..t_end, &walk.marks);
    // The zoom panels show the time around the first modification during the walk; the
    // whole walk when every modification preceded the start.
    let zoom_t = match walk.marks.iter().find(|m| !m.before_start) {
        Some(m) => (m.t - ZOOM_BEFORE_S).max(0.0)..(m.t + ZOOM_AFTER_S).min(t_end),
        None => 0.0..t_end,
    };
    let zoom_t = if zoom_t.start < zoom_t.end {
        zoom_t
    } else {
        0.0..t_end
    };
    let zoom_t = inset_marks(zoom_t, &walk.marks);
    let what = walk
        .marks
        .iter()
        .map(|m| m.label.as_str())
        .collect::<Vec<_>>()
        .join("; ");
    Some(Comparison {
        caption: format!("{}, {name}: {what}", walk.name),
        columns,
        t,
        zoom_t,
    })
}

/// `modification.png`: the columns of `c` (the comparison columns and the walk itself, or the
/// walk alone), on the same axes.
pub(super) fn comparison_figure(
    path: &Path,
    walk: &Walk<'_>,
    c: &Comparison<'_>,
) -> Result<(), Box<dyn Error>> {
    let plane = walk.plane;
    let axis = ["x", "y"][plane];
    let dt = walk.dt;
    let cols = &c.columns;
    let series: Vec<Vec<Series>> = cols
        .iter()
        .map(|c| plane_series(c.trajectory, dt, plane, axis))
        .collect();
    let limits: Vec<_> = cols
        .iter()
        .map(|c| limit_lines(c.trajectory, dt, plane, walk.sole))
        .collect();
    let zooms: Vec<Series> = cols
        .iter()
        .map(|c| fluctuation_series(c.trajectory, dt, plane, axis))
        .collect();
    let y = upper_range(series.iter().flatten(), &limits.iter().collect::<Vec<_>>());
    let zy = zoom_range(&zooms);
    let spans: Vec<_> = cols.iter().map(|c| phase_spans(c.trajectory, dt)).collect();
    let zoom_t = c.zoom_t.clone();
    // A single column is drawn as wide as two.
    let n = cols.len().max(2) as u32;
    let size = (COLUMN_W * n + LEGEND_W, PLANE_SIZE.1);
    render(path, size, |root, px| {
        let body = root
            .margin(px.u(8), 0, 0, 0)
            .titled(&c.caption, px.font(25))?;
        let w = body.dim_in_pixel().0;
        let (plot, legend) = body.split_horizontally(w.saturating_sub(px.u(LEGEND_W)));
        let columns = plot.split_evenly((1, cols.len()));
        for (i, area) in columns.iter().enumerate() {
            let area = area.titled(cols[i].title, px.font(17))?;
            let h = area.dim_in_pixel().1;
            let (upper, lower) = area.split_vertically((f64::from(h) * UPPER) as u32);
            // The largest fluctuation of the column, in its zoom panel.
            let peak = zooms[i]
                .points
                .iter()
                .map(|p| p.1)
                .filter(|v| v.is_finite())
                .fold(0.0_f64, |m, v| if v.abs() > m.abs() { v } else { m });
            draw_panel(
                &upper,
                px,
                &Panel {
                    t: c.t.clone(),
                    y: y.clone(),
                    x_desc: "",
                    y_desc: &format!("{axis} [m]"),
                    y_digits: 2,
                    spans: &spans[i],
                    limits: Some(limits[i].clone()),
                    series: &series[i],
                    marks: cols[i].marks,
                    mark_labels: false,
                    note: None,
                },
            )?;
            draw_panel(
                &lower,
                px,
                &Panel {
                    t: zoom_t.clone(),
                    y: zy.clone(),
                    x_desc: "time [s]",
                    y_desc: "fluctuation [mm]",
                    y_digits: 1,
                    spans: &spans[i],
                    limits: None,
                    series: std::slice::from_ref(&zooms[i]),
                    marks: cols[i].marks,
                    mark_labels: false,
                    note: Some(format!(
                        "zoom {:.1} … {:.1} s; largest in single support: {peak:+.1} mm",
                        zoom_t.start.max(0.0),
                        zoom_t.end
                    )),
                },
            )?;
        }
        let entries = legend_entries(&series[0], &zooms[0], !walk.marks.is_empty());
        draw_legend(&legend, px, &entries)?;
        Ok(())
    })
}
