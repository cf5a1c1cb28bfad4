//! glTF 2.0 (`.gltf` with embedded base64 or external buffers) and GLB reader and writer.
//!
//! Reading uses the `gltf` crate (1.x) for the validated document structure only; buffers are
//! resolved here (GLB blob, `data:` URIs, files next to the `.gltf`) and accessor bytes are read
//! here with checked offsets, so a malformed file is an error naming the accessor rather than a
//! panic. Every triangle primitive (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`) of every mesh
//! instance in the default scene (else scene 0; without scenes: every mesh, untransformed) is
//! read with its node's world transform applied; vertices of the primitives are concatenated
//! in traversal order (scene roots in order, depth first, primitives in order). A node transform
//! with negative determinant flips the triangles' winding (as the glTF spec requires). Colours
//! (`COLOR_0`, float or normalized integer, RGB or RGBA) are kept when every primitive has them.
//!
//! Writing produces one mesh with one primitive: `POSITION` (f32, with min/max), `NORMAL`
//! (area-weighted, f32), optional `COLOR_0` (f32 RGB), u32 indices, and a plain double-sided
//! material. Colours: symcorr's per-vertex colours are sRGB bytes (as PLY stores them and
//! viewers show them), while glTF's `COLOR_0` is **linear** (glTF 2.0 §3.7.2.1), so the writer
//! converts sRGB → linear and the reader linear → sRGB (IEC 61966-2-1 transfer function). The
//! linear values are stored as f32, not as normalised bytes, so that a write → read round trip
//! gives the same bytes back (8-bit linear would merge dark shades). Positions are f32 in glTF: a write → read round trip is exact only
//! for coordinates representable in f32.
//!
//! Public here: [`MorphAnimationWriter`], an animated GLB of a mesh moving through frames
//! (morph targets and an animation of their weights), written frame by frame; the plain
//! readers and writers are reached through [`crate::io::read`] and [`crate::io::write`].

use std::borrow::Cow;
use std::io::Read as _;
use std::path::{Component, Path, PathBuf};

use base64::Engine as _;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::Semantic;
use nalgebra::{Matrix4, Vector3};
use serde_json::json;

mod morph;

pub use morph::{MorphAnimationWriter, MorphInterpolation};

use super::{LoadedMesh, Source};
use crate::{MeshError, TriMesh};

/// A node transform; glTF stores it column-major, which is also nalgebra's layout.
type Mat4 = Matrix4<f64>;

/// The affine part of `m` applied to `p` (a glTF node matrix's last row is `0 0 0 1`; it is
/// not used, so a malformed one cannot divide the point).
fn apply(m: &Mat4, p: [f64; 3]) -> [f64; 3] {
    let p = m.fixed_view::<3, 3>(0, 0) * Vector3::from(p) + m.fixed_view::<3, 1>(0, 3);
    p.into()
}

/// Determinant of the linear part: negative for a mirroring transform.
fn det3(m: &Mat4) -> f64 {
    m.fixed_view::<3, 3>(0, 0).determinant()
}

