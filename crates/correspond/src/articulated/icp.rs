//! Articulated ICP: every bone re-fitted rigidly to the pairs of the vertices it carries,
//! anchored by its two joints, then the template re-skinned (DESIGN.md, Algorithm 7, step 4).

use super::transforms::{kabsch, skin, BoneTransforms, FitPair};
use super::twist::{TwistLimit, TwistPrior};
use super::Alignment;
use crate::CorrespondError;
use nalgebra::{IsometryMatrix3, Point3, Rotation3, Translation3, Vector3};
use rayon::prelude::*;
use symcorr_skeleton::{Bone, BONES};

/// Posed template positions and unit normals, and the last round's nearest pool vertices
/// (sampled vertices only; the others `(0, ∞)`).
type Posed = (Vec<Point3<f64>>, Vec<Vector3<f64>>, Vec<(u32, f64)>);

/// A bone is re-fitted only with at least this many pairs.
const MIN_BONE_PAIRS: usize = 20;
/// A vertex pairs for a bone only when its skinning weight on the bone exceeds this.
const MIN_PAIR_WEIGHT: f64 = 0.1;

/// How many ICP rounds, from which gate (a start from the skeletons or from an earlier fit).
#[derive(Debug, Clone, Copy)]
pub(super) struct Rounds {
    /// Rounds.
    pub iterations: usize,
    /// Gate of the first round (√area units); the last one's is `gate_end`.
    pub gate_start: f64,
    /// When the occlusion test runs.
    pub occlusion: OcclusionTest,
    /// About how many target vertices pair with the template the other way round
    /// ([`TargetPairs`](crate::TargetPairs)).
    pub target_points: usize,
    /// Each bone's step is taken this many times ([`over_relaxed`]; 1: as fitted).
    pub relaxation: f64,
}

/// When the ICP rounds test which template vertices the target's viewpoint shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum OcclusionTest {
    /// Every round, on the round's pose: from the skeletons, where the first rounds move
    /// the template by centimetres.
    EveryRound,
    /// Once, on the pose the rounds start from: from a warm start, where the rounds move it
    /// by millimetres and the test costs as much as a round's searches (testing every round
    /// changed neither error nor flips there; from the skeletons it added flips:
    /// docs/decisions/2026-12-03-track-throughput.md).
    Once,
}

