//! OpenNI2 `.oni` recordings as a sequence of timed depth frames ([`OniRecording`], feature
//! `openni2`), the counterpart of a recording folder ([`crate::Recording`]) for
//! [`crate::DepthSource`].
//!
//! # Where each part comes from
//!
//! * **Frames and times** — [`OniRecording::open`] walks the file's records once (headers only,
//!   in Rust, no frame is decoded) and keeps, for every depth frame in file order, its
//!   timestamp: microseconds in the file, seconds here (`t_us / 10⁶`; OpenNI2's recorder writes
//!   the first frame at 0). The file's own index is used, not a playback pass, because playback
//!   can deliver nothing at all (below) and a time is wanted for every frame, read or not.
//! * **Intrinsics** — from the depth stream's video mode and field of view as OpenNI2 reports
//!   them ([`Intrinsics::from_field_of_view`]: `fx = width / (2·tan(hfov/2))`, principal point
//!   at the image centre); a recording without a field of view (OpenNI2's Dummy device) gets
//!   the nominal Kinect v1 focal length scaled to its width.
//! * **Depth images** — OpenNI2's own file player ([`FilePlayback`], manual playback), read
//!   forward: frame `i` is the next frame the player hands over whose timestamp is frame `i`'s.
//!   Asking for an earlier frame than the last one read reopens the file and reads forward from
//!   its start (OniFile's seek blocks forever when it fails, so it is never used). Only the
//!   current frame is in memory.
//!
//! Debian's OpenNI 2.2 plays no frame of a recording made from its Dummy device (its file
//! player drops every frame of a recording without a cropping property; see
//! [`crate::openni2`]). Such a recording still opens, with its frame count, times and
//! intrinsics; reading a frame waits [`FRAME_TIMEOUT_MS`] once, then every frame is refused
//! at once with [`KinectError::Recording`] saying that the player delivers no frame.
//!
//! ```no_run
//! # fn main() -> Result<(), symcorr_kinect::KinectError> {
//! use symcorr_kinect::oni::OniRecording;
//! let mut rec = OniRecording::open("session.oni")?;
//! println!("{} frames, the last at {:?} s", rec.len(), rec.time(rec.len() - 1));
//! let depth = rec.frame(0)?; // millimetres, the size of rec.intrinsics()
//! # let _ = depth; Ok(()) }
//! ```

use crate::camera::Intrinsics;
use crate::depth::DepthFrame;
use crate::error::KinectError;
use crate::openni2::{FilePlayback, StampedDepth, STATUS_TIME_OUT};
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// How long [`OniRecording::frame`] waits for OpenNI2's file player to hand over a frame.
pub const FRAME_TIMEOUT_MS: i32 = 5000;

/// An `.oni` recording (see the [module docs](self)): its depth frames' times and the camera's
/// intrinsics, read at opening; the frames on demand, in increasing order.
#[derive(Debug)]
pub struct OniRecording {
    path: PathBuf,
    intrinsics: Intrinsics,
    /// Every depth frame's timestamp in the file, microseconds, strictly increasing.
    stamps_us: Vec<u64>,
    times_s: Vec<f64>,
    player: Option<Player>,
    /// Set once the player has handed over no frame at all: later reads fail at once with it.
    stalled: Option<String>,
}

/// The file player and what it handed over last.
#[derive(Debug)]
struct Player {
    playback: FilePlayback,
    /// The last frame read and not yet returned (read past a frame that never came).
    pending: Option<StampedDepth>,
    /// Timestamp of the last frame the player handed over, `None` before the first.
    last_us: Option<u64>,
}

impl OniRecording {
    /// Opens an `.oni` file: indexes its depth frames (times) and opens OpenNI2's file player
    /// for the video mode and field of view (intrinsics).
    ///
    /// Errors: [`KinectError::Io`] (missing, unreadable); [`KinectError::Recording`] naming the
    /// file (not an `.oni` file, no depth stream, no depth frame, timestamps that do not
    /// increase); [`KinectError::OpenNi`] from OpenNI2.
    pub fn open(path: impl AsRef<Path>) -> Result<OniRecording, KinectError> {
        let path = path.as_ref().to_path_buf();
        let stamps_us = index_depth_frames(&path)?;
        let playback = FilePlayback::open(&path)?;
        let mode = playback.stream().video_mode()?;
        let (width, height) = match (u32::try_from(mode.width), u32::try_from(mode.height)) {
            (Ok(w), Ok(h)) if w > 0 && h > 0 => (w, h),
            _ => {
                return Err(rec_err(
                    &path,
                    format!("depth video mode {}x{}", mode.width, mode.height),
                ))
            }
        };
        let fov = playback
            .stream()
            .field_of_view()
            .map(|(h, v)| (f64::from(h), f64::from(v)));
        let intrinsics = Intrinsics::from_field_of_view(width, height, fov);
        intrinsics.validate()?;
        Ok(OniRecording {
            times_s: stamps_us.iter().map(|&t| t as f64 / 1e6).collect(),
            stamps_us,
            intrinsics,
            player: Some(Player {
                playback,
                pending: None,
                last_us: None,
            }),
            stalled: None,
            path,
        })
    }

