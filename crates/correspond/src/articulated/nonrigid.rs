//! The non-rigid step of the articulated method (DESIGN.md, Algorithm 7, step 5): what rigid
//! bones blended by skinning weights cannot express (another rig's skinning, soft tissue,
//! body shape) is pulled in by a smooth displacement field over the template's edge graph.

use super::Alignment;
use crate::CorrespondError;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Jacobi iterations per round of the non-rigid step.
const NONRIGID_JACOBI: usize = 30;

/// Vertices per parallel task of a Jacobi sweep (a vertex's update is a few dozen flops).
const JACOBI_CHUNK: usize = 1024;

/// Scale σ of the Geman–McClure weight of a held pair, as a fraction of the round's gate.
const ROBUST_SCALE: f64 = 0.5;

/// How much of a pair's offset along the target's tangent plane the field follows: the
/// nearest scan vertex is a sample of the surface, and its tangential offset is mostly where
/// the sampling fell (and a depth sensor's noise is along the line of sight).
const TANGENTIAL_SHARE: f64 = 0.3;

/// Moves `posed` by `rounds` rounds
/// ([`ArticulatedOptions::nonrigid_rounds`](crate::ArticulatedOptions) or, from a warm start,
/// `warm_nonrigid_rounds`) of a smooth displacement field; nothing without the template's edge
/// graph (`neighbors`, one list per vertex). Each round pairs every posed vertex with its nearest
/// pool vertex, keeps the pairs that hold at the round's gate (coarse to fine, from
/// `nonrigid_gate_start` to `gate_end`, so a body part further off than the final gate — a
/// heavier shape's belly — is pulled in by the early rounds), and spreads their offsets `d_v`
/// by Jacobi iterations of `min Σ r_v|s_v − d_v|² + λ Σ_edges |s_u − s_v|²` (`r_v` 0 without
/// a held pair). On a whole surface `d_v` is the offset and `r_v` 1. On a sensor's view (a
/// target with a border, [`Alignment::is_scan`]) `d_v` is the offset's component along the
/// target's normal plus [`TANGENTIAL_SHARE`] of the rest, and `r_v` the Geman–McClure IRLS
/// weight `(σ²/(σ² + |x_v − y_v|²))²`
/// with σ = [`ROBUST_SCALE`]·gate (Geman & McClure 1987; Black & Rangarajan 1996, the
/// outlier-process view): the gate truncates, and within it a far pair — a sensor outlier, a
/// flying pixel at a silhouette — pulls less than a near one. The normals stay those of the
/// skinning. `hints` (the matches before
/// this step) start the first round's searches; returns the last round's matches, or `hints`
/// when no round ran.
pub(super) fn nonrigid_step(
    al: &Alignment<'_>,
    posed: &mut [Point3<f64>],
    posed_normals: &[Vector3<f64>],
    hints: Vec<(u32, f64)>,
    rounds: usize,
) -> Result<Vec<(u32, f64)>, CorrespondError> {
    let options = al.options;
    let n = posed.len();
    let Some(nb) = al.template.neighbors.filter(|nb| nb.len() == n) else {
        return Ok(hints);
    };
    // The edge graph as compressed rows (offsets, then neighbours in the lists' order): the
    // Jacobi sweeps read it thirty times per round.
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0usize);
    for list in nb {
        offsets.push(offsets[offsets.len() - 1] + list.len());
    }
    let adjacent: Vec<u32> = nb.iter().flatten().copied().collect();
    let mut hints = hints;
    let scan = al.is_scan();
    let g0 = options.nonrigid_gate_start.max(options.gate_end);
    for round in 0..rounds {
        let frac = if rounds > 1 {
            round as f64 / (rounds - 1) as f64
        } else {
            1.0
        };
        let round_gate = al.unit_len * g0 * (options.gate_end / g0).powf(frac);
        let visible = al.visibility(posed, posed_normals);
        let (near, reverse) = al.candidates_and_reverse(
            posed,
            posed_normals,
            None,
            visible.as_deref(),
            round_gate,
            Some(&hints),
        )?;
        let held = al.held(
            posed,
            posed_normals,
            &near,
            visible.as_deref(),
            round_gate,
            reverse.as_ref(),
            true,
        );
        let mut d = vec![Vector3::zeros(); n];
        let mut r = vec![0.0; n];
        let s2 = (ROBUST_SCALE * round_gate).powi(2);
        for (v, &(q, _)) in near.iter().enumerate() {
            if held[v] {
                let offset = al.target_positions[q as usize] - posed[v];
                if scan {
                    let normal = al.target_normals[q as usize];
                    let along = normal * normal.dot(&offset);
                    d[v] = along + (offset - along) * TANGENTIAL_SHARE;
                    r[v] = (s2 / (s2 + offset.norm_squared())).powi(2);
                } else {
                    d[v] = offset;
                    r[v] = 1.0;
                }
            }
        }
        let lambda = options.nonrigid_smoothing;
        // Per vertex, its data term and the factor of its update (0 where nothing pulls).
        let data: Vec<Vector3<f64>> = (0..n).map(|v| d[v] * r[v]).collect();
        let scale: Vec<f64> = (0..n)
            .map(|v| {
                let wsum = r[v] + lambda * nb[v].len() as f64;
                if wsum > 0.0 {
                    1.0 / wsum
                } else {
                    0.0
                }
            })
            .collect();
        // Two buffers swapped between sweeps: a sweep allocates nothing.
        let mut field = d;
        let mut next = vec![Vector3::zeros(); n];
        for _ in 0..NONRIGID_JACOBI {
            next.par_iter_mut()
                .with_min_len(JACOBI_CHUNK)
                .enumerate()
                .for_each(|(v, out)| {
                    let mut acc = data[v];
                    for &u in &adjacent[offsets[v]..offsets[v + 1]] {
                        acc += field[u as usize] * lambda;
                    }
                    *out = if scale[v] > 0.0 {
                        acc * scale[v]
                    } else {
                        Vector3::zeros()
                    };
                });
            std::mem::swap(&mut field, &mut next);
        }
        for (x, f) in posed.iter_mut().zip(&field) {
            *x += f;
        }
        hints = near;
    }
    Ok(hints)
}
