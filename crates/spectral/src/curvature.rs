//! Discrete Gaussian curvature (the paper's eq. 4).

use nalgebra::Point3;
use std::f64::consts::PI;
use symcorr_mesh::TriMesh;

/// Gaussian curvature per vertex, the paper's eq. 4: `gc(p) = 3 (2π − Σ α_i) / Σ A(f_i)`,
/// the angle defect over one third of the incident area (the barycentric vertex area).
///
/// Boundary vertices (on an edge used by exactly one triangle) use `π` instead of `2π`: that
/// is the discrete geodesic-curvature convention, which makes a flat disk's boundary vertices
/// zero instead of spuriously huge. With it, `Σ_v gc(v)·A_v/3` equals `2π χ` minus the total
/// boundary turning (Gauss–Bonnet), e.g. `4π` on a closed genus-0 mesh and `0` for a flat disk.
///
/// Angles are `atan2(|u×w|, u·w)`. A vertex in no triangle (or only zero-area ones) gets 0.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_spectral::gaussian_curvature;
/// let mesh = TriMesh::new(
///     vec![[1.,0.,0.],[-1.,0.,0.],[0.,1.,0.],[0.,-1.,0.],[0.,0.,1.],[0.,0.,-1.]],
///     vec![[0,2,4],[2,1,4],[1,3,4],[3,0,4],[2,0,5],[1,2,5],[3,1,5],[0,3,5]],
/// ).unwrap();
/// let gc = gaussian_curvature(&mesh);
/// let areas = mesh.triangle_areas();
/// let total: f64 = gc.iter().map(|g| g * 4.0 * areas[0] / 3.0).sum();
/// assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-12);
/// ```
pub fn gaussian_curvature(mesh: &TriMesh) -> Vec<f64> {
    let n = mesh.num_vertices();
    let mut angle = vec![0.0; n];
    let mut area = vec![0.0; n];
    let mut on_face = vec![false; n];
    for t in &mesh.triangles {
        let p = t.map(|v| Point3::from(mesh.positions[v as usize]));
        let [p0, p1, p2] = p;
        let a = 0.5 * (p1 - p0).cross(&(p2 - p0)).norm();
        for k in 0..3 {
            let u = p[(k + 1) % 3] - p[k];
            let w = p[(k + 2) % 3] - p[k];
            let v = t[k] as usize;
            angle[v] += u.cross(&w).norm().atan2(u.dot(&w));
            area[v] += a;
            on_face[v] = true;
        }
    }
    let boundary = boundary_vertices(mesh);
    (0..n)
        .map(|v| {
            if !on_face[v] || area[v] <= 0.0 {
                return 0.0;
            }
            let full = if boundary[v] { PI } else { 2.0 * PI };
            3.0 * (full - angle[v]) / area[v]
        })
        .collect()
}

/// True for vertices on an edge that belongs to exactly one triangle.
pub(crate) fn boundary_vertices(mesh: &TriMesh) -> Vec<bool> {
    let mut e: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(a, b)| (a.min(b), a.max(b))))
        .collect();
    e.sort_unstable();
    let mut b = vec![false; mesh.num_vertices()];
    let mut i = 0;
    while i < e.len() {
        let mut j = i + 1;
        while j < e.len() && e[j] == e[i] {
            j += 1;
        }
        if j - i == 1 {
            b[e[i].0 as usize] = true;
            b[e[i].1 as usize] = true;
        }
        i = j;
    }
    b
}
