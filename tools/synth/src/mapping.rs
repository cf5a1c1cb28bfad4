//! The two documented tables that turn the 53-bone MakeHuman `game_engine` rig into symcorr's
//! canonical skeleton: rig → 20 Kinect v1 joints ([`JOINT_TABLE`]) and rig bone → 17 segments
//! ([`segment_of_bone`]), plus the reference segment labels built from them.
//!
//! ## Rig → Kinect joints
//!
//! | Kinect joint | rig point | carried by bone |
//! |---|---|---|
//! | hip_center | `pelvis` head (cube `joint-pelvis`) | pelvis |
//! | spine | `spine_02` head (cube `joint-spine-3`) | spine_02 |
//! | shoulder_center | `neck_01` head (cube `joint-neck`) | neck_01 |
//! | head | midpoint of `head` head and tail (centre of the skull) | head |
//! | shoulder_left/right | `upperarm_l/r` head | upperarm |
//! | elbow_left/right | `lowerarm_l/r` head | lowerarm |
//! | wrist_left/right | `hand_l/r` head | hand |
//! | hand_left/right | midpoint of `hand_l/r` head and `middle_01_l/r` head (middle of the palm) | hand |
//! | hip_left/right | `thigh_l/r` head | thigh |
//! | knee_left/right | `calf_l/r` head | calf |
//! | ankle_left/right | `foot_l/r` head | foot |
//! | foot_left/right | `ball_l/r` head (ball of the foot) | foot |
//!
//! Each joint is a rest-pose point moved rigidly by its carrying bone, so joints follow posing
//! exactly; rig points are computed from the shaped mesh, so they follow shape changes.
//!
//! ## Rig bones → 17 segments (reference labels)
//!
//! | rig bones | segment |
//! |---|---|
//! | `Root`, `pelvis` | pelvis, hip_left or hip_right (see below) |
//! | `spine_01` | pelvis (it lies between hip_center and the Kinect spine joint) |
//! | `spine_02`, `spine_03` | torso |
//! | `neck_01`, `head` | head |
//! | `clavicle_l/r` | clavicle_left/right |
//! | `upperarm_l/r` | upper_arm_left/right |
//! | `lowerarm_l/r`, `hand_l/r`, every finger bone `*_l/r` | forearm_left/right (forearm+hand) |
//! | `thigh_l/r` | thigh_left/right |
//! | `calf_l/r` | shin_left/right |
//! | `foot_l/r`, `ball_l/r` | foot_left/right |
//!
//! A vertex's label is the segment of its dominant-weight bone. The rig has no bone for the
//! Kinect hip bones (hip_center → hip_left/right), so vertices dominated by `Root`/`pelvis` are
//! split between pelvis, hip_left and hip_right by the nearest of those three Kinect bones (point
//! to segment distance, rest pose of the base shape; ties go to pelvis). Labels are computed
//! once on the base shape's rest pose and are the same for every body of a dataset (they are
//! per-vertex ground truth, like the vertex ids).

use symcorr_skeleton::{Joint, Segment, Skeleton};

use crate::body::{Body, Posed};
use crate::error::Result;
use nalgebra::{Point3, Vector3};

use crate::math::V3;

/// How a Kinect joint is placed on the rig: the mean of some bone heads/tails, carried by a bone.
#[derive(Debug, Clone, Copy)]
pub struct JointRule {
    /// The Kinect joint.
    pub joint: Joint,
    /// Rig points averaged: `(bone, true = tail / false = head)`.
    pub points: &'static [(&'static str, bool)],
    /// The bone that carries the point when posing.
    pub carrier: &'static str,
}

const fn rule(
    joint: Joint,
    points: &'static [(&'static str, bool)],
    carrier: &'static str,
) -> JointRule {
    JointRule {
        joint,
        points,
        carrier,
    }
}

