//! The depth frames of an OpenNI2 `.oni` recording and their timestamps, read from the file's
//! records in pure Rust (no OpenNI2 needed, compiled in every build): [`depth_frame_times`] on
//! bytes in memory, [`depth_frame_times_in`] on a file (or any `Read + Seek`), which reads only
//! the record headers and the few field bytes it needs and skips every frame's payload.
//!
//! What is kept: the timestamps (µs, as in the file) of the `NEW_DATA` records of the first
//! depth node, in file order, up to the `END` record or the end of a file cut short (a record
//! that does not fit in the file ends the walk; the complete frames before it are kept).
//! What is refused, as an [`OniIndexError`]: data not starting with the `NI10` header, a
//! damaged record header, a recording without a depth stream or without depth frames, depth
//! times that do not increase strictly.
//!
//! The layout (OpenNI's `DataRecords.h`, all little-endian, packed): a 24-byte file header
//! (identity `NI10`, version u8 major, u8 minor, u16 maintenance, u32 build, max timestamp u64,
//! max node id u32); then records, each a header of magic `"NIR\0"`, type, node id, fields size
//! (header included), payload size (u32 each) and the undo position (u64 from file version
//! 1.0.1 on, u32 before), then the fields, then the payload. `NODE_ADDED` fields start with the
//! node name (u32 length, bytes) and the node type (u32); `NEW_DATA` fields with the timestamp
//! (u64) and the frame number (u32).
//!
//! The input is untrusted: nothing here panics, and no size field of the file drives an
//! allocation (the only one is the list of times, one per record actually present, so at most
//! one per 36 bytes of input). Fuzzed (`crates/kinect/fuzz`, target `oni_index`).
//!
//! ```
//! use symcorr_kinect::oni_index::{depth_frame_times, OniIndexError};
//! let e = depth_frame_times(b"PK\x03\x04 a zip, not a recording").unwrap_err();
//! assert!(matches!(e, OniIndexError::NotOni));
//! ```

use std::io::{self, BufReader, Read, Seek, SeekFrom};
use thiserror::Error;

/// `"NIR\0"`, the first four bytes of every record.
pub(crate) const RECORD_MAGIC: u32 = 0x0052_494E;
const RECORD_NODE_ADDED_1_0_0_4: u32 = 0x02;
const RECORD_NODE_ADDED_1_0_0_5: u32 = 0x0C;
pub(crate) const RECORD_NODE_ADDED: u32 = 0x0D;
pub(crate) const RECORD_NEW_DATA: u32 = 0x0A;
pub(crate) const RECORD_END: u32 = 0x0B;
pub(crate) const RECORD_INT_PROPERTY: u32 = 0x03;
/// The node type of a depth stream in a `NODE_ADDED` record.
pub(crate) const NODE_TYPE_DEPTH: u32 = 2;
/// The file header: `NI10`, version (u8, u8, u16, u32), max timestamp u64, max node id u32.
const FILE_HEADER_BYTES: u64 = 24;
/// A record header with a 64-bit undo position (file version 1.0.1 and later).
const RECORD_HEADER_BYTES: u64 = 28;
/// A record header with a 32-bit undo position (files before 1.0.1, OpenNI 1.x).
const RECORD_HEADER_BYTES_OLD: u64 = 24;

/// Why an `.oni` file's depth frames could not be listed. The messages do not name the file:
/// the caller does (`oni::OniRecording::open` puts them in a `KinectError::Recording`).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OniIndexError {
    /// The data does not start with an `.oni` file header (`NI10`), or is shorter than one.
    #[error("not an OpenNI recording (expected an .oni file starting with \"NI10\")")]
    NotOni,
    /// A record header is not one: wrong magic, or a fields size smaller than the header.
    #[error("byte {offset}: not a record header (the file is damaged)")]
    DamagedRecord {
        /// Where the record starts, bytes from the start of the file.
        offset: u64,
    },
    /// No `NODE_ADDED` record of a depth node before the end.
    #[error("no depth stream in the recording")]
    NoDepthStream,
    /// A depth stream, but no complete frame of it.
    #[error("no depth frames in the recording")]
    NoDepthFrames,
    /// A depth frame's timestamp is not after the previous one's.
    #[error(
        "depth frame {frame} at {t_us} µs is not after the previous one's {previous_us} µs \
         (times must increase strictly)"
    )]
    TimesNotIncreasing {
        /// The frame (0-based, among the depth frames).
        frame: usize,
        /// Its timestamp, µs.
        t_us: u64,
        /// The previous depth frame's timestamp, µs.
        previous_us: u64,
    },
    /// Reading or seeking failed ([`depth_frame_times_in`] only).
    #[error("reading the recording: {0}")]
    Io(#[from] io::Error),
}

