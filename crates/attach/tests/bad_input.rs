//! Bad input: clear errors or reported repairs, never a panic.

use symcorr_attach::testbody::{capsule_body, t_pose};
use symcorr_attach::{attach, label, AttachError, AttachOptions, Joint, JointRepair, Skeleton};
use symcorr_mesh::TriMesh;

fn body() -> (Skeleton, TriMesh) {
    let sk = t_pose(1.0);
    let (mesh, _) = capsule_body(&sk, 0.03);
    (sk, mesh)
}

#[test]
fn empty_skeleton_is_an_error() {
    let (_, mesh) = body();
    // All joints untracked.
    let mut sk = t_pose(1.0);
    sk.confidence = [0.0; 20];
    let e = attach(&mesh, &sk, &AttachOptions::default()).unwrap_err();
    assert!(
        matches!(e, AttachError::EmptySkeleton { usable: 0, .. }),
        "{e}"
    );
    // All joints at the origin (what an untracked Kinect frame reports).
    let zeros = Skeleton::from_arrays([[0.0; 3]; 20]);
    let e = label(&mesh, &zeros).unwrap_err();
    assert!(matches!(e, AttachError::EmptySkeleton { .. }), "{e}");
    assert!(e.to_string().contains("empty"));
}

#[test]
fn non_finite_joints_are_interpolated_or_dropped_and_reported() {
    let (mut sk, mesh) = body();
    sk.positions[Joint::ElbowLeft.index()] = [f64::NAN, 0.0, 0.0].into();
    sk.positions[Joint::FootRight.index()] = [f64::INFINITY; 3].into();
    let a = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let rep = &a.diagnostics.repaired_joints;
    assert!(rep.contains(&(Joint::ElbowLeft, JointRepair::Interpolated)));
    assert!(rep.contains(&(Joint::FootRight, JointRepair::Dropped)));
    // The interpolated elbow is the midpoint of shoulder and wrist (before refinement moves it
    // by at most the move cap).
    let want = nalgebra::Point3::new(0.39, 1.25, 0.0);
    let got = a.joints.position(Joint::ElbowLeft);
    let d = nalgebra::distance(&got, &want);
    assert!(d < 0.08 * a.diagnostics.skeleton_height + 1e-9, "{got:?}");
    // The right foot bone is dropped: no vertex is labelled foot_right.
    assert_eq!(a.diagnostics.dropped_bones, vec![18]);
    assert!(a
        .labels
        .iter()
        .all(|&s| s != symcorr_attach::Segment::FootRight));
    assert!(a
        .joints
        .positions
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite())));
}

#[test]
fn a_skeleton_100_times_too_large_is_rescaled_and_a_hopeless_one_refused() {
    let (sk, mesh) = body();
    let mut big = sk.clone();
    for p in &mut big.positions {
        *p = p.map(|c| 100.0 * c);
    }
    let a = attach(&mesh, &big, &AttachOptions::default()).unwrap();
    assert_eq!(a.diagnostics.alignment.scale, 0.01);
    // 37× is no unit conversion: either no power of ten fits the extents, or the nearest one
    // leaves the skeleton too large to fit.
    let mut odd = sk.clone();
    for p in &mut odd.positions {
        *p = p.map(|c| 37.0 * c);
    }
    let e = attach(&mesh, &odd, &AttachOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            AttachError::AlignmentFailed { .. } | AttachError::ScaleMismatch { .. }
        ),
        "{e}"
    );
    // A billion times: no power of ten up to 10⁶ reconciles the extents.
    let mut odd = sk.clone();
    for p in &mut odd.positions {
        *p = p.map(|c| 1e9 * c);
    }
    let e = attach(&mesh, &odd, &AttachOptions::default()).unwrap_err();
    assert!(matches!(e, AttachError::ScaleMismatch { .. }), "{e}");
    // Right size, but a different shape (a skeleton squashed flat along its height) fits
    // nowhere.
    let mut flat = sk.clone();
    for p in &mut flat.positions {
        *p = nalgebra::Point3::new(p[0] * 3.0 + 5.0, 0.0, p[1] * 0.3 + 9.0);
    }
    let e = attach(&mesh, &flat, &AttachOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            AttachError::AlignmentFailed { .. } | AttachError::ScaleMismatch { .. }
        ),
        "{e}"
    );
}

