//! Segment pools: which target vertices a template vertex may be matched to (the skeleton
//! filter of §3.2 as a hard constraint on every nearest-neighbour search), and the exact
//! nearest neighbour within a pool by blocked brute force ([`nearest_in_pools`]) for the
//! refined method's high-dimensional features (the articulated method's 6-D queries use the
//! k-d trees of module `kdtree`).

use crate::{same_len, CorrespondError};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;
use symcorr_skeleton::{BodySide, Segment};
use symcorr_spectral::EdgeGraph;

/// Which target vertices a template vertex may be matched to.
///
/// A template vertex belongs to a *group*: its segment and, on the midline segments (pelvis,
/// torso, head), its sagittal half. A group's pool is every target vertex within geodesic
/// distance `band` of the target's region of that segment (so label boundaries that moved
/// between the two meshes do not cut good matches off), minus the vertices on the other side
/// of the body: a vertex's side is its segment's side (left/right limb) or, on the midline, its
/// half; a pool never mixes a left point with a right one. Hence no match of a constrained map
/// ever crosses from a left segment to a right one, and the two halves of the midline stay
/// apart — the skeleton filter (§3.2) as a hard constraint on every nearest-neighbour search.
#[derive(Debug, Clone)]
pub struct SegmentPools {
    /// Group index per template vertex.
    groups: Vec<u32>,
    /// Target vertices per group.
    pools: Vec<Vec<u32>>,
    /// Template vertices per group.
    members: Vec<Vec<u32>>,
}

/// The segments that share a joint with `s` in the skeleton (DESIGN.md's table: e.g. the torso
/// meets the pelvis at the spine joint, and the head and both clavicles at the shoulder centre).
///
/// ```
/// use symcorr_skeleton::Segment::*;
/// use symcorr_correspond::adjacent_segments;
/// assert_eq!(adjacent_segments(ForearmLeft), vec![UpperArmLeft]);
/// assert!(adjacent_segments(Torso).contains(&ClavicleRight));
/// ```
pub fn adjacent_segments(s: Segment) -> Vec<Segment> {
    let joints = |x: Segment| {
        x.bones()
            .iter()
            .flat_map(|b| [b.parent, b.child])
            .collect::<Vec<_>>()
    };
    let mine = joints(s);
    Segment::ALL
        .into_iter()
        .filter(|&o| o != s && joints(o).iter().any(|j| mine.contains(j)))
        .collect()
}

/// The side of a vertex: its segment's side on a limb, its sagittal half on the midline.
fn vertex_side(s: Segment, half: BodySide) -> BodySide {
    match s.side() {
        BodySide::Midline => half,
        x => x,
    }
}

impl SegmentPools {
    /// Builds the groups of the template and their target pools.
    ///
    /// `band` is in the target's length units (e.g. `0.02·√area`); `graph` is the target's
    /// edge graph (geodesic band). Halves are optional (`None`: midline segments are one group
    /// each). A pool is never empty: if the target has no vertex of some template segment
    /// (or none on the compatible side within the band), the pool falls back to every target
    /// vertex of a compatible side, and failing that to every target vertex.
    ///
    /// Errors: [`CorrespondError::LengthMismatch`] when a side's halves disagree with its
    /// labels, or the graph with the target's labels.
    pub fn new(
        template: (&[Segment], Option<&[BodySide]>),
        target: (&[Segment], Option<&[BodySide]>),
        graph: &EdgeGraph,
        band: f64,
    ) -> Result<SegmentPools, CorrespondError> {
        SegmentPools::build(template, target, graph, band, false)
    }

