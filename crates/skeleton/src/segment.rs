//! The 17 body segments and the side of the body each is on.

use crate::{Bone, Joint};
use serde::{Deserialize, Serialize};

/// One of the 17 body segments of DESIGN.md, numbered as there.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)] // the variants are DESIGN.md's segment names
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
    /// Number of body segments.
    pub const COUNT: usize = 17;

    /// The midline segments, whose [`Segment::side`] is [`BodySide::Midline`]: single segments
    /// with a left and a right half, which a sagittal plane splits.
    pub const MIDLINE: [Segment; 3] = [Segment::Pelvis, Segment::Torso, Segment::Head];

    /// All 17 segments, index = label.
    pub const ALL: [Segment; Segment::COUNT] = [
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

    /// The side of the body this segment is on; pelvis, torso and head are on the midline.
    ///
    /// ```
    /// use symcorr_skeleton::{BodySide, Segment};
    /// assert_eq!(Segment::ThighLeft.side(), BodySide::Left);
    /// assert_eq!(Segment::ThighRight.side(), BodySide::Right);
    /// assert_eq!(Segment::Torso.side(), BodySide::Midline);
    /// assert!(Segment::ThighLeft.side().opposes(Segment::FootRight.side()));
    /// ```
    pub fn side(self) -> BodySide {
        match self.mirror().index().cmp(&self.index()) {
            std::cmp::Ordering::Greater => BodySide::Left,
            std::cmp::Ordering::Less => BodySide::Right,
            std::cmp::Ordering::Equal => BodySide::Midline,
        }
    }

    /// The skeleton bones (parent joint → child joint) that make up this segment. Every segment
    /// has one bone except the forearms, which are elbow→wrist plus wrist→hand.
    pub fn bones(self) -> &'static [Bone] {
        use Joint as J;
        match self {
            Segment::Pelvis => &[Bone {
                parent: J::HipCenter,
                child: J::Spine,
            }],
            Segment::Torso => &[Bone {
                parent: J::Spine,
                child: J::ShoulderCenter,
            }],
            Segment::Head => &[Bone {
                parent: J::ShoulderCenter,
                child: J::Head,
            }],
            Segment::ClavicleLeft => &[Bone {
                parent: J::ShoulderCenter,
                child: J::ShoulderLeft,
            }],
            Segment::ClavicleRight => &[Bone {
                parent: J::ShoulderCenter,
                child: J::ShoulderRight,
            }],
            Segment::UpperArmLeft => &[Bone {
                parent: J::ShoulderLeft,
                child: J::ElbowLeft,
            }],
            Segment::UpperArmRight => &[Bone {
                parent: J::ShoulderRight,
                child: J::ElbowRight,
            }],
            Segment::ForearmLeft => &[
                Bone {
                    parent: J::ElbowLeft,
                    child: J::WristLeft,
                },
                Bone {
                    parent: J::WristLeft,
                    child: J::HandLeft,
                },
            ],
            Segment::ForearmRight => &[
                Bone {
                    parent: J::ElbowRight,
                    child: J::WristRight,
                },
                Bone {
                    parent: J::WristRight,
                    child: J::HandRight,
                },
            ],
            Segment::HipLeft => &[Bone {
                parent: J::HipCenter,
                child: J::HipLeft,
            }],
            Segment::HipRight => &[Bone {
                parent: J::HipCenter,
                child: J::HipRight,
            }],
            Segment::ThighLeft => &[Bone {
                parent: J::HipLeft,
                child: J::KneeLeft,
            }],
            Segment::ThighRight => &[Bone {
                parent: J::HipRight,
                child: J::KneeRight,
            }],
            Segment::ShinLeft => &[Bone {
                parent: J::KneeLeft,
                child: J::AnkleLeft,
            }],
            Segment::ShinRight => &[Bone {
                parent: J::KneeRight,
                child: J::AnkleRight,
            }],
            Segment::FootLeft => &[Bone {
                parent: J::AnkleLeft,
                child: J::FootLeft,
            }],
            Segment::FootRight => &[Bone {
                parent: J::AnkleRight,
                child: J::FootRight,
            }],
        }
    }
}

/// Which side of the body: the subject's anatomical left or right, or the midline.
///
/// A match between a [`BodySide::Left`] and a [`BodySide::Right`] point is a left/right flip;
/// midline points may match either side's neighbours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BodySide {
    /// The subject's left.
    Left,
    /// On (or within a margin of) the sagittal plane.
    #[default]
    Midline,
    /// The subject's right.
    Right,
}

impl BodySide {
    /// `+1` left, `-1` right, `0` midline: the sign of the coordinate along a left-pointing
    /// sagittal normal.
    pub fn sign(self) -> i8 {
        match self {
            BodySide::Left => 1,
            BodySide::Midline => 0,
            BodySide::Right => -1,
        }
    }

    /// The side a signed distance along a left-pointing normal lies on: left above `margin`,
    /// right below `-margin`, midline within it (and for NaN).
    pub fn of_signed_distance(d: f64, margin: f64) -> BodySide {
        if d > margin {
            BodySide::Left
        } else if d < -margin {
            BodySide::Right
        } else {
            BodySide::Midline
        }
    }

    /// True when one side is left and the other right (a midline side opposes nothing).
    pub fn opposes(self, other: BodySide) -> bool {
        self.sign() * other.sign() < 0
    }

    /// The other side (the midline stays).
    pub fn mirror(self) -> BodySide {
        match self {
            BodySide::Left => BodySide::Right,
            BodySide::Midline => BodySide::Midline,
            BodySide::Right => BodySide::Left,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BONES;

    #[test]
    fn mirror_is_an_involution_that_swaps_sides() {
        for s in Segment::ALL {
            assert_eq!(s.mirror().mirror(), s);
            let l = s.name().ends_with("_left");
            let r = s.name().ends_with("_right");
            assert_eq!(s.side().sign(), i8::from(l) - i8::from(r), "{}", s.name());
            assert_eq!(s.mirror().side(), s.side().mirror());
            if l || r {
                assert_ne!(s.mirror(), s);
                assert_eq!(s.mirror().name().ends_with("_left"), r);
            } else {
                assert_eq!(s.mirror(), s);
            }
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
        assert_eq!(Segment::from_index(Segment::COUNT), None);
    }

    #[test]
    fn sides_of_signed_distances() {
        assert_eq!(BodySide::of_signed_distance(0.2, 0.1), BodySide::Left);
        assert_eq!(BodySide::of_signed_distance(-0.2, 0.1), BodySide::Right);
        assert_eq!(BodySide::of_signed_distance(0.05, 0.1), BodySide::Midline);
        assert_eq!(
            BodySide::of_signed_distance(f64::NAN, 0.0),
            BodySide::Midline
        );
        assert!(!BodySide::Left.opposes(BodySide::Midline));
        assert!(BodySide::Right.opposes(BodySide::Left));
    }
}
