//! Self-contained HTML pages that show symcorr's results in a browser (`symcorr view`): one file,
//! no server, no network, opened from disk.
//!
//! # Data flow
//! The caller reads the inputs (meshes with [`crate::io::read_mesh`], the JSON files with
//! [`crate::formats`]) and hands them to a page builder:
//! * [`pair_page`] — a [`PairView`]: a `symcorr.correspondence/1` file with its two meshes, and
//!   optionally the benchmark's ground truth ([`PairTruth::from_dataset`]: true point and
//!   geodesic error per match, computed by symcorr-eval);
//! * [`labels_page`] — a [`LabelsView`]: a `symcorr.labels/1` file with its mesh and joints;
//! * [`track_page`] — a [`TrackView`] read from a `symcorr track` output folder
//!   ([`TrackView::read`]: `track.json`, `posed.npy`, the rest mesh of `template_track.glb`).
//!
//! Each builder checks that the file fits the meshes (vertex counts, ids in range) before
//! anything is made — an error is a [`ViewError`], one line — and returns the page as a string,
//! which the caller writes with the atomic writer (`symcorr_mesh::io::OutputBatch`).
//!
//! # The page
//! The page is `assets/view/page.html` with three things put in: three.js
//! (`assets/three/three.cjs`, the CommonJS build of a pinned release, wrapped into a classic
//! script that defines `THREE`) and the viewer's own script (`assets/view/view.js`: an orbit
//! camera, picking, colour modes, the timeline), both compiled into the binary with
//! `include_str!`, and the data as one JSON object in a
//! `<script type="application/json" id="symcorr-data">` element. Arrays are base64 of
//! little-endian typed arrays: positions `Float32Array`, triangles `Uint32Array`, segment labels
//! `Uint8Array` (255: none), posed track frames `Uint16Array` quantised over their bounding box.
//! The page reports its state as `window.symcorrView` (DESIGN.md, `symcorr view`), which the
//! browser tests under `tests/browser/` read.
//!
//! What the page needs is computed here, not in the browser: for a sparse correspondence, each
//! vertex's nearest matched vertex along the mesh edges ([`nearest_sources`]), so that colours
//! and heat maps cover the whole surface; the per-match error of `--truth`.

mod track;

pub use track::{TrackView, DEFAULT_MAX_FRAMES};

use crate::formats::{CorrespondenceFile, LabelsFile};
use serde_json::{json, Value};
use std::collections::VecDeque;
use std::path::Path;
use symcorr_attach::palette::PALETTE;
use symcorr_attach::{Segment, BONES};
use symcorr_correspond::Pair;
use symcorr_eval::{evaluate_pair, Dataset, EvalGraph, MeshIds};
use symcorr_mesh::TriMesh;

/// The three.js release inlined into every page (`assets/three/`, see DESIGN.md).
pub const THREE_VERSION: &str = "0.170.0";

const THREE_JS: &str = include_str!("../../assets/three/three.cjs");
const PAGE_HTML: &str = include_str!("../../assets/view/page.html");
const VIEW_JS: &str = include_str!("../../assets/view/view.js");

/// Label value of a vertex without a segment in the embedded `Uint8Array`s.
const NO_SEGMENT: u8 = 255;

/// Why a page cannot be made: the inputs do not fit together. One line, naming the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewError {
    /// A file names vertices a mesh does not have, or was made for another mesh.
    #[error("{file}: {message}")]
    Mismatch {
        /// The file.
        file: String,
        /// What does not fit.
        message: String,
    },
    /// Reading an input (a track folder's files, a dataset's truth table).
    #[error("{0}")]
    Read(String),
}

fn mismatch(file: &str, message: String) -> ViewError {
    ViewError::Mismatch {
        file: file.to_string(),
        message,
    }
}

/// A correspondence with its two meshes, as read from the files it names.
#[derive(Debug, Clone, Copy)]
pub struct PairView<'a> {
    /// The template mesh (input vertex order).
    pub template: &'a TriMesh,
    /// The target mesh (input vertex order).
    pub target: &'a TriMesh,
    /// The correspondence file.
    pub correspondence: &'a CorrespondenceFile,
    /// The file's name, for errors and the page title.
    pub name: &'a str,
    /// Ground truth, when a benchmark dataset was given.
    pub truth: Option<&'a PairTruth>,
}