pub(crate) fn read(bytes: &[u8], src: &Source, expect_glb: bool) -> Result<LoadedMesh, MeshError> {
    if expect_glb && !bytes.starts_with(b"glTF") {
        return Err(src.malformed("header", "not a GLB file (missing the `glTF` magic)"));
    }
    // The GLB container is split here (gltf 1.4.1's GLB parser underflows on a header length
    // below 12 — a fuzz finding); the JSON goes to gltf-json, then our own validation pass.
    let (json, blob) = if bytes.starts_with(b"glTF") {
        split_glb(bytes, src)?
    } else {
        (bytes, None)
    };
    let root =
        gltf::json::Root::from_slice(json).map_err(|e| src.malformed("JSON", e.to_string()))?;
    let doc = &gltf::Document::from_json_without_validation(root);
    validate(doc, src)?;

    // External buffers share the input size limit with the file itself.
    let mut budget = src.max_input_bytes.saturating_sub(bytes.len() as u64);
    let mut buffers: Vec<Cow<[u8]>> = Vec::new();
    for b in doc.buffers() {
        let what = || format!("buffer {}", b.index());
        let data: Cow<[u8]> = match b.source() {
            gltf::buffer::Source::Bin => match blob {
                Some(blob) => Cow::Borrowed(blob),
                None => {
                    return Err(
                        src.malformed(what(), "refers to the GLB binary chunk, but there is none")
                    )
                }
            },
            gltf::buffer::Source::Uri(uri) => {
                Cow::Owned(load_uri(uri, b.length(), &mut budget, src, &what())?)
            }
        };
        if data.len() < b.length() {
            return Err(src.malformed(
                what(),
                format!("declares {} bytes but holds {}", b.length(), data.len()),
            ));
        }
        buffers.push(data);
    }

    let input_bytes = bytes.len() + buffers.iter().map(|b| b.len()).sum::<usize>();
    let mut out = Output {
        limit: instance_limit(input_bytes),
        ..Output::default()
    };
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    match scene {
        Some(scene) => {
            let mut seen = vec![false; doc.nodes().len()];
            for node in scene.nodes() {
                visit(node, &mut seen, &buffers, src, &mut out)?;
            }
        }
        None => {
            for mesh in doc.meshes() {
                add_mesh(&mesh, &Mat4::identity(), &buffers, src, &mut out)?;
            }
        }
    }
    if out.primitives == 0 && !out.skipped_modes.is_empty() {
        return Err(src.malformed(
            "meshes",
            format!(
                "no triangle primitives: the file has only LINES/POINTS primitives (mode {})",
                out.skipped_modes.join(", ")
            ),
        ));
    }
    let colors = (out.all_colored && !out.colors.is_empty()).then_some(out.colors);
    src.finish(out.positions, out.triangles, colors)
}

fn le32(b: &[u8], at: usize) -> Option<usize> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize)
}

