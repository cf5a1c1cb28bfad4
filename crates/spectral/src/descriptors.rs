//! Spectral point descriptors: HKS (Sun, Ovsjanikov, Guibas 2009) and scale-invariant HKS
//! (Bronstein & Kokkinos 2010).

use crate::{Eigenpairs, SpectralError};
use faer::linalg::matmul::matmul;
use faer::{get_global_parallelism, Accum, Mat};

/// φ_i(x)² for every vertex and pair, `n × k`.
fn squared_vectors(e: &Eigenpairs) -> Mat<f64> {
    Mat::from_fn(e.num_vertices(), e.len(), |i, j| e.vectors[(i, j)].powi(2))
}

/// `out = Φ² · weights` (`n × T`), `weights` is `k × T`.
fn weighted_sum(e: &Eigenpairs, weights: &Mat<f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(e.num_vertices(), weights.ncols());
    matmul(
        out.as_mut(),
        Accum::Replace,
        squared_vectors(e).as_ref(),
        weights.as_ref(),
        1.0,
        get_global_parallelism(),
    );
    out
}

/// Heat kernel signature `k_t(x,x) = Σ_i e^{−λ_i t} φ_i(x)²` over all pairs in `e` (including
/// the constant ones), `n × times.len()`; column j is time `times[j]` (units: length²).
///
/// ```
/// # use symcorr_mesh::TriMesh;
/// # use symcorr_spectral::*;
/// # let mesh = TriMesh::new(
/// #     vec![[1.,0.,0.],[-1.,0.,0.],[0.,1.,0.],[0.,-1.,0.],[0.,0.,1.],[0.,0.,-1.]],
/// #     vec![[0,2,4],[2,1,4],[1,3,4],[3,0,4],[2,0,5],[1,2,5],[3,1,5],[0,3,5]],
/// # ).unwrap();
/// let e = eigenpairs(&Laplacian::new(&mesh).unwrap(), 6, &EigenOptions::default()).unwrap();
/// let h = hks(&e, &hks_times(&e, 5));
/// assert_eq!((h.nrows(), h.ncols()), (6, 5));
/// ```
pub fn hks(e: &Eigenpairs, times: &[f64]) -> Mat<f64> {
    let w = Mat::from_fn(e.len(), times.len(), |i, j| (-e.values[i] * times[j]).exp());
    weighted_sum(e, &w)
}

/// `count` times log-spaced between `4 ln 10 / λ_max` and `4 ln 10 / λ_1` (Sun et al. 2009's
/// range, λ_1 the first non-zero eigenvalue). Needs at least one non-zero eigenvalue; otherwise
/// returns `count` copies of 1.
pub fn hks_times(e: &Eigenpairs, count: usize) -> Vec<f64> {
    let nz: Vec<f64> = e.values.iter().copied().filter(|&v| v > 0.0).collect();
    let (Some(&lo), Some(&hi)) = (nz.first(), nz.last()) else {
        return vec![1.0; count];
    };
    let (t_min, t_max) = (4.0 * 10f64.ln() / hi, 4.0 * 10f64.ln() / lo);
    if count == 1 {
        return vec![t_min];
    }
    (0..count)
        .map(|j| (t_min.ln() + (t_max.ln() - t_min.ln()) * j as f64 / (count - 1) as f64).exp())
        .collect()
}

/// Parameters of [`si_hks`]. Defaults are Bronstein & Kokkinos 2010 (§5): `α = 2`,
/// `τ = 1, 1+1/16, …, 25`, the 6 lowest frequencies.
#[derive(Debug, Clone)]
pub struct SiHksParams {
    /// Base of the logarithmic time sampling `t = α^τ`.
    pub alpha: f64,
    /// First τ.
    pub tau_start: f64,
    /// Last τ (inclusive).
    pub tau_end: f64,
    /// Increment of τ.
    pub tau_step: f64,
    /// Number of low frequencies kept (including the 0th).
    pub frequencies: usize,
}

impl Default for SiHksParams {
    fn default() -> Self {
        SiHksParams {
            alpha: 2.0,
            tau_start: 1.0,
            tau_end: 25.0,
            tau_step: 1.0 / 16.0,
            frequencies: 6,
        }
    }
}

