//! The offset between a joint log's clock and the depth frames' clock, estimated from the
//! frames themselves ([`estimate_joint_offset`]).
//!
//! A skeleton tracker and a depth recorder stamp their frames with different clocks; a
//! recording's log is read at `depth time + offset` ([`JointTrack`]). A wrong offset puts a
//! swinging foot or hand where it was a few frames earlier or later: on the synthetic fixture
//! recording (its log 40 ms ahead), tracking with an offset of 0 instead of 0.04 s doubled the
//! matches that jump between frames (0.44 → 0.96 %).
//!
//! Where the offset is right, every tracked joint lies inside the body the depth camera sees —
//! behind the surface at its pixel, never in front of it. A joint read at the wrong time leaves
//! the body's silhouette or comes out in front of the limb it belongs to, and then lies in front
//! of whatever surface the camera saw at its pixel (the limb, the wall behind the body). The
//! estimate is the candidate offset whose joints lie least in front of the surface, on average
//! over the tracked joints of frames spread over the recording: a visual-hull test in the depth
//! image, without meshing. Measured on 14 synthetic recordings (log 40 ms ahead): estimates
//! 0.02–0.07 s, and a log shifted by half a second or a second is found shifted by as much
//! (docs/decisions/2026-12-05-joint-offset-estimate.md).

use crate::{DepthFrame, DepthSource, Intrinsics, JointTrack, KinectError};

/// How an offset is searched ([`estimate_joint_offset`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetSearch {
    /// The smallest and largest offset tried, seconds.
    pub range_s: (f64, f64),
    /// The step between offsets tried, seconds.
    pub step_s: f64,
    /// How far in front of the observed surface a joint may lie before it counts (metres): the
    /// sensor's noise and a tracker's wrists and ankles at the skin.
    pub margin_m: f64,
    /// The most one joint adds (metres): a joint in front of the far wall counts no more than
    /// one just off the body.
    pub cap_m: f64,
    /// An offset is a candidate only where the log covers at least this share of the joint
    /// lookups of the offset that covers most: an offset that reads the log only at its ends
    /// is not judged on a few frames.
    pub min_coverage: f64,
}

impl Default for OffsetSearch {
    /// ±2 s in steps of 10 ms (a third of a frame at 30 fps), margin 3 cm, cap 30 cm, coverage
    /// 0.8.
    fn default() -> Self {
        OffsetSearch {
            range_s: (-2.0, 2.0),
            step_s: 0.01,
            margin_m: 0.03,
            cap_m: 0.3,
            min_coverage: 0.8,
        }
    }
}

/// The result of [`estimate_joint_offset`].
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetEstimate {
    /// The estimated offset: the log is read at `depth time + offset_s`.
    pub offset_s: f64,
    /// Its score: the mean distance (metres, capped) by which the tracked joints lie in front
    /// of the observed surface.
    pub score_m: f64,
    /// Per offset tried: the offset, its score and the joint lookups it scored (an offset
    /// whose log covers no frame has `NaN`).
    pub curve: Vec<(f64, f64, usize)>,
}

