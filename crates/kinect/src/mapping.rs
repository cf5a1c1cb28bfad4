//! Mapping of other trackers' skeletons (NiTE 15 joints, Kinect v2 25 joints, Azure Kinect 32
//! joints) onto the canonical Kinect v1 20-joint skeleton, and interpolation of joints a source
//! lacks.
//!
//! ## NiTE (OpenNI/NiTE 2, 15 joints) → Kinect v1
//!
//! | NiTE | Kinect v1 | note |
//! |---|---|---|
//! | head | head | |
//! | neck | shoulder_center | NiTE's neck sits where v1 puts the shoulder centre |
//! | torso | spine | NiTE's torso centre; v1's spine joint is the closest |
//! | shoulder_*, elbow_* | shoulder_*, elbow_* | |
//! | hand_* | hand_* | NiTE has no wrist/hand split |
//! | hip_*, knee_* | hip_*, knee_* | |
//! | foot_* | ankle_* | NiTE's foot joint sits at the ankle |
//! | — | hip_center | interpolated: midpoint of the hips |
//! | — | wrist_* | interpolated: 80 % of the way elbow → hand |
//! | — | foot_* | extrapolated in front of and below the ankle (rules below) |
//!
//! ## Kinect v2 (25 joints) → Kinect v1
//!
//! | Kinect v2 | Kinect v1 |
//! |---|---|
//! | spine_base (0) | hip_center |
//! | spine_mid (1) | spine |
//! | spine_shoulder (20) | shoulder_center |
//! | head (3) | head |
//! | shoulder/elbow/wrist/hand/hip/knee/ankle/foot left/right (4–19) | same name, same index |
//! | neck (2), hand_tip_* (21, 23), thumb_* (22, 24) | dropped (neck is used for shoulder_center only if spine_shoulder is missing) |
//!
//! ## Azure Kinect Body Tracking (32 joints) → Kinect v1
//!
//! | Azure Kinect (`k4abt_joint_id_t`) | Kinect v1 | note |
//! |---|---|---|
//! | pelvis (0) | hip_center | |
//! | spine_navel (1) | spine | |
//! | neck (3) | shoulder_center | the base of the neck, where v1 and v2 put the shoulder centre |
//! | head (26) | head | |
//! | shoulder/elbow/wrist/hand/hip/knee/ankle/foot left/right | same name | |
//! | spine_chest (2), clavicle_* (4, 11), handtip_*, thumb_* (9, 10, 16, 17) | dropped | |
//! | nose, eye_*, ear_* (27–31) | dropped | the nose and ears give `Skeleton::head_turn` |
//!
//! The SDK's own files are in its depth camera's frame (millimetres, +x right, +y down):
//! [`crate::k4abt`] turns them into Kinect camera space. A `symcorr.joints/1` file with skeleton
//! `azure_kinect` is, like every `symcorr.joints/1` file, in Kinect camera space already.
//!
//! ## Interpolation rules (any source)
//!
//! A canonical joint that is missing is estimated from its tracked bone-chain neighbours
//! (confidence > 0), in this order of preference, and flagged in
//! [`Skeleton::interpolated`](symcorr_skeleton::Skeleton) with confidence
//! `0.5 × min(confidence of the joints used)`:
//! hip_center = mid(hips); shoulder_center = mid(shoulders); spine = 30 % hip_center → shoulder_center;
//! head = shoulder_center + 0.5·(shoulder_center − spine); wrist = 80 % elbow → hand;
//! hand = wrist + 0.25·(wrist − elbow); elbow = mid(shoulder, wrist or hand); knee = mid(hip, ankle);
//! ankle = knee + (knee − hip) (shin ≈ thigh); foot = ankle + |knee − ankle| · (0.3·facing −
//! 0.18·up), where up is the unit vector shoulder_center − hip_center (− spine without a hip
//! centre) and facing = (left − right) × up from the shoulders (from the hips where the
//! shoulders give no direction) (DESIGN.md: left/right are the subject's sides; in Kinect camera
//! space a subject facing the sensor faces −z). The foot's offset is close to the canonical
//! rig's at rest (the bundled body: 0.32 shin lengths in front of the ankle, 0.18 below); the
//! shoulders, because a tracker's most common swap is the legs', which would turn feet
//! estimated from the hips backwards. Measured on NiTE logs of nine recordings against the
//! offset 0.3·facing from the hips alone:
//! docs/decisions/2026-12-05-joint-log-units-clocks-and-lost-bodies.md.
//!
//! A joint that no tracked neighbour can estimate is left **untracked**: at (0, 0, 0) with
//! confidence 0 and not flagged, as the Kinect SDK reports a joint it does not track (a joint
//! the source gives with confidence 0 keeps the position it was given, untracked as well). A
//! frame in which the tracker lost the body (every joint untracked) is therefore kept as such —
//! `track` skips it with that reason, a single-frame command refuses it — and one untracked hip
//! does not make a whole log unreadable.

