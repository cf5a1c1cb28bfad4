//! The depth camera model: pinhole intrinsics and THE projection between Kinect camera space and
//! depth pixels. Every part of symcorr (scan meshing here, the virtual Kinect of the fixture
//! generator) goes through [`Intrinsics::project`] / [`Intrinsics::unproject`], so there is one
//! definition of the conventions.
//!
//! ## Conventions
//!
//! Kinect camera space (Microsoft Kinect SDK): right-handed, metres, origin at the depth sensor,
//! **+x to the sensor's left**, **+y up**, **+z out of the sensor into the scene** (depth).
//! A subject facing the sensor has their own right side at +x.
//!
//! Depth pixels `(u, v)`: `u` is the column (0 at the left edge of the image, growing rightwards),
//! `v` the row (0 at the top, growing downwards); pixel centres are at integer `(u, v)`.
//! The projection is the Kinect SDK v1's own (`NuiTransformSkeletonToDepthImage`) for a
//! [`Mirroring::Mirrored`] image, the default:
//!
//! ```text
//! u = cx + fx · x / z        (+x, the sensor's left, appears on the image's right: the image is
//!                             mirrored, as SDK v1 and v2 deliver it; a subject facing the sensor
//!                             sees their right hand on the image's right, as in a mirror)
//! v = cy − fy · y / z        (+y up in space means v grows downward)
//! ```
//!
//! and `unproject(u, v, z) = ((u − cx)·z/fx, (cy − v)·z/fy, z)`. A [`Mirroring::Direct`] image —
//! the image as the lens forms it, which the Azure Kinect and Orbbec SDKs, Intel RealSense and
//! OpenNI with mirroring off deliver — has `u = cx − fx · x / z` and
//! `unproject(u, v, z) = ((cx − u)·z/fx, (cy − v)·z/fy, z)`: the same camera space, its columns
//! the other way round (`"mirrored": false` in the JSON form).
//!
//! symcorr never uses OpenNI's `CoordinateConverter` (whose world X grows with u as well, but
//! whose y/z units are millimetres); depth frames from any source are unprojected with these
//! intrinsics.

use crate::error::KinectError;
use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `format` tag of an intrinsics JSON file.
pub const INTRINSICS_FORMAT: &str = "symcorr.intrinsics/1";

/// Largest image width or height [`Intrinsics::validate`] accepts, pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Focal lengths [`Intrinsics::validate`] accepts, pixels (a Kinect v1 has 571 px at 640×480).
pub const FOCAL_RANGE_PX: std::ops::RangeInclusive<f64> = 1.0..=100_000.0;

/// Which way a depth image's columns run against Kinect camera space's +x (the sensor's left;
/// module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mirroring {
    /// +x on the image's right, as a mirror shows the subject: the Kinect SDK v1 and v2
    /// images, and the default of `symcorr.intrinsics/1`.
    #[default]
    Mirrored,
    /// +x on the image's left, the image as the lens forms it: the Azure Kinect and Orbbec
    /// SDKs, Intel RealSense, OpenNI with mirroring off (`"mirrored": false`).
    Direct,
}

/// Pinhole intrinsics of a depth camera, in pixels. JSON form:
/// `{"format":"symcorr.intrinsics/1","width":640,"height":480,"fx":580.0,"fy":580.0,"cx":319.5,"cy":239.5}`,
/// with `"mirrored": false` for a [`Mirroring::Direct`] image (absent: mirrored).
///
/// ```
/// use symcorr_kinect::Intrinsics;
/// let k = Intrinsics::kinect_v1();
/// let p = nalgebra::Point3::new(0.3, -0.2, 2.0);
/// let [u, v] = k.project(&p);
/// assert!(u > k.cx && v > k.cy); // +x → right of centre (mirrored image), −y → below centre
/// let q = k.unproject(u, v, p.z);
/// assert!((q - p).norm() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "IntrinsicsJson", into = "IntrinsicsJson")]
pub struct Intrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along u, pixels.
    pub fx: f64,
    /// Focal length along v, pixels.
    pub fy: f64,
    /// Principal point column, pixels.
    pub cx: f64,
    /// Principal point row, pixels.
    pub cy: f64,
    /// Which way the image's columns run ([`Mirroring::Mirrored`] unless the JSON says
    /// `"mirrored": false`).
    pub mirroring: Mirroring,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct IntrinsicsJson {
    format: String,
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    /// True (or absent) for the Kinect SDK's mirrored images; written only when false. A
    /// `bool`: `null` is refused like any other non-boolean.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    mirrored: bool,
}

fn yes() -> bool {
    true
}

fn is_true(b: &bool) -> bool {
    *b
}

