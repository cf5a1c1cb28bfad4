//! Virtual-Kinect outputs: a single-view scan with per-pixel ground truth, and sequences.
//!
//! Scan folder: `depth.png` (PNG-16, z in mm, 0 = none), `vertex_ids.png` (PNG-16, body vertex
//! id + 1 per pixel, 0 = none), `intrinsics.json` (`symcorr.intrinsics/1`), `camera.json`
//! (position, look-at, the world → camera rigid transform, the body mesh it saw), `joints.json`
//! (`symcorr.joints/1`, Kinect camera space).
//!
//! Sequence folder: `depth/frame_NNN.png`, `joints.json` (one frame per depth frame, `time_s`
//! = frame / fps), `intrinsics.json`, `camera.json`.

use std::path::Path;

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde_json::json;
use symcorr_kinect::joints::{write_joints_json, JointFrame, JointLog};
use symcorr_kinect::write_depth_png16;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{Joint, Skeleton};

use crate::body::{Body, Pose};
use crate::dataset::{mkdir, write_text};
use crate::error::{Result, SynthError};
use crate::mapping::kinect_joints;
use crate::math::Rigid;
use crate::poses::unit_f64;
use crate::render::{render, Camera, Realism, Rendering, NO_VERTEX};
use crate::tracker::{tracker_joints, TrackerNoise};

fn kerr(e: symcorr_kinect::KinectError) -> SynthError {
    SynthError::Invalid(e.to_string())
}

/// A skeleton moved into camera space.
pub fn skeleton_to_camera(s: &Skeleton, to_cam: &Rigid) -> Skeleton {
    let mut out = s.clone();
    for p in out.positions.iter_mut() {
        *p = to_cam.apply((*p).into()).into();
    }
    out
}

fn write_camera_files(
    out: &Path,
    camera: &Camera,
    mesh_ref: &str,
    realism: &Realism,
) -> Result<()> {
    let k = serde_json::to_string(&camera.intrinsics)
        .map_err(|e| SynthError::Invalid(e.to_string()))?;
    write_text(&out.join("intrinsics.json"), &(k + "\n"))?;
    write_camera_json(out, camera, mesh_ref, realism)
}

/// Writes `camera.json`: the camera's position, look-at point, world → camera transform, the
/// body mesh it saw (`mesh_ref`) and the realism settings.
pub(crate) fn write_camera_json(
    out: &Path,
    camera: &Camera,
    mesh_ref: &str,
    realism: &Realism,
) -> Result<()> {
    let cam = camera_json(camera, mesh_ref, realism);
    let text =
        serde_json::to_string_pretty(&cam).map_err(|e| SynthError::Invalid(e.to_string()))?;
    write_text(&out.join("camera.json"), &(text + "\n"))
}

/// The `symcorr.synth-camera/1` object of `write_camera_json` (a scan's `camera.json`).
pub fn camera_json(camera: &Camera, mesh_ref: &str, realism: &Realism) -> serde_json::Value {
    let t = camera.world_to_camera();
    // The file keeps its layout: rotation as rows, translation as an array.
    let rotation_rows: [[f64; 3]; 3] = [0, 1, 2].map(|k| t.r.row(k).transpose().into());
    let translation: [f64; 3] = t.t.into();
    let mut cam = json!({
        "format": "symcorr.synth-camera/1",
        "position": camera.position,
        "look_at": camera.look_at,
        "world_to_camera": {"rotation_rows": rotation_rows, "translation": translation},
        "body": mesh_ref,
        "realism": {
            "axial_noise": realism.axial_noise, "quantise": realism.quantise,
            "grazing_deg": realism.grazing_deg, "edge_dropout": realism.edge_dropout,
            "floor": realism.floor, "wall": realism.wall, "seed": realism.seed,
        },
    });
    if realism.has_v1_terms() {
        // Only then, so that the files of the other presets stay as they were.
        cam["realism"]["axial_coeff"] = json!(realism.axial_coeff);
        cam["realism"]["silhouette_jump_m"] = json!(realism.silhouette_jump_m);
        cam["realism"]["random_dropout"] = json!(realism.random_dropout);
        cam["realism"]["ir_shadow"] = json!(realism.ir_shadow);
    }
    cam
}

