//! Joint-log replay, handedness against a mesh, and depth → scan meshing on analytically rendered
//! depth frames.

use nalgebra::{distance, Point3, Vector3};
use std::path::PathBuf;
use symcorr_attach::{handedness_verdict, Handedness};
use symcorr_kinect::scan::{
    depth_to_points, fuse_depth_frames, scan_mesh, ComponentFilter, ScanOptions,
};
use symcorr_kinect::{read_joints, DepthFrame, FrameSelect, Intrinsics, JointLog, KinectError};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{Bone, Joint, Skeleton};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/kinect")
        .join(name)
}

fn standing() -> Skeleton {
    read_joints(fixture("standing_v1.json")).unwrap().frames[0]
        .skeleton
        .clone()
}

/// Frame rate of the test logs: frames 0.1 s apart.
const FPS: f64 = 10.0;

fn shifted(s: &Skeleton, d: [f64; 3]) -> Skeleton {
    let mut out = s.clone();
    for p in out.positions.iter_mut() {
        for c in 0..3 {
            p[c] += d[c];
        }
    }
    out
}

#[test]
fn replay_selects_frames_by_index_and_time() {
    let base = standing();
    let log = JointLog::from_skeletons(
        (0..5)
            .map(|i| shifted(&base, [0.01 * i as f64, 0.0, 0.0]))
            .collect(),
        FPS,
    );
    assert_eq!(log.frame(3).unwrap(), &log.frames[3].skeleton);
    assert!(matches!(log.frame(5), Err(KinectError::Replay(_))));
    // 0.26 s is nearest to frame 3 (0.3 s).
    assert_eq!(
        log.select(FrameSelect::Time(0.26)).unwrap(),
        log.frames[3].skeleton
    );
    assert_eq!(
        log.select(FrameSelect::Time(-4.0)).unwrap(),
        log.frames[0].skeleton
    );
    assert!(log.select(FrameSelect::Time(f64::NAN)).is_err());
    let e = log
        .select(FrameSelect::Window {
            start_s: 5.0,
            end_s: 6.0,
        })
        .unwrap_err();
    assert!(matches!(e, KinectError::Replay(_)), "{e}");
}

