//! Skeleton filter (paper §3.2): a candidate on a different body segment than the template
//! point is dropped — this is what keeps a left limb from matching a right one.

use crate::{Candidate, Descriptors};
use symcorr_attach::Segment;

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
    /// by descriptor was used instead (the issue's fallback).
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
/// `-1`/`+1` for a vertex clearly on the subject's right/left of the skeleton's sagittal plane,
/// `0` near the plane (or on a limb). A candidate whose half is the opposite non-zero value of
/// the point's is dropped too.
///
/// If no candidate survives, the list becomes the single target vertex of the same segment
/// whose descriptor is nearest (counted in [`FilterStats::fallbacks`]). If the target has no
/// vertex of that segment, the filter falls back to sides: candidates on a segment of the
/// opposite side are dropped ([`FilterStats::segment_missing`]).
///
/// ```
/// use symcorr_attach::Segment::{ThighLeft, ThighRight};
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
    halves: Option<(&[i8], &[i8])>,
    template: &Descriptors,
    target: &Descriptors,
) -> FilterStats {
    // Segments present on the target.
    let mut present = [false; 17];
    for s in target_labels {
        present[s.index()] = true;
    }
    let compatible = |p: u32, q: u32| -> bool {
        let (sp, sq) = (template_labels[p as usize], target_labels[q as usize]);
        let same = if present[sp.index()] {
            sq == sp
        } else {
            side(sp) * side(sq) >= 0
        };
        same && halves.is_none_or(|(hp, hq)| hp[p as usize] * hq[q as usize] >= 0)
    };
    assert_eq!(cands.len(), points.len(), "one candidate list per point");
    // Target vertices per segment, for the fallback search.
    let mut by_segment: Vec<Vec<u32>> = vec![Vec::new(); 17];
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

/// `+1` for a segment on the subject's left, `-1` on the right, `0` on the midline.
fn side(s: Segment) -> i8 {
    if s.mirror() == s {
        0
    } else if s.name().ends_with("_left") {
        1
    } else {
        -1
    }
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
        let hu = [-1i8, 0, 1];
        let s = skeleton_filter(
            &mut c,
            &[0],
            (&[Torso], &[Torso; 3]),
            Some((&[1], &hu)),
            &t,
            &u,
        );
        assert_eq!(s.removed, 1);
        let got: Vec<u32> = c[0].iter().map(|c| c.vertex).collect();
        assert_eq!(got, vec![1, 2]);
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