/// What the file says of its depth stream: the frames' timestamps and the stream's mirroring.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DepthStreamIndex {
    /// Every depth frame's timestamp, µs, strictly increasing, at least one.
    pub times_us: Vec<u64>,
    /// The stream's mirroring property (OpenNI's `ONI_STREAM_PROPERTY_MIRRORING`, recorded as
    /// the integer property `xnMirror`) as it stood at the first frame: `Some(true)` for an
    /// image shown as in a mirror (the Kinect SDK's), `Some(false)` for the image as the lens
    /// forms it, `None` when the recording does not say (OpenNI2's Dummy and Kinect-SDK
    /// drivers record none).
    pub mirrored: Option<bool>,
}

/// The timestamps (µs, strictly increasing, at least one) of the depth frames of an `.oni` file
/// held in memory (see the [module docs](self)).
pub fn depth_frame_times(bytes: &[u8]) -> Result<Vec<u64>, OniIndexError> {
    walk(&mut SliceInput(bytes)).map(|i| i.times_us)
}

/// [`depth_frame_times`] of the recording that `reader` holds from its byte 0 to its end (a
/// [`std::fs::File`], for example): reads the record headers and the few field bytes it needs
/// through a buffer, seeking over the payloads, so a large recording is never read whole.
/// The reader's position afterwards is unspecified.
pub fn depth_frame_times_in<R: Read + Seek>(reader: R) -> Result<Vec<u64>, OniIndexError> {
    depth_stream_index_in(reader).map(|i| i.times_us)
}

/// [`depth_frame_times_in`] with the depth stream's recorded mirroring
/// ([`DepthStreamIndex::mirrored`]); same errors.
pub fn depth_stream_index_in<R: Read + Seek>(reader: R) -> Result<DepthStreamIndex, OniIndexError> {
    let mut r = BufReader::new(reader);
    let len = r.seek(SeekFrom::End(0))?;
    walk(&mut ReaderInput { r, at: len, len })
}

/// [`depth_stream_index_in`] of an `.oni` file held in memory.
///
/// ```
/// use symcorr_kinect::oni_index::depth_stream_index;
/// use symcorr_kinect::{oni_write::oni_bytes, DepthFrame, Intrinsics, Mirroring};
/// let k = Intrinsics {
///     mirroring: Mirroring::Direct,
///     ..Intrinsics::from_field_of_view(4, 3, None)
/// };
/// let frame = DepthFrame::new(4, 3, vec![1000; 12]).unwrap();
/// let index = depth_stream_index(&oni_bytes(&k, &[0], &[frame]).unwrap()).unwrap();
/// assert_eq!((index.times_us, index.mirrored), (vec![0], Some(false)));
/// ```
pub fn depth_stream_index(bytes: &[u8]) -> Result<DepthStreamIndex, OniIndexError> {
    walk(&mut SliceInput(bytes))
}

/// Random access to the input: its length, and exact reads at a position.
trait Input {
    fn len(&self) -> u64;
    /// Fills `buf` from `pos` on; the caller has checked that it lies within [`Input::len`].
    fn read_at(&mut self, pos: u64, buf: &mut [u8]) -> Result<(), OniIndexError>;
}

struct SliceInput<'a>(&'a [u8]);

