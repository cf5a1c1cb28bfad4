//! The 20 joints of the canonical skeleton and its 19 bones.

use serde::{Deserialize, Serialize};

/// One of the 20 Kinect v1 joints, in Kinect SDK v1 order. Left/right are the subject's
/// anatomical sides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)] // the variants are the Kinect SDK's joint names
pub enum Joint {
    HipCenter,
    Spine,
    ShoulderCenter,
    Head,
    ShoulderLeft,
    ElbowLeft,
    WristLeft,
    HandLeft,
    ShoulderRight,
    ElbowRight,
    WristRight,
    HandRight,
    HipLeft,
    KneeLeft,
    AnkleLeft,
    FootLeft,
    HipRight,
    KneeRight,
    AnkleRight,
    FootRight,
}

impl Joint {
    /// Number of joints of the canonical skeleton.
    pub const COUNT: usize = 20;

    /// All 20 joints in Kinect SDK v1 order (the index is the SDK's `NUI_SKELETON_POSITION_INDEX`).
    pub const ALL: [Joint; Joint::COUNT] = [
        Joint::HipCenter,
        Joint::Spine,
        Joint::ShoulderCenter,
        Joint::Head,
        Joint::ShoulderLeft,
        Joint::ElbowLeft,
        Joint::WristLeft,
        Joint::HandLeft,
        Joint::ShoulderRight,
        Joint::ElbowRight,
        Joint::WristRight,
        Joint::HandRight,
        Joint::HipLeft,
        Joint::KneeLeft,
        Joint::AnkleLeft,
        Joint::FootLeft,
        Joint::HipRight,
        Joint::KneeRight,
        Joint::AnkleRight,
        Joint::FootRight,
    ];

    /// Index in [`Joint::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The `symcorr.joints/1` name, e.g. `"shoulder_left"`.
    pub const fn name(self) -> &'static str {
        match self {
            Joint::HipCenter => "hip_center",
            Joint::Spine => "spine",
            Joint::ShoulderCenter => "shoulder_center",
            Joint::Head => "head",
            Joint::ShoulderLeft => "shoulder_left",
            Joint::ElbowLeft => "elbow_left",
            Joint::WristLeft => "wrist_left",
            Joint::HandLeft => "hand_left",
            Joint::ShoulderRight => "shoulder_right",
            Joint::ElbowRight => "elbow_right",
            Joint::WristRight => "wrist_right",
            Joint::HandRight => "hand_right",
            Joint::HipLeft => "hip_left",
            Joint::KneeLeft => "knee_left",
            Joint::AnkleLeft => "ankle_left",
            Joint::FootLeft => "foot_left",
            Joint::HipRight => "hip_right",
            Joint::KneeRight => "knee_right",
            Joint::AnkleRight => "ankle_right",
            Joint::FootRight => "foot_right",
        }
    }

    /// Parses a `symcorr.joints/1` name.
    pub fn from_name(name: &str) -> Option<Joint> {
        Joint::ALL.into_iter().find(|j| j.name() == name)
    }

    /// The joint on the other side of the body (midline joints map to themselves).
    pub fn mirror(self) -> Joint {
        use Joint::*;
        match self {
            ShoulderLeft => ShoulderRight,
            ElbowLeft => ElbowRight,
            WristLeft => WristRight,
            HandLeft => HandRight,
            ShoulderRight => ShoulderLeft,
            ElbowRight => ElbowLeft,
            WristRight => WristLeft,
            HandRight => HandLeft,
            HipLeft => HipRight,
            KneeLeft => KneeRight,
            AnkleLeft => AnkleRight,
            FootLeft => FootRight,
            HipRight => HipLeft,
            KneeRight => KneeLeft,
            AnkleRight => AnkleLeft,
            FootRight => FootLeft,
            j => j,
        }
    }

    /// [`Joint::mirror`] if `swap`, else the joint itself.
    pub fn mirror_if(self, swap: bool) -> Joint {
        if swap {
            self.mirror()
        } else {
            self
        }
    }

    /// The parent joint in the kinematic tree rooted at the hip centre (`None` for the root).
    pub fn parent(self) -> Option<Joint> {
        BONES.iter().find(|b| b.child == self).map(|b| b.parent)
    }
}

/// A bone of the kinematic tree: `parent → child`, both joints of the canonical skeleton.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Bone {
    /// The joint nearer the root (the hip centre).
    pub parent: Joint,
    /// The joint further from the root.
    pub child: Joint,
}