impl PairView<'_> {
    /// Checks that the correspondence file fits the meshes (what [`pair_page`] checks first;
    /// [`PairTruth::from_dataset`] needs it too).
    pub fn check(&self) -> Result<(), ViewError> {
        self.checked_segments().map(|_| ())
    }

    fn checked_segments(&self) -> Result<(Vec<u8>, Vec<u8>), ViewError> {
        let corr = self.correspondence;
        let file = self.name;
        let (nt, ng) = (self.template.num_vertices(), self.target.num_vertices());
        check_count(
            file,
            "template",
            corr.template.vertices,
            nt,
            &corr.template.path,
        )?;
        check_count(file, "target", corr.target.vertices, ng, &corr.target.path)?;
        for (k, &(p, q, _)) in corr.pairs.iter().enumerate() {
            if p as usize >= nt {
                return Err(mismatch(
                    file,
                    format!("pair {k}: template vertex {p} out of range (the template has {nt} vertices)"),
                ));
            }
            if q as usize >= ng {
                return Err(mismatch(
                    file,
                    format!(
                        "pair {k}: target vertex {q} out of range (the target has {ng} vertices)"
                    ),
                ));
            }
        }
        let missing = corr.no_counterpart.as_deref().unwrap_or(&[]);
        if let Some(&p) = missing.iter().find(|&&p| p as usize >= nt) {
            return Err(mismatch(
                file,
                format!("no_counterpart: template vertex {p} out of range (the template has {nt} vertices)"),
            ));
        }
        let template_segments = segment_bytes(file, "template", &corr.segments.template, nt)?;
        let target_segments = segment_bytes(file, "target", &corr.segments.target, ng)?;
        if let Some(t) = self.truth {
            if t.true_target.len() != corr.pairs.len() || t.error.len() != corr.pairs.len() {
                return Err(mismatch(
                    file,
                    "ground truth made for another correspondence".to_string(),
                ));
            }
        }
        Ok((template_segments, target_segments))
    }
}

/// Ground truth of a pair, per match of its correspondence file (same order as `pairs`).
#[derive(Debug, Clone, PartialEq)]
pub struct PairTruth {
    /// The target vertex the template point truly corresponds to (`None`: the dataset has
    /// none, e.g. a point a partial scan does not show).
    pub true_target: Vec<Option<u32>>,
    /// The geodesic error of the match over √area (symcorr-eval's metric; `None`: not scored).
    pub error: Vec<Option<f64>>,
    /// What the errors are measured on and over.
    pub unit: String,
}

impl PairTruth {
    /// The ground truth of `pair` from a benchmark dataset in DESIGN.md's layout: template
    /// vertex `p` is target vertex `p`, or, when the target has a truth table
    /// (`truth/NAME.txt`, a partial scan), target vertex `v` is common vertex `truth[v]`.
    /// The mesh names are the stems of the correspondence file's paths.
    ///
    /// Every match with a true point is scored by `symcorr_eval::evaluate_pair` on the input
    /// meshes as read (no repair): the edge-path geodesic distance on the target over the
    /// target's √area, or for a partial target on the template (symcorr-eval's module docs).
    ///
    /// Errors: the meshes are not in the dataset, or do not fit its files.
    pub fn from_dataset(pair: &PairView<'_>, dataset: &Path) -> Result<PairTruth, ViewError> {
        let ds = Dataset::open(dataset, None).map_err(|e| ViewError::Read(e.to_string()))?;
        let corr = pair.correspondence;
        let name_of = |path: &str| -> Result<String, ViewError> {
            let stem = Path::new(path)
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or(path)
                .to_string();
            if ds.meshes.contains_key(&stem) {
                Ok(stem)
            } else {
                Err(ViewError::Read(format!(
                    "{}: no mesh named {stem:?} in the dataset (from {path})",
                    dataset.display()
                )))
            }
        };
        // The template must be one of the dataset's meshes (its ids are the common order).
        name_of(&corr.template.path)?;
        let target_name = name_of(&corr.target.path)?;
        let table = match ds.truth.get(&target_name) {
            Some(p) => {
                Some(symcorr_eval::read_truth(p).map_err(|e| ViewError::Read(e.to_string()))?)
            }
            None => None,
        };
        if let Some(t) = &table {
            if t.len() != pair.target.num_vertices() {
                return Err(ViewError::Read(format!(
                    "{}: truth table of {} vertices, the target has {}",
                    ds.truth[&target_name].display(),
                    t.len(),
                    pair.target.num_vertices()
                )));
            }
        }
        PairTruth::from_table(pair, table.as_deref())
    }

