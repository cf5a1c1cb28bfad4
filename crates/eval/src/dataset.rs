//! Benchmark datasets in DESIGN.md's layout and the scoring of a pair against their ground truth.
//!
//! A dataset is a folder with `meshes/NAME.{off,ply,obj,gltf,glb}` (the same vertex order in
//! every mesh, so the ground truth of template vertex `p` is target vertex `p`),
//! `joints/NAME.*` (any joint format symcorr-kinect reads), an optional `mirror.txt` (line `i`:
//! the vertex mirror-symmetric to vertex `i`) and `pairs.txt` (`template target` per line;
//! blank lines and `#` comments ignored).
//!
//! Extension for partial scans (not in DESIGN.md's layout, optional): `truth/NAME.txt` gives,
//! for a mesh whose vertices are *not* in the common order (a single-view scan), one line per
//! vertex: the id of the corresponding vertex in the common order, or `-1` when it has none.
//! A pair whose target has a truth file is evaluated on the visible part: only template points
//! that some target vertex corresponds to. A match `p ↦ q` lands on the common-order point
//! `c = truth(q)`; its error is the geodesic distance from `c` to `p` **on the template**
//! over the template's √area, and it is a flip when `c` lies nearer to `mirror(p)` than to `p`
//! on the template (counted where `g(p, mirror(p)) > 0.1·√area`). Distances on the template,
//! not on the scan, because a single-view scan's holes and cracks make its own geodesics
//! wander far from the body's (the SHREC'16 partial-matching benchmark measures on the full
//! shape for the same reason). Templates must be in the common order (no truth file).
//!
//! [`Dataset::open`] reads and checks the folder; [`Dataset::check_pair`] checks a pair's vertex
//! counts against its truth table and the mirror map once the meshes are read;
//! [`evaluate_pair`] scores one pair's matches, whatever repair the matcher applied to the
//! meshes ([`MeshIds`]); [`Pooled`] pools the scores of several pairs. Reading meshes and
//! joints and running a matcher is the caller's part (`symcorr bench` in the `symcorr` crate).

use crate::metrics::{cumulative_curve, evaluate, within, EvalGraph, Evaluation};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use symcorr_correspond::Pair;

/// Mesh file extensions recognised in `meshes/`, in order of preference.
const MESH_EXTENSIONS: [&str; 5] = ["off", "ply", "obj", "glb", "gltf"];

/// A benchmark dataset folder.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// The folder.
    pub root: PathBuf,
    /// Mesh file per name.
    pub meshes: BTreeMap<String, PathBuf>,
    /// Joint file per name.
    pub joints: BTreeMap<String, PathBuf>,
    /// `mirror.txt`, if present.
    pub mirror: Option<Vec<u32>>,
    /// `(template, target)` names.
    pub pairs: Vec<(String, String)>,
    /// `truth/NAME.txt` per name that has one (partial scans; see the module docs).
    pub truth: BTreeMap<String, PathBuf>,
}

/// Errors of the benchmark files: the file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EvalError {
    /// A dataset file or folder (pairs file, `mirror.txt`, `truth/NAME.txt`, `meshes/`,
    /// `joints/`) is missing, unreadable or malformed, or does not fit the meshes.
    #[error("{file}: {message}")]
    File {
        /// The file or folder.
        file: String,
        /// What is wrong.
        message: String,
    },
}

fn file_err(path: &Path, message: impl Into<String>) -> EvalError {
    EvalError::File {
        file: path.display().to_string(),
        message: message.into(),
    }
}

fn list_by_stem(
    dir: &Path,
    accept: impl Fn(&str) -> bool,
) -> Result<BTreeMap<String, PathBuf>, EvalError> {
    let rd = std::fs::read_dir(dir).map_err(|e| file_err(dir, e.to_string()))?;
    let mut out: BTreeMap<String, PathBuf> = BTreeMap::new();
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        let (Some(stem), Some(ext)) = (
            p.file_stem().and_then(|s| s.to_str()),
            p.extension().and_then(|s| s.to_str()),
        ) else {
            continue;
        };
        if stem.starts_with('.') || !accept(&ext.to_ascii_lowercase()) {
            continue;
        }
        out.entry(stem.to_string()).or_insert(p);
    }
    Ok(out)
}

