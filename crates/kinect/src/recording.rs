//! Recordings, the reading side: a recording folder of depth frames with their times
//! ([`Recording`]), the joints of a joint log at a depth frame's time ([`JointTrack`]), temporal
//! smoothing of joints ([`OneEuroFilter`], [`SkeletonFilter`]) and the evidence that a tracker
//! exchanged left and right between two frames ([`swap_evidence`]).
//!
//! # The recording folder
//!
//! ```text
//! intrinsics.json        symcorr.intrinsics/1 (Intrinsics::read)
//! depth/000000.png       PNG-16, depth in millimetres, 0 = no reading
//! depth/000001.png       six-digit frame numbers from 0, no gap
//! ...
//! depth_times.txt        one line per depth frame: its time in seconds
//! ```
//!
//! Other files are allowed and ignored (a `.png` in `depth/` whose name is all digits but not
//! six of them is refused: it is a mis-numbered frame). [`Recording::open`] checks the layout
//! up front (intrinsics, contiguous frame files, one finite and strictly increasing time per
//! frame, the first frame's size against the intrinsics from its PNG header) without decoding
//! any image; [`Recording::frame`] decodes one frame on demand and checks its size too. The two
//! text files are parsed in memory by [`Intrinsics::from_json_str`] and [`parse_depth_times`].
//! A recording holds its intrinsics and one `f64` per frame (its time), never the depth images.
//!
//! ```
//! use symcorr_kinect::{write_depth_png16, DepthFrame, Intrinsics, Mirroring, Recording};
//! let dir = tempfile::tempdir().unwrap();
//! let k = Intrinsics {
//!     width: 4, height: 3, fx: 5.0, fy: 5.0, cx: 1.5, cy: 1.0,
//!     mirroring: Mirroring::Mirrored,
//!     distortion: None,
//! };
//! k.write(dir.path().join("intrinsics.json")).unwrap();
//! std::fs::create_dir(dir.path().join("depth")).unwrap();
//! for i in 0..2 {
//!     let frame = DepthFrame::new(4, 3, vec![2000 + i; 12]).unwrap();
//!     write_depth_png16(dir.path().join(format!("depth/{i:06}.png")), &frame).unwrap();
//! }
//! std::fs::write(dir.path().join("depth_times.txt"), "0.0\n0.0333\n").unwrap();
//!
//! let rec = Recording::open(dir.path()).unwrap();
//! assert_eq!(rec.len(), 2);
//! assert_eq!(rec.time(1), Some(0.0333));
//! assert_eq!(rec.frame(1).unwrap().at(0, 0), Some(2001));
//! ```

use crate::camera::Intrinsics;
use crate::depth::{png_size, read_depth_png16, DepthFrame};
use crate::error::KinectError;
use crate::geom::median;
use crate::joints::{JointFrame, JointLog, KINECT_FPS};
use nalgebra::{Point3, Vector3};
use std::path::{Path, PathBuf};
pub use symcorr_skeleton::LimbPair;
use symcorr_skeleton::{Joint, Skeleton};

/// The intrinsics file of a recording folder.
pub const INTRINSICS_FILE: &str = "intrinsics.json";

/// The folder of depth frames in a recording folder.
pub const DEPTH_DIR: &str = "depth";

/// The frame times file of a recording folder.
pub const DEPTH_TIMES_FILE: &str = "depth_times.txt";

/// Digits of a depth frame's file name (`000000.png`).
pub const FRAME_DIGITS: usize = 6;

/// A recording folder (see the [module docs](self)), opened and checked; depth frames are read
/// on demand by [`Recording::frame`].
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    dir: PathBuf,
    pub(crate) intrinsics: Intrinsics,
    times_s: Vec<f64>,
}

/// The name of depth frame `i`'s file in `depth/`.
fn frame_file_name(i: usize) -> String {
    format!("{i:0width$}.png", width = FRAME_DIGITS)
}

impl Recording {
    /// Opens a recording folder and checks its layout: `intrinsics.json` is valid
    /// ([`Intrinsics::read`]); `depth/` holds `000000.png`, `000001.png`, … with no gap;
    /// `depth_times.txt` has one time per frame, each finite and later than the one before,
    /// the median interval between them within [`FRAME_PERIODS_S`]. No PNG is decoded.
    ///
    /// Errors: [`KinectError::Io`] (a missing file or folder, named); [`KinectError::Json`] for
    /// the intrinsics; [`KinectError::Recording`] naming the folder or file (no frames, a missing
    /// frame number, a mis-numbered frame file, as many times as frames, times not in
    /// seconds, a first frame of another size than the intrinsics); [`KinectError::Parse`]
    /// naming `depth_times.txt` and the line (not a number, not finite, not increasing).
    ///
    /// ```
    /// use symcorr_kinect::{Intrinsics, KinectError, Recording};
    /// let dir = tempfile::tempdir().unwrap();
    /// Intrinsics::kinect_v1().write(dir.path().join("intrinsics.json")).unwrap();
    /// std::fs::create_dir(dir.path().join("depth")).unwrap();
    /// let e = Recording::open(dir.path()).unwrap_err();
    /// assert!(matches!(e, KinectError::Recording { .. }));
    /// assert!(e.to_string().ends_with("depth: no depth frames (expected 000000.png, 000001.png, …)"));
    /// ```
    pub fn open(dir: impl AsRef<Path>) -> Result<Recording, KinectError> {
        let dir = dir.as_ref().to_path_buf();
        let intrinsics = Intrinsics::read(dir.join(INTRINSICS_FILE))?;
        let count = count_frames(&dir.join(DEPTH_DIR))?;
        let times_s = read_times(&dir.join(DEPTH_TIMES_FILE), count)?;
        check_first_frame_size(&dir.join(DEPTH_DIR).join(frame_file_name(0)), &intrinsics)?;
        Ok(Recording {
            dir,
            intrinsics,
            times_s,
        })
    }

    /// The number of depth frames (at least 1).
    pub fn len(&self) -> usize {
        self.times_s.len()
    }

    /// Always `false`: a recording has at least one frame ([`Recording::open`] refuses none).
    pub fn is_empty(&self) -> bool {
        self.times_s.is_empty()
    }

