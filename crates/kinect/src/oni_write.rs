//! Writing OpenNI2 `.oni` recordings of depth frames in pure Rust (no OpenNI2 needed, compiled
//! in every build): [`write_oni`] streams timed depth frames (millimetres, [`DepthFrame`]) and
//! the camera's intrinsics into a file that OpenNI 2.2's own file player (the `OniFile` driver)
//! plays frame by frame; [`write_recording_oni`] converts a recording folder
//! ([`crate::Recording`]); [`oni_bytes`] builds one in memory.
//!
//! # Layout
//!
//! The records of [`crate::oni_index`] (all little-endian, packed; record headers of file
//! version 1.0.1, with a 64-bit undo position), in the order OpenNI2's own recorder writes them:
//!
//! 1. the file header: `NI10`, version 1.0.1.0, the last frame's timestamp, max node id 1;
//! 2. `NODE_ADDED` of one depth node (id 1, name `Depth`, type 2), codec `NONE`, the frame
//!    count, the first and last timestamps and where the seek table is;
//! 3. the node's properties (`INT_PROPERTY` name + u32 size 8 + u64, `GENERAL_PROPERTY`
//!    name + u32 size + bytes), each turned by the player into an OpenNI2 stream property:
//!    `oniRequiredFrameSize` (bytes of one frame), `xnIsGenerating` 1, `xnDeviceMaxDepth`
//!    65 535 (`MAX_VALUE`: every u16 is a valid millimetre value, and the writer does not look
//!    at the frames ahead), `xnSupportedMapOutputModes{Count,}` and `xnMapOutputMode` (width,
//!    height, fps: the `VIDEO_MODE`, from which the player derives the stride),
//!    `xnSupportedPixelFormats`, `xnPixelFormat` 4 (16-bit greyscale: `DEPTH_1_MM` for a depth
//!    node), `oniPixelFormat` 100 (`DEPTH_1_MM`), `xnMirror` (OpenNI's mirroring: 1 for the
//!    Kinect SDK's mirrored image, 0 for one as the lens forms it, [`crate::Mirroring`]),
//!    **`xnCropping`** (disabled, the full image) and
//!    `xnFOV` (horizontal and vertical field of view, two f64, radians);
//! 4. `NODE_STATE_READY`, `NODE_DATA_BEGIN` (frame count, last timestamp);
//! 5. one `NEW_DATA` record per frame: timestamp (µs, u64), frame number (1, 2, …), and the
//!    frame's pixels row by row as u16 as payload; its undo position is the previous frame's
//!    record;
//! 6. `NODE_REMOVED` (undo position: the `NODE_ADDED` record), the `SEEK_TABLE` (one 20-byte
//!    entry per frame — timestamp u64, configuration 0 u32, record position u64 — after an
//!    all-zero entry for frame 0), `END`.
//!
//! # What the player needs, and why
//!
//! * **The cropping property.** OpenNI 2.2's `PlayerStream` asks the recorded source for its
//!   video mode, stride *and cropping* before it hands over each frame, and drops the frame when
//!   any is missing. A recording without `xnCropping` (one of OpenNI2's Dummy device, which
//!   implements no cropping property) therefore plays no frame at all. The player checks the
//!   property's size: `XnCropping` is 12 bytes (u32 enabled, four u16); 10 bytes make opening
//!   the file fail.
//! * **The codec** `NONE` (`XN_CODEC_UNCOMPRESSED`, the four bytes `N O N E`): the player's
//!   uncompressed codec copies the payload as it is, so what is written is what every frame's
//!   pixels are, bit for bit, and the writer needs no table or state. OpenNI2's recorder writes
//!   `16zT` (16-bit deltas with an embedded table) instead; it is about 60 times smaller on the
//!   Dummy's test pattern, but a second implementation of a compressor is not needed here.
//! * **The field of view** is the only camera model an `.oni` holds; OpenNI2 reports it as f32
//!   (`HORIZONTAL_FOV`, `VERTICAL_FOV`), and [`Intrinsics::from_field_of_view`] turns it back
//!   into focal lengths with the principal point at the image centre. So intrinsics whose
//!   principal point is not the centre are refused ([`OniWriteError::OffCentre`]); focal
//!   lengths come back within the f32 rounding of the angle (285.63 px at 320 px wide reads
//!   back as 285.630 009 6 px).
//! * The seek table and the `END` record are not needed to play the file forward (found by
//!   leaving them out); they are written as the recorder writes them, for seeking and for the
//!   end of the file.
//!
//! Timestamps must increase strictly (the player's manual playback, and
//! [`crate::oni_index`], identify frames by them). Writes are atomic (a temporary file renamed
//! into place, [`symcorr_mesh::io::OutputBatch`]); a large recording is streamed, one frame in
//! memory at a time.
//!
//! ```
//! use symcorr_kinect::{oni_index::depth_frame_times, oni_write::oni_bytes, DepthFrame, Intrinsics};
//! let k = Intrinsics::from_field_of_view(4, 3, Some((1.0, 0.8)));
//! let frame = |mm| DepthFrame::new(4, 3, vec![mm; 12]).unwrap();
//! let bytes = oni_bytes(&k, &[0, 33_333], &[frame(1500), frame(1510)]).unwrap();
//! assert_eq!(depth_frame_times(&bytes).unwrap(), vec![0, 33_333]);
//! ```

