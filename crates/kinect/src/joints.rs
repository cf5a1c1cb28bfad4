//! Joint dumps and logs: `symcorr.joints/1` JSON (read and write), Kinect SDK v1 text dumps,
//! NTU RGB+D `.skeleton` files and Azure Kinect body tracking JSON, all turned into a
//! [`JointLog`] of canonical [`Skeleton`]s.
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
use nalgebra::Point3;
use serde::de::{self, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::error::Category;
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
    /// Azure Kinect Body Tracking JSON (`k4abt`, 32 joints, several bodies per frame;
    /// [`crate::k4abt`]).
    AzureKinect,
}

impl JointFormat {
    /// Parses a `--joints-format` value: `json`, `kinect-text` (or `kinect_text`, `text`),
    /// `ntu` (or `skeleton`), `k4abt` (or `azure-kinect`).
    pub fn from_name(name: &str) -> Option<JointFormat> {
        match name.to_ascii_lowercase().replace('_', "-").as_str() {
            "json" | "symcorr" | "symcorr.joints/1" => Some(JointFormat::Json),
            "kinect-text" | "text" | "kinect-v1-text" | "sdk" => Some(JointFormat::KinectText),
            "ntu" | "skeleton" | "ntu-skeleton" => Some(JointFormat::NtuSkeleton),
            "k4abt" | "azure-kinect" | "azure" => Some(JointFormat::AzureKinect),
            _ => None,
        }
    }

    /// Recognises the format from the content: JSON starts with `{` (Azure Kinect's when it has
    /// the key `"k4abt_sdk_version"` or `"joint_positions"`, else `symcorr.joints/1`); a Kinect
    /// text dump has 61 numbers on its first data line; an NTU file starts with a single integer
    /// (frame count).
    /// [`JointFormat::detect_with_reason`] also says why nothing matched.
    pub fn detect(text: &str) -> Option<JointFormat> {
        JointFormat::detect_with_reason(text).ok()
    }

    /// [`JointFormat::detect`], or, when no format matches, one line saying what was tried and
    /// why each failed (quoting at most [`QUOTE_CHARS`] characters of the first data line).
    ///
    /// ```
    /// use symcorr_kinect::JointFormat;
    /// assert_eq!(JointFormat::detect_with_reason("3\n"), Ok(JointFormat::NtuSkeleton));
    /// let why = JointFormat::detect_with_reason("1 2.5 3\n").unwrap_err();
    /// assert_eq!(
    ///     why,
    ///     "not JSON (starts with `1`, not `{`), not a Kinect SDK text log (first line \
    ///      `1 2.5 3` has 3 fields, expected 61), not an NTU .skeleton file (first line has 3 \
    ///      fields, expected the frame count alone)"
    /// );
    /// ```
    pub fn detect_with_reason(text: &str) -> Result<JointFormat, String> {
        let trimmed = text.trim_start_matches('\u{feff}').trim_start();
        let Some(c) = trimmed.chars().next() else {
            return Err("the file is empty (or only white space)".into());
        };
        if c == '{' {
            return Ok(
                if crate::k4abt::K4ABT_KEYS.iter().any(|k| trimmed.contains(k)) {
                    JointFormat::AzureKinect
                } else {
                    JointFormat::Json
                },
            );
        }
        let not_json = format!("not JSON (starts with `{}`, not `{{`)", c.escape_debug());
        let Some(first) = trimmed
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'))
        else {
            return Err("the file has only blank lines and # comments".into());
        };
        let n = crate::sdk_text::tokens(first).count();
        match n {
            61 => return Ok(JointFormat::KinectText),
            1 if first.parse::<u64>().is_ok() => return Ok(JointFormat::NtuSkeleton),
            _ => {}
        }
        let ntu = if n == 1 {
            "the first line is not a frame count, a non-negative integer".to_string()
        } else {
            format!("first line has {n} fields, expected the frame count alone")
        };
        Err(format!(
            "{not_json}, not a Kinect SDK text log (first line `{}` has {n} field{}, expected 61), \
             not an NTU .skeleton file ({ntu})",
            quote(first),
            if n == 1 { "" } else { "s" }
        ))
    }
}

