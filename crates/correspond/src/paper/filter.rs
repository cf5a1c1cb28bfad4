//! Skeleton filter (paper §3.2): a candidate on a different body segment than the template
//! point is dropped — this is what keeps a left limb from matching a right one.

use crate::{Candidate, Descriptors};
use symcorr_skeleton::{BodySide, Segment};

/// What the filter did, over all points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FilterStats {
    /// Template points filtered.
    pub points: usize,
    /// Candidates kept (same segment).
    pub kept: usize,
    /// Candidates removed (different segment).
    pub removed: usize,
    /// Points where no candidate survived and the nearest target vertex *of the same segment*
    /// by descriptor was used instead (the filter's fallback).
    pub fallbacks: usize,
    /// Points whose segment does not occur on the target at all (attachment gave it no
    /// vertex, or a partial scan misses it); for them only candidates on the *other side* are
    /// dropped (a left segment keeps left and midline candidates), with the same fallback.
    pub segment_missing: usize,
}

/// Applies the skeleton filter in place: `cands[i]` are the candidates of template point
/// `points[i]`; afterwards every list holds only target vertices with the point's segment.
///
/// `halves` (optional, one table per mesh) refine the midline segments (pelvis, torso, head),
/// which have a left and a right half that the segment label alone cannot tell apart:
/// [`BodySide::Right`]/[`BodySide::Left`] for a vertex clearly on the subject's right/left of
/// the skeleton's sagittal plane, [`BodySide::Midline`] near the plane (or on a limb). A
/// candidate whose half opposes the point's is dropped too.
///
/// If no candidate survives, the list becomes the single target vertex of the same segment
/// whose descriptor is nearest (counted in [`FilterStats::fallbacks`]). If the target has no
/// vertex of that segment, the filter falls back to sides: candidates on a segment of the
/// opposite side are dropped ([`FilterStats::segment_missing`]).
///
/// ```
/// use symcorr_skeleton::Segment::{ThighLeft, ThighRight};
/// use symcorr_correspond::{skeleton_filter, Candidate, Descriptors};
/// let d = Descriptors::new(2, 1, vec![0.0, 0.1]).unwrap();
/// let mut c = vec![vec![Candidate { vertex: 1, distance: 0.0 }, Candidate { vertex: 0, distance: 0.1 }]];
/// let s = skeleton_filter(&mut c, &[0], (&[ThighLeft, ThighRight], &[ThighLeft, ThighRight]), None, &d, &d);
/// assert_eq!(c[0][0].vertex, 0);
/// assert_eq!(s.removed, 1);
/// ```
///
/// Panics if `points`, `cands` and the label/descriptor tables disagree in length (a caller
/// bug, not bad input: the pipeline builds them together).
pub fn skeleton_filter(
    cands: &mut [Vec<Candidate>],
    points: &[u32],
    (template_labels, target_labels): (&[Segment], &[Segment]),
    halves: Option<(&[BodySide], &[BodySide])>,
    template: &Descriptors,
    target: &Descriptors,
) -> FilterStats {
    // Segments present on the target.
    let mut present = [false; Segment::COUNT];
    for s in target_labels {
        present[s.index()] = true;
    }
    let compatible = |p: u32, q: u32| -> bool {
        let (sp, sq) = (template_labels[p as usize], target_labels[q as usize]);
        let same = if present[sp.index()] {
            sq == sp
        } else {
            !sp.side().opposes(sq.side())
        };
        same && halves.is_none_or(|(hp, hq)| !hp[p as usize].opposes(hq[q as usize]))
    };
    assert_eq!(cands.len(), points.len(), "one candidate list per point");
    // Target vertices per segment, for the fallback search.
    let mut by_segment: Vec<Vec<u32>> = vec![Vec::new(); Segment::COUNT];
    for (v, s) in target_labels.iter().enumerate() {
        by_segment[s.index()].push(v as u32);
    }
    let all: Vec<u32> = (0..target_labels.len() as u32).collect();
    let mut stats = FilterStats {
        points: points.len(),
        ..FilterStats::default()
    };
    for (list, &p) in cands.iter_mut().zip(points) {
        let seg = template_labels[p as usize];
        let before = list.len();
        let mut pool = &by_segment[seg.index()];
        if pool.is_empty() {
            stats.segment_missing += 1;
            pool = &all;
        }
        if pool.is_empty() {
            continue;
        }
        list.retain(|c| compatible(p, c.vertex));
        stats.kept += list.len();
        stats.removed += before - list.len();
        if list.is_empty() {
            stats.fallbacks += 1;
            let nearest = |strict: bool| {
                pool.iter()
                    .filter(|&&q| !strict || compatible(p, q))
                    .map(|&q| Candidate {
                        vertex: q,
                        distance: template.distance(p as usize, target, q as usize),
                    })
                    .min_by(|a, b| a.distance.total_cmp(&b.distance))
            };
            // A compatible vertex if there is one, else the nearest of the pool (non-empty,
            // checked above).
            list.extend(nearest(true).or_else(|| nearest(false)));
        }
    }
    stats
}

