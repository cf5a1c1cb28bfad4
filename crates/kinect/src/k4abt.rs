//! The Azure Kinect Body Tracking SDK's JSON (`k4abt`, the SDK's `offline_processor` sample's
//! output; Orbbec's Femto cameras run the same SDK):
//!
//! ```text
//! { "k4abt_sdk_version": "1.1.2", "source_file": "take.mkv",
//!   "joint_names": ["PELVIS", "SPINE_NAVEL", …],            (32, k4abt_joint_id_t order)
//!   "bone_list": [["SPINE_CHEST", "SPINE_NAVEL"], …],
//!   "frames": [ { "frame_id": 0, "timestamp_usec": 233344, "num_bodies": 1,
//!                 "bodies": [ { "body_id": 1,
//!                               "joint_positions": [[x, y, z], …],        (32, millimetres)
//!                               "joint_orientations": [[w, x, y, z], …] } ] }, … ] }
//! ```
//!
//! Positions are in the depth camera's frame: millimetres, +x right and +y down as the image
//! shows them, +z into the scene. Kinect camera space (DESIGN.md, [`crate::camera`]) has +x to
//! the sensor's left and +y up, so a position `(x, y, z)` becomes `(−x, −y, z) / 1000` metres: a
//! turn by half a turn about the optical axis, not a mirror, so the subject's left stays their
//! left. The SDK's depth images are not mirrored: a recording folder made from them keeps them as
//! they are with `"mirrored": false` in its intrinsics ([`crate::Mirroring::Direct`]), and the
//! device's depth calibration (`k4a_calibration_intrinsic_parameters_t`) gives
//! `"distortion": [k1, k2, p1, p2, k3, k4, k5, k6]` ([`crate::Distortion`]; the SDK's
//! Brown–Conrady model is OpenCV's when its centre of distortion `codx`, `cody` is zero, and
//! symcorr models no other).
//!
//! A frame's time is its `timestamp_usec` (the device clock, in µs; the depth frames' times of a
//! recording folder made from the same capture are on that clock). The joints map onto the
//! canonical skeleton with the table in [`crate::mapping`]; the file has no per-joint
//! confidence, so every joint of a body is tracked (confidence 1). With several bodies the one
//! selected ([`BodySelect`]: by default the body present in the most frames, the first seen on
//! a tie) is kept; a frame without it is kept as a frame in which the tracker lost the body
//! (every joint untracked), so that a recording's frame at that time is reported as such. The
//! nose and the ears say how far the head is turned against the chest
//! ([`Skeleton::head_turn`](symcorr_skeleton::Skeleton::head_turn), from
//! [`head_turn_from_face`]): the joints do not show a head turning about its own bone. The
//! orientations and the bone list are not read.

use crate::error::KinectError;
use crate::joints::{most_tracked, BodySelect, JointFrame, JointLog};
use crate::mapping::{
    head_turn_from_face, neck_axis_and_chest, FacePoints, Partial, SkeletonKind, AZURE_KINECT_NAMES,
};
use nalgebra::Point3;
use serde::Deserialize;
use serde_json::error::Category;

/// Keys only a `k4abt` file has ([`JointFormat::detect`](crate::JointFormat::detect) looks for
/// them in a JSON file).
pub(crate) const K4ABT_KEYS: [&str; 2] = ["\"k4abt_sdk_version\"", "\"joint_positions\""];

#[derive(Deserialize)]
struct File {
    joint_names: Option<Vec<String>>,
    frames: Option<Vec<Frame>>,
}

#[derive(Deserialize)]
struct Frame {
    timestamp_usec: Option<f64>,
    bodies: Option<Vec<Body>>,
}

#[derive(Deserialize)]
struct Body {
    body_id: Option<u64>,
    joint_positions: Option<Vec<[f64; 3]>>,
}

