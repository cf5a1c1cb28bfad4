//! Depth frame → organised point cloud → scan mesh.
//!
//! 1. Every pixel with a depth in `[min_depth_m, max_depth_m]` is unprojected with
//!    [`Intrinsics::unproject`] (the organised cloud keeps the pixel grid).
//! 2. Background: with a skeleton, points outside the bounding box of its tracked joints grown
//!    by `background_margin_m` are dropped (walls, furniture, other people); a skeleton that
//!    tracks no joint (the tracker lost the body) is refused. First the joints must
//!    lie on the body the frame shows (at least half within [`JOINT_DEPTH_TOLERANCE_M`] of the
//!    surface at their pixel); joints of another frame, camera or unit are refused rather than
//!    left to crop the body.
//! 3. Floor: RANSAC plane fit ([`ScanOptions::floor_iterations`] samples, deterministic seed);
//!    the plane must be within 35° of horizontal (the skeleton's up, or camera +y without a
//!    skeleton) and, with a skeleton, below the hip centre; its inliers (within
//!    `floor_threshold_m`) are dropped.
//! 4. Grid triangulation: each 2×2 pixel block gives up to two triangles, kept only if no edge
//!    spans a depth jump larger than `discontinuity_m` (a silhouette edge, not a surface).
//!    Triangles are counter-clockwise seen from the camera (their normals face it). A
//!    [`Mirroring::Direct`](crate::Mirroring) image splits each block along its other diagonal
//!    and turns the triangles the other way, so that it gives the triangles of the same
//!    image mirrored, as the same camera-space surface.
//! 5. Connected components are kept by [`ScanOptions::components`] ([`ComponentFilter`]): by
//!    default every component near the skeleton's bones (a body seen in profile falls apart at
//!    its own depth jumps — the near arm in front of the torso, one leg in front of the other
//!    — and each piece is body), else the largest.
//!
//! The result keeps, per vertex, the pixel it came from (`v · width + u`), so results can be
//! related back to the depth image. [`fuse_depth_frames`] merges a few frames of a static subject
//! into one (per-pixel median) before meshing, which removes most of the sensor's flicker.

use crate::camera::{Intrinsics, Mirroring, PixelRays};
use crate::depth::DepthFrame;
use crate::error::KinectError;
use crate::geom::{median, normalize};
use nalgebra::{Point3, Vector3};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{Joint, Skeleton};

/// Parameters of [`scan_mesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct ScanOptions {
    /// Nearest valid depth, metres (Kinect v1: 0.4 m in near mode, 0.8 m by default).
    pub min_depth_m: f64,
    /// Farthest valid depth, metres.
    pub max_depth_m: f64,
    /// Largest depth difference along a triangle edge, metres.
    pub discontinuity_m: f64,
    /// Remove the floor plane.
    pub remove_floor: bool,
    /// RANSAC samples for the floor.
    pub floor_iterations: usize,
    /// Distance to the floor plane below which a point is floor, metres.
    pub floor_threshold_m: f64,
    /// Margin around the skeleton's bounding box kept as foreground, metres.
    pub background_margin_m: f64,
    /// Which connected components are kept.
    pub components: ComponentFilter,
    /// Seed of the RANSAC sampler (results are deterministic for a given seed).
    pub seed: u64,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions {
            min_depth_m: 0.4,
            max_depth_m: 8.0,
            discontinuity_m: 0.05,
            remove_floor: true,
            floor_iterations: 300,
            floor_threshold_m: 0.02,
            background_margin_m: 0.3,
            components: ComponentFilter::default(),
            seed: 0x5eed,
        }
    }
}

/// Which connected components of the grid mesh a scan keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ComponentFilter {
    /// Every component.
    All,
    /// Only the largest (by triangles).
    Largest,
    /// With a skeleton, every component whose median vertex lies within `max_median_m` of the
    /// nearest bone (between tracked joints) and that has at least `min_share` of the largest
    /// component's triangles (a few flying pixels at a silhouette are not body); without a
    /// skeleton, the largest. A body turned sideways is several components — the near arm
    /// and leg are cut from the torso and the far leg by depth jumps — and all of them are
    /// body; a ball or a chair inside the skeleton's box is not near a bone.
    NearBones {
        /// Largest median distance from a kept component's vertices to the nearest bone,
        /// metres.
        max_median_m: f64,
        /// Smallest kept component, as a share of the largest one's triangles.
        min_share: f64,
    },
}

impl Default for ComponentFilter {
    /// [`ComponentFilter::NearBones`] within 0.35 m (a slim torso's surface lies about 0.15 m
    /// from its spine, a heavy one's belly 0.3 m) and at least 0.5 % of the largest component.
    fn default() -> Self {
        ComponentFilter::NearBones {
            max_median_m: 0.35,
            min_share: 0.005,
        }
    }
}

