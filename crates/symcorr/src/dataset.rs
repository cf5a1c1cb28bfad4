//! Benchmark datasets in DESIGN.md's layout and the benchmark runner behind `symcorr bench`.
//!
//! A dataset is a folder with `meshes/NAME.{off,ply,obj,gltf,glb}` (the same vertex order in
//! every mesh, so the ground truth of template vertex `p` is target vertex `p`),
//! `joints/NAME.*` (any joint format symcorr-kinect reads), an optional `mirror.txt` (line `i`:
//! the vertex mirror-symmetric to vertex `i`) and `pairs.txt` (`template target` per line;
//! blank lines and `#` comments ignored).
//!
//! Each mesh is prepared once ([`PreparedMesh`]), then the pairs run in parallel (rayon).

use crate::{Correspondence, Pipeline, PipelineError, PreparedMesh};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr_attach::Skeleton;
use symcorr_correspond::{cumulative_curve, evaluate, table1_row, EvalGraph, Evaluation};

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
        Ok(Dataset {
            root: root.to_path_buf(),
            meshes,
            joints,
            mirror,
            pairs: list,
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
            .map(|p| p.correspondence.filter.fallbacks)
            .sum()
    }
}

/// Evaluates `corr` against the identity ground truth of a dataset (input vertex `i` of the
/// template corresponds to input vertex `i` of the target) on `target`'s evaluation graph
/// (built on its repaired mesh), with `mirror` (input ids of the target) for the flip rate.
///
/// The stages run on repaired meshes, so ids are translated: template id → input id = the
/// target's input id of the truth → the target's repaired id. A match whose true point the
/// target's repair removed is left out of the evaluation.
pub fn evaluate_identity(
    template: &PreparedMesh,
    target: &PreparedMesh,
    graph: &EvalGraph,
    corr: &Correspondence,
    mirror: Option<&[u32]>,
) -> (Evaluation, Vec<f64>) {
    let to_target = target.prepared_ids();
    let mut pairs = Vec::with_capacity(corr.matches.len());
    let mut truth = Vec::with_capacity(corr.matches.len());
    let mut confidence = Vec::with_capacity(corr.matches.len());
    for m in &corr.matches {
        let input = template.input_id(m.template) as usize;
        if let Some(&Some(q)) = to_target.get(input) {
            truth.push(q);
            pairs.push((truth.len() as u32 - 1, m.target));
            confidence.push(m.confidence);
        }
    }
    // The mirror map in the target's repaired ids (a removed mirror image maps to itself:
    // such a point cannot be counted as a flip).
    let mirror: Option<Vec<u32>> = mirror.map(|m| {
        (0..target.num_vertices() as u32)
            .map(|v| {
                m.get(target.input_id(v) as usize)
                    .and_then(|&i| to_target.get(i as usize).copied().flatten())
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

/// Progress events of [`run_bench`].
#[derive(Debug, Clone, Copy)]
pub enum Progress {
    /// Preparing meshes: `done` of `total`.
    Prepared { done: usize, total: usize },
    /// Matching pairs: `done` of `total`.
    Matched { done: usize, total: usize },
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
        if na != nb {
            return Err(file_err(
                &dataset.root,
                format!(
                    "pair {a} {b}: {na} and {nb} vertices; a benchmark needs the same vertex order in every mesh",
                ),
            ));
        }
        if let Some(m) = &dataset.mirror {
            if m.len() != nb || m.iter().any(|&i| i as usize >= nb) {
                return Err(file_err(
                    &dataset.root.join("mirror.txt"),
                    format!(
                        "{} entries (or an id ≥ {nb}): the meshes have {nb} vertices",
                        m.len(),
                    ),
                ));
            }
        }
    }
    // Evaluation graphs per target, built once.
    let graphs: BTreeMap<&str, EvalGraph> = dataset
        .pairs
        .iter()
        .map(|(_, b)| b.as_str())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .map(|b| (b, EvalGraph::new(&prepared[index[b]].1.mesh)))
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
            let (evaluation, conf) = evaluate_identity(
                &ta.1,
                &tb.1,
                &graphs[b.as_str()],
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
