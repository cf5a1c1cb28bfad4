//! Validation ([`validate`]) and repair ([`repair`]) of triangle meshes, with reports.
//!
//! **Validation and repair.** [`validate`] reports (never fails): non-finite vertices,
//! out-of-range triangles, repeated-vertex and zero-area triangles (area ≤
//! [`DEFAULT_ZERO_AREA_REL`] × bbox diagonal²), duplicate triangles (same vertex set in any
//! order), unreferenced vertices, non-manifold edges (> 2 triangles) and vertices (> 1 fan),
//! inconsistently oriented edges, components (triangles joined through shared vertices, with
//! triangle counts) and boundary loops. [`repair`] refuses invalid input (non-finite,
//! out-of-range, empty are errors — it does not guess), then per [`RepairOptions`] removes
//! degenerate/zero-area triangles, duplicates (first kept), optionally the triangles beyond
//! the first two at a non-manifold edge, small components or all but the largest, optionally
//! splits non-manifold vertices (one copy per extra fan), and drops unreferenced vertices.
//! **vertex_map convention:** `Repaired::vertex_map[new_id] = input_id`; kept vertices keep
//! their relative order (the map is increasing over them) and split copies are appended at the
//! end, mapping to the vertex they copy; `triangle_map` does the same for triangles. Results
//! computed on the repaired mesh are reported in input ids through these maps.

use std::fmt;

use nalgebra::Point3;

use crate::{MeshError, TriMesh};

/// Default zero-area tolerance: a triangle whose area is at most this times the squared
/// bounding-box diagonal counts as zero-area (scale-invariant; 1e-12 is far below any real
/// triangle of a scan yet above round-off of collinear points).
pub const DEFAULT_ZERO_AREA_REL: f64 = 1e-12;

/// What [`validate`] found. Plain fields (counts and id lists, input ids) so it can be printed
/// ([`fmt::Display`]) or serialised by callers as it is.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ValidationReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Vertices with a NaN or infinite coordinate (an error for [`repair`]).
    pub non_finite_vertices: Vec<u32>,
    /// Triangles referring to a vertex that does not exist (an error for [`repair`]).
    pub out_of_range_triangles: Vec<u32>,
    /// Triangles using the same vertex twice.
    pub degenerate_triangles: Vec<u32>,
    /// Triangles with three distinct vertices but (near) zero area (collinear or coincident
    /// corners), see [`DEFAULT_ZERO_AREA_REL`].
    pub zero_area_triangles: Vec<u32>,
    /// Triangles with the same vertex set as an earlier triangle (the earlier one is not listed).
    pub duplicate_triangles: Vec<u32>,
    /// Vertices used by no triangle.
    pub unreferenced_vertices: Vec<u32>,
    /// Edges `[a, b]` (`a < b`) shared by more than two triangles.
    pub non_manifold_edges: Vec<[u32; 2]>,
    /// Vertices whose incident triangles form more than one fan (e.g. two cones touching at a tip).
    pub non_manifold_vertices: Vec<u32>,
    /// Edges used twice in the same direction by their two triangles (inconsistent orientation).
    pub inconsistently_oriented_edges: usize,
    /// Triangle count of every connected component (triangles connected through shared
    /// vertices), largest first.
    pub component_triangles: Vec<usize>,
    /// Boundary loops as vertex sequences (each closed: the last vertex connects to the first).
    /// A boundary that cannot be closed (at non-manifold or inconsistently oriented spots) is
    /// listed as the open chain found.
    pub boundary_loops: Vec<Vec<u32>>,
}

impl ValidationReport {
    /// Number of connected components (of triangles).
    pub fn components(&self) -> usize {
        self.component_triangles.len()
    }

    /// True when nothing is invalid or questionable: no non-finite coordinates, no out-of-range
    /// indices, at least one triangle, no degenerate/zero-area/duplicate triangles, no
    /// unreferenced vertices, manifold, consistently oriented, one component. Boundaries are
    /// allowed (single-view scans have them): see [`ValidationReport::is_closed`].
    pub fn is_clean(&self) -> bool {
        self.triangles > 0
            && self.non_finite_vertices.is_empty()
            && self.out_of_range_triangles.is_empty()
            && self.degenerate_triangles.is_empty()
            && self.zero_area_triangles.is_empty()
            && self.duplicate_triangles.is_empty()
            && self.unreferenced_vertices.is_empty()
            && self.non_manifold_edges.is_empty()
            && self.non_manifold_vertices.is_empty()
            && self.inconsistently_oriented_edges == 0
            && self.components() == 1
    }

