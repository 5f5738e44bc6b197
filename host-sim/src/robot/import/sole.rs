//! The sole of an imported foot, from its collision geometry.
//!
//! Every collision shape of the foot's links (their visual shapes if they have none) is turned
//! into points in the ankle frame: a box's eight corners, a sphere's lowest point, a
//! cylinder's two end circles (32 points each), a capsule's two end spheres' lowest points
//! and end circles, a mesh's vertices (scaled; STL, COLLADA `.dae` and OBJ). The **sole plane** is the lowest point's height `z_s`; the **contact points**
//! those within [`CONTACT_BAND_M`] of it. The sole centre is the foot's sole frame where the
//! URDF gives one (a frame fixed below the ankle), the middle of the contact points' bounds
//! otherwise; the sole rectangle is the largest one centred there inside those bounds.

use std::fs::File;
use std::io::BufReader;

use urdf_rs::Geometry;

use super::{err, pose_of, resolve, ImportError, Tree};
use crate::robot::model::{mul_mv, transpose, Mat3, Pose, Vec3};

/// Points this close above the lowest one are the sole's \[m\].
pub const CONTACT_BAND_M: f64 = 0.005;

/// A foot's sole in its ankle frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sole {
    /// The sole centre \[m\].
    pub centre: Vec3,
    /// The sole's orientation: level with the base at zero joint angles.
    pub rotation: Mat3,
    /// Length (along x) and width (along y) \[m\].
    pub size: [f64; 2],
}

fn circle(pose: &Pose, radius: f64, z: f64, out: &mut Vec<Vec3>) {
    for k in 0..32 {
        let a = f64::from(k) * std::f64::consts::TAU / 32.0;
        out.push(pose.apply([radius * a.cos(), radius * a.sin(), z]));
    }
}

