//! The sparse Cholesky factor of `K = L + εM` and the blocked triangular solves of the
//! shift-invert operator.
//!
//! faer computes the factorisation (AMD ordering; simplicial or supernodal by its own flop
//! heuristic; its parallel supernodal kernels). The factor is then copied into a plain
//! compressed-column lower triangle and solved with the kernels below, because faer's
//! `Llt::solve_in_place` was the bottleneck of the eigensolver:
//!
//! * it runs each supernode's small dense triangular solve and update with the *global*
//!   parallelism, i.e. one rayon fork/join (and spinning barrier) per supernode. A mesh factor
//!   has tens of thousands of small supernodes: a block solve with 8 right-hand sides on the
//!   100k-vertex sphere took ~270 ms (and far longer when the other core is busy);
//! * the simplicial path and the per-supernode scatter loops walk the right-hand side column by
//!   column, touching every factor entry once per column.
//!
//! Here the right-hand sides of a block are stored interleaved (row-major, `W` values per
//! vertex, `W ∈ {1, 2, 4, 8}`), so every factor entry is loaded once per block and updates `W`
//! contiguous values (one or two SIMD registers; the loops are compiled for the CPU's vector
//! extensions through `pulp`'s runtime dispatch). Column groups of a block run as separate rayon
//! tasks (no synchronisation inside a solve). The scaling `M^½ · K⁻¹ · M^½` of the operator and
//! the fill-reducing permutation are folded into the gather/scatter.
//!
//! Measured: `docs/decisions/2026-11-23-eigensolver-shift-invert-block-lanczos.md`.

use crate::SpectralError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SparseColMatRef;
use faer::{MatMut, MatRef, Side};

/// `K = P C Cᵀ Pᵀ` with `C` lower triangular, stored by columns: `diag[j] = C_jj` and the
/// strictly lower entries of column j at `col_ptr[j]..col_ptr[j+1]` of `row_idx`/`val`.
pub(super) struct ShiftedFactor {
    n: usize,
    /// Permuted position i holds original vertex `perm[i]`.
    perm: Vec<usize>,
    diag: Vec<f64>,
    col_ptr: Vec<usize>,
    row_idx: Vec<u32>,
    val: Vec<f64>,
}

impl ShiftedFactor {
    /// Factors the symmetric positive-definite `matrix` (lower triangle read).
    pub(super) fn new(matrix: SparseColMatRef<'_, usize, f64>) -> Result<Self, SpectralError> {
        Self::with_threshold(matrix, SupernodalThreshold::AUTO)
    }

