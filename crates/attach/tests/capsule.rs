//! Attachment on the procedural capsule body (exact and perturbed skeletons, known reference
//! labels), including single-view scans and frame changes.

mod common;

use common::{agreement, noisy, unambiguous, Rng};
use symcorr_attach::testbody::{capsule_body, t_pose};
use symcorr_attach::{attach, AttachOptions, HeatMesh, Joint, LimbPair, Segment, Skeleton};
use symcorr_mesh::TriMesh;

fn body() -> (Skeleton, TriMesh, Vec<Segment>, Vec<bool>) {
    let sk = t_pose(1.0);
    let (mesh, reference) = capsule_body(&sk, 0.02);
    let core = unambiguous(&mesh, &sk, 0.03);
    (sk, mesh, reference, core)
}

#[test]
fn exact_skeleton_labels_the_capsule_body() {
    let (sk, mesh, reference, core) = body();
    let a = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let all = vec![true; mesh.num_vertices()];
    let (agree_all, mirror) = agreement(&mesh, &a.labels, &reference, &all);
    let (agree, _) = agreement(&mesh, &a.labels, &reference, &core);
    eprintln!("capsule exact: core agreement {agree:.4}, all {agree_all:.4}, mirror {mirror}");
    assert!(agree >= 0.95, "core agreement {agree}");
    assert_eq!(mirror, 0.0);
    // Nothing to align, nothing mirrored, one component that sees its bones.
    assert!(a.diagnostics.alignment.is_identity());
    assert!(!a.diagnostics.mirror.swapped);
    assert!(a.diagnostics.mirror.mesh_evidence.unwrap() > 0.3);
    assert_eq!(a.diagnostics.components.len(), 1);
    assert!(!a.diagnostics.components[0].fallback);
    // Exact joints sit on the capsule axes: refinement barely moves them.
    for m in &a.diagnostics.joint_moves {
        assert!(m.distance() < 0.02, "{:?} moved {}", m.joint, m.distance());
    }
    // Weights: rows sum to one. Without joint planes the label is the segment with the largest
    // weight; joint planes only move labels between segments that share a joint (two sweeps:
    // at most two hops, e.g. thigh → hip → pelvis), and never change the weights.
    let plain = attach(
        &mesh,
        &sk,
        &AttachOptions {
            joint_planes: false,
            ..AttachOptions::default()
        },
    )
    .unwrap();
    assert_eq!(plain.weights, a.weights);
    let shares_joint = |x: Segment, y: Segment| {
        x.bones().iter().any(|b| {
            y.bones().iter().any(|c| {
                b.parent == c.parent
                    || b.parent == c.child
                    || b.child == c.parent
                    || b.child == c.child
            })
        })
    };
    let mut moved = 0;
    for v in 0..mesh.num_vertices() {
        let row = a.weights.row(v);
        assert!(!row.is_empty());
        let s: f64 = row.iter().map(|r| r.1).sum();
        assert!((s - 1.0).abs() < 1e-9);
        let sw = plain.weights.segment_weights(v);
        assert!(sw.iter().all(|&w| w <= sw[plain.labels[v].index()]));
        let (x, y) = (plain.labels[v], a.labels[v]);
        if x != y {
            moved += 1;
            assert!(
                shares_joint(x, y)
                    || Segment::ALL
                        .iter()
                        .any(|&z| shares_joint(x, z) && shares_joint(z, y)),
                "vertex {v}: {x:?} -> {y:?}"
            );
        }
    }
    assert!(moved > 0, "joint planes changed nothing");
}

#[test]
fn noisy_and_surface_biased_joints_still_label_without_swaps() {
    let (sk, mesh, reference, core) = body();
    for seed in [1u64, 2, 3] {
        let mut rng = Rng(seed);
        let bad = noisy(&sk, &mesh, 0.03, 0.10, &mut rng);
        let a = attach(&mesh, &bad, &AttachOptions::default()).unwrap();
        let all = vec![true; mesh.num_vertices()];
        let (agree, mirror) = agreement(&mesh, &a.labels, &reference, &core);
        let (agree_all, mirror_all) = agreement(&mesh, &a.labels, &reference, &all);
        eprintln!(
            "capsule noisy seed {seed}: core {agree:.4} all {agree_all:.4} mirror {mirror_all}"
        );
        assert!(agree >= 0.90, "seed {seed}: core agreement {agree}");
        assert_eq!(mirror, 0.0);
        assert_eq!(mirror_all, 0.0);
    }
}

