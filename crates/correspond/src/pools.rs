//! Segment-constrained dense matching (DESIGN.md, Algorithm 7): nearest neighbours restricted
//! to the template point's body segment ([`SegmentPools`]), an initial dense map from any
//! per-vertex descriptor ([`nearest_in_pools`]), and ZoomOut refinement (Melzi et al. 2019)
//! whose every point-map recovery is restricted the same way ([`zoomout`]).
//!
//! The refined method ([`refine_dense`]) matches every template vertex in three steps:
//!
//! 1. **Skeleton landmark coordinates.** Per mesh, one landmark source set per joint
//!    ([`skeleton_landmarks`](crate::skeleton_landmarks)): the *ring* where the plane through
//!    the joint, normal to its bone, cuts the surface of the segments meeting there, and the
//!    surface *tip* beyond each end joint; plus the vertex nearest each refined joint
//!    ([`joint_landmarks`](crate::joint_landmarks)) — 40 columns. Every vertex's heat-method
//!    geodesic distance to each of them over √area
//!    ([`landmark_coordinates`](crate::landmark_coordinates)) gives coordinates that
//!    correspond by joint name, survive isometries and tell left from right.
//! 2. **Initial map** ([`nearest_in_pools`]): nearest neighbour in landmark ⊕ si-HKS space
//!    (si-HKS columns scaled to unit standard deviation over both meshes, weight
//!    [`RefineOptions::descriptor_weight`]) within the point's pool: the target region of its
//!    segment grown by a geodesic band ([`RefineOptions::band`], so label boundaries that moved
//!    between meshes do not cut good matches off), never on the other side of the body; midline
//!    segments are split by sagittal halves refined by the surface's own symmetry
//!    ([`refine_symmetry_plane`](crate::refine_symmetry_plane)), because a noisy shoulder line
//!    or a turned head tilts the joint plane by many degrees.
//! 3. **Segment-constrained ZoomOut** ([`zoomout`]): functional map `C = Φ_kᵀ M Π Ψ_k` from the
//!    current map, then the point map recovered by nearest neighbour of rows of `Φ_k C` among
//!    rows of `Ψ_k` within the same pools; `k` 20 → 60 by 8; every iteration but the last on an
//!    even stride sample of at most [`DEFAULT_ZOOMOUT_POINTS`] template vertices (masses
//!    rescaled to the total area).
//!
//! Measured: `docs/decisions/2026-11-23-refined-method.md`.

use crate::CorrespondError;
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

