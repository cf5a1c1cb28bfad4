//! Does a joint log belong to a recording's depth frames? Checked on a few frames before a run
//! ([`check_log`]), so that a log of another recording or clock, or with axes other than the
//! depth camera's, is refused with its cause instead of tracked into plausible garbage.
//!
//! Each frame's own guards do not catch such a log. Its skeletons still lie near the body (a
//! mirrored log of a subject near the image's centre, a log a second off of a subject walking
//! in place), the attachment swaps sides or turns the skeleton to fit the scan, a frame's poor
//! skeleton fit is accepted (a correct log's can be poor in one frame: a profile view), and the
//! match pulls the template onto the view well enough to hold more than
//! [`MIN_VIEW_HELD`](crate::MIN_VIEW_HELD) of it — with 28–34 % of its matches flipped.
//! Across frames the skeletons tell: the points along a log's bones
//! ([`FitCheckKind::Outside`]: each joint and three points per bone) lie inside the body the
//! camera sees (its visual hull) when the log was recorded with the frames, and a fifth to a
//! third of them outside it when not (docs/decisions/2026-12-05-joint-log-check.md).
//!
//! Two plainer mismatches are named before that: a log with no frame near any depth frame's
//! time (stamped on another clock: every frame would be skipped, [`LogMismatch::Clocks`]), and
//! a log whose joints lie off the body in most sampled frames (another unit or camera: those
//! frames' scans would refuse them, [`LogMismatch::OffBody`]).

use super::TrackOptions;
use super::Tracker;
use crate::{Pipeline, PreparedMesh};
use symcorr_attach::{FitCheckKind, FitQuality};
use symcorr_kinect::scan::{
    depth_unit_hint, height_ratio, joints_on_depth, JointsOnDepth, MAX_HEIGHT_RATIO,
};
use symcorr_kinect::{DepthSource, JointTrack, SkipReason};

/// Frames [`check_log`] looks at by default, spread over the run.
pub const LOG_CHECK_FRAMES: usize = 8;

/// The largest median share of a sampled frame's bone points outside the body the camera sees
/// ([`FitCheckKind::Outside`]) a log passes with ([`LogCheck::verdict`]). On 14 recordings,
/// logs recorded with their frames measured at most 0.091 (a close view, the feet out of the
/// image; 0.104 for a log facing away, read turned); logs mirrored, half a second or a second
/// off, or of another recording at least 0.182: docs/decisions/2026-12-05-joint-log-check.md.
pub const MAX_LOG_OUTSIDE: f64 = 0.15;

/// Fewer frames with a skeleton fit than this give no verdict: each frame's own guards decide.
pub const MIN_LOG_CHECK_FITS: usize = 3;

/// A median [`height_ratio`] above this (up to [`MAX_HEIGHT_RATIO`], which refuses) passes the
/// log with a warning ([`LogCheck::warnings`]). Recordings read with their own camera's
/// intrinsics measured medians of 1.04–1.05 (eight synthetic recordings, 320×240 and 640×480,
/// 2.5–3.8 m; 1.00–1.09 on 14 recordings before); the fixture read with a focal length 10 % short (a
/// Kinect v1's colour camera's 525 px for its depth camera's 580) measured 1.12, and its
/// matches erred twice as far (mean error 0.0178 → 0.0365), every frame passing its own
/// checks. (docs/decisions/2026-12-06-focal-length-warning.md.)
pub const WARN_HEIGHT_RATIO: f64 = 1.10;

/// What a log that passes [`LogCheck::verdict`] may still do to every frame's matches
/// ([`LogCheck::warnings`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LogWarning {
    /// The frames' scans are taller than the log's skeletons along the spine, though not so
    /// much that the log is refused ([`LogMismatch::Scale`]).
    #[error(
        "the depth frames' scans are a median {median:.2}× as tall as the joint log's skeletons \
         along the spine on {frames} frames spread over the run (frames read with their own \
         camera's intrinsics measure 1.00–1.09×; a focal length 10 % short gives about 1.12×): \
         if fx {fx} px is not the depth camera's own (a colour camera's, another resolution's), \
         correct the intrinsics — a focal length 10 % short doubled the matches' error"
    )]
    TallScans {
        /// Sampled frames with a scan and a skeleton.
        frames: usize,
        /// Their median [`height_ratio`].
        median: f64,
        /// The focal length the frames were read with, pixels.
        fx: f64,
    },
}