    /// True when the surface has no boundary.
    pub fn is_closed(&self) -> bool {
        self.boundary_loops.is_empty()
    }
}

fn list<T: fmt::Debug>(f: &mut fmt::Formatter<'_>, name: &str, items: &[T]) -> fmt::Result {
    if items.is_empty() {
        return Ok(());
    }
    const SHOW: usize = 8;
    write!(f, "\n  {name}: {}", items.len())?;
    let shown: Vec<String> = items.iter().take(SHOW).map(|x| format!("{x:?}")).collect();
    write!(
        f,
        " ({}{})",
        shown.join(", "),
        if items.len() > SHOW { ", …" } else { "" }
    )
}

impl fmt::Display for ValidationReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} vertices, {} triangles, {} component(s), {} boundary loop(s): {}",
            self.vertices,
            self.triangles,
            self.components(),
            self.boundary_loops.len(),
            if self.is_clean() {
                "clean"
            } else {
                "problems found"
            }
        )?;
        list(f, "non-finite vertices", &self.non_finite_vertices)?;
        list(
            f,
            "triangles with out-of-range indices",
            &self.out_of_range_triangles,
        )?;
        list(
            f,
            "degenerate triangles (repeated vertex)",
            &self.degenerate_triangles,
        )?;
        list(f, "zero-area triangles", &self.zero_area_triangles)?;
        list(f, "duplicate triangles", &self.duplicate_triangles)?;
        list(f, "unreferenced vertices", &self.unreferenced_vertices)?;
        list(f, "non-manifold edges", &self.non_manifold_edges)?;
        list(f, "non-manifold vertices", &self.non_manifold_vertices)?;
        if self.inconsistently_oriented_edges > 0 {
            write!(
                f,
                "\n  inconsistently oriented edges: {}",
                self.inconsistently_oriented_edges
            )?;
        }
        if self.components() > 1 {
            list(f, "triangles per component", &self.component_triangles)?;
        }
        if !self.boundary_loops.is_empty() {
            let lens: Vec<usize> = self.boundary_loops.iter().map(Vec::len).collect();
            list(f, "boundary loop lengths", &lens)?;
        }
        Ok(())
    }
}

/// Validates a mesh with the default zero-area tolerance. Never panics, even on a `TriMesh`
/// built by hand with non-finite coordinates or out-of-range indices (those are reported and
/// the offending triangles left out of the other checks).
pub fn validate(mesh: &TriMesh) -> ValidationReport {
    validate_with(mesh, DEFAULT_ZERO_AREA_REL)
}

/// Validates a mesh; `zero_area_rel` is the zero-area tolerance relative to the squared
/// bounding-box diagonal.
pub fn validate_with(mesh: &TriMesh, zero_area_rel: f64) -> ValidationReport {
    let n = mesh.num_vertices();
    let mut r = ValidationReport {
        vertices: n,
        triangles: mesh.num_triangles(),
        ..Default::default()
    };
    for (v, p) in mesh.positions.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            r.non_finite_vertices.push(v as u32);
        }
    }
    let bad_vertex =
        |i: u32| (i as usize) >= n || !mesh.positions[i as usize].iter().all(|c| c.is_finite());
    let mut usable = Vec::with_capacity(mesh.num_triangles());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri.iter().any(|&i| (i as usize) >= n) {
            r.out_of_range_triangles.push(t as u32);
        } else if !tri.iter().any(|&i| bad_vertex(i)) {
            usable.push(t as u32);
        }
    }
    let usable_mesh_area_tol = zero_area_tolerance(mesh, zero_area_rel);
    let (degenerate, zero_area, duplicates) =
        classify_triangles(mesh, &usable, usable_mesh_area_tol);
    r.degenerate_triangles = degenerate;
    r.zero_area_triangles = zero_area;
    r.duplicate_triangles = duplicates;

    let mut referenced = vec![false; n];
    for &t in &usable {
        for &i in &mesh.triangles[t as usize] {
            referenced[i as usize] = true;
        }
    }
    for t in &r.out_of_range_triangles {
        for &i in &mesh.triangles[*t as usize] {
            if (i as usize) < n {
                referenced[i as usize] = true;
            }
        }
    }
    r.unreferenced_vertices = (0..n as u32).filter(|&v| !referenced[v as usize]).collect();

    // Topology over triangles with three distinct, valid vertices.
    let proper: Vec<u32> = usable
        .iter()
        .copied()
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t as usize];
            a != b && b != c && a != c
        })
        .collect();
    let topo = Topology::new(mesh, &proper);
    r.non_manifold_edges = topo.non_manifold_edges();
    r.inconsistently_oriented_edges = topo.inconsistent_edges();
    r.non_manifold_vertices = non_manifold_vertices(mesh, &proper, n);
    r.boundary_loops = topo.boundary_loops(n);
    r.component_triangles = component_sizes(mesh, &usable, n);
    r
}

