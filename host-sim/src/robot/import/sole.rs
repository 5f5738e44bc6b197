//! The sole of an imported foot, from its collision geometry.
//!
//! Every collision shape of the foot's links (their visual shapes if they have none) is turned
//! into points in the ankle frame: a box's eight corners, a sphere's lowest point, a
//! cylinder's two end circles (32 points each), a capsule's two end spheres' lowest points
//! and end circles, a mesh's vertices (STL, COLLADA `.dae` placed by its node transforms
//! ([`super::collada`]) and OBJ; then the URDF's mesh `scale`). The **sole plane** is the
//! lowest point's height `z_s`; the **contact points** those within [`CONTACT_BAND_M`] of it.
//!
//! The geometry is checked against the leg: its lowest point must lie below the ankle and at
//! most [`MAX_SOLE_DEPTH`] leg lengths below it, its contact points span at most one leg
//! length; otherwise the import is refused naming the shape (the mesh or primitive, its link
//! and its placement) that puts the sole there.
//!
//! The sole centre is a frame of the foot where the URDF gives one that fits the geometry: a
//! massless link without geometry fixed to the foot (or the `--sole` link) lying on the sole
//! plane (within [`CONTACT_BAND_M`]), inside the contact points' bounds, whose centred
//! rectangle spans at least [`SOLE_COVER`] of those bounds along and across (one named
//! `…sole…` first, then the one nearest the bounds' middle). Otherwise the centre is the
//! middle of the bounds; a `--sole` link or a frame named `…sole…` that does not fit is
//! named in a warning with its placement. The sole rectangle is the largest one centred
//! there inside the bounds.

use std::fs::File;
use std::io::BufReader;

use urdf_rs::Geometry;

use super::{err, pose_of, resolve, ImportError, Tree};
use crate::robot::model::{mul_mv, transpose, Mat3, Pose, Vec3};

/// Points this close above the lowest one are the sole's \[m\].
pub const CONTACT_BAND_M: f64 = 0.005;
/// A sole frame is the sole centre only if the rectangle centred on it spans at least this
/// fraction of the contact points' bounds, along and across.
pub const SOLE_COVER: f64 = 0.7;
/// The foot's lowest point at most this many leg lengths (hip to ankle) below the ankle.
pub const MAX_SOLE_DEPTH: f64 = 0.5;

/// A foot's sole in its ankle frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Sole {
    /// The sole centre \[m\].
    pub centre: Vec3,
    /// The sole's orientation: level with the base at zero joint angles.
    pub rotation: Mat3,
    /// Length (along x) and width (along y) \[m\].
    pub size: [f64; 2],
    /// Where the centre comes from: the frame's link, or the geometry.
    pub from: String,
    /// What the import warns about this sole.
    pub warnings: Vec<String>,
}

/// A frame the sole may be centred on: its link, its pose in the ankle frame, and whether
/// the user named it (`--sole`).
pub(crate) struct Frame {
    pub(crate) link: String,
    pub(crate) pose: Pose,
    pub(crate) named: bool,
}

fn circle(pose: &Pose, radius: f64, z: f64, out: &mut Vec<Vec3>) {
    for k in 0..32 {
        let a = f64::from(k) * std::f64::consts::TAU / 32.0;
        out.push(pose.apply([radius * a.cos(), radius * a.sin(), z]));
    }
}

