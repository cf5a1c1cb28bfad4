//! Handedness check and joint refinement (DESIGN.md, Algorithm 1: "move each joint to the
//! interior, toward the medial axis of its cross-section, keep bone lengths plausible").
//!
//! **Handedness.** The torso frame (up = hip → shoulder centre, left = right → left shoulders
//! and hips) gives the facing direction `left × up`. The feet must point the same way — the
//! ankle→foot joints, and the mesh around the ankles (toes reach further forward than heels) —
//! each foot compared with the facing direction carried into that shin's frame (with a flexed
//! hip and a bent knee the toes point down, not forward); and bent knees must lie in front of
//! the hip–ankle line (knees are hinges that bend forward). The combined evidence is exactly
//! antisymmetric under a side swap; the sides are swapped only below `-`[`MIRROR_MARGIN`], and
//! weak evidence leaves the skeleton as given (reported in [`MirrorCheck`]).
//!
//! **Refinement.** Each limb joint moves to the centre of the mesh cross-section perpendicular
//! to its limb: an algebraic circle fit, which also works on the half-rings of a single-view
//! scan, restricted to the connected piece of that cross-section nearest the joint so that a
//! joint never jumps to another limb, and only a circle passing within `OFF_CIRCLE` × the
//! skeleton's height of the joint counts (a joint lies near its limb's axis; a centre far out
//! belongs to another surface the slab caught, such as a hip the hand rests on). Shoulder,
//! hip and hip-centre joints are only re-centred in depth: the hip centre's cross-section runs
//! into the tops of the thighs, and a circle-fit centre moves sideways with a flexed leg. Moves
//! are capped ([`AttachOptions::max_joint_move`]); left/right bone lengths that differ by more
//! than [`AttachOptions::bone_length_tolerance`] are set to their mean.
//!
//! Measured: `docs/decisions/2026-11-23-attach-handedness-check.md`,
//! `docs/decisions/2026-12-02-attach-refinement-off-circle.md`,
//! `docs/decisions/2026-12-02-attach-noisy-joint-limit.md`.

use crate::geom::{unit, Joints};
use crate::tables::MeshTables;
use crate::{AttachOptions, Joint, JointMove, MirrorCheck, BONES};
use nalgebra::{distance, Matrix3, Point3, Vector3};
use symcorr_mesh::geometry::closest_on_segment;
use symcorr_mesh::TriMesh;

/// A swap needs the combined facing evidence ([`crate::MirrorCheck::evidence`]) below
/// `-MIRROR_MARGIN`. The evidence is exactly antisymmetric under a side swap, so the margin
/// trades missed fixes for wrong swaps, and a wrong swap mirrors every label (a whole map
/// flipped). On 40 generated bodies, exact and σ = 3 cm joints, every correct skeleton scores
/// ≥ +0.33 (tools/synth/tests/attach_labels.rs, `handedness_of_the_40_bodies`; measured:
/// `docs/decisions/2026-11-23-attach-handedness-check.md`).
pub const MIRROR_MARGIN: f64 = 0.45;

/// The torso frame `(up, left, facing)`: up = hip centre → shoulder centre, left = right → left
/// shoulders and hips (made orthogonal to up), facing = left × up (right-handed).
pub(crate) fn torso_frame(p: &Joints, usable: &[bool; 20]) -> Option<[Vector3<f64>; 3]> {
    use Joint as J;
    let u = |j: Joint| usable[j.index()];
    let up = unit(p[J::ShoulderCenter.index()] - p[J::HipCenter.index()])?;
    let mut l = Vector3::zeros();
    for (a, b) in [
        (J::ShoulderLeft, J::ShoulderRight),
        (J::HipLeft, J::HipRight),
    ] {
        if u(a) && u(b) {
            l += p[a.index()] - p[b.index()];
        }
    }
    let left = unit(l - up * l.dot(&up))?;
    let facing = left.cross(&up);
    Some([up, left, facing])
}

