//! Exact nearest neighbours in a few dimensions: a static k-d tree (Bentley 1975; median
//! splits on the widest axis of a sample of each node's points, buckets of [`LEAF`] points)
//! and one tree per segment pool.
//!
//! The articulated alignment asks, a dozen times per pair, for every template vertex's nearest
//! target vertex of its pool in position + normal space (6 dimensions). Brute force costs
//! `n × pool` per call and dominated the 53k-vertex pairs; a tree per pool, built once per
//! pair, answers each query in about `log pool`. The refined method's spectral features have
//! 20–60 dimensions, where trees do not prune, and keep the blocked brute force of
//! [`nearest_in_pools`](crate::nearest_in_pools).

use crate::{same_len, CorrespondError, SegmentPools};
use rayon::prelude::*;

/// Points per leaf bucket.
const LEAF: usize = 16;

/// Points of a node that choose its splitting axis (the widest spread among them).
const SPREAD_SAMPLE: usize = 64;

#[derive(Debug, Clone, Copy)]
enum Node {
    /// Points `start..end` of the tree's reordered arrays.
    Leaf { start: u32, end: u32 },
    /// Points with `x[axis] < value` go left (`left`), the others right (`right`).
    Split {
        axis: u8,
        value: f64,
        left: u32,
        right: u32,
    },
}

/// A static k-d tree over points in `K` dimensions, each carrying a `u32` id.
#[derive(Debug, Clone)]
pub(crate) struct KdTree<const K: usize> {
    points: Vec<[f64; K]>,
    ids: Vec<u32>,
    nodes: Vec<Node>,
}

impl<const K: usize> KdTree<K> {
    /// The tree of `points` with their `ids` (same length; non-finite coordinates are
    /// allowed but such points are never returned as nearest).
    pub(crate) fn new(points: Vec<[f64; K]>, ids: Vec<u32>) -> KdTree<K> {
        debug_assert_eq!(points.len(), ids.len());
        // The points are reordered themselves, not through an index: the selections and
        // partitions of the build then read memory in order.
        let mut items: Vec<([f64; K], u32)> = points.into_iter().zip(ids).collect();
        let mut nodes = Vec::with_capacity(2 * items.len() / LEAF + 1);
        if !items.is_empty() {
            build(&mut items, 0, &mut nodes);
        }
        let (points, ids) = items.into_iter().unzip();
        KdTree { points, ids, nodes }
    }

    /// The id of the point nearest to `q` and the squared distance; `None` for an empty tree
    /// (or one whose points are all non-finite).
    #[cfg(test)]
    pub(crate) fn nearest(&self, q: &[f64; K]) -> Option<(u32, f64)> {
        self.nearest_within(q, (u32::MAX, f64::INFINITY))
    }

    /// [`KdTree::nearest`] starting from a known candidate `start` (an id of this tree and its
    /// squared distance to `q`): the same answer, found sooner when the candidate is near —
    /// the previous round's match of an ICP point that moved a little. `start` must be one of
    /// the tree's points at its true distance (or `(u32::MAX, ∞)` for none); a finite bound
    /// from elsewhere could hide the true nearest point.
    pub(crate) fn nearest_within(&self, q: &[f64; K], start: (u32, f64)) -> Option<(u32, f64)> {
        let mut best = start;
        if !self.nodes.is_empty() {
            let mut offsets = [0.0; K];
            self.search(0, q, 0.0, &mut offsets, &mut best);
        }
        (best.0 != u32::MAX).then_some(best)
    }

    /// Descends into `node`, whose cell lies at squared distance `cell_d2` from `q` with
    /// per-axis offsets `offsets` (Arya & Mount's incremental distance, *SODA* 1993: a far
    /// child is skipped when its whole cell, not only the splitting plane, is farther than the
    /// best point so far).
    fn search(
        &self,
        node: usize,
        q: &[f64; K],
        cell_d2: f64,
        offsets: &mut [f64; K],
        best: &mut (u32, f64),
    ) {
        if cell_d2 > best.1 {
            return;
        }
        match self.nodes[node] {
            Node::Leaf { start, end } => {
                for i in start as usize..end as usize {
                    let p = &self.points[i];
                    let mut d = 0.0;
                    for k in 0..K {
                        let t = p[k] - q[k];
                        d += t * t;
                    }
                    // Ties go to the smaller id, as brute force in id order would.
                    if d < best.1 || (d == best.1 && self.ids[i] < best.0) {
                        *best = (self.ids[i], d);
                    }
                }
            }
            Node::Split {
                axis,
                value,
                left,
                right,
            } => {
                let axis = axis as usize;
                let delta = q[axis] - value;
                let (near, far) = if delta < 0.0 {
                    (left, right)
                } else {
                    (right, left)
                };
                self.search(near as usize, q, cell_d2, offsets, best);
                let old = offsets[axis];
                offsets[axis] = delta;
                // Summed afresh in the leaves' axis order, not updated by `− old² + delta²`:
                // every term is at most the matching term of any point of the far cell, and
                // rounding is monotone, so the bound never exceeds a point's computed distance.
                let far_d2: f64 = offsets.iter().map(|o| o * o).sum();
                // `<=`: a point at exactly the best distance on the far side may hold a
                // smaller id (ties are broken by id).
                if far_d2 <= best.1 {
                    self.search(far as usize, q, far_d2, offsets, best);
                }
                offsets[axis] = old;
            }
        }
    }
}

