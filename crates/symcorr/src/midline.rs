//! The left and right halves of the midline segments (pelvis, torso, head). They are single
//! segments with two halves, so the segment labels alone cannot stop a left/right flip on them;
//! the paper pipeline's extended filter and the refined method's pools also use the side of a
//! sagittal plane. The planes come from the skeleton ([`SagittalPlanes`]: each segment's own
//! joints, so they follow a twisted spine); the skull's, and every plane of
//! [`symmetric_midline_halves`], are refined by the surface's own left/right symmetry
//! ([`refine_symmetry_plane`], an iterated reflect–match–refit). Measured choices:
//! `docs/decisions/2026-11-23-midline-halves-and-skull-plane.md`,
//! `docs/decisions/2026-11-23-sagittal-band.md` and `docs/decisions/2026-11-23-refined-method.md`.

use nalgebra::{Point3, Vector3};
use symcorr_correspond::refine_symmetry_plane;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{BodySide, Joint, Plane, SagittalPlanes, Segment, Skeleton};

/// Where the skull's own plane takes over from the shoulders' ([`midline_halves`]), as a
/// fraction of the neck → head bone.
const SKULL_START: f64 = 0.5;

/// At most this many vertices feed a symmetry-plane fit (an even stride sample): the fit
/// converges on a few hundred points, and its cost grows with the count.
const SYMMETRY_POINTS: usize = 1500;

/// Iterations of [`refine_symmetry_plane`].
const SYMMETRY_ITERATIONS: usize = 10;

/// A plane as the point and unit normal the distances below use.
type PlaneFrame = (Point3<f64>, Vector3<f64>);

fn frame(plane: Plane) -> PlaneFrame {
    (plane.origin, plane.normal)
}

/// The symmetry plane of `points` (an even stride sample of at most [`SYMMETRY_POINTS`]),
/// starting from `start`.
fn symmetry_plane(points: Vec<[f64; 3]>, start: PlaneFrame) -> PlaneFrame {
    let stride = points.len().div_ceil(SYMMETRY_POINTS).max(1);
    let points: Vec<[f64; 3]> = points.into_iter().step_by(stride).collect();
    let (o, n) =
        refine_symmetry_plane(&points, start.0.into(), start.1.into(), SYMMETRY_ITERATIONS);
    (o.into(), n.into())
}

/// Signed distance of `x` to the plane (`+` on the side the normal points to: the subject's
/// left).
fn signed_distance(x: [f64; 3], (o, n): PlaneFrame) -> f64 {
    (Point3::from(x) - o).dot(&n)
}

/// The side of each vertex on a midline segment (pelvis, torso, head): [`BodySide::Left`] or
/// [`BodySide::Right`] of its segment's sagittal plane beyond `margin` (mesh units),
/// [`BodySide::Midline`] within it and on every limb segment.
///
/// The plane of each segment is spanned by its own joints ([`SagittalPlanes`]): the pelvis'
/// through the midpoint of the hips with normal `hip_left − hip_right`, the head's through the
/// midpoint of the shoulders with normal `shoulder_left − shoulder_right`, the torso's through
/// the mean of both with the sum of both normals. The skull (head vertices beyond half the
/// neck → head bone) is the exception: no joint says how the head is turned against the
/// shoulders, so its plane is the shoulders' refined by the skull's own symmetry; the neck
/// keeps the shoulders' plane.
///
/// ```
/// use symcorr::midline_halves;
/// use symcorr_attach::testbody::t_pose;
/// use symcorr_mesh::TriMesh;
/// use symcorr_skeleton::{BodySide, Segment};
/// let skeleton = t_pose(1.0); // facing −z: the subject's left is +x
/// let mesh = TriMesh::new(
///     vec![[0.1, 1.0, 0.05], [-0.1, 1.0, 0.05], [0.12, 0.7, 0.0]],
///     vec![[0, 1, 2]],
/// ).unwrap();
/// let labels = [Segment::Pelvis, Segment::Pelvis, Segment::ThighLeft];
/// let halves = midline_halves(&mesh, &labels, &skeleton, 0.0);
/// assert_eq!(halves, [BodySide::Left, BodySide::Right, BodySide::Midline]);
/// ```
pub fn midline_halves(
    mesh: &TriMesh,
    labels: &[Segment],
    joints: &Skeleton,
    margin: f64,
) -> Vec<BodySide> {
    midline_signed_distances(mesh, labels, joints)
        .into_iter()
        .map(|d| BodySide::of_signed_distance(d, margin))
        .collect()
}

