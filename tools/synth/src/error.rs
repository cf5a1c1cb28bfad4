use std::path::PathBuf;

/// Everything that can go wrong while loading assets or generating data.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A text asset is malformed.
    #[error("{path}:{line}: {msg}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0 when the whole file is at fault).
        line: usize,
        /// What was expected.
        msg: String,
    },
    /// A JSON asset or input is malformed.
    #[error("{path}: {msg}")]
    Json {
        /// The file.
        path: PathBuf,
        /// What was expected.
        msg: String,
    },
    /// A request that cannot be met (unknown pose, bone, shape, bad option value).
    #[error("{0}")]
    Invalid(String),
    /// The generated mesh failed validation.
    #[error(transparent)]
    Mesh(#[from] symcorr_mesh::MeshError),
    /// An OpenNI2 recording (.oni) could not be written.
    #[error(transparent)]
    Oni(#[from] symcorr_kinect::oni_write::OniWriteError),
}

impl SynthError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        SynthError::Io {
            path: path.into(),
            source,
        }
    }
    pub(crate) fn parse(path: impl Into<PathBuf>, line: usize, msg: impl Into<String>) -> Self {
        SynthError::Parse {
            path: path.into(),
            line,
            msg: msg.into(),
        }
    }
    pub(crate) fn json(path: impl Into<PathBuf>, msg: impl std::fmt::Display) -> Self {
        SynthError::Json {
            path: path.into(),
            msg: msg.to_string(),
        }
    }
}

/// Result alias.
pub type Result<T> = std::result::Result<T, SynthError>;
