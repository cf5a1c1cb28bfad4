//! Synthetic Kinect recordings: the project's recording folder (`symcorr.recording/1`), as
//! `symcorr track` reads it, with a joint log corrupted the way real trackers corrupt theirs and
//! the ground truth beside it.
//!
//! Motion: the body walks in place ([`walk_pose`]) while turning about the vertical axis from
//! facing the camera to `max_turn_deg` (profile at 90°) and back: turn(t) = max ·
//! (1 − cos 2πt/T)/2 over the recording's duration T; with `head_turn_deg` the head also turns
//! against the chest (a subject looking around: [`head_turn_deg`]). Each depth frame is rendered
//! by the virtual Kinect ([`render`]) with the given realism; frame `f` uses noise stream `f`.
//!
//! Folder (other tools write the same layout):
//! * `intrinsics.json` — `symcorr.intrinsics/1` ([`symcorr_kinect::Intrinsics`]);
//! * `depth/NNNNNN.png` — PNG-16 depth in mm (0 = no reading), six-digit frame numbers from 0;
//! * `depth_times.txt` — one line per depth frame: its time in seconds (decimal text);
//! * `joints.json` — the joint log (`symcorr.joints/1`) with its own frame times;
//! * `truth/NNNNNN.png` — PNG-16, per pixel the id + 1 of the body-model vertex seen, 0 = none;
//! * `truth/joints.json` — the exact joints (camera space) at the depth frames' times;
//! * `recording.json` — the manifest (`symcorr.recording/1`): frame count, rates, every
//!   corruption applied to the joint log, the turn per frame, the generating settings;
//! * `camera.json` — the virtual camera's pose and realism (as in the scan folder).
//!
//! Corruptions of `joints.json` (all from one seeded ChaCha8 stream, bit-for-bit reproducible):
//! * clock: the log's frames are exactly `1/fps` apart and its clock runs
//!   [`JOINT_CLOCK_OFFSET_S`] ahead (log time = true time + 0.04 s), while the depth frames'
//!   times are jittered by up to ±[`DEPTH_TIME_JITTER_S`] around `f/fps`; log frame `k` shows
//!   the body at true time `k/fps`;
//! * jitter: Gaussian per coordinate, σ growing with the joint's depth z from 1 cm (z ≤ 2 m) to
//!   3 cm (z ≥ 4 m), doubled for inferred joints ([`jitter_sigma_m`]);
//! * inferred joints: while the turn exceeds [`INFERRED_MIN_TURN_DEG`], the far-side elbow,
//!   wrist, hand, knee, ankle and foot get confidence [`INFERRED_CONFIDENCE`] (the Kinect SDK's
//!   "inferred" state);
//! * leg swaps: a few runs of 3–6 frames, only while the turn exceeds [`SWAP_MIN_TURN_DEG`], in
//!   which the left and right hip, knee, ankle and foot are exchanged (positions and confidences);
//! * lost body: two consecutive frames in which the tracker saw no body. A `symcorr.joints/1`
//!   frame must name all 20 joints, so these frames are kept with every joint at (0, 0, 0) and
//!   confidence 0 — what the Kinect SDK reports for an untracked skeleton.

use std::path::Path;

use nalgebra::Point3;
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use serde_json::json;
use symcorr_kinect::joints::{write_joints_json, JointFrame, JointLog};
use symcorr_kinect::k4abt::to_k4abt_json;
use symcorr_kinect::mapping::{head_turn_from_face, FacePoints, SkeletonKind};
use symcorr_kinect::{write_depth_png16, Intrinsics};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{Joint, Skeleton};

use crate::body::Body;
use crate::dataset::{mkdir, write_text};
use crate::error::{Result, SynthError};
use crate::fixtures::WALK_PERIOD_S;
use crate::kinect::skeleton_to_camera;
use crate::mapping::{face_points, kinect_joints};
use crate::noise::standard_normal;
use crate::poses::{unit_f64, walk_pose, WalkCurves};
use crate::render::{render, Camera, Realism};

/// The `format` tag of `recording.json`.
pub const RECORDING_FORMAT: &str = "symcorr.recording/1";

