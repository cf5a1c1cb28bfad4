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
