//! Triangle meshes for symcorr: the [`TriMesh`] type, readers and writers ([`io`]),
//! validation and repair ([`validate`], [`repair`]), and per-element geometry and adjacency
//! ([`geometry`]).
//!
//! [`TriMesh`] holds f64 positions and u32 triangles. Vertex `i` of a mesh read from a file is
//! vertex `i` of that file: correspondence ground truth is the vertex index, so no reader or
//! repair ever renumbers silently (repairs return a map back to the input's ids).
//!
//! ```
//! use symcorr_mesh::TriMesh;
//! let mesh = TriMesh::new(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
//!     vec![[0, 1, 2]],
//! ).unwrap();
//! assert!((mesh.total_area() - 0.5).abs() < 1e-12);
//! ```
//!
//! # Decisions
//!
//! **Readers.** [`io::read`] picks the format by extension (case-insensitive: `.off`, `.obj`,
//! `.ply`, `.gltf`, `.glb`); [`io::read_with_format`] overrides it; [`io::read_from_bytes`]
//! parses memory (used by the fuzz targets in `fuzz/`). Every reader keeps file vertex order,
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
//!   findings); buffers (GLB chunk, base64 `data:` URIs, files next to the `.gltf`) and
//!   accessor bytes are read here with checked offsets. All triangle primitives (incl. strips
//!   and fans) of the default scene (else scene 0; with no scene, every mesh untransformed) are
//!   concatenated in depth-first node order with world transforms applied; a mirroring
//!   transform flips winding. Sparse and bufferView-less accessors are rejected, and so is a
//!   scene instancing more than max(4 Mi, 64 × input bytes) vertices or triangles (a small
//!   file can otherwise describe an arbitrarily large scene).
//!
//! **Writers** ([`io::write`], [`io::write_with`], [`io::write_to_bytes`]) produce OFF/COFF,
//! OBJ, PLY (binary little-endian by default — doubles, so exact — or ascii) and glTF 2.0 (GLB,
//! or `.gltf` with an embedded buffer) with per-vertex colours. Text formats print f64 in the
//! shortest round-trip form, so write → read is bit-exact; glTF stores f32 positions (exact
//! for f32 values; beyond f32's range is [`MeshError::NotRepresentable`]). GLB output carries
//! `asset.version` 2.0, 4-byte-aligned views, POSITION min/max, unit NORMALs and COLOR_0 as
//! normalized u8 RGB (stride 4; colour bytes are stored unconverted). All writes are atomic:
//! a temporary file in the target directory is synced and renamed over the target.
//!
//! **Validation and repair.** [`validate`] reports (never fails): non-finite vertices,
//! out-of-range triangles, repeated-vertex and zero-area triangles (area ≤
//! [`DEFAULT_ZERO_AREA_REL`] × bbox diagonal²), duplicate triangles (same vertex set in any
//! order), unreferenced vertices, non-manifold edges (> 2 triangles) and vertices (> 1 fan),
//! inconsistently oriented edges, components (triangles joined through shared vertices, with
//! triangle counts) and boundary loops. [`repair`] refuses invalid input (non-finite,
//! out-of-range, empty are errors — it does not guess), then per [`RepairOptions`] removes
//! degenerate/zero-area triangles, duplicates (first kept), optionally the triangles beyond
//! the first two at a non-manifold edge, small components or all but the largest, optionally
//! splits non-manifold vertices (one copy per extra fan), and drops unreferenced vertices.
//! **vertex_map convention:** `Repaired::vertex_map[new_id] = input_id`; kept vertices keep
//! their relative order (the map is increasing over them) and split copies are appended at the
//! end, mapping to the vertex they copy; `triangle_map` does the same for triangles. Results
//! computed on the repaired mesh are reported in input ids through these maps.

mod error;
pub mod geometry;
pub mod io;
pub mod subdivide;
#[doc(hidden)]
pub mod testmesh;
mod validate;

pub use error::MeshError;
pub use validate::{
    repair, validate, validate_with, RepairOptions, RepairReport, Repaired, ValidationReport,
    DEFAULT_ZERO_AREA_REL,
};

/// A triangle mesh: positions (f64) and counter-clockwise triangles (u32 vertex indices).
///
/// Invariants established by [`TriMesh::new`]: every coordinate is finite and every index is
/// `< positions.len()`. Code in this workspace relies on them (indexing never goes out of range).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions, in file order.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Builds a mesh, checking that coordinates are finite and indices in range.
    ///
    /// Errors: [`MeshError::Empty`] without vertices or triangles, [`MeshError::NonFinite`],
    /// [`MeshError::IndexOutOfRange`].
    pub fn new(positions: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if positions.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty {
                vertices: positions.len(),
                triangles: triangles.len(),
            });
        }
        if let Some((vertex, _)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        {
            return Err(MeshError::NonFinite { vertex });
        }
        let n = positions.len();
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    index: index as usize,
                    vertices: n,
                });
            }
        }
        Ok(TriMesh {
            positions,
            triangles,
        })
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
}
