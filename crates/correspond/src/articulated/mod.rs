//! Skeleton-driven articulated alignment: symcorr's default method, for whole bodies and
//! partial targets (single-view scans) alike (DESIGN.md, Algorithm 7).
//!
//! Intrinsic descriptors (si-HKS, Laplace–Beltrami bases, geodesic landmark coordinates) change
//! wholesale when half of the surface is missing: a single-view scan has a long boundary, holes
//! at every occlusion, and geodesics that run around them. The skeleton does not: both meshes
//! come with their joints in their own frames. [`articulated_match`] therefore works
//! *extrinsically* (lengths in √area units, see [`ArticulatedOptions`]):
//!
//! 1. **Pools and trees.** Each template segment's pool is the target region of that segment
//!    and of its skeleton neighbours ([`SegmentPools::with_adjacent`]), grown by a geodesic band
//!    ([`ArticulatedOptions::band`]) and never on the other side of the body; no sagittal
//!    halves. One exact k-d tree per pool over position ⊕ β·normal (6-D, β =
//!    [`ArticulatedOptions::normal_weight`]) answers every nearest-neighbour query below.
//! 2. **Pose the template** onto the target's skeleton by linear blend skinning with the
//!    template's bone-heat weights ([`bone_transforms`]: the pelvis and the chest get full frames
//!    from the hips and shoulders, every other bone the smallest rotation taking its direction
//!    onto the target's, composed down the kinematic chain; [`skin`]).
//! 3. **Head twist search.** The joints fix a bone's direction, not its roll, and a roughly
//!    round head can sit in a wrong roll that ICP does not leave: the head bone is started at
//!    each of [`TWISTS`] about the target's neck → head axis, refined by a few rigid ICP steps on
//!    at most 600 of its vertices, and the start with the lowest truncated residual wins.
//! 4. **Articulated ICP** ([`ArticulatedOptions::iterations`] rounds, on an even stride sample
//!    of at most [`ArticulatedOptions::icp_points`] template vertices): every sampled vertex is
//!    paired with its nearest pool vertex; a pair holds when it is within the round's gate
//!    (shrinking geometrically from [`ArticulatedOptions::gate_start`] to
//!    [`ArticulatedOptions::gate_end`]), its normals agree
//!    ([`ArticulatedOptions::min_normal_cosine`]: the template's back has no counterpart on a
//!    front view) and its target point is not on the target's border beyond
//!    [`ArticulatedOptions::boundary_gate`]. Each bone with at least 20 pairs of weight > 0.1 is
//!    re-fitted by weighted Kabsch (Arun et al. 1987) to them plus its two joints as anchors
//!    ([`ArticulatedOptions::joint_anchor`]), then the template is re-skinned.
//! 5. **Non-rigid step** (needs the template's edge graph, [`ArticulatedSide::neighbors`]):
//!    what rigid bones blended by skinning weights cannot express (another rig's skinning, soft
//!    tissue, body shape) is pulled in by a smooth displacement field — the held pairs' offsets
//!    spread over the edge graph by Jacobi iterations of
//!    `min Σ r_v|s_v − d_v|² + λ Σ_edges |s_u − s_v|²` — over
//!    [`ArticulatedOptions::nonrigid_rounds`] rounds whose gates run coarse to fine from
//!    [`ArticulatedOptions::nonrigid_gate_start`] to `gate_end`.
//! 6. **Map**: every template vertex takes the nearest target vertex of its pool; it *has a
//!    counterpart* when that pair holds at the final gate; confidence `1/(1 + d/gate)`.
//!
//! Left and right never mix: the pools are the skeleton filter (§3.2) as a hard constraint.
//! Measured: `docs/decisions/2026-11-23-articulated-alignment.md`,
//! `docs/decisions/2026-11-23-articulated-nonrigid-step.md`,
//! `docs/decisions/2026-12-01-articulated-adjacent-pools.md`,
//! `docs/decisions/2026-12-01-articulated-kdtrees.md`.

use crate::kdtree::PoolTrees;
use crate::{CorrespondError, SegmentPools};
use faer::Mat;
use rayon::prelude::*;
use symcorr_attach::BoneWeights;
use symcorr_mesh::geometry::{
    add, closest_on_segment, cross, dot, mat_vec, norm, scale, sub, unit,
};
use symcorr_skeleton::{Bone, Joint, Segment, Skeleton, BONES};

/// The nearest-neighbour features of the alignment: position ⊕ β·normal.
fn features(positions: &[[f64; 3]], normals: &[[f64; 3]], beta: f64) -> Vec<[f64; 6]> {
    positions
        .iter()
        .zip(normals)
        .map(|(&[x, y, z], &n)| {
            let [a, b, c] = scale(n, beta);
            [x, y, z, a, b, c]
        })
        .collect()
}

