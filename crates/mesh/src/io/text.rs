//! Shared helpers for the line-based text formats (OFF, OBJ, ascii PLY).

use super::Source;
use crate::MeshError;

/// Iterates over the lines of `bytes` as `(1-based line number, text)`, with everything from
/// `comment` on removed (when given) and surrounding whitespace trimmed. Lines that are not
/// UTF-8 (after comment removal) are an error naming the line.
pub(crate) struct Lines<'a> {
    rest: &'a [u8],
    line: usize,
    comment: Option<u8>,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(bytes: &'a [u8], comment: Option<u8>) -> Self {
        Lines {
            rest: bytes,
            line: 0,
            comment,
        }
    }

    /// The next line, or `None` at the end of input.
    pub(crate) fn next_line(
        &mut self,
        src: &Source,
    ) -> Option<Result<(usize, &'a str), MeshError>> {
        if self.rest.is_empty() {
            return None;
        }
        self.line += 1;
        let end = self
            .rest
            .iter()
            .position(|&b| b == b'\n')
            .unwrap_or(self.rest.len());
        let mut raw = &self.rest[..end];
        self.rest = if end < self.rest.len() {
            &self.rest[end + 1..]
        } else {
            &[]
        };
        if let Some(c) = self.comment {
            if let Some(p) = raw.iter().position(|&b| b == c) {
                raw = &raw[..p];
            }
        }
        Some(match std::str::from_utf8(raw) {
            Ok(s) => Ok((self.line, s.trim())),
            Err(_) => Err(src.parse_err(self.line, "line is not valid UTF-8")),
        })
    }

    /// The next line that is not empty after comment removal.
    pub(crate) fn next_content(
        &mut self,
        src: &Source,
    ) -> Option<Result<(usize, &'a str), MeshError>> {
        loop {
            match self.next_line(src)? {
                Ok((_, "")) => continue,
                other => return Some(other),
            }
        }
    }

    /// The remaining, not yet consumed bytes.
    pub(crate) fn remaining(&self) -> &'a [u8] {
        self.rest
    }

    /// Number of lines consumed so far.
    pub(crate) fn line(&self) -> usize {
        self.line
    }
}

/// Parses a finite f64 coordinate.
pub(crate) fn parse_coord(
    tok: &str,
    src: &Source,
    line: usize,
    what: &str,
) -> Result<f64, MeshError> {
    let v: f64 = tok
        .parse()
        .map_err(|_| src.parse_err(line, format!("{what}: {tok:?} is not a number")))?;
    if !v.is_finite() {
        return Err(src.parse_err(line, format!("{what}: non-finite coordinate {tok:?}")));
    }
    Ok(v)
}

/// Parses the `x y z` in the first three of a vertex line's tokens (more may follow); `what`
/// names the vertex in errors (`vertex 12`).
pub(crate) fn parse_xyz(
    toks: &[&str],
    src: &Source,
    line: usize,
    what: &str,
) -> Result<[f64; 3], MeshError> {
    if toks.len() < 3 {
        return Err(src.parse_err(
            line,
            format!("{what}: expected x y z, found {} values", toks.len()),
        ));
    }
    Ok([
        parse_coord(toks[0], src, line, what)?,
        parse_coord(toks[1], src, line, what)?,
        parse_coord(toks[2], src, line, what)?,
    ])
}

/// Parses a non-negative integer count or index.
pub(crate) fn parse_usize(
    tok: &str,
    src: &Source,
    line: usize,
    what: &str,
) -> Result<usize, MeshError> {
    tok.parse::<usize>().map_err(|_| {
        src.parse_err(
            line,
            format!("{what}: {tok:?} is not a non-negative integer"),
        )
    })
}

/// Parses a colour component: an integer in 0..=255, or a real number in [0, 1] (scaled by 255).
pub(crate) fn parse_color(tok: &str, src: &Source, line: usize) -> Result<u8, MeshError> {
    if let Ok(i) = tok.parse::<i64>() {
        return u8::try_from(i)
            .map_err(|_| src.parse_err(line, format!("colour component {i} is outside 0..=255")));
    }
    let v: f64 = tok
        .parse()
        .map_err(|_| src.parse_err(line, format!("colour component {tok:?} is not a number")))?;
    if !(0.0..=1.0).contains(&v) {
        return Err(src.parse_err(
            line,
            format!("real colour component {tok:?} is outside [0, 1]"),
        ));
    }
    Ok((v * 255.0).round() as u8)
}

/// Capacity to reserve for a declared element count: never more than the input could hold
/// (`bytes_left / min_bytes_per_element`), so a lying header cannot exhaust memory.
pub(crate) fn capped_capacity(
    declared: usize,
    bytes_left: usize,
    min_bytes_per_element: usize,
) -> usize {
    declared.min(bytes_left / min_bytes_per_element.max(1))
}

/// Appends the fan triangulation `(v0, v_k, v_k+1)` of a polygon.
pub(crate) fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[k], poly[k + 1]]);
    }
}
