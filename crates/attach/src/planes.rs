//! Segment boundaries by joint planes (the rigid-skinning convention).
//!
//! Bone heat decides *which limb* a vertex belongs to (it is visibility-aware and smooth), but
//! its argmax puts the boundary between two neighbouring segments wherever the heat from their
//! bones balances, which drifts far from the joint where one bone is short (the Kinect pelvis and
//! hip bones are 10 cm long; bone heat gives most of the pelvis to the torso and thighs). Here
//! every pair of segments that share a skeleton joint `J` is separated by the plane through `J`
//! whose normal bisects the two bone directions (`d_A` pointing into `J`, `d_B` out of it):
//! a vertex labelled `A` or `B` goes to `B` iff `(x − J)·unit(d̂_A + d̂_B) > 0`. For two bones
//! leaving the same joint (siblings: pelvis/hips at the hip centre, head/clavicles at the shoulder
//! centre) this is the plane bisecting the angle between them — between the left and right
//! siblings it is the sagittal plane through the midline joint, made to contain the trunk axis
//! (hip centre → shoulder centre) so that a noisy twin bone cannot tilt it through a thigh.
//!
//! Two sweeps over the pairs, so thigh → hip → pelvis can chain; a plane changes a vertex's side
//! only into the twin *root* (hip, clavicle: [`keep_limb_sides`]), where the midline guard can
//! still make it midline. The midline guard ([`midline_guard`]): a vertex labelled hip
//! (clavicle) within the band of the left/right plane gets the midline segment instead (pelvis;
//! head or torso by their plane) — there the side is decided by centimetres of joint error, and
//! a midline label is only a disagreement where a twin label would be a left/right swap.
//!
//! Measured: `docs/decisions/2026-11-23-attach-joint-planes.md`,
//! `docs/decisions/2026-11-23-attach-midline-guard-band.md`,
//! `docs/decisions/2026-11-23-attach-left-right-labels.md`.

use crate::geom::{unit, Joints};
use crate::{BodySide, Bone, Joint, Segment};
use nalgebra::{distance, Point3, Vector3};

/// One boundary: segments `a` and `b` meet at `joint`; `normal` points into `b`'s side.
#[derive(Debug, Clone, Copy)]
pub(crate) struct JointPlane {
    pub a: Segment,
    pub b: Segment,
    pub joint: Joint,
    pub normal: Vector3<f64>,
}

impl JointPlane {
    /// The point the plane passes through: its joint.
    pub(crate) fn origin(&self, p: &Joints) -> Point3<f64> {
        p[self.joint.index()]
    }
}

/// Unit direction from joint `j` along segment `s`: its bone touching `j` (pointing away from
/// `j`), else towards its first bone's midpoint (segments that meet on the surface without
/// sharing a joint, e.g. torso and upper arm). `None` if a joint it needs is unusable.
pub(crate) fn segment_direction(
    s: Segment,
    j: Joint,
    p: &Joints,
    usable: &[bool; 20],
) -> Option<Vector3<f64>> {
    let ok = |x: Joint| usable[x.index()];
    if !ok(j) {
        return None;
    }
    if let Some(&Bone {
        parent: u,
        child: v,
    }) = s.bones().iter().find(|b| b.parent == j || b.child == j)
    {
        let other = if u == j { v } else { u };
        return if ok(other) {
            unit(p[other.index()] - p[j.index()])
        } else {
            None
        };
    }
    let &Bone {
        parent: u,
        child: v,
    } = s.bones().first()?;
    if !(ok(u) && ok(v)) {
        return None;
    }
    let mid = Point3::from((p[u.index()].coords + p[v.index()].coords) * 0.5);
    unit(mid - p[j.index()])
}

/// The skeleton joint two segments share, if any (the first found along `a`'s bones).
pub(crate) fn shared_joint(a: Segment, b: Segment) -> Option<Joint> {
    a.bones().iter().find_map(|u| {
        b.bones().iter().find_map(|r| {
            [u.parent, u.child]
                .into_iter()
                .find(|&x| x == r.parent || x == r.child)
        })
    })
}