/// Estimates the offset of `track`'s log clock against the depth clock from `frames` (each a
/// depth frame and its time on the depth clock, seen through `intrinsics`): per offset of
/// `search`, the mean over the frames' tracked joints (confidence > 0) that project into the
/// image of how far each lies in front of the surface the camera saw at its pixel, beyond
/// `margin_m`, capped at `cap_m` (a pixel without a reading adds nothing). Among the offsets
/// whose log covers at least `min_coverage` of the most lookups, the least mean wins; where a
/// run of neighbouring offsets shares it (a slow motion), the middle of the run (of the run
/// nearest 0, if several). The log is read at `time + offset` whatever `track`'s own offset.
/// `None` when no offset's log covers any joint lookup, or `search` is empty or asks for more
/// than [`MAX_OFFSETS`] offsets.
///
/// ```
/// use nalgebra::{Point3, Vector3};
/// use symcorr_kinect::clock::{estimate_joint_offset, OffsetSearch};
/// use symcorr_kinect::{DepthFrame, Intrinsics, JointLog, JointTrack, Mirroring};
/// use symcorr_skeleton::Skeleton;
/// // A hand swinging left and right in front of a wall 3 m away.
/// let cam = Intrinsics {
///     width: 64, height: 48, fx: 60.0, fy: 60.0, cx: 32.0, cy: 24.0,
///     mirroring: Mirroring::Mirrored,
///     distortion: None,
/// };
/// let hand = |t: f64| Point3::new(0.5 * (2.0 * t).sin(), 0.0, 2.0);
/// let frame = |t: f64| {
///     let mut mm = vec![3000u16; 64 * 48];
///     let [u, v] = cam.project(&hand(t));
///     for y in v.round() as usize - 3..=v.round() as usize + 3 {
///         for x in u.round() as usize - 3..=u.round() as usize + 3 {
///             mm[y * 64 + x] = 2000; // the hand, 7 px wide
///         }
///     }
///     DepthFrame::new(64, 48, mm).unwrap()
/// };
/// // The log's clock reads 0.1 s more: its frame stamped t holds the hand at t − 0.1, its
/// // joint 2 cm inside the hand.
/// let at = |t: f64| Skeleton::from_positions([hand(t - 0.1) + Vector3::z() * 0.02; 20]);
/// let log = JointLog::from_skeletons((0..90).map(|k| at(k as f64 / 30.0)).collect(), 30.0);
/// let track = JointTrack::new(log, 0.0).unwrap();
/// let frames: Vec<(f64, DepthFrame)> =
///     (0..20).map(|k| 0.5 + 0.1 * k as f64).map(|t| (t, frame(t))).collect();
/// let search = OffsetSearch { range_s: (-0.5, 0.5), ..OffsetSearch::default() };
/// let estimate = estimate_joint_offset(&frames, &cam, &track, &search).unwrap();
/// assert!((estimate.offset_s - 0.1).abs() < 0.02, "{}", estimate.offset_s);
/// ```
pub fn estimate_joint_offset(
    frames: &[(f64, DepthFrame)],
    intrinsics: &Intrinsics,
    track: &JointTrack,
    search: &OffsetSearch,
) -> Option<OffsetEstimate> {
    let (lo, hi) = search.range_s;
    if !(search.step_s > 0.0 && lo.is_finite() && hi.is_finite() && lo <= hi) {
        return None;
    }
    let steps = ((hi - lo) / search.step_s + 1e-9).floor();
    if steps > MAX_OFFSETS as f64 {
        return None;
    }
    let steps = steps as usize;
    let curve: Vec<(f64, f64, usize)> = (0..=steps)
        .map(|k| {
            // Rounded to the nanosecond: `lo + k·step` in binary is a hair off the decimal
            // steps a user reads (0.049999999999999822 for 0.05).
            let offset = nanoseconds(lo + k as f64 * search.step_s);
            let (sum, n) = in_front(frames, intrinsics, track, offset, search);
            (offset, if n > 0 { sum / n as f64 } else { f64::NAN }, n)
        })
        .collect();
    let most = curve.iter().map(|c| c.2).max().unwrap_or(0);
    if most == 0 {
        return None;
    }
    let candidate = |c: &(f64, f64, usize)| c.2 as f64 >= search.min_coverage * most as f64;
    let score_m = curve
        .iter()
        .filter(|c| candidate(c))
        .map(|c| c.1)
        .fold(f64::INFINITY, f64::min);
    // The offsets that reach the least score form runs (a slow motion leaves every joint
    // inside the body over a range of offsets): the run nearest 0, and its middle.
    let best = |c: &(f64, f64, usize)| candidate(c) && c.1 <= score_m;
    let start = (0..curve.len())
        .filter(|&k| best(&curve[k]))
        .min_by(|&a, &b| curve[a].0.abs().total_cmp(&curve[b].0.abs()))?;
    let mut first = start;
    while first > 0 && best(&curve[first - 1]) {
        first -= 1;
    }
    let mut last = start;
    while last + 1 < curve.len() && best(&curve[last + 1]) {
        last += 1;
    }
    let offset_s = nanoseconds(0.5 * (curve[first].0 + curve[last].0));
    Some(OffsetEstimate {
        offset_s,
        score_m,
        curve,
    })
}

