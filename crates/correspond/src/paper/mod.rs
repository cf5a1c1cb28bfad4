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

/// The skeleton filter of the paper's method (§3.2), as the paper wrote it or extended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PaperFilter {
    /// No filter: the ablation, the paper's method without its contribution.
    Off,
    /// §3.2 as written: a candidate survives only on the template point's segment.
    Strict,
    /// Beyond the paper: [`PaperFilter::Strict`], and on the midline segments (pelvis, torso,
    /// head) also the same sagittal half ([`PaperInputs::halves`], when both sides have them)
    /// and, with a ratio, the [`sagittal_band`] (when both sides have
    /// [`PaperInputs::sagittal`]): a midline point's candidates must lie on its side at least
    /// this fraction of its own (normalised) distance from the plane.
    Extended {
        /// The band's ratio; `None` keeps the halves without the band.
        sagittal_ratio: Option<f64>,
    },
}

impl PaperFilter {
    /// The extended filter with the measured band ratio ([`DEFAULT_SAGITTAL_RATIO`]).
    pub const DEFAULT: PaperFilter = PaperFilter::Extended {
        sagittal_ratio: Some(DEFAULT_SAGITTAL_RATIO),
    };
}

impl Default for PaperFilter {
    fn default() -> Self {
        PaperFilter::DEFAULT
    }
}

/// Options of [`match_points`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MatchOptions {
    /// The candidate rule (§3.1).
    pub candidates: CandidateOptions,
    /// The skeleton filter (§3.2).
    pub filter: PaperFilter,
}

/// Default band ratio of [`PaperFilter::Extended`] (measured:
/// `docs/decisions/2026-11-23-sagittal-band.md`).
pub const DEFAULT_SAGITTAL_RATIO: f64 = 0.5;

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
    let (filter, band) = apply_filter(&mut cands, points, template, target, options.filter);
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

/// The filter stage of [`match_points`] on candidate lists: the segment filter (with the
/// halves when extended), then the band.
fn apply_filter(
    cands: &mut [Vec<Candidate>],
    points: &[u32],
    template: &PaperInputs<'_>,
    target: &PaperInputs<'_>,
    filter: PaperFilter,
) -> (FilterStats, BandStats) {
    let (halves, ratio) = match filter {
        PaperFilter::Off => return (FilterStats::default(), BandStats::default()),
        PaperFilter::Strict => (None, None),
        PaperFilter::Extended { sagittal_ratio } => (
            template.halves.zip(target.halves),
            sagittal_ratio.zip(template.sagittal.zip(target.sagittal)),
        ),
    };
    let labels = (template.labels, target.labels);
    let stats = skeleton_filter(
        cands,
        points,
        labels,
        halves,
        template.descriptors,
        target.descriptors,
    );
    let band = match ratio {
        Some((ratio, sagittal)) => sagittal_band(
            cands,
            points,
            labels,
            sagittal,
            ratio,
            template.descriptors,
            target.descriptors,
        ),
        None => BandStats::default(),
    };
    (stats, band)
}

/// One template point through the paper's stages (its Fig. 2): the candidates before and after
/// the filter, and the one eq. 8 selects. [`explain_point`] computes it.
#[derive(Debug, Clone, PartialEq)]
pub struct PointExplanation {
    /// The template point.
    pub point: u32,
    /// Its candidates by descriptor (§3.1), nearest first, before the filter.
    pub candidates: Vec<Candidate>,
    /// What the filter left, nearest first; when it removed every candidate, its fallback
    /// (the nearest target vertex of the point's segment by descriptor, not one of
    /// [`PointExplanation::candidates`]).
    pub filtered: Vec<Candidate>,
    /// The filter removed every candidate and [`PointExplanation::filtered`] is its fallback.
    pub fallback: bool,
    /// The candidate eq. 8 selects from the filtered ones, and its `|D̂(c) − D̂(p)|`.
    pub selected: Option<(Candidate, f64)>,
}

