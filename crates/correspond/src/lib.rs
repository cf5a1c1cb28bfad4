//! The matching stages of symcorr and the evaluation metrics (DESIGN.md, Algorithms 3–7 and
//! Metrics). Every stage is a plain function on plain data: it can be tested alone, and the
//! `symcorr` crate wires the spectral inputs (symcorr-spectral) and the segment labels and
//! bone weights (symcorr-attach) into it.
//!
//! # Three methods
//! * **The paper's** ("Symmetry-Aware Human Shape Correspondence Using Skeleton"):
//!   [`candidates()`] (§3.1, the nearest si-HKS descriptors) → [`skeleton_filter`] (§3.2, drop
//!   candidates on another segment; beyond the paper also another sagittal half of a midline
//!   segment, and the [`sagittal_band`]) → [`select`] (§3.3, eq. 7–8 with [`base_profile`]).
//!   [`match_points`] runs them for a set of template points; [`farthest_point_sample`] picks
//!   the sparse mode's points.
//! * **Refined** ([`refine_dense`]): skeleton landmark coordinates ⊕ si-HKS, nearest neighbour
//!   within [`SegmentPools`], then segment-constrained [`zoomout`] (module `refine`).
//! * **Articulated** ([`articulated_match`], symcorr's default): the template skinned onto the
//!   target's skeleton, articulated ICP within segment pools, a non-rigid step, nearest target
//!   vertex of the pool (module `articulated`). Extrinsic, so partial targets work.
//!
//! [`evaluate`], [`cumulative_curve`] and [`table1_row`] are the paper's measurements.
//!
//! ```
//! use symcorr_skeleton::Segment::{ThighLeft, ThighRight};
//! use symcorr_correspond::{match_points, Descriptors, MatchOptions, Side};
//! // Two vertices per mesh with identical descriptors (a perfect left/right symmetry): only
//! // the segments tell them apart.
//! let d = Descriptors::new(2, 1, vec![1.0, 1.0]).unwrap();
//! let labels = [ThighLeft, ThighRight];
//! let profile = [0.3, 0.3];
//! let side = Side { descriptors: &d, labels: &labels, profile: &profile, halves: None, sagittal: None, positions: None };
//! let out = match_points(&side, &side, &[0, 1], &MatchOptions::default()).unwrap();
//! assert_eq!(out.matches[0].target, 0);
//! assert_eq!(out.matches[1].target, 1);
//! ```
//!
//! # Invariants and conventions
//! * A match never joins a left segment to a right one: the filter and the pools are the
//!   skeleton constraint. If the filter removes every candidate, the nearest target vertex of
//!   the same segment by descriptor is used and counted ([`FilterStats::fallbacks`]); a segment
//!   the target lacks keeps its side-compatible candidates ([`FilterStats::segment_missing`]).
//! * Eq. 8 uses `|D̂(c) − D̂(p)|`, `D̂` the *mean* base-set distance over √area; ties go to the
//!   nearer descriptor. The candidate threshold, when used, is relative (`d ≤ t·d₁(p)`).
//! * Confidence in (0, 1], per method: paper, `1/(1 + s/s̃)` from the spread `s` of the
//!   filtered candidates around the chosen one when target positions are given
//!   ([`Side::positions`]; a fallback match gets 0), else `1/(1 + d/d̃ + g/g̃)` from descriptor
//!   distance and eq. 8 gap ([`assign_confidence`]); refined, `1/(1 + r/r̃)` from the final
//!   spectral residual; articulated, `1/(1 + d/gate)` from the final distance and gate.
//! * Metrics use edge-path Dijkstra geodesics stopped at the ground truth ([`evaluate`]).
//!
//! # Measured choices
//! In `docs/decisions/`: `2026-11-23-paper-pipeline-defaults.md` (N = [`DEFAULT_NEAREST`]),
//! `2026-11-23-midline-halves-and-skull-plane.md`, `2026-11-23-sagittal-band.md`
//! ([`DEFAULT_SAGITTAL_RATIO`]), the paper pipeline's dead ends
//! (`2026-12-01-lateral-band-rejected.md`, `2026-12-02-paper-pipeline-remaining-flips.md`,
//! `2026-12-02-paper-candidate-stage-variants.md`), `2026-11-23-refined-method.md`,
//! `2026-11-23-articulated-alignment.md`, `2026-11-23-articulated-nonrigid-step.md`,
//! `2026-12-01-articulated-adjacent-pools.md` and `2026-12-01-articulated-kdtrees.md`.