    /// The folder the recording was opened from.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The depth camera's intrinsics (`intrinsics.json`).
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// The time of frame `i` in seconds (`depth_times.txt`), `None` past the last frame.
    pub fn time(&self, i: usize) -> Option<f64> {
        self.times_s.get(i).copied()
    }

    /// Every frame's time in seconds, strictly increasing.
    pub fn times(&self) -> &[f64] {
        &self.times_s
    }

    /// The path of frame `i`'s PNG (whether or not `i` is in range).
    pub fn frame_path(&self, i: usize) -> PathBuf {
        self.dir.join(DEPTH_DIR).join(frame_file_name(i))
    }

    /// Reads and decodes depth frame `i` and checks that its size is the intrinsics' size.
    ///
    /// Errors: [`KinectError::Recording`] for `i` out of range or a frame of another size (naming
    /// the file); [`KinectError::Io`] / [`KinectError::Png`] from reading the PNG (the file was
    /// removed or is not a 16-bit greyscale PNG).
    pub fn frame(&self, i: usize) -> Result<DepthFrame, KinectError> {
        if i >= self.len() {
            return Err(KinectError::Recording {
                file: self.dir.join(DEPTH_DIR).display().to_string(),
                message: format!(
                    "frame {i} requested, but the recording has {} frames (0..={})",
                    self.len(),
                    self.len().saturating_sub(1)
                ),
            });
        }
        let path = self.frame_path(i);
        let frame = read_depth_png16(&path)?;
        check_frame_size(&path, (frame.width, frame.height), &self.intrinsics, "")?;
        Ok(frame)
    }
}

/// Refuses a recording whose first frame has another size than its intrinsics: intrinsics of
/// another camera or mode would otherwise skip every frame one by one, each with the same
/// reason, and the run would end "successfully" having matched nothing. Only the PNG header is
/// read. A first frame whose header cannot be read is left to [`Recording::frame`], which skips
/// that frame alone (one damaged file does not refuse a recording).
fn check_first_frame_size(path: &Path, k: &Intrinsics) -> Result<(), KinectError> {
    match png_size(path) {
        Ok(size) => check_frame_size(
            path,
            size,
            k,
            ": the intrinsics are another camera's or another depth mode's",
        ),
        Err(_) => Ok(()),
    }
}

/// Refuses a frame at `path` whose `(width, height)` is not the intrinsics' size, the message
/// ended by `cause`.
fn check_frame_size(
    path: &Path,
    (w, h): (u32, u32),
    k: &Intrinsics,
    cause: &str,
) -> Result<(), KinectError> {
    if (w, h) == (k.width, k.height) {
        return Ok(());
    }
    Err(KinectError::Recording {
        file: path.display().to_string(),
        message: format!(
            "depth frame is {w}x{h}, but {INTRINSICS_FILE} says {}x{}{cause}",
            k.width, k.height
        ),
    })
}

/// The number of frame files in `depth_dir`, checked to be `000000.png` … with no gap.
fn count_frames(depth_dir: &Path) -> Result<usize, KinectError> {
    let dir_name = depth_dir.display().to_string();
    let rec_err = |file: String, message: String| KinectError::Recording { file, message };
    let mut numbers: Vec<usize> = Vec::new();
    let entries = std::fs::read_dir(depth_dir).map_err(|e| KinectError::io(&dir_name, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| KinectError::io(&dir_name, e))?;
        let name = entry.file_name();
        let Some(stem) = name.to_str().and_then(|n| n.strip_suffix(".png")) else {
            continue;
        };
        if stem.is_empty() || !stem.bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        if stem.len() != FRAME_DIGITS {
            return Err(rec_err(
                depth_dir.join(&name).display().to_string(),
                format!(
                    "frame file names have {FRAME_DIGITS} digits (000000.png, 000001.png, …), \
                     this one {}",
                    stem.len()
                ),
            ));
        }
        // Six ASCII digits always parse.
        let n = stem.parse::<usize>().map_err(|e| {
            rec_err(
                depth_dir.join(&name).display().to_string(),
                format!("not a frame number: {e}"),
            )
        })?;
        numbers.push(n);
    }
    if numbers.is_empty() {
        return Err(rec_err(
            dir_name,
            "no depth frames (expected 000000.png, 000001.png, …)".into(),
        ));
    }
    numbers.sort_unstable();
    if let Some((i, &found)) = numbers.iter().enumerate().find(|(i, n)| *i != **n) {
        let before = if i == 0 {
            "no frame before it".to_string()
        } else {
            format!("found {} to {}", frame_file_name(0), frame_file_name(i - 1))
        };
        return Err(rec_err(
            depth_dir.join(frame_file_name(i)).display().to_string(),
            format!(
                "missing: frame numbers must be contiguous from 000000 ({before}, then {})",
                frame_file_name(found)
            ),
        ));
    }
    Ok(numbers.len())
}

/// The times of `depth_times.txt` ([`parse_depth_times`] on the file's text, which must be
/// UTF-8), frames a plausible period apart ([`FRAME_PERIODS_S`]).
fn read_times(path: &Path, frames: usize) -> Result<Vec<f64>, KinectError> {
    let (text, file) = crate::error::read_input_text(path, |file, message| {
        KinectError::Recording { file, message }
    })?;
    let times = parse_depth_times(&text, frames, &file)?;
    let mut gaps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    check_frame_period(median(&mut gaps), "the depth frames")
        .map_err(|message| KinectError::Recording { file, message })?;
    Ok(times)
}

/// The median interval between frames that depth cameras and skeleton trackers run at (1 ms
/// to 5 s: 1000 to 0.2 frames per second). A median outside it means times in another unit —
/// milliseconds read as seconds put 30 Hz frames 33 s apart.
pub const FRAME_PERIODS_S: std::ops::RangeInclusive<f64> = 0.001..=5.0;