/// The median of `v` (the mean of the middle two for an even count), `None` when empty.
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    match v.len() {
        0 => None,
        n if n % 2 == 1 => Some(v[m]),
        _ => Some(0.5 * (v[m - 1] + v[m])),
    }
}

/// The share of the bone points outside the body the camera sees, when the fit measured it.
fn outside(fit: &FitQuality) -> Option<f64> {
    Some(fit.check(FitCheckKind::Outside)?.value)
}

/// What the sampled frames of [`check_log`] showed.
#[derive(Debug, Clone, PartialEq)]
pub struct LogCheck {
    /// When no frame of the run has a joint log frame near its time, the two clocks; the
    /// frames are then not observed.
    pub clocks: Option<ClockGap>,
    /// Per sampled frame with a skeleton in the log, how its joints lie on the depth frame
    /// ([`joints_on_depth`]).
    pub on_depth: Vec<JointsOnDepth>,
    /// Per sampled frame, its index in the recording and how well the log's skeleton at its
    /// time sits in its scan — as logged or turned half a turn about its spine, whichever
    /// leaves fewer bone points outside — or why the frame has no skeleton fit (no log frame
    /// near its time, no body in the depth, joints the scan refuses, an unreadable frame).
    pub frames: Vec<(usize, Result<FitQuality, String>)>,
    /// Per sampled frame prepared, how tall its scan is against the skeleton along the spine
    /// ([`height_ratio`]).
    pub heights: Vec<f64>,
    /// The focal length the frames were read with, pixels (for the message).
    pub fx: f64,
}

/// A joint log refused by [`LogCheck::verdict`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LogMismatch {
    /// The log's skeletons stick out of the bodies the frames show.
    #[error(
        "the joint log does not fit the depth frames: on {fits} frames spread over the run a \
         median {median:.0} % of the points along its bones lie outside the body the camera \
         sees (at most {max:.0} % accepted; logs recorded with their frames measured 0–11 %). \
         The log may belong to another recording or clock (check the joint offset, or estimate \
         it from the frames), its axes may differ from the depth camera's (mirrored: a recording \
         folder whose depth is not mirrored as the Kinect SDK's needs \"mirrored\": false in its \
         intrinsics.json; another up axis), or the intrinsics may be another camera's",
        median = 100.0 * median_outside,
        max = 100.0 * MAX_LOG_OUTSIDE
    )]
    Outside {
        /// Frames with a skeleton fit.
        fits: usize,
        /// Their median share of bone points outside the visual hull.
        median_outside: f64,
    },
    /// No frame of the run has a log frame near its time.
    #[error("{0}")]
    Clocks(ClockGap),
    /// The frames' scans are much taller than the log's skeletons along the spine.
    #[error(
        "the depth frames' scans are a median {median:.2}× as tall as the joint log's skeletons \
         along the spine on {frames} frames spread over the run (at most {max:.2}× accepted; a \
         body's own joints measure 0.85–1.12×): the intrinsics' focal length (fx {fx}) may be \
         another camera's, or the log may be another subject's",
        max = MAX_HEIGHT_RATIO
    )]
    Scale {
        /// Sampled frames with a scan and a skeleton.
        frames: usize,
        /// Their median [`height_ratio`].
        median: f64,
        /// The focal length the frames were read with, pixels.
        fx: f64,
    },
    /// In most sampled frames the log's joints do not lie on the body the depth shows.
    #[error(
        "the joint log does not lie on the depth frames: in {off} of {frames} frames spread over \
         the run fewer than half of the joints project onto a surface within {tolerance} m of \
         their depth{hint}. The log may be in another unit, belong to another recording or \
         clock (check the joint offset), its axes may differ from the depth camera's \
         (mirrored: a recording folder whose depth is not mirrored as the Kinect SDK's needs \
         \"mirrored\": false in its intrinsics.json; another up axis), or the intrinsics may be \
         another camera's",
        tolerance = symcorr_kinect::scan::JOINT_DEPTH_TOLERANCE_M
    )]
    OffBody {
        /// Sampled frames with a skeleton.
        frames: usize,
        /// Of those, the frames whose joints do not lie on the body.
        off: usize,
        /// The unit mismatch the median depth ratio of those frames suggests
        /// ([`depth_unit_hint`]), or "".
        hint: String,
    },
}

