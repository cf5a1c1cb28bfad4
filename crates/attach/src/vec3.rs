//! Tiny 3-vector helpers on `[f64; 3]` (the rest come from `symcorr_mesh::geometry`).

pub(crate) use symcorr_mesh::geometry::{cross, dot, norm, sub};

#[inline]
pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub(crate) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

/// `a` scaled to unit length, or `None` if it is (numerically) zero.
#[inline]
pub(crate) fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = norm(a);
    (l > 1e-12 && l.is_finite()).then(|| scale(a, 1.0 / l))
}

#[inline]
pub(crate) fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    add(a, scale(sub(b, a), t))
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
