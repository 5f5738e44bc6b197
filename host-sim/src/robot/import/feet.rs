//! Which links are the feet, when `--sole` does not say: the lowest geometry, not the lowest
//! frame.
//!
//! The URDF's rigid bodies are its links grouped by fixed joints; an **end body** is one with
//! no moving joint below it (a foot, a hand, a head). Each end body's lowest point is that of
//! its collision shapes (its visual ones if it has none) at zero joint angles; the feet are
//! the end body with the lowest point on each side of the base (left: its first link's
//! origin at positive y). A massless frame (a sensor or a sole frame) is part of the body it
//! is fixed to, so it is never taken for a foot by itself; whether it is the sole centre is
//! decided against the foot's geometry ([`super::sole`]). If no end body on a side has
//! geometry, the lowest leaf link on each side is taken (and refused later if its foot has
//! no geometry). An end body whose shapes cannot be read (a mesh of another format) below the
//! lowest geometry on its side refuses the import, the shape named.

use std::collections::BTreeMap;

use urdf_rs::JointType;

use super::{sole, ImportError, Tree};
use crate::robot::model::{cross, mul_mv, norm, sub, transpose, Pose};

/// The end bodies below `base`: each as its first link (moved by a joint) and its links
/// with their poses in that link's frame.
pub(crate) fn end_bodies(t: &Tree, base: &str) -> Vec<Vec<(String, Pose)>> {
    let mut out = Vec::new();
    let mut roots = Vec::new();
    let mut stack = vec![base.to_string()];
    while let Some(l) = stack.pop() {
        for &j in t.kids(&l) {
            let joint = &t.urdf.joints[j];
            if joint.joint_type != JointType::Fixed {
                roots.push(joint.child.link.clone());
            }
            stack.push(joint.child.link.clone());
        }
    }
    for root in roots {
        let mut body = Vec::new();
        let mut end = true;
        let mut stack = vec![(root.clone(), Pose::IDENTITY)];
        while let Some((l, p)) = stack.pop() {
            for &j in t.kids(&l) {
                let joint = &t.urdf.joints[j];
                if joint.joint_type == JointType::Fixed {
                    stack.push((
                        joint.child.link.clone(),
                        p.then(&super::pose_of(&joint.origin)),
                    ));
                } else {
                    end = false;
                }
            }
            body.push((l, p));
        }
        if end {
            out.push(body);
        }
    }
    out
}

/// The feet by their geometry (see the module docs): the first link of the left and the
/// right foot, `None` if a side has no end body with geometry. An end body whose shapes cannot
/// be read, lower (its first link's origin) than the lowest geometry on its side, is the
/// error.
pub(crate) fn by_geometry(
    t: &Tree,
    base: &str,
    zero: &BTreeMap<String, Pose>,
) -> Result<Option<[String; 2]>, ImportError> {
    let mut best: [Option<(f64, String)>; 2] = [None, None];
    let mut unread: [Option<(f64, ImportError)>; 2] = [None, None];
    for body in end_bodies(t, base) {
        let first = &body[0].0;
        let Some(at) = zero.get(first) else { continue };
        let side = if at.p[1] > 0.0 {
            0
        } else if at.p[1] < 0.0 {
            1
        } else {
            continue;
        };
        let down = mul_mv(&transpose(&at.r), [0.0, 0.0, -1.0]);
        let pts = match sole::foot_points(t, &body, down) {
            Ok((pts, _)) => pts,
            Err(e) => {
                if unread[side].as_ref().is_none_or(|(z, _)| at.p[2] < *z) {
                    unread[side] = Some((at.p[2], e));
                }
                continue;
            }
        };
        let Some(low) = pts
            .iter()
            .map(|(p, _)| at.apply(*p)[2])
            .min_by(f64::total_cmp)
        else {
            continue;
        };
        if best[side].as_ref().is_none_or(|(z, _)| low < *z) {
            best[side] = Some((low, first.clone()));
        }
    }
    for (b, u) in best.iter().zip(unread) {
        if let Some((z, e)) = u {
            if b.as_ref().is_none_or(|(low, _)| z < *low) {
                return Err(e);
            }
        }
    }
    Ok(match best {
        [Some((_, l)), Some((_, r))] => Some([l, r]),
        _ => None,
    })
}

/// The knee of the leg to `leaf` if it bends forward of the base's x axis (the robot then
/// faces −x, as iCub's `root_link` does): the leg's moving joint farthest from both the hip
/// and the ankle, flexed towards the longer side of its range, moves the ankle towards +x.
/// `None` if it moves it towards −x, or if the knee has no range to tell.
pub(crate) fn knee_bends_forward(
    t: &Tree,
    base: &str,
    zero: &BTreeMap<String, Pose>,
    leaf: &str,
) -> Option<String> {
    let moving: Vec<usize> = t
        .path(base, leaf)?
        .into_iter()
        .filter(|&j| t.urdf.joints[j].joint_type != JointType::Fixed)
        .collect();
    let at = |j: usize| zero.get(&t.urdf.joints[j].child.link);
    let hip = at(*moving.first()?)?.p;
    let ankle = at(*moving.last()?)?.p;
    let apart = |j: usize| at(j).map_or(0.0, |p| norm(sub(p.p, hip)).min(norm(sub(p.p, ankle))));
    let knee = moving
        .iter()
        .copied()
        .max_by(|&a, &b| apart(a).total_cmp(&apart(b)))?;
    let joint = &t.urdf.joints[knee];
    let l = &joint.limit;
    if joint.joint_type != JointType::Revolute
        || l.lower.partial_cmp(&l.upper) != Some(std::cmp::Ordering::Less)
        || apart(knee) <= 0.0
    {
        return None;
    }
    let flex = if l.upper.abs() >= l.lower.abs() {
        1.0
    } else {
        -1.0
    };
    let frame = at(knee)?;
    let axis = mul_mv(&frame.r, joint.axis.xyz.0).map(|v| v * flex);
    let d = cross(axis, sub(ankle, frame.p));
    (d[0] > 0.5 * norm(d)).then(|| joint.name.clone())
}

/// Turns the base frame by 180° about z: the joints from the base and the base's inertial
/// are placed in the turned frame.
pub(crate) fn turn_base(t: &mut Tree, base: &str) {
    let turn = Pose {
        p: [0.0; 3],
        r: [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
    };
    let turned = |o: &urdf_rs::Pose| {
        let p = turn.then(&super::pose_of(o));
        let (r, pi, y) = super::text::rpy(&p);
        urdf_rs::Pose {
            xyz: urdf_rs::Vec3(p.p),
            rpy: urdf_rs::Vec3([r, pi, y]),
        }
    };
    for j in t.kids(base).to_vec() {
        let o = turned(&t.urdf.joints[j].origin);
        t.urdf.joints[j].origin = o;
    }
    let i = t.links[base];
    let o = turned(&t.urdf.links[i].inertial.origin);
    t.urdf.links[i].inertial.origin = o;
}
