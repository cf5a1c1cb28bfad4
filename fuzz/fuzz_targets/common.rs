// Shared check for every reader target: parsing arbitrary bytes must return Ok or a typed
// error (never panic, hang or over-allocate), and whatever parses must survive a write → read
// round trip through every writer.

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
    for (f, enc) in [
        (Format::Off, PlyEncoding::Ascii),
        (Format::Ply, PlyEncoding::Ascii),
        (Format::Ply, PlyEncoding::BinaryLittleEndian),
    ] {
        let bytes = io::write_to_bytes(m, loaded.colors.as_deref(), f, enc).expect("writable");
        let back = io::read_from_bytes(&bytes, f).expect("own output reads back");
        assert_eq!(&back.mesh, m, "{f:?} round trip");
        assert_eq!(back.colors, loaded.colors, "{f:?} colour round trip");
    }
}
