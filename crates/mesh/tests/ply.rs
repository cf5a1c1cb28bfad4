//! PLY reader/writer tests: encodings, property orders, colours, list types, malformed input.

use symcorr_mesh::io::{self, Format, PlyEncoding};
use symcorr_mesh::{MeshError, TriMesh};

fn ply(b: &[u8]) -> Result<io::LoadedMesh, MeshError> {
    io::read_from_bytes(b, Format::Ply)
}

fn quad() -> TriMesh {
    TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.5],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap()
}

#[test]
fn ascii_any_property_order_extra_props_and_elements() {
    let text = "ply\r\nformat ascii 1.0\ncomment hi\nobj_info x\nelement vertex 4\nproperty float nx\n\
        property uchar blue\nproperty double z\nproperty uchar red\nproperty float y\nproperty uchar green\n\
        property float x\nelement material 1\nproperty list uchar float weird\nproperty int id\n\
        element face 1\nproperty int flags\nproperty list uint short vertex_index\nproperty list uchar int other\n\
        end_header\n\
        9 3 0 1 0 0 0\n9 0 0 2 0 0 1\n9 0 0 0 1 255 1\n9 0 0.5 0 1 0 0\n\
        2 1.5 2.5 7\n\
        -1 4 0 1 2 3 2 100 200\n";
    let m = ply(text.as_bytes()).unwrap();
    assert_eq!(m.mesh, quad());
    assert_eq!(
        m.colors.unwrap(),
        vec![[1, 0, 3], [2, 0, 0], [0, 255, 0], [0, 0, 0]]
    );
}

fn binary_quad(big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty double z\n\
         property short extra\nelement face 1\nproperty list ushort uchar vertex_indices\nend_header\n"
    )
    .into_bytes();
    let q = quad();
    for p in &q.positions {
        let (x, y, z) = (p[0] as f32, p[1] as f32, p[2]);
        if big_endian {
            b.extend_from_slice(&x.to_be_bytes());
            b.extend_from_slice(&y.to_be_bytes());
            b.extend_from_slice(&z.to_be_bytes());
            b.extend_from_slice(&(-3i16).to_be_bytes());
        } else {
            b.extend_from_slice(&x.to_le_bytes());
            b.extend_from_slice(&y.to_le_bytes());
            b.extend_from_slice(&z.to_le_bytes());
            b.extend_from_slice(&(-3i16).to_le_bytes());
        }
    }
    b.extend_from_slice(&if big_endian {
        4u16.to_be_bytes()
    } else {
        4u16.to_le_bytes()
    });
    b.extend_from_slice(&[0, 1, 2, 3]);
    b
}

#[test]
fn binary_little_and_big_endian() {
    for be in [false, true] {
        let m = ply(&binary_quad(be)).unwrap();
        assert_eq!(m.mesh, quad(), "big_endian={be}");
        assert!(m.colors.is_none());
    }
}

#[test]
fn binary_truncated_names_element() {
    let b = binary_quad(false);
    for cut in [b.len() - 1, b.len() - 5, b.len() - 40] {
        match ply(&b[..cut]).unwrap_err() {
            MeshError::Malformed { element, .. } => assert!(
                element.contains("face") || element.contains("vertex"),
                "{element}"
            ),
            e => panic!("{e:?}"),
        }
    }
}

#[test]
fn writer_round_trips_both_encodings_with_colours() {
    let m = quad();
    let colors = [[1, 2, 3], [4, 5, 6], [7, 8, 9], [250, 251, 252]];
    for enc in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
        for c in [None, Some(&colors[..])] {
            let bytes = io::write_to_bytes(&m, c, Format::Ply, enc).unwrap();
            let back = ply(&bytes).unwrap();
            assert_eq!(back.mesh, m);
            assert_eq!(back.colors.as_deref(), c);
        }
    }
}

fn parse_line(e: MeshError) -> usize {
    match e {
        MeshError::Parse { line, .. } => line,
        other => panic!("expected a Parse error, got {other:?}"),
    }
}

