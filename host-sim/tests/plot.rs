//! Tests of `host_sim::output::plot`: the PNGs of the paper's figures for the `fig4` walk are valid
//! PNGs of a sensible size that show the plotted series (their colours are found in the
//! decoded pixels), anti-aliased; the support phases are shaded in proportion to their
//! durations; the modification is marked, and `modification.png` and the moved landings appear
//! only for a walk with a modification; the data behind the figures (step numbers, first
//! planned poses, the modification instant, sole limits, the ZMP fluctuation of the
//! comparison columns) is what the scenario says; a modification before the start is shown
//! as what it is (the walk planned with it from the start), its mark inside the plot area.

use std::fs;
use std::path::{Path, PathBuf};

use host_sim::eval::multibody::{evaluate, MbSample};
use host_sim::output::plot::{
    fluctuation, landings, modification_marks, sole_limits, walked_landings, write_plots, Mark,
    Walk, COMPARISON_FILE, FILES, PRE_START_TITLE, SOLE_LENGTH, SOLE_WIDTH,
};
use host_sim::robot::model::Model;
use host_sim::scenario::{self, Run, Scenario};
use planner_core::gait::{Footstep, GaitParams, Phase, Side};

/// The colours of `plot/time.rs` and `plot/top.rs`: COG, planned ZMP, multi-body ZMP, the
/// modification mark, the shades of single and double support, a first planned pose.
const COG: [u8; 3] = [0x1f, 0x5f, 0xbf];
const ZMP: [u8; 3] = [0xd6, 0x27, 0x28];
const MB: [u8; 3] = [0x2c, 0xa0, 0x2c];
const MARK: [u8; 3] = [0x7b, 0x2d, 0x8e];
const SINGLE: [u8; 3] = [0xe4, 0xec, 0xf7];
const DOUBLE: [u8; 3] = [0xfb, 0xed, 0xd2];
const PLANNED: [u8; 3] = [0xe0, 0x7b, 0x00];
const WHITE: [u8; 3] = [0xff; 3];
const DT: f64 = 0.005;

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("plot-tests")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    dir
}

fn play(name: &str) -> (Scenario, Run) {
    let s = scenario::built_in(name).unwrap();
    let run = scenario::run(&s, GaitParams::hrp2());
    (s, run)
}

fn walk<'a>(name: &'a str, s: &Scenario, run: &'a Run, mb: Option<&'a [MbSample]>) -> Walk<'a> {
    Walk::from_run(name, s, run, DT, GaitParams::hrp2(), mb).unwrap()
}

/// Width and height from the IHDR chunk, after checking the signature and the chunk layout.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(
        bytes.len() > 33,
        "too short for a PNG: {} bytes",
        bytes.len()
    );
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[8..12], &13u32.to_be_bytes(), "IHDR length");
    assert_eq!(&bytes[12..16], b"IHDR", "first chunk is IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert_eq!(bytes[24], 8, "bit depth");
    assert_eq!(bytes[25], 2, "colour type RGB");
    assert_eq!(
        &bytes[bytes.len() - 8..bytes.len() - 4],
        b"IEND",
        "last chunk is IEND"
    );
    (w, h)
}

/// Decoded RGB pixels (with the png crate).
fn pixels(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    let px = buf.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    (info.width, info.height, px)
}

fn count(rgb: &[[u8; 3]], c: [u8; 3]) -> usize {
    rgb.iter().filter(|p| **p == c).count()
}

/// Pixels that are `a·c + (1 − a)·bg` for one of the backgrounds, `a` within `alpha`, each
/// channel within 2 of it: the edge pixels of an anti-aliased line of colour `c`.
fn blends(rgb: &[[u8; 3]], c: [u8; 3], alpha: (f64, f64)) -> usize {
    let backgrounds = [WHITE, SINGLE, DOUBLE];
    rgb.iter()
        .filter(|p| {
            backgrounds.iter().any(|bg| {
                // The channel with the largest contrast gives a; the others must agree.
                let k = (0..3)
                    .max_by_key(|&k| (i32::from(c[k]) - i32::from(bg[k])).abs())
                    .unwrap();
                let d = f64::from(c[k]) - f64::from(bg[k]);
                if d.abs() < 60.0 {
                    return false;
                }
                let a = (f64::from(p[k]) - f64::from(bg[k])) / d;
                a > alpha.0
                    && a < alpha.1
                    && (0..3).all(|j| {
                        let want = a * f64::from(c[j]) + (1.0 - a) * f64::from(bg[j]);
                        (f64::from(p[j]) - want).abs() <= 2.0
                    })
            })
        })
        .count()
}

