//! symcorr: skeleton-aware human shape correspondence — the pipeline API behind the `symcorr`
//! command. Given two meshes of human bodies and the skeletons a depth camera tracked beside
//! them, it matches template vertices to target vertices without mapping a left limb onto a
//! right one.
//!
//! # Data flow
//! * [`PreparedMesh::new`] — everything about one mesh, computed once and reused for every pair
//!   it is in: the default mesh repair (`symcorr_mesh::repair`), skeleton attachment and segment
//!   labels (symcorr-attach), and, for the methods that need them and in parallel with the
//!   attachment, the cotan Laplacian, eigenpairs, si-HKS, curvature, base vertex set and its
//!   geodesic profile (symcorr-spectral).
//! * [`Pipeline::run`] — one pair, with one of three [`Method`]s (symcorr-correspond):
//!   [`Method::Articulated`], **the default**: the template, skinned with its bone-heat weights,
//!   posed onto the target's skeleton, fitted bone by bone and pulled onto the target; every
//!   template vertex takes the nearest target vertex of its segment pool. It needs no spectral
//!   stage, handles single-view scans ([`PreparedMesh::is_partial`]) and says which template
//!   points a scan does not show ([`Correspondence::has_counterpart`]).
//!   [`Pipeline::run_on_view`] is `run` guarded for a scan: a fit that holds too little of its
//!   view ([`Correspondence::view_held`]) is tried with the scan's joints turned half a turn
//!   about their spine (a skeleton facing away from the camera); a view on which neither fit
//!   holds clearly more ([`turn_verdict`]) is refused, and so is a fit that holds under half;
//!   `symcorr match`, `bench` and the Python package run it.
//!   [`Method::Refined`]: skeleton landmark coordinates + si-HKS within segment pools, then
//!   segment-constrained ZoomOut. [`Method::Paper`]: the paper's si-HKS candidates, skeleton
//!   filter and eq. 8 selection (DESIGN.md, Algorithms 1–6).
//! * [`track::Tracker`] — a recorded session frame by frame: the joints at each depth frame's
//!   time, limb swaps fixed by continuity, smoothing, the frame's scan prepared and matched with
//!   the pipeline's method against one prepared template; `symcorr track` streams the rows into
//!   [`npy`] files.
//! * [`io`] reads the input meshes and joint files; [`label::label_mesh`] labels one mesh as
//!   `symcorr label` does; [`bench`](mod@bench) runs a benchmark folder in
//!   DESIGN.md's layout and scores it with symcorr-eval; [`output`] writes the
//!   `symcorr.correspondence/1` JSON ([`formats`]), coloured meshes and the error-curve plot;
//!   [`cache`] keeps eigenpairs on disk between runs; [`view`] makes a self-contained HTML page of
//!   a correspondence, a labels file or a track run (`symcorr view`).
//!
//! ```
//! use symcorr::{Mode, Pipeline, PipelineOptions};
//! // A small capsule body in a T-pose and its skeleton, matched onto itself.
//! let (mesh, joints) = symcorr_attach::doc_example();
//! let pipeline = Pipeline::new(PipelineOptions { mode: Mode::Dense, ..Default::default() });
//! let template = pipeline.prepare(mesh.clone(), &joints).unwrap();
//! let target = pipeline.prepare(mesh, &joints).unwrap();
//! let corr = pipeline.run(&template, &target).unwrap();
//! assert_eq!(corr.pairs.len(), template.num_vertices());
//! ```
//!
//! # Invariants
//! * Every output speaks the input file's vertex ids ([`PreparedMesh::input_id`]), whatever
//!   the repair removed; the stages work on the repaired mesh. Components no bone reaches are
//!   left out of it ([`PreparedMesh::unreached`]): unlabelled, never matched.
//! * Each mesh's skeleton fits it or preparing fails naming the check
//!   (`symcorr_attach::FitQuality`), unless the attachment options accept a poor fit; each mesh
//!   has its own unit ([`PreparedMesh::metres_per_unit`]).
//! * Options that would silently run something other than asked are errors
//!   ([`PipelineOptions::check`]: the skeleton-filter ablation exists only for the paper).
//! * Stage timings are wall clock per stage; attachment runs concurrently with the spectral
//!   stages, so they overlap. `symcorr bench` reports `seconds_per_pair` as the standalone cost
//!   of a pair (both meshes prepared plus matching) and `wall_seconds` for the whole run.
//! * The demo reads its fixtures from `--fixtures DIR`, else `$SYMCORR_FIXTURES`, else the
//!   repository's `fixtures/synth/bodies` (path fixed at compile time).
//!
//! # Measured choices
//! In `docs/decisions/`: the default method (`2026-11-23-default-method-articulated.md`), the
//! si-HKS window, candidates, eigenpairs ([`DEFAULT_EIGENPAIRS`]), base radius
//! ([`DEFAULT_BASE_RADIUS`]) and confidence (`2026-11-23-paper-pipeline-defaults.md`), the
//! midline halves ([`midline_halves`]; `2026-11-23-midline-halves-and-skull-plane.md`) and
//! partial targets ([`PARTIAL_BOUNDARY_RATIO`]; `2026-11-23-partial-targets-scored-on-template.md`).