use crate::geom::normalize;
use nalgebra::{distance, Point3, Vector3};
use symcorr_skeleton::{Joint, Skeleton};

/// The skeleton a tracker reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SkeletonKind {
    /// Kinect for Windows SDK v1: 20 joints (the canonical skeleton).
    KinectV1,
    /// OpenNI NiTE: 15 joints.
    Nite,
    /// Kinect for Windows SDK v2 / NTU RGB+D: 25 joints.
    KinectV2,
    /// Azure Kinect Body Tracking SDK (`k4abt`, also behind Orbbec's Femto cameras): 32 joints.
    AzureKinect,
}

impl SkeletonKind {
    /// The name used in `symcorr.joints/1` (`"kinect_v1"`, `"nite"`, `"kinect_v2"`).
    pub fn name(self) -> &'static str {
        match self {
            SkeletonKind::KinectV1 => "kinect_v1",
            SkeletonKind::Nite => "nite",
            SkeletonKind::KinectV2 => "kinect_v2",
            SkeletonKind::AzureKinect => "azure_kinect",
        }
    }

    /// Parses a `symcorr.joints/1` skeleton name.
    pub fn from_name(name: &str) -> Option<SkeletonKind> {
        match name {
            "kinect_v1" => Some(SkeletonKind::KinectV1),
            "nite" => Some(SkeletonKind::Nite),
            "kinect_v2" => Some(SkeletonKind::KinectV2),
            "azure_kinect" => Some(SkeletonKind::AzureKinect),
            _ => None,
        }
    }

    /// The joint names of this skeleton in its native order.
    pub fn joint_names(self) -> &'static [&'static str] {
        match self {
            SkeletonKind::KinectV1 => &KINECT_V1_NAMES,
            SkeletonKind::Nite => &NITE_NAMES,
            SkeletonKind::KinectV2 => &KINECT_V2_NAMES,
            SkeletonKind::AzureKinect => &AZURE_KINECT_NAMES,
        }
    }

    /// The canonical joint a native joint (by index in [`SkeletonKind::joint_names`]) maps to,
    /// or `None` if it is dropped.
    pub fn canonical(self, native: usize) -> Option<Joint> {
        match self {
            SkeletonKind::KinectV1 => Joint::ALL.get(native).copied(),
            SkeletonKind::Nite => NITE_TO_V1.get(native).copied(),
            SkeletonKind::KinectV2 => KINECT_V2_TO_V1.get(native).copied().flatten(),
            SkeletonKind::AzureKinect => AZURE_KINECT_TO_V1.get(native).copied().flatten(),
        }
    }
}

/// Kinect v1's 20 joints in SDK order: the canonical [`Joint`] names (one owner of the spelling).
const KINECT_V1_NAMES: [&str; Joint::COUNT] = {
    let mut names = [""; Joint::COUNT];
    let mut i = 0;
    while i < 20 {
        names[i] = Joint::ALL[i].name();
        i += 1;
    }
    names
};

/// NiTE's 15 joints in `nite::JointType` order.
pub const NITE_NAMES: [&str; 15] = [
    "head",
    "neck",
    "shoulder_left",
    "shoulder_right",
    "elbow_left",
    "elbow_right",
    "hand_left",
    "hand_right",
    "torso",
    "hip_left",
    "hip_right",
    "knee_left",
    "knee_right",
    "foot_left",
    "foot_right",
];

const NITE_TO_V1: [Joint; 15] = [
    Joint::Head,
    Joint::ShoulderCenter,
    Joint::ShoulderLeft,
    Joint::ShoulderRight,
    Joint::ElbowLeft,
    Joint::ElbowRight,
    Joint::HandLeft,
    Joint::HandRight,
    Joint::Spine,
    Joint::HipLeft,
    Joint::HipRight,
    Joint::KneeLeft,
    Joint::KneeRight,
    Joint::AnkleLeft,
    Joint::AnkleRight,
];

