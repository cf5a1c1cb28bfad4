//! Geometric checks: generalised winding number (inside/outside), triangle–triangle
//! intersection with a uniform-grid broad phase (self-intersection of distant body parts), and
//! nearest-vertex queries.

use std::collections::HashMap;

use symcorr_mesh::TriMesh;

use nalgebra::{Point3, Vector3};

use crate::math::V3;

/// Generalised winding number of `mesh` at `p` (Jacobson et al. 2013): the sum of the signed
/// solid angles of the triangles (Van Oosterom & Strackee 1983) over 4π. ≈ 1 inside a closed,
/// outward-oriented mesh, ≈ 0 outside.
pub fn winding_number(mesh: &TriMesh, p: V3) -> f64 {
    let p = Point3::from(p);
    let mut total = 0.0;
    for t in 0..mesh.num_triangles() {
        let [a, b, c] = mesh.corners(t).map(|q| Point3::from(q) - p);
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let num = a.dot(&b.cross(&c));
        let den = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
        total += 2.0 * num.atan2(den);
    }
    total / (4.0 * std::f64::consts::PI)
}

fn seg_tri(p: V3, q: V3, [a, b, c]: [V3; 3]) -> bool {
    // Möller–Trumbore on the segment p→q (parameter in [0, 1]).
    let (p, a) = (Point3::from(p), Point3::from(a));
    let d: Vector3<f64> = Point3::from(q) - p;
    let e1 = Point3::from(b) - a;
    let e2 = Point3::from(c) - a;
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() < 1e-18 {
        return false;
    }
    let inv = 1.0 / det;
    let s = p - a;
    let u = inv * s.dot(&h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(&e1);
    let v = inv * d.dot(&qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = inv * e2.dot(&qv);
    (0.0..=1.0).contains(&t)
}

/// Whether two triangles intersect (an edge of one crosses the other). Coplanar touching is
/// not reported; that is enough to catch interpenetrating body parts.
pub fn triangles_intersect(t1: [V3; 3], t2: [V3; 3]) -> bool {
    (0..3).any(|i| seg_tri(t1[i], t1[(i + 1) % 3], t2))
        || (0..3).any(|i| seg_tri(t2[i], t2[(i + 1) % 3], t1))
}

/// Pairs of intersecting triangles `(t1, t2)` with `t1 < t2` for which `distant(t1, t2)` holds
/// (the caller decides which parts may touch), found through a uniform grid of cell size
/// `cell` over the triangles' bounding boxes. Triangles sharing a vertex are never tested.
pub fn self_intersections(
    mesh: &TriMesh,
    cell: f64,
    mut distant: impl FnMut(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    let key = |p: V3| -> [i64; 3] {
        [
            (p[0] / cell).floor() as i64,
            (p[1] / cell).floor() as i64,
            (p[2] / cell).floor() as i64,
        ]
    };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let mut boxes = Vec::with_capacity(mesh.num_triangles());
    for t in 0..mesh.num_triangles() {
        let c = mesh.corners(t);
        let mut lo = c[0];
        let mut hi = c[0];
        for p in &c[1..] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let (a, b) = (key(lo), key(hi));
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    grid.entry([x, y, z]).or_default().push(t as u32);
                }
            }
        }
        boxes.push((lo, hi));
    }
    let overlap = |i: usize, j: usize| {
        let (a, b) = (boxes[i], boxes[j]);
        (0..3).all(|k| a.0[k] <= b.1[k] && b.0[k] <= a.1[k])
    };
    let mut found = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut cells: Vec<_> = grid.into_iter().collect();
    cells.sort_by_key(|(k, _)| *k);
    for (_, tris) in cells {
        for (n, &i) in tris.iter().enumerate() {
            for &j in &tris[n + 1..] {
                let (i, j) = (i.min(j) as usize, i.max(j) as usize);
                if !overlap(i, j) {
                    continue;
                }
                let (ti, tj) = (mesh.triangles[i], mesh.triangles[j]);
                if ti.iter().any(|v| tj.contains(v)) || !distant(i, j) {
                    continue;
                }
                if seen.insert((i, j)) && triangles_intersect(mesh.corners(i), mesh.corners(j)) {
                    found.push((i, j));
                }
            }
        }
    }
    found.sort_unstable();
    found
}

/// Index of the vertex of `mesh` nearest to `p` (brute force; meshes here are small).
pub fn nearest_vertex(mesh: &TriMesh, p: V3) -> usize {
    let p = Point3::from(p);
    let mut best = (0, f64::INFINITY);
    for (i, &q) in mesh.positions.iter().enumerate() {
        let d = (p - Point3::from(q)).norm_squared();
        if d < best.1 {
            best = (i, d);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_mesh::testmesh::tetrahedron;

    #[test]
    fn winding_number_is_one_inside_zero_outside() {
        let m = tetrahedron();
        assert!((winding_number(&m, [0.1, 0.1, 0.1]) - 1.0).abs() < 1e-9);
        assert!(winding_number(&m, [1.0, 1.0, 1.0]).abs() < 1e-9);
    }

    #[test]
    fn crossing_triangles_intersect_and_separated_ones_do_not() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let b = [[0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.8, -0.5, 0.0]];
        assert!(triangles_intersect(a, b));
        let c = [[0.2, 0.2, 0.1], [0.3, 0.2, 0.5], [0.2, 0.3, 0.5]];
        assert!(!triangles_intersect(a, c));
    }
}
