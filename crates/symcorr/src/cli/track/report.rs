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

/// The summary of the `done` frame lines of a run of `total` frames: counts, the corrections
/// made and the mean coverage and confidence of the matched frames. The caller adds what only
/// it knows (throughput, the animated template).
pub(super) fn summary(done: &[Value], total: usize) -> Value {
    let ok: Vec<&Value> = done.iter().filter(|e| e["status"] == "ok").collect();
    let mean = |key: &str| {
        if ok.is_empty() {
            Value::Null
        } else {
            json!(
                ok.iter()
                    .map(|e| e[key].as_f64().unwrap_or(0.0))
                    .sum::<f64>()
                    / ok.len() as f64
            )
        }
    };
    let fixed = |name: &str| {
        done.iter()
            .filter(|e| {
                e["corrections"]
                    .as_array()
                    .is_some_and(|c| c.iter().any(|x| x == name))
            })
            .count()
    };
    json!({
        "frames": done.len(),
        "frames_in_run": total,
        "ok": ok.len(),
        "skipped": done.len() - ok.len(),
        "legs_swap_fixed": fixed("legs_swap_fixed"),
        "arms_swap_fixed": fixed("arms_swap_fixed"),
        "sides_swap_fixed": fixed("sides_swap_fixed"),
        "mean_coverage": mean("coverage"),
        "mean_confidence": mean("mean_confidence"),
    })
}

/// Stages `track.json` (`symcorr.track/1`: the journal's `header`, the `done` frame lines and
/// `summary`) and `track.svg` of a run of `total` frames into `out`.
pub(super) fn stage(
    batch: &mut OutputBatch,
    out: &Path,
    header: &Value,
    done: &[Value],
    total: usize,
    summary: &Value,
) -> Result<(), CliError> {
    let doc = json!({
        "format": "symcorr.track/1",
        "run": header,
        "frames": done,
        "summary": summary,
    });
    let text = serde_json::to_string(&doc).map_err(|e| CliError(e.to_string()))?;
    batch
        .add(&out.join(TRACK_JSON), text.as_bytes())
        .map_err(|e| CliError(e.to_string()))?;
    batch
        .add(&out.join(TRACK_SVG), track_svg(done, total).as_bytes())
        .map_err(|e| CliError(e.to_string()))?;
    Ok(())
}

/// Per processed frame (x: its position in the run): coverage, mean confidence and the time it
/// took relative to the slowest frame; skipped frames are gaps.
fn track_svg(frames: &[Value], total: usize) -> String {
    let slowest = frames
        .iter()
        .filter_map(|f| f["seconds"].as_f64())
        .fold(0.0f64, f64::max);
    let series = |key: &str, scale: f64| -> Vec<(f64, f64)> {
        frames
            .iter()
            .enumerate()
            .filter(|(_, f)| f["status"] == "ok")
            .filter_map(|(k, f)| {
                f[key]
                    .as_f64()
                    .map(|v| (k as f64, (v / scale).clamp(0.0, 1.0)))
            })
            .collect()
    };
    let curves = vec![
        ("coverage".to_string(), series("coverage", 1.0)),
        (
            "mean confidence".to_string(),
            series("mean_confidence", 1.0),
        ),
        (
            format!("seconds (100 % = {slowest:.2} s)"),
            series("seconds", slowest.max(f64::MIN_POSITIVE)),
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
