//! `footprints.png`: the walk seen from above, with equal scales on both axes.

use std::error::Error;
use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{
    bounds, configure_mesh, draw_legend, draw_series, render, Area, Key, Px, Series, SUPERSAMPLE,
};
use super::time::{COG_COLOR, LEGEND_W, MB_COLOR, ZMP_COLOR};
use super::Walk;
use planner_core::gait::{Footstep, Side};

const LEFT_COLOR: RGBColor = RGBColor(0x30, 0x30, 0x90);
const RIGHT_COLOR: RGBColor = RGBColor(0x90, 0x30, 0x30);
const START_COLOR: RGBColor = RGBColor(0x80, 0x80, 0x80);
const PLANNED_COLOR: RGBColor = RGBColor(0xe0, 0x7b, 0x00);

/// Corners of a sole centred at (x, y) with heading `yaw`, closed (5 points).
fn sole_outline(x: f64, y: f64, yaw: f64, sole: [f64; 2]) -> Vec<(f64, f64)> {
    let (s, c) = yaw.sin_cos();
    let (a, b) = (0.5 * sole[0], 0.5 * sole[1]);
    [(a, b), (-a, b), (-a, -b), (a, -b), (a, b)]
        .iter()
        .map(|&(u, v)| (x + c * u - s * v, y + s * u + c * v))
        .collect()
}

/// A landing's step number: inside the sole, near its outer edge (away from the other foot,
/// where the COG and ZMP paths do not pass) \[m from the centre\].
fn inside(sole: [f64; 2]) -> f64 {
    0.3 * sole[1]
}
/// A first planned pose's step number: just beyond the sole's outer edge.
fn outside(sole: [f64; 2]) -> f64 {
    0.5 * sole[1] + 0.022
}

/// Where a sole's step number goes: `out` m from its centre towards its outer side and
/// `ahead` m towards its toe.
fn label_point(f: &Footstep<f64>, out: f64, ahead: f64) -> (f64, f64) {
    let out = if f.side == Side::Left { out } else { -out };
    let (s, c) = f.yaw.sin_cos();
    (f.x + c * ahead - s * out, f.y + s * ahead + c * out)
}

/// Places the numbers of the first planned poses: beyond the sole's outer edge, or else
/// beyond its heel or its toe, whichever first keeps clear of the numbers already placed
/// (`taken`, to which it adds them); `px_per_m` converts to the figure's pixels.
fn place_planned_labels(
    planned: &[Footstep<f64>],
    sole: [f64; 2],
    taken: &mut Vec<(f64, f64)>,
    px_per_m: f64,
) -> Vec<(f64, f64)> {
    // A number with its brackets is about 35 × 15 px.
    let clear = |p: (f64, f64), q: &(f64, f64)| {
        ((p.0 - q.0) * px_per_m).abs() > 38.0 || ((p.1 - q.1) * px_per_m).abs() > 18.0
    };
    let end = 0.5 * sole[0] + 0.035;
    planned
        .iter()
        .map(|p| {
            let candidates = [
                label_point(p, outside(sole), 0.0),
                label_point(p, 0.0, -end),
                label_point(p, 0.0, end),
                label_point(p, outside(sole) + 0.03, 0.0),
            ];
            let at = candidates
                .iter()
                .copied()
                .find(|c| taken.iter().all(|t| clear(*c, t)))
                .unwrap_or(candidates[0]);
            taken.push(at);
            at
        })
        .collect()
}

fn side_color(side: Side) -> &'static RGBColor {
    match side {
        Side::Left => &LEFT_COLOR,
        Side::Right => &RIGHT_COLOR,
    }
}

/// Pixel size of the decorations around the plotting area (caption, label areas, margins,
/// legend strip) of the layout, measured at drawing resolution on a scratch bitmap and given
/// in final pixels.
fn decorations(caption: &str) -> Result<(u32, u32), Box<dyn Error>> {
    let px = Px(SUPERSAMPLE);
    let (w, h) = (px.u(1000), px.u(800));
    let mut buf = vec![0u8; (w as usize) * (h as usize) * 3];
    let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
    let (plot, _) = layout(&root, px, caption)?;
    let chart = chart_builder(&plot, px).build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    Ok(((w - pw) / px.0, (h - ph) / px.0))
}