/// The joint log's clock runs this much ahead of the depth clock (seconds).
pub const JOINT_CLOCK_OFFSET_S: f64 = 0.04;

/// Depth frame times are `f/fps` plus a uniform jitter within ± this (seconds).
pub const DEPTH_TIME_JITTER_S: f64 = 0.003;

/// Leg swaps happen only while the body is turned more than this from the camera (degrees).
pub const SWAP_MIN_TURN_DEG: f64 = 50.0;

/// Far-side limb joints are reported as inferred while the turn exceeds this (degrees).
pub const INFERRED_MIN_TURN_DEG: f64 = 60.0;

/// Confidence of an inferred joint (the Kinect SDK's "inferred" tracking state).
pub const INFERRED_CONFIDENCE: f64 = 0.5;

/// Shortest and longest leg swap, frames.
pub const SWAP_FRAMES: (usize, usize) = (3, 6);

/// Sideways frames per leg swap (at least one swap when any run of sideways frames fits one).
pub const SIDEWAYS_FRAMES_PER_SWAP: usize = 45;

/// The leg joints a swap exchanges, as (left, right) pairs.
pub const LEG_PAIRS: [(Joint, Joint); 4] = [
    (Joint::HipLeft, Joint::HipRight),
    (Joint::KneeLeft, Joint::KneeRight),
    (Joint::AnkleLeft, Joint::AnkleRight),
    (Joint::FootLeft, Joint::FootRight),
];

/// Far-side joints flagged inferred in profile: (left-side joints, right-side joints).
const FAR_SIDE: [(Joint, Joint); 6] = [
    (Joint::ElbowLeft, Joint::ElbowRight),
    (Joint::WristLeft, Joint::WristRight),
    (Joint::HandLeft, Joint::HandRight),
    (Joint::KneeLeft, Joint::KneeRight),
    (Joint::AnkleLeft, Joint::AnkleRight),
    (Joint::FootLeft, Joint::FootRight),
];

/// The command that regenerates the committed recording `fixtures/synth/recording/` (run from
/// the workspace root after `cargo build --release -p symcorr-synth`, or through `cargo run`);
/// its manifest stores this text. [`fixture_recording`] gives the same settings.
pub const FIXTURE_COMMAND: &str = "symcorr-synth recording --frames 60 --fps 30 --width 320 \
     --height 240 --seed 7 --out fixtures/synth/recording";

/// The settings of the committed recording: 60 frames at 30 fps, 320×240, seed 7 (corruptions
/// and sensor noise), the command-line defaults otherwise (camera at (0, 0, 2.6) looking at
/// (0, −0.05, 0), Kinect realism, a turn to 90°).
///
/// Errors: none in practice (the intrinsics are valid); typed for the caller's `?`.
pub fn fixture_recording() -> Result<(RecordingSpec, Camera, Realism)> {
    let camera = Camera {
        intrinsics: kinect_v1_intrinsics(320, 240)?,
        ..Camera::kinect_v1([0.0, 0.0, 2.6], [0.0, -0.05, 0.0])
    };
    let spec = RecordingSpec {
        frames: 60,
        fps: 30.0,
        max_turn_deg: 90.0,
        head_turn_deg: 0.0,
        seed: 7,
        command: FIXTURE_COMMAND.into(),
    };
    Ok((spec, camera, Realism::kinect(7)))
}

/// First noise stream of the face points' jitter (one per frame, after it the frame number).
const FACE_STREAM: u64 = 1 << 41;

/// Noise stream of the corruption schedule (frame streams are the frame numbers).
const SCHEDULE_STREAM: u64 = 1 << 40;

/// What to record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSpec {
    /// Number of depth frames (and joint-log frames).
    pub frames: usize,
    /// Nominal frame rate of both streams (frames per second).
    pub fps: f64,
    /// Largest turn about the vertical axis, reached halfway (degrees; 90 = profile).
    pub max_turn_deg: f64,
    /// Largest turn of the head against the chest, about the neck (degrees; 0: the head turns
    /// with the chest), as [`head_turn_deg`].
    pub head_turn_deg: f64,
    /// Seed of the joint-log corruptions and of the depth-time jitter.
    pub seed: u64,
    /// The command that generated the recording (stored in the manifest).
    pub command: String,
}