mod articulated;
mod candidates;
mod filter;
mod kdtree;
mod landmarks;
mod metrics;
mod pools;
mod sample;
mod selection;
mod symmetry;

pub use articulated::{
    articulated_match, bone_transforms, outward_normals, skin, ArticulatedMatches,
    ArticulatedOptions, ArticulatedSide, BoneTransform, Mat3, DEFAULT_ICP_POINTS, TWISTS,
};
pub use candidates::{candidates, Candidate, CandidateOptions, Descriptors};
pub use filter::{sagittal_band, skeleton_filter, BandStats, FilterStats};
pub use landmarks::{joint_landmarks, landmark_coordinates, skeleton_landmarks};
pub use metrics::{
    cumulative_curve, evaluate, table1_row, within, EvalGraph, Evaluation, FLIP_MIN_SEPARATION,
};
pub use pools::{
    adjacent_segments, coverage, nearest_in_pools, refine_dense, zoomout, RefineOptions,
    RefineSide, RefinedMatches, SegmentPools, SpectralBasis, ZoomOutOptions, ZoomOutResult,
    DEFAULT_ZOOMOUT_POINTS,
};
pub use sample::farthest_point_sample;
pub use selection::{assign_confidence, base_profile, select, Match, Pair};
pub use symmetry::refine_symmetry_plane;

use std::time::Instant;
use symcorr_skeleton::Segment;

/// Default number of nearest candidates per template point (§3.1), chosen by measurement
/// (`docs/decisions/2026-11-23-paper-pipeline-defaults.md`).
pub const DEFAULT_NEAREST: usize = 5;

/// Errors of the matching stages.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CorrespondError {
    /// An argument is inconsistent or out of range (the message says which).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
}

/// Everything the matching stages need about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// Point descriptors (si-HKS), one row per vertex.
    pub descriptors: &'a Descriptors,
    /// Segment label per vertex (symcorr-attach).
    pub labels: &'a [Segment],
    /// Base-set profile `D̂` per vertex ([`base_profile`]).
    pub profile: &'a [f64],
    /// Optional sagittal half per vertex for the midline segments (see [`skeleton_filter`]):
    /// `-1` right, `+1` left, `0` near the plane or not on a midline segment.
    pub halves: Option<&'a [i8]>,
    /// Optional sagittal coordinate per vertex for the midline segments (see
    /// [`sagittal_band`]): signed distance to the segment's sagittal plane over the segment's
    /// half-width, `+` on the subject's left, `0` on limb segments.
    pub sagittal: Option<&'a [f64]>,
    /// Optional vertex positions: on the target side they give each match its candidate
    /// spread, from which its confidence is computed ([`assign_confidence`]).
    pub positions: Option<&'a [[f64; 3]]>,
}

impl Side<'_> {
    fn check(&self, name: &str) -> Result<(), CorrespondError> {
        let n = self.descriptors.len();
        if self.labels.len() != n
            || self.profile.len() != n
            || self.halves.is_some_and(|h| h.len() != n)
            || self.sagittal.is_some_and(|h| h.len() != n)
            || self.positions.is_some_and(|h| h.len() != n)
        {
            return Err(CorrespondError::InvalidArgument(format!(
                "{name}: {n} descriptors, {} labels, {} profile values",
                self.labels.len(),
                self.profile.len()
            )));
        }
        Ok(())
    }
}

