//! Benchmarks of the spectral core (the speed targets of the README's "Spectral core" table).
//!
//! Inputs: the 13,380-vertex body fixture, and a 100,002-vertex deformed geodesic sphere
//! (icosahedron, each face split 100×100, projected, then stretched and bumped so the spectrum
//! has no symmetric multiplicities) from `symcorr_spectral::testmesh`.

#![allow(missing_docs)] // criterion_group! generates undocumented public functions

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Duration;
use symcorr_mesh::TriMesh;
use symcorr_spectral::*;

fn body() -> TriMesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/body/body.off");
    symcorr_mesh::io::read(path).expect("body fixture").mesh
}

fn bench_body(c: &mut Criterion) {
    let mesh = body();
    let mut g = c.benchmark_group("body_13k");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("laplacian_mass", |b| {
        b.iter(|| Laplacian::new(black_box(&mesh)).unwrap())
    });
    let lap = Laplacian::new(&mesh).unwrap();
    g.bench_function("factor_L_plus_eps_M", |b| {
        b.iter(|| lap.factor(1e-6, None).unwrap())
    });
    g.bench_function("eigenpairs_k100", |b| {
        b.iter(|| eigenpairs(&lap, 100, &EigenOptions::default()).unwrap())
    });
    let graph = EdgeGraph::new(&mesh);
    let sources: Vec<u32> = (0..100).map(|i| (i * 131) as u32).collect();
    g.bench_function("dijkstra_100_sources", |b| {
        b.iter(|| graph.distances_many(black_box(&sources)).unwrap())
    });
    g.bench_function("heat_setup", |b| {
        b.iter(|| HeatGeodesics::with_laplacian(&mesh, &lap, 1.0).unwrap())
    });
    let heat = HeatGeodesics::with_laplacian(&mesh, &lap, 1.0).unwrap();
    g.bench_function("heat_1_source", |b| {
        b.iter(|| heat.distance(black_box(&[0])).unwrap())
    });
    g.bench_function("heat_100_sources", |b| {
        b.iter(|| heat.distances_many(black_box(&sources)).unwrap())
    });
    let eig = eigenpairs(&lap, 100, &EigenOptions::default()).unwrap();
    g.bench_function("si_hks_default", |b| {
        b.iter(|| si_hks(&eig, &SiHksParams::default()).unwrap())
    });
    g.finish();
}

fn bench_100k(c: &mut Criterion) {
    let mesh = testmesh::deformed_sphere(100);
    assert_eq!(mesh.num_vertices(), 100_002);
    let mut g = c.benchmark_group("sphere_100k");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    g.bench_function("laplacian_mass", |b| {
        b.iter(|| Laplacian::new(black_box(&mesh)).unwrap())
    });
    let lap = Laplacian::new(&mesh).unwrap();
    g.bench_function("eigenpairs_k100", |b| {
        b.iter(|| eigenpairs(&lap, 100, &EigenOptions::default()).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench_body, bench_100k);
criterion_main!(benches);
