//! Candidates (paper §3.1): for a template point `p`, the target vertices whose point
//! descriptor (si-HKS) is closest to `p`'s.
//!
//! Distances are Euclidean in descriptor space. All pairwise squared distances of a block of
//! template points are computed at once as `‖a‖² + ‖b‖² − 2·a·b` with one dense matrix product
//! (faer), then each row is reduced to its candidates with a partial selection; blocks run in
//! parallel (rayon). A 13.4k × 13.4k dense pass is one 13.4k × d × 13.4k product.

use crate::{same_len, CorrespondError};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use rayon::prelude::*;

/// Per-vertex descriptors: `n` rows of `dim` values, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Descriptors {
    n: usize,
    dim: usize,
    data: Vec<f64>,
}

impl Descriptors {
    /// Descriptors from a row-major buffer of `n·dim` values.
    ///
    /// Errors: [`CorrespondError::InvalidOptions`] if `dim == 0`,
    /// [`CorrespondError::LengthMismatch`] if `data.len() != n·dim`,
    /// [`CorrespondError::NotFinite`] if a value is not finite.
    pub fn new(n: usize, dim: usize, data: Vec<f64>) -> Result<Descriptors, CorrespondError> {
        if dim == 0 {
            return Err(CorrespondError::InvalidOptions(format!(
                "descriptors of length 0 for {n} vertices"
            )));
        }
        same_len(
            &format!("descriptor buffer ({n} vertices × {dim} values)"),
            n * dim,
            data.len(),
        )?;
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(CorrespondError::NotFinite {
                what: "descriptor",
                row: i / dim,
            });
        }
        Ok(Descriptors { n, dim, data })
    }

    /// Descriptors from the rows of an `n × dim` matrix (e.g. what symcorr-spectral returns).
    pub fn from_mat(m: faer::MatRef<'_, f64>) -> Result<Descriptors, CorrespondError> {
        let (n, dim) = (m.nrows(), m.ncols());
        let mut data = Vec::with_capacity(n * dim);
        for i in 0..n {
            for j in 0..dim {
                data.push(m[(i, j)]);
            }
        }
        Descriptors::new(n, dim, data)
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True without vertices.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Descriptor length.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The descriptor of vertex `v`.
    pub fn row(&self, v: usize) -> &[f64] {
        &self.data[v * self.dim..(v + 1) * self.dim]
    }

    /// Euclidean distance between row `a` of `self` and row `b` of `other`.
    pub fn distance(&self, a: usize, other: &Descriptors, b: usize) -> f64 {
        self.row(a)
            .iter()
            .zip(other.row(b))
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    }
}

/// Which target vertices become candidates (paper §3.1: "among the N nearest" or "below a
/// threshold"; with both, the N nearest of those below the threshold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CandidateOptions {
    /// Keep at most this many nearest target vertices. `None`: no count limit (then a
    /// threshold is required).
    pub nearest: Option<usize>,
    /// Keep only target vertices with descriptor distance `≤ threshold · d₁(p)`, where `d₁(p)`
    /// is the distance to `p`'s nearest target descriptor (relative, so that the rule does not
    /// depend on the descriptor's scale). `None`: no threshold. The nearest vertex always
    /// survives, so every point has at least one candidate.
    pub threshold: Option<f64>,
}

impl Default for CandidateOptions {
    /// `nearest: Some(DEFAULT_NEAREST)`, no threshold (chosen by measurement:
    /// `docs/decisions/2026-11-23-paper-pipeline-defaults.md`).
    fn default() -> Self {
        CandidateOptions {
            nearest: Some(crate::DEFAULT_NEAREST),
            threshold: None,
        }
    }
}

/// A candidate target vertex and its descriptor distance to the template point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Target vertex.
    pub vertex: u32,
    /// Euclidean descriptor distance.
    pub distance: f64,
}