fn zero_area_tolerance(mesh: &TriMesh, rel: f64) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in mesh
        .positions
        .iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
    {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let d2: f64 = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum();
    if d2.is_finite() {
        rel * d2
    } else {
        0.0
    }
}

/// Splits `tris` into (repeated-vertex, zero-area, duplicate-of-earlier) lists. A triangle is
/// listed in at most one of them, in that order of precedence.
fn classify_triangles(
    mesh: &TriMesh,
    tris: &[u32],
    area_tol: f64,
) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let (mut degenerate, mut zero, mut dup) = (Vec::new(), Vec::new(), Vec::new());
    let mut keys: Vec<([u32; 3], u32)> = Vec::with_capacity(tris.len());
    for &t in tris {
        let tri = mesh.triangles[t as usize];
        let [a, b, c] = tri;
        if a == b || b == c || a == c {
            degenerate.push(t);
            continue;
        }
        let [p, q, s] = mesh.corners(t as usize).map(Point3::from);
        let area = 0.5 * (q - p).cross(&(s - p)).norm();
        if area <= area_tol {
            zero.push(t);
            continue;
        }
        let mut k = tri;
        k.sort_unstable();
        keys.push((k, t));
    }
    let n = keys
        .iter()
        .map(|(k, _)| k[0] as usize + 1)
        .max()
        .unwrap_or(0);
    let (keys, _) = bucket_sort(&keys, n, |(k, _)| k[0] as usize);
    for w in keys.windows(2) {
        if w[0].0 == w[1].0 {
            dup.push(w[1].1);
        }
    }
    dup.sort_unstable();
    (degenerate, zero, dup)
}

/// `items` ordered by `key` (below `keys`), then by their own order, with the offsets of each
/// key's run (`keys + 1` of them: key `k` holds `start[k]..start[k + 1]`): a counting sort by
/// the key, then each short run sorted. Where the key is the items' leading field — an edge's
/// or a triangle's smallest vertex — that is the order of one sort of them all, found in
/// linear time (a recorded frame's scan is validated and repaired on every frame).
fn bucket_sort<T: Ord + Copy>(
    items: &[T],
    keys: usize,
    key: impl Fn(&T) -> usize,
) -> (Vec<T>, Vec<usize>) {
    let mut start = vec![0usize; keys + 1];
    for item in items {
        start[key(item) + 1] += 1;
    }
    for k in 0..keys {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut sorted = items.to_vec();
    for item in items {
        let k = key(item);
        sorted[fill[k]] = *item;
        fill[k] += 1;
    }
    for k in 0..keys {
        sorted[start[k]..start[k + 1]].sort_unstable();
    }
    (sorted, start)
}

/// Undirected edges with the triangles using them, for triangles with distinct vertices.
struct Topology {
    /// (min, max, triangle, forward) sorted: forward = the triangle traverses min → max.
    half: Vec<(u32, u32, u32, bool)>,
}

impl Topology {
    fn new(mesh: &TriMesh, tris: &[u32]) -> Self {
        let halves: Vec<(u32, u32, u32, bool)> = tris
            .iter()
            .flat_map(|&t| {
                let tri = mesh.triangles[t as usize];
                [0, 1, 2].map(|k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    (a.min(b), a.max(b), t, a < b)
                })
            })
            .collect();
        let n = halves.iter().map(|h| h.1 as usize + 1).max().unwrap_or(0);
        let (half, _) = bucket_sort(&halves, n, |h| h.0 as usize);
        Topology { half }
    }

    /// Groups of half-edges sharing an undirected edge.
    fn groups(&self) -> impl Iterator<Item = &[(u32, u32, u32, bool)]> {
        self.half.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1)
    }

    fn non_manifold_edges(&self) -> Vec<[u32; 2]> {
        self.groups()
            .filter(|g| g.len() > 2)
            .map(|g| [g[0].0, g[0].1])
            .collect()
    }

    fn inconsistent_edges(&self) -> usize {
        self.groups()
            .filter(|g| g.len() == 2 && g[0].3 == g[1].3)
            .count()
    }

    fn boundary_loops(&self, n: usize) -> Vec<Vec<u32>> {
        // Boundary half-edges in their triangle's direction; outgoing lists per start vertex.
        let mut out: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut count = 0usize;
        for g in self.groups().filter(|g| g.len() == 1) {
            let (lo, hi, _, fwd) = g[0];
            let (a, b) = if fwd { (lo, hi) } else { (hi, lo) };
            out[a as usize].push(b);
            count += 1;
        }
        let mut loops = Vec::new();
        let mut used = 0usize;
        for start in 0..n {
            while let Some(first) = out[start].pop() {
                let mut chain = vec![start as u32];
                let mut cur = first;
                used += 1;
                while cur as usize != start {
                    chain.push(cur);
                    match out[cur as usize].pop() {
                        Some(next) => {
                            cur = next;
                            used += 1;
                        }
                        None => break, // open chain
                    }
                }
                loops.push(chain);
                if used >= count {
                    break;
                }
            }
        }
        loops
    }
}

