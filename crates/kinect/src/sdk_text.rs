//! Kinect SDK v1 text dumps: one frame per line, `frame x1 y1 z1 … x20 y20 z20` (61 values,
//! metres, SDK joint order), separated by whitespace or commas. Empty lines and lines starting
//! with `#` are skipped. The first value is the frame number; the time is `frame / 30 s`.
//! A joint at exactly (0, 0, 0) is how the SDK writes an untracked joint: it is interpolated
//! along its bone chain where tracked neighbours allow and flagged, otherwise kept untracked
//! (confidence 0; see [`crate::mapping`]). A line of zeros is a frame in which the tracker saw
//! no body.

use crate::error::KinectError;
use crate::joints::{JointFrame, JointLog, KINECT_FPS};
use crate::mapping::{Partial, SkeletonKind};
use std::fmt::Write;
use symcorr_skeleton::Joint;

pub(crate) fn tokens(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
}

/// Parses a Kinect SDK v1 text dump; `file` names it in errors.
pub fn parse_kinect_text(text: &str, file: &str) -> Result<JointLog, KinectError> {
    let mut frames = Vec::new();
    for (li, line) in text.lines().enumerate() {
        let line = line.trim().trim_start_matches('\u{feff}');
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let err = |message: String| KinectError::Parse {
            file: file.to_string(),
            line: li + 1,
            message,
        };
        let mut values = [0.0f64; 61];
        let mut n = 0;
        for tok in tokens(line) {
            if n == 61 {
                return Err(err(format!(
                    "expected 61 values (frame and 20 joints × xyz), found more: {:?}",
                    tok
                )));
            }
            values[n] = tok
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("value {} is not a finite number: {tok:?}", n + 1)))?;
            n += 1;
        }
        if n != 61 {
            return Err(err(format!(
                "expected 61 values (frame and 20 joints × xyz), found {n}"
            )));
        }
        if values[0] < 0.0 {
            return Err(err(format!("frame number {} is negative", values[0])));
        }
        let mut partial = Partial::new();
        for j in Joint::ALL {
            let k = 1 + 3 * j.index();
            let p = [values[k], values[k + 1], values[k + 2]];
            if p != [0.0, 0.0, 0.0] {
                partial.set(j, p.into(), 1.0);
            }
        }
        let skeleton = partial.complete().map_err(|j| {
            err(format!(
                "joint {:?}: its estimate from its neighbours is not a finite position",
                j.name()
            ))
        })?;
        frames.push(JointFrame {
            time_s: values[0] / KINECT_FPS,
            skeleton,
        });
    }
    if frames.is_empty() {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: "the Kinect text dump has no frames".into(),
        });
    }
    Ok(JointLog {
        skeleton_kind: SkeletonKind::KinectV1,
        frames,
    })
}

/// Writes a log as a Kinect SDK v1 text dump (frame number = round(time_s · 30)). Confidence
/// and interpolation flags are not part of this format and are lost.
pub fn to_kinect_text(log: &JointLog) -> String {
    let mut s = String::new();
    for f in &log.frames {
        let _ = write!(s, "{}", (f.time_s * KINECT_FPS).round());
        for p in &f.skeleton.positions {
            let _ = write!(s, " {} {} {}", p[0], p[1], p[2]);
        }
        s.push('\n');
    }
    s
}