/// Template points per block of the distance matrix (block × target_n doubles of scratch).
const BLOCK: usize = 256;

/// The candidates of every template point in `points`, each list sorted by distance
/// (nearest first) — paper §3.1.
///
/// ```
/// use symcorr_correspond::{candidates, CandidateOptions, Descriptors};
/// let t = Descriptors::new(2, 1, vec![0.0, 1.0]).unwrap();
/// let u = Descriptors::new(3, 1, vec![0.9, 0.1, 5.0]).unwrap();
/// let c = candidates(&t, &u, &[0, 1], &CandidateOptions { nearest: Some(2), threshold: None }).unwrap();
/// assert_eq!(c[0][0].vertex, 1);
/// assert_eq!(c[1][0].vertex, 0);
/// assert_eq!(c[0].len(), 2);
/// ```
///
/// Errors: [`CorrespondError::LengthMismatch`] for descriptors of different lengths,
/// [`CorrespondError::EmptyMesh`] for an empty target, [`CorrespondError::IndexOutOfRange`]
/// for a point out of range, [`CorrespondError::InvalidOptions`] for options that select
/// nothing (`nearest = Some(0)`, or neither rule given) or a threshold below 1.
pub fn candidates(
    template: &Descriptors,
    target: &Descriptors,
    points: &[u32],
    options: &CandidateOptions,
) -> Result<Vec<Vec<Candidate>>, CorrespondError> {
    same_len(
        "target descriptor length (as the template's)",
        template.dim,
        target.dim,
    )?;
    if target.n == 0 {
        return Err(CorrespondError::EmptyMesh { side: "target" });
    }
    if let Some(&p) = points.iter().find(|&&p| p as usize >= template.n) {
        return Err(CorrespondError::IndexOutOfRange {
            what: "template point",
            index: p as usize,
            len: template.n,
        });
    }
    match (options.nearest, options.threshold) {
        (Some(0), _) | (None, None) => {
            return Err(CorrespondError::InvalidOptions(
                "candidate options select nothing: give nearest ≥ 1 and/or a threshold".into(),
            ))
        }
        (_, Some(t)) if !(t.is_finite() && t >= 1.0) => {
            return Err(CorrespondError::InvalidOptions(format!(
                "candidate threshold {t} must be a finite factor ≥ 1"
            )))
        }
        _ => {}
    }
    let dim = target.dim;
    let m = target.n;
    // Target as a dim × m matrix and its squared norms, shared by all blocks.
    let tgt = Mat::from_fn(dim, m, |j, i| target.data[i * dim + j]);
    let tgt_sq: Vec<f64> = (0..m)
        .map(|i| target.row(i).iter().map(|x| x * x).sum())
        .collect();
    let blocks: Vec<&[u32]> = points.chunks(BLOCK).collect();
    let out: Vec<Vec<Vec<Candidate>>> = blocks
        .par_iter()
        .map(|block| {
            let b = block.len();
            let tpl = Mat::from_fn(b, dim, |r, j| template.data[block[r] as usize * dim + j]);
            let mut prod = Mat::<f64>::zeros(b, m);
            matmul(
                prod.as_mut(),
                Accum::Replace,
                tpl.as_ref(),
                tgt.as_ref(),
                1.0,
                Par::Seq,
            );
            let mut row = vec![0.0; m];
            (0..b)
                .map(|r| {
                    let a_sq: f64 = template.row(block[r] as usize).iter().map(|x| x * x).sum();
                    for (i, d) in row.iter_mut().enumerate() {
                        // Clamp: rounding can make the expansion slightly negative.
                        *d = (a_sq + tgt_sq[i] - 2.0 * prod[(r, i)]).max(0.0);
                    }
                    select_row(&row, options)
                })
                .collect()
        })
        .collect();
    Ok(out.into_iter().flatten().collect())
}

