//! `host-sim robot import URDF [--sole LEFT,RIGHT] --out FILE.toml`: a robot file from a
//! robot description (URDF, read with `urdf-rs`).
//!
//! What the import derives, and what it states:
//!
//! * **The floating base**: the URDF's root link (the one link that is no joint's child); a
//!   massless root with a single fixed or floating child (a `world` or footprint frame) gives
//!   way to that child. It is the waist of the model; if the knees bend forward of its x axis
//!   (the robot faces −x), it is turned by 180° about z ([`feet::knee_bends_forward`]).
//! * **The legs**: the feet are the end bodies whose geometry reaches lowest, one on each side
//!   ([`feet`]; or the `--sole` links); each leg is the path from the root to its foot, with exactly
//!   six revolute (or continuous) joints and no other moving joint. Fixed joints on the path
//!   are folded into the next joint's origin, and the links they carry into the link before.
//! * **The upper body**: every link off the legs' paths (torso, arms, head, grippers) at zero
//!   joint angles, merged rigidly into one `trunk` body (its mass in the COM and the ZMP); the
//!   root link's own body is the `waist`. Links hanging from a leg link are merged into it; a
//!   link fixed to the base before both legs, once.
//! * **Masses and inertias**: each `<inertial>` as given (its `rpy` turned into the link frame,
//!   the full tensor kept), merged by the parallel-axis theorem ([`Body::merged`]); every merged
//!   tensor positive definite as the engine takes it.
//! * **The soles** ([`sole`]): the collision geometry of the foot (the last leg link and what
//!   is fixed to it, or its visual geometry if it has none: boxes, cylinders, capsules, spheres,
//!   STL, COLLADA ([`collada`]) and OBJ meshes with `package://` resolved by the directory of
//!   that name above the URDF or on `ROS_PACKAGE_PATH`); the sole plane is its lowest point,
//!   the sole its points within [`sole::CONTACT_BAND_M`] of it; the sole centre a frame of the
//!   foot that fits that geometry (Talos's `left_sole_link`), the sole's middle otherwise (a
//!   sole frame that does not fit is named in a warning); the sole rectangle the largest one
//!   centred there inside the contact points' bounds. The sole is flat in the ankle frame.
//! * **The standing posture**: the feet straight below the hips (`step_width` the distance of
//!   the sole centres at zero angles), the waist lowered by [`KNEE_DROP`] of the leg length
//!   (hip to ankle) from the straight-legged height, so that the knees bend as HRP-2's do
//!   (HRP-2: 8.8 %), or less where a static check of single support finds a pitch joint's
//!   torque above its share of the effort limit or a joint outside its range ([`posture`];
//!   refused naming the joint if no drop down to 3 % passes); the LIPM `cog_height` the
//!   whole-body COG height there.
//! * **The reach limits**: HRP-2's limits scaled by the ratio `k` of the legs' workspace
//!   radius at the walking height, `r = √((0.97 L)² − h²)` (`L` the leg length, `h` hip to
//!   ankle height, a 3 % knee margin), to HRP-2's; then shrunk by steps of 0.01 of HRP-2's
//!   until the leg's inverse kinematics reaches every corner of the limits, with the feet
//!   1 cm farther apart and the waist anywhere from 30 % to 70 % of the way between them, and
//!   with the waist midway within the joint ranges ([`reach`]; refused below 0.1). The
//!   limits that mix lengths along and across the walk allow for a stance wider than `k`
//!   HRP-2's 0.2 m: the feet distance at least `√(max_forward² + step_width²)`, the stride HRP-2's scaled plus the
//!   excess width.
//! * **The gait**: HRP-2's timing, preview weights and eq. 18 limits (the built-in scenarios
//!   are timed for them); the swing height HRP-2's 0.05 m scaled as the reach.
//!
//! Refused, with the file and line named: XML that is not well-formed (a file cut short: where
//! it ends and which element is open; [`xml`]). Refused, with the URDF element named: several
//! or no root links, a massless base, a leg without six revolute joints (or with a prismatic,
//! planar or floating joint), no pair of feet below the base, a foot without geometry or with
//! geometry out of proportion to the leg (the shape named), a moving link without an
//! `<inertial>`, an inertia tensor that is not positive definite, a mesh of another format, a
//! standing posture the legs cannot reach.

