//! Sagittal planes refined by the surface's own left/right symmetry.
//!
//! The midline segments (pelvis, torso, head) are split into halves by a plane built from the
//! joints; with noisy joints, or a head turned relative to the shoulders, that plane is off by
//! many degrees and whole regions land in the wrong half. [`refine_symmetry_plane`] improves
//! it from the geometry (iterated reflect–match–refit, like ICP for a reflection).

use nalgebra::{Matrix3, Point3, Vector3};

/// Refines a symmetry plane `(origin, normal)` of the point set `points`: reflect every point
/// across the plane, pair it with its nearest point (brute force, so keep the set to a few
/// thousand points), and refit the plane to the pairs — normal = the dominant direction of the
/// pair differences (power iteration on their scatter matrix, sign kept), origin = the mean of
/// the pair midpoints. Pairs farther apart after reflection than twice their median are
/// ignored (parts that are not symmetric). Returns the input plane unchanged when `points` has
/// fewer than 8 points or the normal is zero. Arrays in and out, like the mesh positions the
/// points come from.
///
/// ```
/// use symcorr_correspond::refine_symmetry_plane;
/// // A box of points symmetric about x = 0.3; start from a slightly tilted, shifted plane.
/// let mut pts = Vec::new();
/// for i in 0..10 { for j in 0..10 { for s in [-1.0, 1.0] {
///     pts.push([0.3 + s * (0.1 + 0.02 * i as f64), 0.05 * j as f64, 0.01 * (i * j) as f64]);
/// }}}
/// let (o, n) = refine_symmetry_plane(&pts, [0.28, 0.0, 0.0], [1.0, 0.05, 0.0], 10);
/// assert!((o[0] - 0.3).abs() < 1e-6 && n[0] > 0.999);
/// ```
pub fn refine_symmetry_plane(
    points: &[[f64; 3]],
    origin: [f64; 3],
    normal: [f64; 3],
    iterations: usize,
) -> ([f64; 3], [f64; 3]) {
    let normal = Vector3::from(normal);
    let nn = normal.norm();
    if points.len() < 8 || nn == 0.0 || !nn.is_finite() {
        return (origin, normal.into());
    }
    let points: Vec<Point3<f64>> = points.iter().copied().map(Point3::from).collect();
    let (mut o, mut n) = (Point3::from(origin), normal / nn);
    for _ in 0..iterations {
        // Reflect and pair.
        let pairs: Vec<(usize, usize, f64)> = points
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let s = (x - o).dot(&n);
                let r = x - n * (2.0 * s);
                let (j, d) = points
                    .iter()
                    .enumerate()
                    .map(|(j, y)| (j, (y - r).norm_squared()))
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .unwrap_or((i, 0.0));
                (i, j, d)
            })
            .collect();
        let mut ds: Vec<f64> = pairs.iter().map(|p| p.2).collect();
        let k = ds.len() / 2;
        ds.select_nth_unstable_by(k, f64::total_cmp);
        let cut = 4.0 * ds[k].max(f64::MIN_POSITIVE); // squared: twice the median distance
                                                      // Scatter of the differences (x − y) of pairs on opposite sides, and mean midpoint.
        let mut scatter = Matrix3::zeros();
        let mut mid = Vector3::zeros();
        let mut count = 0usize;
        for &(i, j, d) in &pairs {
            if d > cut || i == j {
                continue;
            }
            let (x, y) = (points[i].coords, points[j].coords);
            let v = x - y;
            scatter += v * v.transpose();
            mid += (x + y) / 2.0;
            count += 1;
        }
        if count < 4 {
            break;
        }
        // Power iteration from the current normal (keeps the sign).
        let mut v = n;
        for _ in 0..50 {
            let w = scatter * v;
            let l = w.norm();
            if l == 0.0 {
                break;
            }
            v = w / l;
        }
        if v.dot(&n) < 0.0 {
            v = -v;
        }
        let new_o = Point3::from(mid / count as f64);
        let moved = (new_o - o).norm_squared();
        let turned = 1.0 - v.dot(&n);
        o = new_o;
        n = v;
        if moved < 1e-18 && turned < 1e-15 {
            break;
        }
    }
    (o.into(), n.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_tilted_plane_from_a_far_start() {
        // A bumpy, asymmetric-along-the-plane cloud symmetric about the plane through (0.1, 0,
        // 0) with normal (cos 20°, sin 20°, 0).
        let (c, s) = (20f64.to_radians().cos(), 20f64.to_radians().sin());
        let mut pts = Vec::new();
        for i in 0..12 {
            for j in 0..12 {
                let u = 0.05 + 0.03 * i as f64; // distance from the plane
                let v = 0.04 * j as f64;
                let w = 0.02 * (i * i) as f64 + 0.1 * (j as f64).sin();
                for sign in [-1.0, 1.0] {
                    let a = sign * u;
                    // plane frame: normal (c, s, 0), in-plane (−s, c, 0) and z.
                    pts.push([0.1 + a * c - v * s, a * s + v * c, w]);
                }
            }
        }
        // Start 8° off and shifted (joint-built planes are off by about that much).
        let t = 12f64.to_radians();
        let (o, n) = refine_symmetry_plane(&pts, [0.0, 0.1, 0.0], [t.cos(), t.sin(), 0.0], 30);
        let dot = n[0] * c + n[1] * s;
        assert!(dot > 0.9999, "normal {n:?}");
        let off = (o[0] - 0.1) * c + o[1] * s;
        assert!(off.abs() < 1e-6, "origin off the plane by {off}");
    }

    #[test]
    fn too_few_points_leave_the_plane() {
        let (o, n) = refine_symmetry_plane(&[[0.0; 3]; 3], [1.0, 2.0, 3.0], [0.0, 2.0, 0.0], 5);
        assert_eq!((o, n), ([1.0, 2.0, 3.0], [0.0, 2.0, 0.0]));
    }
}