/// Renders one view of a posed body and writes the scan folder (see module docs). `mesh_ref`
/// names the world-frame body mesh in `camera.json`.
pub fn write_scan(
    out: &Path,
    mesh: &TriMesh,
    joints_world: &Skeleton,
    camera: &Camera,
    realism: &Realism,
    mesh_ref: &str,
) -> Result<Rendering> {
    mkdir(out)?;
    let r = render(mesh, camera, realism, 0);
    write_depth_png16(out.join("depth.png"), &r.depth_frame()).map_err(kerr)?;
    write_depth_png16(out.join("vertex_ids.png"), &r.vertex_id_frame()).map_err(kerr)?;
    let cam_joints = skeleton_to_camera(joints_world, &camera.world_to_camera());
    let log = JointLog::from_skeletons(vec![cam_joints], symcorr_kinect::joints::KINECT_FPS);
    write_joints_json(out.join("joints.json"), &log).map_err(kerr)?;
    write_camera_files(out, camera, mesh_ref, realism)?;
    Ok(r)
}

/// Renders `poses` of `body` as a sequence at `fps` and writes the sequence folder.
pub fn write_sequence(
    out: &Path,
    body: &Body<'_>,
    poses: &[Pose],
    fps: f64,
    camera: &Camera,
    realism: &Realism,
) -> Result<()> {
    mkdir(&out.join("depth"))?;
    let to_cam = camera.world_to_camera();
    let mut frames = Vec::new();
    for (f, pose) in poses.iter().enumerate() {
        let posed = body.pose(pose)?;
        let r = render(&posed.mesh, camera, realism, f as u64);
        write_depth_png16(
            out.join("depth").join(format!("frame_{f:03}.png")),
            &r.depth_frame(),
        )
        .map_err(kerr)?;
        frames.push(JointFrame {
            time_s: f as f64 / fps,
            skeleton: skeleton_to_camera(&kinect_joints(body, &posed)?, &to_cam),
        });
    }
    let log = JointLog {
        skeleton_kind: symcorr_kinect::mapping::SkeletonKind::KinectV1,
        frames,
    };
    write_joints_json(out.join("joints.json"), &log).map_err(kerr)?;
    write_camera_files(out, camera, "(posed per frame; see joints.json)", realism)
}

/// A single-view scan as a benchmark target: the mesh `symcorr_kinect::scan_mesh` builds from
/// one rendered view ([`scan_options`]), the joints in camera space, and
/// per scan vertex the body vertex seen at its pixel (`None` where no body vertex was: floor,
/// wall) — the `truth/NAME.txt` of a symcorr benchmark dataset.
pub struct ScanTarget {
    /// The scan mesh (Kinect camera space).
    pub mesh: TriMesh,
    /// The skeleton in camera space.
    pub joints: Skeleton,
    /// Body vertex per scan vertex.
    pub truth: Vec<Option<u32>>,
    /// Joints a tracker would infer (not seen; see [`crate::tracker`]); all `false` for exact
    /// joints.
    pub inferred: [bool; Joint::COUNT],
}

/// The scan options of [`scan_target`]: the default ones with only the largest component kept,
/// as when the benchmark scans (`bodies20_scans`), the committed test scans and the MakeHuman
/// boundary convention's training scans were made — they stay reproducible bit for bit. The
/// default (`ComponentFilter::NearBones`) keeps more only where a view splits the body (a body
/// turned sideways), which these mostly frontal views seldom do.
pub fn scan_options() -> symcorr_kinect::ScanOptions {
    symcorr_kinect::ScanOptions {
        components: symcorr_kinect::ComponentFilter::Largest,
        ..symcorr_kinect::ScanOptions::default()
    }
}

/// Renders `mesh` (world frame) from `camera` and turns the view into a [`ScanTarget`].
/// `stream` separates the sensor noise of different bodies that share a seed.
pub fn scan_target(
    mesh: &TriMesh,
    joints_world: &Skeleton,
    camera: &Camera,
    realism: &Realism,
    stream: u64,
) -> Result<ScanTarget> {
    scan_target_with(
        mesh,
        joints_world,
        camera,
        realism,
        stream,
        &scan_options(),
        None,
    )
}

