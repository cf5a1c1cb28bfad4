//! Small 3-D helpers: row-major 3×3 matrices, rigid transforms, Blender Euler angles and the
//! change of frame between MakeHuman's OBJ frame (y up) and Blender's armature frame (z up).

/// A 3-vector.
pub type V3 = [f64; 3];
/// A row-major 3×3 matrix (`m[row][col]`).
pub type M3 = [[f64; 3]; 3];

/// The identity matrix.
pub const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

// Vector arithmetic has one owner in the workspace: symcorr-mesh.
#[cfg_attr(not(test), allow(unused_imports))]
pub(crate) use symcorr_mesh::geometry::dist;
pub(crate) use symcorr_mesh::geometry::{add, cross, dot, norm, scale, sub};

pub(crate) fn normalize(a: V3) -> V3 {
    let n = norm(a);
    if n > 0.0 {
        scale(a, 1.0 / n)
    } else {
        a
    }
}
/// Matrix product `a · b`.
pub fn mul(a: &M3, b: &M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
        }
    }
    m
}

/// Matrix–vector product `m · v`.
pub fn mul_v(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// Transpose (the inverse of a rotation).
pub fn transpose(m: &M3) -> M3 {
    let mut t = [[0.0; 3]; 3];
    for (r, row) in m.iter().enumerate() {
        for (c, x) in row.iter().enumerate() {
            t[c][r] = *x;
        }
    }
    t
}

/// Rotation by `angle` radians about the unit `axis` (Rodrigues).
pub fn axis_angle(axis: V3, angle: f64) -> M3 {
    let [x, y, z] = normalize(axis);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// Blender's `XYZ` Euler rotation (the default rotation mode of pose bones and of
/// `rotation_euler` curves): X first, then Y, then Z, i.e. `R = Rz · Ry · Rx`.
pub fn euler_xyz(e: V3) -> M3 {
    let rx = axis_angle([1.0, 0.0, 0.0], e[0]);
    let ry = axis_angle([0.0, 1.0, 0.0], e[1]);
    let rz = axis_angle([0.0, 0.0, 1.0], e[2]);
    mul(&rz, &mul(&ry, &rx))
}

/// Blender's `vec_roll_to_mat3`: the rest orientation of a bone whose local +Y points along
/// `dir` (unit) after the shortest-arc rotation from +Y, then rolled by `roll` about `dir`.
/// Columns are the bone's local X, Y, Z axes in armature space.
pub fn vec_roll_to_mat3(dir: V3, roll: f64) -> M3 {
    let [x, y, z] = normalize(dir);
    let theta = 1.0 + y;
    let theta_alt = x * x + z * z;
    // Column-major in Blender; here b[row][col].
    let b: M3 = if theta > 1e-5 || theta_alt > 1e-9 {
        let theta = if theta <= 1e-5 {
            theta_alt * 0.5 + theta_alt * theta_alt * 0.125
        } else {
            theta
        };
        [
            [1.0 - x * x / theta, x, -x * z / theta],
            [-x, y, -z],
            [-x * z / theta, z, 1.0 - z * z / theta],
        ]
    } else {
        // dir is (anti-)parallel to −Y: Blender flips X and Y.
        [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
    };
    mul(&axis_angle([x, y, z], roll), &b)
}

/// A rigid transform `p ↦ r·p + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    /// Rotation.
    pub r: M3,
    /// Translation.
    pub t: V3,
}

impl Rigid {
    /// The identity transform.
    pub const IDENTITY: Rigid = Rigid {
        r: IDENTITY,
        t: [0.0; 3],
    };

    /// Applies the transform to a point.
    pub fn apply(&self, p: V3) -> V3 {
        add(mul_v(&self.r, p), self.t)
    }

    /// `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Rigid) -> Rigid {
        Rigid {
            r: mul(&self.r, &other.r),
            t: self.apply(other.t),
        }
    }

    /// The inverse transform (rotations are orthonormal).
    pub fn inverse(&self) -> Rigid {
        let rt = transpose(&self.r);
        Rigid {
            r: rt,
            t: scale(mul_v(&rt, self.t), -1.0),
        }
    }
}

/// MakeHuman OBJ frame (x = subject's left, y up, z = subject's front) → Blender frame
/// (x left, y back, z up), as Blender's OBJ importer does: `(x, y, z) ↦ (x, −z, y)`.
pub fn obj_to_blender(p: V3) -> V3 {
    [p[0], -p[2], p[1]]
}

/// Inverse of [`obj_to_blender`].
pub fn blender_to_obj(b: V3) -> V3 {
    [b[0], b[2], -b[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &M3, b: &M3) -> bool {
        (0..3).all(|r| (0..3).all(|c| (a[r][c] - b[r][c]).abs() < 1e-12))
    }

    #[test]
    fn roll_matrix_maps_y_to_direction_and_is_orthonormal() {
        for dir in [
            [0.3, 0.5, -0.8],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [1.0, 0.0, 0.0],
        ] {
            let m = vec_roll_to_mat3(dir, 0.7);
            let y = [m[0][1], m[1][1], m[2][1]];
            let d = normalize(dir);
            assert!(dist(y, d) < 1e-12, "{dir:?}");
            assert!(close(&mul(&m, &transpose(&m)), &IDENTITY));
        }
        // Roll 0 along +Y is the identity.
        assert!(close(&vec_roll_to_mat3([0.0, 1.0, 0.0], 0.0), &IDENTITY));
    }

    #[test]
    fn euler_order_is_x_then_y_then_z() {
        // Rotating +Y by 90° about X gives +Z; then 90° about Z leaves +Z unchanged.
        let m = euler_xyz([
            std::f64::consts::FRAC_PI_2,
            0.0,
            std::f64::consts::FRAC_PI_2,
        ]);
        assert!(dist(mul_v(&m, [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]) < 1e-12);
        // +X: about X unchanged, about Z → +Y.
        assert!(dist(mul_v(&m, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]) < 1e-12);
    }

    #[test]
    fn frames_round_trip() {
        let p = [0.1, -2.0, 3.5];
        assert_eq!(blender_to_obj(obj_to_blender(p)), p);
    }
}