/// The most offsets one search tries ([`estimate_joint_offset`] gives `None` beyond: ±2 s in
/// steps of 10 ms are 401).
pub const MAX_OFFSETS: usize = 100_000;

/// Frames [`estimate_recording_offset`] reads by default, spread over the recording.
pub const OFFSET_FRAMES: usize = 30;

/// [`estimate_joint_offset`] on `frames` depth frames spread evenly over the whole of `source`
/// (a frame that cannot be read, or has no time, is left out): the same estimate for every
/// slice of a recording, so that slices tracked apart are one run.
///
/// Errors: [`KinectError::Track`] when there is no estimate (no offset of `search` reads a
/// tracked joint of the log on these frames, or `search` is empty or too long).
pub fn estimate_recording_offset(
    source: &mut DepthSource,
    track: &JointTrack,
    frames: usize,
    search: &OffsetSearch,
) -> Result<OffsetEstimate, KinectError> {
    let (n, k) = (source.len(), frames.min(source.len()));
    let sample: Vec<(f64, DepthFrame)> = (0..k)
        .map(|i| (2 * i + 1) * n / (2 * k))
        .filter_map(|i| Some((source.time(i)?, source.frame(i).ok()?)))
        .collect();
    estimate_joint_offset(&sample, source.intrinsics(), track, search).ok_or_else(|| {
        KinectError::Track(format!(
            "no offset within {}..{} s reads a tracked joint of the log on the recording's \
             frames (the log and the recording share no time)",
            search.range_s.0, search.range_s.1
        ))
    })
}

/// A joint offset as a user gives it: seconds, or estimated from the recording
/// ([`JointOffset::resolve`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointOffset {
    /// This many seconds: the log is read at `depth time + seconds`.
    Seconds(f64),
    /// Estimated by [`estimate_recording_offset`] on [`OFFSET_FRAMES`] frames with the default
    /// [`OffsetSearch`].
    Auto,
}

impl JointOffset {
    /// The offset in seconds: as given, or estimated on frames spread over the whole of
    /// `source` (the same estimate for every slice of a recording, so that slices merge).
    ///
    /// Errors: those of [`estimate_recording_offset`].
    pub fn resolve(self, source: &mut DepthSource, track: &JointTrack) -> Result<f64, KinectError> {
        match self {
            JointOffset::Seconds(s) => Ok(s),
            JointOffset::Auto => {
                estimate_recording_offset(source, track, OFFSET_FRAMES, &OffsetSearch::default())
                    .map(|e| e.offset_s)
            }
        }
    }
}

/// `t` rounded to the nanosecond.
fn nanoseconds(t: f64) -> f64 {
    (t * 1e9).round() / 1e9
}

