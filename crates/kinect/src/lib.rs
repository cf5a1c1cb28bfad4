//! Kinect ingestion for symcorr: joint dumps and logs → canonical [`Skeleton`]s, depth frames →
//! scan meshes, and (feature `openni2`) OpenNI2 devices and `.oni` recordings.
//!
//! * [`joints`]: `symcorr.joints/1` JSON (read/write; skeletons `kinect_v1`, `nite`, `kinect_v2`),
//!   Kinect SDK v1 text dumps, NTU RGB+D `.skeleton` files; format detected from the content.
//! * [`mapping`]: the NiTE 15-joint and Kinect v2 25-joint tables and the interpolation rules.
//! * [`camera`]: [`Intrinsics`] and the single projection/unprojection convention.
//! * [`depth`]: [`DepthFrame`] and PNG-16 reading/writing.
//! * [`replay`]: a frame by index/time, robust window average, bone-length consistency.
//! * [`handedness`]: is a skeleton's left/right consistent with a mesh?
//! * [`scan`]: depth frame → organised cloud → scan mesh (floor, background, discontinuities).
//! * `openni2` (feature `openni2`): safe OpenNI2 wrapper; devices, `.oni` playback, recorder.
//!
//! ## Decisions the design leaves open
//!
//! * Joint logs are always held in metres; `symcorr.joints/1` may say `"units": "mm"` and is
//!   converted on reading. The writer always writes the canonical 20 joints (`kinect_v1`, `m`),
//!   and an extra per-frame `"interpolated": [joint names]` list when an importer interpolated any.
//! * A `kinect_v1` JSON frame must name all 20 joints (missing → error); `nite` and `kinect_v2`
//!   frames may lack joints, which are interpolated ([`mapping`]).
//! * Files without timestamps get `time_s = frame / 30`.
//! * Writes are atomic: a temporary file next to the target, then a rename.
//! * Camera conventions ([`camera`]): Kinect camera space (+x to the sensor's left, +y up, +z
//!   into the scene) and the Kinect SDK v1 projection `u = cx + fx·x/z`, `v = cy − fy·y/z`
//!   (SDK v1's mirrored depth image). [`Intrinsics::kinect_v1`] is the SDK's nominal
//!   571.26 px focal length at 640×480.
//! * Kinect SDK text dumps write untracked joints as `0 0 0`; they are interpolated and flagged.
//! * NTU files: frames without the selected body are skipped (some clips start without one).
//! * Replay's robust average: coordinate-wise median, outlier frames (median joint deviation
//!   > 3× typical + 1 cm) dropped, then confidence-weighted median ([`replay`]).
//! * Scan meshing thresholds ([`ScanOptions`]): 5 cm depth discontinuity, 2 cm floor distance,
//!   30 cm background margin around the skeleton, floor within 35° of horizontal and ≥ 30 cm
//!   below the hips.
//! * OpenNI2 is initialised once per process and never shut down (`oniShutdown` crashes on this
//!   machine's OpenNI 2.2; see `openni2`).
//!
//! [`Skeleton`]: symcorr_attach::Skeleton

pub mod camera;
pub mod depth;
mod error;
mod geom;
pub mod handedness;
pub mod joints;
pub mod mapping;
pub mod ntu;
#[cfg(feature = "openni2")]
pub mod openni2;
pub mod replay;
pub mod scan;
pub mod sdk_text;

pub use camera::Intrinsics;
pub use depth::{read_depth_png16, write_depth_png16, DepthFrame};
pub use error::KinectError;
pub use handedness::{check_handedness, Handedness, HandednessReport};
pub use joints::{
    read_joints, read_joints_with_format, write_joints_json, JointFormat, JointFrame, JointLog,
};
pub use mapping::SkeletonKind;
pub use replay::{BoneLengthReport, FrameSelect};
pub use scan::{fuse_depth_frames, scan_mesh, ScanMesh, ScanOptions};

use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file + rename) through the one owner of that,
/// [`symcorr_mesh::io::write_file_atomic`].
pub(crate) fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), KinectError> {
    symcorr_mesh::io::write_file_atomic(path, bytes).map_err(|e| match e {
        symcorr_mesh::MeshError::Io { file, source } => KinectError::io(&file, source),
        other => KinectError::io(
            &path.display().to_string(),
            std::io::Error::other(other.to_string()),
        ),
    })
}