    /// Like [`SegmentPools::new`], but a group's pool also holds the target regions of the
    /// segments adjacent to its own in the skeleton (sharing a joint, [`adjacent_segments`]),
    /// still never the other side of the body. For a map that is already aligned
    /// extrinsically, where a label boundary that moved between the two meshes must not cut
    /// the true vertex out of the pool (a neck vertex the target's attachment gave to a
    /// clavicle), while left and right stay apart.
    ///
    /// ```
    /// use symcorr_skeleton::Segment::{ClavicleLeft, ClavicleRight, Torso};
    /// use symcorr_correspond::SegmentPools;
    /// use symcorr_mesh::TriMesh;
    /// use symcorr_spectral::EdgeGraph;
    /// // Three target vertices far apart (no band reaches across).
    /// let mesh = TriMesh::new(vec![[0.0, 0.0, 0.0], [9.0, 0.0, 0.0], [0.0, 9.0, 0.0]], vec![[0, 1, 2]]).unwrap();
    /// let graph = EdgeGraph::new(&mesh);
    /// let target = [Torso, ClavicleLeft, ClavicleRight];
    /// let strict = SegmentPools::new((&[ClavicleLeft], None), (&target, None), &graph, 0.1).unwrap();
    /// assert_eq!(strict.pool_of(0), &[1]);
    /// let wide = SegmentPools::with_adjacent((&[ClavicleLeft], None), (&target, None), &graph, 0.1).unwrap();
    /// assert_eq!(wide.pool_of(0), &[0, 1]); // the torso joins; the right clavicle never does
    /// ```
    pub fn with_adjacent(
        template: (&[Segment], Option<&[BodySide]>),
        target: (&[Segment], Option<&[BodySide]>),
        graph: &EdgeGraph,
        band: f64,
    ) -> Result<SegmentPools, CorrespondError> {
        SegmentPools::build(template, target, graph, band, true)
    }

    fn build(
        template: (&[Segment], Option<&[BodySide]>),
        target: (&[Segment], Option<&[BodySide]>),
        graph: &EdgeGraph,
        band: f64,
        adjacent: bool,
    ) -> Result<SegmentPools, CorrespondError> {
        let (tl, th) = template;
        let (ul, uh) = target;
        if let Some(h) = th {
            same_len(
                "segment pools: template halves (one per label)",
                tl.len(),
                h.len(),
            )?;
        }
        if let Some(h) = uh {
            same_len(
                "segment pools: target halves (one per label)",
                ul.len(),
                h.len(),
            )?;
        }
        same_len(
            "segment pools: target graph vertices (one per label)",
            ul.len(),
            graph.len(),
        )?;
        let half_of = |h: Option<&[BodySide]>, v: usize| h.map_or(BodySide::Midline, |h| h[v]);
        // Group key: segment index·3 + (half + 1).
        let key = |s: Segment, h: BodySide| s.index() * 3 + (h.sign() + 1) as usize;
        let mut group_of_key = [u32::MAX; Segment::COUNT * 3];
        let mut keys = Vec::new();
        let mut groups = Vec::with_capacity(tl.len());
        let mut members: Vec<Vec<u32>> = Vec::new();
        for (v, &s) in tl.iter().enumerate() {
            let h = if s.side() == BodySide::Midline {
                half_of(th, v)
            } else {
                BodySide::Midline
            };
            let k = key(s, h);
            if group_of_key[k] == u32::MAX {
                group_of_key[k] = keys.len() as u32;
                keys.push((s, h));
                members.push(Vec::new());
            }
            let g = group_of_key[k];
            groups.push(g);
            members[g as usize].push(v as u32);
        }
        // Target vertices per segment.
        let mut by_segment: Vec<Vec<u32>> = vec![Vec::new(); Segment::COUNT];
        for (v, s) in ul.iter().enumerate() {
            by_segment[s.index()].push(v as u32);
        }
        let target_side: Vec<BodySide> = ul
            .iter()
            .enumerate()
            .map(|(v, &s)| vertex_side(s, half_of(uh, v)))
            .collect();
        // Geodesic band around each used segment's region (bounded multi-source Dijkstra).
        let allowed = |s: Segment| -> Vec<Segment> {
            let mut a = vec![s];
            if adjacent {
                a.extend(adjacent_segments(s));
            }
            a
        };
        let mut used = [false; Segment::COUNT];
        for &(s, _) in &keys {
            for a in allowed(s) {
                used[a.index()] = true;
            }
        }
        let bands: Vec<Option<Vec<f64>>> = (0..Segment::COUNT)
            .into_par_iter()
            .map(|i| {
                (used[i] && !by_segment[i].is_empty())
                    .then(|| graph.distances_within(&by_segment[i], band).ok())
                    .flatten()
            })
            .collect();
        let pools = keys
            .iter()
            .map(|&(s, h)| {
                let side = vertex_side(s, h);
                let ok_side = |q: usize| !side.opposes(target_side[q]);
                let regions: Vec<&Vec<f64>> = allowed(s)
                    .into_iter()
                    .filter_map(|a| bands[a.index()].as_ref())
                    .collect();
                let banded: Vec<u32> = (0..ul.len())
                    .filter(|&q| regions.iter().any(|d| d[q].is_finite()) && ok_side(q))
                    .map(|q| q as u32)
                    .collect();
                // Never an empty pool: the side-compatible vertices, else every vertex.
                if !banded.is_empty() {
                    return banded;
                }
                let sided: Vec<u32> = (0..ul.len())
                    .filter(|&q| ok_side(q))
                    .map(|q| q as u32)
                    .collect();
                if sided.is_empty() {
                    (0..ul.len() as u32).collect()
                } else {
                    sided
                }
            })
            .collect();
        Ok(SegmentPools {
            groups,
            pools,
            members,
        })
    }

