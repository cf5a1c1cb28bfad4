//! Cotan Laplacian (stiffness), lumped mass, and prefactored sparse Cholesky systems.

use crate::SpectralError;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut, MatRef, Side};
use nalgebra::{Point3, Vector3};
use symcorr_mesh::TriMesh;

/// Cotangents are clamped to `[-COT_CLAMP, COT_CLAMP]`.
///
/// An angle of θ ≈ 1e-5 rad has cot θ ≈ 1e5; a sliver that thin contributes a weight that
/// dwarfs every other edge weight and ruins the conditioning of the Cholesky factor without
/// adding geometric information, so larger cotangents (angles closer to 0 or π) are clamped.
pub const COT_CLAMP: f64 = 1e5;

/// A triangle whose doubled area is below `DEGENERATE_REL · (longest edge)²` is treated as
/// degenerate: it contributes neither stiffness nor mass (its angles are not defined).
pub const DEGENERATE_REL: f64 = 1e-12;

/// Cotan Laplace–Beltrami operator of a triangle mesh, split into stiffness and lumped mass.
///
/// Convention: **positive semi-definite**. `stiffness` is the symmetric matrix
/// `L_ij = -(cot α_ij + cot β_ij)/2` for an edge (i, j) (α, β the angles opposite the edge),
/// `L_ii = -Σ_j L_ij`, so `L·1 = 0` and `xᵀLx = ½ Σ_edges w_ij (x_i - x_j)² ≥ 0` (for
/// non-negative weights; with obtuse angles some w_ij < 0 but L stays PSD because it is a sum
/// of per-triangle PSD matrices). The continuous operator is `Δ ≈ -M⁻¹ L`; eigenpairs solve
/// `L φ = λ M φ` with `λ ≥ 0`.
///
/// `mass` is the lumped barycentric mass `M_ii = Σ_{f ∋ i} area(f)/3`.
///
/// Cotangents of angles within ~1e-5 rad of 0 or π are clamped to ±[`COT_CLAMP`];
/// numerically degenerate triangles ([`DEGENERATE_REL`]) are skipped entirely.
///
/// ```
/// use symcorr_mesh::TriMesh;
/// use symcorr_spectral::Laplacian;
/// let mesh = TriMesh::new(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
///     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
/// ).unwrap();
/// let lap = Laplacian::new(&mesh).unwrap();
/// // L·1 = 0
/// let ones = vec![1.0; 4];
/// assert!(lap.apply_stiffness(&ones).iter().all(|v| v.abs() < 1e-12));
/// // Factor L + 1·M once and solve.
/// let sys = lap.factor(1.0, None).unwrap();
/// let x = sys.solve(&lap.mass);
/// assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-12)); // (L + M)·1 = M·1
/// ```
#[derive(Debug, Clone)]
pub struct Laplacian {
    /// Symmetric cotan stiffness matrix (both triangles stored, all diagonal entries present),
    /// PSD convention: `L·1 = 0`, `xᵀLx ≥ 0`.
    pub stiffness: SparseColMat<usize, f64>,
    /// Lumped barycentric vertex mass (one third of the incident triangle areas), all `> 0`.
    pub mass: Vec<f64>,
    /// Index into `stiffness`'s value array of each diagonal entry.
    diag_index: Vec<usize>,
    /// Connected component of each vertex (over triangles) and their number.
    component: Vec<u32>,
    num_components: usize,
}

/// Cotangent of the angle between `u` and `v`, clamped (see [`COT_CLAMP`]).
#[inline]
pub(crate) fn cot(u: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    let c = u.cross(v).norm();
    let d = u.dot(v);
    if c <= d.abs() / COT_CLAMP {
        COT_CLAMP.copysign(d)
    } else {
        d / c
    }
}