/// The rig → Kinect joint table (see the module docs), in Kinect SDK order.
pub const JOINT_TABLE: [JointRule; 20] = [
    rule(Joint::HipCenter, &[("pelvis", false)], "pelvis"),
    rule(Joint::Spine, &[("spine_02", false)], "spine_02"),
    rule(Joint::ShoulderCenter, &[("neck_01", false)], "neck_01"),
    rule(Joint::Head, &[("head", false), ("head", true)], "head"),
    rule(Joint::ShoulderLeft, &[("upperarm_l", false)], "upperarm_l"),
    rule(Joint::ElbowLeft, &[("lowerarm_l", false)], "lowerarm_l"),
    rule(Joint::WristLeft, &[("hand_l", false)], "hand_l"),
    rule(
        Joint::HandLeft,
        &[("hand_l", false), ("middle_01_l", false)],
        "hand_l",
    ),
    rule(Joint::ShoulderRight, &[("upperarm_r", false)], "upperarm_r"),
    rule(Joint::ElbowRight, &[("lowerarm_r", false)], "lowerarm_r"),
    rule(Joint::WristRight, &[("hand_r", false)], "hand_r"),
    rule(
        Joint::HandRight,
        &[("hand_r", false), ("middle_01_r", false)],
        "hand_r",
    ),
    rule(Joint::HipLeft, &[("thigh_l", false)], "thigh_l"),
    rule(Joint::KneeLeft, &[("calf_l", false)], "calf_l"),
    rule(Joint::AnkleLeft, &[("foot_l", false)], "foot_l"),
    rule(Joint::FootLeft, &[("ball_l", false)], "foot_l"),
    rule(Joint::HipRight, &[("thigh_r", false)], "thigh_r"),
    rule(Joint::KneeRight, &[("calf_r", false)], "calf_r"),
    rule(Joint::AnkleRight, &[("foot_r", false)], "foot_r"),
    rule(Joint::FootRight, &[("ball_r", false)], "foot_r"),
];

/// The segment of a rig bone (see the module docs); `None` for `Root` and `pelvis`, whose
/// vertices are split geometrically between pelvis and the two hips.
pub fn segment_of_bone(name: &str) -> Option<Segment> {
    use Segment as S;
    let side = |l: S, r: S| {
        if name.ends_with("_l") {
            Some(l)
        } else if name.ends_with("_r") {
            Some(r)
        } else {
            None
        }
    };
    let stem = name.trim_end_matches("_l").trim_end_matches("_r");
    match stem {
        "Root" | "pelvis" => None,
        "spine_01" => Some(S::Pelvis),
        "spine_02" | "spine_03" => Some(S::Torso),
        "neck_01" | "head" => Some(S::Head),
        "clavicle" => side(S::ClavicleLeft, S::ClavicleRight),
        "upperarm" => side(S::UpperArmLeft, S::UpperArmRight),
        "lowerarm" | "hand" => side(S::ForearmLeft, S::ForearmRight),
        s if ["thumb", "index", "middle", "ring", "pinky"]
            .iter()
            .any(|f| s.starts_with(f)) =>
        {
            side(S::ForearmLeft, S::ForearmRight)
        }
        "thigh" => side(S::ThighLeft, S::ThighRight),
        "calf" => side(S::ShinLeft, S::ShinRight),
        "foot" | "ball" => side(S::FootLeft, S::FootRight),
        _ => None,
    }
}

/// The posed Kinect skeleton of a body (OBJ frame, metres; confidence 1 everywhere).
pub fn kinect_joints(body: &Body<'_>, posed: &Posed) -> Result<Skeleton> {
    let mut positions = [[0.0; 3]; 20];
    for r in JOINT_TABLE {
        let mut p = Vector3::zeros();
        for &(bone, tail) in r.points {
            let b = &body.bones[body.bone(bone)?];
            p += Vector3::from(if tail { b.tail } else { b.head });
        }
        let p = p * (1.0 / r.points.len() as f64);
        positions[r.joint.index()] = body.carry(&posed.skin, body.bone(r.carrier)?, p.into());
    }
    Ok(Skeleton::from_arrays(positions))
}

/// The face points an Azure Kinect tracker reports, `[nose, ear_left, ear_right]` (OBJ frame,
/// metres): rest points about the centre of the skull (the Kinect head joint, the midpoint of
/// the `head` bone) — the nose 10 cm in front, the ears 7.5 cm to each side — carried by the
/// `head` bone, so that they turn with the head as the joints do not. Only their directions
/// matter to a reader (the face looks from the ears' midpoint to the nose).
pub fn face_points(body: &Body<'_>, posed: &Posed) -> Result<[V3; 3]> {
    let b = body.bone("head")?;
    let bone = &body.bones[b];
    let mid = Vector3::from(bone.head) * 0.5 + Vector3::from(bone.tail) * 0.5;
    // Blender frame: +z up, the body faces −y, its left is +x.
    let at = |d: [f64; 3]| body.carry(&posed.skin, b, (mid + Vector3::from(d)).into());
    Ok([
        at([0.0, -0.10, 0.0]),
        at([0.075, 0.0, 0.0]),
        at([-0.075, 0.0, 0.0]),
    ])
}

