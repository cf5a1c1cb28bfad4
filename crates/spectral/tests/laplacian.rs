//! Cotan Laplacian and mass matrix invariants, the Dirichlet energy of linear functions, and the
//! sparse factorisation.

mod common;

use common::*;
use faer::Mat;
use symcorr_spectral::Laplacian;

fn check_basic(mesh: &symcorr_mesh::TriMesh) {
    let lap = Laplacian::new(mesh).unwrap();
    let n = mesh.num_vertices();
    // L·1 = 0.
    let l1 = lap.apply_stiffness(&vec![1.0; n]);
    let scale = lap
        .stiffness
        .val()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(l1.iter().all(|v| v.abs() < 1e-12 * scale), "L·1 != 0");
    // Symmetry: compare L to its transpose entrywise.
    let dense = lap.stiffness.to_dense();
    for j in 0..n {
        for i in 0..n {
            assert!((dense[(i, j)] - dense[(j, i)]).abs() <= 1e-14 * scale);
        }
    }
    // Mass sums to the total area.
    let total: f64 = lap.mass.iter().sum();
    assert!((total - mesh.total_area()).abs() < 1e-12 * total);
    // PSD on random vectors: xᵀLx ≥ 0.
    let mut s = 12345u64;
    for _ in 0..20 {
        let x: Vec<f64> = (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        assert!(lap.stiffness_form(&x, &x) >= -1e-12 * scale);
    }
}

#[test]
fn laplacian_invariants_sphere_disk() {
    check_basic(&icosphere(2));
    check_basic(&disk(6));
}

#[test]
fn laplacian_reproduces_dirichlet_energy_of_linear_function_on_flat_disk() {
    // For a linear function f = x on a flat mesh, the cotan Dirichlet energy fᵀLf equals
    // ∫|∇f|² = area exactly (the cotan formula is exact for piecewise-linear functions).
    let mesh = disk(8);
    let lap = Laplacian::new(&mesh).unwrap();
    let f: Vec<f64> = mesh.positions.iter().map(|p| p[0]).collect();
    let e = lap.stiffness_form(&f, &f);
    assert!(
        (e - mesh.total_area()).abs() < 1e-12,
        "{e} vs {}",
        mesh.total_area()
    );
    // And L·f vanishes at interior vertices (discrete harmonicity of linear functions).
    let lf = lap.apply_stiffness(&f);
    let boundary_start = mesh.num_vertices() - 6 * 8;
    assert!(lf[..boundary_start].iter().all(|v| v.abs() < 1e-12));
}

#[test]
fn factor_solves_screened_poisson_many_rhs() {
    let mesh = icosphere(3);
    let lap = Laplacian::new(&mesh).unwrap();
    let n = mesh.num_vertices();
    let h: Vec<f64> = (0..n).map(|i| if i % 7 == 0 { 3.0 } else { 0.0 }).collect();
    let sys = lap.factor(0.0, Some(&h)).unwrap();
    let b = Mat::from_fn(n, 19, |i, j| ((i * 31 + j * 17) % 13) as f64 - 6.0);
    let x = sys.solve_many(b.as_ref());
    // Residual (L + H) x - b.
    for j in 0..19 {
        let xj: Vec<f64> = (0..n).map(|i| x[(i, j)]).collect();
        let lx = lap.apply_stiffness(&xj);
        for i in 0..n {
            let r = lx[i] + h[i] * xj[i] - b[(i, j)];
            assert!(r.abs() < 1e-9, "residual {r}");
        }
    }
    // L alone (singular) must fail, not return garbage.
    assert!(
        lap.factor(0.0, None).is_err() || {
            // Cholesky of an exactly singular PSD matrix may succeed with a tiny pivot; then the
            // solution of L x = 1 cannot satisfy it (1 is not in the range of L).
            let s = lap.factor(0.0, None).unwrap();
            let x = s.solve(&vec![1.0; n]);
            let r = lap.apply_stiffness(&x);
            r.iter().any(|v| (v - 1.0).abs() > 1e-3 || !v.is_finite())
        }
    );
}

#[test]
fn body_laplacian_builds() {
    let mesh = body();
    let lap = Laplacian::new(&mesh).unwrap();
    let l1 = lap.apply_stiffness(&vec![1.0; mesh.num_vertices()]);
    assert!(l1.iter().all(|v| v.abs() < 1e-9));
    assert!(lap.mass.iter().all(|&m| m > 0.0));
}

#[test]
fn zero_mass_vertex_is_an_error() {
    let mut m = icosphere(1);
    m.positions.push([5.0, 5.0, 5.0]);
    let err = Laplacian::new(&m).unwrap_err();
    assert!(
        matches!(err, symcorr_spectral::SpectralError::ZeroMass { vertex } if vertex == m.num_vertices() - 1)
    );
}