#[test]
fn swapped_sides_are_detected_and_fixed_or_refused() {
    let (sk, mesh, reference, core) = body();
    let swapped = sk.swap_sides();
    let a = attach(&mesh, &swapped, &AttachOptions::default()).unwrap();
    assert!(a.diagnostics.mirror.swapped);
    let (agree, mirror) = agreement(&mesh, &a.labels, &reference, &core);
    assert!(agree >= 0.95 && mirror == 0.0, "{agree} {mirror}");
    let refuse = AttachOptions {
        mirror: symcorr_attach::MirrorPolicy::Refuse,
        ..AttachOptions::default()
    };
    let e = attach(&mesh, &swapped, &refuse).unwrap_err();
    assert!(e.to_string().contains("swapped"), "{e}");
}

#[test]
fn one_swapped_limb_pair_is_swapped_back_alone_or_refused() {
    let (sk, mesh, reference, core) = body();
    let plain = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    assert_eq!(plain.diagnostics.mirror.swapped_limbs, None);
    for pair in [LimbPair::Arms, LimbPair::Legs] {
        let a = attach(&mesh, &sk.swap_limbs(pair), &AttachOptions::default()).unwrap();
        let m = &a.diagnostics.mirror;
        assert_eq!(m.swapped_limbs, Some(pair), "{pair:?}");
        assert!(!m.swapped, "{pair:?}: the rest of the body was not swapped");
        let (agree, mirror) = agreement(&mesh, &a.labels, &reference, &core);
        assert!(agree >= 0.95 && mirror == 0.0, "{pair:?}: {agree} {mirror}");
        assert_eq!(a.labels, plain.labels, "{pair:?}");
        // The refined joints are the unswapped skeleton's, with its confidences.
        assert_eq!(a.joints.positions, plain.joints.positions, "{pair:?}");
        let refuse = AttachOptions {
            mirror: symcorr_attach::MirrorPolicy::Refuse,
            ..AttachOptions::default()
        };
        let e = attach(&mesh, &sk.swap_limbs(pair), &refuse).unwrap_err();
        let name = if pair == LimbPair::Arms {
            "arms'"
        } else {
            "legs'"
        };
        assert!(e.to_string().contains(name), "{e}");
        // Both pairs swapped is the whole skeleton mirrored: the whole-body fix, no pair.
        let both = sk.swap_limbs(LimbPair::Arms).swap_limbs(LimbPair::Legs);
        let b = attach(&mesh, &both, &AttachOptions::default()).unwrap();
        assert!(b.diagnostics.mirror.swapped && b.diagnostics.mirror.swapped_limbs.is_none());
    }
}

#[test]
fn a_swapped_limb_pair_nothing_tells_apart_is_refused() {
    // Feet straight below the ankles and straight legs: no forward cue at all, so an arm swap
    // and a leg swap look the same.
    let mut sk = t_pose(1.0);
    for (ankle, foot) in [
        (Joint::AnkleLeft, Joint::FootLeft),
        (Joint::AnkleRight, Joint::FootRight),
    ] {
        sk.positions[foot.index()] = sk.positions[ankle.index()] - nalgebra::Vector3::y() * 0.06;
    }
    let (mesh, _) = capsule_body(&sk, 0.02);
    assert!(attach(&mesh, &sk, &AttachOptions::default()).is_ok());
    let e = attach(
        &mesh,
        &sk.swap_limbs(LimbPair::Arms),
        &AttachOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, symcorr_attach::AttachError::LimbSidesUndetermined { .. }),
        "{e}"
    );
    assert!(
        e.to_string().contains("neither the feet nor the knees"),
        "{e}"
    );
}

#[test]
fn units_rotation_and_offset_are_aligned() {
    let (sk, mesh, reference, core) = body();
    // Skeleton in centimetres, rotated 90° about y and moved.
    let mut moved = sk.clone();
    for p in &mut moved.positions {
        *p = nalgebra::Point3::new(
            100.0 * p[2] + 30.0,
            100.0 * p[1] - 12.0,
            -100.0 * p[0] + 7.0,
        );
    }
    let a = attach(&mesh, &moved, &AttachOptions::default()).unwrap();
    let al = &a.diagnostics.alignment;
    assert_eq!(al.scale, 0.01);
    assert!(!al.is_identity());
    assert!(al.fit_after < 0.08 && al.fit_before > al.fit_after);
    let (agree, mirror) = agreement(&mesh, &a.labels, &reference, &core);
    assert!(agree >= 0.9 && mirror == 0.0, "{agree} {mirror}");
    // Mesh in decimetres, skeleton in metres: scale 10.
    let dm = TriMesh {
        positions: mesh.positions.iter().map(|p| p.map(|c| 10.0 * c)).collect(),
        triangles: mesh.triangles.clone(),
    };
    let a = attach(&dm, &sk, &AttachOptions::default()).unwrap();
    assert_eq!(a.diagnostics.alignment.scale, 10.0);
    let (agree, mirror) = agreement(&dm, &a.labels, &reference, &core);
    assert!(agree >= 0.95 && mirror == 0.0, "{agree} {mirror}");
}