fn layout<'a>(
    root: &Area<'a>,
    px: Px,
    caption: &str,
) -> Result<(Area<'a>, Area<'a>), Box<dyn Error>> {
    let body = root.margin(px.u(8), 0, 0, 0).titled(caption, px.font(25))?;
    let w = body.dim_in_pixel().0;
    Ok(body.split_horizontally(w.saturating_sub(px.u(LEGEND_W))))
}

fn chart_builder<'a, 'b>(area: &'a Area<'b>, px: Px) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut b = ChartBuilder::on(area);
    b.margin(px.u(12))
        .margin_right(px.u(20))
        .x_label_area_size(px.u(56))
        .y_label_area_size(px.u(84));
    b
}

pub(super) fn footprint_figure(path: &Path, walk: &Walk<'_>) -> Result<(), Box<dyn Error>> {
    let tr = walk.trajectory;
    let start = &tr[0].feet;
    let stance: Vec<_> = start
        .iter()
        .map(|f| sole_outline(f.x, f.y, f.yaw, walk.sole))
        .collect();
    let mut series = vec![
        Series {
            label: "COG".into(),
            color: COG_COLOR,
            width: 2,
            points: tr.iter().map(|r| (r.x.cog, r.y.cog)).collect(),
            dashed: false,
        },
        Series {
            label: "ZMP (planned)".into(),
            color: ZMP_COLOR,
            width: 2,
            points: tr.iter().map(|r| (r.x.zmp, r.y.zmp)).collect(),
            dashed: false,
        },
    ];
    if let Some(mb) = walk.mb {
        series.push(Series {
            label: "ZMP (multi-body)".into(),
            color: MB_COLOR,
            width: 1,
            points: mb.iter().map(|s| (s.mb_zmp_x, s.mb_zmp_y)).collect(),
            dashed: false,
        });
    }
    let landed: Vec<_> = walk
        .landings
        .iter()
        .map(|l| sole_outline(l.foot.x, l.foot.y, l.foot.yaw, walk.sole))
        .collect();
    let planned: Vec<_> = walk
        .landings
        .iter()
        .filter_map(|l| {
            l.planned
                .map(|p| (l.id, p, sole_outline(p.x, p.y, p.yaw, walk.sole)))
        })
        .collect();
    // The multi-body ZMP is left out of the bounds: its finite-difference ends may jump.
    // The scale before the labels are placed (they hardly change it).
    let scale_of = |pts: &mut dyn Iterator<Item = (f64, f64)>| {
        let pts: Vec<_> = pts.collect();
        let (x_lo, x_hi) = bounds(pts.iter().map(|p| p.0));
        let (y_lo, y_hi) = bounds(pts.iter().map(|p| p.1));
        (1100.0 / (x_hi - x_lo + 0.1)).min(800.0 / (y_hi - y_lo + 0.1))
    };
    let rough = scale_of(
        &mut stance
            .iter()
            .chain(&landed)
            .chain(planned.iter().map(|p| &p.2))
            .flatten()
            .copied(),
    );
    let mut taken: Vec<(f64, f64)> = walk
        .landings
        .iter()
        .filter(|l| l.id.is_some())
        .map(|l| label_point(&l.foot, inside(walk.sole), 0.0))
        .collect();
    let planned_poses: Vec<_> = planned.iter().map(|p| p.1).collect();
    let labels = place_planned_labels(&planned_poses, walk.sole, &mut taken, rough);
    // Room for the numbers themselves (about 0.02 m beyond their centres).
    let label_box: Vec<(f64, f64)> = labels
        .iter()
        .flat_map(|&(x, y)| [(x - 0.03, y - 0.02), (x + 0.03, y + 0.02)])
        .collect();
    let all = || {
        stance
            .iter()
            .chain(&landed)
            .chain(planned.iter().map(|p| &p.2))
            .flatten()
            .chain(series[..2].iter().flat_map(|s| s.points.iter()))
            .chain(&label_box)
            .copied()
    };
    let (x_lo, x_hi) = bounds(all().map(|p| p.0));
    let (y_lo, y_hi) = bounds(all().map(|p| p.1));
    if !(x_lo.is_finite() && x_hi.is_finite() && y_lo.is_finite() && y_hi.is_finite()) {
        return Err("footprints: no finite point to draw".into());
    }
    let margin = 0.05;
    let (x_lo, x_hi, y_lo, y_hi) = (x_lo - margin, x_hi + margin, y_lo - margin, y_hi + margin);
    // Equal scaling: fit the data into at most 1100 × 800 px of plotting area (and at least
    // 600 × 300), widening the shorter range around its centre.
    let (span_x, span_y) = (x_hi - x_lo, y_hi - y_lo);
    let scale = (1100.0 / span_x).min(800.0 / span_y); // final px per m
    let pw = (span_x * scale).max(600.0).round() as u32;
    let ph = (span_y * scale).max(300.0).round() as u32;
    let (half_x, half_y) = (0.5 * f64::from(pw) / scale, 0.5 * f64::from(ph) / scale);
    let (cx, cy) = (0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi));
    let caption = format!("{}: footprints (top view)", walk.name);
    let (dw, dh) = decorations(&caption)?;
    let all_plane = f64::NEG_INFINITY..f64::INFINITY;

    render(path, (pw + dw, ph + dh), |root, px| {
        let (plot, legend) = layout(root, px, &caption)?;
        let mut chart = chart_builder(&plot, px)
            .build_cartesian_2d((cx - half_x)..(cx + half_x), (cy - half_y)..(cy + half_y))?;
        configure_mesh(&mut chart, px, "x [m]", "y [m]", (1, 2))?;
        let sole = |o: &Vec<(f64, f64)>, c: RGBColor| Polygon::new(o.clone(), c.mix(0.07));
        // The initial stance (grey), the landings by side, the first planned poses of moved
        // steps (dashed, on top: they often coincide with other landings); then the paths;
        // the step numbers last.
        for o in &stance {
            chart.draw_series(std::iter::once(sole(o, START_COLOR)))?;
            let s = START_COLOR.stroke_width(px.u(2));
            chart.draw_series(std::iter::once(PathElement::new(o.clone(), s)))?;
        }
        for (l, o) in walk.landings.iter().zip(&landed) {
            let c = *side_color(l.foot.side);
            chart.draw_series(std::iter::once(sole(o, c)))?;
            let s = c.stroke_width(px.u(2));
            chart.draw_series(std::iter::once(PathElement::new(o.clone(), s)))?;
        }
        for (_, _, o) in &planned {
            chart.draw_series(std::iter::once(DashedPathElement::new(
                o.clone(),
                px.i(8),
                px.i(5),
                PLANNED_COLOR.stroke_width(px.u(2)),
            )))?;
        }
        for s in &series {
            draw_series(&mut chart, px, s, (&all_plane, &all_plane))?;
        }
        let number = |c: &'static RGBColor| {
            px.font(15)
                .color(c)
                .pos(Pos::new(HPos::Center, VPos::Center))
        };
        for l in &walk.landings {
            if let Some(id) = l.id {
                let at = label_point(&l.foot, inside(walk.sole), 0.0);
                let style = number(side_color(l.foot.side));
                chart.draw_series(std::iter::once(Text::new(id.to_string(), at, style)))?;
            }
        }
        for ((id, _, _), &at) in planned.iter().zip(&labels) {
            if let Some(id) = id {
                let style = number(&PLANNED_COLOR);
                chart.draw_series(std::iter::once(Text::new(format!("({id})"), at, style)))?;
            }
        }
        let mut entries = vec![
            ("initial stance".to_string(), Key::Sole(START_COLOR)),
            ("left sole, step number".to_string(), Key::Sole(LEFT_COLOR)),
            (
                "right sole, step number".to_string(),
                Key::Sole(RIGHT_COLOR),
            ),
        ];
        if !planned.is_empty() {
            entries.push((
                "(n): step n as first".to_string(),
                Key::DashedSole(PLANNED_COLOR),
            ));
            entries.push(("planned, before it moved".to_string(), Key::None));
        }
        entries.extend(
            series
                .iter()
                .map(|s| (s.label.clone(), Key::Line(s.color, s.width.max(2)))),
        );
        draw_legend(&legend, px, &entries)?;
        Ok(())
    })
}
