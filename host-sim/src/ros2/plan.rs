//! A footstep list checked and matched against the steps the gateway knows, before anything is
//! sent: what the list asks of the node ([`Planned`]) or why the whole list is refused
//! ([`ListError`]).
//!
//! Every footstep is validated once, here: `robot_side` 0 or 1, a finite location and
//! orientation, a unit quaternion (norm within [`NORM_TOLERANCE`] of 1) that is level (tilt
//! within [`TILT_TOLERANCE`]), at most [`MAX_LIST`] steps, alternating feet, no id twice, a
//! known execution mode, and every pose representable on the bus in the node's frame. A list
//! that breaks one of these is refused whole and changes nothing.
//!
//! Matching (execution mode OVERRIDE, and STREAM taken as OVERRIDE): a footstep whose
//! non-zero `sequence_id` names a step the gateway knows *is* that step; a list whose ids are
//! all 0 is matched by position with the steps not yet lifted off. The list must then read
//! `[steps already lifted off] [every step not yet lifted off, in queue order] [new steps]`:
//! the node's queue can be extended and its steps moved, never reordered, and a step cannot
//! be taken out of it while the robot walks (only the whole queue, by a stop). A list that
//! leaves queued steps out is refused (`queued_steps_left_out`) while walking; while standing
//! it replaces them (the queue is dropped first). A step already lifted off and sent with
//! another pose is refused alone (`lifted_off`); the rest of the list is carried out. QUEUE:
//! every step is new (an id the gateway knows is `duplicate_id`) and appended.

use planner_core::gait::Side;
use planner_core::wire::WireStep;

use super::msg::{
    FootstepDataListMessage, EXECUTION_MODE_OVERRIDE, EXECUTION_MODE_QUEUE, EXECUTION_MODE_STREAM,
    MAX_LIST, ROBOT_SIDE_LEFT, ROBOT_SIDE_RIGHT,
};

/// How far a quaternion's norm may be from 1.
pub const NORM_TOLERANCE: f64 = 1e-3;
/// The largest tilt (roll or pitch) of a footstep's orientation \[rad\]: the floor is flat.
pub const TILT_TOLERANCE: f64 = 0.01;

/// A planar pose: x, y \[m\] and heading \[rad\].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// x \[m\].
    pub x: f64,
    /// y \[m\].
    pub y: f64,
    /// Heading \[rad\].
    pub yaw: f64,
}

impl Pose {
    /// `other` (given in this pose's frame) in the frame this pose is given in.
    pub fn compose(&self, other: &Pose) -> Pose {
        let (s, c) = self.yaw.sin_cos();
        Pose {
            x: self.x + c * other.x - s * other.y,
            y: self.y + s * other.x + c * other.y,
            yaw: wrap(self.yaw + other.yaw),
        }
    }

    /// `other` (given in the frame this pose is given in) in this pose's frame.
    pub fn relative(&self, other: &Pose) -> Pose {
        let (s, c) = self.yaw.sin_cos();
        let (dx, dy) = (other.x - self.x, other.y - self.y);
        Pose {
            x: c * dx + s * dy,
            y: -s * dx + c * dy,
            yaw: wrap(other.yaw - self.yaw),
        }
    }

    /// The same pose on the footstep grid of the bus (0.5 mm, 2π/4096 rad), `None` where the
    /// bus cannot carry it.
    pub fn on_grid(&self) -> Option<WireStep> {
        WireStep::from_si(0, false, self.x, self.y, self.yaw)
    }
}

/// An angle wrapped into (−π, π].
pub fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

/// One footstep of a list, validated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Draft {
    /// The footstep's `sequence_id`.
    pub id: u32,
    /// Its index in the list.
    pub index: i32,
    /// The foot that steps.
    pub side: Side,
    /// The sole's pose in the world frame.
    pub pose: Pose,
}

/// Why a whole list is refused: the reason's name and the words.
#[derive(Clone, Debug, PartialEq)]
pub struct ListError {
    /// The offending step's index (−1: the list as a whole).
    pub index: i32,
    /// The offending step's id (0: none).
    pub id: u32,
    /// The reason's name.
    pub reason: &'static str,
    /// The reason in words.
    pub detail: String,
}

