//! Validation and repair on hand-made meshes whose defects are known by construction.

use nalgebra::Vector3;
use proptest::prelude::*;
use symcorr_mesh::{repair, validate, MeshError, RepairOptions, TriMesh};

fn tetra_at(o: [f64; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ]
    .map(|q| (Vector3::from(q) + Vector3::from(o)).into());
    (p.to_vec(), vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
}

#[test]
fn body_fixture_validates_clean_and_closed() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/body/body.off");
    let m = symcorr_mesh::io::read(path).unwrap().mesh;
    let r = validate(&m);
    assert!(r.is_clean(), "{r}");
    assert!(r.is_closed());
    assert_eq!(r.component_triangles, vec![26_756]);
    let fixed = repair(&m, &RepairOptions::default()).unwrap();
    assert!(fixed.report.unchanged(), "{}", fixed.report);
    assert_eq!(fixed.mesh, m);
}

#[test]
fn open_square_has_one_boundary_loop() {
    let m = TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let r = validate(&m);
    assert!(r.is_clean(), "{r}");
    assert_eq!(r.boundary_loops.len(), 1);
    let mut l = r.boundary_loops[0].clone();
    // The loop follows the triangles' orientation: 0 → 1 → 2 → 3 up to rotation.
    let s = l.iter().position(|&v| v == 0).unwrap();
    l.rotate_left(s);
    assert_eq!(l, vec![0, 1, 2, 3]);
    assert_eq!(m.boundary_loops(), r.boundary_loops);
    assert_eq!(m.boundary_vertices(), vec![true; 4]);
    let (p, t) = tetra_at([0.0; 3]);
    let closed = TriMesh::new(p, t).unwrap();
    assert!(closed.boundary_loops().is_empty());
    assert_eq!(closed.boundary_vertices(), vec![false; 4]);
}

#[test]
fn square_with_two_holes_style_annulus_has_two_loops() {
    // A square frame: outer 4 vertices, inner 4 vertices, 8 triangles → 2 boundary loops.
    let mut p = vec![
        [0.0, 0.0, 0.0],
        [3.0, 0.0, 0.0],
        [3.0, 3.0, 0.0],
        [0.0, 3.0, 0.0],
    ];
    p.extend([
        [1.0, 1.0, 0.0],
        [2.0, 1.0, 0.0],
        [2.0, 2.0, 0.0],
        [1.0, 2.0, 0.0],
    ]);
    let mut t = Vec::new();
    for k in 0..4u32 {
        let (o0, o1, i0, i1) = (k, (k + 1) % 4, 4 + k, 4 + (k + 1) % 4);
        t.push([o0, o1, i1]);
        t.push([o0, i1, i0]);
    }
    let r = validate(&TriMesh::new(p, t).unwrap());
    assert!(r.is_clean(), "{r}");
    let mut lens: Vec<usize> = r.boundary_loops.iter().map(Vec::len).collect();
    lens.sort();
    assert_eq!(lens, vec![4, 4]);
}

