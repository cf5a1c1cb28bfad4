//! Ground-truth invariants of the generator. Reads only the project's fixtures/.

use nalgebra::Point3;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use symcorr_skeleton::{Joint, Segment};
use symcorr_synth::geom::winding_number;
use symcorr_synth::mapping::{kinect_joints, reference_labels};
use symcorr_synth::noise::{apply_joint_noise, JointNoise};
use symcorr_synth::poses::named_pose;
use symcorr_synth::render::{render, Camera, Realism, NO_VERTEX};
use symcorr_synth::{Assets, Model, Pose, Shape};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn model() -> &'static Model {
    static M: OnceLock<Model> = OnceLock::new();
    M.get_or_init(|| Model::new(Assets::load(&Assets::default_dir()).unwrap()).unwrap())
}

fn heavy() -> Shape {
    Shape::parse("male-young-minmuscle-maxweight=0.5").unwrap()
}

fn test_poses() -> Vec<(String, Pose)> {
    let m = model();
    let mut v: Vec<(String, Pose)> = ["rest", "t-pose", "arms-down", "walk-10", "walk-60"]
        .iter()
        .map(|n| (n.to_string(), named_pose(&m.assets, n).unwrap()))
        .collect();
    let path = root().join("fixtures/synth/bodies/manifest.json");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let random = manifest["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["pose"] == "random-7")
        .unwrap();
    let rotations = serde_json::from_value(random["rotations"].clone()).unwrap();
    v.push(("random-7".into(), Pose { rotations }));
    v
}

fn d(a: [f64; 3], b: [f64; 3]) -> f64 {
    nalgebra::distance(&Point3::from(a), &Point3::from(b))
}

#[test]
fn rest_pose_reproduces_the_base_mesh() {
    let base = symcorr_mesh::io::read(root().join("fixtures/body/body.off"))
        .unwrap()
        .mesh;
    let body = model().body(&Shape::default()).unwrap();
    let posed = body.pose(&Pose::default()).unwrap();
    assert_eq!(
        posed.mesh.triangles, base.triangles,
        "same fan triangulation and order"
    );
    assert_eq!(posed.mesh.num_vertices(), 13_380);
    for (i, (p, q)) in posed.mesh.positions.iter().zip(&base.positions).enumerate() {
        let q = [q[0] * 0.1, q[1] * 0.1, q[2] * 0.1]; // decimetres → metres
        assert!(d(*p, q) < 1e-12, "vertex {i}: {p:?} vs {q:?}");
    }
}

#[test]
fn posing_preserves_bone_lengths() {
    let m = model();
    for shape in [Shape::default(), heavy()] {
        let body = m.body(&shape).unwrap();
        let rest = body.pose(&Pose::default()).unwrap();
        let rest_joints = kinect_joints(&body, &rest).unwrap();
        for (name, pose) in test_poses() {
            let posed = body.pose(&pose).unwrap();
            for (b, bone) in body.bones.iter().enumerate() {
                let (h, t) = body.posed_bone(&posed.skin, b);
                let (h0, t0) = body.posed_bone(&rest.skin, b);
                assert!(
                    (d(h, t) - d(h0, t0)).abs() < 1e-9,
                    "{name}: rig bone {}",
                    bone.name
                );
                // Child heads stay attached to their parent (no bone translates).
                if let Some(p) = bone.parent {
                    let (_, pt0) = body.posed_bone(&rest.skin, p);
                    let (_, pt) = body.posed_bone(&posed.skin, p);
                    if d(pt0, h0) < 1e-9 {
                        assert!(d(pt, h) < 1e-9, "{name}: {} detached", bone.name);
                    }
                }
            }
            // Kinect limb bones lie on one rigid rig bone each: their lengths are preserved.
            let j = kinect_joints(&body, &posed).unwrap();
            for (a, b) in [
                (Joint::ShoulderLeft, Joint::ElbowLeft),
                (Joint::ElbowRight, Joint::WristRight),
                (Joint::HipLeft, Joint::KneeLeft),
                (Joint::KneeRight, Joint::AnkleRight),
                (Joint::AnkleLeft, Joint::FootLeft),
            ] {
                let l0 = nalgebra::distance(&rest_joints.position(a), &rest_joints.position(b));
                let l = nalgebra::distance(&j.position(a), &j.position(b));
                assert!((l - l0).abs() < 1e-9, "{name}: {a:?}-{b:?} {l0} → {l}");
            }
            if name != "rest" {
                let moved = posed
                    .mesh
                    .positions
                    .iter()
                    .zip(&rest.mesh.positions)
                    .any(|(p, q)| d(*p, *q) > 0.05);
                assert!(moved, "{name} does not move the body");
            }
        }
    }
}

#[test]
fn joints_lie_inside_the_body() {
    let m = model();
    for shape in [Shape::default(), heavy()] {
        let body = m.body(&shape).unwrap();
        for (name, pose) in test_poses() {
            let posed = body.pose(&pose).unwrap();
            let j = kinect_joints(&body, &posed).unwrap();
            for joint in Joint::ALL {
                let w = winding_number(&posed.mesh, j.position(joint).into());
                assert!(w > 0.5, "{name}: {} has winding number {w}", joint.name());
            }
        }
    }
    // And the check can fail: a point beside the body is outside.
    let body = m.body(&Shape::default()).unwrap();
    assert!(winding_number(&body.rest, [0.0, 0.0, 1.0]).abs() < 0.01);
}

#[test]
fn mirror_map_is_an_involution_and_a_symmetry_of_the_rest_mesh() {
    let m = model();
    let mirror = m.assets.body_mirror().unwrap();
    let rest = m.body(&Shape::default()).unwrap().rest;
    let mut fixed = 0;
    for (i, &j) in mirror.iter().enumerate() {
        assert_eq!(
            mirror[j as usize] as usize, i,
            "mirror is not an involution at {i}"
        );
        let p = rest.positions[i];
        let q = rest.positions[j as usize];
        assert!(
            d([-p[0], p[1], p[2]], q) < 1e-6,
            "vertex {i} ↦ {j}: {p:?} vs {q:?}"
        );
        fixed += (j as usize == i) as usize;
    }
    assert!(
        fixed < 500,
        "{fixed} midline vertices: the map should swap sides"
    );
    // The committed mirror.txt is the same map.
    let text = std::fs::read_to_string(root().join("fixtures/synth/bodies/mirror.txt")).unwrap();
    let file: Vec<u32> = text.lines().map(|l| l.parse().unwrap()).collect();
    assert_eq!(file, mirror);
}

#[test]
fn reference_labels_respect_the_mirror_map() {
    let m = model();
    let body = m.body(&Shape::default()).unwrap();
    let labels = reference_labels(&body).unwrap();
    let mirror = m.assets.body_mirror().unwrap();
    let areas = body.rest.vertex_areas();
    let total: f64 = areas.iter().sum();
    let mut agree = 0.0;
    for v in 0..labels.len() {
        let s = Segment::from_index(labels[v] as usize).unwrap();
        if labels[mirror[v] as usize] as usize == s.mirror().index() {
            agree += areas[v];
        }
    }
    assert!(
        agree / total >= 0.99,
        "only {:.4} of the area respects the mirror",
        agree / total
    );
    // Every segment is used, and left segments sit at +x (the subject's left).
    for s in Segment::ALL {
        let vs: Vec<usize> = (0..labels.len())
            .filter(|&v| labels[v] as usize == s.index())
            .collect();
        assert!(!vs.is_empty(), "segment {} has no vertex", s.name());
        let mean_x = vs.iter().map(|&v| body.rest.positions[v][0]).sum::<f64>() / vs.len() as f64;
        if s.name().ends_with("_left") {
            assert!(mean_x > 0.02, "{} at x = {mean_x}", s.name());
        }
    }
    // The committed labels are these.
    let text = std::fs::read_to_string(root().join("fixtures/synth/bodies/labels/s1_walk-10.txt"))
        .unwrap();
    let file: Vec<u8> = text.lines().map(|l| l.parse().unwrap()).collect();
    assert_eq!(file, labels);
}

fn point_triangle_distance(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> f64 {
    // Minimise over a fine barycentric grid plus the exact plane projection when inside.
    let [p, a, b, c] = [p, a, b, c].map(Point3::from);
    let (e0, e1, w) = (b - a, c - a, p - a);
    let (d00, d01, d11, d20, d21) = (
        e0.dot(&e0),
        e0.dot(&e1),
        e1.dot(&e1),
        w.dot(&e0),
        w.dot(&e1),
    );
    let den = d00 * d11 - d01 * d01;
    let v = (d11 * d20 - d01 * d21) / den;
    let u = (d00 * d21 - d01 * d20) / den;
    let q = |s: f64, t: f64| a + e0 * s + e1 * t;
    if v >= 0.0 && u >= 0.0 && u + v <= 1.0 {
        return nalgebra::distance(&p, &q(v, u));
    }
    let mut best = f64::INFINITY;
    let n = 64;
    for i in 0..=n {
        for j in 0..=(n - i) {
            best = best.min(nalgebra::distance(
                &p,
                &q(i as f64 / n as f64, j as f64 / n as f64),
            ));
        }
    }
    best
}

#[test]
fn rendered_pixels_back_project_onto_their_ground_truth_vertex_surface() {
    let m = model();
    let body = m.body(&Shape::default()).unwrap();
    let posed = body
        .pose(&named_pose(&m.assets, "walk-10").unwrap())
        .unwrap();
    let camera = Camera::kinect_v1([0.3, 0.2, 2.4], [0.0, -0.05, 0.0]);
    let r = render(&posed.mesh, &camera, &Realism::default(), 0);
    let to_world = camera.world_to_camera().inverse();
    let vt = posed.mesh.vertex_triangles();
    let k = camera.intrinsics;
    let mut checked = 0;
    for (i, &v) in r.vertex_id.iter().enumerate() {
        if v == NO_VERTEX {
            assert_eq!(r.depth_mm[i], 0, "background pixel with depth");
            continue;
        }
        let (u, row) = ((i % k.width as usize) as f64, (i / k.width as usize) as f64);
        let p = to_world.apply(k.unproject(u, row, r.depth_mm[i] as f64 / 1000.0).into());
        let dist = vt[v as usize]
            .iter()
            .map(|&t| point_triangle_distance(p, posed.mesh.corners(t as usize)))
            .fold(f64::INFINITY, f64::min);
        assert!(
            dist <= 0.002,
            "pixel {i}: {dist} m from vertex {v}'s surface"
        );
        checked += 1;
    }
    assert!(checked > 10_000, "only {checked} body pixels");
    // The committed ideal scan has the same kind of ground truth.
    let ids = symcorr_kinect::read_depth_png16(root().join("fixtures/synth/scan/vertex_ids.png"))
        .unwrap();
    assert!(ids.data_mm.iter().filter(|&&x| x > 0).count() > 10_000);
}

#[test]
fn joint_noise_is_seeded_and_as_requested() {
    let m = model();
    let body = m.body(&Shape::default()).unwrap();
    let posed = body.pose(&Pose::default()).unwrap();
    let exact = kinect_joints(&body, &posed).unwrap();
    let noise = JointNoise {
        sigma_cm: 3.0,
        surface_fraction: 0.1,
        drop_fraction: 0.1,
        seed: 5,
    };
    let a = apply_joint_noise(&exact, &posed.mesh, &noise, 0);
    assert_eq!(a, apply_joint_noise(&exact, &posed.mesh, &noise, 0));
    assert_ne!(a, apply_joint_noise(&exact, &posed.mesh, &noise, 1));
    assert_eq!(a.confidence.iter().filter(|&&c| c == 0.0).count(), 2);
    // σ over many draws (surface bias off) ≈ 3 cm.
    let plain = JointNoise {
        surface_fraction: 0.0,
        drop_fraction: 0.0,
        ..noise
    };
    let mut sq = 0.0;
    let mut n = 0.0;
    for s in 0..200 {
        let b = apply_joint_noise(&exact, &posed.mesh, &plain, s);
        for (p, q) in b.positions.iter().zip(&exact.positions) {
            for k in 0..3 {
                sq += (p[k] - q[k]).powi(2);
                n += 1.0;
            }
        }
    }
    let sigma = (sq / n).sqrt();
    assert!((sigma - 0.03).abs() < 0.002, "σ = {sigma}");
}

#[test]
fn committed_fixtures_regenerate_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    symcorr_synth::fixtures::write_fixtures(model(), dir.path()).unwrap();
    let committed = root().join("fixtures/synth");
    let mut stack = vec![PathBuf::new()];
    let mut files = 0;
    while let Some(rel) = stack.pop() {
        for e in std::fs::read_dir(dir.path().join(&rel)).unwrap() {
            let e = e.unwrap();
            let r = rel.join(e.file_name());
            let meta = std::fs::symlink_metadata(e.path()).unwrap();
            if meta.file_type().is_symlink() {
                assert_eq!(
                    std::fs::read_link(e.path()).unwrap(),
                    std::fs::read_link(committed.join(&r)).unwrap()
                );
            } else if meta.is_dir() {
                stack.push(r);
            } else {
                let new = std::fs::read(e.path()).unwrap();
                let old = std::fs::read(committed.join(&r))
                    .unwrap_or_else(|_| panic!("{} not committed", r.display()));
                assert!(
                    new == old,
                    "{} differs from the committed fixture",
                    r.display()
                );
                files += 1;
            }
        }
    }
    assert!(files > 50, "{files} files");
}

/// A scan dataset (`DatasetSpec::scans`): each pair's target is a single-view scan whose truth
/// file names, for each scan vertex, the body vertex seen at its pixel — that vertex, moved into
/// camera space, lies next to the scan vertex.
#[test]
fn scan_dataset_truth_names_the_vertex_seen() {
    use symcorr_synth::dataset::{write_dataset, DatasetSpec, MeshFormat, ScanSpec};
    let dir = tempfile::tempdir().unwrap();
    let camera = Camera::kinect_v1([0.0, 0.0, 2.6], [0.0, -0.05, 0.0]);
    let spec = DatasetSpec {
        shapes: vec![("s".into(), Shape::default())],
        poses: vec!["rest".into(), "t-pose".into()],
        format: MeshFormat::Ply,
        noise: None,
        command: "test".into(),
        share_meshes_with: None,
        scans: Some(ScanSpec::fixed(camera, Realism::default())),
        subdivide: 0,
        finer_targets: 0,
    };
    write_dataset(model(), &spec, dir.path()).unwrap();
    let pairs = std::fs::read_to_string(dir.path().join("pairs.txt")).unwrap();
    assert_eq!(pairs.trim(), "s_rest s_t-pose_scan");
    let body = symcorr_mesh::io::read(dir.path().join("meshes/s_t-pose.ply"))
        .unwrap()
        .mesh;
    let scan = symcorr_mesh::io::read(dir.path().join("meshes/s_t-pose_scan.ply"))
        .unwrap()
        .mesh;
    let truth: Vec<i64> = std::fs::read_to_string(dir.path().join("truth/s_t-pose_scan.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(truth.len(), scan.num_vertices());
    let to_cam = camera.world_to_camera();
    let mut seen = std::collections::BTreeSet::new();
    let mut worst: f64 = 0.0;
    for (v, &t) in truth.iter().enumerate() {
        if t < 0 {
            continue;
        }
        seen.insert(t);
        let q = to_cam.apply(body.positions[t as usize]);
        worst = worst.max(d(scan.positions[v], q));
    }
    // Ideal sensor: a pixel sees a point of a triangle whose nearest vertex is named; body
    // triangles are ~1–2 cm across.
    assert!(worst < 0.03, "worst distance {worst} m");
    // A front view sees a good part of the body, not all of it.
    let frac = seen.len() as f64 / body.num_vertices() as f64;
    assert!(frac > 0.25 && frac < 0.7, "{frac}");
}

/// Subdivided datasets: the extended mirror map is (up to the few edges re-mirrored by
/// position) an involution and a symmetry of the subdivided rest mesh.
#[test]
fn subdivided_mirror_map_is_a_symmetry() {
    let m = model();
    let base = m.body(&Shape::default()).unwrap();
    let labels = reference_labels(&base).unwrap();
    let mirror = m.assets.body_mirror().unwrap();
    let (sub_mirror, sub_labels, unmatched) = symcorr_synth::dataset::subdivided_tables(
        &base.rest.triangles,
        &base.rest.positions,
        &mirror,
        &labels,
        1,
    )
    .unwrap();
    let sub = symcorr_mesh::subdivide::loop_subdivide(&base.rest)
        .unwrap()
        .mesh;
    assert_eq!(sub_mirror.len(), sub.num_vertices());
    assert_eq!(sub_labels.len(), sub.num_vertices());
    assert!(unmatched < sub.num_vertices() / 100, "{unmatched}");
    let involution = (0..sub_mirror.len())
        .filter(|&v| sub_mirror[sub_mirror[v] as usize] as usize == v)
        .count();
    assert!(involution as f64 > 0.99 * sub_mirror.len() as f64);
    let mut worst: f64 = 0.0;
    for (v, &w) in sub_mirror.iter().enumerate() {
        let p = sub.positions[v];
        worst = worst.max(d([-p[0], p[1], p[2]], sub.positions[w as usize]));
    }
    assert!(worst < 0.01, "worst reflection error {worst} m");
}

/// Finer targets (`DatasetSpec::finer_targets`): the target is the body subdivided once more;
/// its first `n` vertices are the body's (moved only by Loop's smoothing mask) and the truth
/// file says so.
#[test]
fn finer_targets_keep_the_body_vertices_first() {
    use symcorr_synth::dataset::{write_dataset, DatasetSpec, MeshFormat};
    let dir = tempfile::tempdir().unwrap();
    let spec = DatasetSpec {
        shapes: vec![("s".into(), Shape::default())],
        poses: vec!["rest".into(), "walk-10".into()],
        format: MeshFormat::Ply,
        noise: None,
        command: "test".into(),
        share_meshes_with: None,
        scans: None,
        subdivide: 0,
        finer_targets: 1,
    };
    write_dataset(model(), &spec, dir.path()).unwrap();
    let pairs = std::fs::read_to_string(dir.path().join("pairs.txt")).unwrap();
    assert_eq!(pairs.trim(), "s_rest s_walk-10_fine");
    let read = |n: &str| {
        symcorr_mesh::io::read(dir.path().join(format!("meshes/{n}.ply")))
            .unwrap()
            .mesh
    };
    let (body, fine) = (read("s_walk-10"), read("s_walk-10_fine"));
    let n = body.num_vertices();
    assert_eq!(fine.num_vertices(), n + body.edges().len());
    let truth: Vec<i64> = std::fs::read_to_string(dir.path().join("truth/s_walk-10_fine.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(truth.len(), fine.num_vertices());
    assert!(truth[..n].iter().enumerate().all(|(v, &t)| t == v as i64));
    assert!(truth[n..].iter().all(|&t| t == -1));
    let worst = (0..n)
        .map(|v| d(body.positions[v], fine.positions[v]))
        .fold(0.0, f64::max);
    assert!(worst < 0.01, "Loop's vertex mask moved a vertex {worst} m");
}
