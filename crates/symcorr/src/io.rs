//! The driver's input files: meshes (symcorr-mesh's readers) and joint files (symcorr-kinect's
//! readers, one frame picked). Every command reads its inputs here; outputs are written through
//! [`symcorr_mesh::io::atomic_write`] (see [`crate::output`]).

use crate::PipelineError;
use std::path::Path;
use symcorr_kinect::JointFormat;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;

/// Reads a mesh file (OFF, OBJ, PLY, glTF/GLB, by extension) in the file's vertex order.
pub fn read_mesh(path: &Path) -> Result<TriMesh, PipelineError> {
    Ok(symcorr_mesh::io::read(path)?.mesh)
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