/// Runs the stages of [`match_points`] for one template point and keeps what each did
/// ([`PointExplanation`]). The selected candidate is the one `match_points` matches `point` to.
///
/// Errors: as [`match_points`].
///
/// ```
/// use symcorr_skeleton::Segment::{ThighLeft, ThighRight};
/// use symcorr_correspond::{explain_point, Descriptors, MatchOptions, PaperInputs};
/// let d = Descriptors::new(2, 1, vec![1.0, 1.0]).unwrap();
/// let (labels, profile) = ([ThighLeft, ThighRight], [0.3, 0.3]);
/// let side = PaperInputs { descriptors: &d, labels: &labels, profile: &profile,
///                          halves: None, sagittal: None, positions: None };
/// let e = explain_point(&side, &side, 0, &MatchOptions::default()).unwrap();
/// assert_eq!(e.candidates.len(), 2); // both thighs look alike to the descriptor
/// assert_eq!(e.filtered.len(), 1); // the filter keeps the left one
/// assert_eq!(e.selected.unwrap().0.vertex, 0);
/// ```
pub fn explain_point(
    template: &PaperInputs<'_>,
    target: &PaperInputs<'_>,
    point: u32,
    options: &MatchOptions,
) -> Result<PointExplanation, CorrespondError> {
    template.check("template")?;
    target.check("target")?;
    let points = [point];
    let mut cands = candidates(
        template.descriptors,
        target.descriptors,
        &points,
        &options.candidates,
    )?;
    let before = cands.first().cloned().unwrap_or_default();
    let (filter, band) = apply_filter(&mut cands, &points, template, target, options.filter);
    let filtered = cands.first().cloned().unwrap_or_default();
    let selected = select(&cands, &points, template.profile, target.profile)
        .first()
        .map(|m| {
            (
                Candidate {
                    vertex: m.target,
                    distance: m.descriptor_distance,
                },
                m.profile_gap,
            )
        });
    Ok(PointExplanation {
        point,
        candidates: before,
        filtered,
        fallback: filter.fallbacks + band.fallbacks > 0,
        selected,
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
            filter: PaperFilter::Off,
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
            filter: PaperFilter::Extended {
                sagittal_ratio: None,
            },
            ..MatchOptions::default()
        };
        let out = match_points(&ts, &us, &[0], &off).unwrap();
        assert_eq!(out.matches[0].target, 0);
        assert_eq!(out.band, BandStats::default());
        // The ablation is the paper without its filter: no band either.
        let ablation = MatchOptions {
            filter: PaperFilter::Off,
            ..MatchOptions::default()
        };
        let out = match_points(&ts, &us, &[0], &ablation).unwrap();
        assert_eq!(out.matches[0].target, 0);
    }

    /// The paper's filter keeps the other half of a torso; the extended one does not, and
    /// [`explain_point`] shows both lists and the match [`match_points`] makes.
    #[test]
    fn strict_filter_keeps_the_other_half_of_a_midline_segment() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(3, 1, vec![0.01, 0.02, 0.5]).unwrap();
        let ts = PaperInputs {
            descriptors: &t,
            labels: &[Torso],
            profile: &[0.5],
            halves: Some(&[BodySide::Left]),
            sagittal: None,
            positions: None,
        };
        let us = PaperInputs {
            descriptors: &u,
            labels: &[Torso, Torso, ThighLeft],
            profile: &[0.5, 0.6, 0.5],
            halves: Some(&[BodySide::Right, BodySide::Left, BodySide::Midline]),
            sagittal: None,
            positions: None,
        };
        for (filter, kept, target) in [
            (PaperFilter::Off, 3, 0),
            (PaperFilter::Strict, 2, 0),
            (PaperFilter::DEFAULT, 1, 1),
        ] {
            let o = MatchOptions {
                filter,
                ..MatchOptions::default()
            };
            let e = explain_point(&ts, &us, 0, &o).unwrap();
            assert_eq!(e.candidates.len(), 3, "{filter:?}");
            assert_eq!(e.filtered.len(), kept, "{filter:?}");
            assert!(!e.fallback);
            assert_eq!(e.selected.unwrap().0.vertex, target, "{filter:?}");
            let m = match_points(&ts, &us, &[0], &o).unwrap();
            assert_eq!(m.matches[0].target, target, "{filter:?}");
        }
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