/// [`scan_target`] with the scan options `options` and, with `tracker = Some((noise, labels))`,
/// tracker joints ([`crate::tracker::tracker_joints`]; `labels` = reference segment label per
/// mesh vertex) instead of the exact ones; the scan mesh is built with the joints it reports.
pub fn scan_target_with(
    mesh: &TriMesh,
    joints_world: &Skeleton,
    camera: &Camera,
    realism: &Realism,
    stream: u64,
    options: &symcorr_kinect::ScanOptions,
    tracker: Option<(&TrackerNoise, &[u8])>,
) -> Result<ScanTarget> {
    let r = render(mesh, camera, realism, stream);
    let exact = skeleton_to_camera(joints_world, &camera.world_to_camera());
    let (joints, inferred) = match tracker {
        Some((noise, labels)) => {
            tracker_joints(&exact, &r, &camera.intrinsics, labels, noise, stream)
        }
        None => (exact, [false; Joint::COUNT]),
    };
    let scan =
        symcorr_kinect::scan_mesh(&r.depth_frame(), &camera.intrinsics, Some(&joints), options)
            .map_err(kerr)?;
    let truth = scan
        .pixel_ids
        .iter()
        .map(|&px| match r.vertex_id.get(px as usize) {
            Some(&v) if v != NO_VERTEX => Some(v),
            _ => None,
        })
        .collect();
    Ok(ScanTarget {
        mesh: scan.mesh,
        joints,
        truth,
        inferred,
    })
}

/// How the cameras of a scan dataset are drawn, per body: the horizontal distance to the body's
/// centre (the middle of its bounding box, which the camera looks at), the azimuth about the
/// vertical through it (0 = the subject faces the camera, positive = toward the subject's left),
/// its magnitude uniform in `abs_azimuth_deg` and its side ± with probability ½, and the height
/// above the floor (the body's lowest point); each uniform, from a ChaCha8 stream per body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSampling {
    /// Horizontal distance range, metres.
    pub distance_m: (f64, f64),
    /// Range of |azimuth|, degrees.
    pub abs_azimuth_deg: (f64, f64),
    /// Camera height above the floor, metres.
    pub height_m: (f64, f64),
    /// Seed of the ChaCha8 stream.
    pub seed: u64,
}

/// One drawn camera of [`CameraSampling`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledView {
    /// The camera (body frame).
    pub camera: Camera,
    /// Horizontal distance to the look-at point, metres.
    pub distance_m: f64,
    /// Azimuth, degrees.
    pub azimuth_deg: f64,
    /// Height above the floor, metres.
    pub height_m: f64,
}

impl CameraSampling {
    /// Users' scans: 2.5–3.2 m away, azimuth uniform in ±35°, camera 0.6–1.6 m high.
    pub fn frontal(seed: u64) -> CameraSampling {
        CameraSampling {
            distance_m: (2.5, 3.2),
            abs_azimuth_deg: (0.0, 35.0),
            height_m: (0.6, 1.6),
            seed,
        }
    }

    /// Profile views: as [`CameraSampling::frontal`] with |azimuth| in 60–90°, either side.
    pub fn profile(seed: u64) -> CameraSampling {
        CameraSampling {
            abs_azimuth_deg: (60.0, 90.0),
            ..CameraSampling::frontal(seed)
        }
    }

    /// The camera of body number `stream` whose posed mesh is `mesh` (body frame).
    pub fn draw(&self, mesh: &TriMesh, stream: u64) -> SampledView {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(stream);
        let mut uniform = |(lo, hi): (f64, f64)| lo + (hi - lo) * unit_f64(&mut rng);
        let distance_m = uniform(self.distance_m);
        let abs_az = uniform(self.abs_azimuth_deg);
        let height_m = uniform(self.height_m);
        let side = if uniform((0.0, 1.0)) < 0.5 { -1.0 } else { 1.0 };
        let azimuth_deg = side * abs_az;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &mesh.positions {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        let look_at = [0, 1, 2].map(|c| 0.5 * (lo[c] + hi[c]));
        let (s, c) = azimuth_deg.to_radians().sin_cos();
        let position = [
            look_at[0] + distance_m * s,
            lo[1] + height_m,
            look_at[2] + distance_m * c,
        ];
        SampledView {
            camera: Camera::kinect_v1(position, look_at),
            distance_m,
            azimuth_deg,
            height_m,
        }
    }
}
