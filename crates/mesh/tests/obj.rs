//! OBJ reader/writer tests: file order kept, corner forms, relative indices, malformed input.

use symcorr_mesh::io::{self, Format, PlyEncoding};
use symcorr_mesh::{MeshError, TriMesh};

fn obj(s: &str) -> Result<io::LoadedMesh, MeshError> {
    io::read_from_bytes(s.as_bytes(), Format::Obj)
}

fn parse_line(e: MeshError) -> usize {
    match e {
        MeshError::Parse { line, .. } => line,
        other => panic!("expected a Parse error, got {other:?}"),
    }
}

#[test]
fn vertex_order_is_file_order_with_all_corner_forms() {
    // Faces use the vertices in reverse order: a renumbering reader (tobj) would move them.
    let m = obj(
        "# c\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nvt 0 0\nvn 0 0 1\nv 1 1 0\nv 0 1 0.25\n\
                 g g1\nusemtl m\ns off\nf 4/1/1 3//1 2/1\nf -4 -3 -2 -1\nl 1 2\n",
    )
    .unwrap();
    assert_eq!(
        m.mesh.positions,
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.25]
        ]
    );
    assert_eq!(m.mesh.triangles, vec![[3, 2, 1], [0, 1, 2], [0, 2, 3]]);
    assert!(m.colors.is_none());
}

#[test]
fn relative_indices_resolve_against_vertices_so_far() {
    let m = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -1 -2 -3\n").unwrap();
    assert_eq!(m.mesh.triangles, vec![[0, 1, 2], [3, 2, 1]]);
}

#[test]
fn vertex_colours_kept_only_when_every_vertex_has_them() {
    let m = obj("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n").unwrap();
    assert_eq!(
        m.colors.unwrap(),
        vec![[255, 0, 0], [0, 255, 0], [0, 0, 128]]
    );
    let m = obj("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n").unwrap();
    assert!(m.colors.is_none());
}

#[test]
fn writer_round_trips_with_and_without_colours() {
    let m = TriMesh::new(
        vec![
            [0.1, -2.5e-7, 3.0],
            [1.0 / 7.0, 0.0, 0.0],
            [0.0, 1e300, 0.0],
        ],
        vec![[0, 1, 2], [2, 1, 0]],
    )
    .unwrap();
    let colors = [[0, 1, 2], [128, 254, 255], [17, 99, 200]];
    for c in [None, Some(&colors[..])] {
        let bytes = io::write_to_bytes(&m, c, Format::Obj, PlyEncoding::default()).unwrap();
        let back = obj(std::str::from_utf8(&bytes).unwrap()).unwrap();
        assert_eq!(back.mesh, m);
        assert_eq!(back.colors.as_deref(), c);
    }
}

#[test]
fn malformed_inputs_give_typed_errors_with_lines() {
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err()),
        4
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err()),
        4
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n").unwrap_err()),
        3
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n").unwrap_err()),
        4
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n").unwrap_err()),
        4
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").unwrap_err()),
        2
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n").unwrap_err()),
        2
    );
    assert_eq!(
        parse_line(obj("v 0 0 0 2 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err()),
        1
    );
    assert_eq!(
        parse_line(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n").unwrap_err()),
        4
    );
    // A truncated file (cut inside the face list) still parses what it has, and a file without
    // faces is a typed whole-mesh error.
    assert!(matches!(
        obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap_err(),
        MeshError::InFile { .. }
    ));
    assert!(matches!(obj("").unwrap_err(), MeshError::InFile { .. }));
}