/// `rounds` of articulated ICP from `transforms` (updated in place), on the even stride
/// `sample` of the template (per pool group). Each round pairs every sampled posed vertex
/// with its nearest pool vertex, keeps the pairs that hold at the round's gate (shrinking
/// geometrically from the rounds' `gate_start` to `gate_end`), the template vertices the
/// target's viewpoint cannot see excluded, adds the target → template pairs of the round
/// ([`TargetPairs`](crate::TargetPairs), about `rounds.target_points` target vertices each
/// paired with its nearest shown posed template vertex), re-fits each bone with enough pairs
/// by weighted Kabsch plus its two joints as anchors (held within `limit` for its bone), and
/// re-skins. Visibility is tested as `rounds.occlusion` says. Returns the final posed
/// positions and normals, and the last round's matches (hints for the searches after it).
pub(super) fn articulated_icp(
    al: &Alignment<'_>,
    transforms: &mut BoneTransforms,
    sample: &[Vec<u32>],
    rounds: Rounds,
    limit: Option<&TwistLimit>,
    prior: Option<&TwistPrior>,
) -> Result<Posed, CorrespondError> {
    let (template, target, options) = (&al.template, &al.target, al.options);
    let (mut posed, mut posed_normals) =
        skin(template.positions, template.normals, al.weights, transforms);
    let iterations = rounds.iterations.max(1);
    let gate_start = rounds.gate_start.max(options.gate_end);
    let mut last: Option<Vec<(u32, f64)>> = None;
    let mut visible = al.visibility(&posed, &posed_normals);
    let target_pairs = options.target_to_template.filter(|t| t.weight > 0.0);
    let target_sample = if target_pairs.is_some() {
        al.target_sample(rounds.target_points)
    } else {
        Vec::new()
    };
    let mut target_hints = vec![u32::MAX; target_sample.len()];
    for it in 0..iterations {
        if it > 0 && rounds.occlusion == OcclusionTest::EveryRound {
            visible = al.visibility(&posed, &posed_normals);
        }
        let frac = if iterations > 1 {
            it as f64 / (iterations - 1) as f64
        } else {
            1.0
        };
        let gate = al.unit_len * (gate_start * (options.gate_end / gate_start).powf(frac));
        let (near, reverse) = al.candidates_and_reverse(
            &posed,
            &posed_normals,
            Some(sample),
            visible.as_deref(),
            gate,
            last.as_deref(),
        )?;
        let held = al.held(
            &posed,
            &posed_normals,
            &near,
            visible.as_deref(),
            gate,
            reverse.as_ref(),
            true,
        );
        // Pairs per bone: (rest position, target position, weight).
        let mut per_bone: Vec<Vec<FitPair>> = vec![Vec::new(); Bone::COUNT];
        for (v, &(q, _)) in near.iter().enumerate() {
            if !held[v] {
                continue; // not in the sample, hidden, nothing near, or another part's
            }
            let y = al.target_positions[q as usize];
            for &(b, w) in al.weights.row(v) {
                if w > MIN_PAIR_WEIGHT {
                    per_bone[b].push((al.template_positions[v], y, w));
                }
            }
        }
        if let Some(share) = target_pairs.map(|t| t.weight) {
            // The reciprocal check's tree is this pose's shown template; without the check,
            // one of its own.
            let own;
            let shown = match &reverse {
                Some(r) => &r.tree,
                None => {
                    own = al.shown_tree(&posed, &posed_normals, visible.as_deref());
                    &own
                }
            };
            let back = al.target_pairs(
                shown,
                &posed,
                &posed_normals,
                visible.as_deref(),
                &target_sample,
                &mut target_hints,
                gate,
            );
            add_target_pairs(
                &mut per_bone,
                &back,
                |v| al.weights.row(v),
                (&al.template_positions, &al.target_positions),
                share,
            );
        }
        // The prior's pairs from this round's pose, before the bones move.
        let prior_pairs = prior.map(|pr| {
            let wsum: f64 = per_bone[pr.bone].iter().map(|p| p.2).sum();
            (pr.bone, pr.pairs(transforms, wsum))
        });
        transforms
            .par_iter_mut()
            .zip(per_bone.into_par_iter())
            .enumerate()
            .for_each(|(b, (tr, mut pairs))| {
                if pairs.len() < MIN_BONE_PAIRS {
                    return;
                }
                let wsum: f64 = pairs.iter().map(|p| p.2).sum();
                // The skeleton anchors the fit: both joints of the bone pulled to the
                // target's joints.
                // Not at a joint the target's skeleton lost (placed, not seen).
                for j in [BONES[b].parent, BONES[b].child] {
                    if target.joints.tracks(j) {
                        pairs.push((
                            template.joints.position(j),
                            target.joints.position(j),
                            options.anchor(b, j) * wsum,
                        ));
                    }
                }
                if let Some((pb, extra)) = &prior_pairs {
                    if *pb == b {
                        pairs.extend_from_slice(extra);
                    }
                }
                if let Some(fit) = kabsch(&pairs) {
                    let fit = if rounds.relaxation == 1.0 {
                        fit
                    } else {
                        over_relaxed(tr, &fit, &pairs, rounds.relaxation)
                    };
                    *tr = match limit {
                        Some(l) if l.bone == b => l.apply(fit),
                        _ => fit,
                    };
                }
            });
        (posed, posed_normals) = skin(template.positions, template.normals, al.weights, transforms);
        last = Some(near);
    }
    let last = last.unwrap_or_else(|| vec![(0, f64::INFINITY); posed.len()]);
    Ok((posed, posed_normals, last))
}

/// The step of a bone's fit from `old` to `new`, taken `alpha` times: the step's rotation
/// vector and its translation of the pairs' centroid (posed by `old`, weighted) scaled by
/// `alpha`, about that centroid. ICP from a nearby pose converges linearly (each warm round of
/// a recording moved the template about 0.6 as far as the round before): for a linear
/// contraction of rate ρ ∈ [0, 1) the over-relaxed step contracts by |1 − α(1 − ρ)|, faster for
/// any 1 < α < 2 and still convergent where ρ = 0; a converged bone (`new` = `old`) stays.
/// (Successive over-relaxation; Besl & McKay 1992 extrapolate ICP's steps to the same end.)
fn over_relaxed(
    old: &IsometryMatrix3<f64>,
    new: &IsometryMatrix3<f64>,
    pairs: &[FitPair],
    alpha: f64,
) -> IsometryMatrix3<f64> {
    let (mut c, mut wsum) = (Vector3::zeros(), 0.0);
    for &(x, _, w) in pairs {
        c += (old * x).coords * w;
        wsum += w;
    }
    if wsum <= 0.0 {
        return *new;
    }
    let c = c / wsum;
    let step = new * old.inverse();
    let rotation = Rotation3::new(step.rotation.scaled_axis() * alpha);
    let shift = (step * Point3::from(c)).coords - c;
    // p ↦ rotation (p − c) + c + α·shift.
    let relaxed = IsometryMatrix3::from_parts(
        Translation3::from(c + shift * alpha - rotation * c),
        rotation,
    );
    relaxed * old
}