/// Options of [`match_points`].
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOptions {
    /// The candidate rule (§3.1).
    pub candidates: CandidateOptions,
    /// Apply the skeleton filter (§3.2). `false` is the ablation: the paper's method without
    /// its contribution.
    pub skeleton_filter: bool,
    /// Within the filter, also separate the left and right halves of the midline segments
    /// ([`Side::halves`], when both sides have them). `false` is the paper's filter exactly.
    pub midline_halves: bool,
    /// Beyond the paper: the sagittal band ([`sagittal_band`], when both sides have
    /// [`Side::sagittal`] and the filter is on): a midline point's candidates must lie on its
    /// side at least this fraction of its own (normalised) distance from the plane. `None`
    /// switches it off.
    pub sagittal_ratio: Option<f64>,
}

/// Default [`MatchOptions::sagittal_ratio`] (measured: `docs/decisions/2026-11-23-sagittal-band.md`).
pub const DEFAULT_SAGITTAL_RATIO: f64 = 0.5;

impl Default for MatchOptions {
    fn default() -> Self {
        MatchOptions {
            candidates: CandidateOptions::default(),
            skeleton_filter: true,
            midline_halves: true,
            sagittal_ratio: Some(DEFAULT_SAGITTAL_RATIO),
        }
    }
}

/// The result of [`match_points`].
#[derive(Debug, Clone)]
pub struct PointMatches {
    /// One match per template point that had a candidate, in the order of the points.
    pub matches: Vec<Match>,
    /// What the skeleton filter did (all zero when it was off).
    pub filter: FilterStats,
    /// What the sagittal band did (all zero when it was off).
    pub band: BandStats,
    /// Mean number of candidates per point before the filter.
    pub mean_candidates: f64,
    /// Seconds per stage: `candidates`, `skeleton_filter`, `selection`.
    pub timings: Vec<(&'static str, f64)>,
}

/// Stages 1–3 for the template points `points`: candidates, skeleton filter, selection.
///
/// Errors: [`CorrespondError::InvalidArgument`] if a side's tables disagree in length, the
/// descriptors differ in length between sides, or a point is out of range.
pub fn match_points(
    template: &Side<'_>,
    target: &Side<'_>,
    points: &[u32],
    options: &MatchOptions,
) -> Result<PointMatches, CorrespondError> {
    template.check("template")?;
    target.check("target")?;
    let mut timings = Vec::new();
    let t = Instant::now();
    let mut cands = candidates(
        template.descriptors,
        target.descriptors,
        points,
        &options.candidates,
    )?;
    timings.push(("candidates", t.elapsed().as_secs_f64()));
    let mean_candidates =
        cands.iter().map(Vec::len).sum::<usize>() as f64 / cands.len().max(1) as f64;
    let t = Instant::now();
    let filter = if options.skeleton_filter {
        let halves = match (options.midline_halves, template.halves, target.halves) {
            (true, Some(a), Some(b)) => Some((a, b)),
            _ => None,
        };
        skeleton_filter(
            &mut cands,
            points,
            (template.labels, target.labels),
            halves,
            template.descriptors,
            target.descriptors,
        )
    } else {
        FilterStats::default()
    };
    let band = match (
        options.skeleton_filter,
        options.sagittal_ratio,
        template.sagittal,
        target.sagittal,
    ) {
        (true, Some(ratio), Some(a), Some(b)) => sagittal_band(
            &mut cands,
            points,
            (template.labels, target.labels),
            (a, b),
            ratio,
            template.descriptors,
            target.descriptors,
        ),
        _ => BandStats::default(),
    };
    timings.push(("skeleton_filter", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let mut matches = select(&cands, points, template.profile, target.profile);
    if let Some(pos) = target.positions {
        // Points without candidates got no match, so walk the lists in step with the matches.
        let mut it = cands.iter().filter(|c| !c.is_empty());
        for m in matches.iter_mut() {
            let Some(list) = it.next() else { break };
            let c = pos[m.target as usize];
            let others: Vec<f64> = list
                .iter()
                .filter(|x| x.vertex != m.target)
                .map(|x| {
                    let q = pos[x.vertex as usize];
                    ((q[0] - c[0]).powi(2) + (q[1] - c[1]).powi(2) + (q[2] - c[2]).powi(2)).sqrt()
                })
                .collect();
            m.candidate_spread = Some(if others.is_empty() {
                f64::INFINITY
            } else {
                others.iter().sum::<f64>() / others.len() as f64
            });
        }
        assign_confidence(&mut matches);
    }
    timings.push(("selection", t.elapsed().as_secs_f64()));
    Ok(PointMatches {
        matches,
        filter,
        band,
        mean_candidates,
        timings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use Segment::*;

    #[test]
    fn ablation_flips_symmetric_points_and_the_filter_fixes_them() {
        // Target vertex 0 (left) and 1 (right) have identical descriptors and profiles; the
        // template's left point is slightly nearer the right one in descriptor space.
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(2, 1, vec![0.011, 0.01]).unwrap();
        let tl = [ThighLeft];
        let ul = [ThighLeft, ThighRight];
        let tp = [0.5];
        let up = [0.5, 0.5];
        let ts = Side {
            descriptors: &t,
            labels: &tl,
            profile: &tp,
            halves: None,
            sagittal: None,
            positions: None,
        };
        let us = Side {
            descriptors: &u,
            labels: &ul,
            profile: &up,
            halves: None,
            sagittal: None,
            positions: None,
        };
        let off = MatchOptions {
            skeleton_filter: false,
            ..MatchOptions::default()
        };
        assert_eq!(
            match_points(&ts, &us, &[0], &off).unwrap().matches[0].target,
            1
        );
        let on = match_points(&ts, &us, &[0], &MatchOptions::default()).unwrap();
        assert_eq!(on.matches[0].target, 0);
        assert_eq!(on.filter.removed, 1);
        assert_eq!(on.timings.len(), 3);
    }

    /// A torso point well left of the plane; its candidates are a vertex on the plane (the
    /// navel, say) with the best eq. 8 gap and one as far left as the point with a worse gap.
    /// The paper's selection takes the vertex on the plane; the sagittal band does not.
    #[test]
    fn sagittal_band_keeps_midline_points_off_the_plane() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(2, 1, vec![0.01, 0.02]).unwrap();
        let ts = Side {
            descriptors: &t,
            labels: &[Torso],
            profile: &[0.5],
            halves: Some(&[1]),
            sagittal: Some(&[0.7]),
            positions: None,
        };
        let us = Side {
            descriptors: &u,
            labels: &[Torso, Torso],
            profile: &[0.5, 0.6],
            halves: Some(&[0, 1]),
            sagittal: Some(&[0.0, 0.7]),
            positions: None,
        };
        let on = match_points(&ts, &us, &[0], &MatchOptions::default()).unwrap();
        assert_eq!(on.matches[0].target, 1);
        assert_eq!(on.band.removed, 1);
        let off = MatchOptions {
            sagittal_ratio: None,
            ..MatchOptions::default()
        };
        let out = match_points(&ts, &us, &[0], &off).unwrap();
        assert_eq!(out.matches[0].target, 0);
        assert_eq!(out.band, BandStats::default());
        // The ablation is the paper without its filter: no band either.
        let ablation = MatchOptions {
            skeleton_filter: false,
            ..MatchOptions::default()
        };
        let out = match_points(&ts, &us, &[0], &ablation).unwrap();
        assert_eq!(out.matches[0].target, 0);
    }

    #[test]
    fn mismatched_tables_are_errors() {
        let d = Descriptors::new(2, 1, vec![0.0, 1.0]).unwrap();
        let s = Side {
            descriptors: &d,
            labels: &[Torso],
            profile: &[0.0, 0.0],
            halves: None,
            sagittal: None,
            positions: None,
        };
        assert!(match_points(&s, &s, &[0], &MatchOptions::default()).is_err());
    }
}