/// Facing evidence from the skeleton's feet and from the mesh around the ankles.
pub(crate) fn mirror_check(
    mesh: &TriMesh,
    p: &Joints,
    usable: &[bool; 20],
    height: f64,
) -> MirrorCheck {
    use Joint as J;
    let mut out = MirrorCheck::default();
    let Some([_, left, facing]) = torso_frame(p, usable) else {
        return out;
    };
    out.facing = Some(facing);
    out.knee_evidence = knee_evidence(p, usable, facing);
    let (mut sk, mut nsk, mut me, mut nme) = (0.0, 0, 0.0, 0);
    let mut offset = 0.0;
    for (knee, ankle, foot) in [
        (J::KneeLeft, J::AnkleLeft, J::FootLeft),
        (J::KneeRight, J::AnkleRight, J::FootRight),
    ] {
        let (k, a, f) = (p[knee.index()], p[ankle.index()], p[foot.index()]);
        // The torso's facing direction made perpendicular to this shin: with a flexed hip or a
        // bent knee the foot turns with the shin (kneeling: the toes point down, not forward),
        // so the foot is compared with the facing direction carried into the shin's frame.
        let (facing, left) = match unit(k - a) {
            Some(s) => match unit(facing - s * facing.dot(&s)) {
                Some(f) if facing.dot(&s).abs() < 0.95 => (f, unit(s.cross(&f)).unwrap_or(left)),
                _ => (facing, left),
            },
            None => (facing, left),
        };
        if usable[ankle.index()] && usable[foot.index()] {
            if let Some(d) = unit(f - a) {
                sk += d.dot(&facing);
                nsk += 1;
            }
        }
        if !(usable[knee.index()] && usable[ankle.index()]) {
            continue;
        }
        // The foot: surface below the ankle (along the shin), near it laterally.
        let Some(shin) = unit(k - a) else {
            continue;
        };
        let reach = 0.16 * height;
        let (mut fwd, mut back) = (0.0f64, 0.0f64);
        let mut n = 0;
        for v in &mesh.positions {
            let e = Point3::from(*v) - a;
            if e.dot(&shin) > 0.02 * height
                || e.norm() > reach
                || e.dot(&left).abs() > 0.06 * height
            {
                continue;
            }
            let t = e.dot(&facing);
            fwd = fwd.max(t);
            back = back.max(-t);
            n += 1;
        }
        if n >= 8 && fwd + back > 0.0 {
            me += (fwd - back) / (fwd + back);
            offset += fwd - back;
            nme += 1;
            out.mesh_vertices += n;
        }
    }
    out.skeleton_evidence = (nsk > 0).then(|| sk / nsk as f64);
    out.mesh_evidence = (nme > 0).then(|| me / nme as f64);
    out.mesh_offset = (nme > 0).then(|| offset / nme as f64);
    out
}

/// The knees' flexion cue: a knee is a hinge that bends forward, so a bent knee lies in front of
/// the hip–ankle line (along the torso's facing direction) and a mirrored skeleton, whose
/// facing direction is reversed, puts it behind. Per leg `cos(knee offset, facing)` weighted by
/// how bent the leg is (offset / thigh length, from 0 below 0.05 to 1 at 0.25: a straight leg
/// says nothing), averaged over the legs. Independent of the feet, so it holds where the feet are
/// unreliable (a kneeling or sitting pose, a foot joint on the surface).
fn knee_evidence(p: &Joints, usable: &[bool; 20], facing: Vector3<f64>) -> Option<f64> {
    use Joint as J;
    let mut sum = 0.0;
    let mut n = 0;
    for (hip, knee, ankle) in [
        (J::HipLeft, J::KneeLeft, J::AnkleLeft),
        (J::HipRight, J::KneeRight, J::AnkleRight),
    ] {
        if !(usable[hip.index()] && usable[knee.index()] && usable[ankle.index()]) {
            continue;
        }
        let (h, k, a) = (p[hip.index()], p[knee.index()], p[ankle.index()]);
        let (q, _) = closest_on_segment(&k, &h, &a);
        let off = k - q;
        let thigh = distance(&h, &k);
        if !(thigh > 0.0) {
            continue;
        }
        n += 1;
        let Some(d) = unit(off) else { continue };
        // Offsets under 5 % of the thigh (2 cm on an adult) are joint noise on a straight leg.
        let bend = ((off.norm() / thigh - 0.05) / 0.2).clamp(0.0, 1.0);
        sum += bend * d.dot(&facing);
    }
    (n > 0).then(|| sum / n as f64)
}

