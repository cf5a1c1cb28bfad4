//! Kinect ingestion for symcorr: joint dumps and logs → canonical [`Skeleton`]s, depth frames →
//! scan meshes, and (feature `openni2`) OpenNI2 devices and `.oni` recordings.
//!
//! # Data flow
//! * Joints: a file in any supported format ([`joints`]: `symcorr.joints/1` JSON with
//!   skeletons `kinect_v1`, `nite` or `kinect_v2`; Kinect SDK v1 text dumps, [`sdk_text`]; NTU
//!   RGB+D `.skeleton` files, [`ntu`]; Azure Kinect body tracking JSON, [`k4abt`]; detected
//!   from the content) → [`mapping`] onto the 20
//!   Kinect v1 joints (missing joints interpolated along their chain and flagged) → a
//!   [`JointLog`] in metres → [`replay`]: a frame by index or time, or a robust average over a
//!   window ([`FrameSelect`]) → one [`Skeleton`] for symcorr-attach.
//! * Depth: a PNG-16 frame ([`depth`]) or an OpenNI2 stream (`openni2`) + [`Intrinsics`]
//!   ([`camera`]) → organised point cloud → [`scan_mesh`] (background, floor and depth
//!   discontinuities removed; [`scan`]). Whether a skeleton's left/right agree with a scan is
//!   symcorr-attach's `handedness_verdict` (this crate depends on mesh and skeleton only).
//! * Recordings: a recording folder ([`Recording`]: intrinsics, numbered PNG-16 depth frames, their
//!   times) → per depth frame, the joint log's skeleton at its time ([`JointTrack`], interpolated
//!   or skipped), smoothed over time ([`SkeletonFilter`], one-euro) and checked for left/right
//!   swaps between frames ([`swap_evidence`]; [`recording`]). The offset between the log's
//!   clock and the depth clock can be estimated from the frames themselves ([`clock`]: the
//!   offset whose joints lie least in front of the surface the camera saw). A tracker reads
//!   either a folder or (feature `openni2`) an OpenNI2 `.oni` file through one type,
//!   [`DepthSource`] ([`source`]; the `.oni` side: `oni::OniRecording`, times from the file's
//!   frame timestamps, intrinsics from the stream's field of view). Listing an `.oni` file's
//!   depth frames and their times needs no OpenNI2 ([`oni_index`], in every build), and neither
//!   does writing one that OpenNI2's player plays ([`oni_write`]: from timed depth frames or a
//!   recording folder).
//!
//! ```
//! use symcorr_skeleton::Joint;
//! use symcorr_kinect::{read_joints, FrameSelect, Intrinsics, SkeletonKind};
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/kinect/standing_nite.json");
//! let log = read_joints(path).unwrap(); // NiTE's 15 joints, in millimetres
//! assert_eq!(log.skeleton_kind, SkeletonKind::Nite);
//! let skeleton = log.select(FrameSelect::Index(0)).unwrap(); // 20 joints, metres
//! let head = skeleton.position(Joint::Head);
//! assert!((head[2] - 2.5).abs() < 1e-9);
//! // NiTE has no wrists: interpolated 80 % of the way elbow → hand, and flagged.
//! assert!(skeleton.interpolated[Joint::WristLeft.index()]);
//! let [u, v] = Intrinsics::kinect_v1().project(&head); // pixel of the head in the depth image
//! assert!(u.is_finite() && v.is_finite());
//! ```
//!
//! # Invariants and conventions
//! * Joint logs are held in metres in Kinect camera space (+x to the sensor's left, +y up, +z
//!   into the scene); `"units": "mm"` is converted on reading, and the Azure Kinect SDK's
//!   millimetres in its own camera frame (+x right, +y down) by a half turn about the optical
//!   axis ([`k4abt`]). The writer always writes the
//!   canonical 20 joints (`kinect_v1`, `m`) and lists interpolated joints per frame. A
//!   `kinect_v1` frame must name all 20 joints; files without timestamps get
//!   `time_s = frame / 30`; SDK text dumps' untracked `0 0 0` joints are interpolated.
//! * One projection convention ([`Intrinsics::project`]): the Kinect SDK v1's
//!   `u = cx + fx·x/z`, `v = cy − fy·y/z` (its mirrored depth image), or `u = cx − fx·x/z` for
//!   an image as the lens forms it ([`Mirroring::Direct`]: Azure Kinect, RealSense), through
//!   OpenCV's lens model when the intrinsics have one ([`Distortion`]);
//!   [`Intrinsics::kinect_v1`] is the nominal 571.26 px focal length at 640×480.
//! * Every failure is a typed [`KinectError`] naming the file and the line (text formats) or
//!   frame (JSON); nothing panics on bad input (fuzzed: `crates/kinect/fuzz`). Writes are atomic.
//! * Defaults of the robust average ([`replay`]) and of scan meshing ([`ScanOptions`]: 5 cm
//!   depth discontinuity, 2 cm floor distance, 30 cm background margin) are documented there.
//! * OpenNI2 is initialised once per process and never shut down (`oniShutdown` crashes on
//!   this machine's OpenNI 2.2).
//!
//! [`Skeleton`]: symcorr_skeleton::Skeleton

pub mod camera;
pub mod clock;
pub mod depth;
mod error;
mod geom;
pub mod joints;
pub mod k4abt;
pub mod mapping;
pub mod ntu;
#[cfg(feature = "openni2")]
pub mod oni;
pub mod oni_index;
pub mod oni_write;
#[cfg(feature = "openni2")]
#[allow(unsafe_code)] // the OpenNI2 C API: every call is wrapped and checked in this module
pub mod openni2;
pub mod recording;
pub mod replay;
pub mod scan;
pub mod sdk_text;
pub mod source;

pub use camera::{Distortion, Intrinsics, Mirroring, PixelRays};
pub use depth::{read_depth_png16, write_depth_png16, DepthFrame};
pub use error::KinectError;
pub use joints::{
    read_joints, read_joints_with_format, write_joints_json, JointFormat, JointFrame, JointLog,
};
pub use mapping::SkeletonKind;
pub use recording::{
    arms_swapped, legs_swapped, limb_swap_evidence, parse_depth_times, swap_evidence,
    JointMoveFilter, JointTrack, LimbPair, OneEuroFilter, Recording, SkeletonFilter, SkipReason,
    TimedSkeleton,
};
pub use replay::{BoneLengthReport, FrameSelect};
pub use scan::{
    fuse_depth_frames, scan_mesh, scan_mesh_with_rays, ComponentFilter, ScanMesh, ScanOptions,
};
pub use source::DepthSource;

use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file + rename) through the one owner of that,
/// [`symcorr_mesh::io::atomic_write`], its I/O error as this crate's [`KinectError::Io`].
pub(crate) fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), KinectError> {
    symcorr_mesh::io::atomic_write(path, bytes).map_err(|e| match e {
        symcorr_mesh::MeshError::Io { file, source } => KinectError::io(&file, source),
        other => KinectError::io(
            &path.display().to_string(),
            std::io::Error::other(other.to_string()),
        ),
    })
}
