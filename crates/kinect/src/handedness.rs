//! Is a skeleton's left/right consistent with a mesh? A tracker (or a converter) that swapped the
//! subject's sides produces a skeleton whose torso frame faces backwards: with left = the
//! subject's left and up = shoulder_center − hip_center, the facing direction is
//! `f = (left − right) × up` (DESIGN.md conventions; a subject facing a Kinect faces −z). The
//! mesh tells which way the body really faces: **feet point forward**. For each foot, the mesh
//! vertices near the floor end of the leg (below the ankle + 30 % of the shin, within one shin
//! length of the ankle horizontally) have a centroid ahead of the ankle along the true facing
//! direction. A positive mean offset along `f` means the skeleton is consistent; a negative one
//! means its sides are swapped relative to the surface.
//!
//! The skeleton and the mesh must be in the same frame (e.g. both in Kinect camera space, or the
//! skeleton already aligned to the mesh).

use crate::geom::{cross, dot, norm, normalize, scale, sub};
use symcorr_attach::{Joint, Skeleton};
use symcorr_mesh::TriMesh;

/// Verdict of [`check_handedness`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Handedness {
    /// The skeleton's facing direction agrees with the mesh.
    Consistent,
    /// Left and right are swapped relative to the mesh (use `Skeleton::swap_sides`).
    Swapped,
    /// The mesh gives no usable cue (no foot geometry found, or the offset is too small).
    Undetermined,
}

/// What [`check_handedness`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct HandednessReport {
    /// The verdict.
    pub verdict: Handedness,
    /// The skeleton's facing direction (unit), `(left − right) × up`.
    pub facing: [f64; 3],
    /// Mean offset (metres) of the foot geometry ahead of the ankles along `facing`.
    pub foot_offset_m: f64,
    /// Number of mesh vertices used.
    pub vertices_used: usize,
}

/// Checks a skeleton's left/right against a mesh (module docs). `min_offset_m` is the smallest
/// foot offset that counts as evidence (1 cm is a good default).
pub fn check_handedness(
    skeleton: &Skeleton,
    mesh: &TriMesh,
    min_offset_m: f64,
) -> HandednessReport {
    let p = |j: Joint| skeleton.position(j);
    let up = sub(p(Joint::ShoulderCenter), p(Joint::HipCenter));
    let left = {
        let s = sub(p(Joint::ShoulderLeft), p(Joint::ShoulderRight));
        let h = sub(p(Joint::HipLeft), p(Joint::HipRight));
        [s[0] + h[0], s[1] + h[1], s[2] + h[2]]
    };
    let undetermined = |facing: [f64; 3]| HandednessReport {
        verdict: Handedness::Undetermined,
        facing,
        foot_offset_m: 0.0,
        vertices_used: 0,
    };
    let (Some(up_n), Some(facing)) = (normalize(up), normalize(cross(left, up))) else {
        return undetermined([0.0; 3]);
    };
    let mut offsets = Vec::new();
    let mut used = 0;
    for (knee, ankle) in [
        (Joint::KneeLeft, Joint::AnkleLeft),
        (Joint::KneeRight, Joint::AnkleRight),
    ] {
        let a = p(ankle);
        let shin = norm(sub(p(knee), a));
        if shin <= 0.0 {
            continue;
        }
        let top = 0.3 * shin;
        let mut sum = 0.0;
        let mut n = 0usize;
        for &v in &mesh.positions {
            let d = sub(v, a);
            let h = dot(d, up_n);
            if h > top {
                continue;
            }
            let horizontal = sub(d, scale(up_n, h));
            if norm(horizontal) > shin {
                continue;
            }
            sum += dot(horizontal, facing);
            n += 1;
        }
        if n > 0 {
            offsets.push(sum / n as f64);
            used += n;
        }
    }
    if offsets.is_empty() {
        return undetermined(facing);
    }
    let offset = offsets.iter().sum::<f64>() / offsets.len() as f64;
    let verdict = if offset >= min_offset_m {
        Handedness::Consistent
    } else if offset <= -min_offset_m {
        Handedness::Swapped
    } else {
        Handedness::Undetermined
    };
    HandednessReport {
        verdict,
        facing,
        foot_offset_m: offset,
        vertices_used: used,
    }
}
