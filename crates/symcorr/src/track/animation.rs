//! The animated template of a tracked recording (`template_track.glb`): the template following
//! the recording, built from the posed template per frame that `symcorr track` streams into
//! `posed.npy` (float32, frames × template vertices × 3, camera space in metres; NaN rows for
//! frames without a pose).
//!
//! The GLB (written by [`symcorr_mesh::io::gltf::MorphAnimationWriter`]) holds the template's
//! rest mesh, one morph target per kept posed frame (its displacement from the rest positions)
//! and an animation that shows target k at that frame's time, relative to the first frame of
//! the run, with positions blended linearly between two kept frames. Frames without a pose
//! (skipped, or a method that poses nothing) are left out: the animation passes from the pose
//! before them to the pose after them. A long run keeps at most [`max_targets`] frames, chosen
//! evenly ([`decimate`], first and last kept): the animation's weights are targets² floats
//! and every target is a copy of the mesh, so both the file and a viewer's load grow with it.

use crate::npy::{NpyError, NpyReader, NpyType};
use std::path::Path;
use symcorr_mesh::io::gltf::{MorphAnimationWriter, MorphInterpolation};
use symcorr_mesh::io::OutputBatch;
use symcorr_mesh::{MeshError, TriMesh};

/// Most morph targets in a `template_track.glb`: weights of 600 × 600 floats (1.4 MB), and
/// within the texture-array layers WebGL 2 viewers (three.js) commonly allow.
pub const MAX_TARGETS: usize = 600;

/// Most bytes of morph targets in a `template_track.glb` (1 GiB): a large template keeps
/// fewer than [`MAX_TARGETS`] frames.
pub const MAX_TARGET_BYTES: u64 = 1 << 30;

/// The most frames a template of `vertices` vertices keeps: [`MAX_TARGETS`], fewer when their
/// displacements would pass [`MAX_TARGET_BYTES`], at least 1.
///
/// ```
/// use symcorr::track::animation::{max_targets, MAX_TARGETS};
/// assert_eq!(max_targets(13380), MAX_TARGETS);
/// assert_eq!(max_targets(1_000_000), 89);
/// ```
pub fn max_targets(vertices: usize) -> usize {
    let per_target = 12 * vertices.max(1) as u64;
    let by_bytes = usize::try_from(MAX_TARGET_BYTES / per_target).unwrap_or(usize::MAX);
    MAX_TARGETS.min(by_bytes).max(1)
}

/// `keep` of `count` items chosen evenly: all of them when `count ≤ keep`, else the items
/// nearest to `keep` evenly spaced positions from the first to the last (both kept).
///
/// ```
/// use symcorr::track::animation::decimate;
/// assert_eq!(decimate(4, 10), [0, 1, 2, 3]);
/// assert_eq!(decimate(10, 4), [0, 3, 6, 9]);
/// assert_eq!(decimate(10, 1), [0]);
/// ```
pub fn decimate(count: usize, keep: usize) -> Vec<usize> {
    if count <= keep {
        return (0..count).collect();
    }
    if keep <= 1 {
        return (0..keep.min(count)).collect();
    }
    // round(i (count − 1) / (keep − 1)): consecutive positions are at least 1 apart, so the
    // rounded ones strictly increase.
    let (a, b) = (count - 1, keep - 1);
    (0..keep).map(|i| (2 * i * a + b) / (2 * b)).collect()
}

/// One row of `posed.npy`, as the track's journal describes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PosedRow {
    /// The recording's frame number.
    pub frame: usize,
    /// The frame's time, seconds (depth stream clock).
    pub time_s: f64,
    /// Whether the row holds a pose (otherwise it is NaN).
    pub posed: bool,
}

/// What [`stage_template_track`] staged.
#[derive(Debug, Clone, PartialEq)]
pub struct TemplateTrack {
    /// Rows of the run with a pose.
    pub posed_frames: usize,
    /// Morph targets in the file (kept frames).
    pub targets: usize,
    /// The cap it was decimated to ([`max_targets`]).
    pub max_targets: usize,
    /// The recording's frame numbers of the kept frames, in order.
    pub kept_frames: Vec<usize>,
    /// Size of the file, bytes.
    pub bytes: u64,
}