impl Laplacian {
    /// Builds the cotan stiffness and lumped mass of `mesh`.
    ///
    /// Errors: [`SpectralError::ZeroMass`] if a vertex has no (non-degenerate) incident
    /// triangle — repair the mesh first (`symcorr_mesh::repair`).
    pub fn new(mesh: &TriMesh) -> Result<Laplacian, SpectralError> {
        let n = mesh.num_vertices();
        // Sparsity: for every column, the sorted list of neighbours plus the vertex itself.
        let neighbors = mesh.vertex_neighbors();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(n + 2 * mesh.num_triangles() * 3 / 2 + n);
        let mut diag_index = Vec::with_capacity(n);
        col_ptr.push(0usize);
        for (j, nb) in neighbors.iter().enumerate() {
            let mut inserted = false;
            for &i in nb {
                if !inserted && i as usize > j {
                    diag_index.push(row_idx.len());
                    row_idx.push(j);
                    inserted = true;
                }
                row_idx.push(i as usize);
            }
            if !inserted {
                diag_index.push(row_idx.len());
                row_idx.push(j);
            }
            col_ptr.push(row_idx.len());
        }
        let mut val = vec![0.0; row_idx.len()];
        let mut mass = vec![0.0; n];
        let pos = |row: usize, col: usize| -> usize {
            let s = &row_idx[col_ptr[col]..col_ptr[col + 1]];
            // Invariant: (row, col) is an edge of the mesh, so it is in the pattern.
            col_ptr[col] + s.binary_search(&row).unwrap_or(0)
        };
        for t in &mesh.triangles {
            let p = t.map(|v| Point3::from(mesh.positions[v as usize]));
            let [p0, p1, p2] = p;
            let e = [p1 - p0, p2 - p1, p0 - p2];
            let longest = e.iter().map(|x| x.dot(x)).fold(0.0, f64::max);
            let area2 = e[0].cross(&e[1]).norm();
            if area2 <= DEGENERATE_REL * longest || area2 == 0.0 {
                continue;
            }
            for k in 0..3 {
                mass[t[k] as usize] += area2 / 6.0;
                // Angle at corner k is opposite the edge (k+1, k+2).
                let a = p[k];
                let (i, j) = (t[(k + 1) % 3] as usize, t[(k + 2) % 3] as usize);
                let w = 0.5 * cot(&(p[(k + 1) % 3] - a), &(p[(k + 2) % 3] - a));
                val[pos(i, j)] -= w;
                val[pos(j, i)] -= w;
                val[diag_index[i]] += w;
                val[diag_index[j]] += w;
            }
        }
        if let Some(vertex) = mass.iter().position(|&m| m <= 0.0) {
            return Err(SpectralError::ZeroMass { vertex });
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let (component, num_components) = mesh.connected_components();
        Ok(Laplacian {
            stiffness: SparseColMat::new(symbolic, val),
            mass,
            diag_index,
            component,
            num_components,
        })
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// Always false (a Laplacian has at least one vertex); for clippy's `len` convention.
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Connected component of every vertex (`0..num_components`) and the number of components.
    /// Each component contributes one zero eigenvalue (its constant function).
    pub fn components(&self) -> (&[u32], usize) {
        (&self.component, self.num_components)
    }

    /// Total area (sum of the lumped mass).
    pub fn total_area(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// `L·x` for one vector.
    pub fn apply_stiffness(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.len()];
        let (sym, val) = self.stiffness.parts();
        let cp = sym.col_ptr();
        let ri = sym.row_idx();
        // L is symmetric: column j times x_j accumulated = row products.
        for j in 0..self.len() {
            let mut acc = 0.0;
            for p in cp[j]..cp[j + 1] {
                acc += val[p] * x[ri[p]];
            }
            y[j] = acc;
        }
        y
    }

    /// `xᵀ L y` — convenient for Rayleigh quotients and energies.
    pub fn stiffness_form(&self, x: &[f64], y: &[f64]) -> f64 {
        self.apply_stiffness(y)
            .iter()
            .zip(x)
            .map(|(a, b)| a * b)
            .sum()
    }

    /// `L + a·diag(mass) + diag(h)` as a new sparse matrix with the same pattern.
    ///
    /// `h` (if given) must have one entry per vertex.
    pub fn shifted(
        &self,
        a: f64,
        h: Option<&[f64]>,
    ) -> Result<SparseColMat<usize, f64>, SpectralError> {
        if let Some(h) = h {
            if h.len() != self.len() {
                return Err(SpectralError::InvalidArgument(format!(
                    "diagonal has {} entries, the mesh has {} vertices",
                    h.len(),
                    self.len()
                )));
            }
        }
        let mut m = self.stiffness.clone();
        let val = m.val_mut();
        for (v, &d) in self.diag_index.iter().enumerate() {
            val[d] += a * self.mass[v] + h.map_or(0.0, |h| h[v]);
        }
        Ok(m)
    }

    /// Factors `L + a·diag(mass) + diag(h)` once with faer's sparse Cholesky (AMD ordering,
    /// supernodal), for many later solves.
    ///
    /// The matrix must be positive definite: `a > 0`, or `h ≥ 0` and non-zero on every
    /// connected component (e.g. bone heat `L + H`). Errors: [`SpectralError::Factorization`]
    /// if it is not (numerically).
    pub fn factor(&self, a: f64, h: Option<&[f64]>) -> Result<SystemFactor, SpectralError> {
        SystemFactor::new(&self.shifted(a, h)?)
    }
}

/// A sparse symmetric positive-definite matrix factored once by Cholesky (`LLᵀ`), for solving
/// many right-hand sides. `Send + Sync`: solves may run in parallel from several threads.
#[derive(Debug, Clone)]
pub struct SystemFactor {
    llt: Llt<usize, f64>,
    n: usize,
}

impl SystemFactor {
    /// Factors a symmetric positive-definite matrix (only its lower triangle is read).
    pub fn new(matrix: &SparseColMat<usize, f64>) -> Result<SystemFactor, SpectralError> {
        let n = matrix.nrows();
        if matrix.ncols() != n {
            return Err(SpectralError::InvalidArgument(format!(
                "matrix is {}×{}, not square",
                n,
                matrix.ncols()
            )));
        }
        let symbolic = SymbolicLlt::try_new(matrix.symbolic(), Side::Lower)
            .map_err(|e| SpectralError::Factorization(format!("symbolic analysis: {e:?}")))?;
        let llt =
            Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), Side::Lower).map_err(|e| {
                SpectralError::Factorization(format!("{e} (matrix not positive definite?)"))
            })?;
        Ok(SystemFactor { llt, n })
    }

    /// Size of the system.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false for a factored system; for clippy's `len` convention.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Solves `A X = B` in place for every column of `rhs` (one blocked solve: much faster
    /// than one column at a time).
    ///
    /// # Panics
    /// If `rhs.nrows()` differs from the system size (a programming error).
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        assert_eq!(rhs.nrows(), self.n, "right-hand side has the wrong length");
        self.llt.solve_in_place(rhs);
    }

    /// Solves `A x = b` for one right-hand side.
    ///
    /// # Panics
    /// If `b.len()` differs from the system size (a programming error).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = Mat::from_fn(self.n, 1, |i, _| b[i]);
        self.solve_in_place(x.as_mut());
        (0..self.n).map(|i| x[(i, 0)]).collect()
    }

    /// Solves `A X = B` for all columns of `b`, returning `X`.
    pub fn solve_many(&self, b: MatRef<'_, f64>) -> Mat<f64> {
        let mut x = b.to_owned();
        self.solve_in_place(x.as_mut());
        x
    }
}
