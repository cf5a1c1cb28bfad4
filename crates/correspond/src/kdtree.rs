//! Exact nearest neighbours in a few dimensions: a static k-d tree (Bentley 1975; median
//! splits on the widest axis, buckets of [`LEAF`] points) and one tree per segment pool.
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
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * points.len() / LEAF + 1);
        if !points.is_empty() {
            build(&points, &mut order, 0, &mut nodes);
        }
        let ids = order.iter().map(|&i| ids[i as usize]).collect();
        let points = order.iter().map(|&i| points[i as usize]).collect();
        KdTree { points, ids, nodes }
    }

    /// The id of the point nearest to `q` and the squared distance; `None` for an empty tree
    /// (or one whose points are all non-finite).
    pub(crate) fn nearest(&self, q: &[f64; K]) -> Option<(u32, f64)> {
        let mut best = (u32::MAX, f64::INFINITY);
        if !self.nodes.is_empty() {
            self.search(0, q, &mut best);
        }
        (best.0 != u32::MAX).then_some(best)
    }

    fn search(&self, node: usize, q: &[f64; K], best: &mut (u32, f64)) {
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
                let delta = q[axis as usize] - value;
                let (near, far) = if delta < 0.0 {
                    (left, right)
                } else {
                    (right, left)
                };
                self.search(near as usize, q, best);
                // `<=`: a point at exactly the best distance on the far side may hold a
                // smaller id (ties are broken by id).
                if delta * delta <= best.1 {
                    self.search(far as usize, q, best);
                }
            }
        }
    }
}

/// Builds the subtree of `order[..]` (indices into `points`, reordered in place) whose first
/// point sits at `offset` of the final arrays; returns its node index.
fn build<const K: usize>(
    points: &[[f64; K]],
    order: &mut [u32],
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
    // The widest axis over the finite coordinates.
    let mut lo = [f64::INFINITY; K];
    let mut hi = [f64::NEG_INFINITY; K];
    for &i in order.iter() {
        for ((l, h), &x) in lo.iter_mut().zip(hi.iter_mut()).zip(&points[i as usize]) {
            if x.is_finite() {
                *l = l.min(x);
                *h = h.max(x);
            }
        }
    }
    let (axis, widest) = lo.iter().zip(&hi).map(|(l, h)| h - l).enumerate().fold(
        (0, f64::NEG_INFINITY),
        |best, (k, w)| {
            if w > best.1 {
                (k, w)
            } else {
                best
            }
        },
    );
    if widest <= 0.0 {
        return me as u32; // all equal (or non-finite) along every axis: one bucket
    }
    let mid = order.len() / 2;
    let key = |i: &u32| points[*i as usize][axis];
    order.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
    let value = key(&order[mid]);
    // Points equal to the split value may lie on both sides after selection; put every point
    // below `value` left, the rest right, so that the search's rule (`< value` is left) holds.
    let mut split = 0;
    for i in 0..order.len() {
        if key(&order[i]) < value {
            order.swap(i, split);
            split += 1;
        }
    }
    if split == 0 {
        return me as u32; // the median is the minimum: no useful split along the widest axis
    }
    let (lo, hi) = order.split_at_mut(split);
    let left = build(points, lo, offset, nodes);
    let right = build(points, hi, offset + split, nodes);
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
                Ok(KdTree::new(pts, pool.clone()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(PoolTrees { trees })
    }

    /// For every template vertex `p` (rows of `template`), the target vertex of `p`'s pool
    /// nearest to it and the squared distance — the same answer as
    /// [`nearest_in_pools`](crate::nearest_in_pools) on these features, ties to the smaller
    /// id. Only the members `subset` (per group) are searched when given; the others get
    /// `(0, ∞)`.
    ///
    /// Errors: [`CorrespondError::LengthMismatch`] when `template` has another length than
    /// the pools were built for, or the trees were built for other pools.
    pub(crate) fn nearest(
        &self,
        pools: &SegmentPools,
        template: &[[f64; 6]],
        subset: Option<&[Vec<u32>]>,
    ) -> Result<Vec<(u32, f64)>, CorrespondError> {
        same_len(
            "template feature rows (one per vertex of the pools)",
            pools.num_template(),
            template.len(),
        )?;
        same_len("k-d trees (one per pool)", pools.len(), self.trees.len())?;
        let members = subset.unwrap_or(pools.members());
        let mut out = vec![(0u32, f64::INFINITY); template.len()];
        let found: Vec<Vec<(u32, (u32, f64))>> = members
            .par_iter()
            .enumerate()
            .map(|(g, m)| {
                m.par_chunks(512)
                    .flat_map_iter(|chunk| {
                        chunk.iter().filter_map(move |&v| {
                            self.trees[g]
                                .nearest(&template[v as usize])
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

        #[test]
        fn six_dimensional_tree_matches_brute_force(
            pts in prop::collection::vec(prop::array::uniform6(-1.0f64..1.0), 1..400),
            q in prop::array::uniform6(-1.5f64..1.5),
        ) {
            let tree = KdTree::new(pts.clone(), (0..pts.len() as u32).collect());
            prop_assert_eq!(tree.nearest(&q), brute(&pts, &q));
        }
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
