//! Rigid bone transforms: the initial pose of every bone from the two skeletons
//! ([`bone_transforms`]), linear blend skinning ([`skin`]), the weighted rigid fit of the ICP
//! ([`kabsch`], Arun et al. 1987) and the global orientation of a scan's normals
//! ([`outward_normals`]).

use nalgebra::{IsometryMatrix3, Matrix3, Point3, Rotation3, Translation3, Vector3};
use rayon::prelude::*;
use symcorr_attach::BoneWeights;
use symcorr_skeleton::{Bone, Joint, Segment, Skeleton, BONES};

/// One rigid transform `x ↦ R·x + t` per bone of [`BONES`] (rotation kept as a matrix: the
/// fits produce matrices, and a quaternion round trip would change their rounding).
pub type BoneTransforms = [IsometryMatrix3<f64>; Bone::COUNT];

/// `a` scaled to unit length, or `None` if it is (numerically) zero or not finite. Multiplies
/// by the reciprocal norm (not `normalize`'s division) so that results keep their rounding.
pub(crate) fn unit(a: Vector3<f64>) -> Option<Vector3<f64>> {
    let l = a.norm();
    (l > 1e-12 && l.is_finite()).then(|| a * (1.0 / l))
}

/// The rigid transform with rotation matrix `r` and translation `t`.
pub(crate) fn isometry(r: Matrix3<f64>, t: Vector3<f64>) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(Translation3::from(t), Rotation3::from_matrix_unchecked(r))
}

/// The orthonormal frame (as the columns of a matrix) with first axis along `x` and second
/// axis in the plane of `x` and `y`; `None` when they are (nearly) parallel.
fn frame(x: Vector3<f64>, y: Vector3<f64>) -> Option<Matrix3<f64>> {
    let e1 = unit(x)?;
    let in_plane = y - e1 * e1.dot(&y);
    let e2 = unit(in_plane)?;
    if in_plane.norm() < 1e-3 * y.norm() {
        return None;
    }
    let e3 = e1.cross(&e2);
    Some(Matrix3::from_columns(&[e1, e2, e3]))
}

/// The smallest rotation taking direction `a` onto direction `b` (Rodrigues); the identity
/// when either is zero, a half turn about an axis normal to `a` when they are opposite.
pub(crate) fn swing(a: Vector3<f64>, b: Vector3<f64>) -> Matrix3<f64> {
    let (Some(a), Some(b)) = (unit(a), unit(b)) else {
        return Matrix3::identity();
    };
    let c = a.dot(&b);
    if c < -1.0 + 1e-9 {
        // Opposite: rotate by π about any axis k normal to a, R = 2kkᵀ − I.
        let helper = if a.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let Some(k) = unit(a.cross(&helper)) else {
            return Matrix3::identity();
        };
        return k * k.transpose() * 2.0 - Matrix3::identity();
    }
    // R = I + [v]× + [v]×² / (1 + c), v = a × b.
    let vx = a.cross(&b).cross_matrix();
    let vx2 = vx * vx;
    Matrix3::identity() + (vx + vx2 / (1.0 + c))
}

/// One rigid transform per bone of [`BONES`] that carries the `from` skeleton's bones onto the
/// `to` skeleton's.
///
/// The pelvis bones (hip centre → spine and → each hip) share the rotation between the two
/// pelvis frames (hip line, then spine direction); the chest bones (spine → shoulder centre)
/// the rotation between the chest frames (shoulder line, then spine). Every other bone takes
/// the smallest rotation carrying its parent-rotated direction onto the target's direction,
/// composed with its parent bone's rotation. Twist about a limb shows in the joints only where
/// a hinge bends: the upper arm and the thigh are then turned about their target direction so
/// that the plane of the elbow's (knee's) bend falls on the target's, in full from a bend of
/// 30° in both skeletons, not at all below 15° (a tracker's noise turns a flatter plane at
/// will); the forearm and shin follow. The ICP of
/// [`articulated_match`](crate::articulated_match) fits the rest of every twist, and searches
/// the head's. Each translation puts the bone's midpoint on the target bone's midpoint,
/// splitting a length difference between both ends.
///
/// ```
/// use nalgebra::Point3;
/// use symcorr_correspond::bone_transforms;
/// let s = symcorr_attach::testbody::t_pose(1.0);
/// let x = Point3::new(0.1, 0.2, 0.3);
/// for b in bone_transforms(&s, &s) {
///     assert!((b * x - x).norm() < 1e-12);
/// }
/// ```
pub fn bone_transforms(from: &Skeleton, to: &Skeleton) -> BoneTransforms {
    limb_transforms(from, to, LimbTwist::Hinge)
}

