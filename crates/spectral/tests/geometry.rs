//! Curvature (Gauss–Bonnet on spheres, disks and the body) and geodesics (Dijkstra against
//! Euclidean bounds and the heat method) on meshes with known answers.

mod common;

use common::*;
use nalgebra::Vector3;
use std::f64::consts::PI;
use symcorr_spectral::*;

fn total_curvature(mesh: &symcorr_mesh::TriMesh) -> f64 {
    let gc = gaussian_curvature(mesh);
    let mut area = vec![0.0; mesh.num_vertices()];
    for (t, a) in mesh.triangles.iter().zip(mesh.triangle_areas()) {
        for &v in t {
            area[v as usize] += a / 3.0;
        }
    }
    gc.iter().zip(&area).map(|(g, a)| g * a).sum()
}

#[test]
fn gauss_bonnet_closed_genus_zero() {
    for level in 0..4 {
        let t = total_curvature(&icosphere(level));
        assert!((t - 4.0 * PI).abs() < 1e-10, "level {level}: {t}");
    }
    let t = total_curvature(&body());
    assert!((t - 4.0 * PI).abs() < 1e-8, "body: {t}");
}

#[test]
fn gauss_bonnet_flat_disk_with_boundary_convention() {
    // Interior vertices of a flat disk have zero curvature; with the π convention the boundary
    // carries the total turning 2π (χ = 1).
    let mesh = disk(8);
    let gc = gaussian_curvature(&mesh);
    let interior = mesh.num_vertices() - 48;
    assert!(gc[..interior].iter().all(|g| g.abs() < 1e-10));
    let t = total_curvature(&mesh);
    assert!((t - 2.0 * PI).abs() < 1e-10, "{t}");
}

#[test]
fn sphere_curvature_is_about_one() {
    // Unit sphere: K = 1 everywhere.
    let gc = gaussian_curvature(&icosphere(4));
    let mean = gc.iter().sum::<f64>() / gc.len() as f64;
    assert!((mean - 1.0).abs() < 0.01, "{mean}");
}

#[test]
fn dijkstra_on_flat_disk_bounds_euclidean() {
    let mesh = disk(10);
    let sources = [0u32, 17, 100];
    let rows = dijkstra_many(&mesh, &sources).unwrap();
    for (row, &s) in rows.iter().zip(&sources) {
        let single = dijkstra(&mesh, s).unwrap();
        assert_eq!(row, &single);
        let ps = mesh.positions[s as usize];
        for (v, &d) in row.iter().enumerate() {
            let p = mesh.positions[v];
            let e = ((p[0] - ps[0]).powi(2) + (p[1] - ps[1]).powi(2)).sqrt();
            assert!(d >= e - 1e-12, "vertex {v}: dijkstra {d} < euclidean {e}");
            // Edge paths on this mesh are not much longer than straight lines.
            assert!(d <= 1.4 * e + 1e-12, "vertex {v}: {d} vs {e}");
        }
    }
    assert!(dijkstra(&mesh, mesh.num_vertices() as u32).is_err());
}

#[test]
fn heat_method_on_flat_disk_close_to_euclidean() {
    let mesh = disk(20);
    let heat = HeatGeodesics::new(&mesh, 1.0).unwrap();
    let d = heat.distance(&[0]).unwrap();
    assert_eq!(d[0], 0.0);
    let mut worst = 0.0f64;
    for (v, p) in mesh.positions.iter().enumerate() {
        let e = (p[0] * p[0] + p[1] * p[1]).sqrt();
        if e > 0.2 {
            worst = worst.max((d[v] - e).abs() / e);
        }
    }
    assert!(worst < 0.05, "heat method off by {worst}");
    // The blocked parallel variant gives the same rows as single queries.
    let many = heat.distances_many(&[0, 5, 300]).unwrap();
    for (row, s) in many.iter().zip([0u32, 5, 300]) {
        let single = heat.distance(&[s]).unwrap();
        for (a, b) in row.iter().zip(&single) {
            assert!((a - b).abs() < 1e-12);
        }
    }
}

