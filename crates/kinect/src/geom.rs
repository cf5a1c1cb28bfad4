//! 3-vector helpers: the arithmetic is symcorr-mesh's (one owner); only the normalisation
//! with this crate's tolerance lives here.

pub(crate) use symcorr_mesh::geometry::{add, cross, dot, lerp, norm, scale, sub};

/// Unit vector, or `None` for a (near-)zero vector.
pub(crate) fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(a);
    if n > 1e-12 && n.is_finite() {
        Some(scale(a, 1.0 / n))
    } else {
        None
    }
}