    /// Number of groups.
    pub fn len(&self) -> usize {
        self.pools.len()
    }

    /// True without groups (an empty template).
    pub fn is_empty(&self) -> bool {
        self.pools.is_empty()
    }

    /// The target vertices template vertex `p` may be matched to, in ascending order.
    pub fn pool_of(&self, p: u32) -> &[u32] {
        &self.pools[self.groups[p as usize] as usize]
    }

    /// May template vertex `p` be matched to target vertex `q` (is `q` in
    /// [`SegmentPools::pool_of`] `p`)? A binary search: every pool is built in ascending order.
    pub fn pool_contains(&self, p: u32, q: u32) -> bool {
        self.pool_of(p).binary_search(&q).is_ok()
    }

    /// Number of template vertices.
    pub fn num_template(&self) -> usize {
        self.groups.len()
    }

    /// Target vertices per group.
    pub(crate) fn pools(&self) -> &[Vec<u32>] {
        &self.pools
    }

    /// Template vertices per group.
    pub(crate) fn members(&self) -> &[Vec<u32>] {
        &self.members
    }

    /// The template vertices of each group for which `keep` holds (a subset for
    /// [`nearest_in_pools_for`]).
    pub(crate) fn members_where(&self, keep: impl Fn(u32) -> bool) -> Vec<Vec<u32>> {
        self.members
            .iter()
            .map(|m| m.iter().copied().filter(|&v| keep(v)).collect())
            .collect()
    }
}

/// For every template vertex `p`, the target vertex of `p`'s pool whose feature row is nearest
/// (Euclidean) to `p`'s, and that squared distance. `template` is `n_template × d`, `target`
/// is `n_target × d`.
///
/// Exact brute force per group: `‖a‖² + ‖b‖² − 2 a·b` by one dense product per block of 256
/// template rows against the group's pool (faer), blocks in parallel (rayon).
///
/// Errors: [`CorrespondError::LengthMismatch`] if the widths differ or the template has a
/// different number of rows than the pools were built for,
/// [`CorrespondError::IndexOutOfRange`] if a pool names a row beyond `target`.
pub fn nearest_in_pools(
    template: MatRef<'_, f64>,
    target: MatRef<'_, f64>,
    pools: &SegmentPools,
) -> Result<Vec<(u32, f64)>, CorrespondError> {
    nearest_in_pools_for(template, target, pools, None)
}

