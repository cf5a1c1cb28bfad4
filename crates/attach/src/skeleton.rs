//! The canonical skeleton: Kinect v1's 20 joints, 19 bones, and the 17 body segments of
//! DESIGN.md (the two wrist→hand bones are merged into the forearms).

use serde::{Deserialize, Serialize};

/// One of the 20 Kinect v1 joints, in Kinect SDK v1 order. Left/right are the subject's
/// anatomical sides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
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
    /// All 20 joints in Kinect SDK v1 order (the index is the SDK's `NUI_SKELETON_POSITION_INDEX`).
    pub const ALL: [Joint; 20] = [
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
        BONES.iter().find(|b| b.1 == self).map(|b| b.0)
    }
}

/// One of the 17 body segments of DESIGN.md, numbered as there.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Segment {
    Pelvis = 0,
    Torso = 1,
    Head = 2,
    ClavicleLeft = 3,
    ClavicleRight = 4,
    UpperArmLeft = 5,
    UpperArmRight = 6,
    ForearmLeft = 7,
    ForearmRight = 8,
    HipLeft = 9,
    HipRight = 10,
    ThighLeft = 11,
    ThighRight = 12,
    ShinLeft = 13,
    ShinRight = 14,
    FootLeft = 15,
    FootRight = 16,
}

impl Segment {
    /// All 17 segments, index = label.
    pub const ALL: [Segment; 17] = [
        Segment::Pelvis,
        Segment::Torso,
        Segment::Head,
        Segment::ClavicleLeft,
        Segment::ClavicleRight,
        Segment::UpperArmLeft,
        Segment::UpperArmRight,
        Segment::ForearmLeft,
        Segment::ForearmRight,
        Segment::HipLeft,
        Segment::HipRight,
        Segment::ThighLeft,
        Segment::ThighRight,
        Segment::ShinLeft,
        Segment::ShinRight,
        Segment::FootLeft,
        Segment::FootRight,
    ];

    /// The label (0..17) used in files.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The segment with label `i`, if `i < 17`.
    pub fn from_index(i: usize) -> Option<Segment> {
        Segment::ALL.get(i).copied()
    }

    /// The `symcorr.labels/1` name, e.g. `"upper_arm_left"`.
    pub fn name(self) -> &'static str {
        match self {
            Segment::Pelvis => "pelvis",
            Segment::Torso => "torso",
            Segment::Head => "head",
            Segment::ClavicleLeft => "clavicle_left",
            Segment::ClavicleRight => "clavicle_right",
            Segment::UpperArmLeft => "upper_arm_left",
            Segment::UpperArmRight => "upper_arm_right",
            Segment::ForearmLeft => "forearm_left",
            Segment::ForearmRight => "forearm_right",
            Segment::HipLeft => "hip_left",
            Segment::HipRight => "hip_right",
            Segment::ThighLeft => "thigh_left",
            Segment::ThighRight => "thigh_right",
            Segment::ShinLeft => "shin_left",
            Segment::ShinRight => "shin_right",
            Segment::FootLeft => "foot_left",
            Segment::FootRight => "foot_right",
        }
    }

    /// The twin on the other side (midline segments map to themselves).
    pub fn mirror(self) -> Segment {
        use Segment::*;
        match self {
            ClavicleLeft => ClavicleRight,
            ClavicleRight => ClavicleLeft,
            UpperArmLeft => UpperArmRight,
            UpperArmRight => UpperArmLeft,
            ForearmLeft => ForearmRight,
            ForearmRight => ForearmLeft,
            HipLeft => HipRight,
            HipRight => HipLeft,
            ThighLeft => ThighRight,
            ThighRight => ThighLeft,
            ShinLeft => ShinRight,
            ShinRight => ShinLeft,
            FootLeft => FootRight,
            FootRight => FootLeft,
            s => s,
        }
    }

    /// The side of the body this segment is on: `1` left, `-1` right, `0` a midline segment
    /// (pelvis, torso, head). The product of two sides is negative exactly when one segment is
    /// a left one and the other a right one.
    ///
    /// ```
    /// use symcorr_attach::Segment;
    /// assert_eq!(Segment::ThighLeft.side(), 1);
    /// assert_eq!(Segment::ThighRight.side(), -1);
    /// assert_eq!(Segment::Torso.side(), 0);
    /// ```
    pub fn side(self) -> i8 {
        match self.mirror().index().cmp(&self.index()) {
            std::cmp::Ordering::Greater => 1,
            std::cmp::Ordering::Less => -1,
            std::cmp::Ordering::Equal => 0,
        }
    }

    /// The skeleton bones (parent joint → child joint) that make up this segment. Every segment
    /// has one bone except the forearms, which are elbow→wrist plus wrist→hand.
    pub fn bones(self) -> &'static [(Joint, Joint)] {
        use Joint as J;
        match self {
            Segment::Pelvis => &[(J::HipCenter, J::Spine)],
            Segment::Torso => &[(J::Spine, J::ShoulderCenter)],
            Segment::Head => &[(J::ShoulderCenter, J::Head)],
            Segment::ClavicleLeft => &[(J::ShoulderCenter, J::ShoulderLeft)],
            Segment::ClavicleRight => &[(J::ShoulderCenter, J::ShoulderRight)],
            Segment::UpperArmLeft => &[(J::ShoulderLeft, J::ElbowLeft)],
            Segment::UpperArmRight => &[(J::ShoulderRight, J::ElbowRight)],
            Segment::ForearmLeft => &[(J::ElbowLeft, J::WristLeft), (J::WristLeft, J::HandLeft)],
            Segment::ForearmRight => &[
                (J::ElbowRight, J::WristRight),
                (J::WristRight, J::HandRight),
            ],
            Segment::HipLeft => &[(J::HipCenter, J::HipLeft)],
            Segment::HipRight => &[(J::HipCenter, J::HipRight)],
            Segment::ThighLeft => &[(J::HipLeft, J::KneeLeft)],
            Segment::ThighRight => &[(J::HipRight, J::KneeRight)],
            Segment::ShinLeft => &[(J::KneeLeft, J::AnkleLeft)],
            Segment::ShinRight => &[(J::KneeRight, J::AnkleRight)],
            Segment::FootLeft => &[(J::AnkleLeft, J::FootLeft)],
            Segment::FootRight => &[(J::AnkleRight, J::FootRight)],
        }
    }
}