pub mod cli;
pub mod collada;
mod feet;
pub mod posture;
pub mod reach;
pub mod sole;
mod text;
pub mod xml;

use text::{multibody, planner_part, Planner};

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use planner_core::gait::Side;
use urdf_rs::JointType;

use super::model::{norm, rot_rpy, sub, Body, Pose, Vec3, IDENTITY};
use super::Robot;

/// The waist is lowered from the straight-legged height by this fraction of the leg length.
pub const KNEE_DROP: f64 = 0.088;
/// Knee margin of the reach limits: the hip–ankle distance at most this fraction of the leg.
pub const REACH_MARGIN: f64 = 0.97;

/// Why a URDF was refused.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportError(pub String);

impl std::fmt::Display for ImportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl std::error::Error for ImportError {}

fn err<T>(m: impl Into<String>) -> Result<T, ImportError> {
    Err(ImportError(m.into()))
}

fn pose_of(o: &urdf_rs::Pose) -> Pose {
    Pose {
        p: o.xyz.0,
        r: rot_rpy(o.rpy.0),
    }
}

/// A link's `<inertial>` as a body in the link frame (`None`: none, or massless).
fn inertial(l: &urdf_rs::Link) -> Option<Body> {
    let i = &l.inertial;
    let m = i.mass.value;
    if m.is_nan() || m <= 0.0 {
        return None;
    }
    let t = &i.inertia;
    let body = Body {
        mass: m,
        com: [0.0; 3],
        inertia: [
            [t.ixx, t.ixy, t.ixz],
            [t.ixy, t.iyy, t.iyz],
            [t.ixz, t.iyz, t.izz],
        ],
    };
    Some(body.moved(&pose_of(&i.origin)))
}

/// `b`'s inertia tensor as the engine takes it (each principal moment at least 1e-6 kg m²,
/// [`crate::physics::model`]) positive definite: else an error naming `what`.
fn positive(b: &Body, what: &str) -> Result<(), ImportError> {
    let mut i = b.inertia;
    for (k, row) in i.iter_mut().enumerate() {
        row[k] = row[k].max(1e-6);
    }
    let m2 = i[0][0] * i[1][1] - i[0][1] * i[1][0];
    let det = i[0][0] * (i[1][1] * i[2][2] - i[1][2] * i[2][1])
        - i[0][1] * (i[1][0] * i[2][2] - i[1][2] * i[2][0])
        + i[0][2] * (i[1][0] * i[2][1] - i[1][1] * i[2][0]);
    if b.mass <= 0.0 || (m2 > 0.0 && det > 0.0) {
        return Ok(());
    }
    let i = &b.inertia;
    err(format!(
        "{what}: its inertia tensor about its centre of mass (ixx {}, iyy {}, izz {}, ixy {}, \
         ixz {}, iyz {}) is not positive definite: no body has it (a tensor about another point \
         than the <inertial> origin?), and the engine cannot simulate it",
        i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2]
    ))
}

/// The URDF as a tree.
pub(crate) struct Tree {
    pub(crate) urdf: urdf_rs::Robot,
    pub(crate) dir: PathBuf,
    links: BTreeMap<String, usize>,
    /// Joint index by child link.
    parent: BTreeMap<String, usize>,
    /// Joint indices by parent link.
    children: BTreeMap<String, Vec<usize>>,
}

