//! Kinect-like joint noise: Gaussian jitter, bias toward the surface, dropped joints — seeded.

use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;

use crate::geom::nearest_vertex;
use crate::poses::unit_f64;

/// What noise to add to exact joints. The default adds none.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointNoise {
    /// Standard deviation of isotropic Gaussian noise per coordinate, centimetres.
    pub sigma_cm: f64,
    /// Fraction of joints (per frame, rounded to the nearest count) moved onto the body surface
    /// (to the nearest mesh vertex) before the Gaussian noise, as a tracker that sees only the
    /// front of the body reports them.
    pub surface_fraction: f64,
    /// Fraction of joints (per frame, rounded) reported with confidence 0 (position kept).
    pub drop_fraction: f64,
    /// Seed of the ChaCha8 stream.
    pub seed: u64,
}

impl JointNoise {
    /// Whether this adds anything.
    pub fn is_none(&self) -> bool {
        self.sigma_cm == 0.0 && self.surface_fraction == 0.0 && self.drop_fraction == 0.0
    }
}

/// A standard normal draw (Box–Muller; `u1` in (0, 1]).
pub fn standard_normal(rng: &mut impl RngCore) -> f64 {
    let u1 = 1.0 - unit_f64(rng);
    let u2 = unit_f64(rng);
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// `count` distinct joint indices out of 20 (partial Fisher–Yates).
fn choose(rng: &mut impl RngCore, count: usize) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..20).collect();
    for i in 0..count.min(20) {
        let j = i + (rng.next_u64() % (20 - i) as u64) as usize;
        idx.swap(i, j);
    }
    idx.truncate(count.min(20));
    idx
}

/// Applies `noise` to exact joints of a body whose surface is `mesh` (same frame). `stream`
/// distinguishes independent draws with the same seed (e.g. the body or frame index), so that
/// output is bit-for-bit reproducible and independent of generation order.
pub fn apply_joint_noise(
    exact: &Skeleton,
    mesh: &TriMesh,
    noise: &JointNoise,
    stream: u64,
) -> Skeleton {
    let mut out = exact.clone();
    if noise.is_none() {
        return out;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(noise.seed);
    rng.set_stream(stream);
    let n_surface = (noise.surface_fraction * 20.0).round() as usize;
    for j in choose(&mut rng, n_surface) {
        out.positions[j] = mesh.positions[nearest_vertex(mesh, out.positions[j].into())].into();
    }
    let sigma = noise.sigma_cm / 100.0;
    for p in out.positions.iter_mut() {
        for c in p.iter_mut() {
            *c += sigma * standard_normal(&mut rng);
        }
    }
    let n_drop = (noise.drop_fraction * 20.0).round() as usize;
    for j in choose(&mut rng, n_drop) {
        out.confidence[j] = 0.0;
    }
    out
}
