//! The canonical Kinect skeleton, its 17 body segments, and skeleton attachment.
//!
//! [`Skeleton`], [`Joint`] and [`Segment`] (with [`Segment::mirror`]) are the types every joint
//! importer in symcorr produces. [`attach`] fits a skeleton into a triangle mesh and computes
//! Baran & Popović (2007) bone-heat weights and one of the 17 segment labels per vertex;
//! [`label`] is the one-call version with default options. The crate is usable on its own.
//!
//! # Data flow (DESIGN.md, Algorithm 1)
//! mesh + skeleton → joint repair (untracked joints rebuilt along their chain or dropped) →
//! frame alignment ([`FrameAlignment`]: units by a power of ten, then one of 24 axis rotations)
//! → handedness check ([`MirrorCheck`], [`MirrorPolicy`]; on its own: [`check_handedness`],
//! and as a verdict for a scan: [`handedness_verdict`]) → joint refinement (limb joints to
//! their cross-section's centre) → bone heat (`(L + M·H) W = M·H·P`, one sparse Cholesky for
//! all 19 bones, on the mesh or on clusters of a dense one: [`HeatMesh`]; [`BoneWeights`]) →
//! labels: the segment with the largest weight, side first; joint planes between neighbouring
//! segments ([`AttachOptions::joint_planes`]); the midline guard
//! ([`AttachOptions::midline_band`]); optionally a learned [`BoundaryConvention`] →
//! [`Attachment`] with its [`Diagnostics`]. The module sources explain each step.
//!
//! ```
//! use symcorr_attach::{attach, AttachOptions, Segment};
//! # let (mesh, skeleton) = symcorr_attach::doc_example();
//! let a = attach(&mesh, &skeleton, &AttachOptions::default()).unwrap();
//! assert_eq!(a.labels.len(), mesh.num_vertices());
//! // Every row of the weights sums to one.
//! let s: f64 = a.weights.row(0).iter().map(|&(_, w)| w).sum();
//! assert!((s - 1.0).abs() < 1e-9);
//! assert!(a.labels.contains(&Segment::ForearmLeft));
//! ```
//!
//! # Invariants
//! * Every vertex gets a label and a weight row (bones of [`BONES`], weights in (0, 1] summing
//!   to 1). A component no bone is visible from gets the nearest bone
//!   ([`ComponentReport::fallback`]); nothing is left empty.
//! * Sides come from bone heat and the skeleton: joint planes move a vertex across the body only
//!   into a twin root (hip, clavicle), the midline guard turns such labels near the sagittal
//!   plane into midline ones, and a convention never moves a vertex to the other side.
//! * The skeleton's sides are swapped only on clear evidence ([`MIRROR_MARGIN`]).
//! * Nothing is guessed silently: repairs, moves, refused moves and fallbacks are reported in
//!   [`Diagnostics`]; a scale mismatch other than a power of ten, a skeleton that fits nowhere
//!   and out-of-range options are errors ([`AttachError`]).
//!
//! # Measured choices
//! Measured against a rig's reference labels on generated MakeHuman bodies (tools/synth), in
//! `docs/decisions/`: `2026-11-23-attach-joint-planes.md` (and the agreement baseline),
//! `2026-11-23-attach-midline-guard-band.md`, `2026-11-23-attach-left-right-labels.md`,
//! `2026-11-23-attach-handedness-check.md`, `2026-12-02-attach-refinement-off-circle.md`,
//! `2026-12-01-attach-learned-boundary-convention.md` (with its two `2026-12-02-attach-convention-*`
//! follow-ups) and `2026-12-02-attach-noisy-joint-limit.md`.

// `!(x > 0.0)` is deliberate throughout: it is true for NaN as well.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod align;
mod bvh;
mod convention;
mod convention_makehuman;
mod error;
mod fit;
mod geom;
mod handedness;
mod heat;
pub mod palette;
mod planes;
mod refine;
mod repair;
mod tables;

pub use convention::{
    boundaries, BoundaryConvention, BoundaryRule, LabelledBody, ASYMMETRY_FACTOR, MIN_SIDE_BAND,
    SIDE_MARGIN,
};
pub use error::AttachError;
pub use fit::{camera_side, FitCheck, FitCheckKind, FitQuality, FIT_THRESHOLD, REACH};
pub use handedness::{handedness_verdict, Handedness, HandednessReport};
pub use symcorr_skeleton::{
    BodySide, Bone, Joint, LimbPair, Plane, SagittalPlanes, Segment, Skeleton, BONES,
};

use nalgebra::{Point3, Rotation3, Vector3};
use symcorr_mesh::TriMesh;

/// What to do when the skeleton's left and right are swapped relative to the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MirrorPolicy {
    /// Swap the skeleton's sides and report it (default).
    Fix,
    /// Return [`AttachError::MirroredSkeleton`].
    Refuse,
    /// Do not check.
    Ignore,
}

/// What to do when the skeleton fails a fit check ([`FitQuality`]) even after the rotation
/// search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoorFitPolicy {
    /// Return [`AttachError::PoorFit`] naming the worst check (default).
    Refuse,
    /// Attach anyway; [`FitQuality::accepted_poor_fit`] says so.
    Accept,
}

