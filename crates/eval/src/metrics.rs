//! Evaluation (DESIGN.md, Metrics): geodesic error normalised by √area(target), its mean and
//! cumulative curve, the paper's Table 1 row, and the flip rate.
//!
//! # Geodesics used
//! `g(q, q*)` is the shortest path along mesh edges (Dijkstra, the paper's eq. 5–6 — what the
//! paper's own evaluation and selection use), computed by a search from `q` that **stops as soon
//! as `q*` is settled**: a match with error `e` explores only the disc of radius `e` around
//! `q`, so evaluating 13k dense matches costs about as much as a few full Dijkstra runs. Edge
//! paths overestimate true geodesics by a few percent on irregular triangulations (zig-zag);
//! this bias is the same for every method evaluated with this code.
//!
//! The search is symcorr-spectral's [`EdgeGraph::search`] (the one owner of edge-graph
//! geodesics; whole distance rows would cost `V log V` per match); evaluation never feeds the
//! matching itself.
//!
//! A flip is a match lying strictly closer to `mirror(q*)` than to `q*`; the same search
//! detects it (`mirror(q*)` settled before `q*`). Only matches where `g(q*, mirror(q*)) >
//! 0.1·√area` are counted — a second search from `q*` bounded by that radius decides it.
//! Vertices unreachable from each other (another connected component) get the Euclidean
//! distance instead.

use nalgebra::{distance, Point3};
use rayon::prelude::*;
use symcorr_mesh::TriMesh;
use symcorr_spectral::{DijkstraScratch, EdgeGraph};

/// The relative radius under which a vertex and its mirror image are too close for a flip to
/// be counted (DESIGN.md, Metrics: 0.1·√area).
pub const FLIP_MIN_SEPARATION: f64 = 0.1;

/// Mesh edges as a weighted graph (symcorr-spectral's [`EdgeGraph`]: CSR, Euclidean edge
/// lengths) with the vertex positions for the Euclidean fallback.
#[derive(Debug, Clone)]
pub struct EvalGraph {
    graph: EdgeGraph,
    positions: Vec<[f64; 3]>,
}

impl EvalGraph {
    /// The edge graph of `mesh`.
    pub fn new(mesh: &TriMesh) -> EvalGraph {
        EvalGraph {
            graph: EdgeGraph::new(mesh),
            positions: mesh.positions.clone(),
        }
    }

    fn euclid(&self, a: u32, b: u32) -> f64 {
        distance(
            &Point3::from(self.positions[a as usize]),
            &Point3::from(self.positions[b as usize]),
        )
    }

    /// Dijkstra from `source` ([`EdgeGraph::search`]); `visit(v, d)` is called as each vertex
    /// is settled, in order of distance, and returns false to stop. Stops by itself beyond
    /// `radius`.
    ///
    /// Panics if `source` is not a vertex of the graph (as indexing the positions with it
    /// would): the public entry points document this.
    fn search(
        &self,
        s: &mut DijkstraScratch,
        source: u32,
        radius: f64,
        visit: impl FnMut(u32, f64) -> bool,
    ) {
        let n = self.positions.len();
        assert!(
            (source as usize) < n,
            "vertex {source} out of range (the mesh has {n} vertices)"
        );
        // Invariant: source checked above and every scratch is made for this graph.
        self.graph
            .search(s, source, radius, visit)
            .expect("source in range, scratch sized for this graph");
    }

    /// Edge-path geodesic distance between `a` and `b` (Euclidean if unreachable). Panics if
    /// `a` or `b` is not a vertex.
    ///
    /// ```
    /// use symcorr_mesh::TriMesh;
    /// use symcorr_eval::EvalGraph;
    /// let m = TriMesh::new(vec![[0.0; 3], [3.0, 0.0, 0.0], [3.0, 4.0, 0.0]], vec![[0, 1, 2]]).unwrap();
    /// assert_eq!(EvalGraph::new(&m).distance(0, 2), 5.0);
    /// ```
    pub fn distance(&self, a: u32, b: u32) -> f64 {
        let mut s = DijkstraScratch::new(&self.graph);
        let mut out = None;
        self.search(&mut s, a, f64::INFINITY, |v, d| {
            if v == b {
                out = Some(d);
                false
            } else {
                true
            }
        });
        out.unwrap_or_else(|| self.euclid(a, b))
    }
}

/// Per-match evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// `g(q, q*) / √area(target)` per match, in the order given.
    pub errors: Vec<f64>,
    /// Per match: `None` when the flip is not counted (no mirror map, or `q*` within
    /// 0.1·√area of its mirror image), else whether the match is a flip.
    pub flips: Vec<Option<bool>>,
    /// √area of the target.
    pub sqrt_area: f64,
}