const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn malformed_ascii_inputs() {
    let ok = format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert_eq!(ply(ok.as_bytes()).unwrap().mesh.num_triangles(), 1);
    // NaN coordinate, named by line 11 (header is 9 lines).
    let e = ply(format!("{HEAD}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n").as_bytes()).unwrap_err();
    assert!(e.to_string().contains("non-finite"), "{e}");
    assert_eq!(parse_line(e), 11);
    // Index out of range, negative index.
    let e = ply(format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").as_bytes()).unwrap_err();
    assert!(e.to_string().contains("face 0"), "{e}");
    assert_eq!(parse_line(e), 13);
    assert_eq!(
        parse_line(ply(format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n").as_bytes()).unwrap_err()),
        13
    );
    // Truncated body; wrong element counts (fewer vertices than declared).
    assert!(matches!(
        ply(format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1").as_bytes()).unwrap_err(),
        MeshError::Parse { .. }
    ));
    assert!(ply(format!("{HEAD}0 0 0\n1 0 0\n3 0 1 2\n").as_bytes()).is_err());
    // Not a number; two-vertex face.
    assert_eq!(
        parse_line(ply(format!("{HEAD}0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n").as_bytes()).unwrap_err()),
        11
    );
    assert!(ply(format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n2 0 1\n").as_bytes()).is_err());
    // Header problems.
    assert_eq!(parse_line(ply(b"plx\n").unwrap_err()), 1);
    assert_eq!(
        parse_line(ply(b"ply\nformat ascii 1.0\nelement vertex 3\n").unwrap_err()),
        4
    );
    assert_eq!(
        parse_line(ply(b"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n").unwrap_err()),
        3
    );
    assert_eq!(
        parse_line(
            ply(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty quad x\nend_header\n")
                .unwrap_err()
        ),
        4
    );
    assert_eq!(
        parse_line(ply(b"ply\nformat ebcdic 1.0\nend_header\n").unwrap_err()),
        2
    );
    assert_eq!(
        parse_line(ply(b"ply\nelement vertex 0\nend_header\n").unwrap_err()),
        3
    );
    assert!(matches!(
        ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n")
            .unwrap_err(),
        MeshError::Malformed { .. }
    ));
    // Lying counts: huge vertex count or list length must fail fast, not allocate.
    let e = ply(b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0").unwrap_err();
    assert!(matches!(e, MeshError::Malformed { .. }), "{e}");
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty uchar x\nproperty uchar y\nproperty uchar z\nelement face 1\nproperty list uint uint vertex_indices\nend_header\n".to_vec();
    b.extend_from_slice(&[0; 9]);
    b.extend_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(ply(&b).unwrap_err(), MeshError::Malformed { .. }));
    // Float-typed index list is rejected at the header.
    assert_eq!(parse_line(ply(b"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n").unwrap_err()), 4);
    // No faces: whole-mesh Empty error wrapped with the file name.
    let e = ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n").unwrap_err();
    assert!(matches!(e, MeshError::InFile { .. }), "{e}");
}

#[test]
fn face_element_before_vertex_element_and_float_colours() {
    let text = "ply\nformat ascii 1.0\nelement face 2\nproperty list char uint vertex_indices\n\
                element vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
                property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\nend_header\n\
                3 0 1 2\n3 0 2 3\n\
                0 0 0 1 0 0\n1 0 0 0 1 0\n1 1 0 0 0 1\n0 1 0.5 0.5 0.5 0.5\n";
    let m = ply(text.as_bytes()).unwrap();
    assert_eq!(m.mesh, quad());
    assert_eq!(
        m.colors.unwrap(),
        vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128]]
    );
    // Out-of-range float colour and forward index beyond the declared vertex count.
    let bad = text.replace("0 1 0.5 0.5 0.5 0.5", "0 1 0.5 0.5 1.5 0.5");
    assert!(matches!(
        ply(bad.as_bytes()).unwrap_err(),
        MeshError::Parse { .. }
    ));
    let bad = text.replace("3 0 2 3\n", "3 0 2 4\n");
    assert!(ply(bad.as_bytes())
        .unwrap_err()
        .to_string()
        .contains("face 1"));
}

/// An ascii element is one line: a value too many or too few is blamed on that element and
/// its line, not on the element that would have read the stray value next.
#[test]
fn ascii_value_count_is_checked_per_element_line() {
    let parse = |body: &str| match ply(format!("{HEAD}{body}").as_bytes()).unwrap_err() {
        MeshError::Parse { line, message, .. } => (line, message),
        other => panic!("expected a Parse error, got {other:?}"),
    };
    // Extra value on vertex 1 (line 11; the header is 9 lines).
    let (line, msg) = parse("0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n");
    assert_eq!(line, 11);
    assert_eq!(
        msg,
        "vertex 1: has 4 values, the header declares 3 properties"
    );
    // Missing value on vertex 0 (line 10).
    let (line, msg) = parse("0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert_eq!(line, 10);
    assert_eq!(
        msg,
        "vertex 0: has 2 values, the header declares 3 properties"
    );
    // A face with more indices than its count says, or fewer.
    let (line, msg) = parse("0 0 0\n1 0 0\n0 1 0\n3 0 1 2 2\n");
    assert_eq!(line, 13);
    assert!(msg.starts_with("face 0: has 5 values"), "{msg}");
    let (line, msg) = parse("0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n");
    assert_eq!(line, 13);
    assert!(
        msg.starts_with("face 0: the line ends after 4 values"),
        "{msg}"
    );
    // Blank lines between elements and CRLF line ends are fine.
    let ok = format!("{HEAD}0 0 0\r\n\n1 0 0\r\n0 1 0\n\n3 0 1 2");
    assert_eq!(ply(ok.as_bytes()).unwrap().mesh.num_triangles(), 1);
}
