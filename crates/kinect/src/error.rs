use thiserror::Error;

/// Everything that can go wrong reading joint dumps, depth frames and recordings, or building a
/// scan mesh.
///
/// File errors carry the file name (`<memory>` for in-memory input) and, for text formats, the
/// 1-based line; for JSON the frame index (0-based, as in the file's `frames` array).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum KinectError {
    /// The file could not be opened, read or written.
    #[error("{file}: {source}")]
    Io {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A text file (Kinect SDK text dump, NTU `.skeleton`) is malformed at a line (1-based).
    #[error("{file}:{line}: {message}")]
    Parse {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// The line (1-based).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A JSON file is not valid JSON or does not have the expected shape.
    #[error("{file}: {message}")]
    Json {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A frame of a joint file is invalid (missing or non-finite joint, bad confidence, ...).
    #[error("{file}: frame {frame}: {message}")]
    Frame {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// The frame (0-based).
        frame: usize,
        /// What is wrong.
        message: String,
    },
    /// A `symcorr.joints/1` file names a skeleton this crate does not know.
    #[error(
        "{file}: unknown skeleton {name:?}; expected \"kinect_v1\", \"nite\" or \"kinect_v2\""
    )]
    UnknownSkeleton {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// The skeleton name found.
        name: String,
    },
    /// The joint file format could not be recognised from the content.
    #[error("{file}: unrecognised joint file format: {message}")]
    UnknownFormat {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// No usable frame: the file has no frames, or no frame has the requested/any body.
    #[error("{file}: {message}")]
    NoBody {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A PNG depth image is malformed or not 16-bit greyscale.
    #[error("{file}: {message}")]
    Png {
        /// The file (`<memory>` for in-memory input).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A depth frame does not match the size its intrinsics (or the call) expect.
    #[error("depth frame is {width}x{height} with {values} values, expected {expected}")]
    DepthSize {
        /// Frame width in pixels.
        width: u32,
        /// Frame height in pixels.
        height: u32,
        /// Number of depth values given.
        values: usize,
        /// What was expected.
        expected: String,
    },
    /// Invalid camera intrinsics.
    #[error("invalid intrinsics: {0}")]
    Intrinsics(String),
    /// A replay request that the log cannot satisfy (frame out of range, empty window, ...).
    #[error("{0}")]
    Replay(String),
    /// A recording folder does not have the expected layout, or a frame of it does not fit it
    /// (naming the folder or file).
    #[error("{file}: {message}")]
    Recording {
        /// The folder or file.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// The file is an OpenNI2 recording (`.oni`), but this build reads none: symcorr-kinect was
    /// built without its `openni2` feature.
    #[error(
        "{file}: an OpenNI2 recording (.oni), but this build cannot read one: \
         rebuild with `--features openni2` (needs libopenni2-dev)"
    )]
    OniNotBuilt {
        /// The `.oni` file.
        file: String,
    },
    /// A joint log cannot be used as a track (empty, times not increasing, bad offset), or its
    /// clock offset cannot be estimated from a recording ([`crate::clock`]).
    #[error("joint track: {0}")]
    Track(String),
    /// A one-euro filter parameter is out of range ([`crate::OneEuroFilter::new`]).
    #[error("one-euro filter {parameter} = {value}: expected {expected}")]
    FilterParameter {
        /// The parameter.
        parameter: &'static str,
        /// Its value.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// A scan option is out of range ([`crate::ScanOptions::validate`]).
    #[error("scan option {option} = {value}: expected {expected}")]
    ScanOption {
        /// The option (the [`crate::ScanOptions`] field).
        option: &'static str,
        /// Its value.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// Building the scan mesh failed (e.g. nothing left after background removal).
    #[error("scan: {0}")]
    Scan(String),
    /// The depth image and the joints disagree about left and right: clearly more joints lie
    /// on the body with the image's columns reversed ([`crate::scan::check_mirroring`]).
    #[error("the depth image and the joints disagree about left and right: {given} joints lie on the body with the image read as {}, {reversed} with its columns reversed; if the camera's depth is {} (an Azure Kinect's, Orbbec's or RealSense's is not mirrored, the Kinect SDK's is), set \"mirrored\": {} in the intrinsics, else the joints' x axis is reversed", if *.stated_mirrored { "mirrored" } else { "not mirrored" }, if *.stated_mirrored { "not mirrored" } else { "mirrored" }, !*.stated_mirrored)]
    MirroringMismatch {
        /// Joints on the body as the intrinsics read the image.
        given: usize,
        /// Joints on the body with the columns reversed.
        reversed: usize,
        /// The intrinsics say the image is mirrored (the Kinect SDK's convention).
        stated_mirrored: bool,
    },
    /// The scan is much taller than its skeleton along the spine
    /// ([`crate::scan::check_scale`]).
    #[error("the scan is {ratio:.2}× as tall as its skeleton along the spine (a body's own joints measure 0.85–1.12×): the intrinsics' focal length (fx {fx}) may be another camera's or in other units, or the joints may be another subject's")]
    ScaleMismatch {
        /// [`crate::scan::height_ratio`].
        ratio: f64,
        /// The focal length the image was read with, pixels.
        fx: f64,
    },
    /// An error from the mesh crate.
    #[error(transparent)]
    Mesh(#[from] symcorr_mesh::MeshError),
    /// An OpenNI2 call failed; `message` is OpenNI2's extended error text (`oniGetExtendedError`).
    #[error("OpenNI2 {call} failed (status {status}): {message}")]
    OpenNi {
        /// The OpenNI2 function.
        call: String,
        /// Its status code.
        status: i32,
        /// What is wrong.
        message: String,
    },
}

impl KinectError {
    pub(crate) fn io(file: &str, source: std::io::Error) -> Self {
        KinectError::Io {
            file: file.to_string(),
            source,
        }
    }
}

/// Reads a whole input file through symcorr-mesh's bounded reader (at most
/// `DEFAULT_MAX_INPUT_BYTES`): a wrong path such as `/dev/zero` is an error, not exhausted memory.
/// I/O errors stay [`KinectError::Io`].
pub(crate) fn read_input(path: &std::path::Path) -> Result<Vec<u8>, KinectError> {
    use symcorr_mesh::{io, MeshError};
    match io::read_input(path, io::DEFAULT_MAX_INPUT_BYTES) {
        Err(MeshError::Io { file, source }) => Err(KinectError::Io { file, source }),
        other => Ok(other?),
    }
}

/// A whole input file ([`read_input`]) as UTF-8 text, and the file's name for messages. Bytes
/// that are not UTF-8 give the error `not_utf8` builds from the file's name and a message
/// naming the first bad byte (each reader says which kind of error that is for its format).
pub(crate) fn read_input_text(
    path: &std::path::Path,
    not_utf8: impl FnOnce(String, String) -> KinectError,
) -> Result<(String, String), KinectError> {
    let file = path.display().to_string();
    let bytes = read_input(path)?;
    match String::from_utf8(bytes) {
        Ok(text) => Ok((text, file)),
        Err(e) => {
            let message = format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to());
            Err(not_utf8(file, message))
        }
    }
}