/// Refuses a median frame `period` (seconds; `None`: a single frame, nothing to judge) outside
/// [`FRAME_PERIODS_S`], naming `what` and the unit the times seem to be in.
fn check_frame_period(period: Option<f64>, what: &str) -> Result<(), String> {
    let Some(p) = period.filter(|p| !FRAME_PERIODS_S.contains(p)) else {
        return Ok(());
    };
    let units: Vec<&str> = [
        (1e-3, "milliseconds"),
        (1e-6, "microseconds"),
        (1e-9, "nanoseconds"),
    ]
    .into_iter()
    .filter(|(scale, _)| FRAME_PERIODS_S.contains(&(p * scale)))
    .map(|(_, unit)| unit)
    .collect();
    let unit = match units[..] {
        [] => String::new(),
        _ => format!(" (they look like {})", units.join(" or ")),
    };
    let p = if p >= 1e-3 {
        format!("{p:.3}")
    } else {
        format!("{p:.3e}")
    };
    Err(format!(
        "{what} are a median {p} s apart, not {}–{} s as a camera's or a tracker's frames are: \
         times must be in seconds{unit}",
        FRAME_PERIODS_S.start(),
        FRAME_PERIODS_S.end()
    ))
}

/// Parses the text of a recording folder's `depth_times.txt` ([`DEPTH_TIMES_FILE`]) for a
/// recording of `frames` depth frames; `file` names it in errors. Line `i + 1` is the time of
/// depth frame `i` in seconds: a number (surrounding whitespace and a `\r\n` line end are
/// allowed), finite and greater than the line before. There must be exactly `frames` such
/// lines: a final newline is optional and blank lines after the last time are ignored, but a
/// blank line before a time is an error (it would shift every later frame); a leading
/// byte-order mark is skipped.
///
/// Errors: [`KinectError::Parse`] naming `file` and the line (1-based): an empty line, not a
/// number, not finite, not after the previous time; then [`KinectError::Recording`] naming
/// `file` when the number of times is not `frames`.
///
/// ```
/// use symcorr_kinect::{parse_depth_times, KinectError};
/// let times = parse_depth_times("0.0\n0.0333\r\n 0.0667 \n", 3, "<memory>").unwrap();
/// assert_eq!(times, vec![0.0, 0.0333, 0.0667]);
/// let e = parse_depth_times("0.0\n0.0\n", 2, "depth_times.txt").unwrap_err();
/// assert!(matches!(e, KinectError::Parse { line: 2, .. }));
/// assert_eq!(
///     e.to_string(),
///     "depth_times.txt:2: time 0 s is not after the previous frame's 0 s \
///      (times must increase strictly)"
/// );
/// let e = parse_depth_times("0.0\n\n", 2, "depth_times.txt").unwrap_err();
/// assert_eq!(e.to_string(), "depth_times.txt: 1 time for 2 depth frames (one line per frame)");
/// ```
pub fn parse_depth_times(text: &str, frames: usize, file: &str) -> Result<Vec<f64>, KinectError> {
    let parse_err = |line: usize, message: String| KinectError::Parse {
        file: file.to_string(),
        line,
        message,
    };
    // A byte-order mark, as Windows tools write UTF-8, is no part of the first line.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Blank lines after the last time are no frames (scripts often end with one); a blank line
    // before a time is refused below, since it would shift every later frame's number.
    let text = text.trim_end();
    // Every time but the last takes at least two bytes ("0\n"): no more room than the text has.
    let mut times: Vec<f64> = Vec::with_capacity(frames.min(text.len() / 2 + 1));
    for (i, line) in text.lines().enumerate() {
        let field = line.trim();
        let what = format!("the time of depth frame {i} in seconds");
        if field.is_empty() {
            return Err(parse_err(i + 1, format!("empty line; expected {what}")));
        }
        let t: f64 = field.parse().map_err(|_| {
            parse_err(
                i + 1,
                format!(
                    "`{}` is not a number; expected {what}",
                    crate::joints::quote(field)
                ),
            )
        })?;
        if !t.is_finite() {
            return Err(parse_err(
                i + 1,
                format!("time `{}` is not finite", crate::joints::quote(field)),
            ));
        }
        if let Some(&prev) = times.last() {
            if t <= prev {
                return Err(parse_err(
                    i + 1,
                    format!(
                        "time {t} s is not after the previous frame's {prev} s \
                         (times must increase strictly)"
                    ),
                ));
            }
        }
        times.push(t);
    }
    if times.len() != frames {
        return Err(KinectError::Recording {
            file: file.to_string(),
            message: format!(
                "{} for {} (one line per frame)",
                count(times.len(), "time", "times"),
                count(frames, "depth frame", "depth frames")
            ),
        });
    }
    Ok(times)
}

/// `n` and its noun, singular for one: "1 time", "2 times".
fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// How many log frame periods from a time a log frame may be and still be used
/// ([`JointTrack::at`]).
pub const MAX_GAP_PERIODS: f64 = 1.5;

/// A joint log looked up at depth frames' times: the skeleton at `time + offset_s`, interpolated
/// between the two nearest log frames.
///
/// ```
/// use symcorr_kinect::{JointLog, JointTrack, SkipReason};
/// use symcorr_skeleton::{Joint, Skeleton};
/// let at = |x: f64| Skeleton::from_arrays([[x, 1.0, 2.0]; 20]);
/// let log = JointLog::from_skeletons(vec![at(0.0), at(0.3), at(0.6)], 30.0);
/// // The joint clock runs 10 ms ahead of the depth clock.
/// let track = JointTrack::new(log, 0.01).unwrap();
/// let s = track.at(0.0 / 30.0 + 0.5 / 30.0 - 0.01).unwrap(); // half-way between frames 0 and 1
/// assert!(s.interpolated && (s.before, s.after) == (0, 1));
/// assert!((s.skeleton.position(Joint::Head).x - 0.15).abs() < 1e-9);
/// assert!(matches!(track.at(1.0), Err(SkipReason::NoSkeleton { .. })));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrack {
    log: JointLog,
    offset_s: f64,
    period_s: f64,
}

/// A skeleton at a depth frame's time ([`JointTrack::at`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TimedSkeleton {
    /// The skeleton; a joint's confidence is 0 where it is not tracked at this time.
    pub skeleton: Skeleton,
    /// The time looked up in the log: the depth frame's time plus the track's offset, seconds.
    pub log_time_s: f64,
    /// The log frame at or before `log_time_s` used (equal to `after` for a single frame).
    pub before: usize,
    /// The log frame after `log_time_s` used (equal to `before` for a single frame).
    pub after: usize,
    /// Weight of `after` in the interpolation, in [0, 1] (0 for a single frame).
    pub weight_after: f64,
    /// Whether the skeleton was interpolated between two log frames (`before != after`).
    pub interpolated: bool,
}