impl TryFrom<IntrinsicsJson> for Intrinsics {
    type Error = String;
    fn try_from(j: IntrinsicsJson) -> Result<Self, String> {
        if j.format != INTRINSICS_FORMAT {
            return Err(format!(
                "format is {:?}, expected {INTRINSICS_FORMAT:?}",
                j.format
            ));
        }
        let k = Intrinsics {
            width: j.width,
            height: j.height,
            fx: j.fx,
            fy: j.fy,
            cx: j.cx,
            cy: j.cy,
            mirroring: if j.mirrored {
                Mirroring::Mirrored
            } else {
                Mirroring::Direct
            },
        };
        k.validate().map_err(|e| e.to_string())?;
        Ok(k)
    }
}

impl From<Intrinsics> for IntrinsicsJson {
    fn from(k: Intrinsics) -> Self {
        IntrinsicsJson {
            format: INTRINSICS_FORMAT.to_string(),
            width: k.width,
            height: k.height,
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
            mirrored: k.mirroring == Mirroring::Mirrored,
        }
    }
}

impl Intrinsics {
    /// The intrinsics of a `width`×`height` depth camera with horizontal and vertical fields of
    /// view `fov_rad` (radians, as OpenNI2 reports them): `fx = width / (2·tan(hfov/2))`,
    /// `fy = height / (2·tan(vfov/2))`, principal point at the image centre. Without a usable
    /// field of view (`None`, or an angle not in (0, π)), the nominal Kinect v1 focal length
    /// scaled to the width ([`Intrinsics::kinect_v1`]: 571.26 px at 640 px), for both axes.
    ///
    /// ```
    /// use symcorr_kinect::Intrinsics;
    /// let k = Intrinsics::from_field_of_view(640, 480, Some((1.0, 0.8)));
    /// assert!((k.fx - 320.0 / 0.5f64.tan()).abs() < 1e-9);
    /// assert_eq!((k.cx, k.cy), (320.0, 240.0));
    /// let dummy = Intrinsics::from_field_of_view(320, 240, None);
    /// assert!((dummy.fx - 285.63).abs() < 1e-9 && dummy.fy == dummy.fx);
    /// ```
    pub fn from_field_of_view(width: u32, height: u32, fov_rad: Option<(f64, f64)>) -> Intrinsics {
        let (w, h) = (f64::from(width), f64::from(height));
        let usable = |a: f64| a > 0.0 && a < std::f64::consts::PI;
        let (fx, fy) = match fov_rad {
            Some((hf, vf)) if usable(hf) && usable(vf) => {
                (0.5 * w / (hf / 2.0).tan(), 0.5 * h / (vf / 2.0).tan())
            }
            _ => {
                let k = Intrinsics::kinect_v1();
                let f = k.fx * w / f64::from(k.width);
                (f, f)
            }
        };
        Intrinsics {
            width,
            height,
            fx,
            fy,
            cx: w / 2.0,
            cy: h / 2.0,
            mirroring: Mirroring::Mirrored,
        }
    }

    /// Nominal Kinect v1 (Xbox 360 / Kinect for Windows) depth camera at 640×480:
    /// fx = fy = 571.26 px, cx = 320, cy = 240.
    ///
    /// Source: Kinect for Windows SDK v1.8 `NuiImageCamera.h`:
    /// `NUI_CAMERA_DEPTH_NOMINAL_FOCAL_LENGTH_IN_PIXELS = 285.63` for 320×240 (so ×2 at
    /// 640×480; it matches the nominal 58.5° horizontal field of view), and
    /// `NuiTransformSkeletonToDepthImage` puts the optical axis at half the width and height.
    pub fn kinect_v1() -> Intrinsics {
        Intrinsics {
            width: 640,
            height: 480,
            fx: 571.26,
            fy: 571.26,
            cx: 320.0,
            cy: 240.0,
            mirroring: Mirroring::Mirrored,
        }
    }