fn check_files(written: &[PathBuf], dir: &Path, with_mb: bool, comparison: bool) {
    let mut names: Vec<&str> = FILES.to_vec();
    if comparison {
        names.push(COMPARISON_FILE);
    }
    assert_eq!(written.len(), names.len());
    for (path, name) in written.iter().zip(names) {
        assert_eq!(path, &dir.join(name));
        let bytes = fs::read(path).unwrap();
        let (w, h) = png_size(&bytes);
        let (dw, dh, rgb) = pixels(path);
        assert_eq!((w, h), (dw, dh));
        let white = count(&rgb, WHITE) as f64 / rgb.len() as f64;
        let (cog, zmp, mb) = (count(&rgb, COG), count(&rgb, ZMP), count(&rgb, MB));
        println!(
            "{name}: {w} x {h} px, {} bytes, {:.1} % white, COG {cog} px, ZMP {zmp} px, MB {mb} px",
            bytes.len(),
            100.0 * white
        );
        assert!((600..=2400).contains(&w), "{name}: width {w}");
        assert!((400..=1400).contains(&h), "{name}: height {h}");
        assert!(bytes.len() > 20_000, "{name}: only {} bytes", bytes.len());
        assert!(
            (0.1..0.99).contains(&white),
            "{name}: {white} of the pixels white"
        );
        assert!(cog > 300, "{name}: COG line missing ({cog} px)");
        assert!(zmp > 300, "{name}: ZMP line missing ({zmp} px)");
        // The comparison figure has no multi-body line.
        if with_mb && name != COMPARISON_FILE {
            assert!(mb > 100, "{name}: multi-body ZMP line missing ({mb} px)");
        } else {
            assert_eq!(mb, 0, "{name}: multi-body colour without multi-body data");
        }
    }
}

#[test]
fn fig4_figures_are_valid_pngs() {
    let (s, run) = play("fig4");
    let dir = out_dir("fig4");
    let written = write_plots(&dir, &walk("fig4", &s, &run, None)).unwrap();
    check_files(&written, &dir, false, true);
    // Plane figures have a fixed size; the footprint plot has equal axis scaling, so a walk
    // of about 1.6 m along x by 0.5 m across is much wider than tall; the comparison has
    // three columns.
    assert_eq!(png_size(&fs::read(&written[0]).unwrap()), (1200, 880));
    let (w, h) = png_size(&fs::read(&written[2]).unwrap());
    assert!(w > 2 * h, "footprints {w} x {h}");
    let (w, _) = png_size(&fs::read(&written[3]).unwrap());
    assert!(w > 1600, "comparison width {w}");
}

#[test]
fn fig4_figures_with_multibody_zmp() {
    let (s, run) = play("fig4");
    let mb: Vec<MbSample> = evaluate(&Model::hrp2(), &run.trajectory, DT).unwrap();
    let dir = out_dir("fig4-mb");
    let written = write_plots(&dir, &walk("fig4", &s, &run, Some(&mb))).unwrap();
    check_files(&written, &dir, true, true);
}

#[test]
fn lines_are_anti_aliased() {
    let (s, run) = play("fig4");
    let dir = out_dir("aa");
    let written = write_plots(&dir, &walk("fig4", &s, &run, None)).unwrap();
    for path in &written {
        let (_, _, rgb) = pixels(path);
        let (cog, zmp) = (count(&rgb, COG), count(&rgb, ZMP));
        // Partly covered pixels at the edges of the lines: without anti-aliasing a line is
        // drawn in its exact colour only.
        let (cog_edge, zmp_edge) = (
            blends(&rgb, COG, (0.15, 0.85)),
            blends(&rgb, ZMP, (0.15, 0.85)),
        );
        println!(
            "{}: COG {cog} px + {cog_edge} edge px, ZMP {zmp} px + {zmp_edge} edge px",
            path.display()
        );
        assert!(
            cog_edge > cog / 4,
            "{}: COG edges {cog_edge}",
            path.display()
        );
        assert!(
            zmp_edge > zmp / 4,
            "{}: ZMP edges {zmp_edge}",
            path.display()
        );
    }
}

