//! The k smallest eigenpairs of `L φ = λ M φ` by shift-invert block Lanczos (DESIGN.md,
//! Algorithms 2).
//!
//! Method:
//! 1. Factor `K = L + εM` once (faer sparse Cholesky, AMD ordering), then copy the factor into a
//!    plain compressed-column triangle solved by this module's own kernels (`eigen/factor.rs`):
//!    the b right-hand sides of a block are interleaved so each factor entry is read once per
//!    block, column groups run on separate rayon tasks, and the `M^½` scaling and permutation
//!    are folded into the gather/scatter. faer's `Llt::solve_in_place` forks rayon once per
//!    supernode and was the largest cost at 100k vertices.
//! 2. Block Lanczos (block size b, default 8) on the symmetric operator `A = M^½ K⁻¹ M^½` (its
//!    largest eigenvalues `θ = 1/(λ + ε)` belong to the smallest `λ`), with full
//!    re-orthogonalisation of every new block against the whole basis by block classical
//!    Gram–Schmidt (`eigen/ortho.rs`): BLAS-3 products, cache-blocked and fused so the basis is
//!    streamed three times instead of four, rows split over the rayon threads. The second
//!    Gram–Schmidt correction is measured and applied whenever it exceeds 1e-13 relative
//!    ("twice is enough", but without paying for the second update when the first pass
//!    already left `‖QᵀW‖ ≤ 5e-15‖W‖`, which is most steps).
//! 3. After every solve, project out the known null space: the constant function of each
//!    connected component (`M^½ 1_c` in the symmetric coordinates). Those pairs (`λ = 0`) are
//!    returned exactly; without this, rounding in the nearly singular solve leaks the constant
//!    mode into everything and eigenvalues are only good to ~1e-7.
//! 4. Convergence is tested on the projected matrix at block boundaries once the basis holds
//!    r + 2b vectors (every 4 blocks while fewer than ¾ of the wanted pairs have converged,
//!    then every 2), so the iteration stops as soon as all wanted pairs are there rather than
//!    only when the basis is full.
//! 5. Thick restart (Wu & Simon 2000) when the basis reaches its size limit: keep the best Ritz
//!    vectors, continue from the residual block. The basis is `n × (m+b)`; m is shrunk towards
//!    [`EigenOptions::memory_budget_bytes`] but never below `r + 3b`, so a k whose whole dense
//!    working set would exceed [`EigenOptions::dense_limit_bytes`] is refused up front.
//! 6. Finish: `φ = M^-½ y` for the converged Ritz vectors; the values returned are the Rayleigh
//!    quotients `φᵀLφ / φᵀMφ` with the exact `L` (second-order accurate in the Ritz vector
//!    error, so they agree with scipy to ~1e-13). A dense Rayleigh–Ritz rotation with `L` gave
//!    the same values and cost three `n × k × k` products (1.4 s at 100k vertices).
//!
//! Why these choices: before this design the time went to faer's per-supernode parallel
//! solve (100k vertices) and to the re-orthogonalisation products (13k body). Block size 8 was
//! the fastest of 4, 6, 8, 10 on the body (smaller blocks take fewer steps, but each block
//! product and solve is less efficient); the basis size `max(2k+20, k+40)` and keeping half of
//! the surplus Ritz vectors at a restart were within noise of the alternatives tried.
//! Measured: `docs/decisions/2026-11-23-eigensolver-shift-invert-block-lanczos.md`.

mod factor;
mod ortho;

use crate::{Laplacian, SpectralError};
use factor::ShiftedFactor;
use faer::linalg::matmul::matmul;
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::{get_global_parallelism, Accum, Mat, MatRef, Side};
use std::time::Instant;

