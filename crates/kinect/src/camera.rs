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
//! ## Lens distortion
//!
//! A camera may add OpenCV's lens model ([`Distortion`]; `"distortion": [k1, k2, p1, p2, k3,
//! k4, k5, k6]` in the JSON form, 4, 5 or 8 numbers in OpenCV's `distCoeffs` order). It acts on
//! the normalised image coordinates of the image as stored, `a = (u − cx)/fx`,
//! `b = (v − cy)/fy` — the coordinates a calibration of those very images (OpenCV's
//! `calibrateCamera`, the Azure Kinect's factory calibration, a Kinect v2's `CameraIntrinsics`)
//! is expressed in. `project` computes the undistorted `(a, b)` as above, distorts it and
//! scales it to pixels; `unproject` inverts the distortion by Newton's method. Without it the
//! projection is the pinhole above, bit for bit.
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

impl Mirroring {
    /// The direction of an OpenNI stream whose mirroring property (`xnMirror` in a recording,
    /// `ONI_STREAM_PROPERTY_MIRRORING` on a device) is `mirrored`: on is the Kinect SDK's
    /// mirrored image, off the image as the lens forms it; a stream that reports none (a
    /// Kinect through the SDK's driver, whose image is mirrored) is taken as mirrored.
    ///
    /// ```
    /// use symcorr_kinect::Mirroring;
    /// assert_eq!(Mirroring::from_openni(Some(false)), Mirroring::Direct);
    /// assert_eq!(Mirroring::from_openni(None), Mirroring::Mirrored);
    /// ```
    pub fn from_openni(mirrored: Option<bool>) -> Mirroring {
        match mirrored {
            Some(false) => Mirroring::Direct,
            Some(true) | None => Mirroring::Mirrored,
        }
    }

    /// The other direction.
    ///
    /// ```
    /// use symcorr_kinect::Mirroring;
    /// assert_eq!(Mirroring::Mirrored.other(), Mirroring::Direct);
    /// ```
    pub fn other(self) -> Mirroring {
        match self {
            Mirroring::Mirrored => Mirroring::Direct,
            Mirroring::Direct => Mirroring::Mirrored,
        }
    }
}

/// Lens distortion in OpenCV's camera model (the "rational" model; Brown–Conrady, OpenCV's
/// and ROS's `plumb_bob`, is `k4 = k5 = k6 = 0`). A normalised, undistorted image point
/// `(a, b)` (module docs) with `r² = a² + b²` is seen at
///
/// ```text
/// a_d = a·R + 2·p1·a·b + p2·(r² + 2a²)      R = (1 + k1·r² + k2·r⁴ + k3·r⁶)
/// b_d = b·R + p1·(r² + 2b²) + 2·p2·a·b          / (1 + k4·r² + k5·r⁴ + k6·r⁶)
/// ```
///
/// (OpenCV's `projectPoints`; the model the Azure Kinect SDK's devices report,
/// `K4A_CALIBRATION_LENS_DISTORTION_MODEL_BROWN_CONRADY`, is the same when its centre of
/// distortion `codx`, `cody` is zero; no other centre is modelled). The coefficients are those
/// of the image as stored: reversing its columns negates `p2` ([`Intrinsics::columns_reversed`]).
/// Thin-prism and tilted-sensor terms (OpenCV's 12- and 14-coefficient forms) are not modelled.
///
/// ```
/// use symcorr_kinect::Distortion;
/// let d = Distortion::from_opencv(&[0.09, -0.27, 0.0, 0.0, 0.09]).unwrap(); // a Kinect v2
/// let [ad, bd] = d.distort(0.4, -0.3);
/// let [a, b] = d.undistort(ad, bd).unwrap();
/// assert!((a - 0.4).abs() < 1e-12 && (b + 0.3).abs() < 1e-12);
/// assert_eq!(d.to_opencv(), vec![0.09, -0.27, 0.0, 0.0, 0.09]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    /// Radial coefficients `[k1, k2, k3, k4, k5, k6]`: numerator `k1..k3`, denominator `k4..k6`.
    pub radial: [f64; 6],
    /// Tangential (decentring) coefficients `[p1, p2]`.
    pub tangential: [f64; 2],
}

