//! Block classical Gram–Schmidt with a measured second pass (CGS2 when it matters), fused and
//! cache-blocked.
//!
//! Full re-orthogonalisation of a new block `W` (n × b) against the Lanczos basis `Q` (n × j)
//! dominates the eigensolver's cost once `j` is in the hundreds: it is memory-bound (the basis
//! is 20–200 MB). Textbook CGS2 streams `Q` four times (`C₁ = QᵀW`, `W −= QC₁`, `C₂ = QᵀW`,
//! `W −= QC₂`). Here the middle two are fused row chunk by row chunk — after `W_r −= Q_r C₁` the
//! chunk `Q_r` is still in cache and `C₂ += Q_rᵀ W_r` is exact because `C₂ = Σ_r Q_rᵀ W_r` — so
//! `Q` is streamed three times, and only twice when `C₂` shows that the second correction would
//! not change `W` beyond rounding (see [`SECOND_PASS_TOL`]; 40 of 48 block steps on the body).
//! Products are formed as `Cᵀ = WᵀQ` (faer's gemm handles that orientation without repacking
//! the tall operand, ~2× faster than `QᵀW` here). Rows are split
//! into one contiguous part per rayon thread; the b × j partial sums are added afterwards.
//!
//! Measured: `docs/decisions/2026-11-23-eigensolver-shift-invert-block-lanczos.md`.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// Rows per cache block: `Q_r` (≤ ~300 columns) stays in L2 between the fused products.
const CHUNK: usize = 256;
/// Relative size of the second Gram–Schmidt correction below which it is not applied.
/// With every pass applied, `‖QᵀW‖/‖W‖` after the first pass was 3e-17…5e-15 in all 48 block
/// steps of the body (k = 100); with this test the second update ran in 8 of 48 steps on both
/// the body and the 100k sphere, and M-orthonormality and the scipy agreement (~1e-13) were
/// unchanged. The correction is applied whenever it would move `W` by more than this.
const SECOND_PASS_TOL: f64 = 1e-13;
/// Below this many rows the thread split costs more than it gains.
const PARALLEL_MIN_ROWS: usize = 4096;

/// Sweep 1 on one row part: `ct += Wᵀ Q`.
fn sweep_project(q: MatRef<'_, f64>, w: MatRef<'_, f64>, mut ct: MatMut<'_, f64>) {
    let n = q.nrows();
    let mut r0 = 0;
    while r0 < n {
        let rr = CHUNK.min(n - r0);
        matmul(
            ct.as_mut(),
            Accum::Add,
            w.subrows(r0, rr).transpose(),
            q.subrows(r0, rr),
            1.0,
            Par::Seq,
        );
        r0 += rr;
    }
}

/// Sweep 2 on one row part: `W −= Q C₁`, then (chunk still cached) `c2t += Wᵀ Q`.
fn sweep_update_project(
    q: MatRef<'_, f64>,
    mut w: MatMut<'_, f64>,
    c1: MatRef<'_, f64>,
    mut c2t: MatMut<'_, f64>,
) {
    let n = q.nrows();
    let mut r0 = 0;
    while r0 < n {
        let rr = CHUNK.min(n - r0);
        let qc = q.subrows(r0, rr);
        let mut wc = w.as_mut().subrows_mut(r0, rr);
        matmul(wc.as_mut(), Accum::Add, qc, c1, -1.0, Par::Seq);
        matmul(
            c2t.as_mut(),
            Accum::Add,
            wc.as_ref().transpose(),
            qc,
            1.0,
            Par::Seq,
        );
        r0 += rr;
    }
}

/// Sweep 3 on one row part: `W −= Q C₂`.
fn sweep_update(q: MatRef<'_, f64>, mut w: MatMut<'_, f64>, c2: MatRef<'_, f64>) {
    let n = q.nrows();
    let mut r0 = 0;
    while r0 < n {
        let rr = CHUNK.min(n - r0);
        matmul(
            w.as_mut().subrows_mut(r0, rr),
            Accum::Add,
            q.subrows(r0, rr),
            c2,
            -1.0,
            Par::Seq,
        );
        r0 += rr;
    }
}

/// Runs `f` on `parts` contiguous row ranges of (`q`, `w`) in parallel, summing the b × j
/// matrices the calls return.
fn split_rows<F>(q: MatRef<'_, f64>, w: MatMut<'_, f64>, parts: usize, f: &F) -> Mat<f64>
where
    F: Fn(MatRef<'_, f64>, MatMut<'_, f64>) -> Mat<f64> + Sync,
{
    if parts <= 1 {
        return f(q, w);
    }
    let left = parts / 2;
    let mid = q.nrows() * left / parts;
    let (q0, q1) = q.split_at_row(mid);
    let (w0, w1) = w.split_at_row_mut(mid);
    let (mut a, b) = rayon::join(
        || split_rows(q0, w0, left, f),
        || split_rows(q1, w1, parts - left, f),
    );
    a += &b;
    a
}