/// The times of a run's depth frames and of a joint log that has no frame near any of them
/// (within [`MAX_GAP_PERIODS`](symcorr_kinect::recording::MAX_GAP_PERIODS) log periods): the
/// two were stamped on different clocks — another origin (a log stamped from the epoch or the
/// tracker's start), or another recording — or, when the two spans overlap, the log has a gap
/// over the run's frames.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub struct ClockGap {
    /// The first and last time of the run's depth frames, seconds.
    pub depth_s: [f64; 2],
    /// The first and last time of the joint log, seconds.
    pub log_s: [f64; 2],
    /// The joint offset the log was read with ([`TrackOptions::joint_offset_s`]).
    pub offset_s: f64,
}

impl std::fmt::Display for ClockGap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ([d0, d1], [l0, l1], o) = (self.depth_s, self.log_s, self.offset_s);
        write!(
            f,
            "no depth frame of the run has a joint log frame near its time: the frames run from \
             {d0:.3} to {d1:.3} s, read in the log at {:.3} to {:.3} s (joint offset {o} s), \
             and the log runs from {l0:.3} to {l1:.3} s",
            d0 + o,
            d1 + o
        )?;
        if (d0 + o).max(l0) <= (d1 + o).min(l1) {
            write!(
                f,
                "; the log has no frames over the run's (a gap in the log)"
            )
        } else {
            write!(
                f,
                "; the two are stamped on different clocks (another origin or another \
                 recording): a joint offset of {:.3} s would align their starts",
                l0 - d0
            )
        }
    }
}

impl LogCheck {
    /// Per sampled frame with a skeleton fit, the share of its bone points outside the body
    /// the camera sees ([`FitCheckKind::Outside`]).
    pub fn outside(&self) -> Vec<f64> {
        self.frames
            .iter()
            .filter_map(|(_, r)| outside(r.as_ref().ok()?))
            .collect()
    }

    /// The median of [`LogCheck::outside`] (the mean of the middle two for an even count);
    /// `None` without a skeleton fit.
    pub fn median_outside(&self) -> Option<f64> {
        median(self.outside())
    }

    /// Refuses the log when no frame of the run has a log frame near its time
    /// ([`LogMismatch::Clocks`]); when at least [`MIN_LOG_CHECK_FITS`] sampled frames have a
    /// skeleton and in more than half of them the joints do not lie on the body
    /// ([`LogMismatch::OffBody`]: another camera, another unit); or when at least
    /// [`MIN_LOG_CHECK_FITS`] frames have a skeleton fit and their median share of bone points
    /// outside the body the camera sees is above
    /// [`MAX_LOG_OUTSIDE`] ([`LogMismatch::Outside`]).
    pub fn verdict(&self) -> Result<(), LogMismatch> {
        if let Some(gap) = self.clocks {
            return Err(LogMismatch::Clocks(gap));
        }
        let frames = self.on_depth.len();
        let off = self.on_depth.iter().filter(|o| !o.lie_on_body()).count();
        if frames >= MIN_LOG_CHECK_FITS && 2 * off > frames {
            // The depths of the frames whose joints are off: those say why.
            let ratios: Vec<f64> = (self.on_depth.iter())
                .filter(|o| !o.lie_on_body())
                .filter_map(|o| o.depth_ratio)
                .collect();
            return Err(LogMismatch::OffBody {
                frames,
                off,
                hint: depth_unit_hint(median(ratios)),
            });
        }
        if let Some(m) = median(self.heights.clone()) {
            if self.heights.len() >= MIN_LOG_CHECK_FITS && m > MAX_HEIGHT_RATIO {
                return Err(LogMismatch::Scale {
                    frames: self.heights.len(),
                    median: m,
                    fx: self.fx,
                });
            }
        }
        let fits = self.outside().len();
        match self.median_outside() {
            Some(median) if fits >= MIN_LOG_CHECK_FITS && median > MAX_LOG_OUTSIDE => {
                Err(LogMismatch::Outside {
                    fits,
                    median_outside: median,
                })
            }
            _ => Ok(()),
        }
    }
}