/// `target` with every joint it does not track ([`Skeleton::tracks`]: one the attachment could
/// not rebuild and parked at the hip centre) placed where the last tracked bone above it carries
/// the template's joint ([`bone_motion`]: each bone by its smallest rotation down the chain, so
/// that no hinge's bend plane reads a lost joint; the torso's bone for a hip or a shoulder): the
/// lost part of the limb follows it rigidly in the template's pose, instead of every bone below
/// it being posed onto the hip centre. The placed joints stay untracked, so the fit takes no anchor
/// at them and their bones are fitted by their pairs alone. `None` when `target` tracks every
/// joint.
pub(crate) fn complete_untracked(template: &Skeleton, target: &Skeleton) -> Option<Skeleton> {
    if Joint::ALL.iter().all(|&j| target.tracks(j)) {
        return None;
    }
    let transforms = bone_motion(template, target);
    let bone_index = |child: Joint| BONES.iter().position(|b| b.child == child);
    let mut out = target.clone();
    // The transform that carries each placed joint (BONES lists parents before children).
    let mut carrier: [Option<IsometryMatrix3<f64>>; Joint::COUNT] = [None; Joint::COUNT];
    for bone in BONES {
        let (p, c) = (bone.parent, bone.child);
        if target.tracks(c) {
            continue;
        }
        let t = match carrier[p.index()] {
            Some(t) => t,
            None => {
                // The bone ending at the tracked parent, when its own parent is tracked too;
                // else (the hip centre, or a parent bone half lost) the torso's bone.
                let up = bone_index(p).filter(|&b| target.tracks(BONES[b].parent));
                transforms[up.unwrap_or(0)]
            }
        };
        carrier[c.index()] = Some(t);
        out.positions[c.index()] = t * template.position(c);
    }
    Some(out)
}

/// [`bone_transforms`] with every limb bone turned by its smallest rotation alone: how the
/// bones of a fit move from one frame of a recording to the next. The fit already holds each
/// limb's twist, refined by its ICP; the change of a bend plane between two frames' joints is
/// mostly the tracker's noise (with it, a 160×240 recording's mean error rose 0.0207 → 0.0218,
/// `docs/decisions/2026-12-05-limb-hinge-twist.md`).
pub(crate) fn bone_motion(from: &Skeleton, to: &Skeleton) -> BoneTransforms {
    limb_transforms(from, to, LimbTwist::Swing)
}

/// How [`limb_transforms`] turns the upper arm and the thigh about their direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LimbTwist {
    /// By the bend plane of a bent elbow or knee ([`hinge_twist`]).
    Hinge,
    /// Not at all: the smallest rotation.
    Swing,
}

/// [`bone_transforms`] and [`bone_motion`].
fn limb_transforms(from: &Skeleton, to: &Skeleton, twist: LimbTwist) -> BoneTransforms {
    let (pf, pt) = (|j| from.position(j), |j| to.position(j));
    let frame_rotation = |x: (Joint, Joint), y: (Joint, Joint)| -> Option<Matrix3<f64>> {
        let f = frame(pf(x.1) - pf(x.0), pf(y.1) - pf(y.0))?;
        let t = frame(pt(x.1) - pt(x.0), pt(y.1) - pt(y.0))?;
        Some(t * f.transpose())
    };
    use Joint as J;
    let pelvis = frame_rotation((J::HipRight, J::HipLeft), (J::HipCenter, J::Spine))
        .unwrap_or_else(|| {
            swing(
                pf(J::Spine) - pf(J::HipCenter),
                pt(J::Spine) - pt(J::HipCenter),
            )
        });
    let chest = frame_rotation(
        (J::ShoulderRight, J::ShoulderLeft),
        (J::Spine, J::ShoulderCenter),
    )
    .unwrap_or(pelvis);
    let mut rotations = [Matrix3::identity(); Bone::COUNT];
    for (b, bone) in BONES.iter().enumerate() {
        let (p, c) = (bone.parent, bone.child);
        rotations[b] = match (p, c) {
            (J::HipCenter, _) => pelvis,
            (J::Spine, J::ShoulderCenter) => chest,
            (J::ShoulderCenter, _) => {
                let d = chest * (pf(c) - pf(p));
                swing(d, pt(c) - pt(p)) * chest
            }
            _ => {
                // Parent bone: the one ending at p (BONES lists parents first).
                let parent = BONES.iter().position(|pb| pb.child == p).unwrap_or(0);
                let r = rotations[parent];
                let d = r * (pf(c) - pf(p));
                let swung = swing(d, pt(c) - pt(p)) * r;
                match hinge_below(c).filter(|_| twist == LimbTwist::Hinge) {
                    Some(g) => {
                        hinge_twist(&swung, [pf(p), pf(c), pf(g)], [pt(p), pt(c), pt(g)]) * swung
                    }
                    None => swung,
                }
            }
        };
    }
    let mut out = [IsometryMatrix3::identity(); Bone::COUNT];
    for (b, bone) in BONES.iter().enumerate() {
        let (p, c) = (bone.parent, bone.child);
        let r = rotations[b];
        let mid_from = (pf(p).coords + pf(c).coords) * 0.5;
        let mid_to = (pt(p).coords + pt(c).coords) * 0.5;
        out[b] = isometry(r, mid_to - r * mid_from);
    }
    out
}