/// Options of [`attach`]. `AttachOptions::default()` is what [`label`] uses.
#[derive(Debug, Clone)]
pub struct AttachOptions {
    /// Detect and correct units, offset and axis rotation between skeleton and mesh.
    pub align: bool,
    /// Move joints to the centres of their cross-sections.
    pub refine_joints: bool,
    /// Handling of a left/right-swapped skeleton.
    pub mirror: MirrorPolicy,
    /// Handling of a skeleton that fails a fit check ([`FitQuality`]).
    pub poor_fit: PoorFitPolicy,
    /// Baran–Popović heat constant `c` in `H_ii = c/d²` (mass-weighted system).
    pub heat_constant: f64,
    /// The mesh the bone-heat system is solved on (default [`HeatMesh::Input`]).
    pub heat_mesh: HeatMesh,
    /// Weights below this (after clipping, before normalisation) are dropped.
    pub min_weight: f64,
    /// Largest joint move during refinement, as a fraction of the skeleton's height.
    pub max_joint_move: f64,
    /// Relative left/right bone-length difference above which both are set to their mean.
    pub bone_length_tolerance: f64,
    /// Reach of each segment's bones (index = [`Segment::index`]): bone heat uses the distance
    /// divided by the reach, so a segment with reach 2 claims vertices twice as far away.
    /// See [`DEFAULT_SEGMENT_REACH`].
    pub segment_reach: [f64; 17],
    /// Decide the boundary between two segments that share a joint by the joint plane — the
    /// plane through the joint whose normal bisects the two bone directions; between left and
    /// right twins the sagittal plane, made to contain the trunk axis — instead of the
    /// bone-heat argmax. Bone heat still decides which limb a vertex belongs to. Default `true`.
    pub joint_planes: bool,
    /// Half-width of the midline guard band, as a fraction of the skeleton's height: a vertex
    /// labelled hip (clavicle) within it of the left/right plane gets the midline segment
    /// (pelvis; torso or head); 0 disables it. With a [`AttachOptions::convention`] it is also the widest
    /// side band of the convention's rules and of the guard that runs after them (narrower
    /// for less noisy joints, see [`MIN_SIDE_BAND`]). Only used with
    /// [`AttachOptions::joint_planes`].
    pub midline_band: f64,
    /// Segment boundaries learned from a rig's skinning ([`BoundaryConvention`]), applied after
    /// the joint planes and the midline guard; `None` keeps the joint planes' bisectors.
    /// Only used with [`AttachOptions::joint_planes`].
    pub convention: Option<BoundaryConvention>,
}

/// The mesh on which bone heat's linear system is solved.
///
/// ```
/// use symcorr_attach::{attach, AttachOptions, HeatMesh};
/// # let (mesh, skeleton) = symcorr_attach::doc_example();
/// let options = AttachOptions { heat_mesh: HeatMesh::Clustered { radius: 0.006 }, ..Default::default() };
/// let a = attach(&mesh, &skeleton, &options).unwrap();
/// assert_eq!(a.labels.len(), mesh.num_vertices());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HeatMesh {
    /// The input mesh itself (Baran & Popović 2007).
    Input,
    /// The input's vertices gathered into clusters along its edges, each within `radius`
    /// (a fraction of the skeleton's height) of its seed vertex; the system is solved on the
    /// mesh of the clusters and every vertex takes its cluster's weights. Bone heat is smooth,
    /// so a dense mesh (a depth scan's 5 mm pixels) loses only the boundary's position within
    /// a cluster while the solve and the visibility rays shrink by the cluster size. A mesh
    /// whose edges are all longer than the radius is solved as [`HeatMesh::Input`].
    Clustered {
        /// Largest distance from a cluster's seed, in skeleton heights.
        radius: f64,
    },
}

/// Default [`AttachOptions::segment_reach`]: 1 for every segment (plain Baran–Popović).
pub const DEFAULT_SEGMENT_REACH: [f64; 17] = [1.0; 17];

impl Default for AttachOptions {
    fn default() -> Self {
        AttachOptions {
            align: true,
            refine_joints: true,
            mirror: MirrorPolicy::Fix,
            poor_fit: PoorFitPolicy::Refuse,
            heat_constant: 1.0,
            heat_mesh: HeatMesh::Input,
            min_weight: 0.01,
            max_joint_move: 0.08,
            bone_length_tolerance: 0.15,
            segment_reach: DEFAULT_SEGMENT_REACH,
            joint_planes: true,
            midline_band: 0.05,
            convention: None,
        }
    }
}

/// The similarity that took the skeleton into the mesh's frame: `p_mesh = scale·R·p + translation`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameAlignment {
    /// Uniform scale (a power of ten; 1 when units agreed).
    pub scale: f64,
    /// Rotation (identity unless the joints did not fit as given; then one of the 24 that
    /// permute the axes).
    pub rotation: Rotation3<f64>,
    /// Translation in mesh units.
    pub translation: Vector3<f64>,
    /// Median distance from a joint to the nearest mesh vertex, in skeleton heights, as given
    /// (after the scale only).
    pub fit_before: f64,
    /// The same after the alignment.
    pub fit_after: f64,
    /// Median distance from a mesh vertex to the nearest bone after the alignment, in skeleton
    /// heights (the bones must run through the whole mesh).
    pub coverage: f64,
}

impl FrameAlignment {
    /// The identity (no alignment).
    pub fn identity() -> Self {
        FrameAlignment {
            scale: 1.0,
            rotation: Rotation3::identity(),
            translation: Vector3::zeros(),
            fit_before: f64::NAN,
            fit_after: f64::NAN,
            coverage: f64::NAN,
        }
    }