#[test]
fn support_phases_are_shaded_in_proportion() {
    let (s, run) = play("fig4");
    let dir = out_dir("shade");
    let written = write_plots(&dir, &walk("fig4", &s, &run, None)).unwrap();
    let ticks = |f: fn(Phase) -> bool| run.trajectory.iter().filter(|r| f(r.phase)).count();
    let single = ticks(|p| matches!(p, Phase::Single(_)));
    let double = ticks(|p| p == Phase::Double);
    let t_ratio = single as f64 / double as f64;
    for path in &written[..2] {
        let (_, _, rgb) = pixels(path);
        let (a, b) = (count(&rgb, SINGLE), count(&rgb, DOUBLE));
        let px_ratio = a as f64 / b as f64;
        println!(
            "{}: single {a} px, double {b} px, ratio {px_ratio:.2} (time {t_ratio:.2})",
            path.display()
        );
        assert!(a > 100_000 && b > 20_000, "{}", path.display());
        // Both shades fill the same panel heights (less the lines over them, and the legend).
        assert!(
            (0.8..1.25).contains(&(px_ratio / t_ratio)),
            "{}: shade ratio {px_ratio} vs time ratio {t_ratio}",
            path.display()
        );
    }
}

#[test]
fn only_a_modified_walk_has_the_mark_the_comparison_and_moved_landings() {
    for (name, modified) in [("fig4", true), ("straight", false)] {
        let (s, run) = play(name);
        let dir = out_dir(&format!("mark-{name}"));
        let w = walk(name, &s, &run, None);
        assert_eq!(w.columns.len(), if modified { 2 } else { 0 }, "{name}");
        let written = write_plots(&dir, &w).unwrap();
        assert_eq!(dir.join(COMPARISON_FILE).exists(), modified, "{name}");
        assert_eq!(written.len(), 3 + usize::from(modified), "{name}");
        for path in &written[..2] {
            let (_, _, rgb) = pixels(path);
            let m = count(&rgb, MARK);
            println!("{}: mark {m} px", path.display());
            assert_eq!(m > 200, modified, "{}: {m} mark pixels", path.display());
        }
        let (_, _, rgb) = pixels(&written[2]);
        let p = count(&rgb, PLANNED);
        println!("{}: planned outlines {p} px", written[2].display());
        assert_eq!(p > 200, modified, "{name}: {p} px of first planned poses");
    }
}

#[test]
fn fig4_landings_have_step_numbers_and_first_planned_poses() {
    let (_, run) = play("fig4");
    let l = landings(&run);
    let ids: Vec<u16> = l
        .iter()
        .map(|l| l.id.expect("every landing has an id"))
        .collect();
    assert_eq!(ids, (0..=11).collect::<Vec<_>>());
    for l in &l {
        let id = l.id.unwrap();
        let (_, queued) = run.footsteps.iter().find(|(i, _)| *i == id).unwrap();
        assert!((l.foot.x - queued.x).abs() < 1e-9, "step {id}");
        match l.planned {
            // Steps 0 to 2 were not modified; from step 3 on, each moved 0.2 m ahead.
            None => assert!(id < 3, "step {id} has no planned pose"),
            Some(p) => {
                assert!(id >= 3, "step {id}");
                assert!((l.foot.x - p.x - 0.2).abs() < 1e-9, "step {id}: {p:?}");
                assert_eq!((p.side, p.y), (l.foot.side, l.foot.y));
            }
        }
    }
    // The initial stance is not a landing.
    let walked = walked_landings(&run.trajectory);
    assert_eq!(walked.len(), 12);
    assert_eq!(walked[0].side, Side::Right);
}

#[test]
fn fig4_modification_is_marked_at_its_effect() {
    let (_, run) = play("fig4");
    let marks = modification_marks(&run, DT);
    assert_eq!(marks.len(), 1, "{marks:?}");
    // Sent in the tick before the single support at 4.0 s, in effect from that tick on.
    let sent = run
        .events
        .iter()
        .find(|e| matches!(e.command, scenario::Command::Modify(..)))
        .unwrap()
        .tick;
    assert!((marks[0].t - (sent + 1) as f64 * DT).abs() < 1e-12);
    assert!((marks[0].t - 4.0).abs() < 1e-9, "{}", marks[0].t);
    let adj = run.adjustments[0].adjust_s;
    assert!(adj > 0.2, "ΔT {adj}");
    let label = &marks[0].label;
    assert!(label.contains("steps 3–11"), "{label}");
    assert!(label.contains(&format!("ΔT {adj:+.3} s")), "{label}");
    let (_, straight) = play("straight");
    assert!(modification_marks(&straight, DT).is_empty());
}