/// A 3×3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A rigid transform `x ↦ R·x + t` of one bone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoneTransform {
    /// Rotation `R` (row-major).
    pub rotation: Mat3,
    /// Translation `t`.
    pub translation: [f64; 3],
}

impl BoneTransform {
    /// The identity.
    pub const IDENTITY: BoneTransform = BoneTransform {
        rotation: IDENTITY,
        translation: [0.0; 3],
    };

    /// `R·x + t`.
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        add(mat_vec(&self.rotation, x), self.translation)
    }

    /// `R·n` (a direction).
    pub fn rotate(&self, n: [f64; 3]) -> [f64; 3] {
        mat_vec(&self.rotation, n)
    }
}

fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

fn transpose(a: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[j][i];
        }
    }
    out
}

/// The orthonormal frame (as the columns of a matrix) with first axis along `x` and second
/// axis in the plane of `x` and `y`; `None` when they are (nearly) parallel.
fn frame(x: [f64; 3], y: [f64; 3]) -> Option<Mat3> {
    let e1 = unit(x)?;
    let e2 = unit(sub(y, scale(e1, dot(e1, y))))?;
    if norm(sub(y, scale(e1, dot(e1, y)))) < 1e-3 * norm(y) {
        return None;
    }
    let e3 = cross(e1, e2);
    Some([
        [e1[0], e2[0], e3[0]],
        [e1[1], e2[1], e3[1]],
        [e1[2], e2[2], e3[2]],
    ])
}

/// The smallest rotation taking unit vector `a` onto unit vector `b` (Rodrigues); the identity
/// when either is zero, a half turn about an axis normal to `a` when they are opposite.
fn swing(a: [f64; 3], b: [f64; 3]) -> Mat3 {
    let (Some(a), Some(b)) = (unit(a), unit(b)) else {
        return IDENTITY;
    };
    let c = dot(a, b);
    let v = cross(a, b);
    if c < -1.0 + 1e-9 {
        // Opposite: rotate by π about any axis normal to a.
        let helper = if a[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let Some(k) = unit(cross(a, helper)) else {
            return IDENTITY;
        };
        // R = 2kkᵀ − I.
        let mut r = [[0.0; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = 2.0 * k[i] * k[j] - if i == j { 1.0 } else { 0.0 };
            }
        }
        return r;
    }
    // R = I + [v]× + [v]×² / (1 + c).
    let vx = [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
    let vx2 = mat_mul(&vx, &vx);
    let mut r = IDENTITY;
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] += vx[i][j] + vx2[i][j] / (1.0 + c);
        }
    }
    r
}

/// One rigid transform per bone of [`BONES`] that carries the `from` skeleton's bones onto the
/// `to` skeleton's.
///
/// The pelvis bones (hip centre → spine and → each hip) share the rotation between the two
/// pelvis frames (hip line, then spine direction); the chest bones (spine → shoulder centre)
/// the rotation between the chest frames (shoulder line, then spine). Every other bone takes
/// the smallest rotation carrying its parent-rotated direction onto the target's direction,
/// composed with its parent bone's rotation (twist about a limb is not observable from the
/// joints; the ICP of [`articulated_match`] fits it, and searches the head's). Each
/// translation puts the bone's midpoint on the target bone's midpoint, splitting a length
/// difference between both ends.
///
/// ```
/// use symcorr_skeleton::Skeleton;
/// use symcorr_correspond::bone_transforms;
/// let s = symcorr_attach::testbody::t_pose(1.0);
/// let t = bone_transforms(&s, &s);
/// let x = [0.1, 0.2, 0.3];
/// for b in t {
///     let y = b.apply(x);
///     assert!((0..3).all(|i| (y[i] - x[i]).abs() < 1e-12));
/// }
/// ```
pub fn bone_transforms(from: &Skeleton, to: &Skeleton) -> [BoneTransform; 19] {
    let pf = |j: Joint| -> [f64; 3] { from.position(j).into() };
    let pt = |j: Joint| -> [f64; 3] { to.position(j).into() };
    let frame_rotation = |x: (Joint, Joint), y: (Joint, Joint)| -> Option<Mat3> {
        let f = frame(sub(pf(x.1), pf(x.0)), sub(pf(y.1), pf(y.0)))?;
        let t = frame(sub(pt(x.1), pt(x.0)), sub(pt(y.1), pt(y.0)))?;
        Some(mat_mul(&t, &transpose(&f)))
    };
    use Joint as J;
    let pelvis = frame_rotation((J::HipRight, J::HipLeft), (J::HipCenter, J::Spine))
        .unwrap_or_else(|| {
            swing(
                sub(pf(J::Spine), pf(J::HipCenter)),
                sub(pt(J::Spine), pt(J::HipCenter)),
            )
        });
    let chest = frame_rotation(
        (J::ShoulderRight, J::ShoulderLeft),
        (J::Spine, J::ShoulderCenter),
    )
    .unwrap_or(pelvis);
    let mut rotations: [Mat3; 19] = [IDENTITY; 19];
    for (b, bone) in BONES.iter().enumerate() {
        let (p, c) = (bone.parent, bone.child);
        rotations[b] = match (p, c) {
            (J::HipCenter, _) => pelvis,
            (J::Spine, J::ShoulderCenter) => chest,
            (J::ShoulderCenter, _) => {
                let d = mat_vec(&chest, sub(pf(c), pf(p)));
                mat_mul(&swing(d, sub(pt(c), pt(p))), &chest)
            }
            _ => {
                // Parent bone: the one ending at p (BONES lists parents first).
                let parent = BONES.iter().position(|pb| pb.child == p).unwrap_or(0);
                let r = rotations[parent];
                let d = mat_vec(&r, sub(pf(c), pf(p)));
                mat_mul(&swing(d, sub(pt(c), pt(p))), &r)
            }
        };
    }
    let mut out = [BoneTransform::IDENTITY; 19];
    for (b, bone) in BONES.iter().enumerate() {
        let (p, c) = (bone.parent, bone.child);
        let r = rotations[b];
        let mid_from = scale(add(pf(p), pf(c)), 0.5);
        let mid_to = scale(add(pt(p), pt(c)), 0.5);
        out[b] = BoneTransform {
            rotation: r,
            translation: sub(mid_to, mat_vec(&r, mid_from)),
        };
    }
    out
}

