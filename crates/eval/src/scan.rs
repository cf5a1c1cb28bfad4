//! What a single-view scan shows of the template, and how well a matcher's `no_counterpart`
//! list agrees with it (DESIGN.md, Metrics: scans).
//!
//! # Shown, hidden, and the band between
//! The ground truth of a scan (`truth/NAME.txt`) names, per scan vertex, the body vertex seen
//! at its pixel. A template point is **shown** when some scan vertex's truth names it: the
//! camera saw that body vertex (it was rendered, unoccluded, and the scan kept its pixel).
//! Not every unnamed point is hidden, though: the truth names the nearest corner of the
//! triangle seen at each pixel, so where the template is finer than the pixel grid (the face,
//! the hands) a visible vertex may never be named, and at a silhouette the sensor samples the
//! surface at a grazing angle. Neither answer is wrong within a short distance of a seen
//! point, so a point that is not shown but lies within [`SHOWN_BAND`]·√area of a shown one
//! along the template's edges is in the **band** and scored neither way; every other point is
//! **hidden**.
//!
//! # Scores
//! * **coverage** = shown points given a counterpart / shown points;
//! * **`no_counterpart` precision** = listed hidden points / listed points outside the band;
//! * **`no_counterpart` recall** = listed hidden points / hidden points.

use crate::dataset::MeshIds;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Width of the band between shown and hidden points, in units of the template's √area
/// (about 2 cm on a body): a few template edges, a few pixels of a depth camera at 3 m.
pub const SHOWN_BAND: f64 = 0.015;

/// Per template vertex of the mesh the matcher worked on: shown, hidden, or neither (the band).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShownPoints {
    /// Shown by the scan (some scan vertex's truth names it).
    pub shown: Vec<bool>,
    /// Hidden: neither shown nor an edge neighbour of a shown point.
    pub hidden: Vec<bool>,
}

impl ShownPoints {
    /// The shown and hidden template points of a scan: `template` relates the template the
    /// matcher worked on to the common ids the truth speaks, `positions` and `neighbors` are
    /// its vertices and edge graph, `target_truth` the common id per scan input vertex
    /// (`None`: nothing seen there).
    ///
    /// ```
    /// use symcorr_eval::{MeshIds, ShownPoints};
    /// // A path 0 – 1 – 2 – 3 with edges of 0.01 (area 1: the band is 0.015 wide); the scan
    /// // saw vertex 0 only.
    /// let ids = MeshIds { input_ids: &[0, 1, 2, 3], prepared_ids: &[Some(0), Some(1), Some(2), Some(3)], area: 1.0 };
    /// let positions = [[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.02, 0.0, 0.0], [0.03, 0.0, 0.0]];
    /// let neighbors = vec![vec![1], vec![0, 2], vec![1, 3], vec![2]];
    /// let s = ShownPoints::new(&ids, &positions, &neighbors, &[Some(0), None, Some(0)]);
    /// assert_eq!(s.shown, [true, false, false, false]);
    /// assert_eq!(s.hidden, [false, false, true, true]); // vertex 1 is the band
    /// ```
    pub fn new(
        template: &MeshIds<'_>,
        positions: &[[f64; 3]],
        neighbors: &[Vec<u32>],
        target_truth: &[Option<u32>],
    ) -> ShownPoints {
        let n = template.input_ids.len();
        let mut shown = vec![false; n];
        for c in target_truth.iter().flatten() {
            if let Some(Some(p)) = template.prepared_ids.get(*c as usize) {
                if let Some(s) = shown.get_mut(*p as usize) {
                    *s = true;
                }
            }
        }
        // Distance along the edges to the nearest shown point, searched no farther than the
        // band (multi-source Dijkstra).
        let band = SHOWN_BAND * template.area.sqrt();
        let mut dist = vec![f64::INFINITY; n];
        let mut heap = BinaryHeap::new();
        for v in (0..n).filter(|&v| shown[v]) {
            dist[v] = 0.0;
            heap.push(Reverse((0u64, v)));
        }
        // Distances are non-negative: their IEEE bit patterns order like the numbers.
        while let Some(Reverse((key, v))) = heap.pop() {
            let d = f64::from_bits(key);
            if d > dist[v] {
                continue;
            }
            for &u in neighbors.get(v).map_or(&[][..], Vec::as_slice) {
                let u = u as usize;
                let (Some(a), Some(b)) = (positions.get(v), positions.get(u)) else {
                    continue;
                };
                let e = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
                if u < n && d + e < dist[u] && d + e <= band {
                    dist[u] = d + e;
                    heap.push(Reverse(((d + e).to_bits(), u)));
                }
            }
        }
        let hidden = dist.iter().map(|d| d.is_infinite()).collect();
        ShownPoints { shown, hidden }
    }
}

/// Counts behind coverage and the `no_counterpart` precision and recall; they add over pairs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ScanScores {
    /// Template points the scan shows.
    pub shown: usize,
    /// Shown points the matcher gave a counterpart.
    pub shown_matched: usize,
    /// Template points the scan does not show (outside the band).
    pub hidden: usize,
    /// Points the matcher listed without a counterpart, outside the band.
    pub listed: usize,
    /// Listed points that are hidden.
    pub listed_hidden: usize,
}

