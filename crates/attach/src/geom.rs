//! The two 3-vector helpers attach needs beyond nalgebra's operators. Both keep the operation
//! order the measured labels were produced with (`v · (1/|v|)`, not nalgebra's `v / |v|`).

use nalgebra::{Point3, Vector3};

/// Joint positions indexed by [`crate::Joint::index`].
pub(crate) type Joints = [Point3<f64>; 20];

/// `v` scaled to unit length, or `None` if it is (numerically) zero or not finite.
#[inline]
pub(crate) fn unit(v: Vector3<f64>) -> Option<Vector3<f64>> {
    let l = v.norm();
    (l > 1e-12 && l.is_finite()).then(|| v * (1.0 / l))
}

/// Closest point to `p` on the segment `a–b`, and its distance.
#[inline]
pub(crate) fn closest_on_segment(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
) -> (Point3<f64>, f64) {
    let ab = b - a;
    let l2 = ab.dot(&ab);
    let t = if l2 > 0.0 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = a + ab * t;
    (q, (p - q).norm())
}

/// `a + t (b − a)` (nalgebra's `lerp` is `(1 − t) a + t b`, which rounds differently).
#[inline]
pub(crate) fn lerp(a: &Point3<f64>, b: &Point3<f64>, t: f64) -> Point3<f64> {
    a + (b - a) * t
}
