//! `posed.npy` and `template_track.glb` of `symcorr track`: the template posed onto each frame,
//! streamed row by row like the correspondence, and at the end of the run the animated
//! template built from it ([`symcorr::track::animation`]).

use super::report::FrameDigest;
use super::CliError;
use serde_json::{json, Value};
use std::path::Path;
use symcorr::npy::{NpyType, NpyWriter};
use symcorr::track::animation::{max_targets, stage_template_track, PosedRow};
use symcorr_mesh::io::OutputBatch;
use symcorr_mesh::TriMesh;

/// The posed template per frame: float32, frames × template vertices × 3.
pub(super) const POSED_NPY: &str = "posed.npy";
/// The animated template.
pub(super) const TEMPLATE_GLB: &str = "template_track.glb";

fn npy_err(e: symcorr::npy::NpyError) -> CliError {
    CliError(e.to_string())
}

/// `posed.npy` in `out` for a run of `rows` frames of a template of `n` vertices: created, or
/// with `resume_after: Some(k)` reopened after its first k rows. A folder whose run started
/// before posed.npy was written gets the file with NaN rows for the frames already done.
pub(super) fn open(
    out: &Path,
    rows: usize,
    n: usize,
    resume_after: Option<usize>,
) -> Result<NpyWriter, CliError> {
    let path = out.join(POSED_NPY);
    match resume_after {
        Some(k) if path.exists() => {
            NpyWriter::resume_shaped(&path, NpyType::F32, rows, &[n, 3], k).map_err(npy_err)
        }
        _ => {
            let mut w =
                NpyWriter::create_shaped(&path, NpyType::F32, rows, &[n, 3]).map_err(npy_err)?;
            for _ in 0..resume_after.unwrap_or(0) {
                push(&mut w, None, n)?;
            }
            Ok(w)
        }
    }
}

/// Appends a frame's row: the posed template, or NaN where the frame has none (skipped, or a
/// method that poses nothing).
pub(super) fn push(
    w: &mut NpyWriter,
    posed: Option<&[[f32; 3]]>,
    n: usize,
) -> Result<(), CliError> {
    match posed {
        Some(p) => w.push_f32(p.as_flattened()),
        None => w.push_f32(&vec![f32::NAN; 3 * n]),
    }
    .map_err(npy_err)
}

/// Stages `out`'s `template_track.glb` in `batch` from the `done` frames' rows of `posed_npy`
/// (a file of `total` rows: the run's posed.npy, or the one staged in `batch`) and returns its
/// entry of track.json's summary, or the error.
pub(super) fn stage_glb(
    batch: &mut OutputBatch,
    out: &Path,
    posed_npy: &Path,
    template: &TriMesh,
    done: &[FrameDigest],
    total: usize,
) -> Result<Value, CliError> {
    let rows: Vec<PosedRow> = done
        .iter()
        .map(|e| PosedRow {
            frame: e.frame,
            time_s: e.time_s,
            posed: e.posed,
        })
        .collect();
    let cap = max_targets(template.num_vertices());
    let staged = stage_template_track(
        batch,
        &out.join(TEMPLATE_GLB),
        template,
        posed_npy,
        total,
        &rows,
        cap,
    )
    .map_err(|e| CliError(format!("{}: {e}", out.display())))?;
    Ok(match staged {
        Some(t) => json!({
            "file": TEMPLATE_GLB,
            "posed_frames": t.posed_frames,
            "targets": t.targets,
            "max_targets": t.max_targets,
            "decimated": t.targets < t.posed_frames,
            "first_frame": t.kept_frames.first(),
            "last_frame": t.kept_frames.last(),
            "bytes": t.bytes,
        }),
        None => json!({"file": null, "posed_frames": 0, "targets": 0, "max_targets": cap}),
    })
}