/// Linear blend skinning: `x'_v = Σ_b w_vb (R_b x_v + t_b)`, normals `n'_v ∝ Σ_b w_vb R_b n_v`.
///
/// `weights` has one row per vertex (bone indexes into [`BONES`]), `transforms` one entry per
/// bone. Returns the posed positions and unit normals.
pub fn skin(
    positions: &[[f64; 3]],
    normals: &[[f64; 3]],
    weights: &BoneWeights,
    transforms: &[BoneTransform; 19],
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    positions
        .par_iter()
        .zip(normals.par_iter())
        .enumerate()
        .map(|(v, (&x, &n))| {
            let (mut px, mut pn) = ([0.0; 3], [0.0; 3]);
            for &(b, w) in weights.row(v) {
                px = add(px, scale(transforms[b].apply(x), w));
                pn = add(pn, scale(transforms[b].rotate(n), w));
            }
            (px, unit(pn).unwrap_or(n))
        })
        .unzip()
}

/// A fit pair: (template rest position, target position, weight).
type Pair = ([f64; 3], [f64; 3], f64);

/// Weighted Kabsch: the rotation and translation minimising `Σ w_i |R a_i + t − b_i|²`;
/// `None` with fewer than three points of positive weight or a degenerate cross-covariance.
fn kabsch(pairs: &[Pair]) -> Option<BoneTransform> {
    let wsum: f64 = pairs.iter().map(|p| p.2).sum();
    if pairs.iter().filter(|p| p.2 > 0.0).count() < 3 || wsum <= 0.0 {
        return None;
    }
    let mut ca = [0.0; 3];
    let mut cb = [0.0; 3];
    for &(a, b, w) in pairs {
        ca = add(ca, scale(a, w / wsum));
        cb = add(cb, scale(b, w / wsum));
    }
    // H = Σ w (a − ā)(b − b̄)ᵀ.
    let mut h = Mat::<f64>::zeros(3, 3);
    for &(a, b, w) in pairs {
        let (da, db) = (sub(a, ca), sub(b, cb));
        for i in 0..3 {
            for j in 0..3 {
                h[(i, j)] += w * da[i] * db[j];
            }
        }
    }
    let svd = h.svd().ok()?;
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    if s[0].is_nan() || s[0] <= 0.0 || s[1] < 1e-9 * s[0] {
        return None;
    }
    // R = V diag(1, 1, det(V Uᵀ)) Uᵀ.
    let mut r = [[0.0; 3]; 3];
    let vu = |i: usize, j: usize, k: usize| v[(i, k)] * u[(j, k)];
    let det = {
        let mut m = [[0.0; 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..3).map(|k| vu(i, j, k)).sum();
            }
        }
        dot(m[0], cross(m[1], m[2]))
    };
    let d = [1.0, 1.0, det.signum()];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| d[k] * vu(i, j, k)).sum();
        }
    }
    if r.iter().flatten().any(|x| !x.is_finite()) {
        return None;
    }
    Some(BoneTransform {
        rotation: r,
        translation: sub(cb, mat_vec(&r, ca)),
    })
}

