//! The matching stages of the paper "Symmetry-Aware Human Shape Correspondence Using Skeleton"
//! and the evaluation metrics (DESIGN.md, Algorithms 3–6 and Metrics).
//!
//! Each stage is a plain function on plain data, so that it can be tested alone and reused by
//! refinements (DESIGN.md, Algorithm 7):
//!
//! 1. [`candidates`] (§3.1): the target vertices nearest in descriptor space (si-HKS).
//! 2. [`skeleton_filter`] (§3.2): drop candidates on a different body segment.
//! 3. [`base_profile`] + [`select`] (§3.3, eq. 7–8): keep the candidate whose normalised summed
//!    geodesic distance to the base vertex set is closest to the template point's.
//! 4. [`evaluate`], [`cumulative_curve`], [`table1_row`]: the paper's measurements.
//!
//! [`match_points`] runs 1–3 for a set of template points; [`farthest_point_sample`] picks the
//! sparse mode's points. The spectral inputs (descriptors, base-set geodesics) and the segment
//! labels are computed by symcorr-spectral and symcorr-attach; the `symcorr` crate wires them.
//!
//! ```
//! use symcorr_attach::Segment::{ThighLeft, ThighRight};
//! use symcorr_correspond::{match_points, Descriptors, MatchOptions, Side};
//! // Two vertices per mesh with identical descriptors (a perfect left/right symmetry): only
//! // the segments tell them apart.
//! let d = Descriptors::new(2, 1, vec![1.0, 1.0]).unwrap();
//! let labels = [ThighLeft, ThighRight];
//! let profile = [0.3, 0.3];
//! let side = Side { descriptors: &d, labels: &labels, profile: &profile, halves: None, sagittal: None, positions: None };
//! let out = match_points(&side, &side, &[0, 1], &MatchOptions::default()).unwrap();
//! assert_eq!(out.matches[0].target, 0);
//! assert_eq!(out.matches[1].target, 1);
//! ```
//!
//! # Beyond the paper: the refined dense method (DESIGN.md, Algorithm 7)
//!
//! [`refine_dense`] matches every template vertex in three steps:
//!
//! 1. **Skeleton landmark coordinates.** Per mesh, one landmark source set per joint
//!    ([`skeleton_landmarks`]): the *ring* where the plane through the joint, normal to its
//!    bone, cuts the surface of the segments meeting there (elbows, knees, shoulders, spine …)
//!    and the surface *tip* beyond each end joint (top of the head, fingertips, toes); plus the
//!    vertex nearest each refined joint ([`joint_landmarks`]) — 40 columns. Every vertex's heat-
//!    method geodesic distance to each of them over √area ([`landmark_coordinates`]; one
//!    prefactored system, solves in parallel) gives coordinates that correspond by joint name,
//!    survive isometries and tell left from right.
//! 2. **Initial map** ([`nearest_in_pools`]): nearest neighbour in landmark ⊕ si-HKS space
//!    (si-HKS columns scaled to unit standard deviation over both meshes, weight
//!    [`RefineOptions::descriptor_weight`]), restricted to the point's [`SegmentPools`] pool:
//!    the target region of the point's segment grown by a geodesic band
//!    ([`RefineOptions::band`], so label boundaries that moved between meshes do not cut good
//!    matches off), never on the other side of the body (a left limb never meets a right one;
//!    midline segments are split by sagittal halves).
//! 3. **Segment-constrained ZoomOut** ([`zoomout`], Melzi et al. 2019): functional map
//!    `C = Φ_kᵀ M Π Ψ_k` from the current map, then the point map recovered by nearest
//!    neighbour of rows of `Φ_k C` among rows of `Ψ_k` within the same pools; `k` 20 → 60 by 8.
//!    The anchor option (appending landmark features to every recovery) is off by default.
//!
//! Confidence = `1/(1 + r/r̃)` from the final spectral residual `r`; [`coverage`] reports
//! the fraction of target vertices hit. Midline halves for this method come from the joints'
//! planes refined by the surface's own symmetry ([`refine_symmetry_plane`]), because a noisy
//! shoulder line or a turned head tilts the joint plane by many degrees.
//!
//! Measured choices (generated bodies, 16 pairs of 13,380 vertices; developer experiment
//! `symcorr-experiments --bin refine_eval`, whose landmark/plane options mirror the pipeline's):
//! * si-HKS weight: landmarks alone 0.0276 → weight 1: 0.0094 on the two walk pairs
//!   (0.1: 0.0169, 3 and 10: 0.0093); all 16 pairs: weight 1 0.0245, 3 0.0242, si-HKS alone
//!   (weight 1000) 0.0242 but with 10× more initial-map flips (0.45 % vs 0.23 %).
//! * Landmarks: nearest-vertex points only 0.0245 (exact joints); rings + tips + points 0.0227.
//!   On the two hardest cross-shape pairs: points 0.053, rings + tips 0.044, all three 0.040.
//! * Symmetry-refined halves, σ = 3 cm joints: flips 1.01 % → 0.06 % (mean 0.0308 → 0.0282);
//!   with the joint planes the head flipped wholesale under shoulder noise.
//! * Eigenpairs: 100 instead of 60 (ZoomOut to 100) on the walk pairs: 0.0358 vs 0.0392 with
//!   landmarks alone, at twice the eigensolve time — kept 60.
//! * ZoomOut step (20 → 60, all 16 pairs): 4 → 0.0227, 8 → 0.0229 in half the steps, 20 →
//!   0.0255; default 8.
//! * Large meshes: every ZoomOut iteration but the last runs on an even stride sample of at
//!   most [`DEFAULT_ZOOMOUT_POINTS`] template vertices (masses rescaled to the total area);
//!   53.5k ↔ 53.5k (Loop-subdivided body, rest → T-pose): ZoomOut 32 s → 2.7 s, whole pair
//!   6.9 s (2 cores, load ≈ 2), error 0.0200, no flips. The 13.4k bodies run in full.
//! * Anchors in ZoomOut (weights 0.3/1/3): no gain (0.056/0.056/0.065 vs 0.051 on the hardest
//!   pair); off.
//! * Permuting the target's vertex ids changes nothing (tested in the symcorr crate on a
//!   permuted capsule body).
//!
//! # Beyond the paper: skeleton-driven articulated alignment (symcorr's default)
//!
//! [`articulated_match`] (module docs of `articulated.rs`) poses the template onto the target's
//! skeleton by linear blend skinning with the template's bone-heat weights ([`bone_transforms`],
//! [`skin`]), re-fits each bone by weighted Kabsch to nearest neighbours within the segment
//! pools (8 iterations, gates 0.10 → 0.03·√area, joints as anchors), searches the head's twist
//! about the neck, pulls the result onto the target with a smooth displacement field, then
//! maps each template vertex to the nearest target vertex of its pool. It
//! is extrinsic, so a partial target (a single-view scan) is no harder than a whole one; a
//! template point has a counterpart when its nearest target point is within the final gate,
//! faces the same way and is not on the target's border beyond one edge.
//!
//! Measured choices (generated bodies, dense, 12 pairs incl. the hardest random poses, release
//! build, 2 cores):
//! * Pools without sagittal halves: with the halves (symmetry-refined planes) 0.0108 mean /
//!   0.32 % flips, without 0.0050 / 0.01 % — a turned head's symmetry plane fitted by
//!   reflection ICP was off by tens of degrees and the halves forced whole half-heads wrong.
//! * Head twist search: off 0.0062 / 0.06 %, on 0.0050 / 0.01 % (whole meshes); in
//!   `s0_rest → s0_random-5` the head had been left 46° off about the neck. Starts within ±90°
//!   only: ±180° turned whole heads round (back for face) with σ = 3 cm joints (13 of 58 pairs).
//! * The head axis from the skull's symmetry plane instead of the search: worse (0.0094 /
//!   0.37 %), dropped.
//! * Iterations 8 vs 15, final gate 0.03 vs 0.02, joint anchor 0.02–0.5, normal weight 0–0.1:
//!   all within 0.002 of each other on 12 scan pairs (0.020–0.025); defaults kept.
//! * Non-rigid step (3 rounds, λ = 5, on the template's edge graph) after the ICP: exact
//!   joints 0.0050 → 0.0040, σ = 3 cm joints 0.0187 → 0.0159, scans 0.0203 → 0.0198 (12
//!   pairs each; λ = 1: 0.0045 exact).
//! * Large meshes: ICP fits on an even sample of at most [`DEFAULT_ICP_POINTS`] template
//!   vertices and the twist search on at most 600 head vertices; the final map uses all.
//!
//! # Decisions the design leaves open
//! * **Candidate rule.** Both rules of §3.1 are offered ([`CandidateOptions`]): the `N` nearest
//!   and/or a threshold. The threshold is *relative* (`d ≤ t·d₁(p)`, `d₁` the nearest
//!   descriptor distance) because si-HKS values have no natural scale. Default: the
//!   [`DEFAULT_NEAREST`] nearest, no threshold — measured on the generated bodies (see the
//!   `symcorr` crate docs and README for the sweep).
//! * **Selection.** Eq. 8 uses `|D̂(c) − D̂(p)|` with `D̂(v) = mean_b g(v, b) / √area` (mean
//!   over the base set, so sets of different sizes compare). Ties go to the nearer descriptor.
//! * **Confidence** of a match: `1 / (1 + d/d̃ + g/g̃)` — descriptor distance and eq. 8 gap,
//!   each over its median in the match set ([`assign_confidence`]).
//! * **Midline halves** (beyond the paper, on by default, [`MatchOptions::midline_halves`]):
//!   pelvis, torso and head are single segments with a left and a right half, so the paper's
//!   filter cannot stop a flip there; the pipeline passes a per-vertex side of the skeleton's
//!   sagittal plane ([`Side::halves`]) and the filter also requires the same half.
//! * **Sagittal band** (beyond the paper, on by default, [`MatchOptions::sagittal_ratio`],
//!   [`sagittal_band`]): the halves still let eq. 8 pick a vertex *on* the plane (the navel,
//!   the spine, the chin), about as far from the true point as from its mirror image — most of
//!   the remaining flips were such picks, with the true point and the template point 0.05–0.1
//!   √area off the plane and the match within 0.01. A midline point's candidates must lie on
//!   its side at least half its own distance from the plane, distances over each segment's
//!   half-width ([`Side::sagittal`]). Measured (58 pairs of generated bodies, exact joints,
//!   sparse, same build): flips 0.170 % → 0.027 %, mean error 0.0443 → 0.0439; ratio 0.3:
//!   0.029 %, 0.7: 0.027 %. Distances over √area instead of the half-width: the same within
//!   one flip; a symmetric difference rule `|s(q) − s(p)| ≤ τ` left more flips (0.034 % at
//!   τ = 0.02 √area) and points without any candidate. Planes refined by the surface's symmetry
//!   (as the refined method uses) made the paper's method worse with exact joints (0.26 %
//!   flips without the band). With σ = 3 cm joints (sparse): flips 0.733 % → 0.307 % at a
//!   mean error cost of 0.0530 → 0.0542 (ratio 0.2: 0.491 %, 0.0534; 0.35: 0.403 %, 0.0539).
//!   Limb candidates restricted to the point's position along its bone chain (± 0.15 or
//!   0.25 of the chain) did not remove the crotch flips the band cannot reach: not kept.
//!   An *intrinsic lateral band* (session 4, not kept): on the head and the limbs, candidates
//!   on the point's side of `lat(v) = (g(v, right shoulder/hip) − g(v, left …)) / √area` at
//!   least `ratio·|lat(p)|` out, with the same fallback as the sagittal band. 58 pairs,
//!   sparse, exact joints: flips 11 → 2 (ratio 0.5, landmarks = vertex nearest each joint;
//!   head 7 → 1, thigh 3 → 0), mean 0.0437 → 0.0438; but σ = 3 cm joints 0.0524 / 0.25 % →
//!   0.0573 / 0.28 % (ratio 0: 0.0551 / 0.34 %; 0.25: 0.0559 / 0.30 %). Shoulder and hip
//!   *rings* as landmarks: exact 5 flips, 0.0435; noisy 0.0570 / 0.28 %. Without the
//!   fallback (a point whose candidates all fail keeps them): exact 0.0436 / 11 flips, noisy
//!   0.0526 / 0.24 % — the flips it removed were all fallbacks, and the fallback is what costs
//!   the noisy mean. Applied to the pelvis, torso and hips too: 27 flips (landmarks near the
//!   groin move with the thighs).
//!   What the 11 remaining exact-joint flips are (session 6, experiment `paper_flips --verbose`
//!   of experiments/README.md):
//!   gross errors, not side confusions. Seven are head points of shape s0 matched on shape s1
//!   (the s0 → s1 random pairs) with errors 0.11–0.19 √area, on the *correct* half: the
//!   si-HKS of the true vertex is 0.23–0.27 away, while a few target vertices on the back of
//!   the neck and skull (the same four "hubs" for every point) are at 0.15–0.17, so all five
//!   candidates lie there; eq. 8 would prefer the true vertex (gap 0.037–0.048 vs 0.064–0.092)
//!   but it is not a candidate. In the head's frame (position along shoulder centre → head)
//!   the points sit at 1.0–1.26 bone lengths, the hubs at 0.66–0.76. A head-only axial band
//!   `|t(q) − t(p)| ≤ δ` with the same fallback: δ = 0.2 → 16 flips, 0.3 → 13, 0.4 → 8 (mean
//!   0.0437 → 0.0432–0.0435) — the fallback's nearest descriptor inside the band is again a
//!   gross error. Three are crotch points of s1_rest (thigh_right, all raw candidates on the
//!   left thigh or far down the right one); one is a template attachment label (pelvis where
//!   the rig says thigh_left). Zero needs a candidate stage that finds the true vertex, i.e.
//!   a descriptor that survives a change of shape on the head; the refined method's extrinsic
//!   alignment is what does that. Hubness-corrected candidates (CSLS-like: rank by
//!   `d(p, q) − w·r(q)`, `r(q)` the mean distance of target vertex `q` to its `k` nearest
//!   template descriptors, brute force in the experiment): k = 10, w = 1: mean 0.0437 → 0.0399
//!   but 12 flips; w = 0.5: 0.0423, 10 flips; k = 30, w = 1: 0.0398, 12 flips. Not kept (the
//!   flip rate is what is open; the mean is already far under the paper's 0.083), but the
//!   mean-error gain is worth having if the candidate stage is revisited.
//!   Candidate-stage variants measured in session 7 (`paper_flips`, 58 pairs, sparse,
//!   exact joints, same build; base 0.0437 / 11 flips of 47,622), none kept: *filter first*
//!   (the N nearest descriptors among the compatible target vertices instead of the survivors
//!   of the N nearest overall; variant `f`) N = 5: 0.0472 / 8, N = 10: 0.0523 / 8 — the
//!   crotch points gain a candidate near the truth, every other point gains bad ones;
//!   *spatially diverse candidates* (skip a compatible vertex within ρ·√area of one already
//!   taken; `x`) ρ = 0.02: 0.0541 / 15, 0.05: 0.0692 / 11, with filter first ρ = 0.03: 0.0596 /
//!   9; *adaptive widening* (a point whose best eq. 8 gap exceeds τ gets the M nearest
//!   compatible vertices; `g`, `w`) τ = 0.05, M = 50: 0.0441 / 16; τ = 0.03, M = 20: 0.0447 /
//!   29; τ = 0.02, M = 20: 0.0463 / 44; *reverse nearest neighbours* (keep `q` only if `p` is
//!   among the `K` template descriptors nearest `q`, against hubs; `k`) K = 20 / 50 / 200:
//!   0.0434–0.0437 / 11 (at K = 20 the same segments as the base); with 20 raw candidates
//!   K = 50 / 200: 0.0512 / 10, 0.0517 / 8. More candidates let eq. 8's single scalar pick
//!   more gross errors, as in session 1's N sweep. *si-HKS frequencies* (symcorr's
//!   `PrepareOptions::si_hks`, `paper_flips --si-hks-frequencies`, `--eigenpairs`,
//!   `--si-hks-tau-start`): 6 → 16:
//!   0.0432 / 9 (σ = 3 cm joints 0.0524 / 117 → 0.0519 / 116 flips), 32: 0.0431 / 9, 16 with
//!   100 eigenpairs: 0.0429 / 9, 16 with the window from τ = −10: 0.0472 / 25. A small gain on
//!   both, not taken into the defaults because it moves every refined and paper figure for
//!   two flips; the remaining flips are then 3–4 head, 4 thigh, 1 template label.
//!   Whole benchmark with the skull plane of `symcorr::midline_halves` (release binary,
//!   58 pairs each, `symcorr bench --method paper`): exact joints sparse 0.0444 / 0.172 % →
//!   0.0437 / 0.02 %, dense 0.0352 / 0.184 % → 0.0344 / 0.04 %; σ = 3 cm sparse 0.0532 /
//!   0.79 % → 0.0524 / 0.25 %.
//! * **Fallback.** If the filter removes every candidate, the nearest target vertex of the same
//!   segment by descriptor is used and counted ([`FilterStats::fallbacks`]); if the target has
//!   no vertex of that segment at all, the point keeps its unfiltered candidates
//!   ([`FilterStats::segment_missing`]).
//! * **Sparse sample.** Euclidean farthest-point sampling ([`farthest_point_sample`]).
//! * **Metric geodesics**: edge-path Dijkstra stopped when the ground-truth vertex is settled
//!   (see [`metrics`](crate::evaluate)).

