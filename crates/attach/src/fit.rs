//! Fit quality: how well the aligned skeleton sits in its mesh ([`FitQuality`]).
//!
//! A skeleton that overlaps the body can still be wrong: turned about the vertical axis, upside
//! down, from another pose or another body. Every check below is a deviation measured against
//! the mesh, with an upper limit; the skeleton fits when every check is within its limit.
//!
//! * `surface_distance` — median joint-to-nearest-vertex distance (skeleton heights).
//! * `coverage` — median distance from a mesh vertex to its nearest bone (skeleton heights):
//!   the bones must run through the whole mesh.
//! * `outside` — fraction of points along the bones (each joint and three points per bone)
//!   that lie outside the surface, by the outward normal of their nearest vertex. Closed
//!   surfaces, and depth scans in their camera's space ([`camera_side`]): the
//!   camera saw the space in front of the surface and beside its silhouette empty, so a bone
//!   there is outside the body (the visual hull; the normals turned to the camera). Skipped on
//!   other open surfaces. The rotation search ranks its placements by the closed surface's
//!   outside depth, on open surfaces by the joints' distance to the surface (on scans the
//!   outside depth recovered fewer turned skeletons:
//!   `docs/decisions/2026-12-03-turned-skeletons-on-scans.md`).
//! * `facing_conflict` — the skeleton's own facing cues (ankle → foot joints, knee bend) against
//!   the mesh's (the surface around the ankles reaches forward, to the toes): a rigidly turned
//!   skeleton keeps its own cues but contradicts the mesh's. `min(|skeleton|, |mesh|)` when the
//!   two disagree in sign, else 0. Skipped without feet in the mesh.
//! * `unreached` — fraction of the mesh's vertices in connected components no bone comes within
//!   [`REACH`] skeleton heights of (a stray object beside the body); such components are listed
//!   in [`FitQuality::unreached`] and are never labelled by the pipeline.
//!
//! The score is `min` over the checks of `1 − value / (2·limit)` clamped to `[0, 1]`: 1 is a
//! perfect fit, [`FIT_THRESHOLD`] (0.5) is a check exactly at its limit. The limits were
//! measured on generated bodies with exact and noisy (σ = 3 cm) joints against turned, flipped,
//! other-pose and other-body joints: `docs/decisions/2026-12-02-attach-fit-quality.md`.

use crate::bvh::TriangleBvh;
use crate::geom::{bone_segments, distance_to_bones, Joints};
use crate::refine::torso_frame;
use crate::tables::MeshTables;
use crate::{Joint, MirrorCheck, Skeleton};
use nalgebra::{Point3, Rotation3, Unit, Vector3};
use symcorr_mesh::TriMesh;

/// The score at which a fit is accepted: every check within its limit.
pub const FIT_THRESHOLD: f64 = 0.5;

/// A component whose nearest vertex is farther than this from every bone (skeleton heights)
/// is not reached by the skeleton.
pub const REACH: f64 = 0.25;

/// How far beyond the surface a point along the bones must lie to count as outside (skeleton
/// heights, ~2.5 cm on an adult): tracker noise puts wrists and ankles just outside their limb.
pub const OUTSIDE_MARGIN: f64 = 0.015;

/// The mesh's facing cue (in [-1, 1]) that counts as full agreement with a clear skeleton cue;
/// `facing_conflict` is the shortfall from it.
pub const FACING_AGREEMENT: f64 = 0.3;

/// One measured aspect of the fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FitCheckKind {
    /// Median joint-to-surface distance (skeleton heights).
    SurfaceDistance,
    /// Median vertex-to-bone distance (skeleton heights).
    Coverage,
    /// Fraction of points along the bones outside a closed surface or a depth scan's visual hull.
    Outside,
    /// Disagreement between the skeleton's and the mesh's facing cues.
    FacingConflict,
    /// Fraction of vertices in components no bone reaches.
    Unreached,
}