impl Input for SliceInput<'_> {
    fn len(&self) -> u64 {
        self.0.len() as u64
    }

    fn read_at(&mut self, pos: u64, buf: &mut [u8]) -> Result<(), OniIndexError> {
        let src = usize::try_from(pos)
            .ok()
            .and_then(|p| self.0.get(p..))
            .and_then(|s| s.get(..buf.len()))
            .ok_or_else(|| OniIndexError::Io(io::ErrorKind::UnexpectedEof.into()))?;
        buf.copy_from_slice(src);
        Ok(())
    }
}

struct ReaderInput<R> {
    r: BufReader<R>,
    /// The reader's position.
    at: u64,
    len: u64,
}

impl<R: Read + Seek> Input for ReaderInput<R> {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&mut self, pos: u64, buf: &mut [u8]) -> Result<(), OniIndexError> {
        if pos != self.at {
            // Forward within the buffer keeps it; anything else is a real seek.
            match pos.checked_sub(self.at).map(i64::try_from) {
                Some(Ok(ahead)) => self.r.seek_relative(ahead)?,
                _ => {
                    self.r.seek(SeekFrom::Start(pos))?;
                }
            }
        }
        // Unknown until the read succeeds.
        self.at = u64::MAX;
        self.r.read_exact(buf)?;
        self.at = pos.saturating_add(buf.len() as u64);
        Ok(())
    }
}

fn u32_at(buf: &[u8], k: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(b) = buf.get(4 * k..4 * k + 4) {
        w.copy_from_slice(b);
    }
    u32::from_le_bytes(w)
}

/// The name of the integer property OpenNI2's recorder writes a stream's mirroring as.
pub(crate) const MIRROR_PROPERTY: &str = "xnMirror";

/// Walks the records (see the module docs for the layout).
fn walk(input: &mut impl Input) -> Result<DepthStreamIndex, OniIndexError> {
    let len = input.len();
    if len < FILE_HEADER_BYTES {
        return Err(OniIndexError::NotOni);
    }
    let mut head = [0u8; FILE_HEADER_BYTES as usize];
    input.read_at(0, &mut head)?;
    if &head[0..4] != b"NI10" {
        return Err(OniIndexError::NotOni);
    }
    let version = (head[4], head[5], u16::from_le_bytes([head[6], head[7]]));
    let header_bytes = if version < (1, 0, 1) {
        RECORD_HEADER_BYTES_OLD
    } else {
        RECORD_HEADER_BYTES
    };
    let mut depth_node: Option<u32> = None;
    let mut stamps: Vec<u64> = Vec::new();
    let mut mirrored: Option<bool> = None;
    let mut pos = FILE_HEADER_BYTES;
    let mut header = [0u8; RECORD_HEADER_BYTES as usize];
    let header = &mut header[..header_bytes as usize];
    while pos.checked_add(header_bytes).is_some_and(|end| end <= len) {
        input.read_at(pos, header)?;
        let (magic, kind, node, fields, payload) = (
            u32_at(header, 0),
            u32_at(header, 1),
            u32_at(header, 2),
            u64::from(u32_at(header, 3)),
            u64::from(u32_at(header, 4)),
        );
        if magic != RECORD_MAGIC || fields < header_bytes {
            return Err(OniIndexError::DamagedRecord { offset: pos });
        }
        let next = pos.saturating_add(fields).saturating_add(payload);
        if kind == RECORD_END || next > len {
            break; // the end, or a record cut short by an interrupted recording
        }
        // Within the file from here on: pos + fields <= next <= len.
        let field_start = pos + header_bytes;
        let field_bytes = fields - header_bytes;
        match kind {
            RECORD_NODE_ADDED | RECORD_NODE_ADDED_1_0_0_5 | RECORD_NODE_ADDED_1_0_0_4
                if depth_node.is_none() && field_bytes >= 8 =>
            {
                let mut w = [0u8; 4];
                input.read_at(field_start, &mut w)?;
                let name_len = u64::from(u32::from_le_bytes(w));
                if name_len + 8 <= field_bytes {
                    input.read_at(field_start + 4 + name_len, &mut w)?;
                    if u32::from_le_bytes(w) == NODE_TYPE_DEPTH {
                        depth_node = Some(node);
                    }
                }
            }
            // `INT_PROPERTY` fields: the name (u32 length with its NUL, bytes), then the
            // value's size (u32, 8) and the value (u64). The mirroring in effect at the first
            // frame is the stream's.
            RECORD_INT_PROPERTY if Some(node) == depth_node && stamps.is_empty() => {
                let name = MIRROR_PROPERTY.as_bytes();
                let n = name.len() + 1; // with its NUL
                if field_bytes == (4 + n + 12) as u64 {
                    let mut f = [0u8; 4 + MIRROR_PROPERTY.len() + 1 + 12];
                    input.read_at(field_start, &mut f)?;
                    let value = f
                        .get(8 + n..16 + n)
                        .and_then(|v| <[u8; 8]>::try_from(v).ok());
                    if u32_at(&f, 0) as usize == n
                        && f.get(4..4 + name.len()) == Some(name)
                        && f.get(4 + n..8 + n) == Some(&8u32.to_le_bytes()[..])
                    {
                        if let Some(v) = value {
                            mirrored = Some(u64::from_le_bytes(v) != 0);
                        }
                    }
                }
            }
            RECORD_NEW_DATA if Some(node) == depth_node && field_bytes >= 12 => {
                let mut ts = [0u8; 8];
                input.read_at(field_start, &mut ts)?;
                let t = u64::from_le_bytes(ts);
                if let Some(&previous_us) = stamps.last() {
                    if t <= previous_us {
                        return Err(OniIndexError::TimesNotIncreasing {
                            frame: stamps.len(),
                            t_us: t,
                            previous_us,
                        });
                    }
                }
                stamps.push(t);
            }
            _ => {}
        }
        pos = next;
    }
    if depth_node.is_none() {
        return Err(OniIndexError::NoDepthStream);
    }
    if stamps.is_empty() {
        return Err(OniIndexError::NoDepthFrames);
    }
    Ok(DepthStreamIndex {
        times_us: stamps,
        mirrored,
    })
}

