//! The head twist search of the articulated method: the joints fix a bone's direction, not
//! its roll, and a roughly round head can sit in a wrong roll that nearest-neighbour ICP does
//! not leave, so the head bone is started at several twists and the best start wins.

use super::transforms::{isometry, kabsch, unit, FitPair};
use super::Alignment;
use crate::kdtree::KdTree;
use crate::CorrespondError;
use nalgebra::{IsometryMatrix3, Point3, Rotation3, Unit, UnitQuaternion, Vector3};
use symcorr_skeleton::{Segment, Skeleton, BONES};

/// Largest twist of the head about its bone against the pose the chest gives it, degrees.
/// A neck turns about ±80° (range of motion of cervical rotation); every fit of the head —
/// the starts of the twist search, their ICP steps and the articulated ICP's rounds — is held
/// within it. Seen in profile, a head's back fits the visible side about as well as its face,
/// and unconstrained ICP steps turned whole heads round (mirrored ears and cheeks).
pub const MAX_HEAD_TWIST_DEG: f64 = 90.0;

/// A bone whose twist about its target axis is held within ±`max` of a reference pose.
#[derive(Debug, Clone, Copy)]
pub(super) struct TwistLimit {
    /// The bone (index into [`BONES`]).
    pub bone: usize,
    /// The reference pose (template frame → target frame).
    reference: IsometryMatrix3<f64>,
    /// The target bone's unit axis, parent → child joint.
    axis: Unit<Vector3<f64>>,
    /// The bone's parent joint in the template frame: kept where a fit puts it.
    pivot: Point3<f64>,
    /// Largest twist, radians.
    max: f64,
}

impl TwistLimit {
    /// The limit of bone `b` around `reference`; `None` when the target bone has no length.
    pub fn new(
        al: &Alignment<'_>,
        b: usize,
        reference: IsometryMatrix3<f64>,
        max_deg: f64,
    ) -> Option<TwistLimit> {
        let (p, c) = (BONES[b].parent, BONES[b].child);
        let axis = unit(al.target.joints.position(c) - al.target.joints.position(p))?;
        Some(TwistLimit {
            bone: b,
            reference,
            axis: Unit::new_unchecked(axis),
            pivot: al.template.joints.position(p),
            max: max_deg.to_radians(),
        })
    }

    /// `fit` with its twist against the reference clamped to ±max (swing–twist decomposition of
    /// the relative rotation about the target axis); the parent joint stays where `fit` puts it.
    pub fn apply(&self, fit: IsometryMatrix3<f64>) -> IsometryMatrix3<f64> {
        let relative = fit.rotation * self.reference.rotation.inverse();
        let q = UnitQuaternion::from_rotation_matrix(&relative);
        // q = swing · twist, twist = (w, (v·a) a) normalised: angle 2·atan2(v·a, w).
        let along = q.imag().dot(&self.axis);
        let mut angle = 2.0 * along.atan2(q.w);
        if angle > std::f64::consts::PI {
            angle -= std::f64::consts::TAU;
        } else if angle < -std::f64::consts::PI {
            angle += std::f64::consts::TAU;
        }
        if angle.abs() <= self.max {
            return fit;
        }
        let twist = UnitQuaternion::from_axis_angle(&self.axis, angle);
        let swing = q * twist.inverse();
        let held = swing * UnitQuaternion::from_axis_angle(&self.axis, self.max.copysign(angle));
        let r = held.to_rotation_matrix() * self.reference.rotation;
        let x = fit * self.pivot;
        isometry(*r.matrix(), x.coords - r * self.pivot.coords)
    }
}

