//! The committed fixture set (`fixtures/synth/`) and single-body output.

use std::path::{Path, PathBuf};

use crate::body::{Model, Shape};
use crate::dataset::{write_dataset, write_joints, write_text, DatasetSpec, MeshFormat};
use crate::error::Result;
use crate::mapping::{kinect_joints, reference_labels, SelfIntersectionCheck};
use crate::noise::{apply_joint_noise, JointNoise};

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
    };
    write_dataset(model, &spec, &out.join("bodies"))?;
    let noisy = DatasetSpec {
        noise: Some(FIXTURE_NOISE),
        share_meshes_with: Some(PathBuf::from("../bodies")),
        ..spec
    };
    write_dataset(model, &noisy, &out.join("bodies_noisy"))?;
    Ok(())
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
