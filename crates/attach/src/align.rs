//! Frame alignment: bring the skeleton into the mesh's units and frame (DESIGN.md, Algorithm 1:
//! "express the skeleton in the mesh's frame").
//!
//! Scale by a power of ten when the skeleton's and the mesh's extents disagree (mm, cm, dm, m,
//! km; any other mismatch is refused, not guessed), then, only if the joints do not already sit
//! in the mesh, the best of the 24 axis rotations about the bounding-box centres. Refused when
//! nothing fits ([`FIT_LIMIT`], [`COVER_LIMIT`]).

use crate::geom::{bone_segments, distance_to_bones, Joints};
use crate::repair::{extent, skeleton_height};
use crate::{AttachError, FrameAlignment};
use nalgebra::{distance, Matrix3, Point3, Rotation3, Vector3};
use symcorr_mesh::TriMesh;

/// Largest accepted median joint-to-surface distance, in skeleton heights. Joints inside a
/// body sit at most a torso half-depth (~0.07 heights) from the surface; a joint set in
/// another frame is typically ≥ 0.2 away.
pub(crate) const FIT_LIMIT: f64 = 0.08;

/// Largest accepted median distance from a mesh vertex to the nearest bone, in skeleton
/// heights: the bones must run through the whole mesh (a limb is ~0.03 heights thick, the torso
/// ~0.1), not just have their joints somewhere inside it.
pub(crate) const COVER_LIMIT: f64 = 0.12;

/// Accepted mesh/skeleton extent ratio without a unit change. A full body's mesh box is a little
/// larger than its joints' box; a scan may include some background.
const RATIO_BAND: (f64, f64) = (0.5, 3.0);

/// Median distance from the usable joints to their nearest mesh vertex, over `height`.
pub(crate) fn fit(mesh: &TriMesh, p: &Joints, usable: &[bool; 20], height: f64) -> f64 {
    let mut d: Vec<f64> = (0..20)
        .filter(|&j| usable[j])
        .map(|j| {
            mesh.positions
                .iter()
                .map(|v| (Point3::from(*v) - p[j]).norm_squared())
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .collect();
    d.sort_by(f64::total_cmp);
    if d.is_empty() {
        return f64::INFINITY;
    }
    d[d.len() / 2] / height.max(f64::MIN_POSITIVE)
}

/// Median distance from (up to 1000 evenly spread) mesh vertices to the nearest bone, over
/// `height`.
pub(crate) fn coverage(mesh: &TriMesh, p: &Joints, usable: &[bool; 20], height: f64) -> f64 {
    let bones = bone_segments(p, usable);
    let stride = (mesh.num_vertices() / 1000).max(1);
    let mut d: Vec<f64> = mesh
        .positions
        .iter()
        .step_by(stride)
        .map(|&x| distance_to_bones(&Point3::from(x), &bones))
        .collect();
    d.sort_by(f64::total_cmp);
    if d.is_empty() {
        return f64::INFINITY;
    }
    d[d.len() / 2] / height.max(f64::MIN_POSITIVE)
}

/// The 24 proper rotations that permute the coordinate axes (with signs).
fn axis_rotations() -> Vec<Rotation3<f64>> {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut out = Vec::with_capacity(24);
    for p in perms {
        for signs in 0..8 {
            let mut r = Matrix3::zeros();
            for (row, &col) in p.iter().enumerate() {
                r[(row, col)] = if signs & (1 << row) != 0 { -1.0 } else { 1.0 };
            }
            // A signed permutation is orthogonal; only the reflections are left out.
            if r.determinant() > 0.0 {
                out.push(Rotation3::from_matrix_unchecked(r));
            }
        }
    }
    out
}

fn bbox_centre(points: impl Iterator<Item = Point3<f64>>) -> Vector3<f64> {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    (lo + hi) * 0.5
}

/// Aligns `p` (in place) to the mesh and returns what was applied.
pub(crate) fn align(
    mesh: &TriMesh,
    p: &mut Joints,
    usable: &[bool; 20],
) -> Result<FrameAlignment, AttachError> {
    let (lo, hi) = mesh.bounding_box();
    let mesh_extent = distance(&Point3::from(lo), &Point3::from(hi));
    let skel_extent = extent(p, usable);
    if !(skel_extent > 0.0) || !skel_extent.is_finite() {
        return Err(AttachError::EmptySkeleton {
            usable: usable.iter().filter(|&&u| u).count(),
            extent: skel_extent,
        });
    }
    // Units: the power of ten that brings the extent ratio closest to a typical 1.2.
    let ratio = mesh_extent / skel_extent;
    let s = if (RATIO_BAND.0..=RATIO_BAND.1).contains(&ratio) {
        1.0
    } else {
        let k = ((ratio / 1.2).log10()).round();
        let s = 10f64.powf(k);
        if !(RATIO_BAND.0..=RATIO_BAND.1).contains(&(ratio / s)) || k.abs() > 6.0 {
            return Err(AttachError::ScaleMismatch {
                skeleton_extent: skel_extent,
                mesh_extent,
            });
        }
        s
    };
    let scaled: Joints = std::array::from_fn(|j| p[j] * s);
    let height = skeleton_height(&scaled, usable);
    let fit_before = fit(mesh, &scaled, usable, height);
    let cover_before = coverage(mesh, &scaled, usable, height);
    let mut best = FrameAlignment {
        scale: s,
        fit_before,
        fit_after: fit_before,
        coverage: cover_before,
        ..FrameAlignment::identity()
    };
    let ok = |f: f64, c: f64| f <= FIT_LIMIT && c <= COVER_LIMIT;
    if !ok(fit_before, cover_before) {
        let mut best_score = f64::INFINITY;
        // Not in place: try every axis rotation with the bounding-box centres matched.
        let cm = bbox_centre(mesh.positions.iter().map(|&x| Point3::from(x)));
        let cj = bbox_centre((0..20).filter(|&j| usable[j]).map(|j| scaled[j]));
        for r in axis_rotations() {
            let t = cm - r * cj;
            let q: Joints = std::array::from_fn(|j| r * scaled[j] + t);
            let f = fit(mesh, &q, usable, height);
            let c = coverage(mesh, &q, usable, height);
            if f / FIT_LIMIT + c / COVER_LIMIT < best_score {
                best_score = f / FIT_LIMIT + c / COVER_LIMIT;
                best.rotation = r;
                best.translation = t;
                best.fit_after = f;
                best.coverage = c;
            }
        }
        if !ok(best.fit_after, best.coverage) {
            return Err(AttachError::AlignmentFailed {
                scale: s,
                residual: best.fit_after,
                coverage: best.coverage,
            });
        }
    }
    for q in p.iter_mut() {
        *q = best.apply(q);
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn there_are_24_distinct_axis_rotations() {
        let r = axis_rotations();
        assert_eq!(r.len(), 24);
        for (i, a) in r.iter().enumerate() {
            for b in &r[i + 1..] {
                assert_ne!(a, b);
            }
        }
    }
}