/// Splits a GLB file into its JSON chunk and optional BIN chunk, checking every length.
fn split_glb<'a>(bytes: &'a [u8], src: &Source) -> Result<(&'a [u8], Option<&'a [u8]>), MeshError> {
    let short = |what: &str| src.malformed("GLB header", format!("file too short for {what}"));
    let version = le32(bytes, 4).ok_or_else(|| short("the version"))?;
    if version != 2 {
        return Err(src.malformed(
            "GLB header",
            format!("unsupported GLB version {version} (expected 2)"),
        ));
    }
    let length = le32(bytes, 8).ok_or_else(|| short("the length"))?;
    if length < 12 || length > bytes.len() {
        return Err(src.malformed(
            "GLB header",
            format!(
                "declared length {length}, but the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    let data = &bytes[..length];
    let mut pos = 12;
    let mut json: Option<&[u8]> = None;
    let mut bin: Option<&[u8]> = None;
    let mut index = 0;
    while pos < data.len() {
        let what = format!("GLB chunk {index} (byte {pos})");
        let len = le32(data, pos).ok_or_else(|| src.malformed(&what, "truncated chunk header"))?;
        let kind = data
            .get(pos + 4..pos + 8)
            .ok_or_else(|| src.malformed(&what, "truncated chunk header"))?;
        let body = (pos + 8)
            .checked_add(len)
            .and_then(|end| data.get(pos + 8..end))
            .ok_or_else(|| {
                src.malformed(
                    &what,
                    format!("chunk of {len} bytes runs past the end of the file"),
                )
            })?;
        match (index, kind) {
            (0, b"JSON") => json = Some(body),
            (0, _) => return Err(src.malformed(&what, "the first chunk must be JSON")),
            (1, b"BIN\0") => bin = Some(body),
            _ => {} // unknown chunks are skipped, as the spec says
        }
        pos += 8 + len;
        index += 1;
    }
    let json = json.ok_or_else(|| src.malformed("GLB", "no JSON chunk"))?;
    Ok((json, bin))
}

/// Runs the `gltf` crate's validation (which the document accessors rely on: they unwrap
/// checked enums and indices), tolerating only a missing `min`/`max` on `POSITION`: the spec
/// requires them, but many exporters omit them and this reader does not need them.
fn validate(doc: &gltf::Document, src: &Source) -> Result<(), MeshError> {
    use gltf::json::validation::{Checked, Error, Validate};
    let root = doc.as_json();
    // gltf-json 1.4.1's primitive validation hook indexes `accessors[POSITION]` before the
    // index itself is checked, and panics on an out-of-range index (found by fuzzing): check
    // those indices first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(i) = prim.attributes.get(&Checked::Valid(Semantic::Positions)) {
                if i.value() >= root.accessors.len() {
                    return Err(src.malformed(
                        format!("mesh {m} primitive {p}"),
                        format!(
                            "POSITION refers to accessor {}, but there are {}",
                            i.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let p = path();
        let harmless =
            matches!(error, Error::Missing) && (p.0.ends_with(".min") || p.0.ends_with(".max"));
        if !harmless {
            errors.push(format!("{}: {error}", p.0));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        Err(src.malformed("document", format!("invalid glTF: {}", errors.join("; "))))
    }
}

#[derive(Default)]
struct Output {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    colors: Vec<[u8; 3]>,
    all_colored: bool,
    primitives: usize,
    /// The non-triangle primitive modes skipped (`LINES (1)`, …), in first-seen order.
    skipped_modes: Vec<String>,
    /// Most vertices (and triangles) the scene may instantiate, see [`instance_limit`].
    limit: usize,
}

/// Node instancing multiplies meshes, so a small file can describe an enormous scene (a few
/// kB of JSON instancing one primitive thousands of times, thousands of times over). The
/// reader refuses scenes with more than max(4 Mi, 64 × input bytes) vertices or triangles —
/// far above any real instancing of a scanned body, far below exhausting memory.
fn instance_limit(input_bytes: usize) -> usize {
    (1usize << 22).max(input_bytes.saturating_mul(64))
}

/// Depth-first, pre-order walk from a scene root (iterative: a deep node chain cannot
/// overflow the stack), adding every mesh instance with its world transform.
fn visit(
    root: gltf::Node,
    seen: &mut [bool],
    buffers: &[Cow<[u8]>],
    src: &Source,
    out: &mut Output,
) -> Result<(), MeshError> {
    let mut stack = vec![(root, Mat4::identity())];
    while let Some((node, parent)) = stack.pop() {
        // glTF node hierarchies are disjoint strict trees: a node reached twice means a cycle
        // or a node with two parents, both invalid (and a cycle would never end).
        let i = node.index();
        if seen.get(i).copied().unwrap_or(true) {
            return Err(src.malformed(
                format!("node {i}"),
                "is reached twice in the scene graph (cycle or two parents)",
            ));
        }
        seen[i] = true;
        let local = node.transform().matrix();
        let local = Mat4::from(local.map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            add_mesh(&mesh, &world, buffers, src, out)?;
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(())
}

fn add_mesh(
    mesh: &gltf::Mesh,
    world: &Mat4,
    buffers: &[Cow<[u8]>],
    src: &Source,
    out: &mut Output,
) -> Result<(), MeshError> {
    let flip = det3(world) < 0.0;
    for prim in mesh.primitives() {
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            // Points and lines carry no surface; remembered for the error if nothing else does.
            let name = mode_name(mode);
            if !out.skipped_modes.contains(&name) {
                out.skipped_modes.push(name);
            }
            continue;
        }
        let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
        let pos_acc = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| src.malformed(&what, "has no POSITION attribute"))?;
        let (pos, dims) = read_accessor(&pos_acc, buffers, src)?;
        if dims != 3 {
            return Err(src.malformed(
                format!("accessor {}", pos_acc.index()),
                "POSITION must be VEC3",
            ));
        }
        let n = pos_acc.count();
        let base = out.positions.len();
        if base + n > u32::MAX as usize {
            return Err(src.malformed(&what, "too many vertices for u32 indices"));
        }
        if base + n > out.limit {
            return Err(src.malformed(
                &what,
                format!(
                    "the scene instantiates more than {} vertices (limit for a file of this size)",
                    out.limit
                ),
            ));
        }
        out.positions.extend(
            pos.chunks_exact(3)
                .map(|p| apply(world, [p[0], p[1], p[2]])),
        );

        match prim.get(&Semantic::Colors(0)) {
            Some(acc) if out.all_colored || out.primitives == 0 => {
                let (c, dims) = read_accessor(&acc, buffers, src)?;
                if !(dims == 3 || dims == 4) || acc.count() != n {
                    return Err(src.malformed(
                        format!("accessor {}", acc.index()),
                        "COLOR_0 must be VEC3 or VEC4 with one colour per vertex",
                    ));
                }
                out.colors.extend(
                    c.chunks_exact(dims)
                        .map(|c| [0, 1, 2].map(|k| linear_to_srgb8(c[k]))),
                );
                out.all_colored = true;
            }
            _ => out.all_colored = false,
        }
        out.primitives += 1;

        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => {
                let (idx, dims) = read_accessor(&acc, buffers, src)?;
                if dims != 1 || acc.data_type() == DataType::F32 {
                    return Err(src.malformed(
                        format!("accessor {}", acc.index()),
                        "indices must be integer SCALAR",
                    ));
                }
                let mut v = Vec::with_capacity(idx.len());
                for (k, &i) in idx.iter().enumerate() {
                    if i < 0.0 || i >= n as f64 {
                        return Err(src.malformed(
                            format!("accessor {} element {k}", acc.index()),
                            format!("index {i} is out of range for {n} vertices ({what})"),
                        ));
                    }
                    v.push(i as u32);
                }
                v
            }
            None => (0..n as u32).collect(),
        };
        if out.triangles.len() + indices.len() > out.limit {
            return Err(src.malformed(
                &what,
                format!(
                    "the scene instantiates more than {} triangles (limit for a file of this size)",
                    out.limit
                ),
            ));
        }
        let b = base as u32; // base + n ≤ u32::MAX, checked above
        let mut push = |t: [u32; 3]| {
            let t = if flip { [t[0], t[2], t[1]] } else { t };
            out.triangles.push(t.map(|i| i + b));
        };
        match mode {
            Mode::Triangles => indices
                .chunks_exact(3)
                .for_each(|t| push([t[0], t[1], t[2]])),
            Mode::TriangleStrip => {
                for k in 0..indices.len().saturating_sub(2) {
                    let (a, b2, c) = (indices[k], indices[k + 1], indices[k + 2]);
                    push(if k % 2 == 0 { [a, b2, c] } else { [b2, a, c] });
                }
            }
            _ => {
                for k in 1..indices.len().saturating_sub(1) {
                    push([indices[0], indices[k], indices[k + 1]]);
                }
            }
        }
    }
    Ok(())
}

/// A primitive mode as the spec names it, with its number (`LINE_STRIP (3)`).
fn mode_name(mode: Mode) -> String {
    let name = match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    };
    format!("{name} ({})", mode.as_gl_enum())
}

/// Reads every component of an accessor as f64 (normalized integers mapped to [0, 1] or
/// [-1, 1]); returns the values flattened and the number of components per element.
fn read_accessor(
    acc: &gltf::Accessor,
    buffers: &[Cow<[u8]>],
    src: &Source,
) -> Result<(Vec<f64>, usize), MeshError> {
    let what = || format!("accessor {}", acc.index());
    if acc.sparse().is_some() {
        return Err(src.malformed(what(), "sparse accessors are not supported"));
    }
    let view = acc.view().ok_or_else(|| {
        src.malformed(
            what(),
            "has no bufferView (zero-filled accessors are not supported)",
        )
    })?;
    let dims = match acc.dimensions() {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 => 4,
        _ => return Err(src.malformed(what(), "matrix accessors are not supported here")),
    };
    let ty = acc.data_type();
    let comp = ty.size();
    let elem = comp * dims;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(src.malformed(
            what(),
            format!("byteStride {stride} is smaller than the element size {elem}"),
        ));
    }
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| src.malformed(what(), "buffer is missing"))?;
    let count = acc.count();
    let view_end = view.offset().checked_add(view.length());
    let view_bytes = view_end
        .and_then(|e| buffer.get(view.offset()..e))
        .ok_or_else(|| {
            src.malformed(
                format!("bufferView {}", view.index()),
                "lies outside its buffer",
            )
        })?;
    if count > 0 {
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(acc.offset()))
            .and_then(|x| x.checked_add(elem));
        if end.is_none_or(|e| e > view_bytes.len()) {
            return Err(src.malformed(
                what(),
                format!(
                    "{count} elements at offset {} stride {stride} run past its bufferView",
                    acc.offset()
                ),
            ));
        }
    }
    let norm = acc.normalized();
    let mut out = Vec::with_capacity(count * dims);
    for k in 0..count {
        let start = acc.offset() + k * stride; // in range: checked above
        for j in 0..dims {
            let o = start + j * comp;
            let b = &view_bytes[o..o + comp];
            let v = match ty {
                DataType::I8 => {
                    let x = b[0] as i8 as f64;
                    if norm {
                        (x / 127.0).max(-1.0)
                    } else {
                        x
                    }
                }
                DataType::U8 => {
                    let x = b[0] as f64;
                    if norm {
                        x / 255.0
                    } else {
                        x
                    }
                }
                DataType::I16 => {
                    let x = i16::from_le_bytes([b[0], b[1]]) as f64;
                    if norm {
                        (x / 32767.0).max(-1.0)
                    } else {
                        x
                    }
                }
                DataType::U16 => {
                    let x = u16::from_le_bytes([b[0], b[1]]) as f64;
                    if norm {
                        x / 65535.0
                    } else {
                        x
                    }
                }
                DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            };
            out.push(v);
        }
    }
    Ok((out, dims))
}

fn load_uri(
    uri: &str,
    byte_length: usize,
    budget: &mut u64,
    src: &Source,
    what: &str,
) -> Result<Vec<u8>, MeshError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or_else(|| src.malformed(what, "data URI is not base64"))?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| src.malformed(what, format!("bad base64 data: {e}")));
    }
    let dir = src.dir.as_ref().ok_or_else(|| {
        src.malformed(
            what,
            format!("external buffer {uri:?} cannot be resolved when reading from memory"),
        )
    })?;
    let path = confined_path(dir, uri, src)?;
    let refuse = |message: String| MeshError::ExternalBuffer {
        file: src.name.clone(),
        uri: uri.to_string(),
        message,
    };
    let io_err = |source| MeshError::Io {
        file: format!("{}: buffer uri {uri:?} ({})", src.name, path.display()),
        source,
    };
    // Checked before opening too: opening a FIFO for reading would wait for a writer.
    if !std::fs::metadata(&path).map_err(io_err)?.is_file() {
        return Err(refuse("is not a regular file".to_string()));
    }
    let file = std::fs::File::open(&path).map_err(io_err)?;
    let meta = file.metadata().map_err(io_err)?;
    if !meta.is_file() {
        return Err(refuse("is not a regular file".to_string()));
    }
    if meta.len() < byte_length as u64 {
        return Err(refuse(format!(
            "the file has {} bytes, but the buffer's byteLength is {byte_length}",
            meta.len()
        )));
    }
    if byte_length as u64 > *budget {
        return Err(MeshError::InputTooLarge {
            file: format!("{} with its buffer {uri:?}", src.name),
            limit: src.max_input_bytes,
        });
    }
    *budget -= byte_length as u64;
    // Only byteLength bytes are read (a longer file's tail is not part of the buffer); the
    // file holds at least that many (checked above) and they fit the input budget.
    let mut data = Vec::with_capacity(byte_length);
    file.take(byte_length as u64)
        .read_to_end(&mut data)
        .map_err(io_err)?;
    if data.len() < byte_length {
        return Err(refuse(format!(
            "the file ended after {} bytes, but the buffer's byteLength is {byte_length}",
            data.len()
        )));
    }
    Ok(data)
}

