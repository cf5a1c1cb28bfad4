//! NTU RGB+D `.skeleton` files (Kinect v2). Layout, one item per line:
//!
//! ```text
//! frame_count
//! per frame:  body_count
//!   per body: body_id clipped_edges hand_left_conf hand_left_state hand_right_conf
//!             hand_right_state is_restricted lean_x lean_y tracking_state      (10 values)
//!             joint_count                                                       (25)
//!             25 × "x y z depth_x depth_y colour_x colour_y ow ox oy oz state"  (12 values)
//! ```
//!
//! The joint-count line is optional (some converters omit it); when present it must be 25.
//! Joint tracking state 2 (tracked) → confidence 1, 1 (inferred) → 0.5, 0 → 0. The 25 Kinect v2
//! joints map onto the canonical skeleton with the table in [`crate::mapping`]. Frames in which
//! the selected body is absent (NTU files have such frames at the start of some clips) are
//! skipped; the time of a kept frame is its index in the file / 30 s. A file in which no frame has
//! the body is an error ([`KinectError::NoBody`]).

use crate::error::KinectError;
use crate::joints::{most_tracked, BodySelect, JointFrame, JointLog, KINECT_FPS};
use crate::mapping::{Partial, SkeletonKind};
use crate::sdk_text::tokens;
use nalgebra::Point3;

struct Lines<'a> {
    inner: std::iter::Enumerate<std::str::Lines<'a>>,
    file: &'a str,
    last: usize,
}

impl<'a> Lines<'a> {
    fn next_tokens(&mut self, what: &str) -> Result<(usize, Vec<&'a str>), KinectError> {
        for (i, l) in self.inner.by_ref() {
            self.last = i + 1;
            let t: Vec<&str> = tokens(l.trim_start_matches('\u{feff}')).collect();
            if !t.is_empty() {
                return Ok((i + 1, t));
            }
        }
        Err(KinectError::Parse {
            file: self.file.to_string(),
            line: self.last + 1,
            message: format!("unexpected end of file: expected {what}"),
        })
    }

    fn err(&self, line: usize, message: String) -> KinectError {
        KinectError::Parse {
            file: self.file.to_string(),
            line,
            message,
        }
    }

    fn count(&mut self, what: &str, max: u64) -> Result<(usize, u64), KinectError> {
        let (line, t) = self.next_tokens(what)?;
        if t.len() != 1 {
            return Err(self.err(
                line,
                format!("expected {what} (one integer), found {} values", t.len()),
            ));
        }
        let n = t[0]
            .parse::<u64>()
            .map_err(|_| self.err(line, format!("expected {what}, found {:?}", t[0])))?;
        if n > max {
            return Err(self.err(line, format!("{what} {n} is larger than {max}")));
        }
        Ok((line, n))
    }
}

type Body = (u64, [(Point3<f64>, u8); 25]);

