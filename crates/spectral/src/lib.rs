//! Spectral geometry for symcorr (the paper's §3.1 and §3.3 machinery).
//!
//! * [`Laplacian`]: cotan stiffness `L` (positive semi-definite convention, `L·1 = 0`) and lumped
//!   barycentric mass `M`; [`SystemFactor`] factors `L + a·M + diag(h)` once (faer sparse
//!   Cholesky) and solves many right-hand sides.
//! * [`eigenpairs`]: the k smallest pairs of `L φ = λ M φ` by shift-invert block Lanczos (own
//!   blocked triangular solves on faer's Cholesky factor, full re-orthogonalisation by fused
//!   block Gram–Schmidt, per-component deflation of the constant, early convergence tests, thick
//!   restart, Rayleigh quotients with the exact `L`); agrees with scipy's
//!   `eigsh(L, k, M=M, sigma=-1e-8)` to ~1e-13 relative. See the `eigen` module docs (source)
//!   for the method and the measurements behind each choice.
//! * Descriptors: [`hks`], [`si_hks`] (Bronstein & Kokkinos 2010).
//! * [`gaussian_curvature`] (paper eq. 4), geodesics by [`dijkstra`] / [`EdgeGraph`] (paper
//!   eq. 5–6) and the heat method ([`HeatGeodesics`]), and the paper's [`base_vertex_set`] (§3.3).
//! * [`cache`]: eigenpairs on disk (`*.symcorr-eigs`, versioned, keyed by a SHA-256 of the mesh
//!   and the solver settings, checksummed), [`cache::eigenpairs_cached`] around [`eigenpairs`].
//!
//! ```
//! use symcorr_mesh::TriMesh;
//! use symcorr_spectral::*;
//! let mesh = TriMesh::new(
//!     vec![[1.,0.,0.],[-1.,0.,0.],[0.,1.,0.],[0.,-1.,0.],[0.,0.,1.],[0.,0.,-1.]],
//!     vec![[0,2,4],[2,1,4],[1,3,4],[3,0,4],[2,0,5],[1,2,5],[3,1,5],[0,3,5]],
//! ).unwrap();
//! let lap = Laplacian::new(&mesh).unwrap();
//! let eig = eigenpairs(&lap, 5, &EigenOptions::default()).unwrap();
//! let desc = si_hks(&eig, &SiHksParams::default()).unwrap(); // n × 6
//! let gc = gaussian_curvature(&mesh);
//! let base = base_vertex_set(&mesh, &gc, 0.5).unwrap();
//! let d = dijkstra_many(&mesh, &base).unwrap(); // one row per base vertex
//! assert_eq!((desc.nrows(), d.len()), (6, base.len()));
//! ```
//!
//! # Decisions the design leaves open
//! * Sign convention: `L` is PSD; eigenpairs solve `L φ = λ M φ`, `λ ≥ 0`.
//! * Cotangents are clamped to ±1e5 (angles within ~1e-5 rad of 0 or π); numerically
//!   degenerate triangles (doubled area < 1e-12·longest edge²) are ignored. A vertex left with
//!   zero mass is an error ([`SpectralError::ZeroMass`]) — repair the mesh first.
//! * Eigenvectors are M-orthonormal; the constant pair of each connected component is returned
//!   exactly (λ = 0, `1/√area_c` on the component); signs make the largest-magnitude entry
//!   positive. Default shift `ε = 1e-8·n/area` (scale-invariant), tolerance 1e-10 on the
//!   shift-inverted residual, block size 8, basis `max(2k+20, k+40)` columns capped by a 1 GiB
//!   budget. Convergence is tested every 2–4 blocks (not only when the basis is full); the
//!   eigenvalues are per-vector Rayleigh quotients (no dense Rayleigh–Ritz rotation: same values
//!   to ~1e-13, ~1.4 s less at 100k vertices).
//! * Gaussian curvature at boundary vertices uses `π − Σα` (geodesic-curvature convention).
//! * Heat method: `t = h²` by default (h the mean edge length), Neumann boundary conditions in
//!   both solves, Poisson solved with one pinned vertex per component (no regularisation), then
//!   shifted so the source is 0; other components are infinitely far.
//! * si-HKS defaults (Bronstein & Kokkinos 2010): `t = 2^τ`, τ = 1..25 step 1/16, 6 frequencies;
//!   times are in the mesh's own length units².
//! * Base vertex set radius is in units of `√(total area)`; geodesics there are Dijkstra.
//! * Source indices out of range are errors, not panics (so [`dijkstra`] returns a `Result`).
//! * Eigenpair cache: a file is used only when its key (mesh bits, `k`, every [`EigenOptions`]
//!   field, the Laplacian constants, [`cache::SOLVER_REVISION`]) and the lumped mass match bit
//!   for bit; anything else (stale, corrupted, another format version) is recomputed and the
//!   file rewritten. Timings stored in a file are those of the original solve.

pub mod cache;
mod curvature;
mod descriptors;
mod eigen;
mod geodesic;
mod laplacian;
mod sampling;
#[doc(hidden)]
pub mod testmesh;

pub use curvature::gaussian_curvature;
pub use descriptors::{hks, hks_times, si_hks, SiHksParams};
pub use eigen::{eigenpairs, EigenOptions, Eigenpairs};
pub use geodesic::{dijkstra, dijkstra_many, DijkstraScratch, EdgeGraph, HeatGeodesics};
pub use laplacian::{Laplacian, SystemFactor, COT_CLAMP, DEGENERATE_REL};
pub use sampling::base_vertex_set;

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