/// Why [`JointTrack::at`] has no skeleton for a time: the depth frame is to be skipped.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SkipReason {
    /// No log frame lies within [`MAX_GAP_PERIODS`] log frame periods of the time (the log
    /// dropped frames, or the time is outside the log); or the time is not finite (gap ∞).
    #[error("no joint log frame within {MAX_GAP_PERIODS} log periods (the nearest is {nearest_gap_s} s away)")]
    NoSkeleton {
        /// Distance in seconds from the time to the nearest log frame.
        nearest_gap_s: f64,
    },
    /// The log frames at this time track no joint (every confidence 0).
    #[error("the joint log frames at this time track no joint (every confidence is 0)")]
    NoBody,
}

impl JointTrack {
    /// A track over `log`, whose clock reads `offset_s` more than the depth frames' clock (a
    /// depth frame at `t` is matched with the log at `t + offset_s`). A frame that repeats the
    /// one before it exactly (time, joints, confidence) is dropped. The log frame period is the
    /// median of the log's frame intervals (1/30 s, [`KINECT_FPS`], for a one-frame log).
    ///
    /// Errors: [`KinectError::Track`] for an empty log, a non-finite offset, log times that are
    /// not finite or do not increase strictly (naming the frame; two different skeletons at one
    /// time are ambiguous), or a median frame interval
    /// outside [`FRAME_PERIODS_S`] (times in another unit than seconds).
    ///
    /// ```
    /// use symcorr_kinect::{JointLog, JointTrack};
    /// use symcorr_skeleton::Skeleton;
    /// let log = JointLog::from_skeletons(vec![Skeleton::from_arrays([[0.0, 1.0, 2.0]; 20]); 4], 15.0);
    /// let track = JointTrack::new(log, 0.0).unwrap();
    /// assert!((track.period_s() - 1.0 / 15.0).abs() < 1e-12);
    /// ```
    pub fn new(mut log: JointLog, offset_s: f64) -> Result<JointTrack, KinectError> {
        if log.frames.is_empty() {
            return Err(KinectError::Track("the joint log has no frames".into()));
        }
        if !offset_s.is_finite() {
            return Err(KinectError::Track(format!(
                "time offset {offset_s} s is not finite"
            )));
        }
        if let Some((i, f)) = log
            .frames
            .iter()
            .enumerate()
            .find(|(_, f)| !f.time_s.is_finite())
        {
            return Err(KinectError::Track(format!(
                "joint log frame {i} has time {} s, not a finite number",
                f.time_s
            )));
        }
        let mut gaps = Vec::with_capacity(log.frames.len().saturating_sub(1));
        let mut kept: Vec<JointFrame> = Vec::with_capacity(log.frames.len());
        // The file's index of the last kept frame, for messages.
        let mut last = 0;
        for (i, f) in std::mem::take(&mut log.frames).into_iter().enumerate() {
            if let Some(prev) = kept.last() {
                // A logger that writes the latest skeleton at every depth frame repeats a
                // skeleton frame the tracker has not yet replaced: it carries nothing.
                if f == *prev {
                    continue;
                }
                let (a, b) = (prev.time_s, f.time_s);
                if b <= a {
                    return Err(KinectError::Track(format!(
                        "joint log frame {i} at {b} s is not after frame {last} at {a} s \
                         (a track needs strictly increasing times)"
                    )));
                }
                gaps.push(b - a);
            }
            kept.push(f);
            last = i;
        }
        log.frames = kept;
        let period_s = median(&mut gaps);
        check_frame_period(period_s, "the joint log's frames").map_err(KinectError::Track)?;
        let period_s = period_s.unwrap_or(1.0 / KINECT_FPS);
        Ok(JointTrack {
            log,
            offset_s,
            period_s,
        })
    }

    /// The joint log.
    pub fn log(&self) -> &JointLog {
        &self.log
    }

    /// The offset added to a depth frame's time to find it in the log, seconds.
    pub fn offset_s(&self) -> f64 {
        self.offset_s
    }

    /// The log frame period (median interval between log frames), seconds.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// The skeleton at `time_s + offset_s` in the log, found by binary search (O(log n)):
    ///
    /// * the log frames just before (or at) and just after that time which lie within
    ///   [`MAX_GAP_PERIODS`] periods of it are used; none → [`SkipReason::NoSkeleton`];
    /// * one frame (or a frame at exactly that time) → its skeleton as it is;
    /// * two frames → per joint, linear interpolation of the positions with confidence the
    ///   smaller of the two; a joint tracked (confidence > 0) in only one of them keeps that
    ///   frame's position and confidence if that frame is within half a period of the time, and
    ///   is otherwise untracked (confidence 0, position interpolated, not flagged). A limb pair
    ///   exchanged between the two frames (a tracker's left/right swap: [`limb_swap_evidence`]
    ///   above [`SWAP_EVIDENCE_THRESHOLD`]) is not interpolated: its joints are the nearer
    ///   frame's.
    ///   The `interpolated` flag of a tracked joint is that of the frame(s) it came from; the
    ///   head's turn ([`Skeleton::head_turn`]) is blended like a tracked joint's position;
    /// * a result with every confidence 0 → [`SkipReason::NoBody`].
    ///
    /// ```
    /// use symcorr_kinect::{JointLog, JointTrack, SkipReason};
    /// use symcorr_skeleton::Skeleton;
    /// let mut lost = Skeleton::from_arrays([[0.0, 1.0, 2.0]; 20]);
    /// lost.confidence = [0.0; 20];
    /// let log = JointLog::from_skeletons(vec![lost.clone(), lost], 30.0);
    /// let track = JointTrack::new(log, 0.0).unwrap();
    /// assert_eq!(track.at(0.01), Err(SkipReason::NoBody));
    /// ```
    pub fn at(&self, time_s: f64) -> Result<TimedSkeleton, SkipReason> {
        let t = time_s + self.offset_s;
        if !t.is_finite() {
            return Err(SkipReason::NoSkeleton {
                nearest_gap_s: f64::INFINITY,
            });
        }
        let frames = &self.log.frames;
        let max_gap = MAX_GAP_PERIODS * self.period_s;
        // Frames [0, k) are at or before t.
        let k = frames.partition_point(|f| f.time_s <= t);
        let before = k.checked_sub(1).map(|i| (i, t - frames[i].time_s));
        let after = frames.get(k).map(|f| (k, f.time_s - t));
        let nearest_gap_s = [before, after]
            .iter()
            .flatten()
            .map(|(_, g)| *g)
            .fold(f64::INFINITY, f64::min);
        let near = |x: Option<(usize, f64)>| x.filter(|(_, g)| *g <= max_gap);
        let (skeleton, before, after, weight_after) = match (near(before), near(after)) {
            (None, None) => return Err(SkipReason::NoSkeleton { nearest_gap_s }),
            (Some((i, _)), None) | (None, Some((i, _))) => (frames[i].skeleton.clone(), i, i, 0.0),
            // A log frame at exactly this time.
            (Some((i, gi)), Some(_)) if gi <= 0.0 => (frames[i].skeleton.clone(), i, i, 0.0),
            (Some((i, gi)), Some((j, gj))) => {
                let w = gi / (gi + gj);
                let s = self.blend(&frames[i].skeleton, &frames[j].skeleton, w, gi, gj);
                (s, i, j, w)
            }
        };
        if skeleton.confidence.iter().all(|c| *c <= 0.0) {
            return Err(SkipReason::NoBody);
        }
        Ok(TimedSkeleton {
            skeleton,
            log_time_s: t,
            before,
            after,
            weight_after,
            interpolated: before != after,
        })
    }

