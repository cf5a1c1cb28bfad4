//! glTF/GLB tests: writer output is valid glTF 2.0 and reads back; hand-built scenes with node
//! transforms, several primitives, index types, external buffers; malformed files give errors.

use base64::Engine as _;
use serde_json::{json, Value};
use symcorr_mesh::io::{self, Format, PlyEncoding};
use symcorr_mesh::{testmesh, MeshError, TriMesh};

/// The shared tetrahedron with its apex raised to z = 1.5, so the bounds differ per axis.
fn tetra() -> TriMesh {
    let mut m = testmesh::tetrahedron();
    m.positions[3][2] = 1.5;
    m
}

fn glb_chunks(b: &[u8]) -> (Value, Vec<u8>) {
    assert_eq!(&b[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(b[4..8].try_into().unwrap()), 2);
    assert_eq!(
        u32::from_le_bytes(b[8..12].try_into().unwrap()) as usize,
        b.len()
    );
    let jl = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    assert_eq!(&b[16..20], b"JSON");
    assert_eq!(jl % 4, 0);
    let doc: Value = serde_json::from_slice(&b[20..20 + jl]).unwrap();
    let bl = u32::from_le_bytes(b[20 + jl..24 + jl].try_into().unwrap()) as usize;
    assert_eq!(&b[24 + jl..28 + jl], b"BIN\0");
    assert_eq!(bl % 4, 0);
    (doc, b[28 + jl..28 + jl + bl].to_vec())
}

#[test]
fn glb_writer_is_valid_gltf2_and_round_trips_with_colours() {
    let m = tetra();
    let colors = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [10, 20, 30]];
    let bytes = io::write_to_bytes(&m, Some(&colors), Format::Glb, PlyEncoding::default()).unwrap();
    let (doc, bin) = glb_chunks(&bytes);
    assert_eq!(doc["asset"]["version"], "2.0");
    assert_eq!(
        doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
        bin.len()
    );
    for v in doc["bufferViews"].as_array().unwrap() {
        assert_eq!(v["byteOffset"].as_u64().unwrap() % 4, 0, "view alignment");
        if let Some(s) = v["byteStride"].as_u64() {
            assert_eq!(s % 4, 0);
        }
    }
    let prim = &doc["meshes"][0]["primitives"][0];
    let pos = &doc["accessors"][prim["attributes"]["POSITION"].as_u64().unwrap() as usize];
    assert_eq!(pos["min"], json!([0.0, 0.0, 0.0]));
    assert_eq!(pos["max"], json!([1.0, 1.0, 1.5]));
    let col = &doc["accessors"][prim["attributes"]["COLOR_0"].as_u64().unwrap() as usize];
    // COLOR_0 is linear (glTF 2.0): sRGB 255 → 1.0, sRGB 10 → 0.003035 (IEC 61966-2-1).
    assert_eq!(col["componentType"], 5126);
    let view = &doc["bufferViews"][col["bufferView"].as_u64().unwrap() as usize];
    let off = view["byteOffset"].as_u64().unwrap() as usize;
    let f = |i: usize| f32::from_le_bytes(bin[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!(f(0), 1.0);
    assert_eq!(f(1), 0.0);
    assert!((f(9) - 0.003_035).abs() < 1e-6, "{}", f(9));
    assert!((f(10) - 0.006_995).abs() < 1e-6, "{}", f(10));

    let back = io::read_from_bytes(&bytes, Format::Glb).unwrap();
    assert_eq!(back.mesh, m);
    assert_eq!(back.colors.as_deref(), Some(&colors[..]));
    // The gltf crate's own validation accepts the file.
    assert!(gltf::Gltf::from_slice(&bytes).is_ok());
}

#[test]
fn embedded_gltf_round_trips_through_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.gltf");
    io::write(&path, &tetra(), None).unwrap();
    let back = io::read(&path).unwrap();
    assert_eq!(back.mesh, tetra());
    assert!(back.colors.is_none());
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A scene: root node (translate +10 x) → child with mesh 0 (scale -1 on x: mirrored) and a
/// second root with mesh 1 (two primitives: u8-indexed triangles and a non-indexed strip).
fn scene(uri: Option<&str>) -> (Value, Vec<u8>) {
    let mut bin = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // 36 bytes, view 0
    bin.extend_from_slice(&[0, 1, 2, 0]); // view 1: u8 indices (+1 pad)
    bin.extend(f32s(&[
        0.0, 0.0, 5.0, 1.0, 0.0, 5.0, 0.0, 1.0, 5.0, 1.0, 1.0, 5.0,
    ])); // view 2 @40
    let mut buffer = json!({"byteLength": bin.len()});
    if let Some(u) = uri {
        buffer["uri"] = json!(u);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"translation": [10.0, 0.0, 0.0], "children": [1]},
            {"scale": [-1.0, 1.0, 1.0], "mesh": 0},
            {"mesh": 1}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
            {"primitives": [
                {"attributes": {"POSITION": 0}, "indices": 1, "mode": 4},
                {"attributes": {"POSITION": 2}, "mode": 5},
                {"attributes": {"POSITION": 2}, "mode": 1}
            ]}
        ],
        "buffers": [buffer],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 3},
            {"buffer": 0, "byteOffset": 40, "byteLength": 48}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3"}
        ]
    });
    (doc, bin)
}