impl ScanScores {
    /// Scores a matcher's answer: `template_points[i]` (a vertex of the template the matcher
    /// worked on) has a counterpart when `has_counterpart[i]`. Points the matcher did not
    /// consider (a sparse sample) count for nothing.
    ///
    /// ```
    /// use symcorr_eval::{ScanScores, ShownPoints};
    /// let s = ShownPoints { shown: vec![true, true, false, false], hidden: vec![false, false, false, true] };
    /// // 0 matched, 1 listed (wrongly), 2 in the band, 3 listed (rightly).
    /// let c = ScanScores::new(&s, &[0, 1, 2, 3], &[true, false, false, false]);
    /// assert_eq!(c.coverage(), Some(0.5));
    /// assert_eq!(c.precision(), Some(0.5));
    /// assert_eq!(c.recall(), Some(1.0));
    /// ```
    pub fn new(
        points: &ShownPoints,
        template_points: &[u32],
        has_counterpart: &[bool],
    ) -> ScanScores {
        let mut s = ScanScores::default();
        for (&p, &h) in template_points.iter().zip(has_counterpart) {
            let p = p as usize;
            let (shown, hidden) = (
                points.shown.get(p).copied().unwrap_or(false),
                points.hidden.get(p).copied().unwrap_or(false),
            );
            s.shown += usize::from(shown);
            s.shown_matched += usize::from(shown && h);
            s.hidden += usize::from(hidden);
            s.listed += usize::from(!h && (shown || hidden));
            s.listed_hidden += usize::from(!h && hidden);
        }
        s
    }

    /// Shown points given a counterpart / shown points (`None` when none is shown).
    pub fn coverage(&self) -> Option<f64> {
        ratio(self.shown_matched, self.shown)
    }

    /// Listed hidden points / listed points outside the band (`None` when none listed).
    pub fn precision(&self) -> Option<f64> {
        ratio(self.listed_hidden, self.listed)
    }

    /// Listed hidden points / hidden points (`None` when none is hidden).
    pub fn recall(&self) -> Option<f64> {
        ratio(self.listed_hidden, self.hidden)
    }
}

impl std::ops::Add for ScanScores {
    type Output = ScanScores;

    /// The sum of two pairs' counts.
    fn add(self, o: ScanScores) -> ScanScores {
        ScanScores {
            shown: self.shown + o.shown,
            shown_matched: self.shown_matched + o.shown_matched,
            hidden: self.hidden + o.hidden,
            listed: self.listed + o.listed,
            listed_hidden: self.listed_hidden + o.listed_hidden,
        }
    }
}

fn ratio(a: usize, b: usize) -> Option<f64> {
    (b > 0).then(|| a as f64 / b as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5 × 1 strip of unit squares: vertices 0..6 on the bottom row, 6..12 on the top.
    /// The scan (in reverse order, through a repair that dropped input vertex 11) saw the
    /// left two columns.
    #[test]
    fn shown_band_hidden_on_a_strip_through_a_repair() {
        let m = symcorr_mesh::testmesh::grid(5, 1, [1.0, 1.0]);
        // Repair: input vertex 11 removed; prepared ids shift down by nothing else.
        let input_ids: Vec<u32> = (0..11).collect();
        let mut prepared_ids: Vec<Option<u32>> = (0..11).map(Some).collect();
        prepared_ids.push(None);
        // Area 5 000: the band is 0.015·√5000 ≈ 1.06, one edge (not a diagonal, √2).
        let ids = MeshIds {
            input_ids: &input_ids,
            prepared_ids: &prepared_ids,
            area: 5000.0,
        };
        let mut nb = m.vertex_neighbors();
        nb.truncate(11);
        for l in &mut nb {
            l.retain(|&u| u < 11);
        }
        let truth = [Some(7), None, Some(6), Some(1), Some(0), Some(0)];
        let s = ShownPoints::new(&ids, &m.positions[..11], &nb, &truth);
        let shown: Vec<usize> = (0..11).filter(|&v| s.shown[v]).collect();
        assert_eq!(shown, [0, 1, 6, 7]);
        // Column 2 (vertices 2 and 8) is one edge from column 1: the band. Columns 3–5 are
        // hidden.
        let hidden: Vec<usize> = (0..11).filter(|&v| s.hidden[v]).collect();
        assert_eq!(hidden, [3, 4, 5, 9, 10]);
        // A matcher listing the right side from column 2 on, and vertex 0 by mistake.
        let points: Vec<u32> = (0..11).collect();
        let has: Vec<bool> = (0..11).map(|v| v != 0 && v % 6 < 2).collect();
        let c = ScanScores::new(&s, &points, &has);
        assert_eq!(c.shown, 4);
        assert_eq!(c.shown_matched, 3);
        assert_eq!(c.hidden, 5);
        assert_eq!(
            c.listed, 6,
            "vertex 0 and the five hidden; the band not counted"
        );
        assert_eq!(c.listed_hidden, 5);
        assert_eq!(c.recall(), Some(1.0));
        assert!((c.precision().unwrap() - 5.0 / 6.0).abs() < 1e-12);
        // Pooled with a pair that matched everything: recall halves.
        let all = ScanScores::new(&s, &points, &[true; 11]);
        let both = c + all;
        assert_eq!(both.recall(), Some(0.5));
        assert_eq!(both.coverage(), Some(7.0 / 8.0));
        assert_eq!(ScanScores::default().coverage(), None);
    }
}