/// [`nearest_in_pools`] for the template vertices `subset` only (all when `None`; otherwise
/// per group, like [`SegmentPools::members_where`]); entries of other vertices are `(0, ∞)`.
pub(crate) fn nearest_in_pools_for(
    template: MatRef<'_, f64>,
    target: MatRef<'_, f64>,
    pools: &SegmentPools,
    subset: Option<&[Vec<u32>]>,
) -> Result<Vec<(u32, f64)>, CorrespondError> {
    same_len(
        "target feature columns (as the template's)",
        template.ncols(),
        target.ncols(),
    )?;
    same_len(
        "template feature rows (one per vertex of the pools)",
        pools.num_template(),
        template.nrows(),
    )?;
    if let Some(&q) = pools
        .pools
        .iter()
        .flatten()
        .find(|&&q| q as usize >= target.nrows())
    {
        return Err(CorrespondError::IndexOutOfRange {
            what: "pool vertex (target feature row)",
            index: q as usize,
            len: target.nrows(),
        });
    }
    const BLOCK: usize = 256;
    let d = template.ncols();
    // Gathered pools, one matrix per group.
    let gathered: Vec<(Mat<f64>, Vec<f64>)> = pools
        .pools
        .par_iter()
        .map(|pool| {
            let m = Mat::from_fn(pool.len(), d, |i, j| target[(pool[i] as usize, j)]);
            let norms = (0..pool.len())
                .map(|i| (0..d).map(|j| m[(i, j)] * m[(i, j)]).sum())
                .collect();
            (m, norms)
        })
        .collect();
    // Work items: (group, block of members).
    let members = subset.unwrap_or(&pools.members);
    let items: Vec<(usize, &[u32])> = members
        .iter()
        .enumerate()
        .flat_map(|(g, m)| m.chunks(BLOCK).map(move |c| (g, c)))
        .collect();
    let results: Vec<Vec<(u32, (u32, f64))>> = items
        .par_iter()
        .map(|&(g, block)| {
            let (db, norms) = &gathered[g];
            let pool = &pools.pools[g];
            if pool.is_empty() {
                return block.iter().map(|&p| (p, (0, f64::INFINITY))).collect();
            }
            let q = Mat::from_fn(block.len(), d, |i, j| template[(block[i] as usize, j)]);
            let mut prod = Mat::<f64>::zeros(block.len(), pool.len());
            matmul(
                prod.as_mut(),
                Accum::Replace,
                q.as_ref(),
                db.as_ref().transpose(),
                1.0,
                Par::Seq,
            );
            block
                .iter()
                .enumerate()
                .map(|(i, &p)| {
                    let qn: f64 = (0..d).map(|j| q[(i, j)] * q[(i, j)]).sum();
                    let mut best = (0usize, f64::INFINITY);
                    for (k, &n) in norms.iter().enumerate() {
                        let v = n - 2.0 * prod[(i, k)];
                        if v < best.1 {
                            best = (k, v);
                        }
                    }
                    (p, (pool[best.0], (best.1 + qn).max(0.0)))
                })
                .collect()
        })
        .collect();
    let mut out = vec![(0u32, f64::INFINITY); template.nrows()];
    for (p, r) in results.into_iter().flatten() {
        out[p as usize] = r;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use Segment::*;

    /// Every segment's adjacent pool holds its own and its skeleton neighbours' regions and
    /// never a vertex of the other side: 17 separate triangles, one per segment, 100 apart.
    #[test]
    fn adjacent_pools_never_cross_sides() {
        let positions: Vec<[f64; 3]> = (0..Segment::COUNT)
            .flat_map(|i| {
                let x = 100.0 * i as f64;
                [[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]]
            })
            .collect();
        let triangles = (0..Segment::COUNT as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        let mesh = symcorr_mesh::TriMesh::new(positions, triangles).unwrap();
        let graph = EdgeGraph::new(&mesh);
        let target: Vec<Segment> = Segment::ALL.iter().flat_map(|&s| [s; 3]).collect();
        let template = Segment::ALL;
        let pools =
            SegmentPools::with_adjacent((&template, None), (&target, None), &graph, 0.5).unwrap();
        for (p, &s) in template.iter().enumerate() {
            let got: Vec<Segment> = pools
                .pool_of(p as u32)
                .iter()
                .map(|&q| target[q as usize])
                .collect();
            assert!(got.contains(&s), "{s:?}");
            for &o in &got {
                assert!(!o.side().opposes(s.side()), "{s:?} pool holds {o:?}");
                assert!(
                    o == s || adjacent_segments(s).contains(&o),
                    "{s:?} pool holds {o:?}"
                );
            }
            for o in adjacent_segments(s) {
                if !o.side().opposes(s.side()) {
                    assert!(got.contains(&o), "{s:?} pool lacks {o:?}");
                }
            }
        }
        // The torso's neighbours: pelvis, head and both clavicles.
        let mut torso = adjacent_segments(Torso);
        torso.sort_by_key(|s| s.index());
        assert_eq!(torso, vec![Pelvis, Head, ClavicleLeft, ClavicleRight]);
    }

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed >> 33
    }

    /// `perm[old] = new` applied to a mesh's vertex ids.
    /// A strip of 2·w vertices: the first half left, the second right, with a midline column.
    fn strip(w: usize) -> (symcorr_mesh::TriMesh, Vec<Segment>, Vec<BodySide>) {
        let mut pos = Vec::new();
        for y in 0..2 {
            for x in 0..w {
                pos.push([x as f64, y as f64, 0.0]);
            }
        }
        let mut tris = Vec::new();
        for x in 0..w - 1 {
            let (a, b, c, d) = (x as u32, x as u32 + 1, (w + x) as u32, (w + x + 1) as u32);
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
        let mesh = symcorr_mesh::TriMesh::new(pos, tris).unwrap();
        let mid = w / 2;
        let labels: Vec<Segment> = (0..2 * w)
            .map(|v| match (v % w).cmp(&mid) {
                std::cmp::Ordering::Less => ThighLeft,
                std::cmp::Ordering::Equal => Pelvis,
                std::cmp::Ordering::Greater => ThighRight,
            })
            .collect();
        // Midline vertices on the left half (y = 0) and right half (y = 1).
        let halves: Vec<BodySide> = (0..2 * w)
            .map(|v| match (v % w == mid, v / w) {
                (true, 0) => BodySide::Left,
                (true, _) => BodySide::Right,
                (false, _) => BodySide::Midline,
            })
            .collect();
        (mesh, labels, halves)
    }

    #[test]
    fn pools_never_cross_sides_even_when_features_prefer_it() {
        let (mesh, labels, halves) = strip(11);
        let g = EdgeGraph::new(&mesh);
        // Huge band: every vertex is geodesically near every segment, so only sides separate.
        let pools =
            SegmentPools::new((&labels, Some(&halves)), (&labels, Some(&halves)), &g, 1e9).unwrap();
        let side = |v: usize| vertex_side(labels[v], halves[v]);
        for p in 0..labels.len() {
            for &q in pools.pool_of(p as u32) {
                assert!(!side(p).opposes(side(q as usize)), "{p} may match {q}");
            }
        }
        // Features that are the mirror image: each vertex's best feature match is its mirror.
        let n = labels.len();
        let f = Mat::from_fn(n, 1, |v, _| ((v % 11) as f64 - 5.0).abs());
        let g2 = Mat::from_fn(n, 1, |v, _| ((v % 11) as f64 - 5.0).abs() + 0.01);
        let nn = nearest_in_pools(f.as_ref(), g2.as_ref(), &pools).unwrap();
        for (p, (q, d)) in nn.iter().enumerate() {
            assert!(!side(p).opposes(side(*q as usize)));
            assert!((d - 1e-4).abs() < 1e-9, "exact squared distance: {d}");
        }
        // A segment the target lacks: the pool falls back to the compatible side, not empty.
        let mut no_shin = labels.clone();
        no_shin[0] = ShinLeft;
        let fb = SegmentPools::new((&no_shin, Some(&halves)), (&labels, Some(&halves)), &g, 0.0)
            .unwrap();
        let pool = fb.pool_of(0);
        assert!(!pool.is_empty());
        assert!(pool.iter().all(|&q| side(q as usize) != BodySide::Right));
        // A zero band keeps each segment to itself.
        let tight =
            SegmentPools::new((&labels, Some(&halves)), (&labels, Some(&halves)), &g, 0.0).unwrap();
        for p in 0..n {
            assert!(tight
                .pool_of(p as u32)
                .iter()
                .all(|&q| labels[q as usize] == labels[p]));
        }
    }

    #[test]
    fn nearest_in_pools_equals_brute_force() {
        let (mesh, labels, halves) = strip(9);
        let g = EdgeGraph::new(&mesh);
        let pools =
            SegmentPools::new((&labels, Some(&halves)), (&labels, Some(&halves)), &g, 1.5).unwrap();
        let mut seed = 11u64;
        let n = labels.len();
        let mut r = || (lcg(&mut seed) % 1000) as f64 / 1000.0;
        let a = Mat::from_fn(n, 4, |_, _| r());
        let b = Mat::from_fn(n, 4, |_, _| r());
        let nn = nearest_in_pools(a.as_ref(), b.as_ref(), &pools).unwrap();
        for p in 0..n {
            let d = |q: u32| {
                (0..4)
                    .map(|j| (a[(p, j)] - b[(q as usize, j)]).powi(2))
                    .sum::<f64>()
            };
            let best = pools
                .pool_of(p as u32)
                .iter()
                .copied()
                .min_by(|&x, &y| d(x).total_cmp(&d(y)))
                .unwrap();
            assert_eq!(nn[p].0, best);
            assert!((nn[p].1 - d(best)).abs() < 1e-12);
        }
        // Wrong widths are errors.
        let c = Mat::<f64>::zeros(n, 3);
        assert!(nearest_in_pools(a.as_ref(), c.as_ref(), &pools).is_err());
    }
}
