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
//!    onto the target's, composed down the kinematic chain, the upper arm and the thigh then
//!    turned so that a bent elbow's or knee's plane falls on the target's; [`skin`]; module
//!    `transforms`).
//! 3. **Head twist search.** The joints fix a bone's direction, not its roll, and a roughly
//!    round head can sit in a wrong roll that ICP does not leave: the head bone is started at
//!    each of [`TWISTS`] about the target's neck → head axis, refined by a few rigid ICP steps on
//!    at most 600 of its vertices, and the start with the lowest truncated residual wins
//!    (module `twist`).
//! 4. **Articulated ICP** ([`ArticulatedOptions::iterations`] rounds, on an even stride sample
//!    of at most [`ArticulatedOptions::icp_points`] template vertices): every sampled vertex is
//!    paired with its nearest pool vertex; a pair holds when it is within the round's gate
//!    (shrinking geometrically from [`ArticulatedOptions::gate_start`] to
//!    [`ArticulatedOptions::gate_end`]), its normals agree
//!    ([`ArticulatedOptions::min_normal_cosine`]: the template's back has no counterpart on a
//!    front view) and its target point is not on the target's border beyond
//!    [`ArticulatedOptions::boundary_gate`]. With a target viewpoint, a posed vertex hidden
//!    behind the posed template (module `visibility`) or facing away from the viewpoint
//!    ([`ArticulatedOptions::min_facing_cosine`]) takes no pair. The other way round, a
//!    scattered sample of the target's vertices is paired with their nearest shown posed
//!    template vertex under the same tests and pools
//!    ([`ArticulatedOptions::target_to_template`]): a sensor's view is all surface the template
//!    must explain, while template points can pair with what the view lacks. Each bone with at
//!    least 20 pairs of weight > 0.1 is re-fitted by weighted Kabsch (Arun et al. 1987) to both
//!    sets plus its two joints as anchors
//!    ([`ArticulatedOptions::joint_anchor`]; none at a joint the target's skeleton does not
//!    track, which is placed by the last tracked bone above it; the head's anchor at the
//!    neck's base is weaker,
//!    [`ArticulatedOptions::head_neck_anchor`]: the neck bends below the skull, so the two
//!    joints do not give the skull's pitch); with a target viewpoint the head's fit also pulls
//!    its twist towards the chest's ([`ArticulatedOptions::head_twist_prior`]: one view of a
//!    round head barely pins it) — or, where the target's skeleton reports the head's turn
//!    against the chest (`Skeleton::head_turn`, a tracker that sees the face), towards that
//!    turn ([`ArticulatedOptions::head_turn_prior`]). Then the template is re-skinned (module
//!    `icp`). From an
//!    earlier fit ([`ArticulatedStart::Warm`]) onto a view, the head is then started again at
//!    each of [`WARM_TWISTS`] and refined scan → template on its own points; a turned start
//!    is kept only when it explains the scan's head clearly better
//!    ([`ArticulatedOptions::head_warm_twist`]: a subject looking aside, which the joints do
//!    not show).
//! 5. **Non-rigid step** (needs the template's edge graph, [`ArticulatedInputs::neighbors`]):
//!    what rigid bones blended by skinning weights cannot express (another rig's skinning, soft
//!    tissue, body shape) is pulled in by a smooth displacement field — the held pairs' offsets
//!    spread over the edge graph by Jacobi iterations of
//!    `min Σ r_v|s_v − d_v|² + λ Σ_edges |s_u − s_v|²` — over
//!    [`ArticulatedOptions::nonrigid_rounds`] rounds whose gates run coarse to fine from
//!    [`ArticulatedOptions::nonrigid_gate_start`] to `gate_end` (module `nonrigid`).
//! 6. **Map**: every template vertex takes the nearest target vertex of its pool; it *has a
//!    counterpart* when that pair holds at the final gate; confidence `1/(1 + d/gate)`, on a
//!    target with a border (a scan) times `1/(1 + σ/0.001)` and `1/(1 + g/0.04)`: σ the RMS
//!    point-to-plane residual of the vertex's bones, g how far the fit moved the vertex from
//!    the pose of the skeletons alone (module `confidence`); fitted from the skeletons onto a
//!    view, a head vertex's confidence also falls with the evidence that a turned head would
//!    explain the scan's head points better ([`ArticulatedOptions::head_twist_doubt`]). It
//!    ranks the matches and decides nothing. Without [`ArticulatedOptions::guess_hidden`]
//!    only the vertices that can have a counterpart are searched (the others get
//!    confidence 0).
//!
//! Left and right never mix: the pools are the skeleton filter (§3.2) as a hard constraint.
//! Measured: `docs/decisions/2026-11-23-articulated-alignment.md`,
//! `docs/decisions/2026-11-23-articulated-nonrigid-step.md`,
//! `docs/decisions/2026-12-01-articulated-adjacent-pools.md`,
//! `docs/decisions/2026-12-01-articulated-kdtrees.md`,
//! `docs/decisions/2026-12-03-confidence-ranking.md`,
//! `docs/decisions/2026-12-05-head-warm-twist.md`,
//! `docs/decisions/2026-12-05-target-to-template-pairs.md`,
//! `docs/decisions/2026-12-06-cold-head-twist-scan-to-template.md`.

mod confidence;
mod icp;
mod nonrigid;
mod transforms;
mod twist;
mod visibility;

pub use transforms::{bone_transforms, outward_normals, skin, BoneTransforms};
use twist::{TwistLimit, TwistPrior};
pub use twist::{MAX_HEAD_TWIST_DEG, TWISTS, WARM_TWISTS};

use crate::kdtree::{KdTree, PoolTrees};
use crate::{CorrespondError, Pair, SegmentPools};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::time::Instant;
use symcorr_attach::BoneWeights;
use symcorr_skeleton::{Bone, Joint, Segment, Skeleton, BONES};
use symcorr_spectral::EdgeGraph;