/// Reduces one row of squared distances to the sorted candidate list.
fn select_row(sq: &[f64], options: &CandidateOptions) -> Vec<Candidate> {
    let mut idx: Vec<u32> = (0..sq.len() as u32).collect();
    let by = |a: &u32, b: &u32| sq[*a as usize].total_cmp(&sq[*b as usize]);
    if let Some(k) = options.nearest {
        let k = k.min(idx.len());
        if k < idx.len() {
            idx.select_nth_unstable_by(k - 1, by);
            idx.truncate(k);
        }
    }
    if let Some(t) = options.threshold {
        let best = idx
            .iter()
            .map(|&i| sq[i as usize])
            .fold(f64::INFINITY, f64::min);
        let limit = best * t * t;
        idx.retain(|&i| sq[i as usize] <= limit);
    }
    idx.sort_unstable_by(by);
    idx.into_iter()
        .map(|i| Candidate {
            vertex: i,
            distance: sq[i as usize].sqrt(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(t: &Descriptors, u: &Descriptors, p: usize, k: usize) -> Vec<u32> {
        let mut v: Vec<(f64, u32)> = (0..u.len())
            .map(|q| (t.distance(p, u, q), q as u32))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v.into_iter().take(k).map(|x| x.1).collect()
    }

    fn pseudo(n: usize, dim: usize, seed: u64) -> Descriptors {
        let mut s = seed;
        let data = (0..n * dim)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect();
        Descriptors::new(n, dim, data).unwrap()
    }

    #[test]
    fn nearest_matches_brute_force_across_blocks() {
        let t = pseudo(600, 7, 1);
        let u = pseudo(900, 7, 2);
        let pts: Vec<u32> = (0..600).step_by(3).collect();
        let c = candidates(
            &t,
            &u,
            &pts,
            &CandidateOptions {
                nearest: Some(5),
                threshold: None,
            },
        )
        .unwrap();
        for (i, &p) in pts.iter().enumerate() {
            let got: Vec<u32> = c[i].iter().map(|c| c.vertex).collect();
            assert_eq!(got, brute(&t, &u, p as usize, 5), "point {p}");
            for w in c[i].windows(2) {
                assert!(w[0].distance <= w[1].distance);
            }
            assert!(
                (c[i][0].distance - t.distance(p as usize, &u, c[i][0].vertex as usize)).abs()
                    < 1e-9
            );
        }
    }

    #[test]
    fn threshold_is_relative_to_the_nearest() {
        let t = Descriptors::new(1, 1, vec![0.0]).unwrap();
        let u = Descriptors::new(4, 1, vec![1.0, 1.4, 1.6, -1.2]).unwrap();
        let c = candidates(
            &t,
            &u,
            &[0],
            &CandidateOptions {
                nearest: None,
                threshold: Some(1.5),
            },
        )
        .unwrap();
        let got: Vec<u32> = c[0].iter().map(|c| c.vertex).collect();
        assert_eq!(got, vec![0, 3, 1]);
        let c = candidates(
            &t,
            &u,
            &[0],
            &CandidateOptions {
                nearest: Some(2),
                threshold: Some(1.5),
            },
        )
        .unwrap();
        assert_eq!(c[0].len(), 2);
    }

    #[test]
    fn bad_arguments_are_errors() {
        let t = Descriptors::new(1, 2, vec![0.0, 0.0]).unwrap();
        let u = Descriptors::new(1, 1, vec![0.0]).unwrap();
        assert!(candidates(&t, &u, &[0], &CandidateOptions::default()).is_err());
        assert!(candidates(&t, &t, &[1], &CandidateOptions::default()).is_err());
        assert!(candidates(
            &t,
            &t,
            &[0],
            &CandidateOptions {
                nearest: None,
                threshold: None
            }
        )
        .is_err());
        assert!(Descriptors::new(2, 2, vec![0.0; 3]).is_err());
        assert!(Descriptors::new(1, 1, vec![f64::NAN]).is_err());
    }
}
