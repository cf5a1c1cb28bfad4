//! A left/right verdict for a skeleton against a mesh (e.g. a single-view scan), from the
//! evidence of [`check_handedness`](crate::check_handedness): a verdict needs foot geometry in
//! the mesh that reaches at least `min_offset_m` farther forward than backward, and combined
//! evidence beyond [`MIRROR_MARGIN`]; anything weaker is [`Handedness::Undetermined`]. A
//! skeleton whose shoulders and hips point opposite ways across the spine has one limb pair
//! exchanged; the verdict names it ([`Handedness::LimbsSwapped`]) when the evidence tells
//! which, as [`attach`](crate::attach) decides before it swaps that pair back.
//!
//! The skeleton and the mesh must be in the same frame (e.g. both in Kinect camera space, or the
//! skeleton already aligned to the mesh).

use crate::{check_handedness, LimbPair, Skeleton, MIRROR_MARGIN};
use nalgebra::Vector3;
use symcorr_mesh::TriMesh;

/// Verdict of [`handedness_verdict`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Handedness {
    /// The skeleton's facing direction agrees with the mesh.
    Consistent,
    /// Left and right are swapped relative to the mesh (use [`Skeleton::swap_sides`]).
    Swapped,
    /// One limb pair's left and right are exchanged against the rest of the skeleton (a
    /// tracker's arm or leg swap; use [`Skeleton::swap_limbs`]); the facing evidence is that of
    /// the skeleton with the pair swapped back.
    LimbsSwapped(LimbPair),
    /// The mesh gives no usable cue (no foot geometry found, or the evidence is too weak).
    Undetermined,
}

/// What [`handedness_verdict`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct HandednessReport {
    /// The verdict.
    pub verdict: Handedness,
    /// The skeleton's facing direction (unit), `(left − right) × up`; zero if the torso is
    /// degenerate.
    pub facing: Vector3<f64>,
    /// How much farther (metres, for a mesh in metres) the surface around the ankles reaches
    /// forward than backward along `facing`, mean over the feet.
    pub foot_offset_m: f64,
    /// Number of mesh vertices used.
    pub vertices_used: usize,
    /// The combined evidence ([`MirrorCheck::evidence`](crate::MirrorCheck::evidence);
    /// positive: consistent).
    pub evidence: f64,
}

/// Checks `skeleton`'s left/right against `mesh` (module docs). `min_offset_m` is the smallest
/// foot offset that counts as evidence (1 cm is a good default). Never fails: an empty mesh or
/// a skeleton without usable joints is [`Handedness::Undetermined`].
///
/// ```
/// use symcorr_attach::{handedness_verdict, Handedness};
/// # let (mesh, skeleton) = symcorr_attach::doc_example();
/// let r = handedness_verdict(&mesh, &skeleton, 0.01);
/// assert_ne!(r.verdict, Handedness::Swapped);
/// ```
pub fn handedness_verdict(
    mesh: &TriMesh,
    skeleton: &Skeleton,
    min_offset_m: f64,
) -> HandednessReport {
    let undetermined = HandednessReport {
        verdict: Handedness::Undetermined,
        facing: Vector3::zeros(),
        foot_offset_m: 0.0,
        vertices_used: 0,
        evidence: 0.0,
    };
    let Ok(check) = check_handedness(mesh, skeleton) else {
        return undetermined;
    };
    let swapped_limbs = check.swapped_limbs;
    let facing = check.facing.unwrap_or_else(Vector3::zeros);
    let evidence = check.evidence();
    let Some(offset) = check.mesh_offset else {
        return HandednessReport {
            verdict: swapped_limbs.map_or(Handedness::Undetermined, Handedness::LimbsSwapped),
            facing,
            evidence,
            ..undetermined
        };
    };
    let verdict = if let Some(pair) = swapped_limbs {
        Handedness::LimbsSwapped(pair)
    } else if offset >= min_offset_m && evidence > MIRROR_MARGIN {
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