/// A soft hold on a bone's twist against its parent bone's fitted pose: the bone keeps the
/// rotation it has in its parent's frame at rest unless its pairs say otherwise. A round
/// head's visible side does not pin its twist — seen turning into profile, the fitted head
/// lagged the body by 12–25° and its far eye socket paired across the nose; a head turns
/// with the chest unless the neck turns it. `docs/decisions/2026-12-03-head-twist-prior.md`.
#[derive(Debug, Clone, Copy)]
pub(super) struct TwistPrior {
    /// The bone (index into [`BONES`]).
    pub bone: usize,
    /// Its parent bone (the one ending at its parent joint).
    parent: usize,
    /// The bone's unit direction at rest (template), parent → child joint.
    template_axis: Vector3<f64>,
    /// The bone's midpoint at rest.
    mid: Point3<f64>,
    /// Four template-frame offsets from `mid`, normal to the bone, one bone length long.
    offsets: [Vector3<f64>; 4],
    /// The weight of each of the four prior pairs, relative to the bone's total pair weight.
    weight: f64,
    /// The turn (radians, right-handed about the bone) the bone is held at against its parent,
    /// beyond the template's own: 0 for the template's rest relation.
    turn: f64,
}

impl TwistPrior {
    /// The prior of bone `b` of the `template` skeleton (at rest) with `weight`
    /// ([`ArticulatedOptions::head_twist_prior`](super::ArticulatedOptions::head_twist_prior)),
    /// holding the bone turned by `turn` radians about itself against the template's own
    /// relation to its parent (0: that relation;
    /// [`ArticulatedOptions::head_turn_prior`](super::ArticulatedOptions::head_turn_prior): the
    /// turn the target's tracker reports less the template's); `None` for a bone without a
    /// parent bone or without length.
    pub fn new(template: &Skeleton, b: usize, weight: f64, turn: f64) -> Option<TwistPrior> {
        let (p, c) = (BONES[b].parent, BONES[b].child);
        let parent = BONES.iter().position(|pb| pb.child == p)?;
        let (tp, tc) = (template.position(p), template.position(c));
        let template_axis = unit(tc - tp)?;
        let helper = if template_axis.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = unit(template_axis.cross(&helper))? * (tc - tp).norm();
        let e2 = template_axis.cross(&e1);
        Some(TwistPrior {
            bone: b,
            parent,
            template_axis,
            mid: Point3::from((tp.coords + tc.coords) * 0.5),
            offsets: [e1, -e1, e2, -e2],
            weight: weight / 4.0,
            turn,
        })
    }

    /// The prior's four pairs for the bone's weighted rigid fit in `transforms` (the round's
    /// current pose), `pair_weight` the bone's total pair weight: the offsets from the bone's
    /// midpoint, each pulled to where the parent's current rotation, swung onto the bone's
    /// current direction and turned by the prior's turn about it, carries it about the bone's
    /// current midpoint. Centred on the midpoint and keeping the bone's direction, they act on
    /// its twist alone; the swing is left to the pairs and the joint anchors.
    pub fn pairs(
        &self,
        transforms: &super::transforms::BoneTransforms,
        pair_weight: f64,
    ) -> [super::transforms::FitPair; 4] {
        let parent = transforms[self.parent].rotation.matrix();
        // The bone's current direction: the prior holds the twist about it, not the swing.
        let current = transforms[self.bone].rotation.matrix() * self.template_axis;
        let r = super::transforms::swing(parent * self.template_axis, current) * parent;
        let r = Rotation3::from_axis_angle(&Unit::new_normalize(current), self.turn) * r;
        let mid = transforms[self.bone] * self.mid;
        let w = self.weight * pair_weight;
        self.offsets.map(|d| (self.mid + d, mid + r * d, w))
    }
}

/// A bone's own points of a single-view target — the target vertices labelled with the bone's
/// segment — and the template vertices mostly on the bone (weight > 0.5): the bone's pose is
/// fitted and scored scan → template, every own point paired with its nearest posed vertex.
///
/// One view of a round head barely pins its twist template → scan: the points of the template
/// it turns away still find scan points (the face's side on the cheek), and the nearest-point
/// pairs of a noisy sensor's face hold any twist within ±30° about equally. Scan → template,
/// the face the scan shows must be explained by the posed head: on a head turned 43° against
/// its fit the mean squared distance was 1.1·10⁻⁴ m² at the true pose against 2.0·10⁻⁴ at the
/// fit (1.2–1.6·10⁻⁴ at ±8°, 3–7·10⁻⁴ at ±30°), while template → scan preferred a pose 15° off
/// the truth (`docs/decisions/2026-12-05-head-warm-twist.md`).
#[derive(Debug, Clone)]
pub(super) struct OwnPoints {
    /// The bone (index into [`BONES`]).
    pub bone: usize,
    /// The template vertices mostly on the bone, at rest: a pose is rigid, so the posed vertex
    /// nearest a target point is the rest vertex nearest the point moved back by the pose.
    tree: KdTree<3>,
    /// Target vertices labelled with the bone's segment (an even sample of at most
    /// [`TWIST_POINTS`]).
    target: Vec<usize>,
}

