//! The robot file's text: numbers, the `[multibody]` table.

use std::fmt::Write;
use std::path::Path;

use super::{round_mm, Parts};
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

/// HRP-2's robot file's planner part, with the values of this robot.
pub(super) struct Planner {
    pub(super) cog_height: f64,
    pub(super) gravity: f64,
    pub(super) sole: [f64; 2],
    pub(super) step_width: f64,
    pub(super) step_height: f64,
    pub(super) scale: f64,
}

pub(super) fn planner_part(name: &str, urdf: &Path, p: &Planner) -> String {
    let h = super::Robot::hrp2();
    let r = h.planner.reach;
    let k = p.scale;
    let hw = p.step_width;
    format!(
        "# {name}: imported from {urdf} by `host-sim robot import`.\n\
         # The import's derivations and margins: host-sim/src/robot/import/mod.rs. Gait timing,\n\
         # preview weights and eq. 18 limits are HRP-2's; lengths are this robot's.\n\
         name = {name:?}\n\n\
         [pendulum]\ncog_height = {}\ngravity = {}\n\n\
         [timing]\ncontrol_period = 0.005\nsingle_support = 0.7\ndouble_support = 0.1\nstart = 0.8\n\
         settle = 0.7\nstand = 0.005\nrest = 0.5\n\n\
         [adjustment]\nmin = -0.2\nmax = 0.35\n\n\
         [feet]\nsole_length = {}\nsole_width = {}\nstep_width = {}\nstep_height = {}\n\n\
         [reach]                 # HRP-2's scaled by {} (the legs' workspace at the walking height, every corner reached)\n\
         max_forward = {}\nmax_backward = {}\nmin_width = {}\nmax_width = {}\nmax_yaw = {}\n\
         max_feet_distance = {}\nyaw_cost = {}\nmax_stride = {}\nmax_growth = {}\n\n\
         [preview]\nqe = 1.0\nr = 1e-6\nshaping = true\n\n",
        num(p.cog_height),
        num(p.gravity),
        num(p.sole[0]),
        num(p.sole[1]),
        num(hw),
        num(p.step_height),
        num(k),
        num(round_mm(r.max_forward * k)),
        num(round_mm(r.max_backward * k)),
        num(round_mm((hw - (0.2 - r.min_width) * k).max(p.sole[1] + 0.01))),
        num(round_mm(hw + (r.max_width - 0.2) * k)),
        num(r.max_yaw),
        num(round_mm(
            (r.max_feet_distance * k).max((r.max_forward * k).hypot(hw) + 0.0005)
        )),
        num(r.yaw_cost * k),
        num(round_mm(r.max_stride * k + (hw - 0.2 * k).max(0.0))),
        num(round_mm(r.max_growth * k)),
        urdf = urdf.display(),
    )
}