/// The points of one shape placed at `pose`; `down`: the floor's downward unit vector in the
/// frame `pose` places the shape in (a sphere's, a capsule's end's lowest point lies along it,
/// whatever the frame's tilt).
pub(crate) fn points(
    t: &Tree,
    g: &Geometry,
    pose: &Pose,
    down: Vec3,
    out: &mut Vec<Vec3>,
) -> Result<(), ImportError> {
    let lowest = |c: Vec3, r: f64| [c[0] + r * down[0], c[1] + r * down[1], c[2] + r * down[2]];
    match g {
        Geometry::Box { size } => {
            for k in 0..8 {
                let c = |i: usize| if k >> i & 1 == 1 { 0.5 } else { -0.5 } * size.0[i];
                out.push(pose.apply([c(0), c(1), c(2)]));
            }
        }
        Geometry::Sphere { radius } => out.push(lowest(pose.apply([0.0; 3]), *radius)),
        Geometry::Cylinder { radius, length } => {
            circle(pose, *radius, 0.5 * length, out);
            circle(pose, *radius, -0.5 * length, out);
        }
        Geometry::Capsule { radius, length } => {
            for z in [0.5 * length, -0.5 * length] {
                out.push(lowest(pose.apply([0.0, 0.0, z]), *radius));
                circle(pose, *radius, z, out);
            }
        }
        Geometry::Mesh { filename, scale } => {
            let path = resolve(filename, &t.dir)?;
            let ext = path
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            let named = |e: String| ImportError(format!("<mesh filename=\"{filename}\">: {e}"));
            let vertices: Vec<Vec3> = match ext.as_str() {
                "stl" => {
                    let mut f =
                        BufReader::new(File::open(&path).map_err(|e| named(e.to_string()))?);
                    let mesh = stl_io::read_stl(&mut f).map_err(|e| named(e.to_string()))?;
                    mesh.vertices.iter().map(|v| v.0.map(f64::from)).collect()
                }
                "dae" | "obj" => {
                    let text = std::fs::read_to_string(&path).map_err(|e| named(e.to_string()))?;
                    let v = if ext == "dae" {
                        super::collada::vertices(&text).map_err(named)?
                    } else {
                        obj(&text)
                    };
                    if v.is_empty() {
                        return Err(named("no vertex positions found".into()));
                    }
                    v
                }
                _ => {
                    return err(format!(
                        "<mesh filename=\"{filename}\">: the soles are read from STL, COLLADA \
                         (.dae) and OBJ meshes only"
                    ))
                }
            };
            let s = scale.map_or([1.0; 3], |s| s.0);
            for v in vertices {
                out.push(pose.apply([v[0] * s[0], v[1] * s[1], v[2] * s[2]]));
            }
        }
    }
    Ok(())
}

/// The vertex positions of an OBJ file (its `v x y z` lines).
fn obj(text: &str) -> Vec<Vec3> {
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .filter_map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            (v.len() >= 3).then(|| [v[0], v[1], v[2]])
        })
        .collect()
}

/// A shape as the URDF writes it, for messages.
fn shape_name(g: &Geometry) -> String {
    match g {
        Geometry::Box { size } => format!("<box size=\"{:?}\">", size.0),
        Geometry::Sphere { radius } => format!("<sphere radius=\"{radius}\">"),
        Geometry::Cylinder { radius, length } => {
            format!("<cylinder radius=\"{radius}\" length=\"{length}\">")
        }
        Geometry::Capsule { radius, length } => {
            format!("<capsule radius=\"{radius}\" length=\"{length}\">")
        }
        Geometry::Mesh { filename, scale } => match scale {
            Some(s) => format!("<mesh filename=\"{filename}\" scale=\"{:?}\">", s.0),
            None => format!("<mesh filename=\"{filename}\">"),
        },
    }
}

fn xyz(v: Vec3) -> String {
    format!("({:.4}, {:.4}, {:.4})", v[0], v[1], v[2])
}

/// Points, each with the index of its shape, and the shapes' descriptions.
pub(crate) type FootPoints = (Vec<(Vec3, usize)>, Vec<String>);

/// The points of a foot's shapes (its collision shapes, or its visual ones if it has none)
/// in the ankle frame, each with the index of its shape in the descriptions returned; `down`
/// as for [`points`], in the ankle frame.
pub(crate) fn foot_points(
    t: &Tree,
    links: &[(String, Pose)],
    down: Vec3,
) -> Result<FootPoints, ImportError> {
    let mut pts = Vec::new();
    let mut shapes = Vec::new();
    for kind in ["collision", "visual"] {
        for (name, pose) in links {
            let l = t.link(name);
            let list: Vec<(&urdf_rs::Pose, &Geometry)> = if kind == "collision" {
                l.collision
                    .iter()
                    .map(|c| (&c.origin, &c.geometry))
                    .collect()
            } else {
                l.visual.iter().map(|v| (&v.origin, &v.geometry)).collect()
            };
            for (origin, g) in list {
                let at = pose.then(&pose_of(origin));
                let mut v = Vec::new();
                points(t, g, &at, down, &mut v)?;
                pts.extend(v.into_iter().map(|p| (p, shapes.len())));
                shapes.push(format!(
                    "the <{kind}> {} of <link name=\"{name}\"> (origin xyz=\"{}\" rpy=\"{}\", \
                     placed at {} in the ankle frame)",
                    shape_name(g),
                    xyz(origin.xyz.0),
                    xyz(origin.rpy.0),
                    xyz(at.p),
                ));
            }
        }
        if !pts.is_empty() {
            break;
        }
    }
    Ok((pts, shapes))
}