impl OwnPoints {
    /// The own points of bone `b`; `None` when the target has no viewpoint (a whole surface
    /// pins a head's twist template → target), when `b` carries no segment of its own, when
    /// the target has fewer than [`MIN_OWN_POINTS`] own points or the template fewer than
    /// [`MIN_TWIST_VERTICES`] vertices mostly on the bone.
    pub fn new(al: &Alignment<'_>, b: usize) -> Option<OwnPoints> {
        al.target.viewpoint?;
        let segment = Segment::ALL
            .into_iter()
            .find(|s| s.bones().contains(&BONES[b]))?;
        let target: Vec<usize> = (0..al.target_positions.len())
            .filter(|&q| al.target.labels.get(q) == Some(&segment))
            .collect();
        let template = mostly_on_bone(al, b);
        if target.len() < MIN_OWN_POINTS || template.len() < MIN_TWIST_VERTICES {
            return None;
        }
        let target = even_sample(target, TWIST_POINTS);
        let rest = template
            .iter()
            .map(|&v| al.template_positions[v as usize].coords.into())
            .collect();
        Some(OwnPoints {
            bone: b,
            tree: KdTree::new(rest, template),
            target,
        })
    }

    /// Each own point's squared distance to the bone posed by `pose` (its nearest posed
    /// vertex), at most `gate²`: the terms of [`OwnPoints::pairs`]' score, one per point.
    fn squared_distances(
        &self,
        al: &Alignment<'_>,
        pose: &IsometryMatrix3<f64>,
        gate: f64,
    ) -> Vec<f64> {
        let back = pose.inverse();
        self.target
            .iter()
            .map(|&q| {
                let y = back * al.target_positions[q];
                self.tree
                    .nearest_within(&y.coords.into(), (u32::MAX, gate * gate))
                    .map_or(gate * gate, |(_, d)| d)
            })
            .collect()
    }

    /// Every own target point within `gate` of the bone posed by `pose` paired with its
    /// nearest posed template vertex, as (rest position, target position, weight 1), and the
    /// mean squared distance of all own points to the posed bone, each at most `gate²`
    /// (positions only: a sensor's normals are too noisy to score a twist by).
    ///
    /// `hints` (one per own point, `u32::MAX` for none) hold each point's vertex of an earlier
    /// call and are updated: a pose a step away has its nearest vertex near the last one, so
    /// the search starts from it (the same answer, found sooner).
    pub fn pairs(
        &self,
        al: &Alignment<'_>,
        pose: &IsometryMatrix3<f64>,
        gate: f64,
        hints: &mut [u32],
    ) -> (Vec<FitPair>, f64) {
        let back = pose.inverse();
        let mut pairs = Vec::with_capacity(self.target.len());
        let mut total = 0.0;
        for (&q, hint) in self.target.iter().zip(hints.iter_mut()) {
            let y = back * al.target_positions[q];
            let start = al
                .template_positions
                .get(*hint as usize)
                .map(|x| (x - y).norm_squared())
                .filter(|&d| d <= gate * gate)
                .map_or((u32::MAX, gate * gate), |d| (*hint, d));
            match self.tree.nearest_within(&y.coords.into(), start) {
                Some((v, d)) => {
                    *hint = v;
                    total += d;
                    pairs.push((
                        al.template_positions[v as usize],
                        al.target_positions[q],
                        1.0,
                    ));
                }
                None => total += gate * gate,
            }
        }
        (pairs, total / self.target.len() as f64)
    }
}

/// Every `⌈len / at_most⌉`-th item of `items`, from the first: at most `at_most` of them.
fn even_sample<T: Copy>(items: Vec<T>, at_most: usize) -> Vec<T> {
    let stride = items.len().div_ceil(at_most.max(1)).max(1);
    items.into_iter().step_by(stride).collect()
}