/// Builds `.oni` files record by record, for the tests here and in [`crate::oni`].
#[cfg(test)]
pub(crate) mod build {
    pub(crate) use super::NODE_TYPE_DEPTH;
    use super::{RECORD_END, RECORD_NEW_DATA, RECORD_NODE_ADDED};

    /// A record: header (64-bit undo position, or 32-bit with `old`), fields, payload.
    pub(crate) fn record_v(
        old: bool,
        kind: u32,
        node: u32,
        fields: &[u8],
        payload: &[u8],
    ) -> Vec<u8> {
        let header = if old { 24 } else { 28 };
        let mut out = Vec::new();
        for w in [
            super::RECORD_MAGIC,
            kind,
            node,
            header + fields.len() as u32,
            payload.len() as u32,
        ] {
            out.extend(w.to_le_bytes());
        }
        if old {
            out.extend(0u32.to_le_bytes());
        } else {
            out.extend(0u64.to_le_bytes());
        }
        out.extend(fields);
        out.extend(payload);
        out
    }

    /// A record of a file of version 1.0.1 or later.
    pub(crate) fn record(kind: u32, node: u32, fields: &[u8], payload: &[u8]) -> Vec<u8> {
        record_v(false, kind, node, fields, payload)
    }

    /// The file header of version 1.0.1 (or 1.0.0, with 32-bit undo positions, with `old`).
    pub(crate) fn file_header_v(old: bool) -> Vec<u8> {
        let mut out = b"NI10".to_vec();
        out.extend([1, 0]);
        out.extend(u16::from(!old).to_le_bytes());
        out.extend(0u32.to_le_bytes());
        out.extend(u64::MAX.to_le_bytes());
        out.extend(1u32.to_le_bytes());
        out
    }

    pub(crate) fn file_header() -> Vec<u8> {
        file_header_v(false)
    }