/// Parses an Azure Kinect Body Tracking JSON file keeping the selected body; `file` names it in
/// errors.
///
/// Errors: [`KinectError::Json`] for text that is not JSON or not of this shape (no `frames`,
/// a joint name the SDK does not have, no timestamps); [`KinectError::Frame`] naming the frame
/// for a body without an id, a position list of another length than the joint names, or a
/// coordinate that is not a finite number; [`KinectError::NoBody`] when no frame has a body (or
/// the one asked for).
///
/// ```
/// use symcorr_kinect::k4abt::parse_k4abt;
/// use symcorr_kinect::joints::BodySelect;
/// use symcorr_skeleton::Joint;
/// // One frame, one body: joint j at x = 20·j mm (right in the image), 10 cm up, 2.5 m away.
/// let joints: Vec<String> = (0..32).map(|j| format!("[{}, -100, 2500]", 20 * j)).collect();
/// let text = format!(
///     r#"{{"k4abt_sdk_version": "1.1.2", "frames": [{{"timestamp_usec": 500000,
///        "bodies": [{{"body_id": 1, "joint_positions": [{}]}}]}}]}}"#,
///     joints.join(", ")
/// );
/// let log = parse_k4abt(&text, "take.json", BodySelect::MostTracked).unwrap();
/// let frame = &log.frames[0];
/// assert_eq!(frame.time_s, 0.5);
/// // The neck (joint 3) is the shoulder centre: 60 mm to the image's right is the sensor's
/// // right, −x in Kinect space; 100 mm up is +y.
/// let p = frame.skeleton.position(Joint::ShoulderCenter);
/// assert!((p.x + 0.06).abs() < 1e-12 && (p.y - 0.1).abs() < 1e-12 && (p.z - 2.5).abs() < 1e-12);
/// ```
pub fn parse_k4abt(text: &str, file: &str, select: BodySelect) -> Result<JointLog, KinectError> {
    let json_err = |message: String| KinectError::Json {
        file: file.to_string(),
        message,
    };
    let frame_err = |frame: usize, message: String| KinectError::Frame {
        file: file.to_string(),
        frame,
        message,
    };
    let text = text.trim_start_matches('\u{feff}');
    if !text.trim_start().starts_with('{') {
        return Err(json_err("expected a JSON object at the top level".into()));
    }
    let root: File = serde_json::from_str(text).map_err(|e| {
        json_err(match e.classify() {
            Category::Data => format!("not an Azure Kinect body tracking file: {e}"),
            _ => format!("invalid JSON: {e}"),
        })
    })?;
    // Native index (into AZURE_KINECT_NAMES) of each position of a body.
    let order: Vec<usize> = match &root.joint_names {
        None => (0..AZURE_KINECT_NAMES.len()).collect(),
        Some(names) => names
            .iter()
            .map(|n| {
                let lower = n.to_ascii_lowercase();
                AZURE_KINECT_NAMES
                    .iter()
                    .position(|k| *k == lower)
                    .ok_or_else(|| {
                        json_err(format!(
                            "joint_names: {:?} is not an Azure Kinect body tracking joint",
                            crate::joints::quote(n)
                        ))
                    })
            })
            .collect::<Result<_, _>>()?,
    };
    if let Some(d) = (0..order.len()).find(|&i| order[..i].contains(&order[i])) {
        return Err(json_err(format!(
            "joint_names: {:?} is listed twice",
            AZURE_KINECT_NAMES[order[d]]
        )));
    }
    let frames = root
        .frames
        .ok_or_else(|| json_err("missing \"frames\" (an array)".into()))?;
    if frames.is_empty() {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: "the joint file has no frames".into(),
        });
    }
    // Each body's positions, checked, per frame.
    let mut bodies: Vec<Vec<(u64, Vec<[f64; 3]>)>> = Vec::with_capacity(frames.len());
    let mut times = Vec::with_capacity(frames.len());
    for (fi, frame) in frames.into_iter().enumerate() {
        let t = frame
            .timestamp_usec
            .ok_or_else(|| frame_err(fi, "missing \"timestamp_usec\" (a number)".into()))?;
        if !(t.is_finite() && t >= 0.0) {
            return Err(frame_err(
                fi,
                format!("timestamp_usec is {t}, expected a number ≥ 0"),
            ));
        }
        times.push(t * 1e-6);
        let mut kept = Vec::new();
        for (bi, body) in frame.bodies.unwrap_or_default().into_iter().enumerate() {
            let id = body
                .body_id
                .ok_or_else(|| frame_err(fi, format!("body {bi}: missing \"body_id\"")))?;
            let positions = body
                .joint_positions
                .ok_or_else(|| frame_err(fi, format!("body {bi}: missing \"joint_positions\"")))?;
            if positions.len() != order.len() {
                return Err(frame_err(
                    fi,
                    format!(
                        "body {bi}: {} joint positions for {} joints",
                        positions.len(),
                        order.len()
                    ),
                ));
            }
            if let Some((j, p)) = positions
                .iter()
                .enumerate()
                .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
            {
                return Err(frame_err(
                    fi,
                    format!("body {bi}, joint {j}: position {p:?} is not finite"),
                ));
            }
            kept.push((id, positions));
        }
        bodies.push(kept);
    }
    let id = match select {
        BodySelect::Id(id) => id,
        BodySelect::MostTracked => {
            // Every joint of a present body is tracked: the body in the most frames.
            most_tracked(bodies.iter().flatten().map(|b| (b.0, 1))).ok_or_else(|| {
                KinectError::NoBody {
                    file: file.to_string(),
                    message: format!("no frame of the {} has a body", bodies.len()),
                }
            })?
        }
    };
    if !bodies.iter().flatten().any(|b| b.0 == id) {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: format!("no frame of the {} has body {id}", bodies.len()),
        });
    }
    let mut out = Vec::with_capacity(bodies.len());
    for (fi, (frame, time_s)) in bodies.iter().zip(times).enumerate() {
        // The body's positions in Kinect space, by native index.
        let mut native = [None; AZURE_KINECT_NAMES.len()];
        if let Some((_, positions)) = frame.iter().find(|b| b.0 == id) {
            for (&k, p) in order.iter().zip(positions) {
                native[k] = Some(Point3::new(-p[0], -p[1], p[2]) * 1e-3);
            }
        }
        let mut partial = Partial::new();
        for (k, p) in native.iter().enumerate() {
            if let (Some(p), Some(j)) = (p, SkeletonKind::AzureKinect.canonical(k)) {
                partial.set(j, *p, 1.0);
            }
        }
        let mut skeleton = partial.complete().map_err(|j| {
            frame_err(
                fi,
                format!(
                    "joint {:?}: its estimate from its neighbours is not a finite position",
                    j.name()
                ),
            )
        })?;
        let at = |name: &str| {
            let k = AZURE_KINECT_NAMES.iter().position(|n| *n == name)?;
            native[k]
        };
        if let (Some(nose), Some(left), Some(right)) = (at("nose"), at("ear_left"), at("ear_right"))
        {
            let face = FacePoints {
                nose,
                ears: [left, right],
            };
            skeleton.head_turn = head_turn_from_face(&skeleton, &face);
        }
        out.push(JointFrame { time_s, skeleton });
    }
    Ok(JointLog {
        skeleton_kind: SkeletonKind::AzureKinect,
        frames: out,
    })
}

