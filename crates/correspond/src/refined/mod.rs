//! The refined dense method (DESIGN.md, Algorithm 7): nearest neighbours restricted to the
//! template point's body segment ([`SegmentPools`]), an initial dense map from skeleton
//! landmark coordinates and si-HKS ([`nearest_in_pools`]), and ZoomOut refinement (Melzi et
//! al. 2019) whose every point-map recovery is restricted the same way ([`zoomout`]).
//!
//! The refined method ([`refine_dense`]) matches every template vertex in three steps:
//!
//! 1. **Skeleton landmark coordinates.** Per mesh, one landmark source set per joint
//!    ([`skeleton_landmarks`], module `landmarks`): the *ring* where the plane through
//!    the joint, normal to its bone, cuts the surface of the segments meeting there, and the
//!    surface *tip* beyond each end joint; plus the vertex nearest each refined joint
//!    ([`joint_landmarks`]) — 40 columns. Every vertex's heat-method
//!    geodesic distance to each of them over √area
//!    ([`landmark_coordinates`]) gives coordinates that
//!    correspond by joint name, survive isometries and tell left from right.
//! 2. **Initial map** ([`nearest_in_pools`]): nearest neighbour in landmark ⊕ si-HKS space
//!    (si-HKS columns scaled to unit standard deviation over both meshes, weight
//!    [`RefineOptions::descriptor_weight`]) within the point's pool: the target region of its
//!    segment grown by a geodesic band ([`RefineOptions::band`], so label boundaries that moved
//!    between meshes do not cut good matches off), never on the other side of the body; midline
//!    segments are split by sagittal halves refined by the surface's own symmetry
//!    ([`refine_symmetry_plane`], module `symmetry`), because a noisy shoulder line
//!    or a turned head tilts the joint plane by many degrees.
//! 3. **Segment-constrained ZoomOut** ([`zoomout`]): functional map `C = Φ_kᵀ M Π Ψ_k` from the
//!    current map, then the point map recovered by nearest neighbour of rows of `Φ_k C` among
//!    rows of `Ψ_k` within the same pools; `k` 20 → 60 by 8; every iteration but the last on an
//!    even stride sample of at most [`DEFAULT_ZOOMOUT_POINTS`] template vertices (masses
//!    rescaled to the total area; module `zoomout`).
//!
//! Measured: `docs/decisions/2026-11-23-refined-method.md`.

mod landmarks;
mod symmetry;
mod zoomout;

pub use landmarks::{joint_landmarks, landmark_coordinates, skeleton_landmarks};
pub use symmetry::refine_symmetry_plane;
pub use zoomout::{
    coverage, zoomout, SpectralBasis, ZoomOutOptions, ZoomOutResult, DEFAULT_ZOOMOUT_POINTS,
};

use crate::pools::{nearest_in_pools, SegmentPools};
use crate::{same_len, CorrespondError};
use faer::{Mat, MatRef};
use symcorr_skeleton::{BodySide, Segment};
use symcorr_spectral::EdgeGraph;

/// Everything [`refine_dense`] needs about one mesh.
#[derive(Debug, Clone, Copy)]
pub struct RefinedInputs<'a> {
    /// Laplace–Beltrami basis (eigenvectors and lumped mass).
    pub basis: SpectralBasis<'a>,
    /// Landmark coordinates (`n × L`, same landmarks in the same order on both meshes), e.g.
    /// from [`landmark_coordinates`].
    pub landmarks: MatRef<'a, f64>,
    /// Point descriptors (si-HKS), `n × d`.
    pub descriptors: &'a crate::Descriptors,
    /// Segment label per vertex.
    pub labels: &'a [Segment],
    /// Sagittal half per vertex of the midline segments (see [`SegmentPools`]).
    pub halves: Option<&'a [BodySide]>,
    /// The mesh's edge graph (used on the target side for the boundary band).
    pub graph: &'a EdgeGraph,
    /// Total surface area.
    pub area: f64,
}

/// Options of [`refine_dense`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Weight of the si-HKS columns (each scaled to unit standard deviation over both meshes)
    /// next to the landmark coordinates in the initial map's feature space.
    pub descriptor_weight: f64,
    /// Geodesic band around a segment's target region that its pool also covers, in √area.
    pub band: f64,
    /// ZoomOut schedule.
    pub zoomout: ZoomOutOptions,
}

impl Default for RefineOptions {
    /// Weight 1, band 0.02, ZoomOut 20 → 60 by 8 (measured on the generated bodies:
    /// `docs/decisions/2026-11-23-refined-method.md`).
    fn default() -> Self {
        RefineOptions {
            descriptor_weight: 1.0,
            band: 0.02,
            zoomout: ZoomOutOptions::default(),
        }
    }
}