/// Adds the target → template pairs `back` (`(target vertex, template vertex)`,
/// [`ArticulatedOptions::target_to_template`](crate::ArticulatedOptions)) to the bones' pairs
/// `per_bone` as the template → target pairs are: per bone carrying the template vertex with a
/// skinning weight above [`MIN_PAIR_WEIGHT`] (`row`: a vertex's `(bone, weight)` entries), the
/// vertex's rest position, the target position and the weight — all scaled so that their total
/// weight is `share` times the total already in `per_bone`. `points`: the template's rest
/// positions and the target's positions.
fn add_target_pairs<'w>(
    per_bone: &mut [Vec<FitPair>],
    back: &[(u32, u32)],
    row: impl Fn(usize) -> &'w [(usize, f64)],
    points: (&[Point3<f64>], &[Point3<f64>]),
    share: f64,
) {
    let (rest, target) = points;
    let forward: f64 = per_bone.iter().flatten().map(|p| p.2).sum();
    let mut added: Vec<Vec<FitPair>> = vec![Vec::new(); per_bone.len()];
    for &(q, v) in back {
        for &(b, w) in row(v as usize) {
            if w > MIN_PAIR_WEIGHT {
                added[b].push((rest[v as usize], target[q as usize], w));
            }
        }
    }
    let total: f64 = added.iter().flatten().map(|p| p.2).sum();
    // Zero-weight pairs would still count towards a bone's MIN_BONE_PAIRS.
    if total <= 0.0 || forward <= 0.0 {
        return;
    }
    let scale = share * forward / total;
    for (pairs, extra) in per_bone.iter_mut().zip(added) {
        pairs.extend(extra.into_iter().map(|(x, y, w)| (x, y, w * scale)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn an_over_relaxed_step_goes_alpha_times_as_far_about_the_centroid() {
        let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
        let pairs: Vec<FitPair> = [p(1.0, 0.0, 0.0), p(-1.0, 0.0, 0.0), p(0.0, 2.0, 0.0)]
            .into_iter()
            .map(|x| (x, x, 1.0))
            .collect();
        let old = IsometryMatrix3::from_parts(
            Translation3::new(0.5, -0.2, 0.1),
            Rotation3::new(Vector3::new(0.1, 0.2, -0.3)),
        );
        // A step of 0.05 rad about z through the posed centroid, and a shift of 1 cm.
        let c = old * Point3::new(0.0, 2.0 / 3.0, 0.0);
        let turn = |a: f64, s: f64| {
            let r = Rotation3::new(Vector3::new(0.0, 0.0, a));
            IsometryMatrix3::from_parts(
                Translation3::from(c.coords - r * c.coords + Vector3::new(s, 0.0, 0.0)),
                r,
            )
        };
        let new = turn(0.05, 0.01) * old;
        let relaxed = over_relaxed(&old, &new, &pairs, 1.5);
        let expected = turn(0.075, 0.015) * old;
        for &(x, _, _) in &pairs {
            assert_relative_eq!(relaxed * x, expected * x, epsilon = 1e-12);
        }
        // α = 1 is the fitted step; a converged bone stays where it is.
        assert_relative_eq!(
            over_relaxed(&old, &new, &pairs, 1.0) * pairs[2].0,
            new * pairs[2].0,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            over_relaxed(&old, &old, &pairs, 1.5) * pairs[0].0,
            old * pairs[0].0,
            epsilon = 1e-12
        );
    }

    #[test]
    fn target_pairs_join_their_bones_scaled_to_the_share() {
        let p = |x: f64| Point3::new(x, 0.0, 0.0);
        let rest = [p(0.0), p(1.0), p(2.0)];
        let target = [p(10.0), p(11.0)];
        // Vertex 0 on bone 0; vertex 1 split 0.5/0.5 over bones 0 and 1; vertex 2 on bone 1
        // with a weight too small to pair (0.05) and on bone 2.
        let rows: [&[(usize, f64)]; 3] =
            [&[(0, 1.0)], &[(0, 0.5), (1, 0.5)], &[(1, 0.05), (2, 0.95)]];
        let mut per_bone: Vec<Vec<FitPair>> = vec![vec![(p(0.0), p(5.0), 3.0)], vec![], vec![]];
        // Target 0 pairs with vertex 1, target 1 with vertex 2.
        add_target_pairs(
            &mut per_bone,
            &[(0, 1), (1, 2)],
            |v| rows[v],
            (&rest, &target),
            2.0,
        );
        // Added weight before scaling: 0.5 + 0.5 + 0.95 = 1.95; scaled to 2 × 3 = 6.
        let s = 6.0 / 1.95;
        assert_eq!(per_bone[0].len(), 2);
        assert_eq!(per_bone[0][1].0, rest[1]);
        assert_eq!(per_bone[0][1].1, target[0]);
        assert_relative_eq!(per_bone[0][1].2, 0.5 * s, epsilon = 1e-12);
        assert_eq!(per_bone[1].len(), 1); // vertex 2's 0.05 on bone 1 does not pair
        assert_relative_eq!(per_bone[1][0].2, 0.5 * s, epsilon = 1e-12);
        assert_eq!((per_bone[2][0].0, per_bone[2][0].1), (rest[2], target[1]));
        let added: f64 = per_bone.iter().flatten().skip(1).map(|x| x.2).sum();
        assert_relative_eq!(added, 6.0, epsilon = 1e-12);
        // Without template → target pairs there is nothing to scale against: nothing is added.
        let mut empty: Vec<Vec<FitPair>> = vec![vec![]; 3];
        add_target_pairs(&mut empty, &[(0, 1)], |v| rows[v], (&rest, &target), 1.0);
        assert!(empty.iter().all(Vec::is_empty));
    }
}