#[test]
fn robust_average_drops_outlier_frames_and_weights_by_confidence() {
    let base = standing();
    // Small symmetric jitter around the base pose, one frame 0.5 m off (a mis-track).
    let mut frames: Vec<Skeleton> = [-0.004, 0.002, 0.0, -0.002, 0.004, 0.001, -0.001]
        .iter()
        .map(|&e| shifted(&base, [e, -e, e]))
        .collect();
    frames.insert(3, shifted(&base, [0.5, 0.0, 0.0]));
    frames.insert(5, shifted(&base, [0.45, 0.1, 0.0]));
    // The head is untracked (confidence 0) and wrong in two otherwise good frames.
    for f in [0, 1] {
        frames[f].positions[Joint::Head.index()][1] += 0.3;
        frames[f].confidence[Joint::Head.index()] = 0.0;
    }
    let log = JointLog::from_skeletons(frames, FPS);
    let avg = log
        .select(FrameSelect::Window {
            start_s: 0.0,
            end_s: 10.0,
        })
        .unwrap();
    for j in Joint::ALL {
        let d: f64 = (0..3)
            .map(|c| (avg.position(j)[c] - base.position(j)[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d < 0.005, "{j:?} off by {d}");
    }
    // A plain mean would have moved x by (0.5 + 0.45) / 9 ≈ 0.1 m.
    assert!(avg.confidence[Joint::Head.index()] < 1.0);
    assert_eq!(avg.confidence[Joint::Spine.index()], 1.0);
}

#[test]
fn robust_average_leaves_out_frames_that_lost_the_body() {
    let base = standing();
    let mut lost = base.clone();
    lost.positions = [Point3::origin(); 20];
    lost.confidence = [0.0; 20];
    // Five frames without a body around three with it: a coordinate median over all eight
    // would be the origin.
    let mut frames = vec![lost.clone(); 5];
    frames.splice(
        1..1,
        [-0.002, 0.0, 0.002].map(|e| shifted(&base, [e, 0.0, 0.0])),
    );
    let log = JointLog::from_skeletons(frames, FPS);
    let all = FrameSelect::Window {
        start_s: 0.0,
        end_s: 10.0,
    };
    let avg = log.select(all).unwrap();
    for j in Joint::ALL {
        assert!(
            distance(&avg.position(j), &base.position(j)) < 0.005,
            "{j:?}"
        );
    }
    let log = JointLog::from_skeletons(vec![lost; 3], FPS);
    let e = log.select(all).unwrap_err();
    assert!(e.to_string().contains("tracks a joint"), "{e}");
}

#[test]
fn bone_length_report_finds_the_stretching_bone() {
    let base = standing();
    let rigid = JointLog::from_skeletons(
        (0..4)
            .map(|i| shifted(&base, [0.1 * i as f64, 0.0, 0.0]))
            .collect(),
        FPS,
    );
    let r = rigid.bone_lengths();
    assert_eq!(r.bones.len(), 19);
    assert!(r.max_relative_std < 1e-12, "{}", r.max_relative_std);
    assert!(r.is_consistent(0.01));
    // Left forearm 30 % longer in one of four frames (hand moved along with the wrist).
    let mut frames: Vec<Skeleton> = (0..4).map(|_| base.clone()).collect();
    let (e, w) = (
        base.position(Joint::ElbowLeft),
        base.position(Joint::WristLeft),
    );
    let stretch = [0, 1, 2].map(|c| 0.3 * (w[c] - e[c]));
    for j in [Joint::WristLeft, Joint::HandLeft] {
        for (q, d) in frames[2].positions[j.index()].iter_mut().zip(stretch) {
            *q += d;
        }
    }
    let r = JointLog::from_skeletons(frames, FPS).bone_lengths();
    assert_eq!(r.worst_bone, Bone::new(Joint::ElbowLeft, Joint::WristLeft));
    assert!(!r.is_consistent(0.05));
    let fore = &r.bones[5];
    assert_eq!(fore.bone, Bone::new(Joint::ElbowLeft, Joint::WristLeft));
    assert!((fore.max / fore.min - 1.3).abs() < 1e-9);
    assert!(r.to_string().contains("elbow_left"));
}

/// An axis-aligned box as a closed triangle mesh, appended to `pos`/`tri`.
fn push_box(pos: &mut Vec<[f64; 3]>, tri: &mut Vec<[u32; 3]>, lo: [f64; 3], hi: [f64; 3]) {
    let b = pos.len() as u32;
    for i in 0..8 {
        pos.push([
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]);
    }
    for f in [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ] {
        tri.push([b + f[0], b + f[1], b + f[2]]);
    }
}

/// A blocky body matching the standing fixture: torso, shins, and feet pointing to −z.
fn blocky_body() -> TriMesh {
    let (mut p, mut t) = (Vec::new(), Vec::new());
    push_box(&mut p, &mut t, [-0.18, -0.05, 2.4], [0.18, 0.5, 2.6]);
    for s in [-1.0, 1.0] {
        let (x0, x1) = if s < 0.0 {
            (-0.14, -0.06)
        } else {
            (0.06, 0.14)
        };
        push_box(&mut p, &mut t, [x0, -0.88, 2.47], [x1, -0.48, 2.57]);
        push_box(&mut p, &mut t, [x0, -0.95, 2.32], [x1, -0.88, 2.56]);
    }
    TriMesh::new(p, t).unwrap()
}

#[test]
fn handedness_detects_swapped_sides_from_the_feet() {
    let s = standing();
    let mesh = blocky_body();
    let ok = handedness_verdict(&mesh, &s, 0.01);
    assert_eq!(ok.verdict, Handedness::Consistent, "{ok:?}");
    // Facing the sensor: −z.
    assert!(ok.facing[2] < -0.99, "{:?}", ok.facing);
    assert!(ok.foot_offset_m > 0.02);
    let swapped = handedness_verdict(&mesh, &s.swap_sides(), 0.01);
    assert_eq!(swapped.verdict, Handedness::Swapped, "{swapped:?}");
    assert!((swapped.foot_offset_m + ok.foot_offset_m).abs() < 1e-9);
    // No geometry near the feet: undetermined.
    let (mut p, mut t) = (Vec::new(), Vec::new());
    push_box(&mut p, &mut t, [-0.18, -0.05, 2.4], [0.18, 0.5, 2.6]);
    let torso = TriMesh::new(p, t).unwrap();
    assert_eq!(
        handedness_verdict(&torso, &s, 0.01).verdict,
        Handedness::Undetermined
    );
}

const C: [f64; 3] = [0.0, 0.0, 2.5];
const R: f64 = 0.3;
const BLOB: [f64; 3] = [0.4, 0.35, 2.45];

/// Ray-cast depth (mm) of a scene: a sphere (the "subject"), a small blob beside it, the floor
/// y = −1 and a wall z = 4, seen through `k`.
fn render(k: &Intrinsics) -> DepthFrame {
    let sphere = |d: Vector3<f64>, c: Vector3<f64>, r: f64| -> Option<f64> {
        let a = d.dot(&d);
        let b = -2.0 * d.dot(&c);
        let cc = c.dot(&c) - r * r;
        let disc = b * b - 4.0 * a * cc;
        (disc >= 0.0).then(|| (-b - disc.sqrt()) / (2.0 * a))
    };
    let mut data = Vec::new();
    for v in 0..k.height {
        for u in 0..k.width {
            let d = k.unproject(u as f64, v as f64, 1.0).coords;
            let mut t: f64 = 4.0;
            if d[1] < 0.0 {
                t = t.min(-1.0 / d[1]);
            }
            for (c, r) in [(C, R), (BLOB, 0.05)] {
                if let Some(s) = sphere(d, c.into(), r) {
                    t = t.min(s);
                }
            }
            data.push((t * 1000.0).round() as u16);
        }
    }
    DepthFrame::new(k.width, k.height, data).unwrap()
}

fn subject_skeleton() -> Skeleton {
    let mut p = [[0.0; 3]; 20];
    for (i, q) in p.iter_mut().enumerate() {
        let t = i as f64 / 19.0;
        *q = [0.2 * (2.0 * t - 1.0), 0.2 - 0.4 * t, 2.4 + 0.2 * t];
    }
    p[Joint::HipCenter.index()] = [0.0, -0.2, 2.5];
    p[Joint::ShoulderCenter.index()] = [0.0, 0.2, 2.5];
    p[Joint::FootLeft.index()] = [-0.1, -0.95, 2.45];
    p[Joint::FootRight.index()] = [0.1, -0.95, 2.45];
    Skeleton::from_arrays(p)
}

fn small_k() -> Intrinsics {
    // Kinect v1 at 320×240.
    Intrinsics {
        width: 320,
        height: 240,
        fx: 285.63,
        fy: 285.63,
        cx: 160.0,
        cy: 120.0,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
        distortion: None,
    }
}

#[test]
fn scan_keeps_only_the_subject_surface() {
    let k = small_k();
    let frame = render(&k);
    let s = subject_skeleton();
    let scan = scan_mesh(&frame, &k, Some(&s), &ScanOptions::default()).unwrap();
    let m = &scan.mesh;
    assert!(m.num_vertices() > 500, "{}", m.num_vertices());
    assert_eq!(scan.pixel_ids.len(), m.num_vertices());
    for (i, p) in m.positions.iter().enumerate() {
        let p = Point3::from(*p);
        let r = distance(&p, &C.into());
        assert!(
            (r - R).abs() < 0.01,
            "vertex {i} at {p:?} is not on the sphere (r = {r})"
        );
        // The pixel id map points back at the pixel the vertex came from.
        let [u, v] = k.project(&p);
        let id = scan.pixel_ids[i];
        assert!(
            (u - (id % k.width) as f64).abs() < 1e-6 && (v - (id / k.width) as f64).abs() < 1e-6
        );
    }
    // Triangles face the camera (counter-clockwise seen from it).
    for t in 0..m.num_triangles() {
        let [a, b, c] = m.corners(t).map(Point3::from);
        let n = (b - a).cross(&(c - a));
        assert!(n.dot(&a.coords) < 0.0, "triangle {t} faces away");
    }
    let plane = scan.report.floor_plane.expect("floor found");
    assert!(
        plane[1] > 0.999 && (plane[3] - 1.0).abs() < 0.01,
        "{plane:?}"
    );
    assert!(scan.report.floor_removed > 1000);
    assert!(scan.report.background_removed > 1000);
    // The blob was inside the foreground box but is a separate, smaller component.
    assert!(scan.report.component_vertices_removed > 10);
}

/// A frame and the same frame with its columns reversed, `(u, v) → (width − 1 − u, v)`.
fn columns_reversed(frame: &DepthFrame) -> DepthFrame {
    let w = frame.width as usize;
    let data = frame
        .data_mm
        .chunks(w)
        .flat_map(|row| row.iter().rev().copied())
        .collect();
    DepthFrame::new(frame.width, frame.height, data).unwrap()
}

/// An image as the lens forms it (the Azure Kinect's, RealSense's: `Mirroring::Direct`) scans
/// as the same camera-space surface as the Kinect SDK's mirrored image of the same view: the
/// same points from mirrored pixels, the same triangles, facing the camera; read as mirrored
/// instead, the surface comes out mirrored in x.
#[test]
fn a_direct_image_scans_as_the_surface_its_mirror_shows() {
    let k = small_k();
    let frame = render(&k);
    let s = subject_skeleton();
    let opts = ScanOptions::default();
    let mirrored = scan_mesh(&frame, &k, Some(&s), &opts).unwrap();
    let kd = k.columns_reversed();
    assert_eq!(kd.mirroring, symcorr_kinect::Mirroring::Direct);
    let flipped = columns_reversed(&frame);
    let direct = scan_mesh(&flipped, &kd, Some(&s), &opts).unwrap();
    let w = k.width;
    let mirror_pixel = |id: u32| (id / w) * w + (w - 1 - id % w);
    // Vertex by vertex through the pixels: the same points.
    let at: std::collections::HashMap<u32, usize> = mirrored
        .pixel_ids
        .iter()
        .enumerate()
        .map(|(i, &id)| (id, i))
        .collect();
    assert_eq!(direct.mesh.num_vertices(), mirrored.mesh.num_vertices());
    let mut to_mirrored = Vec::new();
    for (i, &id) in direct.pixel_ids.iter().enumerate() {
        let j = at[&mirror_pixel(id)];
        let (p, q) = (direct.mesh.positions[i], mirrored.mesh.positions[j]);
        assert!(
            (0..3).all(|c| (p[c] - q[c]).abs() < 1e-9),
            "{p:?} against {q:?}"
        );
        to_mirrored.push(j);
    }
    // The same triangles (as vertex sets), every one facing the camera.
    let key = |t: [u32; 3]| {
        let mut t = t;
        t.sort_unstable();
        t
    };
    let mut a: Vec<[u32; 3]> = (0..direct.mesh.num_triangles())
        .map(|t| key(direct.mesh.triangles[t].map(|v| to_mirrored[v as usize] as u32)))
        .collect();
    let mut b: Vec<[u32; 3]> = mirrored.mesh.triangles.iter().map(|&t| key(t)).collect();
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b);
    for t in 0..direct.mesh.num_triangles() {
        let [p, q, r] = direct.mesh.corners(t).map(Point3::from);
        assert!(
            (q - p).cross(&(r - p)).dot(&p.coords) < 0.0,
            "triangle {t} faces away"
        );
    }
    // The pixel ids still name the direct image's own pixels.
    for (i, &id) in direct.pixel_ids.iter().enumerate() {
        let [u, v] = kd.project(&Point3::from(direct.mesh.positions[i]));
        assert!((u - f64::from(id % w)).abs() < 1e-6 && (v - f64::from(id / w)).abs() < 1e-6);
    }
    // The flipped image read as mirrored is the mirror image: its points at −x.
    let as_mirrored = Intrinsics {
        mirroring: symcorr_kinect::Mirroring::Mirrored,
        distortion: None,
        ..kd
    };
    let wrong = scan_mesh(&flipped, &as_mirrored, None, &ScanOptions::default()).unwrap();
    let right = scan_mesh(&frame, &k, None, &ScanOptions::default()).unwrap();
    let sorted = |m: &TriMesh, sx: f64| {
        let mut p: Vec<[f64; 3]> = m
            .positions
            .iter()
            .map(|p| [sx * p[0], p[1], p[2]])
            .collect();
        p.sort_by(|a, b| a.partial_cmp(b).unwrap());
        p
    };
    let (a, b) = (sorted(&wrong.mesh, -1.0), sorted(&right.mesh, 1.0));
    assert_eq!(a.len(), b.len());
    assert!(a
        .iter()
        .zip(&b)
        .all(|(p, q)| (0..3).all(|c| (p[c] - q[c]).abs() < 1e-9)));
    assert!(
        b.iter().any(|p| p[0].abs() > 0.1),
        "a scene that is not flat in x"
    );
}

/// Distance from `p` to the nearest surface of [`render`]'s scene: the sphere, the blob, the
/// floor (y = −1) and the wall (z = 4).
fn off_scene(p: &Point3<f64>) -> f64 {
    [
        (distance(p, &C.into()) - R).abs(),
        (distance(p, &BLOB.into()) - 0.05).abs(),
        (p.y + 1.0).abs(),
        (p.z - 4.0).abs(),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_distorted_image_scans_onto_the_surfaces_the_lens_saw() {
    // A wide lens with barrel distortion (about 9 % at the image's corners) and decentring.
    let lens = symcorr_kinect::Distortion::from_opencv(&[-0.25, 0.07, 0.001, -0.0005]).unwrap();
    let k = Intrinsics {
        distortion: Some(lens),
        ..small_k()
    };
    k.validate().unwrap();
    let frame = render(&k);
    let keep_floor = ScanOptions {
        remove_floor: false,
        components: symcorr_kinect::ComponentFilter::All,
        ..ScanOptions::default()
    };
    let scan = scan_mesh(&frame, &k, None, &keep_floor).unwrap();
    assert!(scan.mesh.num_vertices() > 320 * 240 / 2);
    for (i, p) in scan.mesh.positions.iter().enumerate() {
        let p = Point3::from(*p);
        // Depths are whole millimetres; a ray's point is off its surface by at most that
        // over the cosine of the grazing floor, far from the camera.
        assert!(off_scene(&p) < 0.01, "vertex {i} at {p:?}");
        // Back onto its pixel (the scan's rays are single precision: 10⁻⁷ of a ray).
        let [u, v] = k.project(&p);
        let id = scan.pixel_ids[i];
        assert!(
            (u - f64::from(id % k.width)).abs() < 1e-4
                && (v - f64::from(id / k.width)).abs() < 1e-4
        );
    }
    // Read as a pinhole camera, the floor towards the image's corners is centimetres off.
    let pinhole = scan_mesh(&frame, &small_k(), None, &keep_floor).unwrap();
    let worst = pinhole
        .mesh
        .positions
        .iter()
        .map(|p| off_scene(&Point3::from(*p)))
        .fold(0.0, f64::max);
    assert!(worst > 0.05, "{worst}");
}

#[test]
fn joints_of_another_frame_or_unit_are_refused_not_used_to_crop() {
    let k = small_k();
    let frame = render(&k);
    let moved = |f: &dyn Fn([f64; 3]) -> [f64; 3]| {
        let s = subject_skeleton();
        let mut p = [[0.0; 3]; 20];
        for (i, q) in p.iter_mut().enumerate() {
            *q = f(s.positions[i].into());
        }
        Skeleton::from_arrays(p)
    };
    // The person a metre to the side (joints of another frame), and joints in millimetres:
    // only the second is said to be in another unit.
    for (s, unit) in [
        (moved(&|[x, y, z]| [x + 1.0, y, z]), None),
        (moved(&|q| q.map(|c| c * 1000.0)), Some("0.001×")),
    ] {
        let e = scan_mesh(&frame, &k, Some(&s), &ScanOptions::default()).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("do not lie on the body") && !msg.contains('\n'),
            "{msg}"
        );
        assert_eq!(
            msg.contains("the depth readings at the joints"),
            unit.is_some(),
            "{msg}"
        );
        assert!(unit.is_none_or(|u| msg.contains(u)), "{msg}");
    }
    // A few centimetres of tracker offset is not another frame.
    let s = moved(&|[x, y, z]| [x + 0.03, y - 0.02, z + 0.05]);
    assert!(scan_mesh(&frame, &k, Some(&s), &ScanOptions::default()).is_ok());
}

#[test]
fn untracked_joints_do_not_crop_and_a_lost_body_is_refused() {
    let k = small_k();
    let frame = render(&k);
    let full = scan_mesh(
        &frame,
        &k,
        Some(&subject_skeleton()),
        &ScanOptions::default(),
    )
    .unwrap();
    // A hand the tracker lost, reported as the SDK does: (0, 0, 0), confidence 0. Inside the box
    // it would stretch it to the camera and let the wall and the blob in.
    let mut s = subject_skeleton();
    s.positions[Joint::HandLeft.index()] = Point3::origin();
    s.confidence[Joint::HandLeft.index()] = 0.0;
    let lost_hand = scan_mesh(&frame, &k, Some(&s), &ScanOptions::default()).unwrap();
    assert_eq!(lost_hand.mesh.num_vertices(), full.mesh.num_vertices());
    assert_eq!(
        lost_hand.report.background_removed,
        full.report.background_removed
    );
    // Every joint untracked: the tracker saw no body. Refused, naming the cause.
    s.positions = [Point3::origin(); 20];
    s.confidence = [0.0; 20];
    let e = scan_mesh(&frame, &k, Some(&s), &ScanOptions::default()).unwrap_err();
    assert!(
        matches!(e, KinectError::Scan(_)) && e.to_string().contains("tracks no joint"),
        "{e}"
    );
}

#[test]
fn a_frame_without_any_reading_is_refused_naming_the_depth_not_the_joints() {
    // A camera that delivered an empty frame (every pixel 0): the joints are right, and the
    // message must not send the user to them.
    let k = small_k();
    let mut frame = render(&k);
    frame.data_mm.iter_mut().for_each(|d| *d = 0);
    for skeleton in [Some(subject_skeleton()), None] {
        let e = scan_mesh(&frame, &k, skeleton.as_ref(), &ScanOptions::default()).unwrap_err();
        let m = e.to_string();
        assert!(matches!(e, KinectError::Scan(_)), "{e}");
        assert!(m.contains("the depth frame has no reading"), "{m}");
        assert!(!m.contains("joint"), "{m}");
    }
}

#[test]
fn without_cleanup_the_grid_mesh_never_bridges_depth_jumps() {
    let k = small_k();
    let frame = render(&k);
    let opts = ScanOptions {
        remove_floor: false,
        components: ComponentFilter::All,
        ..ScanOptions::default()
    };
    let scan = scan_mesh(&frame, &k, None, &opts).unwrap();
    // Wall, floor, sphere and blob are all there...
    let zs: Vec<f64> = scan.mesh.positions.iter().map(|p| p[2]).collect();
    assert!(zs.iter().any(|&z| (z - 4.0).abs() < 1e-9));
    assert!(zs.iter().any(|&z| z < 2.3));
    assert!(scan.report.discontinuity_triangles > 100);
    // ...but no triangle spans a jump larger than the threshold.
    for t in 0..scan.mesh.num_triangles() {
        let c = scan.mesh.corners(t);
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            assert!((c[a][2] - c[b][2]).abs() <= opts.discontinuity_m + 1e-12);
        }
    }
    // Every valid pixel with a valid right and lower neighbour on the same surface is meshed:
    // the grid has about two triangles per pixel.
    assert!(scan.mesh.num_triangles() > 320 * 240);
}

#[test]
fn scan_errors_are_typed() {
    let k = small_k();
    let frame = render(&k);
    let e = scan_mesh(
        &frame,
        &Intrinsics::kinect_v1(),
        None,
        &ScanOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, KinectError::DepthSize { .. }), "{e}");
    let empty = DepthFrame::new(320, 240, vec![0; 320 * 240]).unwrap();
    let e = scan_mesh(&empty, &k, None, &ScanOptions::default()).unwrap_err();
    assert!(matches!(e, KinectError::Scan(_)), "{e}");
    assert!(fuse_depth_frames(&[]).is_err());
    let other = DepthFrame::new(2, 2, vec![1; 4]).unwrap();
    assert!(matches!(
        fuse_depth_frames(&[frame, other]),
        Err(KinectError::DepthSize { .. })
    ));
}