/// Vertices whose incident (proper) triangles form more than one edge-connected fan.
fn non_manifold_vertices(mesh: &TriMesh, tris: &[u32], n: usize) -> Vec<u32> {
    fan_groups(mesh, tris, n)
        .into_iter()
        .map(|(v, _)| v)
        .collect()
}

/// The vertices whose incident triangles form more than one fan (triangles around the vertex
/// connected through edges at the vertex), ascending, each with its fans, ordered by their
/// smallest triangle id. Only those: the fans of every other vertex would be one allocation
/// per vertex for nothing.
fn fan_groups(mesh: &TriMesh, tris: &[u32], n: usize) -> Vec<(u32, Vec<Vec<u32>>)> {
    // Incident triangles per vertex, compressed rows (counts, offsets, then triangle ids).
    let mut start = vec![0usize; n + 1];
    for &t in tris {
        for &v in &mesh.triangles[t as usize] {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut incident_ids = vec![0u32; start[n]];
    for &t in tris {
        for &v in &mesh.triangles[t as usize] {
            incident_ids[fill[v as usize]] = t;
            fill[v as usize] += 1;
        }
    }
    let mut result = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut spokes: Vec<(u32, usize)> = Vec::new();
    let mut root_fan: Vec<usize> = Vec::new();
    for v in 0..n {
        let inc = &incident_ids[start[v]..start[v + 1]];
        if inc.is_empty() {
            continue;
        }
        // Union-find over the incident triangles, joined through shared spokes (v, w).
        parent.clear();
        parent.extend(0..inc.len());
        spokes.clear();
        for (k, &t) in inc.iter().enumerate() {
            for &w in &mesh.triangles[t as usize] {
                if w as usize != v {
                    spokes.push((w, k));
                }
            }
        }
        spokes.sort_unstable();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for w in spokes.windows(2) {
            if w[0].0 == w[1].0 {
                let (a, b) = (find(&mut parent, w[0].1), find(&mut parent, w[1].1));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
        if (0..inc.len()).all(|k| find(&mut parent, k) == 0) {
            continue; // one fan
        }
        let mut fans: Vec<Vec<u32>> = Vec::new();
        root_fan.clear();
        root_fan.resize(inc.len(), usize::MAX);
        for (k, &t) in inc.iter().enumerate() {
            let r = find(&mut parent, k);
            if root_fan[r] == usize::MAX {
                root_fan[r] = fans.len();
                fans.push(Vec::new());
            }
            fans[root_fan[r]].push(t);
        }
        result.push((v as u32, fans));
    }
    result
}

/// Triangle count per component (triangles joined through shared vertices), largest first.
fn component_sizes(mesh: &TriMesh, tris: &[u32], n: usize) -> Vec<usize> {
    let (comp_of_tri, ncomp) = triangle_components(mesh, tris, n);
    let mut sizes = vec![0usize; ncomp];
    for c in comp_of_tri {
        sizes[c as usize] += 1;
    }
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

/// Component id (dense, in order of first triangle) for each triangle of `tris`.
fn triangle_components(mesh: &TriMesh, tris: &[u32], n: usize) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for &t in tris {
        let tri = mesh.triangles[t as usize];
        for k in 1..3 {
            let (a, b) = (find(&mut parent, tri[0]), find(&mut parent, tri[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut id = vec![u32::MAX; n];
    let mut count = 0u32;
    let comps = tris
        .iter()
        .map(|&t| {
            let r = find(&mut parent, mesh.triangles[t as usize][0]) as usize;
            if id[r] == u32::MAX {
                id[r] = count;
                count += 1;
            }
            id[r]
        })
        .collect();
    (comps, count as usize)
}

/// What [`repair`] does. The default removes degenerate, zero-area and duplicate triangles and
/// unreferenced vertices, and keeps everything else.
#[derive(Debug, Clone, PartialEq)]
pub struct RepairOptions {
    /// Remove triangles with a repeated vertex and zero-area triangles.
    pub remove_degenerate: bool,
    /// Zero-area tolerance relative to the squared bounding-box diagonal.
    pub zero_area_rel: f64,
    /// Remove triangles with the same vertex set as an earlier one (the first is kept).
    pub remove_duplicates: bool,
    /// At an edge shared by more than two triangles, remove the triangles beyond the first two
    /// (in input order) that use it.
    pub remove_non_manifold_edge_triangles: bool,
    /// Give every fan after the first of a non-manifold vertex its own copy of the vertex
    /// (appended after the kept vertices; `vertex_map` sends the copy to the same input id).
    pub split_non_manifold_vertices: bool,
    /// Keep only the component with the most triangles (the first such on a tie).
    pub keep_largest_component: bool,
    /// Remove components with fewer triangles than this (0: keep all).
    pub min_component_triangles: usize,
    /// Remove vertices used by no triangle (also those of removed triangles/components).
    pub remove_unreferenced: bool,
    /// Turn triangles so that every component is consistently oriented: across each edge shared
    /// by two triangles the two run in opposite directions. A closed component ends up facing
    /// outward (positive signed volume); an open one keeps the orientation of the majority of
    /// its triangles.
    pub orient_consistently: bool,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            remove_degenerate: true,
            zero_area_rel: DEFAULT_ZERO_AREA_REL,
            remove_duplicates: true,
            remove_non_manifold_edge_triangles: false,
            split_non_manifold_vertices: false,
            keep_largest_component: false,
            min_component_triangles: 0,
            remove_unreferenced: true,
            orient_consistently: true,
        }
    }
}

/// What [`repair`] changed, with the validation before and after. Counts refer to the input.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RepairReport {
    /// Validation of the input.
    pub before: ValidationReport,
    /// Triangles removed for a repeated vertex.
    pub removed_degenerate_triangles: usize,
    /// Triangles removed for zero area.
    pub removed_zero_area_triangles: usize,
    /// Duplicate triangles removed.
    pub removed_duplicate_triangles: usize,
    /// Triangles removed at non-manifold edges.
    pub removed_non_manifold_edge_triangles: usize,
    /// Components removed (too small, or not the largest).
    pub removed_components: usize,
    /// Triangles removed with those components.
    pub removed_component_triangles: usize,
    /// Vertex copies added by splitting non-manifold vertices.
    pub added_split_vertices: usize,
    /// Vertices removed as unreferenced.
    pub removed_vertices: usize,
    /// Triangles turned (their vertex order reversed) to orient their component consistently.
    pub turned_triangles: usize,
    /// Validation of the result.
    pub after: ValidationReport,
}

impl RepairReport {
    /// True when the repair changed nothing.
    pub fn unchanged(&self) -> bool {
        self.removed_degenerate_triangles
            + self.removed_zero_area_triangles
            + self.removed_duplicate_triangles
            + self.removed_non_manifold_edge_triangles
            + self.removed_component_triangles
            + self.added_split_vertices
            + self.removed_vertices
            + self.turned_triangles
            == 0
    }
}

impl fmt::Display for RepairReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "before: {}", self.before)?;
        if self.unchanged() {
            write!(f, "repair: nothing changed")?;
        } else {
            write!(f, "repair:")?;
            let items = [
                (
                    self.removed_degenerate_triangles,
                    "degenerate triangles removed",
                ),
                (
                    self.removed_zero_area_triangles,
                    "zero-area triangles removed",
                ),
                (
                    self.removed_duplicate_triangles,
                    "duplicate triangles removed",
                ),
                (
                    self.removed_non_manifold_edge_triangles,
                    "triangles removed at non-manifold edges",
                ),
                (self.removed_components, "components removed"),
                (
                    self.removed_component_triangles,
                    "triangles removed with those components",
                ),
                (
                    self.added_split_vertices,
                    "vertex copies added at non-manifold vertices",
                ),
                (self.removed_vertices, "unreferenced vertices removed"),
                (
                    self.turned_triangles,
                    "triangles turned to orient their component consistently",
                ),
            ];
            for (n, what) in items.iter().filter(|(n, _)| *n > 0) {
                write!(f, "\n  {n} {what}")?;
            }
        }
        write!(f, "\nafter: {}", self.after)
    }
}

/// A repaired mesh, what was done, and the map back to the input.
#[derive(Debug, Clone, PartialEq)]
pub struct Repaired {
    /// The repaired mesh.
    pub mesh: TriMesh,
    /// What was found and changed.
    pub report: RepairReport,
    /// `vertex_map[new] = input vertex id`. Kept vertices keep their relative order (the map is
    /// increasing over them); split copies come last and map to the vertex they copy.
    pub vertex_map: Vec<u32>,
    /// `triangle_map[new] = input triangle id` (increasing).
    pub triangle_map: Vec<u32>,
}

/// Repairs a mesh as [`RepairOptions`] says, returning the new mesh, a report, and the map from
/// new vertex ids to input vertex ids (so results on the repaired mesh can be reported in the
/// input's ids).
///
/// Errors: [`MeshError::NonFinite`], [`MeshError::IndexOutOfRange`], [`MeshError::Empty`] for
/// an invalid input (repair does not guess coordinates), [`MeshError::NothingLeft`] when every
/// triangle would be removed.
///
/// ```
/// use symcorr_mesh::{repair, RepairOptions, TriMesh};
/// // A triangle, a repeated-vertex triangle, a duplicate, an unused vertex and a far-away island.
/// let mesh = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [9.0, 9.0, 9.0],
///          [5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]],
///     vec![[0, 1, 2], [0, 0, 1], [2, 0, 1], [4, 5, 6]],
/// ).unwrap();
/// let options = RepairOptions { keep_largest_component: true, ..Default::default() };
/// let fixed = repair(&mesh, &options).unwrap();
/// assert_eq!(fixed.mesh.triangles, vec![[0, 1, 2]]);
/// assert_eq!(fixed.vertex_map, vec![0, 1, 2]); // new vertex -> input vertex
/// assert_eq!(fixed.report.removed_degenerate_triangles, 1);
/// assert_eq!(fixed.report.removed_duplicate_triangles, 1);
/// assert!(fixed.report.after.is_clean());
/// println!("{}", fixed.report);
/// ```
pub fn repair(mesh: &TriMesh, options: &RepairOptions) -> Result<Repaired, MeshError> {
    // Re-establish TriMesh's invariants: the fields are public, so they may have been broken.
    let checked = TriMesh::new(mesh.positions.clone(), mesh.triangles.clone())?;
    let mesh = &checked;
    let n = mesh.num_vertices();
    let before = validate_with(mesh, options.zero_area_rel);
    let mut report = RepairReport::default();

    let mut keep = vec![true; mesh.num_triangles()];
    if options.remove_degenerate {
        for &t in &before.degenerate_triangles {
            keep[t as usize] = false;
        }
        for &t in &before.zero_area_triangles {
            keep[t as usize] = false;
        }
        report.removed_degenerate_triangles = before.degenerate_triangles.len();
        report.removed_zero_area_triangles = before.zero_area_triangles.len();
    }
    if options.remove_duplicates {
        // Among kept triangles (a duplicate of a removed triangle is not a duplicate). With the
        // degenerate and zero-area ones removed, the kept triangles are exactly those the
        // validation compared, so its list is the answer (sorting them all again cost a
        // recorded frame's scan as much as the validation's own sort).
        let dups = if options.remove_degenerate {
            before.duplicate_triangles.clone()
        } else {
            let kept: Vec<u32> = (0..mesh.num_triangles() as u32)
                .filter(|&t| keep[t as usize])
                .collect();
            classify_triangles(mesh, &kept, f64::NEG_INFINITY).2
        };
        for &t in &dups {
            keep[t as usize] = false;
        }
        report.removed_duplicate_triangles = dups.len();
    }
    if options.remove_non_manifold_edge_triangles {
        // Greedy in input order: a triangle stays if none of its edges already has two.
        let mut uses: std::collections::HashMap<(u32, u32), u8> = std::collections::HashMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if !keep[t] || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                continue;
            }
            let edges = [0, 1, 2].map(|k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                (a.min(b), a.max(b))
            });
            if edges.iter().any(|e| uses.get(e).copied().unwrap_or(0) >= 2) {
                keep[t] = false;
                report.removed_non_manifold_edge_triangles += 1;
            } else {
                for e in edges {
                    *uses.entry(e).or_insert(0) += 1;
                }
            }
        }
    }
    if options.keep_largest_component || options.min_component_triangles > 0 {
        let kept: Vec<u32> = (0..mesh.num_triangles() as u32)
            .filter(|&t| keep[t as usize])
            .collect();
        let (comp, ncomp) = triangle_components(mesh, &kept, n);
        let mut size = vec![0usize; ncomp];
        for &c in &comp {
            size[c as usize] += 1;
        }
        let largest = (0..ncomp).max_by(|&a, &b| size[a].cmp(&size[b]).then(b.cmp(&a)));
        let drop: Vec<bool> = (0..ncomp)
            .map(|c| {
                (options.keep_largest_component && Some(c) != largest)
                    || size[c] < options.min_component_triangles
            })
            .collect();
        report.removed_components = drop.iter().filter(|&&d| d).count();
        for (k, &t) in kept.iter().enumerate() {
            if drop[comp[k] as usize] {
                keep[t as usize] = false;
                report.removed_component_triangles += 1;
            }
        }
    }

    let triangle_map: Vec<u32> = (0..mesh.num_triangles() as u32)
        .filter(|&t| keep[t as usize])
        .collect();
    if triangle_map.is_empty() {
        return Err(MeshError::NothingLeft {
            reason: format!(
                "all {} triangles were removed (degenerate, duplicate, or in removed components)",
                mesh.num_triangles()
            ),
        });
    }
    let mut triangles: Vec<[u32; 3]> = triangle_map
        .iter()
        .map(|&t| mesh.triangles[t as usize])
        .collect();

    // Compact vertices, preserving order.
    let mut used = vec![!options.remove_unreferenced; n];
    for t in &triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut new_id = vec![u32::MAX; n];
    let mut vertex_map: Vec<u32> = Vec::with_capacity(n);
    for v in 0..n {
        if used[v] {
            new_id[v] = vertex_map.len() as u32;
            vertex_map.push(v as u32);
        }
    }
    report.removed_vertices = n - vertex_map.len();
    for t in &mut triangles {
        *t = t.map(|v| new_id[v as usize]);
    }
    let mut positions: Vec<[f64; 3]> = vertex_map
        .iter()
        .map(|&v| mesh.positions[v as usize])
        .collect();

    if options.split_non_manifold_vertices {
        let tmp = TriMesh {
            positions: positions.clone(),
            triangles: triangles.clone(),
        };
        let all: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&t| {
                let [a, b, c] = triangles[t as usize];
                a != b && b != c && a != c
            })
            .collect();
        let fans = fan_groups(&tmp, &all, positions.len());
        for (v, fans) in &fans {
            let v = *v as usize;
            for fan in fans.iter().skip(1) {
                let copy = positions.len() as u32;
                positions.push(positions[v]);
                vertex_map.push(vertex_map[v]);
                report.added_split_vertices += 1;
                for &t in fan {
                    for i in &mut triangles[t as usize] {
                        if *i == v as u32 {
                            *i = copy;
                        }
                    }
                }
            }
        }
    }

    if options.orient_consistently {
        report.turned_triangles = orient_consistently(&positions, &mut triangles);
    }
    let repaired = TriMesh::new(positions, triangles)?;
    // Nothing removed, split or turned: the repaired mesh is the input, and so is its report
    // (a scan's mesh usually is; validating it again would cost as much as the first time).
    report.after = if report.unchanged() {
        before.clone()
    } else {
        validate_with(&repaired, options.zero_area_rel)
    };
    report.before = before;
    Ok(Repaired {
        mesh: repaired,
        report,
        vertex_map,
        triangle_map,
    })
}

