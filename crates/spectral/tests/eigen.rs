//! The eigensolver against known spectra (the sphere's l(l+1) with multiplicities), deflation of
//! components, restarts, and its errors.

mod common;

use common::*;
use symcorr_spectral::{
    eigenpairs, si_hks, EigenOptions, Eigenpairs, Laplacian, SiHksParams, SpectralError,
};

fn m_orthonormality_defect(lap: &Laplacian, e: &Eigenpairs) -> f64 {
    let k = e.len();
    let n = e.num_vertices();
    let mut worst = 0.0f64;
    for a in 0..k {
        for b in 0..=a {
            let g: f64 = (0..n)
                .map(|i| lap.mass[i] * e.vectors[(i, a)] * e.vectors[(i, b)])
                .sum();
            let want = if a == b { 1.0 } else { 0.0 };
            worst = worst.max((g - want).abs());
        }
    }
    worst
}

/// Independent residual check: ‖Lφ − λMφ‖/‖Mφ‖ from the stiffness matrix alone.
fn residual(lap: &Laplacian, e: &Eigenpairs, j: usize) -> f64 {
    let n = e.num_vertices();
    let phi: Vec<f64> = (0..n).map(|i| e.vectors[(i, j)]).collect();
    let lp = lap.apply_stiffness(&phi);
    let (mut r, mut m) = (0.0, 0.0);
    for i in 0..n {
        r += (lp[i] - e.values[j] * lap.mass[i] * phi[i]).powi(2);
        m += (lap.mass[i] * phi[i]).powi(2);
    }
    (r / m).sqrt()
}

#[test]
fn icosphere_eigenvalues_approach_l_lplus1_with_multiplicity() {
    // Eigenvalues of the unit sphere: l(l+1) with multiplicity 2l+1. l = 0..=4 → 25 pairs.
    let k = 25;
    let mut prev_err = f64::INFINITY;
    for level in 2..=4 {
        let mesh = icosphere(level);
        let lap = Laplacian::new(&mesh).unwrap();
        let e = eigenpairs(&lap, k, &EigenOptions::default()).unwrap();
        assert_eq!(e.values[0], 0.0);
        let mut idx = 0;
        let mut err = 0.0f64;
        for l in 0..=4usize {
            let exact = (l * (l + 1)) as f64;
            for _ in 0..(2 * l + 1) {
                err = err.max((e.values[idx] - exact).abs() / exact.max(1.0));
                idx += 1;
            }
        }
        eprintln!(
            "level {level}: n = {}, max relative error {err:.3e}, iterations {}, residual {:.1e}",
            mesh.num_vertices(),
            e.iterations,
            e.residual_max
        );
        assert!(
            err < prev_err / 3.0,
            "error did not shrink: {err} vs {prev_err}"
        );
        prev_err = err;
        for j in 0..k {
            assert!(residual(&lap, &e, j) < 1e-8 * e.values[j].max(1.0));
        }
        assert!(m_orthonormality_defect(&lap, &e) < 1e-10);
    }
    assert!(prev_err < 0.01);
}

#[test]
fn two_components_are_deflated() {
    let a = icosphere(2);
    let b = icosphere(2);
    let mesh = union(&a, &b, [5.0, 0.0, 0.0]);
    let lap = Laplacian::new(&mesh).unwrap();
    let single = eigenpairs(&Laplacian::new(&a).unwrap(), 10, &EigenOptions::default()).unwrap();
    let e = eigenpairs(&lap, 12, &EigenOptions::default()).unwrap();
    assert_eq!(e.num_components, 2);
    assert_eq!(&e.values[..2], &[0.0, 0.0]);
    // Each non-zero eigenvalue of one sphere appears twice.
    for i in 1..6 {
        let v = single.values[i];
        let a = e.values[2 * i];
        let b = e.values[2 * i + 1];
        assert!(
            (a - v).abs() < 1e-9 * v && (b - v).abs() < 1e-9 * v,
            "{v} vs {a}, {b}"
        );
    }
    assert!(m_orthonormality_defect(&lap, &e) < 1e-10);
    // Constant vectors are supported on one component each.
    let n = a.num_vertices();
    assert!(e.vectors[(0, 0)] > 0.0 && e.vectors[(n, 0)] == 0.0);
    assert!(e.vectors[(0, 1)] == 0.0 && e.vectors[(n, 1)] > 0.0);
}

#[test]
fn thick_restart_gives_the_same_answer() {
    // Block size 8 on the icosphere (exact multiplicities up to 5 from icosahedral symmetry);
    // single-vector Lanczos (block 1) only on a randomly perturbed sphere with a simple
    // spectrum — with restarts it can lose copies of exactly repeated eigenvalues.
    let sphere = icosphere(3);
    let mut bumpy = sphere.clone();
    let mut s = 99u64;
    for p in &mut bumpy.positions {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let f = 1.0 + 0.05 * ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
        *p = [p[0] * f, p[1] * f, p[2] * f];
    }
    for (mesh, block_size) in [(&sphere, 8), (&bumpy, 1)] {
        let lap = Laplacian::new(mesh).unwrap();
        let full = eigenpairs(&lap, 40, &EigenOptions::default()).unwrap();
        let opts = EigenOptions {
            max_basis: Some(72),
            block_size,
            ..Default::default()
        };
        let restarted = eigenpairs(&lap, 40, &opts).unwrap();
        assert!(restarted.restarts > 0, "test must exercise restarts");
        for (a, b) in full.values.iter().zip(&restarted.values) {
            assert!(
                (a - b).abs() <= 1e-10 * a.max(1.0),
                "block {block_size}: {a} vs {b}"
            );
        }
        assert!(m_orthonormality_defect(&lap, &restarted) < 1e-10);
    }
}

