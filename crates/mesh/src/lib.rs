//! Triangle meshes for symcorr: the [`TriMesh`] type, readers and writers ([`io`]),
//! validation and repair ([`validate()`], [`repair()`]), per-element geometry and adjacency
//! ([`geometry`], [`TriMesh::boundary_loops`], [`TriMesh::vertex_areas`]) and Loop
//! subdivision ([`subdivide`]).
//!
//! # Data flow
//! file (OFF, OBJ, PLY ascii/binary, glTF/GLB) → [`io::read`] → [`TriMesh`] (f64 positions,
//! u32 counter-clockwise triangles) → [`validate()`] (a report, never a failure) →
//! [`repair()`] (degenerate, zero-area and duplicate triangles, unreferenced vertices, optionally
//! non-manifold elements and small components removed; a map back to the input's ids) → the
//! other crates → [`io::write`] (OFF, OBJ, PLY, glTF/GLB with per-vertex colours, atomically).
//!
//! ```
//! use symcorr_mesh::{io, repair, RepairOptions, TriMesh};
//! // Two triangles and a stray vertex (3) that no triangle uses.
//! let mesh = TriMesh::new(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [5.0, 5.0, 5.0], [1.0, 1.0, 0.0]],
//!     vec![[0, 1, 2], [1, 4, 2]],
//! ).unwrap();
//! assert!((mesh.total_area() - 1.0).abs() < 1e-12);
//! let fixed = repair(&mesh, &RepairOptions::default()).unwrap();
//! assert_eq!(fixed.vertex_map, vec![0, 1, 2, 4]); // new id → input id
//! // Text formats round-trip f64 exactly; vertex order is the file's.
//! let bytes = io::write_to_bytes(&mesh, None, io::Format::Off, io::PlyEncoding::default()).unwrap();
//! assert_eq!(io::read_from_bytes(&bytes, io::Format::Off).unwrap().mesh, mesh);
//! ```
//!
//! # Invariants
//! * Vertex `i` of a mesh read from a file is vertex `i` of that file: correspondence ground
//!   truth is the vertex index, so no reader or repair renumbers silently. Readers are our own
//!   for OFF, OBJ and PLY (tobj renumbers vertices in face order; see
//!   `docs/decisions/2026-11-23-dependencies-and-own-parsers.md`).
//! * [`TriMesh::new`] guarantees finite coordinates and in-range indices; readers reject
//!   NaN/inf and out-of-range indices with an error naming the line or element, and never size
//!   an allocation from a header count the input could not hold.
//! * `Repaired::vertex_map[new_id] = input_id`: kept vertices keep their relative order (the
//!   map is increasing over them), split copies are appended at the end; `triangle_map` does
//!   the same for triangles. Results on the repaired mesh are reported in input ids.
//! * Writes are atomic: a temporary file in the target directory, synced and renamed.
//!
//! The [`io`] module documents each format's choices (glTF scenes, colours, f32 positions).

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
