//! Writing a benchmark dataset folder in DESIGN.md's layout.
//!
//! ```text
//! DIR/meshes/NAME.ply     posed bodies, same vertex order everywhere (ground truth = identity)
//! DIR/joints/NAME.json    symcorr.joints/1, one frame, body frame (see crate docs)
//! DIR/labels/NAME.txt     reference segment label (0..16, DESIGN.md numbering) per vertex, one per line
//! DIR/mirror.txt          line i: the vertex mirror-symmetric to vertex i
//! DIR/pairs.txt           `template target` (NAMEs) per line
//! DIR/manifest.json       shapes, poses (with every bone rotation), noise, the generating command
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde_json::json;
use symcorr_kinect::joints::{write_joints_json, JointLog};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;

use crate::body::{Body, Model, Pose, Shape};
use crate::error::{Result, SynthError};
use crate::mapping::{kinect_joints, reference_labels, SelfIntersectionCheck};
use crate::noise::{apply_joint_noise, JointNoise};
use crate::poses::{named_pose, random_pose_unchecked, read_pose_json};

/// Mesh file format of a dataset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary little-endian PLY (compact, exact f64).
    Ply,
    /// ASCII OFF.
    Off,
}

impl MeshFormat {
    fn ext(self) -> &'static str {
        match self {
            MeshFormat::Ply => "ply",
            MeshFormat::Off => "off",
        }
    }
}

/// What to generate.
#[derive(Debug, Clone)]
pub struct DatasetSpec {
    /// Named shapes: `(name, shape)`; body names are `SHAPE_POSE`.
    pub shapes: Vec<(String, Shape)>,
    /// Pose names: named poses, `random-SEED`, or `file:PATH` (rotations JSON).
    pub poses: Vec<String>,
    /// Mesh format.
    pub format: MeshFormat,
    /// Joint noise for the joint files (`None` = exact joints).
    pub noise: Option<JointNoise>,
    /// The command line to record in the manifest.
    pub command: String,
    /// Instead of writing `meshes/` and `labels/`, make them symbolic links to this (relative)
    /// folder's `meshes/` and `labels/` — a joint-noise variant that shares another dataset's
    /// meshes.
    pub share_meshes_with: Option<PathBuf>,
    /// Make every pair's target a single-view scan of the target body (see [`ScanSpec`]).
    pub scans: Option<ScanSpec>,
    /// Loop-subdivide every posed mesh this many times (0: none). New vertices follow the
    /// input's (`symcorr_mesh::subdivide`), so all meshes still share one vertex order; the
    /// mirror map and the reference labels are extended (see [`subdivided_tables`]).
    pub subdivide: u32,
    /// Make every pair's target a *finer* mesh: the target body Loop-subdivided this many more
    /// times, written as `meshes/NAME_fine` with `truth/NAME_fine.txt` (vertex `v < n` is body
    /// vertex `v`, the new edge vertices have none). Template and target then have different
    /// triangulations, so a method cannot profit from a shared one. 0: off.
    pub finer_targets: u32,
}

/// The mirror map and reference labels of a mesh after `levels` Loop subdivisions of
/// `triangles`: the vertex of edge `[a, b]` mirrors to the vertex of edge `[m(a), m(b)]` and
/// takes the label of `a` (the lower id). An edge whose mirror image is not an edge (a quad
/// split along the other diagonal on the other side) mirrors to the vertex nearest its
/// reflection `x ↦ −x` (the rest mesh is symmetric about x = 0); the number of such edges is
/// returned.
pub fn subdivided_tables(
    triangles: &[[u32; 3]],
    positions: &[[f64; 3]],
    mirror: &[u32],
    labels: &[u8],
    levels: u32,
) -> Result<(Vec<u32>, Vec<u8>, usize)> {
    let mut mesh = TriMesh::new(positions.to_vec(), triangles.to_vec())?;
    let (mut mirror, mut labels) = (mirror.to_vec(), labels.to_vec());
    let mut unmatched = 0;
    for _ in 0..levels {
        let s = symcorr_mesh::subdivide::loop_subdivide(&mesh)?;
        let n = mesh.num_vertices() as u32;
        let mut missing = Vec::new();
        for &[a, b] in &s.edges {
            let (ma, mb) = (mirror[a as usize], mirror[b as usize]);
            let key = if ma < mb { [ma, mb] } else { [mb, ma] };
            match s.edges.binary_search(&key) {
                Ok(i) => mirror.push(n + i as u32),
                Err(_) => {
                    missing.push(mirror.len());
                    mirror.push(ma);
                }
            }
            labels.push(labels[a as usize]);
        }
        // A quad split along the other diagonal on the other side: its edge vertex mirrors to
        // the vertex nearest its reflection x ↦ −x (the body frame's sagittal plane).
        let p = &s.mesh.positions;
        for &v in &missing {
            let q = [-p[v][0], p[v][1], p[v][2]];
            let d2 = |w: &[f64; 3]| (0..3).map(|k| (w[k] - q[k]).powi(2)).sum::<f64>();
            let best = (0..p.len())
                .min_by(|&x, &y| d2(&p[x]).total_cmp(&d2(&p[y])))
                .unwrap_or(v);
            mirror[v] = best as u32;
        }
        unmatched += missing.len();
        mesh = s.mesh;
    }
    Ok((mirror, labels, unmatched))
}