use crate::camera::Intrinsics;
use crate::depth::DepthFrame;
use crate::error::KinectError;
use crate::oni_index::{
    MIRROR_PROPERTY, NODE_TYPE_DEPTH, RECORD_END, RECORD_INT_PROPERTY, RECORD_MAGIC,
    RECORD_NEW_DATA, RECORD_NODE_ADDED,
};
use crate::recording::Recording;
use std::io::{self, Write};
use std::ops::Range;
use std::path::Path;
use thiserror::Error;

/// `XN_CODEC_UNCOMPRESSED`: the four bytes `NONE`, read as a little-endian u32.
pub const CODEC_UNCOMPRESSED: u32 = u32::from_le_bytes(*b"NONE");
/// `ONI_PIXEL_FORMAT_DEPTH_1_MM`.
pub const PIXEL_FORMAT_DEPTH_1_MM: u64 = 100;
/// `MAX_VALUE` written for the depth stream: the whole u16 range (module docs).
pub const MAX_DEPTH_MM: u64 = u16::MAX as u64;

const RECORD_GENERAL_PROPERTY: u32 = 0x06;
const RECORD_NODE_REMOVED: u32 = 0x07;
const RECORD_NODE_DATA_BEGIN: u32 = 0x08;
const RECORD_NODE_STATE_READY: u32 = 0x09;
const RECORD_SEEK_TABLE: u32 = 0x0E;
/// A record header: magic, type, node id, fields size, payload size (u32), undo position (u64).
const RECORD_HEADER_BYTES: usize = 28;
/// A `NEW_DATA` record's fields: the header, the timestamp (u64) and the frame number (u32).
const NEW_DATA_FIELDS_BYTES: usize = RECORD_HEADER_BYTES + 12;
/// One seek table entry: timestamp u64, configuration id u32, record position u64.
const SEEK_ENTRY_BYTES: usize = 20;
/// The depth node's id and name.
const NODE_ID: u32 = 1;
const NODE_NAME: &str = "Depth";
/// `XN_PIXEL_FORMAT_GRAYSCALE_16_BIT`, what OpenNI2's recorder writes for a depth node.
const XN_PIXEL_FORMAT_GRAYSCALE_16: u64 = 4;
/// The frame rate written when the times give none (a single frame).
const DEFAULT_FPS: u32 = 30;

