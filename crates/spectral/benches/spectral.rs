//! Benchmarks of the spectral core (DESIGN.md / issue 2 "Performance").
//!
//! Inputs: the 13,380-vertex body fixture, and a 100,002-vertex deformed geodesic sphere
//! (icosahedron, each face split 100×100, projected, then stretched and bumped so the spectrum
//! has no symmetric multiplicities) built here.

use criterion::{criterion_group, criterion_main, Criterion};
use std::collections::HashMap;
use std::hint::black_box;
use std::time::Duration;
use symcorr_mesh::TriMesh;
use symcorr_spectral::*;

fn body() -> TriMesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/body/body.off");
    symcorr_mesh::io::read(path).expect("body fixture").mesh
}

/// Class-I geodesic sphere of frequency `f` (10 f² + 2 vertices), deformed.
fn big_sphere(f: usize) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let ico: [[f64; 3]; 12] = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let faces: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut pos: Vec<[f64; 3]> = Vec::new();
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut tris = Vec::new();
    for fc in faces {
        let [a, b, c] = fc.map(|i| ico[i]);
        let mut id = |i: usize, j: usize| -> u32 {
            let w = [(f - i - j) as f64, i as f64, j as f64];
            let p: [f64; 3] =
                std::array::from_fn(|d| (w[0] * a[d] + w[1] * b[d] + w[2] * c[d]) / f as f64);
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            let p = [p[0] / l, p[1] / l, p[2] / l];
            let key = p.map(|x| (x * 1e9).round() as i64);
            *index.entry(key).or_insert_with(|| {
                pos.push(p);
                (pos.len() - 1) as u32
            })
        };
        for i in 0..f {
            for j in 0..f - i {
                let (p0, p1, p2) = (id(i, j), id(i + 1, j), id(i, j + 1));
                tris.push([p0, p1, p2]);
                if i + j + 1 < f {
                    let p3 = id(i + 1, j + 1);
                    tris.push([p1, p3, p2]);
                }
            }
        }
    }
    for p in &mut pos {
        let bump = 1.0 + 0.1 * (3.0 * p[0]).sin() * (2.0 * p[1]).cos();
        *p = [1.3 * p[0] * bump, 0.8 * p[1] * bump, p[2] * bump];
    }
    TriMesh::new(pos, tris).expect("valid sphere")
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
    let mesh = big_sphere(100);
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