    /// [`ShiftedFactor::new`] with faer's simplicial/supernodal choice given (tests use both).
    fn with_threshold(
        matrix: SparseColMatRef<'_, usize, f64>,
        threshold: SupernodalThreshold,
    ) -> Result<Self, SpectralError> {
        let n = matrix.nrows();
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
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
        let perm: Vec<usize> = match symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n).collect(),
        };
        let mut diag = vec![0.0; n];
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx: Vec<u32> = Vec::with_capacity(values.len());
        let mut val: Vec<f64> = Vec::with_capacity(values.len());
        let bad = || SpectralError::Factorization("unexpected Cholesky factor layout".into());
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (cp, ri) = (s.col_ptr(), s.row_idx());
                for j in 0..n {
                    let (a, b) = (cp[j], cp[j + 1]);
                    // faer stores the diagonal first in each column of a simplicial factor.
                    if a >= b || ri[a] != j {
                        return Err(bad());
                    }
                    diag[j] = values[a];
                    for p in a + 1..b {
                        if values[p] != 0.0 {
                            row_idx.push(ri[p] as u32);
                            val.push(values[p]);
                        }
                    }
                    col_ptr.push(row_idx.len());
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let lref = SupernodalLltRef::new(s, &values);
                for sn in 0..s.n_supernodes() {
                    let node = lref.supernode(sn);
                    let (start, pattern, m) = (node.start(), node.pattern(), node.val());
                    let size = m.ncols();
                    for c in 0..size {
                        diag[start + c] = m[(c, c)];
                        // Below the diagonal inside the supernode, then its shared pattern
                        // (explicit zeros from supernode amalgamation are dropped).
                        for r in c + 1..size {
                            let v = m[(r, c)];
                            if v != 0.0 {
                                row_idx.push((start + r) as u32);
                                val.push(v);
                            }
                        }
                        for (idx, &r) in pattern.iter().enumerate() {
                            let v = m[(size + idx, c)];
                            if v != 0.0 {
                                row_idx.push(r as u32);
                                val.push(v);
                            }
                        }
                        col_ptr.push(row_idx.len());
                    }
                }
                if col_ptr.len() != n + 1 {
                    return Err(bad());
                }
            }
        }
        if n > u32::MAX as usize {
            return Err(SpectralError::InvalidArgument(format!(
                "{n} vertices: more than the solver's 32-bit indices"
            )));
        }
        Ok(ShiftedFactor {
            n,
            perm,
            diag,
            col_ptr,
            row_idx,
            val,
        })
    }

    /// `out = S K⁻¹ S x` column by column, with `S = diag(scale)`.
    ///
    /// Columns are split into one group per rayon thread; each group is solved in interleaved
    /// chunks of 8, 4, 2 or 1 columns.
    ///
    /// `scratch` is grown to `n · ncols` values and reused across calls (a fresh multi-MB buffer
    /// per solve costs page faults on every call).
    pub(super) fn solve_scaled(
        &self,
        x: MatRef<'_, f64>,
        out: MatMut<'_, f64>,
        scale: &[f64],
        scratch: &mut Vec<f64>,
    ) {
        let tasks = rayon::current_num_threads().clamp(1, x.ncols().max(1));
        if scratch.len() < self.n * x.ncols() {
            scratch.resize(self.n * x.ncols(), 0.0);
        }
        self.solve_split(x, out, scale, tasks, scratch);
    }

    fn solve_split(
        &self,
        x: MatRef<'_, f64>,
        out: MatMut<'_, f64>,
        scale: &[f64],
        tasks: usize,
        scratch: &mut [f64],
    ) {
        let n = self.n;
        if tasks <= 1 || x.ncols() < 2 {
            let mut c0 = 0;
            let mut out = out;
            while c0 < x.ncols() {
                let w = match x.ncols() - c0 {
                    r if r >= 8 => 8,
                    r if r >= 4 => 4,
                    r if r >= 2 => 2,
                    _ => 1,
                };
                let xs = x.subcols(c0, w);
                let os = out.as_mut().subcols_mut(c0, w);
                let buf = &mut scratch[..n * w];
                match w {
                    8 => self.solve_chunk::<8>(xs, os, scale, buf),
                    4 => self.solve_chunk::<4>(xs, os, scale, buf),
                    2 => self.solve_chunk::<2>(xs, os, scale, buf),
                    _ => self.solve_chunk::<1>(xs, os, scale, buf),
                }
                c0 += w;
            }
            return;
        }
        let left = tasks / 2;
        let split = x.ncols() * left / tasks;
        let (x0, x1) = x.split_at_col(split);
        let (o0, o1) = out.split_at_col_mut(split);
        let (s0, s1) = scratch.split_at_mut(n * split);
        rayon::join(
            || self.solve_split(x0, o0, scale, left, s0),
            || self.solve_split(x1, o1, scale, tasks - left, s1),
        );
    }

    /// Solves `W` columns at once in an interleaved buffer (see the module docs).
    fn solve_chunk<const W: usize>(
        &self,
        x: MatRef<'_, f64>,
        mut out: MatMut<'_, f64>,
        scale: &[f64],
        buf: &mut [f64],
    ) {
        // Gather: permute and scale.
        for (i, &v) in self.perm.iter().enumerate() {
            let s = scale[v];
            for c in 0..W {
                buf[i * W + c] = s * x[(v, c)];
            }
        }
        pulp::Arch::new().dispatch(|| sweep::<W>(self, buf));
        // Scatter: undo the permutation and scale.
        for (i, &v) in self.perm.iter().enumerate() {
            let s = scale[v];
            for c in 0..W {
                out[(v, c)] = s * buf[i * W + c];
            }
        }
    }
}