/// The result of [`refine_dense`].
#[derive(Debug, Clone)]
pub struct RefinedMatches {
    /// One pair per template vertex, in vertex order.
    pub pairs: Vec<crate::Pair>,
    /// Per template vertex, the final spectral residual `r` ([`ZoomOutResult::residual`],
    /// square-rooted) behind its confidence.
    pub residual: Vec<f64>,
    /// The initial (landmark + descriptor) map, target vertex per template vertex.
    pub initial: Vec<u32>,
    /// Fraction of target vertices hit by the final map ([`coverage`]).
    pub coverage: f64,
    /// Seconds per stage: `segment_pools`, `initial_map`, `zoomout`.
    pub timings: Vec<(&'static str, f64)>,
}

/// The refined dense method (DESIGN.md, Algorithm 7): segment pools, an initial map by nearest
/// neighbour in landmark-coordinate + si-HKS space within each pool, then segment-constrained
/// ZoomOut. Every template vertex gets a match; its confidence is `1 / (1 + r/r̃)` with `r`
/// the final spectral residual ([`ZoomOutResult::residual`], square-rooted) and `r̃` its
/// median, with `r` kept in [`RefinedMatches::residual`].
///
/// Errors: [`CorrespondError::LengthMismatch`] when a side's basis, landmark or descriptor
/// rows disagree with its labels, or the sides have different landmark or descriptor counts.
pub fn refine_dense(
    template: &RefinedInputs<'_>,
    target: &RefinedInputs<'_>,
    options: &RefineOptions,
) -> Result<RefinedMatches, CorrespondError> {
    use std::time::Instant;
    let (n, m) = (template.labels.len(), target.labels.len());
    for (name, s, len) in [("template", template, n), ("target", target, m)] {
        let rows = [
            ("basis rows", s.basis.vectors.nrows()),
            ("landmark rows", s.landmarks.nrows()),
            ("descriptors", s.descriptors.len()),
        ];
        for (table, found) in rows {
            same_len(&format!("{name} {table} (one per label)"), len, found)?;
        }
    }
    same_len(
        "target landmark columns (as many as the template's)",
        template.landmarks.ncols(),
        target.landmarks.ncols(),
    )?;
    same_len(
        "target descriptor length (as the template's)",
        template.descriptors.dim(),
        target.descriptors.dim(),
    )?;
    let mut timings = Vec::new();
    let t = Instant::now();
    let pools = SegmentPools::new(
        (template.labels, template.halves),
        (target.labels, target.halves),
        target.graph,
        options.band * target.area.sqrt(),
    )?;
    timings.push(("segment_pools", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    // si-HKS columns to unit standard deviation over both meshes.
    let h = template.descriptors.dim();
    let scale: Vec<f64> = (0..h)
        .map(|j| {
            let vals = (0..n)
                .map(|i| template.descriptors.row(i)[j])
                .chain((0..m).map(|i| target.descriptors.row(i)[j]));
            let (mut s1, mut s2, mut c) = (0.0, 0.0, 0.0);
            for v in vals {
                s1 += v;
                s2 += v * v;
                c += 1.0;
            }
            let var = (s2 / c - (s1 / c).powi(2)).max(0.0);
            if var > 0.0 {
                var.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let features = |s: &RefinedInputs<'_>, rows: usize| {
        let l = s.landmarks.ncols();
        Mat::from_fn(rows, l + h, |i, j| {
            if j < l {
                s.landmarks[(i, j)]
            } else {
                options.descriptor_weight * s.descriptors.row(i)[j - l] / scale[j - l]
            }
        })
    };
    let (fa, fb) = (features(template, n), features(target, m));
    let initial: Vec<u32> = nearest_in_pools(fa.as_ref(), fb.as_ref(), &pools)?
        .into_iter()
        .map(|x| x.0)
        .collect();
    timings.push(("initial_map", t.elapsed().as_secs_f64()));
    let t = Instant::now();
    let z = zoomout(
        template.basis,
        target.basis,
        &initial,
        &pools,
        Some((fa.as_ref(), fb.as_ref())),
        &options.zoomout,
    )?;
    timings.push(("zoomout", t.elapsed().as_secs_f64()));
    let r: Vec<f64> = z.residual.iter().map(|x| x.sqrt()).collect();
    let median = {
        let mut v = r.clone();
        let k = v.len() / 2;
        if v.is_empty() {
            1.0
        } else {
            v.select_nth_unstable_by(k, f64::total_cmp);
            v[k].max(f64::MIN_POSITIVE)
        }
    };
    let pairs = z
        .map
        .iter()
        .zip(&r)
        .enumerate()
        .map(|(p, (&q, &r))| crate::Pair {
            template: p as u32,
            target: q,
            confidence: 1.0 / (1.0 + r / median),
        })
        .collect();
    Ok(RefinedMatches {
        pairs,
        residual: r,
        coverage: coverage(&z.map, m),
        initial,
        timings,
    })
}