impl SiHksParams {
    /// The window symcorr's pipeline uses, with times **relative to the mesh's area** (apply
    /// with [`SiHksParams::relative_to_area`]): Bronstein & Kokkinos's `α = 2`, step 1/16 and 6
    /// frequencies, over `t/area ∈ [2^-8, 2^3]` (`τ ∈ [−8, 3]`).
    ///
    /// Why relative: the paper's absolute window (`τ ∈ [1, 25]`, `t ≥ 2`) suits meshes
    /// normalised to a small scale; on a body in metres it lies where every non-constant
    /// eigenfunction has decayed (`e^{-λt}` with `λ·area ≈ 4πk`), leaving no detail (mean error
    /// ≈ 0.10 on the generated bodies). `[−8, 3]` was the best of six relative windows swept
    /// (measured: `docs/decisions/2026-11-23-paper-pipeline-defaults.md`).
    ///
    /// ```
    /// use symcorr_spectral::SiHksParams;
    /// let rel = SiHksParams::area_relative();
    /// let abs = rel.relative_to_area(4.0); // t = 4·2^τ: τ shifted by log2(4) = 2
    /// assert_eq!((abs.tau_start, abs.tau_end), (-6.0, 5.0));
    /// ```
    pub fn area_relative() -> SiHksParams {
        SiHksParams {
            tau_start: -8.0,
            tau_end: 3.0,
            ..SiHksParams::default()
        }
    }

    /// These parameters read as relative to a mesh of total area `area` (times
    /// `t = area·α^τ`), turned into the absolute ones [`si_hks`] takes:
    /// `τ' = τ + log_α(area)` for the start and end of the window, everything else unchanged.
    /// Scaling a mesh by `s` multiplies its area and every diffusion time by `s²`, so the
    /// samples land on the same relative times.
    pub fn relative_to_area(&self, area: f64) -> SiHksParams {
        let shift = area.ln() / self.alpha.ln();
        SiHksParams {
            tau_start: self.tau_start + shift,
            tau_end: self.tau_end + shift,
            ..self.clone()
        }
    }
}

/// Scale-invariant HKS (Bronstein & Kokkinos 2010), `n × frequencies`.
///
/// For each vertex: sample `h(τ) = log k_{α^τ}(x,x)` (HKS over all pairs of `e`), take the
/// discrete derivative `h(τ_{j+1}) − h(τ_j)` (a global scaling of the shape by s multiplies t
/// by s², a shift of τ and an additive constant in log k; the derivative removes the constant),
/// then the magnitude of its discrete Fourier transform (removes the shift) and keep the lowest
/// frequencies. Times are in the mesh's length units²; the window must cover the diffusion
/// scales of the shape (for a body in decimetres or metres the default does).
///
/// Errors: invalid parameters (non-positive step, `α ≤ 1`, fewer than 2 samples, more
/// frequencies than the DFT has).
pub fn si_hks(e: &Eigenpairs, params: &SiHksParams) -> Result<Mat<f64>, SpectralError> {
    let p = params;
    let bad = |m: &str| Err(SpectralError::InvalidArgument(format!("si-HKS: {m}")));
    if p.tau_step.is_nan()
        || p.tau_step <= 0.0
        || p.alpha.is_nan()
        || p.alpha <= 1.0
        || p.tau_end.is_nan()
        || p.tau_end <= p.tau_start
    {
        return bad("need tau_step > 0, alpha > 1 and tau_end > tau_start");
    }
    let samples_f = ((p.tau_end - p.tau_start) / p.tau_step + 1e-9).floor() + 1.0;
    // The heat kernel is sampled into an n × samples matrix: refuse a window too long for
    // memory before the count is converted (a saturating cast plus one would overflow).
    let cols = if samples_f >= usize::MAX as f64 {
        usize::MAX
    } else {
        samples_f as usize
    };
    crate::check_dense("si-HKS heat kernel samples", e.num_vertices(), cols)?;
    let samples = cols;
    let len = samples - 1; // length of the derivative sequence
    if len < 1 || p.frequencies == 0 || p.frequencies > len / 2 + 1 {
        return bad("frequencies must be in 1..=samples/2");
    }
    crate::check_dense("si-HKS DFT basis", p.frequencies, len)?;
    let times: Vec<f64> = (0..samples)
        .map(|j| p.alpha.powf(p.tau_start + p.tau_step * j as f64))
        .collect();
    let h = hks(e, &times);
    let n = e.num_vertices();
    // DFT basis for the kept frequencies.
    let (cos, sin): (Vec<f64>, Vec<f64>) = (0..p.frequencies * len)
        .map(|idx| {
            let (f, j) = (idx / len, idx % len);
            let a = -2.0 * std::f64::consts::PI * (f * j) as f64 / len as f64;
            (a.cos(), a.sin())
        })
        .unzip();
    let mut out = Mat::<f64>::zeros(n, p.frequencies);
    let mut d = vec![0.0; len];
    for x in 0..n {
        for (j, dj) in d.iter_mut().enumerate() {
            // Invariant: HKS over a set including the constant pair is > 0, so log is finite.
            *dj = h[(x, j + 1)].ln() - h[(x, j)].ln();
        }
        for f in 0..p.frequencies {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, dj) in d.iter().enumerate() {
                re += dj * cos[f * len + j];
                im += dj * sin[f * len + j];
            }
            out[(x, f)] = (re * re + im * im).sqrt();
        }
    }
    Ok(out)
}