/// Forward (`C y = b`) and backward (`Cᵀ x = y`) substitution on an interleaved buffer.
/// `#[inline(always)]` so that it is compiled inside `pulp`'s feature-enabled dispatch.
#[inline(always)]
fn sweep<const W: usize>(f: &ShiftedFactor, buf: &mut [f64]) {
    let n = f.n;
    for j in 0..n {
        let d = 1.0 / f.diag[j];
        let mut xj = [0.0f64; W];
        for (c, v) in xj.iter_mut().enumerate() {
            *v = buf[j * W + c] * d;
        }
        buf[j * W..j * W + W].copy_from_slice(&xj);
        let (a, b) = (f.col_ptr[j], f.col_ptr[j + 1]);
        for (&r, &l) in f.row_idx[a..b].iter().zip(&f.val[a..b]) {
            let dst = &mut buf[r as usize * W..r as usize * W + W];
            for c in 0..W {
                dst[c] -= l * xj[c];
            }
        }
    }
    for j in (0..n).rev() {
        let mut acc = [0.0f64; W];
        acc.copy_from_slice(&buf[j * W..j * W + W]);
        let (a, b) = (f.col_ptr[j], f.col_ptr[j + 1]);
        for (&r, &l) in f.row_idx[a..b].iter().zip(&f.val[a..b]) {
            let src = &buf[r as usize * W..r as usize * W + W];
            for c in 0..W {
                acc[c] -= l * src[c];
            }
        }
        let d = 1.0 / f.diag[j];
        for c in 0..W {
            buf[j * W + c] = acc[c] * d;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{testmesh, Laplacian};
    use faer::Mat;

    /// `S K⁻¹ S X` against faer's own `Llt` solve (through [`crate::SystemFactor`]), for both
    /// factor layouts and block widths that exercise every interleave width and the split.
    #[test]
    fn blocked_solve_matches_faer_llt() {
        let mesh = testmesh::deformed_sphere(12);
        let lap = Laplacian::new(&mesh).unwrap();
        let n = lap.len();
        let shift = 0.1;
        let k = lap.shifted(shift, None).unwrap();
        let reference = lap.factor(shift, None).unwrap();
        let scale: Vec<f64> = lap.mass.iter().map(|m| m.sqrt()).collect();
        for threshold in [
            SupernodalThreshold::FORCE_SIMPLICIAL,
            SupernodalThreshold::FORCE_SUPERNODAL,
        ] {
            let f = ShiftedFactor::with_threshold(k.as_ref(), threshold).unwrap();
            let mut scratch = Vec::new();
            for ncols in [1usize, 3, 8, 15] {
                let x = Mat::from_fn(n, ncols, |i, c| ((i * 7 + c * 13) % 23) as f64 - 11.0);
                let mut out = Mat::zeros(n, ncols);
                f.solve_scaled(x.as_ref(), out.as_mut(), &scale, &mut scratch);
                let sx = Mat::from_fn(n, ncols, |i, c| scale[i] * x[(i, c)]);
                let y = reference.solve_many(sx.as_ref());
                let want = Mat::from_fn(n, ncols, |i, c| scale[i] * y[(i, c)]);
                let err = (&out - &want).norm_max();
                assert!(
                    err <= 1e-12 * want.norm_max(),
                    "{threshold:?}, {ncols} columns: error {err:e}"
                );
            }
        }
    }
}
