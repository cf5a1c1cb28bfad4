//! ZoomOut (Melzi et al. 2019) whose every point-map recovery is restricted to the template
//! point's [`SegmentPools`]: the refined method's last step.

use crate::pools::{nearest_in_pools_for, SegmentPools};
use crate::{same_len, CorrespondError};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// A Laplace–Beltrami basis: M-orthonormal eigenvectors (columns, ascending eigenvalue) and the
/// lumped mass per vertex.
#[derive(Debug, Clone, Copy)]
pub struct SpectralBasis<'a> {
    /// `n × k` eigenvectors, `ΦᵀMΦ = I`.
    pub vectors: MatRef<'a, f64>,
    /// Lumped (diagonal) mass per vertex.
    pub mass: &'a [f64],
}

/// Default [`ZoomOutOptions::max_points`]: 16,000 (a 13.4k body runs every iteration in full).
pub const DEFAULT_ZOOMOUT_POINTS: usize = 16_000;

/// Options of [`zoomout`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoomOutOptions {
    /// Weight of the anchor features (e.g. landmark coordinates) appended to the spectral
    /// embedding in every point-map recovery; the embedding is scaled to unit mean squared row
    /// norm first, so the weight is relative. 0 = plain ZoomOut.
    pub anchor_weight: f64,
    /// Basis size of the first functional map.
    pub k_start: usize,
    /// Basis size of the last (capped by the bases' sizes).
    pub k_end: usize,
    /// Increase of `k` per iteration.
    pub step: usize,
    /// Template vertices used by every iteration but the last (an even stride sample when the
    /// template has more); the last iteration maps every vertex. Bounds the cost on large
    /// meshes (the nearest-neighbour search is quadratic in a segment's size).
    pub max_points: usize,
}

impl Default for ZoomOutOptions {
    /// 20 → 60 in steps of 8 (measured: `docs/decisions/2026-11-23-refined-method.md`).
    fn default() -> Self {
        ZoomOutOptions {
            k_start: 20,
            k_end: 60,
            step: 8,
            anchor_weight: 0.0,
            max_points: DEFAULT_ZOOMOUT_POINTS,
        }
    }
}

/// The result of [`zoomout`].
#[derive(Debug, Clone)]
pub struct ZoomOutResult {
    /// Target vertex per template vertex.
    pub map: Vec<u32>,
    /// Squared spectral residual per template vertex at the last step (`‖(ΦC)_p − Ψ_{map(p)}‖²`):
    /// small when the functional map explains the point's match.
    pub residual: Vec<f64>,
    /// The last functional map (`k × k`, target coefficients → template coefficients).
    pub c: Mat<f64>,
    /// Basis sizes used, in order.
    pub ks: Vec<usize>,
}