/// What [`articulated_match`] needs about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct ArticulatedInputs<'a> {
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
    /// The mesh's triangles; on the template side they carry the occlusion test of a
    /// single-view target (`None`: no occlusion test).
    pub triangles: Option<&'a [[u32; 3]]>,
    /// Where a single-view mesh was seen from (a depth scan's camera centre, in the mesh's
    /// frame); on the target side it turns on the occlusion test: a template vertex hidden
    /// behind the posed template's own surface, seen from here, has no counterpart (module
    /// `visibility`). `None`: the mesh is not one view (or its viewpoint is unknown).
    pub viewpoint: Option<Point3<f64>>,
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
    /// The head bone's anchor at its parent joint (`ShoulderCenter`, the base of the neck),
    /// relative to [`ArticulatedOptions::joint_anchor`]. The neck bends between that joint and
    /// the `Head` joint (the skull's centre, carried by the skull), so the line through the two
    /// does not give the skull's pitch: a nodding head anchored at both ends was held 27° off
    /// its truth. A weaker anchor at the neck's base lets the head's pairs decide its swing
    /// about the skull's centre, and still conditions a fit with few pairs.
    /// (0.3, [`DEFAULT_HEAD_NECK_ANCHOR`]:
    /// `docs/decisions/2026-12-04-head-neck-anchor.md`.)
    pub head_neck_anchor: f64,
    /// Geodesic band of the target pools (see [`SegmentPools::new`]), in the target's √area.
    pub band: f64,
    /// At most this many template vertices (an even stride sample) drive the ICP fits.
    pub icp_points: usize,
    /// A pair whose target point lies on the target's boundary is rejected (and the template
    /// point has no counterpart) when longer than this; a target with a viewpoint uses
    /// [`ArticulatedOptions::seen_boundary_gate`] instead.
    /// (0.015: a single-view scan has holes inside its silhouette as well, and at 0.01 one
    /// shown template point in 16 went to `no_counterpart`; a wider gate pairs the flanks
    /// beyond a silhouette. `docs/decisions/2026-12-03-scan-matching.md`.)
    pub boundary_gate: f64,
    /// [`ArticulatedOptions::boundary_gate`] of a target with a viewpoint. (0.02: the fit's
    /// error at a scan's border reaches 0.022; the flanks just beyond a silhouette, which a
    /// wider gate pairs, face away from the camera and the facing test
    /// ([`ArticulatedOptions::min_facing_cosine`]) leaves them out.
    /// `docs/decisions/2026-12-03-facing-test.md`.)
    pub seen_boundary_gate: f64,
    /// Rounds of the non-rigid step after the ICP (0: none).
    pub nonrigid_rounds: usize,
    /// Pair-rejection distance of the first non-rigid round; the rounds' gates shrink
    /// geometrically to [`ArticulatedOptions::gate_end`].
    pub nonrigid_gate_start: f64,
    /// Smoothness weight λ of the non-rigid displacement field (per edge, against 1 per
    /// accepted pair).
    pub nonrigid_smoothing: f64,
    /// With a target viewpoint: a posed template vertex farther than this behind the posed
    /// template's nearest surface along its line of sight is occluded (no pair, no
    /// counterpart).
    pub occlusion_tolerance: f64,
    /// With a target viewpoint: a posed template vertex whose normal makes a cosine below
    /// this with its line of sight to the viewpoint is not visible (no pair, no counterpart),
    /// like an occluded one. 0: a surface facing away from the camera cannot be seen by it —
    /// near a silhouette the occlusion test misses such a vertex (no other triangle lies in
    /// front of it by the tolerance) and the scan's grazing border normals pass the normal
    /// test. A positive value also refuses shown points, the posed normals being 10–15° off
    /// (`docs/decisions/2026-12-03-facing-test.md`).
    pub min_facing_cosine: f64,
    /// ICP iterations from a warm start ([`ArticulatedStart::Warm`]).
    pub warm_iterations: usize,
    /// Pair-rejection distance of the first iteration from a warm start.
    pub warm_gate_start: f64,
    /// Rounds of the non-rigid step from a warm start (0: none); their gates run from
    /// [`ArticulatedOptions::nonrigid_gate_start`] to [`ArticulatedOptions::gate_end`] as
    /// those of [`ArticulatedOptions::nonrigid_rounds`] do. Measured:
    /// `docs/decisions/2026-12-04-track-heat-clusters-and-warm-rounds.md`.
    pub warm_nonrigid_rounds: usize,
    /// Over-relaxation of the ICP rounds from a warm start: each bone's fitted step is taken
    /// this many times (1: as fitted; within (0, 2), else the match is refused: at 2 a step
    /// the pairs pin at once would swing back and forth). Those few rounds had not converged
    /// (each moved the template about 0.6 as far as the one before); a subject 3.2 m from a
    /// Kinect v1, whose depth is coarser, kept the rounds' error as jumping matches.
    /// ([`DEFAULT_WARM_RELAXATION`]: `docs/decisions/2026-12-06-warm-over-relaxation.md`.)
    pub warm_relaxation: f64,
    /// Reciprocal check (`None`: off): a pair (template vertex `v` → target vertex `q`) holds
    /// only when the posed template vertex nearest `q` (same features, among those the
    /// target's viewpoint shows) lies within this distance of `v` on the template at rest.
    /// A template vertex the target does not show — the far cheek of a head posed turned
    /// less than it is — takes the nearest shown surface, which belongs to another part of
    /// the template; its pull turns the fit towards the wrong pose and its match flips or
    /// jumps. In every ICP round, non-rigid round and the final map.
    pub reciprocal_radius: Option<f64>,
    /// Does the final map pair every template vertex? `true`: a vertex without a counterpart
    /// is paired with its nearest pool vertex all the same (a guess). `false`: the map
    /// searches only the vertices that can have a counterpart (shown, and no farther than a
    /// pair that holds at the final gate can be), and a vertex without one gets confidence 0
    /// (its pair names the nearest pool vertex where that search found one, else its last
    /// match or vertex 0 with an infinite distance) — for a caller that drops those pairs (a
    /// tracker). The vertices with a counterpart get the same pairs either way.
    pub guess_hidden: bool,
    /// Head twist prior (`None`: off) of a target seen from a viewpoint: the weight, relative
    /// to the head's total pair weight in each of its ICP fits, of four pairs that hold the
    /// head's twist at its rest pose against the chest's fitted pose. One view of a round
    /// head barely pins its twist (pairs slide along it): turning into profile, the fitted
    /// head lagged the body by 12–25° and its far eye socket paired across the nose. The
    /// prior assumes the head turns with the chest, and pulls a head turned against it back
    /// by a few degrees; a whole surface shows the face and is fitted without it (there it
    /// only biased the turned heads of bodies20's random poses: 0.0025 → 0.0031 mean error).
    /// (0.1, [`DEFAULT_HEAD_TWIST_PRIOR`]: `docs/decisions/2026-12-03-head-twist-prior.md`.)
    pub head_twist_prior: Option<f64>,
    /// Reported head turn prior (`None`: off): when the target's skeleton reports how far the
    /// head is turned against the chest ([`Skeleton::head_turn`], a tracker that sees the face:
    /// the Azure Kinect's nose and ears), the weight, relative to the head's total pair weight
    /// in each of its ICP fits, of the four pairs that hold the head's twist at that turn
    /// against the chest's fitted pose (less the template's own reported turn). It replaces
    /// [`ArticulatedOptions::head_twist_prior`] there, on any target: a measured turn, where
    /// the other assumes the head turns with the chest. From the skeletons the head starts at
    /// that turn instead of the twist search's pick, and from a warm start the warm twist
    /// search ([`ArticulatedOptions::head_warm_twist`]) is skipped.
    /// ([`DEFAULT_HEAD_TURN_PRIOR`]: `docs/decisions/2026-12-05-reported-head-turn.md`.)
    pub head_turn_prior: Option<f64>,
    /// Warm twist search (`None`, or a share not above 0: off): from an earlier fit onto a
    /// target seen from a viewpoint, after the ICP rounds the head is started again at ±15°
    /// and ±30° about its bone and each start refined scan → template on the head's own points
    /// (the scan vertices labelled head, each paired with its nearest posed head vertex;
    /// positions only; a frame whose head shows fewer than 200 points is not searched);
    /// a turned start replaces the rounds' pose only when its mean squared distance is below
    /// this share of the unturned start's. The joints do not show a head turning against the
    /// chest, and neither the ICP rounds nor the twist prior follow it: a subject looking 40°
    /// left and right kept a head 35–45° too little turned (0.22 % flips, all on the head). On
    /// five recordings whose heads turn with the chest no frame's head turned at 0.85 (at 0.9,
    /// one frame of the fixture's).
    /// (0.85, [`DEFAULT_HEAD_WARM_TWIST`]: `docs/decisions/2026-12-05-head-warm-twist.md`.)
    pub head_warm_twist: Option<f64>,
    /// Head twist doubt (`None`: off): on a target seen from a viewpoint, fitted from the
    /// skeletons, the head is also started at ±15° and ±30° about its bone after the ICP rounds
    /// and each start refined scan → template on the head's own points, as the warm twist
    /// search does; the fit does not move, but when a turned start explains those points
    /// better by `t` standard errors of their paired differences, each vertex's confidence
    /// is divided by `1 + w·t / scale` (`w` its skinning weight on the head bone, `scale` this
    /// value; a head that shows fewer than 200 points is not doubted). A single view barely
    /// pins a head's twist, the head holds a third of the template's vertices, and a head
    /// turned against the chest keeps the chest's twist. Table 1's best 10 % over the mean on
    /// `bodies20_kinect` 0.687 → 0.638, tracker joints 0.721 → 0.723.
    /// (16, [`DEFAULT_HEAD_TWIST_DOUBT`]:
    /// `docs/decisions/2026-12-06-cold-head-twist-scan-to-template.md`.)
    pub head_twist_doubt: Option<f64>,
    /// Target → template pairs in every ICP round ([`TargetPairs`]; `None`: off): the target
    /// paired with the template the other way round. A sensor's view is surface the template
    /// must explain wherever it lies, while a template point pairs with the nearest view point
    /// even where the view lacks its own (a hole's rim, the last points before a silhouette),
    /// pulling the fit onto them. On single-view scans the mean error fell 4–6 % and the worst
    /// pair of `bodies20_kinect` from 0.0321 to 0.0288; on whole surfaces it changed nothing.
    /// ([`TargetPairs::default`]:
    /// `docs/decisions/2026-12-05-target-to-template-pairs.md`.)
    pub target_to_template: Option<TargetPairs>,
}

impl Default for ArticulatedOptions {
    fn default() -> Self {
        ArticulatedOptions {
            iterations: 8,
            gate_start: 0.10,
            gate_end: 0.03,
            normal_weight: 0.03,
            min_normal_cosine: 0.3,
            joint_anchor: 0.1,
            head_neck_anchor: DEFAULT_HEAD_NECK_ANCHOR,
            band: 0.02,
            icp_points: DEFAULT_ICP_POINTS,
            boundary_gate: 0.015,
            seen_boundary_gate: 0.02,
            nonrigid_rounds: 3,
            nonrigid_gate_start: 0.06,
            nonrigid_smoothing: 5.0,
            occlusion_tolerance: 0.01,
            min_facing_cosine: 0.0,
            warm_iterations: 4,
            warm_gate_start: 0.05,
            warm_nonrigid_rounds: 2,
            warm_relaxation: DEFAULT_WARM_RELAXATION,
            reciprocal_radius: None,
            guess_hidden: true,
            head_twist_prior: Some(DEFAULT_HEAD_TWIST_PRIOR),
            head_turn_prior: Some(DEFAULT_HEAD_TURN_PRIOR),
            head_warm_twist: Some(DEFAULT_HEAD_WARM_TWIST),
            head_twist_doubt: Some(DEFAULT_HEAD_TWIST_DOUBT),
            target_to_template: Some(TargetPairs::default()),
        }
    }
}