/// Combined evidence: the mesh and the knees count fully, the feet joints (noisy) half.
pub(crate) fn mirror_decision(m: &MirrorCheck) -> f64 {
    m.mesh_evidence.unwrap_or(0.0)
        + 0.5 * m.skeleton_evidence.unwrap_or(0.0)
        + m.knee_evidence.unwrap_or(0.0)
}

pub(crate) struct Refined {
    pub moves: Vec<JointMove>,
    pub skipped: Vec<(Joint, &'static str)>,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// Centre of the limb's cross-section.
    Limb,
    /// Shoulder / hip joints: only the depth (facing) coordinate.
    Junction,
    /// Torso midline joints: cross-section perpendicular to up.
    Torso,
}

fn kind(j: Joint) -> Kind {
    use Joint as J;
    match j {
        J::Spine | J::ShoulderCenter => Kind::Torso,
        // The hip centre's cross-section runs into the tops of the thighs; with a flexed or
        // abducted leg its centre moved the joint 5 cm sideways (and with it the left/right
        // boundary of the pelvis): depth only, like the hips.
        J::HipCenter => Kind::Junction,
        J::ShoulderLeft | J::ShoulderRight | J::HipLeft | J::HipRight => Kind::Junction,
        _ => Kind::Limb,
    }
}

fn children(j: Joint) -> impl Iterator<Item = Joint> {
    BONES.iter().filter(move |b| b.parent == j).map(|b| b.child)
}

/// Vertices of `set` grouped into connected pieces (mesh edges within the set).
fn pieces(set: &[u32], adj: &[Vec<u32>], mark: &mut [u32], stamp: u32) -> Vec<Vec<u32>> {
    for &v in set {
        mark[v as usize] = stamp;
    }
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for &s in set {
        if !seen.insert(s) {
            continue;
        }
        let mut comp = vec![s];
        let mut i = 0;
        while i < comp.len() {
            let v = comp[i];
            i += 1;
            for &w in &adj[v as usize] {
                if mark[w as usize] == stamp && seen.insert(w) {
                    comp.push(w);
                }
            }
        }
        out.push(comp);
    }
    out
}

/// Algebraic (Kåsa) circle fit of 2-D points: centre and radius. Works on partial arcs, which
/// is what a single-view scan gives.
fn circle_fit(pts: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    if pts.len() < 5 {
        return None;
    }
    // Centre the data for conditioning.
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let my = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    // Minimise Σ (x² + y² + D x + E y + F)²  →  3×3 normal equations.
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for p in pts {
        let (x, y) = (p[0] - mx, p[1] - my);
        let row = Vector3::new(x, y, 1.0);
        let z = -(x * x + y * y);
        for i in 0..3 {
            for k in 0..3 {
                a[(i, k)] += row[i] * row[k];
            }
            b[i] += row[i] * z;
        }
    }
    // Cramer's rule; nalgebra's 3×3 determinant is the same cofactor expansion along row 0.
    let d = a.determinant();
    let scale_ = a[(0, 0)] * a[(1, 1)] * a[(2, 2)];
    if d.abs() <= 1e-12 * scale_.abs() || d == 0.0 {
        return None;
    }
    let mut sol = [0.0; 3];
    for (c, s) in sol.iter_mut().enumerate() {
        let mut m = a;
        m.set_column(c, &b);
        *s = m.determinant() / d;
    }
    let (cx, cy) = (-sol[0] / 2.0, -sol[1] / 2.0);
    let r2 = cx * cx + cy * cy - sol[2];
    if !(r2 > 0.0) {
        return None;
    }
    Some(([cx + mx, cy + my], r2.sqrt()))
}

/// How far (fraction of the skeleton's height) a limb joint may lie off the circle fitted to
/// its limb's cross-section and still be moved to its centre: joint noise (σ = 3 cm) and
/// joints on or outside the surface are inside this allowance (the 40 generated bodies, exact
/// and noisy, label exactly as without it).
const OFF_CIRCLE: f64 = 0.05;

/// Two unit vectors spanning the plane perpendicular to `n`.
fn plane_basis(n: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let t = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = unit(n.cross(&t)).unwrap_or_else(Vector3::z);
    (e1, n.cross(&e1))
}

/// Refines the joint positions in place.
pub(crate) fn refine(
    tables: &MeshTables<'_>,
    p: &mut Joints,
    usable: &[bool; 20],
    height: f64,
    options: &AttachOptions,
) -> Refined {
    let mut moves = Vec::new();
    let mut skipped = Vec::new();
    let mesh = tables.mesh;
    let adj = tables.neighbors();
    let mean_edge = {
        let e = mesh.edges();
        e.iter()
            .map(|&[a, b]| {
                distance(
                    &mesh.positions[a as usize].into(),
                    &mesh.positions[b as usize].into(),
                )
            })
            .sum::<f64>()
            / e.len().max(1) as f64
    };
    let frame = torso_frame(p, usable);
    // Boundary vertices (edges with one triangle): a cross-section containing one is open (a
    // single-view scan), where only limbs can be centred (circle fit on the visible arc); the
    // torso's and the shoulders'/hips' depth centres are unknowable there.
    let on_boundary = &tables.boundary().vertices;
    let max_move = options.max_joint_move * height;
    let mut mark = vec![0u32; mesh.num_vertices()];
    let orig = *p;
    for (stamp, j) in Joint::ALL.into_iter().enumerate() {
        if !usable[j.index()] {
            continue;
        }
        let x = orig[j.index()];
        let k = kind(j);
        // Local axis and scale of the cross-section.
        let parent = j.parent().filter(|q| usable[q.index()]);
        let child = children(j).find(|c| usable[c.index()] && kind(*c) != Kind::Junction);
        let (axis, bone_len) = match k {
            Kind::Torso | Kind::Junction => match frame {
                Some(f) => (f[0], 0.25 * height),
                None => continue,
            },
            Kind::Limb => {
                let a = parent.and_then(|q| unit(x - orig[q.index()]));
                let b = child.and_then(|c| unit(orig[c.index()] - x));
                let len = parent
                    .map(|q| distance(&x, &orig[q.index()]))
                    .into_iter()
                    .chain(child.map(|c| distance(&x, &orig[c.index()])))
                    .fold(0.0, f64::max);
                let axis = match (a, b) {
                    (Some(a), Some(b)) => unit(a + b).unwrap_or(a),
                    (Some(a), None) | (None, Some(a)) => a,
                    (None, None) => continue,
                };
                (axis, len)
            }
        };
        let half = (0.08 * bone_len).max(1.5 * mean_edge);
        let radius = match k {
            Kind::Limb => max_move + 0.5 * bone_len.min(0.25 * height),
            Kind::Torso => 0.2 * height,
            Kind::Junction => 0.12 * height,
        };
        let set: Vec<u32> = (0..mesh.num_vertices() as u32)
            .filter(|&v| {
                let e = Point3::from(mesh.positions[v as usize]) - x;
                let h = e.dot(&axis);
                h.abs() <= half && (e - axis * h).norm() <= radius
            })
            .collect();
        let (e1, e2) = plane_basis(axis);
        let mut best: Option<(Point3<f64>, f64)> = None;
        let mut open = false;
        for piece in pieces(&set, adj, &mut mark, stamp as u32 + 1) {
            if k != Kind::Limb && piece.iter().any(|&v| on_boundary[v as usize]) {
                open = true;
                continue;
            }
            let centre = if k == Kind::Junction {
                // Depth centre only: the shoulder/hip cross-section runs into the torso.
                let Some(f) = frame else { continue };
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for &v in &piece {
                    let t = (Point3::from(mesh.positions[v as usize]) - x).dot(&f[2]);
                    lo = lo.min(t);
                    hi = hi.max(t);
                }
                if piece.len() < 5 {
                    continue;
                }
                x + f[2] * (0.5 * (lo + hi))
            } else {
                let pts: Vec<[f64; 2]> = piece
                    .iter()
                    .map(|&v| {
                        let e = Point3::from(mesh.positions[v as usize]) - x;
                        [e.dot(&e1), e.dot(&e2)]
                    })
                    .collect();
                let Some((c, r)) = circle_fit(&pts) else {
                    continue;
                };
                // A joint lies near its limb's axis, so the limb's circle passes within about
                // its radius of it; a centre much farther out belongs to another surface the
                // slab caught (a hip the hand rests on, a few noisy pixels of a scan whose
                // wrist is hidden). Measured on the Kinect-realism scan: a circle of 5 mm radius
                // fitted to 7 hip pixels 13 cm from the left wrist moved the wrist 12 cm onto
                // the hip.
                if r > radius || c[0].hypot(c[1]) > r + OFF_CIRCLE * height {
                    continue;
                }
                x + (e1 * c[0] + e2 * c[1])
            };
            let d = distance(&centre, &x);
            if best.is_none_or(|b| d < b.1) {
                best = Some((centre, d));
            }
        }
        match best {
            Some((c, d)) if d <= max_move => {
                if d > 0.0 {
                    p[j.index()] = c;
                    moves.push(JointMove {
                        joint: j,
                        from: x,
                        to: c,
                        reason: if k == Kind::Junction {
                            "depth centre"
                        } else {
                            "cross-section centre"
                        },
                    });
                }
            }
            Some(_) => skipped.push((j, "cross-section centre farther than the move limit")),
            None if open => skipped.push((j, "open cross-section (scan): left as given")),
            None => skipped.push((j, "no cross-section found")),
        }
    }
    symmetric_bone_lengths(p, usable, options.bone_length_tolerance, &mut moves);
    Refined { moves, skipped }
}

/// Left/right limb bone pairs whose lengths should agree (refinement evens them out;
/// `planes::joint_asymmetry` measures them).
pub(crate) const TWIN_LIMB_BONES: [((Joint, Joint), (Joint, Joint)); 4] = {
    use Joint as J;
    [
        (
            (J::ShoulderLeft, J::ElbowLeft),
            (J::ShoulderRight, J::ElbowRight),
        ),
        ((J::ElbowLeft, J::WristLeft), (J::ElbowRight, J::WristRight)),
        ((J::HipLeft, J::KneeLeft), (J::HipRight, J::KneeRight)),
        ((J::KneeLeft, J::AnkleLeft), (J::KneeRight, J::AnkleRight)),
    ]
};

fn descendants(j: Joint) -> Vec<Joint> {
    let mut out = vec![j];
    let mut i = 0;
    while i < out.len() {
        let c: Vec<Joint> = children(out[i]).collect();
        out.extend(c);
        i += 1;
    }
    out
}

/// Sets left/right bone pairs that differ by more than `tol` (relative) to their mean length,
/// moving the child joint (and everything below it) along its bone.
fn symmetric_bone_lengths(
    p: &mut Joints,
    usable: &[bool; 20],
    tol: f64,
    moves: &mut Vec<JointMove>,
) {
    for ((la, lb), (ra, rb)) in TWIN_LIMB_BONES {
        if ![la, lb, ra, rb].iter().all(|j| usable[j.index()]) {
            continue;
        }
        let ll = distance(&p[la.index()], &p[lb.index()]);
        let lr = distance(&p[ra.index()], &p[rb.index()]);
        let mean = 0.5 * (ll + lr);
        if !(mean > 0.0) || (ll - lr).abs() <= tol * mean {
            continue;
        }
        for (a, b, l) in [(la, lb, ll), (ra, rb, lr)] {
            let Some(d) = unit(p[b.index()] - p[a.index()]) else {
                continue;
            };
            let delta = d * (mean - l);
            let from = p[b.index()];
            for q in descendants(b) {
                p[q.index()] += delta;
            }
            moves.push(JointMove {
                joint: b,
                from,
                to: p[b.index()],
                reason: "bone length",
            });
        }
    }
}

/// Distance from `x` to the nearest bone segment (for tests and diagnostics).
#[allow(dead_code)]
pub(crate) fn nearest_bone_distance(x: &Point3<f64>, p: &Joints) -> f64 {
    BONES
        .iter()
        .map(|b| closest_on_segment(x, &p[b.parent.index()], &p[b.child.index()]).1)
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An open tube of `radius` around the line through `centre` along unit `axis`.
    fn tube(centre: Point3<f64>, axis: Vector3<f64>, radius: f64) -> TriMesh {
        let (e1, e2) = plane_basis(axis);
        let (rings, k) = (9usize, 24usize);
        let mut positions = Vec::new();
        for i in 0..rings {
            let h = 0.004 * (i as f64 - 4.0);
            for j in 0..k {
                let t = std::f64::consts::TAU * j as f64 / k as f64;
                let off = e1 * (radius * t.cos()) + e2 * (radius * t.sin());
                positions.push((centre + axis * h + off).into());
            }
        }
        let mut triangles = Vec::new();
        for i in 0..rings as u32 - 1 {
            for j in 0..k as u32 {
                let (a, b) = (i * k as u32 + j, i * k as u32 + (j + 1) % k as u32);
                triangles.push([a, b, a + k as u32]);
                triangles.push([b, b + k as u32, a + k as u32]);
            }
        }
        TriMesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn a_joint_is_not_moved_to_a_surface_far_off_its_circle() {
        // Only a thin tube (5 mm radius, like a few noisy scan pixels) lies in the left wrist's
        // cross-section, 10 cm from the joint: the wrist stays where it is. A tube of forearm
        // radius 2 cm from the joint is the wrist's own cross-section: it moves there.
        let sk = crate::testbody::t_pose(1.0);
        let p = sk.positions;
        let (e, w, h) = (
            p[Joint::ElbowLeft.index()],
            p[Joint::WristLeft.index()],
            p[Joint::HandLeft.index()],
        );
        let axis = unit(unit(w - e).unwrap() + unit(h - w).unwrap()).unwrap();
        let (e1, _) = plane_basis(axis);
        let usable = [true; 20];
        let options = AttachOptions::default();
        for (offset, radius, moved) in [(0.10, 0.005, false), (0.02, 0.03, true)] {
            let mesh = tube(w + e1 * offset, axis, radius);
            let mut q = p;
            let r = refine(
                &crate::tables::MeshTables::new(&mesh),
                &mut q,
                &usable,
                1.7,
                &options,
            );
            let d = distance(&q[Joint::WristLeft.index()], &w);
            if moved {
                assert!((d - offset).abs() < 1e-3, "moved {d}");
            } else {
                assert_eq!(d, 0.0, "moved {d}");
                assert!(r.skipped.iter().any(|s| s.0 == Joint::WristLeft));
            }
        }
    }

    #[test]
    fn circle_fit_recovers_a_half_circle() {
        let pts: Vec<[f64; 2]> = (0..20)
            .map(|i| {
                let t = std::f64::consts::PI * i as f64 / 19.0;
                [2.0 + 0.5 * t.cos(), -1.0 + 0.5 * t.sin()]
            })
            .collect();
        let (c, r) = circle_fit(&pts).unwrap();
        assert!((c[0] - 2.0).abs() < 1e-9 && (c[1] + 1.0).abs() < 1e-9);
        assert!((r - 0.5).abs() < 1e-9);
    }
}