/// Options of [`eigenpairs`].
#[derive(Debug, Clone)]
pub struct EigenOptions {
    /// Convergence: a Ritz pair of `A` is converged when its residual `‖A y − θ y‖ ≤ tol·θ`.
    /// Eigenvalue errors are then of order `tol²·λ`. Default `1e-10`.
    pub tol: f64,
    /// Shift ε of `K = L + εM`. Default `None`: `1e-8 · n / area` (λ has units 1/area and
    /// `n/area` is the scale of the largest eigenvalues, so the default is scale-invariant).
    pub shift: Option<f64>,
    /// Largest Lanczos basis (columns) before a thick restart. Default `None`:
    /// `max(2k + 20, k + 40)`, capped by `memory_budget_bytes` and by `n`.
    pub max_basis: Option<usize>,
    /// Memory budget for the Lanczos basis, in bytes. Default 1 GiB
    /// (100k vertices × 600 columns × 8 B = 480 MB, so k = 300 at 100k vertices fits).
    pub memory_budget_bytes: usize,
    /// Number of thick restarts before giving up with [`SpectralError::NotConverged`]. Default 200.
    pub max_restarts: usize,
    /// Seed of the deterministic start vectors. Default 0x5eed.
    pub seed: u64,
    /// Block size b of block Lanczos: b vectors per blocked sparse solve and per Gram–Schmidt
    /// sweep (fewer passes over the basis, faster solves, and degenerate eigenvalues of
    /// multiplicity ≤ b are found without relying on rounding). Default 8. Symmetric meshes
    /// have exactly repeated eigenvalues (an icosphere up to 5-fold); with `block_size` below
    /// the multiplicity, restarted Lanczos can miss copies.
    pub block_size: usize,
    /// Largest dense working set [`eigenpairs`] may allocate, in bytes (basis, result vectors,
    /// restart and Ritz-vector copies, projected matrix and its eigendecomposition). A `k` whose working set is larger is refused with
    /// [`SpectralError::TooManyEigenpairs`] before anything is allocated, instead of aborting
    /// on a failed allocation. Default 8 GiB: a third of a 24 GiB machine, so the two meshes
    /// of a `match` fit side by side with room to spare. Unlike `memory_budget_bytes` (a
    /// target the basis size is shrunk to meet) this is a hard limit; it never changes the
    /// result of a solve that is allowed.
    pub dense_limit_bytes: usize,
}

/// Default of [`EigenOptions::dense_limit_bytes`]: 8 GiB.
pub const DEFAULT_DENSE_LIMIT_BYTES: usize = 8 << 30;

impl Default for EigenOptions {
    fn default() -> Self {
        EigenOptions {
            tol: 1e-10,
            shift: None,
            max_basis: None,
            memory_budget_bytes: 1 << 30,
            max_restarts: 200,
            seed: 0x5eed,
            block_size: 8,
            dense_limit_bytes: DEFAULT_DENSE_LIMIT_BYTES,
        }
    }
}

/// The k smallest eigenpairs of `L φ = λ M φ`.
#[derive(Debug, Clone)]
pub struct Eigenpairs {
    /// Eigenvalues, ascending, `λ ≥ 0`. The first `num_components` are exactly 0.
    pub values: Vec<f64>,
    /// Eigenvectors as columns, `n × k`, M-orthonormal (`ΦᵀMΦ = I`). Column `c <
    /// num_components` is the constant `1/√area_c` on component `c`, zero elsewhere. Signs are
    /// fixed so that the entry of largest magnitude is positive.
    pub vectors: Mat<f64>,
    /// Number of connected components (= number of exact zero eigenvalues included, capped at k).
    pub num_components: usize,
    /// `max_i ‖Lφ_i − λ_i Mφ_i‖ / ‖Mφ_i‖` over the non-constant pairs, with the returned Rayleigh quotients (the
    /// constant pairs have residual 0 by construction): an a-posteriori accuracy check.
    pub residual_max: f64,
    /// Lanczos steps (operator applications = sparse solves) used.
    pub iterations: usize,
    /// Thick restarts used.
    pub restarts: usize,
    /// Wall time of the sparse Cholesky factorisation of `L + εM`, seconds.
    pub factorization_s: f64,
    /// Wall time of the Lanczos iteration and finish (everything after the factorisation), seconds.
    pub lanczos_s: f64,
}

impl Eigenpairs {
    /// Number of pairs k.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True when no pairs were computed (never, for a successful [`eigenpairs`] call).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vectors.nrows()
    }
}

/// Deterministic pseudo-random numbers (splitmix64), for start vectors.
struct SplitMix(u64);
impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// The shift-inverted operator and its known null space, in symmetric coordinates `y = M^½ φ`.
struct Operator<'a> {
    factor: ShiftedFactor,
    sqrt_mass: Vec<f64>,
    component: &'a [u32],
    /// `M^½ 1_c / √area_c` evaluated per vertex: entry i is `√m_i / √area_{c(i)}`.
    null_vec: Vec<f64>,
    num_components: usize,
}

