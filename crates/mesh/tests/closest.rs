//! `closest_on_triangle` against an independent reference: the nearest of a dense grid of
//! points on the triangle (and on its edges), which is within the grid's spacing of the true
//! closest point.

use nalgebra::Point3;
use proptest::prelude::*;
use symcorr_mesh::geometry::closest_on_triangle;

fn point() -> impl Strategy<Value = Point3<f64>> {
    (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

/// The smallest distance from `p` to the points `a + s·(b − a) + t·(c − a)`, `s, t ≥ 0`,
/// `s + t ≤ 1`, on a grid of `n` steps per edge.
fn grid_distance(p: &Point3<f64>, [a, b, c]: [&Point3<f64>; 3], n: usize) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..=n {
        for j in 0..=(n - i) {
            let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
            let q = a + (b - a) * s + (c - a) * t;
            best = best.min(nalgebra::distance(p, &q));
        }
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn closest_point_is_the_nearest_point_of_the_triangle(
        p in point(), a in point(), b in point(), c in point()
    ) {
        let (w, d) = closest_on_triangle(&p, &a, &b, &c);
        prop_assert!(w.iter().all(|&x| (0.0..=1.0).contains(&x)), "{w:?}");
        prop_assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{w:?}");
        let q = Point3::from(a.coords * w[0] + b.coords * w[1] + c.coords * w[2]);
        prop_assert!((nalgebra::distance(&p, &q) - d).abs() < 1e-12);
        // No point of the triangle is nearer (the grid is on it), and the grid's nearest
        // point is within one grid step (longest edge / n) of the true closest point.
        let n = 200;
        let step = [(b - a).norm(), (c - b).norm(), (a - c).norm()]
            .into_iter()
            .fold(0.0, f64::max) / n as f64;
        let g = grid_distance(&p, [&a, &b, &c], n);
        prop_assert!(d <= g + 1e-12, "closest {d}, a grid point at {g}");
        prop_assert!(d >= g - 2.0 * step, "closest {d}, grid {g}, step {step}");
    }
}

#[test]
fn degenerate_triangles_give_the_nearest_point_of_their_longest_edge() {
    let [a, b, c] = [
        Point3::origin(),
        Point3::new(2.0, 0.0, 0.0),
        Point3::new(1.0, 0.0, 0.0),
    ];
    let (w, d) = closest_on_triangle(&Point3::new(0.5, 1.0, 0.0), &a, &b, &c);
    assert_eq!(w, [0.75, 0.25, 0.0]);
    assert_eq!(d, 1.0);
    // All three corners at one place.
    let (w, d) = closest_on_triangle(&Point3::new(0.0, 3.0, 4.0), &a, &a, &a);
    assert_eq!((w.iter().sum::<f64>(), d), (1.0, 5.0));
}
