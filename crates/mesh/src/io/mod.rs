//! Reading and writing mesh files: OFF, OBJ, PLY (ascii and binary), glTF/GLB.
//!
//! Vertex `i` of the file is vertex `i` of the returned [`TriMesh`] in every format (for glTF:
//! the vertices of the triangle primitives, concatenated in mesh / primitive / node order).
//! Polygons are fan-triangulated `(v0, v_k, v_k+1)`. The format is chosen by the file
//! extension (case-insensitive) unless given explicitly. Writers are atomic: they write a
//! temporary file in the target's directory and rename it over the target, so a failed write
//! never leaves a half-written file.
//!
//! **Readers.** [`read`] picks the format by extension (case-insensitive: `.off`, `.obj`,
//! `.ply`, `.gltf`, `.glb`); [`read_with_format`] overrides it; [`read_with_options`] also
//! sets the input size limit ([`DEFAULT_MAX_INPUT_BYTES`], 1 GiB: no file, device or FIFO is
//! read past it); [`read_from_bytes`] parses memory (used by the fuzz targets in `fuzz/`). Every reader keeps file vertex order,
//! fan-triangulates polygons `(v0, vk, vk+1)`, rejects NaN/inf coordinates and out-of-range
//! indices with an error naming the line (text) or element (binary), and never sizes an
//! allocation from a header count without checking that the input could hold that many
//! elements. A file without faces is [`MeshError::Empty`] (wrapped with the file name).
//! - OFF, OBJ and PLY are hand-written. OBJ: tobj renumbers vertices in face order, so it is
//!   not used; f64 throughout; `v/vt/vn` corners and negative (relative) indices; the
//!   `v x y z r g b` colour extension is kept only if every vertex has it. PLY: a small parser
//!   instead of ply-rs-bw — the reader needs only `x y z`, `red green blue` and one index list,
//!   and owning it lets every count and list length be checked against the bytes present
//!   (ascii, binary little/big endian; any property order and types; `vertex_indices` or
//!   `vertex_index`; other properties/elements skipped).
//! - glTF/GLB: the `gltf` crate parses and validates the JSON document (its GLB container
//!   parser is replaced by a checked one, and one validation panic is pre-empted — both fuzz
//!   findings); buffers (GLB chunk, base64 `data:` URIs, files in the `.gltf`'s own folder —
//!   no absolute paths, `..` or symlinks leading out, no devices; at most `byteLength` bytes
//!   each, counted against the input size limit) and
//!   accessor bytes are read here with checked offsets. All triangle primitives (incl. strips
//!   and fans) of the default scene (else scene 0; with no scene, every mesh untransformed) are
//!   concatenated in depth-first node order with world transforms applied; a mirroring
//!   transform flips winding. Sparse and bufferView-less accessors are rejected, and so is a
//!   scene instancing more than max(4 Mi, 64 × input bytes) vertices or triangles (a small
//!   file can otherwise describe an arbitrarily large scene).
//!
//! **Writers** ([`write()`], [`write_with`], [`write_to_bytes`]) produce OFF/COFF,
//! OBJ, PLY (binary little-endian by default — doubles, so exact — or ascii) and glTF 2.0 (GLB,
//! or `.gltf` with an embedded buffer) with per-vertex colours. Text formats print f64 in the
//! shortest round-trip form, so write → read is bit-exact; glTF stores f32 positions (exact
//! for f32 values; beyond f32's range is [`MeshError::NotRepresentable`]). GLB output carries
//! `asset.version` 2.0, 4-byte-aligned views, POSITION min/max, unit NORMALs and COLOR_0 as
//! linear f32 RGB (converted from symcorr's sRGB bytes and back on reading, so the round trip
//! is exact; see the `gltf` submodule's source docs). An animated GLB — a mesh moving through
//! frames as morph targets — is streamed by [`gltf::MorphAnimationWriter`].

use std::path::{Path, PathBuf};

use crate::{MeshError, TriMesh};

pub mod gltf;
mod obj;
mod off;
mod output;
mod ply;
mod text;

pub use output::{check_output, resolve_output, Destination, OutputBatch};

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Object File Format (`.off`), incl. `COFF` with per-vertex colours.
    Off,
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// Stanford PLY (`.ply`), ascii or binary (little/big endian) when reading.
    Ply,
    /// glTF 2.0 JSON (`.gltf`) with embedded (base64) or external buffers.
    Gltf,
    /// Binary glTF 2.0 (`.glb`).
    Glb,
}