impl Tree {
    fn new(urdf: urdf_rs::Robot, dir: PathBuf) -> Result<Self, ImportError> {
        let links: BTreeMap<String, usize> = urdf
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| (l.name.clone(), i))
            .collect();
        let mut parent = BTreeMap::new();
        let mut children: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (i, j) in urdf.joints.iter().enumerate() {
            for l in [&j.parent.link, &j.child.link] {
                if !links.contains_key(l) {
                    return err(format!(
                        "<joint name=\"{}\">: no <link name=\"{l}\">",
                        j.name
                    ));
                }
            }
            if parent.insert(j.child.link.clone(), i).is_some() {
                return err(format!(
                    "<link name=\"{}\"> is the child of two joints",
                    j.child.link
                ));
            }
            children.entry(j.parent.link.clone()).or_default().push(i);
        }
        Ok(Self {
            urdf,
            dir,
            links,
            parent,
            children,
        })
    }

    fn link(&self, name: &str) -> &urdf_rs::Link {
        &self.urdf.links[self.links[name]]
    }

    fn kids(&self, name: &str) -> &[usize] {
        self.children.get(name).map_or(&[], |v| v.as_slice())
    }

    /// The floating base (see the module docs).
    fn base(&self) -> Result<String, ImportError> {
        let roots: Vec<&String> = self
            .links
            .keys()
            .filter(|l| !self.parent.contains_key(*l))
            .collect();
        let mut base = match roots.as_slice() {
            [one] => (*one).clone(),
            [] => return err("no floating-base candidate: every <link> is a joint's child"),
            many => {
                return err(format!(
                    "no floating-base candidate: {} root links ({})",
                    many.len(),
                    many.iter()
                        .map(|s| s.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            }
        };
        while inertial(self.link(&base)).is_none() {
            match self.kids(&base) {
                [j] if matches!(
                    self.urdf.joints[*j].joint_type,
                    JointType::Fixed | JointType::Floating
                ) =>
                {
                    base = self.urdf.joints[*j].child.link.clone();
                }
                _ => {
                    return err(format!(
                        "no floating-base candidate: the root <link name=\"{base}\"> has no \
                         <inertial> and more than one child"
                    ))
                }
            }
        }
        Ok(base)
    }

    /// The joints from `base` down to `leaf`.
    fn path(&self, base: &str, leaf: &str) -> Option<Vec<usize>> {
        let mut out = Vec::new();
        let mut at = leaf.to_string();
        while at != base {
            let j = *self.parent.get(&at)?;
            out.push(j);
            at = self.urdf.joints[j].parent.link.clone();
        }
        out.reverse();
        Some(out)
    }

    /// Every link's pose in the base frame at zero joint angles.
    fn zero_poses(&self, base: &str) -> BTreeMap<String, Pose> {
        let mut out = BTreeMap::new();
        let mut stack = vec![(base.to_string(), Pose::IDENTITY)];
        while let Some((l, p)) = stack.pop() {
            for &j in self.kids(&l) {
                let joint = &self.urdf.joints[j];
                stack.push((joint.child.link.clone(), p.then(&pose_of(&joint.origin))));
            }
            out.insert(l, p);
        }
        out
    }

    /// The bodies of `link` and of every link below it through joints not in `skip`, in the
    /// frame of `link` (moved by `at`).
    fn subtree_body(&self, link: &str, at: &Pose, skip: &BTreeSet<usize>, acc: &mut Body) {
        if let Some(b) = inertial(self.link(link)) {
            *acc = acc.merged(&b.moved(at));
        }
        for &j in self.kids(link) {
            if skip.contains(&j) {
                continue;
            }
            let joint = &self.urdf.joints[j];
            let p = at.then(&pose_of(&joint.origin));
            self.subtree_body(&joint.child.link, &p, skip, acc);
        }
    }
}

/// One leg as imported: the six joints and links of the model, the ankle link's URDF links.
struct LegImport {
    specs: Vec<LinkOut>,
    /// URDF links rigidly part of the foot, with their poses in the ankle frame.
    foot: Vec<(String, Pose)>,
    /// The ankle link (the last moved one).
    ankle: String,
    /// The links fixed to the base before the first joint, in the base frame.
    pre: Body,
}

/// A leg link as written to the robot file.
struct LinkOut {
    joint: String,
    link: String,
    origin: Pose,
    axis: Vec3,
    range: Option<[f64; 2]>,
    effort: Option<f64>,
    velocity: Option<f64>,
    body: Body,
}

fn leg(
    t: &Tree,
    base: &str,
    leaf: &str,
    on_legs: &BTreeSet<usize>,
    pre_done: &mut BTreeSet<String>,
) -> Result<LegImport, ImportError> {
    let path = t
        .path(base, leaf)
        .ok_or_else(|| ImportError(format!("<link name=\"{leaf}\"> is not below the base")))?;
    let moving: Vec<usize> = path
        .iter()
        .copied()
        .filter(|&j| t.urdf.joints[j].joint_type != JointType::Fixed)
        .collect();
    for &j in &moving {
        let joint = &t.urdf.joints[j];
        if !matches!(
            joint.joint_type,
            JointType::Revolute | JointType::Continuous
        ) {
            return err(format!(
                "<joint name=\"{}\" type=\"{}\">: a leg's joints must be revolute",
                joint.name,
                format!("{:?}", joint.joint_type).to_lowercase()
            ));
        }
    }
    if moving.len() != 6 {
        let names: Vec<&str> = moving
            .iter()
            .map(|&j| t.urdf.joints[j].name.as_str())
            .collect();
        return err(format!(
            "the leg to <link name=\"{leaf}\"> has {} revolute joints ({}): six are needed, hip \
             to ankle",
            moving.len(),
            names.join(", ")
        ));
    }
    let mut specs: Vec<LinkOut> = Vec::new();
    let mut at = Pose::IDENTITY; // the current URDF link in the current model link's frame
    let mut foot = Vec::new();
    let mut pre = Body::NONE;
    for &j in &path {
        let joint = &t.urdf.joints[j];
        let o = at.then(&pose_of(&joint.origin));
        let child = &joint.child.link;
        if joint.joint_type == JointType::Fixed {
            at = o;
        } else {
            let l = &joint.limit;
            let range = (joint.joint_type == JointType::Revolute
                && l.lower.is_finite()
                && l.upper.is_finite()
                && l.lower < l.upper)
                .then_some([l.lower, l.upper]);
            let n = norm(joint.axis.xyz.0);
            specs.push(LinkOut {
                joint: joint.name.clone(),
                link: child.clone(),
                origin: o,
                axis: joint.axis.xyz.0.map(|v| v / n),
                range,
                effort: (l.effort > 0.0 && l.effort.is_finite()).then_some(l.effort),
                velocity: (l.velocity > 0.0 && l.velocity.is_finite()).then_some(l.velocity),
                body: Body::NONE,
            });
            at = Pose::IDENTITY;
        }
        // The link's own body and everything hanging from it off the legs.
        // (A link fixed to the base before both legs' first joints is merged once.)
        let acc = match specs.last_mut() {
            Some(s) => Some(&mut s.body),
            None => pre_done.insert(child.clone()).then_some(&mut pre),
        };
        if let Some(acc) = acc {
            t.subtree_body(child, &at, on_legs, acc);
        }
        if specs.len() == 6 {
            foot.push((child.clone(), at));
        }
    }
    // Links fixed below the ankle off the path belong to the foot too.
    let ankle = &t.urdf.joints[moving[5]].child.link;
    let mut stack = vec![(ankle.clone(), Pose::IDENTITY)];
    while let Some((l, p)) = stack.pop() {
        if !foot.iter().any(|(n, _)| *n == l) {
            foot.push((l.clone(), p));
        }
        for &j in t.kids(&l) {
            let joint = &t.urdf.joints[j];
            if joint.joint_type == JointType::Fixed {
                stack.push((joint.child.link.clone(), p.then(&pose_of(&joint.origin))));
            }
        }
    }
    for (i, s) in specs.iter().enumerate() {
        let last_or_apart = i == 5 || specs[i + 1].origin.p != [0.0; 3];
        if s.body.mass <= 0.0 && last_or_apart {
            return err(format!(
                "<link name=\"{}\"> (moved by <joint name=\"{}\">) has no <inertial>: the \
                 engine cannot move a massless body",
                s.link, s.joint
            ));
        }
    }
    Ok(LegImport {
        specs,
        foot,
        ankle: ankle.clone(),
        pre,
    })
}

/// What an import produced: the robot file's text and the robot read back from it.
pub struct Imported {
    /// The robot file.
    pub toml: String,
    /// The robot it describes.
    pub robot: Robot,
    /// What the import warns about (a sole frame it did not use, and why).
    pub warnings: Vec<String>,
}

/// Finds `package://NAME/…`: the directory `NAME` above `dir`, or on `ROS_PACKAGE_PATH`.
pub(crate) fn resolve(filename: &str, dir: &Path) -> Result<PathBuf, ImportError> {
    if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, tail) = rest.split_once('/').unwrap_or((rest, ""));
        let env = std::env::var("ROS_PACKAGE_PATH").unwrap_or_default();
        let roots = dir
            .ancestors()
            .filter(|a| a.file_name().is_some_and(|n| n == pkg))
            .map(Path::to_path_buf)
            .chain(
                env.split(':')
                    .filter(|s| !s.is_empty())
                    .map(|s| Path::new(s).join(pkg)),
            );
        for r in roots {
            let p = r.join(tail);
            if p.exists() {
                return Ok(p);
            }
        }
        return err(format!(
            "<mesh filename=\"{filename}\">: package `{pkg}` not found above {} or on \
             ROS_PACKAGE_PATH",
            dir.display()
        ));
    }
    let p = Path::new(filename.strip_prefix("file://").unwrap_or(filename));
    Ok(if p.is_absolute() {
        p.into()
    } else {
        dir.join(p)
    })
}