/// Largest [`ScanOptions::floor_iterations`] [`ScanOptions::validate`] accepts.
pub const MAX_FLOOR_ITERATIONS: usize = 100_000;

impl ScanOptions {
    /// Checks every numeric option: depths finite with `0 ≤ min_depth_m < max_depth_m`,
    /// `discontinuity_m` and `floor_threshold_m` finite and > 0, `background_margin_m` finite
    /// and ≥ 0, `floor_iterations` at most [`MAX_FLOOR_ITERATIONS`].
    ///
    /// Errors: [`KinectError::ScanOption`], naming the option.
    ///
    /// ```
    /// use symcorr_kinect::ScanOptions;
    /// assert!(ScanOptions::default().validate().is_ok());
    /// let bad = ScanOptions { discontinuity_m: f64::NAN, ..ScanOptions::default() };
    /// assert_eq!(
    ///     bad.validate().unwrap_err().to_string(),
    ///     "scan option discontinuity_m = NaN: expected a finite length > 0 (metres)"
    /// );
    /// ```
    pub fn validate(&self) -> Result<(), KinectError> {
        let bad = |option: &'static str, value: String, expected: &'static str| {
            Err(KinectError::ScanOption {
                option,
                value,
                expected,
            })
        };
        let o = self;
        if !(o.min_depth_m.is_finite() && o.min_depth_m >= 0.0) {
            return bad(
                "min_depth_m",
                format!("{:?}", o.min_depth_m),
                "a finite depth >= 0 (metres)",
            );
        }
        if !(o.max_depth_m.is_finite() && o.max_depth_m > o.min_depth_m) {
            return bad(
                "max_depth_m",
                format!("{:?}", o.max_depth_m),
                "a finite depth > min_depth_m (metres)",
            );
        }
        for (option, v) in [
            ("discontinuity_m", o.discontinuity_m),
            ("floor_threshold_m", o.floor_threshold_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(option, format!("{v:?}"), "a finite length > 0 (metres)");
            }
        }
        if !(o.background_margin_m.is_finite() && o.background_margin_m >= 0.0) {
            return bad(
                "background_margin_m",
                format!("{:?}", o.background_margin_m),
                "a finite length >= 0 (metres)",
            );
        }
        if o.floor_iterations > MAX_FLOOR_ITERATIONS {
            return bad(
                "floor_iterations",
                o.floor_iterations.to_string(),
                "at most 100000",
            );
        }
        Ok(())
    }
}

/// A triangulated scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanMesh {
    /// The mesh, Kinect camera space, metres.
    pub mesh: TriMesh,
    /// Per vertex, the pixel id `v · width + u` it was unprojected from.
    pub pixel_ids: Vec<u32>,
    /// What the pipeline removed.
    pub report: ScanReport,
}

/// Counts of what each stage kept or removed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ScanReport {
    /// Pixels with a valid depth.
    pub valid_pixels: usize,
    /// Points dropped as background (outside the skeleton's box).
    pub background_removed: usize,
    /// The floor plane `n·p + d = 0` (unit `n`), if one was found.
    pub floor_plane: Option<[f64; 4]>,
    /// Points dropped as floor.
    pub floor_removed: usize,
    /// Triangles rejected at depth discontinuities.
    pub discontinuity_triangles: usize,
    /// Vertices dropped with smaller components.
    pub component_vertices_removed: usize,
}

/// Per pixel of an image of `pixels`: is it a corner of one of `tris`? (A flag per pixel,
/// not a sort of every corner: this runs on every recorded frame.)
fn used_pixels(tris: &[[usize; 3]], pixels: usize) -> Vec<bool> {
    let mut used = vec![false; pixels];
    for &v in tris.iter().flatten() {
        used[v] = true;
    }
    used
}

/// Distinct vertices of `tris` (pixels of an image of `pixels`).
fn count_vertices(tris: &[[usize; 3]], pixels: usize) -> usize {
    used_pixels(tris, pixels).iter().filter(|&&u| u).count()
}