/// The sagittal coordinate of each vertex on a midline segment (pelvis, torso, head) for the
/// sagittal band (symcorr-correspond's `sagittal_band`, beyond the paper): the signed distance
/// to the segment's plane of [`midline_halves`] (`+` on the subject's left) over the segment's
/// half-width on this mesh — the 90th percentile of the segment's |distances| — so that bodies
/// of different build compare; `0` on every limb segment.
pub fn midline_sagittal(mesh: &TriMesh, labels: &[Segment], joints: &Skeleton) -> Vec<f64> {
    let mut d = midline_signed_distances(mesh, labels, joints);
    for seg in Segment::MIDLINE {
        let mut abs: Vec<f64> = d
            .iter()
            .zip(labels)
            .filter(|(_, &l)| l == seg)
            .map(|(x, _)| x.abs())
            .collect();
        if abs.is_empty() {
            continue;
        }
        let k = (abs.len() * 9 / 10).min(abs.len() - 1);
        abs.select_nth_unstable_by(k, f64::total_cmp);
        let width = abs[k];
        for (x, &l) in d.iter_mut().zip(labels) {
            if l == seg {
                *x = if width > 0.0 { *x / width } else { 0.0 };
            }
        }
    }
    d
}

/// Signed distance of each midline vertex to its segment's plane ([`midline_halves`]), `0` on
/// limb segments.
fn midline_signed_distances(mesh: &TriMesh, labels: &[Segment], joints: &Skeleton) -> Vec<f64> {
    let planes = SagittalPlanes::of(joints);
    // The skull: head vertices beyond SKULL_START of the neck → head bone. Its plane starts from
    // the shoulder normal through the head joint.
    let neck = joints.position(Joint::ShoulderCenter);
    let top = joints.position(Joint::Head);
    let bone = top - neck;
    let bone_sq = bone.norm_squared();
    let on_skull =
        |x: [f64; 3]| bone_sq > 0.0 && (Point3::from(x) - neck).dot(&bone) > SKULL_START * bone_sq;
    let skull: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .zip(labels)
        .filter(|(x, &l)| l == Segment::Head && on_skull(**x))
        .map(|(x, _)| *x)
        .collect();
    let skull_plane = symmetry_plane(skull, (top, planes.shoulders.normal));
    mesh.positions
        .iter()
        .zip(labels)
        .map(|(&x, s)| {
            let plane = match s {
                Segment::Pelvis => frame(planes.pelvis),
                Segment::Torso => frame(planes.torso),
                Segment::Head if on_skull(x) => skull_plane,
                Segment::Head => frame(planes.shoulders),
                _ => return 0.0,
            };
            signed_distance(x, plane)
        })
        .collect()
}

/// The sagittal planes of [`midline_halves`] (margin 0), each refined by the surface's own
/// left/right symmetry ([`refine_symmetry_plane`] on an even sample of at most 1,500 of the
/// segment's vertices): a noisy shoulder line or a head turned against the shoulders
/// tilts a joint plane by many degrees, the surface's symmetry plane does not. Every midline
/// vertex gets a side (one exactly on the plane counts as left); limb vertices are
/// [`BodySide::Midline`]. The refined method's halves.
pub fn symmetric_midline_halves(
    mesh: &TriMesh,
    labels: &[Segment],
    joints: &Skeleton,
) -> Vec<BodySide> {
    let planes = SagittalPlanes::of(joints);
    let fit = |seg: Segment, plane: Plane| {
        let points: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .zip(labels)
            .filter(|(_, &l)| l == seg)
            .map(|(x, _)| *x)
            .collect();
        symmetry_plane(points, frame(plane))
    };
    let pelvis = fit(Segment::Pelvis, planes.pelvis);
    let torso = fit(Segment::Torso, planes.torso);
    let head = fit(Segment::Head, planes.shoulders);
    mesh.positions
        .iter()
        .zip(labels)
        .map(|(&x, s)| {
            let plane = match s {
                Segment::Pelvis => pelvis,
                Segment::Torso => torso,
                Segment::Head => head,
                _ => return BodySide::Midline,
            };
            if signed_distance(x, plane) >= 0.0 {
                BodySide::Left
            } else {
                BodySide::Right
            }
        })
        .collect()
}