/// Resolves a relative buffer uri inside `dir` (the glTF file's folder): refuses absolute
/// paths, other URI schemes, `..` leading above the folder and (after canonicalizing both)
/// a path that ends outside it, e.g. through a symlink.
fn confined_path(dir: &Path, uri: &str, src: &Source) -> Result<PathBuf, MeshError> {
    let refuse = |message: &str| MeshError::ExternalBuffer {
        file: src.name.clone(),
        uri: uri.to_string(),
        message: message.to_string(),
    };
    let decoded = percent_decode(uri);
    let scheme = decoded
        .split_once(':')
        .is_some_and(|(s, _)| !s.is_empty() && !s.contains('/'));
    if scheme {
        return Err(refuse(
            "only data: URIs and paths relative to the glTF file are read",
        ));
    }
    let rel = Path::new(&decoded);
    let mut depth = 0usize;
    for c in rel.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => {
                return Err(refuse(
                    "is an absolute path; buffers are read only from the glTF file's folder",
                ))
            }
            Component::ParentDir => {
                depth = depth
                    .checked_sub(1)
                    .ok_or_else(|| refuse("leads out of the glTF file's folder (`..`)"))?;
            }
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
        }
    }
    let path = dir.join(rel);
    let canon = |p: &Path| {
        std::fs::canonicalize(p).map_err(|source| MeshError::Io {
            file: format!("{}: buffer uri {uri:?} ({})", src.name, p.display()),
            source,
        })
    };
    let base = canon(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    })?;
    let target = canon(&path)?;
    if !target.starts_with(&base) {
        return Err(refuse(&format!(
            "leads out of the glTF file's folder (to {})",
            target.display()
        )));
    }
    Ok(target)
}