#[test]
fn heat_method_two_components() {
    let a = icosphere(2);
    let mesh = union(&a, &a, [4.0, 0.0, 0.0]);
    let heat = HeatGeodesics::new(&mesh, 1.0).unwrap();
    let d = heat.distance(&[3]).unwrap();
    let n = a.num_vertices();
    assert!(d[..n].iter().all(|x| x.is_finite()));
    assert!(d[n..].iter().all(|x| x.is_infinite()));
    // Antipode of vertex 3 on the unit sphere is at distance π.
    let p = a.positions[3];
    let anti = (0..n)
        .min_by(|&i, &j| {
            let f = |k: usize| (Vector3::from(a.positions[k]) + Vector3::from(p)).norm_squared();
            f(i).total_cmp(&f(j))
        })
        .unwrap();
    assert!((d[anti] - PI).abs() < 0.1 * PI, "{}", d[anti]);
}

#[test]
fn base_vertex_set_is_a_separated_cover() {
    let mesh = body();
    let gc = gaussian_curvature(&mesh);
    let radius = 0.1;
    let r = radius * mesh.total_area().sqrt();
    let base = base_vertex_set(&mesh, &gc, radius).unwrap();
    assert!(base.len() > 5 && base.len() < 500, "{}", base.len());
    let max = gc.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(gc[base[0] as usize], max);
    let rows = dijkstra_many(&mesh, &base).unwrap();
    // Separated: each base vertex is farther than r from every earlier one.
    for i in 0..base.len() {
        for row in rows.iter().take(i) {
            assert!(row[base[i] as usize] > r);
        }
    }
    // Cover: every vertex is within r of some base vertex.
    for v in 0..mesh.num_vertices() {
        assert!(rows.iter().any(|row| row[v] <= r), "vertex {v} uncovered");
    }
    assert!(base_vertex_set(&mesh, &gc[1..], radius).is_err());
}

#[test]
fn hks_satisfies_the_heat_trace_identity() {
    let mesh = icosphere(3);
    let lap = Laplacian::new(&mesh).unwrap();
    let e = eigenpairs(&lap, 25, &EigenOptions::default()).unwrap();
    let n = mesh.num_vertices();
    // Σ_x M_x k_t(x,x) = Σ_i e^{-λ_i t} (heat trace).
    let times = hks_times(&e, 4);
    let h = hks(&e, &times);
    for (j, &t) in times.iter().enumerate() {
        let lhs: f64 = (0..n).map(|x| lap.mass[x] * h[(x, j)]).sum();
        let rhs: f64 = e.values.iter().map(|l| (-l * t).exp()).sum();
        assert!((lhs - rhs).abs() < 1e-9 * rhs);
    }
}

#[test]
fn si_hks_is_scale_invariant() {
    // Scaling by 2 multiplies t by 4: a shift of exactly 2 in τ = log2 t (32 samples at step
    // 1/16). With a window wide enough for the derivative to vanish at both ends, |DFT| is
    // unchanged.
    let mesh = icosphere(2);
    let mut big = mesh.clone();
    for p in &mut big.positions {
        *p = [2.0 * p[0], 2.0 * p[1], 2.0 * p[2]];
    }
    let params = SiHksParams {
        tau_start: -30.0,
        tau_end: 20.0,
        ..Default::default()
    };
    let opts = EigenOptions::default();
    let e1 = eigenpairs(&Laplacian::new(&mesh).unwrap(), 20, &opts).unwrap();
    let e2 = eigenpairs(&Laplacian::new(&big).unwrap(), 20, &opts).unwrap();
    let s1 = si_hks(&e1, &params).unwrap();
    let s2 = si_hks(&e2, &params).unwrap();
    assert_eq!(s1.ncols(), 6);
    let mut worst = 0.0f64;
    for x in 0..mesh.num_vertices() {
        for f in 0..6 {
            worst = worst.max((s1[(x, f)] - s2[(x, f)]).abs() / s1[(x, 0)].abs());
        }
    }
    assert!(worst < 1e-6, "{worst}");
    // Plain HKS is not scale invariant (sanity: the test can fail).
    let h1 = hks(&e1, &[0.1]);
    let h2 = hks(&e2, &[0.1]);
    assert!((h1[(0, 0)] - h2[(0, 0)]).abs() > 1e-3 * h1[(0, 0)]);
    assert!(si_hks(
        &e1,
        &SiHksParams {
            tau_step: 0.0,
            ..Default::default()
        }
    )
    .is_err());
}