/// ZoomOut (Melzi, Ren, Rodolà, Sharma, Wonka, Ovsjanikov 2019) with segment-constrained point
/// maps.
///
/// `map[p]` is the current target vertex of template vertex `p`. Each iteration with basis size
/// `k` estimates the functional map `C = Φ_kᵀ M Π Ψ_k` (`Φ` template basis, `Ψ` target basis,
/// `Π` the pull-back of the point map), then recovers the point map: `map(p)` = the target
/// vertex of `p`'s pool ([`SegmentPools`]) whose row of `Ψ_k` is nearest to row `p` of `Φ_k C`.
/// `k` grows from `k_start` to `k_end` by `step`.
///
/// Errors: [`CorrespondError::LengthMismatch`] for inconsistent sizes,
/// [`CorrespondError::InvalidOptions`] for `k_start == 0` or `step == 0`,
/// [`CorrespondError::IndexOutOfRange`] for a map entry beyond the target.
pub fn zoomout(
    template: SpectralBasis<'_>,
    target: SpectralBasis<'_>,
    map: &[u32],
    pools: &SegmentPools,
    anchors: Option<(MatRef<'_, f64>, MatRef<'_, f64>)>,
    options: &ZoomOutOptions,
) -> Result<ZoomOutResult, CorrespondError> {
    let (n, m) = (template.vectors.nrows(), target.vectors.nrows());
    if let Some((a, b)) = anchors {
        same_len(
            "zoomout: template anchor rows (one per basis row)",
            n,
            a.nrows(),
        )?;
        same_len(
            "zoomout: target anchor rows (one per basis row)",
            m,
            b.nrows(),
        )?;
        same_len(
            "zoomout: target anchor columns (as the template's)",
            a.ncols(),
            b.ncols(),
        )?;
    }
    same_len(
        "zoomout: template masses (one per basis row)",
        n,
        template.mass.len(),
    )?;
    same_len(
        "zoomout: target masses (one per basis row)",
        m,
        target.mass.len(),
    )?;
    same_len(
        "zoomout: map entries (one per template basis row)",
        n,
        map.len(),
    )?;
    if options.k_start == 0 || options.step == 0 {
        return Err(CorrespondError::InvalidOptions(format!(
            "zoomout: k_start ({}) and step ({}) must be positive",
            options.k_start, options.step
        )));
    }
    if let Some(&q) = map.iter().find(|&&q| q as usize >= m) {
        return Err(CorrespondError::IndexOutOfRange {
            what: "zoomout: map entry (target vertex)",
            index: q as usize,
            len: m,
        });
    }
    let kmax = options
        .k_end
        .min(template.vectors.ncols())
        .min(target.vectors.ncols());
    let mut ks = Vec::new();
    let mut k = options.k_start.min(kmax);
    loop {
        ks.push(k);
        if k >= kmax {
            break;
        }
        k = (k + options.step).min(kmax);
    }
    // Intermediate iterations on an even stride sample of at most `max_points` vertices, its
    // masses rescaled to the total (a quadrature of ∫ φ ψ∘T).
    let stride = n.div_ceil(options.max_points.max(1)).max(1);
    let in_sample = |p: usize| p.is_multiple_of(stride);
    let sample_members: Option<Vec<Vec<u32>>> =
        (stride > 1).then(|| pools.members_where(|p| in_sample(p as usize)));
    let mass_scale = if stride > 1 {
        let total: f64 = template.mass.iter().sum();
        let sampled: f64 = (0..n)
            .filter(|&p| in_sample(p))
            .map(|p| template.mass[p])
            .sum();
        if sampled > 0.0 {
            total / sampled
        } else {
            1.0
        }
    } else {
        1.0
    };
    // Φᵀ M (sampled rows only, rescaled, for the intermediate iterations), for the largest k.
    let phi_m_sampled = Mat::from_fn(n, kmax, |i, j| {
        if in_sample(i) {
            template.vectors[(i, j)] * template.mass[i] * mass_scale
        } else {
            0.0
        }
    });
    let phi_m_full = (stride > 1)
        .then(|| Mat::from_fn(n, kmax, |i, j| template.vectors[(i, j)] * template.mass[i]));
    let mut current = map.to_vec();
    let mut residual = vec![0.0; n];
    let mut c = Mat::<f64>::zeros(0, 0);
    let last = ks.len().saturating_sub(1);
    for (step, &k) in ks.iter().enumerate() {
        // All vertices in the last iteration; the sample before (when there is one).
        let subset = if step == last {
            None
        } else {
            sample_members.as_deref()
        };
        // The functional map uses the sample's rows in every iteration but the first after a
        // full one — i.e. the rows whose map entries were just updated.
        let phi_m = match (&phi_m_full, step) {
            (Some(full), 0) => full,
            _ => &phi_m_sampled,
        };
        // Π Ψ_k: the target basis pulled back through the current map.
        let pulled = Mat::from_fn(n, k, |i, j| target.vectors[(current[i] as usize, j)]);
        c = Mat::<f64>::zeros(k, k);
        matmul(
            c.as_mut(),
            Accum::Replace,
            phi_m.as_ref().subcols(0, k).transpose(),
            pulled.as_ref(),
            1.0,
            Par::rayon(0),
        );
        let mut q = Mat::<f64>::zeros(n, k);
        matmul(
            q.as_mut(),
            Accum::Replace,
            template.vectors.subcols(0, k),
            c.as_ref(),
            1.0,
            Par::rayon(0),
        );
        let nn = match anchors {
            Some((a, b)) if options.anchor_weight > 0.0 => {
                // Unit mean squared row norm for the embedding, then the weighted anchors.
                let ms: f64 = (0..m)
                    .map(|i| (0..k).map(|j| target.vectors[(i, j)].powi(2)).sum::<f64>())
                    .sum::<f64>()
                    / m.max(1) as f64;
                let s = 1.0 / ms.sqrt().max(f64::MIN_POSITIVE);
                let w = options.anchor_weight;
                let (ka, d) = (a.ncols(), k + a.ncols());
                let qa = Mat::from_fn(n, d, |i, j| {
                    if j < k {
                        s * q[(i, j)]
                    } else {
                        w * a[(i, j - k)]
                    }
                });
                let tb = Mat::from_fn(m, d, |i, j| {
                    if j < k {
                        s * target.vectors[(i, j)]
                    } else {
                        w * b[(i, j - k)]
                    }
                });
                debug_assert_eq!(ka + k, d);
                nearest_in_pools_for(qa.as_ref(), tb.as_ref(), pools, subset)?
            }
            _ => nearest_in_pools_for(q.as_ref(), target.vectors.subcols(0, k), pools, subset)?,
        };
        for (p, (t, r)) in nn.into_iter().enumerate() {
            if subset.is_none() || in_sample(p) {
                current[p] = t;
                residual[p] = r;
            }
        }
    }
    Ok(ZoomOutResult {
        map: current,
        residual,
        c,
        ks,
    })
}

