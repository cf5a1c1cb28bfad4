//! Small 3-D helpers on nalgebra types: rigid transforms, Blender's bone frames and Euler
//! angles, and the change of frame between MakeHuman's OBJ frame (y up) and Blender's armature
//! frame (z up).

use nalgebra::{Matrix3, Vector3};

/// A 3-vector as assets, poses and meshes store it; convert with `Vector3::from` /
/// `Point3::from` for arithmetic.
pub type V3 = [f64; 3];
/// A 3×3 matrix.
pub type M3 = Matrix3<f64>;

/// `a` scaled to unit length (multiplied by the reciprocal of its norm); a zero vector is
/// returned unchanged.
pub(crate) fn normalize(a: Vector3<f64>) -> Vector3<f64> {
    let n = a.norm();
    if n > 0.0 {
        a * (1.0 / n)
    } else {
        a
    }
}

/// Rotation by `angle` radians about the unit `axis` (Rodrigues).
pub fn axis_angle(axis: Vector3<f64>, angle: f64) -> M3 {
    let [x, y, z] = normalize(axis).into();
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    // Arguments in row-major order.
    M3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    )
}

/// Blender's `XYZ` Euler rotation (the default rotation mode of pose bones and of
/// `rotation_euler` curves): X first, then Y, then Z, i.e. `R = Rz · Ry · Rx`.
pub fn euler_xyz(e: V3) -> M3 {
    let rx = axis_angle(Vector3::x(), e[0]);
    let ry = axis_angle(Vector3::y(), e[1]);
    let rz = axis_angle(Vector3::z(), e[2]);
    rz * (ry * rx)
}

/// Blender's `vec_roll_to_mat3`: the rest orientation of a bone whose local +Y points along
/// `dir` (unit) after the shortest-arc rotation from +Y, then rolled by `roll` about `dir`.
/// Columns are the bone's local X, Y, Z axes in armature space.
pub fn vec_roll_to_mat3(dir: Vector3<f64>, roll: f64) -> M3 {
    let dir = normalize(dir);
    let [x, y, z] = dir.into();
    let theta = 1.0 + y;
    let theta_alt = x * x + z * z;
    // Column-major in Blender; `M3::new` takes rows.
    let b = if theta > 1e-5 || theta_alt > 1e-9 {
        let theta = if theta <= 1e-5 {
            theta_alt * 0.5 + theta_alt * theta_alt * 0.125
        } else {
            theta
        };
        M3::new(
            1.0 - x * x / theta,
            x,
            -x * z / theta,
            -x,
            y,
            -z,
            -x * z / theta,
            z,
            1.0 - z * z / theta,
        )
    } else {
        // dir is (anti-)parallel to −Y: Blender flips X and Y.
        M3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0))
    };
    axis_angle(dir, roll) * b
}

/// A rigid transform `p ↦ r·p + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    /// Rotation.
    pub r: M3,
    /// Translation.
    pub t: Vector3<f64>,
}

impl Rigid {
    /// Applies the transform to a point.
    pub fn apply(&self, p: V3) -> V3 {
        (self.r * Vector3::from(p) + self.t).into()
    }

    /// `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Rigid) -> Rigid {
        Rigid {
            r: self.r * other.r,
            t: self.r * other.t + self.t,
        }
    }

    /// The inverse transform (rotations are orthonormal).
    pub fn inverse(&self) -> Rigid {
        let rt = self.r.transpose();
        Rigid {
            r: rt,
            t: -(rt * self.t),
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
        (a - b).amax() < 1e-12
    }

    #[test]
    fn roll_matrix_maps_y_to_direction_and_is_orthonormal() {
        for dir in [
            [0.3, 0.5, -0.8],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [1.0, 0.0, 0.0],
        ] {
            let dir = Vector3::from(dir);
            let m = vec_roll_to_mat3(dir, 0.7);
            assert!((m.column(1) - normalize(dir)).norm() < 1e-12, "{dir:?}");
            assert!(close(&(m * m.transpose()), &M3::identity()));
        }
        // Roll 0 along +Y is the identity.
        assert!(close(&vec_roll_to_mat3(Vector3::y(), 0.0), &M3::identity()));
    }

    #[test]
    fn euler_order_is_x_then_y_then_z() {
        // Rotating +Y by 90° about X gives +Z; then 90° about Z leaves +Z unchanged.
        let m = euler_xyz([
            std::f64::consts::FRAC_PI_2,
            0.0,
            std::f64::consts::FRAC_PI_2,
        ]);
        assert!((m * Vector3::y() - Vector3::z()).norm() < 1e-12);
        // +X: about X unchanged, about Z → +Y.
        assert!((m * Vector3::x() - Vector3::y()).norm() < 1e-12);
    }

    #[test]
    fn frames_round_trip() {
        let p = [0.1, -2.0, 3.5];
        assert_eq!(blender_to_obj(obj_to_blender(p)), p);
    }
}