mod articulated;
mod candidates;
mod filter;
mod kdtree;
mod landmarks;
mod metrics;
mod refine;
mod sample;
mod selection;
mod symmetry;

pub use articulated::{
    articulated_match, bone_transforms, outward_normals, skin, ArticulatedMatches,
    ArticulatedOptions, ArticulatedSide, BoneTransform, Mat3, DEFAULT_ICP_POINTS, TWISTS,
};
pub use candidates::{candidates, Candidate, CandidateOptions, Descriptors};
pub use filter::{sagittal_band, skeleton_filter, BandStats, FilterStats};
pub use landmarks::{joint_landmarks, landmark_coordinates, skeleton_landmarks};
pub use metrics::{
    cumulative_curve, evaluate, table1_row, within, EvalGraph, Evaluation, FLIP_MIN_SEPARATION,
};
pub use refine::{
    adjacent_segments, coverage, nearest_in_pools, refine_dense, zoomout, RefineOptions,
    RefineSide, RefinedMatches, SegmentPools, SpectralBasis, ZoomOutOptions, ZoomOutResult,
    DEFAULT_ZOOMOUT_POINTS,
};
pub use sample::farthest_point_sample;
pub use selection::{assign_confidence, base_profile, select, Match};
pub use symmetry::refine_symmetry_plane;