/// What [`write_recording`] wrote, and the corruptions it applied.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSummary {
    /// Number of frames.
    pub frames: usize,
    /// Depth frame times, seconds.
    pub depth_times_s: Vec<f64>,
    /// The body's turn at each depth frame, degrees.
    pub turn_deg: Vec<f64>,
    /// Leg swaps as inclusive `[first, last]` joint-log frame ranges.
    pub swaps: Vec<[usize; 2]>,
    /// Joint-log frames without a body.
    pub lost_body_frames: Vec<usize>,
    /// Joint-log frames with inferred far-side joints.
    pub inferred_frames: Vec<usize>,
}

/// Kinect v1 intrinsics for a `width × height` depth image: the 640×480 focal length scaled by
/// `width / 640` (square pixels), principal point at the image centre.
///
/// Errors: [`SynthError::Invalid`] when the result fails [`Intrinsics::validate`].
pub fn kinect_v1_intrinsics(width: u32, height: u32) -> Result<Intrinsics> {
    let base = Intrinsics::kinect_v1();
    let f = base.fx * f64::from(width) / f64::from(base.width);
    let k = Intrinsics {
        width,
        height,
        fx: f,
        fy: f,
        cx: f64::from(width) / 2.0,
        cy: f64::from(height) / 2.0,
        ..base
    };
    k.validate()
        .map_err(|e| SynthError::Invalid(e.to_string()))?;
    Ok(k)
}

/// The body's turn about the vertical axis at true time `t_s` of a recording lasting
/// `duration_s`, degrees (0 outside the recording).
pub fn turn_deg(t_s: f64, duration_s: f64, max_turn_deg: f64) -> f64 {
    if duration_s <= 0.0 {
        return 0.0;
    }
    let u = (t_s / duration_s).clamp(0.0, 1.0);
    max_turn_deg * (1.0 - (2.0 * std::f64::consts::PI * u).cos()) / 2.0
}

/// A subject looking left and right: how far the head is turned against the chest at true time
/// `t_s`, degrees — `max · sin(2πt / HEAD_TURN_PERIOD_S)`, shared equally by the neck and the
/// head bones as a twist about each (the head joint moves by millimetres: a turn of the head
/// about its own axis is what a skeleton tracker cannot report).
pub fn head_turn_deg(t_s: f64, max_deg: f64) -> f64 {
    max_deg * (2.0 * std::f64::consts::PI * t_s / HEAD_TURN_PERIOD_S).sin()
}

/// Period of [`head_turn_deg`], seconds: a look to one side and the other.
pub const HEAD_TURN_PERIOD_S: f64 = 3.0;

/// σ of the joint jitter per coordinate (metres) for a joint at depth `z_m`: 1 cm up to 2 m,
/// rising linearly to 3 cm at 4 m and beyond; doubled for an inferred joint.
pub fn jitter_sigma_m(z_m: f64, inferred: bool) -> f64 {
    let cm = (1.0 + (z_m - 2.0)).clamp(1.0, 3.0);
    let cm = if inferred { 2.0 * cm } else { cm };
    cm / 100.0
}

/// Moves `p` by Gaussian jitter of [`jitter_sigma_m`] per coordinate (three draws from `rng`).
fn jitter(p: &mut Point3<f64>, inferred: bool, rng: &mut ChaCha8Rng) {
    let sigma = jitter_sigma_m(p.z, inferred);
    for x in p.coords.iter_mut() {
        *x += sigma * standard_normal(rng);
    }
}

fn kerr(e: symcorr_kinect::KinectError) -> SynthError {
    SynthError::Invalid(e.to_string())
}

/// Rotation by `deg` about the world's vertical axis (+y) through the origin.
fn turn_point(p: [f64; 3], deg: f64) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]
}