/// Starting twists of the head twist search of [`articulated_match`](crate::articulated_match),
/// in degrees: within a head's range of rotation against the chest (about ±80°; the starting
/// pose is the chest's). Wider starts let a head whose back fits about as well as its face
/// turn round: with σ = 3 cm joints, ±180° flipped whole heads in 13 of 58 pairs.
pub const TWISTS: [f64; 7] = [0.0, 30.0, 60.0, 90.0, -30.0, -60.0, -90.0];
/// Starting twists of the warm twist search (after the ICP rounds from an earlier fit), in
/// degrees around the rounds' pose: a head turns by a few degrees between frames, and a
/// fit that lagged a turn by tens of degrees catches up in one or two frames.
pub const WARM_TWISTS: [f64; 5] = [0.0, 15.0, -15.0, 30.0, -30.0];

/// How [`twist_search`] pairs and scores a pose of the bone, and which start it keeps.
#[derive(Debug, Clone, Copy)]
pub(super) enum TwistScore<'o> {
    /// From the skeletons: an even sample of the vertices mostly on the bone (weight > 0.5)
    /// paired with their nearest pool vertices, scored by the mean truncated squared distance
    /// (position and normal, the search's own metric); the best start wins.
    TemplateToTarget,
    /// After the ICP rounds from an earlier fit: scan → template with the bone's own points
    /// ([`OwnPoints::pairs`]); a turned start wins only when its score is below `gain` times
    /// the unturned start's
    /// ([`ArticulatedOptions::head_warm_twist`](super::ArticulatedOptions::head_warm_twist)).
    OwnPoints {
        /// The bone's own points.
        own: &'o OwnPoints,
        /// Largest share of the unturned start's score a turned start may keep.
        gain: f64,
    },
}

/// At most this many vertices of the bone score each start of [`twist_search`].
const TWIST_POINTS: usize = 600;
/// Rigid ICP steps per start of [`twist_search`].
const TWIST_ICP_STEPS: usize = 4;
/// A target with fewer own points of the bone's segment has no [`OwnPoints`]: a head seen at
/// 2 cm per pixel (160 pixels across, 3 m away: about 110 points) does not pin its twist, and
/// the warm search turned such heads wrongly (7 → 23 flips on a 160×240 recording); at 320×240
/// and 2.5 m a head shows about 650.
const MIN_OWN_POINTS: usize = 200;
/// A bone with fewer vertices mostly on it keeps its initial transform.
const MIN_TWIST_VERTICES: usize = 20;

/// The best twist of bone `b` about its target axis. Starting from `initial` turned by each
/// of `twists` (degrees) about the target bone (axis through its parent joint), a few rigid
/// ICP steps scored as `score` says; every ICP step is held within `limit` (of bone `b`,
/// around `initial`). With [`TwistScore::TemplateToTarget`] the best start wins (the first on
/// a tie); with [`TwistScore::OwnPoints`] a turned start wins only when it explains the
/// bone's own points clearly better than the unturned one, and otherwise `initial` is kept
/// as it was.
pub(super) fn twist_search(
    al: &Alignment<'_>,
    b: usize,
    initial: IsometryMatrix3<f64>,
    limit: Option<&TwistLimit>,
    twists: &[f64],
    score: TwistScore<'_>,
) -> Result<IsometryMatrix3<f64>, CorrespondError> {
    let (template, target, options) = (&al.template, &al.target, al.options);
    let pairing = match score {
        TwistScore::TemplateToTarget => match Sample::new(al, b) {
            Some(sample) => Pairing::Sample(sample),
            None => return Ok(initial),
        },
        TwistScore::OwnPoints { own, .. } => Pairing::Own(own),
    };
    let (p, c) = (BONES[b].parent, BONES[b].child);
    let pivot = target.joints.position(p);
    let Some(axis) = unit(target.joints.position(c) - pivot) else {
        return Ok(initial);
    };
    let gate = options.gate_start * template.area.sqrt();
    let fit = |start| refit(al, &pairing, b, start, limit, gate);
    let mut best = fit(initial)?;
    let unturned = best.1;
    let axis = Unit::new_unchecked(axis);
    for &deg in twists.iter().filter(|&&d| d != 0.0) {
        // The start turned about the target bone's axis through its parent joint.
        let candidate = fit(turned_about(&initial, &axis, &pivot, deg))?;
        if candidate.1 < best.1 {
            best = candidate;
        }
    }
    match score {
        TwistScore::OwnPoints { gain, .. } if best.1 > gain * unturned => Ok(initial),
        _ => Ok(best.0),
    }
}