/// The sole of a foot made of `links` (each with its pose in the ankle frame, the first the
/// ankle link), centred on one of `frames` if one fits (see the module docs); `level`: the
/// ankle frame's orientation in the base frame at zero joint angles (the sole is level with
/// the base there, whatever the ankle frame's axes: the points are taken in base-aligned
/// axes); `leg`: the leg's length, hip to ankle \[m\].
pub(crate) fn sole(
    t: &Tree,
    links: &[(String, Pose)],
    frames: &[Frame],
    level: &Mat3,
    leg: f64,
) -> Result<Sole, ImportError> {
    let down = mul_mv(&transpose(level), [0.0, 0.0, -1.0]);
    let (pts, shapes) = foot_points(t, links, down)?;
    let names = links
        .iter()
        .map(|(n, _)| format!("<link name=\"{n}\">"))
        .collect::<Vec<_>>()
        .join(", ");
    if pts.is_empty() {
        return err(format!(
            "the foot ({names}) has no <collision> or <visual> geometry: its sole cannot be found"
        ));
    }
    let pts: Vec<(Vec3, usize)> = pts.iter().map(|(p, s)| (mul_mv(level, *p), *s)).collect();
    let (lowest, _) = pts
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .0[2].total_cmp(&b.1 .0[2]))
        .map_or((0, 0.0), |(i, p)| (i, p.0[2]));
    let zs = pts[lowest].0[2];
    let contact: Vec<&(Vec3, usize)> = pts
        .iter()
        .filter(|p| p.0[2] <= zs + CONTACT_BAND_M)
        .collect();
    let lo = |i: usize| contact.iter().map(|p| p.0[i]).fold(f64::INFINITY, f64::min);
    let hi = |i: usize| {
        contact
            .iter()
            .map(|p| p.0[i])
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let (x0, x1, y0, y1) = (lo(0), hi(0), lo(1), hi(1));
    let ankle = &links[0].0;
    // The geometry against the leg.
    let at_lowest = &shapes[pts[lowest].1];
    if zs >= 0.0 || -zs > MAX_SOLE_DEPTH * leg {
        return err(format!(
            "the foot's lowest point lies {:.4} m {} the ankle <link name=\"{ankle}\"> (legs \
             {leg:.4} m, hip to ankle; a sole lies below the ankle, at most {MAX_SOLE_DEPTH} \
             legs): it is a point of {at_lowest}: are the mesh's units, its COLLADA node \
             transforms or its scale wrong?",
            zs.abs(),
            if zs >= 0.0 { "above" } else { "below" }
        ));
    }
    for (i, a, b) in [(0, x0, x1), (1, y0, y1)] {
        if b - a > leg {
            let far = contact
                .iter()
                .max_by(|p, q| {
                    (p.0[i] - 0.5 * (a + b))
                        .abs()
                        .total_cmp(&(q.0[i] - 0.5 * (a + b)).abs())
                })
                .map_or(at_lowest, |p| &shapes[p.1]);
            return err(format!(
                "the foot's sole spans {:.4} m {} (legs {leg:.4} m, hip to ankle): its far end \
                 is a point of {far}: are the mesh's units, its COLLADA node transforms or its \
                 scale wrong?",
                b - a,
                if i == 0 { "along" } else { "across" }
            ));
        }
    }
    // The centre: a frame that fits, or the middle.
    let half = |c: f64, a: f64, b: f64| (c - a).min(b - c);
    let fit = |c: Vec3| -> Result<(), String> {
        if (c[2] - zs).abs() > CONTACT_BAND_M {
            return Err(format!(
                "lies {:.4} m {} the foot's lowest point ({at_lowest})",
                (c[2] - zs).abs(),
                if c[2] > zs { "above" } else { "below" }
            ));
        }
        let cover = [
            2.0 * half(c[0], x0, x1) / (x1 - x0),
            2.0 * half(c[1], y0, y1) / (y1 - y0),
        ];
        if cover.iter().any(|v| v.is_nan() || *v < SOLE_COVER) {
            return Err(format!(
                "is off the middle of the foot's contact area ({:.4} × {:.4} m): a sole centred \
                 on it spans {:.0} % of it along and {:.0} % across (at least {:.0} % wanted)",
                x1 - x0,
                y1 - y0,
                100.0 * cover[0].max(0.0),
                100.0 * cover[1].max(0.0),
                100.0 * SOLE_COVER
            ));
        }
        Ok(())
    };
    let middle = [0.5 * (x0 + x1), 0.5 * (y0 + y1)];
    let mut fits: Vec<(&Frame, Vec3)> = Vec::new();
    let mut warnings = Vec::new();
    for f in frames {
        let c = mul_mv(level, f.pose.p);
        match fit(c) {
            Ok(()) => fits.push((f, c)),
            Err(why) if f.named || f.link.to_lowercase().contains("sole") => {
                warnings.push(format!(
                    "the sole frame <link name=\"{}\"> (at {} in the frame of the ankle \
                     <link name=\"{ankle}\">) {why}: the sole is centred on the foot's \
                     geometry instead",
                    f.link,
                    xyz(f.pose.p)
                ));
            }
            Err(_) => {}
        }
    }
    fits.sort_by(|a, b| {
        let named = |f: &Frame| !(f.named || f.link.to_lowercase().contains("sole"));
        let off = |c: &Vec3| (c[0] - middle[0]).hypot(c[1] - middle[1]);
        named(a.0)
            .cmp(&named(b.0))
            .then(off(&a.1).total_cmp(&off(&b.1)))
    });
    let (centre, from) = match fits.first() {
        Some((f, c)) => (*c, format!("<link name=\"{}\">", f.link)),
        None => (
            [middle[0], middle[1], zs],
            "the middle of the foot's contact geometry".to_string(),
        ),
    };
    let size = [2.0 * half(centre[0], x0, x1), 2.0 * half(centre[1], y0, y1)];
    if !(size[0] > 0.01 && size[1] > 0.01) {
        return err(format!(
            "the foot ({names}): its collision geometry gives a sole of {:.3} × {:.3} m around \
             its centre",
            size[0], size[1]
        ));
    }
    let back = transpose(level);
    Ok(Sole {
        centre: mul_mv(&back, centre),
        rotation: back,
        size,
        from,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_vertices() {
        assert_eq!(
            obj("# c\nv 1 2 3\nvn 0 0 1\nv 4 5 6 1\n"),
            vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
        );
    }

    /// A foot of four balls under an ankle frame pitched by 0.4 rad at zero angles: the sole
    /// plane is the balls' lowest points on the floor's vertical, 0.07 m below the ankle, and
    /// the sole centre straight below it (taking a ball's lowest point along the tilted
    /// frame's z put the plane 1.6 mm high and the centre 7.8 mm behind).
    #[test]
    fn balls_under_a_tilted_ankle_frame_touch_straight_below_their_centres() {
        use crate::robot::model::{rot_rpy, sub};
        let level = rot_rpy([0.0, 0.4, 0.0]);
        let back = transpose(&level);
        let mut foot = String::from("<robot name=\"r\"><link name=\"foot\">");
        for (x, y) in [(0.1, 0.05), (0.1, -0.05), (-0.1, 0.05), (-0.1, -0.05)] {
            let c = mul_mv(&back, [x, y, -0.05]);
            foot += &format!(
                "<collision><origin xyz=\"{} {} {}\"/><geometry><sphere radius=\"0.02\"/>\
                 </geometry></collision>",
                c[0], c[1], c[2]
            );
        }
        foot += "</link></robot>";
        let urdf = urdf_rs::read_from_string(&foot).expect("URDF");
        let t = Tree::new(urdf, ".".into()).expect("tree");
        let s = sole(&t, &[("foot".into(), Pose::IDENTITY)], &[], &level, 0.6).expect("sole");
        let want = mul_mv(&back, [0.0, 0.0, -0.07]);
        assert!(
            crate::robot::model::norm(sub(s.centre, want)) < 1e-9,
            "{:?} vs {want:?}",
            s.centre
        );
        assert!(
            (s.size[0] - 0.2).abs() < 1e-9 && (s.size[1] - 0.1).abs() < 1e-9,
            "{s:?}"
        );
    }
}