/// Most characters of a line that [`JointFormat::detect_with_reason`] quotes (escapes included).
pub const QUOTE_CHARS: usize = 40;

/// The start of `line`, control characters escaped (`\t`, `\u{1d}`), at most [`QUOTE_CHARS`]
/// characters in all, then `…` if cut.
pub(crate) fn quote(line: &str) -> String {
    let mut out = String::new();
    let mut len = 0;
    for c in line.chars() {
        let piece: String = if c.is_control() {
            c.escape_debug().collect()
        } else {
            c.to_string()
        };
        let n = piece.chars().count();
        if len + n > QUOTE_CHARS {
            out.push('…');
            break;
        }
        out.push_str(&piece);
        len += n;
    }
    out
}

/// Which body of a multi-body file (NTU, Azure Kinect) to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BodySelect {
    /// The body with the most tracked joints summed over the file.
    #[default]
    MostTracked,
    /// The body with this tracking id.
    Id(u64),
}

/// [`BodySelect::MostTracked`] over a multi-body file: from `(body id, tracked joints)` per
/// body per frame, the id with the most tracked joints summed over the file, the first seen on
/// a tie; `None` without bodies.
pub(crate) fn most_tracked(bodies: impl Iterator<Item = (u64, usize)>) -> Option<u64> {
    // (id, sum), in order of first appearance.
    let mut score: Vec<(u64, usize)> = Vec::new();
    for (id, tracked) in bodies {
        match score.iter_mut().find(|s| s.0 == id) {
            Some(s) => s.1 += tracked,
            None => score.push((id, tracked)),
        }
    }
    score
        .iter()
        .fold(None::<(u64, usize)>, |best, s| match best {
            Some(b) if b.1 >= s.1 => Some(b),
            _ => Some(*s),
        })
        .map(|(id, _)| id)
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
///
/// Errors: [`KinectError::UnknownFormat`] (one line: what was tried and why each failed, see
/// [`JointFormat::detect_with_reason`]) or the error of the recognised format's parser.
pub fn parse_joints(text: &str, file: &str) -> Result<(JointLog, JointFormat), KinectError> {
    let format =
        JointFormat::detect_with_reason(text).map_err(|message| KinectError::UnknownFormat {
            file: file.to_string(),
            message,
        })?;
    parse_joints_as(text, file, format, BodySelect::MostTracked).map(|log| (log, format))
}

/// Parses joint-file text in a given format. A log in which no frame tracks a joint (every
/// joint untracked, as when the tracker never saw a body) is [`KinectError::NoBody`].
pub fn parse_joints_as(
    text: &str,
    file: &str,
    format: JointFormat,
    body: BodySelect,
) -> Result<JointLog, KinectError> {
    let log = match format {
        JointFormat::Json => parse_joints_json(text, file),
        JointFormat::KinectText => crate::sdk_text::parse_kinect_text(text, file),
        JointFormat::NtuSkeleton => crate::ntu::parse_ntu(text, file, body),
        JointFormat::AzureKinect => crate::k4abt::parse_k4abt(text, file, body),
    }?;
    if !log.frames.iter().any(|f| f.skeleton.tracks_any()) {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: format!(
                "no frame of the {} tracks a joint (every confidence is 0)",
                log.frames.len()
            ),
        });
    }
    Ok(log)
}

fn read_text(path: &Path) -> Result<(String, String), KinectError> {
    crate::error::read_input_text(path, |file, message| KinectError::UnknownFormat {
        file,
        message,
    })
}

/// The `symcorr.joints/1` file as written (`F` = [`FrameFile`]) and as read (`F` = a frame not
/// yet checked, so that an error in it names its frame).
#[derive(Debug, Serialize, Deserialize)]
struct JointsFile<F> {
    format: Option<String>,
    skeleton: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    units: Option<String>,
    frames: Option<Vec<F>>,
}