    /// The number of depth frames (at least 1).
    pub fn len(&self) -> usize {
        self.times_s.len()
    }

    /// Always `false`: [`OniRecording::open`] refuses a recording without depth frames.
    pub fn is_empty(&self) -> bool {
        self.times_s.is_empty()
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The depth camera's intrinsics (from the stream's field of view and video mode).
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// The time of frame `i` in seconds (its timestamp in the file), `None` past the last frame.
    pub fn time(&self, i: usize) -> Option<f64> {
        self.times_s.get(i).copied()
    }

    /// Every frame's time in seconds, strictly increasing.
    pub fn times(&self) -> &[f64] {
        &self.times_s
    }

    /// Depth frame `i`, read through OpenNI2's file player. Cheapest in increasing order (the
    /// frames in between are read and dropped); an earlier frame than the last one read
    /// reopens the file.
    ///
    /// Errors: [`KinectError::Recording`] naming the file for `i` out of range, a frame the
    /// player did not deliver (timed out, skipped, or no frame at all from this recording) or
    /// of another size than the intrinsics; [`KinectError::OpenNi`] from OpenNI2.
    pub fn frame(&mut self, i: usize) -> Result<DepthFrame, KinectError> {
        let Some(&want) = self.stamps_us.get(i) else {
            return Err(rec_err(
                &self.path,
                format!(
                    "frame {i} requested, but the recording has {} frames (0..={})",
                    self.len(),
                    self.len().saturating_sub(1)
                ),
            ));
        };
        if let Some(why) = &self.stalled {
            return Err(rec_err(&self.path, format!("frame {i} not read: {why}")));
        }
        // The player only goes forward: start again for a frame at or before the last one.
        let behind = self.player.as_ref().is_none_or(|p| {
            p.last_us.is_some_and(|t| t >= want)
                && p.pending.as_ref().is_none_or(|f| f.timestamp_us != want)
        });
        if behind {
            self.player = None; // the old player is closed before the file is opened again
            self.player = Some(Player {
                playback: FilePlayback::open(&self.path)?,
                pending: None,
                last_us: None,
            });
        }
        let player = self
            .player
            .as_mut()
            .ok_or_else(|| rec_err(&self.path, "internal: no player after opening one".into()))?;
        let got = loop {
            let next = match player.pending.take() {
                Some(f) => f,
                None => match player.playback.read_frame(FRAME_TIMEOUT_MS) {
                    Ok(f) => f,
                    Err(KinectError::OpenNi { status, .. }) if status == STATUS_TIME_OUT => {
                        let never = player.last_us.is_none();
                        self.player = None;
                        let why = if never {
                            let why = format!(
                                "OpenNI2's file player delivers no frame of this recording \
                                 (nothing within {FRAME_TIMEOUT_MS} ms; OpenNI 2.2 drops every \
                                 frame of a recording without a cropping property, such as one \
                                 of its Dummy device)"
                            );
                            self.stalled = Some(why.clone());
                            why
                        } else {
                            format!("OpenNI2's file player delivered nothing within {FRAME_TIMEOUT_MS} ms")
                        };
                        return Err(rec_err(&self.path, format!("frame {i} not read: {why}")));
                    }
                    Err(e) => {
                        self.player = None;
                        return Err(e);
                    }
                },
            };
            player.last_us = Some(f_max(player.last_us, next.timestamp_us));
            if next.timestamp_us >= want {
                break next;
            }
        };
        if got.timestamp_us > want {
            let at = got.timestamp_us;
            player.pending = Some(got);
            return Err(rec_err(
                &self.path,
                format!(
                    "frame {i} (at {want} µs) was not delivered: OpenNI2's file player went on \
                     to the frame at {at} µs"
                ),
            ));
        }
        let depth = got.depth;
        let k = &self.intrinsics;
        if (depth.width, depth.height) != (k.width, k.height) {
            return Err(rec_err(
                &self.path,
                format!(
                    "frame {i} is {}x{}, but the depth stream's video mode is {}x{}",
                    depth.width, depth.height, k.width, k.height
                ),
            ));
        }
        Ok(depth)
    }
}

