//! `track.json` and `track.svg` of a run folder, made from its journal's header and frame
//! lines: one owner for `symcorr track` (at the end of a run) and `symcorr track-merge` (over
//! the merged slices' frames), so that both folders read the same.

use super::CliError;
use serde_json::{json, Value};
use std::path::Path;
use symcorr_mesh::io::OutputBatch;

/// The run's report file.
pub(super) const TRACK_JSON: &str = "track.json";
/// Its plot.
pub(super) const TRACK_SVG: &str = "track.svg";

/// What the summary, the plot and the animated template need of one frame line: a few
/// numbers per frame, so that a run of any length keeps only these in memory and `track.json`'s
/// frame lines are streamed from the journal.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct FrameDigest {
    /// The recording's frame number.
    pub frame: usize,
    /// Its time, seconds (NaN when unknown).
    pub time_s: f64,
    /// Matched (status `ok`).
    pub ok: bool,
    /// A posed template row was written.
    pub posed: bool,
    /// Coverage (matched frames).
    pub coverage: Option<f64>,
    /// Mean confidence (matched frames).
    pub mean_confidence: Option<f64>,
    /// Wall seconds from reading the frame to writing its rows.
    pub seconds: Option<f64>,
    /// Legs, arms and whole-skeleton swaps fixed, a skeleton turned back, and sides continued
    /// from the previous frames.
    pub fixed: [bool; 5],
}

/// The corrections the summary counts, in [`FrameDigest::fixed`]'s order.
const FIXES: [&str; 5] = [
    "legs_swap_fixed",
    "arms_swap_fixed",
    "sides_swap_fixed",
    "skeleton_turn_fixed",
    "sides_continued",
];

impl FrameDigest {
    /// The digest of a journal frame line.
    pub(super) fn of(entry: &Value) -> FrameDigest {
        let has = |name: &str| {
            entry["corrections"]
                .as_array()
                .is_some_and(|c| c.iter().any(|x| x == name))
        };
        FrameDigest {
            frame: entry["frame"].as_u64().unwrap_or(0) as usize,
            time_s: entry["time_s"].as_f64().unwrap_or(f64::NAN),
            ok: entry["status"] == "ok",
            posed: entry["posed"] == true,
            coverage: entry["coverage"].as_f64(),
            mean_confidence: entry["mean_confidence"].as_f64(),
            seconds: entry["seconds"].as_f64(),
            fixed: FIXES.map(has),
        }
    }
}

/// The summary of the `done` frames of a run of `total` frames: counts, the corrections made
/// and the mean coverage and confidence of the matched frames. The caller adds what only it
/// knows (throughput, the animated template).
pub(super) fn summary(done: &[FrameDigest], total: usize) -> Value {
    let ok: Vec<&FrameDigest> = done.iter().filter(|e| e.ok).collect();
    let mean = |key: fn(&FrameDigest) -> Option<f64>| {
        if ok.is_empty() {
            Value::Null
        } else {
            json!(ok.iter().map(|e| key(e).unwrap_or(0.0)).sum::<f64>() / ok.len() as f64)
        }
    };
    let fixed = |k: usize| done.iter().filter(|e| e.fixed[k]).count();
    json!({
        "frames": done.len(),
        "frames_in_run": total,
        "ok": ok.len(),
        "skipped": done.len() - ok.len(),
        "legs_swap_fixed": fixed(0),
        "arms_swap_fixed": fixed(1),
        "sides_swap_fixed": fixed(2),
        "skeleton_turn_fixed": fixed(3),
        "sides_continued": fixed(4),
        "mean_coverage": mean(|e| e.coverage),
        "mean_confidence": mean(|e| e.mean_confidence),
    })
}

/// Stages `track.json` (`symcorr.track/1`: the journal's `header`, the frame lines that
/// `frame_lines` writes — one JSON object per line, in order — and `summary`) and `track.svg`
/// (from `done`, the same frames) of a run of `total` frames into `out`. The frame lines are
/// streamed into the staged file, never held together in memory.
pub(super) fn stage(
    batch: &mut OutputBatch,
    out: &Path,
    header: &Value,
    frame_lines: impl FnOnce(&mut dyn FnMut(&str) -> std::io::Result<()>) -> std::io::Result<()>,
    done: &[FrameDigest],
    total: usize,
    summary: &Value,
) -> Result<(), CliError> {
    batch
        .add_streamed(&out.join(TRACK_JSON), |w| {
            write!(
                w,
                "{{\"format\":\"symcorr.track/1\",\"run\":{header},\"frames\":["
            )?;
            let mut first = true;
            frame_lines(&mut |line: &str| {
                if !first {
                    w.write_all(b",")?;
                }
                first = false;
                w.write_all(line.trim_end().as_bytes())
            })?;
            write!(w, "],\"summary\":{summary}}}")
        })
        .map_err(|e| CliError(e.to_string()))?;
    batch
        .add(&out.join(TRACK_SVG), track_svg(done, total).as_bytes())
        .map_err(|e| CliError(e.to_string()))?;
    Ok(())
}

/// Per processed frame (x: its position in the run): coverage, mean confidence and the time it
/// took relative to the slowest frame; skipped frames are gaps.
fn track_svg(frames: &[FrameDigest], total: usize) -> String {
    let slowest = frames
        .iter()
        .filter_map(|f| f.seconds)
        .fold(0.0f64, f64::max);
    let series = |key: fn(&FrameDigest) -> Option<f64>, scale: f64| -> Vec<(f64, f64)> {
        frames
            .iter()
            .enumerate()
            .filter(|(_, f)| f.ok)
            .filter_map(|(k, f)| key(f).map(|v| (k as f64, (v / scale).clamp(0.0, 1.0))))
            .collect()
    };
    let curves = vec![
        ("coverage".to_string(), series(|f| f.coverage, 1.0)),
        (
            "mean confidence".to_string(),
            series(|f| f.mean_confidence, 1.0),
        ),
        (
            format!("seconds (100 % = {slowest:.2} s)"),
            series(|f| f.seconds, slowest.max(f64::MIN_POSITIVE)),
        ),
    ];
    symcorr::output::line_plot_svg(
        &symcorr::output::PlotAxes {
            title: "symcorr track",
            x_label: "frame of the run",
            y_label: "% (coverage, confidence, time)",
            max_x: total.max(1) as f64,
        },
        &curves,
    )
}