impl FitCheckKind {
    /// Every check, in report order.
    pub const ALL: [FitCheckKind; 5] = [
        FitCheckKind::SurfaceDistance,
        FitCheckKind::Coverage,
        FitCheckKind::Outside,
        FitCheckKind::FacingConflict,
        FitCheckKind::Unreached,
    ];

    /// The check's name in outputs (`surface_distance`, …).
    pub fn name(self) -> &'static str {
        match self {
            FitCheckKind::SurfaceDistance => "surface_distance",
            FitCheckKind::Coverage => "coverage",
            FitCheckKind::Outside => "outside",
            FitCheckKind::FacingConflict => "facing_conflict",
            FitCheckKind::Unreached => "unreached",
        }
    }

    /// The check's limit (module docs).
    pub fn limit(self) -> f64 {
        match self {
            FitCheckKind::SurfaceDistance => 0.08,
            FitCheckKind::Coverage => 0.2,
            FitCheckKind::Outside => 0.3,
            FitCheckKind::FacingConflict => 0.25,
            FitCheckKind::Unreached => 0.1,
        }
    }

    /// What a failure of this check usually means, for error messages.
    pub fn meaning(self) -> &'static str {
        match self {
            FitCheckKind::SurfaceDistance => "the joints lie away from the surface",
            FitCheckKind::Coverage => "the bones do not run through the whole mesh",
            FitCheckKind::Outside => "the bones stick out of the body",
            FitCheckKind::FacingConflict => {
                "the skeleton faces another way than the body (its feet point backwards)"
            }
            FitCheckKind::Unreached => "much of the mesh is far from every bone",
        }
    }
}

/// One check's measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitCheck {
    /// Which check.
    pub kind: FitCheckKind,
    /// The measured deviation (module docs); lower is better.
    pub value: f64,
    /// [`FitCheckKind::limit`].
    pub limit: f64,
    /// `value <= limit`.
    pub passed: bool,
}

impl FitCheck {
    fn new(kind: FitCheckKind, value: f64) -> FitCheck {
        let limit = kind.limit();
        FitCheck {
            kind,
            value,
            limit,
            // NaN fails.
            passed: value <= limit,
        }
    }

    /// `1 − value / (2·limit)` clamped to `[0, 1]` (0 for NaN).
    pub fn quality(&self) -> f64 {
        let q = 1.0 - self.value / (2.0 * self.limit);
        if q.is_nan() {
            0.0
        } else {
            q.clamp(0.0, 1.0)
        }
    }
}

/// How well the skeleton fits its mesh, measured after alignment and the handedness fix
/// (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FitQuality {
    /// `min` over the checks of [`FitCheck::quality`]; at least [`FIT_THRESHOLD`] when every
    /// check passed.
    pub score: f64,
    /// The checks that applied (a check without its inputs — `outside` on an open surface,
    /// `facing_conflict` without feet — is left out).
    pub checks: Vec<FitCheck>,
    /// Vertices of the components no bone reaches (sorted).
    pub unreached: Vec<u32>,
    /// True when the fit failed a check and was used anyway ([`crate::PoorFitPolicy::Accept`]).
    pub accepted_poor_fit: bool,
}

impl FitQuality {
    /// True when every check passed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.passed)
    }

    /// The failed check farthest beyond its limit.
    pub fn worst(&self) -> Option<&FitCheck> {
        self.checks
            .iter()
            .filter(|c| !c.passed)
            .min_by(|a, b| a.quality().total_cmp(&b.quality()))
    }

    /// The check of the given kind, if it applied.
    pub fn check(&self, kind: FitCheckKind) -> Option<&FitCheck> {
        self.checks.iter().find(|c| c.kind == kind)
    }
}

/// What the checks share about the mesh: positions and outward normals as nalgebra types,
/// whether the surface is closed, and the connected components.
pub(crate) struct FitMesh {
    positions: Vec<Point3<f64>>,
    normals: Vec<Vector3<f64>>,
    /// Outward sign of the normals for a closed surface, or towards the camera for a depth scan
    /// seen from the origin (`None`: another open surface, no inside).
    outward: Option<f64>,
    /// True for a closed surface.
    closed: bool,
    components: (Vec<u32>, usize),
}