#[test]
fn sole_limits_hold_the_planned_zmp() {
    for name in ["fig4", "turn", "lateral"] {
        let (_, run) = play(name);
        for (k, r) in run.trajectory.iter().enumerate() {
            for (plane, zmp) in [(0, r.x.zmp), (1, r.y.zmp)] {
                let (lo, hi) = sole_limits(r, plane, [SOLE_LENGTH, SOLE_WIDTH]);
                assert!(lo < hi, "{name} row {k}");
                assert!(
                    (lo - 1e-9..=hi + 1e-9).contains(&zmp),
                    "{name} row {k} plane {plane}: ZMP {zmp} outside {lo} … {hi}"
                );
                if name == "fig4" && plane == 0 && matches!(r.phase, Phase::Single(_)) {
                    assert!((hi - lo - SOLE_LENGTH).abs() < 1e-12, "{name} row {k}");
                }
            }
        }
    }
}

#[test]
fn fig4_comparison_shows_what_the_time_adjustment_does() {
    // The paper's Fig. 4: without the adjustment the ZMP leaves the sole centre by about
    // 26 mm in the single support after the modification; with it, by about 1 mm.
    let (s, run) = play("fig4");
    let w = walk("fig4", &s, &run, None);
    assert_eq!(w.plane, 0);
    let peak = |tr: &[planner_core::gait::Reference<f64>]| {
        tr.iter()
            .filter_map(|r| fluctuation(r, 0))
            .fold(0.0_f64, |m, v| m.max(v.abs()))
    };
    let (first, bare, walked) = (
        peak(&w.columns[0].trajectory),
        peak(&w.columns[1].trajectory),
        peak(&run.trajectory),
    );
    println!("largest sagittal fluctuation: first plan {first}, without adjustment {bare}, walked {walked}");
    assert!(bare > 0.015, "{bare}");
    assert!(walked < 0.002 && first < 0.002, "{walked} {first}");
    // The first plan lands step 3 at 0.4 m, the walk at 0.6 m.
    let left_x = |tr| {
        walked_landings(tr)
            .iter()
            .filter(|f| f.side == Side::Left)
            .map(|f| f.x)
            .collect::<Vec<_>>()
    };
    assert!((left_x(&w.columns[0].trajectory)[1] - 0.4).abs() < 1e-9);
    assert!((left_x(&run.trajectory)[1] - 0.6).abs() < 1e-9);
}

#[test]
fn turn_footprints_keep_equal_scaling() {
    // A quarter turn spans about 1 m in both x and y: the plot is roughly square.
    let (s, run) = play("turn");
    let dir = out_dir("turn");
    let written = write_plots(&dir, &walk("turn", &s, &run, None)).unwrap();
    let (w, h) = png_size(&fs::read(&written[2]).unwrap());
    println!("turn footprints: {w} x {h} px");
    assert!((0.8..1.5).contains(&(w as f64 / h as f64)), "{w} x {h}");
}

#[test]
fn bad_inputs_are_refused() {
    let (_, run) = play("fig4");
    let dir = out_dir("bad");
    let e = write_plots(&dir, &Walk::new("x", &[], DT)).unwrap_err();
    assert!(e.to_string().contains("empty trajectory"), "{e}");
    for dt in [0.0, -0.005, f64::NAN, f64::INFINITY] {
        let e = write_plots(&dir, &Walk::new("x", &run.trajectory, dt)).unwrap_err();
        assert!(e.to_string().contains("dt must be positive"), "{e}");
    }
    let mut w = Walk::new("x", &run.trajectory, DT);
    w.plane = 2;
    let e = write_plots(&dir, &w).unwrap_err();
    assert!(e.to_string().contains("plane 2"), "{e}");
    assert!(!dir.exists(), "nothing written on bad input");
}

