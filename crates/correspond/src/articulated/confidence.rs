//! What the final map's confidence knows about a whole region of the fit, beyond the distance
//! of each vertex to its match (DESIGN.md, Algorithm 7, step 6).
//!
//! The wrong matches left on a depth scan are whole regions slid along the surface — a forearm
//! a few centimetres along its own axis, a head in a wrong roll — where the surface fits well,
//! so a vertex's own distance cannot see them. Two per-region signs of such a fit are measured
//! here (`docs/decisions/2026-12-03-confidence-ranking.md`):
//!
//! - [`bone_residuals`]: the RMS point-to-plane residual of the pairs each bone carries, blended
//!   per vertex by its skinning weights ([`blend`]). A bone the rigid fit could not lay on the
//!   scan (another shape, a slid or twisted fit) leaves a wider residual over its whole region.
//! - the disagreement between the fitted pose and the pose the two skeletons alone give
//!   (`|skinned − skeleton-posed|`): where the ICP had to move a region far from where the
//!   joints put it, either the joints or the fit are off, and the map there is less sure.

use nalgebra::{Point3, Vector3};
use symcorr_attach::BoneWeights;
use symcorr_skeleton::Bone;

/// A pair counts for a bone only when its vertex's skinning weight on the bone exceeds this
/// (the ICP's own threshold, module `icp`).
const MIN_PAIR_WEIGHT: f64 = 0.1;
/// A bone with fewer held pairs than this takes the residual of all the held pairs (the ICP
/// does not re-fit such a bone either).
const MIN_BONE_PAIRS: usize = 20;

/// Per bone of [`BONES`](symcorr_skeleton::BONES), the weighted RMS point-to-plane residual
/// `sqrt(Σ w r² / Σ w)`, `r = n_q·(x_v − y_q)`, over the pairs (template vertex `v` → target
/// vertex `q = matches[v].0`) that `held` keeps, each counted for every bone whose weight on
/// `v` exceeds [`MIN_PAIR_WEIGHT`] with that weight. `posed` are the posed template points,
/// `target` the target's positions and unit normals. A bone with fewer than
/// [`MIN_BONE_PAIRS`] pairs takes the residual of all held pairs (0 without any).
pub(super) fn bone_residuals(
    weights: &BoneWeights,
    posed: &[Point3<f64>],
    target: (&[Point3<f64>], &[Vector3<f64>]),
    matches: &[(u32, f64)],
    held: &[bool],
) -> [f64; Bone::COUNT] {
    let (positions, normals) = target;
    // Per bone: Σ w r², Σ w, pairs; and the same over all held pairs.
    let mut sums = [(0.0, 0.0, 0usize); Bone::COUNT];
    let (mut all_r2, mut all_n) = (0.0, 0usize);
    for (v, (&(q, _), _)) in matches
        .iter()
        .zip(held)
        .enumerate()
        .filter(|(_, (_, &h))| h)
    {
        let q = q as usize;
        let r = normals[q].dot(&(posed[v] - positions[q]));
        all_r2 += r * r;
        all_n += 1;
        for &(b, w) in weights.row(v) {
            if w > MIN_PAIR_WEIGHT {
                sums[b].0 += w * r * r;
                sums[b].1 += w;
                sums[b].2 += 1;
            }
        }
    }
    let overall = if all_n > 0 {
        (all_r2 / all_n as f64).sqrt()
    } else {
        0.0
    };
    sums.map(|(r2, w, count)| {
        if count >= MIN_BONE_PAIRS && w > 0.0 {
            (r2 / w).sqrt()
        } else {
            overall
        }
    })
}

/// A per-bone value blended at template vertex `v` by its skinning weights
/// (`Σ_b w_vb x_b / Σ_b w_vb`; 0 for a vertex without weights).
pub(super) fn blend(weights: &BoneWeights, v: usize, per_bone: &[f64; Bone::COUNT]) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for &(b, wb) in weights.row(v) {
        s += wb * per_bone[b];
        w += wb;
    }
    if w > 0.0 {
        s / w
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_attach::testbody::{capsule_body, t_pose};
    use symcorr_attach::{attach, AttachOptions};
    use symcorr_skeleton::{Joint, BONES};

    /// The residual of a bone whose pairs lie off their target planes is that offset; a bone
    /// whose pairs lie on them has none, and the blend follows the skinning weights.
    #[test]
    fn a_bone_laid_off_its_planes_has_the_wider_residual() {
        let sk = t_pose(1.0);
        let (mesh, _) = capsule_body(&sk, 0.03);
        let att = attach(&mesh, &sk, &AttachOptions::default()).expect("capsule body attaches");
        let n = mesh.num_vertices();
        let forearm = BONES
            .iter()
            .position(|b| b.parent == Joint::ElbowLeft)
            .expect("the left forearm is a bone");
        // Target: the template itself, normals along +z everywhere; the posed points of the
        // vertices carried mostly by the left forearm sit 1 cm above their targets.
        let target: Vec<Point3<f64>> = mesh.positions.iter().map(|&p| p.into()).collect();
        let normals = vec![Vector3::z(); n];
        let on_forearm = |v: usize| {
            att.weights
                .row(v)
                .iter()
                .any(|&(b, w)| b == forearm && w > 0.5)
        };
        let posed: Vec<Point3<f64>> = target
            .iter()
            .enumerate()
            .map(|(v, p)| {
                if on_forearm(v) {
                    p + Vector3::z() * 0.01
                } else {
                    *p
                }
            })
            .collect();
        let matches: Vec<(u32, f64)> = (0..n as u32).map(|v| (v, 0.0)).collect();
        let held = vec![true; n];
        let r = bone_residuals(&att.weights, &posed, (&target, &normals), &matches, &held);
        assert!(r[forearm] > 0.005, "forearm residual {}", r[forearm]);
        let spine = BONES
            .iter()
            .position(|b| b.parent == Joint::Spine)
            .expect("the chest is a bone");
        assert!(r[spine] < 1e-12, "chest residual {}", r[spine]);
        // The vertex the chest carries most: its blend stays near the chest's 0.
        let chest_weight = |v: usize| {
            att.weights
                .row(v)
                .iter()
                .filter(|&&(b, _)| b == spine)
                .map(|&(_, w)| w)
                .sum::<f64>()
        };
        let cv = (0..n)
            .max_by(|&u, &v| chest_weight(u).total_cmp(&chest_weight(v)))
            .expect("vertices");
        let fv = (0..n).find(|&v| on_forearm(v)).expect("forearm vertices");
        assert!(blend(&att.weights, fv, &r) > 0.5 * r[forearm]);
        assert!(blend(&att.weights, cv, &r) < 0.1 * r[forearm]);
        // No held pair: every bone takes the overall residual, 0.
        let none = bone_residuals(
            &att.weights,
            &posed,
            (&target, &normals),
            &matches,
            &vec![false; n],
        );
        assert!(none.iter().all(|&x| x == 0.0));
    }
}
