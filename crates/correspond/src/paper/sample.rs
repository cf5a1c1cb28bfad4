//! Farthest-point sampling of template points (sparse mode).

use nalgebra::{Point3, Vector3};
use symcorr_mesh::TriMesh;

/// `n` vertices of `mesh` by farthest-point sampling in Euclidean 3-space (each new point is
/// the vertex farthest from all chosen ones), starting from the vertex farthest from the
/// centroid. Deterministic. Returns every vertex (in order) when `n ≥ vertices`.
///
/// Euclidean rather than geodesic: on a body the two differ only where limbs touch, coverage is
/// what matters for a sample, and it costs `n·V` instead of `n` Dijkstra runs.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.1, 0.1, 0.0]],
///                      vec![[0, 1, 2], [1, 2, 3]]).unwrap();
/// let s = symcorr_correspond::farthest_point_sample(&m, 3);
/// assert_eq!(s.len(), 3);
/// assert!(!s.contains(&3)); // the point nearest another is left out
/// ```
pub fn farthest_point_sample(mesh: &TriMesh, n: usize) -> Vec<u32> {
    let v = mesh.num_vertices();
    if n >= v {
        return (0..v as u32).collect();
    }
    if n == 0 {
        return Vec::new();
    }
    let p: Vec<Point3<f64>> = mesh.positions.iter().copied().map(Point3::from).collect();
    let mut c = Vector3::zeros();
    for q in &p {
        c += q.coords / v as f64;
    }
    let c = Point3::from(c);
    let d2 = |a: &Point3<f64>, b: &Point3<f64>| (a - b).norm_squared();
    let argmax = |d: &[f64]| {
        d.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i)
    };
    let start = argmax(&p.iter().map(|q| d2(q, &c)).collect::<Vec<_>>());
    let mut out = Vec::with_capacity(n);
    let mut dist = vec![f64::INFINITY; v];
    let mut next = start;
    for _ in 0..n {
        out.push(next as u32);
        let s = p[next];
        for (d, q) in dist.iter_mut().zip(&p) {
            *d = d.min(d2(q, &s));
        }
        next = argmax(&dist);
    }
    out
}