    /// [`PairTruth::from_dataset`] with the target's truth table given (`None`: the common
    /// vertex order).
    ///
    /// Errors: the correspondence does not fit the meshes ([`PairView::check`]).
    pub fn from_table(
        pair: &PairView<'_>,
        table: Option<&[Option<u32>]>,
    ) -> Result<PairTruth, ViewError> {
        pair.check()?;
        let (nt, ng) = (pair.template.num_vertices(), pair.target.num_vertices());
        let pairs = &pair.correspondence.pairs;
        // The true target vertex of each template vertex.
        let mut truth_of: Vec<Option<u32>> = vec![None; nt];
        match table {
            None => {
                for (p, t) in truth_of.iter_mut().enumerate().take(ng) {
                    *t = Some(p as u32);
                }
            }
            Some(table) => {
                for (v, c) in table.iter().enumerate() {
                    if let Some(slot) = c.and_then(|c| truth_of.get_mut(c as usize)) {
                        slot.get_or_insert(v as u32);
                    }
                }
            }
        }
        // Only the matches symcorr-eval scores (a true point, and for a partial target a
        // landing point with a common id), so that its errors line up with them.
        let scored: Vec<usize> = (0..pairs.len())
            .filter(|&k| {
                let (p, q, _) = pairs[k];
                truth_of.get(p as usize).copied().flatten().is_some()
                    && table.is_none_or(|t| {
                        t.get(q as usize)
                            .copied()
                            .flatten()
                            .is_some_and(|c| (c as usize) < nt)
                    })
            })
            .collect();
        let matches: Vec<Pair> = scored
            .iter()
            .map(|&k| Pair {
                template: pairs[k].0,
                target: pairs[k].1,
                confidence: pairs[k].2,
            })
            .collect();
        let ids = |n: usize| -> (Vec<u32>, Vec<Option<u32>>) {
            ((0..n as u32).collect(), (0..n as u32).map(Some).collect())
        };
        let (ti, tp) = ids(nt);
        let (gi, gp) = ids(ng);
        let template_ids = MeshIds {
            input_ids: &ti,
            prepared_ids: &tp,
            area: pair.template.total_area(),
        };
        let target_ids = MeshIds {
            input_ids: &gi,
            prepared_ids: &gp,
            area: pair.target.total_area(),
        };
        let (graph, unit) = match table {
            None => (
                EvalGraph::new(pair.target),
                "geodesic distance on the target / √area",
            ),
            Some(_) => (
                EvalGraph::new(pair.template),
                "geodesic distance on the template / √area (partial target)",
            ),
        };
        let (evaluation, _) =
            evaluate_pair(&template_ids, &target_ids, table, &graph, &matches, None);
        let mut error = vec![None; pairs.len()];
        // Invariant: every prefiltered match is scored, in order; should that ever change the
        // errors are left out rather than misattributed.
        if evaluation.errors.len() == scored.len() {
            for (&k, &e) in scored.iter().zip(&evaluation.errors) {
                error[k] = Some(e);
            }
        }
        Ok(PairTruth {
            true_target: pairs
                .iter()
                .map(|&(p, _, _)| truth_of.get(p as usize).copied().flatten())
                .collect(),
            error,
            unit: unit.to_string(),
        })
    }
}

/// A labels file with its mesh.
#[derive(Debug, Clone, Copy)]
pub struct LabelsView<'a> {
    /// The mesh (input vertex order).
    pub mesh: &'a TriMesh,
    /// The labels file.
    pub labels: &'a LabelsFile,
    /// The file's name, for errors and the page title.
    pub name: &'a str,
}

