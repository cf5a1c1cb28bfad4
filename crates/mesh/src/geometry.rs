//! Per-element geometry and connectivity of a [`TriMesh`].

use nalgebra::{Point3, Vector3};

use crate::TriMesh;

/// Fraction of a surface's area that must face the origin, all one way, for the origin to be
/// taken as its camera centre ([`TriMesh::origin_facing_side`]). A depth scan in camera space
/// faces its camera everywhere; a partial mesh in any other frame faces the origin from both
/// sides.
pub const ORIGIN_FACING_FRACTION: f64 = 0.95;

/// How far from the origin, in diagonals of its bounding box, a surface must lie for the origin
/// to be its camera ([`TriMesh::origin_facing_side`]). A depth camera sees a whole body from
/// 1.5–4 m (a diagonal of about 2 m, ratio ≥ 0.7) and a close-up of a torso from 0.5 m (a
/// diagonal of 0.6 m, 0.8); the origin of a body-centred frame lies within its body (≤ 0.1).
pub const CAMERA_STANDOFF: f64 = 0.25;

/// Closest point to `p` on the segment `a–b`, and its distance.
///
/// ```
/// use nalgebra::Point3;
/// use symcorr_mesh::geometry::closest_on_segment;
/// let (q, d) = closest_on_segment(
///     &Point3::new(1.0, 2.0, 0.0),
///     &Point3::origin(),
///     &Point3::new(4.0, 0.0, 0.0),
/// );
/// assert_eq!((q, d), (Point3::new(1.0, 0.0, 0.0), 2.0));
/// ```
#[inline]
pub fn closest_on_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> (Point3<f64>, f64) {
    let ab = b - a;
    let l2 = ab.dot(&ab);
    let t = if l2 > 0.0 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = a + ab * t;
    (q, nalgebra::distance(p, &q))
}

/// Closest point to `p` on the triangle `a b c`, as barycentric weights `[wa, wb, wc]`
/// (non-negative, summing to 1), and its distance.
///
/// Decides which Voronoi region of the triangle `p` projects into — a corner, an edge or the
/// face — from the signs of the dot products of Ericson, *Real-Time Collision Detection*
/// (2005), §5.1.5. A degenerate triangle (zero area) gives the closest point on its longest
/// edge.
///
/// ```
/// use nalgebra::Point3;
/// use symcorr_mesh::geometry::closest_on_triangle;
/// let [a, b, c] = [Point3::origin(), Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)];
/// let (w, d) = closest_on_triangle(&Point3::new(0.25, 0.25, 2.0), &a, &b, &c);
/// assert_eq!((w, d), ([0.5, 0.25, 0.25], 2.0));
/// // Beyond corner b: the corner itself.
/// assert_eq!(closest_on_triangle(&Point3::new(3.0, -1.0, 0.0), &a, &b, &c).0, [0.0, 1.0, 0.0]);
/// ```
pub fn closest_on_triangle(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> ([f64; 3], f64) {
    let weights = closest_weights(p, a, b, c);
    let q = Point3::from(a.coords * weights[0] + b.coords * weights[1] + c.coords * weights[2]);
    (weights, nalgebra::distance(p, &q))
}

/// The barycentric weights of [`closest_on_triangle`].
fn closest_weights(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    if ab.cross(&ac).norm_squared() <= f64::EPSILON * ab.norm_squared() * ac.norm_squared() {
        // Degenerate: the longest edge holds the whole triangle.
        let edges = [(0, 1, a, b), (1, 2, b, c), (0, 2, a, c)];
        let (i, j, u, v) = edges
            .into_iter()
            .max_by(|x, y| {
                (x.3 - x.2)
                    .norm_squared()
                    .total_cmp(&(y.3 - y.2).norm_squared())
            })
            .unwrap_or((0, 1, a, b));
        let uv = v - u;
        let l2 = uv.norm_squared();
        let t = if l2 > 0.0 {
            ((p - u).dot(&uv) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut w = [0.0; 3];
        w[i] = 1.0 - t;
        w[j] = t;
        return w;
    }
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0]; // corner a
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0]; // corner b
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return [1.0 - t, t, 0.0]; // edge ab
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0]; // corner c
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return [1.0 - t, 0.0, t]; // edge ac
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - t, t]; // edge bc
    }
    // Inside the face.
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
}