/// Why an `.oni` file was not written. Nothing is written on any error (no file, no
/// temporary file left behind).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OniWriteError {
    /// No frames (or an empty range of them).
    #[error("no depth frames to write")]
    NoFrames,
    /// As many times as frames are needed.
    #[error("{times} frame times for {frames} depth frames")]
    CountMismatch {
        /// The number of times given.
        times: usize,
        /// The number of frames given.
        frames: usize,
    },
    /// A frame's time is not after the previous one's (after rounding to whole µs).
    #[error(
        "depth frame {frame} at {t_us} µs is not after the previous one's {previous_us} µs \
         (times must increase strictly)"
    )]
    TimesNotIncreasing {
        /// The frame (0-based, among the frames written).
        frame: usize,
        /// Its timestamp, µs.
        t_us: u64,
        /// The previous frame's timestamp, µs.
        previous_us: u64,
    },
    /// A frame time (seconds) that is no timestamp: negative, not finite, or beyond u64 µs.
    #[error("depth frame {frame} at {time_s} s: an .oni timestamp is a whole number of µs ≥ 0")]
    BadTime {
        /// The frame (0-based, among the frames written).
        frame: usize,
        /// Its time, seconds.
        time_s: f64,
    },
    /// The intrinsics are not valid ([`Intrinsics::validate`]).
    #[error("invalid intrinsics: {0}")]
    Intrinsics(String),
    /// The principal point is not the image centre, which an `.oni` file cannot say (it holds
    /// the field of view only; module docs).
    #[error(
        "principal point ({cx}, {cy}) is not the image centre ({}, {}): an .oni file holds \
         the field of view only, and OpenNI2 recordings are read with the principal point at \
         the centre",
        f64::from(*width) / 2.0,
        f64::from(*height) / 2.0
    )]
    OffCentre {
        /// Principal point column, pixels.
        cx: f64,
        /// Principal point row, pixels.
        cy: f64,
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
    },
    /// Intrinsics with a lens [`Distortion`](crate::Distortion): an .oni file keeps a field of
    /// view, not a lens model, so its frames would be read back as a pinhole camera's.
    #[error(
        "the intrinsics have a lens distortion model, but an .oni file keeps only a field of \
         view: its frames would be read back as a pinhole camera's"
    )]
    Distorted,
    /// An image too large for one record (its bytes overflow the u32 payload size, or a side
    /// overflows the u16 of the cropping property).
    #[error("a {width}x{height} depth frame does not fit in an .oni record")]
    TooLarge {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// A frame of another size than the intrinsics.
    #[error("depth frame {frame} is {width}x{height}, but the intrinsics are {expected_width}x{expected_height}")]
    FrameSize {
        /// The frame (0-based, among the frames written).
        frame: usize,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The intrinsics' width.
        expected_width: u32,
        /// The intrinsics' height.
        expected_height: u32,
    },
    /// Reading a frame to write failed.
    #[error("depth frame {frame}: {source}")]
    Frame {
        /// The frame (0-based, among the frames written).
        frame: usize,
        /// Why.
        #[source]
        source: Box<KinectError>,
    },
    /// Writing the file failed (the error names it).
    #[error(transparent)]
    Output(#[from] symcorr_mesh::MeshError),
}

/// The checked description of a file to write: everything but the pixels.
#[derive(Debug, Clone)]
struct Plan {
    width: u32,
    height: u32,
    fps: u32,
    /// Horizontal and vertical field of view, radians.
    fov: (f64, f64),
    /// The image is mirrored (the Kinect SDK's; `xnMirror` 1) or as the lens forms it (0).
    mirrored: bool,
    times_us: Vec<u64>,
    /// The bytes before the first frame record (header, node, properties, data begin).
    head: Vec<u8>,
    /// Bytes of one frame's pixels.
    frame_bytes: u32,
}

impl Plan {
    fn new(k: &Intrinsics, times_us: &[u64]) -> Result<Plan, OniWriteError> {
        k.validate()
            .map_err(|e| OniWriteError::Intrinsics(e.to_string()))?;
        if k.distortion.is_some() {
            return Err(OniWriteError::Distorted);
        }
        let (w, h) = (f64::from(k.width), f64::from(k.height));
        if k.cx != w / 2.0 || k.cy != h / 2.0 {
            return Err(OniWriteError::OffCentre {
                cx: k.cx,
                cy: k.cy,
                width: k.width,
                height: k.height,
            });
        }
        let too_large = OniWriteError::TooLarge {
            width: k.width,
            height: k.height,
        };
        let frame_bytes = u64::from(k.width) * u64::from(k.height) * 2;
        let frame_bytes = u32::try_from(frame_bytes).map_err(|_| too_large)?;
        if u16::try_from(k.width).is_err() || u16::try_from(k.height).is_err() {
            return Err(OniWriteError::TooLarge {
                width: k.width,
                height: k.height,
            });
        }
        let (Some(&first), Some(&last)) = (times_us.first(), times_us.last()) else {
            return Err(OniWriteError::NoFrames);
        };
        for (i, pair) in times_us.windows(2).enumerate() {
            if pair[1] <= pair[0] {
                return Err(OniWriteError::TimesNotIncreasing {
                    frame: i + 1,
                    t_us: pair[1],
                    previous_us: pair[0],
                });
            }
        }
        let fps = if times_us.len() > 1 {
            let span_s = (last - first) as f64 / 1e6;
            let rate = (times_us.len() - 1) as f64 / span_s;
            // Whole frames per second, as the video mode holds them; at least 1.
            rate.round().clamp(1.0, f64::from(u16::MAX)) as u32
        } else {
            DEFAULT_FPS
        };
        let fov = (2.0 * (0.5 * w / k.fx).atan(), 2.0 * (0.5 * h / k.fy).atan());
        let mut plan = Plan {
            width: k.width,
            height: k.height,
            fps,
            fov,
            mirrored: k.mirroring == crate::Mirroring::Mirrored,
            times_us: times_us.to_vec(),
            head: Vec::new(),
            frame_bytes,
        };
        // The node record says where the seek table is, which depends on the head's length
        // only through its own fixed-size field: build it once to measure, then for real.
        plan.head = plan.head_bytes(0);
        let seek_table_at = plan.seek_table_position();
        plan.head = plan.head_bytes(seek_table_at);
        Ok(plan)
    }

    fn frame_record_bytes(&self) -> u64 {
        NEW_DATA_FIELDS_BYTES as u64 + u64::from(self.frame_bytes)
    }

    /// Where frame `i`'s record starts.
    fn frame_position(&self, i: usize) -> u64 {
        self.head.len() as u64 + i as u64 * self.frame_record_bytes()
    }

    /// The whole file's size.
    fn file_bytes(&self) -> u64 {
        self.frame_position(self.times_us.len()) + self.tail_bytes().len() as u64
    }

    /// After the frames and the `NODE_REMOVED` record (a bare header).
    fn seek_table_position(&self) -> u64 {
        self.frame_position(self.times_us.len()) + RECORD_HEADER_BYTES as u64
    }

    /// The file header, the node and its properties, up to the first frame record.
    fn head_bytes(&self, seek_table_at: u64) -> Vec<u8> {
        let n = self.times_us.len() as u32;
        let first = self.times_us.first().copied().unwrap_or(0);
        let last = self.times_us.last().copied().unwrap_or(0);
        let mut out = b"NI10".to_vec();
        out.extend([1, 0]); // version 1.0.1.0: 64-bit undo positions
        out.extend(1u16.to_le_bytes());
        out.extend(0u32.to_le_bytes());
        out.extend(last.to_le_bytes());
        out.extend(NODE_ID.to_le_bytes());

        let mut fields = name_field(NODE_NAME);
        fields.extend(NODE_TYPE_DEPTH.to_le_bytes());
        fields.extend(CODEC_UNCOMPRESSED.to_le_bytes());
        fields.extend(n.to_le_bytes());
        fields.extend(first.to_le_bytes());
        fields.extend(last.to_le_bytes());
        fields.extend(seek_table_at.to_le_bytes());
        record(&mut out, RECORD_NODE_ADDED, &fields, 0, 0);

        let mode: Vec<u8> = [self.width, self.height, self.fps]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        int_property(
            &mut out,
            "oniRequiredFrameSize",
            u64::from(self.frame_bytes),
        );
        int_property(&mut out, "xnIsGenerating", 1);
        int_property(&mut out, "xnDeviceMaxDepth", MAX_DEPTH_MM);
        int_property(&mut out, "xnSupportedMapOutputModesCount", 1);
        general_property(&mut out, "xnSupportedMapOutputModes", &mode);
        general_property(&mut out, "xnMapOutputMode", &mode);
        // What OpenNI2's recorder writes for a 16-bit depth node.
        general_property(&mut out, "xnSupportedPixelFormats", &8u32.to_le_bytes());
        int_property(&mut out, "xnPixelFormat", XN_PIXEL_FORMAT_GRAYSCALE_16);
        int_property(&mut out, "oniPixelFormat", PIXEL_FORMAT_DEPTH_1_MM);
        int_property(&mut out, MIRROR_PROPERTY, u64::from(self.mirrored));
        // XnCropping: enabled (u32), x and y offset, width and height (u16). Checked to fit.
        let mut cropping = 0u32.to_le_bytes().to_vec();
        for v in [0, 0, self.width as u16, self.height as u16] {
            cropping.extend(u16::to_le_bytes(v));
        }
        general_property(&mut out, "xnCropping", &cropping);
        let mut fov = self.fov.0.to_le_bytes().to_vec();
        fov.extend(self.fov.1.to_le_bytes());
        general_property(&mut out, "xnFOV", &fov);

        record(&mut out, RECORD_NODE_STATE_READY, &[], 0, 0);
        let mut begin = n.to_le_bytes().to_vec();
        begin.extend(last.to_le_bytes());
        record(&mut out, RECORD_NODE_DATA_BEGIN, &begin, 0, 0);
        out
    }

    /// A frame record's header and fields (its payload, the pixels, follows).
    fn frame_header(&self, i: usize) -> Vec<u8> {
        let mut fields = self.times_us[i].to_le_bytes().to_vec();
        fields.extend((i as u32 + 1).to_le_bytes());
        let undo = if i == 0 {
            0
        } else {
            self.frame_position(i - 1)
        };
        let mut out = Vec::with_capacity(NEW_DATA_FIELDS_BYTES);
        record(&mut out, RECORD_NEW_DATA, &fields, self.frame_bytes, undo);
        out
    }

    /// `NODE_REMOVED`, the seek table and `END`.
    fn tail_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let node_added_at = 24; // right after the file header
        record(&mut out, RECORD_NODE_REMOVED, &[], 0, node_added_at);
        let mut table = vec![0u8; SEEK_ENTRY_BYTES]; // frame 0: none
        for (i, t) in self.times_us.iter().enumerate() {
            table.extend(t.to_le_bytes());
            table.extend(0u32.to_le_bytes());
            table.extend(self.frame_position(i).to_le_bytes());
        }
        let payload = u32::try_from(table.len()).unwrap_or(u32::MAX);
        record(&mut out, RECORD_SEEK_TABLE, &[], payload, 0);
        out.extend(table);
        out.extend_from_slice(&end_record());
        out
    }
}

