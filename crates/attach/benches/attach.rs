//! Attachment (alignment + refinement + bone heat + labels) on the 13,380-vertex synth body.

#![allow(missing_docs)] // criterion_group! generates undocumented public functions

use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;
use symcorr_attach::{attach, AttachOptions, Joint, Skeleton};

fn load() -> (symcorr_mesh::TriMesh, Skeleton) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/bodies");
    let mesh = symcorr_mesh::io::read(root.join("meshes/s0_walk-10.ply"))
        .expect("synth fixture")
        .mesh;
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("joints/s0_walk-10.json")).expect("joints"),
    )
    .expect("json");
    let mut sk = Skeleton::from_arrays([[0.0; 3]; 20]);
    for j in Joint::ALL {
        let a = v["frames"][0]["joints"][j.name()]
            .as_array()
            .expect("joint");
        sk.positions[j.index()] =
            nalgebra::Point3::from(std::array::from_fn(|k| a[k].as_f64().expect("number")));
    }
    (mesh, sk)
}

fn bench(c: &mut Criterion) {
    let (mesh, sk) = load();
    let mut g = c.benchmark_group("attach");
    g.sample_size(20);
    g.bench_function("synth_body_13380", |b| {
        b.iter(|| attach(&mesh, &sk, &AttachOptions::default()).expect("attach"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
