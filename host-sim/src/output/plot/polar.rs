//! `push_map_<phase>.png`: a push-recovery map on polar axes. The radius is the velocity change
//! of the largest push walked through (`Δv = F Δt / m`, m/s), the angle the push's direction in
//! the walking frame (0° forward, up the page; 90° to the left); one closed line per
//! configuration, and IHMC's Atlas thresholds as crosses (forward 0.78 m/s up, backward
//! 0.49 m/s down, inward 0.22 and outward 0.25 m/s at the sides).

use std::error::Error;
use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{ensure_font, render};

/// The configurations' colours, in the order given.
const COLORS: [RGBColor; 3] = [
    RGBColor(0x80, 0x80, 0x80),
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
];
/// IHMC's Atlas thresholds (direction in degrees, Δv in m/s).
const ATLAS: [(f64, f64); 4] = [(0.0, 0.78), (180.0, 0.49), (90.0, 0.22), (270.0, 0.25)];

/// The point of direction `deg` and radius `r` on the page (forward up, left to the left).
fn page(deg: f64, r: f64) -> (f64, f64) {
    let a = deg.to_radians();
    (-r * a.sin(), r * a.cos())
}

/// Writes the polar map `series` (name, (direction °, Δv m/s) points) to `path`.
pub fn write_polar(
    path: &Path,
    title: &str,
    series: &[(&str, Vec<(f64, f64)>)],
) -> Result<(), Box<dyn Error>> {
    ensure_font()?;
    let largest = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|q| q.1))
        .chain(ATLAS.iter().map(|a| a.1))
        .fold(0.0f64, f64::max);
    let rmax = (largest / 0.25).ceil().max(1.0) * 0.25;
    render(path, (640, 700), |root, px| {
        let (top, rest) = root.split_vertically(px.u(40));
        top.draw(&Text::new(
            title.to_string(),
            (px.i(320), px.i(20)),
            px.font(16).pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        let (plot, legend) = rest.split_vertically(px.u(600));
        let m = rmax * 1.12;
        let mut chart = ChartBuilder::on(&plot)
            .margin(px.u(10))
            .build_cartesian_2d(-m..m, -m..m)?;
        // Rings every 0.25 m/s and spokes every 45°.
        let grid = RGBColor(0xc8, 0xc8, 0xc8);
        let mut r = 0.25;
        while r <= rmax + 1e-9 {
            let ring: Vec<(f64, f64)> = (0..=120).map(|i| page(3.0 * f64::from(i), r)).collect();
            chart.draw_series(std::iter::once(PathElement::new(
                ring,
                grid.stroke_width(px.u(1)),
            )))?;
            let (x, y) = page(22.5, r);
            let unit = if r + 0.25 > rmax + 1e-9 { " m/s" } else { "" };
            chart.draw_series(std::iter::once(Text::new(
                format!("Δv {r:.2}{unit}"),
                (x, y),
                px.font(11).color(&RGBColor(0x60, 0x60, 0x60)),
            )))?;
            r += 0.25;
        }
        for i in 0..8 {
            let d = 45.0 * f64::from(i);
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(0.0, 0.0), page(d, rmax)],
                grid.stroke_width(px.u(1)),
            )))?;
            let (x, y) = page(d, rmax * 1.06);
            chart.draw_series(std::iter::once(Text::new(
                format!("{d:.0}°"),
                (x, y),
                px.font(12).pos(Pos::new(HPos::Center, VPos::Center)),
            )))?;
        }
        // Earlier configurations drawn wider, so that equal ones stay visible under later ones.
        let n = series.len() as u32;
        for (i, ((_, points), color)) in series.iter().zip(COLORS.iter().cycle()).enumerate() {
            let width = px.u(2 + 2 * (n - 1 - i as u32));
            let mut line: Vec<(f64, f64)> = points.iter().map(|&(d, v)| page(d, v)).collect();
            if points.len() > 2 {
                if let Some(&first) = line.first() {
                    line.push(first);
                }
            }
            chart.draw_series(std::iter::once(PathElement::new(
                line,
                color.stroke_width(width),
            )))?;
            chart.draw_series(
                points
                    .iter()
                    .map(|&(d, v)| Circle::new(page(d, v), px.u(3), color.filled())),
            )?;
        }
        chart.draw_series(
            ATLAS
                .iter()
                .map(|&(d, v)| Cross::new(page(d, v), px.u(5), BLACK.stroke_width(px.u(2)))),
        )?;
        // The legend.
        let mut x = px.i(20);
        for ((name, _), color) in series.iter().zip(COLORS.iter().cycle()) {
            legend.draw(&PathElement::new(
                vec![(x, px.i(30)), (x + px.i(24), px.i(30))],
                color.stroke_width(px.u(2)),
            ))?;
            legend.draw(&Text::new(
                name.to_string(),
                (x + px.i(30), px.i(30)),
                px.font(13).pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
            x += px.i(150);
        }
        legend.draw(&Cross::new(
            (x, px.i(30)),
            px.u(5),
            BLACK.stroke_width(px.u(2)),
        ))?;
        legend.draw(&Text::new(
            "Atlas (IHMC)".to_string(),
            (x + px.i(10), px.i(30)),
            px.font(13).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
        Ok(())
    })
}
