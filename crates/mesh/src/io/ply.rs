//! PLY reader (ascii, binary little- and big-endian) and writer (binary little-endian, ascii).
//!
//! A small hand-written parser rather than ply-rs-bw: the reader needs only `x y z`, optional
//! `red green blue` and one index list, and owning the parser lets every count and list length
//! be checked against the bytes actually present before anything is allocated (a lying header
//! cannot exhaust memory), and every error name the line (ascii) or the element (binary).
//!
//! Accepted: properties in any order and of any scalar type (`char/int8 … double/float64`);
//! extra properties and extra elements are skipped; the face list may be called
//! `vertex_indices` or `vertex_index`, with any integer count and index type, and polygons of any
//! size are fan-triangulated. Vertex colours `red green blue` (or `diffuse_red …`) are kept (uchar as is; float/double
//! in [0, 1] scaled by 255; other integers must be in 0..=255). In ascii, every element is one
//! line (blank lines between elements are skipped): a line with more or fewer values than the
//! element's properties take is an error naming the element and the line, so a stray value is
//! blamed on its own line rather than on whatever element would have read it next.

use std::fmt::Write as _;

use super::text::{capped_capacity, fan};
use super::{LoadedMesh, PlyEncoding, Source};
use crate::{MeshError, TriMesh};

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// What the reader does with a property.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    Coord(usize),
    Color(usize),
    Indices,
    Ignore,
}

#[derive(Debug, Clone)]
enum Property {
    Scalar(Scalar, Role),
    List {
        count: Scalar,
        item: Scalar,
        role: Role,
    },
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Number of header lines (so ascii body lines continue the count).
    lines: usize,
}