fn end_record() -> Vec<u8> {
    let mut out = Vec::new();
    record(&mut out, RECORD_END, &[], 0, 0);
    out
}

/// Appends a record header for `fields` (the header's own bytes included in the fields size)
/// and `payload` bytes to follow, then the fields. The node is always the depth node, except for
/// `END` (node 0).
fn record(out: &mut Vec<u8>, kind: u32, fields: &[u8], payload: u32, undo: u64) {
    let node = if kind == RECORD_END { 0 } else { NODE_ID };
    // Fields are a few hundred bytes at most (names and small structs).
    let fields_size = (RECORD_HEADER_BYTES + fields.len()) as u32;
    for w in [RECORD_MAGIC, kind, node, fields_size, payload] {
        out.extend(w.to_le_bytes());
    }
    out.extend(undo.to_le_bytes());
    out.extend(fields);
}

/// A name as the records hold it: u32 length with the NUL, the bytes, NUL.
fn name_field(name: &str) -> Vec<u8> {
    let mut out = (name.len() as u32 + 1).to_le_bytes().to_vec();
    out.extend(name.as_bytes());
    out.push(0);
    out
}

fn int_property(out: &mut Vec<u8>, name: &str, value: u64) {
    let mut fields = name_field(name);
    fields.extend(8u32.to_le_bytes());
    fields.extend(value.to_le_bytes());
    record(out, RECORD_INT_PROPERTY, &fields, 0, 0);
}

