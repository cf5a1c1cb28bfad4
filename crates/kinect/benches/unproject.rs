//! Depth image → points at 640×480, a pinhole camera against the same camera with a lens
//! model: the rays found for one frame ([`depth_to_points`], Newton's method per pixel), the
//! ray table alone ([`Intrinsics::pixel_rays`]), and a scan with the rays at hand
//! ([`scan_mesh_with_rays`], what `symcorr track` does per frame).
#![allow(missing_docs)] // criterion_group! generates undocumented public functions

use criterion::{criterion_group, criterion_main, Criterion};
use symcorr_kinect::scan::depth_to_points;
use symcorr_kinect::{scan_mesh_with_rays, DepthFrame, Distortion, Intrinsics, ScanOptions};

/// A wall 3 m away with a ball of 0.4 m radius 2.5 m away in front of it: every pixel reads.
fn frame(k: &Intrinsics) -> DepthFrame {
    let mut data = Vec::new();
    for v in 0..k.height {
        for u in 0..k.width {
            let d = k.unproject(f64::from(u), f64::from(v), 1.0).coords;
            let (a, b, c) = (d.norm_squared(), -5.0 * d.z, 2.5 * 2.5 - 0.16);
            let disc = b * b - 4.0 * a * c;
            let t = if disc >= 0.0 {
                (-b - disc.sqrt()) / (2.0 * a)
            } else {
                3.0
            };
            data.push((t * 1000.0).round() as u16);
        }
    }
    DepthFrame::new(k.width, k.height, data).unwrap()
}

fn bench(c: &mut Criterion) {
    let pinhole = Intrinsics::kinect_v1();
    // The Azure Kinect's rational model (its narrow mode's factory calibration, roughly).
    let azure = [
        0.4989, -0.0155, -0.0000532, 0.0000436, -0.0063, 0.835, 0.1196, -0.03,
    ];
    let lens = Intrinsics {
        distortion: Some(Distortion::from_opencv(&azure).unwrap()),
        ..pinhole
    };
    for (name, k) in [("pinhole", pinhole), ("rational_lens", lens)] {
        let f = frame(&k);
        c.bench_function(&format!("depth_to_points_640x480_{name}"), |b| {
            b.iter(|| depth_to_points(&f, &k, 0.4, 8.0).unwrap())
        });
        c.bench_function(&format!("pixel_rays_640x480_{name}"), |b| {
            b.iter(|| k.pixel_rays())
        });
        let rays = k.pixel_rays();
        let opts = ScanOptions::default();
        c.bench_function(&format!("scan_mesh_with_rays_640x480_{name}"), |b| {
            b.iter(|| scan_mesh_with_rays(&f, &rays, None, &opts).unwrap())
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