    /// Per-joint blend of `a` (`gap_a` seconds before the time) and `b` (`gap_b` after), weight
    /// `w` of `b` (see [`JointTrack::at`]).
    fn blend(&self, a: &Skeleton, b: &Skeleton, w: f64, gap_a: f64, gap_b: f64) -> Skeleton {
        let half = 0.5 * self.period_s;
        let mut out = a.clone();
        // A limb pair the tracker swapped between the two frames is not blended: halfway
        // between a left leg and the right one is neither, and a continuity check against such
        // legs lets a swap in gradually. Each joint of the pair takes the nearer frame's.
        let mut unblended = [false; Joint::COUNT];
        for pair in [LimbPair::Arms, LimbPair::Legs] {
            if limb_swap_evidence(a, b, pair) > SWAP_EVIDENCE_THRESHOLD {
                for l in pair.left_joints() {
                    unblended[l.index()] = true;
                    unblended[l.mirror().index()] = true;
                }
            }
        }
        for (j, &whole) in unblended.iter().enumerate() {
            if whole {
                let near = if w < 0.5 { a } else { b };
                out.positions[j] = near.positions[j];
                out.confidence[j] = near.confidence[j];
                out.interpolated[j] = near.interpolated[j];
                continue;
            }
            let (ca, cb) = (a.confidence[j], b.confidence[j]);
            let lerp = a.positions[j] + (b.positions[j] - a.positions[j]) * w;
            let (p, c, flag) = match (ca > 0.0, cb > 0.0) {
                (true, true) => (lerp, ca.min(cb), a.interpolated[j] || b.interpolated[j]),
                (true, false) if gap_a <= half => (a.positions[j], ca, a.interpolated[j]),
                (false, true) if gap_b <= half => (b.positions[j], cb, b.interpolated[j]),
                // Untracked here: not flagged, so that nothing takes its position for one.
                _ => (lerp, 0.0, false),
            };
            out.positions[j] = p;
            out.confidence[j] = c;
            out.interpolated[j] = flag;
        }
        // The head's turn as a tracked joint's position: blended, or the near frame's alone.
        out.head_turn = match (a.head_turn, b.head_turn) {
            (Some(x), Some(y)) => Some(x + (y - x) * w),
            (Some(x), None) if gap_a <= half => Some(x),
            (None, Some(y)) if gap_b <= half => Some(y),
            _ => None,
        };
        out
    }
}

/// A one-euro filter (Casiez, Roussel & Vogel, "1 € Filter: A Simple Speed-based Low-pass Filter
/// for Noisy Input in Interactive Systems", CHI 2012) on one coordinate: an exponential low-pass
/// filter whose cutoff frequency rises with the signal's (filtered) speed,
///
/// ```text
/// cutoff = min_cutoff_hz + beta · |dx̂/dt|,  α(f) = 1 / (1 + 1/(2π f Δt)),
/// x̂ = α(cutoff) · x + (1 − α(cutoff)) · x̂_prev
/// ```
///
/// with `dx̂/dt` the derivative `(x − x̂_prev)/Δt` low-passed at `d_cutoff_hz`. At rest the
/// cutoff is low and jitter is smoothed away; in fast motion it rises and the lag stays small,
/// which a fixed low-pass filter (or a moving average) cannot do both of: this is why joints are
/// smoothed with it. `Δt` comes from the samples' times, so dropped frames are handled; after a
/// skipped frame of long gap, [`OneEuroFilter::reset`] restarts it.
///
/// The defaults ([`OneEuroFilter::KINECT_30HZ`]) are for Kinect skeletons in metres at 30 Hz,
/// tuned as the paper says (β = 0, lower `min_cutoff_hz` until the jitter at rest is acceptable,
/// then raise β until fast motion lags little): `min_cutoff_hz` 1 Hz, `beta` 5 per (m/s) (the
/// cutoff reaches 6 Hz at 1 m/s, a hand's speed in a gesture), `d_cutoff_hz` 1 Hz (the paper's
/// value). Measured in this crate's tests: on a static joint with 1 cm white jitter they lower
/// its standard deviation by a factor of 2.6 (a fixed 1 Hz low-pass: 3.3); a 30 cm jump is
/// followed to within 5 mm in 4 frames (the fixed low-pass is still 12 cm short after 5).
///
/// ```
/// use symcorr_kinect::OneEuroFilter;
/// let mut f = OneEuroFilter::default();
/// assert_eq!(f.filter(0.0, 1.0), 1.0); // the first sample passes through
/// let y = f.filter(1.0 / 30.0, 1.1);
/// assert!(y > 1.0 && y < 1.1);
/// f.reset();
/// assert_eq!(f.filter(5.0, 2.0), 2.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneEuroFilter {
    min_cutoff_hz: f64,
    beta: f64,
    d_cutoff_hz: f64,
    state: Option<EuroState>,
}