fn parse_header(bytes: &[u8], src: &Source) -> Result<Header, MeshError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(src.parse_err(
                line_no + 1,
                "file ends inside the PLY header (no end_header)",
            ));
        }
        line_no += 1;
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |p| pos + p);
        let raw = &bytes[pos..end];
        pos = (end + 1).min(bytes.len());
        let line = std::str::from_utf8(raw)
            .map_err(|_| src.parse_err(line_no, "PLY header line is not valid UTF-8"))?
            .trim();
        if line_no == 1 {
            if line != "ply" {
                return Err(
                    src.parse_err(1, format!("expected the magic line `ply`, found {line:?}"))
                );
            }
            continue;
        }
        let toks: Vec<&str> = line.split_whitespace().collect();
        match toks.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if toks.len() != 3 {
                    return Err(src.parse_err(line_no, "expected `format ENCODING 1.0`"));
                }
                encoding = Some(match toks[1] {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big_endian: false },
                    "binary_big_endian" => Encoding::Binary { big_endian: true },
                    other => {
                        return Err(src.parse_err(line_no, format!("unknown PLY format {other:?}")))
                    }
                });
                if toks[2] != "1.0" {
                    return Err(src.parse_err(
                        line_no,
                        format!("unsupported PLY version {:?} (expected 1.0)", toks[2]),
                    ));
                }
            }
            Some("element") => {
                if toks.len() != 3 {
                    return Err(src.parse_err(line_no, "expected `element NAME COUNT`"));
                }
                let count = toks[2].parse::<usize>().map_err(|_| {
                    src.parse_err(
                        line_no,
                        format!("element count {:?} is not a non-negative integer", toks[2]),
                    )
                })?;
                if elements.iter().any(|e| e.name == toks[1]) {
                    return Err(
                        src.parse_err(line_no, format!("element {:?} declared twice", toks[1]))
                    );
                }
                elements.push(Element {
                    name: toks[1].to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let Some(el) = elements.last_mut() else {
                    return Err(src.parse_err(line_no, "property before any element"));
                };
                let ty = |s: &str| {
                    Scalar::parse(s).ok_or_else(|| {
                        src.parse_err(line_no, format!("unknown property type {s:?}"))
                    })
                };
                let is_vertex = el.name == "vertex";
                let is_face = el.name == "face";
                if toks.get(1) == Some(&"list") {
                    if toks.len() != 5 {
                        return Err(src.parse_err(
                            line_no,
                            "expected `property list COUNT_TYPE ITEM_TYPE NAME`",
                        ));
                    }
                    let (count, item) = (ty(toks[2])?, ty(toks[3])?);
                    if count.is_float() {
                        return Err(
                            src.parse_err(line_no, "a list count type must be an integer type")
                        );
                    }
                    let wants_indices = is_face
                        && matches!(toks[4], "vertex_indices" | "vertex_index")
                        && !el.props.iter().any(|p| {
                            matches!(
                                p,
                                Property::List {
                                    role: Role::Indices,
                                    ..
                                }
                            )
                        });
                    if wants_indices && item.is_float() {
                        return Err(
                            src.parse_err(line_no, "face vertex indices must have an integer type")
                        );
                    }
                    let role = if wants_indices {
                        Role::Indices
                    } else {
                        Role::Ignore
                    };
                    el.props.push(Property::List { count, item, role });
                } else {
                    if toks.len() != 3 {
                        return Err(src.parse_err(line_no, "expected `property TYPE NAME`"));
                    }
                    let t = ty(toks[1])?;
                    let mut role = match (is_vertex, toks[2]) {
                        (true, "x") => Role::Coord(0),
                        (true, "y") => Role::Coord(1),
                        (true, "z") => Role::Coord(2),
                        (true, "red" | "diffuse_red") => Role::Color(0),
                        (true, "green" | "diffuse_green") => Role::Color(1),
                        (true, "blue" | "diffuse_blue") => Role::Color(2),
                        _ => Role::Ignore,
                    };
                    if role != Role::Ignore
                        && el
                            .props
                            .iter()
                            .any(|p| matches!(p, Property::Scalar(_, r) if *r == role))
                    {
                        role = Role::Ignore; // a repeated name: the first one counts
                    }
                    el.props.push(Property::Scalar(t, role));
                }
            }
            Some("end_header") => {
                let encoding = encoding
                    .ok_or_else(|| src.parse_err(line_no, "end_header before any `format` line"))?;
                return Ok(Header {
                    encoding,
                    elements,
                    body: pos,
                    lines: line_no,
                });
            }
            Some(other) => {
                return Err(
                    src.parse_err(line_no, format!("unexpected PLY header keyword {other:?}"))
                )
            }
        }
    }
}