impl Operator<'_> {
    /// Removes the components along every `M^½ 1_c` (orthonormal, disjoint supports).
    fn deflate(&self, w: &mut [f64]) {
        if self.num_components == 1 {
            // One component (the usual case): a plain dot product and update, which vectorise
            // (the general loop below accumulates through `dots[c]` and does not).
            let dot: f64 = w.iter().zip(&self.null_vec).map(|(x, u)| x * u).sum();
            for (x, u) in w.iter_mut().zip(&self.null_vec) {
                *x -= dot * u;
            }
            return;
        }
        let mut dots = vec![0.0; self.num_components];
        for ((x, &c), &u) in w.iter().zip(self.component).zip(&self.null_vec) {
            dots[c as usize] += x * u;
        }
        for ((x, &c), &u) in w.iter_mut().zip(self.component).zip(&self.null_vec) {
            *x -= dots[c as usize] * u;
        }
    }

    /// `W = A X` for a block of columns (one blocked sparse solve), deflated.
    fn apply_block(&self, x: MatRef<'_, f64>, w: &mut Mat<f64>, scratch: &mut Vec<f64>) {
        self.factor
            .solve_scaled(x, w.as_mut(), &self.sqrt_mass, scratch);
        for c in 0..x.ncols() {
            self.deflate(as_slice_mut(w, c));
        }
    }
}

fn as_slice_mut(m: &mut Mat<f64>, j: usize) -> &mut [f64] {
    // Invariant: columns of an owned faer Mat are contiguous.
    m.col_mut(j)
        .try_as_col_major_mut()
        .expect("owned Mat columns are contiguous")
        .as_slice_mut()
}

fn col_norm(m: &Mat<f64>, j: usize) -> f64 {
    m.col(j).norm_l2()
}

/// Orthogonalises column `w` (n×1) against `basis` (n×j, orthonormal) with two passes of
/// classical Gram–Schmidt (matrix–vector products), adding the coefficients into `coef`.
fn reorthogonalise(basis: MatRef<'_, f64>, w: &mut Mat<f64>, coef: &mut Mat<f64>, op: &Operator) {
    let par = get_global_parallelism();
    let j = basis.ncols();
    let mut c = Mat::<f64>::zeros(j, 1);
    for _pass in 0..2 {
        if j > 0 {
            matmul(
                c.as_mut(),
                Accum::Replace,
                basis.transpose(),
                w.as_ref(),
                1.0,
                par,
            );
            matmul(w.as_mut(), Accum::Add, basis, c.as_ref(), -1.0, par);
            for i in 0..j {
                coef[(i, 0)] += c[(i, 0)];
            }
        }
        op.deflate(as_slice_mut(w, 0));
    }
}

/// Fills `w` with a random unit vector orthogonal to `basis` and to the null space.
fn random_orthogonal(basis: MatRef<'_, f64>, w: &mut Mat<f64>, rng: &mut SplitMix, op: &Operator) {
    for _attempt in 0..5 {
        for i in 0..w.nrows() {
            w[(i, 0)] = rng.next_f64();
        }
        op.deflate(as_slice_mut(w, 0));
        let mut scratch = Mat::<f64>::zeros(basis.ncols(), 1);
        reorthogonalise(basis, w, &mut scratch, op);
        let nrm = col_norm(w, 0);
        if nrm > 1e-8 {
            for i in 0..w.nrows() {
                w[(i, 0)] /= nrm;
            }
            return;
        }
    }
    // Only reachable if basis + null space already span everything; then any vector will do
    // and the caller's β = 0 decouples it.
    w.fill(0.0);
}

