//! Bone heat (Baran & Popović 2007, "Automatic rigging and animation of 3D characters", §4):
//! `(L + M·H) w_b = M·H·p_b` for every bone `b`, one factorisation for all of them.
//!
//! For each vertex the nearest *visible* bone(s) get `H_ii = c/d²` (`c` =
//! [`AttachOptions::heat_constant`](crate::AttachOptions)). Visible: the segment from the
//! vertex to the bone crosses no triangle (a small BVH), and the bone lies behind the vertex's
//! tangent plane (`n·(q − x) ≤ 0`, outward normals) — where two limbs touch, the segment to the
//! *other* limb's bone crosses no triangle either. A mesh wound inwards is recognised by a
//! majority vote over the nearest bones and its normals turned round. Only bones within `FAR` ×
//! the nearest bone's distance are tried. `L` is symcorr-spectral's cotan Laplacian (PSD);
//! the mass `M` makes the system unit-free, as Pinocchio's area-normalised Laplacian does.
//! Weights are clipped to [0, 1], those below [`AttachOptions::min_weight`](crate::AttachOptions)
//! dropped, rows normalised. A component from which no bone is visible gets the nearest bone
//! (ignoring visibility) as its heat source instead of an empty row, and is reported
//! ([`ComponentReport::fallback`]); vertices in no non-degenerate triangle get the nearest
//! bone's label.
//!
//! With [`HeatMesh::Clustered`] all of this runs on the mesh of clusters of the input's
//! vertices (`cluster`), each cluster at its seed vertex (whose triangles the visibility rays
//! skip), and every vertex takes its cluster's row.

use crate::bvh::TriangleBvh;
use crate::geom::Joints;
use crate::tables::MeshTables;
use crate::{AttachError, BoneWeights, ComponentReport, HeatMesh, BONES};
use faer::Mat;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use symcorr_mesh::geometry::closest_on_segment;
use symcorr_mesh::TriMesh;
use symcorr_spectral::{Laplacian, DEGENERATE_REL};

/// Bones within this relative distance of the nearest visible one share its heat (ties, as in
/// Pinocchio's 1.0001).
const TIE: f64 = 1e-4;

/// Bones farther than `FAR` × the nearest bone's distance are not tried as heat sources.
const FAR: f64 = 2.0;

pub(crate) struct Heat {
    pub weights: BoneWeights,
    pub components: Vec<ComponentReport>,
    pub nearest_bone_vertices: usize,
}

/// The heat sources of one vertex: `(distance to the nearest visible bone, tied bones)`,
/// or the nearest bone ignoring visibility with `visible = false`.
struct Source {
    d: f64,
    bones: Vec<usize>,
    visible: bool,
}

/// A bone as a heat source of a vertex: `(distance / reach, bone, closest point)`.
type BoneDistance = (f64, usize, Point3<f64>);

/// Per active bone `(distance / reach, bone, closest point)` from `x`, in `active`'s order
/// (a bone with reach 2 claims vertices twice as far), and the closest point of the nearest
/// bone by plain distance (the first of equals; `x` without bones).
fn bone_distances(
    x: &Point3<f64>,
    p: &Joints,
    active: &[usize],
    reach: &[f64; 19],
) -> (Vec<BoneDistance>, Point3<f64>) {
    let mut nearest: Option<(f64, Point3<f64>)> = None;
    let d = active
        .iter()
        .map(|&b| {
            let (q, d) =
                closest_on_segment(x, &p[BONES[b].parent.index()], &p[BONES[b].child.index()]);
            if nearest.is_none_or(|(best, _)| d.total_cmp(&best).is_lt()) {
                nearest = Some((d, q));
            }
            (d / reach[b], b, q)
        })
        .collect();
    (d, nearest.map_or(*x, |(_, q)| q))
}