/// Kinect v2's 25 joints in `JointType` order (also the NTU RGB+D order).
pub const KINECT_V2_NAMES: [&str; 25] = [
    "spine_base",
    "spine_mid",
    "neck",
    "head",
    "shoulder_left",
    "elbow_left",
    "wrist_left",
    "hand_left",
    "shoulder_right",
    "elbow_right",
    "wrist_right",
    "hand_right",
    "hip_left",
    "knee_left",
    "ankle_left",
    "foot_left",
    "hip_right",
    "knee_right",
    "ankle_right",
    "foot_right",
    "spine_shoulder",
    "hand_tip_left",
    "thumb_left",
    "hand_tip_right",
    "thumb_right",
];

const KINECT_V2_TO_V1: [Option<Joint>; 25] = {
    use Joint as J;
    [
        Some(J::HipCenter),
        Some(J::Spine),
        None, // neck: fallback for shoulder_center only
        Some(J::Head),
        Some(J::ShoulderLeft),
        Some(J::ElbowLeft),
        Some(J::WristLeft),
        Some(J::HandLeft),
        Some(J::ShoulderRight),
        Some(J::ElbowRight),
        Some(J::WristRight),
        Some(J::HandRight),
        Some(J::HipLeft),
        Some(J::KneeLeft),
        Some(J::AnkleLeft),
        Some(J::FootLeft),
        Some(J::HipRight),
        Some(J::KneeRight),
        Some(J::AnkleRight),
        Some(J::FootRight),
        Some(J::ShoulderCenter),
        None,
        None,
        None,
        None,
    ]
};

/// The Azure Kinect Body Tracking SDK's 32 joints in `k4abt_joint_id_t` order, lower case (the
/// SDK's own spelling is upper case: `SPINE_NAVEL`).
pub const AZURE_KINECT_NAMES: [&str; 32] = [
    "pelvis",
    "spine_navel",
    "spine_chest",
    "neck",
    "clavicle_left",
    "shoulder_left",
    "elbow_left",
    "wrist_left",
    "hand_left",
    "handtip_left",
    "thumb_left",
    "clavicle_right",
    "shoulder_right",
    "elbow_right",
    "wrist_right",
    "hand_right",
    "handtip_right",
    "thumb_right",
    "hip_left",
    "knee_left",
    "ankle_left",
    "foot_left",
    "hip_right",
    "knee_right",
    "ankle_right",
    "foot_right",
    "head",
    "nose",
    "eye_left",
    "ear_left",
    "eye_right",
    "ear_right",
];

const AZURE_KINECT_TO_V1: [Option<Joint>; 32] = {
    use Joint as J;
    [
        Some(J::HipCenter),
        Some(J::Spine),
        None, // spine_chest
        Some(J::ShoulderCenter),
        None, // clavicle_left
        Some(J::ShoulderLeft),
        Some(J::ElbowLeft),
        Some(J::WristLeft),
        Some(J::HandLeft),
        None, // handtip_left
        None, // thumb_left
        None, // clavicle_right
        Some(J::ShoulderRight),
        Some(J::ElbowRight),
        Some(J::WristRight),
        Some(J::HandRight),
        None, // handtip_right
        None, // thumb_right
        Some(J::HipLeft),
        Some(J::KneeLeft),
        Some(J::AnkleLeft),
        Some(J::FootLeft),
        Some(J::HipRight),
        Some(J::KneeRight),
        Some(J::AnkleRight),
        Some(J::FootRight),
        Some(J::Head),
        None, // nose
        None, // eye_left
        None, // ear_left
        None, // eye_right
        None, // ear_right
    ]
};

/// A tracker's face: the points that say which way the head looks (the Azure Kinect's nose and
/// ears; its eyes add nothing the ears do not).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacePoints {
    /// The tip of the nose.
    pub nose: Point3<f64>,
    /// The two ears, in either order.
    pub ears: [Point3<f64>; 2],
}

