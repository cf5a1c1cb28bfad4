//! The matching stages of symcorr (DESIGN.md, Algorithms 3–7): three methods that map template
//! vertices to target vertices of another human body mesh without ever joining a left part to
//! a right one. Every stage is a plain function on plain data (evaluation is symcorr-eval's);
//! the `symcorr` crate prepares the spectral inputs (symcorr-spectral) and the segment
//! labels, skeleton and bone weights (symcorr-attach) and wires them in.
//!
//! # Data flow
//! * **Paper** (module `paper`, [`PaperInputs`] per mesh): [`candidates()`] (§3.1, nearest
//!   si-HKS descriptors) → [`skeleton_filter`] (§3.2, plus sagittal halves and the
//!   [`sagittal_band`]) → [`select`] (§3.3, eq. 7–8 with [`base_profile`]); [`match_points`]
//!   runs them, [`farthest_point_sample`] picks the sparse mode's points.
//! * **Refined** (module `refined`, [`RefinedInputs`]): landmark coordinates ⊕ si-HKS, nearest
//!   neighbour within [`SegmentPools`], then segment-constrained [`zoomout`] ([`refine_dense`]).
//! * **Articulated** (module `articulated`, [`ArticulatedInputs`]; symcorr's default):
//!   [`articulated_match`] skins the template onto the target's skeleton, runs articulated ICP
//!   within segment pools and a non-rigid step, then maps each vertex to the nearest target
//!   vertex of its pool. Extrinsic, so partial targets work.
//!
//! Every method returns [`Pair`]s; symcorr-eval's `evaluate`, `cumulative_curve` and
//! `table1_row` measure them. 3-D data inside the crate is nalgebra's; mesh positions arrive as the
//! `[f64; 3]` rows of `symcorr_mesh::TriMesh`.
//!
//! ```
//! use symcorr_skeleton::Segment::{ThighLeft, ThighRight};
//! use symcorr_correspond::{match_points, Descriptors, MatchOptions, PaperInputs};
//! // Two vertices per mesh with identical descriptors (a perfect left/right symmetry): only
//! // the segments tell them apart.
//! let d = Descriptors::new(2, 1, vec![1.0, 1.0]).unwrap();
//! let (labels, profile) = ([ThighLeft, ThighRight], [0.3, 0.3]);
//! let side = PaperInputs { descriptors: &d, labels: &labels, profile: &profile,
//!                          halves: None, sagittal: None, positions: None };
//! let out = match_points(&side, &side, &[0, 1], &MatchOptions::default()).unwrap();
//! assert_eq!((out.matches[0].target, out.matches[1].target), (0, 1));
//! ```
//!
//! # Invariants
//! * A match never joins a left segment to a right one: the filter and the pools are the
//!   skeleton constraint. When the filter leaves no candidate, the nearest target vertex of the
//!   same segment by descriptor is used and counted ([`FilterStats::fallbacks`]).
//! * Eq. 8 uses `|D̂(c) − D̂(p)|`, `D̂` the *mean* base-set distance over √area; ties go to the
//!   nearer descriptor.
//! * Confidence is in (0, 1] and means what its method says: candidate spread or descriptor
//!   distance and eq. 8 gap ([`assign_confidence`]), spectral residual ([`RefinedMatches`]),
//!   final fit distance ([`ArticulatedMatches`]).
//! * The methods' entry points return a [`CorrespondError`] for inconsistent input; a few
//!   single stages (`skeleton_filter`, `sagittal_band`, `skeleton_landmarks`) panic instead, as
//!   documented. Lengths in options are in √area units.
//!
//! # Measured choices
//! In `docs/decisions/` (each module's docs name its own): the paper pipeline's defaults,
//! midline halves and sagittal band (`2026-11-23-paper-pipeline-defaults.md`,
//! `2026-11-23-midline-halves-and-skull-plane.md`, `2026-11-23-sagittal-band.md`) and its dead
//! ends (`2026-12-01-lateral-band-rejected.md`, `2026-12-02-paper-pipeline-remaining-flips.md`,
//! `2026-12-02-paper-candidate-stage-variants.md`); `2026-11-23-refined-method.md`; the
//! articulated method (`2026-11-23-articulated-alignment.md`,
//! `2026-11-23-articulated-nonrigid-step.md`, `2026-12-01-articulated-adjacent-pools.md`,
//! `2026-12-01-articulated-kdtrees.md`).

mod articulated;
mod kdtree;
mod paper;
mod pools;
mod refined;

