//! OFF reader/writer tests, incl. malformed input and the committed body fixture.

use symcorr_mesh::io::{self, Format};
use symcorr_mesh::{MeshError, TriMesh};

fn off(s: &str) -> Result<io::LoadedMesh, MeshError> {
    io::read_from_bytes(s.as_bytes(), Format::Off)
}

fn parse_line(e: &MeshError) -> usize {
    match e {
        MeshError::Parse { line, .. } => *line,
        other => panic!("expected a Parse error, got {other:?}"),
    }
}

#[test]
fn body_fixture_is_closed_manifold_single_component() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/body/body.off");
    let m = io::read(path).unwrap().mesh;
    assert_eq!(m.num_vertices(), 13_380);
    assert_eq!(m.num_triangles(), 26_756);
    assert_eq!(m.connected_components().1, 1);
    // Closed manifold: every edge in exactly two triangles, Euler characteristic 2 (genus 0).
    let e = m.edges().len();
    assert_eq!(3 * m.num_triangles(), 2 * e);
    assert_eq!(
        m.num_vertices() as i64 - e as i64 + m.num_triangles() as i64,
        2
    );
}

#[test]
fn header_comments_edge_count_and_quads() {
    let m = off("# leading comment\nOFF # keyword comment\n\n4 1 # no edge count\n0 0 0\n1 0 0\n1 1 0 # c\n0 1 0\n4 0 1 2 3\n")
        .unwrap();
    assert_eq!(m.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert!(m.colors.is_none());
    let m = off("OFF 3 1 3\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 255 0 0\n").unwrap();
    assert_eq!(m.mesh.num_triangles(), 1);
}

#[test]
fn coff_colours_int_and_float() {
    let m =
        off("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 1.0 0 1\n0 1 0 0 0 0.5\n3 0 1 2\n").unwrap();
    assert_eq!(
        m.colors.unwrap(),
        vec![[255, 0, 0], [0, 255, 0], [0, 0, 128]]
    );
}

#[test]
fn noff_normals_skipped() {
    let m = off("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
    assert_eq!(m.mesh.positions[1], [1.0, 0.0, 0.0]);
}

#[test]
fn malformed_inputs_give_typed_errors_with_lines() {
    // Truncated: fewer vertices than declared.
    assert_eq!(
        parse_line(&off("OFF\n3 1 0\n0 0 0\n1 0 0\n").unwrap_err()),
        5
    );
    // Truncated: fewer faces than declared.
    let e = off("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap_err();
    assert!(e.to_string().contains("1 of 2 faces"), "{e}");
    // Bad counts.
    assert_eq!(parse_line(&off("OFF\nthree 1 0\n").unwrap_err()), 2);
    assert_eq!(parse_line(&off("OFF\n3\n").unwrap_err()), 2);
    // NaN / inf coordinate.
    let e = off("OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").unwrap_err();
    assert_eq!(parse_line(&e), 4);
    assert!(e.to_string().contains("non-finite"), "{e}");
    assert_eq!(
        parse_line(&off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n").unwrap_err()),
        5
    );
    // Index out of range.
    let e = off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").unwrap_err();
    assert_eq!(parse_line(&e), 6);
    assert!(e.to_string().contains("vertex 3"), "{e}");
    // Face declares more vertices than it lists; face with two vertices.
    assert_eq!(
        parse_line(&off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n").unwrap_err()),
        6
    );
    assert_eq!(
        parse_line(&off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n").unwrap_err()),
        6
    );
    // Not OFF; binary OFF; empty file.
    assert_eq!(parse_line(&off("PLY\n").unwrap_err()), 1);
    assert!(off("OFF BINARY\n").is_err());
    assert!(matches!(off("").unwrap_err(), MeshError::Parse { .. }));
    // Colour out of range.
    assert_eq!(
        parse_line(
            &off("COFF\n3 1 0\n0 0 0 256 0 0\n1 0 0 0 0 0\n0 1 0 0 0 0\n3 0 1 2\n").unwrap_err()
        ),
        3
    );
    // No faces at all: a whole-mesh error wrapped with the file name.
    let e = off("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n").unwrap_err();
    match e {
        MeshError::InFile { file, source } => {
            assert_eq!(file, "<memory>");
            assert!(matches!(*source, MeshError::Empty { .. }));
        }
        other => panic!("{other:?}"),
    }
    // Huge declared counts must not allocate; they simply run out of lines.
    assert!(off("OFF\n18446744073709551615 1 0\n0 0 0\n").is_err());
}

#[test]
fn io_errors_name_the_file() {
    let e = io::read("/nonexistent/dir/x.off").unwrap_err();
    assert!(e.to_string().contains("/nonexistent/dir/x.off"), "{e}");
    let e = io::read("mesh.xyz").unwrap_err();
    assert!(matches!(e, MeshError::UnknownFormat { .. }), "{e}");
}

#[test]
fn write_is_atomic_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.OFF");
    let mesh = TriMesh::new(
        vec![[0.1, 0.2, 0.3], [1e-300, -0.0, 7.0], [1.0 / 3.0, 2.0, -5.5]],
        vec![[0, 1, 2]],
    )
    .unwrap();
    io::write(&path, &mesh, None).unwrap();
    assert_eq!(io::read(&path).unwrap().mesh, mesh);
    // A failing write (colour count mismatch) leaves the existing file untouched and no temp file.
    let before = std::fs::read(&path).unwrap();
    assert!(io::write(&path, &mesh, Some(&[[1, 2, 3]])).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[cfg(unix)]
#[test]
fn written_files_are_not_private_temp_files() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.off");
    let mesh = TriMesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )
    .unwrap();
    io::write(&path, &mesh, None).unwrap();
    let mode = |p: &std::path::Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    // Same mode as a file written directly (0666 minus the umask), not the temp file's 0600.
    let direct = dir.path().join("direct.txt");
    std::fs::write(&direct, b"x").unwrap();
    assert_eq!(mode(&path), mode(&direct));
}