/// The filter's memory: the previous sample's time, filtered value and filtered derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
struct EuroState {
    time_s: f64,
    x_hat: f64,
    dx_hat: f64,
}

impl Default for OneEuroFilter {
    /// [`OneEuroFilter::KINECT_30HZ`].
    fn default() -> Self {
        OneEuroFilter::KINECT_30HZ
    }
}

/// `α` of an exponential smoother with cutoff `cutoff_hz` for samples `dt` seconds apart.
fn smoothing_factor(dt: f64, cutoff_hz: f64) -> f64 {
    let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz);
    1.0 / (1.0 + tau / dt)
}

impl OneEuroFilter {
    /// Defaults for Kinect skeletons in metres at 30 Hz: `min_cutoff_hz` 1, `beta` 5,
    /// `d_cutoff_hz` 1 (see the type's docs).
    pub const KINECT_30HZ: OneEuroFilter = OneEuroFilter {
        min_cutoff_hz: 1.0,
        beta: 5.0,
        d_cutoff_hz: 1.0,
        state: None,
    };

    /// A filter with the given parameters: cutoffs in Hz, finite and > 0; `beta` (Hz per unit
    /// of speed, e.g. per m/s) finite and ≥ 0.
    ///
    /// Errors: [`KinectError::FilterParameter`] naming the parameter.
    ///
    /// ```
    /// use symcorr_kinect::OneEuroFilter;
    /// assert!(OneEuroFilter::new(1.0, 0.0, 1.0).is_ok());
    /// assert_eq!(
    ///     OneEuroFilter::new(0.0, 5.0, 1.0).unwrap_err().to_string(),
    ///     "one-euro filter min_cutoff_hz = 0: expected a finite number > 0"
    /// );
    /// ```
    pub fn new(min_cutoff_hz: f64, beta: f64, d_cutoff_hz: f64) -> Result<Self, KinectError> {
        let positive = "a finite number > 0";
        for (parameter, value, ok, expected) in [
            (
                "min_cutoff_hz",
                min_cutoff_hz,
                min_cutoff_hz.is_finite() && min_cutoff_hz > 0.0,
                positive,
            ),
            (
                "beta",
                beta,
                beta.is_finite() && beta >= 0.0,
                "a finite number ≥ 0",
            ),
            (
                "d_cutoff_hz",
                d_cutoff_hz,
                d_cutoff_hz.is_finite() && d_cutoff_hz > 0.0,
                positive,
            ),
        ] {
            if !ok {
                return Err(KinectError::FilterParameter {
                    parameter,
                    value,
                    expected,
                });
            }
        }
        Ok(OneEuroFilter {
            min_cutoff_hz,
            beta,
            d_cutoff_hz,
            state: None,
        })
    }

    /// The cutoff frequency at rest, Hz.
    pub fn min_cutoff_hz(&self) -> f64 {
        self.min_cutoff_hz
    }

    /// How much the cutoff rises with speed, Hz per unit of speed.
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// The cutoff frequency of the derivative's low-pass filter, Hz.
    pub fn d_cutoff_hz(&self) -> f64 {
        self.d_cutoff_hz
    }

    /// Forgets the past: the next sample passes through unchanged (after a skipped frame).
    pub fn reset(&mut self) {
        self.state = None;
    }

    /// Filters sample `x` taken at `time_s` seconds and returns the filtered value. The first
    /// sample after creation or [`OneEuroFilter::reset`] passes through, and so does a sample
    /// whose time is not after the previous one's (the filter restarts from it). A non-finite
    /// `x` is returned as it is and leaves the filter unchanged.
    pub fn filter(&mut self, time_s: f64, x: f64) -> f64 {
        if !x.is_finite() {
            return x;
        }
        let restart = EuroState {
            time_s,
            x_hat: x,
            dx_hat: 0.0,
        };
        let Some(prev) = self.state else {
            self.state = Some(restart);
            return x;
        };
        let dt = time_s - prev.time_s;
        if !(dt > 0.0 && dt.is_finite()) {
            self.state = Some(restart);
            return x;
        }
        let dx = (x - prev.x_hat) / dt;
        let a_d = smoothing_factor(dt, self.d_cutoff_hz);
        let dx_hat = prev.dx_hat + a_d * (dx - prev.dx_hat);
        let cutoff = self.min_cutoff_hz + self.beta * dx_hat.abs();
        let a = smoothing_factor(dt, cutoff);
        // α·x + (1 − α)·x̂_prev, written so that a constant signal stays exactly constant.
        let x_hat = prev.x_hat + a * (x - prev.x_hat);
        self.state = Some(EuroState {
            time_s,
            x_hat,
            dx_hat,
        });
        x_hat
    }
}

/// `v` through one filter per coordinate at `time_s`.
fn filter_xyz(fs: &mut [OneEuroFilter; 3], time_s: f64, v: Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        fs[0].filter(time_s, v.x),
        fs[1].filter(time_s, v.y),
        fs[2].filter(time_s, v.z),
    )
}

/// One [`OneEuroFilter`] per joint coordinate of a skeleton (60 in all), and one for the head's
/// turn ([`Skeleton::head_turn`], when the skeleton reports it), filtered as the arc the nose
/// moves along ([`TURN_ARM_M`] × the turn, metres) so that the joints' parameters apply.
///
/// ```
/// use symcorr_kinect::{OneEuroFilter, SkeletonFilter};
/// use symcorr_skeleton::Skeleton;
/// let mut f = SkeletonFilter::new(OneEuroFilter::default());
/// let still = Skeleton::from_arrays([[0.1, 1.0, 2.0]; 20]);
/// for i in 0..10 {
///     assert_eq!(f.filter(i as f64 / 30.0, &still), still); // a constant stays constant
/// }
/// f.reset(); // after a skipped depth frame
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SkeletonFilter {
    filters: [[OneEuroFilter; 3]; Joint::COUNT],
    turn: OneEuroFilter,
}

/// The lever arm at which [`SkeletonFilter`] filters the head's turn, metres: about the nose's
/// distance from the head's axis. In radians a tracker's noise moves the turn ten times as
/// fast as it moves a joint in metres, and the one-euro filter's speed term would open up for
/// it.
pub const TURN_ARM_M: f64 = 0.1;

