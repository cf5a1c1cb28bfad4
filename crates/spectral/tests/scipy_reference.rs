//! Comparison against fixtures/spectral/reference.json, produced independently by
//! tools/reference/make_reference.py (numpy/scipy/potpourri3d/pygeodesic). The meaning of each
//! key is the JSON's own `description` field.

mod common;

use serde_json::Value;
use symcorr_mesh::TriMesh;
use symcorr_spectral::*;

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn reference() -> Value {
    let text = std::fs::read_to_string(root().join("fixtures/spectral/reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn ref_mesh(r: &Value) -> TriMesh {
    let mesh = symcorr_mesh::io::read(root().join(r["mesh"].as_str().unwrap()))
        .unwrap()
        .mesh;
    assert_eq!(mesh.num_vertices() as u64, r["vertices"].as_u64().unwrap());
    assert_eq!(
        mesh.num_triangles() as u64,
        r["triangles"].as_u64().unwrap()
    );
    mesh
}

fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(1e-300))
        .fold(0.0, f64::max)
}

#[test]
fn mass_and_stiffness_match_scipy() {
    let r = reference();
    let mesh = ref_mesh(&r);
    let lap = Laplacian::new(&mesh).unwrap();
    assert!(max_rel(&lap.mass, &floats(&r["mass"])) < 1e-12);
    let dense = lap.stiffness.to_dense();
    let diag: Vec<f64> = (0..mesh.num_vertices()).map(|i| dense[(i, i)]).collect();
    assert!(max_rel(&diag, &floats(&r["stiffness_diagonal"])) < 1e-12);
    let fro = lap
        .stiffness
        .val()
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    let want = r["stiffness_frobenius_norm"].as_f64().unwrap();
    assert!((fro - want).abs() < 1e-12 * want);
}

#[test]
fn eigenvalues_match_scipy_eigsh() {
    let r = reference();
    let mesh = ref_mesh(&r);
    let lap = Laplacian::new(&mesh).unwrap();
    let want = floats(&r["eigenvalues"]);
    let e = eigenpairs(&lap, want.len(), &EigenOptions::default()).unwrap();
    // λ_0 = 0 exactly here; scipy's is ~1e-15.
    assert!(want[0].abs() < 1e-12 && e.values[0] == 0.0);
    let rel = max_rel(&e.values[1..], &want[1..]);
    eprintln!("ref mesh: max relative eigenvalue difference {rel:.2e}");
    assert!(rel < 1e-9, "{rel}");
}

#[test]
fn body_eigenvalues_match_scipy_eigsh() {
    let r = reference();
    let mesh = symcorr_mesh::io::read(root().join(r["body_mesh"].as_str().unwrap()))
        .unwrap()
        .mesh;
    assert_eq!(
        mesh.num_vertices() as u64,
        r["body_vertices"].as_u64().unwrap()
    );
    let lap = Laplacian::new(&mesh).unwrap();
    let want = floats(&r["body_eigenvalues"]);
    let e = eigenpairs(&lap, want.len(), &EigenOptions::default()).unwrap();
    assert_eq!(e.values[0], 0.0);
    let rel = max_rel(&e.values[1..], &want[1..]);
    eprintln!("body: max relative eigenvalue difference {rel:.2e}");
    assert!(rel < 1e-9, "{rel}");
}

#[test]
fn hks_matches_scipy() {
    let r = reference();
    let mesh = ref_mesh(&r);
    let lap = Laplacian::new(&mesh).unwrap();
    let e = eigenpairs(
        &lap,
        floats(&r["eigenvalues"]).len(),
        &EigenOptions::default(),
    )
    .unwrap();
    let times = floats(&r["hks_times"]);
    // Our own recipe for the times gives the reference's times.
    assert!(max_rel(&hks_times(&e, times.len()), &times) < 1e-9);
    let h = hks(&e, &times);
    let mut worst = 0.0f64;
    for (v, row) in r["hks"].as_array().unwrap().iter().enumerate() {
        let want = floats(row);
        for (j, w) in want.iter().enumerate() {
            worst = worst.max((h[(v, j)] - w).abs() / w.abs());
        }
    }
    eprintln!("HKS max relative difference {worst:.2e}");
    assert!(worst < 1e-9, "{worst}");
}

#[test]
fn curvature_matches_reference() {
    let r = reference();
    let mesh = ref_mesh(&r);
    let gc = gaussian_curvature(&mesh);
    let want = floats(&r["gaussian_curvature"]);
    let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let worst = gc
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-10 * scale, "{worst}");
}

#[test]
fn dijkstra_matches_scipy_csgraph() {
    let r = reference();
    let mesh = ref_mesh(&r);
    let s = r["dijkstra_source"].as_u64().unwrap() as u32;
    let d = dijkstra(&mesh, s).unwrap();
    let want = floats(&r["dijkstra"]);
    let worst = d
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-12, "{worst}");
    // Dijkstra paths are never shorter than the exact polyhedral geodesic.
    if let Some(exact) = r["exact_geodesic"].as_array() {
        for (a, b) in d.iter().zip(exact) {
            assert!(*a >= b.as_f64().unwrap() - 1e-9);
        }
    }
}

#[test]
fn heat_geodesics_match_numpy_heat_method() {
    let r = reference();
    let mesh = ref_mesh(&r);
    let s = r["dijkstra_source"].as_u64().unwrap() as u32;
    let heat = HeatGeodesics::new(&mesh, 1.0).unwrap();
    let t_ref = r["heat_t"].as_f64().unwrap();
    assert!((heat.time() - t_ref).abs() < 1e-12 * t_ref);
    let d = heat.distance(&[s]).unwrap();
    let want = floats(&r["heat_geodesic_numpy"]);
    let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let worst = d
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    eprintln!("heat method vs numpy: max abs difference {worst:.2e} (scale {scale:.2})");
    assert!(worst < 1e-9 * scale, "{worst}");
    // And within a few % of the exact geodesic on average.
    if let Some(exact) = r["exact_geodesic"].as_array() {
        let (mut sum, mut cnt) = (0.0, 0);
        for (a, b) in d.iter().zip(exact) {
            let b = b.as_f64().unwrap();
            if b > 0.0 {
                sum += (a - b).abs() / b;
                cnt += 1;
            }
        }
        assert!(sum / (cnt as f64) < 0.03);
    }
}