/// How far the head is turned against the chest ([`Skeleton::head_turn`]), from a tracker's
/// face and the canonical skeleton `s` it belongs to: the face looks from the ears' midpoint to
/// the nose, the chest along the normal of the shoulder line and the neck → head axis (shoulder
/// centre → head) — on the side the face is on, so that no left/right label is read, and a
/// turn beyond ±π/2 is taken for the nearer one within it (a neck turns about ±80°); the
/// signed angle between the two about the neck → head axis, right-handed about it (positive:
/// towards the subject's left). `None` when an axis is degenerate (the face points together,
/// the shoulders or the face along the neck).
///
/// ```
/// use nalgebra::Point3;
/// use symcorr_kinect::mapping::{head_turn_from_face, FacePoints};
/// use symcorr_skeleton::{Joint, Skeleton};
/// // Facing the camera (−z), the subject's left at −x; the face turned 30° to the left.
/// let mut xyz = [[0.0, 1.0, 2.5]; Joint::COUNT];
/// xyz[Joint::ShoulderCenter.index()] = [0.0, 1.4, 2.5];
/// xyz[Joint::Head.index()] = [0.0, 1.6, 2.5];
/// xyz[Joint::ShoulderLeft.index()] = [-0.2, 1.4, 2.5];
/// xyz[Joint::ShoulderRight.index()] = [0.2, 1.4, 2.5];
/// let s = Skeleton::from_arrays(xyz);
/// let (sin, cos) = 30f64.to_radians().sin_cos();
/// let face = FacePoints {
///     nose: Point3::new(-0.1 * sin, 1.6, 2.5 - 0.1 * cos),
///     ears: [
///         Point3::new(0.07 * cos, 1.6, 2.5 - 0.07 * sin),
///         Point3::new(-0.07 * cos, 1.6, 2.5 + 0.07 * sin),
///     ],
/// };
/// let turn = head_turn_from_face(&s, &face).unwrap();
/// assert!((turn - 30f64.to_radians()).abs() < 1e-9);
/// ```
pub fn head_turn_from_face(s: &Skeleton, face: &FacePoints) -> Option<f64> {
    let (up, across) = neck_axis_and_chest(s)?;
    let flat = |v: Vector3<f64>| normalize(v - up * up.dot(&v));
    let mid = Point3::from((face.ears[0].coords + face.ears[1].coords) * 0.5);
    let looks = flat(face.nose - mid)?;
    let mut chest = flat(across)?;
    if chest.dot(&looks) < 0.0 {
        chest = -chest;
    }
    Some(up.dot(&chest.cross(&looks)).atan2(chest.dot(&looks)))
}

/// The axes a head's turn is measured in: the unit neck → head axis (shoulder centre → head)
/// and the chest's forward direction normal to it, `(left − right shoulder) × axis`, not
/// normalised (by the labels: [`head_turn_from_face`] takes the side the face is on). `None`
/// when the axis is degenerate.
pub(crate) fn neck_axis_and_chest(s: &Skeleton) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let up = normalize(s.position(Joint::Head) - s.position(Joint::ShoulderCenter))?;
    let lateral = s.position(Joint::ShoulderLeft) - s.position(Joint::ShoulderRight);
    Some((up, lateral.cross(&up)))
}

/// Index of Kinect v2's neck joint (used as a fallback for shoulder_center).
pub(crate) const KINECT_V2_NECK: usize = 2;

/// Normalises a joint name: accepts `left_shoulder` / `LeftShoulder`-style aliases for
/// `shoulder_left` (NiTE and SDK spellings).
pub(crate) fn normalise_name(name: &str) -> String {
    // CamelCase → snake_case.
    let mut snake = String::with_capacity(name.len() + 4);
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 && !snake.ends_with('_') {
                snake.push('_');
            }
            snake.push(c.to_ascii_lowercase());
        } else if c == '-' || c == ' ' {
            snake.push('_');
        } else {
            snake.push(c);
        }
    }
    for side in ["left", "right"] {
        if let Some(rest) = snake.strip_prefix(&format!("{side}_")) {
            return format!("{rest}_{side}");
        }
    }
    snake
}

/// A partially known canonical skeleton: what an importer measured.
#[derive(Debug, Clone)]
pub(crate) struct Partial {
    pub positions: [Option<Point3<f64>>; Joint::COUNT],
    pub confidence: [f64; Joint::COUNT],
}

impl Partial {
    pub fn new() -> Self {
        Partial {
            positions: [None; Joint::COUNT],
            confidence: [0.0; 20],
        }
    }

    pub fn set(&mut self, j: Joint, p: Point3<f64>, c: f64) {
        self.positions[j.index()] = Some(p);
        self.confidence[j.index()] = c;
    }

    /// A tracked joint (confidence > 0): what estimates may be built from.
    fn get(&self, j: Joint) -> Option<(Point3<f64>, f64)> {
        let c = self.confidence[j.index()];
        self.positions[j.index()]
            .filter(|_| c > 0.0)
            .map(|p| (p, c))
    }