impl SkeletonFilter {
    /// A filter for every joint coordinate, each a fresh copy of `template`'s parameters.
    pub fn new(template: OneEuroFilter) -> SkeletonFilter {
        let mut fresh = template;
        fresh.reset();
        SkeletonFilter {
            filters: [[fresh; 3]; Joint::COUNT],
            turn: fresh,
        }
    }

    /// Forgets the past of every coordinate (after a skipped frame).
    pub fn reset(&mut self) {
        for f in self.filters.iter_mut().flatten() {
            f.reset();
        }
        self.turn.reset();
    }

    /// The skeleton at `time_s` with every joint position and the head's turn filtered
    /// ([`OneEuroFilter::filter`]; a skeleton without a turn forgets the turn's past);
    /// confidences and `interpolated` flags are kept as they are.
    pub fn filter(&mut self, time_s: f64, skeleton: &Skeleton) -> Skeleton {
        let mut out = skeleton.clone();
        for (p, fs) in out.positions.iter_mut().zip(self.filters.iter_mut()) {
            *p = Point3::from(filter_xyz(fs, time_s, p.coords));
        }
        match skeleton.head_turn {
            Some(t) => out.head_turn = Some(self.turn.filter(time_s, t * TURN_ARM_M) / TURN_ARM_M),
            None => self.turn.reset(),
        }
        out
    }
}

/// A first-order low-pass, per joint coordinate, of how far a step moved a skeleton's joints:
/// for a skeleton `given` and the same joints `moved` by that step (the attachment's refinement,
/// which re-centres each joint in its limb's cross-section of one depth frame), the skeleton at
/// `given` plus the low-passed moves. Each coordinate is a [`OneEuroFilter`] with `beta` 0, which
/// Casiez et al. 2012 note is an exponential smoother of cutoff `min_cutoff_hz`.
///
/// Why: a tracker's joints, smoothed by [`SkeletonFilter`], follow the body; the refinement's
/// moves are a bias of the tracker's joints against the limbs' centres plus the noise of circle
/// fits on one frame's half-rings, 4–9 cm on a head 3.2 m from a Kinect v1. The bias changes as
/// slowly as the body turns; the noise changes every frame. Smoothing the moves, not the
/// joints, adds no lag to the body's motion
/// (`docs/decisions/2026-12-06-refinement-moves-smoothed.md`).
///
/// ```
/// use symcorr_kinect::JointMoveFilter;
/// use symcorr_skeleton::Skeleton;
/// let mut f = JointMoveFilter::DEFAULT;
/// let given = Skeleton::from_arrays([[0.0, 1.0, 2.0]; 20]);
/// let moved = Skeleton::from_arrays([[0.04, 1.0, 2.0]; 20]); // every joint moved 4 cm in x
/// let first = f.filter(0.0, &given, &moved);
/// assert_eq!(first, moved); // the first frame's moves pass through
/// let back = f.filter(1.0 / 30.0, &given, &given); // the next frame's step moved nothing
/// let x = back.positions[0].x;
/// assert!(x > 0.02 && x < 0.04); // most of the 4 cm kept: one frame's moves are noisy
/// f.reset();
/// assert_eq!(f.filter(2.0, &given, &given), given);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct JointMoveFilter {
    filters: [[OneEuroFilter; 3]; Joint::COUNT],
}

impl JointMoveFilter {
    /// Cutoff 1 Hz, the cutoff at rest of [`OneEuroFilter::KINECT_30HZ`]: at 30 frames/s each
    /// frame's moves weigh 0.17.
    pub const DEFAULT: JointMoveFilter = JointMoveFilter {
        filters: [[OneEuroFilter {
            min_cutoff_hz: 1.0,
            beta: 0.0,
            d_cutoff_hz: 1.0,
            state: None,
        }; 3]; Joint::COUNT],
    };

    /// A filter of cutoff `cutoff_hz` (finite and > 0).
    ///
    /// Errors: [`KinectError::FilterParameter`].
    ///
    /// ```
    /// use symcorr_kinect::JointMoveFilter;
    /// assert!(JointMoveFilter::new(2.0).is_ok());
    /// assert!(JointMoveFilter::new(f64::NAN).is_err());
    /// ```
    pub fn new(cutoff_hz: f64) -> Result<JointMoveFilter, KinectError> {
        let f = OneEuroFilter::new(cutoff_hz, 0.0, cutoff_hz)?;
        Ok(JointMoveFilter {
            filters: [[f; 3]; Joint::COUNT],
        })
    }

    /// Forgets the past (after a skipped frame): the next moves pass through.
    pub fn reset(&mut self) {
        for f in self.filters.iter_mut().flatten() {
            f.reset();
        }
    }

    /// `moved` with each joint at `given`'s plus the low-passed move `moved − given` at
    /// `time_s` (a time not after the previous one's restarts the filter, like
    /// [`OneEuroFilter::filter`]); confidences, flags and the head's turn are `moved`'s.
    pub fn filter(&mut self, time_s: f64, given: &Skeleton, moved: &Skeleton) -> Skeleton {
        let mut out = moved.clone();
        for ((p, (g, m)), fs) in out
            .positions
            .iter_mut()
            .zip(given.positions.iter().zip(&moved.positions))
            .zip(self.filters.iter_mut())
        {
            *p = g + filter_xyz(fs, time_s, m - g);
        }
        out
    }
}

/// [`limb_swap_evidence`] above which [`legs_swapped`] / [`arms_swapped`] say a pair was
/// exchanged: the limbs fit the previous frame at least three times better (in summed squared
/// distance) exchanged than as given. A margin above 0, so that limbs passing each other (legs
/// in a crossing step, equally good both ways) do not flip the verdict on noise.
pub const SWAP_EVIDENCE_THRESHOLD: f64 = 0.5;