/// Where [`articulated_match`] starts.
#[derive(Debug, Clone, Copy)]
pub enum ArticulatedStart<'a> {
    /// From the two skeletons alone: [`bone_transforms`] and the head's twist search (steps 2
    /// and 3 of the module docs), then [`ArticulatedOptions::iterations`] ICP rounds.
    Skeletons,
    /// From a nearby earlier fit onto the same template — the previous frame of a recording:
    /// its bone transforms, each moved by how its bone moved between that fit's target
    /// skeleton and this one's (the smallest rotation of each limb bone, without
    /// [`bone_transforms`]' hinge twist, composed with `transforms[b]`).
    /// What the joints cannot say (a bone's roll, the head's twist) carries over from the
    /// earlier fit instead of being searched again; [`ArticulatedOptions::warm_iterations`]
    /// ICP rounds from [`ArticulatedOptions::warm_gate_start`] follow, each bone's steps
    /// over-relaxed by [`ArticulatedOptions::warm_relaxation`].
    Warm {
        /// The earlier fit's final bone transforms ([`ArticulatedMatches::transforms`]).
        transforms: &'a BoneTransforms,
        /// The earlier fit's target skeleton (the refined joints it was posed onto).
        joints: &'a Skeleton,
    },
}

/// Default [`ArticulatedOptions::head_twist_prior`].
pub const DEFAULT_HEAD_TWIST_PRIOR: f64 = 0.1;

/// Default [`ArticulatedOptions::head_turn_prior`].
pub const DEFAULT_HEAD_TURN_PRIOR: f64 = 0.3;

/// Default [`ArticulatedOptions::head_warm_twist`].
pub const DEFAULT_HEAD_WARM_TWIST: f64 = 0.85;

/// The default [`ArticulatedOptions::head_twist_doubt`]: the standard errors of evidence for
/// a turned head at which a head vertex's confidence halves.
pub const DEFAULT_HEAD_TWIST_DOUBT: f64 = 16.0;

/// The target → template pairs of the ICP rounds ([`ArticulatedOptions::target_to_template`]):
/// a scattered sample of about `points` target vertices (`warm_points` from a warm start,
/// [`ArticulatedStart::Warm`]), each paired with its nearest shown
/// posed template vertex (features as the template → target search's) and kept when the pair
/// holds at the round's gate as a template → target pair must and the target vertex is in the
/// template vertex's pool (left and right never mix). They join each bone's fit with their
/// skinning weights, scaled so that their total is `weight` times the template → target
/// pairs' total.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetPairs {
    /// Total weight against the template → target pairs' (not above 0: none are added).
    pub weight: f64,
    /// About this many target vertices from the skeletons.
    pub points: usize,
    /// About this many target vertices from a warm start (a pose already within millimetres).
    pub warm_points: usize,
}

impl Default for TargetPairs {
    /// Weight 1 (each direction has the same say); 4,000 points (on `bodies20_kinect` 0.0160
    /// mean error, as with every scan vertex, at 15 % less time per pair) and 1,000 from a
    /// warm start (recordings as accurate as with 4,000; `track` at 640×480 lost 2–7 % of its
    /// frame rate to the pairs, with 4,000 10 %).
    fn default() -> Self {
        TargetPairs {
            weight: 1.0,
            points: 4_000,
            warm_points: 1_000,
        }
    }
}

/// Default [`ArticulatedOptions::warm_relaxation`].
pub const DEFAULT_WARM_RELAXATION: f64 = 1.5;

/// Default [`ArticulatedOptions::head_neck_anchor`].
pub const DEFAULT_HEAD_NECK_ANCHOR: f64 = 0.3;

impl ArticulatedOptions {
    /// [`ArticulatedOptions::head_twist_doubt`] when it is on (a positive scale).
    fn head_doubt_scale(&self) -> Option<f64> {
        self.head_twist_doubt.filter(|&s| s > 0.0)
    }

    /// The weight of bone `b`'s anchor at `joint` (one of its two joints) per unit of the
    /// bone's pair weight: [`ArticulatedOptions::joint_anchor`], times
    /// [`ArticulatedOptions::head_neck_anchor`] for the head bone's parent joint.
    pub(crate) fn anchor(&self, b: usize, joint: Joint) -> f64 {
        let bone = BONES[b];
        if bone == Bone::new(Joint::ShoulderCenter, Joint::Head) && joint == bone.parent {
            self.joint_anchor * self.head_neck_anchor
        } else {
            self.joint_anchor
        }
    }
}

/// Default [`ArticulatedOptions::icp_points`].
pub const DEFAULT_ICP_POINTS: usize = 16_000;

/// The result of [`articulated_match`].
#[derive(Debug, Clone)]
pub struct ArticulatedMatches {
    /// One pair per template vertex, in vertex order; `confidence` falls with the final
    /// distance and, on a scan, with the residual of the vertex's bones and the fit's distance
    /// from the skeletons' pose (`final_map`).
    pub pairs: Vec<crate::Pair>,
    /// Per template vertex, the final distance from the posed template point to its match,
    /// over √area.
    pub distance: Vec<f64>,
    /// Per template vertex: does the target show it (within the final gate, same facing)?
    pub has_counterpart: Vec<bool>,
    /// A target seen from a viewpoint (a depth scan): per template vertex, does the final pose
    /// show it to the viewpoint (the occlusion and facing tests)? `None` for a target without
    /// a viewpoint. [`ArticulatedMatches::view_held`] compares it with `has_counterpart`.
    pub in_view: Option<Vec<bool>>,
    /// The template posed onto the target (the final skinning and the non-rigid step).
    pub posed: Vec<Point3<f64>>,
    /// The final bone transforms (template frame → target frame), one per bone of
    /// [`BONES`](symcorr_skeleton::BONES).
    pub transforms: BoneTransforms,
    /// Seconds per stage: `segment_pools`, `pool_trees` (both only when the index was built
    /// here, [`articulated_match`]), `articulated_icp` (with the head's twist search),
    /// `nonrigid`, `map`.
    pub timings: Vec<(&'static str, f64)>,
}

impl ArticulatedMatches {
    /// A target seen from a viewpoint: the fraction of the template points the final pose
    /// shows to the viewpoint ([`ArticulatedMatches::in_view`]) that found a counterpart on
    /// the target. A fit that lies on the scan holds most of what it says the camera sees
    /// (0.66–0.99 on the virtual-Kinect scan sets and recordings measured); a template posed on
    /// a skeleton turned away from the camera shows the camera its back, which the scan's front
    /// does not hold (0.27–0.70). `None` without a viewpoint or with nothing in view.
    /// (`docs/decisions/2026-12-03-track-turned-skeletons.md`.)
    pub fn view_held(&self) -> Option<f64> {
        // The share is counted in points: the areas are not needed.
        self.view_hold(&[]).map(|h| h.fraction())
    }

    /// [`ArticulatedMatches::view_held`] as counts and as surface: how many template points
    /// the final pose shows the viewpoint and how many of them found a counterpart, and the
    /// template surface they stand for (`template_areas`: the template's barycentric vertex
    /// areas at rest, `symcorr_mesh::TriMesh::vertex_areas`, one per template vertex; a
    /// missing entry counts 0). `None` without a viewpoint or with nothing in view.
    pub fn view_hold(&self, template_areas: &[f64]) -> Option<ViewHold> {
        let in_view = self.in_view.as_ref()?;
        let mut hold = ViewHold {
            shown: 0,
            held: 0,
            shown_area: 0.0,
            held_area: 0.0,
        };
        for (v, (&s, &h)) in in_view.iter().zip(&self.has_counterpart).enumerate() {
            if s {
                let a = template_areas.get(v).copied().unwrap_or(0.0);
                hold.shown += 1;
                hold.shown_area += a;
                if h {
                    hold.held += 1;
                    hold.held_area += a;
                }
            }
        }
        (hold.shown > 0).then_some(hold)
    }
}

/// Of the template points a fit shows a target's viewpoint, how many found a counterpart, and
/// the template surface they stand for ([`ArticulatedMatches::view_hold`], which gives
/// `0 < shown`, `held ≤ shown` and `held_area ≤ shown_area`). The counts weigh every vertex
/// alike, so a finely meshed region (a template's face) counts for more than its surface; the
/// areas do not.
///
/// ```
/// use symcorr_correspond::ViewHold;
/// let h = ViewHold { shown: 4000, held: 3000, shown_area: 0.5, held_area: 0.45 };
/// assert_eq!(h.fraction(), 0.75);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewHold {
    /// Template points the fit shows the viewpoint (occlusion and facing tests).
    pub shown: usize,
    /// Of those, the points with a counterpart on the target: what the fit lays on the scan.
    pub held: usize,
    /// The template surface of the shown points (their vertex areas at rest).
    pub shown_area: f64,
    /// The template surface of the held points: how much of the template the fit lays on the
    /// scan, whatever its meshing.
    pub held_area: f64,
}

