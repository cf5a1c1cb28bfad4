//! Triangle meshes for symcorr.
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

mod error;
pub mod geometry;
pub mod io;
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