#[test]
fn defects_are_found_and_repaired_with_a_vertex_map() {
    // Input: unused vertex 0, then a tetra (1..=4), a degenerate triangle, a zero-area
    // (collinear) triangle, a duplicate with other winding, and an island triangle (5..=7).
    let (tp, tt) = tetra_at([0.0; 3]);
    let mut p = vec![[50.0, 50.0, 50.0]];
    p.extend(tp);
    p.extend([
        [5.0, 0.0, 0.0],
        [6.0, 0.0, 0.0],
        [5.0, 1.0, 0.0],
        [7.0, 0.0, 0.0],
    ]);
    let mut t: Vec<[u32; 3]> = tt.iter().map(|t| t.map(|i| i + 1)).collect();
    t.push([1, 1, 2]); // 4: degenerate
    t.push([5, 6, 8]); // 5: collinear (5,0,0) (6,0,0) (7,0,0)
    t.push([2, 1, 3]); // 6: duplicate of triangle 0 ([1, 3, 2]) with the other winding
    t.push([5, 6, 7]); // 7: island
    let m = TriMesh::new(p.clone(), t).unwrap();
    let r = validate(&m);
    assert_eq!(r.degenerate_triangles, vec![4]);
    assert_eq!(r.zero_area_triangles, vec![5]);
    assert_eq!(r.duplicate_triangles, vec![6]);
    assert_eq!(r.unreferenced_vertices, vec![0]);
    assert_eq!(r.components(), 2);
    assert!(!r.is_clean());
    let text = r.to_string();
    assert!(text.contains("duplicate triangles: 1"), "{text}");

    let fixed = repair(&m, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.report.removed_degenerate_triangles, 1);
    assert_eq!(fixed.report.removed_zero_area_triangles, 1);
    assert_eq!(fixed.report.removed_duplicate_triangles, 1);
    assert_eq!(fixed.report.removed_vertices, 2); // 0, and 8 (only in the collinear triangle)
    assert_eq!(fixed.vertex_map, vec![1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(fixed.triangle_map, vec![0, 1, 2, 3, 7]);
    assert_eq!(fixed.report.after.components(), 2);
    assert!(fixed.report.after.unreferenced_vertices.is_empty());

    let largest = repair(
        &m,
        &RepairOptions {
            keep_largest_component: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(largest.vertex_map, vec![1, 2, 3, 4]);
    assert_eq!(largest.mesh.num_triangles(), 4);
    assert_eq!(largest.report.removed_components, 1);
    assert!(largest.report.after.is_clean(), "{}", largest.report);
    assert!(largest.report.after.is_closed());
    let text = largest.report.to_string();
    assert!(text.contains("components removed"), "{text}");
}

#[test]
fn non_manifold_edge_detected_and_trimmed() {
    // Three triangles sharing edge (0, 1).
    let m = TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    )
    .unwrap();
    let r = validate(&m);
    assert_eq!(r.non_manifold_edges, vec![[0, 1]]);
    let opts = RepairOptions {
        remove_non_manifold_edge_triangles: true,
        ..Default::default()
    };
    let fixed = repair(&m, &opts).unwrap();
    assert_eq!(fixed.triangle_map, vec![0, 1]);
    assert_eq!(fixed.vertex_map, vec![0, 1, 2, 3]);
    assert!(fixed.report.after.non_manifold_edges.is_empty());
}

#[test]
fn bowtie_vertex_detected_and_split() {
    // Two tetrahedra sharing vertex 0 only: vertex 0 has two fans.
    let (p1, t1) = tetra_at([0.0; 3]);
    let mut p = p1;
    p.extend([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]);
    let mut t = t1;
    // Second tetra on vertices 0, 4, 5, 6 (mirrored, so orientation is outward too).
    t.extend([[0, 4, 5], [0, 6, 4], [4, 6, 5], [0, 5, 6]]);
    let m = TriMesh::new(p, t).unwrap();
    let r = validate(&m);
    assert_eq!(r.non_manifold_vertices, vec![0]);
    assert_eq!(r.components(), 1);
    assert!(r.non_manifold_edges.is_empty());
    let opts = RepairOptions {
        split_non_manifold_vertices: true,
        ..Default::default()
    };
    let fixed = repair(&m, &opts).unwrap();
    assert_eq!(fixed.report.added_split_vertices, 1);
    assert_eq!(fixed.vertex_map, vec![0, 1, 2, 3, 4, 5, 6, 0]);
    assert!(fixed.report.after.non_manifold_vertices.is_empty());
    assert_eq!(fixed.report.after.components(), 2);
    assert_eq!(fixed.mesh.positions[7], fixed.mesh.positions[0]);
}

#[test]
fn invalid_inputs_are_errors_not_panics() {
    let bad = TriMesh {
        positions: vec![[0.0, f64::NAN, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        triangles: vec![[0, 1, 2]],
    };
    assert!(matches!(
        repair(&bad, &RepairOptions::default()),
        Err(MeshError::NonFinite { vertex: 0 })
    ));
    assert_eq!(validate(&bad).non_finite_vertices, vec![0]);
    let bad = TriMesh {
        positions: vec![[0.0; 3]; 3],
        triangles: vec![[0, 1, 9]],
    };
    assert!(matches!(
        repair(&bad, &RepairOptions::default()),
        Err(MeshError::IndexOutOfRange { .. })
    ));
    assert_eq!(validate(&bad).out_of_range_triangles, vec![0]);
    assert!(!validate(&TriMesh::default()).is_clean());
    assert!(matches!(
        repair(&TriMesh::default(), &RepairOptions::default()),
        Err(MeshError::Empty { .. })
    ));
    // Every triangle degenerate: nothing left.
    let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![[0, 0, 1]]).unwrap();
    assert!(matches!(
        repair(&m, &RepairOptions::default()),
        Err(MeshError::NothingLeft { .. })
    ));
}

fn arb_mesh() -> impl Strategy<Value = TriMesh> {
    (1usize..12).prop_flat_map(|n| {
        (
            prop::collection::vec(prop::array::uniform3(-3i8..4), n),
            prop::collection::vec(prop::array::uniform3(0..n as u32), 1..20),
        )
            .prop_map(|(p, t)| {
                TriMesh::new(p.into_iter().map(|q| q.map(|x| x as f64)).collect(), t).unwrap()
            })
    })
}

proptest! {
    /// The maps always point back to the input: positions and triangles of the repaired mesh
    /// are the input's, renamed through `vertex_map` / `triangle_map`; and the result has no
    /// defect of the kinds removed.
    #[test]
    fn repair_maps_point_back_to_the_input(m in arb_mesh(), largest in any::<bool>(), split in any::<bool>(), trim in any::<bool>()) {
        let opts = RepairOptions {
            keep_largest_component: largest,
            split_non_manifold_vertices: split,
            remove_non_manifold_edge_triangles: trim,
            ..Default::default()
        };
        let before = validate(&m);
        match repair(&m, &opts) {
            Ok(fixed) => {
                prop_assert_eq!(fixed.vertex_map.len(), fixed.mesh.num_vertices());
                prop_assert_eq!(fixed.triangle_map.len(), fixed.mesh.num_triangles());
                for (v, &orig) in fixed.vertex_map.iter().enumerate() {
                    prop_assert_eq!(fixed.mesh.positions[v], m.positions[orig as usize]);
                }
                // Each triangle is the input's, renamed, or the input's turned (the orientation
                // repair reverses its order), and the report counts the turned ones.
                let mut turned = 0;
                for (t, &orig) in fixed.triangle_map.iter().enumerate() {
                    let renamed = fixed.mesh.triangles[t].map(|v| fixed.vertex_map[v as usize]);
                    let [a, b, c] = m.triangles[orig as usize];
                    if renamed != [a, b, c] {
                        prop_assert_eq!(renamed, [a, c, b]);
                        turned += 1;
                    }
                }
                prop_assert_eq!(turned, fixed.report.turned_triangles);
                let kept = fixed.mesh.num_vertices() - fixed.report.added_split_vertices;
                prop_assert!(fixed.vertex_map[..kept].windows(2).all(|w| w[0] < w[1]));
                let after = &fixed.report.after;
                prop_assert!(after.degenerate_triangles.is_empty());
                prop_assert!(after.zero_area_triangles.is_empty());
                prop_assert!(after.duplicate_triangles.is_empty());
                prop_assert!(after.unreferenced_vertices.is_empty());
                if largest && !split { prop_assert_eq!(after.components(), 1); }
                if trim { prop_assert!(after.non_manifold_edges.is_empty()); }
                if split && !trim { prop_assert!(after.non_manifold_vertices.is_empty()); }
                prop_assert_eq!(&fixed.report.before, &before);
                // The report after is the repaired mesh's, whether it was validated again or
                // (nothing changed) carried over, and the boundary length read from it is the
                // mesh's.
                prop_assert_eq!(after, &validate(&fixed.mesh));
                let from_report: f64 =
                    after.boundary_loops.iter().map(|l| fixed.mesh.loop_length(l)).sum();
                prop_assert!((from_report - fixed.mesh.boundary_length()).abs() <= 1e-9);
            }
            Err(MeshError::NothingLeft { .. }) => {
                prop_assert_eq!(
                    before.degenerate_triangles.len() + before.zero_area_triangles.len(),
                    m.num_triangles()
                );
            }
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }
}

/// Signed volume of a closed mesh (positive when its triangles face outward).
fn signed_volume(m: &TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| nalgebra::Vector3::from(m.positions[v as usize]));
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

/// The default repair orients every component consistently: a closed one outward, an open one
/// as most of its triangles were, and it counts the triangles it turned.
#[test]
fn repair_orients_components_consistently_and_outward() {
    let tet = symcorr_mesh::testmesh::tetrahedron();
    assert!(signed_volume(&tet) > 0.0);
    // One face turned: the repair turns it back.
    let mut one = tet.clone();
    one.triangles[2].swap(1, 2);
    assert_eq!(validate(&one).inconsistently_oriented_edges, 3);
    let r = repair(&one, &RepairOptions::default()).unwrap();
    assert_eq!(r.report.turned_triangles, 1);
    assert_eq!(r.mesh.triangles, tet.triangles);
    assert!(!r.report.unchanged());
    // Every face inward: consistent, but a closed surface must face outward.
    let mut inward = tet.clone();
    for t in &mut inward.triangles {
        t.swap(1, 2);
    }
    let r = repair(&inward, &RepairOptions::default()).unwrap();
    assert_eq!(r.report.turned_triangles, 4);
    assert!(signed_volume(&r.mesh) > 0.0);
    assert_eq!(r.report.after.inconsistently_oriented_edges, 0);
    // An open strip of three triangles with the middle one turned: the majority wins.
    let strip = TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 2.0, 0.0],
        ],
        vec![[0, 1, 2], [1, 2, 3], [2, 3, 4]],
    )
    .unwrap();
    let r = repair(&strip, &RepairOptions::default()).unwrap();
    assert_eq!(r.report.turned_triangles, 1);
    assert_eq!(r.mesh.triangles[1], [1, 3, 2]);
    assert_eq!(r.report.after.inconsistently_oriented_edges, 0);
    // A consistent mesh is left alone, and the option can be switched off.
    let r = repair(&tet, &RepairOptions::default()).unwrap();
    assert!(r.report.unchanged());
    let off = RepairOptions {
        orient_consistently: false,
        ..RepairOptions::default()
    };
    assert_eq!(repair(&one, &off).unwrap().report.turned_triangles, 0);
}

/// The bundled bodies are consistent and face outward: the repair leaves them unchanged.
#[test]
fn bundled_bodies_need_no_turning() {
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/bodies/meshes");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let m = symcorr_mesh::io::read(&path).unwrap().mesh;
        let r = repair(&m, &RepairOptions::default()).unwrap();
        assert_eq!(r.report.turned_triangles, 0, "{}", path.display());
        assert!(signed_volume(&m) > 0.0, "{}", path.display());
    }
}
