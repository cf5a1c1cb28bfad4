//! Wavefront OBJ reader and writer, hand-written so that vertex `i` of the file stays vertex `i`
//! (tobj renumbers vertices in face order) and coordinates stay f64.
//!
//! Read: `v x y z [w]` and the common colour extension `v x y z r g b` (reals in [0, 1]; colours
//! are kept only when every vertex has them), and `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn`
//! corners, 1-based or negative (relative: `-1` is the latest vertex so far) indices; polygons
//! are fan-triangulated. Everything else (`vt`, `vn`, `g`, `o`, `s`, `usemtl`, `l`, …) is ignored.

use std::fmt::Write as _;

use super::text::{fan, parse_coord, parse_xyz, Lines};
use super::{LoadedMesh, Source};
use crate::{MeshError, TriMesh};

fn is_keyword(line: &[u8], kw: &[u8]) -> bool {
    line.starts_with(kw) && line.get(kw.len()).is_some_and(|b| b.is_ascii_whitespace())
}

pub(crate) fn read(bytes: &[u8], src: &Source) -> Result<LoadedMesh, MeshError> {
    // A first pass counts the vertices so that positive (forward) indices can be checked on
    // the line where they occur.
    let total = bytes
        .split(|&b| b == b'\n')
        .filter(|l| is_keyword(l.trim_ascii_start(), b"v"))
        .count();
    if total > u32::MAX as usize {
        return Err(src.parse_err(1, format!("{total} vertices exceed the u32 index range")));
    }
    let mut lines = Lines::new(bytes, Some(b'#'));
    let mut positions: Vec<[f64; 3]> = Vec::with_capacity(total);
    let mut colors: Vec<[u8; 3]> = Vec::new();
    let mut all_colored = true;
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut poly: Vec<u32> = Vec::new();
    while let Some(next) = lines.next_content(src) {
        let (l, text) = next?;
        let mut toks = text.split_whitespace();
        match toks.next() {
            Some("v") => {
                let t: Vec<&str> = toks.collect();
                let what = format!("vertex {}", positions.len());
                positions.push(parse_xyz(&t, src, l, &what)?);
                if all_colored && t.len() >= 6 {
                    let mut c = [0u8; 3];
                    for k in 0..3 {
                        let x = parse_coord(t[3 + k], src, l, &what)?;
                        if !(0.0..=1.0).contains(&x) {
                            return Err(src.parse_err(
                                l,
                                format!("{what}: colour component {x} is outside [0, 1]"),
                            ));
                        }
                        c[k] = (x * 255.0).round() as u8;
                    }
                    colors.push(c);
                } else {
                    all_colored = false;
                }
            }
            Some("f") => {
                poly.clear();
                let f = triangles.len();
                for corner in toks {
                    let idx = corner.split('/').next().unwrap_or_default();
                    let i: i64 = idx.parse().map_err(|_| {
                        src.parse_err(
                            l,
                            format!("face corner {corner:?} does not start with a vertex index"),
                        )
                    })?;
                    let resolved = if i > 0 {
                        (i - 1) as u64
                    } else if i < 0 {
                        let r = positions.len() as i64 + i;
                        if r < 0 {
                            return Err(src.parse_err(
                                l,
                                format!("relative index {i} reaches before the first vertex ({} defined so far)", positions.len()),
                            ));
                        }
                        r as u64
                    } else {
                        return Err(src.parse_err(l, "vertex index 0 (OBJ indices start at 1)"));
                    };
                    if resolved >= total as u64 {
                        return Err(src.parse_err(
                            l,
                            format!("face refers to vertex {i}, but the file has {total} vertices"),
                        ));
                    }
                    poly.push(resolved as u32); // < total ≤ u32::MAX, checked above
                }
                if poly.len() < 3 {
                    return Err(src.parse_err(
                        l,
                        format!(
                            "face (triangle {f}) has {} vertices; at least 3 are needed",
                            poly.len()
                        ),
                    ));
                }
                fan(&poly, &mut triangles);
            }
            _ => {}
        }
    }
    let colors = (all_colored && !colors.is_empty()).then_some(colors);
    src.finish(positions, triangles, colors)
}

pub(crate) fn write(mesh: &TriMesh, colors: Option<&[[u8; 3]]>) -> Vec<u8> {
    let mut s = String::with_capacity(40 * mesh.num_vertices() + 24 * mesh.num_triangles() + 64);
    s.push_str("# written by symcorr-mesh\n");
    for (v, p) in mesh.positions.iter().enumerate() {
        // `{}` on f64 is the shortest exact round-trip representation.
        let _ = write!(s, "v {} {} {}", p[0], p[1], p[2]);
        if let Some(c) = colors.and_then(|c| c.get(v)) {
            let _ = write!(
                s,
                " {} {} {}",
                c[0] as f64 / 255.0,
                c[1] as f64 / 255.0,
                c[2] as f64 / 255.0
            );
        }
        s.push('\n');
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s.into_bytes()
}