/// Fraction of `num_target` target vertices hit by `map` (1 for a surjective map): how close a
/// dense map is to one-to-one between equally sampled meshes.
pub fn coverage(map: &[u32], num_target: usize) -> f64 {
    if num_target == 0 {
        return 0.0;
    }
    let mut hit = vec![false; num_target];
    for &q in map {
        if let Some(h) = hit.get_mut(q as usize) {
            *h = true;
        }
    }
    hit.iter().filter(|&&h| h).count() as f64 / num_target as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_skeleton::Segment::Torso;
    use symcorr_spectral::testmesh::deformed_sphere;
    use symcorr_spectral::{eigenpairs, EdgeGraph, EigenOptions, Laplacian};

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed >> 33
    }

    /// `perm[old] = new` applied to a mesh's vertex ids.
    fn permuted(mesh: &symcorr_mesh::TriMesh, perm: &[u32]) -> symcorr_mesh::TriMesh {
        let mut pos = vec![[0.0; 3]; perm.len()];
        for (o, &n) in perm.iter().enumerate() {
            let p = mesh.positions[o];
            // Rotate by 90° about z as well: the map must not depend on the embedding.
            pos[n as usize] = [-p[1], p[0], p[2]];
        }
        let tris = mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| perm[v as usize]))
            .collect();
        symcorr_mesh::TriMesh::new(pos, tris).unwrap()
    }

    #[test]
    fn zoomout_recovers_a_permutation_from_a_corrupted_map() {
        let a = deformed_sphere(8);
        let n = a.num_vertices();
        let mut seed = 3u64;
        let mut perm: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            perm.swap(i, lcg(&mut seed) as usize % (i + 1));
        }
        let b = permuted(&a, &perm);
        let (la, lb) = (Laplacian::new(&a).unwrap(), Laplacian::new(&b).unwrap());
        let ea = eigenpairs(&la, 40, &EigenOptions::default()).unwrap();
        let eb = eigenpairs(&lb, 40, &EigenOptions::default()).unwrap();
        // 30 % of the true map replaced by random target vertices.
        let init: Vec<u32> = (0..n)
            .map(|p| {
                if lcg(&mut seed) % 10 < 3 {
                    (lcg(&mut seed) % n as u64) as u32
                } else {
                    perm[p]
                }
            })
            .collect();
        let labels = vec![Torso; n];
        let pools =
            SegmentPools::new((&labels, None), (&labels, None), &EdgeGraph::new(&b), 0.0).unwrap();
        let z = zoomout(
            SpectralBasis {
                vectors: ea.vectors.as_ref(),
                mass: &la.mass,
            },
            SpectralBasis {
                vectors: eb.vectors.as_ref(),
                mass: &lb.mass,
            },
            &init,
            &pools,
            None,
            &ZoomOutOptions {
                k_start: 6,
                k_end: 40,
                step: 2,
                anchor_weight: 0.0,
                // Intermediate iterations on every 2nd vertex, the last on all.
                max_points: 400,
            },
        )
        .unwrap();
        let right = |m: &[u32]| (0..n).filter(|&p| m[p] == perm[p]).count() as f64 / n as f64;
        assert!(right(&init) < 0.75);
        assert!(right(&z.map) > 0.97, "recovered {}", right(&z.map));
        assert_eq!(z.ks.first(), Some(&6));
        assert_eq!(z.ks.last(), Some(&40));
        assert!(coverage(&z.map, n) > 0.95);
    }
}