#[test]
fn single_view_scan_labels_its_visible_surface() {
    let (sk, mesh, reference, core) = body();
    // A front scan: keep triangles whose normal faces the camera at +z.
    let normals = mesh.triangle_normals();
    let tris: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .zip(&normals)
        .filter(|(_, n)| n[2] > 0.1)
        .map(|(t, _)| *t)
        .collect();
    let mut used = vec![false; mesh.num_vertices()];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    // Keep vertex ids (unused vertices are labelled by their nearest bone and not scored).
    let scan = TriMesh {
        positions: mesh.positions.clone(),
        triangles: tris,
    };
    let mut rng = Rng(7);
    let bad = noisy(&sk, &mesh, 0.03, 0.10, &mut rng);
    for (name, s) in [("exact", &sk), ("noisy", &bad)] {
        let a = attach(&scan, s, &AttachOptions::default()).unwrap();
        let mask: Vec<bool> = (0..used.len()).map(|v| used[v] && core[v]).collect();
        let (agree, mirror) = agreement(&scan, &a.labels, &reference, &mask);
        eprintln!("capsule scan {name}: visible core {agree:.4} mirror {mirror}");
        assert!(agree >= 0.9, "{name}: {agree}");
        assert_eq!(mirror, 0.0);
        assert!(!a.diagnostics.mirror.swapped);
    }
}

#[test]
fn inward_winding_gives_the_same_labels() {
    // Bone heat only takes bones behind a vertex's tangent plane as heat sources, which needs
    // outward normals; a mesh wound the other way round must be recognised and give the same
    // labels and weights.
    let (sk, mesh, _, _) = body();
    let mut flipped = mesh.clone();
    for t in &mut flipped.triangles {
        t.swap(1, 2);
    }
    let a = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let b = attach(&flipped, &sk, &AttachOptions::default()).unwrap();
    let differ = (0..mesh.num_vertices())
        .filter(|&v| a.labels[v] != b.labels[v])
        .count();
    assert_eq!(
        differ,
        0,
        "{differ} of {} labels differ",
        mesh.num_vertices()
    );
    // The same weights up to round-off (the triangles' corner order changes sums).
    for v in 0..mesh.num_vertices() {
        let (wa, wb) = (a.weights.segment_weights(v), b.weights.segment_weights(v));
        for s in 0..17 {
            assert!((wa[s] - wb[s]).abs() < 1e-9, "vertex {v}: {wa:?} vs {wb:?}");
        }
    }
}

#[test]
fn bone_heat_on_clusters_labels_a_dense_body_as_on_the_body_itself() {
    // A body sampled every 1 cm (about 0.6 % of its height), clustered to 1.2 % of its height:
    // a few vertices per cluster, the boundaries known to a cluster's width.
    let sk = t_pose(1.0);
    let (mesh, reference) = capsule_body(&sk, 0.01);
    let core = unambiguous(&mesh, &sk, 0.03);
    let input = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let options = AttachOptions {
        heat_mesh: HeatMesh::Clustered { radius: 0.012 },
        ..AttachOptions::default()
    };
    let clustered = attach(&mesh, &sk, &options).unwrap();
    let (agree, mirror) = agreement(&mesh, &clustered.labels, &reference, &core);
    let same = (0..mesh.num_vertices())
        .filter(|&v| clustered.labels[v] == input.labels[v])
        .count() as f64
        / mesh.num_vertices() as f64;
    eprintln!(
        "capsule clustered heat: core agreement {agree:.4}, same label as unclustered {same:.4}"
    );
    assert!(agree >= 0.95, "core agreement {agree}");
    assert_eq!(mirror, 0.0);
    assert!(same >= 0.97, "{same}");
    // Every input vertex is counted in its component, and each row still sums to one.
    let counted: usize = clustered
        .diagnostics
        .components
        .iter()
        .map(|c| c.vertices)
        .sum();
    assert_eq!(counted, mesh.num_vertices());
    for v in 0..mesh.num_vertices() {
        let s: f64 = clustered.weights.row(v).iter().map(|&(_, w)| w).sum();
        assert!((s - 1.0).abs() < 1e-9, "row {v} sums to {s}");
    }
}