/// One frame of a `symcorr.joints/1` file, joint names as in the file.
#[derive(Debug, Serialize, Deserialize)]
struct FrameFile {
    #[serde(
        default,
        deserialize_with = "some_number",
        skip_serializing_if = "Option::is_none"
    )]
    time_s: Option<f64>,
    joints: Option<Named<[f64; 3]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    confidence: Option<Named<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    interpolated: Option<Vec<String>>,
    /// [`Skeleton::head_turn`] (radians, so that it reads back exactly), when the tracker
    /// reported it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    head_turn_rad: Option<f64>,
}

/// `time_s` is optional, but `null` is not a time.
fn some_number<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    f64::deserialize(d)
        .map(Some)
        .map_err(|e| de::Error::custom(format!("time_s: {e}")))
}

/// A JSON object kept as `(name, value)` pairs in file order (written in that order too: the
/// joints in SDK order). An error in a value names its key.
#[derive(Debug)]
struct Named<T>(Vec<(String, T)>);

/// What a value of a [`Named`] object is, for error messages.
trait Entry {
    const WHAT: &'static str;
}

impl Entry for [f64; 3] {
    const WHAT: &'static str = "joint";
}

impl Entry for f64 {
    const WHAT: &'static str = "confidence of";
}

impl<T: Serialize> Serialize for Named<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<'de, T: Deserialize<'de> + Entry> Deserialize<'de> for Named<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Entry> Visitor<'de> for V<T> {
            type Value = Named<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Named<T>, A::Error> {
                let mut out = Vec::new();
                while let Some(k) = map.next_key::<String>()? {
                    let v = map
                        .next_value::<T>()
                        .map_err(|e| de::Error::custom(format!("{} {k:?}: {e}", T::WHAT)))?;
                    out.push((k, v));
                }
                Ok(Named(out))
            }
        }
        d.deserialize_map(V(std::marker::PhantomData))
    }
}

/// Parses `symcorr.joints/1` JSON.
pub fn parse_joints_json(text: &str, file: &str) -> Result<JointLog, KinectError> {
    let json_err = |message: String| KinectError::Json {
        file: file.to_string(),
        message,
    };
    let text = text.trim_start_matches('\u{feff}');
    // Two passes: the header and the shape of the file first (the frames skipped), then each
    // frame checked and converted as soon as it is parsed (`FrameSeq`), so that a long log
    // never exists as one JSON tree (tens of bytes of tree per byte of text).
    let root: JointsFile<de::IgnoredAny> = serde_json::from_str(text).map_err(|e| {
        json_err(match e.classify() {
            // serde would also read a struct from an array.
            Category::Data if !text.trim_start().starts_with('{') => {
                "expected a JSON object at the top level".into()
            }
            Category::Data => format!("not a symcorr.joints/1 file: {e}"),
            _ => format!("invalid JSON: {e}"),
        })
    })?;
    match root.format.as_deref() {
        Some(JOINTS_FORMAT) => {}
        Some(other) => {
            return Err(json_err(format!(
                "format is {other:?}, expected {JOINTS_FORMAT:?}"
            )))
        }
        None => return Err(json_err(format!("missing \"format\": {JOINTS_FORMAT:?}"))),
    }
    let kind_name = root
        .skeleton
        .ok_or_else(|| json_err("missing \"skeleton\" (a string)".into()))?;
    let kind = SkeletonKind::from_name(&kind_name).ok_or_else(|| KinectError::UnknownSkeleton {
        file: file.to_string(),
        name: kind_name.clone(),
    })?;
    let unit_scale = match root.units.as_deref() {
        None | Some("m") => 1.0,
        Some("mm") => 0.001,
        Some(u) => {
            return Err(json_err(format!(
                "units is {u:?}, expected \"m\" or \"mm\""
            )))
        }
    };
    let count = root
        .frames
        .ok_or_else(|| json_err("missing \"frames\" (an array)".into()))?
        .len();
    if count == 0 {
        return Err(KinectError::NoBody {
            file: file.to_string(),
            message: "the joint file has no frames".into(),
        });
    }
    // Not `with_capacity(count)`: a hostile file of tiny non-frames would ask for hundreds of
    // bytes per byte of text; the first of them stops the second pass instead.
    let mut frames = Vec::new();
    let mut failed = None;
    let reader = RootFrames(FrameSeq {
        kind,
        unit_scale,
        out: &mut frames,
        failed: &mut failed,
    });
    let parsed = reader.deserialize(&mut serde_json::Deserializer::from_str(text));
    if let Some((frame, message)) = failed {
        return Err(KinectError::Frame {
            file: file.to_string(),
            frame,
            message,
        });
    }
    // The first pass read the same text without error.
    parsed.map_err(|e| json_err(format!("invalid JSON: {e}")))?;
    Ok(JointLog {
        skeleton_kind: kind,
        frames,
    })
}

