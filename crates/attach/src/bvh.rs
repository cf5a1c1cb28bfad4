//! A small bounding-volume hierarchy over a mesh's triangles, for the visibility test of bone
//! heat (Baran & Popović 2007, §4: a bone is visible from a vertex when the segment between them
//! crosses no triangle).

use nalgebra::{Point3, Vector3};
use symcorr_mesh::TriMesh;

/// Triangles per leaf.
const LEAF: usize = 4;

#[derive(Debug, Clone)]
struct Node {
    lo: Point3<f64>,
    hi: Point3<f64>,
    /// Leaf: `start..start+count` into `order`; inner: `count == 0`, children `start`, `start+1`.
    start: usize,
    count: usize,
}

/// Triangle BVH (median split on the longest centroid axis).
#[derive(Debug, Clone)]
pub(crate) struct TriangleBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[Point3<f64>; 3]>,
    ids: Vec<[u32; 3]>,
}

fn bounds<'a>(points: impl Iterator<Item = &'a Point3<f64>>) -> (Point3<f64>, Point3<f64>) {
    let mut lo = Point3::from([f64::INFINITY; 3]);
    let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

impl TriangleBvh {
    /// Builds the hierarchy over every triangle of `mesh`.
    pub(crate) fn new(mesh: &TriMesh) -> Self {
        let tris: Vec<[Point3<f64>; 3]> = (0..mesh.num_triangles())
            .map(|t| mesh.corners(t).map(Point3::from))
            .collect();
        let centroids: Vec<Point3<f64>> = tris
            .iter()
            .map(|c| Point3::from((c[0].coords + c[1].coords + c[2].coords) / 3.0))
            .collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        // Iterative build: (node index, start, end).
        nodes.push(Node {
            lo: Point3::origin(),
            hi: Point3::origin(),
            start: 0,
            count: 0,
        });
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((ni, s, e)) = stack.pop() {
            if e - s <= LEAF {
                nodes[ni].start = s;
                nodes[ni].count = e - s;
                continue;
            }
            let (clo, chi) = bounds(order[s..e].iter().map(|&t| &centroids[t as usize]));
            let span = chi - clo;
            let axis = (0..3)
                .max_by(|&a, &b| span[a].total_cmp(&span[b]))
                .unwrap_or(0);
            let mid = (s + e) / 2;
            order[s..e].select_nth_unstable_by(mid - s, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            let left = nodes.len();
            for _ in 0..2 {
                nodes.push(Node {
                    lo: Point3::origin(),
                    hi: Point3::origin(),
                    start: 0,
                    count: 0,
                });
            }
            nodes[ni].start = left;
            nodes[ni].count = 0;
            stack.push((left, s, mid));
            stack.push((left + 1, mid, e));
        }
        // Boxes bottom-up (children come after their parent): a leaf's from its triangles,
        // an inner node's from its children's — each triangle read once, not once per level.
        for ni in (0..nodes.len()).rev() {
            let n = &nodes[ni];
            // An inner node's children follow the root (`start > 0`); only an empty mesh's
            // root is a leaf without triangles.
            let (lo, hi) = if n.count > 0 || n.start == 0 {
                bounds(
                    order[n.start..n.start + n.count]
                        .iter()
                        .flat_map(|&t| &tris[t as usize]),
                )
            } else {
                let (a, b) = (&nodes[n.start], &nodes[n.start + 1]);
                (a.lo.inf(&b.lo), a.hi.sup(&b.hi))
            };
            nodes[ni].lo = lo;
            nodes[ni].hi = hi;
        }
        TriangleBvh {
            nodes,
            order,
            tris,
            ids: mesh.triangles.clone(),
        }
    }

    /// True if the open segment `a → b` crosses a triangle that does not contain vertex
    /// `skip_vertex` (the segment's own start vertex, whose incident triangles it touches at
    /// `t = 0`).
    pub(crate) fn segment_blocked(
        &self,
        a: &Point3<f64>,
        b: &Point3<f64>,
        skip_vertex: u32,
    ) -> bool {
        if self.nodes.is_empty() || self.tris.is_empty() {
            return false;
        }
        let d = b - a;
        let inv = d.map(|x| if x != 0.0 { 1.0 / x } else { f64::INFINITY });
        let mut stack = Vec::with_capacity(64);
        stack.push(0usize);
        while let Some(ni) = stack.pop() {
            let n = &self.nodes[ni];
            if !slab_hit(a, &inv, &d, &n.lo, &n.hi) {
                continue;
            }
            if n.count > 0 {
                for &t in &self.order[n.start..n.start + n.count] {
                    if self.ids[t as usize].contains(&skip_vertex) {
                        continue;
                    }
                    if segment_triangle(a, &d, &self.tris[t as usize]) {
                        return true;
                    }
                }
            } else {
                stack.push(n.start);
                stack.push(n.start + 1);
            }
        }
        false
    }
}

/// Segment `a + t·d`, `t ∈ [0, 1]`, against an axis-aligned box (slab test).
fn slab_hit(
    a: &Point3<f64>,
    inv: &Vector3<f64>,
    d: &Vector3<f64>,
    lo: &Point3<f64>,
    hi: &Point3<f64>,
) -> bool {
    let mut t0 = 0.0f64;
    let mut t1 = 1.0f64;
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (mut ta, mut tb) = ((lo[k] - a[k]) * inv[k], (hi[k] - a[k]) * inv[k]);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Möller–Trumbore: does `a + t·d` hit the triangle for some `t` in the open interval (0, 1)?
fn segment_triangle(a: &Point3<f64>, d: &Vector3<f64>, tri: &[Point3<f64>; 3]) -> bool {
    let [t0, t1, t2] = tri;
    let e1 = t1 - t0;
    let e2 = t2 - t0;
    let p = d.cross(&e2);
    let det = e1.dot(&p);
    if det.abs() < 1e-300 {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - t0;
    let u = s.dot(&p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(&e1);
    let v = d.dot(&q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = e2.dot(&q) * inv;
    t > 1e-9 && t < 1.0 - 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> TriMesh {
        // Unit cube, 12 triangles.
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let t = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        TriMesh::new(p, t).unwrap()
    }

    #[test]
    fn segments_through_the_cube_are_blocked_and_inside_ones_are_not() {
        let m = cube();
        let bvh = TriangleBvh::new(&m);
        let blocked =
            |a: [f64; 3], b: [f64; 3], skip| bvh.segment_blocked(&a.into(), &b.into(), skip);
        // Outside → inside crosses a face.
        assert!(blocked([0.5, 0.5, -1.0], [0.5, 0.5, 0.5], u32::MAX));
        // Entirely inside: nothing crossed.
        assert!(!blocked([0.2, 0.5, 0.5], [0.8, 0.5, 0.5], u32::MAX));
        // From a corner vertex to the centre: only its own incident faces touch it.
        assert!(!blocked(m.positions[0], [0.5, 0.5, 0.5], 0));
        // From a corner vertex through the cube to the far outside: blocked by the far faces.
        assert!(blocked(m.positions[0], [2.0, 2.0, 2.0], 0));
        // Entirely outside and missing the cube.
        assert!(!blocked([2.0, 0.0, 0.0], [2.0, 1.0, 1.0], u32::MAX));
    }
}