/// Closed axis-aligned box as a separate component.
fn boxed(lo: [f64; 3], hi: [f64; 3], base: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let p: Vec<[f64; 3]> = (0..8)
        .map(|c| {
            [
                if c & 1 == 0 { lo[0] } else { hi[0] },
                if c & 2 == 0 { lo[1] } else { hi[1] },
                if c & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let t = quads
        .iter()
        .flat_map(|q| {
            [
                [q[0] + base, q[1] + base, q[2] + base],
                [q[0] + base, q[2] + base, q[3] + base],
            ]
        })
        .collect();
    (p, t)
}

#[test]
fn an_island_no_bone_can_see_falls_back_to_the_nearest_bone_and_is_reported() {
    let (sk, mut mesh) = body();
    // A box beside the body: the bones are inside the body, so every segment from the box to a
    // bone crosses the body's surface — no bone is visible from it (Blender would leave it
    // with empty weights).
    let n0 = mesh.num_vertices() as u32;
    let (p, t) = boxed([1.0, 0.9, -0.2], [1.4, 1.3, 0.2], n0);
    mesh.positions.extend(p);
    mesh.triangles.extend(t);
    // And a vertex in no triangle.
    mesh.positions.push([0.0, 3.0, 0.0]);
    let a = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let comps = &a.diagnostics.components;
    assert_eq!(comps.len(), 2, "{comps:?}");
    let fallback: Vec<_> = comps.iter().filter(|c| c.fallback).collect();
    assert_eq!(fallback.len(), 1);
    assert_eq!(fallback[0].vertices, 8);
    assert!(a.diagnostics.nearest_bone_vertices >= 1);
    // Every vertex, the island's included, has a full weight row; the box nearest the left
    // hand gets the left forearm.
    for v in 0..mesh.num_vertices() {
        let s: f64 = a.weights.row(v).iter().map(|r| r.1).sum();
        assert!((s - 1.0).abs() < 1e-9, "vertex {v}");
    }
    for v in n0 as usize..n0 as usize + 8 {
        assert_eq!(a.labels[v], symcorr_attach::Segment::ForearmLeft);
    }
}

#[test]
fn an_empty_mesh_and_bad_options_are_errors() {
    let sk = t_pose(1.0);
    let empty = TriMesh::default();
    assert!(matches!(
        attach(&empty, &sk, &AttachOptions::default()),
        Err(AttachError::EmptyMesh { .. })
    ));
    let (_, mesh) = body();
    let o = AttachOptions {
        heat_constant: f64::NAN,
        ..AttachOptions::default()
    };
    assert!(matches!(
        attach(&mesh, &sk, &o),
        Err(AttachError::OptionOutOfRange {
            name: "heat_constant",
            ..
        })
    ));
    for radius in [f64::NAN, 0.0, -0.01, 0.5, f64::INFINITY] {
        let o = AttachOptions {
            heat_mesh: symcorr_attach::HeatMesh::Clustered { radius },
            ..AttachOptions::default()
        };
        assert!(
            matches!(
                attach(&mesh, &sk, &o),
                Err(AttachError::OptionOutOfRange {
                    name: "heat_mesh.radius",
                    ..
                })
            ),
            "radius {radius}"
        );
    }
}

#[test]
fn a_malformed_boundary_convention_is_an_error() {
    use symcorr_attach::{BoundaryConvention, BoundaryRule, Joint, Segment};
    let sk = t_pose(1.0);
    let (_, mesh) = body();
    let rule = |a, b, plane| BoundaryConvention {
        rules: vec![BoundaryRule {
            a,
            b,
            joint: Joint::ElbowLeft,
            plane,
        }],
    };
    let bad = [
        (
            rule(
                Segment::UpperArmLeft,
                Segment::ForearmLeft,
                [f64::NAN, 0.0, 0.0, 0.0, 0.0],
            ),
            true,
        ),
        (
            rule(
                Segment::ForearmLeft,
                Segment::ForearmLeft,
                [1.0, 0.0, 0.0, 0.0, 0.0],
            ),
            true,
        ),
        (
            rule(
                Segment::HipLeft,
                Segment::HipRight,
                [1.0, 0.0, 0.0, 0.0, 0.0],
            ),
            true,
        ),
        // A well-formed rule, but joint planes are off: the convention would be ignored.
        (
            rule(
                Segment::UpperArmLeft,
                Segment::ForearmLeft,
                [1.0, 0.0, 0.0, 0.0, 0.0],
            ),
            false,
        ),
    ];
    for (conv, joint_planes) in bad {
        let o = AttachOptions {
            convention: Some(conv),
            joint_planes,
            ..AttachOptions::default()
        };
        match attach(&mesh, &sk, &o) {
            Err(
                e @ (AttachError::InvalidBoundaryRule { .. }
                | AttachError::ConventionNeedsJointPlanes),
            ) => {
                let msg = e.to_string();
                assert!(!msg.contains('\n'), "{msg}");
                assert_eq!(
                    joint_planes,
                    matches!(e, AttachError::InvalidBoundaryRule { .. }),
                    "{msg}"
                );
            }
            other => panic!(
                "expected an invalid rule or a convention without joint planes, got {:?}",
                other.map(|a| a.labels.len())
            ),
        }
    }
    // The same well-formed rule with joint planes on is accepted.
    let ok = AttachOptions {
        convention: Some(rule(
            Segment::UpperArmLeft,
            Segment::ForearmLeft,
            [1.0, 0.0, 0.0, 0.0, 0.0],
        )),
        ..AttachOptions::default()
    };
    let a = attach(&mesh, &sk, &ok).unwrap();
    assert!(a.diagnostics.convention_changes.is_some());
}
