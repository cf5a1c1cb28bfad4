//! Geodesic distances: Dijkstra over mesh edges (the paper's eq. 5–6) and the heat method
//! (Crane, Weischedel, Wardetzky 2013).

use crate::laplacian::cot;
use crate::{Laplacian, SpectralError, SystemFactor};
use faer::Mat;
use nalgebra::{distance, Point3, Vector3};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use symcorr_mesh::TriMesh;

/// The edge graph of a mesh (CSR adjacency with Euclidean edge lengths), built once and
/// reused by every Dijkstra run.
#[derive(Debug, Clone)]
pub struct EdgeGraph {
    offsets: Vec<usize>,
    targets: Vec<u32>,
    lengths: Vec<f64>,
}

impl EdgeGraph {
    /// Builds the graph of `mesh`'s undirected edges weighted by Euclidean length.
    pub fn new(mesh: &TriMesh) -> EdgeGraph {
        let n = mesh.num_vertices();
        let nb = mesh.vertex_neighbors();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut targets = Vec::new();
        let mut lengths = Vec::new();
        offsets.push(0);
        for (v, list) in nb.iter().enumerate() {
            for &u in list {
                targets.push(u);
                lengths.push(distance(
                    &Point3::from(mesh.positions[u as usize]),
                    &Point3::from(mesh.positions[v]),
                ));
            }
            offsets.push(targets.len());
        }
        EdgeGraph {
            offsets,
            targets,
            lengths,
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True for a graph without vertices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn check(&self, sources: &[u32]) -> Result<(), SpectralError> {
        if let Some(&s) = sources.iter().find(|&&s| s as usize >= self.len()) {
            return Err(SpectralError::InvalidArgument(format!(
                "source vertex {s} out of range (mesh has {} vertices)",
                self.len()
            )));
        }
        Ok(())
    }

    /// Shortest edge-path distances from the nearest of `sources` to every vertex, stopping
    /// at `radius` (vertices farther away get `f64::INFINITY`, as do unreachable ones).
    pub fn distances_within(
        &self,
        sources: &[u32],
        radius: f64,
    ) -> Result<Vec<f64>, SpectralError> {
        self.check(sources)?;
        let mut dist = vec![f64::INFINITY; self.len()];
        self.run(sources, radius, &mut dist);
        Ok(dist)
    }

    /// Dijkstra with a binary heap. Distances are non-negative, so their IEEE bit patterns
    /// order like the numbers and serve as integer heap keys.
    fn run(&self, sources: &[u32], radius: f64, dist: &mut [f64]) {
        let mut heap = BinaryHeap::new();
        for &s in sources {
            dist[s as usize] = 0.0;
            heap.push(Reverse((0u64, s)));
        }
        while let Some(Reverse((key, v))) = heap.pop() {
            let d = f64::from_bits(key);
            let v = v as usize;
            if d > dist[v] {
                continue;
            }
            for e in self.offsets[v]..self.offsets[v + 1] {
                let u = self.targets[e] as usize;
                let nd = d + self.lengths[e];
                if nd < dist[u] && nd <= radius {
                    dist[u] = nd;
                    heap.push(Reverse((nd.to_bits(), u as u32)));
                }
            }
        }
    }

    /// Distances from one source to every vertex (the paper's eq. 5–6).
    pub fn distances(&self, source: u32) -> Result<Vec<f64>, SpectralError> {
        self.distances_within(&[source], f64::INFINITY)
    }

    /// One distance row per source, computed in parallel (rayon).
    pub fn distances_many(&self, sources: &[u32]) -> Result<Vec<Vec<f64>>, SpectralError> {
        self.check(sources)?;
        Ok(sources
            .par_iter()
            .map(|&s| {
                let mut d = vec![f64::INFINITY; self.len()];
                self.run(&[s], f64::INFINITY, &mut d);
                d
            })
            .collect())
    }
}

/// Reusable buffers of [`EdgeGraph::search`], one per thread: visited stamps instead of
/// clearing, so a search that settles few vertices costs only what it touches.
#[derive(Debug, Clone)]
pub struct DijkstraScratch {
    dist: Vec<f64>,
    stamp: Vec<u32>,
    settled: Vec<u32>,
    epoch: u32,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
}

impl DijkstraScratch {
    /// Buffers for searches on `graph` (or any graph with as many vertices).
    pub fn new(graph: &EdgeGraph) -> DijkstraScratch {
        let n = graph.len();
        DijkstraScratch {
            dist: vec![0.0; n],
            stamp: vec![0; n],
            settled: vec![0; n],
            epoch: 0,
            heap: BinaryHeap::new(),
        }
    }
}

impl EdgeGraph {
    /// Dijkstra from `source` that reports vertices as they are settled: `visit(v, d)` is
    /// called for each in order of distance (ties by vertex id) and returns `false` to stop;
    /// the search also stops by itself once the next vertex is beyond `radius`. The distances
    /// are the exact shortest edge paths (the same as [`EdgeGraph::distances`]), so a query
    /// such as "distance from a to b" explores only the disc of that radius around `a`.
    ///
    /// ```
    /// use symcorr_spectral::{DijkstraScratch, EdgeGraph};
    /// let mesh = symcorr_mesh::testmesh::grid(10, 1, [1.0, 1.0]);
    /// let g = EdgeGraph::new(&mesh);
    /// let mut s = DijkstraScratch::new(&g);
    /// let mut to_5 = None;
    /// g.search(&mut s, 0, f64::INFINITY, |v, d| {
    ///     if v == 5 { to_5 = Some(d); }
    ///     v != 5 // stop once vertex 5 is settled
    /// }).unwrap();
    /// assert_eq!(to_5, Some(5.0));
    /// ```
    ///
    /// Errors: `source` out of range, or `scratch` made for a graph of another size
    /// ([`SpectralError::InvalidArgument`]).
    pub fn search(
        &self,
        scratch: &mut DijkstraScratch,
        source: u32,
        radius: f64,
        mut visit: impl FnMut(u32, f64) -> bool,
    ) -> Result<(), SpectralError> {
        self.check(&[source])?;
        let s = scratch;
        if s.dist.len() != self.len() {
            return Err(SpectralError::InvalidArgument(format!(
                "Dijkstra scratch for {} vertices used on a graph of {}",
                s.dist.len(),
                self.len()
            )));
        }
        s.epoch = s.epoch.wrapping_add(1);
        if s.epoch == 0 {
            // Wrapped: reset the stamps once every 2³² searches.
            s.stamp.iter_mut().for_each(|x| *x = 0);
            s.settled.iter_mut().for_each(|x| *x = 0);
            s.epoch = 1;
        }
        let e = s.epoch;
        s.heap.clear();
        s.dist[source as usize] = 0.0;
        s.stamp[source as usize] = e;
        // Non-negative finite f64s order like their bit patterns.
        s.heap.push(Reverse((0f64.to_bits(), source)));
        while let Some(Reverse((bits, v))) = s.heap.pop() {
            let d = f64::from_bits(bits);
            let vi = v as usize;
            if s.settled[vi] == e || d > s.dist[vi] {
                continue;
            }
            if d > radius {
                return Ok(());
            }
            s.settled[vi] = e;
            if !visit(v, d) {
                return Ok(());
            }
            for k in self.offsets[vi]..self.offsets[vi + 1] {
                let u = self.targets[k] as usize;
                let nd = d + self.lengths[k];
                if s.stamp[u] != e || nd < s.dist[u] {
                    s.stamp[u] = e;
                    s.dist[u] = nd;
                    s.heap.push(Reverse((nd.to_bits(), u as u32)));
                }
            }
        }
        Ok(())
    }
}

/// Dijkstra distances over mesh edges from `source` to every vertex (paper eq. 5–6);
/// unreachable vertices get `f64::INFINITY`. Builds the edge graph each call — use
/// [`EdgeGraph`] to reuse it.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_spectral::dijkstra;
/// let mesh = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
///     vec![[0, 1, 2], [0, 2, 3]],
/// ).unwrap();
/// let d = dijkstra(&mesh, 1).unwrap();
/// assert_eq!(d, vec![1.0, 0.0, 1.0, 2.0]); // 1 → 3 has no edge: two unit steps
/// ```
pub fn dijkstra(mesh: &TriMesh, source: u32) -> Result<Vec<f64>, SpectralError> {
    EdgeGraph::new(mesh).distances(source)
}

/// Dijkstra from many sources in parallel: one row (length n) per source.
pub fn dijkstra_many(mesh: &TriMesh, sources: &[u32]) -> Result<Vec<Vec<f64>>, SpectralError> {
    EdgeGraph::new(mesh).distances_many(sources)
}

/// Per-triangle data for the gradient and divergence of the heat method.
#[derive(Debug, Clone)]
struct FaceData {
    tri: [u32; 3],
    /// `N × e_k / (2A)`, e_k the edge opposite corner k (counter-clockwise): the gradient of
    /// the hat function of corner k.
    grad_hat: [Vector3<f64>; 3],
    /// Edges from corner k to corners k+1 and k+2, with the cotangents of the angles opposite
    /// them (at corners k+2 and k+1).
    cots: [f64; 3],
    edges: [Vector3<f64>; 3],
}

/// Heat-method geodesic distances (Crane, Weischedel, Wardetzky 2013) with both linear
/// systems factored once and reused for every query.
///
/// 1. Heat flow: `(M + tL) u = δ_sources` (one implicit Euler step).
/// 2. Per face `X = −∇u/|∇u|`.
/// 3. Poisson: `L φ = −div X` (L the PSD cotan stiffness, so this is `Δφ = ∇·X`), solved with
///    one pinned vertex per connected component (the system is singular but consistent), then
///    shifted so the nearest source is at 0.
///
/// `t = t_factor · h²`, `h` the mean edge length (t_factor = 1 is Crane et al.'s and
/// potpourri3d's default). Boundaries: the cotan Laplacian has natural (Neumann) boundary
/// conditions in both solves; Crane et al. recommend averaging Neumann and Dirichlet on
/// boundaries, which we do not do (distances near a boundary are slightly smoothed).
/// Vertices in components without a source get `f64::INFINITY`.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_spectral::HeatGeodesics;
/// let mesh = TriMesh::new(
///     vec![[1.,0.,0.],[-1.,0.,0.],[0.,1.,0.],[0.,-1.,0.],[0.,0.,1.],[0.,0.,-1.]],
///     vec![[0,2,4],[2,1,4],[1,3,4],[3,0,4],[2,0,5],[1,2,5],[3,1,5],[0,3,5]],
/// ).unwrap();
/// let heat = HeatGeodesics::new(&mesh, 1.0).unwrap();
/// let d = heat.distance(&[4]).unwrap();
/// assert_eq!(d[4], 0.0);
/// assert!(d[5] > d[0]); // the opposite pole is farthest
/// ```
#[derive(Debug, Clone)]
pub struct HeatGeodesics {
    faces: Vec<FaceData>,
    heat: SystemFactor,
    poisson: SystemFactor,
    component: Vec<u32>,
    num_components: usize,
    t: f64,
}

impl HeatGeodesics {
    /// Builds the Laplacian and factors both systems. `t_factor` scales `t = t_factor·h²`.
    pub fn new(mesh: &TriMesh, t_factor: f64) -> Result<HeatGeodesics, SpectralError> {
        let lap = Laplacian::new(mesh)?;
        Self::with_laplacian(mesh, &lap, t_factor)
    }

    /// As [`HeatGeodesics::new`], reusing an existing Laplacian of the same mesh.
    pub fn with_laplacian(
        mesh: &TriMesh,
        lap: &Laplacian,
        t_factor: f64,
    ) -> Result<HeatGeodesics, SpectralError> {
        if lap.len() != mesh.num_vertices() {
            return Err(SpectralError::InvalidArgument(
                "Laplacian and mesh have different vertex counts".into(),
            ));
        }
        if !(t_factor > 0.0 && t_factor.is_finite()) {
            return Err(SpectralError::InvalidArgument(format!(
                "heat-method time factor must be positive, got {t_factor}"
            )));
        }
        let edges = mesh.edges();
        let h = edges
            .iter()
            .map(|[a, b]| {
                distance(
                    &Point3::from(mesh.positions[*a as usize]),
                    &Point3::from(mesh.positions[*b as usize]),
                )
            })
            .sum::<f64>()
            / edges.len().max(1) as f64;
        let t = t_factor * h * h;
        // M + tL = t (L + M/t): factor L + (1/t) M; the right-hand side scale is irrelevant
        // because only the direction of ∇u is used.
        let heat = lap.factor(1.0 / t, None)?;
        let (component, num_components) = lap.components();
        let component = component.to_vec();
        // Pin the first vertex of each component: zero its row and column, unit diagonal.
        let mut pin = vec![false; lap.len()];
        let mut seen = vec![false; num_components];
        for (v, &c) in component.iter().enumerate() {
            if !seen[c as usize] {
                seen[c as usize] = true;
                pin[v] = true;
            }
        }
        let mut pinned = lap.stiffness.clone();
        {
            let (sym, _) = lap.stiffness.parts();
            let col_ptr = sym.col_ptr().to_vec();
            let row_idx = sym.row_idx().to_vec();
            let val = pinned.val_mut();
            for j in 0..lap.len() {
                for p in col_ptr[j]..col_ptr[j + 1] {
                    let i = row_idx[p];
                    if pin[i] || pin[j] {
                        val[p] = if i == j { 1.0 } else { 0.0 };
                    }
                }
            }
        }
        let poisson = SystemFactor::new(&pinned)?;
        let faces = mesh
            .triangles
            .iter()
            .map(|&tri| {
                let p = tri.map(|v| Point3::from(mesh.positions[v as usize]));
                let [p0, p1, p2] = p;
                let nrm = (p1 - p0).cross(&(p2 - p0));
                let a2 = nrm.norm();
                let mut grad_hat = [Vector3::zeros(); 3];
                let mut cots = [0.0; 3];
                let mut edges = [Vector3::zeros(); 3];
                let longest = (0..3)
                    .map(|k| (p[(k + 1) % 3] - p[k]).norm_squared())
                    .fold(0.0, f64::max);
                if a2 > crate::DEGENERATE_REL * longest && a2 > 0.0 {
                    // Component-wise division (not a reciprocal multiply), as before.
                    let unit = nrm / a2;
                    for k in 0..3 {
                        let e = p[(k + 2) % 3] - p[(k + 1) % 3];
                        grad_hat[k] = unit.cross(&e) / a2;
                        // Angle at corner k, opposite edge (k+1, k+2).
                        cots[k] = cot(&(p[(k + 1) % 3] - p[k]), &(p[(k + 2) % 3] - p[k]));
                        edges[k] = p[(k + 1) % 3] - p[k];
                    }
                }
                FaceData {
                    tri,
                    grad_hat,
                    cots,
                    edges,
                }
            })
            .collect();
        Ok(HeatGeodesics {
            faces,
            heat,
            poisson,
            component,
            num_components,
            t,
        })
    }

    /// The diffusion time `t` used.
    pub fn time(&self) -> f64 {
        self.t
    }

    fn check(&self, sources: &[u32]) -> Result<(), SpectralError> {
        let n = self.component.len();
        if sources.is_empty() {
            return Err(SpectralError::InvalidArgument(
                "no source vertex given".into(),
            ));
        }
        if let Some(&s) = sources.iter().find(|&&s| s as usize >= n) {
            return Err(SpectralError::InvalidArgument(format!(
                "source vertex {s} out of range (mesh has {n} vertices)"
            )));
        }
        Ok(())
    }

    /// Right-hand side `−div X` of the Poisson step from the heat solution `u`.
    fn divergence(&self, u: &[f64], n: usize) -> Vec<f64> {
        let mut b = vec![0.0; n];
        for f in &self.faces {
            let [i, j, k] = f.tri.map(|v| v as usize);
            let mut g = Vector3::zeros();
            for (c, &v) in [i, j, k].iter().enumerate() {
                g += f.grad_hat[c] * u[v];
            }
            let gn = g.norm();
            if gn == 0.0 || !gn.is_finite() {
                continue;
            }
            let x = -g / gn;
            // Integrated divergence at corner c: ½ (cot θ_{c+2} (e_{c→c+1}·X) + cot θ_{c+1} (e_{c→c+2}·X)).
            for c in 0..3 {
                let e1 = f.edges[c]; // c → c+1, opposite corner c+2
                let e2 = Vector3::zeros() - f.edges[(c + 2) % 3]; // c → c+2, opposite corner c+1
                let div =
                    0.5 * (f.cots[(c + 2) % 3] * e1.dot(&x) + f.cots[(c + 1) % 3] * e2.dot(&x));
                b[f.tri[c] as usize] -= div;
            }
        }
        b
    }

    /// Shifts φ so that the nearest source is 0 per component; components without a source
    /// become infinite.
    fn finish(&self, phi: &mut [f64], sources: &[u32]) {
        let mut base = vec![f64::INFINITY; self.num_components];
        for &s in sources {
            let c = self.component[s as usize] as usize;
            base[c] = base[c].min(phi[s as usize]);
        }
        for (v, x) in phi.iter_mut().enumerate() {
            let b = base[self.component[v] as usize];
            *x = if b.is_finite() { *x - b } else { f64::INFINITY };
        }
    }

    /// Distance from the nearest of `sources` to every vertex.
    pub fn distance(&self, sources: &[u32]) -> Result<Vec<f64>, SpectralError> {
        self.check(sources)?;
        let n = self.component.len();
        let mut delta = vec![0.0; n];
        for &s in sources {
            delta[s as usize] = 1.0;
        }
        let u = self.heat.solve(&delta);
        let mut b = self.divergence(&u, n);
        self.zero_pins(&mut b);
        let mut phi = self.poisson.solve(&b);
        self.finish(&mut phi, sources);
        Ok(phi)
    }

    fn zero_pins(&self, b: &mut [f64]) {
        let mut seen = vec![false; self.num_components];
        for (v, &c) in self.component.iter().enumerate() {
            if !seen[c as usize] {
                seen[c as usize] = true;
                b[v] = 0.0;
            }
        }
    }

    /// One distance row per source (each from that single source). Sources are processed in
    /// blocks: one blocked heat solve, per-column divergence in parallel (rayon), one blocked
    /// Poisson solve.
    pub fn distances_many(&self, sources: &[u32]) -> Result<Vec<Vec<f64>>, SpectralError> {
        self.check(sources)?;
        let n = self.component.len();
        let mut out = Vec::with_capacity(sources.len());
        for block in sources.chunks(64) {
            let mut rhs = Mat::<f64>::zeros(n, block.len());
            for (j, &s) in block.iter().enumerate() {
                rhs[(s as usize, j)] = 1.0;
            }
            self.heat.solve_in_place(rhs.as_mut());
            let cols: Vec<Vec<f64>> = (0..block.len())
                .into_par_iter()
                .map(|j| {
                    let u: Vec<f64> = (0..n).map(|i| rhs[(i, j)]).collect();
                    let mut b = self.divergence(&u, n);
                    self.zero_pins(&mut b);
                    b
                })
                .collect();
            let mut poisson_rhs = Mat::from_fn(n, block.len(), |i, j| cols[j][i]);
            self.poisson.solve_in_place(poisson_rhs.as_mut());
            for (j, &s) in block.iter().enumerate() {
                let mut phi: Vec<f64> = (0..n).map(|i| poisson_rhs[(i, j)]).collect();
                self.finish(&mut phi, &[s]);
                out.push(phi);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The visited stamps wrap after 2³² searches: results stay right across the wrap.
    #[test]
    fn search_stamps_survive_the_epoch_wrap() {
        let mesh = crate::testmesh::icosphere(2);
        let g = EdgeGraph::new(&mesh);
        let full = g.distances(3).unwrap();
        let mut s = DijkstraScratch::new(&g);
        s.epoch = u32::MAX - 2;
        for _ in 0..5 {
            let mut got = vec![f64::NAN; g.len()];
            g.search(&mut s, 3, f64::INFINITY, |v, d| {
                got[v as usize] = d;
                true
            })
            .unwrap();
            assert_eq!(got, full);
        }
        assert!(s.epoch < 5);
    }
}
