//! The track page's data: a `symcorr track` output folder read into what the page embeds.

use super::{b64, ViewError};
use crate::npy::{NpyReader, NpyType};
use serde_json::{json, Value};
use std::path::Path;

/// Posed frames embedded by default: a longer run keeps this many, chosen evenly (first and
/// last included); the timeline still lists every frame.
pub const DEFAULT_MAX_FRAMES: usize = 50;

/// A `symcorr track` run, as the page shows it.
#[derive(Debug, Clone)]
pub struct TrackView {
    /// The folder, for the title.
    pub name: String,
    /// Template vertices.
    pub vertices: usize,
    /// The template's triangles (from `template_track.glb`'s rest mesh).
    pub triangles: Vec<[u32; 3]>,
    /// `track.json`'s frame entries, in run order.
    pub frames: Vec<Value>,
    /// `track.json`'s summary.
    pub summary: Value,
    /// Per frame entry: the index of its pose in `poses` (`None`: no pose, or not embedded).
    pub pose_of_frame: Vec<Option<usize>>,
    /// Embedded poses, each `vertices × 3` positions (metres, camera space).
    pub poses: Vec<Vec<f32>>,
}

fn read_err(file: &Path, e: impl std::fmt::Display) -> ViewError {
    ViewError::Read(format!("{}: {e}", file.display()))
}

impl TrackView {
    /// Reads the run folder `dir`: `track.json` (frames and summary), `template_track.glb`
    /// (the template's triangles) and `posed.npy` (row k: the k-th frame of the run). At most
    /// `max_frames` posed frames are kept, chosen evenly.
    ///
    /// Errors ([`ViewError::Read`], naming the file): a missing or malformed file, a
    /// `posed.npy` whose shape is not the run's frames × the template's vertices × 3.
    pub fn read(dir: &Path, max_frames: usize) -> Result<TrackView, ViewError> {
        let track_json = dir.join("track.json");
        let text = std::fs::read_to_string(&track_json).map_err(|e| read_err(&track_json, e))?;
        let doc: Value = serde_json::from_str(&text).map_err(|e| read_err(&track_json, e))?;
        if doc["format"] != "symcorr.track/1" {
            return Err(read_err(
                &track_json,
                format!("format {}, expected \"symcorr.track/1\"", doc["format"]),
            ));
        }
        let frames = doc["frames"]
            .as_array()
            .cloned()
            .ok_or_else(|| read_err(&track_json, "no frames list"))?;
        let glb = dir.join("template_track.glb");
        let rest = symcorr_mesh::io::read(&glb)
            .map_err(|e| ViewError::Read(e.to_string()))?
            .mesh;
        let n = rest.num_vertices();
        let rows = doc["summary"]["frames_in_run"]
            .as_u64()
            .map_or(frames.len(), |r| r as usize);
        let posed_path = dir.join("posed.npy");
        let mut reader = NpyReader::open(&posed_path, NpyType::F32, rows, &[n, 3])
            .map_err(|e| ViewError::Read(e.to_string()))?;
        // Frames with a pose, then an even choice of at most max_frames of them.
        let posed: Vec<usize> = (0..frames.len().min(rows))
            .filter(|&k| frames[k]["posed"] == true)
            .collect();
        let keep = choose_evenly(posed.len(), max_frames);
        let mut pose_of_frame = vec![None; frames.len()];
        let mut poses = Vec::with_capacity(keep.len());
        let mut row = Vec::new();
        for i in keep {
            let k = posed[i];
            reader
                .read_f32(k, &mut row)
                .map_err(|e| ViewError::Read(e.to_string()))?;
            if row.iter().all(|x| x.is_finite()) {
                pose_of_frame[k] = Some(poses.len());
                poses.push(row.clone());
            }
        }
        Ok(TrackView {
            name: dir.display().to_string(),
            vertices: n,
            triangles: rest.triangles,
            frames,
            summary: doc["summary"].clone(),
            pose_of_frame,
            poses,
        })
    }

    /// The page's data object.
    pub(super) fn to_json(&self) -> Value {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for pose in &self.poses {
            for p in pose.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        if self.poses.is_empty() {
            (lo, hi) = ([0.0; 3], [1.0; 3]);
        }
        let quantised = self.poses.iter().flat_map(|pose| {
            pose.chunks_exact(3).flat_map(move |p| {
                (0..3).map(move |k| {
                    let span = (hi[k] - lo[k]).max(f32::MIN_POSITIVE);
                    ((p[k] - lo[k]) / span * 65535.0)
                        .round()
                        .clamp(0.0, 65535.0) as u16
                })
            })
        });
        let frames: Vec<Value> = self
            .frames
            .iter()
            .zip(&self.pose_of_frame)
            .map(|(f, pose)| {
                json!({
                    "frame": f["frame"],
                    "time_s": f["time_s"],
                    "status": f["status"],
                    "corrections": f.get("corrections").cloned().unwrap_or(json!([])),
                    "coverage": f.get("coverage").cloned().unwrap_or(Value::Null),
                    "mean_confidence": f.get("mean_confidence").cloned().unwrap_or(Value::Null),
                    "pose": pose,
                })
            })
            .collect();
        json!({
            "kind": "track",
            "title": self.name,
            "segments": super::segment_legend(),
            "track": {
                "vertices": self.vertices,
                "triangles": b64(self.triangles.iter().flatten().copied()),
                "frames": frames,
                "summary": self.summary,
                "poses": {
                    "count": self.poses.len(),
                    "min": lo,
                    "max": hi,
                    "data": b64(quantised),
                },
            },
        })
    }
}

/// At most `max` of `0..n`, evenly spread, first and last included.
fn choose_evenly(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    if max <= 1 {
        return (0..max.min(n)).collect();
    }
    (0..max)
        .map(|i| (i * (n - 1) + (max - 1) / 2) / (max - 1))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::choose_evenly;

    #[test]
    fn choose_evenly_keeps_first_and_last() {
        assert_eq!(choose_evenly(3, 10), [0, 1, 2]);
        let c = choose_evenly(1000, 5);
        assert_eq!(c.len(), 5);
        assert_eq!((c[0], c[4]), (0, 999));
        assert!(c.windows(2).all(|w| w[0] < w[1]));
    }
}