/// The points of one collision shape placed at `pose` (in the ankle frame).
fn points(t: &Tree, g: &Geometry, pose: &Pose, out: &mut Vec<Vec3>) -> Result<(), ImportError> {
    match g {
        Geometry::Box { size } => {
            for k in 0..8 {
                let c = |i: usize| if k >> i & 1 == 1 { 0.5 } else { -0.5 } * size.0[i];
                out.push(pose.apply([c(0), c(1), c(2)]));
            }
        }
        Geometry::Sphere { radius } => {
            let c = pose.apply([0.0; 3]);
            out.push([c[0], c[1], c[2] - radius]);
        }
        Geometry::Cylinder { radius, length } => {
            circle(pose, *radius, 0.5 * length, out);
            circle(pose, *radius, -0.5 * length, out);
        }
        Geometry::Capsule { radius, length } => {
            for z in [0.5 * length, -0.5 * length] {
                let c = pose.apply([0.0, 0.0, z]);
                out.push([c[0], c[1], c[2] - radius]);
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
                    let v = if ext == "dae" { dae(&text) } else { obj(&text) };
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

/// The vertex positions of a COLLADA document: every `<float_array>` of a source whose id
/// names positions, in metres (`<unit meter>`, and a uniform `<scale>` shared by the scene's
/// nodes) and z up (`<up_axis>` `Y_UP` turned). Other node transforms are not applied.
fn dae(text: &str) -> Vec<Vec3> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let at = tag.find(&format!("{name}=\""))? + name.len() + 2;
        Some(tag[at..at + tag[at..].find('"')?].to_string())
    };
    let unit = text
        .find("<unit")
        .and_then(|i| attr(&text[i..i + text[i..].find('>').unwrap_or(0)], "meter"))
        .and_then(|m| m.parse::<f64>().ok())
        .unwrap_or(1.0);
    let y_up = text.contains("<up_axis>Y_UP</up_axis>");
    // The scene's nodes may scale the geometry (a mesh in centimetres under a node scaled by
    // 0.01): one uniform scale shared by every node applies; other node transforms do not.
    let scales: Vec<f64> = text
        .match_indices("<scale")
        .filter_map(|(i, _)| {
            let body = &text[i..];
            let v: Vec<f64> = body[body.find('>')? + 1..body.find("</scale>")?]
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            (v.len() == 3 && v[0] == v[1] && v[1] == v[2]).then_some(v[0])
        })
        .collect();
    let node_scale = match scales.first() {
        Some(&first) if scales.iter().all(|&s| s == first) => first,
        _ => 1.0,
    };
    let unit = unit * node_scale;
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("<float_array") {
        rest = &rest[i..];
        let Some(end_tag) = rest.find('>') else { break };
        let tag = &rest[..end_tag];
        let body_end = rest.find("</float_array>").unwrap_or(end_tag);
        let body = &rest[end_tag + 1..body_end.max(end_tag + 1)];
        let is_position = attr(tag, "id").is_some_and(|id| id.to_lowercase().contains("position"));
        if is_position {
            let v: Vec<f64> = body
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            for c in v.chunks_exact(3) {
                let p = [c[0] * unit, c[1] * unit, c[2] * unit];
                out.push(if y_up { [p[0], -p[2], p[1]] } else { p });
            }
        }
        rest = &rest[end_tag..];
    }
    out
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

/// The sole of a foot made of `links` (each with its pose in the ankle frame), with the
/// URDF's sole frame `frame` if there is one; `level`: the ankle frame's orientation in the
/// base frame at zero joint angles (the sole is level with the base there, whatever the
/// ankle frame's axes: the points are taken in base-aligned axes).
pub(crate) fn sole(
    t: &Tree,
    links: &[(String, Pose)],
    frame: Option<Pose>,
    level: &Mat3,
) -> Result<Sole, ImportError> {
    let mut pts = Vec::new();
    for (name, pose) in links {
        for c in &t.link(name).collision {
            points(t, &c.geometry, &pose.then(&pose_of(&c.origin)), &mut pts)?;
        }
    }
    if pts.is_empty() {
        // No collision shape: the visual one.
        for (name, pose) in links {
            for v in &t.link(name).visual {
                points(t, &v.geometry, &pose.then(&pose_of(&v.origin)), &mut pts)?;
            }
        }
    }
    let names: Vec<&str> = links.iter().map(|(n, _)| n.as_str()).collect();
    if pts.is_empty() {
        return err(format!(
            "the foot (<link name=\"{}\">) has no <collision> or <visual> geometry: its sole \
             cannot be found",
            names.join("\">, <link name=\"")
        ));
    }
    let pts: Vec<Vec3> = pts.iter().map(|p| mul_mv(level, *p)).collect();
    let zs = pts.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    let contact: Vec<&Vec3> = pts.iter().filter(|p| p[2] <= zs + CONTACT_BAND_M).collect();
    let lo = |i: usize| contact.iter().map(|p| p[i]).fold(f64::INFINITY, f64::min);
    let hi = |i: usize| {
        contact
            .iter()
            .map(|p| p[i])
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let (x0, x1, y0, y1) = (lo(0), hi(0), lo(1), hi(1));
    let centre = match frame {
        Some(f) => mul_mv(level, f.p),
        None => [0.5 * (x0 + x1), 0.5 * (y0 + y1), zs],
    };
    let half = |c: f64, a: f64, b: f64| (c - a).min(b - c);
    let size = [2.0 * half(centre[0], x0, x1), 2.0 * half(centre[1], y0, y1)];
    if !(size[0] > 0.01 && size[1] > 0.01) {
        return err(format!(
            "the foot (<link name=\"{}\">): its collision geometry gives a sole of {:.3} × {:.3} m \
             around its centre",
            names.join("\">, <link name=\""),
            size[0],
            size[1]
        ));
    }
    let back = transpose(level);
    Ok(Sole {
        centre: mul_mv(&back, centre),
        rotation: back,
        size,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collada_positions_in_metres_and_z_up() {
        let doc = r#"<COLLADA><asset><unit meter="0.1" name="decimetre"/><up_axis>Y_UP</up_axis></asset>
            <library_geometries><geometry><mesh>
            <source id="a-positions"><float_array id="a-positions-array" count="6">1 2 3 4 5 6</float_array></source>
            <source id="a-normals"><float_array id="a-normals-array" count="3">0 0 1</float_array></source>
            </mesh></geometry></library_geometries>
            <library_visual_scenes><visual_scene><node><scale sid="scale">0.5 0.5 0.5</scale></node></visual_scene></library_visual_scenes>
            </COLLADA>"#;
        // × 0.1 (unit) × 0.5 (the nodes' scale), then y up turned to z up: (x, −z, y).
        let v = dae(doc);
        let want = [[0.05, -0.15, 0.1], [0.2, -0.3, 0.25]];
        assert_eq!(v.len(), 2);
        for (a, b) in v.iter().zip(want) {
            for i in 0..3 {
                assert!((a[i] - b[i]).abs() < 1e-12, "{v:?}");
            }
        }
        assert_eq!(
            obj("# c\nv 1 2 3\nvn 0 0 1\nv 4 5 6 1\n"),
            vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
        );
    }
}