/// Newton's method for [`Distortion::undistort`] stops when the distorted point is matched to
/// this, in normalised coordinates (10⁻⁷ px at a focal length of 1000 px; the step that gets
/// there usually lands far closer, the method converging quadratically).
const UNDISTORT_TOLERANCE: f64 = 1e-10;

/// Largest share of the image's corner radius by which [`Intrinsics::validate`] accepts the
/// tangential terms to move it (`3·max(|p1|, |p2|)·r`; depth cameras' lenses: under 1 %).
pub const MAX_TANGENTIAL_SHARE: f64 = 0.1;

/// Largest magnitude [`Intrinsics::validate`] accepts for a radial coefficient. Depth cameras'
/// calibrations have them below 10 (the Azure Kinect's rational model: under 1); a model with
/// larger ones bends rays sharply close to the image's centre, where the check that it does
/// not fold samples too coarsely to be trusted.
pub const MAX_RADIAL_COEFFICIENT: f64 = 1000.0;

/// At most this many samples of the radial map in [`Intrinsics::validate`] (a lens that has
/// not reached the image's corner by then shows too little of the image).
const MAX_RADIAL_SAMPLES: usize = 200_000;

/// At most this many Newton steps in [`Distortion::undistort`] (from the distorted point it
/// takes 3–6 on the lenses of depth cameras).
const UNDISTORT_MAX_STEPS: usize = 50;

impl Distortion {
    /// The model from OpenCV's `distCoeffs` vector: `[k1, k2, p1, p2]`, `[k1, k2, p1, p2, k3]`
    /// or `[k1, k2, p1, p2, k3, k4, k5, k6]` (the coefficients not given are 0).
    ///
    /// Errors: another length, or a coefficient that is not finite; the message names it.
    pub fn from_opencv(coefficients: &[f64]) -> Result<Distortion, String> {
        if ![4, 5, 8].contains(&coefficients.len()) {
            return Err(format!(
                "distortion has {} coefficients: expected 4, 5 or 8 in OpenCV's order \
                 (k1, k2, p1, p2[, k3[, k4, k5, k6]]); thin-prism and tilted models are \
                 not supported",
                coefficients.len()
            ));
        }
        if let Some((i, c)) = coefficients
            .iter()
            .enumerate()
            .find(|(_, c)| !c.is_finite())
        {
            return Err(format!(
                "distortion coefficient {i} (from 0) is {c:?}: expected a finite number"
            ));
        }
        let at = |i: usize| coefficients.get(i).copied().unwrap_or(0.0);
        Ok(Distortion {
            radial: [at(0), at(1), at(4), at(5), at(6), at(7)],
            tangential: [at(2), at(3)],
        })
    }

    /// OpenCV's `distCoeffs` vector of this model: the shortest of the 4-, 5- and
    /// 8-coefficient forms that holds every non-zero coefficient
    /// ([`Distortion::from_opencv`] reads it back equal).
    pub fn to_opencv(&self) -> Vec<f64> {
        let [k1, k2, k3, k4, k5, k6] = self.radial;
        let [p1, p2] = self.tangential;
        let mut c = vec![k1, k2, p1, p2, k3, k4, k5, k6];
        let len = if [k4, k5, k6].iter().any(|&k| k != 0.0) {
            8
        } else if k3 != 0.0 {
            5
        } else {
            4
        };
        c.truncate(len);
        c
    }

    /// The radial factor `R` at `r²` and its derivative `dR/d(r²)`; `None` where the
    /// denominator vanishes.
    fn radial_factor(&self, s: f64) -> Option<(f64, f64)> {
        let [k1, k2, k3, k4, k5, k6] = self.radial;
        let num = 1.0 + s * (k1 + s * (k2 + s * k3));
        let den = 1.0 + s * (k4 + s * (k5 + s * k6));
        if den.abs() < 1e-12 {
            return None;
        }
        let dnum = k1 + s * (2.0 * k2 + 3.0 * s * k3);
        let dden = k4 + s * (2.0 * k5 + 3.0 * s * k6);
        Some((num / den, (dnum * den - num * dden) / (den * den)))
    }