/// How the targets of a scan dataset are seen: one virtual-Kinect view per target body, made
/// into a mesh by `symcorr_kinect::scan_mesh`, written as `meshes/NAME_scan.ply` with
/// `joints/NAME_scan.json` (camera space, the same joint noise as the body's) and
/// `truth/NAME_scan.txt` (the body vertex seen at each scan vertex's pixel, `-1` for none);
/// `pairs.txt` then lists `template NAME_scan`. Templates stay full bodies in the common order.
///
/// With `cameras`, `tracker` or `near_bones` set, every scan's camera is also written as
/// `cameras/NAME_scan.json` ([`crate::kinect::camera_json`] plus `intrinsics`, the drawn
/// `view` and the `inferred_joints`), so that a method may render into the scan's camera.
#[derive(Debug, Clone, Copy)]
pub struct ScanSpec {
    /// The camera (body frame), unless `cameras` draws one per body.
    pub camera: crate::render::Camera,
    /// Sensor realism.
    pub realism: crate::render::Realism,
    /// Draw each body's camera (seeded per body) instead of using `camera`.
    pub cameras: Option<crate::kinect::CameraSampling>,
    /// Tracker joints for the scans ([`crate::tracker`]) instead of the body's joints.
    pub tracker: Option<crate::tracker::TrackerNoise>,
    /// Build the scan meshes with `symcorr_kinect::ScanOptions::default()` (components near
    /// the bones kept, as `symcorr` does) instead of [`crate::kinect::scan_options`] (the
    /// largest only).
    pub near_bones: bool,
}

impl ScanSpec {
    /// A scan spec as the first scan datasets were made: one camera, exact joints, the largest
    /// component.
    pub fn fixed(camera: crate::render::Camera, realism: crate::render::Realism) -> ScanSpec {
        ScanSpec {
            camera,
            realism,
            cameras: None,
            tracker: None,
            near_bones: false,
        }
    }

    /// Whether the scans' cameras are written (`cameras/`).
    fn writes_cameras(&self) -> bool {
        self.cameras.is_some() || self.tracker.is_some() || self.near_bones
    }
}

/// Joint positions as a single-frame symcorr.joints/1 log.
pub fn single_frame_log(skeleton: Skeleton) -> JointLog {
    JointLog::from_skeletons(vec![skeleton], symcorr_kinect::joints::KINECT_FPS)
}

fn kerr(e: symcorr_kinect::KinectError) -> SynthError {
    SynthError::Invalid(e.to_string())
}

pub(crate) fn write_text(path: &Path, text: &str) -> Result<()> {
    // Atomic: temporary file next to the target, then rename.
    let tmp = path.with_extension("tmp~");
    std::fs::write(&tmp, text).map_err(|e| SynthError::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| SynthError::io(path, e))
}

pub(crate) fn mkdir(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).map_err(|e| SynthError::io(path, e))
}

/// Writes a single-frame joint file.
pub fn write_joints(path: &Path, skeleton: &Skeleton) -> Result<()> {
    write_joints_json(path, &single_frame_log(skeleton.clone())).map_err(kerr)
}