/// Checks that a file made for a mesh of `declared` vertices names `mesh_name`'s `actual`.
fn check_count(
    file: &str,
    what: &str,
    declared: usize,
    actual: usize,
    mesh_name: &str,
) -> Result<(), ViewError> {
    if declared == actual {
        Ok(())
    } else {
        Err(mismatch(
            file,
            format!("made for a {what} of {declared} vertices, but {mesh_name} has {actual}"),
        ))
    }
}

/// The pair page: template and target side by side (DESIGN.md, `symcorr view`).
///
/// Errors ([`ViewError::Mismatch`], naming the file): the file's vertex counts or segment lists
/// differ from the meshes', a pair or `no_counterpart` names a vertex out of range, a segment
/// label is not one of the 17.
pub fn pair_page(view: &PairView<'_>) -> Result<String, ViewError> {
    let (template_segments, target_segments) = view.checked_segments()?;
    let corr = view.correspondence;
    let file = view.name;
    let (nt, ng) = (view.template.num_vertices(), view.target.num_vertices());
    let missing = corr.no_counterpart.as_deref().unwrap_or(&[]);
    let mut blocked = vec![false; nt];
    for &p in missing {
        blocked[p as usize] = true;
    }
    let mut template_sources: Vec<(u32, i32)> = Vec::with_capacity(corr.pairs.len());
    let mut target_sources: Vec<(u32, i32)> = Vec::with_capacity(corr.pairs.len());
    for (k, &(p, q, _)) in corr.pairs.iter().enumerate() {
        template_sources.push((p, k as i32));
        target_sources.push((q, k as i32));
    }
    let template_nearest = nearest_sources(view.template, &template_sources, &blocked);
    let target_nearest = nearest_sources(view.target, &target_sources, &vec![false; ng]);

    let truth = view.truth.map(|t| {
        json!({
            "target": b64(t.true_target.iter().map(|x| x.map_or(-1, |v| v as i32))),
            "error": b64(t.error.iter().map(|e| e.map_or(f32::NAN, |e| e as f32))),
            "unit": t.unit,
        })
    });
    let data = json!({
        "kind": "pair",
        "title": file,
        "segments": segment_legend(),
        "meshes": {
            "template": mesh_json(&corr.template.path, view.template, &template_segments, &template_nearest),
            "target": mesh_json(&corr.target.path, view.target, &target_segments, &target_nearest),
        },
        "pairs": {
            "count": corr.pairs.len(),
            "template": b64(corr.pairs.iter().map(|p| p.0)),
            "target": b64(corr.pairs.iter().map(|p| p.1)),
            "confidence": b64(corr.pairs.iter().map(|p| p.2 as f32)),
        },
        "truth": truth,
        "noCounterpart": b64(missing.iter().copied()),
    });
    Ok(page(file, &data))
}

/// The labels page: the mesh in segment colours with the refined skeleton's joints and bones.
///
/// Errors ([`ViewError::Mismatch`], naming the file): the labels were made for a mesh with
/// another vertex count, or a label is not one of the 17 segments.
pub fn labels_page(view: &LabelsView<'_>) -> Result<String, ViewError> {
    let l = view.labels;
    let file = view.name;
    let n = view.mesh.num_vertices();
    check_count(file, "mesh", l.mesh.vertices, n, &l.mesh.path)?;
    let labels = segment_bytes(file, "mesh", &l.labels, n)?;
    let joints: serde_json::Map<String, Value> = l
        .joints
        .iter()
        .map(|(name, p)| (name.clone(), json!(p)))
        .collect();
    let bones: Vec<[&str; 2]> = BONES
        .iter()
        .filter(|b| l.joints.contains_key(b.parent.name()) && l.joints.contains_key(b.child.name()))
        .map(|b| [b.parent.name(), b.child.name()])
        .collect();
    let data = json!({
        "kind": "labels",
        "title": file,
        "segments": segment_legend(),
        "meshes": {"mesh": mesh_json(&l.mesh.path, view.mesh, &labels, &[])},
        "joints": joints,
        "bones": bones,
    });
    Ok(page(file, &data))
}

/// The track page: the template following the recording, with a timeline of frame statuses.
pub fn track_page(view: &TrackView) -> String {
    page(&view.name, &view.to_json())
}