impl Format {
    /// The format named by a path's extension (case-insensitive), if any.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "off" => Some(Format::Off),
            "obj" => Some(Format::Obj),
            "ply" => Some(Format::Ply),
            "gltf" => Some(Format::Gltf),
            "glb" => Some(Format::Glb),
            _ => None,
        }
    }

    fn from_path_or_err(path: &Path) -> Result<Format, MeshError> {
        Format::from_path(path).ok_or_else(|| MeshError::UnknownFormat {
            file: path.display().to_string(),
            extension: path
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default(),
        })
    }
}

/// How PLY files are encoded when written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    /// `binary_little_endian 1.0` (the default: compact and exact).
    #[default]
    BinaryLittleEndian,
    /// `ascii 1.0` (f64 written in shortest round-trip form, so still exact).
    Ascii,
}

/// A mesh read from a file, with its per-vertex colours if the file had them.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMesh {
    /// The triangle mesh (vertex order as in the file).
    pub mesh: TriMesh,
    /// Per-vertex RGB colours (`COFF`, PLY `red/green/blue`, glTF `COLOR_0`), one per vertex.
    pub colors: Option<Vec<[u8; 3]>>,
}

/// The default for [`ReadOptions::max_input_bytes`]: 1 GiB.
///
/// A mesh file is read whole into memory and then parsed into vectors several times its
/// size, so an unbounded read lets a mistaken path (`/dev/zero`, a FIFO, a multi-gigabyte
/// archive) exhaust memory before any parse error can be reported. The largest meshes symcorr
/// handles (scans of a few million triangles) are a few hundred MB even as ascii PLY; 1 GiB
/// leaves room for those and stops a runaway read early. Raise it with
/// [`ReadOptions::max_input_bytes`] (the CLI's `--max-input-size`).
pub const DEFAULT_MAX_INPUT_BYTES: u64 = 1 << 30;

/// Options for [`read_with_options`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadOptions {
    /// The format; `None` chooses by extension.
    pub format: Option<Format>,
    /// Most bytes read for one mesh: the file itself, plus for `.gltf` its external buffers.
    /// A larger input is [`MeshError::InputTooLarge`], refused from its metadata when it is a
    /// regular file, and after reading `max_input_bytes + 1` bytes otherwise (devices, FIFOs).
    pub max_input_bytes: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            format: None,
            max_input_bytes: DEFAULT_MAX_INPUT_BYTES,
        }
    }
}

/// `bytes` for messages: whole GiB, MiB or KiB when exact (`1 GiB`), else `N bytes`.
pub(crate) fn format_bytes(bytes: u64) -> String {
    const UNITS: [(u64, &str); 3] = [(1 << 30, "GiB"), (1 << 20, "MiB"), (1 << 10, "KiB")];
    for (size, unit) in UNITS {
        if bytes >= size && bytes.is_multiple_of(size) {
            return format!("{} {unit}", bytes / size);
        }
    }
    if bytes == 1 {
        "1 byte".to_string()
    } else {
        format!("{bytes} bytes")
    }
}

/// Reads at most `limit` bytes of an opened file: a regular file longer than `limit` is
/// refused from its metadata before reading; anything else (device, FIFO, a file growing
/// while read) is read through `take(limit + 1)`, so the read stops one byte past the limit.
/// `None` means the input is larger than `limit`; I/O errors are returned as they are.
pub(crate) fn read_capped(file: std::fs::File, limit: u64) -> std::io::Result<Option<Vec<u8>>> {
    use std::io::Read as _;
    let meta = file.metadata()?;
    let mut buf = Vec::new();
    if meta.is_file() {
        if meta.len() > limit {
            return Ok(None);
        }
        // +1: a file that grew since `metadata` ends the read without doubling the buffer.
        buf.reserve(
            usize::try_from(meta.len())
                .unwrap_or(usize::MAX)
                .saturating_add(1),
        );
    }
    file.take(limit.saturating_add(1)).read_to_end(&mut buf)?;
    Ok((buf.len() as u64 <= limit).then_some(buf))
}

/// Where the bytes being parsed came from: a name for error messages and, for glTF, the
/// directory against which external buffer URIs resolve and the byte budget they share with
/// the file.
pub(crate) struct Source {
    pub name: String,
    pub dir: Option<PathBuf>,
    /// [`ReadOptions::max_input_bytes`]: the glTF file and its external buffers together.
    pub max_input_bytes: u64,
}

impl Source {
    pub(crate) fn parse_err(&self, line: usize, message: impl Into<String>) -> MeshError {
        MeshError::Parse {
            file: self.name.clone(),
            line,
            message: message.into(),
        }
    }