/// The heat sources of the vertex `v` at `x`, from its [`bone_distances`] `d`.
fn sources(
    x: Point3<f64>,
    normal: Vector3<f64>,
    v: u32,
    mut d: Vec<BoneDistance>,
    bvh: &TriangleBvh,
) -> Source {
    d.sort_by(|a, b| a.0.total_cmp(&b.0));
    let nearest = Source {
        d: d[0].0,
        bones: vec![d[0].1],
        visible: false,
    };
    for (i, &(di, _, _)) in d.iter().enumerate() {
        // A bone much farther than the nearest one is no sensible heat source (and would pull
        // the vertex to a distant segment): stop looking; the vertex gets its weights by
        // diffusion from its neighbours. Also bounds the number of visibility queries.
        if di > FAR * d[0].0 {
            break;
        }
        // Visibility of the bone at its closest point (Baran & Popović test the segment
        // from the vertex to the bone against the surface), and the bone must lie behind the
        // vertex's tangent plane: where two limbs touch or interpenetrate (inner thighs, a
        // linear-blend-skinned groin) the segment to the *other* limb's bone may cross no
        // triangle, but it leaves this limb through its outward normal.
        if facing(&normal, &x, &d[i].2) || bvh.segment_blocked(&x, &d[i].2, v) {
            continue;
        }
        let mut bones = vec![d[i].1];
        for &(dk, bk, qk) in &d[i + 1..] {
            if dk > di * (1.0 + TIE) {
                break;
            }
            if !facing(&normal, &x, &qk) && !bvh.segment_blocked(&x, &qk, v) {
                bones.push(bk);
            }
        }
        return Source {
            d: di,
            bones,
            visible: true,
        };
    }
    nearest
}

/// True if `q` lies in front of the surface at `x` (outward `normal`): more than
/// [`FRONT`] of the way along the normal.
fn facing(normal: &Vector3<f64>, x: &Point3<f64>, q: &Point3<f64>) -> bool {
    let e = q - x;
    normal.dot(&e) > FRONT * e.norm()
}

/// Cosine between a vertex's outward normal and the direction to a bone above which the bone is
/// "in front of" the surface and no heat source for it (0: the tangent plane).
const FRONT: f64 = 0.0;

/// The bone-heat problem of one mesh: joints `p`, the `active` bones (indices into [`BONES`])
/// with their `reach`, the heat constant `c` and the smallest weight kept.
pub(crate) struct HeatProblem<'a> {
    pub p: &'a Joints,
    pub active: &'a [usize],
    pub reach: &'a [f64; 19],
    pub c: f64,
    pub min_weight: f64,
}

/// Computes bone-heat weights of every vertex of `tables`' mesh on the heat mesh `heat_mesh`
/// asks for (`height`: the skeleton's height, the unit of [`HeatMesh::Clustered`]'s radius).
/// `bvh` is the mesh's ([`TriangleBvh::new`]).
pub(crate) fn bone_heat(
    tables: &MeshTables<'_>,
    bvh: &TriangleBvh,
    problem: &HeatProblem,
    heat_mesh: HeatMesh,
    height: f64,
) -> Result<Heat, AttachError> {
    let mesh = tables.mesh;
    let clusters = match heat_mesh {
        HeatMesh::Input => None,
        HeatMesh::Clustered { radius } => Some(cluster(mesh, tables.neighbors(), radius * height))
            .filter(|c| c.seed.len() < mesh.num_vertices()),
    };
    let Some(cl) = clusters else {
        let ids: Vec<u32> = (0..mesh.num_vertices() as u32).collect();
        let solved = solve(mesh, &ids, bvh, problem)?;
        return Ok(solved.report(mesh.num_vertices(), |v| v));
    };
    let solved = solve(&cl.coarse, &cl.seed, bvh, problem)?;
    Ok(solved.report(mesh.num_vertices(), |v| cl.of[v] as usize))
}

/// Vertices gathered into clusters ([`cluster`]).
struct Clusters {
    /// The mesh of the clusters: one vertex per cluster (at its seed's position), the input's
    /// triangles whose corners lie in three different clusters.
    coarse: TriMesh,
    /// Per input vertex, its cluster.
    of: Vec<u32>,
    /// Per cluster, its seed: the input vertex it grew from.
    seed: Vec<u32>,
}