impl LogCheck {
    /// What the check noticed in a log it passes ([`LogCheck::verdict`]) that may make every
    /// frame's matches worse: scans a median more than [`WARN_HEIGHT_RATIO`] times as tall as
    /// their skeletons on at least [`MIN_LOG_CHECK_FITS`] frames ([`LogWarning::TallScans`]: a
    /// focal length too short for the image). Empty when the check refuses the log.
    ///
    /// ```
    /// use symcorr::track::log_check::{LogCheck, LogWarning};
    /// let mut check = LogCheck {
    ///     clocks: None,
    ///     on_depth: Vec::new(),
    ///     frames: Vec::new(),
    ///     heights: vec![1.11, 1.13, 1.12],
    ///     fx: 525.0,
    /// };
    /// assert!(matches!(check.warnings()[..], [LogWarning::TallScans { frames: 3, .. }]));
    /// check.heights = vec![1.04, 1.05, 1.03];
    /// assert!(check.warnings().is_empty());
    /// ```
    pub fn warnings(&self) -> Vec<LogWarning> {
        if self.verdict().is_err() || self.heights.len() < MIN_LOG_CHECK_FITS {
            return Vec::new();
        }
        match median(self.heights.clone()) {
            Some(median) if median > WARN_HEIGHT_RATIO => vec![LogWarning::TallScans {
                frames: self.heights.len(),
                median,
                fx: self.fx,
            }],
            _ => Vec::new(),
        }
    }
}