    /// True if anything other than the identity was applied.
    pub fn is_identity(&self) -> bool {
        self.scale == 1.0
            && self.translation == Vector3::zeros()
            && self.rotation == Rotation3::identity()
    }

    /// Applies the similarity to a point.
    pub fn apply(&self, p: &Point3<f64>) -> Point3<f64> {
        (self.rotation * p) * self.scale + self.translation
    }
}

/// Result of the left/right handedness check. `Default` is the check not run: no evidence,
/// nothing swapped.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MirrorCheck {
    /// Mean cosine between the ankle→foot joints and the torso frame's facing direction
    /// (`None` without usable feet).
    pub skeleton_evidence: Option<f64>,
    /// Forward-minus-backward reach of the mesh around the ankles along the facing direction,
    /// normalised to [-1, 1] (`None` without usable feet).
    pub mesh_evidence: Option<f64>,
    /// Knee flexion cue in [-1, 1]: bent knees lie in front of the hip–ankle line along the
    /// facing direction (`None` without usable legs; near 0 for straight legs).
    pub knee_evidence: Option<f64>,
    /// The mesh cue in mesh units: how much farther the surface around the ankles reaches
    /// forward than backward along the facing direction, mean over the feet (`None` without
    /// usable feet).
    pub mesh_offset: Option<f64>,
    /// Mesh vertices the mesh cue used (both feet).
    pub mesh_vertices: usize,
    /// The skeleton's facing direction (unit, `left × up` of the torso frame: left = right → left
    /// shoulders and hips, up = hip centre → shoulder centre); `None` if the torso is degenerate.
    pub facing: Option<Vector3<f64>>,
    /// True if the sides were swapped (policy [`MirrorPolicy::Fix`]).
    pub swapped: bool,
    /// The limb pair whose sides were swapped back alone (policy [`MirrorPolicy::Fix`]): its
    /// left → right direction across the spine opposed the other pair's (shoulders against
    /// hips, a tracker's arm or leg swap), and the facing evidence said which of the two
    /// pairs was the exchanged one. The evidence fields describe the corrected skeleton.
    pub swapped_limbs: Option<LimbPair>,
}

impl MirrorCheck {
    /// Combined facing evidence: the mesh around the ankles and the knees' flexion count fully,
    /// the ankle→foot joints half. Exactly antisymmetric under a side swap of the
    /// skeleton; below `-`[`MIRROR_MARGIN`] the skeleton's sides are swapped.
    pub fn evidence(&self) -> f64 {
        refine::mirror_decision(self)
    }

    /// The joint of the skeleton as given that the checked skeleton's joint `j` came from:
    /// through the limb pair swapped back ([`MirrorCheck::swapped_limbs`]), then the whole
    /// side swap ([`MirrorCheck::swapped`]).
    ///
    /// ```
    /// use symcorr_attach::{Joint, LimbPair, MirrorCheck};
    /// let m = MirrorCheck { swapped_limbs: Some(LimbPair::Legs), ..MirrorCheck::default() };
    /// assert_eq!(m.source(Joint::KneeLeft), Joint::KneeRight);
    /// assert_eq!(m.source(Joint::ElbowLeft), Joint::ElbowLeft);
    /// ```
    pub fn source(&self, j: Joint) -> Joint {
        let j = j.mirror_if(self.swapped);
        match self.swapped_limbs {
            Some(pair)
                if pair
                    .left_joints()
                    .iter()
                    .any(|&l| l == j || l.mirror() == j) =>
            {
                j.mirror()
            }
            _ => j,
        }
    }

    /// `skeleton` with the corrections this check made ([`MirrorCheck::source`]): its joints as
    /// the attachment read them.
    ///
    /// ```
    /// use symcorr_attach::{Joint, LimbPair, MirrorCheck, Skeleton};
    /// let mut xyz = [[0.0; 3]; Joint::COUNT];
    /// xyz[Joint::KneeLeft.index()] = [0.1, 0.5, 2.0];
    /// let s = Skeleton::from_arrays(xyz);
    /// let m = MirrorCheck { swapped_limbs: Some(LimbPair::Legs), ..MirrorCheck::default() };
    /// assert_eq!(m.apply(&s).positions, s.swap_limbs(LimbPair::Legs).positions);
    /// ```
    pub fn apply(&self, skeleton: &Skeleton) -> Skeleton {
        let mut out = skeleton.clone();
        for j in Joint::ALL {
            let from = self.source(j).index();
            out.positions[j.index()] = skeleton.positions[from];
            out.confidence[j.index()] = skeleton.confidence[from];
            out.interpolated[j.index()] = skeleton.interpolated[from];
        }
        out
    }

    /// True if the evidence says the skeleton's left and right are swapped relative to the
    /// mesh (`evidence() < -MIRROR_MARGIN`).
    pub fn says_swapped(&self) -> bool {
        self.evidence() < -MIRROR_MARGIN
    }
}

pub use refine::MIRROR_MARGIN;