    pub(crate) fn malformed(
        &self,
        element: impl Into<String>,
        message: impl Into<String>,
    ) -> MeshError {
        MeshError::Malformed {
            file: self.name.clone(),
            element: element.into(),
            message: message.into(),
        }
    }

    /// Builds the final mesh, attaching the file name to whole-mesh errors.
    pub(crate) fn finish(
        &self,
        positions: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
        colors: Option<Vec<[u8; 3]>>,
    ) -> Result<LoadedMesh, MeshError> {
        if let Some(c) = &colors {
            if c.len() != positions.len() {
                return Err(MeshError::InFile {
                    file: self.name.clone(),
                    source: Box::new(MeshError::ColorCount {
                        colors: c.len(),
                        vertices: positions.len(),
                    }),
                });
            }
        }
        let mesh = TriMesh::new(positions, triangles).map_err(|e| MeshError::InFile {
            file: self.name.clone(),
            source: Box::new(e),
        })?;
        Ok(LoadedMesh { mesh, colors })
    }
}

/// Reads a mesh file, choosing the format by extension (`.off`, `.obj`, `.ply`, `.gltf`, `.glb`).
///
/// ```
/// use symcorr_mesh::{io, TriMesh};
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("tri.off");
/// let mesh = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
///     vec![[0, 1, 2]],
/// ).unwrap();
/// io::write(&path, &mesh, None).unwrap();
/// let loaded = io::read(&path).unwrap();
/// assert_eq!(loaded.mesh, mesh);
/// assert!(loaded.colors.is_none());
/// ```
pub fn read(path: impl AsRef<Path>) -> Result<LoadedMesh, MeshError> {
    let path = path.as_ref();
    read_with_format(path, Format::from_path_or_err(path)?)
}

/// Reads a mesh file in the given format, whatever its extension (with the default
/// [`DEFAULT_MAX_INPUT_BYTES`] limit).
pub fn read_with_format(path: impl AsRef<Path>, format: Format) -> Result<LoadedMesh, MeshError> {
    read_with_options(
        path,
        &ReadOptions {
            format: Some(format),
            ..ReadOptions::default()
        },
    )
}

/// Reads a mesh file with explicit [`ReadOptions`] (format, input size limit).
///
/// Errors: as [`read`], and [`MeshError::InputTooLarge`] when the file (for `.gltf`: with its
/// external buffers) has more than `options.max_input_bytes` bytes; at most that many bytes
/// plus one are ever read, also from devices and FIFOs.
///
/// ```
/// use symcorr_mesh::{io, MeshError, TriMesh};
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("tri.off");
/// let mesh = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
///     vec![[0, 1, 2]],
/// ).unwrap();
/// io::write(&path, &mesh, None).unwrap();
/// let small = io::ReadOptions { max_input_bytes: 10, ..Default::default() };
/// let e = io::read_with_options(&path, &small).unwrap_err();
/// assert!(matches!(e, MeshError::InputTooLarge { limit: 10, .. }));
/// ```
pub fn read_with_options(
    path: impl AsRef<Path>,
    options: &ReadOptions,
) -> Result<LoadedMesh, MeshError> {
    let path = path.as_ref();
    let format = match options.format {
        Some(f) => f,
        None => Format::from_path_or_err(path)?,
    };
    let name = path.display().to_string();
    let bytes = read_input(path, options.max_input_bytes)?;
    let src = Source {
        name: name.clone(),
        dir: Some(
            path.parent()
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from(".")),
        ),
        max_input_bytes: options.max_input_bytes,
    };
    parse(&bytes, format, &src)
}

