//! symcorr: skeleton-aware human shape correspondence — the pipeline API behind the `symcorr`
//! command.
//!
//! The paper's pipeline ("Symmetry-Aware Human Shape Correspondence Using Skeleton";
//! DESIGN.md, Algorithms 1–6) in two halves:
//!
//! * [`PreparedMesh::new`] — everything about one mesh: cotan Laplacian, eigenpairs, si-HKS,
//!   Gaussian curvature, base vertex set and its geodesic profile (symcorr-spectral), and,
//!   in parallel, skeleton attachment and segment labels (symcorr-attach). Computed once per
//!   mesh and reused for every pair it is in.
//! * [`Pipeline::run`] — one pair: template points (farthest-point sample or every vertex),
//!   si-HKS candidates, the skeleton filter, eq. 8 selection (symcorr-correspond).
//!
//! Three methods share these halves ([`Method`]):
//! * [`Method::Articulated`], the default: the template, skinned with its bone-heat weights,
//!   is posed onto the target's skeleton and fitted bone by bone (ICP within segment pools,
//!   the head's twist searched); every template vertex then takes the nearest target vertex of
//!   its pool (symcorr-correspond's `articulated_match`). It needs only the attachment (no
//!   spectral stage), handles single-view scans ([`PreparedMesh::is_partial`]) and says which
//!   template points a scan does not show ([`Correspondence::has_counterpart`]).
//! * [`Method::Refined`]: skeleton landmark coordinates + si-HKS initial map within segment
//!   pools, then segment-constrained ZoomOut (DESIGN.md Algorithm 7, `refine_dense`).
//! * [`Method::Paper`], the paper's pipeline above.
//!
//! Why the articulated method is the default (58 pairs of generated bodies, dense, README):
//! exact joints 0.0025 mean error and no flip vs 0.025 for the refined method; single-view scans 0.018 vs
//! 0.11 (measured on the template's surface). Intrinsic descriptors change wholesale when half
//! the surface is missing; the skeleton does not.
//!
//! Every mesh first goes through the default repair
//! (`symcorr_mesh::repair`); the stages work on the repaired mesh and every output speaks the
//! input file's vertex ids ([`PreparedMesh::input_id`]).
//!
//! [`dataset`] runs a benchmark folder in DESIGN.md's layout and [`output`] writes the
//! `symcorr.correspondence/1` JSON, coloured meshes and the error-curve plot.
//!
//! # Decisions the design leaves open
//! * **si-HKS window relative to the area**: times `t = area·2^τ`, `τ ∈ [−8, 3]`, step 1/16,
//!   6 frequencies, from [`DEFAULT_EIGENPAIRS`] = 60 eigenpairs. Bronstein & Kokkinos's absolute
//!   window (`t = 2^1…2^25`) lies, for a body in metres, where every non-constant
//!   eigenfunction has decayed, and gave mean error ≈ 0.10; sweeping the window on a 6-pair
//!   subset of `fixtures/synth/bodies` (500 samples): `[−12, 0]` 0.067, `[−10, 2]` 0.059,
//!   `[−8, 3]` 0.053, `[−8, 5]` 0.057, `[−6, 4]` 0.062, `[−4, 4]` 0.078.
//! * **Candidates**: the N = 5 nearest si-HKS descriptors (same subset: N = 1 0.0625,
//!   5 0.062, 10 0.064, 20 0.067, 100 0.078, 800 0.114 at the `[−12, 0]` window): eq. 8's
//!   scalar selects poorly among many candidates, so few are best.
//! * **Base set radius** 0.1·√area ([`DEFAULT_BASE_RADIUS`]).
//! * **Midline halves**: the skeleton filter also splits pelvis, torso and head by the
//!   skeleton's sagittal plane ([`midline_halves`]); without it those segments flip freely.
//! * **Confidence** from the spread of the filtered candidates (see
//!   [`symcorr_correspond::assign_confidence`]); it makes the Table 1 row increase
//!   monotonically (0.028 for the best 10 % to 0.045 for all, exact joints).
//! * Attachment runs concurrently with the spectral stages (rayon::join); stage timings are
//!   wall-clock per stage, so they overlap and do not add up to the total.
//! * Metrics use edge-path Dijkstra geodesics stopped at the ground truth (see
//!   [`symcorr_correspond::evaluate`]).
//! * `symcorr bench` reports `seconds_per_pair` as the standalone cost of a pair (preparing
//!   both meshes plus matching, wall clock while the other pairs run in parallel), and
//!   `wall_seconds` for the whole run (meshes prepared once each).
//! * The demo reads its fixtures at run time from the repository's `fixtures/synth/bodies`
//!   (path fixed at compile time), or `--fixtures DIR`.
//! * **Default method**: refined, because it measured better than the paper's pipeline on
//!   every generated dataset except single-view scans (README, Measured); `--method paper`
//!   reproduces the paper, and its ablation `--no-skeleton-filter` is refused with the refined
//!   method rather than ignored.

pub mod dataset;
pub mod output;
mod pipeline;

pub use pipeline::{
    midline_halves, midline_sagittal, symmetric_midline_halves, Correspondence, Method, Mode,
    Pipeline, PipelineOptions, PrepareOptions, PreparedMesh, RefineData, DEFAULT_BASE_RADIUS,
    DEFAULT_EIGENPAIRS, DEFAULT_MIDLINE_MARGIN, DEFAULT_SAMPLES, PARTIAL_BOUNDARY_RATIO,
};

/// Everything that can go wrong in the pipeline, by stage.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// Reading, validating or writing a mesh.
    #[error(transparent)]
    Mesh(#[from] symcorr_mesh::MeshError),
    /// Reading a joint file.
    #[error(transparent)]
    Joints(#[from] symcorr_kinect::KinectError),
    /// Laplacian, eigenpairs, descriptors or geodesics.
    #[error(transparent)]
    Spectral(#[from] symcorr_spectral::SpectralError),
    /// Skeleton attachment.
    #[error(transparent)]
    Attach(#[from] symcorr_attach::AttachError),
    /// The matching stages.
    #[error(transparent)]
    Correspond(#[from] symcorr_correspond::CorrespondError),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// A file other than a mesh or joint file (dataset list, output) is wrong.
    #[error("{file}: {message}")]
    File {
        /// The file.
        file: String,
        /// What is wrong.
        message: String,
    },
}
