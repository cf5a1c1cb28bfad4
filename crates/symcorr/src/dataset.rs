//! Benchmark datasets in DESIGN.md's layout and the benchmark runner behind `symcorr bench`.
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
//! Each mesh is prepared once ([`PreparedMesh`]), then the pairs run in parallel (rayon).

use crate::{Correspondence, Pipeline, PipelineError, PreparedMesh};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr_correspond::{cumulative_curve, evaluate, table1_row, EvalGraph, Evaluation};
use symcorr_skeleton::Skeleton;

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

fn file_err(path: &Path, message: impl Into<String>) -> PipelineError {
    PipelineError::File {
        file: path.display().to_string(),
        message: message.into(),
    }
}

fn list_by_stem(
    dir: &Path,
    accept: impl Fn(&str) -> bool,
) -> Result<BTreeMap<String, PathBuf>, PipelineError> {
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
    /// Errors ([`PipelineError::File`]): a missing `meshes/` or `joints/` folder, no pairs file,
    /// a malformed line in it, a pair naming a mesh or joint file that does not exist, a
    /// malformed `mirror.txt`.
    pub fn open(root: &Path, pairs: Option<&Path>) -> Result<Dataset, PipelineError> {
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
pub fn read_truth(path: &Path) -> Result<Vec<Option<u32>>, PipelineError> {
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
pub fn read_mirror(path: &Path) -> Result<Vec<u32>, PipelineError> {
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

/// Reads a joint file (any supported format, detected from the content) and picks a frame
/// (`None`: the first).
pub fn read_skeleton(path: &Path, frame: Option<usize>) -> Result<Skeleton, PipelineError> {
    read_skeleton_as(path, frame, None)
}

/// Like [`read_skeleton`], with the joint format forced (`--joints-format`) instead of detected
/// from the content when `format` is `Some`.
pub fn read_skeleton_as(
    path: &Path,
    frame: Option<usize>,
    format: Option<symcorr_kinect::JointFormat>,
) -> Result<Skeleton, PipelineError> {
    let log = match format {
        Some(f) => symcorr_kinect::read_joints_with_format(path, f)?,
        None => symcorr_kinect::read_joints(path)?,
    };
    let n = log.frames.len();
    let i = frame.unwrap_or(0);
    log.frames
        .into_iter()
        .nth(i)
        .map(|f| f.skeleton)
        .ok_or_else(|| {
            file_err(
                path,
                format!("frame {i} requested, the file has {n} frame(s)"),
            )
        })
}

/// Reads a mesh file.
pub fn read_mesh(path: &Path) -> Result<symcorr_mesh::TriMesh, PipelineError> {
    Ok(symcorr_mesh::io::read(path)?.mesh)
}

/// The result of one pair.
#[derive(Debug, Clone)]
pub struct PairResult {
    /// Template name.
    pub template: String,
    /// Target name.
    pub target: String,
    /// The correspondence.
    pub correspondence: Correspondence,
    /// Per-match errors and flips.
    pub evaluation: Evaluation,
    /// Table 1 row of this pair.
    pub table1_row: [f64; 10],
    /// Seconds the pair costs on its own: preparing both meshes plus matching.
    pub seconds: f64,
    /// Seconds of the pair stages alone (meshes already prepared).
    pub match_seconds: f64,
}

/// A whole benchmark run.
#[derive(Debug, Clone)]
pub struct BenchReport {
    /// Per pair, in the order of the pairs file.
    pub pairs: Vec<PairResult>,
    /// Seconds to prepare each mesh.
    pub prepare_seconds: BTreeMap<String, f64>,
    /// Wall-clock seconds of the whole run (preparation, matching and evaluation).
    pub wall_seconds: f64,
    /// The prepared meshes by name (labels, descriptors, … for writing outputs).
    pub prepared: BTreeMap<String, PreparedMesh>,
}

impl BenchReport {
    /// Mean error over all matches of all pairs.
    pub fn mean_error(&self) -> f64 {
        let (s, n) = self.pairs.iter().fold((0.0, 0usize), |(s, n), p| {
            (
                s + p.evaluation.errors.iter().sum::<f64>(),
                n + p.evaluation.errors.len(),
            )
        });
        if n == 0 {
            0.0
        } else {
            s / n as f64
        }
    }

    /// Flips over counted matches, all pairs (`None` without a mirror map).
    pub fn flip_rate(&self) -> Option<f64> {
        let (c, f) = self.pairs.iter().fold((0, 0), |(c, f), p| {
            let (pc, pf) = p.evaluation.flip_counts();
            (c + pc, f + pf)
        });
        (c > 0).then(|| f as f64 / c as f64)
    }

    /// All errors of all pairs.
    pub fn all_errors(&self) -> Vec<f64> {
        self.pairs
            .iter()
            .flat_map(|p| p.evaluation.errors.iter().copied())
            .collect()
    }

    /// Fraction of all matches with error ≤ x.
    pub fn within(&self, x: f64) -> f64 {
        symcorr_correspond::within(&self.all_errors(), x)
    }

    /// Table 1 row averaged over pairs.
    pub fn table1_row(&self) -> [f64; 10] {
        let mut row = [0.0; 10];
        for p in &self.pairs {
            for (r, x) in row.iter_mut().zip(p.table1_row) {
                *r += x / self.pairs.len().max(1) as f64;
            }
        }
        row
    }

    /// Mean standalone seconds per pair ([`PairResult::seconds`]).
    pub fn seconds_per_pair(&self) -> f64 {
        self.pairs.iter().map(|p| p.seconds).sum::<f64>() / self.pairs.len().max(1) as f64
    }

    /// The cumulative error curve of all matches on [0, 0.25].
    pub fn curve(&self) -> Vec<(f64, f64)> {
        cumulative_curve(&self.all_errors(), 0.25, 100)
    }

    /// Skeleton-filter fallbacks over all pairs.
    pub fn fallbacks(&self) -> usize {
        self.pairs
            .iter()
            .map(|p| p.correspondence.filter_stats().fallbacks)
            .sum()
    }
}

/// Evaluates `corr` against the dataset's ground truth, with `mirror` (common-order ids) for
/// the flip rate. `graph` is the evaluation graph of the target's repaired mesh — or, with
/// `target_truth`, of the template's.
///
/// Without `target_truth`, input vertex `i` of the template corresponds to input vertex `i` of
/// the target (DESIGN.md's layout). With it (a partial scan, see the module docs), target
/// input vertex `v` corresponds to common id `target_truth[v]`; only visible template points
/// are evaluated, on the template's surface. The stages run on repaired
/// meshes, so ids are translated through [`PreparedMesh::input_id`] and
/// [`PreparedMesh::prepared_ids`]; a match whose true point the repair removed is left out.
///
/// Returns the evaluation and the confidences of the evaluated matches (for the Table 1 row).
pub fn evaluate_pair(
    template: &PreparedMesh,
    target: &PreparedMesh,
    target_truth: Option<&[Option<u32>]>,
    graph: &EvalGraph,
    corr: &Correspondence,
    mirror: Option<&[u32]>,
) -> (Evaluation, Vec<f64>) {
    if let Some(t) = target_truth {
        return evaluate_partial(template, target, t, graph, corr, mirror);
    }
    // Input id i of the template is input id i of the target; both through their repairs.
    let to_target = target.prepared_ids();
    let common_to_target = |c: u32| -> Option<u32> { *to_target.get(c as usize)? };
    let mut pairs = Vec::with_capacity(corr.pairs.len());
    let mut truth = Vec::with_capacity(corr.pairs.len());
    let mut confidence = Vec::with_capacity(corr.pairs.len());
    for m in &corr.pairs {
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

/// [`evaluate_pair`] for a partial target: on the template's graph (see the module docs).
fn evaluate_partial(
    template: &PreparedMesh,
    target: &PreparedMesh,
    target_truth: &[Option<u32>],
    graph: &EvalGraph,
    corr: &Correspondence,
    mirror: Option<&[u32]>,
) -> (Evaluation, Vec<f64>) {
    // Common id = template input id → template prepared id.
    let to_template = template.prepared_ids();
    let common_to_template = |c: u32| to_template.get(c as usize).copied().flatten();
    let mut visible = vec![false; template.num_vertices()];
    for c in target_truth.iter().flatten() {
        if let Some(p) = common_to_template(*c) {
            visible[p as usize] = true;
        }
    }
    let mut pairs = Vec::with_capacity(corr.pairs.len());
    let mut confidence = Vec::with_capacity(corr.pairs.len());
    for m in &corr.pairs {
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

/// Progress events of [`run_bench`].
#[derive(Debug, Clone, Copy)]
pub enum Progress {
    /// Preparing meshes.
    Prepared {
        /// Meshes prepared so far.
        done: usize,
        /// Meshes to prepare.
        total: usize,
    },
    /// Matching pairs.
    Matched {
        /// Pairs matched so far.
        done: usize,
        /// Pairs to match.
        total: usize,
    },
}

/// Runs every pair of `dataset` with `pipeline`: prepares each mesh once, matches the pairs in
/// parallel, evaluates against the identity ground truth and `mirror.txt`.
///
/// Errors: a mesh or joint file that does not read, a stage failing on some mesh (the error
/// names the mesh), meshes of a pair with different vertex counts, a mirror map of the wrong
/// length.
pub fn run_bench(
    dataset: &Dataset,
    pipeline: &Pipeline,
    frame: Option<usize>,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<BenchReport, PipelineError> {
    let start = Instant::now();
    let names = dataset.used_names();
    let total = names.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut truths: BTreeMap<&str, Vec<Option<u32>>> = BTreeMap::new();
    for (name, path) in &dataset.truth {
        if names.contains(name) {
            truths.insert(name.as_str(), read_truth(path)?);
        }
    }
    let prepared: Vec<(String, PreparedMesh, f64)> = names
        .par_iter()
        .map(|name| {
            let t = Instant::now();
            let mesh_path = &dataset.meshes[name];
            let in_mesh = |e: PipelineError| file_err(mesh_path, e.to_string());
            let mesh = read_mesh(mesh_path)?;
            let sk = read_skeleton(&dataset.joints[name], frame)?;
            let p = pipeline.prepare(mesh, &sk).map_err(in_mesh)?;
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(Progress::Prepared { done: d, total });
            Ok((name.clone(), p, t.elapsed().as_secs_f64()))
        })
        .collect::<Result<_, PipelineError>>()?;
    let index: BTreeMap<&str, usize> = prepared
        .iter()
        .enumerate()
        .map(|(i, (n, _, _))| (n.as_str(), i))
        .collect();
    for (a, b) in &dataset.pairs {
        let (pa, pb) = (
            &prepared[index[a.as_str()]].1,
            &prepared[index[b.as_str()]].1,
        );
        let (na, nb) = (
            pa.input_mesh().num_vertices(),
            pb.input_mesh().num_vertices(),
        );
        match truths.get(b.as_str()) {
            None if na != nb => {
                return Err(file_err(
                    &dataset.root,
                    format!(
                        "pair {a} {b}: {na} and {nb} vertices; a benchmark needs the same vertex order in every mesh (or truth/{b}.txt for a partial scan)",
                    ),
                ));
            }
            Some(t) if t.len() != nb => {
                return Err(file_err(
                    &dataset.truth[b],
                    format!("{} lines, meshes/{b} has {nb} vertices", t.len()),
                ));
            }
            Some(t) if t.iter().flatten().any(|&c| c as usize >= na) => {
                return Err(file_err(
                    &dataset.truth[b],
                    format!("an id ≥ {na}, the number of vertices of the template {a}"),
                ));
            }
            _ => {}
        }
        if let Some(m) = &dataset.mirror {
            // The mirror map is in the common order: the template's.
            if m.len() != na || m.iter().any(|&i| i as usize >= na) {
                return Err(file_err(
                    &dataset.root.join("mirror.txt"),
                    format!(
                        "{} entries (or an id ≥ {na}): the meshes have {na} vertices",
                        m.len(),
                    ),
                ));
            }
        }
    }
    // Evaluation graphs per target (per template for a partial target), built once.
    let graph_of = |a: &'_ str, b: &'_ str| -> String {
        if truths.contains_key(b) {
            a.to_string()
        } else {
            b.to_string()
        }
    };
    let graphs: BTreeMap<String, EvalGraph> = dataset
        .pairs
        .iter()
        .map(|(a, b)| graph_of(a, b))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .map(|g| {
            let graph = EvalGraph::new(&prepared[index[g.as_str()]].1.mesh);
            (g, graph)
        })
        .collect();
    let total_pairs = dataset.pairs.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let pairs: Vec<PairResult> = dataset
        .pairs
        .par_iter()
        .map(|(a, b)| {
            let (ta, tb) = (&prepared[index[a.as_str()]], &prepared[index[b.as_str()]]);
            let t = Instant::now();
            let corr = pipeline.run(&ta.1, &tb.1)?;
            let match_seconds = t.elapsed().as_secs_f64();
            let (evaluation, conf) = evaluate_pair(
                &ta.1,
                &tb.1,
                truths.get(b.as_str()).map(Vec::as_slice),
                &graphs[&graph_of(a, b)],
                &corr,
                dataset.mirror.as_deref(),
            );
            let row = table1_row(&evaluation.errors, &conf);
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(Progress::Matched {
                done: d,
                total: total_pairs,
            });
            Ok(PairResult {
                template: a.clone(),
                target: b.clone(),
                correspondence: corr,
                evaluation,
                table1_row: row,
                seconds: ta.2 + tb.2 + match_seconds,
                match_seconds,
            })
        })
        .collect::<Result<_, PipelineError>>()?;
    let prepare_seconds = prepared.iter().map(|(n, _, s)| (n.clone(), *s)).collect();
    let wall_seconds = start.elapsed().as_secs_f64();
    Ok(BenchReport {
        pairs,
        prepare_seconds,
        wall_seconds,
        prepared: prepared.into_iter().map(|(n, p, _)| (n, p)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mode, PipelineOptions};
    use symcorr_attach::testbody::{capsule_body, t_pose};
    use symcorr_mesh::TriMesh;

    /// A partial target (the front half of the capsule body, vertices renumbered in reverse,
    /// plus a stray vertex the repair removes) with its truth table: a perfect map evaluates
    /// to zero error and no flips, its mirror image to flips, and back-side template points
    /// are left out.
    #[test]
    fn partial_target_is_evaluated_through_its_truth_table() {
        let sk = t_pose(1.0);
        let (mesh, _) = capsule_body(&sk, 0.04);
        let n = mesh.num_vertices();
        let p = &mesh.positions;
        let mirror: Vec<u32> = (0..n)
            .map(|v| {
                let q = [-p[v][0], p[v][1], p[v][2]];
                (0..n)
                    .min_by(|&a, &b| {
                        let d = |i: usize| (0..3).map(|k| (p[i][k] - q[k]).powi(2)).sum::<f64>();
                        d(a).total_cmp(&d(b))
                    })
                    .unwrap() as u32
            })
            .collect();
        // Front half: triangles whose centroid has z > 0.
        let front: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().map(|&v| p[v as usize][2]).sum::<f64>() > 0.0)
            .collect();
        let mut used: Vec<u32> = front.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        used.reverse();
        let mut new_id = vec![u32::MAX; n];
        for (i, &v) in used.iter().enumerate() {
            new_id[v as usize] = i as u32;
        }
        let mut positions: Vec<[f64; 3]> = used.iter().map(|&v| p[v as usize]).collect();
        positions.push([9.0, 9.0, 9.0]);
        let triangles = front
            .iter()
            .map(|t| t.map(|v| new_id[v as usize]))
            .collect();
        let mut truth: Vec<Option<u32>> = used.iter().map(|&v| Some(v)).collect();
        truth.push(None);
        let scan = TriMesh::new(positions, triangles).unwrap();

        let pipeline = Pipeline::new(PipelineOptions {
            mode: Mode::Sparse { samples: 200 },
            ..PipelineOptions::default()
        });
        let a = pipeline.prepare(mesh, &sk).unwrap();
        let b = pipeline.prepare(scan, &sk).unwrap();
        assert!(b.repair.removed_vertices >= 1, "the stray vertex goes");
        let corr = pipeline.run(&a, &b).unwrap();
        // Partial targets are measured on the template.
        let graph = EvalGraph::new(&a.mesh);
        let to_b = b.prepared_ids();
        let target_of = |common: u32| -> Option<u32> {
            let v = new_id[common as usize];
            if v == u32::MAX {
                None
            } else {
                to_b[v as usize]
            }
        };
        let visible = corr
            .pairs
            .iter()
            .filter(|m| target_of(m.template).is_some())
            .count();
        assert!(visible > 50 && visible < 180, "{visible} visible of 200");

        let mut perfect = corr.clone();
        let mut mirrored = corr.clone();
        for (m, w) in perfect.pairs.iter_mut().zip(&mut mirrored.pairs) {
            if let Some(q) = target_of(m.template) {
                m.target = q;
            }
            if let Some(q) = target_of(mirror[w.template as usize]) {
                w.target = q;
            }
        }
        let (e, conf) = evaluate_pair(&a, &b, Some(&truth), &graph, &perfect, Some(&mirror));
        assert_eq!(e.errors.len(), visible);
        assert_eq!(conf.len(), visible);
        assert!(e.mean_error() < 1e-12, "{}", e.mean_error());
        assert_eq!(e.flip_rate(), Some(0.0));
        let (e, _) = evaluate_pair(&a, &b, Some(&truth), &graph, &mirrored, Some(&mirror));
        assert!(e.mean_error() > 0.05, "{}", e.mean_error());
        assert!(e.flip_rate().unwrap() > 0.5, "{:?}", e.flip_rate());
    }
}