impl FitMesh {
    /// The mesh as the checks see it; `p` (the given placement's joints, `usable` ones) decides
    /// whether a depth scan is seen from the origin ([`camera_side`]); `bvh` is the mesh's.
    pub(crate) fn new(
        tables: &MeshTables<'_>,
        bvh: &TriangleBvh,
        p: &Joints,
        usable: &[bool; 20],
    ) -> FitMesh {
        let mesh = tables.mesh;
        let positions: Vec<Point3<f64>> = mesh.positions.iter().map(|&p| Point3::from(p)).collect();
        let normals = mesh
            .vertex_normals()
            .into_iter()
            .map(Vector3::from)
            .collect();
        // A surface with boundary edges longer than a few √area is a partial view; a closed
        // body (or one with small holes at the eyes or soles) has an inside. Its normals point
        // out when its signed volume is positive. A partial view in its camera's space (a
        // depth scan facing the origin) has an outside too: the space between the camera and
        // the surface, and beside the silhouette, is seen empty — a body's bones cannot lie
        // there (the visual hull); its "outward" normals face the camera.
        let area = mesh.total_area();
        let closed = tables.boundary().length < 0.5 * area.sqrt();
        let outward = if closed {
            Some(if signed_volume(mesh) >= 0.0 {
                1.0
            } else {
                -1.0
            })
        } else {
            camera_side_of(
                mesh,
                bvh,
                TORSO
                    .iter()
                    .filter(|j| usable[j.index()])
                    .map(|j| p[j.index()]),
            )
        };
        FitMesh {
            positions,
            normals,
            outward,
            closed,
            components: mesh.connected_components(),
        }
    }

    /// The vertex counts of the two largest connected components when the second holds at
    /// least a third as many vertices as the first: a mesh holding two bodies (or a body and
    /// something as large), which no one skeleton can fit. `None` for one body, with or without
    /// small stray parts (an arm a depth scan cut off holds far less than the rest).
    pub(crate) fn two_large_parts(&self) -> Option<(usize, usize)> {
        let (labels, count) = &self.components;
        let mut sizes = vec![0usize; *count];
        for &c in labels {
            sizes[c as usize] += 1;
        }
        sizes.sort_unstable_by(|a, b| b.cmp(a));
        match sizes[..] {
            [a, b, ..] if 3 * b >= a => Some((a, b)),
            _ => None,
        }
    }

    /// How far `x` lies outside the surface along its nearest vertex's outward normal (negative
    /// inside); `sign` is [`FitMesh::outward`].
    fn outside_depth(&self, x: &Point3<f64>, sign: f64) -> f64 {
        match self.nearest(x) {
            Some((v, _)) => sign * (x - self.positions[v]).dot(&self.normals[v]),
            None => f64::INFINITY,
        }
    }

    fn nearest(&self, x: &Point3<f64>) -> Option<(usize, f64)> {
        self.positions
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (p - x).norm_squared()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, d)| (i, d.sqrt()))
    }
}