    /// The distorted point and the Jacobian `∂(a_d, b_d)/∂(a, b)` (row-major), `None` where
    /// the radial factor's denominator vanishes.
    fn distort_with_jacobian(&self, a: f64, b: f64) -> Option<([f64; 2], [f64; 4])> {
        let [p1, p2] = self.tangential;
        let s = a * a + b * b;
        let (r, dr) = self.radial_factor(s)?;
        let ad = a * r + 2.0 * p1 * a * b + p2 * (s + 2.0 * a * a);
        let bd = b * r + p1 * (s + 2.0 * b * b) + 2.0 * p2 * a * b;
        let cross = 2.0 * a * b * dr;
        let jacobian = [
            r + 2.0 * a * a * dr + 2.0 * p1 * b + 6.0 * p2 * a,
            cross + 2.0 * p1 * a + 2.0 * p2 * b,
            cross + 2.0 * p1 * a + 2.0 * p2 * b,
            r + 2.0 * b * b * dr + 6.0 * p1 * b + 2.0 * p2 * a,
        ];
        Some(([ad, bd], jacobian))
    }

    /// Where the lens shows the normalised, undistorted point `(a, b)` (the formula above).
    /// Non-finite where the radial factor's denominator vanishes (far outside any image the
    /// model was calibrated on).
    pub fn distort(&self, a: f64, b: f64) -> [f64; 2] {
        self.distort_with_jacobian(a, b)
            .map_or([f64::NAN; 2], |(d, _)| d)
    }

    /// The normalised, undistorted point the lens shows at `(a_d, b_d)`: Newton's method from
    /// `(a_d, b_d)` on [`Distortion::distort`]. `None` where it does not converge or reaches a
    /// point where the model folds (its Jacobian's determinant is not positive) — a point
    /// outside the range the model describes. [`Intrinsics::validate`] checks that every
    /// pixel on the image's border has its point.
    pub fn undistort(&self, ad: f64, bd: f64) -> Option<[f64; 2]> {
        self.undistort_from(ad, bd, [ad, bd])
    }

    /// [`Distortion::undistort`] with Newton's method started at `start` (a neighbouring
    /// pixel's point: two or three steps instead of six or more for a strong lens).
    pub(crate) fn undistort_from(&self, ad: f64, bd: f64, start: [f64; 2]) -> Option<[f64; 2]> {
        // Newton's method, each step halved until it brings the distorted point nearer (a
        // full step almost always does; halving keeps a strong lens from overshooting).
        let residual = |[a, b]: [f64; 2]| {
            self.distort_with_jacobian(a, b).map(|([fa, fb], j)| {
                let e = [fa - ad, fb - bd];
                (e, e[0].hypot(e[1]), j)
            })
        };
        let mut x = start;
        let (mut e, mut norm, mut j) = residual(x)?;
        for _ in 0..UNDISTORT_MAX_STEPS {
            let [j00, j01, j10, j11] = j;
            let det = j00 * j11 - j01 * j10;
            if e[0].abs().max(e[1].abs()) <= UNDISTORT_TOLERANCE {
                // A root where the model folds is not the point the lens shows there.
                return (det > 0.0).then_some(x);
            }
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let step = [
                (j11 * e[0] - j01 * e[1]) / det,
                (j00 * e[1] - j10 * e[0]) / det,
            ];
            let mut t = 1.0;
            loop {
                let next = [x[0] - t * step[0], x[1] - t * step[1]];
                match residual(next) {
                    Some((ne, nn, nj)) if nn < norm => {
                        (x, e, norm, j) = (next, ne, nn, nj);
                        break;
                    }
                    _ if t > 1e-6 => t *= 0.5,
                    _ => return None,
                }
            }
        }
        None
    }

