//! Is a skeleton's left/right consistent with a mesh? A tracker (or a converter) that swapped the
//! subject's sides produces a skeleton whose torso frame faces backwards: with left = the
//! subject's left and up = shoulder_center − hip_center, the facing direction is
//! `f = (left − right) × up` (DESIGN.md conventions; a subject facing a Kinect faces −z).
//!
//! The check itself belongs to symcorr-attach ([`symcorr_attach::check_handedness`], the one
//! `attach` uses to fix a swapped skeleton): the surface around each ankle reaches farther
//! forward (toes) than backward (heel) along the facing direction carried into that shin's
//! frame, the ankle→foot joints point forward, and bent knees lie in front of the hip–ankle
//! line. This module turns its evidence into a verdict for a mesh (e.g. a scan): a verdict
//! needs foot geometry in the mesh and combined evidence beyond
//! [`symcorr_attach::MIRROR_MARGIN`].
//!
//! The skeleton and the mesh must be in the same frame (e.g. both in Kinect camera space, or the
//! skeleton already aligned to the mesh).

use symcorr_attach::MIRROR_MARGIN;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;

/// Verdict of [`check_handedness`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Handedness {
    /// The skeleton's facing direction agrees with the mesh.
    Consistent,
    /// Left and right are swapped relative to the mesh (use `Skeleton::swap_sides`).
    Swapped,
    /// The mesh gives no usable cue (no foot geometry found, or the evidence is too weak).
    Undetermined,
}

/// What [`check_handedness`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct HandednessReport {
    /// The verdict.
    pub verdict: Handedness,
    /// The skeleton's facing direction (unit), `(left − right) × up`.
    pub facing: [f64; 3],
    /// How much farther (metres, for a mesh in metres) the surface around the ankles reaches
    /// forward than backward along `facing`, mean over the feet.
    pub foot_offset_m: f64,
    /// Number of mesh vertices used.
    pub vertices_used: usize,
    /// symcorr-attach's combined evidence (positive: consistent).
    pub evidence: f64,
}

/// Checks a skeleton's left/right against a mesh (module docs). `min_offset_m` is the smallest
/// foot offset that counts as evidence (1 cm is a good default); the combined evidence must also
/// exceed [`symcorr_attach::MIRROR_MARGIN`].
pub fn check_handedness(
    skeleton: &Skeleton,
    mesh: &TriMesh,
    min_offset_m: f64,
) -> HandednessReport {
    let undetermined = HandednessReport {
        verdict: Handedness::Undetermined,
        facing: [0.0; 3],
        foot_offset_m: 0.0,
        vertices_used: 0,
        evidence: 0.0,
    };
    // An empty mesh or a skeleton without usable joints: nothing to decide.
    let Ok(check) = symcorr_attach::check_handedness(mesh, skeleton) else {
        return undetermined;
    };
    let facing = check.facing.unwrap_or([0.0; 3]);
    let evidence = check.evidence();
    let Some(offset) = check.mesh_offset else {
        return HandednessReport {
            facing,
            evidence,
            ..undetermined
        };
    };
    let verdict = if offset >= min_offset_m && evidence > MIRROR_MARGIN {
        Handedness::Consistent
    } else if offset <= -min_offset_m && check.says_swapped() {
        Handedness::Swapped
    } else {
        Handedness::Undetermined
    };
    HandednessReport {
        verdict,
        facing,
        foot_offset_m: offset,
        vertices_used: check.mesh_vertices,
        evidence,
    }
}
