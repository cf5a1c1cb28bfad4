//! A skeleton: one position, confidence and provenance per joint.

use crate::{Bone, Joint, LimbPair};
use nalgebra::{Point3, Vector3};

/// A canonical 20-joint skeleton: one position (metres unless stated otherwise, in whatever
/// frame the source used) and one confidence in [0, 1] per joint. Confidence 0 means the joint
/// was not tracked; its position is then an estimate (see `interpolated`).
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    /// Position per joint, indexed by [`Joint::index`].
    pub positions: [Point3<f64>; Joint::COUNT],
    /// Tracking confidence per joint in [0, 1].
    pub confidence: [f64; Joint::COUNT],
    /// Joints whose position was not measured but interpolated along the bone chain by an importer.
    pub interpolated: [bool; Joint::COUNT],
    /// How far the head is turned against the chest, in radians, about the neck → head axis
    /// (shoulder centre → head), when the tracker reports the face (the Azure Kinect's nose and
    /// ears); positive turns the face towards the subject's left (counter-clockwise seen from
    /// above), within ±π/2. The joints do not show it: a head turns about its own bone. A
    /// relative angle, so a rigid motion of the positions keeps it and a reflection negates it.
    /// `None`: not reported.
    pub head_turn: Option<f64>,
}

impl Skeleton {
    /// A skeleton with all joints at the given positions, confidence 1, nothing interpolated.
    pub fn from_positions(positions: [Point3<f64>; Joint::COUNT]) -> Self {
        Skeleton {
            positions,
            confidence: [1.0; Joint::COUNT],
            interpolated: [false; Joint::COUNT],
            head_turn: None,
        }
    }

    /// [`Skeleton::from_positions`] from plain `[x, y, z]` arrays, in [`Joint::ALL`] order.
    ///
    /// ```
    /// use symcorr_skeleton::{Joint, Skeleton};
    /// let mut xyz = [[0.0; 3]; Joint::COUNT];
    /// xyz[Joint::Head.index()] = [0.0, 1.7, 0.0];
    /// let s = Skeleton::from_arrays(xyz);
    /// assert_eq!(s.position(Joint::Head).y, 1.7);
    /// ```
    pub fn from_arrays(positions: [[f64; 3]; Joint::COUNT]) -> Self {
        Skeleton::from_positions(positions.map(Point3::from))
    }

    /// The positions as plain `[x, y, z]` arrays in [`Joint::ALL`] order (what file formats
    /// hold).
    pub fn to_arrays(&self) -> [[f64; 3]; Joint::COUNT] {
        self.positions.map(|p| p.into())
    }

    /// Position of joint `j`.
    pub fn position(&self, j: Joint) -> Point3<f64> {
        self.positions[j.index()]
    }

    /// Whether joint `j` says where it is: tracked (confidence > 0) or interpolated along its
    /// bone chain by an importer. An untracked joint's position — (0, 0, 0) as the Kinect SDK
    /// writes it, or a stale one — says nothing.
    ///
    /// ```
    /// use symcorr_skeleton::{Joint, Skeleton};
    /// let mut s = Skeleton::from_arrays([[0.0, 1.0, 2.0]; Joint::COUNT]);
    /// s.confidence[Joint::Head.index()] = 0.0;
    /// assert!(!s.tracks(Joint::Head) && s.tracks(Joint::Spine) && s.tracks_any());
    /// s.confidence = [0.0; Joint::COUNT];
    /// assert!(!s.tracks_any()); // the tracker lost the body
    /// ```
    pub fn tracks(&self, j: Joint) -> bool {
        self.confidence[j.index()] > 0.0 || self.interpolated[j.index()]
    }

    /// Whether any joint [`Skeleton::tracks`].
    pub fn tracks_any(&self) -> bool {
        Joint::ALL.into_iter().any(|j| self.tracks(j))
    }

    /// The vector from a bone's parent joint to its child joint.
    pub fn bone_vector(&self, bone: Bone) -> Vector3<f64> {
        self.position(bone.child) - self.position(bone.parent)
    }

