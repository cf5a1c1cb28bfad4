//! The paper's method ("Symmetry-Aware Human Shape Correspondence Using Skeleton"): for each
//! template point, the nearest si-HKS descriptors ([`candidates()`], §3.1) → the skeleton
//! filter ([`skeleton_filter`], §3.2; beyond the paper also the sagittal halves of the midline
//! segments and the [`sagittal_band`]) → eq. 7–8's selection by the base-set profile
//! ([`select`], [`base_profile`], §3.3). [`match_points`] runs the three stages;
//! [`farthest_point_sample`] picks the sparse mode's points.

mod candidates;
mod filter;
mod sample;
mod selection;

pub use candidates::{candidates, Candidate, CandidateOptions, Descriptors};
pub use filter::{sagittal_band, skeleton_filter, BandStats, FilterStats};
pub use sample::farthest_point_sample;
pub use selection::{assign_confidence, base_profile, select, Match};

use crate::{same_len, CorrespondError};
use nalgebra::Point3;
use std::time::Instant;
use symcorr_skeleton::{BodySide, Segment};

/// What the paper's method ([`match_points`]) needs about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct PaperInputs<'a> {
    /// Point descriptors (si-HKS), one row per vertex.
    pub descriptors: &'a Descriptors,
    /// Segment label per vertex (symcorr-attach).
    pub labels: &'a [Segment],
    /// Base-set profile `D̂` per vertex ([`base_profile`]).
    pub profile: &'a [f64],
    /// Optional sagittal half per vertex for the midline segments (see [`skeleton_filter`]):
    /// [`BodySide::Midline`] near the plane or not on a midline segment.
    pub halves: Option<&'a [BodySide]>,
    /// Optional sagittal coordinate per vertex for the midline segments (see
    /// [`sagittal_band`]): signed distance to the segment's sagittal plane over the segment's
    /// half-width, `+` on the subject's left, `0` on limb segments.
    pub sagittal: Option<&'a [f64]>,
    /// Optional vertex positions: on the target side they give each match its candidate
    /// spread, from which its confidence is computed ([`assign_confidence`]).
    pub positions: Option<&'a [[f64; 3]]>,
}

impl PaperInputs<'_> {
    /// Every table has one entry per descriptor row.
    fn check(&self, side: &str) -> Result<(), CorrespondError> {
        let n = self.descriptors.len();
        let tables = [
            ("labels", Some(self.labels.len())),
            ("profile values", Some(self.profile.len())),
            ("halves", self.halves.map(<[BodySide]>::len)),
            ("sagittal coordinates", self.sagittal.map(<[f64]>::len)),
            ("positions", self.positions.map(<[[f64; 3]]>::len)),
        ];
        for (table, len) in tables {
            if let Some(found) = len {
                same_len(&format!("{side} {table} (one per descriptor)"), n, found)?;
            }
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
    /// ([`PaperInputs::halves`], when both sides have them). `false` is the paper's filter exactly.
    pub midline_halves: bool,
    /// Beyond the paper: the sagittal band ([`sagittal_band`], when both sides have
    /// [`PaperInputs::sagittal`] and the filter is on): a midline point's candidates must lie on its
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
/// Errors: [`CorrespondError::LengthMismatch`] if a side's tables disagree in length or the
/// descriptors differ in length between sides, [`CorrespondError::IndexOutOfRange`] for a
/// point out of range (see [`candidates()`] for the rest).
pub fn match_points(
    template: &PaperInputs<'_>,
    target: &PaperInputs<'_>,
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
            let c = Point3::from(pos[m.target as usize]);
            let others: Vec<f64> = list
                .iter()
                .filter(|x| x.vertex != m.target)
                .map(|x| nalgebra::distance(&Point3::from(pos[x.vertex as usize]), &c))
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
        let ts = PaperInputs {
            descriptors: &t,
            labels: &tl,
            profile: &tp,
            halves: None,
            sagittal: None,
            positions: None,
        };
        let us = PaperInputs {
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
        let ts = PaperInputs {
            descriptors: &t,
            labels: &[Torso],
            profile: &[0.5],
            halves: Some(&[BodySide::Left]),
            sagittal: Some(&[0.7]),
            positions: None,
        };
        let us = PaperInputs {
            descriptors: &u,
            labels: &[Torso, Torso],
            profile: &[0.5, 0.6],
            halves: Some(&[BodySide::Midline, BodySide::Left]),
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
        let s = PaperInputs {
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
