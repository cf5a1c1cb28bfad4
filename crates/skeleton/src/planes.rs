//! The skeleton's sagittal planes: the left/right planes of the pelvis, the torso and the
//! shoulders, spanned by the skeleton's own joints.

use crate::{Joint, Skeleton};
use nalgebra::{Point3, Vector3};

/// A plane through `origin` with a unit (or, when its joints coincide, zero) `normal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point of the plane.
    pub origin: Point3<f64>,
    /// Unit normal; the zero vector when the joints that define it coincide (every signed
    /// distance is then 0).
    pub normal: Vector3<f64>,
}

impl Plane {
    /// The plane through `origin` with normal along `normal` (normalised; zero stays zero).
    pub fn new(origin: Point3<f64>, normal: Vector3<f64>) -> Plane {
        Plane {
            origin,
            normal: normal.try_normalize(0.0).unwrap_or_else(Vector3::zeros),
        }
    }

    /// Signed distance of `x` from the plane, positive on the normal's side.
    pub fn signed_distance(&self, x: &Point3<f64>) -> f64 {
        (x - self.origin).dot(&self.normal)
    }
}

/// The three left/right (sagittal) planes of a skeleton's midline segments, each normal
/// pointing to the subject's **left**. Each is spanned by the segment's own joints, so the
/// planes follow a twisted spine:
///
/// * `pelvis`: through the midpoint of the hips, normal `hip_left − hip_right`;
/// * `shoulders`: through the midpoint of the shoulders, normal `shoulder_left − shoulder_right`
///   (the head's plane as far as joints tell: no joint says how the skull is turned);
/// * `torso`: through the mean of both midpoints, normal the sum of both unit normals.
///
/// ```
/// use nalgebra::Point3;
/// use symcorr_skeleton::{Joint, SagittalPlanes, Skeleton};
/// let mut xyz = [[0.0, 1.0, 0.0]; Joint::COUNT];
/// xyz[Joint::HipLeft.index()] = [0.1, 1.0, 0.0];
/// xyz[Joint::HipRight.index()] = [-0.1, 1.0, 0.0];
/// xyz[Joint::ShoulderLeft.index()] = [0.2, 1.5, 0.0];
/// xyz[Joint::ShoulderRight.index()] = [-0.2, 1.5, 0.0];
/// let planes = SagittalPlanes::of(&Skeleton::from_arrays(xyz));
/// // A point on the subject's left (+x here) is on the positive side.
/// assert!(planes.pelvis.signed_distance(&Point3::new(0.05, 1.0, 0.0)) > 0.0);
/// assert!((planes.torso.origin.y - 1.25).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagittalPlanes {
    /// The pelvis's plane (hip joints).
    pub pelvis: Plane,
    /// The torso's plane (between the pelvis's and the shoulders').
    pub torso: Plane,
    /// The shoulders' plane (shoulder joints).
    pub shoulders: Plane,
}

impl SagittalPlanes {
    /// The planes of `skeleton`.
    pub fn of(skeleton: &Skeleton) -> SagittalPlanes {
        let p = |j| skeleton.position(j);
        let pelvis = Plane::new(
            nalgebra::center(&p(Joint::HipLeft), &p(Joint::HipRight)),
            p(Joint::HipLeft) - p(Joint::HipRight),
        );
        let shoulders = Plane::new(
            nalgebra::center(&p(Joint::ShoulderLeft), &p(Joint::ShoulderRight)),
            p(Joint::ShoulderLeft) - p(Joint::ShoulderRight),
        );
        let torso = Plane::new(
            nalgebra::center(&pelvis.origin, &shoulders.origin),
            pelvis.normal + shoulders.normal,
        );
        SagittalPlanes {
            pelvis,
            torso,
            shoulders,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn coincident_joints_give_a_zero_normal() {
        let planes = SagittalPlanes::of(&Skeleton::from_arrays([[1.0, 2.0, 3.0]; Joint::COUNT]));
        assert_eq!(planes.pelvis.normal, Vector3::zeros());
        assert_eq!(
            planes.torso.signed_distance(&Point3::new(5.0, 0.0, 0.0)),
            0.0
        );
    }

    #[test]
    fn torso_normal_bisects_a_twisted_spine() {
        let mut xyz = [[0.0; 3]; Joint::COUNT];
        xyz[Joint::HipLeft.index()] = [1.0, 0.0, 0.0];
        xyz[Joint::HipRight.index()] = [-1.0, 0.0, 0.0];
        // Shoulders turned 90° about the vertical.
        xyz[Joint::ShoulderLeft.index()] = [0.0, 2.0, 1.0];
        xyz[Joint::ShoulderRight.index()] = [0.0, 2.0, -1.0];
        let planes = SagittalPlanes::of(&Skeleton::from_arrays(xyz));
        let h = 0.5f64.sqrt();
        assert_relative_eq!(
            planes.torso.normal,
            Vector3::new(h, 0.0, h),
            epsilon = 1e-12
        );
        assert_relative_eq!(planes.torso.origin, Point3::new(0.0, 1.0, 0.0));
        assert_relative_eq!(
            planes
                .shoulders
                .signed_distance(&Point3::new(3.0, 0.0, 0.25)),
            0.25
        );
    }
}