use std::time::Instant;
use symcorr_attach::Segment;

/// Default number of nearest candidates per template point (§3.1), chosen by measurement.
pub const DEFAULT_NEAREST: usize = 5;

/// Errors of the matching stages.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CorrespondError {
    /// An argument is inconsistent or out of range (the message says which).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
}

/// Everything the matching stages need about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// Point descriptors (si-HKS), one row per vertex.
    pub descriptors: &'a Descriptors,
    /// Segment label per vertex (symcorr-attach).
    pub labels: &'a [Segment],
    /// Base-set profile `D̂` per vertex ([`base_profile`]).
    pub profile: &'a [f64],
    /// Optional sagittal half per vertex for the midline segments (see [`skeleton_filter`]):
    /// `-1` right, `+1` left, `0` near the plane or not on a midline segment.
    pub halves: Option<&'a [i8]>,
    /// Optional sagittal coordinate per vertex for the midline segments (see
    /// [`sagittal_band`]): signed distance to the segment's sagittal plane over the segment's
    /// half-width, `+` on the subject's left, `0` on limb segments.
    pub sagittal: Option<&'a [f64]>,
    /// Optional vertex positions: on the target side they give each match its candidate
    /// spread, from which its confidence is computed ([`assign_confidence`]).
    pub positions: Option<&'a [[f64; 3]]>,
}