impl Bone {
    /// Number of bones of the canonical skeleton.
    pub const COUNT: usize = 19;

    /// The bone `parent → child`.
    pub const fn new(parent: Joint, child: Joint) -> Bone {
        Bone { parent, child }
    }

    /// Index in [`BONES`], `None` if this pair of joints is not a bone of the skeleton.
    pub fn index(self) -> Option<usize> {
        BONES.iter().position(|&b| b == self)
    }

    /// The same bone on the other side of the body (midline bones map to themselves).
    pub fn mirror(self) -> Bone {
        Bone::new(self.parent.mirror(), self.child.mirror())
    }
}

/// The 19 bones of the Kinect v1 skeleton, parents before children.
pub const BONES: [Bone; Bone::COUNT] = {
    use Joint as J;
    [
        Bone::new(J::HipCenter, J::Spine),
        Bone::new(J::Spine, J::ShoulderCenter),
        Bone::new(J::ShoulderCenter, J::Head),
        Bone::new(J::ShoulderCenter, J::ShoulderLeft),
        Bone::new(J::ShoulderLeft, J::ElbowLeft),
        Bone::new(J::ElbowLeft, J::WristLeft),
        Bone::new(J::WristLeft, J::HandLeft),
        Bone::new(J::ShoulderCenter, J::ShoulderRight),
        Bone::new(J::ShoulderRight, J::ElbowRight),
        Bone::new(J::ElbowRight, J::WristRight),
        Bone::new(J::WristRight, J::HandRight),
        Bone::new(J::HipCenter, J::HipLeft),
        Bone::new(J::HipLeft, J::KneeLeft),
        Bone::new(J::KneeLeft, J::AnkleLeft),
        Bone::new(J::AnkleLeft, J::FootLeft),
        Bone::new(J::HipCenter, J::HipRight),
        Bone::new(J::HipRight, J::KneeRight),
        Bone::new(J::KneeRight, J::AnkleRight),
        Bone::new(J::AnkleRight, J::FootRight),
    ]
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joints_and_bones_are_consistent() {
        for (i, j) in Joint::ALL.iter().enumerate() {
            assert_eq!(j.index(), i);
            assert_eq!(Joint::from_name(j.name()), Some(*j));
            assert_eq!(j.mirror().mirror(), *j);
        }
        for (i, b) in BONES.iter().enumerate() {
            assert_eq!(b.index(), Some(i));
            assert_eq!(b.child.parent(), Some(b.parent));
            assert!(b.mirror().index().is_some());
            // Parents before children: the parent bone comes earlier.
            if let Some(pp) = b.parent.parent() {
                assert!(Bone::new(pp, b.parent).index().unwrap() < i);
            }
        }
        assert_eq!(Joint::HipCenter.parent(), None);
        assert_eq!(Bone::new(Joint::Head, Joint::Spine).index(), None);
    }
}

/// A left/right pair of limbs whose joints a tracker may exchange (a leg or arm swap: the
/// pair's left joints reported at the right limb and the other way round).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LimbPair {
    /// Shoulders, elbows, wrists and hands.
    Arms,
    /// Hips, knees, ankles and feet.
    Legs,
}

impl LimbPair {
    /// The pair's name in files and messages: `"arms"` or `"legs"`.
    ///
    /// ```
    /// assert_eq!(symcorr_skeleton::LimbPair::Legs.name(), "legs");
    /// ```
    pub const fn name(self) -> &'static str {
        match self {
            LimbPair::Arms => "arms",
            LimbPair::Legs => "legs",
        }
    }

    /// The left-side joints of the pair (their mirrors, [`Joint::mirror`], are the right side).
    ///
    /// ```
    /// use symcorr_skeleton::{Joint, LimbPair};
    /// assert_eq!(LimbPair::Legs.left_joints()[1], Joint::KneeLeft);
    /// ```
    pub const fn left_joints(self) -> [Joint; 4] {
        match self {
            LimbPair::Arms => [
                Joint::ShoulderLeft,
                Joint::ElbowLeft,
                Joint::WristLeft,
                Joint::HandLeft,
            ],
            LimbPair::Legs => [
                Joint::HipLeft,
                Joint::KneeLeft,
                Joint::AnkleLeft,
                Joint::FootLeft,
            ],
        }
    }
}
