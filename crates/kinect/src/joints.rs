//! Joint dumps and logs: `symcorr.joints/1` JSON (read and write), Kinect SDK v1 text dumps and
//! NTU RGB+D `.skeleton` files, all turned into a [`JointLog`] of canonical [`Skeleton`]s.
//!
//! ```
//! use symcorr_kinect::joints::{parse_joints, JointFormat, JointLog, JointFrame, to_json_string};
//! use symcorr_skeleton::Skeleton;
//! let mut positions = [[0.0; 3]; 20];
//! for (i, p) in positions.iter_mut().enumerate() { *p = [0.01 * i as f64, 1.0, 2.5]; }
//! let log = JointLog::from_skeletons(vec![Skeleton::from_arrays(positions)], 30.0);
//! let text = to_json_string(&log);
//! let (back, format) = parse_joints(&text, "<memory>").unwrap();
//! assert_eq!(format, JointFormat::Json);
//! assert_eq!(back.frames[0].skeleton, log.frames[0].skeleton);
//! ```

use crate::error::KinectError;
use crate::mapping::{normalise_name, Partial, SkeletonKind, KINECT_V2_NECK};
use serde::ser::{SerializeMap, SerializeSeq};
use serde::{Serialize, Serializer};
use serde_json::Value;
use std::path::Path;
use symcorr_skeleton::{Joint, Skeleton};

/// The `format` tag of the native joint file.
pub const JOINTS_FORMAT: &str = "symcorr.joints/1";

/// Frame rate assumed for formats without timestamps (Kinect v1 and v2 run at 30 Hz).
pub const KINECT_FPS: f64 = 30.0;

/// One frame of a joint log.
#[derive(Debug, Clone, PartialEq)]
pub struct JointFrame {
    /// Time of the frame in seconds from the start of the log.
    pub time_s: f64,
    /// The canonical skeleton, metres, Kinect camera space.
    pub skeleton: Skeleton,
}

/// A sequence of frames of one tracked body, mapped onto the canonical 20-joint skeleton.
/// Positions are always in metres (files in millimetres are converted on reading).
#[derive(Debug, Clone, PartialEq)]
pub struct JointLog {
    /// The skeleton the source tracker reported (before mapping to the canonical one).
    pub skeleton_kind: SkeletonKind,
    /// The frames in file order.
    pub frames: Vec<JointFrame>,
}

impl JointLog {
    /// A Kinect v1 log from skeletons sampled at `fps` frames per second.
    pub fn from_skeletons(skeletons: Vec<Skeleton>, fps: f64) -> JointLog {
        JointLog {
            skeleton_kind: SkeletonKind::KinectV1,
            frames: skeletons
                .into_iter()
                .enumerate()
                .map(|(i, skeleton)| JointFrame {
                    time_s: i as f64 / fps,
                    skeleton,
                })
                .collect(),
        }
    }
}

/// A joint file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JointFormat {
    /// `symcorr.joints/1` JSON (skeleton `kinect_v1`, `nite` or `kinect_v2`).
    Json,
    /// Kinect SDK v1 text: `frame x1 y1 z1 … x20 y20 z20` per line.
    KinectText,
    /// NTU RGB+D `.skeleton` (Kinect v2, 25 joints, several bodies per frame).
    NtuSkeleton,
}

impl JointFormat {
    /// Parses a `--joints-format` value: `json`, `kinect-text` (or `kinect_text`, `text`),
    /// `ntu` (or `skeleton`).
    pub fn from_name(name: &str) -> Option<JointFormat> {
        match name.to_ascii_lowercase().replace('_', "-").as_str() {
            "json" | "symcorr" | "symcorr.joints/1" => Some(JointFormat::Json),
            "kinect-text" | "text" | "kinect-v1-text" | "sdk" => Some(JointFormat::KinectText),
            "ntu" | "skeleton" | "ntu-skeleton" => Some(JointFormat::NtuSkeleton),
            _ => None,
        }
    }