/// `(b − a) × (c − a)` for the corners of a triangle: twice its area times its unit normal.
#[inline]
fn corner_cross(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Vector3<f64> {
    let a = Point3::from(a);
    (Point3::from(b) - a).cross(&(Point3::from(c) - a))
}

impl TriMesh {
    /// Area of every triangle.
    pub fn triangle_areas(&self) -> Vec<f64> {
        (0..self.num_triangles())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * corner_cross(a, b, c).norm()
            })
            .collect()
    }

    /// Barycentric area of every vertex: a third of the area of each triangle it is a corner
    /// of (the lumped mass of a P1 finite-element mesh). Sums to [`TriMesh::total_area`].
    ///
    /// ```
    /// use symcorr_mesh::TriMesh;
    /// let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
    /// assert!(m.vertex_areas().iter().all(|&a| (a - 1.0 / 6.0).abs() < 1e-15));
    /// ```
    pub fn vertex_areas(&self) -> Vec<f64> {
        let mut a = vec![0.0; self.num_vertices()];
        for (t, area) in self.triangles.iter().zip(self.triangle_areas()) {
            for &v in t {
                a[v as usize] += area / 3.0;
            }
        }
        a
    }

    /// Total surface area.
    pub fn total_area(&self) -> f64 {
        self.triangle_areas().iter().sum()
    }

    /// Unit normal of every triangle (zero vector for a zero-area triangle).
    pub fn triangle_normals(&self) -> Vec<[f64; 3]> {
        (0..self.num_triangles())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                let n = corner_cross(a, b, c);
                let l = n.norm();
                // Component-wise division, as `normalize` does.
                if l > 0.0 {
                    (n / l).into()
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    }

    /// The side of a camera-space depth scan that faces its camera, the origin: `Some(1.0)` when
    /// at least [`ORIGIN_FACING_FRACTION`] of the surface faces the origin along the triangles'
    /// winding normals, `Some(-1.0)` when that much faces it against them, `None` otherwise
    /// (a closed body, or a partial view in any other frame, faces the origin from both sides).
    /// A depth scan faces its camera everywhere: its triangles come from one depth image.
    /// Each triangle counts by its area times its distance along the line of sight; over one
    /// scan's depth range that is near even. The camera also stands off the surface: no vertex
    /// nearer the origin than [`CAMERA_STANDOFF`] × the diagonal of the mesh's bounding box
    /// (the front half of a body in a frame centred on the body faces the origin from behind,
    /// all one way too, and is no depth scan).
    ///
    /// ```
    /// use symcorr_mesh::TriMesh;
    /// // A square 2 m in front of the origin, wound towards it.
    /// let square = TriMesh::new(
    ///     vec![[0.0, 0.0, 2.0], [0.0, 1.0, 2.0], [1.0, 1.0, 2.0], [1.0, 0.0, 2.0]],
    ///     vec![[0, 1, 2], [0, 2, 3]],
    /// )?;
    /// assert_eq!(square.origin_facing_side(), Some(1.0));
    /// let mut turned = square.clone();
    /// turned.triangles = vec![[0, 2, 1], [0, 3, 2]];
    /// assert_eq!(turned.origin_facing_side(), Some(-1.0));
    /// // The same square 0.2 m from the origin: no camera stands that close to what it sees.
    /// let mut close = square.clone();
    /// close.positions.iter_mut().for_each(|p| p[2] = 0.2);
    /// assert_eq!(close.origin_facing_side(), None);
    /// # Ok::<(), symcorr_mesh::MeshError>(())
    /// ```
    pub fn origin_facing_side(&self) -> Option<f64> {
        let (mut towards, mut away) = (0.0, 0.0);
        for t in 0..self.num_triangles() {
            let [a, b, c] = self.corners(t);
            // Twice the area along the normal, against the direction from the origin.
            let facing = corner_cross(a, b, c)
                .dot(&(Vector3::from(a) + Vector3::from(b) + Vector3::from(c)));
            if facing < 0.0 {
                towards -= facing;
            } else {
                away += facing;
            }
        }
        let (lo, hi) = self.bounding_box();
        let diagonal = (Vector3::from(hi) - Vector3::from(lo)).norm();
        let nearest = self
            .positions
            .iter()
            .map(|&p| Vector3::from(p).norm())
            .fold(f64::INFINITY, f64::min);
        let stands_off = nearest >= CAMERA_STANDOFF * diagonal;
        if !stands_off {
            return None;
        }
        let total = towards + away;
        if total > 0.0 && towards >= ORIGIN_FACING_FRACTION * total {
            Some(1.0)
        } else if total > 0.0 && away >= ORIGIN_FACING_FRACTION * total {
            Some(-1.0)
        } else {
            None
        }
    }

    /// Area-weighted unit vertex normals (zero vector for an isolated vertex).
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        let mut acc = vec![Vector3::zeros(); self.num_vertices()];
        for t in 0..self.num_triangles() {
            let [a, b, c] = self.corners(t);
            let n = corner_cross(a, b, c);
            for &v in &self.triangles[t] {
                acc[v as usize] += n;
            }
        }
        acc.into_iter()
            .map(|n| {
                let l = n.norm();
                if l > 0.0 {
                    (n / l).into()
                } else {
                    n.into()
                }
            })
            .collect()
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Unique undirected edges `(i, j)` with `i < j`, sorted.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        // Bucketed by the smaller end (a counting sort), each short bucket sorted and
        // deduplicated: linear in the triangles, where one sort of every half-edge was a
        // visible share of each recorded frame (edge graphs, Laplacians). Same order.
        let ends = |t: &[u32; 3]| {
            [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(a, b)| (a.min(b), a.max(b)))
        };
        let n = self
            .triangles
            .iter()
            .flatten()
            .map(|&v| v as usize + 1)
            .max()
            .unwrap_or(0);
        let mut start = vec![0usize; n + 1];
        for t in &self.triangles {
            for (a, _) in ends(t) {
                start[a as usize + 1] += 1;
            }
        }
        for a in 0..n {
            start[a + 1] += start[a];
        }
        let mut fill = start.clone();
        let mut upper = vec![0u32; start[n]];
        for t in &self.triangles {
            for (a, b) in ends(t) {
                upper[fill[a as usize]] = b;
                fill[a as usize] += 1;
            }
        }
        let mut e = Vec::with_capacity(upper.len() / 2 + 1);
        for a in 0..n {
            let bucket = &mut upper[start[a]..start[a + 1]];
            bucket.sort_unstable();
            let mut previous = None;
            for &b in bucket.iter() {
                if previous != Some(b) {
                    e.push([a as u32, b]);
                    previous = Some(b);
                }
            }
        }
        e
    }

    /// For every vertex, its neighbouring vertices (sorted, unique).
    pub fn vertex_neighbors(&self) -> Vec<Vec<u32>> {
        let mut adj = vec![Vec::new(); self.num_vertices()];
        for [a, b] in self.edges() {
            adj[a as usize].push(b);
            adj[b as usize].push(a);
        }
        for a in &mut adj {
            a.sort_unstable();
        }
        adj
    }

    /// For every vertex, the triangles that contain it (ascending).
    pub fn vertex_triangles(&self) -> Vec<Vec<u32>> {
        let mut vt = vec![Vec::new(); self.num_vertices()];
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                vt[v as usize].push(t as u32);
            }
        }
        vt
    }

    /// The mesh restricted to the vertices with `keep[v]` (and the triangles whose corners are
    /// all kept), with `map[new] = old`. `keep` must have one entry per vertex.
    ///
    /// ```
    /// let m = symcorr_mesh::testmesh::tetrahedron();
    /// let (sub, map) = m.submesh(&[true, true, true, false]).unwrap();
    /// assert_eq!((sub.num_vertices(), sub.num_triangles()), (3, 1));
    /// assert_eq!(map, vec![0, 1, 2]);
    /// ```
    pub fn submesh(&self, keep: &[bool]) -> Result<(TriMesh, Vec<u32>), crate::MeshError> {
        let n = self.num_vertices();
        let mut new_id = vec![u32::MAX; n];
        let mut map = Vec::new();
        for v in (0..n).filter(|&v| keep.get(v).copied().unwrap_or(false)) {
            new_id[v] = map.len() as u32;
            map.push(v as u32);
        }
        let triangles = self
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&v| new_id[v as usize] != u32::MAX))
            .map(|t| t.map(|v| new_id[v as usize]))
            .collect();
        let positions = map.iter().map(|&v| self.positions[v as usize]).collect();
        Ok((TriMesh::new(positions, triangles)?, map))
    }

    /// Connected components over triangles: `(component id per vertex, number of components)`.
    /// Isolated vertices (in no triangle) each form their own component.
    pub fn connected_components(&self) -> (Vec<u32>, usize) {
        let n = self.num_vertices();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        for t in &self.triangles {
            for k in 1..3 {
                let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let mut id = vec![u32::MAX; n];
        let mut comp = vec![0u32; n];
        let mut count = 0u32;
        for (v, c) in comp.iter_mut().enumerate() {
            let r = find(&mut parent, v as u32) as usize;
            if id[r] == u32::MAX {
                id[r] = count;
                count += 1;
            }
            *c = id[r];
        }
        (comp, count as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::tetrahedron;

    #[test]
    fn tetra_area_edges_components() {
        let m = tetrahedron();
        let expected = 1.5 + 3f64.sqrt() / 2.0;
        assert!((m.total_area() - expected).abs() < 1e-12);
        assert_eq!(m.edges().len(), 6);
        assert_eq!(m.connected_components().1, 1);
        assert!(m.vertex_neighbors().iter().all(|n| n.len() == 3));
    }

    #[test]
    fn edges_are_every_sorted_unique_pair_of_a_triangle() {
        // Shared edges, a repeated triangle, both windings and a vertex in no triangle.
        let triangles = vec![
            [0, 1, 2],
            [2, 1, 3],
            [3, 1, 2],
            [0, 1, 2],
            [5, 4, 0],
            [4, 5, 3],
        ];
        let m = TriMesh {
            positions: vec![[0.0; 3]; 7],
            triangles,
        };
        let mut expected: Vec<[u32; 2]> = m
            .triangles
            .iter()
            .flat_map(|t| {
                [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(a, b)| [a.min(b), a.max(b)])
            })
            .collect();
        expected.sort_unstable();
        expected.dedup();
        assert_eq!(m.edges(), expected);
        assert!(TriMesh {
            positions: Vec::new(),
            triangles: Vec::new()
        }
        .edges()
        .is_empty());
    }

    #[test]
    fn outward_normals_on_tetra() {
        let m = tetrahedron();
        let c = Point3::new(0.25, 0.25, 0.25);
        for (t, n) in m.triangle_normals().iter().enumerate() {
            let p = Point3::from(m.corners(t)[0]);
            assert!(
                Vector3::from(*n).dot(&(p - c)) > 0.0,
                "triangle {t} faces inward"
            );
        }
    }
}