/// The handedness check on its own: is `skeleton`'s left/right consistent with `mesh`? Both must
/// be in the same frame (no alignment is done here). Untracked or non-finite joints are
/// repaired as in [`attach`]; the result's `swapped` is always `false` (nothing is changed);
/// see [`MirrorCheck::says_swapped`]. A limb pair exchanged against the other (shoulders and
/// hips opposed across the spine) is named in `swapped_limbs`, as [`attach`] decides it, and
/// the evidence is then that of the skeleton with the pair swapped back; one that nothing
/// tells apart is [`AttachError::LimbSidesUndetermined`].
///
/// ```
/// # let (mesh, skeleton) = symcorr_attach::doc_example();
/// let ok = symcorr_attach::check_handedness(&mesh, &skeleton).unwrap();
/// assert!(!ok.says_swapped());
/// let mirrored = symcorr_attach::check_handedness(&mesh, &skeleton.swap_sides()).unwrap();
/// assert!(mirrored.says_swapped());
/// ```
pub fn check_handedness(mesh: &TriMesh, skeleton: &Skeleton) -> Result<MirrorCheck, AttachError> {
    if mesh.num_vertices() == 0 {
        return Err(AttachError::EmptyMesh {
            vertices: mesh.num_vertices(),
            triangles: mesh.num_triangles(),
        });
    }
    let rep = repair::repair(skeleton)?;
    let height = repair::skeleton_height(&rep.positions, &rep.usable);
    let (positions, usable, swapped_limbs) =
        limb_pair_step(mesh, rep.positions, rep.usable, height)?;
    let mut check = refine::mirror_check(mesh, &positions, &usable, height);
    check.swapped_limbs = swapped_limbs;
    Ok(check)
}

/// How a joint was repaired before attachment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointRepair {
    /// Rebuilt from neighbouring joints along its chain.
    Interpolated,
    /// Could not be rebuilt; the bones touching it were dropped.
    Dropped,
}

/// A joint moved by refinement.
#[derive(Debug, Clone, PartialEq)]
pub struct JointMove {
    /// The joint.
    pub joint: Joint,
    /// Position before (mesh frame, after alignment).
    pub from: Point3<f64>,
    /// Position after.
    pub to: Point3<f64>,
    /// Why: `"cross-section centre"`, `"depth centre"`, `"bone length"`.
    pub reason: &'static str,
}

impl JointMove {
    /// Distance moved, in mesh units.
    pub fn distance(&self) -> f64 {
        nalgebra::distance(&self.from, &self.to)
    }
}

/// One connected component of the mesh in bone heat.
#[derive(Debug, Clone, PartialEq)]
pub struct ComponentReport {
    /// Vertices in the component.
    pub vertices: usize,
    /// Vertices that saw a bone (heat sources; with [`HeatMesh::Clustered`], the vertices of
    /// the clusters whose seed saw one).
    pub visible_vertices: usize,
    /// True if no vertex saw a bone and the nearest bones were used instead.
    pub fallback: bool,
}

/// Everything [`attach`] did besides labelling: repairs, alignment, moves, fallbacks.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostics {
    /// Joints rebuilt or dropped before anything else.
    pub repaired_joints: Vec<(Joint, JointRepair)>,
    /// Bones (indices into [`BONES`]) left out because a joint was dropped.
    pub dropped_bones: Vec<usize>,
    /// The frame alignment applied.
    pub alignment: FrameAlignment,
    /// The handedness check.
    pub mirror: MirrorCheck,
    /// How well the skeleton fits the mesh after alignment and the handedness fix.
    pub fit: FitQuality,
    /// Joints moved by refinement (in order of application).
    pub joint_moves: Vec<JointMove>,
    /// Joint moves that refinement proposed but refused (too far, or no cross-section).
    pub refinement_skipped: Vec<(Joint, &'static str)>,
    /// Per connected component of the mesh.
    pub components: Vec<ComponentReport>,
    /// Vertices whose weight row came out empty and got the nearest bone instead, plus
    /// vertices in no non-degenerate triangle.
    pub nearest_bone_vertices: usize,
    /// Skeleton height used for relative thresholds (mesh units).
    pub skeleton_height: f64,
    /// Left/right asymmetry of the joints as given (after alignment), where a body is symmetric
    /// in every pose: root mean square of the hip centre's offset from the hips' midpoint and
    /// of the left − right length differences of the hip, thigh, shin, upper-arm and forearm
    /// bones (mesh units). About the joints' noise level: 0 for exact joints, 2–10 cm for
    /// σ = 3 cm noise. `None` without the joints it needs.
    pub joint_asymmetry: Option<f64>,
    /// Vertices whose label the boundary convention changed (its rules, then the midline
    /// guard once more, against the joint planes' labels); `None` without
    /// [`AttachOptions::convention`].
    pub convention_changes: Option<usize>,
    /// Wall-clock seconds per stage: `align`, `mirror`, `fit` (the checks and, when one fails,
    /// the rotation search), `refine`, `heat`, `labels` (argmax, joint planes, midline guard).
    pub timings_s: Vec<(&'static str, f64)>,
}

/// Sparse per-vertex bone weights (CSR): for each vertex, `(bone index into BONES, weight)`
/// pairs with weights in (0, 1] summing to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct BoneWeights {
    offsets: Vec<usize>,
    entries: Vec<(usize, f64)>,
}