#[test]
fn invalid_scan_options_are_refused_naming_the_option() {
    let ok = ScanOptions::default();
    ok.validate().unwrap();
    let cases = [
        (
            ScanOptions {
                discontinuity_m: f64::NAN,
                ..ok.clone()
            },
            "scan option discontinuity_m = NaN: expected a finite length > 0 (metres)",
        ),
        (
            ScanOptions {
                discontinuity_m: 0.0,
                ..ok.clone()
            },
            "scan option discontinuity_m = 0.0: expected a finite length > 0 (metres)",
        ),
        (
            ScanOptions {
                floor_threshold_m: f64::INFINITY,
                ..ok.clone()
            },
            "scan option floor_threshold_m = inf: expected a finite length > 0 (metres)",
        ),
        (
            ScanOptions {
                min_depth_m: -0.1,
                ..ok.clone()
            },
            "scan option min_depth_m = -0.1: expected a finite depth >= 0 (metres)",
        ),
        (
            ScanOptions {
                max_depth_m: 0.3,
                ..ok.clone()
            },
            "scan option max_depth_m = 0.3: expected a finite depth > min_depth_m (metres)",
        ),
        (
            ScanOptions {
                background_margin_m: f64::NEG_INFINITY,
                ..ok.clone()
            },
            "scan option background_margin_m = -inf: expected a finite length >= 0 (metres)",
        ),
        (
            ScanOptions {
                floor_iterations: 100_001,
                ..ok.clone()
            },
            "scan option floor_iterations = 100001: expected at most 100000",
        ),
    ];
    let k = small_k();
    let frame = render(&k);
    for (opts, want) in cases {
        let e = opts.validate().unwrap_err();
        assert_eq!(e.to_string(), want);
        // scan_mesh checks them before any work.
        let e = scan_mesh(&frame, &k, None, &opts).unwrap_err();
        assert!(matches!(e, KinectError::ScanOption { .. }), "{e}");
    }
    // Implausible intrinsics are refused by scan_mesh too.
    let bad = Intrinsics { fx: 1e308, ..k };
    let e = scan_mesh(&frame, &bad, None, &ok).unwrap_err();
    assert!(matches!(e, KinectError::Intrinsics(_)), "{e}");
}

#[test]
fn fusion_takes_the_per_pixel_median() {
    let k = small_k();
    let clean = render(&k);
    let mut noisy = Vec::new();
    for f in 0..5u16 {
        let mut d = clean.clone();
        for (i, v) in d.data_mm.iter_mut().enumerate() {
            match (i + f as usize) % 7 {
                0 => *v = 0,                        // dropout
                1 => *v = v.saturating_add(40 + f), // flicker
                _ => {}
            }
        }
        noisy.push(d);
    }
    let fused = fuse_depth_frames(&noisy).unwrap();
    let wrong = fused
        .data_mm
        .iter()
        .zip(&clean.data_mm)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(wrong, 0);
    // A pixel valid in fewer than half the frames becomes 0.
    let mut sparse: Vec<DepthFrame> = (0..4)
        .map(|_| DepthFrame::new(1, 1, vec![0]).unwrap())
        .collect();
    sparse[0].data_mm[0] = 1234;
    assert_eq!(fuse_depth_frames(&sparse).unwrap().data_mm[0], 0);
    // Points of the fused frame are where the scene is.
    let pts = depth_to_points(&fused, &k, 0.4, 8.0).unwrap();
    assert_eq!(pts.iter().flatten().count(), 320 * 240);
}
