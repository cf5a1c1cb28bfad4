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
//! [`dataset`] runs a benchmark folder in DESIGN.md's layout and [`output`] writes the
//! `symcorr.correspondence/1` JSON, coloured meshes and the error-curve plot.
//!
//! # Decisions the design leaves open
//! * Defaults ([`DEFAULT_EIGENPAIRS`], [`DEFAULT_BASE_RADIUS`],
//!   [`symcorr_correspond::DEFAULT_NEAREST`]) were chosen by measurement on the generated
//!   bodies (see the README); si-HKS parameters are symcorr-spectral's (Bronstein & Kokkinos).
//! * Attachment runs concurrently with the spectral stages (rayon::join); stage timings are
//!   wall-clock per stage, so they overlap and do not add up to the total.
//! * Metrics use edge-path Dijkstra geodesics stopped at the ground truth (see
//!   [`symcorr_correspond::evaluate`]).
//! * The pipeline is ready for a refinement stage after selection (DESIGN.md, Algorithm 7):
//!   [`Correspondence`] holds plain matches, and everything a refinement needs per mesh
//!   (labels, refined joints, descriptors) is in [`PreparedMesh`].

pub mod dataset;
pub mod output;
mod pipeline;

pub use pipeline::{
    midline_halves, Correspondence, Mode, Pipeline, PipelineOptions, PrepareOptions, PreparedMesh,
    DEFAULT_BASE_RADIUS, DEFAULT_EIGENPAIRS, DEFAULT_MIDLINE_MARGIN, DEFAULT_SAMPLES,
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