/// Computes the `k` smallest eigenpairs of `L φ = λ M φ` (see the module docs for the method).
///
/// Errors: `k == 0` ([`SpectralError::InvalidArgument`]); `k > n`, or a k whose dense working
/// set (basis, result, restart and Ritz copies, projected matrix) would exceed
/// [`EigenOptions::dense_limit_bytes`] ([`SpectralError::TooManyEigenpairs`], checked before
/// anything is allocated); factorisation failure; or no convergence within `max_restarts`
/// ([`SpectralError::NotConverged`]).
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_spectral::{eigenpairs, EigenOptions, Laplacian};
/// // A regular octahedron.
/// let mesh = TriMesh::new(
///     vec![[1.,0.,0.],[-1.,0.,0.],[0.,1.,0.],[0.,-1.,0.],[0.,0.,1.],[0.,0.,-1.]],
///     vec![[0,2,4],[2,1,4],[1,3,4],[3,0,4],[2,0,5],[1,2,5],[3,1,5],[0,3,5]],
/// ).unwrap();
/// let lap = Laplacian::new(&mesh).unwrap();
/// let eig = eigenpairs(&lap, 4, &EigenOptions::default()).unwrap();
/// assert_eq!(eig.values[0], 0.0);
/// // The three linear functions x, y, z share one eigenvalue (octahedral symmetry).
/// assert!((eig.values[1] - eig.values[3]).abs() < 1e-10 * eig.values[1]);
/// ```
pub fn eigenpairs(
    laplacian: &Laplacian,
    k: usize,
    options: &EigenOptions,
) -> Result<Eigenpairs, SpectralError> {
    let n = laplacian.len();
    if k == 0 {
        return Err(SpectralError::InvalidArgument(format!(
            "asked for 0 eigenpairs of a mesh with {n} vertices (need k ≥ 1)"
        )));
    }
    // k ≤ n: there are only n eigenpairs. k = n itself is supported (the whole spectrum of
    // a small mesh: plain Lanczos spans the deflated space, see the `r > dim` check below);
    // for large n it is refused by the memory limit below, since it implies an n × n basis.
    if k > n {
        return Err(SpectralError::TooManyEigenpairs {
            k,
            vertices: n,
            max: n,
            reason: "a mesh has as many eigenpairs as vertices".into(),
        });
    }
    let (component, nc) = laplacian.components();
    // The dense working set k implies (basis size and block size as the solver will choose
    // them) must fit in `dense_limit_bytes`; refused here, before any n × k allocation.
    let limit = options.dense_limit_bytes as u128;
    if plan_bytes(n, nc, k, options) > limit {
        // Smallest refused k (the estimate is non-decreasing in k: the basis grows with k).
        let (mut lo, mut hi) = (1usize, k);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if plan_bytes(n, nc, mid, options) > limit {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        return Err(SpectralError::TooManyEigenpairs {
            k,
            vertices: n,
            max: lo - 1,
            reason: format!(
                "the eigensolver's dense storage would be {:.1} GiB, over its limit of {:.1} GiB",
                plan_bytes(n, nc, k, options) as f64 / GIB,
                limit as f64 / GIB
            ),
        });
    }
    let mut area_c = vec![0.0; nc];
    for (m, &c) in laplacian.mass.iter().zip(component) {
        area_c[c as usize] += m;
    }
    // The constant eigenpairs, exact.
    let n_const = nc.min(k);
    let values = vec![0.0; n_const];
    let mut vectors = Mat::<f64>::zeros(n, k);
    for (i, &c) in component.iter().enumerate() {
        if (c as usize) < n_const {
            vectors[(i, c as usize)] = 1.0 / area_c[c as usize].sqrt();
        }
    }
    let r = k - n_const;
    if r == 0 {
        return Ok(Eigenpairs {
            values,
            vectors,
            num_components: n_const,
            residual_max: 0.0,
            iterations: 0,
            restarts: 0,
            factorization_s: 0.0,
            lanczos_s: 0.0,
        });
    }
    let area = laplacian.total_area();
    let eps = options.shift.unwrap_or(1e-8 * n as f64 / area);
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(SpectralError::InvalidArgument(format!(
            "shift must be positive and finite, got {eps}"
        )));
    }
    let sqrt_mass: Vec<f64> = laplacian.mass.iter().map(|m| m.sqrt()).collect();
    let null_vec: Vec<f64> = sqrt_mass
        .iter()
        .zip(component)
        .map(|(s, &c)| s / area_c[c as usize].sqrt())
        .collect();
    let clock = Instant::now();
    let factor = ShiftedFactor::new(laplacian.shifted(eps, None)?.as_ref())?;
    let factorization_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let op = Operator {
        factor,
        sqrt_mass,
        component,
        null_vec,
        num_components: nc,
    };

    // Basis size m (columns 0..m, plus one block for the residual vectors) and block size b.
    let dim = n - nc; // dimension of the deflated space
    if r > dim {
        return Err(SpectralError::InvalidArgument(format!(
            "asked for {k} eigenpairs but only {dim} exist beyond the {nc} constant ones"
        )));
    }
    let (b, m) = basis_plan(n, dim, r, options);

    let mut rng = SplitMix(options.seed);
    let mut q = Mat::<f64>::zeros(n, m + b);
    let mut h = Mat::<f64>::zeros(m, m);
    // Start block: random, deflated, orthonormal.
    let mut w = Mat::<f64>::zeros(n, b);
    for c in 0..b {
        let mut col = Mat::<f64>::zeros(n, 1);
        random_orthogonal(q.as_ref().subcols(0, c), &mut col, &mut rng, &op);
        q.col_mut(c).copy_from(col.col(0));
    }

    let mut start = 0usize;
    let mut iterations = 0usize;
    let mut restarts = 0usize;
    // R of the last block: A Q_j = Q_j H_j + Q_next R E_lastᵀ.
    let mut last_r = Mat::<f64>::zeros(b, b);
    let mut scratch = Vec::new();
    let mut kept = Mat::<f64>::zeros(0, 0);
    loop {
        let mut j = start;
        // Basis size at which the next convergence test is due.
        let mut next_check = first_check(r, b, start);
        let mut verdict = None;
        while j < m {
            op.apply_block(q.as_ref().subcols(j, b), &mut w, &mut scratch);
            iterations += b;
            let norms_before: Vec<f64> = (0..b).map(|c| col_norm(&w, c)).collect();
            // Block classical Gram–Schmidt against the whole basis, second pass when it matters
            // (ortho::cgs2); the basis includes the current block, whose coefficients are the
            // diagonal block of H.
            let coef = ortho::cgs2(q.as_ref().subcols(0, j + b), w.as_mut());
            for c in 0..b {
                op.deflate(as_slice_mut(&mut w, c));
            }
            for c in 0..b {
                for i in 0..j {
                    h[(i, j + c)] = coef[(i, c)];
                    h[(j + c, i)] = coef[(i, c)];
                }
                for d in 0..b {
                    // Diagonal block: symmetrise the two computed copies.
                    let v = 0.5 * (coef[(j + d, c)] + coef[(j + c, d)]);
                    h[(j + d, j + c)] = v;
                }
            }
            // Orthonormalise the new block internally (two-pass MGS): W = Q_next R.
            let mut rmat = Mat::<f64>::zeros(b, b);
            for c in 0..b {
                let nrm = orthonormalise_within_block(&mut w, c, &mut rmat);
                if nrm <= 1e-13 * norms_before[c].max(f64::MIN_POSITIVE) || j + b >= dim {
                    // (Near) invariant subspace: continue with a fresh random direction; the
                    // zero coupling keeps the projected matrix exact.
                    let mut basis_and_w = Mat::<f64>::zeros(n, j + b + c);
                    basis_and_w
                        .as_mut()
                        .subcols_mut(0, j + b)
                        .copy_from(q.as_ref().subcols(0, j + b));
                    basis_and_w
                        .as_mut()
                        .subcols_mut(j + b, c)
                        .copy_from(w.as_ref().subcols(0, c));
                    let mut col = Mat::<f64>::zeros(n, 1);
                    random_orthogonal(basis_and_w.as_ref(), &mut col, &mut rng, &op);
                    w.col_mut(c).copy_from(col.col(0));
                } else {
                    let inv = 1.0 / nrm;
                    for v in as_slice_mut(&mut w, c) {
                        *v *= inv;
                    }
                    rmat[(c, c)] = nrm;
                }
            }
            if j + b < m {
                for c in 0..b {
                    for d in 0..b {
                        h[(j + b + d, j + c)] = rmat[(d, c)];
                        h[(j + c, j + b + d)] = rmat[(d, c)];
                    }
                }
            }
            q.as_mut().subcols_mut(j + b, b).copy_from(w.as_ref());
            last_r = rmat;
            j += b;
            // Early convergence test on the leading j × j block (the Lanczos relation holds
            // at every block boundary), so the run stops as soon as all r pairs are there
            // instead of only when the basis is full.
            if j < m && j >= next_check {
                let v = ritz(h.as_ref().submatrix(0, 0, j, j), &last_r, r, options.tol)?;
                if v.converged >= r {
                    verdict = Some(v);
                    break;
                }
                next_check = j + check_interval(v.converged, r, b);
            }
        }
        let v = match verdict {
            Some(v) => v,
            None => ritz(h.as_ref(), &last_r, r, options.tol)?,
        };
        let s_dim = j;
        if v.converged >= r || m == dim {
            // Ritz vectors Y = Q_s S[:, wanted].
            let mut y = Mat::<f64>::zeros(n, r);
            ortho::tall_times_small(
                y.as_mut(),
                q.as_ref().subcols(0, s_dim),
                v.vectors.as_ref().subcols(0, r),
            );
            let mut out = finish(
                laplacian, &op, y, values, vectors, n_const, iterations, restarts,
            )?;
            out.factorization_s = factorization_s;
            out.lanczos_s = clock.elapsed().as_secs_f64();
            return Ok(out);
        }
        if restarts >= options.max_restarts {
            return Err(SpectralError::NotConverged {
                wanted: k,
                converged: v.converged + n_const,
                iterations,
                residual: v.worst,
            });
        }
        // Thick restart: keep l Ritz vectors (the wanted ones and half of the rest, which
        // speeds up convergence of the last wanted ones), continue from the residual block.
        restarts += 1;
        // l ≥ r + 1 and m − l a positive multiple of b (the next blocks end exactly at m).
        let l0 = r + (m - r) / 2;
        let steps = ((m - l0 + b / 2) / b).clamp(1, (m - r - 1) / b);
        let l = m - steps * b;
        // (Reused across restarts: l is the same every time.)
        if kept.ncols() != l {
            kept = Mat::<f64>::zeros(n, l);
        }
        ortho::tall_times_small(
            kept.as_mut(),
            q.as_ref().subcols(0, m),
            v.vectors.as_ref().subcols(0, l),
        );
        let resid = q.as_ref().subcols(m, b).to_owned();
        q.as_mut().subcols_mut(0, l).copy_from(kept.as_ref());
        q.as_mut().subcols_mut(l, b).copy_from(resid.as_ref());
        h.fill(0.0);
        for c in 0..l {
            h[(c, c)] = v.theta[c];
        }
        start = l;
    }
}