    /// The skeleton with left and right exchanged (positions unchanged, names swapped): what a
    /// left/right-mirrored tracker would have reported.
    pub fn swap_sides(&self) -> Skeleton {
        let mut out = self.clone();
        for j in Joint::ALL {
            out.positions[j.index()] = self.positions[j.mirror().index()];
            out.confidence[j.index()] = self.confidence[j.mirror().index()];
            out.interpolated[j.index()] = self.interpolated[j.mirror().index()];
        }
        out
    }

    /// The skeleton with the left and right joints of one limb pair exchanged (positions
    /// unchanged, names swapped): what a tracker that swapped that pair alone reported.
    ///
    /// ```
    /// use symcorr_skeleton::{Joint, LimbPair, Skeleton};
    /// let mut xyz = [[0.0, 1.0, 2.0]; Joint::COUNT];
    /// xyz[Joint::KneeLeft.index()] = [0.1, 0.5, 2.0];
    /// let s = Skeleton::from_arrays(xyz).swap_limbs(LimbPair::Legs);
    /// assert_eq!(s.position(Joint::KneeRight).x, 0.1);
    /// assert_eq!(s.position(Joint::KneeLeft).x, 0.0);
    /// ```
    pub fn swap_limbs(&self, pair: LimbPair) -> Skeleton {
        let mut out = self.clone();
        for l in pair.left_joints() {
            let (a, b) = (l.index(), l.mirror().index());
            out.positions.swap(a, b);
            out.confidence.swap(a, b);
            out.interpolated.swap(a, b);
        }
        out
    }

    /// The skeleton turned by `angle` radians about its spine — the axis through the hip
    /// centre towards the shoulder centre — right-handed about that axis (confidence and
    /// provenance kept). Turned by π, a skeleton facing the camera faces away from it: what a
    /// log in a frame turned about the vertical, or a tracker that took a back for a front,
    /// reports. `None` when the hip and shoulder centres coincide.
    ///
    /// ```
    /// use approx::assert_relative_eq;
    /// use symcorr_skeleton::{Joint, Skeleton};
    /// let mut xyz = [[0.0, 1.0, 3.0]; Joint::COUNT];
    /// xyz[Joint::HipCenter.index()] = [0.0, 0.0, 3.0];
    /// xyz[Joint::ShoulderCenter.index()] = [0.0, 0.5, 3.0];
    /// xyz[Joint::FootLeft.index()] = [0.1, -0.9, 2.9]; // toes towards the camera at the origin
    /// let s = Skeleton::from_arrays(xyz).turned_about_spine(std::f64::consts::PI).unwrap();
    /// let foot = s.position(Joint::FootLeft);
    /// assert_relative_eq!(foot.coords, nalgebra::Vector3::new(-0.1, -0.9, 3.1), epsilon = 1e-12);
    /// ```
    pub fn turned_about_spine(&self, angle: f64) -> Option<Skeleton> {
        let pivot = self.position(Joint::HipCenter);
        let axis = nalgebra::Unit::try_new(self.position(Joint::ShoulderCenter) - pivot, 1e-12)?;
        let r = nalgebra::Rotation3::from_axis_angle(&axis, angle);
        Some(self.map_positions(|p| pivot + r * (p - pivot)))
    }

    /// The skeleton with every position mapped by `f` (confidence, provenance and the head's
    /// turn kept: `f` is a rigid motion).
    pub fn map_positions(&self, f: impl Fn(Point3<f64>) -> Point3<f64>) -> Skeleton {
        Skeleton {
            positions: self.positions.map(f),
            ..self.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swapping_sides_twice_is_the_identity() {
        let s = Skeleton::from_arrays(std::array::from_fn(|i| [i as f64, 2.0 * i as f64, 0.5]));
        let w = s.swap_sides();
        assert_eq!(w.position(Joint::KneeLeft), s.position(Joint::KneeRight));
        assert_eq!(w.position(Joint::Head), s.position(Joint::Head));
        assert_eq!(w.swap_sides(), s);
        let b = Bone::new(Joint::HipCenter, Joint::Spine);
        assert_eq!(s.bone_vector(b), Vector3::new(1.0, 2.0, 0.0));
    }
}