    /// Recognises the format from the content: JSON starts with `{`; a Kinect text dump has 61
    /// numbers on its first data line; an NTU file starts with a single integer (frame count).
    pub fn detect(text: &str) -> Option<JointFormat> {
        let trimmed = text.trim_start_matches('\u{feff}').trim_start();
        if trimmed.starts_with('{') {
            return Some(JointFormat::Json);
        }
        let first = trimmed
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'))?;
        let n = crate::sdk_text::tokens(first).count();
        match n {
            61 => Some(JointFormat::KinectText),
            1 if first.parse::<u64>().is_ok() => Some(JointFormat::NtuSkeleton),
            _ => None,
        }
    }
}

/// Which body of a multi-body NTU file to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BodySelect {
    /// The body with the most tracked joints summed over the file.
    #[default]
    MostTracked,
    /// The body with this tracking id.
    Id(u64),
}

/// Reads a joint file, recognising its format from the content ([`JointFormat::detect`]).
/// NTU files keep the most-tracked body.
pub fn read_joints(path: impl AsRef<Path>) -> Result<JointLog, KinectError> {
    let (text, file) = read_text(path.as_ref())?;
    parse_joints(&text, &file).map(|(log, _)| log)
}

/// Reads a joint file in the given format (the `--joints-format` override).
pub fn read_joints_with_format(
    path: impl AsRef<Path>,
    format: JointFormat,
) -> Result<JointLog, KinectError> {
    let (text, file) = read_text(path.as_ref())?;
    parse_joints_as(&text, &file, format, BodySelect::MostTracked)
}

/// Reads an NTU RGB+D `.skeleton` file keeping the selected body.
pub fn read_ntu_skeleton(
    path: impl AsRef<Path>,
    body: BodySelect,
) -> Result<JointLog, KinectError> {
    let (text, file) = read_text(path.as_ref())?;
    crate::ntu::parse_ntu(&text, &file, body)
}

/// Parses joint-file text whose format is recognised from the content; `file` names it in errors.
pub fn parse_joints(text: &str, file: &str) -> Result<(JointLog, JointFormat), KinectError> {
    let format = JointFormat::detect(text).ok_or_else(|| KinectError::UnknownFormat {
        file: file.to_string(),
        message: "expected symcorr.joints/1 JSON, a Kinect SDK text dump (61 values per line) \
                  or an NTU .skeleton file"
            .to_string(),
    })?;
    parse_joints_as(text, file, format, BodySelect::MostTracked).map(|log| (log, format))
}

/// Parses joint-file text in a given format.
pub fn parse_joints_as(
    text: &str,
    file: &str,
    format: JointFormat,
    body: BodySelect,
) -> Result<JointLog, KinectError> {
    match format {
        JointFormat::Json => parse_joints_json(text, file),
        JointFormat::KinectText => crate::sdk_text::parse_kinect_text(text, file),
        JointFormat::NtuSkeleton => crate::ntu::parse_ntu(text, file, body),
    }
}

fn read_text(path: &Path) -> Result<(String, String), KinectError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| KinectError::io(&file, e))?;
    let text = String::from_utf8(bytes).map_err(|e| KinectError::UnknownFormat {
        file: file.clone(),
        message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
    })?;
    Ok((text, file))
}