const GIB: f64 = (1u64 << 30) as f64;

/// Block size b and basis size m (columns `0..m`, plus one block for the residual vectors) for
/// r wanted non-constant pairs in a deflated space of dimension `dim` (`n` rows).
fn basis_plan(n: usize, dim: usize, r: usize, options: &EigenOptions) -> (usize, usize) {
    let m0 = options.max_basis.unwrap_or((2 * r + 20).max(r + 40));
    let budget_cols = options.memory_budget_bytes / (8 * n.max(1));
    let mut b = options.block_size.max(1);
    let mut m;
    if m0.min(budget_cols) >= dim {
        // The whole deflated space fits: plain Lanczos spans it exactly.
        b = 1;
        m = dim;
    } else {
        m = m0.min(budget_cols.saturating_sub(b)).max(r + 3 * b);
        m = m.div_ceil(b) * b;
        if m > dim {
            b = 1;
            m = m0.min(dim).max(r);
        }
    }
    if b == 1 && m < dim {
        m = m.max(r + 2).min(dim);
    }
    (b, m)
}

/// Bytes of the dense matrices [`eigenpairs`] holds at its peak for k pairs of an n-vertex
/// Laplacian with nc components (an upper estimate, in `u128` so that it cannot overflow).
fn plan_bytes(n: usize, nc: usize, k: usize, options: &EigenOptions) -> u128 {
    let n_const = nc.min(k);
    let r = k - n_const;
    if r == 0 {
        return 8 * n as u128 * k as u128;
    }
    let dim = n.saturating_sub(nc);
    let (b, m) = basis_plan(n, dim, r.min(dim), options);
    dense_bytes(n, k, r, b, m)
}

