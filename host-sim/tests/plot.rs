//! Tests of `host_sim::plot`: the three PNGs of the paper's figures are written for the `fig4`
//! walk, are valid PNGs of a sensible size, and show the plotted series (their colours are
//! found in the decoded pixels).

use std::fs;
use std::path::{Path, PathBuf};

use host_sim::multibody::{evaluate, MbSample, Model};
use host_sim::plot::write_plots;
use host_sim::scenario::{self, Run};
use planner_core::gait::{Footstep, GaitParams};

const FILES: [&str; 3] = ["sagittal.png", "frontal.png", "footprints.png"];

/// The plotted colours (see `plot.rs`): COG, planned ZMP, multi-body ZMP.
const COG: [u8; 3] = [0x1f, 0x5f, 0xbf];
const ZMP: [u8; 3] = [0xd6, 0x27, 0x28];
const MB: [u8; 3] = [0x2c, 0xa0, 0x2c];

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("plot-tests")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    dir
}

fn fig4() -> (Run, Vec<Footstep<f64>>) {
    let s = scenario::built_in("fig4").unwrap();
    let run = scenario::run(&s, GaitParams::hrp2());
    let steps = run.footsteps.iter().map(|&(_, f)| f).collect();
    (run, steps)
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
fn pixels(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

fn count_colour(rgb: &[u8], c: [u8; 3]) -> usize {
    rgb.chunks_exact(3).filter(|p| *p == c).count()
}

fn non_white_fraction(rgb: &[u8]) -> f64 {
    let n = rgb
        .chunks_exact(3)
        .filter(|p| *p != [255, 255, 255])
        .count();
    n as f64 / (rgb.len() / 3) as f64
}

fn check_files(written: &[PathBuf], dir: &Path, with_mb: bool) {
    assert_eq!(written.len(), 3);
    for (path, name) in written.iter().zip(FILES) {
        assert_eq!(path, &dir.join(name));
        let bytes = fs::read(path).unwrap();
        let (w, h) = png_size(&bytes);
        let (dw, dh, rgb) = pixels(path);
        assert_eq!((w, h), (dw, dh));
        let ink = non_white_fraction(&rgb);
        let (cog, zmp, mb) = (
            count_colour(&rgb, COG),
            count_colour(&rgb, ZMP),
            count_colour(&rgb, MB),
        );
        println!(
            "{name}: {w} x {h} px, {} bytes, {:.1} % ink, COG {cog} px, ZMP {zmp} px, MB {mb} px",
            bytes.len(),
            100.0 * ink
        );
        assert!((600..=2400).contains(&w), "{name}: width {w}");
        assert!((400..=1400).contains(&h), "{name}: height {h}");
        assert!(bytes.len() > 20_000, "{name}: only {} bytes", bytes.len());
        assert!(
            (0.01..0.5).contains(&ink),
            "{name}: {ink} of the pixels drawn"
        );
        assert!(cog > 500, "{name}: COG line missing ({cog} px)");
        assert!(zmp > 500, "{name}: ZMP line missing ({zmp} px)");
        if with_mb {
            assert!(mb > 300, "{name}: multi-body ZMP line missing ({mb} px)");
        } else {
            assert_eq!(mb, 0, "{name}: multi-body colour without multi-body data");
        }
    }
}

#[test]
fn fig4_plots_are_valid_pngs() {
    let (run, steps) = fig4();
    let dir = out_dir("fig4");
    let written = write_plots(&dir, "fig4", &run.trajectory, 0.005, &steps, None).unwrap();
    check_files(&written, &dir, false);
    // Time plots have the fixed size; the footprint plot has equal axis scaling, so a walk
    // of about 1.6 m along x by 0.4 m across is much wider than tall.
    assert_eq!(png_size(&fs::read(&written[0]).unwrap()), (1200, 600));
    let (w, h) = png_size(&fs::read(&written[2]).unwrap());
    assert!(w > 2 * h, "footprints {w} x {h}");
}

#[test]
fn fig4_plots_with_multibody_zmp() {
    let (run, steps) = fig4();
    let mb: Vec<MbSample> = evaluate(&Model::hrp2(), &run.trajectory, 0.005).unwrap();
    let dir = out_dir("fig4-mb");
    let written = write_plots(&dir, "fig4", &run.trajectory, 0.005, &steps, Some(&mb)).unwrap();
    check_files(&written, &dir, true);
}

#[test]
fn lateral_turn_footprints_keep_equal_scaling() {
    // A quarter turn spans about 1 m in both x and y: the plot is roughly square.
    let s = scenario::built_in("turn").unwrap();
    let run = scenario::run(&s, GaitParams::hrp2());
    let steps: Vec<_> = run.footsteps.iter().map(|&(_, f)| f).collect();
    let dir = out_dir("turn");
    let written = write_plots(&dir, "turn", &run.trajectory, 0.005, &steps, None).unwrap();
    let (w, h) = png_size(&fs::read(&written[2]).unwrap());
    println!("turn footprints: {w} x {h} px");
    assert!((0.8..1.5).contains(&(w as f64 / h as f64)), "{w} x {h}");
}

#[test]
fn bad_inputs_are_refused() {
    let (run, steps) = fig4();
    let dir = out_dir("bad");
    let e = write_plots(&dir, "x", &[], 0.005, &steps, None).unwrap_err();
    assert!(e.to_string().contains("empty trajectory"), "{e}");
    for dt in [0.0, -0.005, f64::NAN, f64::INFINITY] {
        let e = write_plots(&dir, "x", &run.trajectory, dt, &steps, None).unwrap_err();
        assert!(e.to_string().contains("dt must be positive"), "{e}");
    }
    assert!(!dir.exists(), "nothing written on bad input");
}