/// The turned body mesh (world frame), its exact joints (camera space), its turn and its face
/// points (camera space, [`face_points`]) at true time `t_s`.
fn body_at(
    body: &Body<'_>,
    walk: Option<&WalkCurves>,
    spec: &RecordingSpec,
    camera: &Camera,
    t_s: f64,
) -> Result<(TriMesh, Skeleton, f64, FacePoints)> {
    let duration = spec.frames as f64 / spec.fps;
    let turn = turn_deg(t_s, duration, spec.max_turn_deg);
    let mut pose = walk_pose(walk, t_s / WALK_PERIOD_S);
    if spec.head_turn_deg != 0.0 {
        let half = head_turn_deg(t_s, spec.head_turn_deg).to_radians() / 2.0;
        // Euler y: the twist about the bone (a rig bone's y axis runs along it).
        for bone in ["neck_01", "head"] {
            pose.rotations.entry(bone.into()).or_insert([0.0; 3])[1] += half;
        }
    }
    let posed = body.pose(&pose)?;
    let joints = kinect_joints(body, &posed)?;
    let to_cam = camera.world_to_camera();
    let [nose, ear_left, ear_right] =
        face_points(body, &posed)?.map(|p| Point3::from(to_cam.apply(turn_point(p, turn))));
    let face = FacePoints {
        nose,
        ears: [ear_left, ear_right],
    };
    let mut mesh = posed.mesh;
    for p in mesh.positions.iter_mut() {
        *p = turn_point(*p, turn);
    }
    let mut world = joints.clone();
    for p in world.positions.iter_mut() {
        *p = turn_point((*p).into(), turn).into();
    }
    Ok((mesh, skeleton_to_camera(&world, &to_cam), turn, face))
}

/// Runs of consecutive frames among `ok` (inclusive ranges).
fn runs(ok: &[bool]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &b) in ok.iter().chain([false].iter()).enumerate() {
        match (b, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s, i - 1));
                start = None;
            }
            _ => {}
        }
    }
    out
}

/// Chooses the leg swaps among the sideways frames (`turn > SWAP_MIN_TURN_DEG`): about one per
/// [`SIDEWAYS_FRAMES_PER_SWAP`] sideways frames (at least one), 3–6 frames each, at least 3
/// frames apart.
fn plan_swaps(rng: &mut ChaCha8Rng, log_turn: &[f64]) -> Vec<[usize; 2]> {
    let sideways: Vec<bool> = log_turn.iter().map(|&t| t > SWAP_MIN_TURN_DEG).collect();
    let count = sideways.iter().filter(|&&b| b).count();
    let wanted = (count / SIDEWAYS_FRAMES_PER_SWAP).max(usize::from(count > 0));
    let mut taken = vec![false; log_turn.len()];
    let mut swaps: Vec<[usize; 2]> = Vec::new();
    let mut attempts = 0;
    while swaps.len() < wanted && attempts < 1000 {
        attempts += 1;
        let span = SWAP_FRAMES.1 - SWAP_FRAMES.0 + 1;
        let len = SWAP_FRAMES.0 + (rng.next_u64() % span as u64) as usize;
        let starts: Vec<usize> = runs(&sideways)
            .into_iter()
            .filter(|&(a, b)| b + 1 >= a + len)
            .flat_map(|(a, b)| a..=b + 1 - len)
            .filter(|&s| {
                let lo = s.saturating_sub(3);
                let hi = (s + len + 3).min(taken.len());
                !taken[lo..hi].iter().any(|&t| t)
            })
            .collect();
        if starts.is_empty() {
            if len == SWAP_FRAMES.0 {
                break;
            }
            continue;
        }
        let s = starts[(rng.next_u64() % starts.len() as u64) as usize];
        taken[s..s + len].iter_mut().for_each(|t| *t = true);
        swaps.push([s, s + len - 1]);
    }
    swaps.sort_unstable();
    swaps
}