/// Builds the subtree of `order[..]` (points with their ids, reordered in place) whose first
/// point sits at `offset` of the final arrays; returns its node index.
fn build<const K: usize>(
    order: &mut [([f64; K], u32)],
    offset: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let me = nodes.len();
    nodes.push(Node::Leaf {
        start: offset as u32,
        end: (offset + order.len()) as u32,
    });
    if order.len() <= LEAF {
        return me as u32;
    }
    // The widest axis over the finite coordinates — of an even-stride sample of at most
    // `SPREAD_SAMPLE` points: the axis only shapes the tree (every search is exact on any
    // tree), and the full scan of every node's points cost a third of the build.
    let widest_axis = |stride: usize| {
        let mut lo = [f64::INFINITY; K];
        let mut hi = [f64::NEG_INFINITY; K];
        for (p, _) in order.iter().step_by(stride) {
            for ((l, h), &x) in lo.iter_mut().zip(hi.iter_mut()).zip(p) {
                if x.is_finite() {
                    *l = l.min(x);
                    *h = h.max(x);
                }
            }
        }
        lo.iter().zip(&hi).map(|(l, h)| h - l).enumerate().fold(
            (0, f64::NEG_INFINITY),
            |best, (k, w)| if w > best.1 { (k, w) } else { best },
        )
    };
    let stride = order.len().div_ceil(SPREAD_SAMPLE);
    let (mut axis, mut widest) = widest_axis(stride);
    if widest <= 0.0 && stride > 1 {
        // The sample is flat: ask every point before calling the node one bucket.
        (axis, widest) = widest_axis(1);
    }
    if widest <= 0.0 {
        return me as u32; // all equal (or non-finite) along every axis: one bucket
    }
    let mid = order.len() / 2;
    let key = |i: &([f64; K], u32)| i.0[axis];
    order.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
    let value = key(&order[mid]);
    // Points equal to the split value may lie on both sides after selection; put every point
    // below `value` left, the rest right, so that the search's rule (`< value` is left) holds.
    // Those after `mid` are at least `value` already: only the first half is moved through.
    let mut split = 0;
    for i in 0..mid {
        if key(&order[i]) < value {
            order.swap(i, split);
            split += 1;
        }
    }
    if split == 0 {
        return me as u32; // the median is the minimum: no useful split along the widest axis
    }
    let (lo, hi) = order.split_at_mut(split);
    let left = build(lo, offset, nodes);
    let right = build(hi, offset + split, nodes);
    nodes[me] = Node::Split {
        axis: axis as u8,
        value,
        left,
        right,
    };
    me as u32
}

/// One k-d tree per group of a [`SegmentPools`] over the target's 6-D features.
#[derive(Debug, Clone)]
pub(crate) struct PoolTrees {
    trees: Vec<KdTree<6>>,
    /// Per tree, which target vertices it holds (a bit per target vertex): a hint is used
    /// only where it is one of the tree's points.
    members: Vec<Vec<u64>>,
    /// The target's features, to measure a hint's distance.
    target: Vec<[f64; 6]>,
}

