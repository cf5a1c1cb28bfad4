//! The two 3-vector helpers attach needs beyond nalgebra's operators (the closest point on a
//! bone is symcorr-mesh's `geometry::closest_on_segment`). Both keep the operation
//! order the measured labels were produced with (`v · (1/|v|)`, not nalgebra's `v / |v|`).

use nalgebra::{Point3, Vector3};

/// Joint positions indexed by [`crate::Joint::index`].
pub(crate) type Joints = [Point3<f64>; crate::Joint::COUNT];

/// `v` scaled to unit length, or `None` if it is (numerically) zero or not finite.
#[inline]
pub(crate) fn unit(v: Vector3<f64>) -> Option<Vector3<f64>> {
    let l = v.norm();
    (l > 1e-12 && l.is_finite()).then(|| v * (1.0 / l))
}

/// The bones between usable joints as segments `(parent, child)`: what coverage, the fit checks
/// and the rotation search measure distances to.
pub(crate) fn bone_segments(p: &Joints, usable: &[bool; 20]) -> Vec<(Point3<f64>, Point3<f64>)> {
    crate::BONES
        .iter()
        .filter(|b| usable[b.parent.index()] && usable[b.child.index()])
        .map(|b| (p[b.parent.index()], p[b.child.index()]))
        .collect()
}

/// Distance from `x` to the nearest of `bones` (infinite without bones).
pub(crate) fn distance_to_bones(x: &Point3<f64>, bones: &[(Point3<f64>, Point3<f64>)]) -> f64 {
    bones
        .iter()
        .map(|(a, b)| symcorr_mesh::geometry::closest_on_segment(x, a, b).1)
        .fold(f64::INFINITY, f64::min)
}

/// `a + t (b − a)` (nalgebra's `lerp` is `(1 − t) a + t b`, which rounds differently).
#[inline]
pub(crate) fn lerp(a: &Point3<f64>, b: &Point3<f64>, t: f64) -> Point3<f64> {
    a + (b - a) * t
}