impl ViewHold {
    /// `held / shown`: the fraction of its view the fit holds (by points,
    /// [`ArticulatedMatches::view_held`]).
    pub fn fraction(&self) -> f64 {
        self.held as f64 / self.shown.max(1) as f64
    }
}

/// Matches every template vertex onto a (possibly partial) target by skeleton-driven
/// articulated alignment (see the module docs). `weights` are the template's bone weights;
/// `graph` is the target's edge graph (pool bands); `start` says where the alignment starts.
///
/// Errors: [`CorrespondError::EmptyMesh`] for a mesh without vertices,
/// [`CorrespondError::LengthMismatch`] when the tables of a side (or the template's weights)
/// disagree in length, [`CorrespondError::InvalidOptions`] for an
/// [`ArticulatedOptions::warm_relaxation`] outside (0, 2).
pub fn articulated_match(
    template: &ArticulatedInputs<'_>,
    weights: &BoneWeights,
    target: &ArticulatedInputs<'_>,
    graph: &EdgeGraph,
    options: &ArticulatedOptions,
    start: ArticulatedStart<'_>,
) -> Result<ArticulatedMatches, CorrespondError> {
    validate(template, weights, target)?;
    // Before the index is built for nothing.
    validate_options(options)?;
    let index = ArticulatedIndex::new(template, target, graph, options)?;
    let mut out = articulated_match_indexed(template, weights, target, &index, options, start)?;
    out.timings.splice(0..0, index.timings.iter().copied());
    Ok(out)
}

