//! Spectral geometry for symcorr: the machinery of the paper's §3.1 (descriptors) and §3.3
//! (curvature, geodesics, base vertex set), and the bases of the refined method.
//!
//! # Data flow
//! mesh → [`Laplacian`] (cotan stiffness `L`, PSD with `L·1 = 0`, and lumped barycentric mass
//! `M`; the one owner of both) → [`eigenpairs`] of `L φ = λ M φ` (shift-invert block Lanczos on
//! faer's sparse Cholesky, own blocked triangular solves and Gram–Schmidt; the `symcorr`
//! driver keeps them in an on-disk cache) → descriptors [`hks`] and [`si_hks`] (Bronstein &
//! Kokkinos 2010).
//! Beside them: [`gaussian_curvature`] (paper eq. 4), geodesics by
//! [`dijkstra`] / [`EdgeGraph`] (paper eq. 5–6) and the heat method ([`HeatGeodesics`], on a
//! prefactored [`SystemFactor`]), and the paper's [`base_vertex_set`] (§3.3).
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
//! # Invariants and conventions
//! * Eigenvectors are M-orthonormal, `λ ≥ 0` ascending; the constant pair of each connected
//!   component is returned exactly (λ = 0, `1/√area_c` on it); signs make the
//!   largest-magnitude entry positive. Agreement with scipy's `eigsh(L, k, M=M, sigma=-1e-8)`:
//!   ~1e-13 relative (tests against `fixtures/spectral/reference.json`).
//! * Cotangents are clamped to ±1e5; numerically degenerate triangles (doubled area
//!   < 1e-12·longest edge²) are ignored; a vertex left with zero mass is an error
//!   ([`SpectralError::ZeroMass`]) — repair the mesh first. Bad indices are errors, not panics.
//! * Default shift `ε = 1e-8·n/area` (scale-invariant), tolerance 1e-10 on the shift-inverted
//!   residual, block size 8, basis `max(2k+20, k+40)` columns capped by a 1 GiB budget (but at least `k + 3b`); a k
//!   whose dense working set would exceed 8 GiB is refused
//!   ([`SpectralError::TooManyEigenpairs`]), and so are descriptor matrices over
//!   [`DENSE_LIMIT_BYTES`] ([`SpectralError::TooLarge`]).
//! * Curvature at boundary vertices uses `π − Σα`. Heat method: `t = h²` (mean edge length),
//!   Neumann boundary conditions, one pinned vertex per component; other components are
//!   infinitely far. Base-set radius in `√(total area)` units, its geodesics Dijkstra.
//! * si-HKS defaults are the paper's absolute window (`t = 2^τ`, τ = 1..25 step 1/16, 6
//!   frequencies); [`SiHksParams::area_relative`] is the window the pipeline uses.
//!
//! Measured: `docs/decisions/2026-11-23-eigensolver-shift-invert-block-lanczos.md` and
//! `docs/decisions/2026-11-23-paper-pipeline-defaults.md` (si-HKS window).

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
pub use eigen::{eigenpairs, EigenOptions, Eigenpairs, DEFAULT_DENSE_LIMIT_BYTES};
pub use geodesic::{dijkstra, dijkstra_many, DijkstraScratch, EdgeGraph, HeatGeodesics};
pub use laplacian::{Laplacian, SystemFactor, COT_CLAMP, DEGENERATE_REL};
pub use sampling::base_vertex_set;

use thiserror::Error;

/// Largest dense matrix the descriptor functions ([`hks`], [`si_hks`]) allocate, in bytes:
/// 8 GiB (a third of a 24 GiB machine). Larger requests are [`SpectralError::TooLarge`].
pub const DENSE_LIMIT_BYTES: usize = 8 << 30;

/// `Err(TooLarge)` when a `rows × cols` f64 matrix is over [`DENSE_LIMIT_BYTES`].
pub(crate) fn check_dense(
    what: &'static str,
    rows: usize,
    cols: usize,
) -> Result<(), SpectralError> {
    let bytes = 8 * rows as u128 * cols as u128;
    if bytes > DENSE_LIMIT_BYTES as u128 {
        return Err(SpectralError::TooLarge {
            what,
            rows,
            cols,
            gib: bytes as f64 / (1u64 << 30) as f64,
            limit_gib: (DENSE_LIMIT_BYTES >> 30) as f64,
        });
    }
    Ok(())
}

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
    /// More eigenpairs were asked for than the solver can compute for this mesh: k must be at
    /// most the number of vertices, and the dense storage the Lanczos basis for k needs must
    /// fit in [`EigenOptions::dense_limit_bytes`]. Nothing was allocated.
    #[error("k = {k} eigenpairs of a {vertices}-vertex mesh: k must be at most {max} ({reason})")]
    TooManyEigenpairs {
        /// Eigenpairs asked for.
        k: usize,
        /// Vertices of the mesh.
        vertices: usize,
        /// Largest k allowed for this mesh and these options.
        max: usize,
        /// Why (which requirement k breaks).
        reason: String,
    },
    /// A dense matrix sized by the input would exceed the documented size limit
    /// ([`DENSE_LIMIT_BYTES`]); refused before allocating.
    #[error("{what} would be a {rows} × {cols} dense matrix ({gib:.1} GiB), over the limit of {limit_gib:.0} GiB")]
    TooLarge {
        /// What the matrix is.
        what: &'static str,
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
        /// Its size in GiB.
        gib: f64,
        /// The limit in GiB.
        limit_gib: f64,
    },
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