    /// Checks that the model describes the whole `width`×`height` image of `k`: the radial
    /// coefficients are at most [`MAX_RADIAL_COEFFICIENT`], the tangential terms are small
    /// ([`MAX_TANGENTIAL_SHARE`]), the radial map `r ↦ r·R(r²)` increases from the centre until
    /// it is past every corner of the image (it does not fold inside the image), and every
    /// pixel on the image's border undistorts ([`Distortion::undistort`]).
    fn check_covers(&self, k: &Intrinsics) -> Result<(), String> {
        let (w, h) = (f64::from(k.width) - 1.0, f64::from(k.height) - 1.0);
        let normalised = |u: f64, v: f64| ((u - k.cx) / k.fx, (v - k.cy) / k.fy);
        // The farthest corner, as a distorted radius, and an allowance for the tangential
        // terms, which move a point by at most about 3·|p|·r² off the radial map.
        let corner = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
            .iter()
            .map(|&(u, v)| {
                let (a, b) = normalised(u, v);
                a.hypot(b)
            })
            .fold(0.0, f64::max);
        if let Some((i, k)) = self
            .radial
            .iter()
            .enumerate()
            .find(|(_, k)| k.abs() > MAX_RADIAL_COEFFICIENT)
        {
            return Err(format!(
                "distortion {:?}: k{} = {k:?} is no lens calibration (at most \
                 {MAX_RADIAL_COEFFICIENT} in magnitude accepted)",
                self.to_opencv(),
                i + 1
            ));
        }
        let p = self.tangential[0].abs().max(self.tangential[1].abs());
        // Decentring moves a lens's image by a fraction of a percent; terms that move the
        // corner by a tenth of its radius are no calibration (a coefficient in another unit).
        if 3.0 * p * corner > MAX_TANGENTIAL_SHARE {
            return Err(format!(
                "distortion {:?}: the tangential coefficients p1, p2 move the image's corner by \
                 up to {:.0} % of its radius (at most {:.0} % accepted)",
                self.to_opencv(),
                300.0 * p * corner,
                100.0 * MAX_TANGENTIAL_SHARE
            ));
        }
        let reach = corner + 3.0 * p * corner * corner + 1e-9;
        // Sampled at a two-thousandth of the corner's radius (at most 10⁻³): with radial
        // coefficients of at most MAX_RADIAL_COEFFICIENT a fold spans several samples.
        let step = (corner / 2000.0).clamp(1e-7, 1e-3);
        let (mut r, mut previous) = (0.0f64, 0.0);
        for taken in 0.. {
            r += step;
            if taken >= MAX_RADIAL_SAMPLES {
                return Err(format!(
                    "distortion {:?}: the lens model shows no point beyond the normalised \
                     radius {previous:.3}, inside the image (its corner is at {corner:.3})",
                    self.to_opencv()
                ));
            }
            let Some((f, _)) = self.radial_factor(r * r) else {
                return Err(format!(
                    "distortion {:?}: the radial factor's denominator vanishes at the \
                     normalised radius {r:.3}, inside the image (its corner is at {corner:.3})",
                    self.to_opencv()
                ));
            };
            let g = r * f;
            if g.is_nan() || g <= previous {
                return Err(format!(
                    "distortion {:?}: the lens model folds at the normalised radius {r:.3} \
                     (it shows no point beyond {previous:.3}), inside the image (its corner \
                     is at {corner:.3}): not a calibration of this image",
                    self.to_opencv()
                ));
            }
            if g >= reach {
                break;
            }
            previous = g;
        }
        let border = (0..k.width)
            .flat_map(|u| [(f64::from(u), 0.0), (f64::from(u), h)])
            .chain((0..k.height).flat_map(|v| [(0.0, f64::from(v)), (w, f64::from(v))]));
        for (u, v) in border {
            let (a, b) = normalised(u, v);
            if self.undistort(a, b).is_none() {
                return Err(format!(
                    "distortion {:?}: pixel ({u}, {v}) does not undistort (Newton's method \
                     finds no point the lens shows there): not a calibration of this image",
                    self.to_opencv()
                ));
            }
        }
        Ok(())
    }
}

/// Pinhole intrinsics of a depth camera, in pixels. JSON form:
/// `{"format":"symcorr.intrinsics/1","width":640,"height":480,"fx":580.0,"fy":580.0,"cx":319.5,"cy":239.5}`,
/// with `"mirrored": false` for a [`Mirroring::Direct`] image (absent: mirrored) and
/// `"distortion": [k1, k2, p1, p2, k3, k4, k5, k6]` (4, 5 or 8 numbers) for a lens model
/// ([`Distortion`]; absent: none).
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
    /// The lens's distortion, `None` for a pinhole camera (the JSON has no `"distortion"`).
    pub distortion: Option<Distortion>,
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
    /// OpenCV's `distCoeffs` (4, 5 or 8 numbers), written only when there is a lens model;
    /// `null` is refused.
    #[serde(
        default,
        deserialize_with = "some_coefficients",
        skip_serializing_if = "Option::is_none"
    )]
    distortion: Option<Vec<f64>>,
}