impl Dataset {
    /// Opens a dataset folder. `pairs` overrides `DIR/pairs.txt`.
    ///
    /// Errors ([`EvalError::File`]): a missing `meshes/` or `joints/` folder, no pairs file,
    /// a malformed line in it, a pair naming a mesh or joint file that does not exist, a
    /// malformed `mirror.txt`.
    pub fn open(root: &Path, pairs: Option<&Path>) -> Result<Dataset, EvalError> {
        if !root.is_dir() {
            return Err(file_err(root, "not a dataset folder"));
        }
        let mut meshes = list_by_stem(&root.join("meshes"), |e| MESH_EXTENSIONS.contains(&e))?;
        // Prefer the first extension in MESH_EXTENSIONS when a name has several files.
        for (name, path) in meshes.iter_mut() {
            for ext in MESH_EXTENSIONS {
                let p = root.join("meshes").join(format!("{name}.{ext}"));
                if p.is_file() {
                    *path = p;
                    break;
                }
            }
        }
        let joints = list_by_stem(&root.join("joints"), |_| true)?;
        let pairs_path = pairs
            .map(Path::to_path_buf)
            .unwrap_or_else(|| root.join("pairs.txt"));
        let text = std::fs::read_to_string(&pairs_path)
            .map_err(|e| file_err(&pairs_path, e.to_string()))?;
        let mut list = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let parts: Vec<&str> = line.split_whitespace().collect();
            if parts.len() != 2 {
                return Err(file_err(
                    &pairs_path,
                    format!("line {}: expected `template target`, got {line:?}", i + 1),
                ));
            }
            for name in &parts {
                if !meshes.contains_key(*name) {
                    return Err(file_err(
                        &pairs_path,
                        format!(
                            "line {}: no mesh meshes/{name}.{{off,ply,obj,glb,gltf}}",
                            i + 1
                        ),
                    ));
                }
                if !joints.contains_key(*name) {
                    return Err(file_err(
                        &pairs_path,
                        format!("line {}: no joint file joints/{name}.*", i + 1),
                    ));
                }
            }
            list.push((parts[0].to_string(), parts[1].to_string()));
        }
        if list.is_empty() {
            return Err(file_err(&pairs_path, "no pairs"));
        }
        let mirror_path = root.join("mirror.txt");
        let mirror = if mirror_path.is_file() {
            Some(read_mirror(&mirror_path)?)
        } else {
            None
        };
        let truth_dir = root.join("truth");
        let truth = if truth_dir.is_dir() {
            list_by_stem(&truth_dir, |e| e == "txt")?
        } else {
            BTreeMap::new()
        };
        for (a, _) in &list {
            if truth.contains_key(a) {
                return Err(file_err(
                    &truth[a],
                    format!("{a} is a template: templates must be in the common vertex order"),
                ));
            }
        }
        Ok(Dataset {
            root: root.to_path_buf(),
            meshes,
            joints,
            mirror,
            pairs: list,
            truth,
        })
    }

    /// Checks pair `template target` once its meshes are read: `template_vertices` and
    /// `target_vertices` are the input meshes' vertex counts, `target_truth` the target's
    /// `truth/NAME.txt` if it has one ([`read_truth`]). The meshes must have the same number of
    /// vertices (or the target a truth table of its length whose ids are template vertices),
    /// and `mirror.txt` must be a map of the template's vertices.
    pub fn check_pair(
        &self,
        (template, target): (&str, &str),
        (template_vertices, target_vertices): (usize, usize),
        target_truth: Option<&[Option<u32>]>,
    ) -> Result<(), EvalError> {
        let (a, b, na, nb) = (template, target, template_vertices, target_vertices);
        let truth_file = || {
            self.truth.get(b).map_or_else(
                || self.root.join("truth").join(format!("{b}.txt")),
                Clone::clone,
            )
        };
        match target_truth {
            None if na != nb => {
                return Err(file_err(
                    &self.root,
                    format!(
                        "pair {a} {b}: {na} and {nb} vertices; a benchmark needs the same vertex order in every mesh (or truth/{b}.txt for a partial scan)",
                    ),
                ));
            }
            Some(t) if t.len() != nb => {
                return Err(file_err(
                    &truth_file(),
                    format!("{} lines, meshes/{b} has {nb} vertices", t.len()),
                ));
            }
            Some(t) if t.iter().flatten().any(|&c| c as usize >= na) => {
                return Err(file_err(
                    &truth_file(),
                    format!("an id ≥ {na}, the number of vertices of the template {a}"),
                ));
            }
            _ => {}
        }
        if let Some(m) = &self.mirror {
            // The mirror map is in the common order: the template's.
            if m.len() != na || m.iter().any(|&i| i as usize >= na) {
                return Err(file_err(
                    &self.root.join("mirror.txt"),
                    format!(
                        "{} entries (or an id ≥ {na}): the meshes have {na} vertices",
                        m.len(),
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The names used by the pairs, each once, sorted.
    pub fn used_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .pairs
            .iter()
            .flat_map(|(a, b)| [a.clone(), b.clone()])
            .collect();
        v.sort();
        v.dedup();
        v
    }
}

/// Reads `truth/NAME.txt`: one line per vertex, the common-order id or `-1` (none).
pub fn read_truth(path: &Path) -> Result<Vec<Option<u32>>, EvalError> {
    let text = std::fs::read_to_string(path).map_err(|e| file_err(path, e.to_string()))?;
    text.lines()
        .enumerate()
        .map(|(i, line)| match line.trim().parse::<i64>() {
            Ok(-1) => Ok(None),
            Ok(v) if (0..=u32::MAX as i64).contains(&v) => Ok(Some(v as u32)),
            _ => Err(file_err(
                path,
                format!("line {}: expected a vertex id or -1, got {line:?}", i + 1),
            )),
        })
        .collect()
}

/// Reads `mirror.txt`: one vertex index per line (line `i` = mirror of vertex `i`).
pub fn read_mirror(path: &Path) -> Result<Vec<u32>, EvalError> {
    let text = std::fs::read_to_string(path).map_err(|e| file_err(path, e.to_string()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let v: u32 = l
            .parse()
            .map_err(|_| file_err(path, format!("line {}: not a vertex index: {l:?}", i + 1)))?;
        out.push(v);
    }
    if let Some((i, &v)) = out
        .iter()
        .enumerate()
        .find(|(_, &v)| v as usize >= out.len())
    {
        return Err(file_err(
            path,
            format!("entry {i}: vertex {v} out of range ({} entries)", out.len()),
        ));
    }
    Ok(out)
}

/// Scores pooled over several pairs: every match of every pair counts once (the error and the
/// flip rate are pooled, not averaged per pair); the Table 1 row is the mean of the pairs' rows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Pooled {
    /// Sum of each pair's errors, per pair.
    error_sums: Vec<f64>,
    /// Every error of every pair, in pair order.
    errors: Vec<f64>,
    /// Matches counted for the flip rate, and flips among them.
    flip_counts: (usize, usize),
    /// Mean of the pairs' Table 1 rows.
    table1_row: [f64; 10],
}

impl Pooled {
    /// Pools `(evaluation, Table 1 row)` of each pair.
    ///
    /// ```
    /// use symcorr_eval::{Evaluation, Pooled};
    /// let e = |errors: Vec<f64>, flips| Evaluation { errors, flips, sqrt_area: 1.0 };
    /// let a = e(vec![0.0, 0.2], vec![Some(false), Some(true)]);
    /// let b = e(vec![0.1], vec![None]);
    /// let p = Pooled::new([(&a, &[0.0; 10]), (&b, &[1.0; 10])]);
    /// assert!((p.mean_error() - 0.1).abs() < 1e-12);
    /// assert_eq!(p.flip_rate(), Some(0.5));
    /// assert_eq!(p.table1_row()[0], 0.5);
    /// ```
    pub fn new<'a>(pairs: impl IntoIterator<Item = (&'a Evaluation, &'a [f64; 10])>) -> Pooled {
        let pairs: Vec<_> = pairs.into_iter().collect();
        let n = pairs.len().max(1) as f64;
        let mut out = Pooled::default();
        for (e, row) in &pairs {
            out.error_sums.push(e.errors.iter().sum::<f64>());
            out.errors.extend_from_slice(&e.errors);
            let (c, f) = e.flip_counts();
            out.flip_counts.0 += c;
            out.flip_counts.1 += f;
            for (r, x) in out.table1_row.iter_mut().zip(row.iter()) {
                *r += x / n;
            }
        }
        out
    }

    /// Mean error over all matches of all pairs (0 without matches).
    pub fn mean_error(&self) -> f64 {
        let s = self.error_sums.iter().fold(0.0, |s, x| s + x);
        if self.errors.is_empty() {
            0.0
        } else {
            s / self.errors.len() as f64
        }
    }

    /// Flips over counted matches, all pairs (`None` when none was counted: no mirror map).
    pub fn flip_rate(&self) -> Option<f64> {
        let (c, f) = self.flip_counts;
        (c > 0).then(|| f as f64 / c as f64)
    }

    /// All errors of all pairs, in pair order.
    pub fn errors(&self) -> &[f64] {
        &self.errors
    }

    /// Fraction of all matches with error ≤ x.
    pub fn within(&self, x: f64) -> f64 {
        within(&self.errors, x)
    }

    /// The Table 1 row averaged over the pairs.
    pub fn table1_row(&self) -> [f64; 10] {
        self.table1_row
    }

    /// The cumulative error curve of all matches on [0, 0.25] (101 points).
    pub fn curve(&self) -> Vec<(f64, f64)> {
        cumulative_curve(&self.errors, 0.25, 100)
    }
}

/// How the mesh a matcher worked on relates to the input file's vertex ids, which the ground
/// truth speaks: a matcher may repair a mesh first (remove degenerate triangles and stray
/// vertices, split non-manifold vertices), and then its matches name the repaired mesh's ids.
#[derive(Debug, Clone, Copy)]
pub struct MeshIds<'a> {
    /// The input id of each vertex of the mesh the matcher worked on.
    pub input_ids: &'a [u32],
    /// The vertex of the mesh the matcher worked on of each input vertex (`None`: removed; a
    /// split vertex names its first copy).
    pub prepared_ids: &'a [Option<u32>],
    /// Surface area of the mesh the matcher worked on.
    pub area: f64,
}

impl MeshIds<'_> {
    fn num_vertices(&self) -> usize {
        self.input_ids.len()
    }

    fn input_id(&self, v: u32) -> u32 {
        self.input_ids[v as usize]
    }
}

/// Evaluates a pair's matches against the dataset's ground truth, with `mirror` (common-order
/// ids) for the flip rate. `matches` name the vertices of the meshes the matcher worked on
/// (`template` and `target` relate them to the input files' ids). `graph` is the evaluation
/// graph of the target's mesh as the matcher worked on it — or, with `target_truth`, of the
/// template's.
///
/// Without `target_truth`, input vertex `i` of the template corresponds to input vertex `i` of
/// the target (DESIGN.md's layout). With it (a partial scan, see the module docs), target
/// input vertex `v` corresponds to common id `target_truth[v]`; only visible template points
/// are evaluated, on the template's surface. A match whose true point the repair removed is
/// left out.
///
/// Returns the evaluation and the confidences of the evaluated matches (for the Table 1 row).
/// Panics if a match names a vertex that `template` or `target` does not have.
///
/// ```
/// use symcorr_correspond::Pair;
/// use symcorr_eval::{evaluate_pair, EvalGraph, MeshIds};
/// use symcorr_mesh::TriMesh;
/// let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
/// // No repair: prepared ids are input ids.
/// let ids = MeshIds { input_ids: &[0, 1, 2], prepared_ids: &[Some(0), Some(1), Some(2)], area: m.total_area() };
/// let matches = [Pair { template: 0, target: 0, confidence: 0.9 }, Pair { template: 1, target: 0, confidence: 0.1 }];
/// let (e, confidence) = evaluate_pair(&ids, &ids, None, &EvalGraph::new(&m), &matches, None);
/// assert_eq!(e.errors[0], 0.0);
/// assert!((e.errors[1] - 1.0 / 0.5f64.sqrt()).abs() < 1e-12);
/// assert_eq!(confidence, [0.9, 0.1]);
/// ```
pub fn evaluate_pair(
    template: &MeshIds<'_>,
    target: &MeshIds<'_>,
    target_truth: Option<&[Option<u32>]>,
    graph: &EvalGraph,
    matches: &[Pair],
    mirror: Option<&[u32]>,
) -> (Evaluation, Vec<f64>) {
    if let Some(t) = target_truth {
        return evaluate_partial(template, target, t, graph, matches, mirror);
    }
    // Input id i of the template is input id i of the target; both through their repairs.
    let to_target = target.prepared_ids;
    let common_to_target = |c: u32| -> Option<u32> { *to_target.get(c as usize)? };
    let mut pairs = Vec::with_capacity(matches.len());
    let mut truth = Vec::with_capacity(matches.len());
    let mut confidence = Vec::with_capacity(matches.len());
    for m in matches {
        if let Some(q) = common_to_target(template.input_id(m.template)) {
            truth.push(q);
            pairs.push((truth.len() as u32 - 1, m.target));
            confidence.push(m.confidence);
        }
    }
    // The mirror map in the target's repaired ids (a removed mirror image maps to the vertex
    // itself: such a point cannot count as a flip).
    let mirror: Option<Vec<u32>> = mirror.map(|m| {
        (0..target.num_vertices() as u32)
            .map(|v| {
                m.get(target.input_id(v) as usize)
                    .copied()
                    .and_then(common_to_target)
                    .unwrap_or(v)
            })
            .collect()
    });
    let evaluation = evaluate(
        graph,
        target.area,
        &pairs,
        |i| truth[i as usize],
        mirror.as_deref(),
    );
    (evaluation, confidence)
}

/// [`evaluate_pair`] for matches that are points on the target's surface
/// ([`crate::surface_errors`]): per `(template vertex, target corners, weights)` a point of a
/// target triangle. Without `target_truth` the error is measured on the target, from the true
/// point of the template vertex; with it (a partial scan) each corner stands for the template
/// point its truth names, the surface point for their weighted mean, and the error is measured
/// on the template from the template vertex (corners without truth are dropped and the
/// weights renormalised). A point is scored when its true point exists — for a scan, when
/// the template vertex is visible and some corner has truth ([`evaluate_pair`] asks it of the
/// matched vertex: the two sets differ only at scan vertices without truth). Returns the errors
/// of the scored points, in order. Panics as [`evaluate_pair`] does.
///
/// ```
/// use symcorr_eval::{evaluate_surface_pair, EvalGraph, MeshIds};
/// use symcorr_mesh::TriMesh;
/// let m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
/// let ids = MeshIds { input_ids: &[0, 1, 2], prepared_ids: &[Some(0), Some(1), Some(2)], area: m.total_area() };
/// // Template vertex 0 reaches the middle of edge 0–1: half an edge from its true point.
/// let e = evaluate_surface_pair(&ids, &ids, None, &EvalGraph::new(&m), &[(0, [0, 1, 2], [0.5, 0.5, 0.0])]);
/// assert!((e[0] - 0.5 / m.total_area().sqrt()).abs() < 1e-12);
/// ```
pub fn evaluate_surface_pair(
    template: &MeshIds<'_>,
    target: &MeshIds<'_>,
    target_truth: Option<&[Option<u32>]>,
    graph: &EvalGraph,
    points: &[(u32, [u32; 3], [f64; 3])],
) -> Vec<f64> {
    let mut scored = Vec::with_capacity(points.len());
    match target_truth {
        None => {
            for &(t, corners, weights) in points {
                let truth = target
                    .prepared_ids
                    .get(template.input_id(t) as usize)
                    .copied()
                    .flatten();
                if let Some(q) = truth {
                    scored.push((q, corners, weights));
                }
            }
            crate::surface_errors(graph, target.area, &scored)
        }
        Some(truth) => {
            let common_to_template =
                |c: u32| template.prepared_ids.get(c as usize).copied().flatten();
            let mut visible = vec![false; template.num_vertices()];
            for c in truth.iter().flatten() {
                if let Some(p) = common_to_template(*c) {
                    visible[p as usize] = true;
                }
            }
            for &(t, corners, weights) in points {
                if !visible[t as usize] {
                    continue;
                }
                let landed = corners.map(|c| {
                    truth
                        .get(target.input_id(c) as usize)
                        .copied()
                        .flatten()
                        .and_then(common_to_template)
                });
                let total: f64 = (0..3)
                    .filter(|&k| landed[k].is_some())
                    .map(|k| weights[k])
                    .sum();
                // The corner the vertex match names carries the point when the others lack truth.
                let Some(first) = landed.iter().flatten().next().copied() else {
                    continue;
                };
                let mut u = [first; 3];
                let mut w = [0.0; 3];
                for k in 0..3 {
                    if let Some(c) = landed[k] {
                        u[k] = c;
                        w[k] = if total > 0.0 { weights[k] / total } else { 0.0 };
                    }
                }
                if total <= 0.0 {
                    w = [1.0, 0.0, 0.0];
                    u[0] = first;
                }
                scored.push((t, u, w));
            }
            crate::surface_errors(graph, template.area, &scored)
        }
    }
}

/// [`evaluate_pair`] for a partial target: on the template's graph (see the module docs).
fn evaluate_partial(
    template: &MeshIds<'_>,
    target: &MeshIds<'_>,
    target_truth: &[Option<u32>],
    graph: &EvalGraph,
    matches: &[Pair],
    mirror: Option<&[u32]>,
) -> (Evaluation, Vec<f64>) {
    // Common id = template input id → template prepared id.
    let to_template = template.prepared_ids;
    let common_to_template = |c: u32| to_template.get(c as usize).copied().flatten();
    let mut visible = vec![false; template.num_vertices()];
    for c in target_truth.iter().flatten() {
        if let Some(p) = common_to_template(*c) {
            visible[p as usize] = true;
        }
    }
    let mut pairs = Vec::with_capacity(matches.len());
    let mut confidence = Vec::with_capacity(matches.len());
    for m in matches {
        if !visible[m.template as usize] {
            continue;
        }
        let landed = target_truth
            .get(target.input_id(m.target) as usize)
            .copied()
            .flatten()
            .and_then(common_to_template);
        if let Some(c) = landed {
            pairs.push((m.template, c));
            confidence.push(m.confidence);
        }
    }
    let mirror: Option<Vec<u32>> = mirror.map(|m| {
        (0..template.num_vertices() as u32)
            .map(|v| {
                m.get(template.input_id(v) as usize)
                    .and_then(|&c| common_to_template(c))
                    .unwrap_or(v)
            })
            .collect()
    });
    let evaluation = evaluate(graph, template.area, &pairs, |p| p, mirror.as_deref());
    (evaluation, confidence)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dataset folder with meshes/joints for `names` (contents are not read by `open`).
    fn folder(names: &[&str], pairs: &str) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for sub in ["meshes", "joints"] {
            std::fs::create_dir(dir.path().join(sub)).unwrap();
        }
        for n in names {
            std::fs::write(dir.path().join(format!("meshes/{n}.off")), "").unwrap();
            std::fs::write(dir.path().join(format!("meshes/{n}.obj")), "").unwrap();
            std::fs::write(dir.path().join(format!("joints/{n}.json")), "").unwrap();
        }
        std::fs::write(dir.path().join("pairs.txt"), pairs).unwrap();
        dir
    }

    fn message(e: EvalError) -> String {
        e.to_string()
    }

    #[test]
    fn open_reads_pairs_and_prefers_off() {
        let dir = folder(&["a", "b"], "# comment\n\na b\nb a # back\n");
        let ds = Dataset::open(dir.path(), None).unwrap();
        assert_eq!(ds.pairs.len(), 2);
        assert_eq!(ds.used_names(), ["a", "b"]);
        assert!(ds.meshes["a"].ends_with("meshes/a.off"));
        assert!(ds.mirror.is_none() && ds.truth.is_empty());
    }

    #[test]
    fn bad_folders_name_the_file_and_the_line() {
        let dir = folder(&["a", "b"], "a b\na c\n");
        let e = message(Dataset::open(dir.path(), None).unwrap_err());
        assert!(e.contains("pairs.txt: line 2: no mesh meshes/c."), "{e}");
        let dir = folder(&["a", "b"], "a b c\n");
        let e = message(Dataset::open(dir.path(), None).unwrap_err());
        assert!(e.contains("line 1: expected `template target`"), "{e}");
        let dir = folder(&["a", "b"], "# nothing\n");
        let e = message(Dataset::open(dir.path(), None).unwrap_err());
        assert!(e.ends_with("pairs.txt: no pairs"), "{e}");
        let dir = folder(&["a", "b"], "a b\n");
        std::fs::write(dir.path().join("mirror.txt"), "1\n0\n5\n").unwrap();
        let e = message(Dataset::open(dir.path(), None).unwrap_err());
        assert!(
            e.contains("mirror.txt: entry 2: vertex 5 out of range"),
            "{e}"
        );
        std::fs::write(dir.path().join("mirror.txt"), "1\nx\n").unwrap();
        let e = message(Dataset::open(dir.path(), None).unwrap_err());
        assert!(e.contains("mirror.txt: line 2: not a vertex index"), "{e}");
    }

    #[test]
    fn check_pair_compares_vertex_counts_truth_and_mirror() {
        let dir = folder(&["a", "b"], "a b\n");
        std::fs::write(dir.path().join("mirror.txt"), "1\n0\n").unwrap();
        std::fs::create_dir(dir.path().join("truth")).unwrap();
        std::fs::write(dir.path().join("truth/b.txt"), "1\n-1\n0\n").unwrap();
        let ds = Dataset::open(dir.path(), None).unwrap();
        let truth = read_truth(&ds.truth["b"]).unwrap();
        assert_eq!(truth, [Some(1), None, Some(0)]);
        ds.check_pair(("a", "b"), (2, 3), Some(&truth)).unwrap();
        let e = message(ds.check_pair(("a", "b"), (2, 4), Some(&truth)).unwrap_err());
        assert!(e.contains("b.txt: 3 lines, meshes/b has 4 vertices"), "{e}");
        let e = message(ds.check_pair(("a", "b"), (2, 3), None).unwrap_err());
        assert!(e.contains("pair a b: 2 and 3 vertices"), "{e}");
        let e = message(ds.check_pair(("a", "b"), (1, 3), Some(&truth)).unwrap_err());
        assert!(e.contains("an id ≥ 1"), "{e}");
        let e = message(ds.check_pair(("a", "b"), (3, 3), None).unwrap_err());
        assert!(e.contains("mirror.txt: 2 entries"), "{e}");
        // A template with a truth table is refused when the folder is opened.
        std::fs::write(dir.path().join("truth/a.txt"), "0\n").unwrap();
        let e = message(Dataset::open(dir.path(), None).unwrap_err());
        assert!(e.contains("a is a template"), "{e}");
    }
}