fn refuse(index: i32, id: u32, reason: &'static str, detail: String) -> ListError {
    ListError {
        index,
        id,
        reason,
        detail,
    }
}

/// The heading of a level unit quaternion, or why it is not one.
pub fn heading(q: &super::msg::Quaternion) -> Result<f64, (&'static str, String)> {
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    if ![x, y, z, w].iter().all(|v| v.is_finite()) {
        return Err(("not_finite", format!("orientation ({x}, {y}, {z}, {w})")));
    }
    let norm = (x * x + y * y + z * z + w * w).sqrt();
    if (norm - 1.0).abs() > NORM_TOLERANCE {
        return Err((
            "bad_orientation",
            format!("orientation's norm {norm:.6}, not 1 within {NORM_TOLERANCE}"),
        ));
    }
    // The tilt of the sole's normal from the vertical: 2 asin(√(x² + y²)) for a unit
    // quaternion.
    let tilt = 2.0 * ((x * x + y * y).sqrt() / norm).min(1.0).asin();
    if tilt > TILT_TOLERANCE {
        return Err((
            "not_level",
            format!("the sole is tilted {tilt:.4} rad (at most {TILT_TOLERANCE} on a flat floor)"),
        ));
    }
    Ok((2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z)))
}

/// Validates every footstep of `msg` (see the module docs); `frame` is the node's frame in the
/// world, in which every pose must be representable on the bus.
pub fn validate(msg: &FootstepDataListMessage, frame: &Pose) -> Result<Vec<Draft>, ListError> {
    let mode = msg.queueing_properties.execution_mode;
    if ![
        EXECUTION_MODE_OVERRIDE,
        EXECUTION_MODE_QUEUE,
        EXECUTION_MODE_STREAM,
    ]
    .contains(&mode)
    {
        return Err(refuse(
            -1,
            0,
            "unknown_mode",
            format!("execution_mode {mode} (0 override, 1 queue, 2 stream)"),
        ));
    }
    let n = msg.footstep_data_list.len();
    if n > MAX_LIST {
        return Err(refuse(
            -1,
            0,
            "too_many_steps",
            format!("{n} footsteps, at most {MAX_LIST}"),
        ));
    }
    let mut drafts: Vec<Draft> = Vec::with_capacity(n);
    for (k, f) in msg.footstep_data_list.iter().enumerate() {
        let (index, id) = (k as i32, f.sequence_id);
        let side = match f.robot_side {
            ROBOT_SIDE_LEFT => Side::Left,
            ROBOT_SIDE_RIGHT => Side::Right,
            s => {
                return Err(refuse(
                    index,
                    id,
                    "unknown_side",
                    format!("robot_side {s} (0 left, 1 right)"),
                ))
            }
        };
        let (x, y) = (f.location.x, f.location.y);
        if !(x.is_finite() && y.is_finite() && f.location.z.is_finite()) {
            return Err(refuse(
                index,
                id,
                "not_finite",
                format!("location ({x}, {y}, {})", f.location.z),
            ));
        }
        let yaw = heading(&f.orientation).map_err(|(r, d)| refuse(index, id, r, d))?;
        let pose = Pose { x, y, yaw };
        if frame.relative(&pose).on_grid().is_none() {
            return Err(refuse(
                index,
                id,
                "out_of_range",
                format!("({x}, {y}) m is beyond the bus's ±32.77 m around the node's frame origin"),
            ));
        }
        if let Some(prev) = drafts.last() {
            if prev.side == side {
                return Err(refuse(
                    index,
                    id,
                    "side_order",
                    format!(
                        "two {side:?} footsteps in a row (indices {} and {k})",
                        k - 1
                    ),
                ));
            }
        }
        if id != 0 && drafts.iter().any(|d| d.id == id) {
            return Err(refuse(
                index,
                id,
                "duplicate_id",
                format!("sequence_id {id} twice in the list"),
            ));
        }
        drafts.push(Draft {
            id,
            index,
            side,
            pose,
        });
    }
    Ok(drafts)
}