/// Chooses two consecutive frames without a body, not at either end of the recording and at
/// least one frame away from any swap; none when the recording is too short.
fn plan_lost(rng: &mut ChaCha8Rng, frames: usize, swaps: &[[usize; 2]]) -> Vec<usize> {
    let near_swap = |f: usize| swaps.iter().any(|&[a, b]| f + 1 >= a && f <= b + 1);
    let starts: Vec<usize> = (1..frames.saturating_sub(2))
        .filter(|&s| !near_swap(s) && !near_swap(s + 1))
        .collect();
    if starts.is_empty() {
        return Vec::new();
    }
    let s = starts[(rng.next_u64() % starts.len() as u64) as usize];
    vec![s, s + 1]
}

/// Renders a recording of `body` walking in place and turning (see the module docs) and writes
/// the recording folder `out`. `walk` is the walk cycle's curves (`Assets::walk`; `None` keeps
/// the spine still).
///
/// Errors: [`SynthError::Invalid`] for zero frames, a non-positive or non-finite frame rate or
/// turn, or a write failure; posing errors as [`SynthError`].
pub fn write_recording(
    out: &Path,
    body: &Body<'_>,
    walk: Option<&WalkCurves>,
    spec: &RecordingSpec,
    camera: &Camera,
    realism: &Realism,
) -> Result<RecordingSummary> {
    if spec.frames == 0 || !(spec.fps.is_finite() && spec.fps > 0.0) {
        return Err(SynthError::Invalid(
            "a recording needs ≥ 1 frame and a frame rate > 0".into(),
        ));
    }
    if !(spec.head_turn_deg.is_finite() && spec.head_turn_deg.abs() <= 80.0) {
        return Err(SynthError::Invalid(
            "the head's turn against the chest must be within ±80° (a neck's range)".into(),
        ));
    }
    if !(spec.max_turn_deg.is_finite() && spec.max_turn_deg.abs() <= 180.0) {
        return Err(SynthError::Invalid(
            "the largest turn must be within ±180°".into(),
        ));
    }
    // Every frame must be at least a jitter apart from its neighbours in time.
    if 1.0 / spec.fps <= 2.0 * DEPTH_TIME_JITTER_S {
        return Err(SynthError::Invalid(format!(
            "frame rate {} is too high for ±{} s depth-time jitter",
            spec.fps, DEPTH_TIME_JITTER_S
        )));
    }
    let n = spec.frames;
    let k = &camera.intrinsics;
    mkdir(&out.join("depth"))?;
    mkdir(&out.join("truth"))?;

    let mut schedule = ChaCha8Rng::seed_from_u64(spec.seed);
    schedule.set_stream(SCHEDULE_STREAM);
    // Depth times, rounded to microseconds so that the text file holds them exactly.
    let depth_times: Vec<f64> = (0..n)
        .map(|f| {
            let j = (2.0 * unit_f64(&mut schedule) - 1.0) * DEPTH_TIME_JITTER_S;
            ((f as f64 / spec.fps + j) * 1e6).round() / 1e6
        })
        .collect();
    let duration = n as f64 / spec.fps;
    let log_turn: Vec<f64> = (0..n)
        .map(|f| turn_deg(f as f64 / spec.fps, duration, spec.max_turn_deg))
        .collect();
    let swaps = plan_swaps(&mut schedule, &log_turn);
    let lost = plan_lost(&mut schedule, n, &swaps);

    let mut truth_frames = Vec::with_capacity(n);
    let mut log_frames = Vec::with_capacity(n);
    let mut turns = Vec::with_capacity(n);
    let mut inferred_frames = Vec::new();
    let mut head_turns = vec![None; n];
    for f in 0..n {
        // The depth frame and its truth.
        let (mesh, exact, turn, _) = body_at(body, walk, spec, camera, depth_times[f])?;
        turns.push(turn);
        let r = render(&mesh, camera, realism, f as u64);
        let name = format!("{f:06}.png");
        write_depth_png16(out.join("depth").join(&name), &r.depth_frame()).map_err(kerr)?;
        write_depth_png16(out.join("truth").join(&name), &r.vertex_id_frame()).map_err(kerr)?;
        truth_frames.push(JointFrame {
            time_s: depth_times[f],
            skeleton: exact,
        });

        // The joint log's frame f: the body at true time f/fps, corrupted.
        let t_log = f as f64 / spec.fps;
        let (_, exact_log, _, face) = body_at(body, walk, spec, camera, t_log)?;
        let mut s = exact_log.clone();
        if lost.contains(&f) {
            s.positions = [nalgebra::Point3::origin(); Joint::COUNT];
            s.confidence = [0.0; Joint::COUNT];
        } else {
            if log_turn[f].abs() > INFERRED_MIN_TURN_DEG {
                // The far side is the one farther from the camera.
                let left_far = exact_log.position(Joint::ShoulderLeft).z
                    > exact_log.position(Joint::ShoulderRight).z;
                for (l, r) in FAR_SIDE {
                    let j = if left_far { l } else { r };
                    s.confidence[j.index()] = INFERRED_CONFIDENCE;
                }
                inferred_frames.push(f);
            }
            if swaps.iter().any(|&[a, b]| (a..=b).contains(&f)) {
                for (l, r) in LEG_PAIRS {
                    s.positions.swap(l.index(), r.index());
                    s.confidence.swap(l.index(), r.index());
                }
            }
            let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
            rng.set_stream(f as u64);
            for (p, &c) in s.positions.iter_mut().zip(&s.confidence) {
                jitter(p, c < 1.0, &mut rng);
            }
            // The face points jitter as a tracked joint does (their own stream: the joints'
            // noise stays what it was). Read against the jittered joints: the reported turn.
            let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
            rng.set_stream(FACE_STREAM + f as u64);
            let mut jittered = face;
            for p in std::iter::once(&mut jittered.nose).chain(jittered.ears.iter_mut()) {
                jitter(p, false, &mut rng);
            }
            head_turns[f] = head_turn_from_face(&s, &jittered);
        }
        log_frames.push(JointFrame {
            time_s: t_log + JOINT_CLOCK_OFFSET_S,
            skeleton: s,
        });
    }

    let mut log = JointLog {
        skeleton_kind: SkeletonKind::KinectV1,
        frames: log_frames,
    };
    write_joints_json(out.join("joints.json"), &log).map_err(kerr)?;
    // The same log as the Azure Kinect's tracker writes it, which also reports the face.
    for (frame, turn) in log.frames.iter_mut().zip(head_turns) {
        frame.skeleton.head_turn = turn;
    }
    write_text(&out.join("joints_k4abt.json"), &to_k4abt_json(&log))?;
    write_joints_json(
        out.join("truth").join("joints.json"),
        &JointLog {
            skeleton_kind: SkeletonKind::KinectV1,
            frames: truth_frames,
        },
    )
    .map_err(kerr)?;
    k.write(out.join("intrinsics.json")).map_err(kerr)?;
    let times: String = depth_times.iter().map(|t| format!("{t:.6}\n")).collect();
    write_text(&out.join("depth_times.txt"), &times)?;

    let summary = RecordingSummary {
        frames: n,
        depth_times_s: depth_times,
        turn_deg: turns,
        swaps,
        lost_body_frames: lost,
        inferred_frames,
    };
    write_manifest(out, spec, camera, realism, body, &summary)?;
    crate::kinect::write_camera_json(out, camera, "(posed per frame; see truth/)", realism)?;
    Ok(summary)
}