pub mod bench;
pub mod cache;
pub mod figures;
pub mod formats;
pub mod io;
pub mod label;
mod midline;
pub mod npy;
pub mod output;
mod pipeline;
mod prepare;
pub mod track;
pub mod view;

pub use midline::{midline_halves, midline_sagittal, symmetric_midline_halves};
pub use pipeline::{
    keeps_turned_fit, turn_verdict, ArticulatedTables, Correspondence, Method, MethodReport, Mode,
    Pipeline, PipelineOptions, SurfacePoint, TurnVerdict, ViewMatch, DEFAULT_SAMPLES,
    MIN_VIEW_HELD, TURN_KEEP_AREA_RATIO, TURN_KEEP_MARGIN, TURN_RETRY_BELOW,
};
pub use prepare::{
    metres_per_unit, PaperData, PrepareOptions, PreparedMesh, RefineData, DEFAULT_BASE_RADIUS,
    DEFAULT_EIGENPAIRS, DEFAULT_MIDLINE_MARGIN, ORIGIN_FACING_FRACTION, PARTIAL_BOUNDARY_RATIO,
};
pub use symcorr_correspond::{ArticulatedStart, BoneTransforms, ViewHold};

/// An option [`PipelineOptions::check`] or [`PreparedMesh::new`] refuses, before any work.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OptionError {
    /// A share of the sides evidence carried over between frames outside [0, 1)
    /// ([`track::SidesMemory`]).
    #[error("sides memory {0}: must be a share in [0, 1) (at 1 or more the evidence of the first frames would outweigh every later frame's)")]
    SidesMemory(f64),
    /// Sparse mode with no template point.
    #[error("sparse mode needs at least one sample")]
    NoSamples,
    /// The paper's candidate rule keeps no candidate.
    #[error("the candidate count must be at least 1")]
    NoCandidates,
    /// The relative candidate threshold is not a finite factor ≥ 1.
    #[error("candidate threshold {0}: must be a factor ≥ 1")]
    CandidateThreshold(f64),
    /// The base vertex set radius is not a positive length.
    #[error("base vertex set radius {0}: must be positive")]
    BaseRadius(f64),
    /// Fewer than two eigenpairs for a method with spectral data.
    #[error("eigenpairs = {0} (need at least 2)")]
    TooFewEigenpairs(usize),
    /// The skeleton filter switched off (the paper's ablation) with another method, whose
    /// segment pools are its skeleton constraint.
    #[error("switching the skeleton filter off is the paper pipeline's ablation; the articulated and refined methods always keep matches on their segment")]
    AblationNeedsPaper,
    /// A paper filter other than the default with another method, which has no such filter.
    #[error("the skeleton filter variant belongs to the paper pipeline; the articulated and refined methods have segment pools instead")]
    PaperFilterNeedsPaper,
}

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
    /// A benchmark dataset file (pairs file, mirror map, truth table; symcorr-eval).
    #[error(transparent)]
    Eval(#[from] symcorr_eval::EvalError),
    /// An option is out of range or does not fit the method ([`PipelineOptions::check`]).
    #[error("invalid option: {0}")]
    Option(#[from] OptionError),
    /// The default mesh repair removed every triangle (all were degenerate).
    #[error("no triangle left after removing degenerate ones")]
    NothingLeftAfterRepair,
    /// A mesh was prepared without the data a method needs ([`PreparedMesh::new`] prepares
    /// for the methods it is given).
    #[error("the mesh was not prepared for the {0:?} method")]
    NotPreparedFor(Method),
    /// A target seen from one viewpoint whose fit holds less than [`MIN_VIEW_HELD`] of the
    /// template points it shows the camera, with the joints as given and turned half a turn
    /// about their spine ([`Pipeline::run_on_view`]).
    #[error(
        "the template does not fit the scan: {:.0} % of the template points the fit shows the \
         camera lie on the scan (at least {:.0} % expected), with the joints as given and \
         turned half a turn about their spine; the joints may belong to another frame, another \
         body or another camera",
        100.0 * held,
        100.0 * MIN_VIEW_HELD
    )]
    ViewNotHeld {
        /// The fraction of its view the kept fit holds.
        held: f64,
    },
    /// A target seen from one viewpoint on which neither the fit on the joints as given nor
    /// the fit on them turned half a turn about their spine holds clearly more
    /// ([`TurnVerdict::Undetermined`]): which way the body faces the camera is unknown, and a
    /// guess would map left onto right over the whole view ([`Pipeline::run_on_view`]).
    #[error(
        "cannot tell which way the body faces the camera: the fit on the joints as given holds \
         {:.0} % of its view, the fit on them turned half a turn about their spine {:.0} %, and \
         neither lays clearly more surface on the scan; the joints may face the other way than \
         the body, or the view shows too little of the body to tell",
        100.0 * given,
        100.0 * turned
    )]
    FacingUndetermined {
        /// The fraction of its view the fit on the joints as given holds.
        given: f64,
        /// The fraction of its view the fit on the turned joints holds.
        turned: f64,
    },
    /// A file other than a mesh or joint file (dataset list, output) is wrong.
    #[error("{file}: {message}")]
    File {
        /// The file.
        file: String,
        /// What is wrong.
        message: String,
    },
}