/// Segment index per vertex as bytes ([`NO_SEGMENT`] for none), checking count and range.
fn segment_bytes(
    file: &str,
    what: &str,
    labels: &[Option<usize>],
    n: usize,
) -> Result<Vec<u8>, ViewError> {
    if labels.len() != n {
        return Err(mismatch(
            file,
            format!(
                "{} {what} segment labels for a {what} of {n} vertices",
                labels.len()
            ),
        ));
    }
    labels
        .iter()
        .enumerate()
        .map(|(v, l)| match l {
            None => Ok(NO_SEGMENT),
            Some(s) if *s < Segment::COUNT => Ok(*s as u8),
            Some(s) => Err(mismatch(
                file,
                format!(
                    "{what} vertex {v}: segment {s} is not one of the {}",
                    Segment::COUNT
                ),
            )),
        })
        .collect()
}

/// The 17 segments' names and palette colours (symcorr-attach's palette), in index order.
fn segment_legend() -> Value {
    Value::Array(
        Segment::ALL
            .iter()
            .map(|s| json!({"name": s.name(), "colour": PALETTE[s.index()]}))
            .collect(),
    )
}

fn mesh_json(path: &str, mesh: &TriMesh, segments: &[u8], nearest: &[i32]) -> Value {
    json!({
        "path": path,
        "vertices": mesh.num_vertices(),
        "positions": b64(mesh.positions.iter().flatten().map(|&x| x as f32)),
        "triangles": b64(mesh.triangles.iter().flatten().copied()),
        "segments": base64(segments),
        "nearestPair": b64(nearest.iter().copied()),
    })
}

/// For each vertex of `mesh`, the value of the nearest source vertex in edge hops
/// (multi-source breadth-first search; the first source listed wins a vertex that several
/// reach at once); −1 where no source is reached. `blocked` vertices are neither entered nor
/// given a value (unless a source).
///
/// ```
/// use symcorr_mesh::TriMesh;
/// let m = TriMesh::new(
///     vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
///     vec![[0, 1, 2], [1, 3, 2]],
/// ).unwrap();
/// let near = symcorr::view::nearest_sources(&m, &[(0, 7)], &[false, false, false, true]);
/// assert_eq!(near, [7, 7, 7, -1]);
/// ```
pub fn nearest_sources(mesh: &TriMesh, sources: &[(u32, i32)], blocked: &[bool]) -> Vec<i32> {
    let n = mesh.num_vertices();
    let mut adjacency: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            adjacency[a as usize].push(b);
            adjacency[b as usize].push(a);
        }
    }
    let mut value = vec![-1; n];
    let mut queue = VecDeque::new();
    for &(v, x) in sources {
        if value[v as usize] == -1 {
            value[v as usize] = x;
            queue.push_back(v);
        }
    }
    while let Some(v) = queue.pop_front() {
        let x = value[v as usize];
        for &w in &adjacency[v as usize] {
            let w = w as usize;
            if value[w] == -1 && !blocked.get(w).copied().unwrap_or(false) {
                value[w] = x;
                queue.push_back(w as u32);
            }
        }
    }
    value
}