pub use articulated::{
    articulated_match, articulated_match_indexed, bone_transforms, outward_normals, skin,
    ArticulatedIndex, ArticulatedInputs, ArticulatedMatches, ArticulatedOptions, ArticulatedStart,
    BoneTransforms, TargetPairs, ViewHold, DEFAULT_HEAD_NECK_ANCHOR, DEFAULT_HEAD_TURN_PRIOR,
    DEFAULT_HEAD_TWIST_DOUBT, DEFAULT_HEAD_TWIST_PRIOR, DEFAULT_HEAD_WARM_TWIST,
    DEFAULT_ICP_POINTS, DEFAULT_WARM_RELAXATION, MAX_HEAD_TWIST_DEG, TWISTS, WARM_TWISTS,
};
pub use paper::{
    assign_confidence, base_profile, candidates, explain_point, farthest_point_sample,
    match_points, sagittal_band, select, skeleton_filter, BandStats, Candidate, CandidateOptions,
    Descriptors, FilterStats, Match, MatchOptions, PaperFilter, PaperInputs, PointExplanation,
    PointMatches, DEFAULT_SAGITTAL_RATIO,
};
pub use pools::{adjacent_segments, nearest_in_pools, SegmentPools};
pub use refined::{
    coverage, joint_landmarks, landmark_coordinates, refine_dense, refine_symmetry_plane,
    skeleton_landmarks, zoomout, RefineOptions, RefinedInputs, RefinedMatches, SpectralBasis,
    ZoomOutOptions, ZoomOutResult, DEFAULT_ZOOMOUT_POINTS,
};

/// Default number of nearest candidates per template point (§3.1), chosen by measurement
/// (`docs/decisions/2026-11-23-paper-pipeline-defaults.md`).
pub const DEFAULT_NEAREST: usize = 5;

/// Errors of the matching stages: bad input, never a numerical failure (the stages degrade
/// instead, e.g. a bone without enough pairs keeps its transform).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CorrespondError {
    /// Two tables that must describe the same vertices (or columns) differ in length.
    #[error("{what}: expected {expected}, found {found}")]
    LengthMismatch {
        /// Which table, on which side.
        what: String,
        /// The length the other tables give.
        expected: usize,
        /// This table's length.
        found: usize,
    },
    /// A mesh without vertices.
    #[error("the {side} mesh has no vertices")]
    EmptyMesh {
        /// `"template"` or `"target"`.
        side: &'static str,
    },
    /// An index (a template point, a map entry, a pool or landmark vertex) beyond its table.
    #[error("{what} {index} out of range ({len} entries)")]
    IndexOutOfRange {
        /// What the index names.
        what: &'static str,
        /// The index.
        index: usize,
        /// The table's length.
        len: usize,
    },
    /// A value that must be finite is not.
    #[error("{what} of row {row} is not finite")]
    NotFinite {
        /// What the value is.
        what: &'static str,
        /// The row (vertex) it belongs to.
        row: usize,
    },
    /// A surface area that is not positive and finite.
    #[error("area {0} is not positive and finite")]
    InvalidArea(f64),
    /// An [`ArticulatedIndex`] used with inputs or options other than those it was built for.
    #[error("the articulated index was built for another template, target or options")]
    IndexMismatch,
    /// A landmark source set without vertices.
    #[error("landmark {0} has no source vertex")]
    EmptyLandmark(usize),
    /// Options (or parameters) outside their domain; the message says which and why.
    #[error("invalid options: {0}")]
    InvalidOptions(String),
    /// The geodesic distances of symcorr-spectral failed.
    #[error("geodesic distances: {0}")]
    Geodesics(#[from] symcorr_spectral::SpectralError),
}

/// `Ok` when a table has the `expected` length, else [`CorrespondError::LengthMismatch`]
/// naming it (`what`, e.g. `"target labels"`).
pub(crate) fn same_len(what: &str, expected: usize, found: usize) -> Result<(), CorrespondError> {
    if expected == found {
        Ok(())
    } else {
        Err(CorrespondError::LengthMismatch {
            what: what.to_string(),
            expected,
            found,
        })
    }
}

/// A matched pair `template → target` with a confidence in (0, 1] (higher is more
/// trustworthy): what every method returns. What a confidence means is the method's own:
/// the paper's ranks by eq. 8's gap ([`assign_confidence`]), the refined method's by the
/// spectral residual, the articulated method's by the final fit distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair {
    /// Template vertex.
    pub template: u32,
    /// Target vertex.
    pub target: u32,
    /// Confidence in (0, 1].
    pub confidence: f64,
}