/// Imports a URDF file; `soles`: the left and right foot links, if given.
pub fn import(path: &Path, soles: Option<[&str; 2]>) -> Result<Imported, ImportError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| ImportError(format!("{}: {e}", path.display())))?;
    // An empty `<texture/>` (a material without an image, as some descriptions write it) is
    // no texture: the reader wants a file name, and the import reads no material.
    let text = text.replace("<texture />", "").replace("<texture/>", "");
    if let Some(problem) = xml::xml_problem(&text) {
        return Err(ImportError(format!(
            "{}: not a readable URDF: {problem}",
            path.display()
        )));
    }
    let urdf = urdf_rs::read_from_string(&text)
        .map_err(|e| ImportError(format!("{}: not a readable URDF: {e}", path.display())))?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let t = Tree::new(urdf, dir)?;
    let base = t.base()?;
    let zero = t.zero_poses(&base);
    // The feet.
    let by_geometry = match soles {
        None => feet::by_geometry(&t, &base, &zero)?,
        Some(_) => None,
    };
    let leaves: [String; 2] = match soles {
        Some(names) => {
            for n in names {
                if !zero.contains_key(n) {
                    return err(format!("--sole: no <link name=\"{n}\"> below the base"));
                }
            }
            names.map(String::from)
        }
        None if by_geometry.is_some() => by_geometry.unwrap_or_default(),
        None => {
            let mut leaves: Vec<(&String, &Pose)> =
                zero.iter().filter(|(l, _)| t.kids(l).is_empty()).collect();
            leaves.sort_by(|a, b| a.1.p[2].total_cmp(&b.1.p[2]));
            let left = leaves.iter().find(|(_, p)| p.p[1] > 0.0);
            let right = leaves.iter().find(|(_, p)| p.p[1] < 0.0);
            match (left, right) {
                (Some(l), Some(r)) => [l.0.clone(), r.0.clone()],
                _ => return err("no pair of feet: no lowest leaf link on each side of the base"),
            }
        }
    };
    if soles.is_none() {
        let at = |l: &str| zero.get(l).map_or([0.0; 3], |p| p.p);
        let below = |p: Vec3| -p[2] > p[0].abs().max(p[1].abs());
        if !leaves.iter().all(|l| below(at(l))) {
            return err(format!(
                "no pair of feet below the base: the lowest bodies on each side, <link name=\"{}\"> \
                 at {:?} and <link name=\"{}\"> at {:?} m in the frame of the \
                 base <link name=\"{base}\"> at zero joint angles, do not lie below it (the \
                 base's z axis must point up)",
                leaves[0],
                at(&leaves[0]).map(round_mm),
                leaves[1],
                at(&leaves[1]).map(round_mm),
            ));
        }
    }
    // A robot whose knees bend forward of the base's x axis faces −x: the base is turned.
    let mut warnings = Vec::new();
    let (mut t, mut zero, mut leaves) = (t, zero, leaves);
    if let Some(knee) = feet::knee_bends_forward(&t, &base, &zero, &leaves[0]) {
        feet::turn_base(&mut t, &base);
        zero = t.zero_poses(&base);
        if soles.is_none() {
            leaves.swap(0, 1);
        }
        warnings.push(format!(
            "the knee <joint name=\"{knee}\"> bends forward of the x axis of the base <link \
             name=\"{base}\">: the robot faces its −x, and the import turns the base frame by \
             180° about z (the robot walks along the URDF's −x)"
        ));
    }
    let paths: Vec<Vec<usize>> = leaves
        .iter()
        .map(|l| t.path(&base, l).unwrap_or_default())
        .collect();
    let on_legs: BTreeSet<usize> = paths.iter().flatten().copied().collect();
    let mut pre_done = BTreeSet::new();
    let legs = [
        leg(&t, &base, &leaves[0], &on_legs, &mut pre_done)?,
        leg(&t, &base, &leaves[1], &on_legs, &mut pre_done)?,
    ];
    // The waist and the upper body.
    let waist = inertial(t.link(&base)).ok_or_else(|| {
        ImportError(format!(
            "<link name=\"{base}\"> (the base) has no <inertial>"
        ))
    })?;
    let mut trunk = Body::NONE;
    for &j in t.kids(&base) {
        if on_legs.contains(&j) {
            continue;
        }
        let joint = &t.urdf.joints[j];
        t.subtree_body(
            &joint.child.link,
            &pose_of(&joint.origin),
            &on_legs,
            &mut trunk,
        );
    }
    for l in &legs {
        trunk = trunk.merged(&l.pre);
    }
    positive(&waist, &format!("<link name=\"{base}\"> (the base)"))?;
    positive(&trunk, "the upper body (every link off the legs, merged)")?;
    for s in legs.iter().flat_map(|l| &l.specs) {
        positive(
            &s.body,
            &format!("<link name=\"{}\"> (with the links fixed to it)", s.link),
        )?;
    }
    // Soles.
    let mut sole_out = [Pose::IDENTITY; 2];
    let mut size = [f64::INFINITY; 2];
    let mut from = Vec::new();
    for (k, l) in legs.iter().enumerate() {
        let level = zero.get(&l.ankle).map_or(IDENTITY, |p| p.r);
        let frames: Vec<sole::Frame> = match soles {
            Some(_) if leaves[k] != l.ankle => l
                .foot
                .iter()
                .filter(|(n, _)| *n == leaves[k])
                .map(|(n, p)| sole::Frame {
                    link: n.clone(),
                    pose: *p,
                    named: true,
                })
                .collect(),
            _ => l.foot[1..]
                .iter()
                .filter(|(n, _)| {
                    let link = t.link(n);
                    link.collision.is_empty() && link.visual.is_empty()
                })
                .map(|(n, p)| sole::Frame {
                    link: n.clone(),
                    pose: *p,
                    named: false,
                })
                .collect(),
        };
        let hip = zero.get(&l.specs[0].link).map_or([0.0; 3], |p| p.p);
        let ankle = zero.get(&l.ankle).map_or([0.0; 3], |p| p.p);
        let s = sole::sole(&t, &l.foot, &frames, &level, norm(sub(ankle, hip)))?;
        sole_out[k] = Pose {
            p: s.centre,
            r: s.rotation,
        };
        size[0] = size[0].min(s.size[0]);
        size[1] = size[1].min(s.size[1]);
        warnings.extend(s.warnings);
        from.push(s.from);
    }
    let parts = Parts {
        waist,
        trunk,
        legs: [&legs[0].specs, &legs[1].specs],
        soles: sole_out,
        sole_size: size,
        sole_from: from,
    };
    let name = if t.urdf.name.is_empty() {
        path.file_stem()
            .map_or("robot".into(), |s| s.to_string_lossy().into())
    } else {
        t.urdf.name.clone()
    };
    let mut imported = write(&name, path, &parts)?;
    imported.warnings.splice(0..0, warnings);
    Ok(imported)
}