/// `start` refined by [`TWIST_ICP_STEPS`] rigid ICP steps of bone `b` paired as `pairing`
/// says, each held within `limit`; the refined pose and its score.
fn refit(
    al: &Alignment<'_>,
    pairing: &Pairing<'_>,
    b: usize,
    start: IsometryMatrix3<f64>,
    limit: Option<&TwistLimit>,
    gate: f64,
) -> Result<(IsometryMatrix3<f64>, f64), CorrespondError> {
    let (template, target, options) = (&al.template, &al.target, al.options);
    let (p, c) = (BONES[b].parent, BONES[b].child);
    let mut tr = start;
    let mut score = f64::INFINITY;
    let mut hints = match pairing {
        Pairing::Own(own) => vec![u32::MAX; own.target.len()],
        Pairing::Sample(_) => Vec::new(),
    };
    for step in 0..=TWIST_ICP_STEPS {
        let (mut pairs, s) = match pairing {
            Pairing::Own(own) => own.pairs(al, &tr, gate, &mut hints),
            Pairing::Sample(sample) => sample.pairs(al, &tr, gate)?,
        };
        score = s;
        if step == TWIST_ICP_STEPS {
            break;
        }
        let held = pairs.len() as f64;
        for j in [p, c].into_iter().filter(|&j| target.joints.tracks(j)) {
            pairs.push((
                template.joints.position(j),
                target.joints.position(j),
                options.anchor(b, j) * held,
            ));
        }
        match kabsch(&pairs) {
            Some(t) => tr = limit.map_or(t, |l| l.apply(t)),
            None => break,
        }
    }
    Ok((tr, score))
}

/// How strongly the scan says that bone `b`, fitted at `pose`, should be turned: the starts
/// of [`twist_search`] (`pose` turned by each of `twists` about the target bone, refined
/// scan → template on `own`'s points) against `pose` refined the same way, each compared
/// point by point (the paired differences of the own points' squared distances, each at most
/// the search gate²). The answer is the largest number of standard errors by which a turned
/// start's mean difference lies below zero; 0 when none does, or when the bone has no
/// length. The fit does not move.
///
/// A single view barely pins a head's twist: a wrong turn scores within a percent or two of
/// the right one, so the search's pick is not kept from the skeletons
/// (`docs/decisions/2026-12-06-cold-head-twist-scan-to-template.md`); how far a turned head
/// explains the scan's head better, measured against the points' own scatter, says how much
/// to doubt the fitted head's matches.
pub(super) fn twist_doubt(
    al: &Alignment<'_>,
    own: &OwnPoints,
    pose: IsometryMatrix3<f64>,
    limit: Option<&TwistLimit>,
    twists: &[f64],
) -> Result<f64, CorrespondError> {
    let b = own.bone;
    let pivot = al.target.joints.position(BONES[b].parent);
    let Some(axis) = unit(al.target.joints.position(BONES[b].child) - pivot) else {
        return Ok(0.0);
    };
    let gate = al.options.gate_start * al.template.area.sqrt();
    let pairing = Pairing::Own(own);
    let (unturned, _) = refit(al, &pairing, b, pose, limit, gate)?;
    let base = own.squared_distances(al, &unturned, gate);
    let axis = Unit::new_unchecked(axis);
    let mut doubt: f64 = 0.0;
    for &deg in twists.iter().filter(|&&d| d != 0.0) {
        let (turned, _) = refit(
            al,
            &pairing,
            b,
            turned_about(&pose, &axis, &pivot, deg),
            limit,
            gate,
        )?;
        let diffs: Vec<f64> = own
            .squared_distances(al, &turned, gate)
            .iter()
            .zip(&base)
            .map(|(t, u)| t - u)
            .collect();
        let n = diffs.len() as f64;
        if n < 2.0 {
            continue;
        }
        let mean = diffs.iter().sum::<f64>() / n;
        let variance = diffs.iter().map(|d| (d - mean) * (d - mean)).sum::<f64>() / (n - 1.0);
        let standard_error = (variance / n).sqrt();
        if standard_error > 0.0 {
            doubt = doubt.max(-mean / standard_error);
        }
    }
    Ok(doubt)
}