fn write_manifest(
    out: &Path,
    spec: &RecordingSpec,
    camera: &Camera,
    realism: &Realism,
    body: &Body<'_>,
    s: &RecordingSummary,
) -> Result<()> {
    let round3 = |x: f64| (x * 1000.0).round() / 1000.0;
    let mut manifest = json!({
        "format": RECORDING_FORMAT,
        "frames": s.frames,
        "fps": spec.fps,
        "width": camera.intrinsics.width,
        "height": camera.intrinsics.height,
        "files": {
            "intrinsics": "intrinsics.json",
            "depth": "depth/NNNNNN.png",
            "depth_times": "depth_times.txt",
            "joints": "joints.json",
            "joints_k4abt": "joints_k4abt.json",
            "truth_vertex_ids": "truth/NNNNNN.png",
            "truth_joints": "truth/joints.json",
            "camera": "camera.json",
        },
        "body_vertices": body.rest.positions.len(),
        "joint_fps": spec.fps,
        "joint_offset_s": JOINT_CLOCK_OFFSET_S,
        "depth_time_jitter_s": DEPTH_TIME_JITTER_S,
        "jitter": {"sigma_cm_at_2m": 1.0, "sigma_cm_at_4m": 3.0, "inferred_factor": 2.0},
        "swaps": s.swaps,
        "swap_joints": LEG_PAIRS.map(|(l, r)| [l.name(), r.name()]),
        "swap_min_turn_deg": SWAP_MIN_TURN_DEG,
        "inferred_frames": s.inferred_frames,
        "inferred_confidence": INFERRED_CONFIDENCE,
        "inferred_min_turn_deg": INFERRED_MIN_TURN_DEG,
        "lost_body_frames": s.lost_body_frames,
        "lost_body": "frames kept, every joint at (0, 0, 0) with confidence 0",
        "max_turn_deg": spec.max_turn_deg,
        "turn_deg": s.turn_deg.iter().map(|&t| round3(t)).collect::<Vec<_>>(),
        "seed": spec.seed,
        "realism_seed": realism.seed,
        "command": spec.command,
    });
    if spec.head_turn_deg != 0.0 {
        // Only when the head turns: the recordings made before it stay byte for byte the same.
        manifest["head_turn_deg"] = json!(spec.head_turn_deg);
        manifest["head_turn_period_s"] = json!(HEAD_TURN_PERIOD_S);
    }
    let text =
        serde_json::to_string_pretty(&manifest).map_err(|e| SynthError::Invalid(e.to_string()))?;
    write_text(&out.join("recording.json"), &(text + "\n"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turn_goes_to_profile_and_back() {
        assert_eq!(turn_deg(0.0, 2.0, 90.0), 0.0);
        assert!((turn_deg(1.0, 2.0, 90.0) - 90.0).abs() < 1e-12);
        assert!(turn_deg(2.0, 2.0, 90.0).abs() < 1e-12);
        assert_eq!(turn_deg(-1.0, 2.0, 90.0), 0.0);
    }

    #[test]
    fn jitter_grows_with_depth_from_1_to_3_cm() {
        assert_eq!(jitter_sigma_m(1.0, false), 0.01);
        assert!((jitter_sigma_m(3.0, false) - 0.02).abs() < 1e-12);
        assert_eq!(jitter_sigma_m(9.0, false), 0.03);
        assert_eq!(jitter_sigma_m(9.0, true), 0.06);
    }

    #[test]
    fn swaps_stay_in_sideways_runs_and_lost_frames_avoid_them() {
        let turn: Vec<f64> = (0..300)
            .map(|f| turn_deg(f as f64 / 30.0, 10.0, 90.0))
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let swaps = plan_swaps(&mut rng, &turn);
        assert_eq!(swaps.len(), 3);
        for &[a, b] in &swaps {
            assert!((SWAP_FRAMES.0..=SWAP_FRAMES.1).contains(&(b - a + 1)));
            assert!((a..=b).all(|f| turn[f] > SWAP_MIN_TURN_DEG));
        }
        let lost = plan_lost(&mut rng, 300, &swaps);
        assert_eq!(lost.len(), 2);
        assert_eq!(lost[1], lost[0] + 1);
        assert!(lost
            .iter()
            .all(|&f| swaps.iter().all(|&[a, b]| f + 1 < a || f > b + 1)));
        assert!(plan_swaps(&mut rng, &[0.0; 10]).is_empty());
        assert!(plan_lost(&mut rng, 3, &[]).is_empty());
    }

    #[test]
    fn scaled_intrinsics_keep_the_field_of_view() {
        let k = kinect_v1_intrinsics(320, 240).unwrap();
        assert!((k.fx - 285.63).abs() < 1e-9);
        assert_eq!((k.cx, k.cy), (160.0, 120.0));
        assert!(kinect_v1_intrinsics(0, 240).is_err());
    }
}