fn general_property(out: &mut Vec<u8>, name: &str, value: &[u8]) {
    let mut fields = name_field(name);
    fields.extend((value.len() as u32).to_le_bytes());
    fields.extend(value);
    record(out, RECORD_GENERAL_PROPERTY, &fields, 0, 0);
}

/// Writes the whole file to `w`, asking `frame` for each frame in order. A frame error is
/// returned as such; an I/O error as `Err(Err(io))`.
fn write_all(
    plan: &Plan,
    w: &mut dyn Write,
    frame: &mut dyn FnMut(usize) -> Result<DepthFrame, KinectError>,
) -> Result<(), Result<OniWriteError, io::Error>> {
    w.write_all(&plan.head).map_err(Err)?;
    let mut pixels = Vec::with_capacity(plan.frame_bytes as usize);
    for i in 0..plan.times_us.len() {
        let f = frame(i).map_err(|source| {
            Ok(OniWriteError::Frame {
                frame: i,
                source: Box::new(source),
            })
        })?;
        if (f.width, f.height) != (plan.width, plan.height)
            || f.data_mm.len() * 2 != plan.frame_bytes as usize
        {
            return Err(Ok(OniWriteError::FrameSize {
                frame: i,
                width: f.width,
                height: f.height,
                expected_width: plan.width,
                expected_height: plan.height,
            }));
        }
        pixels.clear();
        pixels.extend(f.data_mm.iter().flat_map(|v| v.to_le_bytes()));
        w.write_all(&plan.frame_header(i)).map_err(Err)?;
        w.write_all(&pixels).map_err(Err)?;
    }
    w.write_all(&plan.tail_bytes()).map_err(Err)
}

/// Writes an `.oni` file of depth frames at `path`, atomically (module docs): frame `i` has
/// timestamp `times_us[i]` (µs, strictly increasing) and is asked from `frame(i)`, in order, one
/// at a time. The intrinsics give the image size and the field of view; their principal point
/// must be the image centre. Returns the file's size in bytes.
///
/// Errors: [`OniWriteError`]: no times, times not increasing, intrinsics invalid or off-centre,
/// an image too large for a record, a frame of another size or one `frame` could not read,
/// and the output's errors (naming `path`). Nothing is written on error.
pub fn write_oni(
    path: &Path,
    intrinsics: &Intrinsics,
    times_us: &[u64],
    mut frame: impl FnMut(usize) -> Result<DepthFrame, KinectError>,
) -> Result<u64, OniWriteError> {
    let plan = Plan::new(intrinsics, times_us)?;
    let mut failed: Option<OniWriteError> = None;
    let mut batch = symcorr_mesh::io::OutputBatch::new();
    let staged = batch.add_streamed(path, |w| match write_all(&plan, w, &mut frame) {
        Ok(()) => Ok(()),
        Err(Err(io)) => Err(io),
        Err(Ok(e)) => {
            failed = Some(e);
            Err(io::Error::other("a depth frame could not be written"))
        }
    });
    if let Some(e) = failed {
        return Err(e);
    }
    staged?;
    batch.commit()?;
    Ok(plan.file_bytes())
}