/// Parses an NTU RGB+D `.skeleton` file keeping the selected body; `file` names it in errors.
pub fn parse_ntu(text: &str, file: &str, select: BodySelect) -> Result<JointLog, KinectError> {
    let mut lines = Lines {
        inner: text.lines().enumerate(),
        file,
        last: 0,
    };
    // Bounds keep a corrupt count from allocating: 10^6 frames (9 h at 30 Hz), 6 bodies (Kinect v2).
    let (_, frame_count) = lines.count("the frame count", 1_000_000)?;
    let mut frames: Vec<Vec<Body>> = Vec::new();
    for fi in 0..frame_count as usize {
        let (_, body_count) = lines.count(&format!("the body count of frame {fi}"), 6)?;
        let mut bodies = Vec::with_capacity(body_count as usize);
        for bi in 0..body_count {
            let (line, info) = lines.next_tokens(&format!("body {bi} of frame {fi}"))?;
            if info.len() != 10 {
                return Err(lines.err(
                    line,
                    format!(
                        "frame {fi}, body {bi}: expected 10 body values, found {}",
                        info.len()
                    ),
                ));
            }
            let id = info[0].parse::<u64>().map_err(|_| {
                lines.err(
                    line,
                    format!(
                        "frame {fi}, body {bi}: body id {:?} is not an integer",
                        info[0]
                    ),
                )
            })?;
            for (k, t) in info.iter().enumerate().skip(1) {
                if !t.parse::<f64>().is_ok_and(f64::is_finite) {
                    return Err(lines.err(
                        line,
                        format!(
                            "frame {fi}, body {bi}: value {} is not a finite number: {t:?}",
                            k + 1
                        ),
                    ));
                }
            }
            let (mut line, mut t) = lines.next_tokens("the joint count or the first joint")?;
            if t.len() == 1 {
                if t[0] != "25" {
                    return Err(lines.err(
                        line,
                        format!(
                            "frame {fi}, body {bi}: joint count {:?}, expected 25 (Kinect v2)",
                            t[0]
                        ),
                    ));
                }
                (line, t) = lines.next_tokens("joint 0")?;
            }
            let mut joints = [(Point3::origin(), 0u8); 25];
            for (ji, joint) in joints.iter_mut().enumerate() {
                if ji > 0 {
                    (line, t) = lines.next_tokens(&format!("joint {ji}"))?;
                }
                if t.len() != 12 {
                    return Err(lines.err(
                        line,
                        format!(
                            "frame {fi}, body {bi}, joint {ji}: expected 12 values, found {}",
                            t.len()
                        ),
                    ));
                }
                let mut v = [0.0; 11];
                for (k, tok) in t[..11].iter().enumerate() {
                    v[k] = tok.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                        lines.err(
                            line,
                            format!("frame {fi}, body {bi}, joint {ji}: value {} is not a finite number: {tok:?}", k + 1),
                        )
                    })?;
                }
                let state = t[11].parse::<u8>().ok().filter(|s| *s <= 2).ok_or_else(|| {
                    lines.err(
                        line,
                        format!("frame {fi}, body {bi}, joint {ji}: tracking state {:?}, expected 0, 1 or 2", t[11]),
                    )
                })?;
                *joint = (Point3::new(v[0], v[1], v[2]), state);
            }
            bodies.push((id, joints));
        }
        frames.push(bodies);
    }
    if let Ok((line, _)) = lines.next_tokens("") {
        return Err(lines.err(
            line,
            format!("trailing data after the {frame_count} frames the header announces"),
        ));
    }

    let id = match select {
        BodySelect::Id(id) => id,
        BodySelect::MostTracked => most_tracked(
            frames
                .iter()
                .flatten()
                .map(|b| (b.0, b.1.iter().filter(|j| j.1 == 2).count())),
        )
        .ok_or_else(|| KinectError::NoBody {
            file: file.to_string(),
            message: format!("no frame of the {frame_count} has a body"),
        })?,
    };
    let mut out = Vec::new();
    for (fi, bodies) in frames.iter().enumerate() {
        let Some(body) = bodies.iter().find(|b| b.0 == id) else {
            continue;
        };
        if body.1.iter().all(|j| j.1 == 0) {
            continue;
        }
        let mut partial = Partial::new();
        for (ji, (p, state)) in body.1.iter().enumerate() {
            if let Some(j) = SkeletonKind::KinectV2.canonical(ji) {
                partial.set(j, *p, f64::from(*state) / 2.0);
            }
        }
        // Every canonical joint has a Kinect v2 source, so completion never interpolates and
        // every position is a parsed finite number: it cannot fail.
        let skeleton = partial.complete().map_err(|j| KinectError::Frame {
            file: file.to_string(),
            frame: fi,
            message: format!("joint {:?} is not a finite position", j.name()),
        })?;
        out.push(JointFrame {
            time_s: fi as f64 / KINECT_FPS,
            skeleton,
        });
    }
    if out.is_empty() {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: format!("no frame has a tracked body with id {id}"),
        });
    }
    Ok(JointLog {
        skeleton_kind: SkeletonKind::KinectV2,
        frames: out,
    })
}