/// Why `template_track.glb` could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TemplateTrackError {
    /// `posed.npy` could not be read.
    #[error(transparent)]
    Npy(#[from] NpyError),
    /// The GLB could not be written.
    #[error("template_track.glb: {0}")]
    Mesh(#[from] MeshError),
}

/// Stages `glb` in `batch`: the animated template (module docs) of `template` (the template's
/// input mesh, whose vertices are `posed.npy`'s) from the first `rows.len()` rows of `posed_npy`
/// (a file of `rows_in_file` rows), at most `max_targets` of them. Reads one row at a time;
/// the morph targets wait in a scratch file next to `glb`. `Ok(None)` when no row has a pose
/// (nothing staged).
///
/// Errors: [`TemplateTrackError::Npy`] when `posed_npy` is not that file or ends early;
/// [`TemplateTrackError::Mesh`] from the writer (a NaN in a posed row, a time out of order).
pub fn stage_template_track(
    batch: &mut OutputBatch,
    glb: &Path,
    template: &TriMesh,
    posed_npy: &Path,
    rows_in_file: usize,
    rows: &[PosedRow],
    max_targets: usize,
) -> Result<Option<TemplateTrack>, TemplateTrackError> {
    let posed: Vec<usize> = (0..rows.len()).filter(|&r| rows[r].posed).collect();
    if posed.is_empty() {
        return Ok(None);
    }
    let n = template.num_vertices();
    let mut reader = NpyReader::open(posed_npy, NpyType::F32, rows_in_file, &[n, 3])?;
    let scratch_dir = match glb.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut writer = MorphAnimationWriter::new(template, MorphInterpolation::Linear, scratch_dir)?;
    let t0 = rows[0].time_s;
    let mut flat = Vec::with_capacity(3 * n);
    let mut kept_frames = Vec::new();
    for i in decimate(posed.len(), max_targets) {
        let row = posed[i];
        reader.read_f32(row, &mut flat)?;
        let positions: Vec<[f32; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let frame = rows[row].frame;
        writer.push(
            &format!("frame {frame:06}"),
            (rows[row].time_s - t0) as f32,
            &positions,
        )?;
        kept_frames.push(frame);
    }
    let bytes = writer.finish(batch, glb)?;
    Ok(Some(TemplateTrack {
        posed_frames: posed.len(),
        targets: kept_frames.len(),
        max_targets,
        kept_frames,
        bytes,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::npy::NpyWriter;

    #[test]
    fn decimation_is_even_strictly_increasing_and_keeps_both_ends() {
        for count in 1..60 {
            for keep in 1..70 {
                let d = decimate(count, keep);
                assert_eq!(d.len(), count.min(keep), "{count} {keep}");
                assert!(d.windows(2).all(|w| w[0] < w[1]));
                assert_eq!(d[0], 0);
                if keep > 1 {
                    assert_eq!(*d.last().unwrap(), count - 1);
                }
            }
        }
        assert_eq!(decimate(0, 5), Vec::<usize>::new());
        assert_eq!(decimate(20_000, 600).len(), 600);
    }

    /// Rows without a pose are left out, the rest decimated; each kept target reconstructs its
    /// row of posed.npy (checked by splitting the GLB by hand).
    #[test]
    fn kept_rows_reconstruct_the_posed_rows() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let npy = dir.path().join("posed.npy");
        let mut w = NpyWriter::create_shaped(&npy, NpyType::F32, 6, &[3, 3]).unwrap();
        let pose = |r: usize| -> Vec<f32> { (0..9).map(|c| r as f32 * 0.25 + c as f32).collect() };
        let mut rows = Vec::new();
        for r in 0..5 {
            let posed = r != 1;
            w.push_f32(&if posed { pose(r) } else { vec![f32::NAN; 9] })
                .unwrap();
            rows.push(PosedRow {
                frame: 10 + r,
                time_s: 3.0 + r as f64 / 30.0,
                posed,
            });
        }
        drop(w);
        let glb = dir.path().join("t.glb");
        let mut batch = OutputBatch::new();
        let t = stage_template_track(&mut batch, &glb, &mesh, &npy, 6, &rows, 3)
            .unwrap()
            .unwrap();
        batch.commit().unwrap();
        assert_eq!((t.posed_frames, t.targets), (4, 3));
        // Posed rows 0, 2, 3, 4 → decimated to their 0th, 2nd (rounded 1.5) and 3rd.
        assert_eq!(t.kept_frames, [10, 13, 14]);
        let bytes = std::fs::read(&glb).unwrap();
        assert_eq!(bytes.len() as u64, t.bytes);
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let bin = &bytes[20 + json_len + 8..];
        let floats = |view: usize, count: usize| -> Vec<f32> {
            let off = doc["bufferViews"][view]["byteOffset"].as_u64().unwrap() as usize;
            bin[off..off + 4 * count]
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                .collect()
        };
        let rest = floats(0, 9);
        for (k, row) in [0usize, 3, 4].into_iter().enumerate() {
            let d = floats(2 + k, 9);
            let got: Vec<f32> = rest.iter().zip(&d).map(|(a, b)| a + b).collect();
            assert_eq!(got, pose(row));
        }
        let times = floats(5, 3);
        let want = [0.0, 3.0 / 30.0, 4.0 / 30.0].map(|t: f64| t as f32);
        for (a, b) in times.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "{times:?}");
        }
        // No pose at all: nothing staged.
        let none: Vec<PosedRow> = rows
            .iter()
            .map(|r| PosedRow { posed: false, ..*r })
            .collect();
        let mut batch = OutputBatch::new();
        assert!(
            stage_template_track(&mut batch, &glb, &mesh, &npy, 6, &none, 3)
                .unwrap()
                .is_none()
        );
    }
}