/// [`articulated_match`] with the target's search index built beforehand
/// ([`ArticulatedIndex::new`] with the same template, target and options) — a recording's
/// frame has it built on the thread that observed the frame. The result is the same;
/// `timings` lack the index's stages (they are in [`ArticulatedIndex::timings`]).
///
/// Errors: those of [`articulated_match`], and [`CorrespondError::IndexMismatch`] for an
/// index built for another template, target or options.
pub fn articulated_match_indexed(
    template: &ArticulatedInputs<'_>,
    weights: &BoneWeights,
    target: &ArticulatedInputs<'_>,
    index: &ArticulatedIndex,
    options: &ArticulatedOptions,
    start: ArticulatedStart<'_>,
) -> Result<ArticulatedMatches, CorrespondError> {
    validate(template, weights, target)?;
    validate_options(options)?;
    if index.built_for != IndexKey::of(template, target, options) {
        return Err(CorrespondError::IndexMismatch);
    }
    let mut timings = Vec::new();
    // A joint the target's skeleton lost is placed by the limb above it, not at the hip centre
    // where the attachment parked it.
    let completed = transforms::complete_untracked(template.joints, target.joints);
    let target = &ArticulatedInputs {
        joints: completed.as_ref().unwrap_or(target.joints),
        ..*target
    };
    let al = Alignment::new(template, weights, target, index, options);
    let t = Instant::now();
    let (mut transforms, head_limit, head_prior) = initial_transforms(&al, start)?;
    let sample = al.icp_sample();
    let nonrigid_rounds = match start {
        ArticulatedStart::Skeletons => options.nonrigid_rounds,
        ArticulatedStart::Warm { .. } => options.warm_nonrigid_rounds,
    };
    let rounds = match start {
        ArticulatedStart::Skeletons => icp::Rounds {
            iterations: options.iterations,
            gate_start: options.gate_start,
            occlusion: icp::OcclusionTest::EveryRound,
            target_points: options.target_to_template.map_or(0, |t| t.points),
            relaxation: 1.0,
        },
        ArticulatedStart::Warm { .. } => icp::Rounds {
            iterations: options.warm_iterations,
            gate_start: options.warm_gate_start,
            occlusion: icp::OcclusionTest::Once,
            target_points: options.target_to_template.map_or(0, |t| t.warm_points),
            relaxation: options.warm_relaxation,
        },
    };
    let (mut posed, mut posed_normals, near) = icp::articulated_icp(
        &al,
        &mut transforms,
        &sample,
        rounds,
        head_limit.as_ref(),
        head_prior.as_ref(),
    )?;
    // From an earlier fit, the head's twist is searched again on the rounds' pose: its own
    // points of the scan say when the head turned against the chest (module `twist`).
    // Not where the target's skeleton reports the head's turn: that is measured, where the
    // search guesses (`docs/decisions/2026-12-05-reported-head-turn.md`).
    let warm = matches!(start, ArticulatedStart::Warm { .. }) && reported_turn(&al).is_none();
    if let (true, Some(gain)) = (warm, options.head_warm_twist.filter(|&g| g > 0.0)) {
        if let Some(own) = twist::OwnPoints::new(&al, head_bone()) {
            transforms[own.bone] = twist::twist_search(
                &al,
                own.bone,
                transforms[own.bone],
                head_limit.as_ref(),
                &twist::WARM_TWISTS,
                twist::TwistScore::OwnPoints { own: &own, gain },
            )?;
            (posed, posed_normals) =
                transforms::skin(template.positions, template.normals, weights, &transforms);
        }
    }
    // From the skeletons on a view, how much a turned head would explain the scan's head
    // points better: the head's matches are doubted by as much (the fit stays).
    let head_doubt = match (start, options.head_doubt_scale()) {
        (ArticulatedStart::Skeletons, Some(_)) if reported_turn(&al).is_none() => {
            match twist::OwnPoints::new(&al, head_bone()) {
                Some(own) => twist::twist_doubt(
                    &al,
                    &own,
                    transforms[own.bone],
                    head_limit.as_ref(),
                    &twist::WARM_TWISTS,
                )?,
                None => 0.0,
            }
        }
        _ => 0.0,
    };
    timings.push(("articulated_icp", t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let skinned = posed.clone();
    let near = nonrigid::nonrigid_step(&al, &mut posed, &posed_normals, near, nonrigid_rounds)?;
    timings.push(("nonrigid", t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let map = final_map(&al, &posed, &posed_normals, &near, &skinned, head_doubt)?;
    timings.push(("map", t.elapsed().as_secs_f64()));
    Ok(ArticulatedMatches {
        pairs: map.pairs,
        distance: map.distance,
        has_counterpart: map.has_counterpart,
        in_view: map.in_view,
        posed,
        transforms,
        timings,
    })
}

/// Checks the options whose domain the rounds rely on: [`ArticulatedOptions::warm_relaxation`]
/// within (0, 2), where an over-relaxed step still converges.
fn validate_options(options: &ArticulatedOptions) -> Result<(), CorrespondError> {
    let a = options.warm_relaxation;
    if a > 0.0 && a < 2.0 {
        Ok(())
    } else {
        Err(CorrespondError::InvalidOptions(format!(
            "warm_relaxation must lie in (0, 2) (1: each step as fitted), not {a}"
        )))
    }
}

/// Checks that both meshes have vertices, that each side's tables have one entry per vertex,
/// and that the template's bone weights have one row per vertex.
fn validate(
    template: &ArticulatedInputs<'_>,
    weights: &BoneWeights,
    target: &ArticulatedInputs<'_>,
) -> Result<(), CorrespondError> {
    validate_side("template", template)?;
    validate_side("target", target)?;
    if weights.len() != template.positions.len() {
        return Err(CorrespondError::LengthMismatch {
            what: "template bone weight rows (one per vertex)".into(),
            expected: template.positions.len(),
            found: weights.len(),
        });
    }
    Ok(())
}

/// The target's search index for one template: the segment pools
/// ([`SegmentPools::with_adjacent`]) and one k-d tree per pool over the target's features
/// (position ⊕ β·normal) — what [`articulated_match`] builds before its ICP. Built apart
/// ([`ArticulatedIndex::new`]), it moves that work to another thread: a recording's tracker
/// builds each frame's while the previous frame is matched ([`articulated_match_indexed`]).
///
/// ```no_run
/// use symcorr_correspond::{articulated_match_indexed, ArticulatedIndex, ArticulatedInputs, ArticulatedOptions, ArticulatedStart};
/// # let (template, weights, target, graph): (ArticulatedInputs, symcorr_attach::BoneWeights, ArticulatedInputs, symcorr_spectral::EdgeGraph) = unimplemented!();
/// let options = ArticulatedOptions::default();
/// // On the thread that observed the target:
/// let index = ArticulatedIndex::new(&template, &target, &graph, &options)?;
/// // Later, on the thread that matches (the same as `articulated_match` with the graph):
/// let matches = articulated_match_indexed(&template, &weights, &target, &index, &options, ArticulatedStart::Skeletons)?;
/// # Ok::<(), symcorr_correspond::CorrespondError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ArticulatedIndex {
    pools: SegmentPools,
    trees: PoolTrees,
    built_for: IndexKey,
    timings: Vec<(&'static str, f64)>,
}

impl ArticulatedIndex {
    /// The pools of `template`'s segments on `target` (`graph`: the target's edge graph, for
    /// the pools' bands) and their trees, for `options`.
    ///
    /// Errors: [`CorrespondError::EmptyMesh`], [`CorrespondError::LengthMismatch`] (a side's
    /// tables disagree in length), and those of [`SegmentPools::with_adjacent`].
    pub fn new(
        template: &ArticulatedInputs<'_>,
        target: &ArticulatedInputs<'_>,
        graph: &EdgeGraph,
        options: &ArticulatedOptions,
    ) -> Result<ArticulatedIndex, CorrespondError> {
        validate_side("template", template)?;
        validate_side("target", target)?;
        let t = Instant::now();
        let pools = segment_pools(template, target, graph, options)?;
        let t_pools = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let beta = options.normal_weight * template.area.sqrt();
        let features: Vec<[f64; 6]> = target
            .positions
            .iter()
            .zip(target.normals)
            .map(|(x, n)| feature(&Point3::from(*x), &Vector3::from(*n), beta))
            .collect();
        let trees = PoolTrees::new(&pools, &features)?;
        Ok(ArticulatedIndex {
            pools,
            trees,
            built_for: IndexKey::of(template, target, options),
            timings: vec![
                ("segment_pools", t_pools),
                ("pool_trees", t.elapsed().as_secs_f64()),
            ],
        })
    }

    /// Seconds per stage of the build: `segment_pools`, `pool_trees`.
    pub fn timings(&self) -> &[(&'static str, f64)] {
        &self.timings
    }
}

/// What an [`ArticulatedIndex`] was built from, as a fingerprint (a word-wise FNV-1a over the
/// bits of both sides' labels and areas, the target's positions and normals, and the options
/// that shape the pools and trees): an index is used only with the inputs it was built for.
/// The edge graph is not in it; it is taken to be the target's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct IndexKey(u64);

impl IndexKey {
    fn of(
        template: &ArticulatedInputs<'_>,
        target: &ArticulatedInputs<'_>,
        options: &ArticulatedOptions,
    ) -> IndexKey {
        // FNV-1a over 64-bit words, each word's high bits folded down after the multiply (a
        // byte-wise FNV cost 1 % of a recording's CPU).
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u64| {
            h = (h ^ x).wrapping_mul(0x0000_0100_0000_01b3);
            h ^= h >> 29;
        };
        eat(template.area.to_bits());
        eat(target.area.to_bits());
        eat(options.normal_weight.to_bits());
        eat(options.band.to_bits());
        for side in [template, target] {
            eat(side.positions.len() as u64);
            for l in side.labels {
                eat(l.index() as u64);
            }
        }
        for (x, n) in target.positions.iter().zip(target.normals) {
            for c in x.iter().chain(n) {
                eat(c.to_bits());
            }
        }
        IndexKey(h)
    }
}

/// Checks that a side has vertices and one entry per vertex in each of its tables.
fn validate_side(side: &'static str, s: &ArticulatedInputs<'_>) -> Result<(), CorrespondError> {
    let n = s.positions.len();
    if n == 0 {
        return Err(CorrespondError::EmptyMesh { side });
    }
    let tables = [
        ("normals", Some(s.normals.len())),
        ("labels", Some(s.labels.len())),
        ("boundary flags", s.boundary.map(<[bool]>::len)),
    ];
    for (table, len) in tables {
        if let Some(found) = len.filter(|&l| l != n) {
            return Err(CorrespondError::LengthMismatch {
                what: format!("{side} {table} (one per position)"),
                expected: n,
                found,
            });
        }
    }
    Ok(())
}

/// The target pools of the template's segments: each segment's target region and its
/// skeleton neighbours' ([`SegmentPools::with_adjacent`]), grown by the geodesic band.
///
/// No sagittal halves on the midline segments: the alignment already puts each side on its
/// side, and a symmetry plane fitted to a turned head is often off by tens of degrees.
/// Adjacent segments join each pool: a label boundary that moved between the meshes (a neck
/// the target's attachment gave to a clavicle) no longer cuts the true vertex out of the pool.
/// Measured: docs/decisions/2026-11-23-articulated-alignment.md and
/// docs/decisions/2026-12-01-articulated-adjacent-pools.md.
fn segment_pools(
    template: &ArticulatedInputs<'_>,
    target: &ArticulatedInputs<'_>,
    graph: &EdgeGraph,
    options: &ArticulatedOptions,
) -> Result<SegmentPools, CorrespondError> {
    SegmentPools::with_adjacent(
        (template.labels, None),
        (target.labels, None),
        graph,
        options.band * target.area.sqrt(),
    )
}

/// What every step of the alignment shares: both meshes (positions and normals as nalgebra
/// points and vectors), the pools and their k-d trees over position ⊕ β·normal, and the
/// lengths derived from the options.
pub(super) struct Alignment<'a> {
    template: ArticulatedInputs<'a>,
    weights: &'a BoneWeights,
    target: ArticulatedInputs<'a>,
    pools: &'a SegmentPools,
    options: &'a ArticulatedOptions,
    trees: &'a PoolTrees,
    template_positions: Vec<Point3<f64>>,
    template_normals: Vec<Vector3<f64>>,
    target_positions: Vec<Point3<f64>>,
    target_normals: Vec<Vector3<f64>>,
    /// The template's √area: the unit of every length of the options.
    unit_len: f64,
    /// β of the features, in length units.
    beta: f64,
    /// The border gate of this target ([`ArticulatedOptions::boundary_gate`] or, with a
    /// viewpoint, [`ArticulatedOptions::seen_boundary_gate`]) in length units.
    boundary_gate: f64,
    /// The largest squared length of a target normal (1 for unit normals).
    longest_target_normal2: f64,
}

impl<'a> Alignment<'a> {
    /// Converts the meshes; the pools and their trees are `index`'s.
    fn new(
        template: &ArticulatedInputs<'a>,
        weights: &'a BoneWeights,
        target: &ArticulatedInputs<'a>,
        index: &'a ArticulatedIndex,
        options: &'a ArticulatedOptions,
    ) -> Alignment<'a> {
        let points = |p: &[[f64; 3]]| p.iter().copied().map(Point3::from).collect::<Vec<_>>();
        let vectors = |p: &[[f64; 3]]| p.iter().copied().map(Vector3::from).collect::<Vec<_>>();
        let unit_len = template.area.sqrt();
        let beta = options.normal_weight * unit_len;
        let target_positions = points(target.positions);
        let target_normals = vectors(target.normals);
        Alignment {
            template: *template,
            weights,
            target: *target,
            pools: &index.pools,
            options,
            trees: &index.trees,
            longest_target_normal2: target_normals
                .iter()
                .map(|n| n.norm_squared())
                .fold(0.0, f64::max),
            template_positions: points(template.positions),
            template_normals: vectors(template.normals),
            target_positions,
            target_normals,
            unit_len,
            beta,
            // A template point whose nearest target point is on the target's border, and not
            // right at it, lies beyond what the target shows (the standard rejection of
            // partial ICP).
            boundary_gate: unit_len
                * if target.viewpoint.is_some() {
                    options.seen_boundary_gate
                } else {
                    options.boundary_gate
                },
        }
    }

    /// The nearest-neighbour feature of a posed point and its normal.
    fn feature(&self, x: &Point3<f64>, n: &Vector3<f64>) -> [f64; 6] {
        feature(x, n, self.beta)
    }

    /// For every posed template vertex (or only the members `subset` per group), the nearest
    /// target vertex of its pool in feature space and the squared feature distance. `hints`,
    /// an earlier answer of this alignment, only speed the search up (`PoolTrees::nearest`).
    fn nearest(
        &self,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        subset: Option<&[Vec<u32>]>,
        hints: Option<&[(u32, f64)]>,
    ) -> Result<Vec<(u32, f64)>, CorrespondError> {
        let f = self.features(posed, normals);
        self.trees
            .nearest(self.pools, &f, subset, hints, f64::INFINITY)
    }

    /// The nearest-neighbour features of posed points and their normals.
    fn features(&self, posed: &[Point3<f64>], normals: &[Vector3<f64>]) -> Vec<[f64; 6]> {
        posed
            .iter()
            .zip(normals)
            .map(|(x, n)| self.feature(x, n))
            .collect()
    }

    /// [`Alignment::nearest`] for the vertices that can pair at `gate` only: those of `subset`
    /// (all when `None`) that `visible` allows, searched no farther than a pair that
    /// [`Alignment::holds`] at `gate` can be. A vertex left out or with nothing that near
    /// gets `(0, ∞)`; every other answer is the exact nearest, so the pairs that hold are the
    /// same as from [`Alignment::nearest`] — found without searching the pools' far side for
    /// the template's back, which a single view never shows.
    fn candidates(
        &self,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        subset: Option<&[Vec<u32>]>,
        visible: Option<&[bool]>,
        gate: f64,
        hints: Option<&[(u32, f64)]>,
    ) -> Result<Vec<(u32, f64)>, CorrespondError> {
        let f = self.features(posed, normals);
        let members = subset.unwrap_or(self.pools.members());
        let searched: Vec<Vec<u32>> = members
            .iter()
            .map(|m| {
                m.iter()
                    .copied()
                    .filter(|&v| visible.is_none_or(|s| s.get(v as usize) == Some(&true)))
                    .collect()
            })
            .collect();
        // A pair that holds is within `gate` and its normals' dot product is at least
        // `min_normal_cosine`, so its feature distance² = |x − y|² + β²(|n_x|² + |n_y|² −
        // 2 n_x·n_y) is at most this (with the longest normals of either side; a hair more
        // for rounding).
        let longest = normals.iter().map(|n| n.norm_squared()).fold(0.0, f64::max);
        let normal_part =
            (longest + self.longest_target_normal2 - 2.0 * self.options.min_normal_cosine).max(0.0);
        let within = (gate * gate + self.beta * self.beta * normal_part) * (1.0 + 1e-9);
        self.trees
            .nearest(self.pools, &f, Some(&searched), hints, within)
    }

    /// Per posed template vertex (positions and normals), can the target show it: `None` when
    /// every vertex may be shown (no target viewpoint or no template triangles), else the
    /// occlusion test of module `visibility` from the target's viewpoint and the facing test
    /// ([`ArticulatedOptions::min_facing_cosine`]).
    fn visibility(&self, posed: &[Point3<f64>], normals: &[Vector3<f64>]) -> Option<Vec<bool>> {
        let (eye, triangles) = (self.target.viewpoint?, self.template.triangles?);
        let mut visible = visibility::visible_from(
            &eye,
            posed,
            triangles,
            self.options.occlusion_tolerance * self.unit_len,
        );
        for ((s, x), n) in visible.iter_mut().zip(posed).zip(normals) {
            *s = *s && self.faces_viewpoint(x, n);
        }
        Some(visible)
    }

    /// Does the posed template point `x` with normal `n` face the target's viewpoint at a
    /// cosine of at least [`ArticulatedOptions::min_facing_cosine`] (always, without one)?
    fn faces_viewpoint(&self, x: &Point3<f64>, n: &Vector3<f64>) -> bool {
        self.target.viewpoint.is_none_or(|eye| {
            let sight = eye - x;
            n.dot(&sight) >= self.options.min_facing_cosine * sight.norm()
        })
    }

    /// Is the target a sensor's view — a surface with a border (a depth scan, a frame of a
    /// recording)? Its sampling and noise get the non-rigid step's robust data term and the
    /// region terms of the confidence; a whole surface keeps the plain ones (measured:
    /// `docs/decisions/2026-12-03-scan-matching.md`,
    /// `docs/decisions/2026-12-03-confidence-ranking.md`).
    fn is_scan(&self) -> bool {
        self.target.boundary.is_some_and(|b| b.contains(&true))
    }

    /// Does the pair (posed template point `x`, its normal `n`) → target vertex `q` hold at
    /// this gate? Close enough, facing the same way, and not hanging over the target's border.
    fn holds(&self, x: &Point3<f64>, n: &Vector3<f64>, q: u32, gate: f64) -> bool {
        let q = q as usize;
        let d = (x - self.target_positions[q]).norm();
        let on_boundary = self.target.boundary.is_some_and(|b| b[q]);
        d <= gate
            && n.dot(&self.target_normals[q]) >= self.options.min_normal_cosine
            && !(on_boundary && d > self.boundary_gate)
    }

    /// Per entry of `near` (one per template vertex, as [`Alignment::candidates`] or
    /// [`Alignment::nearest`] answer): is the vertex one `visible` allows (all when `None`),
    /// does its pair hold at `gate` ([`Alignment::holds`]) and pass the reciprocal check of
    /// `reverse` (`posed` and `normals` are those it was built from)? With `found_only`, a
    /// vertex with nothing near (`∞`) does not. Tested in parallel, in chunks: each test is
    /// independent of the others.
    #[allow(clippy::too_many_arguments)]
    fn held(
        &self,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        near: &[(u32, f64)],
        visible: Option<&[bool]>,
        gate: f64,
        reverse: Option<&Reverse>,
        found_only: bool,
    ) -> Vec<bool> {
        let holds: Vec<bool> = near
            .par_iter()
            .with_min_len(HELD_CHUNK)
            .enumerate()
            .map(|(v, &(q, d2))| {
                (d2.is_finite() || !found_only)
                    && visible.is_none_or(|s| s.get(v) == Some(&true))
                    && self.holds(&posed[v], &normals[v], q, gate)
            })
            .collect();
        let Some(r) = reverse else {
            return holds;
        };
        // The reciprocal check's search answers a question about the target vertex alone
        // (which shown template vertex is nearest it), so each target vertex is searched once,
        // however many template vertices pair with it (a template finer than the scan pairs
        // several with one), starting from the first of them.
        let mut first = vec![u32::MAX; self.target_positions.len()];
        for (v, (&(q, _), &h)) in near.iter().zip(&holds).enumerate() {
            if h && first[q as usize] == u32::MAX {
                first[q as usize] = v as u32;
            }
        }
        let searched: Vec<(u32, u32)> = first
            .iter()
            .enumerate()
            .filter(|(_, &v)| v != u32::MAX)
            .map(|(q, &v)| (q as u32, v))
            .collect();
        let mut nearest = vec![u32::MAX; self.target_positions.len()];
        let answers: Vec<u32> = searched
            .par_iter()
            .with_min_len(HELD_CHUNK)
            .map(|&(q, v)| self.reverse_nearest(r, posed, normals, v as usize, q))
            .collect();
        for (&(q, _), u) in searched.iter().zip(answers) {
            nearest[q as usize] = u;
        }
        holds
            .par_iter()
            .with_min_len(HELD_CHUNK)
            .enumerate()
            .map(|(v, &h)| {
                h && {
                    let u = nearest[near[v].0 as usize];
                    u == u32::MAX
                        || (self.template_positions[u as usize] - self.template_positions[v])
                            .norm_squared()
                            <= r.radius2
                }
            })
            .collect()
    }

    /// [`Alignment::candidates`] and [`Alignment::reverse`] on the same pose, side by side
    /// (they are independent: the reverse tree is built while the pool trees are searched).
    fn candidates_and_reverse(
        &self,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        subset: Option<&[Vec<u32>]>,
        visible: Option<&[bool]>,
        gate: f64,
        hints: Option<&[(u32, f64)]>,
    ) -> Result<(Matches, Option<Reverse>), CorrespondError> {
        let (near, reverse) = rayon::join(
            || self.candidates(posed, normals, subset, visible, gate, hints),
            || self.reverse(posed, normals, visible),
        );
        Ok((near?, reverse))
    }

    /// The reverse search of the reciprocal check ([`ArticulatedOptions::reciprocal_radius`]):
    /// a k-d tree over the features of the posed template vertices `visible` allows (all
    /// when `None`). `None` when the check is off.
    fn reverse(
        &self,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        visible: Option<&[bool]>,
    ) -> Option<Reverse> {
        let radius = self.options.reciprocal_radius? * self.unit_len;
        Some(Reverse {
            tree: self.shown_tree(posed, normals, visible),
            radius2: radius * radius,
        })
    }

    /// A k-d tree over the features of the posed template vertices `visible` allows (all when
    /// `None`), each carrying its vertex id: the template as the target's points see it.
    fn shown_tree(
        &self,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        visible: Option<&[bool]>,
    ) -> KdTree<6> {
        let (mut points, mut ids) = (Vec::new(), Vec::new());
        for (v, (x, n)) in posed.iter().zip(normals).enumerate() {
            if visible.is_none_or(|s| s.get(v) == Some(&true)) {
                points.push(self.feature(x, n));
                ids.push(v as u32);
            }
        }
        KdTree::new(points, ids)
    }

    /// The target vertices that pair with the template the other way round
    /// ([`ArticulatedOptions::target_to_template`]): [`scattered_sample`] of about `points`.
    fn target_sample(&self, points: usize) -> Vec<u32> {
        scattered_sample(self.target_positions.len(), points)
    }

    /// Per target vertex of `sample`, its nearest posed template vertex in `shown` (a
    /// [`Alignment::shown_tree`] of `posed`, `normals` and `visible`) when that pair holds at
    /// `gate` ([`Alignment::holds`]) and the target vertex is in the template vertex's pool, as
    /// `(target vertex, template vertex)`. `hints` (one per sample entry, `u32::MAX` for none)
    /// hold each entry's answer of an earlier round and are updated: the pose moved little
    /// since, so each search starts from it ([`Alignment::nearest_shown`]: the same answer).
    #[allow(clippy::too_many_arguments)]
    fn target_pairs(
        &self,
        shown: &KdTree<6>,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        visible: Option<&[bool]>,
        sample: &[u32],
        hints: &mut [u32],
        gate: f64,
    ) -> Vec<(u32, u32)> {
        let found: Vec<u32> = sample
            .par_iter()
            .zip(hints.par_iter())
            .with_min_len(HELD_CHUNK)
            .map(|(&q, &hint)| {
                // A hint is a start only while the tree holds it (shown on this pose).
                let start = (hint != u32::MAX
                    && visible.is_none_or(|s| s.get(hint as usize) == Some(&true)))
                .then_some(hint as usize);
                self.nearest_shown(shown, posed, normals, q, start)
            })
            .collect();
        hints.copy_from_slice(&found);
        sample
            .iter()
            .zip(found)
            .filter(|&(&q, v)| {
                v != u32::MAX
                    && self.holds(&posed[v as usize], &normals[v as usize], q, gate)
                    && self.pools.pool_contains(v, q)
            })
            .map(|(&q, v)| (q, v))
            .collect()
    }

    /// The posed template vertex in `shown` (a [`Alignment::shown_tree`] of `posed` and
    /// `normals`) nearest target vertex `q` in feature space (ties to the smaller id);
    /// `u32::MAX` for none. The search starts from `start`, which must be one of the tree's
    /// vertices: at its distance summed as the tree's leaves sum it, the answer is the
    /// unbounded search's, found without visiting the cells farther than it.
    fn nearest_shown(
        &self,
        shown: &KdTree<6>,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        q: u32,
        start: Option<usize>,
    ) -> u32 {
        let q = q as usize;
        let f = self.feature(&self.target_positions[q], &self.target_normals[q]);
        let start = start
            .map(|v| {
                let p = self.feature(&posed[v], &normals[v]);
                let mut d = 0.0;
                for k in 0..6 {
                    let t = p[k] - f[k];
                    d += t * t;
                }
                (v as u32, d)
            })
            .filter(|(_, d)| d.is_finite())
            .unwrap_or((u32::MAX, f64::INFINITY));
        shown.nearest_within(&f, start).map_or(u32::MAX, |(u, _)| u)
    }

    /// The reverse search of the reciprocal check ([`ArticulatedOptions::reciprocal_radius`]):
    /// the shown posed template vertex nearest the target vertex `q` in feature space (ties to
    /// the smaller id). `posed` and `normals` are those `r` was built from, and `v` one of the
    /// vertices it holds (a shown vertex), where the search starts. `u32::MAX` for none (a
    /// tree without finite points), which the check lets pass.
    fn reverse_nearest(
        &self,
        r: &Reverse,
        posed: &[Point3<f64>],
        normals: &[Vector3<f64>],
        v: usize,
        q: u32,
    ) -> u32 {
        // `v` holds a pair: it is shown, one of the tree's points.
        self.nearest_shown(&r.tree, posed, normals, q, Some(v))
    }

    /// The template vertices that drive the ICP fits, per pool group: an even stride sample
    /// of at most [`ArticulatedOptions::icp_points`] (a bone's rigid fit needs hundreds of
    /// pairs, not tens of thousands; the final map uses all).
    fn icp_sample(&self) -> Vec<Vec<u32>> {
        let n = self.template.positions.len();
        let stride = n.div_ceil(self.options.icp_points.max(1)).max(1);
        self.pools
            .members_where(|v| (v as usize).is_multiple_of(stride))
    }
}

/// About `points` of the ids `0..n` (all when `points ≥ n`), scattered over the range: id `q`
/// is kept when its multiplicative hash (Knuth's 2654435761, a bijection of `u32`) falls below
/// the kept share of `2³²`. A scan's vertex ids follow its image rows, so an even stride over
/// them samples the image on a lattice: on a 640×480 recording a stride sample of 1,000 points
/// per frame gave 0.0174 mean error, the scattered one 0.0165.
fn scattered_sample(n: usize, points: usize) -> Vec<u32> {
    if points >= n {
        return (0..n as u32).collect();
    }
    let limit = (points as f64 / n as f64 * 4_294_967_296.0) as u64;
    (0..n as u32)
        .filter(|&q| u64::from(q.wrapping_mul(2_654_435_761)) < limit)
        .collect()
}

/// The posed template's shown vertices as a target point sees them: the reverse search of the
/// reciprocal check ([`Alignment::reverse`]).
pub(super) struct Reverse {
    /// [`Alignment::shown_tree`] of the pose.
    tree: KdTree<6>,
    /// The check's radius, squared, in length units.
    radius2: f64,
}

/// Per template vertex, its nearest target vertex and the squared feature distance (`(0, ∞)`
/// for none).
type Matches = Vec<(u32, f64)>;

/// Pairs per parallel task of [`Alignment::held`] (a test is a distance, a dot product and
/// at most one k-d tree search).
const HELD_CHUNK: usize = 256;

/// Position ⊕ β·normal: the nearest-neighbour feature of the alignment.
fn feature(x: &Point3<f64>, n: &Vector3<f64>, beta: f64) -> [f64; 6] {
    let m = n * beta;
    [x.x, x.y, x.z, m.x, m.y, m.z]
}

/// Vertex `v`'s skinning weight on the head bone.
fn head_weight(weights: &BoneWeights, v: usize) -> f64 {
    let head = head_bone();
    weights
        .row(v)
        .iter()
        .filter(|&&(b, _)| b == head)
        .map(|&(_, w)| w)
        .sum()
}

/// The neck → head bone's index in [`BONES`].
fn head_bone() -> usize {
    let head = Bone::new(Joint::ShoulderCenter, Joint::Head);
    // Invariant: the neck → head bone is one of BONES.
    BONES.iter().position(|&b| b == head).unwrap_or(2)
}

/// The head's turn the target's skeleton reports ([`Skeleton::head_turn`]) and the weight of
/// the prior that holds it ([`ArticulatedOptions::head_turn_prior`]), when both are there.
fn reported_turn(al: &Alignment<'_>) -> Option<(f64, f64)> {
    al.target
        .joints
        .head_turn
        .zip(al.options.head_turn_prior.filter(|&w| w > 0.0))
}

/// The bone transforms that pose the template on the target's skeleton
/// ([`bone_transforms`]), with the head bone's roll chosen by the twist search — or set at the
/// turn the target's skeleton reports ([`ArticulatedOptions::head_turn_prior`]) — and the limit
/// that holds the head's twist near the chest's pose ([`twist::MAX_HEAD_TWIST_DEG`]) in every
/// later fit.
/// From a warm start, the earlier transforms moved by their bones' motion instead (no twist
/// search), the head held within the same limit. From either start, the prior that holds the
/// head at the reported turn, or else the head's twist prior when the target has a viewpoint
/// ([`ArticulatedOptions::head_twist_prior`]).
fn initial_transforms(
    al: &Alignment<'_>,
    start: ArticulatedStart<'_>,
) -> Result<(BoneTransforms, Option<TwistLimit>, Option<TwistPrior>), CorrespondError> {
    let from_skeletons = bone_transforms(al.template.joints, al.target.joints);
    let head_bone = head_bone();
    let limit = TwistLimit::new(
        al,
        head_bone,
        from_skeletons[head_bone],
        twist::MAX_HEAD_TWIST_DEG,
    );
    let reported = reported_turn(al);
    let prior = match reported {
        Some((turn, w)) => {
            let own = al.template.joints.head_turn.unwrap_or(0.0);
            TwistPrior::new(al.template.joints, head_bone, w, turn - own)
        }
        None => al
            .options
            .head_twist_prior
            .filter(|&w| w > 0.0 && al.target.viewpoint.is_some())
            .and_then(|w| TwistPrior::new(al.template.joints, head_bone, w, 0.0)),
    };
    let transforms = match start {
        ArticulatedStart::Skeletons => {
            let mut t = from_skeletons;
            // A reported turn is where the head starts: the prior's pairs alone place it there
            // (the chest's pose from the skeletons, swung onto the head bone, turned).
            let at_reported = reported
                .and(prior.as_ref())
                .and_then(|p| transforms::kabsch(&p.pairs(&t, 1.0)));
            t[head_bone] = match at_reported {
                Some(pose) => pose,
                None => twist::twist_search(
                    al,
                    head_bone,
                    t[head_bone],
                    limit.as_ref(),
                    &twist::TWISTS,
                    twist::TwistScore::TemplateToTarget,
                )?,
            };
            t
        }
        ArticulatedStart::Warm { transforms, joints } => {
            let motion = transforms::bone_motion(joints, al.target.joints);
            let mut t = *transforms;
            for (b, tr) in t.iter_mut().enumerate() {
                *tr = motion[b] * *tr;
            }
            if let Some(l) = &limit {
                t[head_bone] = l.apply(t[head_bone]);
            }
            t
        }
    };
    Ok((transforms, limit, prior))
}

/// The RMS point-to-plane residual of a vertex's bones (in √area) at which a match's
/// confidence halves ([`final_map`], module `confidence`). Chosen on half of the
/// bodies20_kinect pairs: `docs/decisions/2026-12-03-confidence-ranking.md`.
const RESIDUAL_SCALE: f64 = 0.001;

/// The distance (in √area) between a vertex's fitted pose and its pose from the skeletons
/// alone at which a match's confidence halves ([`final_map`], module `confidence`). Chosen on
/// half of the bodies20_kinect pairs: `docs/decisions/2026-12-03-confidence-ranking.md`.
const DISAGREEMENT_SCALE: f64 = 0.04;

/// The dense map of [`articulated_match`], per template vertex.
struct FinalMap {
    pairs: Vec<Pair>,
    distance: Vec<f64>,
    has_counterpart: Vec<bool>,
    in_view: Option<Vec<bool>>,
}

/// Every template vertex takes the nearest target vertex of its pool; it has a counterpart
/// when that pair holds at the final gate (`gate_end`). Its confidence is `1/(1 + d/gate)`
/// from the final distance `d`; on a sensor's view ([`Alignment::is_scan`]) times two factors
/// of the same form `1/(1 + x/scale)` that rank whole regions of the fit, which a vertex's own
/// distance cannot (a forearm slid along its axis still lies on the scan; module
/// `confidence`):
///
/// - `x = σ_v`, the RMS point-to-plane residual of the held pairs of the vertex's bones,
///   blended by its skinning weights, scale [`RESIDUAL_SCALE`]: a bone the rigid fit could not
///   lay on the scan;
/// - `x = |skinned − skeletal|`, how far the fit moved the vertex from the pose the two
///   skeletons alone give ([`bone_transforms`], [`skin`]), scale [`DISAGREEMENT_SCALE`]: a
///   region the ICP had to pull far from its joints.
///
/// The non-rigid step's displacement is no factor: on the scored (shown) points it ranked
/// backwards. The confidence only ranks: it changes no match and no counterpart decision.
/// Measured (Table 1 rows, the terms tried and dropped):
/// `docs/decisions/2026-12-03-confidence-ranking.md`.
/// `hints`: the last nearest-neighbour answer before it (a search speed-up only).
fn final_map(
    al: &Alignment<'_>,
    posed: &[Point3<f64>],
    posed_normals: &[Vector3<f64>],
    hints: &[(u32, f64)],
    skinned: &[Point3<f64>],
    head_doubt: f64,
) -> Result<FinalMap, CorrespondError> {
    let gate = al.options.gate_end * al.unit_len;
    let visible = al.visibility(posed, posed_normals);
    let (near, reverse) = if al.options.guess_hidden {
        let (near, reverse) = rayon::join(
            || al.nearest(posed, posed_normals, None, Some(hints)),
            || al.reverse(posed, posed_normals, visible.as_deref()),
        );
        (near?, reverse)
    } else {
        // Exactly the pairs that can hold at `gate` ([`Alignment::candidates`]); the others
        // are `(0, ∞)`.
        al.candidates_and_reverse(
            posed,
            posed_normals,
            None,
            visible.as_deref(),
            gate,
            Some(hints),
        )?
    };
    // Not searched (without guesses): no counterpart, no distance, no guess.
    let unsearched = |d2: f64| !d2.is_finite() && !al.options.guess_hidden;
    let has_counterpart = al.held(
        posed,
        posed_normals,
        &near,
        visible.as_deref(),
        gate,
        reverse.as_ref(),
        !al.options.guess_hidden,
    );
    let distance: Vec<f64> = near
        .iter()
        .enumerate()
        .map(|(v, &(q, d2))| {
            if unsearched(d2) {
                f64::INFINITY
            } else {
                (posed[v] - al.target_positions[q as usize]).norm()
            }
        })
        .collect();
    // The region terms; a whole surface keeps the distance alone (its distance already ranks,
    // best 10 % 0.0000 on bodies20, and both terms made later entries of its row worse).
    let regional: Vec<f64> = if al.is_scan() {
        let residuals = confidence::bone_residuals(
            al.weights,
            posed,
            (&al.target_positions, &al.target_normals),
            &near,
            &has_counterpart,
        );
        let (skeletal, _) = skin(
            al.template.positions,
            al.template.normals,
            al.weights,
            &bone_transforms(al.template.joints, al.target.joints),
        );
        let (rs, gs) = (
            RESIDUAL_SCALE * al.unit_len,
            DISAGREEMENT_SCALE * al.unit_len,
        );
        (0..posed.len())
            .map(|v| {
                let r = confidence::blend(al.weights, v, &residuals);
                let g = (skinned[v] - skeletal[v]).norm();
                let doubt = al
                    .options
                    .head_doubt_scale()
                    .map_or(0.0, |scale| head_weight(al.weights, v) * head_doubt / scale);
                1.0 / ((1.0 + r / rs) * (1.0 + g / gs) * (1.0 + doubt))
            })
            .collect()
    } else {
        vec![1.0; posed.len()]
    };
    let pairs = near
        .iter()
        .enumerate()
        .map(|(v, &(q, d2))| {
            if unsearched(d2) {
                let last = hints.get(v).filter(|h| h.1.is_finite()).map_or(0, |h| h.0);
                return Pair {
                    template: v as u32,
                    target: last,
                    confidence: 0.0,
                };
            }
            let confidence = if has_counterpart[v] || al.options.guess_hidden {
                regional[v] / (1.0 + distance[v] / gate)
            } else {
                0.0
            };
            Pair {
                template: v as u32,
                target: q,
                confidence,
            }
        })
        .collect();
    Ok(FinalMap {
        pairs,
        distance: distance.iter().map(|d| d / al.unit_len).collect(),
        has_counterpart,
        in_view: visible,
    })
}

#[cfg(test)]
mod tests {
    use super::scattered_sample;

    #[test]
    fn a_scattered_sample_has_about_its_size_and_no_stripes() {
        assert_eq!(scattered_sample(5, 9), vec![0, 1, 2, 3, 4]);
        assert!(scattered_sample(0, 9).is_empty());
        assert!(scattered_sample(100, 0).is_empty());
        // The vertices of a 640 × 480 image in row order, a sample of 1,000.
        let (w, n) = (640usize, 640 * 480);
        let s = scattered_sample(n, 1_000);
        assert!((950..=1_050).contains(&s.len()), "{} ids", s.len());
        assert!(s.windows(2).all(|p| p[0] < p[1]));
        // Spread over the columns and the rows alike (an even stride of 308 keeps 160 of the
        // 640 columns, on a lattice).
        let mut columns = vec![false; w];
        let mut rows = vec![false; n / w];
        for &q in &s {
            columns[q as usize % w] = true;
            rows[q as usize / w] = true;
        }
        let (c, r) = (
            columns.iter().filter(|&&x| x).count(),
            rows.iter().filter(|&&x| x).count(),
        );
        assert!(c > 500 && r > 400, "{c} columns, {r} rows");
    }
}
