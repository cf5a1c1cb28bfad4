//! Property tests: write → read gives the same mesh (and colours) for every writable format,
//! ascii and binary; through files too (format chosen by extension, atomic write).

use proptest::prelude::*;
use symcorr_mesh::io::{self, Format, PlyEncoding, WriteOptions};
use symcorr_mesh::TriMesh;

fn finite_f64() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
        (-1000i32..1000).prop_map(|x| x as f64 / 8.0),
    ]
}

fn f32_exact() -> impl Strategy<Value = f64> + Clone {
    (prop::num::f32::NORMAL | prop::num::f32::SUBNORMAL | prop::num::f32::ZERO)
        .prop_map(|x| x as f64)
}

fn mesh_with(
    coord: impl Strategy<Value = f64> + Clone,
) -> impl Strategy<Value = (TriMesh, Option<Vec<[u8; 3]>>)> {
    (1usize..40).prop_flat_map(move |n| {
        (
            prop::collection::vec(prop::array::uniform3(coord.clone()), n),
            prop::collection::vec(prop::array::uniform3(0..n as u32), 1..60),
            prop::option::of(prop::collection::vec(prop::array::uniform3(any::<u8>()), n)),
        )
            .prop_map(|(p, t, c)| (TriMesh::new(p, t).unwrap(), c))
    })
}

const EXACT: [(Format, PlyEncoding); 4] = [
    (Format::Off, PlyEncoding::Ascii),
    (Format::Obj, PlyEncoding::Ascii),
    (Format::Ply, PlyEncoding::Ascii),
    (Format::Ply, PlyEncoding::BinaryLittleEndian),
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn f64_formats_round_trip_exactly((m, c) in mesh_with(finite_f64())) {
        for (f, enc) in EXACT {
            let bytes = io::write_to_bytes(&m, c.as_deref(), f, enc).unwrap();
            let back = io::read_from_bytes(&bytes, f).unwrap();
            prop_assert_eq!(&back.mesh, &m, "{:?} {:?}", f, enc);
            // Bit-exact, not just ==: -0.0 stays -0.0.
            for (a, b) in back.mesh.positions.iter().zip(&m.positions) {
                prop_assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
            }
            prop_assert_eq!(&back.colors, &c, "{:?} {:?} colours", f, enc);
        }
    }

    #[test]
    fn gltf_and_glb_round_trip_f32_coordinates((m, c) in mesh_with(f32_exact())) {
        for f in [Format::Glb, Format::Gltf] {
            let bytes = io::write_to_bytes(&m, c.as_deref(), f, PlyEncoding::default()).unwrap();
            let back = io::read_from_bytes(&bytes, f).unwrap();
            prop_assert_eq!(&back.mesh, &m, "{:?}", f);
            prop_assert_eq!(&back.colors, &c, "{:?} colours", f);
        }
    }

    #[test]
    fn file_round_trip_by_extension((m, c) in mesh_with(f32_exact()), ascii in any::<bool>()) {
        let dir = tempfile::tempdir().unwrap();
        for ext in ["off", "obj", "ply", "gltf", "glb"] {
            let path = dir.path().join(format!("m.{ext}"));
            let opts = WriteOptions {
                format: None,
                ply_encoding: if ascii { PlyEncoding::Ascii } else { PlyEncoding::BinaryLittleEndian },
            };
            io::write_with(&path, &m, c.as_deref(), &opts).unwrap();
            let back = io::read(&path).unwrap();
            prop_assert_eq!(&back.mesh, &m, "{}", ext);
            prop_assert_eq!(&back.colors, &c, "{} colours", ext);
        }
        // Atomic writes leave no temporary files behind.
        prop_assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 5);
    }
}

#[test]
fn glb_rejects_coordinates_beyond_f32() {
    let m = TriMesh::new(
        vec![[1e300, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let e = io::write_to_bytes(&m, None, Format::Glb, PlyEncoding::default()).unwrap_err();
    assert!(
        matches!(
            e,
            symcorr_mesh::MeshError::NotRepresentable { vertex: 0, .. }
        ),
        "{e}"
    );
}

#[test]
fn explicit_format_overrides_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.dat");
    let m = TriMesh::new(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let opts = WriteOptions {
        format: Some(Format::Ply),
        ply_encoding: PlyEncoding::Ascii,
    };
    io::write_with(&path, &m, None, &opts).unwrap();
    assert!(std::fs::read_to_string(&path)
        .unwrap()
        .starts_with("ply\nformat ascii 1.0\n"));
    assert!(io::read(&path).is_err()); // .dat names no format
    assert_eq!(io::read_with_format(&path, Format::Ply).unwrap().mesh, m);
}