impl Side<'_> {
    fn check(&self, name: &str) -> Result<(), CorrespondError> {
        let n = self.descriptors.len();
        if self.labels.len() != n
            || self.profile.len() != n
            || self.halves.is_some_and(|h| h.len() != n)
            || self.sagittal.is_some_and(|h| h.len() != n)
            || self.positions.is_some_and(|h| h.len() != n)
        {
            return Err(CorrespondError::InvalidArgument(format!(
                "{name}: {n} descriptors, {} labels, {} profile values",
                self.labels.len(),
                self.profile.len()
            )));
        }
        Ok(())
    }
}

/// Options of [`match_points`].
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOptions {
    /// The candidate rule (§3.1).
    pub candidates: CandidateOptions,
    /// Apply the skeleton filter (§3.2). `false` is the ablation: the paper's method without
    /// its contribution.
    pub skeleton_filter: bool,
    /// Within the filter, also separate the left and right halves of the midline segments
    /// ([`Side::halves`], when both sides have them). `false` is the paper's filter exactly.
    pub midline_halves: bool,
    /// Beyond the paper: the sagittal band ([`sagittal_band`], when both sides have
    /// [`Side::sagittal`] and the filter is on): a midline point's candidates must lie on its
    /// side at least this fraction of its own (normalised) distance from the plane. `None`
    /// switches it off.
    pub sagittal_ratio: Option<f64>,
}

