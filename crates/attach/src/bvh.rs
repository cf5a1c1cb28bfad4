//! A small bounding-volume hierarchy over a mesh's triangles, for the visibility test of bone
//! heat (Baran & Popović 2007, §4: a bone is visible from a vertex when the segment between them
//! crosses no triangle).

use symcorr_mesh::TriMesh;

/// Triangles per leaf.
const LEAF: usize = 4;

#[derive(Debug, Clone)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: `start..start+count` into `order`; inner: `count == 0`, children `start`, `start+1`.
    start: usize,
    count: usize,
}

/// Triangle BVH (median split on the longest centroid axis).
#[derive(Debug, Clone)]
pub(crate) struct TriangleBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[[f64; 3]; 3]>,
    ids: Vec<[u32; 3]>,
}

fn bounds(tris: &[[[f64; 3]; 3]], idx: &[u32]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &t in idx {
        for p in &tris[t as usize] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo, hi)
}

impl TriangleBvh {
    /// Builds the hierarchy over every triangle of `mesh`.
    pub(crate) fn new(mesh: &TriMesh) -> Self {
        let tris: Vec<[[f64; 3]; 3]> = (0..mesh.num_triangles()).map(|t| mesh.corners(t)).collect();
        let centroids: Vec<[f64; 3]> = tris
            .iter()
            .map(|c| {
                [
                    (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                    (c[0][1] + c[1][1] + c[2][1]) / 3.0,
                    (c[0][2] + c[1][2] + c[2][2]) / 3.0,
                ]
            })
            .collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        // Iterative build: (node index, start, end).
        nodes.push(Node {
            lo: [0.0; 3],
            hi: [0.0; 3],
            start: 0,
            count: 0,
        });
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((ni, s, e)) = stack.pop() {
            let (lo, hi) = bounds(&tris, &order[s..e]);
            nodes[ni].lo = lo;
            nodes[ni].hi = hi;
            if e - s <= LEAF {
                nodes[ni].start = s;
                nodes[ni].count = e - s;
                continue;
            }
            let mut clo = [f64::INFINITY; 3];
            let mut chi = [f64::NEG_INFINITY; 3];
            for &t in &order[s..e] {
                let c = centroids[t as usize];
                for k in 0..3 {
                    clo[k] = clo[k].min(c[k]);
                    chi[k] = chi[k].max(c[k]);
                }
            }
            let axis = (0..3)
                .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
                .unwrap_or(0);
            let mid = (s + e) / 2;
            order[s..e].select_nth_unstable_by(mid - s, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            let left = nodes.len();
            for _ in 0..2 {
                nodes.push(Node {
                    lo: [0.0; 3],
                    hi: [0.0; 3],
                    start: 0,
                    count: 0,
                });
            }
            nodes[ni].start = left;
            nodes[ni].count = 0;
            stack.push((left, s, mid));
            stack.push((left + 1, mid, e));
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
    pub(crate) fn segment_blocked(&self, a: [f64; 3], b: [f64; 3], skip_vertex: u32) -> bool {
        if self.nodes.is_empty() || self.tris.is_empty() {
            return false;
        }
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let inv = d.map(|x| if x != 0.0 { 1.0 / x } else { f64::INFINITY });
        let mut stack = Vec::with_capacity(64);
        stack.push(0usize);
        while let Some(ni) = stack.pop() {
            let n = &self.nodes[ni];
            if !slab_hit(a, inv, d, n.lo, n.hi) {
                continue;
            }
            if n.count > 0 {
                for &t in &self.order[n.start..n.start + n.count] {
                    if self.ids[t as usize].contains(&skip_vertex) {
                        continue;
                    }
                    if segment_triangle(a, d, &self.tris[t as usize]) {
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
fn slab_hit(a: [f64; 3], inv: [f64; 3], d: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> bool {
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
fn segment_triangle(a: [f64; 3], d: [f64; 3], tri: &[[f64; 3]; 3]) -> bool {
    use symcorr_mesh::geometry::{cross, dot, sub};
    let e1 = sub(tri[1], tri[0]);
    let e2 = sub(tri[2], tri[0]);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-300 {
        return false;
    }
    let inv = 1.0 / det;
    let s = sub(a, tri[0]);
    let u = dot(s, p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = dot(e2, q) * inv;
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
        // Outside → inside crosses a face.
        assert!(bvh.segment_blocked([0.5, 0.5, -1.0], [0.5, 0.5, 0.5], u32::MAX));
        // Entirely inside: nothing crossed.
        assert!(!bvh.segment_blocked([0.2, 0.5, 0.5], [0.8, 0.5, 0.5], u32::MAX));
        // From a corner vertex to the centre: only its own incident faces touch it.
        assert!(!bvh.segment_blocked(m.positions[0], [0.5, 0.5, 0.5], 0));
        // From a corner vertex through the cube to the far outside: blocked by the far faces.
        assert!(bvh.segment_blocked(m.positions[0], [2.0, 2.0, 2.0], 0));
        // Entirely outside and missing the cube.
        assert!(!bvh.segment_blocked([2.0, 0.0, 0.0], [2.0, 1.0, 1.0], u32::MAX));
    }
}