/// What [`sagittal_band`] did, over all points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BandStats {
    /// Midline points the band applied to.
    pub points: usize,
    /// Candidates removed for lying too near the plane (or across it).
    pub removed: usize,
    /// Points left without a candidate, given the nearest target vertex by descriptor among
    /// those of the same segment inside the band instead.
    pub fallbacks: usize,
}

/// The sagittal band (beyond the paper; [`PaperFilter::Extended`](crate::PaperFilter)):
/// for a template point `p` on a midline segment (pelvis, torso, head) with sagittal coordinate
/// `s(p)` (signed distance to the segment's sagittal plane over the segment's half-width, `+`
/// on the subject's left), a candidate `q` is kept only if `s(q)·sign(s(p)) ≥ ratio·|s(p)|`:
/// on the same side *and* not much nearer the plane than `p` is on its own mesh.
///
/// Why: the paper's filter keeps every candidate of the right segment, and the midline halves
/// ([`skeleton_filter`]'s `halves`) every candidate of the right half; but a candidate on the
/// plane itself (the navel, the spine, the chin) is about as far from the true point as from
/// its mirror image, and eq. 8's selection picks such vertices often (measured:
/// `docs/decisions/2026-11-23-sagittal-band.md`).
///
/// `cands[i]` are the (already skeleton-filtered) candidates of `points[i]`; `sagittal` gives
/// the coordinate per vertex of each mesh (0 on limb segments, which the band ignores). When
/// no candidate survives, the list becomes the target vertex of the point's segment inside
/// the band with the nearest descriptor (counted in [`BandStats::fallbacks`]); when the
/// target has no such vertex the list is left as it was.
///
/// ```
/// use symcorr_skeleton::Segment::Torso;
/// use symcorr_correspond::{sagittal_band, Candidate, Descriptors};
/// let d = Descriptors::new(3, 1, vec![0.0, 0.1, 0.2]).unwrap();
/// // Candidate 0 lies on the plane, 1 on the point's side as far out as the point, 2 across.
/// let mut c = vec![vec![Candidate { vertex: 0, distance: 0.0 },
///                       Candidate { vertex: 1, distance: 0.1 },
///                       Candidate { vertex: 2, distance: 0.2 }]];
/// let s = sagittal_band(&mut c, &[1], (&[Torso; 3], &[Torso; 3]), (&[0.0, 0.6, -0.6], &[0.0, 0.6, -0.6]), 0.5, &d, &d);
/// assert_eq!(c[0].iter().map(|c| c.vertex).collect::<Vec<_>>(), vec![1]);
/// assert_eq!(s.removed, 2);
/// ```
///
/// Panics if the tables disagree in length (a caller bug: the pipeline builds them together).
pub fn sagittal_band(
    cands: &mut [Vec<Candidate>],
    points: &[u32],
    (template_labels, target_labels): (&[Segment], &[Segment]),
    (template_sagittal, target_sagittal): (&[f64], &[f64]),
    ratio: f64,
    template: &Descriptors,
    target: &Descriptors,
) -> BandStats {
    assert_eq!(cands.len(), points.len(), "one candidate list per point");
    assert_eq!(template_labels.len(), template_sagittal.len());
    assert_eq!(target_labels.len(), target_sagittal.len());
    let mut by_segment: Vec<Vec<u32>> = vec![Vec::new(); Segment::COUNT];
    for (v, s) in target_labels.iter().enumerate() {
        if is_midline(*s) {
            by_segment[s.index()].push(v as u32);
        }
    }
    let mut stats = BandStats::default();
    for (list, &p) in cands.iter_mut().zip(points) {
        let seg = template_labels[p as usize];
        if !is_midline(seg) {
            continue;
        }
        let sp = template_sagittal[p as usize];
        if !sp.is_finite() || sp == 0.0 {
            continue;
        }
        stats.points += 1;
        let inside = |q: u32| {
            let sq = target_sagittal[q as usize];
            target_labels[q as usize] == seg && sq * sp.signum() >= ratio * sp.abs()
        };
        let before = list.len();
        let kept: Vec<Candidate> = list.iter().copied().filter(|c| inside(c.vertex)).collect();
        if !kept.is_empty() {
            stats.removed += before - kept.len();
            *list = kept;
            continue;
        }
        let nearest = by_segment[seg.index()]
            .iter()
            .filter(|&&q| inside(q))
            .map(|&q| Candidate {
                vertex: q,
                distance: template.distance(p as usize, target, q as usize),
            })
            .min_by(|a, b| a.distance.total_cmp(&b.distance));
        if let Some(c) = nearest {
            stats.removed += before;
            stats.fallbacks += 1;
            *list = vec![c];
        }
    }
    stats
}