/// Where [`to_k4abt_json`] puts the face of a skeleton whose head is turned by
/// [`Skeleton::head_turn`](symcorr_skeleton::Skeleton::head_turn): the head joint, the unit
/// direction the face looks (the chest's forward direction turned that far about the neck →
/// head axis) and the unit direction towards the subject's left across it. `None` without a
/// turn or a chest direction.
fn face_axes(
    s: &symcorr_skeleton::Skeleton,
) -> Option<(Point3<f64>, nalgebra::Vector3<f64>, nalgebra::Vector3<f64>)> {
    let turn = s.head_turn?;
    let (up, across) = neck_axis_and_chest(s)?;
    let chest = crate::geom::normalize(across)?;
    let looks =
        nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(up), turn) * chest;
    Some((
        s.position(symcorr_skeleton::Joint::Head),
        looks,
        up.cross(&looks),
    ))
}

/// The face point `name` (`nose`, `eye_*`, `ear_*`) on a head 15 cm wide at `face` (from
/// [`face_axes`]); `None` for another name.
fn face_point(
    (head, looks, left): (Point3<f64>, nalgebra::Vector3<f64>, nalgebra::Vector3<f64>),
    name: &str,
) -> Option<Point3<f64>> {
    let offset = match name {
        "nose" => looks * 0.10,
        "eye_left" => looks * 0.08 + left * 0.03,
        "eye_right" => looks * 0.08 - left * 0.03,
        "ear_left" => left * 0.075,
        "ear_right" => -left * 0.075,
        _ => return None,
    };
    Some(head + offset)
}

