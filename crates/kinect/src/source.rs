//! One way to read a recorded session, whatever it was recorded as ([`DepthSource`]): a
//! recording folder ([`Recording`]) or, with the `openni2` feature, an OpenNI2 `.oni` file
//! (`OniRecording`). Both give a frame count, each frame's time in seconds, the
//! camera's intrinsics and one depth frame at a time, never all frames at once.
//!
//! ```
//! use symcorr_kinect::{DepthSource, KinectError};
//! // A `.oni` path without the `openni2` feature is a typed error that says what to do.
//! # #[cfg(not(feature = "openni2"))] {
//! let dir = tempfile::tempdir().unwrap();
//! let oni = dir.path().join("session.oni");
//! std::fs::write(&oni, b"NI10").unwrap();
//! let e = DepthSource::open(&oni).unwrap_err();
//! assert!(matches!(e, KinectError::OniNotBuilt { .. }));
//! assert!(e.to_string().contains("rebuild with `--features openni2`"));
//! # }
//! ```

use crate::camera::Intrinsics;
use crate::depth::DepthFrame;
use crate::error::KinectError;
use crate::recording::Recording;
use std::path::Path;

/// A recorded session's depth frames: a recording folder or an `.oni` file (see the
/// [module docs](self)). Frames are best read in increasing order: an `.oni` file is read
/// forward and reopened to go back.
#[derive(Debug)]
#[non_exhaustive]
pub enum DepthSource {
    /// A recording folder (`symcorr.recording/1`).
    Folder(Recording),
    /// An OpenNI2 recording.
    #[cfg(feature = "openni2")]
    Oni(crate::oni::OniRecording),
}

impl DepthSource {
    /// Opens `path`: a file whose name ends in `.oni` (any case) as an OpenNI2 recording,
    /// anything else as a recording folder ([`Recording::open`]).
    ///
    /// Errors: those of [`Recording::open`] or `OniRecording::open`;
    /// [`KinectError::OniNotBuilt`] for a `.oni` file in a build without the `openni2` feature.
    pub fn open(path: impl AsRef<Path>) -> Result<DepthSource, KinectError> {
        let path = path.as_ref();
        let oni = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("oni"))
            && !path.is_dir();
        if oni {
            open_oni(path)
        } else {
            Recording::open(path).map(DepthSource::Folder)
        }
    }

    /// The number of depth frames (at least 1).
    pub fn len(&self) -> usize {
        match self {
            DepthSource::Folder(r) => r.len(),
            #[cfg(feature = "openni2")]
            DepthSource::Oni(r) => r.len(),
        }
    }

    /// Always `false`: both kinds of recording refuse to open without frames.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The time of frame `i` in seconds (`depth_times.txt`, or the `.oni` frame's timestamp),
    /// `None` past the last frame.
    pub fn time(&self, i: usize) -> Option<f64> {
        match self {
            DepthSource::Folder(r) => r.time(i),
            #[cfg(feature = "openni2")]
            DepthSource::Oni(r) => r.time(i),
        }
    }

    /// Every frame's time in seconds, strictly increasing.
    pub fn times(&self) -> &[f64] {
        match self {
            DepthSource::Folder(r) => r.times(),
            #[cfg(feature = "openni2")]
            DepthSource::Oni(r) => r.times(),
        }
    }

    /// The depth camera's intrinsics (`intrinsics.json`, or the `.oni` stream's field of view
    /// and video mode).
    pub fn intrinsics(&self) -> &Intrinsics {
        match self {
            DepthSource::Folder(r) => r.intrinsics(),
            #[cfg(feature = "openni2")]
            DepthSource::Oni(r) => r.intrinsics(),
        }
    }

    /// Replaces the camera's intrinsics with `k` — a calibration of the camera (an `.oni`
    /// stream is read with its principal point at the centre, its focal length from the field
    /// of view and its recorded mirroring), or the image's direction
    /// ([`Mirroring`](crate::Mirroring)) of a stream that recorded none. Frames are then
    /// unprojected with `k`.
    ///
    /// Errors: [`KinectError::Intrinsics`] when `k` does not validate or describes another
    /// image size than the recording's frames (nothing is replaced then).
    ///
    /// ```
    /// use symcorr_kinect::{DepthSource, Intrinsics, Mirroring};
    /// let mut source = DepthSource::open("../../fixtures/synth/recording").unwrap();
    /// let direct = Intrinsics { mirroring: Mirroring::Direct, ..*source.intrinsics() };
    /// source.set_intrinsics(direct).unwrap();
    /// assert_eq!(source.intrinsics().mirroring, Mirroring::Direct);
    /// assert!(source.set_intrinsics(Intrinsics::kinect_v1()).is_err()); // 640×480, not 320×240
    /// ```
    pub fn set_intrinsics(&mut self, k: Intrinsics) -> Result<(), KinectError> {
        k.validate()?;
        let now = self.intrinsics();
        if (k.width, k.height) != (now.width, now.height) {
            return Err(KinectError::Intrinsics(format!(
                "{}x{} px, but the recording's frames are {}x{} px",
                k.width, k.height, now.width, now.height
            )));
        }
        match self {
            DepthSource::Folder(r) => r.intrinsics = k,
            #[cfg(feature = "openni2")]
            DepthSource::Oni(r) => r.intrinsics = k,
        }
        Ok(())
    }

    /// Depth frame `i` ([`Recording::frame`], `OniRecording::frame`).
    pub fn frame(&mut self, i: usize) -> Result<DepthFrame, KinectError> {
        match self {
            DepthSource::Folder(r) => r.frame(i),
            #[cfg(feature = "openni2")]
            DepthSource::Oni(r) => r.frame(i),
        }
    }
}

#[cfg(feature = "openni2")]
fn open_oni(path: &Path) -> Result<DepthSource, KinectError> {
    crate::oni::OniRecording::open(path).map(DepthSource::Oni)
}

#[cfg(not(feature = "openni2"))]
fn open_oni(path: &Path) -> Result<DepthSource, KinectError> {
    Err(KinectError::OniNotBuilt {
        file: path.display().to_string(),
    })
}