#[test]
fn area_relative_si_hks_is_scale_invariant_on_a_narrow_window() {
    // With times relative to the area, a mesh scaled by 3 (τ shift log2 9, not a whole number
    // of samples) is sampled at exactly the same relative times, so even the narrow window
    // [−8, 3], where the derivative does not vanish at the ends, gives the same descriptor.
    let mesh = icosphere(2);
    let mut big = mesh.clone();
    for p in &mut big.positions {
        *p = [3.0 * p[0], 3.0 * p[1], 3.0 * p[2]];
    }
    let rel = SiHksParams::area_relative();
    assert_eq!((rel.tau_start, rel.tau_end, rel.alpha), (-8.0, 3.0, 2.0));
    let opts = EigenOptions::default();
    let (l1, l2) = (
        Laplacian::new(&mesh).unwrap(),
        Laplacian::new(&big).unwrap(),
    );
    let e1 = eigenpairs(&l1, 20, &opts).unwrap();
    let e2 = eigenpairs(&l2, 20, &opts).unwrap();
    let p1 = rel.relative_to_area(mesh.total_area());
    let p2 = rel.relative_to_area(big.total_area());
    assert!((p2.tau_start - p1.tau_start - 9f64.log2()).abs() < 1e-12);
    assert_eq!(p2.tau_end - p2.tau_start, p1.tau_end - p1.tau_start);
    let rel_diff = |a: &faer::Mat<f64>, b: &faer::Mat<f64>| {
        let mut worst = 0.0f64;
        for x in 0..a.nrows() {
            for f in 0..a.ncols() {
                worst = worst.max((a[(x, f)] - b[(x, f)]).abs() / a[(x, 0)].abs());
            }
        }
        worst
    };
    let s1 = si_hks(&e1, &p1).unwrap();
    let s2 = si_hks(&e2, &p2).unwrap();
    assert!(rel_diff(&s1, &s2) < 1e-8, "{}", rel_diff(&s1, &s2));
    // The same absolute window on both is not invariant here (the test can fail).
    let a2 = si_hks(&e2, &p1).unwrap();
    assert!(rel_diff(&s1, &a2) > 1e-3, "{}", rel_diff(&s1, &a2));
}

#[test]
fn bounded_search_settles_in_order_at_the_full_dijkstra_distances() {
    let mesh = body();
    let g = EdgeGraph::new(&mesh);
    let n = g.len();
    let mut scratch = DijkstraScratch::new(&g);
    for source in [0u32, 17, (n / 2) as u32, (n - 1) as u32] {
        let full = g.distances(source).unwrap();
        // Everything: same distances, bit for bit, in non-decreasing order.
        let mut seen = Vec::new();
        g.search(&mut scratch, source, f64::INFINITY, |v, d| {
            seen.push((v, d));
            true
        })
        .unwrap();
        assert_eq!(seen.len(), n);
        assert!(seen.windows(2).all(|w| w[0].1 <= w[1].1));
        assert!(seen
            .iter()
            .all(|&(v, d)| d.to_bits() == full[v as usize].to_bits()));
        // Within a radius: exactly the vertices at most that far.
        let r = full.iter().cloned().fold(0.0, f64::max) * 0.3;
        let mut inside = 0;
        g.search(&mut scratch, source, r, |v, d| {
            assert!(d <= r && d == full[v as usize]);
            inside += 1;
            true
        })
        .unwrap();
        assert_eq!(inside, full.iter().filter(|&&d| d <= r).count());
        // Stopped at a target: its distance, having settled only nearer vertices.
        let target = seen[n * 2 / 3].0;
        let mut settled = 0;
        let mut got = None;
        g.search(&mut scratch, source, f64::INFINITY, |v, d| {
            settled += 1;
            got = (v == target).then_some(d);
            v != target
        })
        .unwrap();
        assert_eq!(got, Some(full[target as usize]));
        let nearer = full.iter().filter(|&&d| d <= full[target as usize]).count();
        assert!(settled <= nearer && nearer < n, "{settled} {nearer}");
    }
    assert!(g.search(&mut scratch, n as u32, 1.0, |_, _| true).is_err());
    let small = EdgeGraph::new(&icosphere(0));
    assert!(small.search(&mut scratch, 0, 1.0, |_, _| true).is_err());
}
