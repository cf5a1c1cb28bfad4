//! Tracker-like joints for a single-view scan: what a skeleton tracker reports, not the rig.
//!
//! Per joint and coordinate, Gaussian noise of σ = [`TrackerNoise::sigma_cm`] (2.5 cm), and
//! [`TrackerNoise::extremity_sigma_cm`] (4.5 cm) at the hands and feet, whose small, fast
//! parts trackers place worst. A joint is *seen* when, within [`VISIBILITY_RADIUS_M`] of its
//! pixel, the view shows a vertex of a segment the joint belongs to (its reference labels, e.g.
//! the elbow: upper arm or forearm). A joint not seen — the far-side shoulder, hip or knee in a
//! profile view, a hand behind the back — is *inferred*, as Kinect-style trackers report it:
//! pulled along its viewing ray to [`TrackerNoise::inferred_depth_m`] behind the visible
//! surface there (the median depth reading in the window) when that is nearer, given
//! confidence [`INFERRED_CONFIDENCE`] and twice the noise. All draws come from one seeded
//! ChaCha8 stream per body (bit-for-bit reproducible).

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use symcorr_kinect::Intrinsics;
use symcorr_skeleton::{Joint, Segment, Skeleton};

use crate::noise::standard_normal;
use crate::render::{Rendering, NO_VERTEX};

/// Confidence of an inferred joint (the Kinect SDK's "inferred" tracking state).
pub const INFERRED_CONFIDENCE: f64 = 0.5;

/// Half-width of the window around a joint's pixel searched for its segments, metres at the
/// joint's depth.
pub const VISIBILITY_RADIUS_M: f64 = 0.04;

/// The tracker model's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerNoise {
    /// Noise per coordinate of the trunk, head and limb joints, centimetres.
    pub sigma_cm: f64,
    /// Noise per coordinate of the hands and feet, centimetres.
    pub extremity_sigma_cm: f64,
    /// How far behind the visible surface an inferred joint is put, metres.
    pub inferred_depth_m: f64,
    /// Seed of the ChaCha8 stream.
    pub seed: u64,
}

impl TrackerNoise {
    /// σ = 2.5 cm, 4.5 cm at hands and feet, inferred joints 5 cm behind the visible surface.
    pub fn kinect_v1(seed: u64) -> TrackerNoise {
        TrackerNoise {
            sigma_cm: 2.5,
            extremity_sigma_cm: 4.5,
            inferred_depth_m: 0.05,
            seed,
        }
    }
}

/// The segments a joint belongs to (it is seen when one of them is).
pub fn joint_segments(j: Joint) -> &'static [Segment] {
    use Joint as J;
    use Segment as S;
    match j {
        J::HipCenter => &[S::Pelvis, S::HipLeft, S::HipRight],
        J::Spine => &[S::Torso, S::Pelvis],
        J::ShoulderCenter => &[S::Torso, S::Head, S::ClavicleLeft, S::ClavicleRight],
        J::Head => &[S::Head],
        J::ShoulderLeft => &[S::ClavicleLeft, S::UpperArmLeft],
        J::ShoulderRight => &[S::ClavicleRight, S::UpperArmRight],
        J::ElbowLeft => &[S::UpperArmLeft, S::ForearmLeft],
        J::ElbowRight => &[S::UpperArmRight, S::ForearmRight],
        J::WristLeft | J::HandLeft => &[S::ForearmLeft],
        J::WristRight | J::HandRight => &[S::ForearmRight],
        J::HipLeft => &[S::HipLeft, S::ThighLeft],
        J::HipRight => &[S::HipRight, S::ThighRight],
        J::KneeLeft => &[S::ThighLeft, S::ShinLeft],
        J::KneeRight => &[S::ThighRight, S::ShinRight],
        J::AnkleLeft => &[S::ShinLeft, S::FootLeft],
        J::AnkleRight => &[S::ShinRight, S::FootRight],
        J::FootLeft => &[S::FootLeft],
        J::FootRight => &[S::FootRight],
    }
}

/// Whether a joint is a hand or a foot.
fn is_extremity(j: Joint) -> bool {
    matches!(
        j,
        Joint::HandLeft | Joint::HandRight | Joint::FootLeft | Joint::FootRight
    )
}

/// Tracker joints from exact camera-space joints `exact`, the view `view` (rendered with
/// intrinsics `k`) and the reference segment label of every mesh vertex. `stream` separates
/// the draws of different bodies. Returns the joints and which were inferred.
pub fn tracker_joints(
    exact: &Skeleton,
    view: &Rendering,
    k: &Intrinsics,
    labels: &[u8],
    noise: &TrackerNoise,
    stream: u64,
) -> (Skeleton, [bool; Joint::COUNT]) {
    let mut rng = ChaCha8Rng::seed_from_u64(noise.seed);
    rng.set_stream(stream);
    let mut out = exact.clone();
    let mut inferred = [false; Joint::COUNT];
    let (w, h) = (view.width as i64, view.height as i64);
    for (ji, &joint) in Joint::ALL.iter().enumerate() {
        let p = exact.positions[ji];
        let mut seen = false;
        let mut readings = Vec::new();
        let [u, v] = k.project(&p);
        if p.z > 0.0 && u.is_finite() && v.is_finite() {
            let r = (k.fx * VISIBILITY_RADIUS_M / p.z).ceil() as i64;
            let (uc, vc) = (u.round() as i64, v.round() as i64);
            let segs = joint_segments(joint);
            for vv in (vc - r).max(0)..=(vc + r).min(h - 1) {
                for uu in (uc - r).max(0)..=(uc + r).min(w - 1) {
                    let i = (vv * w + uu) as usize;
                    let id = view.vertex_id[i];
                    if id != NO_VERTEX {
                        let hit = labels
                            .get(id as usize)
                            .is_some_and(|&l| segs.iter().any(|s| *s as u8 == l));
                        seen |= hit;
                    }
                    if view.depth_mm[i] > 0 {
                        readings.push(view.depth_mm[i]);
                    }
                }
            }
        }
        let mut sigma = if is_extremity(joint) {
            noise.extremity_sigma_cm
        } else {
            noise.sigma_cm
        } / 100.0;
        if !seen {
            inferred[ji] = true;
            out.confidence[ji] = INFERRED_CONFIDENCE;
            sigma *= 2.0;
            if !readings.is_empty() {
                readings.sort_unstable();
                let surface = f64::from(readings[readings.len() / 2]) / 1000.0;
                let z = surface + noise.inferred_depth_m;
                if z < p.z {
                    // Along the viewing ray: the joint stays on its pixel.
                    out.positions[ji] = (p.coords * (z / p.z)).into();
                }
            }
        }
        for c in out.positions[ji].iter_mut() {
            *c += sigma * standard_normal(&mut rng);
        }
    }
    (out, inferred)
}
