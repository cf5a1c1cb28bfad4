//! The one 3-vector helper nalgebra lacks in the form this crate needs.

use nalgebra::Vector3;

/// Unit vector, or `None` for a (near-)zero or non-finite vector. `v · (1/|v|)`, not
/// nalgebra's `v / |v|`: the rounding the imported fixtures were produced with.
pub(crate) fn normalize(v: Vector3<f64>) -> Option<Vector3<f64>> {
    let n = v.norm();
    if n > 1e-12 && n.is_finite() {
        Some(v * (1.0 / n))
    } else {
        None
    }
}