/// The bytes of an `.oni` file of `frames` at `times_us` (as [`write_oni`], in memory).
pub fn oni_bytes(
    intrinsics: &Intrinsics,
    times_us: &[u64],
    frames: &[DepthFrame],
) -> Result<Vec<u8>, OniWriteError> {
    if times_us.len() != frames.len() {
        return Err(OniWriteError::CountMismatch {
            times: times_us.len(),
            frames: frames.len(),
        });
    }
    let plan = Plan::new(intrinsics, times_us)?;
    let mut out = Vec::new();
    let mut get = |i: usize| Ok(frames[i].clone());
    match write_all(&plan, &mut out, &mut get) {
        Ok(()) => Ok(out),
        Err(Ok(e)) => Err(e),
        // Writing to a Vec does not fail; kept typed all the same.
        Err(Err(io)) => Err(OniWriteError::Output(symcorr_mesh::MeshError::Io {
            file: "<memory>".into(),
            source: io,
        })),
    }
}

/// A time in seconds as an `.oni` timestamp: whole microseconds, rounded to the nearest.
/// `None` for a negative, non-finite or too large time.
pub fn timestamp_us(time_s: f64) -> Option<u64> {
    let us = (time_s * 1e6).round();
    // 2⁶⁴ is exactly representable; anything at or above it does not fit.
    (0.0..18_446_744_073_709_551_616.0)
        .contains(&us)
        .then_some(us as u64)
}