/// `normals` (one per vertex), all negated when most of them point *into* the body: towards
/// the bone of the vertex's segment rather than away from it. A scan's triangles may be wound
/// either way; the skeleton says which side is out. One global decision, never per vertex
/// (noisy normals near a bone would otherwise flip individually).
pub fn outward_normals(
    positions: &[[f64; 3]],
    normals: Vec<[f64; 3]>,
    labels: &[Segment],
    joints: &Skeleton,
) -> Vec<[f64; 3]> {
    let mut balance = 0.0;
    for ((&x, n), s) in positions.iter().zip(&normals).zip(labels) {
        let Some(bone) = s.bones().first() else {
            continue;
        };
        let (on_bone, _) = closest_on_segment(
            x,
            joints.position(bone.parent).into(),
            joints.position(bone.child).into(),
        );
        let out = sub(x, on_bone);
        balance += dot(*n, out).signum();
    }
    if balance < 0.0 {
        normals.into_iter().map(|n| scale(n, -1.0)).collect()
    } else {
        normals
    }
}

/// What [`articulated_match`] needs about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct ArticulatedSide<'a> {
    /// Vertex positions.
    pub positions: &'a [[f64; 3]],
    /// Unit vertex normals, pointing out of the body (for a scan: towards the camera).
    pub normals: &'a [[f64; 3]],
    /// Segment label per vertex.
    pub labels: &'a [Segment],
    /// The skeleton (refined joints) in this mesh's frame.
    pub joints: &'a Skeleton,
    /// Per vertex: on the mesh's boundary? (`None`: a closed surface.) Used on the target side.
    pub boundary: Option<&'a [bool]>,
    /// The mesh's vertex neighbours (edge graph); on the template side they carry the
    /// non-rigid step (`None`: no non-rigid step).
    pub neighbors: Option<&'a [Vec<u32>]>,
    /// Total surface area.
    pub area: f64,
}

/// Options of [`articulated_match`]; lengths in units of the template's √area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArticulatedOptions {
    /// ICP iterations.
    pub iterations: usize,
    /// Pair-rejection distance of the first iteration.
    pub gate_start: f64,
    /// Pair-rejection distance of the last iteration and of the final counterpart test.
    pub gate_end: f64,
    /// Weight of the normal difference next to the position in the nearest-neighbour search
    /// (`|x − y|² + (β·|n_x − n_y|)²`, β in √area).
    pub normal_weight: f64,
    /// Minimum cosine between a pair's normals.
    pub min_normal_cosine: f64,
    /// Weight of each joint anchor in a bone's fit, relative to the bone's total vertex weight.
    pub joint_anchor: f64,
    /// Geodesic band of the target pools (see [`SegmentPools::new`]), in the target's √area.
    pub band: f64,
    /// At most this many template vertices (an even stride sample) drive the ICP fits.
    pub icp_points: usize,
    /// A pair whose target point lies on the target's boundary is rejected (and the template
    /// point has no counterpart) when longer than this.
    pub boundary_gate: f64,
    /// Rounds of the non-rigid step after the ICP (0: none).
    pub nonrigid_rounds: usize,
    /// Pair-rejection distance of the first non-rigid round; the rounds' gates shrink
    /// geometrically to [`ArticulatedOptions::gate_end`].
    pub nonrigid_gate_start: f64,
    /// Smoothness weight λ of the non-rigid displacement field (per edge, against 1 per
    /// accepted pair).
    pub nonrigid_smoothing: f64,
}

/// Jacobi iterations per round of the non-rigid step.
const NONRIGID_JACOBI: usize = 30;

impl Default for ArticulatedOptions {
    fn default() -> Self {
        ArticulatedOptions {
            iterations: 8,
            gate_start: 0.10,
            gate_end: 0.03,
            normal_weight: 0.03,
            min_normal_cosine: 0.3,
            joint_anchor: 0.1,
            band: 0.02,
            icp_points: DEFAULT_ICP_POINTS,
            boundary_gate: 0.01,
            nonrigid_rounds: 3,
            nonrigid_gate_start: 0.06,
            nonrigid_smoothing: 5.0,
        }
    }
}

/// Default [`ArticulatedOptions::icp_points`].
pub const DEFAULT_ICP_POINTS: usize = 16_000;

