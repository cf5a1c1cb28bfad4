//! Articulated ICP: every bone re-fitted rigidly to the pairs of the vertices it carries,
//! anchored by its two joints, then the template re-skinned (DESIGN.md, Algorithm 7, step 4).

use super::transforms::{kabsch, skin, BoneTransforms, FitPair};
use super::twist::{TwistLimit, TwistPrior};
use super::Alignment;
use crate::CorrespondError;
use nalgebra::{Point3, Vector3};
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
/// target's viewpoint cannot see excluded, re-fits each bone with enough pairs by weighted
/// Kabsch plus its two joints as anchors (held within `limit` for its bone), and re-skins.
/// Visibility is tested as `rounds.occlusion` says. Returns the final posed positions and normals, and the last round's matches (hints for the
/// searches after it).
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
                for j in [BONES[b].parent, BONES[b].child] {
                    pairs.push((
                        template.joints.position(j),
                        target.joints.position(j),
                        options.anchor(b, j) * wsum,
                    ));
                }
                if let Some((pb, extra)) = &prior_pairs {
                    if *pb == b {
                        pairs.extend_from_slice(extra);
                    }
                }
                if let Some(fit) = kabsch(&pairs) {
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
