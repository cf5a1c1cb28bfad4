//! The committed fixture set (`fixtures/synth/`) and single-body output.

use std::path::{Path, PathBuf};

use crate::body::{Model, Shape};
use crate::dataset::{write_dataset, write_joints, write_text, DatasetSpec, MeshFormat};
use crate::error::Result;
use crate::kinect::{write_scan, write_sequence};
use crate::mapping::{kinect_joints, reference_labels, SelfIntersectionCheck};
use crate::noise::{apply_joint_noise, JointNoise};
use crate::render::{Camera, Realism};

/// The command that regenerates `fixtures/synth/` (run from the workspace root).
pub const FIXTURES_COMMAND: &str =
    "cargo run --release -p symcorr-synth -- fixtures --out fixtures/synth";

/// Shapes of the committed set: `s0` = base mesh, `s1` = heavy male build (`male-young-minmuscle-maxweight=0.5`).
pub fn fixture_shapes() -> Vec<(String, Shape)> {
    let mut s1 = Shape::default();
    s1.weights
        .insert("male-young-minmuscle-maxweight".into(), 0.5);
    vec![("s0".into(), Shape::default()), ("s1".into(), s1)]
}

/// Poses of the committed set.
pub const FIXTURE_POSES: [&str; 6] = [
    "rest",
    "t-pose",
    "arms-down",
    "walk-10",
    "walk-60",
    "random-7",
];

/// Joint noise of the committed noisy variant: σ = 3 cm, 10 % of joints on the surface.
pub const FIXTURE_NOISE: JointNoise = JointNoise {
    sigma_cm: 3.0,
    surface_fraction: 0.1,
    drop_fraction: 0.0,
    seed: 2026,
};

/// Writes the whole fixture set into `out`: `bodies/` (exact joints), `bodies_noisy/` (noisy
/// joints, meshes and labels shared with `bodies/` through symbolic links).
pub fn write_fixtures(model: &Model, out: &Path) -> Result<()> {
    let spec = DatasetSpec {
        shapes: fixture_shapes(),
        poses: FIXTURE_POSES.iter().map(|s| s.to_string()).collect(),
        format: MeshFormat::Ply,
        noise: None,
        command: FIXTURES_COMMAND.into(),
        share_meshes_with: None,
        scans: None,
        subdivide: 0,
        finer_targets: 0,
    };
    write_dataset(model, &spec, &out.join("bodies"))?;
    let noisy = DatasetSpec {
        noise: Some(FIXTURE_NOISE),
        share_meshes_with: Some(PathBuf::from("../bodies")),
        ..spec
    };
    write_dataset(model, &noisy, &out.join("bodies_noisy"))?;

    // Virtual Kinect: one view of s0_walk-10, ideal and realistic, and a short walk sequence.
    let body = model.body(&fixture_shapes()[0].1)?;
    let pose = crate::poses::named_pose(&model.assets, SCAN_POSE)?;
    let posed = body.pose(&pose)?;
    let joints = kinect_joints(&body, &posed)?;
    let camera = fixture_camera();
    let mesh_ref = format!("../bodies/meshes/s0_{SCAN_POSE}.ply");
    write_scan(
        &out.join("scan"),
        &posed.mesh,
        &joints,
        &camera,
        &Realism::default(),
        &mesh_ref,
    )?;
    write_scan(
        &out.join("scan_kinect"),
        &posed.mesh,
        &joints,
        &camera,
        &Realism::kinect(11),
        &mesh_ref,
    )?;
    let poses: Vec<_> = (0..SEQUENCE_FRAMES)
        .map(|f| {
            crate::poses::walk_pose(model.assets.walk.as_ref(), f as f64 / 30.0 / WALK_PERIOD_S)
        })
        .collect();
    write_sequence(
        &out.join("sequence"),
        &body,
        &poses,
        30.0,
        &camera,
        &Realism::kinect(12),
    )?;
    Ok(())
}

/// Pose of the committed single-view scans (`scan/`, `scan_kinect/`): body `s0_walk-10`.
pub const SCAN_POSE: &str = "walk-10";

/// Frames of the committed sequence (30 fps walk).
pub const SEQUENCE_FRAMES: usize = 4;

/// Walk-cycle period used for sequences, seconds (40 frames at 24 fps, as the MPFB2 walk file).
pub const WALK_PERIOD_S: f64 = 40.0 / 24.0;

/// The fixture camera: a Kinect v1 2.6 m in front of the subject (who faces +z) at about
/// 0.8 m above the floor, looking at the body's centre.
pub fn fixture_camera() -> Camera {
    Camera::kinect_v1([0.0, 0.0, 2.6], [0.0, -0.05, 0.0])
}

/// Poses one body and writes its mesh (and optionally joints and labels).
pub fn write_single(
    model: &Model,
    shape: &Shape,
    pose: &str,
    mesh_out: &Path,
    joints_out: Option<&Path>,
    labels_out: Option<&Path>,
    noise: Option<JointNoise>,
) -> Result<()> {
    let base = model.body(&Shape::default())?;
    let labels = reference_labels(&base)?;
    let check = SelfIntersectionCheck::new(&base.rest.triangles, &labels);
    let body = model.body(shape)?;
    let pose = crate::dataset::resolve_pose(model, &body, &check, pose)?;
    let posed = body.pose(&pose)?;
    symcorr_mesh::io::write(mesh_out, &posed.mesh, None)?;
    if let Some(j) = joints_out {
        let exact = kinect_joints(&body, &posed)?;
        let skel = match noise {
            Some(n) => apply_joint_noise(&exact, &posed.mesh, &n, 0),
            None => exact,
        };
        write_joints(j, &skel)?;
    }
    if let Some(l) = labels_out {
        write_text(
            l,
            &labels.iter().map(|l| format!("{l}\n")).collect::<String>(),
        )?;
    }
    Ok(())
}
