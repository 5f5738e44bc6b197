//! Vectors, rotations and rigid-body poses of the multi-body model: world x forward, y left,
//! z up; `R_x(a)`, `R_y(a)`, `R_z(a)` are the elementary right-handed rotations and `R(a, θ)`
//! the rotation by `θ` about the unit axis `a` (Rodrigues: `I + sin θ [a]× + (1 − cos θ) [a]×²`).
//! A URDF `rpy = (r, p, y)` is `R_z(y) R_y(p) R_x(r)`.

use planner_core::gait::FootPose;

/// A 3-vector.
pub type Vec3 = [f64; 3];
/// A 3×3 matrix, row-major (`m[row][column]`).
pub type Mat3 = [[f64; 3]; 3];
/// The six joint angles of one leg \[rad\]: hip yaw, hip roll, hip pitch, knee, ankle pitch,
/// ankle roll.
pub type LegAngles = [f64; 6];

pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn scale(s: f64, a: Vec3) -> Vec3 {
    [s * a[0], s * a[1], s * a[2]]
}

pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm(a: Vec3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

pub fn mul_mv(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

pub fn mul_mm(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

pub fn transpose(m: &Mat3) -> Mat3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

/// Rotation about x by `a` \[rad\].
pub fn rot_x(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Rotation about y by `a` \[rad\].
pub fn rot_y(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Rotation about z by `a` \[rad\].
pub fn rot_z(a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// The rotation vector of a rotation matrix (axis × angle, angle in \[0, π)); accurate for
/// the small rotations between two ticks.
pub fn log_so3(r: &Mat3) -> Vec3 {
    let v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let s = 0.5 * norm(v); // sin θ
    let c = 0.5 * (r[0][0] + r[1][1] + r[2][2] - 1.0); // cos θ
    let theta = s.atan2(c);
    let k = if s > 1e-9 {
        theta / (2.0 * s)
    } else {
        // θ / (2 sin θ) = 1/2 + θ²/12 + O(θ⁴)
        0.5 + theta * theta / 12.0
    };
    scale(k, v)
}

/// Wraps an angle to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let w = a.sin().atan2(a.cos());
    if w <= -core::f64::consts::PI {
        w + 2.0 * core::f64::consts::PI
    } else {
        w
    }
}

/// A rigid-body pose: position and orientation (body-to-world rotation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position \[m\].
    pub p: Vec3,
    /// Orientation: columns are the body axes in the world frame.
    pub r: Mat3,
}

impl Pose {
    /// An upright pose (roll = pitch = 0) at `(x, y, z)` with heading `yaw`.
    pub fn upright(x: f64, y: f64, z: f64, yaw: f64) -> Self {
        Self {
            p: [x, y, z],
            r: rot_z(yaw),
        }
    }

    /// The pose of a sole centre from a reference foot pose (flat sole).
    pub fn sole(f: &FootPose<f64>) -> Self {
        Self::upright(f.x, f.y, f.z, f.yaw)
    }

    /// A point given in this frame, in the world frame.
    pub fn apply(&self, v: Vec3) -> Vec3 {
        add(self.p, mul_mv(&self.r, v))
    }
}

/// The identity rotation.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Rotation by `angle` about the unit `axis` (Rodrigues); the elementary rotations for the
/// coordinate axes, exactly.
pub fn rot_axis(axis: Vec3, angle: f64) -> Mat3 {
    match axis {
        [1.0, 0.0, 0.0] => rot_x(angle),
        [0.0, 1.0, 0.0] => rot_y(angle),
        [0.0, 0.0, 1.0] => rot_z(angle),
        [x, y, z] => {
            let (s, c) = angle.sin_cos();
            let t = 1.0 - c;
            [
                [c + t * x * x, t * x * y - s * z, t * x * z + s * y],
                [t * x * y + s * z, c + t * y * y, t * y * z - s * x],
                [t * x * z - s * y, t * y * z + s * x, c + t * z * z],
            ]
        }
    }
}

/// The rotation of a URDF `rpy`: `R_z(yaw) R_y(pitch) R_x(roll)`.
pub fn rot_rpy(rpy: Vec3) -> Mat3 {
    if rpy == [0.0; 3] {
        return IDENTITY;
    }
    mul_mm(&mul_mm(&rot_z(rpy[2]), &rot_y(rpy[1])), &rot_x(rpy[0]))
}

impl Pose {
    /// The identity pose.
    pub const IDENTITY: Pose = Pose {
        p: [0.0; 3],
        r: IDENTITY,
    };

    /// The pose `other`, given in this frame, in the world frame.
    pub fn then(&self, other: &Pose) -> Pose {
        Pose {
            p: self.apply(other.p),
            r: if other.r == IDENTITY {
                self.r
            } else {
                mul_mm(&self.r, &other.r)
            },
        }
    }

    /// The inverse pose.
    pub fn inverse(&self) -> Pose {
        let rt = transpose(&self.r);
        Pose {
            p: scale(-1.0, mul_mv(&rt, self.p)),
            r: rt,
        }
    }
}