impl PoolTrees {
    /// Trees over `target` (one feature row per target vertex) for every pool of `pools`.
    ///
    /// Errors: [`CorrespondError::IndexOutOfRange`] when a pool names a vertex beyond
    /// `target`.
    pub(crate) fn new(
        pools: &SegmentPools,
        target: &[[f64; 6]],
    ) -> Result<PoolTrees, CorrespondError> {
        let trees = pools
            .pools()
            .par_iter()
            .map(|pool| {
                if let Some(&q) = pool.iter().find(|&&q| q as usize >= target.len()) {
                    return Err(CorrespondError::IndexOutOfRange {
                        what: "pool vertex (target feature row)",
                        index: q as usize,
                        len: target.len(),
                    });
                }
                let pts = pool.iter().map(|&q| target[q as usize]).collect();
                let mut bits = vec![0u64; target.len().div_ceil(64)];
                for &q in pool {
                    bits[q as usize / 64] |= 1 << (q % 64);
                }
                Ok((KdTree::new(pts, pool.clone()), bits))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let (trees, members) = trees.into_iter().unzip();
        Ok(PoolTrees {
            trees,
            members,
            target: target.to_vec(),
        })
    }

    /// For every template vertex `p` (rows of `template`), the target vertex of `p`'s pool
    /// nearest to it and the squared distance — the same answer as
    /// [`nearest_in_pools`](crate::nearest_in_pools) on these features, ties to the smaller
    /// id. Only the members `subset` (per group) are searched when given; the others get
    /// `(0, ∞)`.
    ///
    /// `hints`, an earlier answer (one entry per template vertex, as returned here), start
    /// each search from the earlier match (its distance measured afresh) where that match is
    /// finite and one of the pool's points: between ICP rounds a template point moves little,
    /// so its last match bounds the search tightly. The answer is the same with or without.
    ///
    /// `within` bounds the search (squared distance; `f64::INFINITY` for none): a vertex
    /// whose nearest pool point is farther gets `(0, ∞)`, found without visiting the far cells
    /// — for the ICP rounds, where a pair beyond the gate is dropped anyway.
    ///
    /// Errors: [`CorrespondError::LengthMismatch`] when `template` (or `hints`) has another
    /// length than the pools were built for, or the trees were built for other pools.
    pub(crate) fn nearest(
        &self,
        pools: &SegmentPools,
        template: &[[f64; 6]],
        subset: Option<&[Vec<u32>]>,
        hints: Option<&[(u32, f64)]>,
        within: f64,
    ) -> Result<Vec<(u32, f64)>, CorrespondError> {
        same_len(
            "template feature rows (one per vertex of the pools)",
            pools.num_template(),
            template.len(),
        )?;
        same_len("k-d trees (one per pool)", pools.len(), self.trees.len())?;
        if let Some(h) = hints {
            same_len("hints (one per template vertex)", template.len(), h.len())?;
        }
        let start = |g: usize, v: u32, q: &[f64; 6]| -> (u32, f64) {
            let none = (u32::MAX, within);
            let Some(&(hint, d)) = hints.and_then(|h| h.get(v as usize)) else {
                return none;
            };
            let bits = &self.members[g];
            let member = d.is_finite()
                && bits
                    .get(hint as usize / 64)
                    .is_some_and(|w| w & (1 << (hint % 64)) != 0);
            if !member {
                return none;
            }
            let p = &self.target[hint as usize];
            let mut d = 0.0;
            for k in 0..6 {
                let t = p[k] - q[k];
                d += t * t;
            }
            if d <= within {
                (hint, d)
            } else {
                none
            }
        };
        let members = subset.unwrap_or(pools.members());
        let mut out = vec![(0u32, f64::INFINITY); template.len()];
        let found: Vec<Vec<(u32, (u32, f64))>> = members
            .par_iter()
            .enumerate()
            .map(|(g, m)| {
                m.par_chunks(512)
                    .flat_map_iter(|chunk| {
                        chunk.iter().filter_map(move |&v| {
                            let q = &template[v as usize];
                            self.trees[g]
                                .nearest_within(q, start(g, v, q))
                                .map(|hit| (v, hit))
                        })
                    })
                    .collect()
            })
            .collect();
        for (v, hit) in found.into_iter().flatten() {
            out[v as usize] = hit;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute<const K: usize>(pts: &[[f64; K]], q: &[f64; K]) -> Option<(u32, f64)> {
        let mut best = None::<(u32, f64)>;
        for (i, p) in pts.iter().enumerate() {
            let d: f64 = (0..K).map(|k| (p[k] - q[k]).powi(2)).sum();
            if d.is_finite() && best.is_none_or(|b| d < b.1) {
                best = Some((i as u32, d));
            }
        }
        best
    }

    proptest! {
        /// The tree answers exactly what brute force answers, ties included (coordinates on
        /// a coarse grid make many ties and equal split values).
        #[test]
        fn tree_matches_brute_force(
            pts in prop::collection::vec(prop::array::uniform3(-4i8..4), 0..300),
            qs in prop::collection::vec(prop::array::uniform3(-5i8..5), 1..20),
        ) {
            let pts: Vec<[f64; 3]> = pts.iter().map(|p| p.map(|x| x as f64 * 0.5)).collect();
            let tree = KdTree::new(pts.clone(), (0..pts.len() as u32).collect());
            for q in &qs {
                let q = q.map(|x| x as f64 * 0.5 + 0.1);
                prop_assert_eq!(tree.nearest(&q), brute(&pts, &q));
            }
        }

        /// Starting from any point of the tree (at its true distance) changes nothing.
        #[test]
        fn a_start_candidate_does_not_change_the_answer(
            pts in prop::collection::vec(prop::array::uniform3(-4i8..4), 1..200),
            qs in prop::collection::vec((prop::array::uniform3(-5i8..5), any::<prop::sample::Index>()), 1..20),
        ) {
            let pts: Vec<[f64; 3]> = pts.iter().map(|p| p.map(|x| x as f64 * 0.5)).collect();
            let tree = KdTree::new(pts.clone(), (0..pts.len() as u32).collect());
            for (q, pick) in &qs {
                let q = q.map(|x| x as f64 * 0.5 + 0.1);
                let s = pick.index(pts.len());
                let d: f64 = (0..3).map(|k| (pts[s][k] - q[k]).powi(2)).sum();
                prop_assert_eq!(tree.nearest_within(&q, (s as u32, d)), brute(&pts, &q));
            }
        }

        #[test]
        fn six_dimensional_tree_matches_brute_force(
            pts in prop::collection::vec(prop::array::uniform6(-1.0f64..1.0), 1..400),
            q in prop::array::uniform6(-1.5f64..1.5),
        ) {
            let tree = KdTree::new(pts.clone(), (0..pts.len() as u32).collect());
            prop_assert_eq!(tree.nearest(&q), brute(&pts, &q));
        }
    }

    /// Pool trees answer the same with hints as without, whatever the hints hold: earlier
    /// answers, vertices of another pool, ids out of range, infinite distances.
    #[test]
    fn pool_tree_hints_never_change_the_answer() {
        use crate::SegmentPools;
        use symcorr_skeleton::Segment;
        let n = 402;
        let feature = |i: usize, s: f64| -> [f64; 6] {
            let t = i as f64 * 0.37 + s;
            [
                t.sin(),
                t.cos(),
                (2.0 * t).sin(),
                0.1 * t.cos(),
                0.2,
                (3.0 * t).sin(),
            ]
        };
        let target: Vec<[f64; 6]> = (0..n).map(|i| feature(i, 0.0)).collect();
        let template: Vec<[f64; 6]> = (0..n).map(|i| feature(i, 0.05)).collect();
        let labels: Vec<Segment> = (0..n).map(|i| Segment::ALL[i * 3 / n]).collect();
        let mesh = symcorr_mesh::TriMesh::new(
            target.iter().map(|f| [f[0], f[1], f[2]]).collect(),
            (0..n as u32 / 3)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect(),
        )
        .unwrap();
        let graph = symcorr_spectral::EdgeGraph::new(&mesh);
        let pools = SegmentPools::new((&labels, None), (&labels, None), &graph, 0.0).unwrap();
        let trees = PoolTrees::new(&pools, &target).unwrap();
        let plain = trees
            .nearest(&pools, &template, None, None, f64::INFINITY)
            .unwrap();
        let shifted: Vec<[f64; 6]> = (0..n).map(|i| feature(i, 0.08)).collect();
        let expected = trees
            .nearest(&pools, &shifted, None, None, f64::INFINITY)
            .unwrap();
        let odd: Vec<(u32, f64)> = (0..n)
            .map(|i| match i % 4 {
                0 => ((i as u32 * 7) % n as u32, 0.0),
                1 => (u32::MAX - 1, 1.0),
                2 => (i as u32, f64::INFINITY),
                _ => ((i as u32 + 201) % n as u32, f64::NAN),
            })
            .collect();
        for hints in [&plain, &odd] {
            let hinted = trees
                .nearest(&pools, &shifted, None, Some(hints), f64::INFINITY)
                .unwrap();
            assert_eq!(hinted, expected);
            // Bounded: the same answer where it is within the bound, none beyond.
            let mut ds: Vec<f64> = expected.iter().map(|e| e.1).collect();
            ds.sort_by(f64::total_cmp);
            let bound = ds[n / 2];
            let near = trees
                .nearest(&pools, &shifted, None, Some(hints), bound)
                .unwrap();
            for (got, want) in near.iter().zip(&expected) {
                if want.1 <= bound {
                    assert_eq!(got, want);
                } else {
                    assert_eq!(*got, (0, f64::INFINITY));
                }
            }
        }
        assert!(trees
            .nearest(&pools, &shifted, None, Some(&plain[1..]), f64::INFINITY)
            .is_err());
    }

    #[test]
    fn ids_are_returned_and_non_finite_points_never_win() {
        let pts = vec![[f64::NAN, 0.0], [1.0, 1.0], [5.0, 5.0]];
        let tree = KdTree::new(pts, vec![7, 8, 9]);
        assert_eq!(tree.nearest(&[0.0, 0.0]), Some((8, 2.0)));
        let empty = KdTree::<2>::new(Vec::new(), Vec::new());
        assert_eq!(empty.nearest(&[0.0, 0.0]), None);
        // Many identical points: one bucket, the smallest id.
        let same = KdTree::new(vec![[1.0, 2.0]; 100], (0..100).rev().collect());
        assert_eq!(same.nearest(&[0.0, 0.0]), Some((0, 5.0)));
    }
}