/// The result of [`articulated_match`].
#[derive(Debug, Clone)]
pub struct ArticulatedMatches {
    /// One pair per template vertex, in vertex order; `confidence` is `1/(1 + d/gate)` with
    /// `d` the final distance.
    pub pairs: Vec<crate::Pair>,
    /// Per template vertex, the final distance from the posed template point to its match,
    /// over √area.
    pub distance: Vec<f64>,
    /// Per template vertex: does the target show it (within the final gate, same facing)?
    pub has_counterpart: Vec<bool>,
    /// The template posed onto the target (the final skinning).
    pub posed: Vec<[f64; 3]>,
    /// The final bone transforms (template frame → target frame).
    pub transforms: [BoneTransform; 19],
    /// Seconds per stage: `segment_pools`, `articulated_icp` (with the k-d trees and the head's
    /// twist search), `nonrigid`, `map`.
    pub timings: Vec<(&'static str, f64)>,
}

/// The best twist of bone `b` about its target axis: the skeleton gives a bone's direction,
/// not its roll, and a roughly round part (the head on its neck) can sit in a wrong roll that
/// nearest-neighbour ICP does not leave. Starting from `initial` turned by each of
/// [`TWISTS`] about the target bone, a few rigid ICP steps on the vertices mostly on the bone,
/// scored by the mean truncated squared distance to their nearest pool vertices; the best
/// start wins.
#[allow(clippy::too_many_arguments)]
fn twist_search(
    b: usize,
    initial: BoneTransform,
    template: &ArticulatedSide<'_>,
    weights: &BoneWeights,
    target: &ArticulatedSide<'_>,
    pools: &SegmentPools,
    trees: &PoolTrees,
    beta: f64,
    options: &ArticulatedOptions,
) -> Result<BoneTransform, CorrespondError> {
    let n = template.positions.len();
    let mostly_on_bone: Vec<bool> = (0..n)
        .map(|v| weights.row(v).iter().any(|&(bb, w)| bb == b && w > 0.5))
        .collect();
    // An even sample of at most TWIST_POINTS of them: enough to score a rigid pose.
    let stride = mostly_on_bone
        .iter()
        .filter(|&&x| x)
        .count()
        .div_ceil(TWIST_POINTS)
        .max(1);
    let mut seen = 0usize;
    let on_bone: Vec<bool> = mostly_on_bone
        .iter()
        .map(|&x| {
            if !x {
                return false;
            }
            seen += 1;
            (seen - 1).is_multiple_of(stride)
        })
        .collect();
    let subset = pools.members_where(|v| on_bone[v as usize]);
    let count = on_bone.iter().filter(|&&x| x).count();
    if count < 20 {
        return Ok(initial);
    }
    let (p, c) = (BONES[b].parent, BONES[b].child);
    let pivot: [f64; 3] = target.joints.position(p).into();
    let Some(axis) = unit(sub(target.joints.position(c).into(), pivot)) else {
        return Ok(initial);
    };
    let gate = options.gate_start * template.area.sqrt();
    let fit = |start: BoneTransform| -> Result<(BoneTransform, f64), CorrespondError> {
        let mut tr = start;
        let mut score = f64::INFINITY;
        for step in 0..=TWIST_ICP_STEPS {
            let f: Vec<[f64; 6]> = (0..n)
                .map(|i| {
                    if !on_bone[i] {
                        return [0.0; 6];
                    }
                    let [x, y, z] = tr.apply(template.positions[i]);
                    let [a, b, c] = scale(tr.rotate(template.normals[i]), beta);
                    [x, y, z, a, b, c]
                })
                .collect();
            let near = trees.nearest(pools, &f, Some(&subset))?;
            let mut pairs = Vec::new();
            let mut total = 0.0;
            for v in (0..n).filter(|&v| on_bone[v]) {
                let x = tr.apply(template.positions[v]);
                let y = target.positions[near[v].0 as usize];
                let d = norm(sub(x, y));
                // Scored in the search's own metric (position and normal).
                total += near[v].1.min(gate * gate);
                if d <= gate {
                    pairs.push((template.positions[v], y, 1.0));
                }
            }
            score = total / count as f64;
            if step == TWIST_ICP_STEPS {
                break;
            }
            let anchor = options.joint_anchor * pairs.len() as f64;
            for j in [p, c] {
                pairs.push((
                    template.joints.position(j).into(),
                    target.joints.position(j).into(),
                    anchor,
                ));
            }
            match kabsch(&pairs) {
                Some(t) => tr = t,
                None => break,
            }
        }
        Ok((tr, score))
    };
    let mut best = fit(initial)?;
    for &deg in TWISTS.iter().filter(|&&d| d != 0.0) {
        let r = axis_angle(axis, deg.to_radians());
        let turned = BoneTransform {
            rotation: mat_mul(&r, &initial.rotation),
            translation: add(mat_vec(&r, sub(initial.translation, pivot)), pivot),
        };
        let candidate = fit(turned)?;
        if candidate.1 < best.1 {
            best = candidate;
        }
    }
    Ok(best.0)
}

/// Starting twists of the head twist search of [`articulated_match`], in degrees: within a
/// head's range of rotation against the chest (about ±80°; the starting pose is the chest's).
/// Wider starts let a head whose back fits about as well as its face turn round: with
/// σ = 3 cm joints, ±180° flipped whole heads in 13 of 58 pairs.
pub const TWISTS: [f64; 7] = [0.0, 30.0, 60.0, 90.0, -30.0, -60.0, -90.0];
/// At most this many vertices of the bone score each start of [`twist_search`].
const TWIST_POINTS: usize = 600;
/// Rigid ICP steps per start of [`twist_search`].
const TWIST_ICP_STEPS: usize = 4;

/// The rotation by `angle` about unit `axis` (Rodrigues).
fn axis_angle(axis: [f64; 3], angle: f64) -> Mat3 {
    let (s, c) = angle.sin_cos();
    let [x, y, z] = axis;
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// Matches every template vertex onto a (possibly partial) target by skeleton-driven
/// articulated alignment (see the module docs). `weights` are the template's bone weights;
/// `graph` is the target's edge graph (pool bands).
///
/// Errors: [`CorrespondError::InvalidArgument`] when the tables of a side disagree in length
/// or a mesh is empty.
pub fn articulated_match(
    template: &ArticulatedSide<'_>,
    weights: &BoneWeights,
    target: &ArticulatedSide<'_>,
    graph: &symcorr_spectral::EdgeGraph,
    options: &ArticulatedOptions,
) -> Result<ArticulatedMatches, CorrespondError> {
    use std::time::Instant;
    let (n, m) = (template.positions.len(), target.positions.len());
    for (name, s, len) in [("template", template, n), ("target", target, m)] {
        if len == 0
            || s.normals.len() != len
            || s.labels.len() != len
            || s.boundary.is_some_and(|b| b.len() != len)
        {
            return Err(CorrespondError::InvalidArgument(format!(
                "{name}: {len} positions, {} normals, {} labels",
                s.normals.len(),
                s.labels.len()
            )));
        }
    }
    if weights.len() != n {
        return Err(CorrespondError::InvalidArgument(format!(
            "template: {n} vertices but {} weight rows",
            weights.len()
        )));
    }
    let unit_len = template.area.sqrt();
    // A template point whose nearest target point is on the target's border, and not right at
    // it, lies beyond what the target shows (the standard rejection of partial ICP).
    let boundary_gate = options.boundary_gate * unit_len;
    let on_boundary = |q: u32| target.boundary.is_some_and(|b| b[q as usize]);
    // Does the pair (posed template point, its normal) → target vertex q hold at this gate?
    // Close enough, facing the same way, and not hanging over the target's border.
    let holds = |x: [f64; 3], n: [f64; 3], q: u32, gate: f64| -> bool {
        let d = norm(sub(x, target.positions[q as usize]));
        d <= gate
            && dot(n, target.normals[q as usize]) >= options.min_normal_cosine
            && !(on_boundary(q) && d > boundary_gate)
    };
    let mut timings = Vec::new();
    let t = Instant::now();
    // No sagittal halves on the midline segments: the alignment already puts each side on its
    // side, and a symmetry plane fitted to a turned head is often off by tens of degrees.
    // Adjacent segments join each pool: a label boundary that moved between the meshes (a
    // neck the target's attachment gave to a clavicle) no longer cuts the true vertex out of
    // the pool. Measured: docs/decisions/2026-11-23-articulated-alignment.md and
    // docs/decisions/2026-12-01-articulated-adjacent-pools.md.
    let pools = SegmentPools::with_adjacent(
        (template.labels, None),
        (target.labels, None),
        graph,
        options.band * target.area.sqrt(),
    )?;
    timings.push(("segment_pools", t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let beta = options.normal_weight * unit_len;
    let trees = PoolTrees::new(&pools, &features(target.positions, target.normals, beta))?;
    // The ICP fits use an even stride sample of at most `icp_points` template vertices (a
    // bone's rigid fit needs hundreds of pairs, not tens of thousands); the final map uses all.
    let stride = n.div_ceil(options.icp_points.max(1)).max(1);
    let sample = pools.members_where(|v| (v as usize).is_multiple_of(stride));
    let nearest = |posed: &[[f64; 3]], pn: &[[f64; 3]], subset: Option<&[Vec<u32>]>| {
        trees.nearest(&pools, &features(posed, pn, beta), subset)
    };
    let mut transforms = bone_transforms(template.joints, target.joints);
    let head_bone = BONES
        .iter()
        .position(|&b| b == Bone::new(Joint::ShoulderCenter, Joint::Head))
        .unwrap_or(2);
    transforms[head_bone] = twist_search(
        head_bone,
        transforms[head_bone],
        template,
        weights,
        target,
        &pools,
        &trees,
        beta,
        options,
    )?;
    let (mut posed, mut posed_normals) =
        skin(template.positions, template.normals, weights, &transforms);
    let iterations = options.iterations.max(1);
    for it in 0..iterations {
        let frac = if iterations > 1 {
            it as f64 / (iterations - 1) as f64
        } else {
            1.0
        };
        let gate =
            unit_len * (options.gate_start * (options.gate_end / options.gate_start).powf(frac));
        let near = nearest(&posed, &posed_normals, Some(&sample))?;
        // Pairs per bone: (rest position, target position, weight).
        let mut per_bone: Vec<Vec<Pair>> = vec![Vec::new(); 19];
        for (v, &(q, d2)) in near.iter().enumerate() {
            if !d2.is_finite() {
                continue; // not in the sample
            }
            if !holds(posed[v], posed_normals[v], q, gate) {
                continue;
            }
            let y = target.positions[q as usize];
            for &(b, w) in weights.row(v) {
                if w > 0.1 {
                    per_bone[b].push((template.positions[v], y, w));
                }
            }
        }
        transforms
            .par_iter_mut()
            .zip(per_bone.into_par_iter())
            .enumerate()
            .for_each(|(b, (tr, mut pairs))| {
                if pairs.len() < 20 {
                    return;
                }
                let wsum: f64 = pairs.iter().map(|p| p.2).sum();
                let (p, c) = (BONES[b].parent, BONES[b].child);
                // The skeleton anchors the fit: both joints, carried by the previous transform
                // of the bone, pulled to the target's joints.
                let anchor = options.joint_anchor * wsum;
                for j in [p, c] {
                    pairs.push((
                        template.joints.position(j).into(),
                        target.joints.position(j).into(),
                        anchor,
                    ));
                }
                if let Some(fit) = kabsch(&pairs) {
                    *tr = fit;
                }
            });
        (posed, posed_normals) = skin(template.positions, template.normals, weights, &transforms);
    }
    timings.push(("articulated_icp", t.elapsed().as_secs_f64()));

    // Non-rigid step: what rigid bones blended by bone-heat weights cannot express (another
    // rig's skinning, soft tissue, body shape) is pulled in by a smooth displacement field:
    // each accepted pair's offset to its target point, spread over the template's edge graph
    // (Jacobi iterations of min Σ r_v|s_v − d_v|² + λ Σ_edges |s_u − s_v|²).
    let t = Instant::now();
    let gate = options.gate_end * unit_len;
    if let Some(nb) = template.neighbors.filter(|nb| nb.len() == n) {
        let rounds = options.nonrigid_rounds;
        let g0 = options.nonrigid_gate_start.max(options.gate_end);
        for round in 0..rounds {
            // Coarse to fine, like the ICP's gates: a body part further off than the final
            // gate (a heavier shape's belly) is pulled in by the early rounds.
            let frac = if rounds > 1 {
                round as f64 / (rounds - 1) as f64
            } else {
                1.0
            };
            let round_gate = unit_len * g0 * (options.gate_end / g0).powf(frac);
            let near = nearest(&posed, &posed_normals, None)?;
            let mut d = vec![[0.0; 3]; n];
            let mut r = vec![0.0; n];
            for (v, &(q, _)) in near.iter().enumerate() {
                if holds(posed[v], posed_normals[v], q, round_gate) {
                    d[v] = sub(target.positions[q as usize], posed[v]);
                    r[v] = 1.0;
                }
            }
            let lambda = options.nonrigid_smoothing;
            let mut field = d.clone();
            for _ in 0..NONRIGID_JACOBI {
                field = (0..n)
                    .into_par_iter()
                    .map(|v| {
                        let mut acc = scale(d[v], r[v]);
                        for &u in &nb[v] {
                            acc = add(acc, scale(field[u as usize], lambda));
                        }
                        let wsum = r[v] + lambda * nb[v].len() as f64;
                        if wsum > 0.0 {
                            scale(acc, 1.0 / wsum)
                        } else {
                            [0.0; 3]
                        }
                    })
                    .collect();
            }
            for (x, f) in posed.iter_mut().zip(&field) {
                *x = add(*x, *f);
            }
        }
    }
    timings.push(("nonrigid", t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let near = nearest(&posed, &posed_normals, None)?;
    let mut has_counterpart = Vec::with_capacity(n);
    let mut distance = Vec::with_capacity(n);
    let pairs = near
        .iter()
        .enumerate()
        .map(|(v, &(q, _))| {
            let d = norm(sub(posed[v], target.positions[q as usize]));
            let seen = holds(posed[v], posed_normals[v], q, gate);
            has_counterpart.push(seen);
            distance.push(d / unit_len);
            crate::Pair {
                template: v as u32,
                target: q,
                confidence: 1.0 / (1.0 + d / gate),
            }
        })
        .collect();
    timings.push(("map", t.elapsed().as_secs_f64()));
    Ok(ArticulatedMatches {
        pairs,
        distance,
        has_counterpart,
        posed,
        transforms,
        timings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot_z(a: f64) -> Mat3 {
        let (s, c) = a.sin_cos();
        [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    }

    #[test]
    fn swing_takes_a_onto_b() {
        for (a, b) in [
            ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([1.0, 2.0, 3.0], [-3.0, 0.5, 1.0]),
            ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]),
            ([1.0, 1.0, 0.0], [1.0, 1.0, 0.0]),
        ] {
            let r = swing(a, b);
            let ra = unit(mat_vec(&r, a)).unwrap();
            let ub = unit(b).unwrap();
            assert!(norm(sub(ra, ub)) < 1e-12, "{a:?} → {b:?}: {ra:?}");
            // Orthonormal, det +1.
            let rtr = mat_mul(&transpose(&r), &r);
            for (i, row) in rtr.iter().enumerate() {
                for (j, x) in row.iter().enumerate() {
                    let e = if i == j { 1.0 } else { 0.0 };
                    assert!((x - e).abs() < 1e-12);
                }
            }
            assert!((dot(r[0], cross(r[1], r[2])) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn kabsch_recovers_a_rigid_motion() {
        let r = mat_mul(&rot_z(0.7), &swing([0.0, 0.0, 1.0], [0.3, -0.2, 0.9]));
        let t = [0.4, -1.0, 2.5];
        let pts = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.2],
            [0.0, 1.0, -0.3],
            [0.3, 0.2, 1.0],
            [-0.5, 0.7, 0.1],
        ];
        let pairs: Vec<_> = pts
            .iter()
            .enumerate()
            .map(|(i, &a)| (a, add(mat_vec(&r, a), t), 1.0 + i as f64))
            .collect();
        let fit = kabsch(&pairs).unwrap();
        for (a, b, _) in &pairs {
            assert!(norm(sub(fit.apply(*a), *b)) < 1e-10);
        }
        // Collinear points do not determine a rotation.
        let line: Vec<_> = (0..5)
            .map(|i| ([i as f64, 0.0, 0.0], [0.0, i as f64, 0.0], 1.0))
            .collect();
        assert!(kabsch(&line).is_none());
    }

    /// A rigidly moved skeleton gives the same rigid motion for every bone.
    #[test]
    fn bone_transforms_of_a_rigid_motion_are_that_motion() {
        let s = symcorr_attach::testbody::t_pose(1.0);
        let r = mat_mul(&rot_z(-1.1), &swing([1.0, 0.0, 0.0], [0.2, 0.3, 0.9]));
        let t = [1.0, 2.0, -0.5];
        let mut moved = s.clone();
        for p in moved.positions.iter_mut() {
            *p = add(mat_vec(&r, (*p).into()), t).into();
        }
        for (b, tr) in bone_transforms(&s, &moved).iter().enumerate() {
            for x in [[0.1, 0.5, 0.0], [-0.3, 1.2, 0.2]] {
                let want = add(mat_vec(&r, x), t);
                assert!(norm(sub(tr.apply(x), want)) < 1e-9, "bone {b}");
            }
        }
    }

    /// Bending one elbow moves only the forearm's bones, and carries the wrist onto the
    /// target's wrist.
    #[test]
    fn bone_transforms_follow_a_bent_elbow() {
        let s = symcorr_attach::testbody::t_pose(1.0);
        let mut bent = s.clone();
        let elbow: [f64; 3] = s.position(Joint::ElbowLeft).into();
        let r = rot_z(0.9);
        for j in [Joint::WristLeft, Joint::HandLeft] {
            let p = s.position(j).into();
            bent.positions[j.index()] = add(elbow, mat_vec(&r, sub(p, elbow))).into();
        }
        let tr = bone_transforms(&s, &bent);
        for (b, bone) in BONES.iter().enumerate() {
            for j in [bone.parent, bone.child] {
                let got = tr[b].apply(s.position(j).into());
                assert!(
                    norm(sub(got, bent.position(j).into())) < 1e-9,
                    "bone {b} joint {j:?}"
                );
            }
        }
    }
}