fn some_coefficients<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Vec<f64>>, D::Error> {
    Vec::<f64>::deserialize(d).map(Some)
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
            distortion: j
                .distortion
                .as_deref()
                .map(Distortion::from_opencv)
                .transpose()?,
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
            distortion: k.distortion.map(|d| d.to_opencv()),
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
            distortion: None,
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
            distortion: None,
        }
    }

    /// Checks that the intrinsics describe a plausible depth camera: width and height in
    /// `1..=`[`MAX_IMAGE_SIDE`], focal lengths finite and in [`FOCAL_RANGE_PX`], and the
    /// principal point finite and inside the image or at most half its size outside it; a
    /// [`Distortion`]'s coefficients finite, its radial ones at most [`MAX_RADIAL_COEFFICIENT`],
    /// and its model one that describes the whole image (its radial map does not fold inside
    /// the image's corners, its tangential terms move the corner by at most
    /// [`MAX_TANGENTIAL_SHARE`] of its radius, and every pixel of the border undistorts).
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
        if let Some(d) = &self.distortion {
            if let Some((i, c)) = d
                .radial
                .iter()
                .chain(&d.tangential)
                .enumerate()
                .find(|(_, c)| !c.is_finite())
            {
                return Err(KinectError::Intrinsics(format!(
                    "distortion coefficient {c:?} (the {}): expected a finite number",
                    ["k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2"][i]
                )));
            }
            d.check_covers(self).map_err(KinectError::Intrinsics)?;
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
        let Some(d) = &self.distortion else {
            let x = self.fx * p.x / p.z;
            let u = match self.mirroring {
                Mirroring::Mirrored => self.cx + x,
                Mirroring::Direct => self.cx - x,
            };
            return [u, self.cy - self.fy * p.y / p.z];
        };
        let a = match self.mirroring {
            Mirroring::Mirrored => p.x / p.z,
            Mirroring::Direct => -p.x / p.z,
        };
        let [ad, bd] = d.distort(a, -p.y / p.z);
        [self.cx + self.fx * ad, self.cy + self.fy * bd]
    }

    /// The camera-space point (metres) seen at pixel `(u, v)` with depth `depth_m` (its z).
    /// With a [`Distortion`], Newton's method finds the ray ([`Distortion::undistort`]); a
    /// point where it finds none gets non-finite coordinates. Validated intrinsics have a ray at
    /// every pixel of the image's border (each checked) and a radial map that does not fold
    /// inside it; the interior's pixels are not checked one by one ([`PixelRays`] reads a pixel
    /// without a ray as no reading).
    pub fn unproject(&self, u: f64, v: f64, depth_m: f64) -> Point3<f64> {
        let Some(d) = &self.distortion else {
            let du = match self.mirroring {
                Mirroring::Mirrored => u - self.cx,
                Mirroring::Direct => self.cx - u,
            };
            return Point3::new(
                du * depth_m / self.fx,
                (self.cy - v) * depth_m / self.fy,
                depth_m,
            );
        };
        let ray = d
            .undistort((u - self.cx) / self.fx, (v - self.cy) / self.fy)
            .unwrap_or([f64::NAN; 2]);
        self.point_on_ray(ray, depth_m)
    }

    /// The camera-space point at depth `depth_m` on the ray of the stored image's normalised,
    /// undistorted coordinates `[a, b]` (module docs): `a` runs with +x in a mirrored image,
    /// against it in a direct one; `b` runs against +y.
    fn point_on_ray(&self, [a, b]: [f64; 2], depth_m: f64) -> Point3<f64> {
        let x = match self.mirroring {
            Mirroring::Mirrored => a,
            Mirroring::Direct => -a,
        };
        Point3::new(x * depth_m, -b * depth_m, depth_m)
    }

    /// The same camera with its image's columns reversed: the other [`Mirroring`] and
    /// `cx → width − 1 − cx` (pixel centres at integers), so that column `u` of one image is
    /// column `width − 1 − u` of the other and both unproject it to the same point (to
    /// rounding). Reversing twice gives `cx` back to rounding (exactly where `cx` and
    /// `width − 1 − cx` are exact, as for whole and half pixels); a [`Distortion`]'s `p2`
    /// changes sign (the coefficients are the stored image's). A principal point within a
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
            mirroring: self.mirroring.other(),
            // The image's a = (u − cx)/fx changes sign: p2, the one coefficient odd in a.
            distortion: self.distortion.map(|d| Distortion {
                tangential: [d.tangential[0], -d.tangential[1]],
                ..d
            }),
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
    ///     distortion: None,
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
    ///     distortion: None,
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