/// Pelvis, torso and head: the segments the sagittal plane cuts into halves.
pub(crate) fn is_midline(s: Segment) -> bool {
    Segment::MIDLINE.contains(&s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use Segment::*;

    #[test]
    fn fallback_picks_nearest_of_the_same_segment() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(4, 1, vec![0.1, 0.2, 0.9, 0.5]).unwrap();
        let labels_u = [ShinRight, ShinRight, ShinLeft, ShinLeft];
        let mut c = vec![vec![
            Candidate {
                vertex: 0,
                distance: 0.1,
            },
            Candidate {
                vertex: 1,
                distance: 0.2,
            },
        ]];
        let s = skeleton_filter(&mut c, &[0], (&[ShinLeft], &labels_u), None, &t, &u);
        assert_eq!(s.fallbacks, 1);
        assert_eq!(s.removed, 2);
        assert_eq!(c[0].len(), 1);
        assert_eq!(c[0][0].vertex, 3);
        assert!((c[0][0].distance - 0.5).abs() < 1e-12);
    }

    #[test]
    fn halves_split_midline_segments() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(3, 1, vec![0.1, 0.2, 0.3]).unwrap();
        let mut c = vec![vec![
            Candidate {
                vertex: 0,
                distance: 0.1,
            },
            Candidate {
                vertex: 1,
                distance: 0.2,
            },
            Candidate {
                vertex: 2,
                distance: 0.3,
            },
        ]];
        let hu = [BodySide::Right, BodySide::Midline, BodySide::Left];
        let s = skeleton_filter(
            &mut c,
            &[0],
            (&[Torso], &[Torso; 3]),
            Some((&[BodySide::Left], &hu)),
            &t,
            &u,
        );
        assert_eq!(s.removed, 1);
        let got: Vec<u32> = c[0].iter().map(|c| c.vertex).collect();
        assert_eq!(got, vec![1, 2]);
    }

    #[test]
    fn sagittal_band_drops_near_plane_candidates_and_falls_back_inside_the_band() {
        let t = Descriptors::new(2, 1, vec![0.0, 0.0]).unwrap();
        // Target: 0 on the plane, 1 across it, 2 far out on the left (descriptor far away),
        // 3 on the left but nearer the plane than half the point's distance, 4 a thigh.
        let u = Descriptors::new(5, 1, vec![0.05, 0.06, 0.9, 0.07, 0.01]).unwrap();
        let ul = [Torso, Torso, Torso, Torso, ThighLeft];
        let us = [0.0, -0.8, 0.9, 0.3, 0.0];
        let c = |v: u32, d: f64| Candidate {
            vertex: v,
            distance: d,
        };
        // Point 0 at s = 0.8 on the left; point 1 on a thigh (the band ignores limbs).
        let mut cands = vec![
            vec![c(0, 0.05), c(1, 0.06), c(3, 0.07)],
            vec![c(4, 0.01), c(0, 0.05)],
        ];
        let s = sagittal_band(
            &mut cands,
            &[0, 1],
            (&[Torso, ThighLeft], &ul),
            (&[0.8, 0.0], &us),
            0.5,
            &t,
            &u,
        );
        // Nothing of point 0 survives (3 is at 0.3 < 0.5·0.8): the fallback is vertex 2, the
        // only torso vertex inside the band, even though its descriptor is far.
        assert_eq!(cands[0], vec![c(2, 0.9)]);
        assert_eq!(cands[1].len(), 2);
        assert_eq!(
            s,
            BandStats {
                points: 1,
                removed: 3,
                fallbacks: 1
            }
        );
        // With ratio 0 the same-side candidate 3 is enough.
        let mut cands = vec![vec![c(0, 0.05), c(1, 0.06), c(3, 0.07)]];
        sagittal_band(
            &mut cands,
            &[0],
            (&[Torso], &ul),
            (&[0.8], &us),
            0.0,
            &t,
            &u,
        );
        let got: Vec<u32> = cands[0].iter().map(|c| c.vertex).collect();
        assert_eq!(got, vec![0, 3]);
    }

    #[test]
    fn missing_segment_leaves_candidates() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(2, 1, vec![0.1, 0.2]).unwrap();
        let mut c = vec![vec![Candidate {
            vertex: 1,
            distance: 0.2,
        }]];
        let s = skeleton_filter(&mut c, &[0], (&[Head], &[Torso, Torso]), None, &t, &u);
        assert_eq!(s.segment_missing, 1);
        assert_eq!(c[0].len(), 1);
    }
}