/// The joint past hinge joint `c` (elbow → wrist, knee → ankle); `None` for any other joint.
fn hinge_below(c: Joint) -> Option<Joint> {
    match c {
        Joint::ElbowLeft => Some(Joint::WristLeft),
        Joint::ElbowRight => Some(Joint::WristRight),
        Joint::KneeLeft => Some(Joint::AnkleLeft),
        Joint::KneeRight => Some(Joint::AnkleRight),
        _ => None,
    }
}

/// Bend (degrees) below which a limb's bend plane says nothing of its twist, and from which on
/// it says all: a tracker's 2–3 cm joint noise turns a 30–40 cm limb segment by 4–6°, so the
/// plane of a limb bent by less than ~15° is noise.
const HINGE_BEND_DEG: (f64, f64) = (15.0, 30.0);

/// The twist about the target upper limb (`to[0]` → `to[1]`) that carries the bend plane of the
/// `from` limb (`from`: root, hinge joint, end), as rotated by `swung`, onto the `to` limb's.
/// Elbow and knee are hinges: the forearm and the shin bend in a plane fixed in the upper arm
/// and the thigh, so a bent limb shows its upper segment's twist — the swivel angle of
/// inverse kinematics (Tolani, Goswami & Badler 2000). Weighted by the smaller bend of the two
/// limbs ([`HINGE_BEND_DEG`]); the identity for a straight limb.
fn hinge_twist(swung: &Matrix3<f64>, from: [Point3<f64>; 3], to: [Point3<f64>; 3]) -> Matrix3<f64> {
    let bend = |j: &[Point3<f64>; 3]| -> Option<(Vector3<f64>, f64)> {
        let (a, b) = (unit(j[1] - j[0])?, unit(j[2] - j[1])?);
        let n = a.cross(&b);
        let angle = n.norm().atan2(a.dot(&b)).to_degrees();
        Some((unit(n)?, angle))
    };
    let (Some((nf, bend_f)), Some((nt, bend_t)), Some(axis)) =
        (bend(&from), bend(&to), unit(to[1] - to[0]))
    else {
        return Matrix3::identity();
    };
    let (lo, hi) = HINGE_BEND_DEG;
    let weight = ((bend_f.min(bend_t) - lo) / (hi - lo)).clamp(0.0, 1.0);
    if weight == 0.0 {
        return Matrix3::identity();
    }
    // Both hinge axes are normal to the target upper segment up to the swing's rounding.
    let n = swung * nf;
    let (n, nt) = (n - axis * axis.dot(&n), nt - axis * axis.dot(&nt));
    let angle = axis.dot(&n.cross(&nt)).atan2(n.dot(&nt));
    *Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), weight * angle).matrix()
}

/// Linear blend skinning: `x'_v = Σ_b w_vb (R_b x_v + t_b)`, normals `n'_v ∝ Σ_b w_vb R_b n_v`.
///
/// `weights` has one row per vertex (bone indexes into [`BONES`]), `transforms` one entry per
/// bone. Returns the posed positions and unit normals.
pub fn skin(
    positions: &[[f64; 3]],
    normals: &[[f64; 3]],
    weights: &BoneWeights,
    transforms: &BoneTransforms,
) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
    positions
        .par_iter()
        .zip(normals.par_iter())
        .enumerate()
        .map(|(v, (&x, &n))| {
            let (x, n) = (Point3::from(x), Vector3::from(n));
            let (mut px, mut pn) = (Vector3::zeros(), Vector3::zeros());
            for &(b, w) in weights.row(v) {
                px += (transforms[b] * x).coords * w;
                pn += (transforms[b].rotation * n) * w;
            }
            (Point3::from(px), unit(pn).unwrap_or(n))
        })
        .unzip()
}