/// Turns triangles so that each edge-connected component is consistently oriented (see
/// [`RepairOptions::orient_consistently`]) and returns how many were turned. Orientation spreads
/// from each component's first triangle across edges shared by exactly two triangles; a
/// non-orientable component (a Möbius band) keeps the first orientation each triangle got.
fn orient_consistently(positions: &[[f64; 3]], triangles: &mut [[u32; 3]]) -> usize {
    let proper = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
    // Undirected edge → the triangles using it (ascending), with the direction each runs it
    // in: the half-edges (smaller end, larger end, triangle, forward, side) in sorted order
    // ([`bucket_sort`] by the smaller end), and every triangle side pointing at its edge's run.
    // A hash map of lists cost an allocation per edge on every recorded frame's scan.
    let ends = |tri: &[u32; 3], k: usize| {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        (a.min(b), a.max(b), a < b)
    };
    let vertices = triangles
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let halves: Vec<(u32, u32, u32, bool, u8)> = triangles
        .iter()
        .enumerate()
        .filter(|(_, tri)| proper(tri))
        .flat_map(|(t, tri)| {
            (0..3).map(move |k| {
                let (lo, hi, forward) = ends(tri, k);
                (lo, hi, t as u32, forward, k as u8)
            })
        })
        .collect();
    let (half, bucket) = bucket_sort(&halves, vertices, |h| h.0 as usize);
    let n = triangles.len();
    // The run of `half` holding the edge of each triangle side (`3·t + k`).
    let mut side = vec![(0usize, 0usize); 3 * n];
    for v in 0..vertices {
        let end = bucket[v + 1];
        let mut i = bucket[v];
        while i < end {
            let mut j = i + 1;
            while j < end && half[j].1 == half[i].1 {
                j += 1;
            }
            for &(_, _, t, _, k) in &half[i..j] {
                side[3 * t as usize + k as usize] = (i, j);
            }
            i = j;
        }
    }
    // flip[t]: None = not reached yet.
    let mut flip: Vec<Option<bool>> = vec![None; n];
    let mut turned = 0;
    for start in 0..n {
        if flip[start].is_some() || !proper(&triangles[start]) {
            continue;
        }
        flip[start] = Some(false);
        let mut component = vec![start];
        let mut closed = true;
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(t) = queue.pop_front() {
            let tri = triangles[t];
            let ft = flip[t] == Some(true);
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let (first, last) = side[3 * t + k];
                let users = &half[first..last];
                if users.len() == 1 {
                    closed = false;
                }
                if users.len() != 2 {
                    continue; // a boundary or non-manifold edge carries no orientation
                }
                let forward = (a < b) != ft; // t's direction along the edge after its flip
                for &(_, _, u, dir, _) in users {
                    let u = u as usize;
                    if u == t || flip[u].is_some() {
                        continue;
                    }
                    // Consistent: the neighbour runs the edge the other way.
                    flip[u] = Some(dir == forward);
                    component.push(u);
                    queue.push_back(u);
                }
            }
        }
        let flipped = component.iter().filter(|&&t| flip[t] == Some(true)).count();
        let invert = if closed {
            // Signed volume with the chosen orientation: negative means facing inward.
            let volume: f64 = component
                .iter()
                .map(|&t| {
                    let [a, b, c] =
                        triangles[t].map(|v| nalgebra::Vector3::from(positions[v as usize]));
                    let v = a.dot(&b.cross(&c));
                    if flip[t] == Some(true) {
                        -v
                    } else {
                        v
                    }
                })
                .sum();
            volume < 0.0
        } else {
            // Open: keep the orientation most triangles already had.
            2 * flipped > component.len()
        };
        for &t in &component {
            let f = flip[t] == Some(true);
            if f != invert {
                triangles[t].swap(1, 2);
                turned += 1;
            }
        }
    }
    turned
}

