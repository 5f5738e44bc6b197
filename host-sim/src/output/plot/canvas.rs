//! Drawing helpers shared by the figures: the font, anti-aliased rendering (drawn at
//! [`SUPERSAMPLE`] times the size, then averaged down), the PNG file, the legend strip, tick
//! labels and line series with gaps.

use std::cell::RefCell;
use std::error::Error;
use std::fs;
use std::io::BufWriter;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{FONT_ENV, FONT_PATHS};

/// The family name the font is registered under.
pub(super) const FONT: &str = "sans-serif";

/// Every figure is drawn at this many times its size and averaged down (box filter), which
/// anti-aliases lines, outlines and text.
pub const SUPERSAMPLE: u32 = 3;

pub(super) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Registers the font with plotters once (plotters' `ab_glyph` backend keeps a global table
/// of `'static` font data: the file is read and leaked once per process).
pub(super) fn ensure_font() -> Result<(), String> {
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

/// Pixel sizes of the final image, scaled to the drawing resolution.
#[derive(Clone, Copy)]
pub(super) struct Px(pub u32);

impl Px {
    /// `n` final pixels in drawing pixels.
    pub fn u(self, n: u32) -> u32 {
        n * self.0
    }
    /// The same, signed.
    pub fn i(self, n: i32) -> i32 {
        n * self.0 as i32
    }
    /// A font of `size` final pixels.
    pub fn font(self, size: u32) -> TextStyle<'static> {
        TextStyle::from((FONT, f64::from(size * self.0)))
    }
}

/// Draws a `w × h` figure with `draw` at [`SUPERSAMPLE`] times the size on a white
/// background, averages it down and writes it to `path` as an 8-bit RGB PNG.
pub(super) fn render(
    path: &Path,
    (w, h): (u32, u32),
    draw: impl FnOnce(&Area<'_>, Px) -> Result<(), Box<dyn Error>>,
) -> Result<(), Box<dyn Error>> {
    let s = SUPERSAMPLE;
    let (bw, bh) = (w * s, h * s);
    let mut big = vec![255u8; (bw as usize) * (bh as usize) * 3];
    {
        let root = BitMapBackend::with_buffer(&mut big, (bw, bh)).into_drawing_area();
        draw(&root, Px(s))?;
        root.present()?;
    }
    let small = downsample(&big, (w, h), s);
    let file =
        fs::File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header()?;
    writer.write_image_data(&small)?;
    writer.finish()?;
    Ok(())
}

/// Averages every `s × s` block of the RGB image `big` (`w·s × h·s` pixels) into one pixel.
fn downsample(big: &[u8], (w, h): (u32, u32), s: u32) -> Vec<u8> {
    let (w, h, s) = (w as usize, h as usize, s as usize);
    let bw = w * s;
    let n = (s * s) as u32;
    let mut out = vec![0u8; w * h * 3];
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 3];
            for dy in 0..s {
                let row = ((y * s + dy) * bw + x * s) * 3;
                for p in big[row..row + 3 * s].chunks_exact(3) {
                    acc[0] += u32::from(p[0]);
                    acc[1] += u32::from(p[1]);
                    acc[2] += u32::from(p[2]);
                }
            }
            let o = (y * w + x) * 3;
            for c in 0..3 {
                out[o + c] = ((acc[c] + n / 2) / n) as u8;
            }
        }
    }
    out
}

/// `lo..hi` widened by `pad` of its length on each side (and to at least `min_span`).
pub(super) fn padded(lo: f64, hi: f64, pad: f64, min_span: f64) -> Range<f64> {
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (-1.0, 1.0) };
    let span = (hi - lo).max(min_span);
    let mid = 0.5 * (lo + hi);
    let half = 0.5 * span * (1.0 + 2.0 * pad);
    (mid - half)..(mid + half)
}