/// Every pixel's ray of one camera, for unprojecting many frames: with a lens [`Distortion`]
/// the rays are found once here (Newton's method per pixel, each started from its left
/// neighbour's ray) instead of once per pixel per frame; a pinhole camera keeps no table (its
/// rays are a multiply away). [`Intrinsics::pixel_rays`] makes one.
///
/// ```
/// use symcorr_kinect::{Distortion, Intrinsics};
/// let k = Intrinsics {
///     distortion: Some(Distortion::from_opencv(&[-0.2, 0.05, 0.0, 0.0]).unwrap()),
///     ..Intrinsics::kinect_v1()
/// };
/// let rays = k.pixel_rays();
/// let p = rays.point(600, 20, 2.0).unwrap();
/// assert!((p - k.unproject(600.0, 20.0, 2.0)).norm() < 1e-6);
/// assert!(rays.point(640, 0, 2.0).is_none()); // outside the image
/// ```
#[derive(Debug, Clone)]
pub struct PixelRays {
    intrinsics: Intrinsics,
    /// Row-major, per pixel the undistorted normalised `(a, b)` (NaN: no ray), `f32` — to
    /// 10⁻⁷ of the depth, a fraction of a micrometre, in a third of the memory of `f64` and an
    /// option; `None` for a pinhole camera.
    table: Option<Vec<[f32; 2]>>,
}

impl PixelRays {
    /// The intrinsics the rays are of.
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// The camera-space point seen at pixel `(u, v)` with depth `depth_m`: what
    /// [`Intrinsics::unproject`] gives there (to 10⁻⁷ of the depth with a lens model).
    /// `None` outside the image, and with a lens model at a pixel without a ray (validation
    /// rules them out on the image's border).
    pub fn point(&self, u: u32, v: u32, depth_m: f64) -> Option<Point3<f64>> {
        let k = &self.intrinsics;
        if u >= k.width || v >= k.height {
            return None;
        }
        let Some(table) = &self.table else {
            return Some(k.unproject(f64::from(u), f64::from(v), depth_m));
        };
        let ray = table
            .get(v as usize * k.width as usize + u as usize)?
            .map(f64::from);
        (!ray[0].is_nan()).then(|| k.point_on_ray(ray, depth_m))
    }
}

impl Intrinsics {
    /// Every pixel's ray ([`PixelRays`]): for a lens model a table of `width × height` rays
    /// (8 bytes a pixel), computed here (about 30 ms at 640×480); for a pinhole camera nothing.
    /// For intrinsics that validate (the table is `width × height`).
    pub fn pixel_rays(&self) -> PixelRays {
        let table = self.distortion.map(|lens| {
            let (w, h) = (self.width as usize, self.height as usize);
            let mut table = Vec::with_capacity(w * h);
            for v in 0..h {
                let bd = (v as f64 - self.cy) / self.fy;
                let mut left: Option<[f64; 2]> = None;
                for u in 0..w {
                    let ad = (u as f64 - self.cx) / self.fx;
                    let ray = lens.undistort_from(ad, bd, left.unwrap_or([ad, bd]));
                    table.push(ray.map_or([f32::NAN; 2], |r| r.map(|x| x as f32)));
                    left = ray;
                }
            }
            table
        });
        PixelRays {
            intrinsics: *self,
            table,
        }
    }
}