impl Evaluation {
    /// Mean normalised error (0 without matches).
    pub fn mean_error(&self) -> f64 {
        mean(&self.errors)
    }

    /// Fraction of counted matches that are flips (`None` if none counted).
    pub fn flip_rate(&self) -> Option<f64> {
        let counted = self.flips.iter().filter(|f| f.is_some()).count();
        (counted > 0).then(|| {
            self.flips.iter().filter(|f| **f == Some(true)).count() as f64 / counted as f64
        })
    }

    /// Number of matches counted for the flip rate, and the flips among them.
    pub fn flip_counts(&self) -> (usize, usize) {
        (
            self.flips.iter().filter(|f| f.is_some()).count(),
            self.flips.iter().filter(|f| **f == Some(true)).count(),
        )
    }

    /// Fraction of matches with error `≤ x`.
    pub fn within(&self, x: f64) -> f64 {
        within(&self.errors, x)
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Fraction of `errors` that are `≤ x` (0 for an empty list).
pub fn within(errors: &[f64], x: f64) -> f64 {
    if errors.is_empty() {
        return 0.0;
    }
    errors.iter().filter(|&&e| e <= x).count() as f64 / errors.len() as f64
}

/// Evaluates matches `(template vertex, target vertex)` against ground truth
/// (`truth(template vertex) = q*`, a target vertex), with an optional `mirror` map of the
/// target (`mirror[v]` = the vertex mirror-symmetric to `v`). Runs in parallel (rayon).
/// Panics if a match, truth or mirror vertex is not a vertex of `graph`.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_eval::{evaluate, EvalGraph};
/// let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
/// let g = EvalGraph::new(&m);
/// let e = evaluate(&g, m.total_area(), &[(0, 0), (1, 0)], |p| p, None);
/// assert_eq!(e.errors[0], 0.0);
/// assert!((e.errors[1] - 1.0 / 0.5f64.sqrt()).abs() < 1e-12);
/// ```
pub fn evaluate(
    graph: &EvalGraph,
    target_area: f64,
    matches: &[(u32, u32)],
    truth: impl Fn(u32) -> u32 + Sync,
    mirror: Option<&[u32]>,
) -> Evaluation {
    let sqrt_area = target_area.sqrt();
    let sep = FLIP_MIN_SEPARATION * sqrt_area;
    let results: Vec<(f64, Option<bool>)> = matches
        .par_iter()
        .map_init(
            || DijkstraScratch::new(&graph.graph),
            |s, &(p, q)| {
                let qs = truth(p);
                let m = mirror.map(|m| m[qs as usize]);
                // Is the flip counted? g(q*, m(q*)) > 0.1·√area.
                let counted = m.is_some_and(|m| {
                    let mut near = false;
                    graph.search(s, qs, sep, |v, _| {
                        near = v == m;
                        !near
                    });
                    !near
                });
                let mut d_true = None;
                let mut mirror_first = false;
                graph.search(s, q, f64::INFINITY, |v, d| {
                    if v == qs {
                        d_true = Some(d);
                        return false;
                    }
                    if Some(v) == m {
                        mirror_first = true;
                    }
                    true
                });
                let g = d_true.unwrap_or_else(|| graph.euclid(q, qs));
                let flip = counted.then(|| {
                    // Unreachable q*: decide by Euclidean distances.
                    if d_true.is_none() {
                        m.is_some_and(|m| graph.euclid(q, m) < g)
                    } else {
                        mirror_first
                    }
                });
                (g / sqrt_area, flip)
            },
        )
        .collect();
    let (errors, flips) = results.into_iter().unzip();
    Evaluation {
        errors,
        flips,
        sqrt_area,
    }
}

/// Geodesic errors of matches that are points on a surface rather than vertices, normalised
/// by `√area`: per `(source, corners, weights)` the point `x = Σ wᵢ·corners[i]` of a triangle
/// of `graph`'s mesh, and its error `min_i (‖x − cornerᵢ‖ + g(cornerᵢ, source))` — the
/// shortest path that leaves `x` straight to a corner, then follows the edges ([`evaluate`]'s
/// geodesic, which is what a surface point at a corner reduces to: weights `[1, 0, 0]` give
/// `g(corner, source)`). `source` is the true point. Runs in parallel (rayon). Panics if a
/// vertex is not a vertex of `graph`.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_eval::{surface_errors, EvalGraph};
/// let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
/// let g = EvalGraph::new(&m);
/// let area = m.total_area(); // 0.5
/// // Halfway along edge 0–1, truth at vertex 0: 0.5 away.
/// let e = surface_errors(&g, area, &[(0, [0, 1, 2], [0.5, 0.5, 0.0]), (0, [1, 0, 2], [1.0, 0.0, 0.0])]);
/// assert!((e[0] - 0.5 / area.sqrt()).abs() < 1e-12);
/// assert!((e[1] - 1.0 / area.sqrt()).abs() < 1e-12); // a corner: the edge path
/// ```
pub fn surface_errors(
    graph: &EvalGraph,
    area: f64,
    points: &[(u32, [u32; 3], [f64; 3])],
) -> Vec<f64> {
    let sqrt_area = area.sqrt();
    points
        .par_iter()
        .map_init(
            || DijkstraScratch::new(&graph.graph),
            |s, &(source, corners, weights)| {
                let at = |v: u32| nalgebra::Vector3::from(graph.positions[v as usize]);
                let x: nalgebra::Vector3<f64> =
                    corners.iter().zip(weights).map(|(&c, w)| at(c) * w).sum();
                let straight = corners.map(|c| (at(c) - x).norm());
                // Settle the corners in order of distance from the true point; a corner
                // farther along the edges than the best path so far cannot improve it.
                let mut best = f64::INFINITY;
                let mut found = [false; 3];
                let mut pruned = false;
                graph.search(s, source, f64::INFINITY, |v, d| {
                    if d >= best {
                        pruned = true;
                        return false;
                    }
                    for k in 0..3 {
                        if corners[k] == v {
                            found[k] = true;
                            best = best.min(straight[k] + d);
                        }
                    }
                    !found.iter().all(|&f| f)
                });
                // Corners a whole search never reached (another component): straight lines.
                for k in (0..3).filter(|&k| !found[k] && !pruned) {
                    best = best.min(straight[k] + graph.euclid(corners[k], source));
                }
                best / sqrt_area
            },
        )
        .collect()
}

/// The cumulative error curve: for each of `steps + 1` evenly spaced `x` in `[0, max]`, the
/// fraction of errors `≤ x` (the paper's plots use `max = 0.25`).
pub fn cumulative_curve(errors: &[f64], max: f64, steps: usize) -> Vec<(f64, f64)> {
    let mut sorted = errors.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len().max(1) as f64;
    (0..=steps)
        .map(|i| {
            let x = max * i as f64 / steps.max(1) as f64;
            let c = sorted.partition_point(|&e| e <= x);
            (x, c as f64 / n)
        })
        .collect()
}

/// The paper's Table 1 row: the mean error of the best 10 %, 20 %, …, 100 % of the matches
/// ranked by confidence (highest first). `errors[i]` and `confidence[i]` belong to match `i`.
/// Each bucket holds `⌈k·n/10⌉` matches (at least one); all zero without matches.
///
/// ```
/// let row = symcorr_eval::table1_row(&[0.3, 0.1], &[0.2, 0.9]);
/// assert_eq!(row[0], 0.1);
/// assert!((row[9] - 0.2).abs() < 1e-12);
/// ```
pub fn table1_row(errors: &[f64], confidence: &[f64]) -> [f64; 10] {
    let mut order: Vec<usize> = (0..errors.len()).collect();
    order.sort_by(|&a, &b| confidence[b].total_cmp(&confidence[a]));
    let mut row = [0.0; 10];
    if errors.is_empty() {
        return row;
    }
    let n = errors.len();
    for (k, r) in row.iter_mut().enumerate() {
        let take = ((k + 1) * n).div_ceil(10).max(1);
        *r = order[..take].iter().map(|&i| errors[i]).sum::<f64>() / take as f64;
    }
    row
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat `w × h` grid of unit squares (two triangles each) in the z = 0 plane.
    fn grid(w: usize, h: usize) -> TriMesh {
        symcorr_mesh::testmesh::grid(w, h, [1.0, 1.0])
    }

    #[test]
    fn grid_distances_are_edge_paths() {
        let m = grid(10, 4);
        let g = EvalGraph::new(&m);
        // Along an axis: exact. Along the diagonals present in the triangulation: exact.
        assert!((g.distance(0, 10) - 10.0).abs() < 1e-12);
        assert!((g.distance(0, 4 * 11 + 4) - 4.0 * 2f64.sqrt()).abs() < 1e-12);
        // Against the diagonals: an L-shaped path.
        assert!((g.distance(10, 4 * 11 + 6) - (4.0 * 2f64.sqrt())).abs() > 0.1);
        // Symmetric, and never shorter than Euclidean.
        for (a, b) in [(3u32, 50u32), (17, 40), (0, 54)] {
            let d = g.distance(a, b);
            assert!((d - g.distance(b, a)).abs() < 1e-12);
            assert!(d + 1e-12 >= g.euclid(a, b));
        }
    }

    #[test]
    fn surface_errors_lie_between_the_straight_line_and_every_corner_path() {
        // On a plane: never shorter than the straight line to the true point, never longer
        // than the path through any one corner (computed here with `EvalGraph::distance`, a
        // whole search), equal to the vertex error at a corner.
        let m = grid(12, 9);
        let g = EvalGraph::new(&m);
        let sqrt_area = m.total_area().sqrt();
        let mut points = Vec::new();
        for (k, tri) in m.triangles.iter().enumerate().step_by(7) {
            let source = (k * 31 % m.num_vertices()) as u32;
            let a = (k % 5) as f64 / 5.0;
            let b = (1.0 - a) * ((k % 3) as f64 / 3.0);
            points.push((source, *tri, [a, b, 1.0 - a - b]));
            points.push((source, *tri, [1.0, 0.0, 0.0]));
        }
        let e = surface_errors(&g, m.total_area(), &points);
        for (&(source, corners, w), &err) in points.iter().zip(&e) {
            let at = |v: u32| nalgebra::Vector3::from(m.positions[v as usize]);
            let x: nalgebra::Vector3<f64> = corners.iter().zip(w).map(|(&c, w)| at(c) * w).sum();
            let err = err * sqrt_area;
            assert!(err + 1e-12 >= (x - at(source)).norm(), "{err}");
            let through: Vec<f64> = corners
                .iter()
                .map(|&c| (x - at(c)).norm() + g.distance(c, source))
                .collect();
            assert!(
                through.iter().all(|&t| err <= t + 1e-12),
                "{err} {through:?}"
            );
            assert!(through.iter().any(|&t| (err - t).abs() < 1e-12));
            if w == [1.0, 0.0, 0.0] {
                assert!((err - g.distance(corners[0], source)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn errors_and_flips_on_a_mirrored_strip() {
        // 21 × 1 strip, mirror x ↦ 20 − x.
        let m = grid(20, 1);
        let g = EvalGraph::new(&m);
        let area = m.total_area();
        let mirror: Vec<u32> = (0..m.num_vertices() as u32)
            .map(|v| {
                let (i, j) = (v % 21, v / 21);
                j * 21 + (20 - i)
            })
            .collect();
        // Template vertex v's truth is v itself. Match 2 → 18 is a flip; 2 → 4 is not;
        // 10 → 11 sits on the mirror line (not counted).
        let matches = [(2u32, 18u32), (2, 4), (10, 11), (5, 5)];
        let e = evaluate(&g, area, &matches, |p| p, Some(&mirror));
        let s = area.sqrt();
        assert!((e.errors[0] - 16.0 / s).abs() < 1e-12);
        assert!((e.errors[1] - 2.0 / s).abs() < 1e-12);
        assert_eq!(e.errors[3], 0.0);
        assert_eq!(e.flips, vec![Some(true), Some(false), None, Some(false)]);
        assert_eq!(e.flip_rate(), Some(1.0 / 3.0));
        assert_eq!(e.flip_counts(), (3, 1));
        // Without a mirror map nothing is counted.
        assert_eq!(evaluate(&g, area, &matches, |p| p, None).flip_rate(), None);
    }

    #[test]
    fn curve_and_table_row() {
        let errors = [0.0, 0.05, 0.1, 0.2, 0.3];
        let c = cumulative_curve(&errors, 0.25, 5);
        assert_eq!(c.len(), 6);
        assert_eq!(c[0], (0.0, 0.2));
        assert!((c[5].1 - 0.8).abs() < 1e-12);
        for w in c.windows(2) {
            assert!(w[0].1 <= w[1].1);
        }
        // Confidence ranks the errors in reverse: best 20 % = the smallest one.
        let conf = [5.0, 4.0, 3.0, 2.0, 1.0];
        let row = table1_row(&errors, &conf);
        assert_eq!(row[0], 0.0);
        assert_eq!(row[1], 0.0);
        assert!((row[9] - 0.13).abs() < 1e-12);
        for w in row.windows(2) {
            assert!(w[0] <= w[1] + 1e-15);
        }
        assert_eq!(within(&errors, 0.1), 0.6);
    }
}
