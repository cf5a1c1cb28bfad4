//! Quantities of the input mesh that several steps of [`attach`](crate::attach) read, each
//! computed once, on first use: the fit checks, the joint refinement and the clustered bone
//! heat would otherwise each derive them again from the triangles (on a recorded frame's
//! scan, every frame).

use std::cell::OnceCell;
use symcorr_mesh::TriMesh;

/// The mesh and what is derived from its connectivity alone.
pub(crate) struct MeshTables<'m> {
    pub mesh: &'m TriMesh,
    neighbors: OnceCell<Vec<Vec<u32>>>,
    boundary: OnceCell<Boundary>,
}

/// The boundary (edges of one triangle) as the steps read it.
pub(crate) struct Boundary {
    /// Per vertex: does it lie on a boundary edge?
    pub vertices: Vec<bool>,
    /// [`TriMesh::boundary_length`].
    pub length: f64,
}

impl<'m> MeshTables<'m> {
    pub fn new(mesh: &'m TriMesh) -> Self {
        MeshTables {
            mesh,
            neighbors: OnceCell::new(),
            boundary: OnceCell::new(),
        }
    }

    /// [`TriMesh::vertex_neighbors`].
    pub fn neighbors(&self) -> &[Vec<u32>] {
        self.neighbors.get_or_init(|| self.mesh.vertex_neighbors())
    }

    /// The boundary, from one tracing of its loops: they hold every boundary edge, so their
    /// vertices are [`TriMesh::boundary_vertices`] and their lengths sum to
    /// [`TriMesh::boundary_length`].
    pub fn boundary(&self) -> &Boundary {
        self.boundary.get_or_init(|| {
            let loops = self.mesh.boundary_loops();
            let mut vertices = vec![false; self.mesh.num_vertices()];
            for &v in loops.iter().flatten() {
                vertices[v as usize] = true;
            }
            Boundary {
                vertices,
                length: loops.iter().map(|l| self.mesh.loop_length(l)).sum(),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 4 grid of unit cells (two triangles each) with cell (1, 1) left out: an outer
    /// boundary, a hole, and five inner vertices on neither.
    fn grid_with_hole() -> TriMesh {
        let mut p = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                p.push([i as f64, j as f64, 0.0]);
            }
        }
        let mut t = Vec::new();
        for j in 0..4u32 {
            for i in 0..4u32 {
                if (i, j) == (1, 1) {
                    continue;
                }
                let a = j * 5 + i;
                t.push([a, a + 1, a + 5]);
                t.push([a + 1, a + 6, a + 5]);
            }
        }
        TriMesh::new(p, t).unwrap()
    }

    #[test]
    fn the_boundary_agrees_with_the_mesh_s_own_queries() {
        let m = grid_with_hole();
        let tables = MeshTables::new(&m);
        let b = tables.boundary();
        assert_eq!(b.vertices, m.boundary_vertices());
        assert_eq!(b.vertices.iter().filter(|&&v| v).count(), 16 + 4);
        assert!(!b.vertices[3 * 5 + 3] && b.vertices[5 + 1]);
        approx::assert_relative_eq!(b.length, m.boundary_length());
        approx::assert_relative_eq!(b.length, 16.0 + 4.0);
        assert_eq!(tables.neighbors(), m.vertex_neighbors().as_slice());
    }
}