/// Parses `symcorr.joints/1` JSON.
pub fn parse_joints_json(text: &str, file: &str) -> Result<JointLog, KinectError> {
    let json_err = |message: String| KinectError::Json {
        file: file.to_string(),
        message,
    };
    let root: Value = serde_json::from_str(text.trim_start_matches('\u{feff}'))
        .map_err(|e| json_err(format!("invalid JSON: {e}")))?;
    let obj = root
        .as_object()
        .ok_or_else(|| json_err("expected a JSON object at the top level".into()))?;
    match obj.get("format").and_then(Value::as_str) {
        Some(JOINTS_FORMAT) => {}
        Some(other) => {
            return Err(json_err(format!(
                "format is {other:?}, expected {JOINTS_FORMAT:?}"
            )))
        }
        None => return Err(json_err(format!("missing \"format\": {JOINTS_FORMAT:?}"))),
    }
    let kind_name = obj
        .get("skeleton")
        .and_then(Value::as_str)
        .ok_or_else(|| json_err("missing \"skeleton\" (a string)".into()))?;
    let kind = SkeletonKind::from_name(kind_name).ok_or_else(|| KinectError::UnknownSkeleton {
        file: file.to_string(),
        name: kind_name.to_string(),
    })?;
    let unit_scale = match obj.get("units") {
        None => 1.0,
        Some(Value::String(u)) if u == "m" => 1.0,
        Some(Value::String(u)) if u == "mm" => 0.001,
        Some(u) => return Err(json_err(format!("units is {u}, expected \"m\" or \"mm\""))),
    };
    let frames = obj
        .get("frames")
        .and_then(Value::as_array)
        .ok_or_else(|| json_err("missing \"frames\" (an array)".into()))?;
    if frames.is_empty() {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: "the joint file has no frames".into(),
        });
    }
    let names = kind.joint_names();
    let mut out = Vec::with_capacity(frames.len());
    for (fi, frame) in frames.iter().enumerate() {
        let ferr = |message: String| KinectError::Frame {
            file: file.to_string(),
            frame: fi,
            message,
        };
        let fobj = frame
            .as_object()
            .ok_or_else(|| ferr("expected an object".into()))?;
        let time_s = match fobj.get("time_s") {
            None => fi as f64 / KINECT_FPS,
            Some(t) => t
                .as_f64()
                .filter(|t| t.is_finite())
                .ok_or_else(|| ferr(format!("time_s is {t}, expected a number")))?,
        };
        let joints = fobj
            .get("joints")
            .and_then(Value::as_object)
            .ok_or_else(|| ferr("missing \"joints\" (an object)".into()))?;
        // Native index → (position, confidence).
        let mut native: Vec<Option<[f64; 3]>> = vec![None; names.len()];
        for (name, value) in joints {
            let norm = normalise_name(name);
            let idx = names.iter().position(|n| *n == norm).ok_or_else(|| {
                ferr(format!(
                    "unknown joint {name:?} for skeleton {:?}",
                    kind.name()
                ))
            })?;
            let arr = value
                .as_array()
                .filter(|a| a.len() == 3)
                .ok_or_else(|| ferr(format!("joint {name:?}: expected [x, y, z]")))?;
            let mut p = [0.0; 3];
            for (k, v) in arr.iter().enumerate() {
                p[k] = v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                    ferr(format!(
                        "joint {name:?}: coordinate {v} is not a finite number"
                    ))
                })? * unit_scale;
            }
            native[idx] = Some(p);
        }
        let mut conf: Vec<f64> = vec![1.0; names.len()];
        if let Some(c) = fobj.get("confidence") {
            let cobj = c
                .as_object()
                .ok_or_else(|| ferr("\"confidence\" must be an object".into()))?;
            for (name, value) in cobj {
                let norm = normalise_name(name);
                let idx = names
                    .iter()
                    .position(|n| *n == norm)
                    .ok_or_else(|| ferr(format!("confidence for unknown joint {name:?}")))?;
                conf[idx] = value
                    .as_f64()
                    .filter(|c| (0.0..=1.0).contains(c))
                    .ok_or_else(|| {
                        ferr(format!(
                            "confidence of {name:?} is {value}, expected a number in [0, 1]"
                        ))
                    })?;
            }
        }
        let mut flagged = [false; 20];
        if let Some(list) = fobj.get("interpolated") {
            let arr = list
                .as_array()
                .ok_or_else(|| ferr("\"interpolated\" must be an array of joint names".into()))?;
            for v in arr {
                let j = v
                    .as_str()
                    .and_then(|s| Joint::from_name(&normalise_name(s)))
                    .ok_or_else(|| {
                        ferr(format!("interpolated: {v} is not a kinect_v1 joint name"))
                    })?;
                flagged[j.index()] = true;
            }
        }
        let mut partial = Partial::new();
        for (idx, p) in native.iter().enumerate() {
            if let (Some(p), Some(j)) = (p, kind.canonical(idx)) {
                partial.set(j, (*p).into(), conf[idx]);
            }
        }
        if kind == SkeletonKind::KinectV2
            && partial.positions[Joint::ShoulderCenter.index()].is_none()
        {
            if let Some(p) = native[KINECT_V2_NECK] {
                partial.set(Joint::ShoulderCenter, p.into(), conf[KINECT_V2_NECK]);
            }
        }
        if kind == SkeletonKind::KinectV1 {
            if let Some(j) = Joint::ALL
                .into_iter()
                .find(|j| partial.positions[j.index()].is_none())
            {
                return Err(ferr(format!("missing joint {:?}", j.name())));
            }
        }
        let mut skeleton = partial.complete().map_err(|j| {
            ferr(format!(
                "missing joint {:?} cannot be interpolated (or its estimate is not finite)",
                j.name()
            ))
        })?;
        for (i, f) in flagged.iter().enumerate() {
            skeleton.interpolated[i] |= *f;
        }
        out.push(JointFrame { time_s, skeleton });
    }
    Ok(JointLog {
        skeleton_kind: kind,
        frames: out,
    })
}