/// Keeps the triangles of the components `filter` selects (not [`ComponentFilter::All`]).
fn keep_components(
    tris: &mut Vec<[usize; 3]>,
    points: &[Option<Point3<f64>>],
    skeleton: Option<&Skeleton>,
    filter: ComponentFilter,
) {
    let mut parent: Vec<usize> = (0..points.len()).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for t in tris.iter() {
        for e in [(t[0], t[1]), (t[1], t[2])] {
            let (a, b) = (find(&mut parent, e.0), find(&mut parent, e.1));
            if a != b {
                parent[a] = b;
            }
        }
    }
    let root: Vec<usize> = tris.iter().map(|t| find(&mut parent, t[0])).collect();
    // Triangles per component, indexed by its root pixel.
    let mut size = vec![0usize; points.len()];
    for &r in &root {
        size[r] += 1;
    }
    // Deterministic choice among equal sizes: the smallest root id.
    let Some((largest, largest_size)) = size
        .iter()
        .copied()
        .enumerate()
        .filter(|&(_, c)| c > 0)
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
    else {
        return;
    };
    let bones: Vec<(Point3<f64>, Point3<f64>)> = skeleton
        .map(|s| {
            symcorr_skeleton::BONES
                .iter()
                .filter(|b| {
                    s.confidence[b.parent.index()] > 0.0 && s.confidence[b.child.index()] > 0.0
                })
                .map(|b| (s.position(b.parent), s.position(b.child)))
                .collect()
        })
        .unwrap_or_default();
    let kept: Vec<usize> = match filter {
        ComponentFilter::NearBones {
            max_median_m,
            min_share,
        } if !bones.is_empty() => {
            // Per component, its vertices' distances to the nearest bone.
            let mut distances: std::collections::BTreeMap<usize, Vec<f64>> = Default::default();
            let mut seen = vec![false; points.len()];
            for (t, &r) in tris.iter().zip(&root) {
                if (size[r] as f64) < min_share * largest_size as f64 {
                    continue;
                }
                for &v in t {
                    if std::mem::replace(&mut seen[v], true) {
                        continue;
                    }
                    if let Some(x) = points[v] {
                        let d = bones
                            .iter()
                            .map(|(a, b)| symcorr_mesh::geometry::closest_on_segment(&x, a, b).1)
                            .fold(f64::INFINITY, f64::min);
                        distances.entry(r).or_default().push(d);
                    }
                }
            }
            distances
                .into_iter()
                .filter_map(|(r, mut d)| {
                    let mid = d.len() / 2;
                    let median = *d.select_nth_unstable_by(mid, f64::total_cmp).1;
                    (median <= max_median_m).then_some(r)
                })
                .collect()
        }
        _ => std::iter::once(largest).collect(),
    };
    let mut keep = vec![false; points.len()];
    for r in kept {
        keep[r] = true;
    }
    let mut k = 0;
    tris.retain(|_| {
        k += 1;
        keep[root[k - 1]]
    });
}

/// The organised point cloud: per pixel (row-major) the camera-space point, or `None`.
pub fn depth_to_points(
    frame: &DepthFrame,
    k: &Intrinsics,
    min_depth_m: f64,
    max_depth_m: f64,
) -> Result<Vec<Option<Point3<f64>>>, KinectError> {
    k.validate()?;
    check_frame_size(frame, k)?;
    Ok(points_through(
        frame,
        &k.pixel_rays(),
        min_depth_m,
        max_depth_m,
    ))
}

/// [`KinectError::DepthSize`] unless `frame` has the size of `k` (and its pixels fill it).
fn check_frame_size(frame: &DepthFrame, k: &Intrinsics) -> Result<(), KinectError> {
    if frame.width != k.width
        || frame.height != k.height
        || frame.data_mm.len() != frame.width as usize * frame.height as usize
    {
        return Err(KinectError::DepthSize {
            width: frame.width,
            height: frame.height,
            values: frame.data_mm.len(),
            expected: format!("{}x{} (the intrinsics)", k.width, k.height),
        });
    }
    Ok(())
}

/// [`depth_to_points`] with the camera's rays at hand (the frame's size checked).
fn points_through(
    frame: &DepthFrame,
    rays: &PixelRays,
    min_depth_m: f64,
    max_depth_m: f64,
) -> Vec<Option<Point3<f64>>> {
    let w = frame.width.max(1);
    frame
        .data_mm
        .iter()
        .zip(0u32..)
        .map(|(&d, i)| {
            let z = f64::from(d) / 1000.0;
            (d > 0 && z >= min_depth_m && z <= max_depth_m)
                .then(|| rays.point(i % w, i / w, z))
                .flatten()
        })
        .collect()
}

/// Per-pixel median of several depth frames of a static subject (zeros ignored; a pixel valid
/// in fewer than half the frames becomes 0). All frames must have the same size.
pub fn fuse_depth_frames(frames: &[DepthFrame]) -> Result<DepthFrame, KinectError> {
    let first = frames
        .first()
        .ok_or_else(|| KinectError::Scan("no depth frame to fuse".into()))?;
    for f in frames {
        if f.width != first.width
            || f.height != first.height
            || f.data_mm.len() != first.data_mm.len()
        {
            return Err(KinectError::DepthSize {
                width: f.width,
                height: f.height,
                values: f.data_mm.len(),
                expected: format!("{}x{} like the first frame", first.width, first.height),
            });
        }
    }
    let mut out = vec![0u16; first.data_mm.len()];
    let mut vals = Vec::with_capacity(frames.len());
    for (i, o) in out.iter_mut().enumerate() {
        vals.clear();
        vals.extend(frames.iter().map(|f| f.data_mm[i]).filter(|&d| d > 0));
        if vals.len() * 2 >= frames.len() && !vals.is_empty() {
            vals.sort_unstable();
            *o = vals[vals.len() / 2];
        }
    }
    DepthFrame::new(first.width, first.height, out)
}