/// `pose` turned by `deg` degrees about `axis` through `pivot` (target frame).
fn turned_about(
    pose: &IsometryMatrix3<f64>,
    axis: &Unit<Vector3<f64>>,
    pivot: &Point3<f64>,
    deg: f64,
) -> IsometryMatrix3<f64> {
    let r = *Rotation3::from_axis_angle(axis, deg.to_radians()).matrix();
    let t = r * (pose.translation.vector - pivot.coords) + pivot.coords;
    isometry(r * pose.rotation.matrix(), t)
}

/// How [`twist_search`] pairs a pose of the bone: what its [`TwistScore`] needs, built once
/// per search.
enum Pairing<'o> {
    /// [`TwistScore::TemplateToTarget`].
    Sample(Sample),
    /// [`TwistScore::OwnPoints`].
    Own(&'o OwnPoints),
}

/// The template → target pairing of [`TwistScore::TemplateToTarget`]: an even sample of the
/// template vertices mostly on the bone and the pool members each may pair with.
struct Sample {
    /// The sampled template vertices.
    vertices: Vec<u32>,
    /// Per pool, its members among `vertices`.
    subset: Vec<Vec<u32>>,
}

impl Sample {
    /// An even sample of at most [`TWIST_POINTS`] of bone `b`'s vertices (enough to score a
    /// rigid pose); `None` when it has fewer than [`MIN_TWIST_VERTICES`].
    fn new(al: &Alignment<'_>, b: usize) -> Option<Sample> {
        let vertices = even_sample(mostly_on_bone(al, b), TWIST_POINTS);
        if vertices.len() < MIN_TWIST_VERTICES {
            return None;
        }
        let mut sampled = vec![false; al.template_positions.len()];
        for &v in &vertices {
            sampled[v as usize] = true;
        }
        let subset = al.pools.members_where(|v| sampled[v as usize]);
        Some(Sample { vertices, subset })
    }

    /// Every sampled vertex, posed by `pose`, paired with its nearest pool vertex in the
    /// search's own metric (position and normal) when within `gate`, as (rest position,
    /// target position, weight 1); and the mean of those squared feature distances, each at
    /// most `gate²`.
    fn pairs(
        &self,
        al: &Alignment<'_>,
        pose: &IsometryMatrix3<f64>,
        gate: f64,
    ) -> Result<(Vec<FitPair>, f64), CorrespondError> {
        let mut f = vec![[0.0; 6]; al.template_positions.len()];
        for &v in &self.vertices {
            let v = v as usize;
            f[v] = al.feature(
                &(pose * al.template_positions[v]),
                &(pose.rotation * al.template_normals[v]),
            );
        }
        let near = al
            .trees
            .nearest(al.pools, &f, Some(&self.subset), None, f64::INFINITY)?;
        let mut pairs = Vec::new();
        let mut total = 0.0;
        for &v in &self.vertices {
            let v = v as usize;
            let x = pose * al.template_positions[v];
            let y = al.target_positions[near[v].0 as usize];
            total += near[v].1.min(gate * gate);
            if (x - y).norm() <= gate {
                pairs.push((al.template_positions[v], y, 1.0));
            }
        }
        Ok((pairs, total / self.vertices.len() as f64))
    }
}