#[test]
fn the_figures_use_the_robots_sole() {
    // The second robot of host-sim/tests/robots (0.16 × 0.09 m soles): the walk, its sole
    // limits and the footprints follow its file, not HRP-2's constants.
    let robots = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    let robot = host_sim::robot::Robot::load(&robots.join("small.toml")).unwrap();
    let p = robot.planner.params;
    let file = host_sim::scenario::file::load_file(&robots.join("small-walk.toml")).unwrap();
    let s = &file.scenario;
    let run = scenario::run(s, p);
    let w = Walk::from_run("small", s, &run, p.dt, p, None).unwrap();
    assert_eq!(w.sole, [2.0 * p.sole_half_length, 2.0 * p.sole_half_width]);
    assert!((w.sole[0] - 0.16).abs() < 1e-12 && (w.sole[1] - 0.09).abs() < 1e-12);
    let hrp2 = walk("fig4", &play("fig4").0, &play("fig4").1, None).sole;
    assert_eq!(hrp2, [SOLE_LENGTH, SOLE_WIDTH]);
    for (k, r) in run.trajectory.iter().enumerate() {
        if matches!(r.phase, Phase::Single(_)) {
            let (lo, hi) = sole_limits(r, 0, w.sole);
            assert!((hi - lo - 0.16).abs() < 1e-9, "row {k}: {lo} … {hi}");
            assert!((lo - 1e-9..=hi + 1e-9).contains(&r.x.zmp), "row {k}");
        }
    }
    let dir = out_dir("small");
    let written = write_plots(&dir, &w).unwrap();
    assert_eq!(written.len(), 3);
    let mut bad = w.clone();
    bad.sole = [0.16, 0.0];
    let e = write_plots(&out_dir("small-bad"), &bad).unwrap_err();
    assert!(e.to_string().contains("sole size"), "{e}");
}

/// Five 0.1 m steps and a closing step, right foot first; at t = 0, while the robot stands,
/// steps 3 and 4 move from 0.4 m to 0.45 m; the walk starts at 0.8 s.
const PRE_START: &str = r#"
name = "pre-start"
max_time_s = 20.0

[[step]]
id = 0
side = "right"
x = 0.1
y = -0.1

[[step]]
id = 1
side = "left"
x = 0.2
y = 0.1

[[step]]
id = 2
side = "right"
x = 0.3
y = -0.1

[[step]]
id = 3
side = "left"
x = 0.4
y = 0.1

[[step]]
id = 4
side = "right"
x = 0.4
y = -0.1

[[modify]]
at_s = 0.0
id = 3
x = 0.45
y = 0.1

[[modify]]
at_s = 0.0
id = 4
x = 0.45
y = -0.1

[[command]]
at_s = 0.8
kind = "start"

[[command]]
at_s = 0.8
kind = "stop"
"#;

/// Every mark lies inside `t`, at least 2 % of its span right of its start (the y axis).
fn marks_inside(marks: &[Mark], t: &std::ops::Range<f64>, what: &str) {
    for m in marks {
        let inset = (m.t - t.start) / (t.end - t.start);
        assert!(
            m.t < t.end && inset >= 0.02,
            "{what}: mark at {} s on or next to the axis of {t:?} ({inset})",
            m.t
        );
    }
}

#[test]
fn a_modification_before_the_start_is_shown_as_planned_from_the_start() {
    let s = scenario::file::parse(PRE_START).unwrap();
    let run = scenario::run(&s, GaitParams::hrp2());
    let accepted = |c: fn(&scenario::Command) -> bool| {
        run.events
            .iter()
            .filter(|e| c(&e.command) && e.result.is_ok())
            .count()
    };
    assert_eq!(
        accepted(|c| matches!(c, scenario::Command::Modify(..))),
        2,
        "{:?}",
        run.events
    );
    assert_eq!(accepted(|c| matches!(c, scenario::Command::Start)), 1);
    // The walk lands the steps where they were moved.
    let xs: Vec<f64> = walked_landings(&run.trajectory)
        .iter()
        .map(|f| f.x)
        .collect();
    assert_eq!(xs.len(), 5, "{xs:?}");
    assert!((xs[3] - 0.45).abs() < 1e-9 && (xs[4] - 0.45).abs() < 1e-9);

    let w = walk("pre-start", &s, &run, None);
    assert_eq!(w.marks.len(), 1, "{:?}", w.marks);
    let mark = &w.marks[0];
    assert!(mark.before_start, "{mark:?}");
    assert!(
        mark.label.contains("before the start (0.800 s)") && mark.label.contains("steps 3–4"),
        "{}",
        mark.label
    );
    // Nothing was walked without the modification: no comparison columns (the plan without
    // it was never begun, and "without the time adjustment" is the walk itself).
    assert!(
        w.columns.is_empty(),
        "comparison columns of a modification before the start: {:?}",
        w.columns.iter().map(|c| &c.title).collect::<Vec<_>>()
    );
    assert_eq!(w.title, PRE_START_TITLE);

    // modification.png: the walk alone, saying the modification preceded the start, the mark
    // inside both panels' time axes (not on the y axis).
    let c = w.comparison().expect("modification.png is drawn");
    assert_eq!(c.columns.len(), 1);
    assert_eq!(c.columns[0].title, PRE_START_TITLE);
    assert_eq!(c.columns[0].trajectory.len(), run.trajectory.len());
    assert_eq!(c.columns[0].marks, &w.marks[..]);
    assert!(c.caption.contains("before the start"), "{}", c.caption);
    marks_inside(c.columns[0].marks, &c.t, "modification.png");
    marks_inside(c.columns[0].marks, &c.zoom_t, "modification.png zoom");
    let t_end = (run.trajectory.len() - 1) as f64 * DT;
    assert!((c.t.end - t_end).abs() < 1e-12, "{:?}", c.t);
    assert!((c.zoom_t.end - t_end).abs() < 1e-12, "{:?}", c.zoom_t);
    marks_inside(&w.marks, &w.time_axis(), "sagittal.png");

    // Drawn: the mark's colour is in all three time figures.
    let dir = out_dir("pre-start");
    let written = write_plots(&dir, &w).unwrap();
    check_files(&written, &dir, false, true);
    for path in [&written[0], &written[1], &written[3]] {
        let (_, _, rgb) = pixels(path);
        let m = count(&rgb, MARK);
        println!("{}: mark {m} px", path.display());
        assert!(m > 200, "{}: {m} mark pixels", path.display());
    }
}

