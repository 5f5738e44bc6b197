//! The sole of an imported foot, from its collision geometry.
//!
//! Every collision shape of the foot's links is turned into points in the ankle frame: a
//! box's eight corners, a sphere's lowest point, a cylinder's two end circles (32 points
//! each), a capsule's two end spheres' lowest points and end circles, an STL mesh's vertices
//! (scaled). The **sole plane** is the lowest point's height `z_s`; the **contact points**
//! those within [`CONTACT_BAND_M`] of it. The sole centre is the foot's sole frame where the
//! URDF gives one (a frame fixed below the ankle), the middle of the contact points' bounds
//! otherwise; the sole rectangle is the largest one centred there inside those bounds.

use std::fs::File;
use std::io::BufReader;

use urdf_rs::Geometry;

use super::{err, pose_of, resolve, ImportError, Tree};
use crate::robot::model::{Pose, Vec3};

/// Points this close above the lowest one are the sole's \[m\].
pub const CONTACT_BAND_M: f64 = 0.005;

/// A foot's sole in its ankle frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sole {
    /// The sole centre \[m\].
    pub centre: Vec3,
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
            let is_stl = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("stl"));
            if !is_stl {
                return err(format!(
                    "<mesh filename=\"{filename}\">: only STL meshes are read for the soles"
                ));
            }
            let mut f = BufReader::new(
                File::open(&path)
                    .map_err(|e| ImportError(format!("<mesh filename=\"{filename}\">: {e}")))?,
            );
            let mesh = stl_io::read_stl(&mut f)
                .map_err(|e| ImportError(format!("<mesh filename=\"{filename}\">: {e}")))?;
            let s = scale.map_or([1.0; 3], |s| s.0);
            for v in &mesh.vertices {
                let p = [
                    f64::from(v.0[0]) * s[0],
                    f64::from(v.0[1]) * s[1],
                    f64::from(v.0[2]) * s[2],
                ];
                out.push(pose.apply(p));
            }
        }
    }
    Ok(())
}

/// The sole of a foot made of `links` (each with its pose in the ankle frame), with the
/// URDF's sole frame `frame` if there is one.
pub(crate) fn sole(
    t: &Tree,
    links: &[(String, Pose)],
    frame: Option<Pose>,
) -> Result<Sole, ImportError> {
    let mut pts = Vec::new();
    for (name, pose) in links {
        for c in &t.link(name).collision {
            points(t, &c.geometry, &pose.then(&pose_of(&c.origin)), &mut pts)?;
        }
    }
    let names: Vec<&str> = links.iter().map(|(n, _)| n.as_str()).collect();
    if pts.is_empty() {
        return err(format!(
            "the foot (<link name=\"{}\">) has no <collision> geometry: its sole cannot be found",
            names.join("\">, <link name=\"")
        ));
    }
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
        Some(f) => f.p,
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
    Ok(Sole { centre, size })
}