/// The 19 bones of the Kinect v1 skeleton as (parent, child), parents before children.
pub const BONES: [(Joint, Joint); 19] = {
    use Joint as J;
    [
        (J::HipCenter, J::Spine),
        (J::Spine, J::ShoulderCenter),
        (J::ShoulderCenter, J::Head),
        (J::ShoulderCenter, J::ShoulderLeft),
        (J::ShoulderLeft, J::ElbowLeft),
        (J::ElbowLeft, J::WristLeft),
        (J::WristLeft, J::HandLeft),
        (J::ShoulderCenter, J::ShoulderRight),
        (J::ShoulderRight, J::ElbowRight),
        (J::ElbowRight, J::WristRight),
        (J::WristRight, J::HandRight),
        (J::HipCenter, J::HipLeft),
        (J::HipLeft, J::KneeLeft),
        (J::KneeLeft, J::AnkleLeft),
        (J::AnkleLeft, J::FootLeft),
        (J::HipCenter, J::HipRight),
        (J::HipRight, J::KneeRight),
        (J::KneeRight, J::AnkleRight),
        (J::AnkleRight, J::FootRight),
    ]
};

/// A canonical 20-joint skeleton: one position (metres unless stated otherwise, in whatever
/// frame the source used) and one confidence in [0, 1] per joint. Confidence 0 means the joint
/// was not tracked; its position is then an estimate (see `interpolated`).
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    /// Position per joint, indexed by [`Joint::index`].
    pub positions: [[f64; 3]; 20],
    /// Tracking confidence per joint in [0, 1].
    pub confidence: [f64; 20],
    /// Joints whose position was not measured but interpolated along the bone chain by an importer.
    pub interpolated: [bool; 20],
}

impl Skeleton {
    /// A skeleton with all joints at the given positions, confidence 1, nothing interpolated.
    pub fn from_positions(positions: [[f64; 3]; 20]) -> Self {
        Skeleton {
            positions,
            confidence: [1.0; 20],
            interpolated: [false; 20],
        }
    }

    /// Position of joint `j`.
    pub fn position(&self, j: Joint) -> [f64; 3] {
        self.positions[j.index()]
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_is_an_involution_that_swaps_sides() {
        for s in Segment::ALL {
            assert_eq!(s.mirror().mirror(), s);
            let l = s.name().ends_with("_left");
            let r = s.name().ends_with("_right");
            assert_eq!(s.side(), i8::from(l) - i8::from(r), "{}", s.name());
            assert_eq!(s.mirror().side(), -s.side());
            if l || r {
                assert_ne!(s.mirror(), s);
                assert_eq!(s.mirror().name().ends_with("_left"), r);
            } else {
                assert_eq!(s.mirror(), s);
            }
        }
        for j in Joint::ALL {
            assert_eq!(j.mirror().mirror(), j);
        }
    }

    #[test]
    fn segments_cover_every_bone_once() {
        let mut bones: Vec<_> = Segment::ALL
            .iter()
            .flat_map(|s| s.bones().to_vec())
            .collect();
        bones.sort();
        let mut all = BONES.to_vec();
        all.sort();
        assert_eq!(bones, all);
        for (i, s) in Segment::ALL.iter().enumerate() {
            assert_eq!(s.index(), i);
            assert_eq!(Segment::from_index(i), Some(*s));
        }
        for (i, j) in Joint::ALL.iter().enumerate() {
            assert_eq!(j.index(), i);
            assert_eq!(Joint::from_name(j.name()), Some(*j));
        }
    }
}