/// Peak dense storage of [`eigenpairs`], in bytes, for n rows, k pairs (r of them
/// non-constant), block size b and basis size m: the result `n × k`, the basis `n × (m+b)`
/// with the block `n × b`, the thick-restart copy (`n × l`, `l < m`), the copy of the basis
/// made when a block has to be restarted from a random direction (`n × (m+b)`), the Ritz
/// vectors and their `L`-products at the finish (`2 · n × r`), and the projected matrix with
/// its eigendecomposition (about four `m × m`).
fn dense_bytes(n: usize, k: usize, r: usize, b: usize, m: usize) -> u128 {
    let (n, k, r, b, m) = (n as u128, k as u128, r as u128, b as u128, m as u128);
    8 * (n * (k + 3 * (m + b) + b + 2 * r) + 4 * m * m)
}

/// Ritz pairs of a projected matrix, largest θ first, and how many of the wanted ones have
/// converged (in order).
struct Ritz {
    /// Eigenvectors of the projected matrix, columns in the order of `theta`.
    vectors: Mat<f64>,
    /// Ritz values, descending.
    theta: Vec<f64>,
    /// Leading Ritz pairs (among the first r) whose residual is within tolerance, counted
    /// up to the first that is not.
    converged: usize,
    /// Largest relative residual among the first r.
    worst: f64,
}

