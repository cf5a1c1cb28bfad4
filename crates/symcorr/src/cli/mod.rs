//! One module per subcommand. Each exposes `XArgs` (clap `Args`) and `run(XArgs) -> Result<(), CliError>`.

pub mod bench;
pub mod demo;
pub mod label;
pub mod match_cmd;
pub mod progress;
pub mod scan;
pub mod spectrum;
pub mod track;
pub mod view;

/// A user error: printed as one line on stderr, exit status 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CliError(pub String);

/// Parses a `--joints-format` value (DESIGN.md: joints are detected from content unless forced).
pub fn joints_format(name: Option<&str>) -> Result<Option<symcorr_kinect::JointFormat>, CliError> {
    name.map(|n| {
        symcorr_kinect::JointFormat::from_name(n).ok_or_else(|| {
            CliError(format!(
                "--joints-format {n:?}: expected json, kinect-text, ntu or k4abt"
            ))
        })
    })
    .transpose()
}

impl CliError {
    /// Wraps any error with a context prefix, e.g. the file it concerns.
    pub fn with(context: impl std::fmt::Display, e: impl std::fmt::Display) -> Self {
        CliError(format!("{context}: {e}"))
    }
}