/// A fit pair: (template rest position, target position, weight).
pub(crate) type FitPair = (Point3<f64>, Point3<f64>, f64);

/// Weighted Kabsch (Arun, Huang, Blostein 1987): the rotation and translation minimising
/// `Σ w_i |R a_i + t − b_i|²`; `None` with fewer than three points of positive weight or a
/// degenerate cross-covariance (rank < 2).
pub(crate) fn kabsch(pairs: &[FitPair]) -> Option<IsometryMatrix3<f64>> {
    let wsum: f64 = pairs.iter().map(|p| p.2).sum();
    if pairs.iter().filter(|p| p.2 > 0.0).count() < 3 || wsum <= 0.0 {
        return None;
    }
    let (mut ca, mut cb) = (Vector3::zeros(), Vector3::zeros());
    for &(a, b, w) in pairs {
        ca += a.coords * (w / wsum);
        cb += b.coords * (w / wsum);
    }
    // H = Σ w (a − ā)(b − b̄)ᵀ.
    let mut h = Matrix3::zeros();
    for &(a, b, w) in pairs {
        h += (a.coords - ca) * w * (b.coords - cb).transpose();
    }
    // Singular values in descending order (`svd` sorts them).
    let svd = h.svd(true, true);
    let (u, v_t, s) = (svd.u?, svd.v_t?, svd.singular_values);
    if s[0].is_nan() || s[0] <= 0.0 || s[1] < 1e-9 * s[0] {
        return None;
    }
    // R = V diag(1, 1, det(V Uᵀ)) Uᵀ: a proper rotation even when the best orthogonal map is
    // a reflection (the smallest singular direction flips).
    let v = v_t.transpose();
    let det = (v * u.transpose()).determinant();
    let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, det.signum()));
    let r = v * d * u.transpose();
    if r.iter().any(|x| !x.is_finite()) {
        return None;
    }
    Some(isometry(r, cb - r * ca))
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
    for ((&x, &n), s) in positions.iter().zip(&normals).zip(labels) {
        let Some(bone) = s.bones().first() else {
            continue;
        };
        let x = Point3::from(x);
        let (a, b) = (joints.position(bone.parent), joints.position(bone.child));
        // The closest point of the bone segment a–b.
        let ab = b - a;
        let l2 = ab.dot(&ab);
        let t = if l2 > 0.0 {
            ((x - a).dot(&ab) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let out = x - (a + ab * t);
        balance += Vector3::from(n).dot(&out).signum();
    }
    if balance < 0.0 {
        normals.into_iter().map(|n| n.map(|c| -c)).collect()
    } else {
        normals
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn rot_z(a: f64) -> Matrix3<f64> {
        *Rotation3::from_axis_angle(&Vector3::z_axis(), a).matrix()
    }

    #[test]
    fn swing_takes_a_onto_b() {
        for (a, b) in [
            ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([1.0, 2.0, 3.0], [-3.0, 0.5, 1.0]),
            ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]),
            ([1.0, 1.0, 0.0], [1.0, 1.0, 0.0]),
        ] {
            let (a, b) = (Vector3::from(a), Vector3::from(b));
            let r = swing(a, b);
            assert_relative_eq!(r * a.normalize(), b.normalize(), epsilon = 1e-12);
            // Orthonormal, det +1.
            assert_relative_eq!(r.transpose() * r, Matrix3::identity(), epsilon = 1e-12);
            assert_relative_eq!(r.determinant(), 1.0, epsilon = 1e-12);
        }
    }

    /// The hand-written Kabsch this one replaced (faer's SVD, row-major arrays): kept as the
    /// reference the nalgebra version must reproduce to rounding.
    fn kabsch_reference(pairs: &[FitPair]) -> Option<([[f64; 3]; 3], [f64; 3])> {
        let wsum: f64 = pairs.iter().map(|p| p.2).sum();
        if pairs.iter().filter(|p| p.2 > 0.0).count() < 3 || wsum <= 0.0 {
            return None;
        }
        let mut ca = [0.0; 3];
        let mut cb = [0.0; 3];
        for &(a, b, w) in pairs {
            for i in 0..3 {
                ca[i] += a[i] * (w / wsum);
                cb[i] += b[i] * (w / wsum);
            }
        }
        let mut h = faer::Mat::<f64>::zeros(3, 3);
        for &(a, b, w) in pairs {
            for i in 0..3 {
                for j in 0..3 {
                    h[(i, j)] += w * (a[i] - ca[i]) * (b[j] - cb[j]);
                }
            }
        }
        let svd = h.svd().ok()?;
        let (u, s, v) = (svd.U(), svd.S(), svd.V());
        if s[0].is_nan() || s[0] <= 0.0 || s[1] < 1e-9 * s[0] {
            return None;
        }
        let vu = |i: usize, j: usize, k: usize| v[(i, k)] * u[(j, k)];
        let m = Matrix3::from_fn(|i, j| (0..3).map(|k| vu(i, j, k)).sum::<f64>());
        let d = [1.0, 1.0, m.determinant().signum()];
        let mut r = [[0.0; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..3).map(|k| d[k] * vu(i, j, k)).sum();
            }
        }
        let t = [0, 1, 2].map(|i| cb[i] - (0..3).map(|k| r[i][k] * ca[k]).sum::<f64>());
        Some((r, t))
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    /// Random pairs (noisy rigid motions, pure noise, near-reflections, planar sets): the new
    /// fit equals the reference to rounding, reflection handling included.
    #[test]
    fn kabsch_matches_the_reference_on_random_inputs() {
        let mut seed = 5u64;
        for case in 0..300 {
            let n = 3 + case % 40;
            let r = rot_z(3.0 * lcg(&mut seed))
                * swing(
                    Vector3::z(),
                    Vector3::new(lcg(&mut seed), lcg(&mut seed), 1.0),
                );
            let t = Vector3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed));
            let noise = [0.0, 0.01, 0.3, 3.0][case % 4];
            // Every 5th case mirrors the targets (the best orthogonal map is a reflection).
            let mirror = if case % 5 == 0 { -1.0 } else { 1.0 };
            let planar = case % 7 == 0;
            let pairs: Vec<FitPair> = (0..n)
                .map(|_| {
                    let z = if planar { 0.0 } else { lcg(&mut seed) };
                    let a = Point3::new(lcg(&mut seed), lcg(&mut seed), z);
                    let mut b = r * a.coords + t;
                    b.x *= mirror;
                    let e = Vector3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed));
                    (a, Point3::from(b + e * noise), 0.5 + lcg(&mut seed).abs())
                })
                .collect();
            let (got, want) = (kabsch(&pairs), kabsch_reference(&pairs));
            assert_eq!(got.is_some(), want.is_some(), "case {case}");
            if let (Some(g), Some((wr, wt))) = (got, want) {
                let wr = Matrix3::from_fn(|i, j| wr[i][j]);
                assert_relative_eq!(*g.rotation.matrix(), wr, epsilon = 1e-9);
                assert_relative_eq!(g.translation.vector, Vector3::from(wt), epsilon = 1e-9);
                assert_relative_eq!(g.rotation.matrix().determinant(), 1.0, epsilon = 1e-9);
            }
        }
    }

    #[test]
    fn kabsch_recovers_a_rigid_motion() {
        let r = rot_z(0.7) * swing(Vector3::z(), Vector3::new(0.3, -0.2, 0.9));
        let t = Vector3::new(0.4, -1.0, 2.5);
        let pts = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.2],
            [0.0, 1.0, -0.3],
            [0.3, 0.2, 1.0],
            [-0.5, 0.7, 0.1],
        ];
        let pairs: Vec<FitPair> = pts
            .iter()
            .enumerate()
            .map(|(i, &a)| {
                let a = Point3::from(a);
                (a, Point3::from(r * a.coords + t), 1.0 + i as f64)
            })
            .collect();
        let fit = kabsch(&pairs).unwrap();
        for (a, b, _) in &pairs {
            assert!((fit * a - b).norm() < 1e-10);
        }
        // Collinear points do not determine a rotation.
        let line: Vec<FitPair> = (0..5)
            .map(|i| {
                let i = i as f64;
                (Point3::new(i, 0.0, 0.0), Point3::new(0.0, i, 0.0), 1.0)
            })
            .collect();
        assert!(kabsch(&line).is_none());
    }

    /// Joints a rigidly moved skeleton lost (parked at the hip centre, as the attachment
    /// leaves them) are placed where the motion puts the template's; tracked ones stay.
    #[test]
    fn untracked_joints_follow_the_last_tracked_bone() {
        let s = symcorr_attach::testbody::t_pose(1.0);
        let r = rot_z(0.6) * swing(Vector3::x(), Vector3::new(0.1, -0.3, 0.9));
        let t = Vector3::new(0.2, 0.5, 2.8);
        let moved = s.map_positions(|p| Point3::from(r * p.coords + t));
        assert!(complete_untracked(&s, &moved).is_none(), "nothing lost");
        let mut lost = moved.clone();
        let hip = moved.position(Joint::HipCenter);
        for j in [
            Joint::KneeLeft,
            Joint::AnkleLeft,
            Joint::FootLeft,
            Joint::HandRight,
        ] {
            lost.confidence[j.index()] = 0.0;
            lost.positions[j.index()] = hip;
        }
        let done = complete_untracked(&s, &lost).unwrap();
        for j in Joint::ALL {
            assert!(
                (done.position(j) - moved.position(j)).norm() < 1e-9,
                "{j:?}: {} from its place",
                (done.position(j) - moved.position(j)).norm()
            );
            assert_eq!(done.tracks(j), lost.tracks(j), "{j:?} keeps its tracking");
        }
    }

    /// A rigidly moved skeleton gives the same rigid motion for every bone.
    #[test]
    fn bone_transforms_of_a_rigid_motion_are_that_motion() {
        let s = symcorr_attach::testbody::t_pose(1.0);
        let r = rot_z(-1.1) * swing(Vector3::x(), Vector3::new(0.2, 0.3, 0.9));
        let t = Vector3::new(1.0, 2.0, -0.5);
        let moved = s.map_positions(|p| Point3::from(r * p.coords + t));
        for (b, tr) in bone_transforms(&s, &moved).iter().enumerate() {
            for x in [Point3::new(0.1, 0.5, 0.0), Point3::new(-0.3, 1.2, 0.2)] {
                let want = r * x.coords + t;
                assert!((tr * x).coords.metric_distance(&want) < 1e-9, "bone {b}");
            }
        }
    }

    /// Bending one elbow moves only the forearm's bones, and carries the wrist onto the
    /// target's wrist.
    #[test]
    fn bone_transforms_follow_a_bent_elbow() {
        let s = symcorr_attach::testbody::t_pose(1.0);
        let mut bent = s.clone();
        let elbow = s.position(Joint::ElbowLeft);
        let r = rot_z(0.9);
        for j in [Joint::WristLeft, Joint::HandLeft] {
            bent.positions[j.index()] = elbow + r * (s.position(j) - elbow);
        }
        let tr = bone_transforms(&s, &bent);
        for (b, bone) in BONES.iter().enumerate() {
            for j in [bone.parent, bone.child] {
                let got = tr[b] * s.position(j);
                assert!(
                    (got - bent.position(j)).norm() < 1e-9,
                    "bone {b} joint {j:?}"
                );
            }
        }
    }

    /// `s` with the joints of `moved` turned by `angle` about the axis through `from` and `to`.
    fn turned(s: &Skeleton, moved: &[Joint], from: Joint, to: Joint, angle: f64) -> Skeleton {
        let (o, axis) = (
            s.position(from),
            (s.position(to) - s.position(from)).normalize(),
        );
        let r = Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), angle);
        let mut out = s.clone();
        for &j in moved {
            out.positions[j.index()] = o + r * (s.position(j) - o);
        }
        out
    }

    /// The two limbs the hinge tests bend: root, hinge, end and tip joints.
    const LIMBS: [[Joint; 4]; 2] = [
        [
            Joint::ShoulderLeft,
            Joint::ElbowLeft,
            Joint::WristLeft,
            Joint::HandLeft,
        ],
        [
            Joint::HipRight,
            Joint::KneeRight,
            Joint::AnkleRight,
            Joint::FootRight,
        ],
    ];

    /// A T-pose with its left arm and right leg straightened, then the left elbow and right
    /// knee bent by `bend` radians (forearm about z, shin about x).
    fn bent_limbs(bend: f64) -> Skeleton {
        let mut s = symcorr_attach::testbody::t_pose(1.0);
        for [root, hinge, end, tip] in LIMBS {
            let dir = (s.position(hinge) - s.position(root)).normalize();
            for (from, j) in [(hinge, end), (end, tip)] {
                let l = (s.position(j) - s.position(from)).norm();
                s.positions[j.index()] = s.position(from) + dir * l;
            }
        }
        let mut out = s.clone();
        let (elbow, knee) = (s.position(Joint::ElbowLeft), s.position(Joint::KneeRight));
        let arm = (elbow - s.position(Joint::ShoulderLeft)).normalize();
        let thigh = (knee - s.position(Joint::HipRight)).normalize();
        // Axes normal to the segment: the bend is exactly `bend`.
        let about = |v: Vector3<f64>, helper: Vector3<f64>| {
            Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(v.cross(&helper)), bend)
        };
        let (ra, rl) = (about(arm, Vector3::z()), about(thigh, Vector3::x()));
        for (j, o, r) in [
            (Joint::WristLeft, elbow, ra),
            (Joint::HandLeft, elbow, ra),
            (Joint::AnkleRight, knee, rl),
            (Joint::FootRight, knee, rl),
        ] {
            out.positions[j.index()] = o + r * (s.position(j) - o);
        }
        out
    }

    /// A bent elbow and a bent knee turned about the upper arm and the thigh: the joints show
    /// the turn (the hinge's plane turns with it), and every bone of the two limbs carries
    /// the template's joints onto the target's and turns by exactly that angle. Without the
    /// hinge ([`bone_motion`]) the upper arm and thigh, whose direction does not change, do
    /// not turn at all.
    #[test]
    fn bone_transforms_turn_a_bent_limb_with_its_hinge() {
        let s = bent_limbs(1.0);
        let angle = 0.7;
        let arm = [Joint::WristLeft, Joint::HandLeft];
        let leg = [Joint::AnkleRight, Joint::FootRight];
        let t = turned(&s, &arm, Joint::ShoulderLeft, Joint::ElbowLeft, angle);
        let t = turned(&t, &leg, Joint::HipRight, Joint::KneeRight, angle);
        let tr = bone_transforms(&s, &t);
        let motion = bone_motion(&s, &t);
        for [root, hinge, end, lower] in LIMBS {
            let axis = (s.position(hinge) - s.position(root)).normalize();
            let want = Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), angle);
            for (p, c) in [(root, hinge), (hinge, end), (end, lower)] {
                let b = BONES
                    .iter()
                    .position(|x| x.parent == p && x.child == c)
                    .unwrap();
                approx::assert_relative_eq!(tr[b].rotation.matrix(), want.matrix(), epsilon = 1e-9);
                for j in [p, c] {
                    assert!((tr[b] * s.position(j) - t.position(j)).norm() < 1e-9);
                }
            }
            // Between two frames the limb keeps its fitted twist: the upper segment, whose
            // direction did not change, does not move.
            let upper = BONES
                .iter()
                .position(|x| x.parent == root && x.child == hinge)
                .unwrap();
            approx::assert_relative_eq!(
                motion[upper].rotation.matrix(),
                &Matrix3::identity(),
                epsilon = 1e-12
            );
        }
    }

    /// A limb bent less than [`HINGE_BEND_DEG`]'s lower end shows no twist: a tracker's noise
    /// turns its plane at will. Half way through the ramp, half the turn.
    #[test]
    fn a_nearly_straight_limb_shows_no_twist_and_the_ramp_is_linear() {
        let (lo, hi) = HINGE_BEND_DEG;
        for (bend_deg, share) in [(lo - 1.0, 0.0), ((lo + hi) / 2.0, 0.5), (hi + 5.0, 1.0)] {
            let s = bent_limbs(bend_deg.to_radians());
            let arm = [Joint::WristLeft, Joint::HandLeft];
            let t = turned(&s, &arm, Joint::ShoulderLeft, Joint::ElbowLeft, 0.6);
            let tr = bone_transforms(&s, &t);
            let b = BONES
                .iter()
                .position(|x| x.parent == Joint::ShoulderLeft && x.child == Joint::ElbowLeft)
                .unwrap();
            let axis = (s.position(Joint::ElbowLeft) - s.position(Joint::ShoulderLeft)).normalize();
            let want =
                Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), 0.6 * share);
            approx::assert_relative_eq!(tr[b].rotation.matrix(), want.matrix(), epsilon = 1e-9);
        }
    }
}