#[test]
fn bad_k_and_non_convergence_are_errors() {
    let mesh = icosphere(1);
    let lap = Laplacian::new(&mesh).unwrap();
    assert!(eigenpairs(&lap, 0, &EigenOptions::default()).is_err());
    let err = eigenpairs(&lap, mesh.num_vertices() + 1, &EigenOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            symcorr_spectral::SpectralError::TooManyEigenpairs { .. }
        ),
        "{err}"
    );
    let mesh = icosphere(3);
    let lap = Laplacian::new(&mesh).unwrap();
    let opts = EigenOptions {
        max_basis: Some(32),
        max_restarts: 0,
        ..Default::default()
    };
    let err = eigenpairs(&lap, 30, &opts).unwrap_err();
    assert!(
        matches!(err, symcorr_spectral::SpectralError::NotConverged { .. }),
        "{err}"
    );
}

#[test]
fn all_eigenpairs_of_a_small_mesh() {
    // k = n: the whole spectrum (Lanczos spans the full space), compared with a dense solve.
    let mesh = icosphere(1);
    let n = mesh.num_vertices();
    let lap = Laplacian::new(&mesh).unwrap();
    let e = eigenpairs(&lap, n, &EigenOptions::default()).unwrap();
    // Dense reference: M^-½ L M^-½.
    let l = lap.stiffness.to_dense();
    let a = faer::Mat::from_fn(n, n, |i, j| l[(i, j)] / (lap.mass[i] * lap.mass[j]).sqrt());
    let reference = a.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    for (x, y) in e.values.iter().zip(&reference) {
        assert!((x - y).abs() < 1e-9 * y.abs().max(1.0), "{x} vs {y}");
    }
    assert!(m_orthonormality_defect(&lap, &e) < 1e-10);
}

#[test]
fn k_above_vertex_count_is_a_typed_error() {
    // The 12-vertex icosahedron: k = 12 is the whole spectrum, k = 13 does not exist.
    let mesh = icosphere(0);
    let n = mesh.num_vertices();
    assert_eq!(n, 12);
    let lap = Laplacian::new(&mesh).unwrap();
    assert_eq!(
        eigenpairs(&lap, n, &EigenOptions::default()).unwrap().len(),
        n
    );
    let err = eigenpairs(&lap, n + 1, &EigenOptions::default()).unwrap_err();
    match &err {
        SpectralError::TooManyEigenpairs {
            k, vertices, max, ..
        } => assert_eq!((*k, *vertices, *max), (13, 12, 12)),
        other => panic!("{other}"),
    }
    let text = err.to_string();
    assert!(
        text.starts_with("k = 13 eigenpairs of a 12-vertex mesh: k must be at most 12"),
        "{text}"
    );
    assert!(!text.contains('\n'));
}

#[test]
fn oversize_dense_working_set_is_refused_before_allocating() {
    // With the default 8 GiB limit: k = n − 1 on the 13k-vertex body implies a ~13k-column
    // basis and a dense projected matrix of the same order (over 8 GiB in all). Refused at
    // once; before the check this allocated gigabytes and aborted on faer's AllocError.
    let big = body();
    let n = big.num_vertices();
    let lap = Laplacian::new(&big).unwrap();
    let err = eigenpairs(&lap, n - 1, &EigenOptions::default()).unwrap_err();
    assert!(err_mentions_limit(&err), "{err}");
    assert!(
        matches!(err, SpectralError::TooManyEigenpairs { .. }),
        "{err}"
    );
    // A tight limit on a small mesh: refused with the largest allowed k.
    let mesh = icosphere(1);
    let lap = Laplacian::new(&mesh).unwrap();
    let tight = EigenOptions {
        dense_limit_bytes: 40_000,
        ..Default::default()
    };
    let err = eigenpairs(&lap, 30, &tight).unwrap_err();
    let SpectralError::TooManyEigenpairs { k, max, .. } = err else {
        panic!("{err}");
    };
    assert_eq!(k, 30);
    assert!(max < 30);
    // The largest allowed k is computed, not guessed: max + 1 is refused.
    assert!(matches!(
        eigenpairs(&lap, max + 1, &tight),
        Err(SpectralError::TooManyEigenpairs { .. })
    ));
    assert!(err_mentions_limit(
        &eigenpairs(&lap, 30, &tight).unwrap_err()
    ));
}

fn err_mentions_limit(e: &SpectralError) -> bool {
    let t = e.to_string();
    t.contains("GiB") && t.contains("limit")
}

#[test]
fn oversize_si_hks_window_is_refused() {
    let mesh = icosphere(1);
    let lap = Laplacian::new(&mesh).unwrap();
    let e = eigenpairs(&lap, 6, &EigenOptions::default()).unwrap();
    // 1e12 time samples per vertex: an n × 1e12 matrix, refused instead of aborting.
    let params = SiHksParams {
        tau_step: 1e-12,
        ..SiHksParams::default()
    };
    let err = si_hks(&e, &params).unwrap_err();
    assert!(matches!(err, SpectralError::TooLarge { .. }), "{err}");
    assert!(err.to_string().contains("si-HKS"), "{err}");
}