/// Unit trunk axis, hip centre → shoulder centre (the longest midline baseline, least affected
/// by joint noise).
pub(crate) fn trunk_axis(p: &Joints, usable: &[bool; 20]) -> Option<Vector3<f64>> {
    let (h, s) = (Joint::HipCenter.index(), Joint::ShoulderCenter.index());
    if !(usable[h] && usable[s]) {
        return None;
    }
    unit(p[s] - p[h])
}

/// The planes between every two segments that share a joint (skipping bones that were dropped
/// or are degenerate).
pub(crate) fn joint_planes(p: &Joints, usable: &[bool; 20]) -> Vec<JointPlane> {
    let mut out = Vec::new();
    for (i, &a) in Segment::ALL.iter().enumerate() {
        for &b in &Segment::ALL[i + 1..] {
            let Some(j) = shared_joint(a, b) else {
                continue;
            };
            let (Some(da), Some(db)) = (
                segment_direction(a, j, p, usable),
                segment_direction(b, j, p, usable),
            ) else {
                continue;
            };
            // d_A into the joint is −da; the bisector of (−da, db) is db − da.
            let mut n = db - da;
            // Between left/right twins the bisector is the body's sagittal plane, which
            // contains the trunk axis: keep only the part of the normal perpendicular to it.
            // With one twin bone noisy (a hip joint moved onto the surface near the hip
            // centre, so that hip bone points up) the plain bisector tilts by up to 45° and
            // the plane cuts through the other thigh, whose vertices then took the wrong side.
            if a.mirror() == b {
                if let Some(up) = trunk_axis(p, usable) {
                    n -= up * n.dot(&up);
                }
            }
            if let Some(normal) = unit(n) {
                out.push(JointPlane {
                    a,
                    b,
                    joint: j,
                    normal,
                });
            }
        }
    }
    out
}

/// Re-decides every label between the two segments of each joint plane (two sweeps, so that a
/// vertex moved from a thigh to a hip can then move on to the pelvis).
pub(crate) fn apply(
    positions: &[[f64; 3]],
    p: &Joints,
    planes: &[JointPlane],
    labels: &mut [Segment],
) {
    for _ in 0..2 {
        for pl in planes {
            let o = p[pl.joint.index()];
            for (x, l) in positions.iter().zip(labels.iter_mut()) {
                if *l == pl.a || *l == pl.b {
                    *l = if (Point3::from(*x) - o).dot(&pl.normal) > 0.0 {
                        pl.b
                    } else {
                        pl.a
                    };
                }
            }
        }
    }
}

/// The skeleton's left/right asymmetry where a body is symmetric whatever its pose: the hip
/// centre's offset from the hips' midpoint along the hip line, and the length differences of
/// the hip, thigh, shin, upper-arm and forearm bones of the two sides. Returns the root mean
/// square of the available measures (mesh units), an estimate of the joints' noise; `None`
/// if no measure is available.
pub(crate) fn joint_asymmetry(p: &Joints, usable: &[bool; 20]) -> Option<f64> {
    use Joint as J;
    let ok = |js: &[Joint]| js.iter().all(|j| usable[j.index()]);
    let at = |j: Joint| p[j.index()];
    let len = |a: Joint, b: Joint| distance(&at(a), &at(b));
    let mut m = Vec::new();
    if ok(&[J::HipCenter, J::HipLeft, J::HipRight]) {
        if let Some(u) = unit(at(J::HipLeft) - at(J::HipRight)) {
            let mid = Point3::from((at(J::HipLeft).coords + at(J::HipRight).coords) * 0.5);
            m.push((at(J::HipCenter) - mid).dot(&u));
        }
    }
    let hip_bones = ((J::HipCenter, J::HipLeft), (J::HipCenter, J::HipRight));
    for ((a, b), (ra, rb)) in std::iter::once(hip_bones).chain(crate::refine::TWIN_LIMB_BONES) {
        if ok(&[a, b, ra, rb]) {
            m.push(len(a, b) - len(ra, rb));
        }
    }
    (!m.is_empty()).then(|| (m.iter().map(|x| x * x).sum::<f64>() / m.len() as f64).sqrt())
}

