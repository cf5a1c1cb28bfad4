//! The k smallest eigenpairs of `L φ = λ M φ` by shift-invert Lanczos (DESIGN.md, Algorithms 2).
//!
//! Method:
//! 1. Factor `K = L + εM` once (faer sparse Cholesky).
//! 2. Run Lanczos on the symmetric operator `A = M^½ K⁻¹ M^½` (its largest eigenvalues
//!    `θ = 1/(λ + ε)` belong to the smallest `λ`), with full re-orthogonalisation (classical
//!    Gram–Schmidt, two passes) of every new vector against the whole basis.
//! 3. After every solve, project out the known null space: the constant function of each
//!    connected component (`M^½ 1_c` in the symmetric coordinates). Those pairs (`λ = 0`) are
//!    returned exactly; without this, rounding in the nearly singular solve leaks the constant
//!    mode into everything and eigenvalues are only good to ~1e-7.
//! 4. Thick restart (Wu & Simon 2000) when the basis reaches its size limit: keep the best Ritz
//!    vectors, continue from the residual vector. The basis is `n × (m+1)`, so memory is bounded
//!    by [`EigenOptions::memory_budget_bytes`] whatever k is.
//! 5. Rayleigh–Ritz polish: with the converged vectors `Φ` (M-orthonormal), solve the small
//!    dense problem `ΦᵀLΦ` (faer self-adjoint eigen) and rotate; the values returned are these
//!    Rayleigh quotients.

use crate::{Laplacian, SpectralError, SystemFactor};
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
}

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
    /// `max_i ‖Lφ_i − λ_i Mφ_i‖ / ‖Mφ_i‖` over the non-constant pairs, after the polish (the
    /// constant pairs have residual 0 by construction): an a-posteriori accuracy check.
    pub residual_max: f64,
    /// Lanczos steps (operator applications = sparse solves) used.
    pub iterations: usize,
    /// Thick restarts used.
    pub restarts: usize,
    /// Wall time of the sparse Cholesky factorisation of `L + εM`, seconds.
    pub factorization_s: f64,
    /// Wall time of the Lanczos iteration and polish (everything after the factorisation), seconds.
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
    factor: SystemFactor,
    sqrt_mass: Vec<f64>,
    component: &'a [u32],
    /// `M^½ 1_c / √area_c` evaluated per vertex: entry i is `√m_i / √area_{c(i)}`.
    null_vec: Vec<f64>,
    num_components: usize,
}

