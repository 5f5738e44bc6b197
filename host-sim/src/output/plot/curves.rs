//! A plain figure of curves against time (used by `host-sim physics` for tilt and centre of
//! pressure), in the style of the walk figures.

use std::error::Error;
use std::path::Path;

use plotters::prelude::*;

use super::canvas::{
    bounds, configure_mesh, draw_legend, draw_series, ensure_font, padded, render, Key, Series,
};
use super::time::LEGEND_W;

/// One curve of [`write_time_plot`]: a label, an RGB colour and the (t, value) points.
pub type Curve = (String, (u8, u8, u8), Vec<(f64, f64)>);

/// Size of the figure \[px\].
const SIZE: (u32, u32) = (1200, 520);

/// Writes a figure of `curves` against time to `path`; `axis` labels the value axis. Errors:
/// no usable font, no finite point, an I/O or drawing error.
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
            dashed: false,
        })
        .collect();
    let (t0, t1) = bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let (y0, y1) = bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    if !(t0.is_finite() && y0.is_finite()) {
        return Err(format!("{}: nothing to plot", path.display()).into());
    }
    let t = t0..t1.max(t0 + 1e-3);
    let y = padded(y0, y1, 0.05, 1e-6);
    render(path, SIZE, |root, px| {
        let (plot, legend) = root.split_horizontally(px.u(SIZE.0 - LEGEND_W));
        let mut chart = ChartBuilder::on(&plot)
            .caption(caption, px.font(22))
            .margin(px.u(10))
            .x_label_area_size(px.u(50))
            .y_label_area_size(px.u(80))
            .build_cartesian_2d(t.clone(), y.clone())?;
        configure_mesh(&mut chart, px, "time [s]", axis, (1, 3))?;
        for s in &series {
            draw_series(&mut chart, px, s, (&t, &y))?;
        }
        let entries: Vec<(String, Key)> = series
            .iter()
            .map(|s| (s.label.clone(), Key::Line(s.color, s.width)))
            .collect();
        draw_legend(&legend, px, &entries)
    })
}