/// Summed weights of the left and of the right segments in per-segment weights `w`
/// (midline segments count for neither).
pub(crate) fn side_weights(w: &[f64; 17]) -> (f64, f64) {
    let (mut l, mut r) = (0.0, 0.0);
    for s in Segment::ALL {
        match s.side() {
            BodySide::Left => l += w[s.index()],
            BodySide::Right => r += w[s.index()],
            BodySide::Midline => {}
        }
    }
    (l, r)
}

/// True if two side segments lie on the same side of the body.
pub(crate) fn same_side(a: Segment, b: Segment) -> bool {
    a.side() == b.side()
}

/// True for the segments of an arm chain (clavicle, upper arm, forearm).
pub(crate) fn is_arm(s: Segment) -> bool {
    matches!(root(s), Segment::ClavicleLeft | Segment::ClavicleRight)
}

/// The root (hip or clavicle) of the limb chain a side segment belongs to.
fn root(s: Segment) -> Segment {
    use Segment as S;
    match s {
        S::ClavicleLeft | S::UpperArmLeft | S::ForearmLeft => S::ClavicleLeft,
        S::ClavicleRight | S::UpperArmRight | S::ForearmRight => S::ClavicleRight,
        S::HipLeft | S::ThighLeft | S::ShinLeft | S::FootLeft => S::HipLeft,
        S::HipRight | S::ThighRight | S::ShinRight | S::FootRight => S::HipRight,
        s => s,
    }
}

/// Joint planes change a vertex's side only through the left/right plane between the twin
/// roots (hips, clavicles); chained with the hip/thigh plane of the other side (two sweeps) a
/// groin vertex that bone heat gave to the right thigh could end on the *left thigh* when a
/// noisy hip joint tilted the planes. A limb segment of the other side than bone heat's label
/// needs bone heat's support: such a vertex keeps the other side's root (hip or clavicle), where
/// [`midline_guard`] can still give it the midline label. Returns the number changed.
pub(crate) fn keep_limb_sides(heat_labels: &[Segment], labels: &mut [Segment]) -> usize {
    let mut changed = 0;
    for (h, l) in heat_labels.iter().zip(labels.iter_mut()) {
        if h.side().opposes(l.side()) && root(*l) != *l {
            *l = root(*l);
            changed += 1;
        }
    }
    changed
}