fn check_scene(m: &TriMesh) {
    assert_eq!(m.num_vertices(), 3 + 3 + 4);
    // Mesh 0 through node 0 (translate) ∘ node 1 (mirror x): x ↦ 10 - x.
    assert_eq!(
        &m.positions[0..3],
        &[[10.0, 0.0, 0.0], [9.0, 0.0, 0.0], [10.0, 1.0, 0.0]]
    );
    // Mirrored instance: winding flipped so the normal keeps pointing the same way (+z here).
    assert_eq!(m.triangles[0], [0, 2, 1]);
    assert!(m.triangle_normals()[0][2] > 0.0);
    // Mesh 1, untransformed: triangle, then the strip (two triangles, alternating winding).
    assert_eq!(m.triangles[1], [3, 4, 5]);
    assert_eq!(&m.triangles[2..], &[[6, 7, 8], [8, 7, 9]]);
    assert_eq!(m.positions[9], [1.0, 1.0, 5.0]);
}

#[test]
fn scene_graph_transforms_and_primitives_from_data_uri_glb_and_external_bin() {
    // Embedded base64.
    let (_, bin) = scene(None);
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let (doc, _) = scene(Some(&uri));
    let m = io::read_from_bytes(doc.to_string().as_bytes(), Format::Gltf).unwrap();
    check_scene(&m.mesh);

    // External .bin next to the .gltf (URI with a percent-escaped space).
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("the data.bin"), &bin).unwrap();
    let (doc, _) = scene(Some("the%20data.bin"));
    std::fs::write(dir.path().join("s.gltf"), doc.to_string()).unwrap();
    check_scene(&io::read(dir.path().join("s.gltf")).unwrap().mesh);
    // From memory, an external buffer cannot be resolved.
    let e = io::read_from_bytes(doc.to_string().as_bytes(), Format::Gltf).unwrap_err();
    assert!(e.to_string().contains("buffer 0"), "{e}");
    // A missing .bin is an I/O error naming it.
    std::fs::remove_file(dir.path().join("the data.bin")).unwrap();
    let e = io::read(dir.path().join("s.gltf")).unwrap_err();
    assert!(e.to_string().contains("the data.bin"), "{e}");
    assert!(e.to_string().contains("s.gltf: buffer uri"), "{e}");
}

fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = doc.to_string().into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((28 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

fn malformed_element(e: MeshError) -> String {
    match e {
        MeshError::Malformed { element, .. } => element,
        other => panic!("expected Malformed, got {other:?}"),
    }
}

#[test]
fn hand_built_glb_and_malformed_variants() {
    let (doc, bin) = scene(None);
    check_scene(
        &io::read_from_bytes(&glb(&doc, &bin), Format::Glb)
            .unwrap()
            .mesh,
    );

    // Accessor running past its buffer view.
    let mut d = doc.clone();
    d["accessors"][2]["count"] = json!(5);
    assert_eq!(
        malformed_element(io::read_from_bytes(&glb(&d, &bin), Format::Glb).unwrap_err()),
        "accessor 2"
    );
    // Buffer view outside the buffer.
    let mut d = doc.clone();
    d["bufferViews"][2]["byteLength"] = json!(4800);
    assert!(io::read_from_bytes(&glb(&d, &bin), Format::Glb).is_err());
    // Index out of range.
    let mut b = bin.clone();
    b[38] = 7;
    assert!(
        malformed_element(io::read_from_bytes(&glb(&doc, &b), Format::Glb).unwrap_err())
            .starts_with("accessor 1 element 2")
    );
    // Node cycle.
    let mut d = doc.clone();
    d["nodes"][1]["children"] = json!([0]);
    assert_eq!(
        malformed_element(io::read_from_bytes(&glb(&d, &bin), Format::Glb).unwrap_err()),
        "node 0"
    );
    // Truncated GLB, missing magic, not JSON.
    let full = glb(&doc, &bin);
    for cut in [10, 30, full.len() - 4] {
        assert!(matches!(
            io::read_from_bytes(&full[..cut], Format::Glb).unwrap_err(),
            MeshError::Malformed { .. }
        ));
    }
    assert!(io::read_from_bytes(b"{\"asset\":{\"version\":\"2.0\"}}", Format::Glb).is_err());
    assert!(io::read_from_bytes(b"{ not json", Format::Gltf).is_err());
    // A valid document without any triangles: whole-mesh Empty error.
    let e = io::read_from_bytes(b"{\"asset\":{\"version\":\"2.0\"}}", Format::Gltf).unwrap_err();
    assert!(matches!(e, MeshError::InFile { .. }), "{e}");
    // NaN coordinate in the binary data.
    let mut b = bin.clone();
    b[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(io::read_from_bytes(&glb(&doc, &b), Format::Glb).is_err());
}

#[test]
fn index_types_u16_u32_and_float_colours() {
    for (ct, size) in [(5123u32, 2usize), (5125, 4)] {
        let mut bin = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        for i in [0u32, 1, 2] {
            bin.extend_from_slice(&i.to_le_bytes()[..size]);
        }
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let col_off = bin.len();
        bin.extend(f32s(&[
            1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.5, 1.0,
        ]));
        let doc = json!({
            "asset": {"version": "2.0"},
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 2}, "indices": 1}]}],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": 36},
                {"buffer": 0, "byteOffset": 36, "byteLength": 3 * size},
                {"buffer": 0, "byteOffset": col_off, "byteLength": 48}
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 1, "componentType": ct, "count": 3, "type": "SCALAR"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"}
            ]
        });
        // No scenes: every mesh, untransformed.
        let m = io::read_from_bytes(&glb(&doc, &bin), Format::Glb).unwrap();
        assert_eq!(m.mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(
            m.colors.unwrap(),
            // Linear 0.5 is sRGB 0.7354 → 188.
            vec![[255, 0, 0], [0, 255, 0], [0, 0, 188]]
        );
    }
}