/// The template vertices mostly on bone `b` (skinning weight > 0.5), ascending.
fn mostly_on_bone(al: &Alignment<'_>, b: usize) -> Vec<u32> {
    (0..al.template_positions.len() as u32)
        .filter(|&v| {
            al.weights
                .row(v as usize)
                .iter()
                .any(|&(bb, w)| bb == b && w > 0.5)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::transforms::{bone_transforms, kabsch};
    use super::*;
    use symcorr_skeleton::{Bone, Joint};

    /// The prior's pairs alone fit the head to its rest pose against the chest: a whole body
    /// turned by 70° about the vertical with the head left facing the camera (the lag the
    /// prior is for) gets its head turned by the same 70°.
    #[test]
    fn the_prior_alone_turns_the_head_with_the_chest() {
        let rest = symcorr_attach::testbody::t_pose(1.0);
        let turn = Rotation3::from_axis_angle(&Vector3::y_axis(), 70f64.to_radians());
        let turned = rest.map_positions(|x| turn * x);
        let h = super::super::head_bone();
        let prior = TwistPrior::new(&rest, h, 1.0, 0.0).unwrap();
        let mut transforms = bone_transforms(&rest, &turned);
        let chest = transforms[prior.parent].rotation;
        approx::assert_relative_eq!(chest.matrix(), turn.matrix(), epsilon = 1e-9);
        // The head lags: still at rest, moved only onto the target's neck.
        transforms[h] = IsometryMatrix3::from_parts(
            nalgebra::Translation3::from(
                turn * rest.position(Joint::ShoulderCenter).coords
                    - rest.position(Joint::ShoulderCenter).coords,
            ),
            Rotation3::identity(),
        );
        let fit = kabsch(&prior.pairs(&transforms, 10.0)).unwrap();
        approx::assert_relative_eq!(fit.rotation.matrix(), turn.matrix(), epsilon = 1e-9);
        // Centred on the bone's midpoint: the head's midpoint stays where it was.
        approx::assert_relative_eq!(fit * prior.mid, transforms[h] * prior.mid, epsilon = 1e-9);
    }

    /// A head tilted and twisted against the chest keeps its tilt and loses its twist: the
    /// prior holds the twist, not the swing.
    #[test]
    fn the_prior_holds_the_twist_not_the_tilt() {
        let rest = symcorr_attach::testbody::t_pose(1.0);
        let h = super::super::head_bone();
        let prior = TwistPrior::new(&rest, h, 1.0, 0.0).unwrap();
        let tilt = Rotation3::from_axis_angle(&Vector3::z_axis(), 25f64.to_radians());
        let axis = nalgebra::Unit::new_normalize(prior.template_axis);
        let twist = Rotation3::from_axis_angle(&axis, 40f64.to_radians());
        let mut transforms = [IsometryMatrix3::identity(); Bone::COUNT];
        transforms[h] =
            IsometryMatrix3::from_parts(nalgebra::Translation3::identity(), tilt * twist);
        let fit = kabsch(&prior.pairs(&transforms, 1.0)).unwrap();
        approx::assert_relative_eq!(fit.rotation.matrix(), tilt.matrix(), epsilon = 1e-9);
    }

    /// With a turn (a log that reports the head turned 35° against the chest), the prior's
    /// pairs alone turn a head left at the chest's twist by those 35° about its bone, right-
    /// handed, tilt and all.
    #[test]
    fn the_prior_holds_a_reported_turn() {
        let rest = symcorr_attach::testbody::t_pose(1.0);
        let h = super::super::head_bone();
        let turn = 35f64.to_radians();
        let prior = TwistPrior::new(&rest, h, 1.0, turn).unwrap();
        let tilt = Rotation3::from_axis_angle(&Vector3::z_axis(), 10f64.to_radians());
        let mut transforms = [IsometryMatrix3::identity(); Bone::COUNT];
        transforms[h] = IsometryMatrix3::from_parts(nalgebra::Translation3::identity(), tilt);
        let fit = kabsch(&prior.pairs(&transforms, 1.0)).unwrap();
        let about = nalgebra::Unit::new_normalize(tilt * prior.template_axis);
        let expected = Rotation3::from_axis_angle(&about, turn) * tilt;
        approx::assert_relative_eq!(fit.rotation.matrix(), expected.matrix(), epsilon = 1e-9);
        // No turn: the prior of before.
        let plain = TwistPrior::new(&rest, h, 1.0, 0.0).unwrap();
        let fit = kabsch(&plain.pairs(&transforms, 1.0)).unwrap();
        approx::assert_relative_eq!(fit.rotation.matrix(), tilt.matrix(), epsilon = 1e-9);
    }
}