/// The Azure Kinect Body Tracking JSON of a log, as the SDK's `offline_processor` writes it
/// (the canonical joints turned into its depth camera's frame, millimetres; `timestamp_usec`
/// from each frame's time, rounded to the microsecond; one body, id 1, in every frame that
/// tracks a joint, none in the others). The SDK's joints the canonical skeleton lacks are placed
/// on it: `spine_chest` midway spine → shoulder centre, each clavicle 30 % of the way shoulder
/// centre → shoulder, each thumb 80 % of the way wrist → hand, each hand tip half a wrist → hand
/// beyond the hand, the nose, eyes and ears at the head — or, for a skeleton that reports the
/// head's turn, on a head looking that way, so that reading it back gives the turn. The file
/// has no confidences: an untracked joint of a tracked frame is written where it is, and a time
/// before 0 gives a timestamp the reader refuses. For conversions and tests; [`parse_k4abt`]
/// reads it back to the same canonical positions.
pub fn to_k4abt_json(log: &JointLog) -> String {
    use symcorr_skeleton::Joint as J;
    let mut out = String::from("{\n  \"k4abt_sdk_version\": \"1.1.2\",\n  \"joint_names\": [");
    let names: Vec<String> = AZURE_KINECT_NAMES
        .iter()
        .map(|n| format!("\"{}\"", n.to_ascii_uppercase()))
        .collect();
    out.push_str(&names.join(", "));
    out.push_str("],\n  \"frames\": [");
    for (fi, frame) in log.frames.iter().enumerate() {
        let s = &frame.skeleton;
        let face = face_axes(s);
        let p = |j: J| s.position(j);
        // Where the estimate overflows (coordinates near f64::MAX), the joint it leans on.
        let lerp = |a: J, b: J, t: f64| {
            let q = p(a) + (p(b) - p(a)) * t;
            if q.iter().all(|c| c.is_finite()) {
                q
            } else {
                p(b)
            }
        };
        let positions: Vec<Point3<f64>> = (0..AZURE_KINECT_NAMES.len())
            .map(|native| match SkeletonKind::AzureKinect.canonical(native) {
                Some(j) => p(j),
                None => match AZURE_KINECT_NAMES[native] {
                    "spine_chest" => lerp(J::Spine, J::ShoulderCenter, 0.5),
                    "clavicle_left" => lerp(J::ShoulderCenter, J::ShoulderLeft, 0.3),
                    "clavicle_right" => lerp(J::ShoulderCenter, J::ShoulderRight, 0.3),
                    "thumb_left" => lerp(J::WristLeft, J::HandLeft, 0.8),
                    "thumb_right" => lerp(J::WristRight, J::HandRight, 0.8),
                    "handtip_left" => lerp(J::WristLeft, J::HandLeft, 1.5),
                    "handtip_right" => lerp(J::WristRight, J::HandRight, 1.5),
                    name => face
                        .and_then(|f| face_point(f, name))
                        .unwrap_or_else(|| p(J::Head)),
                },
            })
            .collect();
        let bodies = if s.tracks_any() {
            let joints: Vec<String> = positions
                .iter()
                .map(|q| {
                    // Beyond ±1.8·10³⁰⁵ m a millimetre overflows: such a joint is no body's.
                    let mm = |c: f64| (c * 1e3).clamp(-f64::MAX, f64::MAX);
                    format!("[{}, {}, {}]", mm(-q.x), mm(-q.y), mm(q.z))
                })
                .collect();
            format!(
                "{{\"body_id\": 1, \"joint_positions\": [{}]}}",
                joints.join(", ")
            )
        } else {
            String::new()
        };
        out.push_str(if fi == 0 { "\n    " } else { ",\n    " });
        out.push_str(&format!(
            "{{\"frame_id\": {fi}, \"timestamp_usec\": {}, \"num_bodies\": {}, \"bodies\": [{bodies}]}}",
            (frame.time_s * 1e6).round(),
            usize::from(s.tracks_any())
        ));
    }
    out.push_str("\n  ]\n}\n");
    out
}