fn f_max(a: Option<u64>, b: u64) -> u64 {
    a.map_or(b, |a| a.max(b))
}

fn rec_err(path: &Path, message: String) -> KinectError {
    KinectError::Recording {
        file: path.display().to_string(),
        message,
    }
}

/// `"NIR\0"`, the first four bytes of every record.
const RECORD_MAGIC: u32 = 0x0052_494E;
const RECORD_NODE_ADDED_1_0_0_4: u32 = 0x02;
const RECORD_NODE_ADDED_1_0_0_5: u32 = 0x0C;
const RECORD_NODE_ADDED: u32 = 0x0D;
const RECORD_NEW_DATA: u32 = 0x0A;
const RECORD_END: u32 = 0x0B;
/// The node type of a depth stream in a `NODE_ADDED` record.
const NODE_TYPE_DEPTH: u32 = 2;
/// The file header: identity `NI10`, version (u8, u8, u16, u32), max timestamp u64, max node id u32.
const FILE_HEADER_BYTES: u64 = 24;

/// The timestamps (µs) of the depth frames of an `.oni` file, in file order: the `NEW_DATA`
/// records of its first depth node, up to the `END` record (or the end of a file cut short).
///
/// The layout (OpenNI's `DataRecords.h`, all little-endian, packed): a record header of
/// magic, type, node id, fields size (header included), payload size (u32 each) and the undo
/// position (u64 from file version 1.0.1.0 on, u32 before); then the fields, then the payload.
/// `NODE_ADDED` fields start with the node name (u32 length, bytes) and the node type (u32);
/// `NEW_DATA` fields are the timestamp (u64) and the frame number (u32).
fn index_depth_frames(path: &Path) -> Result<Vec<u64>, KinectError> {
    let file_name = path.display().to_string();
    let io = |e: std::io::Error| KinectError::io(&file_name, e);
    let file = std::fs::File::open(path).map_err(io)?;
    let file_len = file.metadata().map_err(io)?.len();
    let mut r = BufReader::new(file);
    let mut head = [0u8; FILE_HEADER_BYTES as usize];
    if r.read_exact(&mut head).is_err() || &head[0..4] != b"NI10" {
        return Err(rec_err(
            path,
            "not an OpenNI recording (expected an .oni file starting with \"NI10\")".into(),
        ));
    }
    let version = (head[4], head[5], u16::from_le_bytes([head[6], head[7]]));
    // Files before 1.0.1.0 (OpenNI 1.x) have a 32-bit undo position in every record header.
    let header_bytes: u64 = if version < (1, 0, 1) { 24 } else { 28 };
    let mut depth_node: Option<u32> = None;
    let mut stamps: Vec<u64> = Vec::new();
    let mut pos = FILE_HEADER_BYTES;
    let mut buf = [0u8; 28];
    while pos + header_bytes <= file_len {
        r.seek(SeekFrom::Start(pos)).map_err(io)?;
        r.read_exact(&mut buf[..header_bytes as usize])
            .map_err(io)?;
        let word = |k: usize| {
            u32::from_le_bytes([buf[4 * k], buf[4 * k + 1], buf[4 * k + 2], buf[4 * k + 3]])
        };
        let (magic, kind, node, fields, payload) = (word(0), word(1), word(2), word(3), word(4));
        if magic != RECORD_MAGIC || u64::from(fields) < header_bytes {
            return Err(rec_err(
                path,
                format!("byte {pos}: not a record header (the file is damaged)"),
            ));
        }
        let next = pos + u64::from(fields) + u64::from(payload);
        if kind == RECORD_END || next > file_len {
            break; // the end, or a record cut short by an interrupted recording
        }
        let field_bytes = u64::from(fields) - header_bytes;
        match kind {
            RECORD_NODE_ADDED | RECORD_NODE_ADDED_1_0_0_5 | RECORD_NODE_ADDED_1_0_0_4
                if depth_node.is_none() && field_bytes >= 8 =>
            {
                let mut len = [0u8; 4];
                r.read_exact(&mut len).map_err(io)?;
                let name_len = u64::from(u32::from_le_bytes(len));
                if name_len + 8 <= field_bytes {
                    r.seek_relative(name_len as i64).map_err(io)?;
                    let mut ty = [0u8; 4];
                    r.read_exact(&mut ty).map_err(io)?;
                    if u32::from_le_bytes(ty) == NODE_TYPE_DEPTH {
                        depth_node = Some(node);
                    }
                }
            }
            RECORD_NEW_DATA if Some(node) == depth_node && field_bytes >= 12 => {
                let mut ts = [0u8; 8];
                r.read_exact(&mut ts).map_err(io)?;
                let t = u64::from_le_bytes(ts);
                if let Some(&prev) = stamps.last() {
                    if t <= prev {
                        return Err(rec_err(
                            path,
                            format!(
                                "depth frame {} at {t} µs is not after the previous one's \
                                 {prev} µs (times must increase strictly)",
                                stamps.len()
                            ),
                        ));
                    }
                }
                stamps.push(t);
            }
            _ => {}
        }
        pos = next;
    }
    if depth_node.is_none() {
        return Err(rec_err(path, "no depth stream in the recording".into()));
    }
    if stamps.is_empty() {
        return Err(rec_err(path, "no depth frames in the recording".into()));
    }
    Ok(stamps)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record: header (64-bit undo position), fields, payload.
    fn record(kind: u32, node: u32, fields: &[u8], payload: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        for w in [
            RECORD_MAGIC,
            kind,
            node,
            28 + fields.len() as u32,
            payload.len() as u32,
        ] {
            out.extend(w.to_le_bytes());
        }
        out.extend(0u64.to_le_bytes());
        out.extend(fields);
        out.extend(payload);
        out
    }

    fn file_header() -> Vec<u8> {
        let mut out = b"NI10".to_vec();
        out.extend([1, 0]);
        out.extend(1u16.to_le_bytes());
        out.extend(0u32.to_le_bytes());
        out.extend(u64::MAX.to_le_bytes());
        out.extend(1u32.to_le_bytes());
        out
    }

    fn node_added(node: u32, name: &str, ty: u32) -> Vec<u8> {
        let mut f = Vec::new();
        f.extend((name.len() as u32 + 1).to_le_bytes());
        f.extend(name.as_bytes());
        f.push(0);
        f.extend(ty.to_le_bytes());
        f.extend([0u8; 28]); // codec, frames, min/max timestamp, seek table position
        record(RECORD_NODE_ADDED, node, &f, &[])
    }

    fn new_data(node: u32, t: u64, frame: u32) -> Vec<u8> {
        let mut f = t.to_le_bytes().to_vec();
        f.extend(frame.to_le_bytes());
        record(RECORD_NEW_DATA, node, &f, &[7u8; 10])
    }

    #[test]
    fn the_index_keeps_the_depth_nodes_frames_up_to_the_end_record() {
        let mut bytes = file_header();
        bytes.extend(node_added(1, "Image", 3));
        bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
        bytes.extend(new_data(1, 5, 1)); // colour: not a depth frame
        bytes.extend(new_data(2, 0, 1));
        bytes.extend(new_data(2, 33_000, 2));
        bytes.extend(record(RECORD_END, 0, &[], &[]));
        bytes.extend(new_data(2, 66_000, 3)); // after END: not read
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.oni");
        std::fs::write(&p, &bytes).unwrap();
        assert_eq!(index_depth_frames(&p).unwrap(), vec![0, 33_000]);

        // A recording cut short in its last frame keeps the complete ones.
        let mut cut = bytes[..bytes.len() - 1].to_vec();
        let end = record(RECORD_END, 0, &[], &[]);
        let at = cut.windows(end.len()).position(|w| w == end).unwrap();
        cut.truncate(at + 5);
        std::fs::write(&p, &cut).unwrap();
        assert_eq!(index_depth_frames(&p).unwrap(), vec![0, 33_000]);
    }

    #[test]
    fn the_index_refuses_what_is_not_a_usable_recording() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.oni");
        std::fs::write(&p, b"PK\x03\x04 not an oni").unwrap();
        let e = index_depth_frames(&p).unwrap_err().to_string();
        assert!(e.contains("not an OpenNI recording"), "{e}");

        let mut bytes = file_header();
        bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
        std::fs::write(&p, &bytes).unwrap();
        let e = index_depth_frames(&p).unwrap_err().to_string();
        assert!(e.ends_with("no depth frames in the recording"), "{e}");

        bytes.extend(new_data(2, 33_000, 1));
        bytes.extend(new_data(2, 33_000, 2));
        std::fs::write(&p, &bytes).unwrap();
        let e = index_depth_frames(&p).unwrap_err().to_string();
        assert!(e.contains("depth frame 1 at 33000 µs is not after"), "{e}");

        let mut bytes = file_header();
        bytes.extend(b"garbage garbage garbage garbage!");
        std::fs::write(&p, &bytes).unwrap();
        let e = index_depth_frames(&p).unwrap_err().to_string();
        assert!(e.contains("byte 24: not a record header"), "{e}");
    }
}
