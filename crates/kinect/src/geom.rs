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

/// The median of `v` (the mean of the middle two for an even count; `v` is sorted in place),
/// `None` when empty.
pub(crate) fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}