/// The midline guard: a vertex labelled with one of two left/right twins that meet at a midline
/// joint (hips at the hip centre, clavicles at the shoulder centre) but lying within `band` of
/// the plane between them is relabelled with the midline segment at that joint (pelvis; head or
/// torso by their joint plane). Near the midline the side is decided by centimetres of joint
/// error; a midline label there is a disagreement, a twin label would be a left/right swap.
pub(crate) fn midline_guard(
    positions: &[[f64; 3]],
    p: &Joints,
    planes: &[JointPlane],
    band: f64,
    labels: &mut [Segment],
) -> usize {
    use Segment as S;
    let find = |a: Segment, b: Segment| planes.iter().find(|pl| pl.a == a && pl.b == b);
    let mut changed = 0;
    for (l, r) in [
        (S::HipLeft, S::HipRight),
        (S::ClavicleLeft, S::ClavicleRight),
    ] {
        let Some(lr) = find(l, r) else { continue };
        let o = p[lr.joint.index()];
        let head_torso = find(S::Torso, S::Head);
        for (x, lab) in positions.iter().zip(labels.iter_mut()) {
            let x = Point3::from(*x);
            if (*lab != l && *lab != r) || (x - o).dot(&lr.normal).abs() >= band {
                continue;
            }
            *lab = match (l, head_torso) {
                (S::HipLeft, _) => S::Pelvis,
                (_, Some(ht)) if (x - p[ht.joint.index()]).dot(&ht.normal) > 0.0 => S::Head,
                _ => S::Torso,
            };
            changed += 1;
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testbody::t_pose;
    use approx::assert_relative_eq;

    fn plane(planes: &[JointPlane], a: Segment, b: Segment) -> JointPlane {
        *planes.iter().find(|p| p.a == a && p.b == b).unwrap()
    }

    #[test]
    fn a_symmetric_skeleton_has_no_asymmetry_and_a_noisy_one_does() {
        let sk = t_pose(1.0);
        let a = joint_asymmetry(&sk.positions, &[true; 20]).unwrap();
        assert!(a < 1e-12, "{a}");
        // The left leg below the hip moved 4 cm along the thigh: the left thigh is 4 cm longer,
        // every other measure unchanged, so the RMS of the six measures is 4/√6 cm.
        let mut p = sk.positions;
        let (hip, knee) = (p[Joint::HipLeft.index()], p[Joint::KneeLeft.index()]);
        let d = unit(knee - hip).unwrap() * 0.04;
        for j in [Joint::KneeLeft, Joint::AnkleLeft, Joint::FootLeft] {
            p[j.index()] += d;
        }
        let b = joint_asymmetry(&p, &[true; 20]).unwrap();
        assert!((b - 0.04 / 6.0f64.sqrt()).abs() < 1e-9, "{b}");
        // Nothing measurable without the hips and limbs.
        let mut usable = [false; 20];
        usable[Joint::HipCenter.index()] = true;
        assert!(joint_asymmetry(&p, &usable).is_none());
    }

    #[test]
    fn planes_change_sides_only_into_the_twin_root() {
        use Segment as S;
        let heat = [
            S::ThighRight,
            S::ThighRight,
            S::Pelvis,
            S::UpperArmLeft,
            S::ThighLeft,
        ];
        let mut labels = [
            S::ThighLeft,
            S::HipLeft,
            S::ThighLeft,
            S::ForearmRight,
            S::ShinLeft,
        ];
        assert_eq!(keep_limb_sides(&heat, &mut labels), 2);
        assert_eq!(
            labels,
            [
                S::HipLeft,
                S::HipLeft,
                S::ThighLeft,
                S::ClavicleRight,
                S::ShinLeft
            ]
        );
    }

    #[test]
    fn planes_bisect_the_bones_at_their_shared_joint() {
        let sk = t_pose(1.0);
        let planes = joint_planes(&sk.positions, &[true; 20]);
        // 20 pairs of segments share a joint (3 at the hip centre, 6 at the shoulder centre,
        // 1 at the spine, and 5 along each side).
        assert_eq!(planes.len(), 20);
        // Pelvis → torso: both bones point up (y), so the plane is horizontal at the spine.
        let pt = plane(&planes, Segment::Pelvis, Segment::Torso);
        assert_eq!(pt.joint, Joint::Spine);
        assert!((pt.normal[1] - 1.0).abs() < 1e-9, "{:?}", pt.normal);
        // Left/right twins: the sagittal plane, normal towards the right (−x in t_pose).
        let lr = plane(&planes, Segment::HipLeft, Segment::HipRight);
        assert_eq!(lr.joint, Joint::HipCenter);
        assert!(lr.normal[0] < -0.99, "{:?}", lr.normal);
        // Every normal is a unit vector.
        for p in &planes {
            assert_relative_eq!(p.normal.norm_squared(), 1.0, epsilon = 1e-9);
        }
    }

    #[test]
    fn labels_follow_the_side_of_the_plane_and_the_guard_takes_the_midline() {
        let sk = t_pose(1.0);
        let p = sk.positions;
        let planes = joint_planes(&p, &[true; 20]);
        let spine = p[Joint::Spine.index()];
        let hc = p[Joint::HipCenter.index()];
        // Just above the spine joint but labelled pelvis → torso; just below labelled torso → pelvis.
        let xs = [
            [0.1, spine[1] + 0.01, 0.0],
            [0.1, spine[1] - 0.01, 0.0],
            // Right of the midline (−x) but labelled hip_left, 1 cm and 10 cm away.
            [hc[0] - 0.01, hc[1] - 0.05, 0.1],
            [hc[0] - 0.10, hc[1] - 0.02, 0.0],
        ];
        let mut labels = [
            Segment::Pelvis,
            Segment::Torso,
            Segment::HipLeft,
            Segment::HipLeft,
        ];
        apply(&xs, &p, &planes, &mut labels);
        assert_eq!(labels[0], Segment::Torso);
        assert_eq!(labels[1], Segment::Pelvis);
        assert_eq!(labels[3], Segment::HipRight);
        let changed = midline_guard(&xs, &p, &planes, 0.03, &mut labels);
        assert_eq!(changed, 1);
        assert_eq!(labels[2], Segment::Pelvis);
        assert_eq!(labels[3], Segment::HipRight);
    }
}
