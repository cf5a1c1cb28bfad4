//! The driver's input files: meshes (symcorr-mesh's readers) and joint files (symcorr-kinect's
//! readers, one frame picked). Every command reads its inputs here; outputs are written through
//! [`symcorr_mesh::io::atomic_write`] (see [`crate::output`]).

use crate::PipelineError;
use std::path::Path;
use symcorr_kinect::JointFormat;
use symcorr_mesh::io::ReadOptions;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;

/// Parses a byte count: plain bytes (`1048576`) or a whole number with a binary suffix
/// `K`, `M`, `G` or `T` (case-insensitive, optionally followed by `B` or `iB`: `2G`, `512MiB`).
///
/// ```
/// use symcorr::io::parse_byte_size;
/// assert_eq!(parse_byte_size("2G"), Ok(2 << 30));
/// assert_eq!(parse_byte_size("512m"), Ok(512 << 20));
/// assert_eq!(parse_byte_size("1000"), Ok(1000));
/// assert!(parse_byte_size("1.5G").is_err());
/// ```
pub fn parse_byte_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let digits = upper.trim_end_matches(|c: char| c.is_ascii_alphabetic());
    let suffix = &upper[digits.len()..];
    let shift = match suffix {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => {
            return Err(format!(
                "{text:?}: unknown size suffix {suffix:?}; use bytes or K, M, G, T (powers of 1024)"
            ))
        }
    };
    let n: u64 = digits
        .parse()
        .map_err(|_| format!("{text:?} is not a byte count (e.g. 1048576, 512M, 2G)"))?;
    if n == 0 {
        return Err(format!("{text:?}: the limit must be at least 1 byte"));
    }
    n.checked_mul(1u64 << shift)
        .ok_or_else(|| format!("{text:?} does not fit 64 bits"))
}

/// Reads a mesh file (OFF, OBJ, PLY, glTF/GLB, by extension) in the file's vertex order,
/// refusing inputs over `max_input_bytes` (`MeshError::InputTooLarge`; the file plus a
/// `.gltf`'s external buffers; the command line's `--max-input-size`, by default
/// `symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES`, 1 GiB).
pub fn read_mesh(path: &Path, max_input_bytes: u64) -> Result<TriMesh, PipelineError> {
    let options = ReadOptions {
        max_input_bytes,
        ..ReadOptions::default()
    };
    Ok(symcorr_mesh::io::read_with_options(path, &options)?.mesh)
}

/// Reads a joint file (any supported format, detected from the content) and picks a frame
/// (`None`: the first).
pub fn read_skeleton(path: &Path, frame: Option<usize>) -> Result<Skeleton, PipelineError> {
    read_skeleton_as(path, frame, None)
}

/// Like [`read_skeleton`], with the joint format forced (`--joints-format`) instead of detected
/// from the content when `format` is `Some`.
///
/// Errors: [`PipelineError::Joints`] for a file that does not read, [`PipelineError::File`]
/// for a frame the file does not have.
pub fn read_skeleton_as(
    path: &Path,
    frame: Option<usize>,
    format: Option<JointFormat>,
) -> Result<Skeleton, PipelineError> {
    let log = match format {
        Some(f) => symcorr_kinect::read_joints_with_format(path, f)?,
        None => symcorr_kinect::read_joints(path)?,
    };
    let n = log.frames.len();
    let i = frame.unwrap_or(0);
    log.frames
        .into_iter()
        .nth(i)
        .map(|f| f.skeleton)
        .ok_or_else(|| PipelineError::File {
            file: path.display().to_string(),
            message: format!("frame {i} requested, the file has {n} frame(s)"),
        })
}

#[cfg(test)]
mod tests {
    use super::parse_byte_size;

    #[test]
    fn byte_sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_byte_size("1"), Ok(1));
        assert_eq!(parse_byte_size("4k"), Ok(4096));
        assert_eq!(parse_byte_size("3MiB"), Ok(3 << 20));
        assert_eq!(parse_byte_size(" 2GB "), Ok(2 << 30));
        assert_eq!(parse_byte_size("1T"), Ok(1 << 40));
        for bad in ["", "G", "0", "-1", "1.5G", "2X", "99999999999T"] {
            assert!(parse_byte_size(bad).is_err(), "{bad:?}");
        }
    }
}