    /// Checks that the intrinsics describe a plausible depth camera: width and height in
    /// `1..=`[`MAX_IMAGE_SIDE`], focal lengths finite and in [`FOCAL_RANGE_PX`], and the
    /// principal point finite and inside the image or at most half its size outside it.
    ///
    /// Errors: [`KinectError::Intrinsics`], naming the value and what was expected.
    ///
    /// ```
    /// use symcorr_kinect::Intrinsics;
    /// assert!(Intrinsics::kinect_v1().validate().is_ok());
    /// let bad = Intrinsics { fx: 1e308, ..Intrinsics::kinect_v1() };
    /// assert_eq!(
    ///     bad.validate().unwrap_err().to_string(),
    ///     "invalid intrinsics: fx = 1e308: expected a focal length in 1..=100000 px"
    /// );
    /// ```
    pub fn validate(&self) -> Result<(), KinectError> {
        for (name, side) in [("width", self.width), ("height", self.height)] {
            if side == 0 || side > MAX_IMAGE_SIDE {
                return Err(KinectError::Intrinsics(format!(
                    "{name} = {side}: expected 1..={MAX_IMAGE_SIDE} px"
                )));
            }
        }
        for (name, f) in [("fx", self.fx), ("fy", self.fy)] {
            if !FOCAL_RANGE_PX.contains(&f) {
                return Err(KinectError::Intrinsics(format!(
                    "{name} = {f:?}: expected a focal length in {}..={} px",
                    FOCAL_RANGE_PX.start(),
                    FOCAL_RANGE_PX.end()
                )));
            }
        }
        for (name, c, side) in [("cx", self.cx, self.width), ("cy", self.cy, self.height)] {
            let side = f64::from(side);
            let (lo, hi) = (-0.5 * side, 1.5 * side);
            if !(lo..=hi).contains(&c) {
                return Err(KinectError::Intrinsics(format!(
                    "{name} = {c:?}: expected a principal point in {lo}..={hi} px \
                     (inside the image or at most half its size outside)"
                )));
            }
        }
        Ok(())
    }

    /// Projects a camera-space point (metres) to pixel coordinates `[u, v]` (see the module docs).
    /// Points with z ≤ 0 give non-finite or meaningless pixels; callers check `z > 0`.
    ///
    /// ```
    /// use symcorr_kinect::{Intrinsics, Mirroring};
    /// let mirrored = Intrinsics::kinect_v1();
    /// let direct = Intrinsics { mirroring: Mirroring::Direct, ..mirrored };
    /// let p = nalgebra::Point3::new(0.3, 0.0, 2.0); // the sensor's left
    /// assert!(mirrored.project(&p)[0] > mirrored.cx && direct.project(&p)[0] < direct.cx);
    /// ```
    pub fn project(&self, p: &Point3<f64>) -> [f64; 2] {
        let x = self.fx * p.x / p.z;
        let u = match self.mirroring {
            Mirroring::Mirrored => self.cx + x,
            Mirroring::Direct => self.cx - x,
        };
        [u, self.cy - self.fy * p.y / p.z]
    }

    /// The camera-space point (metres) seen at pixel `(u, v)` with depth `depth_m` (its z).
    pub fn unproject(&self, u: f64, v: f64, depth_m: f64) -> Point3<f64> {
        let du = match self.mirroring {
            Mirroring::Mirrored => u - self.cx,
            Mirroring::Direct => self.cx - u,
        };
        Point3::new(
            du * depth_m / self.fx,
            (self.cy - v) * depth_m / self.fy,
            depth_m,
        )
    }

    /// The same camera with its image's columns reversed: the other [`Mirroring`] and
    /// `cx → width − 1 − cx` (pixel centres at integers), so that column `u` of one image is
    /// column `width − 1 − u` of the other and both unproject it to the same point (to
    /// rounding). Reversing twice gives `cx` back to rounding (exactly where `cx` and
    /// `width − 1 − cx` are exact, as for whole and half pixels). A principal point within a
    /// pixel of the upper end of [`Intrinsics::validate`]'s range lands below its lower end.
    ///
    /// ```
    /// use symcorr_kinect::{Intrinsics, Mirroring};
    /// let k = Intrinsics::kinect_v1();
    /// let d = k.columns_reversed();
    /// assert_eq!((d.mirroring, d.cx), (Mirroring::Direct, 319.0));
    /// let (p, q) = (k.unproject(100.0, 50.0, 2.0), d.unproject(539.0, 50.0, 2.0));
    /// assert!((p - q).norm() < 1e-12);
    /// assert_eq!(d.columns_reversed(), k);
    /// ```
    pub fn columns_reversed(&self) -> Intrinsics {
        Intrinsics {
            cx: f64::from(self.width) - 1.0 - self.cx,
            mirroring: match self.mirroring {
                Mirroring::Mirrored => Mirroring::Direct,
                Mirroring::Direct => Mirroring::Mirrored,
            },
            ..*self
        }
    }

    /// Reads a `symcorr.intrinsics/1` JSON file and checks it ([`Intrinsics::validate`]): the
    /// file is read (at most symcorr-mesh's `DEFAULT_MAX_INPUT_BYTES`) and its text parsed by
    /// [`Intrinsics::from_json_str`].
    ///
    /// Errors: [`KinectError::Io`]; [`KinectError::Json`] naming the file, for text that is not
    /// UTF-8, malformed JSON, a wrong `format` or implausible values.
    pub fn read(path: impl AsRef<Path>) -> Result<Intrinsics, KinectError> {
        let (text, file) = crate::error::read_input_text(path.as_ref(), |file, message| {
            KinectError::Json { file, message }
        })?;
        Intrinsics::from_json_str(&text, &file)
    }