/// Small deterministic generator (xorshift64*) for RANSAC sampling.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// RANSAC plane among `points` whose normal is within 35° of `up`; returns (plane, inlier count).
fn ransac_floor(
    points: &[Point3<f64>],
    up: Vector3<f64>,
    below: Option<Point3<f64>>,
    opts: &ScanOptions,
) -> Option<([f64; 4], usize)> {
    if points.len() < 3 {
        return None;
    }
    let cos_max = 35f64.to_radians().cos();
    let mut rng = Rng(opts.seed | 1);
    let mut best: Option<([f64; 4], usize)> = None;
    for _ in 0..opts.floor_iterations {
        let a = points[rng.below(points.len())];
        let b = points[rng.below(points.len())];
        let c = points[rng.below(points.len())];
        let Some(mut n) = normalize((b - a).cross(&(c - a))) else {
            continue;
        };
        if n.dot(&up) < 0.0 {
            n = -n;
        }
        if n.dot(&up) < cos_max {
            continue;
        }
        let d = -n.dot(&a.coords);
        // The floor is under the subject: the hip centre must be well above it.
        if let Some(h) = below {
            if n.dot(&h.coords) + d < 0.3 {
                continue;
            }
        }
        let count = points
            .iter()
            .filter(|p| (n.dot(&p.coords) + d).abs() <= opts.floor_threshold_m)
            .count();
        if best.is_none_or(|(_, c)| count > c) {
            best = Some(([n[0], n[1], n[2], d], count));
        }
    }
    best
}

/// Largest depth difference, metres, between a joint and the surface seen around its pixel for
/// the joint to lie on the body in this frame: a joint sits at most ~0.2 m behind the surface the
/// camera sees (a far-side joint in a profile view), plus the sensor's noise.
pub const JOINT_DEPTH_TOLERANCE_M: f64 = 0.35;

/// The joints a skeleton tracks (confidence > 0, or interpolated by the joint reader) at finite
/// positions; an untracked joint's position — the SDK's (0, 0, 0) — says nothing.
fn usable_joints(s: &Skeleton) -> impl Iterator<Item = Point3<f64>> + '_ {
    Joint::ALL.into_iter().filter_map(|j| tracked(s, j))
}

/// Joint `j`'s position when the skeleton [tracks](Skeleton::tracks) it at a finite position.
fn tracked(s: &Skeleton, j: Joint) -> Option<Point3<f64>> {
    Some(s.position(j)).filter(|p| s.tracks(j) && p.coords.iter().all(|x| x.is_finite()))
}

/// How a skeleton's joints lie on a depth frame ([`joints_on_depth`]): joints of another frame,
/// camera or unit do not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointsOnDepth {
    /// The joints the skeleton tracks (confidence > 0 or interpolated) at finite positions.
    pub usable: usize,
    /// Of those, the joints that project into the image onto a reading within
    /// [`JOINT_DEPTH_TOLERANCE_M`] of their depth (in a 7×7 pixel window, so a joint just beside
    /// a silhouette still finds it; any reading, also one outside the scan's depth range).
    pub on_body: usize,
    /// Over the usable joints in front of the camera with readings in their window: the median
    /// of (the window's median reading / the joint's depth); `None` without any. Far from 1 when
    /// the depth and the joints are in different units (a depth image in tenths of millimetres:
    /// 10; joints in millimetres read as metres: 0.001).
    pub depth_ratio: Option<f64>,
}

impl JointsOnDepth {
    /// At least half of the usable joints lie on the body (true without usable joints: nothing
    /// to judge).
    pub fn lie_on_body(&self) -> bool {
        2 * self.on_body >= self.usable
    }

    /// [`depth_unit_hint`] of [`JointsOnDepth::depth_ratio`].
    pub fn unit_hint(&self) -> String {
        depth_unit_hint(self.depth_ratio)
    }
}