/// Decodes `%XX` escapes of a relative URI (e.g. `%20` for a space).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push(h * 16 + l);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn pad4(v: &mut Vec<u8>, byte: u8) {
    while !v.len().is_multiple_of(4) {
        v.push(byte);
    }
}

/// Builds the glTF JSON and its binary buffer (`uri`: `None` for GLB, a data URI for `.gltf`).
/// sRGB byte → linear intensity in [0, 1] (IEC 61966-2-1).
fn srgb8_to_linear(c: u8) -> f64 {
    let s = c as f64 / 255.0;
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear intensity → sRGB byte (clamped to [0, 1]; NaN reads as 0).
fn linear_to_srgb8(l: f64) -> u8 {
    let l = if l.is_nan() { 0.0 } else { l.clamp(0.0, 1.0) };
    let s = if l <= 0.0031308 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

fn build(mesh: &TriMesh, colors: Option<&[[u8; 3]]>, embed: bool) -> (serde_json::Value, Vec<u8>) {
    let nv = mesh.num_vertices();
    let mut bin: Vec<u8> = Vec::with_capacity(nv * 28 + mesh.num_triangles() * 12);
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &mesh.positions {
        for k in 0..3 {
            let x = p[k] as f32;
            lo[k] = lo[k].min(x);
            hi[k] = hi[k].max(x);
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for n in mesh.vertex_normals() {
        // An isolated or fully degenerate vertex has no normal; glTF requires unit normals.
        let n = if n == [0.0; 3] { [0.0, 0.0, 1.0] } else { n };
        for x in n {
            bin.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
    let nrm_len = bin.len() - pos_len;
    let col_off = bin.len();
    if let Some(c) = colors {
        for c in c {
            for k in c {
                bin.extend_from_slice(&(srgb8_to_linear(*k) as f32).to_le_bytes());
            }
        }
    }
    let col_len = bin.len() - col_off;
    let idx_off = bin.len();
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let idx_len = bin.len() - idx_off;

    let mut views = vec![
        json!({"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962}),
        json!({"buffer": 0, "byteOffset": pos_len, "byteLength": nrm_len, "target": 34962}),
        json!({"buffer": 0, "byteOffset": idx_off, "byteLength": idx_len, "target": 34963}),
    ];
    let mut accessors = vec![
        json!({"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3",
               "min": lo, "max": hi}),
        json!({"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"}),
        json!({"bufferView": 2, "componentType": 5125, "count": 3 * mesh.num_triangles(), "type": "SCALAR"}),
    ];
    let mut attributes = json!({"POSITION": 0, "NORMAL": 1});
    if colors.is_some() {
        views.push(
            json!({"buffer": 0, "byteOffset": col_off, "byteLength": col_len,
                          "target": 34962}),
        );
        accessors
            .push(json!({"bufferView": 3, "componentType": 5126, "count": nv, "type": "VEC3"}));
        attributes["COLOR_0"] = json!(3);
    }
    let mut buffer = json!({"byteLength": bin.len()});
    if embed {
        buffer["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        ));
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "symcorr-mesh"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": 2, "mode": 4, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                                "metallicFactor": 0.0, "roughnessFactor": 1.0},
                       "doubleSided": true}],
        "buffers": [buffer],
        "bufferViews": views,
        "accessors": accessors,
    });
    (doc, bin)
}

/// glTF stores positions as f32: a coordinate beyond f32's range cannot be written.
fn check_f32(mesh: &TriMesh, format: &'static str) -> Result<(), MeshError> {
    for (vertex, p) in mesh.positions.iter().enumerate() {
        if let Some(&value) = p.iter().find(|c| !(**c as f32).is_finite()) {
            return Err(MeshError::NotRepresentable {
                vertex,
                value,
                format,
            });
        }
    }
    Ok(())
}

/// Encodes a binary glTF (GLB) file.
pub(crate) fn write_glb(mesh: &TriMesh, colors: Option<&[[u8; 3]]>) -> Result<Vec<u8>, MeshError> {
    check_f32(mesh, "GLB")?;
    let (doc, mut bin) = build(mesh, colors, false);
    let mut json = doc.to_string().into_bytes();
    pad4(&mut json, b' ');
    pad4(&mut bin, 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}

/// Encodes a `.gltf` JSON file with the buffer embedded as a base64 data URI.
pub(crate) fn write_gltf(mesh: &TriMesh, colors: Option<&[[u8; 3]]>) -> Result<Vec<u8>, MeshError> {
    check_f32(mesh, "glTF")?;
    let (doc, _) = build(mesh, colors, true);
    let mut s = doc.to_string().into_bytes();
    s.push(b'\n');
    Ok(s)
}

#[cfg(test)]
mod colour_tests {
    use super::{linear_to_srgb8, srgb8_to_linear};

    /// Every sRGB byte survives the trip through a linear f32, and the transfer function is
    /// monotonic with the standard's fixed points (0, 1, the 0.04045 knee).
    #[test]
    fn srgb_bytes_round_trip_through_linear_f32() {
        let mut last = -1.0;
        for c in 0..=255u8 {
            let l = srgb8_to_linear(c);
            assert!(l > last);
            last = l;
            assert_eq!(linear_to_srgb8(l as f32 as f64), c);
        }
        assert_eq!(srgb8_to_linear(0), 0.0);
        assert_eq!(srgb8_to_linear(255), 1.0);
        assert!((srgb8_to_linear(10) - 10.0 / 255.0 / 12.92).abs() < 1e-15);
        assert_eq!(linear_to_srgb8(f64::NAN), 0);
        assert_eq!(linear_to_srgb8(2.0), 255);
    }
}