/// How much better the limb joints of `current` (arms and legs) match `previous` with left and
/// right exchanged than as given: `(d_given − d_swapped) / (d_given + d_swapped)`, where `d` is
/// the sum over the limb joints of the squared distance from `previous`'s joint to `current`'s
/// same (given) or mirrored (swapped) joint. In [−1, 1]; positive = the exchanged frame fits
/// better, near −1 for ordinary motion between frames, near +1 for a tracker's left/right swap.
/// Joints with confidence 0 in either frame (or whose mirror has confidence 0 in `current`) are
/// left out; 0 when nothing is left or both sums are 0.
///
/// ```
/// use symcorr_kinect::swap_evidence;
/// use symcorr_skeleton::{Joint, Skeleton};
/// let mut xyz = [[0.0, 1.0, 2.0]; 20];
/// for j in Joint::ALL {
///     // Left joints at +x, right joints at −x, 20 cm apart.
///     xyz[j.index()][0] = if j.mirror() == j { 0.0 } else if j.name().ends_with("left") { 0.1 } else { -0.1 };
/// }
/// let a = Skeleton::from_arrays(xyz);
/// assert_eq!(swap_evidence(&a, &a), -1.0);
/// assert_eq!(swap_evidence(&a, &a.swap_sides()), 1.0);
/// ```
pub fn swap_evidence(previous: &Skeleton, current: &Skeleton) -> f64 {
    let joints = [LimbPair::Arms, LimbPair::Legs].map(LimbPair::left_joints);
    evidence(previous, current, joints.iter().flatten().copied())
}

/// [`swap_evidence`] over one pair of limbs only.
///
/// ```
/// use symcorr_kinect::{limb_swap_evidence, LimbPair};
/// use symcorr_skeleton::Skeleton;
/// let s = Skeleton::from_arrays([[0.0, 1.0, 2.0]; 20]); // every joint at one point
/// assert_eq!(limb_swap_evidence(&s, &s, LimbPair::Legs), 0.0); // no evidence either way
/// ```
pub fn limb_swap_evidence(previous: &Skeleton, current: &Skeleton, pair: LimbPair) -> f64 {
    evidence(previous, current, pair.left_joints().into_iter())
}

/// Whether the legs of `current` are exchanged relative to `previous`
/// ([`limb_swap_evidence`] above [`SWAP_EVIDENCE_THRESHOLD`]).
///
/// ```
/// use symcorr_kinect::legs_swapped;
/// use symcorr_skeleton::{Joint, Skeleton};
/// let mut xyz = [[0.0, 1.0, 2.0]; 20];
/// xyz[Joint::KneeLeft.index()][0] = 0.1;
/// xyz[Joint::KneeRight.index()][0] = -0.1;
/// let a = Skeleton::from_arrays(xyz);
/// assert!(!legs_swapped(&a, &a));
/// assert!(legs_swapped(&a, &a.swap_sides()));
/// ```
pub fn legs_swapped(previous: &Skeleton, current: &Skeleton) -> bool {
    limb_swap_evidence(previous, current, LimbPair::Legs) > SWAP_EVIDENCE_THRESHOLD
}

/// Whether the arms of `current` are exchanged relative to `previous`
/// ([`limb_swap_evidence`] above [`SWAP_EVIDENCE_THRESHOLD`]).
///
/// ```
/// use symcorr_kinect::arms_swapped;
/// use symcorr_skeleton::{Joint, Skeleton};
/// let mut xyz = [[0.0, 1.0, 2.0]; 20];
/// xyz[Joint::HandLeft.index()][0] = 0.3;
/// xyz[Joint::HandRight.index()][0] = -0.3;
/// let a = Skeleton::from_arrays(xyz);
/// assert!(!arms_swapped(&a, &a));
/// assert!(arms_swapped(&a, &a.swap_sides()));
/// ```
pub fn arms_swapped(previous: &Skeleton, current: &Skeleton) -> bool {
    limb_swap_evidence(previous, current, LimbPair::Arms) > SWAP_EVIDENCE_THRESHOLD
}

/// The normalised difference of summed squared distances, given vs swapped, over `left` joints
/// and their mirrors.
fn evidence(previous: &Skeleton, current: &Skeleton, left: impl Iterator<Item = Joint>) -> f64 {
    let (mut given, mut swapped) = (0.0, 0.0);
    for l in left {
        for j in [l, l.mirror()] {
            let (i, m) = (j.index(), j.mirror().index());
            let usable = previous.confidence[i] > 0.0
                && current.confidence[i] > 0.0
                && current.confidence[m] > 0.0;
            if usable {
                given += (current.positions[i] - previous.positions[i]).norm_squared();
                swapped += (current.positions[m] - previous.positions[i]).norm_squared();
            }
        }
    }
    let total = given + swapped;
    if total > 0.0 && total.is_finite() {
        (given - swapped) / total
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn frame_file_names_have_six_digits() {
        assert_eq!(frame_file_name(0), "000000.png");
        assert_eq!(frame_file_name(42), "000042.png");
    }

    #[test]
    fn joint_moves_are_smoothed_without_lagging_the_joints() {
        // The joints walk 1 m/s in x; each frame's step moves them by a bias of 3 cm in z plus
        // ±4 cm of noise alternating in y. The output follows the walk without lag, keeps the
        // bias and damps the noise.
        let mut f = JointMoveFilter::DEFAULT;
        let (mut worst_y, mut worst_lag) = (0.0f64, 0.0f64);
        for i in 0..90 {
            let t = f64::from(i) / 30.0;
            let given = Skeleton::from_arrays([[t, 1.0, 2.0]; Joint::COUNT]);
            let noise = if i % 2 == 0 { 0.04 } else { -0.04 };
            let moved = Skeleton::from_arrays([[t, 1.0 + noise, 2.03]; Joint::COUNT]);
            let out = f.filter(t, &given, &moved);
            let p = out.positions[Joint::Head.index()];
            assert_relative_eq!(p.z, 2.03, epsilon = 1e-9);
            if i >= 10 {
                worst_y = worst_y.max((p.y - 1.0).abs());
            }
            worst_lag = worst_lag.max((p.x - t).abs());
        }
        assert!(worst_lag < 1e-12, "the walk lagged by {worst_lag} m");
        assert!(worst_y < 0.01, "the noise kept {worst_y} m of its 0.04");
    }

    #[test]
    fn smoothing_factor_matches_the_paper() {
        // α = 1 / (1 + τ/Te), τ = 1/(2π fc): at fc = 1/(2π Te), α = 1/2.
        let dt = 0.04;
        let fc = 1.0 / (2.0 * std::f64::consts::PI * dt);
        assert!((smoothing_factor(dt, fc) - 0.5).abs() < 1e-12);
    }
}