fn vertex_side(s: Segment, half: i8) -> i8 {
    match s.side() {
        BodySide::Midline => half.signum(),
        x => x.sign(),
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
    /// Errors: [`CorrespondError::InvalidArgument`] when tables disagree in length.
    pub fn new(
        template: (&[Segment], Option<&[i8]>),
        target: (&[Segment], Option<&[i8]>),
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
        template: (&[Segment], Option<&[i8]>),
        target: (&[Segment], Option<&[i8]>),
        graph: &EdgeGraph,
        band: f64,
    ) -> Result<SegmentPools, CorrespondError> {
        SegmentPools::build(template, target, graph, band, true)
    }

    fn build(
        template: (&[Segment], Option<&[i8]>),
        target: (&[Segment], Option<&[i8]>),
        graph: &EdgeGraph,
        band: f64,
        adjacent: bool,
    ) -> Result<SegmentPools, CorrespondError> {
        let (tl, th) = template;
        let (ul, uh) = target;
        if th.is_some_and(|h| h.len() != tl.len())
            || uh.is_some_and(|h| h.len() != ul.len())
            || graph.len() != ul.len()
        {
            return Err(CorrespondError::InvalidArgument(format!(
                "segment pools: {} template labels, {} target labels, graph of {} vertices, or halves of another length",
                tl.len(),
                ul.len(),
                graph.len()
            )));
        }
        let half_of = |h: Option<&[i8]>, v: usize| h.map_or(0, |h| h[v].signum());
        // Group key: segment index·3 + (half + 1).
        let key = |s: Segment, h: i8| s.index() * 3 + (h + 1) as usize;
        let mut group_of_key = [u32::MAX; 51];
        let mut keys = Vec::new();
        let mut groups = Vec::with_capacity(tl.len());
        let mut members: Vec<Vec<u32>> = Vec::new();
        for (v, &s) in tl.iter().enumerate() {
            let h = if s.side() == BodySide::Midline {
                half_of(th, v)
            } else {
                0
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
        let mut by_segment: Vec<Vec<u32>> = vec![Vec::new(); 17];
        for (v, s) in ul.iter().enumerate() {
            by_segment[s.index()].push(v as u32);
        }
        let target_side: Vec<i8> = ul
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
        let mut used = [false; 17];
        for &(s, _) in &keys {
            for a in allowed(s) {
                used[a.index()] = true;
            }
        }
        let bands: Vec<Option<Vec<f64>>> = (0..17)
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
                let ok_side = |q: usize| side * target_side[q] >= 0;
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

    /// The target vertices template vertex `p` may be matched to.
    pub fn pool_of(&self, p: u32) -> &[u32] {
        &self.pools[self.groups[p as usize] as usize]
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
/// Errors: [`CorrespondError::InvalidArgument`] if the widths differ or the template has a
/// different number of rows than the pools were built for.
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
    if template.ncols() != target.ncols() || template.nrows() != pools.num_template() {
        return Err(CorrespondError::InvalidArgument(format!(
            "features: template {}×{}, target {}×{}, pools for {} template vertices",
            template.nrows(),
            template.ncols(),
            target.nrows(),
            target.ncols(),
            pools.num_template()
        )));
    }
    if let Some(&q) = pools
        .pools
        .iter()
        .flatten()
        .find(|&&q| q as usize >= target.nrows())
    {
        return Err(CorrespondError::InvalidArgument(format!(
            "pool vertex {q} out of range ({} target rows)",
            target.nrows()
        )));
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

/// A Laplace–Beltrami basis: M-orthonormal eigenvectors (columns, ascending eigenvalue) and the
/// lumped mass per vertex.
#[derive(Debug, Clone, Copy)]
pub struct SpectralBasis<'a> {
    /// `n × k` eigenvectors, `ΦᵀMΦ = I`.
    pub vectors: MatRef<'a, f64>,
    /// Lumped (diagonal) mass per vertex.
    pub mass: &'a [f64],
}

/// Default [`ZoomOutOptions::max_points`]: 16,000 (a 13.4k body runs every iteration in full).
pub const DEFAULT_ZOOMOUT_POINTS: usize = 16_000;

/// Options of [`zoomout`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoomOutOptions {
    /// Weight of the anchor features (e.g. landmark coordinates) appended to the spectral
    /// embedding in every point-map recovery; the embedding is scaled to unit mean squared row
    /// norm first, so the weight is relative. 0 = plain ZoomOut.
    pub anchor_weight: f64,
    /// Basis size of the first functional map.
    pub k_start: usize,
    /// Basis size of the last (capped by the bases' sizes).
    pub k_end: usize,
    /// Increase of `k` per iteration.
    pub step: usize,
    /// Template vertices used by every iteration but the last (an even stride sample when the
    /// template has more); the last iteration maps every vertex. Bounds the cost on large
    /// meshes (the nearest-neighbour search is quadratic in a segment's size).
    pub max_points: usize,
}

impl Default for ZoomOutOptions {
    /// 20 → 60 in steps of 8 (measured: `docs/decisions/2026-11-23-refined-method.md`).
    fn default() -> Self {
        ZoomOutOptions {
            k_start: 20,
            k_end: 60,
            step: 8,
            anchor_weight: 0.0,
            max_points: DEFAULT_ZOOMOUT_POINTS,
        }
    }
}

/// The result of [`zoomout`].
#[derive(Debug, Clone)]
pub struct ZoomOutResult {
    /// Target vertex per template vertex.
    pub map: Vec<u32>,
    /// Squared spectral residual per template vertex at the last step (`‖(ΦC)_p − Ψ_{map(p)}‖²`):
    /// small when the functional map explains the point's match.
    pub residual: Vec<f64>,
    /// The last functional map (`k × k`, target coefficients → template coefficients).
    pub c: Mat<f64>,
    /// Basis sizes used, in order.
    pub ks: Vec<usize>,
}

/// ZoomOut (Melzi, Ren, Rodolà, Sharma, Wonka, Ovsjanikov 2019) with segment-constrained point
/// maps.
///
/// `map[p]` is the current target vertex of template vertex `p`. Each iteration with basis size
/// `k` estimates the functional map `C = Φ_kᵀ M Π Ψ_k` (`Φ` template basis, `Ψ` target basis,
/// `Π` the pull-back of the point map), then recovers the point map: `map(p)` = the target
/// vertex of `p`'s pool ([`SegmentPools`]) whose row of `Ψ_k` is nearest to row `p` of `Φ_k C`.
/// `k` grows from `k_start` to `k_end` by `step`.
///
/// Errors: [`CorrespondError::InvalidArgument`] for inconsistent sizes, `k_start == 0` or
/// `step == 0`, or a map entry out of range.
pub fn zoomout(
    template: SpectralBasis<'_>,
    target: SpectralBasis<'_>,
    map: &[u32],
    pools: &SegmentPools,
    anchors: Option<(MatRef<'_, f64>, MatRef<'_, f64>)>,
    options: &ZoomOutOptions,
) -> Result<ZoomOutResult, CorrespondError> {
    let (n, m) = (template.vectors.nrows(), target.vectors.nrows());
    if let Some((a, b)) = anchors {
        if a.nrows() != n || b.nrows() != m || a.ncols() != b.ncols() {
            return Err(CorrespondError::InvalidArgument(format!(
                "zoomout: anchors {}×{} and {}×{} for {n} and {m} vertices",
                a.nrows(),
                a.ncols(),
                b.nrows(),
                b.ncols()
            )));
        }
    }
    if template.mass.len() != n || target.mass.len() != m || map.len() != n {
        return Err(CorrespondError::InvalidArgument(format!(
            "zoomout: template basis {n} rows / mass {}, target basis {m} rows / mass {}, map of {}",
            template.mass.len(),
            target.mass.len(),
            map.len()
        )));
    }
    if options.k_start == 0 || options.step == 0 {
        return Err(CorrespondError::InvalidArgument(
            "zoomout: k_start and step must be positive".into(),
        ));
    }
    if let Some(&q) = map.iter().find(|&&q| q as usize >= m) {
        return Err(CorrespondError::InvalidArgument(format!(
            "zoomout: map entry {q} out of range ({m} target vertices)"
        )));
    }
    let kmax = options
        .k_end
        .min(template.vectors.ncols())
        .min(target.vectors.ncols());
    let mut ks = Vec::new();
    let mut k = options.k_start.min(kmax);
    loop {
        ks.push(k);
        if k >= kmax {
            break;
        }
        k = (k + options.step).min(kmax);
    }
    // Intermediate iterations on an even stride sample of at most `max_points` vertices, its
    // masses rescaled to the total (a quadrature of ∫ φ ψ∘T).
    let stride = n.div_ceil(options.max_points.max(1)).max(1);
    let in_sample = |p: usize| p.is_multiple_of(stride);
    let sample_members: Option<Vec<Vec<u32>>> = (stride > 1).then(|| {
        pools
            .members
            .iter()
            .map(|m| {
                m.iter()
                    .copied()
                    .filter(|&p| in_sample(p as usize))
                    .collect()
            })
            .collect()
    });
    let mass_scale = if stride > 1 {
        let total: f64 = template.mass.iter().sum();
        let sampled: f64 = (0..n)
            .filter(|&p| in_sample(p))
            .map(|p| template.mass[p])
            .sum();
        if sampled > 0.0 {
            total / sampled
        } else {
            1.0
        }
    } else {
        1.0
    };
    // Φᵀ M (sampled rows only, rescaled, for the intermediate iterations), for the largest k.
    let phi_m_sampled = Mat::from_fn(n, kmax, |i, j| {
        if in_sample(i) {
            template.vectors[(i, j)] * template.mass[i] * mass_scale
        } else {
            0.0
        }
    });
    let phi_m_full = (stride > 1)
        .then(|| Mat::from_fn(n, kmax, |i, j| template.vectors[(i, j)] * template.mass[i]));
    let mut current = map.to_vec();
    let mut residual = vec![0.0; n];
    let mut c = Mat::<f64>::zeros(0, 0);
    let last = ks.len().saturating_sub(1);
    for (step, &k) in ks.iter().enumerate() {
        // All vertices in the last iteration; the sample before (when there is one).
        let subset = if step == last {
            None
        } else {
            sample_members.as_deref()
        };
        // The functional map uses the sample's rows in every iteration but the first after a
        // full one — i.e. the rows whose map entries were just updated.
        let phi_m = match (&phi_m_full, step) {
            (Some(full), 0) => full,
            _ => &phi_m_sampled,
        };
        // Π Ψ_k: the target basis pulled back through the current map.
        let pulled = Mat::from_fn(n, k, |i, j| target.vectors[(current[i] as usize, j)]);
        c = Mat::<f64>::zeros(k, k);
        matmul(
            c.as_mut(),
            Accum::Replace,
            phi_m.as_ref().subcols(0, k).transpose(),
            pulled.as_ref(),
            1.0,
            Par::rayon(0),
        );
        let mut q = Mat::<f64>::zeros(n, k);
        matmul(
            q.as_mut(),
            Accum::Replace,
            template.vectors.subcols(0, k),
            c.as_ref(),
            1.0,
            Par::rayon(0),
        );
        let nn = match anchors {
            Some((a, b)) if options.anchor_weight > 0.0 => {
                // Unit mean squared row norm for the embedding, then the weighted anchors.
                let ms: f64 = (0..m)
                    .map(|i| (0..k).map(|j| target.vectors[(i, j)].powi(2)).sum::<f64>())
                    .sum::<f64>()
                    / m.max(1) as f64;
                let s = 1.0 / ms.sqrt().max(f64::MIN_POSITIVE);
                let w = options.anchor_weight;
                let (ka, d) = (a.ncols(), k + a.ncols());
                let qa = Mat::from_fn(n, d, |i, j| {
                    if j < k {
                        s * q[(i, j)]
                    } else {
                        w * a[(i, j - k)]
                    }
                });
                let tb = Mat::from_fn(m, d, |i, j| {
                    if j < k {
                        s * target.vectors[(i, j)]
                    } else {
                        w * b[(i, j - k)]
                    }
                });
                debug_assert_eq!(ka + k, d);
                nearest_in_pools_for(qa.as_ref(), tb.as_ref(), pools, subset)?
            }
            _ => nearest_in_pools_for(q.as_ref(), target.vectors.subcols(0, k), pools, subset)?,
        };
        for (p, (t, r)) in nn.into_iter().enumerate() {
            if subset.is_none() || in_sample(p) {
                current[p] = t;
                residual[p] = r;
            }
        }
    }
    Ok(ZoomOutResult {
        map: current,
        residual,
        c,
        ks,
    })
}

/// Fraction of `num_target` target vertices hit by `map` (1 for a surjective map): how close a
/// dense map is to one-to-one between equally sampled meshes.
pub fn coverage(map: &[u32], num_target: usize) -> f64 {
    if num_target == 0 {
        return 0.0;
    }
    let mut hit = vec![false; num_target];
    for &q in map {
        if let Some(h) = hit.get_mut(q as usize) {
            *h = true;
        }
    }
    hit.iter().filter(|&&h| h).count() as f64 / num_target as f64
}

/// Everything [`refine_dense`] needs about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct RefineSide<'a> {
    /// Laplace–Beltrami basis (eigenvectors and lumped mass).
    pub basis: SpectralBasis<'a>,
    /// Landmark coordinates (`n × L`, same landmarks in the same order on both meshes), e.g.
    /// from [`landmark_coordinates`](crate::landmark_coordinates).
    pub landmarks: MatRef<'a, f64>,
    /// Point descriptors (si-HKS), `n × d`.
    pub descriptors: &'a crate::Descriptors,
    /// Segment label per vertex.
    pub labels: &'a [Segment],
    /// Sagittal half per vertex of the midline segments (see [`SegmentPools`]).
    pub halves: Option<&'a [i8]>,
    /// The mesh's edge graph (used on the target side for the boundary band).
    pub graph: &'a EdgeGraph,
    /// Total surface area.
    pub area: f64,
}

/// Options of [`refine_dense`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Weight of the si-HKS columns (each scaled to unit standard deviation over both meshes)
    /// next to the landmark coordinates in the initial map's feature space.
    pub descriptor_weight: f64,
    /// Geodesic band around a segment's target region that its pool also covers, in √area.
    pub band: f64,
    /// ZoomOut schedule.
    pub zoomout: ZoomOutOptions,
}

impl Default for RefineOptions {
    /// Weight 1, band 0.02, ZoomOut 20 → 60 by 8 (measured on the generated bodies:
    /// `docs/decisions/2026-11-23-refined-method.md`).
    fn default() -> Self {
        RefineOptions {
            descriptor_weight: 1.0,
            band: 0.02,
            zoomout: ZoomOutOptions::default(),
        }
    }
}

/// The result of [`refine_dense`].
#[derive(Debug, Clone)]
pub struct RefinedMatches {
    /// One pair per template vertex, in vertex order.
    pub pairs: Vec<crate::Pair>,
    /// Per template vertex, the final spectral residual `r` ([`ZoomOutResult::residual`],
    /// square-rooted) behind its confidence.
    pub residual: Vec<f64>,
    /// The initial (landmark + descriptor) map, target vertex per template vertex.
    pub initial: Vec<u32>,
    /// Fraction of target vertices hit by the final map ([`coverage`]).
    pub coverage: f64,
    /// Seconds per stage: `segment_pools`, `initial_map`, `zoomout`.
    pub timings: Vec<(&'static str, f64)>,
}

/// The refined dense method (DESIGN.md, Algorithm 7): segment pools, an initial map by nearest
/// neighbour in landmark-coordinate + si-HKS space within each pool, then segment-constrained
/// ZoomOut. Every template vertex gets a match; its confidence is `1 / (1 + r/r̃)` with `r`
/// the final spectral residual ([`ZoomOutResult::residual`], square-rooted) and `r̃` its
/// median, with `r` kept in [`RefinedMatches::residual`].
///
/// Errors: [`CorrespondError::InvalidArgument`] when the sides' tables disagree in size.
pub fn refine_dense(
    template: &RefineSide<'_>,
    target: &RefineSide<'_>,
    options: &RefineOptions,
) -> Result<RefinedMatches, CorrespondError> {
    use std::time::Instant;
    let (n, m) = (template.labels.len(), target.labels.len());
    for (name, s, len) in [("template", template, n), ("target", target, m)] {
        if s.basis.vectors.nrows() != len
            || s.landmarks.nrows() != len
            || s.descriptors.len() != len
        {
            return Err(CorrespondError::InvalidArgument(format!(
                "{name}: {len} labels, basis of {} rows, {} landmark rows, {} descriptors",
                s.basis.vectors.nrows(),
                s.landmarks.nrows(),
                s.descriptors.len()
            )));
        }
    }
    if template.landmarks.ncols() != target.landmarks.ncols()
        || template.descriptors.dim() != target.descriptors.dim()
    {
        return Err(CorrespondError::InvalidArgument(
            "template and target have different landmark or descriptor counts".into(),
        ));
    }
    let mut timings = Vec::new();
    let t = Instant::now();
    let pools = SegmentPools::new(
        (template.labels, template.halves),
        (target.labels, target.halves),
        target.graph,
        options.band * target.area.sqrt(),
    )?;
    timings.push(("segment_pools", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    // si-HKS columns to unit standard deviation over both meshes.
    let h = template.descriptors.dim();
    let scale: Vec<f64> = (0..h)
        .map(|j| {
            let vals = (0..n)
                .map(|i| template.descriptors.row(i)[j])
                .chain((0..m).map(|i| target.descriptors.row(i)[j]));
            let (mut s1, mut s2, mut c) = (0.0, 0.0, 0.0);
            for v in vals {
                s1 += v;
                s2 += v * v;
                c += 1.0;
            }
            let var = (s2 / c - (s1 / c).powi(2)).max(0.0);
            if var > 0.0 {
                var.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let features = |s: &RefineSide<'_>, rows: usize| {
        let l = s.landmarks.ncols();
        Mat::from_fn(rows, l + h, |i, j| {
            if j < l {
                s.landmarks[(i, j)]
            } else {
                options.descriptor_weight * s.descriptors.row(i)[j - l] / scale[j - l]
            }
        })
    };
    let (fa, fb) = (features(template, n), features(target, m));
    let initial: Vec<u32> = nearest_in_pools(fa.as_ref(), fb.as_ref(), &pools)?
        .into_iter()
        .map(|x| x.0)
        .collect();
    timings.push(("initial_map", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let z = zoomout(
        template.basis,
        target.basis,
        &initial,
        &pools,
        Some((fa.as_ref(), fb.as_ref())),
        &options.zoomout,
    )?;
    timings.push(("zoomout", t.elapsed().as_secs_f64()));
    let r: Vec<f64> = z.residual.iter().map(|x| x.sqrt()).collect();
    let median = {
        let mut v = r.clone();
        let k = v.len() / 2;
        if v.is_empty() {
            1.0
        } else {
            v.select_nth_unstable_by(k, f64::total_cmp);
            v[k].max(f64::MIN_POSITIVE)
        }
    };
    let pairs = z
        .map
        .iter()
        .zip(&r)
        .enumerate()
        .map(|(p, (&q, &r))| crate::Pair {
            template: p as u32,
            target: q,
            confidence: 1.0 / (1.0 + r / median),
        })
        .collect();
    Ok(RefinedMatches {
        pairs,
        residual: r,
        coverage: coverage(&z.map, m),
        initial,
        timings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_spectral::testmesh::deformed_sphere;
    use symcorr_spectral::{eigenpairs, EigenOptions, Laplacian};
    use Segment::*;

    /// Every segment's adjacent pool holds its own and its skeleton neighbours' regions and
    /// never a vertex of the other side: 17 separate triangles, one per segment, 100 apart.
    #[test]
    fn adjacent_pools_never_cross_sides() {
        let positions: Vec<[f64; 3]> = (0..17)
            .flat_map(|i| {
                let x = 100.0 * i as f64;
                [[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]]
            })
            .collect();
        let triangles = (0..17u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
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
    fn permuted(mesh: &symcorr_mesh::TriMesh, perm: &[u32]) -> symcorr_mesh::TriMesh {
        let mut pos = vec![[0.0; 3]; perm.len()];
        for (o, &n) in perm.iter().enumerate() {
            let p = mesh.positions[o];
            // Rotate by 90° about z as well: the map must not depend on the embedding.
            pos[n as usize] = [-p[1], p[0], p[2]];
        }
        let tris = mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| perm[v as usize]))
            .collect();
        symcorr_mesh::TriMesh::new(pos, tris).unwrap()
    }

    #[test]
    fn zoomout_recovers_a_permutation_from_a_corrupted_map() {
        let a = deformed_sphere(8);
        let n = a.num_vertices();
        let mut seed = 3u64;
        let mut perm: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            perm.swap(i, lcg(&mut seed) as usize % (i + 1));
        }
        let b = permuted(&a, &perm);
        let (la, lb) = (Laplacian::new(&a).unwrap(), Laplacian::new(&b).unwrap());
        let ea = eigenpairs(&la, 40, &EigenOptions::default()).unwrap();
        let eb = eigenpairs(&lb, 40, &EigenOptions::default()).unwrap();
        // 30 % of the true map replaced by random target vertices.
        let init: Vec<u32> = (0..n)
            .map(|p| {
                if lcg(&mut seed) % 10 < 3 {
                    (lcg(&mut seed) % n as u64) as u32
                } else {
                    perm[p]
                }
            })
            .collect();
        let labels = vec![Torso; n];
        let pools =
            SegmentPools::new((&labels, None), (&labels, None), &EdgeGraph::new(&b), 0.0).unwrap();
        let z = zoomout(
            SpectralBasis {
                vectors: ea.vectors.as_ref(),
                mass: &la.mass,
            },
            SpectralBasis {
                vectors: eb.vectors.as_ref(),
                mass: &lb.mass,
            },
            &init,
            &pools,
            None,
            &ZoomOutOptions {
                k_start: 6,
                k_end: 40,
                step: 2,
                anchor_weight: 0.0,
                // Intermediate iterations on every 2nd vertex, the last on all.
                max_points: 400,
            },
        )
        .unwrap();
        let right = |m: &[u32]| (0..n).filter(|&p| m[p] == perm[p]).count() as f64 / n as f64;
        assert!(right(&init) < 0.75);
        assert!(right(&z.map) > 0.97, "recovered {}", right(&z.map));
        assert_eq!(z.ks.first(), Some(&6));
        assert_eq!(z.ks.last(), Some(&40));
        assert!(coverage(&z.map, n) > 0.95);
    }

    /// A strip of 2·w vertices: the first half left, the second right, with a midline column.
    fn strip(w: usize) -> (symcorr_mesh::TriMesh, Vec<Segment>, Vec<i8>) {
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
        let halves: Vec<i8> = (0..2 * w)
            .map(|v| {
                if v % w == mid {
                    1 - 2 * (v / w) as i8
                } else {
                    0
                }
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
                assert!(side(p) * side(q as usize) >= 0, "{p} may match {q}");
            }
        }
        // Features that are the mirror image: each vertex's best feature match is its mirror.
        let n = labels.len();
        let f = Mat::from_fn(n, 1, |v, _| ((v % 11) as f64 - 5.0).abs());
        let g2 = Mat::from_fn(n, 1, |v, _| ((v % 11) as f64 - 5.0).abs() + 0.01);
        let nn = nearest_in_pools(f.as_ref(), g2.as_ref(), &pools).unwrap();
        for (p, (q, d)) in nn.iter().enumerate() {
            assert!(side(p) * side(*q as usize) >= 0);
            assert!((d - 1e-4).abs() < 1e-9, "exact squared distance: {d}");
        }
        // A segment the target lacks: the pool falls back to the compatible side, not empty.
        let mut no_shin = labels.clone();
        no_shin[0] = ShinLeft;
        let fb = SegmentPools::new((&no_shin, Some(&halves)), (&labels, Some(&halves)), &g, 0.0)
            .unwrap();
        let pool = fb.pool_of(0);
        assert!(!pool.is_empty());
        assert!(pool.iter().all(|&q| side(q as usize) >= 0));
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