/// The unit mismatch a [`JointsOnDepth::depth_ratio`] suggests, as a clause for a message: ""
/// when the depths agree within a factor of 3 (joints beside the body find the background,
/// rarely three times as far) or there is no ratio.
pub fn depth_unit_hint(depth_ratio: Option<f64>) -> String {
    match depth_ratio {
        Some(r) if !(1.0 / 3.0..=3.0).contains(&r) => format!(
            "; the depth readings at the joints' pixels are a median {r:.3}× the joints' depth \
             (depth images hold millimetres, joints metres)"
        ),
        _ => String::new(),
    }
}

/// Largest [`height_ratio`] a scan passes [`check_scale`] with. Scans with their own joints
/// measured 0.85–1.12 (five Kinect-v1 scan sets, 58 scans each, exact and tracker joints,
/// front and profile views: the surface reaches a little beyond the head and foot joints) and
/// 1.00–1.09 on the sampled frames of 14 recordings; a focal length of 0.64 or 0.5 of the
/// image's stretches the body, which the scan's background box (0.3 m around the joints) then
/// crops to 1.37–1.39 for an adult.
pub const MAX_HEIGHT_RATIO: f64 = 1.25;

/// How tall `mesh` is against `s` along the skeleton's spine (hip centre → shoulder centre):
/// the extent of the mesh's vertices over that of the tracked joints. About 1 for a body's
/// scan and its own joints; a focal length too short for the image (another camera's
/// intrinsics) stretches the scan across the line of sight while the joints keep their size.
/// `None` without the spine's joints, or when the joints have no extent along it.
///
/// ```
/// use symcorr_kinect::scan::height_ratio;
/// use symcorr_mesh::TriMesh;
/// use symcorr_skeleton::{Joint, Skeleton};
/// let mut xyz = [[0.0, 1.0, 3.0]; Joint::COUNT];
/// xyz[Joint::HipCenter.index()] = [0.0, 0.0, 3.0];
/// xyz[Joint::FootLeft.index()] = [0.1, -0.8, 3.0];
/// xyz[Joint::Head.index()] = [0.0, 0.8, 3.0];
/// let s = Skeleton::from_arrays(xyz);
/// let mesh = TriMesh::new(
///     vec![[0.0, -0.85, 3.0], [0.2, 0.9, 3.0], [-0.2, 0.0, 3.0]],
///     vec![[0, 1, 2]],
/// ).unwrap();
/// // Joints from −0.8 (the foot) to 1.0 m along the spine, the surface from −0.85 to 0.9.
/// assert!((height_ratio(&mesh, &s).unwrap() - 1.75 / 1.8).abs() < 1e-12);
/// ```
pub fn height_ratio(mesh: &TriMesh, s: &Skeleton) -> Option<f64> {
    let (hip, top) = (
        tracked(s, Joint::HipCenter)?,
        tracked(s, Joint::ShoulderCenter)?,
    );
    let up = normalize(top - hip)?;
    let extent = |values: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        (hi > lo).then_some(hi - lo)
    };
    let joints = extent(&mut usable_joints(s).map(|p| p.coords.dot(&up)))?;
    let surface = extent(
        &mut mesh
            .positions
            .iter()
            .map(|p| Vector3::from(*p).dot(&up))
            .filter(|x| x.is_finite()),
    )?;
    Some(surface / joints)
}

/// Refuses a scan much taller than its skeleton ([`height_ratio`] above
/// [`MAX_HEIGHT_RATIO`]): [`KinectError::ScaleMismatch`], naming the focal length `k` gave.
/// Matched, such a scan (a Kinect v2's focal length on a Kinect v1's image) lay 0.2 m off.
pub fn check_scale(mesh: &TriMesh, s: &Skeleton, k: &Intrinsics) -> Result<(), KinectError> {
    match height_ratio(mesh, s) {
        Some(ratio) if ratio > MAX_HEIGHT_RATIO => {
            Err(KinectError::ScaleMismatch { ratio, fx: k.fx })
        }
        _ => Ok(()),
    }
}