fn point_segment_distance(p: V3, a: V3, b: V3) -> f64 {
    let (p, a) = (Point3::from(p), Point3::from(a));
    let ab = Point3::from(b) - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
    nalgebra::distance(&p, &(a + ab * t))
}

/// Reference segment label (index into [`Segment::ALL`]) of every vertex of `body` (use the base
/// shape at rest; see the module docs for the rule).
pub fn reference_labels(body: &Body<'_>) -> Result<Vec<u8>> {
    let rest = body.pose(&crate::body::Pose::default())?;
    let skel = kinect_joints(body, &rest)?;
    let hip_bones = [
        (Segment::Pelvis, Joint::HipCenter, Joint::Spine),
        (Segment::HipLeft, Joint::HipCenter, Joint::HipLeft),
        (Segment::HipRight, Joint::HipCenter, Joint::HipRight),
    ];
    let seg_of: Vec<Option<Segment>> = body
        .bones
        .iter()
        .map(|b| segment_of_bone(&b.name))
        .collect();
    let mut labels = Vec::with_capacity(rest.mesh.num_vertices());
    for (v, ws) in body.model.weights().iter().enumerate() {
        // Dominant bone; ties → the first in rig order (deterministic).
        let mut best = ws[0];
        for &x in &ws[1..] {
            if x.1 > best.1 {
                best = x;
            }
        }
        let seg = match seg_of[best.0] {
            Some(s) => s,
            None => {
                let p = rest.mesh.positions[v];
                let mut pick = (Segment::Pelvis, f64::INFINITY);
                for (s, a, b) in hip_bones {
                    let d =
                        point_segment_distance(p, skel.position(a).into(), skel.position(b).into());
                    if d < pick.1 - 1e-12 {
                        pick = (s, d);
                    }
                }
                pick.0
            }
        };
        labels.push(seg.index() as u8);
    }
    Ok(labels)
}

/// Hops between two segments in the graph where segments sharing a skeleton joint are adjacent.
pub fn segment_hops() -> [[u8; 17]; 17] {
    let mut d = [[u8::MAX; 17]; 17];
    for a in Segment::ALL {
        d[a.index()][a.index()] = 0;
        for b in Segment::ALL {
            let share = a.bones().iter().any(|x| {
                b.bones().iter().any(|y| {
                    x.parent == y.parent
                        || x.parent == y.child
                        || x.child == y.parent
                        || x.child == y.child
                })
            });
            if share && a != b {
                d[a.index()][b.index()] = 1;
            }
        }
    }
    // Floyd–Warshall on 17 nodes.
    for k in 0..17 {
        for i in 0..17 {
            for j in 0..17 {
                let via = d[i][k].saturating_add(d[k][j]);
                if via < d[i][j] {
                    d[i][j] = via;
                }
            }
        }
    }
    d
}

/// Detects gross self-intersection: triangles of body parts at least three segment hops apart
/// (e.g. a forearm and the torso, or the two thighs) that cross each other. Neighbouring parts
/// (thigh and pelvis, upper arm and torso) are not tested: linear blend skinning folds skin
/// there, which is not what this check is about.
#[derive(Debug, Clone)]
pub struct SelfIntersectionCheck {
    tri_labels: Vec<[u8; 3]>,
    hops: [[u8; 17]; 17],
}

impl SelfIntersectionCheck {
    /// Prepares the check from per-vertex reference labels.
    pub fn new(triangles: &[[u32; 3]], labels: &[u8]) -> Self {
        SelfIntersectionCheck {
            tri_labels: triangles
                .iter()
                .map(|t| t.map(|v| labels[v as usize]))
                .collect(),
            hops: segment_hops(),
        }
    }

    /// Intersecting triangle pairs of distant parts (empty = no gross self-intersection).
    pub fn find(&self, mesh: &symcorr_mesh::TriMesh) -> Vec<(usize, usize)> {
        crate::geom::self_intersections(mesh, 0.03, |i, j| {
            self.tri_labels[i].iter().all(|&a| {
                self.tri_labels[j]
                    .iter()
                    .all(|&b| self.hops[a as usize][b as usize] >= 3)
            })
        })
    }
}