/// The model's parts as imported.
struct Parts<'a> {
    waist: Body,
    trunk: Body,
    legs: [&'a [LinkOut]; 2],
    soles: [Pose; 2],
    sole_size: [f64; 2],
    /// Where each sole centre comes from.
    sole_from: Vec<String>,
}

pub(super) fn round_mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// The workspace radius at the walking height: `√((0.97 L)² − h²)`.
fn workspace(leg: f64, h: f64) -> f64 {
    ((REACH_MARGIN * leg).powi(2) - h * h).max(0.0).sqrt()
}

fn tree_of(multibody: &str) -> Result<super::tree::Tree, ImportError> {
    let table: toml::Table = multibody.parse().map_err(|e| ImportError(format!("{e}")))?;
    table
        .get("multibody")
        .cloned()
        .ok_or_else(|| ImportError("no [multibody]".into()))?
        .try_into()
        .map_err(|e: toml::de::Error| ImportError(format!("{e}")))
}

fn write(name: &str, urdf: &Path, g: &Parts) -> Result<Imported, ImportError> {
    let hrp2 = Robot::hrp2();
    let gravity = hrp2.planner.params.gravity;
    // Zero angles: the sole centres, the hips and the leg length.
    let raw = tree_of(&multibody(g, 1.0))?
        .raw_model(gravity)
        .map_err(|e| ImportError(e.to_string()))?;
    let z = raw.leg_fk(Side::Left, &Pose::IDENTITY, &[0.0; 6]);
    let zr = raw.leg_fk(Side::Right, &Pose::IDENTITY, &[0.0; 6]);
    let step_width = round_mm(z.sole.p[1] - zr.sole.p[1]);
    let hip = z.links[0].p;
    let leg = norm(sub(z.ankle().p, hip));
    // The standing height: the largest drop within the legs' limits ([`posture`]).
    let (mut last, mut first) = (String::new(), None);
    let mut chosen = None;
    for drop in posture::DROPS {
        let waist_height = (-z.sole.p[2] - drop * leg).mul_add(1e4, 0.0).round() / 1e4;
        let mb = multibody(g, waist_height);
        match tree_of(&mb)?.model(gravity, step_width) {
            Err(e) => last = format!("the standing posture: {e}"),
            Ok(m) => match posture::outside_limits(&m, step_width) {
                Some(why) => {
                    first.get_or_insert_with(|| why.clone());
                    last = why;
                }
                None => {
                    chosen = Some((waist_height, mb, m, drop));
                    break;
                }
            },
        }
    }
    let Some((waist_height, mb, model, drop)) = chosen else {
        return err(format!(
            "no standing height keeps the legs within their limits (the waist {} down to {} \
             of the leg below the straight-legged height); at the straightest: {last}",
            posture::DROPS[0],
            posture::DROPS[posture::DROPS.len() - 1],
        ));
    };
    let cog = round_mm(
        model
            .stance_cog_height(step_width)
            .map_err(|e| ImportError(format!("the standing posture: {e}")))?,
    );
    // The reach: HRP-2's scaled by the workspace radii, shrunk until the legs reach every
    // corner of it ([`reach`]).
    let c = hrp2.model.closed_form.expect("HRP-2's leg shape");
    let r_hrp2 = workspace(c.thigh + c.shank, hrp2.model.waist_height - c.ankle_height);
    let h = (waist_height + hip[2]) - (z.ankle().p[2] - z.sole.p[2]);
    let mut scale = (workspace(leg, h) / r_hrp2 * 100.0).floor() / 100.0;
    let written = |scale: f64| -> Result<(String, Robot), ImportError> {
        let planner = Planner {
            cog_height: cog,
            gravity,
            sole: g.sole_size.map(|v| (v * 1000.0).floor() / 1000.0),
            step_width,
            step_height: round_mm(0.05 * scale),
            scale,
        };
        let toml = format!("{}{}", planner_part(name, urdf, &planner), mb);
        let robot =
            Robot::from_toml(&toml).map_err(|e| ImportError(format!("the written file: {e}")))?;
        Ok((toml, robot))
    };
    let (toml, robot) = loop {
        let (toml, robot) = written(scale)?;
        match reach::unreached(&robot.model, &robot.planner.reach) {
            None => break (toml, robot),
            Some(why) if scale <= 0.1 => {
                return err(format!(
                    "the reach limits: even at {scale} of HRP-2's, {why}"
                ))
            }
            Some(_) => scale = ((scale - 0.01) * 100.0).round() / 100.0,
        }
    };
    let warnings = first
        .map(|why| {
            let here = posture::heaviest(&model, step_width).unwrap_or_default();
            format!(
                "the waist stands {:.1} % of the leg below the straight-legged height, not \
                 HRP-2's {:.1} %: at {:.1} %, {why}; here {here}",
                100.0 * drop,
                100.0 * KNEE_DROP,
                100.0 * KNEE_DROP
            )
        })
        .into_iter()
        .collect();
    Ok(Imported {
        toml,
        robot,
        warnings,
    })
}
