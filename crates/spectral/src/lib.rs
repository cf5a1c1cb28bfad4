//! Spectral geometry for symcorr (the paper's §3.1 and §3.3 machinery).
//!
//! * [`Laplacian`]: cotan stiffness `L` (positive semi-definite convention, `L·1 = 0`) and lumped
//!   barycentric mass `M`; [`SystemFactor`] factors `L + a·M + diag(h)` once (faer sparse
//!   Cholesky) and solves many right-hand sides.
//!
//! # Decisions the design leaves open
//! * Sign convention: `L` is PSD; eigenpairs solve `L φ = λ M φ`, `λ ≥ 0`.
//! * Cotangents are clamped to ±1e5 (angles within ~1e-5 rad of 0 or π); numerically
//!   degenerate triangles (doubled area < 1e-12·longest edge²) are ignored. A vertex left with
//!   zero mass is an error ([`SpectralError::ZeroMass`]) — repair the mesh first.

mod eigen;
mod laplacian;

pub use eigen::{eigenpairs, EigenOptions, Eigenpairs};
pub use laplacian::{Laplacian, SystemFactor, COT_CLAMP, DEGENERATE_REL};

use thiserror::Error;

/// Everything that can go wrong in spectral computations.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SpectralError {
    /// A vertex has no non-degenerate incident triangle, so its mass is zero.
    #[error("vertex {vertex} has zero mass (it is in no non-degenerate triangle); repair the mesh first")]
    ZeroMass {
        /// The offending vertex.
        vertex: usize,
    },
    /// Sparse Cholesky failed (matrix not positive definite, or out of memory).
    #[error("sparse Cholesky factorisation failed: {0}")]
    Factorization(String),
    /// An argument is out of range (message says which).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// The eigensolver did not converge within its iteration budget.
    #[error("eigensolver did not converge: {converged} of {wanted} eigenpairs after {iterations} Lanczos steps (largest relative residual {residual:.2e})")]
    NotConverged {
        /// Eigenpairs wanted.
        wanted: usize,
        /// Eigenpairs converged.
        converged: usize,
        /// Lanczos steps taken.
        iterations: usize,
        /// Largest relative residual among the wanted pairs.
        residual: f64,
    },
}