/// Where a step the gateway knows stands, as the matching sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Known {
    /// Its foot has lifted off (it is being swung or has landed).
    Lifted,
    /// Not yet lifted off (in the node's queue, or on its way there).
    Unlifted,
}

/// A step the gateway knows, as the matching needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownStep {
    /// The gateway's index of the step.
    pub key: usize,
    /// Its id (0: none).
    pub id: u32,
    /// Its foot.
    pub side: Side,
    /// Its pose in force (world).
    pub pose: Pose,
    /// Lifted off or not.
    pub known: Known,
}

/// What a list asks of the node.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Planned {
    /// Drop every queued step first (an OVERRIDE that replaces them while standing).
    pub drop_queue: bool,
    /// Steps to move: (the gateway's key, the list's footstep).
    pub modify: Vec<(usize, Draft)>,
    /// Steps already lifted off that the list moves: refused one by one.
    pub late: Vec<(usize, Draft)>,
    /// New steps, in order.
    pub append: Vec<Draft>,
}

/// Two poses the bus cannot tell apart.
pub fn same_on_bus(a: &Pose, b: &Pose) -> bool {
    match (a.on_grid(), b.on_grid()) {
        (Some(p), Some(q)) => (p.x, p.y, p.yaw) == (q.x, q.y, q.yaw),
        _ => false,
    }
}