/// Gathers `mesh`'s vertices into clusters by greedy region growing over its edges: in vertex
/// order, each vertex not yet taken seeds a cluster and takes every untaken vertex it reaches
/// along edges without leaving the ball of `radius` around the seed. Clusters only follow
/// edges, so two sheets that touch without sharing an edge (an arm against the torso) are
/// never merged, and the coarse mesh has the input's connected components. A mesh whose edges
/// are all longer than `radius` is its own clustering.
fn cluster(mesh: &TriMesh, neighbors: &[Vec<u32>], radius: f64) -> Clusters {
    let n = mesh.num_vertices();
    let r2 = radius * radius;
    let mut of = vec![u32::MAX; n];
    let mut seed = Vec::new();
    let mut queue = Vec::new();
    for s in 0..n {
        if of[s] != u32::MAX {
            continue;
        }
        let c = seed.len() as u32;
        seed.push(s as u32);
        of[s] = c;
        let x = Point3::from(mesh.positions[s]);
        queue.clear();
        queue.push(s as u32);
        while let Some(v) = queue.pop() {
            for &u in &neighbors[v as usize] {
                let u = u as usize;
                if of[u] == u32::MAX && (Point3::from(mesh.positions[u]) - x).norm_squared() <= r2 {
                    of[u] = c;
                    queue.push(u as u32);
                }
            }
        }
    }
    let mut seen = std::collections::HashSet::new();
    let triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| of[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .filter(|t| {
            let mut key = *t;
            key.sort_unstable();
            seen.insert(key)
        })
        .collect();
    let positions = seed.iter().map(|&v| mesh.positions[v as usize]).collect();
    Clusters {
        coarse: TriMesh {
            positions,
            triangles,
        },
        of,
        seed,
    }
}

/// What [`solve`] found per vertex of its mesh.
struct Solved {
    rows: Vec<Vec<(usize, f64)>>,
    /// Per vertex: its component among the solved ones (`None`: in no non-degenerate
    /// triangle), whether it saw a bone, whether it took its nearest bone's label.
    vertex: Vec<(Option<u32>, bool, bool)>,
    /// Per component: no vertex of it saw a bone.
    fallback: Vec<bool>,
}

impl Solved {
    /// The weights of every input vertex, `solved_of(v)` being the solved vertex it takes
    /// them from; component counts are of input vertices.
    fn report(self, n_input: usize, solved_of: impl Fn(usize) -> usize) -> Heat {
        let mut components: Vec<ComponentReport> = self
            .fallback
            .iter()
            .map(|&fallback| ComponentReport {
                vertices: 0,
                visible_vertices: 0,
                fallback,
            })
            .collect();
        let mut nearest_bone_vertices = 0;
        let mut rows = Vec::with_capacity(n_input);
        for v in 0..n_input {
            let i = solved_of(v);
            let (comp, visible, nearest) = self.vertex[i];
            if let Some(k) = comp {
                components[k as usize].vertices += 1;
                components[k as usize].visible_vertices += usize::from(visible);
            }
            nearest_bone_vertices += usize::from(nearest);
            rows.push(self.rows[i].clone());
        }
        Heat {
            weights: BoneWeights::from_rows(rows),
            components,
            nearest_bone_vertices,
        }
    }
}

/// Bone heat on `mesh` itself; `bvh_id[v]` is vertex `v`'s id in the mesh `bvh` was built on
/// (what its visibility rays skip).
fn solve(
    mesh: &TriMesh,
    bvh_id: &[u32],
    bvh: &TriangleBvh,
    problem: &HeatProblem,
) -> Result<Solved, AttachError> {
    let HeatProblem {
        p,
        active,
        reach,
        c,
        min_weight,
    } = *problem;
    let n = mesh.num_vertices();
    // The Laplacian needs every vertex in a non-degenerate triangle (same test as
    // symcorr-spectral): solve on that sub-mesh, give the rest their nearest bone.
    let keep_tri: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .copied()
        .filter(|t| {
            let [a, b, c] = t.map(|v| Point3::from(mesh.positions[v as usize]));
            let e = [b - a, c - b, a - c];
            let longest = e.iter().map(|x| x.dot(x)).fold(0.0, f64::max);
            let area2 = e[0].cross(&e[1]).norm();
            area2 > DEGENERATE_REL * longest && area2 > 0.0
        })
        .collect();
    let mut new_id = vec![u32::MAX; n];
    let mut old_id = Vec::new();
    for t in &keep_tri {
        for &v in t {
            if new_id[v as usize] == u32::MAX {
                new_id[v as usize] = old_id.len() as u32;
                old_id.push(v);
            }
        }
    }
    let bone_distance = |x: &Point3<f64>, b: usize| {
        closest_on_segment(x, &p[BONES[b].parent.index()], &p[BONES[b].child.index()])
    };
    let nearest_only = |x: Point3<f64>| -> usize {
        active
            .iter()
            .copied()
            .min_by(|&a, &b| {
                let da = bone_distance(&x, a).1 / reach[a];
                let db = bone_distance(&x, b).1 / reach[b];
                da.total_cmp(&db)
            })
            .unwrap_or(0)
    };
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let mut vertex = vec![(None, false, false); n];
    let mut fallback = Vec::new();
    if !old_id.is_empty() {
        let sub_tris: Vec<[u32; 3]> = keep_tri
            .iter()
            .map(|t| t.map(|v| new_id[v as usize]))
            .collect();
        let sub_pos: Vec<_> = old_id.iter().map(|&v| mesh.positions[v as usize]).collect();
        let sub_mesh = TriMesh {
            positions: sub_pos,
            triangles: sub_tris,
        };
        let m = sub_mesh.num_vertices();
        let mut normals = sub_mesh.vertex_normals();
        // The facing test needs outward normals; a mesh wound the other way round (or a scan
        // meshed facing away) is recognised by its nearest bones lying in front of most
        // vertices, and its normals are turned round.
        // Each vertex's bone distances serve the vote and its heat sources alike.
        let distances: Vec<(Vec<BoneDistance>, bool)> = (0..m)
            .into_par_iter()
            .map(|i| {
                let x = Point3::from(sub_mesh.positions[i]);
                let (d, q) = bone_distances(&x, p, active, reach);
                (d, Vector3::from(normals[i]).dot(&(q - x)) > 0.0)
            })
            .collect();
        let in_front = distances.iter().filter(|d| d.1).count();
        if 2 * in_front > m {
            for n in &mut normals {
                *n = (-Vector3::from(*n)).into();
            }
        }
        let src: Vec<Source> = distances
            .into_par_iter()
            .enumerate()
            .map(|(i, (d, _))| {
                let x = Point3::from(sub_mesh.positions[i]);
                sources(x, normals[i].into(), bvh_id[old_id[i] as usize], d, bvh)
            })
            .collect();
        let lap = Laplacian::new(&sub_mesh).map_err(|e| AttachError::Solver(e.to_string()))?;
        // Per component: at least one heat source, or every vertex uses its nearest bone.
        let (comp, ncomp) = sub_mesh.connected_components();
        let mut visible = vec![0usize; ncomp];
        for i in 0..m {
            if src[i].visible {
                visible[comp[i] as usize] += 1;
            }
        }
        fallback = visible.iter().map(|&v| v == 0).collect();
        for i in 0..m {
            vertex[old_id[i] as usize] = (Some(comp[i]), src[i].visible, false);
        }
        let mut h = vec![0.0; m];
        let mut rhs = Mat::<f64>::zeros(m, active.len());
        let col: std::collections::HashMap<usize, usize> =
            active.iter().enumerate().map(|(i, &b)| (b, i)).collect();
        for i in 0..m {
            let s = &src[i];
            if !(s.visible || fallback[comp[i] as usize]) {
                continue;
            }
            // H_ii = c/d² (a vertex on a bone gets a large but finite weight).
            let d2 = (s.d * s.d).max(1e-12 * lap.mass[i]);
            h[i] = lap.mass[i] * c / d2;
            let share = h[i] / s.bones.len() as f64;
            for b in &s.bones {
                rhs[(i, col[b])] += share;
            }
        }
        let sys = lap
            .factor(0.0, Some(&h))
            .map_err(|e| AttachError::Solver(e.to_string()))?;
        let w = sys.solve_many(rhs.as_ref());
        for i in 0..m {
            let mut row: Vec<(usize, f64)> = (0..active.len())
                .map(|k| (active[k], w[(i, k)].clamp(0.0, 1.0)))
                .filter(|&(_, x)| x >= min_weight && x > 0.0)
                .collect();
            let s: f64 = row.iter().map(|r| r.1).sum();
            if !(s > 0.0) {
                row = vec![(nearest_only(sub_mesh.positions[i].into()), 1.0)];
                vertex[old_id[i] as usize].2 = true;
            } else {
                for r in &mut row {
                    r.1 /= s;
                }
            }
            rows[old_id[i] as usize] = row;
        }
    }
    for v in 0..n {
        if new_id[v] == u32::MAX {
            rows[v] = vec![(nearest_only(mesh.positions[v].into()), 1.0)];
            vertex[v].2 = true;
        }
    }
    Ok(Solved {
        rows,
        vertex,
        fallback,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` grid of unit-square cells (two triangles each) with spacing `step`, at height
    /// `z`, its vertex ids starting at `first`.
    fn sheet(w: usize, h: usize, step: f64, z: f64, first: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let id = |i: usize, j: usize| first + (j * (w + 1) + i) as u32;
        let positions = (0..=h)
            .flat_map(|j| (0..=w).map(move |i| [i as f64 * step, j as f64 * step, z]))
            .collect();
        let triangles = (0..h)
            .flat_map(|j| {
                (0..w).flat_map(move |i| {
                    [
                        [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                        [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
                    ]
                })
            })
            .collect();
        (positions, triangles)
    }

    /// Two parallel sheets 5 mm apart that share no edge (an arm resting on the torso).
    fn two_sheets() -> (TriMesh, usize) {
        let (mut positions, mut triangles) = sheet(20, 20, 0.01, 0.0, 0);
        let first = positions.len();
        let (p, t) = sheet(20, 20, 0.01, 0.005, first as u32);
        positions.extend(p);
        triangles.extend(t);
        (
            TriMesh {
                positions,
                triangles,
            },
            first,
        )
    }

    #[test]
    fn clusters_stay_within_their_radius_and_never_join_sheets_without_an_edge() {
        let (mesh, first) = two_sheets();
        let radius = 0.025;
        let c = cluster(&mesh, &mesh.vertex_neighbors(), radius);
        assert!(
            c.seed.len() * 4 < mesh.num_vertices(),
            "{} clusters of {} vertices",
            c.seed.len(),
            mesh.num_vertices()
        );
        for (v, &k) in c.of.iter().enumerate() {
            let s = c.seed[k as usize] as usize;
            let d = (Point3::from(mesh.positions[v]) - Point3::from(mesh.positions[s])).norm();
            assert!(d <= radius + 1e-12, "vertex {v} lies {d} from its seed");
            assert_eq!(
                v < first,
                s < first,
                "vertex {v} joined the other sheet's cluster"
            );
            assert_eq!(c.of[s], k, "a seed belongs to its own cluster");
        }
        // The coarse mesh keeps the two sheets apart and each in one piece.
        assert_eq!(c.coarse.connected_components().1, 2);
        assert_eq!(c.coarse.num_vertices(), c.seed.len());
    }

    #[test]
    fn a_radius_below_every_edge_leaves_the_mesh_as_it_is() {
        let (mesh, _) = two_sheets();
        let c = cluster(&mesh, &mesh.vertex_neighbors(), 0.004);
        assert_eq!(c.seed.len(), mesh.num_vertices());
        assert!(c.of.iter().enumerate().all(|(v, &k)| k as usize == v));
        assert_eq!(c.coarse.triangles, mesh.triangles);
    }
}
