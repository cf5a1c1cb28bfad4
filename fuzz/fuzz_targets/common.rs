// Shared check for every reader target: parsing arbitrary bytes must return Ok or a typed
// error (never panic, hang or over-allocate), and whatever parses must survive a write → read
// round trip through every writer (exactly for the text/f64 formats; for glTF, whose positions
// are f32, the topology, colours and f32-rounded positions must survive).

use symcorr_mesh::io::{self, Format, PlyEncoding};

pub fn check(data: &[u8], format: Format) {
    let Ok(loaded) = io::read_from_bytes(data, format) else {
        return;
    };
    let m = &loaded.mesh;
    let n = m.num_vertices();
    assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < n));
    assert!(m.positions.iter().flatten().all(|c| c.is_finite()));
    if let Some(c) = &loaded.colors {
        assert_eq!(c.len(), n);
    }
    let colors = loaded.colors.as_deref();
    for (f, enc) in [
        (Format::Off, PlyEncoding::Ascii),
        (Format::Obj, PlyEncoding::Ascii),
        (Format::Ply, PlyEncoding::Ascii),
        (Format::Ply, PlyEncoding::BinaryLittleEndian),
    ] {
        let bytes = io::write_to_bytes(m, colors, f, enc).expect("writable");
        let back = io::read_from_bytes(&bytes, f).expect("own output reads back");
        assert_eq!(&back.mesh, m, "{f:?} round trip");
        assert_eq!(back.colors, loaded.colors, "{f:?} colour round trip");
    }
    // f32 overflow (|x| > f32::MAX) legitimately cannot be stored in glTF.
    if m.positions.iter().flatten().all(|c| (*c as f32).is_finite()) {
        for f in [Format::Glb, Format::Gltf] {
            let bytes = io::write_to_bytes(m, colors, f, PlyEncoding::default()).expect("writable");
            let back = io::read_from_bytes(&bytes, f).expect("own glTF output reads back");
            assert_eq!(back.mesh.triangles, m.triangles, "{f:?} topology");
            assert_eq!(back.colors, loaded.colors, "{f:?} colours");
            for (a, b) in back.mesh.positions.iter().zip(&m.positions) {
                assert_eq!(a.map(|x| x as f32), b.map(|x| x as f32), "{f:?} positions");
            }
        }
    }
}
