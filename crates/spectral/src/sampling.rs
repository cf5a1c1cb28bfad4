//! The paper's base vertex set (§3.3).

use crate::{EdgeGraph, SpectralError};
use symcorr_mesh::TriMesh;

/// Base vertex set (paper §3.3): sort vertices by Gaussian curvature, descending (ties by
/// index); repeatedly take the first unmarked vertex, add it to the set and mark every vertex
/// within geodesic distance `r` of it; stop when all are marked.
///
/// `radius` is in units of `√area` (`r = radius·√(total area)`), so the set is the same for a
/// scaled copy of the mesh. Geodesic distance is Dijkstra over mesh edges (paper eq. 5–6),
/// explored only up to `r` from each chosen vertex.
///
/// Errors: `curvature.len() != n`, a non-finite curvature value, or `radius` not positive.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_spectral::{base_vertex_set, gaussian_curvature};
/// let mesh = TriMesh::new(
///     vec![[1.,0.,0.],[-1.,0.,0.],[0.,1.,0.],[0.,-1.,0.],[0.,0.,1.],[0.,0.,-1.]],
///     vec![[0,2,4],[2,1,4],[1,3,4],[3,0,4],[2,0,5],[1,2,5],[3,1,5],[0,3,5]],
/// ).unwrap();
/// let gc = gaussian_curvature(&mesh);
/// // A huge radius covers everything from the first vertex.
/// assert_eq!(base_vertex_set(&mesh, &gc, 10.0).unwrap(), vec![0]);
/// ```
pub fn base_vertex_set(
    mesh: &TriMesh,
    curvature: &[f64],
    radius: f64,
) -> Result<Vec<u32>, SpectralError> {
    let n = mesh.num_vertices();
    if curvature.len() != n {
        return Err(SpectralError::InvalidArgument(format!(
            "curvature has {} values, the mesh has {n} vertices",
            curvature.len()
        )));
    }
    if let Some(v) = curvature.iter().position(|c| !c.is_finite()) {
        return Err(SpectralError::InvalidArgument(format!(
            "curvature of vertex {v} is not finite"
        )));
    }
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(SpectralError::InvalidArgument(format!(
            "radius must be positive, got {radius}"
        )));
    }
    let r = radius * mesh.total_area().sqrt();
    let graph = EdgeGraph::new(mesh);
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| {
        curvature[b as usize]
            .total_cmp(&curvature[a as usize])
            .then(a.cmp(&b))
    });
    let mut marked = vec![false; n];
    let mut base = Vec::new();
    for &v in &order {
        if marked[v as usize] {
            continue;
        }
        base.push(v);
        let d = graph.distances_within(&[v], r)?;
        for (m, x) in marked.iter_mut().zip(&d) {
            if x.is_finite() {
                *m = true;
            }
        }
    }
    Ok(base)
}