    pub(crate) fn node_added_v(old: bool, node: u32, name: &str, ty: u32) -> Vec<u8> {
        let mut f = Vec::new();
        f.extend((name.len() as u32 + 1).to_le_bytes());
        f.extend(name.as_bytes());
        f.push(0);
        f.extend(ty.to_le_bytes());
        f.extend([0u8; 28]); // codec, frames, min/max timestamp, seek table position
        record_v(old, RECORD_NODE_ADDED, node, &f, &[])
    }

    pub(crate) fn node_added(node: u32, name: &str, ty: u32) -> Vec<u8> {
        node_added_v(false, node, name, ty)
    }

    pub(crate) fn new_data_v(old: bool, node: u32, t: u64, frame: u32, payload: &[u8]) -> Vec<u8> {
        let mut f = t.to_le_bytes().to_vec();
        f.extend(frame.to_le_bytes());
        record_v(old, RECORD_NEW_DATA, node, &f, payload)
    }

    pub(crate) fn new_data(node: u32, t: u64, frame: u32) -> Vec<u8> {
        new_data_v(false, node, t, frame, &[7u8; 10])
    }

    pub(crate) fn end() -> Vec<u8> {
        record(RECORD_END, 0, &[], &[])
    }
}

#[cfg(test)]
mod tests {
    use super::build::*;
    use super::*;
    use std::io::Cursor;

    /// Both entry points, which must agree.
    fn times(bytes: &[u8]) -> Result<Vec<u64>, OniIndexError> {
        let from_slice = depth_frame_times(bytes);
        let from_reader = depth_frame_times_in(Cursor::new(bytes));
        match (&from_slice, &from_reader) {
            (Ok(a), Ok(b)) => assert_eq!(a, b),
            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
            _ => panic!("slice {from_slice:?} but reader {from_reader:?}"),
        }
        from_slice
    }

    fn sample() -> Vec<u8> {
        let mut bytes = file_header();
        bytes.extend(node_added(1, "Image", 3));
        bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
        bytes.extend(new_data(1, 5, 1)); // colour: not a depth frame
        bytes.extend(new_data(2, 0, 1));
        bytes.extend(new_data(2, 33_000, 2));
        bytes.extend(end());
        bytes.extend(new_data(2, 66_000, 3)); // after END: not read
        bytes
    }

    /// An `INT_PROPERTY` record as OpenNI2's recorder writes one: name with its NUL, value size
    /// 8, value.
    fn int_property(node: u32, name: &str, value: u64) -> Vec<u8> {
        let mut f = (name.len() as u32 + 1).to_le_bytes().to_vec();
        f.extend(name.as_bytes());
        f.push(0);
        f.extend(8u32.to_le_bytes());
        f.extend(value.to_le_bytes());
        record(super::RECORD_INT_PROPERTY, node, &f, &[])
    }

    #[test]
    fn the_depth_streams_mirroring_is_the_one_recorded_before_its_first_frame() {
        let with = |records: &[Vec<u8>]| {
            let mut bytes = file_header();
            bytes.extend(node_added(1, "Image", 3));
            bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
            for r in records {
                bytes.extend(r);
            }
            let slice = depth_stream_index(&bytes).unwrap();
            assert_eq!(depth_stream_index_in(Cursor::new(&bytes)).unwrap(), slice);
            slice.mirrored
        };
        let frame = |t| new_data(2, t, 1);
        assert_eq!(with(&[frame(0)]), None);
        assert_eq!(
            with(&[int_property(2, "xnMirror", 0), frame(0)]),
            Some(false)
        );
        assert_eq!(
            with(&[int_property(2, "xnMirror", 1), frame(0)]),
            Some(true)
        );
        // The last value before the first frame; later changes, other nodes' and other
        // properties are not the stream's.
        let (off, on) = (
            int_property(2, "xnMirror", 0),
            int_property(2, "xnMirror", 1),
        );
        assert_eq!(with(&[on.clone(), off.clone(), frame(0)]), Some(false));
        assert_eq!(with(&[frame(0), off.clone(), frame(5)]), None);
        assert_eq!(with(&[int_property(1, "xnMirror", 0), frame(0)]), None);
        assert_eq!(with(&[int_property(2, "xnMirrorX", 0), frame(0)]), None);
    }