/// Reads a whole input file of at most `max_input_bytes` bytes: the one bounded read every input
/// of symcorr goes through (meshes here, joint logs and depth frames in symcorr-kinect). A
/// larger regular file is refused from its length before reading; a device or FIFO
/// (`/dev/zero`) is read no further than one byte past the limit.
///
/// Errors: [`MeshError::Io`], [`MeshError::InputTooLarge`], both naming the file.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("x.txt");
/// std::fs::write(&path, b"0123456789").unwrap();
/// assert_eq!(symcorr_mesh::io::read_input(&path, 10).unwrap().len(), 10);
/// assert!(symcorr_mesh::io::read_input(&path, 9).is_err());
/// ```
pub fn read_input(path: &Path, max_input_bytes: u64) -> Result<Vec<u8>, MeshError> {
    let name = path.display().to_string();
    let io_err = |source| MeshError::Io {
        file: name.clone(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_err)?;
    read_capped(file, max_input_bytes)
        .map_err(io_err)?
        .ok_or_else(|| MeshError::InputTooLarge {
            file: name.clone(),
            limit: max_input_bytes,
        })
}

/// Parses a mesh from memory. Errors name the file `<memory>`; a `.gltf` with external
/// (non-`data:`) buffer URIs cannot be resolved and is an error.
pub fn read_from_bytes(bytes: &[u8], format: Format) -> Result<LoadedMesh, MeshError> {
    let src = Source {
        name: "<memory>".to_string(),
        dir: None,
        max_input_bytes: DEFAULT_MAX_INPUT_BYTES,
    };
    parse(bytes, format, &src)
}

fn parse(bytes: &[u8], format: Format, src: &Source) -> Result<LoadedMesh, MeshError> {
    match format {
        Format::Off => off::read(bytes, src),
        Format::Ply => ply::read(bytes, src),
        Format::Obj => obj::read(bytes, src),
        Format::Gltf => gltf::read(bytes, src, false),
        Format::Glb => gltf::read(bytes, src, true),
    }
}

/// Options for [`write_with`].
#[derive(Debug, Clone, Copy, Default)]
pub struct WriteOptions {
    /// The format; `None` chooses by extension.
    pub format: Option<Format>,
    /// PLY encoding (ignored for other formats).
    pub ply_encoding: PlyEncoding,
}

/// Writes a mesh (and optional per-vertex colours) atomically, choosing the format by extension.
/// PLY is written binary little-endian; use [`write_with`] for ascii.
///
/// ```
/// use symcorr_mesh::{io, TriMesh};
/// let dir = tempfile::tempdir().unwrap();
/// let mesh = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
///     vec![[0, 1, 2]],
/// ).unwrap();
/// let colors = [[255, 0, 0], [0, 255, 0], [0, 0, 255]];
/// io::write(dir.path().join("tri.off"), &mesh, Some(&colors)).unwrap();
/// let back = io::read(dir.path().join("tri.off")).unwrap();
/// assert_eq!(back.colors.as_deref(), Some(&colors[..]));
/// ```
pub fn write(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    colors: Option<&[[u8; 3]]>,
) -> Result<(), MeshError> {
    write_with(path, mesh, colors, &WriteOptions::default())
}

/// Writes a mesh atomically with explicit [`WriteOptions`].
pub fn write_with(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    colors: Option<&[[u8; 3]]>,
    options: &WriteOptions,
) -> Result<(), MeshError> {
    let path = path.as_ref();
    let format = match options.format {
        Some(f) => f,
        None => Format::from_path_or_err(path)?,
    };
    let bytes = write_to_bytes(mesh, colors, format, options.ply_encoding).map_err(|e| {
        MeshError::InFile {
            file: path.display().to_string(),
            source: Box::new(e),
        }
    })?;
    atomic_write(path, &bytes)
}

/// Encodes a mesh in memory in the given format.
pub fn write_to_bytes(
    mesh: &TriMesh,
    colors: Option<&[[u8; 3]]>,
    format: Format,
    ply_encoding: PlyEncoding,
) -> Result<Vec<u8>, MeshError> {
    if let Some(c) = colors {
        if c.len() != mesh.num_vertices() {
            return Err(MeshError::ColorCount {
                colors: c.len(),
                vertices: mesh.num_vertices(),
            });
        }
    }
    match format {
        Format::Off => Ok(off::write(mesh, colors)),
        Format::Ply => Ok(ply::write(mesh, colors, ply_encoding)),
        Format::Obj => Ok(obj::write(mesh, colors)),
        Format::Gltf => gltf::write_gltf(mesh, colors),
        Format::Glb => gltf::write_glb(mesh, colors),
    }
}

/// Writes `bytes` to a temporary file next to `path`, syncs it, then renames it over `path`, so
/// that a failure never leaves a half-written `path` (an [`OutputBatch`] of one file: a
/// symlink is written through, a device or FIFO in place, a directory refused). Every output file of symcorr (meshes, joint
/// logs, depth frames, correspondence and label JSON, plots, the eigenpair cache) goes through
/// this one function.
///
/// Errors: [`MeshError::Io`] naming `path` (directory missing or not writable, disk full, …);
/// the temporary file is removed on every error.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("note.txt");
/// symcorr_mesh::io::atomic_write(&path, b"hello").unwrap();
/// assert_eq!(std::fs::read(&path).unwrap(), b"hello");
/// // A directory that does not exist: an error naming the file, and nothing written.
/// assert!(symcorr_mesh::io::atomic_write(&dir.path().join("no/such.txt"), b"x").is_err());
/// ```
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    let mut batch = OutputBatch::new();
    batch.add(path, bytes)?;
    batch.commit().map(|_| ())
}