/// The `frames` array of a `symcorr.joints/1` file, every other key skipped
/// ([`parse_joints_json`]'s second pass).
struct RootFrames<'a>(FrameSeq<'a>);

impl<'de> DeserializeSeed<'de> for RootFrames<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for RootFrames<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a symcorr.joints/1 object")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let mut seq = Some(self.0);
        while let Some(key) = map.next_key::<String>()? {
            match (key.as_str(), seq.take()) {
                ("frames", Some(frames)) => map.next_value_seed(frames)?,
                (_, rest) => {
                    seq = rest;
                    map.next_value::<de::IgnoredAny>()?;
                }
            }
        }
        Ok(())
    }
}

/// The frames of a `symcorr.joints/1` file, each checked and converted ([`frame_from_json`])
/// as soon as it is parsed; the first bad frame stops the parse and is kept in `failed` as
/// (frame index, message).
struct FrameSeq<'a> {
    kind: SkeletonKind,
    unit_scale: f64,
    out: &'a mut Vec<JointFrame>,
    failed: &'a mut Option<(usize, String)>,
}

impl<'de> DeserializeSeed<'de> for FrameSeq<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for FrameSeq<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("an array of frames")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while let Some(frame) = seq.next_element::<serde_json::Value>()? {
            let fi = self.out.len();
            match frame_from_json(frame, fi, self.kind, self.unit_scale) {
                Ok(f) => self.out.push(f),
                Err(message) => {
                    *self.failed = Some((fi, message));
                    return Err(de::Error::custom("a bad frame"));
                }
            }
        }
        Ok(())
    }
}