/// Matches validated footsteps with the known steps (`known`: the live steps in walking
/// order, lifted ones first) for `mode`; `standing`: the robot stands and is not about to
/// walk, so an OVERRIDE may drop the queue.
pub fn plan(
    drafts: &[Draft],
    mode: u8,
    known: &[KnownStep],
    standing: bool,
) -> Result<Planned, ListError> {
    let mut out = Planned::default();
    let unlifted: Vec<&KnownStep> = known
        .iter()
        .filter(|k| k.known == Known::Unlifted)
        .collect();
    let by_id = |id: u32| known.iter().rev().find(|k| id != 0 && k.id == id);
    if mode == EXECUTION_MODE_QUEUE {
        if let Some(d) = drafts.iter().find(|d| by_id(d.id).is_some()) {
            return Err(refuse(
                d.index,
                d.id,
                "duplicate_id",
                format!(
                    "sequence_id {} names a step already sent; QUEUE appends new steps \
                     (send it with OVERRIDE to move it)",
                    d.id
                ),
            ));
        }
        out.append = drafts.to_vec();
        return Ok(out);
    }
    let positional = drafts.iter().all(|d| d.id == 0);
    let matched: Vec<Option<&KnownStep>> = drafts
        .iter()
        .enumerate()
        .map(|(k, d)| {
            if positional {
                unlifted.get(k).copied()
            } else {
                by_id(d.id)
            }
        })
        .collect();
    // The order the node can follow: lifted, then all unlifted in queue order, then new.
    let mut stage = 0; // 0 lifted, 1 unlifted, 2 new
    let mut order_ok = true;
    let mut positions: Vec<usize> = Vec::new();
    for (d, m) in drafts.iter().zip(&matched) {
        let this = match m {
            Some(k) if k.known == Known::Lifted => 0,
            Some(_) => 1,
            None => 2,
        };
        if this < stage {
            order_ok = false;
        }
        stage = stage.max(this);
        if let Some(k) = m {
            if k.side != d.side {
                return Err(refuse(
                    d.index,
                    d.id,
                    "side_changed",
                    format!(
                        "footstep {} was a {:?} step and is sent as a {:?} step",
                        d.id, k.side, d.side
                    ),
                ));
            }
            if k.known == Known::Unlifted {
                let at = unlifted.iter().position(|u| u.key == k.key).unwrap_or(0);
                if positions.last().is_some_and(|&p| p >= at) {
                    order_ok = false;
                }
                positions.push(at);
            }
        }
    }
    let covers_queue = order_ok && positions.len() == unlifted.len();
    if !covers_queue {
        if standing {
            out.drop_queue = !unlifted.is_empty();
            out.late = drafts
                .iter()
                .zip(&matched)
                .filter(|(d, m)| {
                    matches!(m, Some(k) if k.known == Known::Lifted && !same_on_bus(&k.pose, &d.pose))
                })
                .map(|(d, m)| (m.map(|k| k.key).unwrap_or(0), *d))
                .collect();
            out.append = drafts
                .iter()
                .zip(&matched)
                .filter(|(_, m)| !matches!(m, Some(k) if k.known == Known::Lifted))
                .map(|(d, _)| *d)
                .collect();
            return Ok(out);
        }
        let left_out: Vec<String> = unlifted
            .iter()
            .filter(|u| !matched.iter().any(|m| m.map(|k| k.key) == Some(u.key)))
            .map(|u| u.id.to_string())
            .collect();
        return Err(if order_ok {
            refuse(
                -1,
                0,
                "queued_steps_left_out",
                format!(
                    "the list leaves out queued steps (ids {}) that the node walks next; while \
                     walking a queued step can be moved, not removed: send them again, or \
                     abort first",
                    left_out.join(", ")
                ),
            )
        } else {
            refuse(
                -1,
                0,
                "reordered",
                "the list reorders steps: it must read [lifted-off steps] [every queued step, \
                 in queue order] [new steps]"
                    .to_string(),
            )
        });
    }
    for (d, m) in drafts.iter().zip(&matched) {
        match m {
            Some(k) if same_on_bus(&k.pose, &d.pose) => {}
            Some(k) if k.known == Known::Lifted => out.late.push((k.key, *d)),
            Some(k) => out.modify.push((k.key, *d)),
            None => out.append.push(*d),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::msg::{FootstepDataMessage, Quaternion};
    use super::*;

    fn list(mode: u8, steps: &[(u32, u8, f64, f64)]) -> FootstepDataListMessage {
        FootstepDataListMessage::new(
            7,
            mode,
            steps
                .iter()
                .map(|&(id, side, x, y)| FootstepDataMessage::new(id, side, x, y, 0.0))
                .collect(),
        )
    }

    #[test]
    fn heading_of_a_yaw_quaternion_and_refusals() {
        for yaw in [-3.0, -1.0, 0.0, 0.4, 3.1] {
            let h = heading(&Quaternion::from_yaw(yaw)).unwrap();
            assert!((wrap(h - yaw)).abs() < 1e-12, "{yaw} -> {h}");
        }
        let tilted = Quaternion {
            x: (0.02f64).sin(),
            y: 0.0,
            z: 0.0,
            w: (0.02f64).cos(),
        };
        assert_eq!(heading(&tilted).unwrap_err().0, "not_level");
        let zero = Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 0.0,
        };
        assert_eq!(heading(&zero).unwrap_err().0, "bad_orientation");
        let nan = Quaternion {
            w: f64::NAN,
            ..zero
        };
        assert_eq!(heading(&nan).unwrap_err().0, "not_finite");
    }

    #[test]
    fn validation_refuses_each_malformed_footstep() {
        let frame = Pose::default();
        let ok = list(0, &[(1, 1, 0.1, -0.1), (2, 0, 0.2, 0.1)]);
        assert_eq!(validate(&ok, &frame).unwrap().len(), 2);
        let reason = |m: &FootstepDataListMessage| validate(m, &frame).unwrap_err().reason;
        assert_eq!(reason(&list(0, &[(1, 2, 0.1, -0.1)])), "unknown_side");
        assert_eq!(reason(&list(0, &[(1, 1, f64::NAN, -0.1)])), "not_finite");
        assert_eq!(reason(&list(0, &[(1, 1, 40.0, -0.1)])), "out_of_range");
        assert_eq!(
            reason(&list(0, &[(1, 1, 0.1, -0.1), (2, 1, 0.2, -0.1)])),
            "side_order"
        );
        assert_eq!(
            reason(&list(0, &[(1, 1, 0.1, -0.1), (1, 0, 0.2, 0.1)])),
            "duplicate_id"
        );
        assert_eq!(reason(&list(5, &[(1, 1, 0.1, -0.1)])), "unknown_mode");
        let long: Vec<(u32, u8, f64, f64)> =
            (0..51).map(|k| (k + 1, (k % 2) as u8, 0.0, 0.0)).collect();
        assert_eq!(reason(&list(0, &long)), "too_many_steps");
    }

    fn known(key: usize, id: u32, side: Side, x: f64, lifted: bool) -> KnownStep {
        KnownStep {
            key,
            id,
            side,
            pose: Pose {
                x,
                y: 0.0,
                yaw: 0.0,
            },
            known: if lifted {
                Known::Lifted
            } else {
                Known::Unlifted
            },
        }
    }

    fn drafts(steps: &[(u32, Side, f64)]) -> Vec<Draft> {
        steps
            .iter()
            .enumerate()
            .map(|(k, &(id, side, x))| Draft {
                id,
                index: k as i32,
                side,
                pose: Pose {
                    x,
                    y: 0.0,
                    yaw: 0.0,
                },
            })
            .collect()
    }

    #[test]
    fn override_moves_queued_steps_appends_new_ones_and_refuses_late_changes() {
        use Side::*;
        let k = [
            known(0, 1, Right, 0.1, true),
            known(1, 2, Left, 0.2, false),
            known(2, 3, Right, 0.3, false),
        ];
        let d = drafts(&[
            (1, Right, 0.15),
            (2, Left, 0.2),
            (3, Right, 0.35),
            (4, Left, 0.4),
        ]);
        let p = plan(&d, 0, &k, false).unwrap();
        assert_eq!(p.late.iter().map(|(k, _)| *k).collect::<Vec<_>>(), [0]);
        assert_eq!(p.modify.iter().map(|(k, _)| *k).collect::<Vec<_>>(), [2]);
        assert_eq!(p.append.iter().map(|d| d.id).collect::<Vec<_>>(), [4]);
        assert!(!p.drop_queue);
        // Leaving a queued step out while walking: refused whole; while standing: replaced.
        let short = drafts(&[(3, Right, 0.3)]);
        assert_eq!(
            plan(&short, 0, &k, false).unwrap_err().reason,
            "queued_steps_left_out"
        );
        let p = plan(&short, 0, &k, true).unwrap();
        assert!(p.drop_queue);
        assert_eq!(p.append.len(), 1);
        // Reordering.
        let swapped = drafts(&[(3, Right, 0.3), (2, Left, 0.2)]);
        assert_eq!(
            plan(&swapped, 0, &k, false).unwrap_err().reason,
            "reordered"
        );
        // Positional matching when every id is 0.
        let zeros = drafts(&[(0, Left, 0.25), (0, Right, 0.3), (0, Left, 0.5)]);
        let p = plan(&zeros, 0, &k, false).unwrap();
        assert_eq!(p.modify.iter().map(|(k, _)| *k).collect::<Vec<_>>(), [1]);
        assert_eq!(p.append.len(), 1);
        // QUEUE: only new ids.
        assert_eq!(
            plan(&drafts(&[(2, Left, 0.2)]), 1, &k, false)
                .unwrap_err()
                .reason,
            "duplicate_id"
        );
        assert_eq!(
            plan(&drafts(&[(9, Left, 0.2)]), 1, &k, false)
                .unwrap()
                .append
                .len(),
            1
        );
    }

    #[test]
    fn poses_compose_and_invert() {
        let f = Pose {
            x: 1.0,
            y: -2.0,
            yaw: 0.7,
        };
        let p = Pose {
            x: 0.3,
            y: 0.4,
            yaw: -2.9,
        };
        let back = f.relative(&f.compose(&p));
        assert!((back.x - p.x).abs() < 1e-12 && (back.y - p.y).abs() < 1e-12);
        assert!(wrap(back.yaw - p.yaw).abs() < 1e-12);
    }
}