/// Writes frames `frames` of a recording folder as an `.oni` file at `path` ([`write_oni`]):
/// the same pixels, each frame's time ([`Recording::time`]) rounded to whole µs as its
/// timestamp, the folder's intrinsics as the field of view. Returns the file's size in bytes.
///
/// A recording folder written by `symcorr-synth recording` keeps its times in whole µs, so
/// `OniRecording` (feature `openni2`) reads back the very same times.
///
/// Errors: as [`write_oni`]; [`OniWriteError::NoFrames`] for an empty range or one past the
/// last frame, [`OniWriteError::BadTime`] for a negative time.
pub fn write_recording_oni(
    recording: &Recording,
    frames: Range<usize>,
    path: &Path,
) -> Result<u64, OniWriteError> {
    if frames.is_empty() || frames.end > recording.len() {
        return Err(OniWriteError::NoFrames);
    }
    let times_us = frames
        .clone()
        .map(|i| {
            let t = recording.time(i).unwrap_or(f64::NAN);
            timestamp_us(t).ok_or(OniWriteError::BadTime {
                frame: i - frames.start,
                time_s: t,
            })
        })
        .collect::<Result<Vec<u64>, _>>()?;
    write_oni(path, recording.intrinsics(), &times_us, |i| {
        recording.frame(frames.start + i)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oni_index::{depth_frame_times, OniIndexError};

    fn k(w: u32, h: u32) -> Intrinsics {
        Intrinsics::from_field_of_view(w, h, Some((1.0, 0.8)))
    }

    fn frames(w: u32, h: u32, n: usize) -> Vec<DepthFrame> {
        (0..n)
            .map(|i| {
                let data = (0..w * h)
                    .map(|p| (p as usize * 7 + i * 13) as u16)
                    .collect();
                DepthFrame::new(w, h, data).unwrap()
            })
            .collect()
    }

    fn u32_at(b: &[u8], at: usize) -> u32 {
        u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
    }

    fn u64_at(b: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
    }

    /// Every record: (position, type, fields bytes after the header, payload).
    fn records(b: &[u8]) -> Vec<(usize, u32, &[u8], &[u8])> {
        let mut out = Vec::new();
        let mut pos = 24;
        while pos < b.len() {
            assert_eq!(u32_at(b, pos), RECORD_MAGIC, "record at {pos}");
            let (fields, payload) = (u32_at(b, pos + 12) as usize, u32_at(b, pos + 16) as usize);
            out.push((
                pos,
                u32_at(b, pos + 4),
                &b[pos + 28..pos + fields],
                &b[pos + fields..pos + fields + payload],
            ));
            pos += fields + payload;
        }
        assert_eq!(pos, b.len());
        out
    }

    #[test]
    fn the_index_reads_back_the_times_and_the_records_hold_the_frames() {
        let times = [683, 32_591, 67_916, 100_000];
        let fs = frames(6, 4, times.len());
        let b = oni_bytes(&k(6, 4), &times, &fs).unwrap();
        assert_eq!(depth_frame_times(&b).unwrap(), times);

        // The file header: identity, version 1.0.1, the last timestamp, one node.
        assert_eq!(&b[..4], b"NI10");
        assert_eq!(&b[4..8], &[1, 0, 1, 0]);
        assert_eq!(u64_at(&b, 12), 100_000);
        assert_eq!(u32_at(&b, 20), 1);

        let recs = records(&b);
        let (_, kind, node, _) = recs[0];
        assert_eq!(kind, RECORD_NODE_ADDED);
        // Name "Depth", type, codec, frames, first and last time, seek table position.
        assert_eq!(&node[..10], &[6, 0, 0, 0, b'D', b'e', b'p', b't', b'h', 0]);
        assert_eq!(u32_at(node, 10), NODE_TYPE_DEPTH);
        assert_eq!(u32_at(node, 14), CODEC_UNCOMPRESSED);
        assert_eq!(u32_at(node, 18), 4);
        assert_eq!((u64_at(node, 22), u64_at(node, 30)), (683, 100_000));
        let seek_at = u64_at(node, 38) as usize;
        let seek = recs.iter().find(|r| r.0 == seek_at).unwrap();
        assert_eq!(seek.1, RECORD_SEEK_TABLE);
        assert_eq!(seek.3.len(), 20 * (times.len() + 1));
        assert!(seek.3[..20].iter().all(|&x| x == 0));

        let data: Vec<_> = recs.iter().filter(|r| r.1 == RECORD_NEW_DATA).collect();
        assert_eq!(data.len(), times.len());
        for (i, (pos, _, fields, payload)) in data.iter().enumerate() {
            assert_eq!(u64_at(fields, 0), times[i]);
            assert_eq!(u32_at(fields, 8), i as u32 + 1);
            let pixels: Vec<u16> = payload
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .collect();
            assert_eq!(pixels, fs[i].data_mm);
            // The seek table points at the record; the undo position at the previous one.
            let entry = &seek.3[20 * (i + 1)..20 * (i + 2)];
            assert_eq!(
                (u64_at(entry, 0), u64_at(entry, 12)),
                (times[i], *pos as u64)
            );
            let undo = u64_at(&b, pos + 20);
            assert_eq!(undo, if i == 0 { 0 } else { data[i - 1].0 as u64 });
        }
        assert_eq!(recs.last().unwrap().1, RECORD_END);
    }

    #[test]
    fn the_properties_hold_the_video_mode_cropping_and_field_of_view() {
        let intrinsics = k(8, 6);
        let b = oni_bytes(&intrinsics, &[0, 33_333, 66_667], &frames(8, 6, 3)).unwrap();
        let prop = |name: &str| {
            records(&b)
                .into_iter()
                .find_map(|(_, kind, f, _)| {
                    let n = u32_at(f, 0) as usize;
                    let matches = (kind == RECORD_INT_PROPERTY || kind == RECORD_GENERAL_PROPERTY)
                        && &f[4..4 + n] == format!("{name}\0").as_bytes();
                    matches.then(|| {
                        let size = u32_at(f, 4 + n) as usize;
                        f[8 + n..8 + n + size].to_vec()
                    })
                })
                .unwrap_or_else(|| panic!("no property {name}"))
        };
        assert_eq!(
            prop("xnMapOutputMode"),
            [8, 0, 0, 0, 6, 0, 0, 0, 30, 0, 0, 0]
        );
        assert_eq!(prop("oniPixelFormat"), 100u64.to_le_bytes());
        assert_eq!(prop("oniRequiredFrameSize"), 96u64.to_le_bytes());
        assert_eq!(prop("xnCropping"), [0, 0, 0, 0, 0, 0, 0, 0, 8, 0, 6, 0]);
        let fov = prop("xnFOV");
        let (h, v) = (
            f64::from_le_bytes(fov[..8].try_into().unwrap()),
            f64::from_le_bytes(fov[8..].try_into().unwrap()),
        );
        assert!(
            (h - 1.0).abs() < 1e-12 && (v - 0.8).abs() < 1e-12,
            "{h} {v}"
        );
        // Through OpenNI2's f32 and back to focal lengths.
        let back = Intrinsics::from_field_of_view(8, 6, Some((h as f32 as f64, v as f32 as f64)));
        assert!(
            (back.fx - intrinsics.fx).abs() < 1e-6 * intrinsics.fx,
            "{back:?}"
        );
        assert!(
            (back.fy - intrinsics.fy).abs() < 1e-6 * intrinsics.fy,
            "{back:?}"
        );
    }

    #[test]
    fn bad_input_is_refused_with_a_typed_error() {
        let fs = frames(4, 3, 2);
        let e = oni_bytes(&k(4, 3), &[], &[]).unwrap_err();
        assert!(matches!(e, OniWriteError::NoFrames), "{e}");
        let e = oni_bytes(&k(4, 3), &[5], &fs).unwrap_err();
        assert!(matches!(e, OniWriteError::CountMismatch { .. }), "{e}");
        let e = oni_bytes(&k(4, 3), &[5, 5], &fs).unwrap_err();
        assert!(
            e.to_string().contains("depth frame 1 at 5 µs is not after"),
            "{e}"
        );
        let e = oni_bytes(&k(5, 3), &[5, 6], &fs).unwrap_err();
        assert!(
            matches!(
                e,
                OniWriteError::FrameSize {
                    frame: 0,
                    width: 4,
                    ..
                }
            ),
            "{e}"
        );
        let mut off = k(4, 3);
        off.cx = 1.5;
        let e = oni_bytes(&off, &[5, 6], &fs).unwrap_err();
        assert!(
            e.to_string().contains("not the image centre (2, 1.5)"),
            "{e}"
        );
        // The image's direction is written (xnMirror) and read back.
        let direct = Intrinsics {
            mirroring: crate::Mirroring::Direct,
            distortion: None,
            ..k(4, 3)
        };
        for (k, mirrored) in [(direct, false), (k(4, 3), true)] {
            let b = oni_bytes(&k, &[5, 6], &fs).unwrap();
            let index = crate::oni_index::depth_stream_index(&b).unwrap();
            assert_eq!(index.mirrored, Some(mirrored));
        }
        let lens = crate::Distortion::from_opencv(&[0.01, 0.0, 0.0, 0.0]).ok();
        let distorted = Intrinsics {
            distortion: lens,
            ..k(4, 3)
        };
        let e = oni_bytes(&distorted, &[5, 6], &fs).unwrap_err();
        assert!(matches!(e, OniWriteError::Distorted), "{e}");
        let mut bad = k(4, 3);
        bad.fx = f64::NAN;
        let e = oni_bytes(&bad, &[5, 6], &fs).unwrap_err();
        assert!(matches!(e, OniWriteError::Intrinsics(_)), "{e}");
        assert_eq!(timestamp_us(0.032591), Some(32_591));
        assert_eq!(timestamp_us(-1e-3), None);
        assert_eq!(timestamp_us(f64::INFINITY), None);
        assert_eq!(timestamp_us(1e300), None);
    }

    #[test]
    fn a_file_is_written_atomically_and_a_failing_frame_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.oni");
        let fs = frames(4, 3, 3);
        let size = write_oni(&path, &k(4, 3), &[0, 10, 20], |i| Ok(fs[i].clone())).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(size, bytes.len() as u64);
        assert_eq!(bytes, oni_bytes(&k(4, 3), &[0, 10, 20], &fs).unwrap());

        let other = dir.path().join("b.oni");
        let e = write_oni(&other, &k(4, 3), &[0, 10, 20], |i| {
            if i == 2 {
                Err(KinectError::Replay("gone".into()))
            } else {
                Ok(fs[i].clone())
            }
        })
        .unwrap_err();
        assert!(matches!(e, OniWriteError::Frame { frame: 2, .. }), "{e}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only a.oni: {left:?}");

        let e = write_oni(&dir.path().join("no/such.oni"), &k(4, 3), &[0], |i| {
            Ok(fs[i].clone())
        })
        .unwrap_err();
        assert!(matches!(e, OniWriteError::Output(_)), "{e}");
        assert!(e.to_string().contains("no/such.oni"), "{e}");
    }

    mod props {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(48))]

            /// The index reader never panics on a written file cut at any byte, and keeps
            /// exactly the frames whose records are complete.
            #[test]
            fn every_cut_of_a_written_file_reads_as_its_complete_frames(
                w in 2u32..6,
                h in 1u32..4,
                steps in proptest::collection::vec(1u64..100_000, 1..5),
                start in 0u64..1_000_000,
            ) {
                let times: Vec<u64> = steps
                    .iter()
                    .scan(start, |t, d| { let now = *t; *t += d; Some(now) })
                    .collect();
                let fs = frames(w, h, times.len());
                let b = oni_bytes(&k(w, h), &times, &fs).unwrap();
                prop_assert_eq!(depth_frame_times(&b).unwrap(), times.clone());
                let plan = Plan::new(&k(w, h), &times).unwrap();
                for n in 0..b.len() {
                    let complete = (0..times.len())
                        .take_while(|&i| {
                            plan.frame_position(i) + plan.frame_record_bytes() <= n as u64
                        })
                        .count();
                    match depth_frame_times(&b[..n]) {
                        Ok(t) => prop_assert_eq!(&t[..], &times[..complete], "cut at {}", n),
                        Err(OniIndexError::NotOni) => prop_assert!(n < 24),
                        Err(OniIndexError::NoDepthStream | OniIndexError::NoDepthFrames) => {
                            prop_assert_eq!(complete, 0, "cut at {}", n)
                        }
                        Err(e) => prop_assert!(false, "cut at {}: {}", n, e),
                    }
                }
            }
        }
    }
}
