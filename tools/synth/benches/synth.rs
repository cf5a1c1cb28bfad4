//! Posing and rendering speed on the 13,380-vertex body.
#![allow(missing_docs)] // criterion_group! generates undocumented public functions

use criterion::{criterion_group, criterion_main, Criterion};
use symcorr_synth::render::{render, Camera, Realism};
use symcorr_synth::{poses::named_pose, Assets, Model, Shape};

fn bench(c: &mut Criterion) {
    let model = Model::new(Assets::load(&Assets::default_dir()).unwrap()).unwrap();
    let body = model.body(&Shape::default()).unwrap();
    let pose = named_pose(&model.assets, "walk-10").unwrap();
    c.bench_function("pose_13380_vertices", |b| {
        b.iter(|| body.pose(&pose).unwrap())
    });
    let posed = body.pose(&pose).unwrap();
    let cam = Camera::kinect_v1([0.0, 0.0, 2.6], [0.0, -0.05, 0.0]);
    c.bench_function("render_640x480_ideal", |b| {
        b.iter(|| render(&posed.mesh, &cam, &Realism::default(), 0))
    });
    c.bench_function("render_640x480_kinect", |b| {
        b.iter(|| render(&posed.mesh, &cam, &Realism::kinect(1), 0))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
