//! The sparse Cholesky factor of `K = L + εM` used by the shift-invert operator.
//!
//! Why not [`crate::SystemFactor`]: faer's convenience `Llt::solve_in_place` runs every
//! supernode's small dense triangular solve and update with the *global* parallelism, i.e. one
//! rayon fork/join (and spinning barrier) per supernode. A mesh factor has tens of thousands of
//! small supernodes, so a block solve on the 100k-vertex sphere took ~270 ms for 8 right-hand
//! sides (most of it thread synchronisation, and far worse when the other core is busy). Here
//! each column group of the right-hand side is solved with sequential kernels, and the groups
//! run on separate rayon tasks: no synchronisation inside a solve, both cores busy.

use crate::SpectralError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par, Side};

/// `K = P Lc Lcᵀ Pᵀ` (AMD ordering; faer picks simplicial or supernodal by its flop ratio).
pub(super) struct ShiftedFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl ShiftedFactor {
    /// Factors the symmetric positive-definite `matrix` (lower triangle read).
    pub(super) fn new(matrix: SparseColMatRef<'_, usize, f64>) -> Result<Self, SpectralError> {
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: match std::env::var("SYMCORR_SN").as_deref() {
                    Ok("simp") => faer::sparse::linalg::SupernodalThreshold::FORCE_SIMPLICIAL,
                    Ok("super") => faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
                    _ => faer::sparse::linalg::SupernodalThreshold::AUTO,
                },
                ..Default::default()
            },
        )
        .map_err(|e| SpectralError::Factorization(format!("symbolic analysis: {e:?}")))?;
        let mut values = vec![0.0; symbolic.len_val()];
        // The numeric factorisation is one call: faer's own parallelism pays off here.
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| SpectralError::Factorization("out of memory".into()))?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                matrix,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| {
                SpectralError::Factorization(format!("{e} (matrix not positive definite?)"))
            })?;
        if std::env::var_os("SYMCORR_EIGEN_TRACE").is_some() {
            let kind = match symbolic.raw() {
                faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Simplicial(_) => {
                    "simplicial".to_string()
                }
                faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(s) => {
                    format!("supernodal {}", s.n_supernodes())
                }
            };
            eprintln!("TRACE factor nnz {} {kind}", symbolic.len_val());
        }
        Ok(ShiftedFactor { symbolic, values })
    }

    /// Solves `K X = B` in place, column groups in parallel (see the module docs).
    pub(super) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let tasks = rayon::current_num_threads().clamp(1, rhs.ncols().max(1));
        self.solve_split(rhs, tasks);
    }

    fn solve_split(&self, rhs: MatMut<'_, f64>, tasks: usize) {
        if tasks <= 1 || rhs.ncols() < 2 {
            self.solve_seq(rhs);
            return;
        }
        let left_tasks = tasks / 2;
        let split = rhs.ncols() * left_tasks / tasks;
        let (a, b) = rhs.split_at_col_mut(split);
        rayon::join(
            || self.solve_split(a, left_tasks),
            || self.solve_split(b, tasks - left_tasks),
        );
    }

    fn solve_seq(&self, rhs: MatMut<'_, f64>) {
        if rhs.ncols() == 0 {
            return;
        }
        let req = self
            .symbolic
            .solve_in_place_scratch::<f64>(rhs.ncols(), Par::Seq);
        let mut mem = MemBuffer::new(req);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
}