/// The side of `mesh` that faces its camera, when `mesh` is a depth scan in that camera's space
/// (the camera at the origin) and `joints` its body's: `Some(1.0)` when the triangles' winding
/// normals face the camera, `Some(-1.0)` when they face away from it, `None` for any other mesh.
///
/// A depth scan faces its camera all one way, from a distance
/// ([`TriMesh::origin_facing_side`]), and shows the body's near side: the torso's joints, inside
/// the body, lie beyond the surface along their lines of sight. The origin is refused as the
/// camera when more of them lie clearly in front of the surface (`BEHIND_MARGIN`) than beyond
/// it: this tells a scan from a partial mesh whose origin lies *behind* it (the front half of a
/// body in a frame whose origin is 2 m behind the body faces the origin all one way as well).
///
/// ```
/// use nalgebra::Point3;
/// use symcorr_mesh::TriMesh;
/// // A square 2 m in front of the origin, facing it; a body behind it and one in front of it.
/// let square = TriMesh::new(
///     vec![[-0.5, -0.5, 2.0], [-0.5, 0.5, 2.0], [0.5, 0.5, 2.0], [0.5, -0.5, 2.0]],
///     vec![[0, 1, 2], [0, 2, 3]],
/// )?;
/// let mut body = symcorr_attach::testbody::t_pose(0.5);
/// body.positions.iter_mut().for_each(|p| *p = Point3::new(p.x, p.y - 0.6, 2.1));
/// assert_eq!(symcorr_attach::camera_side(&square, &body), Some(1.0));
/// body.positions.iter_mut().for_each(|p| p.z = 1.9);
/// assert_eq!(symcorr_attach::camera_side(&square, &body), None);
/// # Ok::<(), symcorr_mesh::MeshError>(())
/// ```
pub fn camera_side(mesh: &TriMesh, joints: &Skeleton) -> Option<f64> {
    camera_side_of(
        mesh,
        &TriangleBvh::new(mesh),
        TORSO
            .iter()
            .map(|j| joints.position(*j))
            .filter(|p| p.coords.iter().all(|x| x.is_finite())),
    )
}

/// The joints that vote in [`camera_side`]: on the torso's axis, where a body turned about the
/// vertical keeps them at their depth (a skeleton turned by 180° puts its limbs' joints in front
/// of a scan, which the fit checks must still see).
const TORSO: [Joint; 3] = [Joint::HipCenter, Joint::Spine, Joint::ShoulderCenter];

/// [`camera_side`] with the mesh's `bvh` at hand (attachment builds one for the bone heat too).
fn camera_side_of(
    mesh: &TriMesh,
    bvh: &TriangleBvh,
    joints: impl Iterator<Item = Point3<f64>>,
) -> Option<f64> {
    let side = mesh.origin_facing_side()?;
    let (lo, hi) = mesh.bounding_box();
    let diagonal = (Vector3::from(hi) - Vector3::from(lo)).norm();
    let margin = BEHIND_MARGIN * diagonal;
    // Each torso joint whose line of sight crosses the surface votes: beyond the surface (or
    // less than the margin in front of it: joint noise), or clearly in front of it.
    let (mut beyond, mut in_front) = (0usize, 0usize);
    for x in joints {
        let Some(u) = x.coords.try_normalize(0.0) else {
            continue;
        };
        let x = x + u * margin;
        if bvh.segment_blocked(&Point3::origin(), &x, u32::MAX) {
            beyond += 1;
        } else if bvh.segment_blocked(&x, &(x + u * 2.0 * diagonal), u32::MAX) {
            in_front += 1;
        }
    }
    (in_front <= beyond).then_some(side)
}

/// How far in front of a scan (in diagonals of its bounding box, 10 cm on a body) a torso joint
/// must lie to count against the origin being the scan's camera ([`camera_side`]): tracker noise
/// (2–3 cm) never puts the torso that far out; the origin behind a partial body puts it a torso's
/// half-depth (10–15 cm) in front.
const BEHIND_MARGIN: f64 = 0.05;

fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.num_triangles())
        .map(|t| {
            let [a, b, c] = mesh.corners(t).map(Vector3::from);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

/// Each usable joint and three points along each bone between usable joints.
fn bone_samples(p: &Joints, usable: &[bool; 20]) -> Vec<Point3<f64>> {
    let mut samples: Vec<Point3<f64>> = (0..20).filter(|&j| usable[j]).map(|j| p[j]).collect();
    for (a, c) in bone_segments(p, usable) {
        for t in [0.25, 0.5, 0.75] {
            samples.push(a + (c - a) * t);
        }
    }
    samples
}

/// Measures the fit of the (aligned, handedness-fixed) joints `p` in `mesh` (module docs).
/// `accepted_poor_fit` is false; the caller sets it.
pub(crate) fn measure(
    fm: &FitMesh,
    p: &Joints,
    usable: &[bool; 20],
    height: f64,
    mirror: &MirrorCheck,
) -> FitQuality {
    let h = height.max(f64::MIN_POSITIVE);
    let bones = bone_segments(p, usable);
    let bone_distance = |x: &Point3<f64>| distance_to_bones(x, &bones);
    let median = |mut d: Vec<f64>| {
        d.sort_by(f64::total_cmp);
        d.get(d.len() / 2).copied().unwrap_or(f64::INFINITY)
    };
    let mut checks = Vec::with_capacity(6);
    // Joints to the surface.
    let joint_d: Vec<f64> = (0..20)
        .filter(|&j| usable[j])
        .filter_map(|j| fm.nearest(&p[j]).map(|(_, d)| d / h))
        .collect();
    checks.push(FitCheck::new(
        FitCheckKind::SurfaceDistance,
        median(joint_d),
    ));
    // Vertices to the bones (an even stride of at most 2000).
    let stride = (fm.positions.len() / 2000).max(1);
    let mut cover: Vec<f64> = fm
        .positions
        .iter()
        .step_by(stride)
        .map(|x| bone_distance(x) / h)
        .collect();
    cover.sort_by(f64::total_cmp);
    let p90 = cover
        .get(cover.len() * 9 / 10)
        .copied()
        .unwrap_or(f64::INFINITY);
    checks.push(FitCheck::new(FitCheckKind::Coverage, p90));
    // Points along the bones outside a closed surface.
    if let Some(sign) = fm.outward {
        let samples = bone_samples(p, usable);
        let outside = samples
            .iter()
            .filter(|x| fm.outside_depth(x, sign) > OUTSIDE_MARGIN * h)
            .count();
        checks.push(FitCheck::new(
            FitCheckKind::Outside,
            outside as f64 / samples.len().max(1) as f64,
        ));
    }
    // The skeleton's facing cues against the mesh's: where the skeleton's own cue is clear,
    // the mesh's must agree with it.
    if let Some(m) = mirror.mesh_evidence {
        let s = 0.5 * mirror.skeleton_evidence.unwrap_or(0.0) + mirror.knee_evidence.unwrap_or(0.0);
        if s.abs() >= 0.25 {
            checks.push(FitCheck::new(
                FitCheckKind::FacingConflict,
                (FACING_AGREEMENT - m * s.signum()).max(0.0),
            ));
        }
    }
    // Components no bone reaches.
    let (comp, count) = &fm.components;
    let mut nearest = vec![f64::INFINITY; *count];
    for (v, x) in fm.positions.iter().enumerate() {
        let c = comp[v] as usize;
        // A component already reached needs no more distances.
        if nearest[c] > REACH * h {
            nearest[c] = nearest[c].min(bone_distance(x));
        }
    }
    let unreached: Vec<u32> = (0..fm.positions.len() as u32)
        .filter(|&v| nearest[comp[v as usize] as usize] > REACH * h)
        .collect();
    checks.push(FitCheck::new(
        FitCheckKind::Unreached,
        unreached.len() as f64 / fm.positions.len().max(1) as f64,
    ));
    let score = checks.iter().map(FitCheck::quality).fold(1.0f64, f64::min);
    FitQuality {
        score,
        checks,
        unreached,
        accepted_poor_fit: false,
    }
}

/// A rigid placement `x ↦ r·x + t` of the joints.
pub(crate) type Placement = (Rotation3<f64>, Vector3<f64>);

/// The search's objective: mean depth of the bone samples beyond a closed surface (0 inside; on
/// an open surface, a depth scan too, the joints' distance to it) plus a tenth of the median
/// vertex-to-bone distance, in skeleton heights. Zero-ish for a skeleton inside its body.
fn objective(fm: &FitMesh, p: &Joints, usable: &[bool; 20], h: f64) -> f64 {
    let samples = bone_samples(p, usable);
    let n = samples.len().max(1) as f64;
    let depth: f64 = match fm.outward.filter(|_| fm.closed) {
        Some(sign) => samples
            .iter()
            .map(|x| fm.outside_depth(x, sign).max(0.0))
            .sum(),
        None => samples
            .iter()
            .map(|x| fm.nearest(x).map_or(f64::INFINITY, |(_, d)| d))
            .sum(),
    };
    let bones = bone_segments(p, usable);
    let stride = (fm.positions.len() / 500).max(1);
    let mut cover: Vec<f64> = fm
        .positions
        .iter()
        .step_by(stride)
        .map(|x| distance_to_bones(x, &bones))
        .collect();
    cover.sort_by(f64::total_cmp);
    let median = cover.get(cover.len() / 2).copied().unwrap_or(f64::INFINITY);
    (depth / n + 0.1 * median) / h.max(f64::MIN_POSITIVE)
}

fn place(p: &Joints, (r, t): &Placement) -> Joints {
    std::array::from_fn(|j| r * p[j] + t)
}

/// The placements the rotation search tries after the given one fails a check: the coarse
/// [`candidates`] ranked by [`objective`], the best few refined by a greedy local search over
/// small turns about the torso's axes through the joints' centroid and small shifts (steps
/// halving from 8° and 0.04 heights). Best first.
pub(crate) fn search(
    fm: &FitMesh,
    p: &Joints,
    usable: &[bool; 20],
    height: f64,
    mesh_centroid: &Point3<f64>,
) -> Vec<Placement> {
    let Some([up, left, facing]) = torso_frame(p, usable) else {
        return Vec::new();
    };
    let mut ranked: Vec<(f64, Placement)> = candidates(p, usable, mesh_centroid)
        .into_iter()
        .map(|c| (objective(fm, &place(p, &c), usable, height), c))
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
    ranked.truncate(4);
    let mut out: Vec<(f64, Placement)> = ranked
        .into_iter()
        .map(|(mut best, (mut r, mut t))| {
            let (mut angle, mut shift) = (8f64.to_radians(), 0.04 * height);
            for _ in 0..4 {
                let mut improved = true;
                while improved {
                    improved = false;
                    let q = place(p, &(r, t));
                    let n = usable.iter().filter(|&&u| u).count().max(1) as f64;
                    let c = (0..20)
                        .filter(|&j| usable[j])
                        .map(|j| q[j].coords)
                        .sum::<Vector3<f64>>()
                        / n;
                    let mut moves: Vec<Placement> = Vec::with_capacity(12);
                    for axis in [up, left, facing] {
                        for s in [-1.0, 1.0] {
                            let d =
                                Rotation3::from_axis_angle(&Unit::new_unchecked(axis), s * angle);
                            // Turn about the centroid: x ↦ d(x − c) + c.
                            moves.push((d * r, d * t + c - d * c));
                            moves.push((r, t + axis * (s * shift)));
                        }
                    }
                    for m in moves {
                        let f = objective(fm, &place(p, &m), usable, height);
                        if f < best - 1e-9 {
                            (best, r, t) = (f, m.0, m.1);
                            improved = true;
                        }
                    }
                }
                angle *= 0.5;
                shift *= 0.5;
            }
            (best, (r, t))
        })
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out.into_iter().map(|(_, c)| c).collect()
}

/// The candidate placements of the rotation search: rotations about the skeleton's up axis
/// through the joints' centroid by every 30°, upright and upside down (a half turn about the
/// left axis), each kept in place and moved onto the mesh's centroid. The identity comes
/// first.
fn candidates(p: &Joints, usable: &[bool; 20], mesh_centroid: &Point3<f64>) -> Vec<Placement> {
    let Some([up, left, _]) = torso_frame(p, usable) else {
        return Vec::new();
    };
    let n = usable.iter().filter(|&&u| u).count().max(1) as f64;
    let cj = Point3::from(
        (0..20)
            .filter(|&j| usable[j])
            .map(|j| p[j].coords)
            .sum::<Vector3<f64>>()
            / n,
    );
    let mut out = Vec::with_capacity(48);
    for flip in [false, true] {
        let f = if flip {
            Rotation3::from_axis_angle(&Unit::new_unchecked(left), std::f64::consts::PI)
        } else {
            Rotation3::identity()
        };
        for k in 0..12 {
            let r = Rotation3::from_axis_angle(
                &Unit::new_unchecked(up),
                k as f64 * std::f64::consts::PI / 6.0,
            ) * f;
            // x ↦ r (x − cj) + cj (+ shift onto the mesh's centroid).
            let t = cj.coords - r * cj.coords;
            out.push((r, t));
            out.push((r, t + (mesh_centroid - cj)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::{attach, AttachError, AttachOptions, FitCheckKind, Joint, PoorFitPolicy};
    use nalgebra::{Point3, Vector3};
    use symcorr_mesh::TriMesh;

    #[test]
    fn a_good_skeleton_passes_every_check() {
        let (mesh, sk) = crate::doc_example();
        let a = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
        let fit = &a.diagnostics.fit;
        assert!(fit.passed() && fit.score >= super::FIT_THRESHOLD, "{fit:?}");
        assert!(fit.unreached.is_empty());
        assert!(fit.check(FitCheckKind::SurfaceDistance).is_some());
    }

    #[test]
    fn a_component_no_bone_reaches_is_listed_and_the_rest_is_labelled() {
        let (body, sk) = crate::doc_example();
        let ico = symcorr_mesh::testmesh::icosahedron();
        let n = body.num_vertices() as u32;
        let mut positions = body.positions.clone();
        positions.extend(
            ico.positions
                .iter()
                .map(|p| [p[0] * 0.1 + 3.0, p[1] * 0.1, p[2] * 0.1]),
        );
        let mut triangles = body.triangles.clone();
        triangles.extend(ico.triangles.iter().map(|t| t.map(|v| v + n)));
        let mesh = TriMesh::new(positions, triangles).unwrap();
        let a = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
        let want: Vec<u32> = (n..n + ico.num_vertices() as u32).collect();
        assert_eq!(a.diagnostics.fit.unreached, want);
    }

    #[test]
    fn a_mesh_of_two_bodies_is_named_as_the_likely_cause() {
        // The body twice, side by side: one skeleton covers half of it. The message asks about
        // the mesh, not (only) the joints.
        let (mesh, sk) = crate::doc_example();
        let n = mesh.positions.len() as u32;
        let mut positions = mesh.positions.clone();
        positions.extend(mesh.positions.iter().map(|p| [p[0] + 1.5, p[1], p[2]]));
        let mut triangles = mesh.triangles.clone();
        triangles.extend(mesh.triangles.iter().map(|t| t.map(|v| v + n)));
        let two = TriMesh::new(positions, triangles).unwrap();
        let e = attach(&two, &sk, &AttachOptions::default()).unwrap_err();
        let m = e.to_string();
        assert!(
            matches!(e, AttachError::PoorFit { two_large_parts: Some((a, b)), .. } if a == b),
            "{m}"
        );
        assert!(m.contains("does it hold more than one body?"), "{m}");
        // One body: the question is about the joints.
        let mut far = sk.clone();
        for p in far.positions.iter_mut() {
            p.x += 0.12;
        }
        let refuse = AttachOptions {
            align: false,
            ..AttachOptions::default()
        };
        let m = attach(&mesh, &far, &refuse).unwrap_err().to_string();
        assert!(m.contains("are the joints from another frame"), "{m}");
        assert!(!m.contains("more than one body"), "{m}");
    }

    #[test]
    fn a_skeleton_beside_the_body_is_refused_naming_the_check_or_accepted_when_asked() {
        let (mesh, mut sk) = crate::doc_example();
        // A hand's breadth to the side, with the alignment (and its search) off.
        for p in sk.positions.iter_mut() {
            p.x += 0.12;
        }
        let refuse = AttachOptions {
            align: false,
            ..AttachOptions::default()
        };
        match attach(&mesh, &sk, &refuse) {
            Err(AttachError::PoorFit {
                check,
                value,
                limit,
                ..
            }) => {
                assert!(value > limit, "{check} {value} {limit}");
                assert!(!e_has_newline(check));
            }
            other => panic!("expected PoorFit, got {other:?}"),
        }
        let accept = AttachOptions {
            poor_fit: PoorFitPolicy::Accept,
            ..refuse
        };
        let a = attach(&mesh, &sk, &accept).unwrap();
        assert!(a.diagnostics.fit.accepted_poor_fit && !a.diagnostics.fit.passed());
    }

    /// The capsule body 2.5 m in front of a camera at the origin, facing it, as a depth camera
    /// sees it: the triangles that face the camera, in the camera's space; and its skeleton.
    fn front_view() -> (TriMesh, crate::Skeleton) {
        let (body, mut sk) = crate::doc_example();
        let shift = Vector3::new(0.0, -1.0, -2.5);
        for p in sk.positions.iter_mut() {
            *p += shift;
        }
        let moved: Vec<Point3<f64>> = body
            .positions
            .iter()
            .map(|&p| Point3::from(p) + shift)
            .collect();
        let mut id = vec![u32::MAX; moved.len()];
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for t in &body.triangles {
            let [a, b, c] = t.map(|v| moved[v as usize]);
            if (b - a).cross(&(c - a)).dot(&(Point3::origin() - a)) <= 0.0 {
                continue;
            }
            triangles.push(t.map(|v| {
                if id[v as usize] == u32::MAX {
                    id[v as usize] = positions.len() as u32;
                    positions.push(moved[v as usize].into());
                }
                id[v as usize]
            }));
        }
        (TriMesh::new(positions, triangles).unwrap(), sk)
    }

    #[test]
    fn a_depth_scan_has_an_outside_in_front_of_its_surface() {
        let (scan, sk) = front_view();
        assert_eq!(scan.origin_facing_side(), Some(1.0));
        let measure = AttachOptions {
            align: false,
            poor_fit: PoorFitPolicy::Accept,
            ..AttachOptions::default()
        };
        let a = attach(&scan, &sk, &measure).unwrap();
        let inside = a.diagnostics.fit.check(FitCheckKind::Outside).unwrap();
        assert!(inside.value < 0.05, "{inside:?}");
        // The arms' joints 10 cm towards the camera: the arms hover in front of the body, in
        // the space the camera saw empty, while every joint stays near the surface.
        let mut hovering = sk.clone();
        for j in [
            Joint::ShoulderLeft,
            Joint::ElbowLeft,
            Joint::WristLeft,
            Joint::HandLeft,
            Joint::ShoulderRight,
            Joint::ElbowRight,
            Joint::WristRight,
            Joint::HandRight,
        ] {
            hovering.positions[j.index()].z += 0.1;
        }
        let a = attach(&scan, &hovering, &measure).unwrap();
        let fit = &a.diagnostics.fit;
        let outside = fit.check(FitCheckKind::Outside).unwrap();
        assert!(outside.value > outside.limit, "{outside:?}");
        assert!(
            fit.check(FitCheckKind::SurfaceDistance).unwrap().passed,
            "{fit:?}"
        );
        // The same surface away from its camera has no outside to test.
        let mut elsewhere = scan.clone();
        for p in elsewhere.positions.iter_mut() {
            p[0] += 5.0;
        }
        assert_eq!(elsewhere.origin_facing_side(), None);
        // Seen from behind (the origin 2.5 m behind the body, not its camera): the surface
        // faces the origin all one way, but the joints lie in front of it.
        let mut behind = scan.clone();
        let mut sk_behind = sk.clone();
        for p in behind.positions.iter_mut() {
            p[2] = -5.0 - p[2];
        }
        for p in sk_behind.positions.iter_mut() {
            p.z = -5.0 - p.z;
        }
        assert!(behind.origin_facing_side().is_some());
        assert_eq!(crate::camera_side(&behind, &sk_behind), None);
        assert_eq!(crate::camera_side(&scan, &sk), Some(1.0));
    }

    fn e_has_newline(s: &str) -> bool {
        s.contains('\n')
    }
}
