//! The robot file's text: numbers, the `[multibody]` table.

use std::fmt::Write;

use super::Parts;
use crate::robot::model::{Body, Pose, IDENTITY};

pub(super) fn num(v: f64) -> String {
    let s = format!("{v:.9}");
    let s = s.trim_end_matches('0');
    if s.ends_with('.') {
        format!("{s}0")
    } else {
        s.into()
    }
}

pub(super) fn arr(v: &[f64]) -> String {
    format!(
        "[{}]",
        v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
    )
}

fn body_keys(b: &Body) -> String {
    let i = &b.inertia;
    format!(
        "mass = {}\ncom = {}\ninertia = {}\n",
        num(b.mass),
        arr(&b.com),
        arr(&[i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2]])
    )
}

/// The `[multibody]` part with the waist at `waist_height`.
pub(super) fn multibody(g: &Parts, waist_height: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "[multibody]");
    let _ = writeln!(s, "waist_height = {}", num(waist_height));
    let _ = writeln!(
        s,
        "\n[multibody.waist]       # the base link's own body, its frame"
    );
    s.push_str(&body_keys(&g.waist));
    let _ = writeln!(
        s,
        "\n[multibody.trunk]       # every link off the legs, at zero joint angles, merged"
    );
    s.push_str(&body_keys(&g.trunk));
    let _ = writeln!(
        s,
        "\n[multibody.sole]        # sole centres in the ankle frames\n# from: {}\nleft = {}\nright = {}",
        g.sole_from.join("; "),
        arr(&g.soles[0].p),
        arr(&g.soles[1].p)
    );
    for (side, sole) in ["left", "right"].iter().zip(&g.soles) {
        if sole.r != IDENTITY {
            let (r, p, y) = rpy(sole);
            let _ = writeln!(s, "{side}_rpy = {}", arr(&[r, p, y]));
        }
    }
    for (side, links) in ["left", "right"].iter().zip(g.legs) {
        for l in links {
            let _ = writeln!(s, "\n[[multibody.{side}]]");
            let _ = writeln!(s, "joint = {:?}\nlink = {:?}", l.joint, l.link);
            let (r, p, y) = rpy(&l.origin);
            let _ = writeln!(
                s,
                "origin = {}\nrpy = {}\naxis = {}",
                arr(&l.origin.p),
                arr(&[r, p, y]),
                arr(&l.axis)
            );
            if let Some(r) = l.range {
                let _ = writeln!(s, "range = {}", arr(&r));
            }
            if let Some(e) = l.effort {
                let _ = writeln!(s, "effort = {}", num(e));
            }
            if let Some(v) = l.velocity {
                let _ = writeln!(s, "velocity = {}", num(v));
            }
            s.push_str(&body_keys(&l.body));
        }
    }
    s
}

/// The URDF `rpy` of a rotation (`R = R_z(y) R_y(p) R_x(r)`).
pub(super) fn rpy(p: &Pose) -> (f64, f64, f64) {
    let r = &p.r;
    let pitch = (-r[2][0]).clamp(-1.0, 1.0).asin();
    let roll = r[2][1].atan2(r[2][2]);
    let yaw = r[1][0].atan2(r[0][0]);
    (roll, pitch, yaw)
}