#[test]
fn a_modification_before_the_start_stays_in_the_first_plan_of_a_later_one() {
    // fig4, with step 1 also moved (0.2 m -> 0.25 m) at t = 0, before the start.
    let (mut s, _) = play("fig4");
    let at = s.timeline.iter().position(|(t, _)| *t > 0).unwrap();
    let moved = Footstep::new(Side::Left, 0.25, 0.1, 0.0);
    s.timeline
        .insert(at, (0, scenario::Command::Modify(1, moved)));
    let run = scenario::run(&s, GaitParams::hrp2());
    let w = walk("fig4-pre", &s, &run, None);
    let before: Vec<bool> = w.marks.iter().map(|m| m.before_start).collect();
    assert_eq!(before, [true, false], "{:?}", w.marks);
    // The comparison is about the modification during the walk: (a) is the walk as planned
    // at the start, with step 1 moved.
    assert_eq!(w.columns.len(), 2);
    assert!(
        w.columns[0].title.contains("as planned at the start"),
        "{}",
        w.columns[0].title
    );
    for tr in [&w.columns[0].trajectory, &run.trajectory] {
        let step1 = walked_landings(tr)[1];
        assert!((step1.x - 0.25).abs() < 1e-9, "{step1:?}");
    }
    let step3 = |tr| walked_landings(tr)[3].x;
    assert!((step3(&w.columns[0].trajectory) - 0.4).abs() < 1e-9);
    assert!((step3(&run.trajectory) - 0.6).abs() < 1e-9);
    let c = w.comparison().unwrap();
    assert_eq!(c.columns.len(), 3);
    marks_inside(&w.marks, &c.t, "modification.png");
    // The zoom is around the modification during the walk.
    assert!(
        c.zoom_t.contains(&4.0) && c.zoom_t.start > 2.0,
        "{:?}",
        c.zoom_t
    );
}

#[test]
fn a_modification_during_the_walk_keeps_its_comparison() {
    let (s, run) = play("fig4");
    let w = walk("fig4", &s, &run, None);
    assert!(w.marks.iter().all(|m| !m.before_start));
    let c = w.comparison().unwrap();
    let titles: Vec<&str> = c.columns.iter().map(|c| c.title).collect();
    assert_eq!(
        titles,
        [
            "(a) as first planned: no modification",
            "(b) modified, without the time adjustment",
            "(c) modified, with the time adjustment: as walked",
        ]
    );
    // The first plan shows no mark; the axes begin at 0; the zoom is 1 s before to 2.5 s
    // after the modification.
    assert!(c.columns[0].marks.is_empty());
    assert_eq!(c.columns[2].marks, &w.marks[..]);
    assert_eq!(c.t.start, 0.0);
    assert_eq!(w.time_axis().start, 0.0);
    assert!((c.zoom_t.start - 3.0).abs() < 1e-9 && (c.zoom_t.end - 6.5).abs() < 1e-9);
    assert_eq!(
        c.caption,
        format!("fig4, sagittal plane: {}", w.marks[0].label)
    );
    let (s, run) = play("straight");
    assert!(walk("straight", &s, &run, None).comparison().is_none());
}