/// Refuses an image read with the wrong mirroring: [`KinectError::MirroringMismatch`] when the
/// image read the other way fits `s` clearly better — at least a quarter of the usable joints
/// (and three) more lie on the body with the columns reversed
/// ([`Intrinsics::columns_reversed`]). A depth image whose mirroring the intrinsics state
/// wrongly (an Azure Kinect's, Orbbec's or RealSense's image read as the Kinect SDK's mirrored
/// one, or the other way round), or joints whose x axis is reversed, show the subject's pose on
/// the other side: the limbs' joints miss the body as given and find it read the other way.
/// Scanned and matched as given, such a frame had three matches in four flipped.
///
/// ```
/// use symcorr_kinect::{scan::check_mirroring, DepthFrame, Intrinsics, Mirroring};
/// use symcorr_skeleton::Skeleton;
/// let k = Intrinsics {
///     width: 8, height: 6, fx: 7.0, fy: 7.0, cx: 3.5, cy: 2.5,
///     mirroring: Mirroring::Mirrored,
///     distortion: None,
/// };
/// // A body 2 m away on the image's left two columns only; every joint on it as given.
/// let mut depth = vec![0u16; 48];
/// for v in 0..6 { depth[v * 8] = 2000; depth[v * 8 + 1] = 2000; }
/// let frame = DepthFrame::new(8, 6, depth).unwrap();
/// let u0 = k.unproject(0.5, 2.5, 2.0);
/// let on_body = Skeleton::from_arrays([[u0.x, u0.y, 2.0]; 20]);
/// assert!(check_mirroring(&frame, &k, &on_body).is_ok());
/// // Joints where an image that is not mirrored would show that body: they miss it as given.
/// let direct = Intrinsics { mirroring: Mirroring::Direct, ..k };
/// let u1 = direct.unproject(0.5, 2.5, 2.0);
/// let other_side = Skeleton::from_arrays([[u1.x, u1.y, 2.0]; 20]);
/// let e = check_mirroring(&frame, &k, &other_side).unwrap_err();
/// assert!(e.to_string().contains("\"mirrored\": false"), "{e}");
/// ```
pub fn check_mirroring(
    frame: &DepthFrame,
    k: &Intrinsics,
    s: &Skeleton,
) -> Result<(), KinectError> {
    let given = joints_on_depth(frame, k, s);
    let other = Intrinsics {
        mirroring: k.mirroring.other(),
        ..*k
    };
    let reversed = joints_on_depth(frame, &other, s);
    let margin = (given.usable / 4).max(3);
    if reversed.on_body >= given.on_body + margin {
        return Err(KinectError::MirroringMismatch {
            given: given.on_body,
            reversed: reversed.on_body,
            stated_mirrored: k.mirroring == Mirroring::Mirrored,
        });
    }
    Ok(())
}

/// How `s`'s tracked joints lie on `frame` seen through `k` ([`JointsOnDepth`]). Pixels
/// outside the frame (intrinsics of another size) have no reading.
///
/// ```
/// use symcorr_kinect::{scan::joints_on_depth, DepthFrame, Intrinsics, Mirroring};
/// use symcorr_skeleton::Skeleton;
/// let k = Intrinsics {
///     width: 8, height: 6, fx: 7.0, fy: 7.0, cx: 3.5, cy: 2.5,
///     mirroring: Mirroring::Mirrored,
///     distortion: None,
/// };
/// // A wall 2 m away (2000 mm); joints 2 m away lie on it, joints "2000 m" away do not.
/// let frame = DepthFrame::new(8, 6, vec![2000; 48]).unwrap();
/// let on = joints_on_depth(&frame, &k, &Skeleton::from_arrays([[0.0, 0.0, 2.0]; 20]));
/// assert!(on.lie_on_body() && on.unit_hint().is_empty());
/// let mm = joints_on_depth(&frame, &k, &Skeleton::from_arrays([[0.0, 0.0, 2000.0]; 20]));
/// assert!(!mm.lie_on_body());
/// assert!(mm.unit_hint().contains("0.001×"));
/// ```
pub fn joints_on_depth(frame: &DepthFrame, k: &Intrinsics, s: &Skeleton) -> JointsOnDepth {
    let (w, h) = (i64::from(frame.width), i64::from(frame.height));
    let (mut usable, mut on_body, mut ratios) = (0, 0, Vec::new());
    for p in usable_joints(s) {
        usable += 1;
        if p.z <= 0.0 {
            continue;
        }
        let [u, v] = k.project(&p);
        // Far outside the image (a joint at the camera's plane projects to infinity) is outside.
        let clamp = |x: f64, side: i64| x.round().clamp(-8.0, (side + 8) as f64) as i64;
        let (u, v) = (clamp(u, w), clamp(v, h));
        let mut window: Vec<f64> = (-3..=3)
            .flat_map(|dv| (-3..=3).map(move |du| (u + du, v + dv)))
            .filter(|(x, y)| (0..w).contains(x) && (0..h).contains(y))
            .filter_map(|(x, y)| frame.data_mm.get((y * w + x) as usize))
            .filter(|&&d| d > 0)
            .map(|&d| f64::from(d) / 1000.0)
            .collect();
        if window
            .iter()
            .any(|z| (z - p.z).abs() <= JOINT_DEPTH_TOLERANCE_M)
        {
            on_body += 1;
        }
        if let Some(m) = median(&mut window) {
            ratios.push(m / p.z);
        }
    }
    JointsOnDepth {
        usable,
        on_body,
        depth_ratio: median(&mut ratios),
    }
}