/// The summed in-front distance of the tracked joints of `frames` read at `time + offset`,
/// and how many joint lookups it sums.
fn in_front(
    frames: &[(f64, DepthFrame)],
    intrinsics: &Intrinsics,
    track: &JointTrack,
    offset: f64,
    search: &OffsetSearch,
) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0usize);
    for (time, depth) in frames {
        let Ok(timed) = track.at(time + offset - track.offset_s()) else {
            continue;
        };
        let s = &timed.skeleton;
        for (p, &c) in s.positions.iter().zip(&s.confidence) {
            if !(c > 0.0 && p.z > 0.0) {
                continue;
            }
            let [u, v] = intrinsics.project(p);
            let (u, v) = (u.round(), v.round());
            if !(u >= 0.0 && v >= 0.0) {
                continue;
            }
            let Some(mm) = depth.at(u as u32, v as u32) else {
                continue;
            };
            n += 1;
            if mm > 0 {
                let ahead = f64::from(mm) / 1000.0 - p.z - search.margin_m;
                sum += ahead.clamp(0.0, search.cap_m);
            }
        }
    }
    (sum, n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::JointLog;
    use nalgebra::Point3;
    use symcorr_skeleton::Skeleton;

    const CAM: Intrinsics = Intrinsics {
        width: 80,
        height: 60,
        fx: 70.0,
        fy: 70.0,
        cx: 40.0,
        cy: 30.0,
        mirroring: crate::Mirroring::Mirrored,
        distortion: None,
    };

    /// Two hands swinging at different rates in front of a wall 3.5 m away, a torso between them;
    /// joints sit 2 cm behind the surface they belong to.
    fn body(t: f64) -> [Point3<f64>; 20] {
        let mut p = [Point3::new(0.0, 0.0, 2.52); 20];
        p[0] = Point3::new(0.6 * (1.7 * t).sin(), 0.2, 2.02);
        p[1] = Point3::new(-0.6 * (1.3 * t).cos(), -0.3, 2.22);
        p
    }

    fn frame(t: f64) -> DepthFrame {
        let mut mm = vec![3500u16; 80 * 60];
        let mut paint = |c: Point3<f64>, half: i64| {
            let [u, v] = CAM.project(&c);
            for dv in -half..=half {
                for du in -half..=half {
                    let (x, y) = (u.round() as i64 + du, v.round() as i64 + dv);
                    if (0..80).contains(&x) && (0..60).contains(&y) {
                        let i = (y * 80 + x) as usize;
                        let z = ((c.z - 0.02) * 1000.0) as u16;
                        mm[i] = mm[i].min(z);
                    }
                }
            }
        };
        let p = body(t);
        paint(p[2], 6);
        paint(p[0], 2);
        paint(p[1], 2);
        DepthFrame::new(80, 60, mm).unwrap()
    }

    /// A log whose clock reads `log_ahead_s` more than the depth frames' clock.
    fn track(log_ahead_s: f64, confidence: f64) -> JointTrack {
        let skeletons = (0..300)
            .map(|k| {
                let mut s = Skeleton::from_positions(body(k as f64 / 30.0 - log_ahead_s));
                s.confidence = [confidence; 20];
                s
            })
            .collect();
        JointTrack::new(JointLog::from_skeletons(skeletons, 30.0), 0.0).unwrap()
    }

    fn frames() -> Vec<(f64, DepthFrame)> {
        (0..30)
            .map(|k| {
                let t = 2.0 + 0.21 * k as f64;
                (t, frame(t))
            })
            .collect()
    }

    #[test]
    fn the_offset_the_log_was_made_with_is_found() {
        let search = OffsetSearch::default();
        for ahead in [-0.7, -0.05, 0.0, 0.04, 0.33, 1.2] {
            // The log's frame k (stamped k/30 s) holds the body at depth time k/30 − ahead.
            let e = estimate_joint_offset(&frames(), &CAM, &track(ahead, 1.0), &search).unwrap();
            assert!(
                (e.offset_s - ahead).abs() <= 0.02,
                "log {ahead} s ahead: estimated {} s",
                e.offset_s
            );
            assert!(e.score_m < 0.01, "{}", e.score_m);
        }
    }

    #[test]
    fn the_track_s_own_offset_does_not_change_the_estimate() {
        let log = track(0.2, 1.0);
        let shifted = JointTrack::new(log.log().clone(), 0.5).unwrap();
        let search = OffsetSearch::default();
        let a = estimate_joint_offset(&frames(), &CAM, &log, &search).unwrap();
        let b = estimate_joint_offset(&frames(), &CAM, &shifted, &search).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn nothing_to_judge_gives_no_estimate() {
        let search = OffsetSearch::default();
        // Untracked joints only.
        assert_eq!(
            estimate_joint_offset(&frames(), &CAM, &track(0.0, 0.0), &search),
            None
        );
        // No frames; a log far from every frame's time; a bad search.
        assert_eq!(
            estimate_joint_offset(&[], &CAM, &track(0.0, 1.0), &search),
            None
        );
        let late: Vec<(f64, DepthFrame)> = vec![(100.0, frame(0.0))];
        assert_eq!(
            estimate_joint_offset(&late, &CAM, &track(0.0, 1.0), &search),
            None
        );
        for step_s in [0.0, f64::NAN, 1e-9] {
            let bad = OffsetSearch { step_s, ..search };
            assert_eq!(
                estimate_joint_offset(&frames(), &CAM, &track(0.0, 1.0), &bad),
                None
            );
        }
    }
}