/// Samples a random pose (joint limits of [`crate::poses::JOINT_LIMITS`]) until the body shows
/// no gross self-intersection; `seed` fixes the ChaCha8 stream. Returns the pose and the number
/// of draws it took.
pub fn sample_valid_pose(
    body: &Body<'_>,
    check: &SelfIntersectionCheck,
    seed: u64,
) -> Result<(Pose, usize)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for attempt in 1..=200 {
        let pose = random_pose_unchecked(&mut rng);
        if check.find(&body.pose(&pose)?.mesh).is_empty() {
            return Ok((pose, attempt));
        }
    }
    Err(SynthError::Invalid(format!(
        "random pose seed {seed}: no self-intersection-free draw in 200 tries"
    )))
}

/// Resolves a pose name (see [`DatasetSpec::poses`]) for `body`.
pub fn resolve_pose(
    model: &Model,
    body: &Body<'_>,
    check: &SelfIntersectionCheck,
    name: &str,
) -> Result<Pose> {
    if let Some(seed) = name.strip_prefix("random-") {
        let seed: u64 = seed
            .parse()
            .map_err(|_| SynthError::Invalid(format!("pose `{name}`: expected random-SEED")))?;
        Ok(sample_valid_pose(body, check, seed)?.0)
    } else if let Some(path) = name.strip_prefix("file:") {
        read_pose_json(Path::new(path))
    } else {
        named_pose(&model.assets, name)
    }
}

fn pose_label(name: &str) -> String {
    match name.strip_prefix("file:") {
        Some(p) => Path::new(p)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "file".into()),
        None => name.to_string(),
    }
}

/// Pairs of a dataset with shapes `S` and poses `P` (body `s_p`): within each shape, the first
/// pose against every other pose; across shapes, pose `i` of shape `k` against pose `i+1` of
/// shape `k+1` (cyclic) — different pose *and* shape.
pub fn default_pairs(shapes: &[String], poses: &[String]) -> Vec<(String, String)> {
    let name = |s: &str, p: &str| format!("{s}_{p}");
    let mut pairs = Vec::new();
    for s in shapes {
        for p in &poses[1..] {
            pairs.push((name(s, &poses[0]), name(s, p)));
        }
    }
    for k in 0..shapes.len().saturating_sub(1) {
        for i in 0..poses.len() {
            pairs.push((
                name(&shapes[k], &poses[i]),
                name(&shapes[k + 1], &poses[(i + 1) % poses.len()]),
            ));
        }
    }
    pairs
}

#[cfg(unix)]
fn symlink_dir(target: &Path, link: &Path) -> Result<()> {
    std::os::unix::fs::symlink(target, link).map_err(|e| SynthError::io(link, e))
}

#[cfg(not(unix))]
fn symlink_dir(_target: &Path, link: &Path) -> Result<()> {
    Err(SynthError::Invalid(format!(
        "{}: sharing meshes needs symbolic links (unix only)",
        link.display()
    )))
}

/// Summary of a written dataset.
#[derive(Debug, Clone)]
pub struct DatasetSummary {
    /// Body names in generation order.
    pub bodies: Vec<String>,
    /// Pairs written.
    pub pairs: usize,
}