/// Default [`MatchOptions::sagittal_ratio`] (measured: see the crate docs).
pub const DEFAULT_SAGITTAL_RATIO: f64 = 0.5;

impl Default for MatchOptions {
    fn default() -> Self {
        MatchOptions {
            candidates: CandidateOptions::default(),
            skeleton_filter: true,
            midline_halves: true,
            sagittal_ratio: Some(DEFAULT_SAGITTAL_RATIO),
        }
    }
}

/// The result of [`match_points`].
#[derive(Debug, Clone)]
pub struct PointMatches {
    /// One match per template point that had a candidate, in the order of the points.
    pub matches: Vec<Match>,
    /// What the skeleton filter did (all zero when it was off).
    pub filter: FilterStats,
    /// What the sagittal band did (all zero when it was off).
    pub band: BandStats,
    /// Mean number of candidates per point before the filter.
    pub mean_candidates: f64,
    /// Seconds per stage: `candidates`, `skeleton_filter`, `selection`.
    pub timings: Vec<(&'static str, f64)>,
}

/// Stages 1–3 for the template points `points`: candidates, skeleton filter, selection.
///
/// Errors: [`CorrespondError::InvalidArgument`] if a side's tables disagree in length, the
/// descriptors differ in length between sides, or a point is out of range.
pub fn match_points(
    template: &Side<'_>,
    target: &Side<'_>,
    points: &[u32],
    options: &MatchOptions,
) -> Result<PointMatches, CorrespondError> {
    template.check("template")?;
    target.check("target")?;
    let mut timings = Vec::new();
    let t = Instant::now();
    let mut cands = candidates(
        template.descriptors,
        target.descriptors,
        points,
        &options.candidates,
    )?;
    timings.push(("candidates", t.elapsed().as_secs_f64()));
    let mean_candidates =
        cands.iter().map(Vec::len).sum::<usize>() as f64 / cands.len().max(1) as f64;
    let t = Instant::now();
    let filter = if options.skeleton_filter {
        let halves = match (options.midline_halves, template.halves, target.halves) {
            (true, Some(a), Some(b)) => Some((a, b)),
            _ => None,
        };
        skeleton_filter(
            &mut cands,
            points,
            (template.labels, target.labels),
            halves,
            template.descriptors,
            target.descriptors,
        )
    } else {
        FilterStats::default()
    };
    let band = match (
        options.skeleton_filter,
        options.sagittal_ratio,
        template.sagittal,
        target.sagittal,
    ) {
        (true, Some(ratio), Some(a), Some(b)) => sagittal_band(
            &mut cands,
            points,
            (template.labels, target.labels),
            (a, b),
            ratio,
            template.descriptors,
            target.descriptors,
        ),
        _ => BandStats::default(),
    };
    timings.push(("skeleton_filter", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let mut matches = select(&cands, points, template.profile, target.profile);
    if let Some(pos) = target.positions {
        // Points without candidates got no match, so walk the lists in step with the matches.
        let mut it = cands.iter().filter(|c| !c.is_empty());
        for m in matches.iter_mut() {
            let Some(list) = it.next() else { break };
            let c = pos[m.target as usize];
            let others: Vec<f64> = list
                .iter()
                .filter(|x| x.vertex != m.target)
                .map(|x| {
                    let q = pos[x.vertex as usize];
                    ((q[0] - c[0]).powi(2) + (q[1] - c[1]).powi(2) + (q[2] - c[2]).powi(2)).sqrt()
                })
                .collect();
            m.candidate_spread = Some(if others.is_empty() {
                f64::INFINITY
            } else {
                others.iter().sum::<f64>() / others.len() as f64
            });
        }
        assign_confidence(&mut matches);
    }
    timings.push(("selection", t.elapsed().as_secs_f64()));
    Ok(PointMatches {
        matches,
        filter,
        band,
        mean_candidates,
        timings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use Segment::*;

    #[test]
    fn ablation_flips_symmetric_points_and_the_filter_fixes_them() {
        // Target vertex 0 (left) and 1 (right) have identical descriptors and profiles; the
        // template's left point is slightly nearer the right one in descriptor space.
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(2, 1, vec![0.011, 0.01]).unwrap();
        let tl = [ThighLeft];
        let ul = [ThighLeft, ThighRight];
        let tp = [0.5];
        let up = [0.5, 0.5];
        let ts = Side {
            descriptors: &t,
            labels: &tl,
            profile: &tp,
            halves: None,
            sagittal: None,
            positions: None,
        };
        let us = Side {
            descriptors: &u,
            labels: &ul,
            profile: &up,
            halves: None,
            sagittal: None,
            positions: None,
        };
        let off = MatchOptions {
            skeleton_filter: false,
            ..MatchOptions::default()
        };
        assert_eq!(
            match_points(&ts, &us, &[0], &off).unwrap().matches[0].target,
            1
        );
        let on = match_points(&ts, &us, &[0], &MatchOptions::default()).unwrap();
        assert_eq!(on.matches[0].target, 0);
        assert_eq!(on.filter.removed, 1);
        assert_eq!(on.timings.len(), 3);
    }

    /// A torso point well left of the plane; its candidates are a vertex on the plane (the
    /// navel, say) with the best eq. 8 gap and one as far left as the point with a worse gap.
    /// The paper's selection takes the vertex on the plane; the sagittal band does not.
    #[test]
    fn sagittal_band_keeps_midline_points_off_the_plane() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(2, 1, vec![0.01, 0.02]).unwrap();
        let ts = Side {
            descriptors: &t,
            labels: &[Torso],
            profile: &[0.5],
            halves: Some(&[1]),
            sagittal: Some(&[0.7]),
            positions: None,
        };
        let us = Side {
            descriptors: &u,
            labels: &[Torso, Torso],
            profile: &[0.5, 0.6],
            halves: Some(&[0, 1]),
            sagittal: Some(&[0.0, 0.7]),
            positions: None,
        };
        let on = match_points(&ts, &us, &[0], &MatchOptions::default()).unwrap();
        assert_eq!(on.matches[0].target, 1);
        assert_eq!(on.band.removed, 1);
        let off = MatchOptions {
            sagittal_ratio: None,
            ..MatchOptions::default()
        };
        let out = match_points(&ts, &us, &[0], &off).unwrap();
        assert_eq!(out.matches[0].target, 0);
        assert_eq!(out.band, BandStats::default());
        // The ablation is the paper without its filter: no band either.
        let ablation = MatchOptions {
            skeleton_filter: false,
            ..MatchOptions::default()
        };
        let out = match_points(&ts, &us, &[0], &ablation).unwrap();
        assert_eq!(out.matches[0].target, 0);
    }

    #[test]
    fn mismatched_tables_are_errors() {
        let d = Descriptors::new(2, 1, vec![0.0, 1.0]).unwrap();
        let s = Side {
            descriptors: &d,
            labels: &[Torso],
            profile: &[0.0, 0.0],
            halves: None,
            sagittal: None,
            positions: None,
        };
        assert!(match_points(&s, &s, &[0], &MatchOptions::default()).is_err());
    }
}