    /// Parses the text of a `symcorr.intrinsics/1` JSON file and checks it
    /// ([`Intrinsics::validate`]); `file` names it in errors. Every field is required and no
    /// other is allowed; a leading byte-order mark is skipped.
    ///
    /// Errors: [`KinectError::Json`] naming `file`, for malformed JSON, a missing or unknown
    /// field, a wrong `format` or implausible values (the message is [`Intrinsics::validate`]'s).
    ///
    /// ```
    /// use symcorr_kinect::{Intrinsics, KinectError};
    /// let text = r#"{"format":"symcorr.intrinsics/1","width":320,"height":240,
    ///   "fx":285.63,"fy":285.63,"cx":160.0,"cy":120.0}"#;
    /// let k = Intrinsics::from_json_str(text, "<memory>").unwrap();
    /// assert_eq!((k.width, k.fx), (320, 285.63));
    /// assert_eq!(Intrinsics::from_json_str(&k.to_json(), "<memory>").unwrap(), k);
    /// let e = Intrinsics::from_json_str(&text.replace("285.63,\"fy", "0.5,\"fy"), "k.json");
    /// assert!(matches!(e, Err(KinectError::Json { .. })));
    /// assert_eq!(
    ///     e.unwrap_err().to_string(),
    ///     "k.json: invalid intrinsics: fx = 0.5: expected a focal length in 1..=100000 px"
    /// );
    /// ```
    pub fn from_json_str(text: &str, file: &str) -> Result<Intrinsics, KinectError> {
        let json_err = |message: String| KinectError::Json {
            file: file.to_string(),
            message,
        };
        // A byte-order mark, as Windows tools write UTF-8, is no part of the JSON.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let raw: IntrinsicsJson =
            serde_json::from_str(text).map_err(|e| json_err(e.to_string()))?;
        Intrinsics::try_from(raw).map_err(json_err)
    }

    /// The `symcorr.intrinsics/1` JSON text of these intrinsics (one line, no newline), as
    /// [`Intrinsics::write`] writes it; [`Intrinsics::from_json_str`] reads it back equal when
    /// the intrinsics validate (non-finite values are written as `null`).
    ///
    /// ```
    /// use symcorr_kinect::{Intrinsics, Mirroring};
    /// let k = Intrinsics {
    ///     width: 4, height: 3, fx: 5.0, fy: 5.0, cx: 1.5, cy: 1.0,
    ///     mirroring: Mirroring::Mirrored,
    /// };
    /// assert_eq!(
    ///     k.to_json(),
    ///     concat!(
    ///         r#"{"format":"symcorr.intrinsics/1","width":4,"height":3,"#,
    ///         r#""fx":5.0,"fy":5.0,"cx":1.5,"cy":1.0}"#
    ///     )
    /// );
    /// let direct = Intrinsics { mirroring: Mirroring::Direct, ..k };
    /// assert!(direct.to_json().ends_with(r#""cy":1.0,"mirrored":false}"#));
    /// assert_eq!(Intrinsics::from_json_str(&direct.to_json(), "<memory>").unwrap(), direct);
    /// ```
    pub fn to_json(&self) -> String {
        serde_json::to_string(&IntrinsicsJson::from(*self)).unwrap_or_default()
    }

    /// Writes a `symcorr.intrinsics/1` JSON file ([`Intrinsics::to_json`]) atomically.
    ///
    /// Errors: [`KinectError::Intrinsics`] when the intrinsics do not validate
    /// ([`Intrinsics::validate`]; nothing is written: [`Intrinsics::read`] would refuse the
    /// file), else an I/O error.
    ///
    /// ```
    /// use symcorr_kinect::{Intrinsics, KinectError, Mirroring};
    /// let dir = tempfile::tempdir().unwrap();
    /// let path = dir.path().join("intrinsics.json");
    /// let bad = Intrinsics {
    ///     width: 4, height: 3, fx: f64::NAN, fy: 5.0, cx: 1.5, cy: 1.0,
    ///     mirroring: Mirroring::Mirrored,
    /// };
    /// assert!(matches!(bad.write(&path), Err(KinectError::Intrinsics(_))));
    /// assert!(!path.exists());
    /// let k = Intrinsics { fx: 5.0, ..bad };
    /// k.write(&path).unwrap();
    /// assert_eq!(Intrinsics::read(&path).unwrap(), k);
    /// ```
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), KinectError> {
        self.validate()?;
        crate::atomic_write(path.as_ref(), self.to_json().as_bytes())
    }
}
