//! Shared helpers for the attachment tests: area-weighted agreement, the capsule body's
//! unambiguous region, a seeded random generator.
#![allow(dead_code)]

use nalgebra::Point3;
use symcorr_attach::testbody::RADII;
use symcorr_attach::{Segment, Skeleton, BONES};
use symcorr_mesh::TriMesh;

/// `(area fraction with got == want, area fraction with got == mirror(want) ≠ want)` over the
/// vertices where `mask` holds.
pub fn agreement(m: &TriMesh, got: &[Segment], want: &[Segment], mask: &[bool]) -> (f64, f64) {
    let a = m.vertex_areas();
    let (mut total, mut same, mut mirror) = (0.0, 0.0, 0.0);
    for v in 0..a.len() {
        if !mask[v] {
            continue;
        }
        total += a[v];
        if got[v] == want[v] {
            same += a[v];
        } else if want[v].mirror() != want[v] && got[v] == want[v].mirror() {
            mirror += a[v];
        }
    }
    (same / total, mirror / total)
}

fn seg_dist(x: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let [x, a, b] = [x, a, b].map(Point3::from);
    let (ab, ax) = (b - a, x - a);
    let t = (ax.dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (ax - ab * t).norm()
}

/// Vertices at least `margin` away from every capsule but the nearest one, whose nearest bone is
/// that capsule's bone: there the capsule body's reference label is unambiguous (where capsules
/// overlap, "nearest capsule" is not a meaningful ground truth). `sk` is the exact skeleton
/// (metres).
pub fn unambiguous(m: &TriMesh, sk: &Skeleton, margin: f64) -> Vec<bool> {
    m.positions
        .iter()
        .map(|&x| {
            let raw: Vec<f64> = BONES
                .iter()
                .map(|b| seg_dist(x, sk.position(b.parent).into(), sk.position(b.child).into()))
                .collect();
            let argmin = |d: &[f64]| (0..d.len()).min_by(|&a, &b| d[a].total_cmp(&d[b]));
            let mut d: Vec<f64> = raw.iter().zip(RADII).map(|(r, c)| r - c).collect();
            let same = argmin(&d) == argmin(&raw);
            d.sort_by(f64::total_cmp);
            same && d[1] - d[0] > margin
        })
        .collect()
}

/// Small deterministic generator (SplitMix64) with normal deviates (Box–Muller).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let u = self.uniform().max(1e-300);
        let v = self.uniform();
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// Exact joints perturbed as in the benchmark datasets: Gaussian noise of `sigma` per coordinate, and a
/// fraction `biased` of the joints moved onto the surface (to the nearest mesh vertex).
pub fn noisy(sk: &Skeleton, mesh: &TriMesh, sigma: f64, biased: f64, rng: &mut Rng) -> Skeleton {
    let mut out = sk.clone();
    for j in 0..20 {
        let p = &mut out.positions[j];
        if rng.uniform() < biased {
            let x = *p;
            *p = mesh
                .positions
                .iter()
                .copied()
                .min_by(|a, b| {
                    let da: f64 = (0..3).map(|k| (a[k] - x[k]).powi(2)).sum();
                    let db: f64 = (0..3).map(|k| (b[k] - x[k]).powi(2)).sum();
                    da.total_cmp(&db)
                })
                .unwrap()
                .into();
        }
        for c in p.iter_mut() {
            *c += sigma * rng.normal();
        }
    }
    out
}