/// A source of property values: ascii tokens or binary bytes.
trait Body {
    /// Reads a scalar as f64 (every PLY scalar type converts exactly).
    fn real(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> Result<f64, MeshError>;
    /// Reads an integer-typed scalar.
    fn int(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> Result<i64, MeshError>;
    /// Bytes left (binary) or an upper bound on the tokens left (ascii).
    fn left(&self) -> usize;
    /// Minimum encoded size of one value of this type (for capacity and list-length checks).
    fn min_size(&self, ty: Scalar) -> usize;
    fn err(&self, what: &str, msg: &str) -> MeshError;
    /// Starts an element with `props` properties (`lists`: some are lists). Ascii: an element
    /// is one line, so its values are read from the next non-blank line only.
    fn begin_element(&mut self, _props: usize, _lists: bool) {}
    /// Ends the element named `what`. Ascii: its line must hold no further values.
    fn end_element(&mut self, _what: &str) -> Result<(), MeshError> {
        Ok(())
    }
}

struct Binary<'a, 's> {
    bytes: &'a [u8],
    pos: usize,
    big_endian: bool,
    src: &'s Source,
    offset: usize,
}

impl Binary<'_, '_> {
    fn take<const N: usize>(&mut self, what: &dyn Fn() -> String) -> Result<[u8; N], MeshError> {
        let end = self.pos + N;
        let Some(slice) = self.bytes.get(self.pos..end) else {
            return Err(self.err(&what(), "file is truncated"));
        };
        self.pos = end;
        let mut a = [0u8; N];
        a.copy_from_slice(slice);
        if self.big_endian {
            a.reverse();
        }
        Ok(a)
    }
}

impl Body for Binary<'_, '_> {
    fn real(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> Result<f64, MeshError> {
        Ok(match ty {
            Scalar::F32 => f32::from_le_bytes(self.take(what)?) as f64,
            Scalar::F64 => f64::from_le_bytes(self.take(what)?),
            _ => self.int(ty, what)? as f64,
        })
    }

    fn int(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> Result<i64, MeshError> {
        Ok(match ty {
            Scalar::I8 => i8::from_le_bytes(self.take(what)?) as i64,
            Scalar::U8 => u8::from_le_bytes(self.take(what)?) as i64,
            Scalar::I16 => i16::from_le_bytes(self.take(what)?) as i64,
            Scalar::U16 => u16::from_le_bytes(self.take(what)?) as i64,
            Scalar::I32 => i32::from_le_bytes(self.take(what)?) as i64,
            Scalar::U32 => u32::from_le_bytes(self.take(what)?) as i64,
            Scalar::F32 | Scalar::F64 => {
                return Err(self.err(&what(), "expected an integer type"));
            }
        })
    }

    fn left(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn min_size(&self, ty: Scalar) -> usize {
        ty.size()
    }

    fn err(&self, what: &str, msg: &str) -> MeshError {
        self.src
            .malformed(format!("{what} (byte {})", self.offset + self.pos), msg)
    }
}

struct Ascii<'a, 's> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    src: &'s Source,
    /// The element being read: its property count, whether it has lists, values read so far.
    element: Option<(usize, bool)>,
    values: usize,
}

impl<'a> Ascii<'a, '_> {
    /// Skips spaces and tabs (and `\r`), and newlines too when `newlines`.
    fn skip_space(&mut self, newlines: bool) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() || (b == b'\n' && !newlines) {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// The message for an element line with `found` values where its properties take `read`.
    fn count_message(&self, found: usize, read: usize) -> String {
        match self.element {
            Some((props, false)) => {
                format!("has {found} values, the header declares {props} properties")
            }
            Some((props, true)) if found < read => format!(
                "the line ends after {found} values, before its {props} properties (with their list items) are read"
            ),
            Some((props, true)) => format!(
                "has {found} values, but its {props} properties with their list items take {read}"
            ),
            None => format!("has {found} values"),
        }
    }

    fn token(&mut self, what: &dyn Fn() -> String) -> Result<&'a str, MeshError> {
        let in_element = self.element.is_some();
        self.skip_space(!in_element);
        if in_element && self.bytes.get(self.pos).is_none_or(|&b| b == b'\n') {
            let msg = self.count_message(self.values, self.values + 1);
            return Err(self.err(&what(), &msg));
        }
        self.values += 1;
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.err(&what(), "file ends early"));
        }
        std::str::from_utf8(&self.bytes[start..self.pos])
            .map_err(|_| self.err(&what(), "value is not valid UTF-8"))
    }
}

impl Body for Ascii<'_, '_> {
    fn real(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> Result<f64, MeshError> {
        if !ty.is_float() {
            return Ok(self.int(ty, what)? as f64);
        }
        let tok = self.token(what)?;
        tok.parse::<f64>()
            .map_err(|_| self.err(&what(), &format!("{tok:?} is not a number")))
    }

    fn int(&mut self, _ty: Scalar, what: &dyn Fn() -> String) -> Result<i64, MeshError> {
        let tok = self.token(what)?;
        tok.parse::<i64>()
            .map_err(|_| self.err(&what(), &format!("{tok:?} is not an integer")))
    }

    fn left(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn min_size(&self, _ty: Scalar) -> usize {
        1 // at least one digit (separators are not counted: the last value may end the file)
    }

    fn err(&self, what: &str, msg: &str) -> MeshError {
        self.src.parse_err(self.line, format!("{what}: {msg}"))
    }

    fn begin_element(&mut self, props: usize, lists: bool) {
        self.skip_space(true);
        self.element = Some((props, lists));
        self.values = 0;
    }

    fn end_element(&mut self, what: &str) -> Result<(), MeshError> {
        let read = self.values;
        let mut extra = 0;
        loop {
            self.skip_space(false);
            if self.bytes.get(self.pos).is_none_or(|&b| b == b'\n') {
                break;
            }
            extra += 1;
            while self
                .bytes
                .get(self.pos)
                .is_some_and(|b| !b.is_ascii_whitespace())
            {
                self.pos += 1;
            }
        }
        if extra > 0 {
            let msg = self.count_message(read + extra, read);
            return Err(self.err(what, &msg));
        }
        self.element = None;
        Ok(())
    }
}

pub(crate) fn read(bytes: &[u8], src: &Source) -> Result<LoadedMesh, MeshError> {
    let header = parse_header(bytes, src)?;
    let body_bytes = &bytes[header.body..];
    match header.encoding {
        Encoding::Ascii => {
            let mut body = Ascii {
                bytes: body_bytes,
                pos: 0,
                line: header.lines + 1,
                src,
                element: None,
                values: 0,
            };
            read_body(&header, &mut body, src)
        }
        Encoding::Binary { big_endian } => {
            let mut body = Binary {
                bytes: body_bytes,
                pos: 0,
                big_endian,
                src,
                offset: header.body,
            };
            read_body(&header, &mut body, src)
        }
    }
}

fn read_body(header: &Header, body: &mut dyn Body, src: &Source) -> Result<LoadedMesh, MeshError> {
    let vertex = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .ok_or_else(|| src.malformed("header", "no `vertex` element"))?;
    for axis in 0..3 {
        if !vertex
            .props
            .iter()
            .any(|p| matches!(p, Property::Scalar(_, Role::Coord(a)) if *a == axis))
        {
            return Err(src.malformed(
                "header",
                format!("vertex element has no `{}` property", ["x", "y", "z"][axis]),
            ));
        }
    }
    let has_color = (0..3).all(|c| {
        vertex
            .props
            .iter()
            .any(|p| matches!(p, Property::Scalar(_, Role::Color(k)) if *k == c))
    });
    let nv = vertex.count;
    if nv > u32::MAX as usize {
        return Err(src.malformed(
            "header",
            format!("{nv} vertices exceed the u32 index range"),
        ));
    }
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut colors: Vec<[u8; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut poly: Vec<u32> = Vec::new();

    for el in &header.elements {
        if el.props.is_empty() {
            continue; // zero bytes per element: nothing to read
        }
        let min_size: usize = el
            .props
            .iter()
            .map(|p| match p {
                Property::Scalar(t, _) => body.min_size(*t),
                Property::List { count, .. } => body.min_size(*count),
            })
            .sum::<usize>()
            .max(1);
        if el.count > body.left() / min_size {
            return Err(src.malformed(
                format!("element {}", el.name),
                format!(
                    "header declares {} elements, but the file is too short to hold them",
                    el.count
                ),
            ));
        }
        let is_vertex = el.name == "vertex";
        if is_vertex {
            positions.reserve(capped_capacity(el.count, body.left(), min_size));
            if has_color {
                colors.reserve(capped_capacity(el.count, body.left(), min_size));
            }
        }
        let has_lists = el.props.iter().any(|p| matches!(p, Property::List { .. }));
        for i in 0..el.count {
            let what = || format!("{} {i}", el.name);
            body.begin_element(el.props.len(), has_lists);
            let mut p = [0.0; 3];
            let mut c = [0u8; 3];
            let mut has_indices = false;
            for prop in &el.props {
                match *prop {
                    Property::Scalar(ty, role) => {
                        let v = body.real(ty, &what)?;
                        match role {
                            Role::Coord(a) => {
                                if !v.is_finite() {
                                    return Err(body.err(&what(), "non-finite coordinate"));
                                }
                                p[a] = v;
                            }
                            Role::Color(k) if has_color => {
                                c[k] = color_component(v, ty).ok_or_else(|| {
                                    body.err(&what(), &format!("colour component {v} out of range"))
                                })?;
                            }
                            _ => {}
                        }
                    }
                    Property::List { count, item, role } => {
                        let n = body.int(count, &what)?;
                        let n = usize::try_from(n)
                            .map_err(|_| body.err(&what(), &format!("negative list length {n}")))?;
                        if n > body.left() / body.min_size(item) {
                            return Err(body.err(
                                &what(),
                                &format!("list of {n} items runs past the end of the file"),
                            ));
                        }
                        if role == Role::Indices && !has_indices {
                            has_indices = true;
                            poly.clear();
                            for _ in 0..n {
                                let idx = body.int(item, &what)?;
                                if idx < 0 || idx as u64 >= nv as u64 {
                                    return Err(body.err(
                                        &what(),
                                        &format!("refers to vertex {idx}, but the file has {nv} vertices"),
                                    ));
                                }
                                poly.push(idx as u32); // 0 ≤ idx < nv ≤ u32::MAX, checked above
                            }
                            if n < 3 {
                                return Err(body.err(
                                    &what(),
                                    &format!("face has {n} vertices; at least 3 are needed"),
                                ));
                            }
                            fan(&poly, &mut triangles);
                        } else {
                            for _ in 0..n {
                                body.real(item, &what)?;
                            }
                        }
                    }
                }
            }
            body.end_element(&what())?;
            if is_vertex {
                positions.push(p);
                if has_color {
                    colors.push(c);
                }
            }
        }
    }
    src.finish(positions, triangles, has_color.then_some(colors))
}

fn color_component(v: f64, ty: Scalar) -> Option<u8> {
    if ty.is_float() {
        (0.0..=1.0).contains(&v).then(|| (v * 255.0).round() as u8)
    } else if (0.0..=255.0).contains(&v) {
        Some(v as u8)
    } else {
        None
    }
}

pub(crate) fn write(mesh: &TriMesh, colors: Option<&[[u8; 3]]>, encoding: PlyEncoding) -> Vec<u8> {
    let mut h = String::new();
    let fmt = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
    };
    let _ = write!(
        h,
        "ply\nformat {fmt} 1.0\ncomment written by symcorr-mesh\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\n",
        mesh.num_vertices()
    );
    if colors.is_some() {
        h.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    let _ = write!(
        h,
        "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.num_triangles()
    );
    let mut out = h.into_bytes();
    match encoding {
        PlyEncoding::BinaryLittleEndian => {
            out.reserve(mesh.num_vertices() * 27 + mesh.num_triangles() * 13);
            for (v, p) in mesh.positions.iter().enumerate() {
                for c in p {
                    out.extend_from_slice(&c.to_le_bytes());
                }
                if let Some(c) = colors.and_then(|c| c.get(v)) {
                    out.extend_from_slice(c);
                }
            }
            for t in &mesh.triangles {
                out.push(3);
                for i in t {
                    out.extend_from_slice(&i.to_le_bytes());
                }
            }
        }
        PlyEncoding::Ascii => {
            let mut s = String::with_capacity(mesh.num_vertices() * 40 + mesh.num_triangles() * 20);
            for (v, p) in mesh.positions.iter().enumerate() {
                // `{}` on f64 is the shortest exact round-trip representation.
                let _ = write!(s, "{} {} {}", p[0], p[1], p[2]);
                if let Some(c) = colors.and_then(|c| c.get(v)) {
                    let _ = write!(s, " {} {} {}", c[0], c[1], c[2]);
                }
                s.push('\n');
            }
            for t in &mesh.triangles {
                let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
            }
            out.extend_from_slice(s.as_bytes());
        }
    }
    out
}