/// Rayleigh–Ritz on `h` (s × s, the projection of A on the basis); the residual of Ritz pair i
/// is `‖R_last · S[s−b.., i]‖` (block Lanczos relation).
fn ritz(h: MatRef<'_, f64>, last_r: &Mat<f64>, r: usize, tol: f64) -> Result<Ritz, SpectralError> {
    let s_dim = h.nrows();
    let b = last_r.nrows();
    let evd = h
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| SpectralError::Factorization(format!("dense eigen: {e:?}")))?;
    let s = evd.U();
    let vals = evd.S().column_vector();
    // faer sorts ascending; we want the largest θ first.
    let mut vectors = Mat::<f64>::zeros(s_dim, s_dim);
    let mut theta = Vec::with_capacity(s_dim);
    for c in 0..s_dim {
        let i = s_dim - 1 - c;
        vectors.col_mut(c).copy_from(s.col(i));
        theta.push(vals[i]);
    }
    let mut worst = 0.0f64;
    let mut converged = 0usize;
    for rank in 0..r.min(s_dim) {
        let mut acc = 0.0;
        for d in 0..b {
            let mut v = 0.0;
            for c in 0..b {
                v += last_r[(d, c)] * vectors[(s_dim - b + c, rank)];
            }
            acc += v * v;
        }
        let rel = acc.sqrt() / theta[rank].abs().max(f64::MIN_POSITIVE);
        worst = worst.max(rel);
        if rel <= tol && converged == rank {
            converged += 1;
        }
    }
    Ok(Ritz {
        vectors,
        theta,
        converged,
        worst,
    })
}

/// Basis size at which the first convergence test of a cycle is made: r pairs cannot converge
/// in a basis much smaller than r + 2b.
fn first_check(r: usize, b: usize, start: usize) -> usize {
    (r + 2 * b).max(start + 2 * b)
}

/// Blocks until the next convergence test, from the progress so far: the dense eigen-solve of
/// the projected matrix costs about as much as a few block steps on a 10k-vertex mesh, so test
/// rarely while far from convergence and every other block when close.
fn check_interval(converged: usize, r: usize, b: usize) -> usize {
    if 4 * converged < 3 * r {
        4 * b
    } else {
        2 * b
    }
}

/// Orthogonalises column `c` of `w` against its columns `0..c` (two passes of modified
/// Gram–Schmidt, coefficients added into `rmat[(p, c)]`) and returns its remaining norm.
fn orthonormalise_within_block(w: &mut Mat<f64>, c: usize, rmat: &mut Mat<f64>) -> f64 {
    let (left, right) = w.as_mut().split_at_col_mut(c);
    let left = left.as_ref();
    let mut wc = right.col_mut(0);
    for _pass in 0..2 {
        for p in 0..c {
            let wp = left.col(p);
            let d = wp.transpose() * wc.as_ref();
            wc -= d * wp;
            rmat[(p, c)] += d;
        }
    }
    wc.as_ref().norm_l2()
}

