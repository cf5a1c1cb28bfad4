//! OFF (Object File Format) reader and writer.
//!
//! Header keyword `[ST][C][N]OFF` (texture coordinates and normals are skipped, `C` colours kept);
//! the counts `vertices faces [edges]` may follow the keyword on the same line; `#` starts a
//! comment anywhere. One vertex per line, one face per line (`n i0 … i(n-1) [colour]`), faces
//! with more than three vertices are fan-triangulated. Binary OFF and 4D/nD OFF are rejected.

use std::fmt::Write as _;

use super::text::{capped_capacity, fan, parse_color, parse_usize, parse_xyz, Lines};
use super::{LoadedMesh, Source};
use crate::{MeshError, TriMesh};

pub(crate) fn read(bytes: &[u8], src: &Source) -> Result<LoadedMesh, MeshError> {
    let mut lines = Lines::new(bytes, Some(b'#'));
    let (line, header) = lines
        .next_content(src)
        .ok_or_else(|| src.parse_err(1, "empty file: expected an OFF header"))??;
    let mut toks = header.split_whitespace();
    let keyword = toks.next().unwrap_or_default();
    let Some(prefix) = keyword.strip_suffix("OFF") else {
        return Err(src.parse_err(line, format!("expected an OFF header, found {keyword:?}")));
    };
    let (mut has_st, mut has_c, mut has_n) = (false, false, false);
    for ch in prefix.chars() {
        match ch {
            'S' | 'T' => has_st = true,
            'C' => has_c = true,
            'N' => has_n = true,
            _ => {
                return Err(src.parse_err(
                    line,
                    format!("unsupported OFF variant {keyword:?} (only [ST][C][N]OFF)"),
                ))
            }
        }
    }
    let rest: Vec<&str> = toks.collect();
    if rest.first() == Some(&"BINARY") {
        return Err(src.parse_err(line, "binary OFF is not supported"));
    }
    let (count_line, counts) = if rest.is_empty() {
        let (l, text) = lines
            .next_content(src)
            .ok_or_else(|| src.parse_err(line + 1, "missing vertex/face counts"))??;
        (l, text.split_whitespace().collect::<Vec<_>>())
    } else {
        (line, rest)
    };
    if counts.len() < 2 || counts.len() > 3 {
        return Err(src.parse_err(
            count_line,
            format!(
                "expected `vertices faces [edges]`, found {} values",
                counts.len()
            ),
        ));
    }
    let nv = parse_usize(counts[0], src, count_line, "vertex count")?;
    let nf = parse_usize(counts[1], src, count_line, "face count")?;
    if let Some(e) = counts.get(2) {
        parse_usize(e, src, count_line, "edge count")?;
    }
    if nv > u32::MAX as usize {
        return Err(src.parse_err(
            count_line,
            format!("{nv} vertices exceed the u32 index range"),
        ));
    }

    let left = lines.remaining().len();
    let mut positions = Vec::with_capacity(capped_capacity(nv, left, 6));
    let mut colors = has_c.then(|| Vec::with_capacity(capped_capacity(nv, left, 6)));
    for v in 0..nv {
        let (l, text) = lines.next_content(src).ok_or_else(|| {
            src.parse_err(
                lines.line() + 1,
                format!("file ends after {v} of {nv} vertices"),
            )
        })??;
        let t: Vec<&str> = text.split_whitespace().collect();
        positions.push(parse_xyz(&t, src, l, &format!("vertex {v}"))?);
        if let Some(colors) = colors.as_mut() {
            let start = 3 + if has_n { 3 } else { 0 };
            let end = t.len().saturating_sub(if has_st { 2 } else { 0 });
            let n = end.saturating_sub(start);
            if n != 3 && n != 4 {
                return Err(src.parse_err(
                    l,
                    format!("vertex {v}: expected an RGB or RGBA colour after the coordinates, found {n} values"),
                ));
            }
            colors.push([
                parse_color(t[start], src, l)?,
                parse_color(t[start + 1], src, l)?,
                parse_color(t[start + 2], src, l)?,
            ]);
        }
    }

    let left = lines.remaining().len();
    let mut triangles = Vec::with_capacity(capped_capacity(nf, left, 8));
    let mut poly: Vec<u32> = Vec::new();
    for f in 0..nf {
        let (l, text) = lines.next_content(src).ok_or_else(|| {
            src.parse_err(
                lines.line() + 1,
                format!("file ends after {f} of {nf} faces"),
            )
        })??;
        let mut t = text.split_whitespace();
        let what = format!("face {f}");
        let n = parse_usize(t.next().unwrap_or_default(), src, l, &what)?;
        if n < 3 {
            return Err(src.parse_err(
                l,
                format!("face {f} has {n} vertices; at least 3 are needed"),
            ));
        }
        poly.clear();
        for k in 0..n {
            let tok = t.next().ok_or_else(|| {
                src.parse_err(l, format!("face {f} declares {n} vertices but lists {k}"))
            })?;
            let i = parse_usize(tok, src, l, &what)?;
            if i >= nv {
                return Err(src.parse_err(
                    l,
                    format!("face {f} refers to vertex {i}, but the file has {nv} vertices"),
                ));
            }
            poly.push(i as u32); // i < nv ≤ u32::MAX, checked above
        }
        fan(&poly, &mut triangles);
    }
    src.finish(positions, triangles, colors)
}

pub(crate) fn write(mesh: &TriMesh, colors: Option<&[[u8; 3]]>) -> Vec<u8> {
    let mut s = String::with_capacity(32 * (mesh.num_vertices() + mesh.num_triangles()) + 64);
    s.push_str(if colors.is_some() { "COFF\n" } else { "OFF\n" });
    // `{}` on f64 prints the shortest string that parses back to the same value: exact round trip.
    let _ = writeln!(s, "{} {} 0", mesh.num_vertices(), mesh.num_triangles());
    for (v, p) in mesh.positions.iter().enumerate() {
        let _ = write!(s, "{} {} {}", p[0], p[1], p[2]);
        if let Some(c) = colors.and_then(|c| c.get(v)) {
            let _ = write!(s, " {} {} {} 255", c[0], c[1], c[2]);
        }
        s.push('\n');
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s.into_bytes()
}
