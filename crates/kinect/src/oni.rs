//! OpenNI2 `.oni` recordings as a sequence of timed depth frames ([`OniRecording`], feature
//! `openni2`), the counterpart of a recording folder ([`crate::Recording`]) for
//! [`crate::DepthSource`].
//!
//! # Where each part comes from
//!
//! * **Frames and times** — [`OniRecording::open`] walks the file's records once (headers only,
//!   in Rust, no frame is decoded: [`crate::oni_index`]) and keeps, for every depth frame in
//!   file order, its timestamp: microseconds in the file, seconds here (`t_us / 10⁶`; OpenNI2's recorder writes
//!   the first frame at 0). The file's own index is used, not a playback pass, because playback
//!   can deliver nothing at all (below) and a time is wanted for every frame, read or not.
//! * **Intrinsics** — from the depth stream's video mode and field of view as OpenNI2 reports
//!   them ([`Intrinsics::from_field_of_view`]: `fx = width / (2·tan(hfov/2))`, principal point
//!   at the image centre); a recording without a field of view (OpenNI2's Dummy device) gets
//!   the nominal Kinect v1 focal length scaled to its width. The image's direction from the
//!   stream's recorded mirroring property (`xnMirror`, [`crate::oni_index::DepthStreamIndex`]):
//!   on, or not recorded, mirrored as the Kinect SDK's; off, as the lens forms it
//!   ([`Mirroring::Direct`]).
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
//! at once with [`KinectError::Recording`] saying that the player delivers no frame. A
//! recording of a real sensor, or one written by [`crate::oni_write`] (which records the
//! cropping property and the field of view), plays every frame.
//!
//! ```no_run
//! # fn main() -> Result<(), symcorr_kinect::KinectError> {
//! use symcorr_kinect::oni::OniRecording;
//! let mut rec = OniRecording::open("session.oni")?;
//! println!("{} frames, the last at {:?} s", rec.len(), rec.time(rec.len() - 1));
//! let depth = rec.frame(0)?; // millimetres, the size of rec.intrinsics()
//! # let _ = depth; Ok(()) }
//! ```

use crate::camera::{Intrinsics, Mirroring};
use crate::depth::DepthFrame;
use crate::error::KinectError;
use crate::oni_index::{depth_stream_index_in, DepthStreamIndex, OniIndexError};
use crate::openni2::{FilePlayback, StampedDepth, STATUS_TIME_OUT};
use std::path::{Path, PathBuf};

/// How long [`OniRecording::frame`] waits for OpenNI2's file player to hand over a frame.
pub const FRAME_TIMEOUT_MS: i32 = 5000;

/// An `.oni` recording (see the [module docs](self)): its depth frames' times and the camera's
/// intrinsics, read at opening; the frames on demand, in increasing order.
#[derive(Debug)]
pub struct OniRecording {
    path: PathBuf,
    pub(crate) intrinsics: Intrinsics,
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
        let index = index_depth_stream(&path)?;
        let stamps_us = index.times_us;
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
        let intrinsics = Intrinsics {
            mirroring: Mirroring::from_openni(index.mirrored),
            ..Intrinsics::from_field_of_view(width, height, fov)
        };
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

/// The timestamps (µs) of the depth frames of an `.oni` file and its depth stream's mirroring
/// ([`crate::oni_index`]), errors naming the file.
fn index_depth_stream(path: &Path) -> Result<DepthStreamIndex, KinectError> {
    let file_name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| KinectError::io(&file_name, e))?;
    depth_stream_index_in(file).map_err(|e| match e {
        OniIndexError::Io(source) => KinectError::io(&file_name, source),
        e => rec_err(path, e.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oni_index::build::*;

    #[test]
    fn the_index_of_a_file_names_it_in_its_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.oni");
        let mut bytes = file_header();
        bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
        bytes.extend(new_data(2, 0, 1));
        bytes.extend(new_data(2, 33_000, 2));
        bytes.extend(end());
        std::fs::write(&p, &bytes).unwrap();
        assert_eq!(index_depth_stream(&p).unwrap().times_us, vec![0, 33_000]);

        std::fs::write(&p, b"PK\x03\x04 not an oni").unwrap();
        let e = index_depth_stream(&p).unwrap_err();
        assert!(matches!(e, KinectError::Recording { .. }), "{e}");
        let e = e.to_string();
        assert!(e.starts_with(&p.display().to_string()), "{e}");
        assert!(e.contains("not an OpenNI recording"), "{e}");

        let e = index_depth_stream(&dir.path().join("missing.oni")).unwrap_err();
        assert!(matches!(e, KinectError::Io { .. }), "{e}");
    }
}