/// Maps Lanczos vectors back (`φ = M^-½ y`), takes each pair's Rayleigh quotient with `L`
/// (sorted ascending), fixes signs and assembles the result after the constant pairs.
///
/// Why per-vector Rayleigh quotients and no dense Rayleigh–Ritz rotation: the Ritz vectors are
/// already Rayleigh–Ritz vectors of `A` on the whole Krylov space, converged to a residual
/// `tol·θ`; what is left of other eigenvectors in them changes the quotient only to second
/// order (`≈ tol²`), so `φᵀLφ` is as accurate as the rotated one (agreement with scipy stays at
/// ~1e-13) while the rotation cost three `n × r × r` products (~1.4 s at 100k vertices).
#[allow(clippy::too_many_arguments)]
fn finish(
    laplacian: &Laplacian,
    op: &Operator,
    y: Mat<f64>,
    mut values: Vec<f64>,
    mut vectors: Mat<f64>,
    n_const: usize,
    iterations: usize,
    restarts: usize,
) -> Result<Eigenpairs, SpectralError> {
    let n = y.nrows();
    let r = y.ncols();
    let mut phi = y;
    for j in 0..r {
        for (v, s) in as_slice_mut(&mut phi, j).iter_mut().zip(&op.sqrt_mass) {
            *v /= s;
        }
    }
    let mut lphi = Mat::<f64>::zeros(n, r);
    sparse_dense_matmul(
        lphi.as_mut(),
        Accum::Replace,
        laplacian.stiffness.as_ref(),
        phi.as_ref(),
        1.0,
        get_global_parallelism(),
    );
    let mass = &laplacian.mass;
    // Per pair: Rayleigh quotient, residual ‖Lφ − λMφ‖/‖Mφ‖, sign.
    let stats: Vec<(f64, f64, f64)> = (0..r)
        .map(|j| {
            let p = phi.col(j).try_as_col_major().map(|c| c.as_slice());
            let lp = lphi.col(j).try_as_col_major().map(|c| c.as_slice());
            // Invariant: columns of owned matrices are contiguous.
            let (p, lp) = (p.expect("contiguous"), lp.expect("contiguous"));
            let (mut num, mut den) = (0.0, 0.0);
            let mut big = 0usize;
            for i in 0..n {
                num += p[i] * lp[i];
                den += mass[i] * p[i] * p[i];
                if p[i].abs() > p[big].abs() {
                    big = i;
                }
            }
            let lam = (num / den).max(0.0);
            let (mut rn, mut mn) = (0.0, 0.0);
            for i in 0..n {
                let mp = mass[i] * p[i];
                rn += (lp[i] - lam * mp).powi(2);
                mn += mp * mp;
            }
            let sign = if p[big] < 0.0 { -1.0 } else { 1.0 };
            (lam, (rn / mn).sqrt(), sign)
        })
        .collect();
    let mut order: Vec<usize> = (0..r).collect();
    order.sort_by(|&a, &b| stats[a].0.total_cmp(&stats[b].0));
    let mut residual_max = 0.0f64;
    for (c, &j) in order.iter().enumerate() {
        let (lam, res, sign) = stats[j];
        residual_max = residual_max.max(res);
        values.push(lam);
        let src = phi.col(j);
        let mut dst = vectors.col_mut(n_const + c);
        for i in 0..n {
            dst[i] = sign * src[i];
        }
    }
    Ok(Eigenpairs {
        values,
        vectors,
        num_components: n_const,
        residual_max,
        iterations,
        restarts,
        factorization_s: 0.0,
        lanczos_s: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The working-set estimate refuses the sizes that aborted on allocation (the 13k body
    /// near k = n, k = 3000 at 200k vertices) and accepts the pipeline's sizes.
    #[test]
    fn dense_estimate_refuses_oversize_and_accepts_usual_sizes() {
        let o = EigenOptions::default();
        let limit = o.dense_limit_bytes as u128;
        assert!(plan_bytes(13_380, 1, 13_379, &o) > limit);
        assert!(plan_bytes(13_380, 1, 13_000, &o) > limit);
        assert!(plan_bytes(200_000, 1, 3_000, &o) > limit);
        assert!(plan_bytes(13_380, 1, 60, &o) < limit / 100);
        assert!(plan_bytes(100_000, 1, 300, &o) < limit / 2);
        // Non-decreasing in k (the binary search for the largest allowed k relies on it).
        let mut last = 0;
        for k in (1..13_380).step_by(97) {
            let b = plan_bytes(13_380, 1, k, &o);
            assert!(b >= last, "k = {k}");
            last = b;
        }
    }
}