    /// Completes the skeleton with the interpolation rules of the module docs; a joint nothing
    /// tracked can estimate is left untracked. Returns the first joint whose position is not
    /// finite (an estimate between huge coordinates overflows) as the error.
    pub fn complete(mut self) -> Result<Skeleton, Joint> {
        let mut interpolated = [false; 20];
        // Each pass fills what its neighbours allow; three passes settle every chain.
        for _ in 0..4 {
            let mut progress = false;
            for j in Joint::ALL {
                if self.positions[j.index()].is_some() {
                    continue;
                }
                if let Some((p, c)) = self.estimate(j) {
                    self.set(j, p, 0.5 * c);
                    interpolated[j.index()] = true;
                    progress = true;
                }
            }
            if !progress {
                break;
            }
        }
        let mut positions = [Point3::origin(); 20];
        for j in Joint::ALL {
            match self.positions[j.index()] {
                // Interpolating between huge (finite) coordinates can overflow to infinity.
                Some(p) if p.iter().all(|c| c.is_finite()) => positions[j.index()] = p,
                Some(_) => return Err(j),
                // Untracked: the SDK's (0, 0, 0) with confidence 0.
                None => self.confidence[j.index()] = 0.0,
            }
        }
        Ok(Skeleton {
            positions,
            confidence: self.confidence,
            interpolated,
            head_turn: None,
        })
    }

    fn mid(&self, a: Joint, b: Joint) -> Option<(Point3<f64>, f64)> {
        self.at(a, b, 0.5)
    }

    /// `a + t (b − a)` (not nalgebra's `lerp`, which rounds differently).
    fn at(&self, a: Joint, b: Joint, t: f64) -> Option<(Point3<f64>, f64)> {
        let (pa, ca) = self.get(a)?;
        let (pb, cb) = self.get(b)?;
        Some((pa + (pb - pa) * t, ca.min(cb)))
    }

    /// The subject's facing direction and up, unit vectors: up from the hip centre (the spine
    /// without one) to the shoulder centre, facing = (left − right) × up from the shoulders
    /// (the hips where the shoulders give no direction: a leg swap exchanges the hips).
    fn facing(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let (low, _) = self
            .get(Joint::HipCenter)
            .or_else(|| self.get(Joint::Spine))?;
        let (sc, _) = self.get(Joint::ShoulderCenter)?;
        let up = normalize(sc - low)?;
        let across = |l: Joint, r: Joint| {
            let ((pl, _), (pr, _)) = self.get(l).zip(self.get(r))?;
            normalize((pl - pr).cross(&up))
        };
        let facing = across(Joint::ShoulderLeft, Joint::ShoulderRight)
            .or_else(|| across(Joint::HipLeft, Joint::HipRight))?;
        Some((facing, up))
    }

    fn estimate(&self, j: Joint) -> Option<(Point3<f64>, f64)> {
        use Joint as J;
        let side = |l: J, r: J| if is_left(j) { l } else { r };
        match j {
            J::HipCenter => self.mid(J::HipLeft, J::HipRight),
            J::ShoulderCenter => self.mid(J::ShoulderLeft, J::ShoulderRight),
            J::Spine => self.at(J::HipCenter, J::ShoulderCenter, 0.3),
            J::Head => {
                let (sc, c1) = self.get(J::ShoulderCenter)?;
                let (sp, c2) = self.get(J::Spine)?;
                Some((sc + (sc - sp) * 0.5, c1.min(c2)))
            }
            J::WristLeft | J::WristRight => self.at(
                side(J::ElbowLeft, J::ElbowRight),
                side(J::HandLeft, J::HandRight),
                0.8,
            ),
            J::HandLeft | J::HandRight => self.at(
                side(J::ElbowLeft, J::ElbowRight),
                side(J::WristLeft, J::WristRight),
                1.25,
            ),
            J::ElbowLeft | J::ElbowRight => {
                let s = side(J::ShoulderLeft, J::ShoulderRight);
                self.mid(s, side(J::WristLeft, J::WristRight))
                    .or_else(|| self.mid(s, side(J::HandLeft, J::HandRight)))
            }
            J::ShoulderLeft | J::ShoulderRight => None,
            J::HipLeft | J::HipRight => None,
            J::KneeLeft | J::KneeRight => self.mid(
                side(J::HipLeft, J::HipRight),
                side(J::AnkleLeft, J::AnkleRight),
            ),
            J::AnkleLeft | J::AnkleRight => self.at(
                side(J::HipLeft, J::HipRight),
                side(J::KneeLeft, J::KneeRight),
                2.0,
            ),
            J::FootLeft | J::FootRight => {
                let (k, c1) = self.get(side(J::KneeLeft, J::KneeRight))?;
                let (a, c2) = self.get(side(J::AnkleLeft, J::AnkleRight))?;
                let (f, up) = self.facing()?;
                let shin = distance(&k, &a);
                Some((a + (f * 0.3 - up * 0.18) * shin, c1.min(c2)))
            }
        }
    }
}

fn is_left(j: Joint) -> bool {
    j.name().ends_with("_left")
}