/// The `symcorr.joints/1` text of a log: skeleton `kinect_v1` (the canonical joints), units `m`,
/// joints in SDK order, an `interpolated` list of joint names per frame when any joint is.
pub fn to_json_string(log: &JointLog) -> String {
    // Serialising plain numbers, strings and maps cannot fail.
    serde_json::to_string(&LogOut(log)).unwrap_or_default()
}

/// Writes a log as `symcorr.joints/1` (see [`to_json_string`]), atomically: a temporary file in
/// the same directory, then a rename, so a failure never leaves a half-written file.
pub fn write_joints_json(path: impl AsRef<Path>, log: &JointLog) -> Result<(), KinectError> {
    crate::atomic_write(path.as_ref(), to_json_string(log).as_bytes())
}

struct LogOut<'a>(&'a JointLog);
struct FrameOut<'a>(&'a JointFrame);
struct JointsOut<'a>(&'a Skeleton);
struct ConfOut<'a>(&'a Skeleton);
struct InterpOut<'a>(&'a Skeleton);

impl Serialize for LogOut<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(4))?;
        m.serialize_entry("format", JOINTS_FORMAT)?;
        m.serialize_entry("skeleton", SkeletonKind::KinectV1.name())?;
        m.serialize_entry("units", "m")?;
        let frames: Vec<FrameOut> = self.0.frames.iter().map(FrameOut).collect();
        m.serialize_entry("frames", &frames)?;
        m.end()
    }
}

impl Serialize for FrameOut<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let sk = &self.0.skeleton;
        let any = sk.interpolated.iter().any(|&b| b);
        let mut m = s.serialize_map(Some(if any { 4 } else { 3 }))?;
        m.serialize_entry("time_s", &self.0.time_s)?;
        m.serialize_entry("joints", &JointsOut(sk))?;
        m.serialize_entry("confidence", &ConfOut(sk))?;
        if any {
            m.serialize_entry("interpolated", &InterpOut(sk))?;
        }
        m.end()
    }
}

impl Serialize for JointsOut<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(20))?;
        for j in Joint::ALL {
            m.serialize_entry(j.name(), &<[f64; 3]>::from(self.0.positions[j.index()]))?;
        }
        m.end()
    }
}

impl Serialize for ConfOut<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(20))?;
        for j in Joint::ALL {
            m.serialize_entry(j.name(), &self.0.confidence[j.index()])?;
        }
        m.end()
    }
}

impl Serialize for InterpOut<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let list: Vec<&str> = Joint::ALL
            .into_iter()
            .filter(|j| self.0.interpolated[j.index()])
            .map(Joint::name)
            .collect();
        let mut q = s.serialize_seq(Some(list.len()))?;
        for n in list {
            q.serialize_element(n)?;
        }
        q.end()
    }
}