/// The smallest and largest finite value (`(inf, -inf)` when there is none).
pub(super) fn bounds(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// A tick label with `digits` decimals (and no "-0.00").
pub(super) fn tick_label(v: f64, digits: usize) -> String {
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

/// The tick labels a mesh draws on each axis, at most: plotters' key points for this many
/// labels are the values [`label_digits`] formats (`configure_mesh` asks for exactly this).
pub(super) const MESH_LABELS: usize = 11;

/// The most decimals a tick label gets.
const MAX_DIGITS: usize = 9;

/// The fewest decimals, at least `min` (at most [`MAX_DIGITS`]), with which every tick value
/// plotters places on `range` (its key points for [`MESH_LABELS`] labels, as the mesh draws
/// them) is labelled truly: the label read back is the value (to a millionth of the ticks'
/// spacing), so that no two labels are equal and none is rounded to a neighbour's.
pub(super) fn label_digits(range: Range<f64>, min: usize) -> usize {
    let ticks = RangedCoordf64::from(range).key_points(MESH_LABELS);
    let spacing = ticks
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(f64::INFINITY, f64::min);
    let tolerance = if spacing.is_finite() {
        spacing * 1e-6
    } else {
        // One tick: its label is true to its own magnitude.
        ticks.first().map_or(0.0, |v| v.abs() * 1e-6)
    };
    (min..=MAX_DIGITS)
        .find(|&d| {
            ticks.iter().all(|&v| {
                tick_label(v, d)
                    .parse::<f64>()
                    .is_ok_and(|l| (l - v).abs() <= tolerance)
            })
        })
        .unwrap_or(MAX_DIGITS.max(min))
}

/// How a legend entry is marked.
#[derive(Clone, Copy)]
pub(super) enum Key {
    /// A line of this colour and width.
    Line(RGBColor, u32),
    /// A dashed line of this colour.
    Dashed(RGBColor),
    /// A sole outline of this colour (solid).
    Sole(RGBColor),
    /// A dashed sole outline of this colour.
    DashedSole(RGBColor),
    /// A filled box (a shaded interval).
    Fill(RGBColor),
    /// No mark (a heading, or a blank line with an empty label).
    None,
}

/// The legend strip: one entry per line, from the top.
pub(super) fn draw_legend(
    area: &Area<'_>,
    px: Px,
    entries: &[(String, Key)],
) -> Result<(), Box<dyn Error>> {
    let style = px.font(17).pos(Pos::new(HPos::Left, VPos::Center));
    let (x0, x1) = (px.i(6), px.i(36));
    for (i, (label, key)) in entries.iter().enumerate() {
        let y = px.i(44 + 27 * i as i32);
        let (top, bottom) = (y - px.i(7), y + px.i(7));
        match *key {
            Key::None => {}
            Key::Line(c, w) => {
                area.draw(&PathElement::new(
                    vec![(x0, y), (x1, y)],
                    c.stroke_width(px.u(w)),
                ))?;
            }
            Key::Dashed(c) => {
                area.draw(&DashedPathElement::new(
                    vec![(x0, y), (x1, y)],
                    px.i(6),
                    px.i(4),
                    c.stroke_width(px.u(2)),
                ))?;
            }
            Key::Fill(c) => {
                area.draw(&Rectangle::new([(x0, top), (x1, bottom)], c.filled()))?;
            }
            Key::Sole(c) | Key::DashedSole(c) => {
                area.draw(&Rectangle::new(
                    [(x0, top), (x1, bottom)],
                    c.mix(0.08).filled(),
                ))?;
                let outline = vec![(x0, top), (x1, top), (x1, bottom), (x0, bottom), (x0, top)];
                if matches!(key, Key::Sole(_)) {
                    area.draw(&PathElement::new(outline, c.stroke_width(px.u(2))))?;
                } else {
                    area.draw(&DashedPathElement::new(
                        outline,
                        px.i(5),
                        px.i(3),
                        c.stroke_width(px.u(2)),
                    ))?;
                }
            }
        }
        let x = if matches!(key, Key::None) {
            x0
        } else {
            px.i(46)
        };
        area.draw(&Text::new(label.clone(), (x, y), style.clone()))?;
    }
    Ok(())
}

/// A line to draw: non-finite points break it.
pub(super) struct Series {
    /// Legend label.
    pub label: String,
    /// Colour.
    pub color: RGBColor,
    /// Width in final pixels.
    pub width: u32,
    /// The points (NaN: a gap).
    pub points: Vec<(f64, f64)>,
    /// Dashed instead of solid.
    pub dashed: bool,
}

/// Draws `s` as a polyline, broken at non-finite points and at points outside the window
/// `clip` (x range, y range).
pub(super) fn draw_series<X, Y>(
    chart: &mut ChartContext<'_, BitMapBackend<'_>, Cartesian2d<X, Y>>,
    px: Px,
    s: &Series,
    clip: (&Range<f64>, &Range<f64>),
) -> Result<(), Box<dyn Error>>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>,
{
    let style = s.color.stroke_width(px.u(s.width));
    let mut run: Vec<(f64, f64)> = Vec::new();
    let within = |v: f64, r: &Range<f64>| v.is_finite() && v >= r.start && v <= r.end;
    let inside = |p: &(f64, f64)| within(p.0, clip.0) && within(p.1, clip.1);
    let mut flush = |run: &mut Vec<(f64, f64)>| -> Result<(), Box<dyn Error>> {
        if run.len() > 1 {
            if s.dashed {
                chart.draw_series(std::iter::once(DashedPathElement::new(
                    run.clone(),
                    px.i(7),
                    px.i(5),
                    style,
                )))?;
            } else {
                chart.draw_series(std::iter::once(PathElement::new(run.clone(), style)))?;
            }
        }
        run.clear();
        Ok(())
    };
    for p in &s.points {
        if inside(p) {
            run.push(*p);
        } else {
            flush(&mut run)?;
        }
    }
    flush(&mut run)?;
    Ok(())
}

/// The tick labels a mesh drew: (value, label) on the x axis, then on the y axis.
pub(super) type MeshLabels = (Vec<(f64, String)>, Vec<(f64, String)>);

/// The axes, tick labels and a light grid; returns the labels drawn.
pub(super) fn configure_mesh<X, Y>(
    chart: &mut ChartContext<'_, BitMapBackend<'_>, Cartesian2d<X, Y>>,
    px: Px,
    x_desc: &str,
    y_desc: &str,
    (x_digits, y_digits): (usize, usize),
) -> Result<MeshLabels, Box<dyn Error>>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>
        + plotters::coord::ranged1d::ValueFormatter<f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>
        + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    // Enough decimals that every tick plotters draws is labelled truly (and so distinctly);
    // the labels drawn are recorded for the caller.
    let x_digits = label_digits(chart.x_range(), x_digits);
    let y_digits = label_digits(chart.y_range(), y_digits);
    let drawn = RefCell::new((Vec::new(), Vec::new()));
    let xf = |v: &f64| {
        let l = tick_label(*v, x_digits);
        drawn.borrow_mut().0.push((*v, l.clone()));
        l
    };
    let yf = |v: &f64| {
        let l = tick_label(*v, y_digits);
        drawn.borrow_mut().1.push((*v, l.clone()));
        l
    };
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(MESH_LABELS)
        .y_labels(MESH_LABELS)
        .axis_desc_style(px.font(19))
        .label_style(px.font(15))
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.12).stroke_width(px.u(1)))
        .axis_style(BLACK.stroke_width(px.u(1)))
        .set_all_tick_mark_size(px.u(5))
        .draw()?;
    Ok(drawn.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The labels a mesh draws over `x` (and a fixed y range), as the figures draw it.
    fn drawn_labels(x: Range<f64>, min: usize) -> Vec<(f64, String)> {
        ensure_font().expect("the plots' font");
        let (w, h) = (400u32, 300u32);
        let mut buf = vec![255u8; (w * h * 3) as usize];
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let mut chart = ChartBuilder::on(&root)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(x, 0.0..1.0)
            .expect("chart");
        configure_mesh(&mut chart, Px(1), "x", "y", (min, 1))
            .expect("mesh")
            .0
    }

    /// Every axis gets tick labels that are true (each reads back as the value it marks) and
    /// so pairwise different, over spans from 0.1 mm to 9 km at many offsets, with and
    /// without a minimum of decimals: the labels the mesh draws, not a model of them.
    #[test]
    fn tick_labels_are_true_and_distinct_for_every_range() {
        let mut checked = 0;
        for e in -4..=3 {
            for m in [
                1.0, 1.1, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 5.2, 6.0, 7.5, 9.0,
            ] {
                let span = m * 10f64.powi(e);
                for centre in [-1.37, -0.12, 0.005, 0.26, 3.3] {
                    let lo = centre * 10f64.powi(e.max(0)) - 0.5 * span;
                    for min in [0, 2] {
                        let labels = drawn_labels(lo..lo + span, min);
                        assert!(labels.len() >= 2, "{lo}+{span}: {labels:?}");
                        let spacing = labels[1].0 - labels[0].0;
                        for (i, (v, l)) in labels.iter().enumerate() {
                            let read: f64 = l.parse().expect("a number");
                            assert!(
                                (read - v).abs() <= spacing.abs() * 1e-6,
                                "{lo}..{}: {l} marks {v}: {labels:?}",
                                lo + span
                            );
                            assert!(
                                labels[i + 1..].iter().all(|(_, b)| b != l),
                                "{lo}..{}: {l} twice: {labels:?}",
                                lo + span
                            );
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 1000);
        // The footprint plot of a short walk: a 0.05 m grid, two decimals.
        let short: Vec<String> = drawn_labels(-0.26..0.26, 1)
            .into_iter()
            .map(|(_, l)| l)
            .collect();
        assert_eq!(
            short.first().map(String::as_str),
            Some("-0.25"),
            "{short:?}"
        );
        assert_eq!(label_digits(-0.26..0.26, 1), 2);
    }
}