    #[test]
    fn the_index_keeps_the_depth_nodes_frames_up_to_the_end_record() {
        let bytes = sample();
        assert_eq!(times(&bytes).unwrap(), vec![0, 33_000]);

        // A recording cut short in its last frame keeps the complete ones.
        let mut cut = bytes[..bytes.len() - 1].to_vec();
        let end = end();
        let at = cut.windows(end.len()).position(|w| w == end).unwrap();
        cut.truncate(at + 5);
        assert_eq!(times(&cut).unwrap(), vec![0, 33_000]);
    }

    #[test]
    fn the_index_reads_files_before_version_1_0_1() {
        let mut bytes = file_header_v(true);
        bytes.extend(node_added_v(true, 4, "Depth", NODE_TYPE_DEPTH));
        bytes.extend(new_data_v(true, 4, 10, 1, &[1, 2, 3]));
        bytes.extend(new_data_v(true, 4, 20, 2, &[]));
        assert_eq!(times(&bytes).unwrap(), vec![10, 20]);
    }

    #[test]
    fn the_index_reads_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.oni");
        std::fs::write(&p, sample()).unwrap();
        let f = std::fs::File::open(&p).unwrap();
        assert_eq!(depth_frame_times_in(f).unwrap(), vec![0, 33_000]);
    }

    #[test]
    fn the_index_refuses_what_is_not_a_usable_recording() {
        let e = times(b"PK\x03\x04 not an oni").unwrap_err();
        assert!(matches!(e, OniIndexError::NotOni), "{e}");
        assert!(e.to_string().contains("not an OpenNI recording"), "{e}");
        assert!(matches!(times(b"NI10").unwrap_err(), OniIndexError::NotOni));
        assert!(matches!(times(b"").unwrap_err(), OniIndexError::NotOni));

        let mut bytes = file_header();
        assert!(matches!(
            times(&bytes).unwrap_err(),
            OniIndexError::NoDepthStream
        ));
        bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
        let e = times(&bytes).unwrap_err().to_string();
        assert!(e.ends_with("no depth frames in the recording"), "{e}");

        bytes.extend(new_data(2, 33_000, 1));
        bytes.extend(new_data(2, 33_000, 2));
        let e = times(&bytes).unwrap_err().to_string();
        assert!(e.contains("depth frame 1 at 33000 µs is not after"), "{e}");

        let mut bytes = file_header();
        bytes.extend(b"garbage garbage garbage garbage!");
        let e = times(&bytes).unwrap_err().to_string();
        assert!(e.contains("byte 24: not a record header"), "{e}");

        // A fields size smaller than the header itself.
        let mut bytes = file_header();
        let mut r = node_added(2, "Depth", NODE_TYPE_DEPTH);
        r[12..16].copy_from_slice(&27u32.to_le_bytes());
        bytes.extend(r);
        assert!(matches!(
            times(&bytes).unwrap_err(),
            OniIndexError::DamagedRecord { offset: 24 }
        ));
    }

    #[test]
    fn size_fields_at_their_maximum_end_the_walk_without_allocating() {
        let mut bytes = file_header();
        bytes.extend(node_added(2, "Depth", NODE_TYPE_DEPTH));
        bytes.extend(new_data(2, 1, 1));
        let mut huge = new_data(2, 2, 2);
        huge[12..20].copy_from_slice(&[0xFF; 8]); // fields and payload sizes u32::MAX
        bytes.extend(huge);
        assert_eq!(times(&bytes).unwrap(), vec![1]);

        // A depth node whose name length runs past its fields is not taken.
        let mut bytes = file_header();
        let mut node = node_added(2, "Depth", NODE_TYPE_DEPTH);
        node[28..32].copy_from_slice(&u32::MAX.to_le_bytes());
        bytes.extend(node);
        bytes.extend(new_data(2, 1, 1));
        assert!(matches!(
            times(&bytes).unwrap_err(),
            OniIndexError::NoDepthStream
        ));
    }

    mod props {
        use super::*;
        use proptest::prelude::*;

        /// A valid recording: (old layout?, records as (bytes, depth time if a depth frame)).
        fn arb_recording() -> impl Strategy<Value = (Vec<u8>, Vec<(usize, u64)>)> {
            (
                any::<bool>(),
                0u32..3,
                proptest::collection::vec((0u8..3, 1u64..100_000, 0usize..40), 0..12),
                any::<bool>(),
            )
                .prop_map(|(old, colour_nodes, steps, with_end)| {
                    let depth = 7;
                    let mut bytes = file_header_v(old);
                    for n in 0..colour_nodes {
                        bytes.extend(node_added_v(old, n, "Image", 3));
                    }
                    bytes.extend(node_added_v(old, depth, "Depth", NODE_TYPE_DEPTH));
                    // (end of the record, its time) for every depth frame
                    let mut frames = Vec::new();
                    let mut t = 0u64;
                    for (i, (what, dt, payload)) in steps.into_iter().enumerate() {
                        let payload = vec![0xA5u8; payload];
                        match what {
                            0 if colour_nodes > 0 => {
                                bytes.extend(new_data_v(old, 0, dt, i as u32, &payload))
                            }
                            1 => bytes.extend(record_v(old, 0x05, depth, &payload, &[])),
                            _ => {
                                t += dt;
                                bytes.extend(new_data_v(old, depth, t, i as u32, &payload));
                                frames.push((bytes.len(), t));
                            }
                        }
                    }
                    if with_end {
                        bytes.extend(record_v(old, RECORD_END, 0, &[], &[]));
                        bytes.extend(new_data_v(old, depth, t + 1, 0, &[]));
                    }
                    (bytes, frames)
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn arbitrary_bytes_never_panic(
                mut bytes in proptest::collection::vec(any::<u8>(), 0..400),
                header in any::<bool>(),
            ) {
                if header && bytes.len() >= 28 {
                    // Reach the record walk: a file header and a record magic.
                    bytes[..4].copy_from_slice(b"NI10");
                    bytes[24..28].copy_from_slice(&RECORD_MAGIC.to_le_bytes());
                }
                if let Ok(t) = times(&bytes) {
                    prop_assert!(!t.is_empty());
                    prop_assert!(t.windows(2).all(|w| w[0] < w[1]));
                    prop_assert!(24 + 36 * t.len() <= bytes.len());
                }
            }

            #[test]
            fn every_prefix_gives_a_prefix_of_the_frames((bytes, frames) in arb_recording()) {
                let all: Vec<u64> = frames.iter().map(|&(_, t)| t).collect();
                match times(&bytes) {
                    Ok(t) => prop_assert_eq!(&t, &all),
                    Err(e) => {
                        prop_assert!(all.is_empty());
                        prop_assert!(matches!(e, OniIndexError::NoDepthFrames), "{}", e);
                    }
                }
                for n in 0..bytes.len() {
                    let want: Vec<u64> =
                        frames.iter().take_while(|&&(end, _)| end <= n).map(|&(_, t)| t).collect();
                    match times(&bytes[..n]) {
                        Ok(t) => prop_assert_eq!(t, want, "prefix of {} bytes", n),
                        Err(OniIndexError::NotOni) => prop_assert!(n < 24),
                        Err(OniIndexError::NoDepthStream | OniIndexError::NoDepthFrames) => {
                            prop_assert!(want.is_empty(), "prefix of {} bytes", n);
                        }
                        Err(e) => prop_assert!(false, "prefix of {} bytes: {}", n, e),
                    }
                }
            }

            #[test]
            fn single_byte_corruptions_never_panic(
                (bytes, _) in arb_recording(),
                at in any::<proptest::sample::Index>(),
                value in any::<u8>(),
            ) {
                let mut bytes = bytes;
                let i = at.index(bytes.len());
                bytes[i] = value;
                if let Ok(t) = times(&bytes) {
                    prop_assert!(!t.is_empty());
                    prop_assert!(t.windows(2).all(|w| w[0] < w[1]));
                }
            }
        }
    }
}