/// Looks for a log frame near each of `frames`' times (indices into `source`); when there is
/// none for any, records the two clocks ([`LogCheck::clocks`]) and stops. Otherwise takes
/// `samples` frames of `frames` (spread evenly over the list) and records for each how the
/// log's joints at its time lie on its depth ([`LogCheck::on_depth`]) and, observed on its own
/// — a [`Tracker`]'s observer reset before each frame, so no frame borrows from another; its
/// scan prepared, without the search index a match needs — how well the log's skeleton sits
/// in its scan. Nothing is matched or written. [`LogCheck::verdict`] judges the log.
pub fn check_log(
    pipeline: &Pipeline,
    template: &PreparedMesh,
    source: &mut DepthSource,
    joints: &JointTrack,
    options: &TrackOptions,
    frames: &[usize],
    samples: usize,
) -> LogCheck {
    let times: Vec<f64> = frames.iter().filter_map(|&i| source.time(i)).collect();
    // No frames, no clocks to compare.
    let covered = times.is_empty()
        || times.iter().any(|t| {
            !matches!(
                joints.at(t + options.joint_offset_s),
                Err(SkipReason::NoSkeleton { .. })
            )
        });
    let log = &joints.log().frames;
    if let (false, Some(first), Some(last)) = (covered, log.first(), log.last()) {
        let (lo, hi) = times
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        return LogCheck {
            clocks: Some(ClockGap {
                depth_s: [lo, hi],
                log_s: [first.time_s, last.time_s],
                offset_s: options.joint_offset_s,
            }),
            on_depth: Vec::new(),
            frames: Vec::new(),
            heights: Vec::new(),
            fx: source.intrinsics().fx,
        };
    }
    let k = samples.min(frames.len());
    // One tracker, forgotten before each frame: the template's tables are built once.
    let mut tracker = Tracker::new(
        pipeline,
        template,
        *source.intrinsics(),
        joints.clone(),
        options.clone(),
    );
    let intrinsics = *source.intrinsics();
    let mut on_depth = Vec::new();
    let mut heights = Vec::new();
    let frames = (0..k)
        .map(|i| frames[(2 * i + 1) * frames.len() / (2 * k)])
        .map(|index| {
            let time_s = source.time(index).unwrap_or(f64::NAN);
            let fit = source
                .frame(index)
                .map_err(|e| e.to_string())
                .and_then(|depth| {
                    if let Ok(at) = joints.at(time_s + options.joint_offset_s) {
                        on_depth.push(joints_on_depth(&depth, &intrinsics, &at.skeleton));
                    }
                    tracker.reset();
                    let (observer, _) = tracker.parts();
                    let target = observer.prepared(time_s, &depth)?;
                    heights.extend(height_ratio(&target.mesh, &target.attachment.joints));
                    let given = target.attachment.diagnostics.fit.clone();
                    // A skeleton logged facing away from the camera is one the tracker turns back
                    // (module `track`, step 5): its turned reading is judged too.
                    if outside(&given).is_none_or(|o| o <= MAX_LOG_OUTSIDE) {
                        return Ok(given);
                    }
                    let turned = observer
                        .pipeline
                        .prepare_turned(&target)
                        .map(|t| t.attachment.diagnostics.fit);
                    Ok(match turned {
                        Some(t) if outside(&t) < outside(&given) => t,
                        _ => given,
                    })
                });
            (index, fit)
        })
        .collect();
    LogCheck {
        clocks: None,
        on_depth,
        frames,
        heights,
        fx: intrinsics.fx,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_attach::FitCheck;

    fn fit(outside: Option<f64>) -> FitQuality {
        FitQuality {
            score: 0.8,
            checks: outside
                .map(|value| FitCheck {
                    kind: FitCheckKind::Outside,
                    value,
                    limit: FitCheckKind::Outside.limit(),
                    passed: value <= FitCheckKind::Outside.limit(),
                })
                .into_iter()
                .collect(),
            unreached: Vec::new(),
            accepted_poor_fit: false,
        }
    }

    fn check(frames: &[Option<f64>]) -> LogCheck {
        LogCheck {
            clocks: None,
            on_depth: Vec::new(),
            frames: frames
                .iter()
                .enumerate()
                .map(|(i, &o)| (i, Ok(fit(o))))
                .collect(),
            heights: Vec::new(),
            fx: 571.26,
        }
    }

    #[test]
    fn scans_much_taller_than_the_skeletons_are_refused_by_the_median() {
        let mut c = check(&[Some(0.0), Some(0.0), Some(0.0)]);
        c.heights = vec![1.05, 2.1, 1.08];
        assert!(c.verdict().is_ok(), "one odd frame does not refuse a log");
        c.heights = vec![1.9, 2.1, 1.08];
        let e = c.verdict().unwrap_err();
        assert!(matches!(e, LogMismatch::Scale { frames: 3, .. }), "{e:?}");
        assert!(e.to_string().contains("focal length (fx 571.26)"), "{e}");
        c.heights.truncate(2);
        assert!(c.verdict().is_ok(), "two frames are too few");
    }

    #[test]
    fn scans_a_little_too_tall_pass_with_a_warning_naming_the_focal_length() {
        let mut c = check(&[Some(0.0), Some(0.0), Some(0.0)]);
        c.heights = vec![1.04, 1.05, 1.09];
        assert!(c.verdict().is_ok() && c.warnings().is_empty());
        c.heights = vec![1.12, 1.11, 1.3];
        assert!(c.verdict().is_ok());
        let w = c.warnings();
        assert!(
            matches!(w[..], [LogWarning::TallScans { frames: 3, median, .. }] if median == 1.12),
            "{w:?}"
        );
        assert!(w[0].to_string().contains("fx 571.26 px"), "{}", w[0]);
        // Too few frames say nothing; a refused log is refused, not warned about.
        c.heights.truncate(2);
        assert!(c.warnings().is_empty());
        c.heights = vec![1.3, 1.4, 1.12];
        assert!(c.verdict().is_err() && c.warnings().is_empty());
    }

    #[test]
    fn the_median_frame_decides_and_too_few_frames_give_no_verdict() {
        // One frame of a correct log far outside (a poor frame) does not refuse it.
        assert!(check(&[Some(0.0), Some(0.05), Some(0.4), Some(0.02)])
            .verdict()
            .is_ok());
        let refused = check(&[Some(0.3), Some(0.25), Some(0.0), Some(0.29)])
            .verdict()
            .unwrap_err();
        let LogMismatch::Outside {
            fits,
            median_outside,
        } = refused
        else {
            panic!("{refused:?}")
        };
        assert_eq!(fits, 4);
        assert!((median_outside - 0.27).abs() < 1e-12);
        assert!(refused.to_string().contains("a median 27 %"));
        // Two fits are too few; frames without the check (or skipped) do not count.
        assert!(check(&[Some(0.3), Some(0.3), None]).verdict().is_ok());
        let mut skipped = check(&[Some(0.3), Some(0.3)]);
        skipped.frames.push((2, Err("no body".into())));
        assert!(skipped.verdict().is_ok());
        assert_eq!(check(&[]).median_outside(), None);
    }

    #[test]
    fn a_clock_gap_names_both_spans_and_the_offset_that_aligns_them() {
        let epoch = ClockGap {
            depth_s: [0.5, 2.5],
            log_s: [1.7e9, 1.7e9 + 2.0],
            offset_s: -0.04,
        };
        let msg = epoch.to_string();
        let read = "read in the log at 0.460 to 2.460 s (joint offset -0.04 s)";
        assert!(msg.contains(read), "{msg}");
        assert!(msg.contains("different clocks"), "{msg}");
        assert!(msg.contains("a joint offset of 1699999999.500 s"), "{msg}");
        // Spans that overlap: a gap in the log over the run's frames, not another clock.
        let gap = ClockGap {
            log_s: [-1.0, 10.0],
            ..epoch
        };
        let msg = gap.to_string();
        assert!(
            msg.contains("a gap in the log") && !msg.contains("clocks"),
            "{msg}"
        );
    }

    #[test]
    fn joints_off_the_body_in_most_frames_refuse_the_log_naming_the_unit() {
        let on = |on_body: usize, depth_ratio: f64| JointsOnDepth {
            usable: 20,
            on_body,
            depth_ratio: Some(depth_ratio),
        };
        // Three of four frames off the body, their depth readings about 10× the joints' depth:
        // a depth image in tenths of millimetres. Refused before the bone points are judged.
        let mut c = check(&[Some(0.3), Some(0.3), Some(0.3)]);
        c.on_depth = vec![on(0, 9.8), on(20, 1.0), on(1, 10.1), on(0, 10.0)];
        let e = c.verdict().unwrap_err();
        assert!(
            matches!(
                e,
                LogMismatch::OffBody {
                    frames: 4,
                    off: 3,
                    ..
                }
            ),
            "{e:?}"
        );
        assert!(e.to_string().contains("a median 10.000×"), "{e}");
        // Half of them off is not most, two frames are too few to judge: the bone points
        // decide (here 30 % outside: refused as such).
        for on_depth in [
            vec![on(0, 9.8), on(20, 1.0), on(20, 1.0), on(0, 10.0)],
            vec![on(0, 9.8), on(0, 10.0)],
        ] {
            c.on_depth = on_depth;
            assert!(matches!(c.verdict(), Err(LogMismatch::Outside { .. })));
        }
        // Off the body at the right depth (another recording) names no unit.
        c.on_depth = vec![on(0, 1.1); 3];
        let e = c.verdict().unwrap_err().to_string();
        assert!(
            !e.contains("median") && e.contains("another recording"),
            "{e}"
        );
    }
}