/// The page: template, three.js, the viewer's script and the data put together.
fn page(title: &str, data: &Value) -> String {
    // `</` would end the script element early inside a string of the JSON; `<\/` reads the
    // same to JSON.
    let data = data.to_string().replace("</", "<\\/");
    let title = html_escape(title);
    // Placeholders are replaced in one pass, in the template's order, so nothing inserted is
    // scanned again.
    let mut out = String::with_capacity(THREE_JS.len() + VIEW_JS.len() + data.len() + 4096);
    let mut rest = PAGE_HTML;
    while let Some(i) = rest.find("{{") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let Some(j) = after.find("}}") else {
            out.push_str(&rest[i..]);
            rest = "";
            break;
        };
        match &after[..j] {
            "TITLE" => out.push_str(&title),
            "DATA" => out.push_str(&data),
            "THREE" => out.push_str(THREE_JS),
            "THREE_VERSION" => out.push_str(THREE_VERSION),
            "VIEW_JS" => out.push_str(VIEW_JS),
            other => {
                out.push_str("{{");
                out.push_str(other);
                out.push_str("}}");
            }
        }
        rest = &after[j + 2..];
    }
    out.push_str(rest);
    out
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number the page reads back from a little-endian typed array (`Float32Array`,
/// `Uint32Array`, `Int32Array`, `Uint16Array`).
pub(super) trait LittleEndian: Copy {
    /// Appends the number's little-endian bytes.
    fn push_le(self, out: &mut Vec<u8>);
}

macro_rules! little_endian {
    ($($t:ty),*) => {$(
        impl LittleEndian for $t {
            fn push_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
        }
    )*};
}
little_endian!(f32, u32, i32, u16);

/// The numbers as one base64 string of their little-endian bytes: what the page decodes into a
/// typed array.
pub(super) fn b64<T: LittleEndian>(values: impl IntoIterator<Item = T>) -> String {
    let mut bytes = Vec::new();
    for v in values {
        v.push_le(&mut bytes);
    }
    base64(&bytes)
}

/// Standard base64 with padding (RFC 4648), what the page's `atob` reads.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, coded) in cases {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    #[test]
    fn b64_writes_each_number_little_endian() {
        assert_eq!(b64([1u16, 0x0203]), base64(&[1, 0, 3, 2]));
        assert_eq!(b64([0x0102_0304u32]), base64(&[4, 3, 2, 1]));
        assert_eq!(b64([-2i32]), base64(&[0xfe, 0xff, 0xff, 0xff]));
        assert_eq!(b64([1.0f32]), base64(&[0, 0, 0x80, 0x3f]));
        assert_eq!(b64(Vec::<u32>::new()), "");
    }

    /// A flat grid of about `n` vertices.
    fn grid(n: usize) -> TriMesh {
        let side = (n as f64).sqrt().ceil() as u32;
        let positions = (0..side * side)
            .map(|i| [f64::from(i % side), f64::from(i / side), 0.0])
            .collect();
        let mut triangles = Vec::new();
        for y in 0..side - 1 {
            for x in 0..side - 1 {
                let v = y * side + x;
                triangles.push([v, v + 1, v + side]);
                triangles.push([v + 1, v + side + 1, v + side]);
            }
        }
        TriMesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn a_dense_13k_to_25k_pair_page_stays_under_8_mb() {
        let (a, b) = (grid(13_400), grid(25_000));
        let (na, nb) = (a.num_vertices(), b.num_vertices());
        let corr = CorrespondenceFile {
            fit: None,
            format: crate::formats::CORRESPONDENCE_FORMAT.into(),
            no_counterpart: Some(vec![0, 1, 2]),
            pairs: (0..na as u32).map(|v| (v, v, 0.5)).collect(),
            segments: crate::formats::MeshPair {
                target: vec![Some(11); nb],
                template: vec![Some(12); na],
            },
            surface_points: None,
            skeleton_filter: crate::formats::FilterCounts {
                fallbacks: 0,
                kept: 0,
                points: 0,
                removed: 0,
                segment_missing: 0,
            },
            target: crate::formats::MeshRef {
                path: "b.ply".into(),
                vertices: nb,
            },
            template: crate::formats::MeshRef {
                path: "a.ply".into(),
                vertices: na,
            },
            timings_s: BTreeMap::new(),
        };
        let mut view = PairView {
            template: &a,
            target: &b,
            correspondence: &corr,
            name: "corr.json",
            truth: None,
        };
        let truth = PairTruth::from_table(&view, None).unwrap();
        // Identity matches in the common vertex order: every one scored, at zero error.
        assert!(truth.error.iter().all(|&e| e == Some(0.0)));
        view.truth = Some(&truth);
        let html = pair_page(&view).unwrap();
        assert!(html.len() < 8 << 20, "{} bytes", html.len());
    }

    #[test]
    fn page_inlines_three_and_data_without_closing_the_script_early() {
        let html = page("a</script>b", &json!({"path": "x</script><b>"}));
        assert!(html.contains("REVISION = '170'"));
        assert!(html.contains("<\\/script><b>"));
        assert!(!html.contains("x</script>"));
        assert!(html.contains("<title>a&lt;/script&gt;b</title>"));
        for placeholder in ["{{TITLE}}", "{{DATA}}", "{{THREE}}", "{{VIEW_JS}}"] {
            assert!(!html.contains(placeholder), "{placeholder} filled");
        }
        assert!(
            !html.contains("<script src"),
            "nothing loaded from elsewhere"
        );
    }
}