/// Generates and writes a dataset into `out` (created if needed; existing files overwritten).
pub fn write_dataset(model: &Model, spec: &DatasetSpec, out: &Path) -> Result<DatasetSummary> {
    if spec.scans.is_some() && spec.finer_targets > 0 {
        return Err(SynthError::Invalid(
            "targets are either scans or finer meshes, not both".into(),
        ));
    }
    if spec.shapes.is_empty() || spec.poses.is_empty() {
        return Err(SynthError::Invalid(
            "dataset needs at least one shape and one pose".into(),
        ));
    }
    let base = model.body(&Shape::default())?;
    let labels = reference_labels(&base)?;
    let check = SelfIntersectionCheck::new(&base.rest.triangles, &labels);
    let (mirror, labels) = if spec.subdivide > 0 {
        let (m, l, unmatched) = subdivided_tables(
            &base.rest.triangles,
            &base.rest.positions,
            &model.assets.body_mirror()?,
            &labels,
            spec.subdivide,
        )?;
        if unmatched > 0 {
            eprintln!(
                "note: {unmatched} subdivision edges have no mirror edge (quads split along the other diagonal); mirrored by position"
            );
        }
        (m, l)
    } else {
        (model.assets.body_mirror()?, labels)
    };
    mkdir(&out.join("joints"))?;
    match &spec.share_meshes_with {
        None => {
            mkdir(&out.join("meshes"))?;
            mkdir(&out.join("labels"))?;
        }
        Some(other) => {
            for d in ["meshes", "labels"] {
                let link = out.join(d);
                if link.symlink_metadata().is_ok() {
                    std::fs::remove_file(&link).map_err(|e| SynthError::io(&link, e))?;
                }
                symlink_dir(&other.join(d), &link)?;
            }
        }
    }
    let labels_text: String = labels.iter().map(|l| format!("{l}\n")).collect();
    let pose_names: Vec<String> = spec.poses.iter().map(|p| pose_label(p)).collect();
    let shape_names: Vec<String> = spec.shapes.iter().map(|s| s.0.clone()).collect();
    // Poses are resolved once (random ones checked on the base shape) so every shape shares them.
    let poses: Vec<Pose> = spec
        .poses
        .iter()
        .map(|p| resolve_pose(model, &base, &check, p))
        .collect::<Result<_>>()?;
    let mut bodies = Vec::new();
    let mut manifest_bodies = Vec::new();
    let mut stream = 0u64;
    for (sname, shape) in &spec.shapes {
        let body = model.body(shape)?;
        for (pname, pose) in pose_names.iter().zip(&poses) {
            let name = format!("{sname}_{pname}");
            let mut posed = body.pose(pose)?;
            let hits = check.find(&posed.mesh).len();
            let exact = kinect_joints(&body, &posed)?;
            for _ in 0..spec.subdivide {
                posed.mesh = symcorr_mesh::subdivide::loop_subdivide(&posed.mesh)?.mesh;
            }
            let skel = match &spec.noise {
                Some(n) => apply_joint_noise(&exact, &posed.mesh, n, stream),
                None => exact,
            };
            stream += 1;
            let mesh_path: PathBuf = out
                .join("meshes")
                .join(format!("{name}.{}", spec.format.ext()));
            if spec.share_meshes_with.is_none() {
                symcorr_mesh::io::write(&mesh_path, &posed.mesh, None)?;
                write_text(
                    &out.join("labels").join(format!("{name}.txt")),
                    &labels_text,
                )?;
            }
            write_joints(&out.join("joints").join(format!("{name}.json")), &skel)?;
            if let Some(sc) = &spec.scans {
                let view = sc.cameras.map(|c| c.draw(&posed.mesh, stream));
                let camera = view.map_or(sc.camera, |v| v.camera);
                let options = if sc.near_bones {
                    symcorr_kinect::ScanOptions::default()
                } else {
                    crate::kinect::scan_options()
                };
                let t = crate::kinect::scan_target_with(
                    &posed.mesh,
                    &skel,
                    &camera,
                    &sc.realism,
                    stream,
                    &options,
                    sc.tracker.as_ref().map(|n| (n, labels.as_slice())),
                )?;
                let scan_name = format!("{name}_scan");
                symcorr_mesh::io::write(
                    out.join("meshes")
                        .join(format!("{scan_name}.{}", spec.format.ext())),
                    &t.mesh,
                    None,
                )?;
                write_joints(
                    &out.join("joints").join(format!("{scan_name}.json")),
                    &t.joints,
                )?;
                mkdir(&out.join("truth"))?;
                let truth: String = t
                    .truth
                    .iter()
                    .map(|v| match v {
                        Some(v) => format!("{v}\n"),
                        None => "-1\n".to_string(),
                    })
                    .collect();
                write_text(&out.join("truth").join(format!("{scan_name}.txt")), &truth)?;
                if sc.writes_cameras() {
                    let mut cam = crate::kinect::camera_json(
                        &camera,
                        &format!("meshes/{name}.{}", spec.format.ext()),
                        &sc.realism,
                    );
                    cam["intrinsics"] = json!(camera.intrinsics);
                    if let Some(v) = view {
                        cam["view"] = json!({
                            "distance_m": v.distance_m,
                            "azimuth_deg": v.azimuth_deg,
                            "height_m": v.height_m,
                        });
                    }
                    cam["inferred_joints"] = json!(symcorr_skeleton::Joint::ALL
                        .iter()
                        .zip(t.inferred)
                        .filter(|(_, inf)| *inf)
                        .map(|(j, _)| j.name())
                        .collect::<Vec<_>>());
                    mkdir(&out.join("cameras"))?;
                    let text = serde_json::to_string_pretty(&cam)
                        .map_err(|e| SynthError::Invalid(e.to_string()))?;
                    write_text(
                        &out.join("cameras").join(format!("{scan_name}.json")),
                        &(text + "\n"),
                    )?;
                }
            }
            if spec.finer_targets > 0 {
                let n = posed.mesh.num_vertices();
                let mut fine = posed.mesh.clone();
                for _ in 0..spec.finer_targets {
                    fine = symcorr_mesh::subdivide::loop_subdivide(&fine)?.mesh;
                }
                let fine_name = format!("{name}_fine");
                symcorr_mesh::io::write(
                    out.join("meshes")
                        .join(format!("{fine_name}.{}", spec.format.ext())),
                    &fine,
                    None,
                )?;
                write_joints(&out.join("joints").join(format!("{fine_name}.json")), &skel)?;
                mkdir(&out.join("truth"))?;
                let truth: String = (0..fine.num_vertices())
                    .map(|v| {
                        if v < n {
                            format!("{v}\n")
                        } else {
                            "-1\n".into()
                        }
                    })
                    .collect();
                write_text(&out.join("truth").join(format!("{fine_name}.txt")), &truth)?;
            }
            manifest_bodies.push(json!({
                "name": name,
                "shape": sname,
                "shape_weights": shape.weights,
                "pose": pname,
                "rotations": pose.rotations,
                "self_intersecting_triangle_pairs": hits,
            }));
            bodies.push(name);
        }
    }
    let mirror_text: String = mirror.iter().map(|m| format!("{m}\n")).collect();
    write_text(&out.join("mirror.txt"), &mirror_text)?;
    let mut pairs = default_pairs(&shape_names, &pose_names);
    let suffix = if spec.scans.is_some() {
        "_scan"
    } else if spec.finer_targets > 0 {
        "_fine"
    } else {
        ""
    };
    for (_, b) in pairs.iter_mut() {
        b.push_str(suffix);
    }
    let pairs_text: String = pairs.iter().map(|(a, b)| format!("{a} {b}\n")).collect();
    write_text(&out.join("pairs.txt"), &pairs_text)?;
    let segments: Vec<&str> = symcorr_attach::Segment::ALL
        .iter()
        .map(|s| s.name())
        .collect();
    let shapes_json: BTreeMap<&str, &BTreeMap<String, f64>> = spec
        .shapes
        .iter()
        .map(|(n, s)| (n.as_str(), &s.weights))
        .collect();
    let manifest = json!({
        "format": "symcorr.synth-dataset/1",
        "command": spec.command,
        "units": "m",
        "frame": "MakeHuman body frame: x = subject's left, y up, z = subject's front",
        "source": "MakeHuman/MPFB2 CC0 assets (fixtures/mpfb2), game_engine rig, linear blend skinning",
        "vertices": mirror.len(),
        "segments": segments,
        "shapes": shapes_json,
        "noise": spec.noise.map(|n| json!({
            "sigma_cm": n.sigma_cm, "surface_fraction": n.surface_fraction,
            "drop_fraction": n.drop_fraction, "seed": n.seed})),
        "bodies": manifest_bodies,
    });
    let mut manifest = manifest;
    if let Some(sc) = spec.scans.filter(|sc| sc.writes_cameras()) {
        // Only when used, so that the earlier scan datasets' manifests stay as they were.
        let r = &sc.realism;
        manifest["scans"] = json!({
            "realism": crate::kinect::camera_json(&sc.camera, "", r)["realism"],
            "cameras": sc.cameras.map(|c| json!({
                "distance_m": [c.distance_m.0, c.distance_m.1],
                "abs_azimuth_deg": [c.abs_azimuth_deg.0, c.abs_azimuth_deg.1],
                "height_m": [c.height_m.0, c.height_m.1],
                "seed": c.seed})),
            "tracker": sc.tracker.map(|n| json!({
                "sigma_cm": n.sigma_cm, "extremity_sigma_cm": n.extremity_sigma_cm,
                "inferred_depth_m": n.inferred_depth_m, "seed": n.seed})),
            "components": if sc.near_bones { "near_bones" } else { "largest" },
        });
    }
    if spec.subdivide > 0 {
        // Only when used, so the committed fixtures' manifests stay as they were.
        manifest["subdivide"] = json!(spec.subdivide);
    }
    let text =
        serde_json::to_string_pretty(&manifest).map_err(|e| SynthError::Invalid(e.to_string()))?;
    write_text(&out.join("manifest.json"), &(text + "\n"))?;
    Ok(DatasetSummary {
        bodies,
        pairs: pairs.len(),
    })
}