#[test]
fn position_accessor_index_out_of_range_is_an_error_not_a_panic() {
    // Fuzz finding: gltf-json's validation indexed accessors[POSITION] unchecked.
    let doc =
        br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#;
    let e = io::read_from_bytes(doc, Format::Gltf).unwrap_err();
    match e {
        MeshError::Malformed { element, .. } => assert_eq!(element, "mesh 0 primitive 0"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn glb_header_lengths_are_checked() {
    // Fuzz finding: gltf's GLB parser computed `length - 12` unchecked (overflow panic).
    let mut b = b"glTF".to_vec();
    b.extend(2u32.to_le_bytes());
    b.extend(4u32.to_le_bytes());
    let e = io::read_from_bytes(&b, Format::Glb).unwrap_err();
    assert_eq!(malformed_element(e), "GLB header");
    // A chunk longer than the file, a first chunk that is not JSON, a wrong version.
    let (doc, bin) = scene(None);
    let good = glb(&doc, &bin);
    let mut bad = good.clone();
    bad[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(
        malformed_element(io::read_from_bytes(&bad, Format::Glb).unwrap_err())
            .starts_with("GLB chunk 0")
    );
    let mut bad = good.clone();
    bad[16..20].copy_from_slice(b"JSOX");
    assert!(
        malformed_element(io::read_from_bytes(&bad, Format::Glb).unwrap_err())
            .starts_with("GLB chunk 0")
    );
    let mut bad = good.clone();
    bad[4] = 1;
    assert_eq!(
        malformed_element(io::read_from_bytes(&bad, Format::Glb).unwrap_err()),
        "GLB header"
    );
    // A GLB handed to the .gltf reader is still recognised.
    check_scene(&io::read_from_bytes(&good, Format::Gltf).unwrap().mesh);
}

#[test]
fn deep_node_chain_and_child_order() {
    // 20,000 nested nodes each translating +1 in x, the mesh at the bottom: iterative traversal
    // (no stack overflow) and transforms compose down the chain.
    let (mut doc, bin) = scene(None);
    let depth = 20_000usize;
    let mut nodes: Vec<Value> = (0..depth)
        .map(|k| json!({"translation": [1.0, 0.0, 0.0], "children": [k + 1]}))
        .collect();
    nodes.push(json!({"mesh": 0}));
    doc["nodes"] = json!(nodes);
    doc["scenes"] = json!([{"nodes": [0]}]);
    let m = io::read_from_bytes(&glb(&doc, &bin), Format::Glb)
        .unwrap()
        .mesh;
    assert_eq!(m.positions[1], [depth as f64 + 1.0, 0.0, 0.0]);
    // Children are visited in order, depth first: root 0 has children [1, 2] with meshes 1, 0.
    let (mut doc, bin) = scene(None);
    doc["nodes"] =
        json!([{"children": [1, 2]}, {"mesh": 0}, {"mesh": 0, "translation": [0.0, 0.0, 7.0]}]);
    doc["scenes"] = json!([{"nodes": [0]}]);
    let m = io::read_from_bytes(&glb(&doc, &bin), Format::Glb)
        .unwrap()
        .mesh;
    assert_eq!(m.num_vertices(), 6);
    assert_eq!(m.positions[3], [0.0, 0.0, 7.0]);
}

#[test]
fn instancing_bomb_is_refused() {
    // 2,000 root nodes each instancing a mesh of 1,000 primitives over the same 4 vertices:
    // 8 M vertices from a ~100 kB file.
    let (mut doc, bin) = scene(None);
    let prims: Vec<Value> = (0..1000)
        .map(|_| json!({"attributes": {"POSITION": 2}, "mode": 5}))
        .collect();
    doc["meshes"] = json!([{"primitives": prims}]);
    doc["nodes"] = json!((0..2000).map(|_| json!({"mesh": 0})).collect::<Vec<_>>());
    doc["scenes"] = json!([{"nodes": (0..2000).collect::<Vec<_>>()}]);
    let bytes = glb(&doc, &bin);
    assert!(bytes.len() < 200_000);
    let e = io::read_from_bytes(&bytes, Format::Glb).unwrap_err();
    assert!(e.to_string().contains("instantiates more than"), "{e}");
    // The same with 20 nodes (80,000 vertices) is fine.
    doc["nodes"] = json!((0..20).map(|_| json!({"mesh": 0})).collect::<Vec<_>>());
    doc["scenes"] = json!([{"nodes": (0..20).collect::<Vec<_>>()}]);
    let m = io::read_from_bytes(&glb(&doc, &bin), Format::Glb)
        .unwrap()
        .mesh;
    assert_eq!(m.num_vertices(), 80_000);
}

/// A file with only point or line primitives says so, instead of "empty mesh".
#[test]
fn only_lines_and_points_is_named() {
    let (_, bin) = scene(None);
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let (mut doc, _) = scene(Some(&uri));
    doc["meshes"] = json!([
        {"primitives": [{"attributes": {"POSITION": 0}, "mode": 1}]},
        {"primitives": [
            {"attributes": {"POSITION": 2}, "mode": 0},
            {"attributes": {"POSITION": 2}, "mode": 1}
        ]}
    ]);
    let e = io::read_from_bytes(doc.to_string().as_bytes(), Format::Gltf).unwrap_err();
    assert!(matches!(e, MeshError::Malformed { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "<memory>: meshes: no triangle primitives: the file has only LINES/POINTS primitives \
         (mode LINES (1), POINTS (0))"
    );
}
