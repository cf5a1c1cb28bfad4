//! The few 3-vector helpers on `[f64; 3]` that `symcorr_mesh::geometry` does not have.

use symcorr_mesh::geometry::{add, dist, dot, norm, scale, sub};

/// `a` scaled to unit length, or `None` if it is (numerically) zero.
#[inline]
pub(crate) fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = norm(a);
    (l > 1e-12 && l.is_finite()).then(|| scale(a, 1.0 / l))
}

/// Closest point to `p` on the segment `a–b` and its distance.
#[inline]
pub(crate) fn closest_on_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> ([f64; 3], f64) {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 > 0.0 {
        (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = add(a, scale(ab, t));
    (q, dist(p, q))
}

/// `R·p` for a row-major 3×3 matrix.
#[inline]
pub(crate) fn mat_vec(r: &[[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
    [dot(r[0], p), dot(r[1], p), dot(r[2], p)]
}