/// Refuses a skeleton whose joints do not lie on the body this depth frame shows (joints of
/// another frame, camera or unit): fewer than half of the usable joints project onto a surface
/// within [`JOINT_DEPTH_TOLERANCE_M`] of their depth ([`joints_on_depth`]). Without the check
/// the background box built from such joints silently cuts the body.
fn check_joints_on_depth(
    frame: &DepthFrame,
    k: &Intrinsics,
    s: &Skeleton,
) -> Result<(), KinectError> {
    let on = joints_on_depth(frame, k, s);
    if !on.lie_on_body() {
        return Err(KinectError::Scan(format!(
            "the joints do not lie on the body in this depth frame: only {} of {} project onto \
             a surface within {JOINT_DEPTH_TOLERANCE_M} m of their depth; are they from another \
             frame, another camera or in another unit (metres expected)?{}",
            on.on_body,
            on.usable,
            on.unit_hint()
        )));
    }
    Ok(())
}

/// Builds the scan mesh of one depth frame (module docs). With a `skeleton` (same camera space),
/// the background beyond its extent is removed and the floor is searched below its hips.
///
/// Errors: [`KinectError::ScanOption`] for an invalid option ([`ScanOptions::validate`]),
/// [`KinectError::Intrinsics`] for implausible intrinsics ([`Intrinsics::validate`]),
/// [`KinectError::DepthSize`] if the frame does not match the intrinsics,
/// [`KinectError::Scan`] if the frame has no reading in range, nothing is left to triangulate,
/// the skeleton tracks no joint, or its
/// joints do not lie on the body the frame shows (fewer than half within
/// [`JOINT_DEPTH_TOLERANCE_M`] of the surface at their pixel: joints of another frame, camera or
/// unit).
pub fn scan_mesh(
    frame: &DepthFrame,
    k: &Intrinsics,
    skeleton: Option<&Skeleton>,
    opts: &ScanOptions,
) -> Result<ScanMesh, KinectError> {
    // Checked before the rays are found: a lens's table has a ray per pixel of `k`.
    opts.validate()?;
    k.validate()?;
    check_frame_size(frame, k)?;
    scan_checked(frame, &k.pixel_rays(), skeleton, opts)
}

/// [`scan_mesh`] with the camera's rays computed beforehand ([`Intrinsics::pixel_rays`]): for
/// many frames of a camera with a lens model, which would otherwise find every pixel's ray
/// again for each frame. Same errors.
pub fn scan_mesh_with_rays(
    frame: &DepthFrame,
    rays: &PixelRays,
    skeleton: Option<&Skeleton>,
    opts: &ScanOptions,
) -> Result<ScanMesh, KinectError> {
    opts.validate()?;
    rays.intrinsics().validate()?;
    check_frame_size(frame, rays.intrinsics())?;
    scan_checked(frame, rays, skeleton, opts)
}