/// Frame `fi` of a `symcorr.joints/1` file on the canonical skeleton; the error is the message.
fn frame_from_json(
    frame: serde_json::Value,
    fi: usize,
    kind: SkeletonKind,
    unit_scale: f64,
) -> Result<JointFrame, String> {
    if !frame.is_object() {
        // serde would also read a struct from an array.
        return Err("expected an object".into());
    }
    let frame = FrameFile::deserialize(frame).map_err(|e| e.to_string())?;
    let names = kind.joint_names();
    let native_index = |name: &str| {
        let norm = normalise_name(name);
        names.iter().position(|n| *n == norm)
    };
    let time_s = match frame.time_s {
        None => fi as f64 / KINECT_FPS,
        Some(t) if t.is_finite() => t,
        Some(t) => return Err(format!("time_s is {t}, expected a number")),
    };
    let joints = frame
        .joints
        .ok_or_else(|| "missing \"joints\" (an object)".to_string())?;
    // Native index → position.
    let mut native: Vec<Option<Point3<f64>>> = vec![None; names.len()];
    for (name, p) in joints.0 {
        let idx = native_index(&name)
            .ok_or_else(|| format!("unknown joint {name:?} for skeleton {:?}", kind.name()))?;
        if let Some(v) = p.iter().find(|x| !x.is_finite()) {
            return Err(format!(
                "joint {name:?}: coordinate {v} is not a finite number"
            ));
        }
        native[idx] = Some(Point3::from(p) * unit_scale);
    }
    let mut conf: Vec<f64> = vec![1.0; names.len()];
    for (name, c) in frame.confidence.map_or_else(Vec::new, |c| c.0) {
        let idx =
            native_index(&name).ok_or_else(|| format!("confidence for unknown joint {name:?}"))?;
        if !(0.0..=1.0).contains(&c) {
            return Err(format!(
                "confidence of {name:?} is {c}, expected a number in [0, 1]"
            ));
        }
        conf[idx] = c;
    }
    let mut flagged = [false; Joint::COUNT];
    for name in frame.interpolated.unwrap_or_default() {
        let j = Joint::from_name(&normalise_name(&name))
            .ok_or_else(|| format!("interpolated: {name:?} is not a kinect_v1 joint name"))?;
        flagged[j.index()] = true;
    }
    let mut partial = Partial::new();
    for (idx, p) in native.iter().enumerate() {
        if let (Some(p), Some(j)) = (p, kind.canonical(idx)) {
            partial.set(j, *p, conf[idx]);
        }
    }
    if kind == SkeletonKind::KinectV2 && partial.positions[Joint::ShoulderCenter.index()].is_none()
    {
        if let Some(p) = native[KINECT_V2_NECK] {
            partial.set(Joint::ShoulderCenter, p, conf[KINECT_V2_NECK]);
        }
    }
    if kind == SkeletonKind::KinectV1 {
        if let Some(j) = Joint::ALL
            .into_iter()
            .find(|j| partial.positions[j.index()].is_none())
        {
            return Err(format!("missing joint {:?}", j.name()));
        }
    }
    let mut skeleton = partial.complete().map_err(|j| {
        format!(
            "joint {:?}: its estimate from its neighbours is not a finite position",
            j.name()
        )
    })?;
    for (i, f) in flagged.iter().enumerate() {
        skeleton.interpolated[i] |= *f;
    }
    if let Some(turn) = frame.head_turn_rad {
        if !(turn.is_finite() && turn.abs() <= std::f64::consts::FRAC_PI_2) {
            return Err(format!(
                "head_turn_rad is {turn}, expected a number in [-π/2, π/2]"
            ));
        }
        skeleton.head_turn = Some(turn);
    }
    Ok(JointFrame { time_s, skeleton })
}

/// The `symcorr.joints/1` text of a log: skeleton `kinect_v1` (the canonical joints), units `m`,
/// joints in SDK order, an `interpolated` list of joint names per frame when any joint is, and
/// `head_turn_rad` when the frame reports the head's turn ([`Skeleton::head_turn`]).
pub fn to_json_string(log: &JointLog) -> String {
    let named =
        |f: &dyn Fn(Joint) -> f64| Named(Joint::ALL.map(|j| (j.name().to_string(), f(j))).to_vec());
    let file = JointsFile {
        format: Some(JOINTS_FORMAT.to_string()),
        skeleton: Some(SkeletonKind::KinectV1.name().to_string()),
        units: Some("m".to_string()),
        frames: Some(
            log.frames
                .iter()
                .map(|f| {
                    let sk = &f.skeleton;
                    let interpolated: Vec<String> = Joint::ALL
                        .into_iter()
                        .filter(|j| sk.interpolated[j.index()])
                        .map(|j| j.name().to_string())
                        .collect();
                    FrameFile {
                        time_s: Some(f.time_s),
                        joints: Some(Named(
                            Joint::ALL
                                .map(|j| (j.name().to_string(), sk.positions[j.index()].into()))
                                .to_vec(),
                        )),
                        confidence: Some(named(&|j| sk.confidence[j.index()])),
                        interpolated: (!interpolated.is_empty()).then_some(interpolated),
                        head_turn_rad: sk.head_turn,
                    }
                })
                .collect(),
        ),
    };
    // Serialising plain numbers, strings and maps cannot fail.
    serde_json::to_string(&file).unwrap_or_default()
}

/// Writes a log as `symcorr.joints/1` (see [`to_json_string`]), atomically: a temporary file in
/// the same directory, then a rename, so a failure never leaves a half-written file.
pub fn write_joints_json(path: impl AsRef<Path>, log: &JointLog) -> Result<(), KinectError> {
    crate::atomic_write(path.as_ref(), to_json_string(log).as_bytes())
}