impl TriMesh {
    /// Boundary loops as vertex sequences in the triangles' orientation (see
    /// [`ValidationReport::boundary_loops`]); empty for a closed surface. Triangles with a
    /// repeated vertex are ignored.
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        let proper = self.proper_triangles();
        Topology::new(self, &proper).boundary_loops(self.num_vertices())
    }

    /// Total length of the boundary edges (0 for a closed surface): a single-view scan has a
    /// long one.
    pub fn boundary_length(&self) -> f64 {
        self.boundary_loops()
            .iter()
            .map(|l| self.loop_length(l))
            .sum()
    }

    /// Length of the closed polyline through the vertices `l` (the last joined to the first),
    /// e.g. one of [`TriMesh::boundary_loops`] or of a [`ValidationReport`]'s.
    ///
    /// ```
    /// let m = symcorr_mesh::TriMesh::new(
    ///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    ///     vec![[0, 1, 2]],
    /// )?;
    /// assert!((m.loop_length(&[0, 1, 2]) - (2.0 + 2f64.sqrt())).abs() < 1e-12);
    /// # Ok::<(), symcorr_mesh::MeshError>(())
    /// ```
    pub fn loop_length(&self, l: &[u32]) -> f64 {
        (0..l.len())
            .map(|i| {
                let a = self.positions[l[i] as usize];
                let b = self.positions[l[(i + 1) % l.len()] as usize];
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .sum()
    }

    /// For every vertex, whether it lies on the boundary (on an edge used by exactly one
    /// triangle). Triangles with a repeated vertex are ignored.
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let proper = self.proper_triangles();
        let mut on = vec![false; self.num_vertices()];
        for g in Topology::new(self, &proper)
            .groups()
            .filter(|g| g.len() == 1)
        {
            on[g[0].0 as usize] = true;
            on[g[0].1 as usize] = true;
        }
        on
    }

    fn proper_triangles(&self) -> Vec<u32> {
        let n = self.num_vertices();
        (0..self.num_triangles() as u32)
            .filter(|&t| {
                let [a, b, c] = self.triangles[t as usize];
                a != b && b != c && a != c && [a, b, c].iter().all(|&i| (i as usize) < n)
            })
            .collect()
    }
}