/// [`scan_mesh_with_rays`] once its options, intrinsics and frame size are checked.
fn scan_checked(
    frame: &DepthFrame,
    rays: &PixelRays,
    skeleton: Option<&Skeleton>,
    opts: &ScanOptions,
) -> Result<ScanMesh, KinectError> {
    let k = rays.intrinsics();
    let mut points = points_through(frame, rays, opts.min_depth_m, opts.max_depth_m);
    let mut report = ScanReport {
        valid_pixels: points.iter().filter(|p| p.is_some()).count(),
        ..ScanReport::default()
    };
    // Said before anything about the joints: with no reading, no joint can lie on the body,
    // and a message blaming the joints would send the user to the wrong stream.
    if report.valid_pixels == 0 {
        return Err(KinectError::Scan(format!(
            "the depth frame has no reading between {} and {} m (every pixel is 0 or out of \
             that range): the camera saw nothing in this frame",
            opts.min_depth_m, opts.max_depth_m
        )));
    }
    if let Some(s) = skeleton {
        if usable_joints(s).next().is_none() {
            return Err(KinectError::Scan(
                "the skeleton tracks no joint (every confidence is 0): the tracker saw no body \
                 in this frame"
                    .into(),
            ));
        }
        check_joints_on_depth(frame, k, s)?;
        let margin = Vector3::repeat(opts.background_margin_m);
        let mut lo = Point3::from([f64::INFINITY; 3]);
        let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
        // The box of the tracked joints: an untracked joint at the camera would stretch it.
        for p in usable_joints(s) {
            lo = lo.inf(&(p - margin));
            hi = hi.sup(&(p + margin));
        }
        for p in points.iter_mut() {
            if let Some(q) = p {
                let outside = (0..3).any(|c| q[c] < lo[c] || q[c] > hi[c]);
                if outside {
                    *p = None;
                    report.background_removed += 1;
                }
            }
        }
    }
    if opts.remove_floor {
        // The body's up and its lowest trunk joint, from tracked joints only (an untracked
        // hip centre sits at the camera's origin).
        let low = skeleton
            .and_then(|s| tracked(s, Joint::HipCenter).or_else(|| tracked(s, Joint::Spine)));
        let up = skeleton
            .and_then(|s| tracked(s, Joint::ShoulderCenter))
            .zip(low)
            .and_then(|(top, low)| normalize(top - low))
            .unwrap_or_else(Vector3::y);
        let hip = low;
        // In the order of the mirrored image's pixels whatever the image's direction, so that
        // the seeded samples, and the plane, do not depend on it.
        let w = frame.width as usize;
        let candidates: Vec<Point3<f64>> = match k.mirroring {
            Mirroring::Mirrored => points.iter().flatten().copied().collect(),
            Mirroring::Direct => points
                .chunks(w.max(1))
                .flat_map(|row| row.iter().rev().flatten().copied())
                .collect(),
        };
        if let Some((plane, count)) = ransac_floor(&candidates, up, hip, opts) {
            // A handful of coplanar points is not a floor.
            if count >= 50 && count * 50 >= candidates.len() {
                report.floor_plane = Some(plane);
                for p in points.iter_mut() {
                    if let Some(q) = p {
                        if (Vector3::new(plane[0], plane[1], plane[2]).dot(&q.coords) + plane[3])
                            .abs()
                            <= opts.floor_threshold_m
                        {
                            *p = None;
                            report.floor_removed += 1;
                        }
                    }
                }
            }
        }
    }

    // Grid triangulation.
    let (w, h) = (frame.width as usize, frame.height as usize);
    let ok = |a: Point3<f64>, b: Point3<f64>| (a.z - b.z).abs() <= opts.discontinuity_m;
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let direct = k.mirroring == Mirroring::Direct;
    for v in 0..h.saturating_sub(1) {
        for u in 0..w.saturating_sub(1) {
            let ia = v * w + u;
            let (ib, ic, id) = (ia + 1, ia + w, ia + w + 1);
            // A block's corners a b / c d. Mirrored: +x grows with u, so a → b → c turns
            // towards the camera, split along b–c. Direct: +x falls with u; the mirrored
            // image's b–c diagonal is this one's a–d, and a → c → d turns towards the camera.
            let block = if direct {
                [[ia, ic, id], [ia, id, ib]]
            } else {
                [[ia, ib, ic], [ib, id, ic]]
            };
            for [x, y, z] in block {
                if let (Some(px), Some(py), Some(pz)) = (points[x], points[y], points[z]) {
                    if ok(px, py) && ok(py, pz) && ok(pz, px) {
                        tris.push([x, y, z]);
                    } else {
                        report.discontinuity_triangles += 1;
                    }
                }
            }
        }
    }

    // Connected components (union-find over pixels through triangles).
    let mut before_components = None;
    if opts.components != ComponentFilter::All && !tris.is_empty() {
        before_components = Some(count_vertices(&tris, points.len()));
        keep_components(&mut tris, &points, skeleton, opts.components);
    }
    if tris.is_empty() {
        return Err(KinectError::Scan(format!(
            "no triangle left ({} valid pixels, {} background, {} floor, {} across discontinuities)",
            report.valid_pixels,
            report.background_removed,
            report.floor_removed,
            report.discontinuity_triangles
        )));
    }

    // Compact: vertices in pixel order.
    let mut index = vec![u32::MAX; points.len()];
    let used: Vec<usize> = used_pixels(&tris, points.len())
        .iter()
        .enumerate()
        .filter_map(|(px, &u)| u.then_some(px))
        .collect();
    if let Some(before) = before_components {
        report.component_vertices_removed = before - used.len();
    }
    let mut positions = Vec::with_capacity(used.len());
    let mut pixel_ids = Vec::with_capacity(used.len());
    for (n, &px) in used.iter().enumerate() {
        index[px] = n as u32;
        // Every used pixel belongs to a triangle, whose corners all have points.
        if let Some(p) = points[px] {
            positions.push(p.into());
        }
        pixel_ids.push(px as u32);
    }
    let triangles = tris
        .iter()
        .map(|t| [index[t[0]], index[t[1]], index[t[2]]])
        .collect();
    let mesh = TriMesh::new(positions, triangles)?;
    Ok(ScanMesh {
        mesh,
        pixel_ids,
        report,
    })
}

/// The mean distance from the points to a plane `[n, d]` (helper for reports and tests).
pub fn plane_distance(plane: [f64; 4], p: &Point3<f64>) -> f64 {
    let n = Vector3::new(plane[0], plane[1], plane[2]);
    (n.dot(&p.coords) + plane[3]) / n.norm()
}