impl Operator<'_> {
    /// Removes the components along every `M^½ 1_c` (orthonormal, disjoint supports).
    fn deflate(&self, w: &mut [f64]) {
        let mut dots = vec![0.0; self.num_components];
        for ((x, &c), &u) in w.iter().zip(self.component).zip(&self.null_vec) {
            dots[c as usize] += x * u;
        }
        for ((x, &c), &u) in w.iter_mut().zip(self.component).zip(&self.null_vec) {
            *x -= dots[c as usize] * u;
        }
    }

    /// `W = A X` for a block of columns (one blocked sparse solve), deflated.
    fn apply_block(&self, x: MatRef<'_, f64>, w: &mut Mat<f64>) {
        let n = self.sqrt_mass.len();
        for c in 0..x.ncols() {
            for i in 0..n {
                w[(i, c)] = self.sqrt_mass[i] * x[(i, c)];
            }
        }
        self.factor.solve_in_place(w.as_mut());
        for c in 0..x.ncols() {
            let col = as_slice_mut(w, c);
            for (v, s) in col.iter_mut().zip(&self.sqrt_mass) {
                *v *= s;
            }
            self.deflate(col);
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

/// One classical Gram–Schmidt sweep: `C = Qᵀ W`, `W −= Q C`. Memory-bound (it streams the
/// whole basis twice), so the rows are split in two halves processed by two rayon tasks with
/// sequential faer kernels (faer's own parallel split of these skinny products was slower).
fn project_out(basis: MatRef<'_, f64>, w: &mut Mat<f64>, c: &mut Mat<f64>, parallel: bool) {
    let n = basis.nrows();
    let seq = faer::Par::Seq;
    if !parallel || n < 4096 {
        matmul(
            c.as_mut(),
            Accum::Replace,
            basis.transpose(),
            w.as_ref(),
            1.0,
            seq,
        );
        matmul(w.as_mut(), Accum::Add, basis, c.as_ref(), -1.0, seq);
        return;
    }
    let half = n / 2;
    let (q_top, q_bot) = basis.split_at_row(half);
    let mut c_bot = Mat::<f64>::zeros(c.nrows(), c.ncols());
    {
        let (w_top, w_bot) = w.as_ref().split_at_row(half);
        let c_top = c.as_mut();
        rayon::join(
            || matmul(c_top, Accum::Replace, q_top.transpose(), w_top, 1.0, seq),
            || {
                matmul(
                    c_bot.as_mut(),
                    Accum::Replace,
                    q_bot.transpose(),
                    w_bot,
                    1.0,
                    seq,
                )
            },
        );
    }
    *c += &c_bot;
    let (w_top, w_bot) = w.as_mut().split_at_row_mut(half);
    let cr = c.as_ref();
    rayon::join(
        || matmul(w_top, Accum::Add, q_top, cr, -1.0, seq),
        || matmul(w_bot, Accum::Add, q_bot, cr, -1.0, seq),
    );
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
/// Errors: `k == 0` or `k > n` ([`SpectralError::InvalidArgument`]), factorisation failure, or
/// no convergence within `max_restarts` ([`SpectralError::NotConverged`]).
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
    if k == 0 || k > n {
        return Err(SpectralError::InvalidArgument(format!(
            "asked for {k} eigenpairs of a mesh with {n} vertices (need 1 ≤ k ≤ n)"
        )));
    }
    let (component, nc) = laplacian.components();
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
    let factor = laplacian.factor(eps, None)?;
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
    let m0 = options.max_basis.unwrap_or((2 * r + 20).max(r + 40));
    let budget_cols = options.memory_budget_bytes / (8 * n);
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
    let par = get_global_parallelism();
    // R of the last block: A Q_m = Q_m H + Q_next R E_lastᵀ.
    let mut last_r = Mat::<f64>::zeros(b, b);
    let orth_par = !matches!(par, faer::Par::Seq);
    loop {
        let mut j = start;
        while j < m {
            op.apply_block(q.as_ref().subcols(j, b), &mut w);
            iterations += b;
            let norms_before: Vec<f64> = (0..b).map(|c| col_norm(&w, c)).collect();
            // Two passes of block classical Gram–Schmidt against the whole basis.
            let basis = q.as_ref().subcols(0, j + b);
            let mut coef = Mat::<f64>::zeros(j + b, b);
            let mut cpass = Mat::<f64>::zeros(j + b, b);
            for _pass in 0..2 {
                project_out(basis, &mut w, &mut cpass, orth_par);
                for c in 0..b {
                    op.deflate(as_slice_mut(&mut w, c));
                    for i in 0..j + b {
                        coef[(i, c)] += cpass[(i, c)];
                    }
                }
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
                for _pass in 0..2 {
                    for p in 0..c {
                        let dotp = w.col(p).transpose() * w.col(c);
                        let (wp, mut wc) = (w.col(p).to_owned(), w.col_mut(c));
                        wc -= dotp * &wp;
                        rmat[(p, c)] += dotp;
                    }
                }
                let nrm = col_norm(&w, c);
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
                    for i in 0..n {
                        w[(i, c)] /= nrm;
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
        }
        // Ritz values/vectors of the projected matrix.
        let evd = h
            .as_ref()
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| SpectralError::Factorization(format!("dense eigen: {e:?}")))?;
        let s = evd.U();
        let theta = evd.S().column_vector();
        // faer sorts ascending; we want the largest θ first.
        let order: Vec<usize> = (0..m).rev().collect();
        // Residual of Ritz pair i: ‖R_last · S[m−b.., i]‖.
        let residual = |i: usize| -> f64 {
            let mut acc = 0.0;
            for d in 0..b {
                let mut v = 0.0;
                for c in 0..b {
                    v += last_r[(d, c)] * s[(m - b + c, i)];
                }
                acc += v * v;
            }
            acc.sqrt()
        };
        let mut worst = 0.0f64;
        let mut converged = 0usize;
        for (rank, &i) in order.iter().enumerate().take(r) {
            let rel = residual(i) / theta[i].abs().max(f64::MIN_POSITIVE);
            worst = worst.max(rel);
            if rel <= options.tol && converged == rank {
                converged += 1;
            }
        }
        if converged >= r || m == dim {
            // Ritz vectors Y = Q_m S[:, wanted].
            let mut sel = Mat::<f64>::zeros(m, r);
            for (c, &i) in order.iter().take(r).enumerate() {
                sel.col_mut(c).copy_from(s.col(i));
            }
            let mut y = Mat::<f64>::zeros(n, r);
            matmul(
                y.as_mut(),
                Accum::Replace,
                q.as_ref().subcols(0, m),
                sel.as_ref(),
                1.0,
                par,
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
                converged: converged + n_const,
                iterations,
                residual: worst,
            });
        }
        // Thick restart: keep l Ritz vectors (the wanted ones and half of the rest, which
        // speeds up convergence of the last wanted ones), continue from the residual block.
        restarts += 1;
        // l ≥ r + 1 and m − l a positive multiple of b (the next blocks end exactly at m).
        let l0 = r + (m - r) / 2;
        let steps = ((m - l0 + b / 2) / b).clamp(1, (m - r - 1) / b);
        let l = m - steps * b;
        let mut sel = Mat::<f64>::zeros(m, l);
        for (c, &i) in order.iter().take(l).enumerate() {
            sel.col_mut(c).copy_from(s.col(i));
        }
        let mut kept = Mat::<f64>::zeros(n, l);
        matmul(
            kept.as_mut(),
            Accum::Replace,
            q.as_ref().subcols(0, m),
            sel.as_ref(),
            1.0,
            par,
        );
        let resid = q.as_ref().subcols(m, b).to_owned();
        q.as_mut().subcols_mut(0, l).copy_from(kept.as_ref());
        q.as_mut().subcols_mut(l, b).copy_from(resid.as_ref());
        h.fill(0.0);
        for (c, &i) in order.iter().take(l).enumerate() {
            h[(c, c)] = theta[i];
        }
        start = l;
    }
}

/// Maps Lanczos vectors back (`φ = M^-½ y`), Rayleigh–Ritz polishes with `L`, fixes signs and
/// assembles the result after the constant pairs.
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
    let par = get_global_parallelism();
    let mut phi = y;
    for j in 0..r {
        for i in 0..n {
            phi[(i, j)] /= op.sqrt_mass[i];
        }
    }
    // Projected stiffness ΦᵀLΦ (Φ is M-orthonormal to rounding: Y has orthonormal columns).
    let mut lphi = Mat::<f64>::zeros(n, r);
    sparse_dense_matmul(
        lphi.as_mut(),
        Accum::Replace,
        laplacian.stiffness.as_ref(),
        phi.as_ref(),
        1.0,
        par,
    );
    let mut proj = Mat::<f64>::zeros(r, r);
    matmul(
        proj.as_mut(),
        Accum::Replace,
        phi.transpose(),
        lphi.as_ref(),
        1.0,
        par,
    );
    for i in 0..r {
        for j in 0..i {
            let a = 0.5 * (proj[(i, j)] + proj[(j, i)]);
            proj[(i, j)] = a;
            proj[(j, i)] = a;
        }
    }
    let evd = proj
        .as_ref()
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| SpectralError::Factorization(format!("dense eigen: {e:?}")))?;
    let u = evd.U();
    let lam = evd.S().column_vector();
    let mut rot = Mat::<f64>::zeros(n, r);
    matmul(rot.as_mut(), Accum::Replace, phi.as_ref(), u, 1.0, par);
    let mut lrot = Mat::<f64>::zeros(n, r);
    matmul(lrot.as_mut(), Accum::Replace, lphi.as_ref(), u, 1.0, par);
    let mut residual_max = 0.0f64;
    for j in 0..r {
        let lj = lam[j].max(0.0);
        // Sign: largest-magnitude entry positive (deterministic output).
        let mut big = 0usize;
        for i in 0..n {
            if rot[(i, j)].abs() > rot[(big, j)].abs() {
                big = i;
            }
        }
        let sign = if rot[(big, j)] < 0.0 { -1.0 } else { 1.0 };
        let (mut rn, mut mn) = (0.0, 0.0);
        for i in 0..n {
            let m = laplacian.mass[i];
            let mp = m * rot[(i, j)];
            rn += (lrot[(i, j)] - lj * mp).powi(2);
            mn += mp * mp;
            vectors[(i, n_const + j)] = sign * rot[(i, j)];
        }
        residual_max = residual_max.max((rn / mn).sqrt());
        values.push(lj);
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