impl BoneWeights {
    pub(crate) fn from_rows(rows: Vec<Vec<(usize, f64)>>) -> Self {
        let mut offsets = Vec::with_capacity(rows.len() + 1);
        let mut entries = Vec::new();
        offsets.push(0);
        for r in rows {
            entries.extend(r);
            offsets.push(entries.len());
        }
        BoneWeights { offsets, entries }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True for a mesh without vertices (never for a result of [`attach`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The non-zero `(bone, weight)` pairs of vertex `v` (bone indexes [`BONES`]).
    pub fn row(&self, v: usize) -> &[(usize, f64)] {
        &self.entries[self.offsets[v]..self.offsets[v + 1]]
    }

    /// Weights of vertex `v` summed per segment (index = [`Segment::index`]).
    pub fn segment_weights(&self, v: usize) -> [f64; 17] {
        let mut s = [0.0; 17];
        for &(b, w) in self.row(v) {
            s[bone_segment(b).index()] += w;
        }
        s
    }
}

/// The segment that bone `b` (index into [`BONES`]) belongs to.
pub fn bone_segment(b: usize) -> Segment {
    let bone = BONES[b];
    Segment::ALL
        .into_iter()
        .find(|s| s.bones().contains(&bone))
        // Invariant: every bone belongs to exactly one segment (tested in skeleton.rs).
        .unwrap_or(Segment::Torso)
}

/// The result of [`attach`].
#[derive(Debug, Clone, PartialEq)]
pub struct Attachment {
    /// One segment per mesh vertex.
    pub labels: Vec<Segment>,
    /// Bone-heat weights per vertex.
    pub weights: BoneWeights,
    /// The refined skeleton in the mesh's frame (what the bones were placed at).
    pub joints: Skeleton,
    /// What was repaired, applied and moved.
    pub diagnostics: Diagnostics,
}

/// Fits `skeleton` into `mesh` and computes bone-heat weights and segment labels
/// (DESIGN.md, Algorithm 1; see the crate docs for the steps).
///
/// Errors: [`AttachError::EmptyMesh`], [`AttachError::EmptySkeleton`],
/// [`AttachError::ScaleMismatch`], [`AttachError::AlignmentFailed`],
/// [`AttachError::MirroredSkeleton`] (with [`MirrorPolicy::Refuse`]), [`AttachError::Solver`].
///
/// ```
/// use symcorr_attach::{attach, AttachOptions, Segment};
/// # let (mesh, skeleton) = symcorr_attach::doc_example();
/// let a = attach(&mesh, &skeleton, &AttachOptions::default()).unwrap();
/// assert_eq!(a.labels.len(), mesh.num_vertices());
/// assert!(a.labels.contains(&Segment::ForearmLeft) && a.labels.contains(&Segment::ForearmRight));
/// // One weight row per vertex over the 19 bones; each row sums to 1.
/// let sum: f64 = a.weights.row(0).iter().map(|&(_, w)| w).sum();
/// assert!((sum - 1.0).abs() < 1e-9);
/// ```
pub fn attach(
    mesh: &TriMesh,
    skeleton: &Skeleton,
    options: &AttachOptions,
) -> Result<Attachment, AttachError> {
    attach_with_usable(mesh, skeleton, options).map(|(a, _)| a)
}

/// [`attach`], also returning which joints were usable (finite and tracked, or repaired) —
/// what the bones and frames were built from.
pub(crate) fn attach_with_usable(
    mesh: &TriMesh,
    skeleton: &Skeleton,
    options: &AttachOptions,
) -> Result<(Attachment, [bool; 20]), AttachError> {
    check_options(options)?;
    if mesh.num_vertices() == 0 || mesh.num_triangles() == 0 {
        return Err(AttachError::EmptyMesh {
            vertices: mesh.num_vertices(),
            triangles: mesh.num_triangles(),
        });
    }
    let mut timings_s = Vec::new();
    let mut clock = std::time::Instant::now();
    let mut lap = |name: &'static str, clock: &mut std::time::Instant| {
        timings_s.push((name, clock.elapsed().as_secs_f64()));
        *clock = std::time::Instant::now();
    };
    // 1. Repair missing joints.
    let rep = repair::repair(skeleton)?;
    let mut positions = rep.positions;
    // 2. Frame alignment.
    let mut alignment = if options.align {
        align::align(mesh, &mut positions, &rep.usable)?
    } else {
        FrameAlignment::identity()
    };
    let height = repair::skeleton_height(&positions, &rep.usable);
    lap("align", &mut clock);
    // 3. Mirror check, then the fit checks; a skeleton that fails one is searched for a
    //    better placement (turned about its up axis, upside down).
    let (mut positions, mut usable, mut mirror) =
        mirror_step(mesh, positions, rep.usable, height, options.mirror)?;
    lap("mirror", &mut clock);
    // One BVH of the mesh serves the fit checks and the bone heat's visibility rays.
    let bvh = bvh::TriangleBvh::new(mesh);
    let tables = tables::MeshTables::new(mesh);
    let fit_mesh = fit::FitMesh::new(&tables, &bvh, &positions, &usable);
    let mut fit = fit::measure(&fit_mesh, &positions, &usable, height, &mirror);
    if !fit.passed() && options.align {
        let unmirrored = if mirror.swapped {
            swap_sides(&positions, &usable)
        } else {
            (positions, usable)
        };
        let centroid = mesh_centroid(mesh);
        let mut best = None;
        // A limb pair already swapped back stays so (and reported) in every placement.
        let swapped_limbs = mirror.swapped_limbs;
        for (r, t) in fit::search(&fit_mesh, &unmirrored.0, &unmirrored.1, height, &centroid) {
            let q: geom::Joints = std::array::from_fn(|j| r * unmirrored.0[j] + t);
            let Ok((q, qu, mut m)) = mirror_step(mesh, q, unmirrored.1, height, options.mirror)
            else {
                continue;
            };
            m.swapped_limbs = m.swapped_limbs.or(swapped_limbs);
            let f = fit::measure(&fit_mesh, &q, &qu, height, &m);
            if f.passed()
                && best
                    .as_ref()
                    .is_none_or(|b: &(fit::FitQuality, _, _, _, _, _)| f.score > b.0.score)
            {
                best = Some((f, q, qu, m, r, t));
            }
        }
        if let Some((f, q, qu, m, r, t)) = best {
            alignment.rotation = r * alignment.rotation;
            alignment.translation = r * alignment.translation + t;
            alignment.fit_after = f
                .check(FitCheckKind::SurfaceDistance)
                .map_or(f64::NAN, |c| c.value);
            alignment.coverage = align::coverage(mesh, &q, &qu, height);
            (fit, positions, usable, mirror) = (f, q, qu, m);
        }
    }
    if let Some(worst) = fit.worst().copied() {
        match options.poor_fit {
            PoorFitPolicy::Refuse => {
                return Err(AttachError::PoorFit {
                    check: worst.kind.name(),
                    value: worst.value,
                    limit: worst.limit,
                    meaning: worst.kind.meaning(),
                    two_large_parts: fit_mesh.two_large_parts(),
                })
            }
            PoorFitPolicy::Accept => fit.accepted_poor_fit = true,
        }
    }
    lap("fit", &mut clock);
    // Before refinement, which evens out left/right bone lengths.
    let asymmetry = planes::joint_asymmetry(&positions, &usable);
    // 4. Refinement.
    let mut joint_moves = Vec::new();
    let mut refinement_skipped = Vec::new();
    if options.refine_joints {
        let r = refine::refine(&tables, &mut positions, &usable, height, options);
        joint_moves = r.moves;
        refinement_skipped = r.skipped;
    }
    lap("refine", &mut clock);
    // 5. Bone heat.
    let active: Vec<usize> = (0..BONES.len())
        .filter(|&b| usable[BONES[b].parent.index()] && usable[BONES[b].child.index()])
        .collect();
    let dropped_bones: Vec<usize> = (0..BONES.len()).filter(|b| !active.contains(b)).collect();
    let mut reach = [1.0; 19];
    for (b, r) in reach.iter_mut().enumerate() {
        *r = options.segment_reach[bone_segment(b).index()];
    }
    let heat = heat::bone_heat(
        &tables,
        &bvh,
        &heat::HeatProblem {
            p: &positions,
            active: &active,
            reach: &reach,
            c: options.heat_constant,
            min_weight: options.min_weight,
        },
        options.heat_mesh,
        height,
    )?;
    lap("heat", &mut clock);
    let mut labels: Vec<Segment> = (0..mesh.num_vertices())
        .map(|v| side_first_argmax(&heat.weights.segment_weights(v)))
        .collect();
    let mut convention_changes = None;
    if options.joint_planes {
        let planes = planes::joint_planes(&positions, &usable);
        let heat_labels = labels.clone();
        planes::apply(&mesh.positions, &positions, &planes, &mut labels);
        planes::keep_limb_sides(&heat_labels, &mut labels);
        planes::midline_guard(
            &mesh.positions,
            &positions,
            &planes,
            options.midline_band * height,
            &mut labels,
        );
        if let Some(conv) = &options.convention {
            let band = convention::side_band(asymmetry, height, options.midline_band);
            let before = labels.clone();
            convention::apply(
                conv,
                &mesh.positions,
                &positions,
                &usable,
                &planes,
                band,
                &|v| heat.weights.segment_weights(v),
                &mut labels,
            );
            planes::midline_guard(&mesh.positions, &positions, &planes, band, &mut labels);
            convention_changes = Some(labels.iter().zip(&before).filter(|(a, b)| a != b).count());
        }
    }
    lap("labels", &mut clock);
    let mut joints = Skeleton::from_positions(positions);
    // A relative angle, read without left/right labels: the same for the refined joints and
    // whichever sides the mirror check kept.
    joints.head_turn = skeleton.head_turn;
    for j in Joint::ALL {
        joints.confidence[j.index()] = if usable[j.index()] {
            skeleton.confidence[mirror.source(j).index()].max(0.0)
        } else {
            0.0
        };
        joints.interpolated[j.index()] = rep
            .repaired
            .iter()
            .any(|&(k, r)| k == mirror.source(j) && r == JointRepair::Interpolated)
            || skeleton.interpolated[mirror.source(j).index()];
    }
    let attachment = Attachment {
        labels,
        weights: heat.weights,
        joints,
        diagnostics: Diagnostics {
            repaired_joints: rep.repaired,
            dropped_bones,
            alignment,
            mirror,
            fit,
            joint_moves,
            refinement_skipped,
            components: heat.components,
            nearest_bone_vertices: heat.nearest_bone_vertices,
            skeleton_height: height,
            joint_asymmetry: asymmetry,
            convention_changes,
            timings_s,
        },
    };
    Ok((attachment, usable))
}

/// The handedness check on aligned joints and, on clear evidence, the side swap
/// ([`MirrorPolicy`]).
fn mirror_step(
    mesh: &TriMesh,
    positions: geom::Joints,
    usable: [bool; 20],
    height: f64,
    policy: MirrorPolicy,
) -> Result<(geom::Joints, [bool; 20], MirrorCheck), AttachError> {
    if policy == MirrorPolicy::Ignore {
        return Ok((positions, usable, MirrorCheck::default()));
    }
    let (positions, usable, swapped_limbs) = limb_pair_step(mesh, positions, usable, height)?;
    if let (Some(pair), MirrorPolicy::Refuse) = (swapped_limbs, policy) {
        return Err(AttachError::SwappedLimbs { pair });
    }
    let mut mirror = refine::mirror_check(mesh, &positions, &usable, height);
    mirror.swapped_limbs = swapped_limbs;
    let evidence = mirror.evidence();
    if evidence < -MIRROR_MARGIN {
        if policy == MirrorPolicy::Refuse {
            return Err(AttachError::MirroredSkeleton { evidence });
        }
        let (p, u) = swap_sides(&positions, &usable);
        mirror.swapped = true;
        return Ok((p, u, mirror));
    }
    Ok((positions, usable, mirror))
}

/// Below this cosine between the shoulders' and the hips' left → right directions (across the
/// spine) the two pairs point opposite ways: one of them is exchanged. A torso twists by 45–60°
/// at most; 120° leaves room for a tracker's noise on hips 15–25 cm apart.
const OPPOSED_PAIRS_COS: f64 = -0.5;

/// A tracker's swap of one limb pair, undone: when the shoulders' and the hips' left → right
/// directions across the spine oppose ([`OPPOSED_PAIRS_COS`]), the arms and the legs each get
/// swapped back in turn and the facing evidence of the result ([`MirrorCheck::evidence`]: the
/// feet point forward, the knees bend forward, the mesh reaches forward around the ankles)
/// picks the one that makes the body consistent — the other leaves a fully mirrored skeleton,
/// whose evidence is the same with the sign reversed. The torso frame of the whole-body check
/// averages the two pairs' directions, so without this step their disagreement is noise there.
/// Evidence too weak to choose (no feet, straight legs) is an error naming the cause: matching
/// on either guess maps one limb pair onto its twin.
fn limb_pair_step(
    mesh: &TriMesh,
    positions: geom::Joints,
    usable: [bool; 20],
    height: f64,
) -> Result<(geom::Joints, [bool; 20], Option<LimbPair>), AttachError> {
    let Some(cos) = pairs_cosine(&positions, &usable) else {
        return Ok((positions, usable, None));
    };
    if cos > OPPOSED_PAIRS_COS {
        return Ok((positions, usable, None));
    }
    let swapped = |pair: LimbPair| {
        let (mut p, mut u) = (positions, usable);
        for l in pair.left_joints() {
            let (a, b) = (l.index(), l.mirror().index());
            p.swap(a, b);
            u.swap(a, b);
        }
        let evidence = refine::mirror_check(mesh, &p, &u, height).evidence();
        (p, u, evidence)
    };
    let (arms, legs) = (swapped(LimbPair::Arms), swapped(LimbPair::Legs));
    if arms.2 - legs.2 > 2.0 * MIRROR_MARGIN {
        Ok((arms.0, arms.1, Some(LimbPair::Arms)))
    } else if legs.2 - arms.2 > 2.0 * MIRROR_MARGIN {
        Ok((legs.0, legs.1, Some(LimbPair::Legs)))
    } else {
        Err(AttachError::LimbSidesUndetermined {
            cosine: cos,
            evidence: arms.2.max(legs.2),
        })
    }
}

/// The cosine between the shoulders' and the hips' left → right directions, both taken across
/// the spine (hip centre → shoulder centre); `None` without those six joints or when one
/// direction vanishes.
fn pairs_cosine(p: &geom::Joints, usable: &[bool; 20]) -> Option<f64> {
    use Joint as J;
    let joints = [
        J::HipCenter,
        J::ShoulderCenter,
        J::ShoulderLeft,
        J::ShoulderRight,
        J::HipLeft,
        J::HipRight,
    ];
    if !joints.iter().all(|j| usable[j.index()]) {
        return None;
    }
    let up = geom::unit(p[J::ShoulderCenter.index()] - p[J::HipCenter.index()])?;
    let across = |l: Joint, r: Joint| {
        let d = p[l.index()] - p[r.index()];
        geom::unit(d - up * d.dot(&up))
    };
    let s = across(J::ShoulderLeft, J::ShoulderRight)?;
    let h = across(J::HipLeft, J::HipRight)?;
    Some(s.dot(&h))
}

/// The joints with left and right exchanged.
fn swap_sides(positions: &geom::Joints, usable: &[bool; 20]) -> (geom::Joints, [bool; 20]) {
    let mut p = *positions;
    let mut u = *usable;
    for j in Joint::ALL {
        p[j.index()] = positions[j.mirror().index()];
        u[j.index()] = usable[j.mirror().index()];
    }
    (p, u)
}

/// The mean of the mesh's vertices.
fn mesh_centroid(mesh: &TriMesh) -> Point3<f64> {
    let n = mesh.num_vertices().max(1) as f64;
    Point3::from(
        mesh.positions
            .iter()
            .map(|&x| Vector3::from(x))
            .sum::<Vector3<f64>>()
            / n,
    )
}

/// The segment with the largest weight, except that the side is decided first: if the best
/// segment is a left (right) one but the right (left) segments together weigh more than the
/// left (right) ones, the best segment of that side. At the groin a vertex can carry 0.34 of
/// the left thigh and 0.30 + 0.24 of the right hip and thigh; the plain argmax gave it the left
/// thigh against the majority of its weight.
fn side_first_argmax(s: &[f64; 17]) -> Segment {
    let best = |keep: &dyn Fn(Segment) -> bool| {
        Segment::ALL
            .into_iter()
            .filter(|x| keep(*x))
            .max_by(|a, b| s[a.index()].total_cmp(&s[b.index()]))
            .unwrap_or(Segment::Torso)
    };
    let b = best(&|_| true);
    if b.mirror() == b {
        return b;
    }
    let (left, right) = planes::side_weights(s);
    let (own, other) = if b.side() == BodySide::Left {
        (left, right)
    } else {
        (right, left)
    };
    if other > own {
        best(&|x| x != x.mirror() && planes::same_side(x, b.mirror()))
    } else {
        b
    }
}

/// One segment label per vertex with [`AttachOptions::default`] (see [`attach`]).
///
/// ```
/// use symcorr_attach::{label, Segment};
/// # let (mesh, skeleton) = symcorr_attach::doc_example();
/// let labels = label(&mesh, &skeleton).unwrap();
/// assert_eq!(labels.len(), mesh.num_vertices());
/// // A vertex at the left hand's joint is labelled with the left forearm, never the right.
/// let hand = skeleton.position(symcorr_attach::Joint::HandLeft);
/// let nearest = (0..mesh.num_vertices())
///     .min_by(|&a, &b| {
///         let d = |v: usize| (nalgebra::Point3::from(mesh.positions[v]) - hand).norm();
///         d(a).total_cmp(&d(b))
///     })
///     .unwrap();
/// assert_eq!(labels[nearest], Segment::ForearmLeft);
/// ```
pub fn label(mesh: &TriMesh, skeleton: &Skeleton) -> Result<Vec<Segment>, AttachError> {
    attach(mesh, skeleton, &AttachOptions::default()).map(|a| a.labels)
}

fn check_options(o: &AttachOptions) -> Result<(), AttachError> {
    let bad = |name: &'static str, value: f64| Err(AttachError::OptionOutOfRange { name, value });
    if !(o.heat_constant.is_finite() && o.heat_constant > 0.0) {
        return bad("heat_constant", o.heat_constant);
    }
    if !(0.0..0.5).contains(&o.min_weight) {
        return bad("min_weight", o.min_weight);
    }
    if let HeatMesh::Clustered { radius } = o.heat_mesh {
        // More than a tenth of the body would merge whole limbs into a cluster.
        if !(radius.is_finite() && radius > 0.0 && radius <= 0.1) {
            return bad("heat_mesh.radius", radius);
        }
    }
    if !(o.max_joint_move.is_finite() && o.max_joint_move >= 0.0) {
        return bad("max_joint_move", o.max_joint_move);
    }
    if !(o.bone_length_tolerance.is_finite() && o.bone_length_tolerance >= 0.0) {
        return bad("bone_length_tolerance", o.bone_length_tolerance);
    }
    if !(o.midline_band.is_finite() && o.midline_band >= 0.0) {
        return bad("midline_band", o.midline_band);
    }
    if let Some(c) = &o.convention {
        if !o.joint_planes {
            return Err(AttachError::ConventionNeedsJointPlanes);
        }
        if let Some(r) = c
            .rules
            .iter()
            .find(|r| r.a == r.b || r.a.mirror() == r.b || !r.plane.iter().all(|x| x.is_finite()))
        {
            return Err(AttachError::InvalidBoundaryRule {
                a: r.a.name(),
                b: r.b.name(),
                joint: r.joint.name(),
                plane: r.plane,
            });
        }
    }
    if let Some(&r) = o
        .segment_reach
        .iter()
        .find(|r| !(r.is_finite() && **r > 0.0))
    {
        return bad("segment_reach", r);
    }
    Ok(())
}

/// A small stick-figure mesh and its skeleton, for the documentation examples.
#[doc(hidden)]
pub fn doc_example() -> (TriMesh, Skeleton) {
    let sk = testbody::t_pose(1.0);
    (testbody::capsule_body(&sk, 0.04).0, sk)
}

#[doc(hidden)]
pub mod testbody;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_side_with_more_weight_wins() {
        let mut w = [0.0; 17];
        // Groin: left thigh 0.34, right hip 0.30 + right thigh 0.24 → the right thigh.
        w[Segment::ThighLeft.index()] = 0.34;
        w[Segment::HipRight.index()] = 0.30;
        w[Segment::ThighRight.index()] = 0.24;
        w[Segment::Pelvis.index()] = 0.12;
        assert_eq!(side_first_argmax(&w), Segment::HipRight);
        // The left side holds its majority: plain argmax.
        w[Segment::HipLeft.index()] = 0.25;
        assert_eq!(side_first_argmax(&w), Segment::ThighLeft);
        // A midline winner is kept whatever the sides weigh.
        let mut m = [0.0; 17];
        m[Segment::Torso.index()] = 0.4;
        m[Segment::ClavicleLeft.index()] = 0.3;
        m[Segment::UpperArmLeft.index()] = 0.3;
        assert_eq!(side_first_argmax(&m), Segment::Torso);
    }
}