/// Orthogonalises the columns of `w` against the orthonormal columns of `q` by classical
/// Gram–Schmidt with a measured second pass: on return `w ← (I − QQᵀ)² w` (or `(I − QQᵀ) w`
/// when the second correction is below [`SECOND_PASS_TOL`]), and the coefficients of the
/// passes applied (`w_in = Q C + w_out`) are returned, `j × b`.
pub(super) fn cgs2(q: MatRef<'_, f64>, mut w: MatMut<'_, f64>) -> Mat<f64> {
    let (n, j, b) = (q.nrows(), q.ncols(), w.ncols());
    if j == 0 || b == 0 {
        return Mat::zeros(j, b);
    }
    let parts = if n >= PARALLEL_MIN_ROWS {
        rayon::current_num_threads().clamp(1, 8)
    } else {
        1
    };
    let c1t = split_rows(q, w.as_mut(), parts, &|q, w| {
        let mut ct = Mat::zeros(b, j);
        sweep_project(q, w.as_ref(), ct.as_mut());
        ct
    });
    // The updates take C column-major (j × b): with the transposed view of Cᵀ instead, the
    // whole k = 100 body solve used ~7 % more CPU.
    let c1 = c1t.transpose().to_owned();
    let c2t = split_rows(q, w.as_mut(), parts, &|q, w| {
        let mut ct = Mat::zeros(b, j);
        sweep_update_project(q, w, c1.as_ref(), ct.as_mut());
        ct
    });
    // The second correction is `Q C₂`; it changes W by ‖C₂‖ (Q orthonormal). When that is
    // below SECOND_PASS_TOL relative to every column, applying it would only move W at the
    // rounding level, so the third sweep is skipped (the test is exact, not a heuristic bound).
    let second = (0..b).any(|c| {
        let wn = w.as_ref().col(c).norm_l2();
        c2t.as_ref().row(c).norm_l2() > SECOND_PASS_TOL * wn
    });
    if second {
        let c2 = c2t.transpose().to_owned();
        split_rows(q, w.as_mut(), parts, &|q, w| {
            sweep_update(q, w, c2.as_ref());
            Mat::zeros(0, 0)
        });
    }
    let mut c = Mat::zeros(j, b);
    for jj in 0..j {
        for cc in 0..b {
            c[(jj, cc)] = c1t[(cc, jj)] + if second { c2t[(cc, jj)] } else { 0.0 };
        }
    }
    c
}
/// `out = Q S` for a tall `Q` (n × s) and small `S` (s × c): the thick-restart and Ritz-vector
/// products. Rows are split into one part per rayon thread with sequential gemm in each (coarse
/// tasks: no per-panel synchronisation, which degrades badly when the other core is busy).
pub(super) fn tall_times_small(out: MatMut<'_, f64>, q: MatRef<'_, f64>, s: MatRef<'_, f64>) {
    fn go(out: MatMut<'_, f64>, q: MatRef<'_, f64>, s: MatRef<'_, f64>, parts: usize) {
        if parts <= 1 {
            matmul(out, Accum::Replace, q, s, 1.0, Par::Seq);
            return;
        }
        let left = parts / 2;
        let mid = q.nrows() * left / parts;
        let (q0, q1) = q.split_at_row(mid);
        let (o0, o1) = out.split_at_row_mut(mid);
        rayon::join(|| go(o0, q0, s, left), || go(o1, q1, s, parts - left));
    }
    let parts = if q.nrows() >= PARALLEL_MIN_ROWS {
        rayon::current_num_threads().clamp(1, 8)
    } else {
        1
    };
    go(out, q, s, parts);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against a straightforward two-pass projection with an orthonormal basis.
    #[test]
    fn cgs2_matches_plain_projection() {
        for &(n, j, b) in &[(5000usize, 37usize, 3usize), (700, 20, 8), (9000, 1, 1)] {
            let a = Mat::<f64>::from_fn(n, j, |i, k| ((i * 31 + k * 17) % 101) as f64 - 50.0);
            let qr = a.qr();
            let q = qr.compute_thin_Q();
            let w0 = Mat::<f64>::from_fn(n, b, |i, k| ((i * 7 + k * 3) % 13) as f64 - 6.0);
            let mut w = w0.clone();
            let c = cgs2(q.as_ref(), w.as_mut());
            // Orthogonal to Q.
            let qtw = q.transpose() * &w;
            assert!(qtw.norm_max() < 1e-12 * w0.norm_max() * (n as f64).sqrt());
            // w0 = Q C + w.
            let back = &q * &c + &w;
            assert!((&back - &w0).norm_max() < 1e-10 * w0.norm_max());
            // Same result as the plain projection.
            let plain = &w0 - &q * (q.transpose() * &w0);
            assert!((&plain - &w).norm_max() < 1e-10 * w0.norm_max());
        }
    }
}
