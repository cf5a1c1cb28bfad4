//! The benchmark runner behind `symcorr bench`: a dataset folder (symcorr-eval's [`Dataset`],
//! DESIGN.md's layout) run through a [`Pipeline`] and scored by symcorr-eval.
//!
//! Each mesh is read ([`crate::io`]) and prepared once ([`PreparedMesh`]), then the pairs run in
//! parallel (rayon); [`evaluate_pair`] scores a pair in the input files' ids, whatever the
//! mesh repair changed.

use crate::{Correspondence, Pipeline, PipelineError, PreparedMesh};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::time::Instant;
use symcorr_eval::{
    table1_row, Dataset, EvalGraph, Evaluation, MeshIds, Pooled, ScanScores, ShownPoints,
};

/// The result of one pair.
#[derive(Debug, Clone)]
pub struct PairResult {
    /// Template name.
    pub template: String,
    /// Target name.
    pub target: String,
    /// The correspondence ([`Pipeline::run_on_view`], as `symcorr match` runs it).
    pub correspondence: Correspondence,
    /// The target prepared anew on its joints turned half a turn about their spine, when
    /// [`Pipeline::run_on_view`] kept that fit ([`crate::ViewMatch::turned_target`]); the
    /// correspondence then refers to it.
    pub turned_target: Option<PreparedMesh>,
    /// Per-match errors and flips.
    pub evaluation: Evaluation,
    /// Table 1 row of this pair.
    pub table1_row: [f64; 10],
    /// A single-view target's coverage and `no_counterpart` counts (symcorr-eval's
    /// [`ScanScores`]); `None` for a whole surface.
    pub scan: Option<ScanScores>,
    /// The articulated method: the errors of the matches as surface points
    /// ([`Correspondence::surface_points`], symcorr-eval's `evaluate_surface_pair`); `None`
    /// for the methods that give vertices only.
    pub surface_errors: Option<Vec<f64>>,
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
    /// The pairs' scores pooled (symcorr-eval's [`Pooled`]): every match counts once.
    pub fn pooled(&self) -> Pooled {
        Pooled::new(self.pairs.iter().map(|p| (&p.evaluation, &p.table1_row)))
    }

    /// Mean error over all matches of all pairs.
    pub fn mean_error(&self) -> f64 {
        self.pooled().mean_error()
    }

    /// Flips over counted matches, all pairs (`None` without a mirror map).
    pub fn flip_rate(&self) -> Option<f64> {
        self.pooled().flip_rate()
    }

    /// Fraction of all matches with error ≤ x.
    pub fn within(&self, x: f64) -> f64 {
        self.pooled().within(x)
    }

    /// Mean error of the matches as surface points over all pairs (`None` unless every pair
    /// has them: the articulated method).
    pub fn surface_mean_error(&self) -> Option<f64> {
        let mut sum = 0.0;
        let mut n = 0usize;
        for p in &self.pairs {
            let e = p.surface_errors.as_ref()?;
            sum += e.iter().sum::<f64>();
            n += e.len();
        }
        (n > 0).then(|| sum / n as f64)
    }

    /// Table 1 row averaged over pairs.
    pub fn table1_row(&self) -> [f64; 10] {
        self.pooled().table1_row()
    }

    /// Mean standalone seconds per pair ([`PairResult::seconds`]).
    pub fn seconds_per_pair(&self) -> f64 {
        self.pairs.iter().map(|p| p.seconds).sum::<f64>() / self.pairs.len().max(1) as f64
    }

    /// The cumulative error curve of all matches on [0, 0.25].
    pub fn curve(&self) -> Vec<(f64, f64)> {
        self.pooled().curve()
    }

    /// The scan pairs' coverage and `no_counterpart` counts summed (`None` without scans).
    pub fn scan_scores(&self) -> Option<ScanScores> {
        self.pairs
            .iter()
            .filter_map(|p| p.scan)
            .reduce(|a, b| a + b)
    }

    /// Skeleton-filter fallbacks over all pairs.
    pub fn fallbacks(&self) -> usize {
        self.pairs
            .iter()
            .map(|p| p.correspondence.filter_stats().fallbacks)
            .sum()
    }
}

/// Scores `corr` against the dataset's ground truth (symcorr-eval's
/// [`symcorr_eval::evaluate_pair`]), translating the prepared meshes' ids through their
/// repairs ([`PreparedMesh::input_id`], [`PreparedMesh::prepared_ids`]). `graph` is the
/// evaluation graph of the target's prepared mesh — or, with `target_truth` (a partial scan),
/// of the template's.
///
/// On a partial target only the matches with a counterpart are scored: the points listed
/// under `no_counterpart` are not matches of the output (coverage counts them,
/// [`ScanScores`]).
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
    let (ta, tb) = (template.prepared_ids(), target.prepared_ids());
    let listed: Vec<symcorr_correspond::Pair> = match corr.has_counterpart() {
        Some(h) => corr
            .pairs
            .iter()
            .zip(h)
            .filter(|(_, &h)| h)
            .map(|(m, _)| *m)
            .collect(),
        None => corr.pairs.clone(),
    };
    symcorr_eval::evaluate_pair(
        &mesh_ids(template, &ta),
        &mesh_ids(target, &tb),
        target_truth,
        graph,
        &listed,
        mirror,
    )
}

/// The errors of `corr`'s matches as surface points ([`Correspondence::surface_points`]),
/// scored where [`evaluate_pair`] scores them (symcorr-eval's
/// [`symcorr_eval::evaluate_surface_pair`]); `None` for a method that gives vertices only.
pub fn evaluate_surface_points(
    template: &PreparedMesh,
    target: &PreparedMesh,
    target_truth: Option<&[Option<u32>]>,
    graph: &EvalGraph,
    corr: &Correspondence,
) -> Option<Vec<f64>> {
    let points = corr.surface_points(target)?;
    let h = corr.has_counterpart();
    let listed: Vec<(u32, [u32; 3], [f64; 3])> = corr
        .pairs
        .iter()
        .zip(&points)
        .enumerate()
        .filter(|(i, _)| h.is_none_or(|h| h[*i]))
        .map(|(_, (m, p))| (m.template, p.corners, p.weights))
        .collect();
    let (ta, tb) = (template.prepared_ids(), target.prepared_ids());
    Some(symcorr_eval::evaluate_surface_pair(
        &mesh_ids(template, &ta),
        &mesh_ids(target, &tb),
        target_truth,
        graph,
        &listed,
    ))
}

/// A single-view target's coverage and `no_counterpart` counts against its truth table
/// (symcorr-eval's [`ShownPoints`] and [`ScanScores`]); `None` when the correspondence says
/// nothing about counterparts. `neighbors`: the template's prepared mesh's edge graph.
pub fn scan_scores(
    template: &PreparedMesh,
    neighbors: &[Vec<u32>],
    target_truth: &[Option<u32>],
    corr: &Correspondence,
) -> Option<ScanScores> {
    let h = corr.has_counterpart()?;
    let ta = template.prepared_ids();
    let shown = ShownPoints::new(
        &mesh_ids(template, &ta),
        &template.mesh.positions,
        neighbors,
        target_truth,
    );
    let points: Vec<u32> = corr.pairs.iter().map(|m| m.template).collect();
    Some(ScanScores::new(&shown, &points, h))
}

fn mesh_ids<'a>(p: &'a PreparedMesh, prepared_ids: &'a [Option<u32>]) -> MeshIds<'a> {
    MeshIds {
        input_ids: &p.vertex_map,
        prepared_ids,
        area: p.area,
    }
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
    max_input_bytes: u64,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<BenchReport, PipelineError> {
    let start = Instant::now();
    let names = dataset.used_names();
    let total = names.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut truths: BTreeMap<&str, Vec<Option<u32>>> = BTreeMap::new();
    for (name, path) in &dataset.truth {
        if names.contains(name) {
            truths.insert(name.as_str(), symcorr_eval::read_truth(path)?);
        }
    }
    let prepared: Vec<(String, PreparedMesh, f64)> = names
        .par_iter()
        .map(|name| {
            let t = Instant::now();
            let mesh_path = &dataset.meshes[name];
            let in_mesh = |e: PipelineError| PipelineError::File {
                file: mesh_path.display().to_string(),
                message: e.to_string(),
            };
            let mesh = crate::io::read_mesh(mesh_path, max_input_bytes)?;
            let sk = crate::io::read_skeleton(&dataset.joints[name], frame)?;
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
        dataset.check_pair(
            (a, b),
            (
                pa.input_mesh().num_vertices(),
                pb.input_mesh().num_vertices(),
            ),
            truths.get(b.as_str()).map(Vec::as_slice),
        )?;
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
    // Template edge graphs of the scan pairs (the band of ShownPoints).
    let neighbors: BTreeMap<&str, Vec<Vec<u32>>> = dataset
        .pairs
        .iter()
        .filter(|(_, b)| truths.contains_key(b.as_str()))
        .map(|(a, _)| {
            (
                a.as_str(),
                prepared[index[a.as_str()]].1.mesh.vertex_neighbors(),
            )
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
            // A pair's error names the pair: the same meshes may be fine in other pairs.
            let matched = pipeline
                .run_on_view(&ta.1, &tb.1)
                .map_err(|e| PipelineError::File {
                    file: format!("pair {a} → {b}"),
                    message: e.to_string(),
                })?;
            let match_seconds = t.elapsed().as_secs_f64();
            let (corr, turned_target) = (matched.correspondence, matched.turned_target);
            let target = turned_target.as_ref().unwrap_or(&tb.1);
            let (evaluation, conf) = evaluate_pair(
                &ta.1,
                target,
                truths.get(b.as_str()).map(Vec::as_slice),
                &graphs[&graph_of(a, b)],
                &corr,
                dataset.mirror.as_deref(),
            );
            let row = table1_row(&evaluation.errors, &conf);
            let surface_errors = evaluate_surface_points(
                &ta.1,
                target,
                truths.get(b.as_str()).map(Vec::as_slice),
                &graphs[&graph_of(a, b)],
                &corr,
            );
            let scan = match (truths.get(b.as_str()), neighbors.get(a.as_str())) {
                (Some(t), Some(nb)) => scan_scores(&ta.1, nb, t, &corr),
                _ => None,
            };
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(Progress::Matched {
                done: d,
                total: total_pairs,
            });
            Ok(PairResult {
                template: a.clone(),
                target: b.clone(),
                correspondence: corr,
                turned_target,
                evaluation,
                table1_row: row,
                scan,
                surface_errors,
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
        // Only the matches with a counterpart are scored; coverage counts the others.
        let has = corr.has_counterpart().unwrap();
        let listed = corr
            .pairs
            .iter()
            .zip(has)
            .filter(|(m, &h)| h && target_of(m.template).is_some())
            .count();
        assert!(listed > visible / 2, "{listed} of {visible}");
        let (e, conf) = evaluate_pair(&a, &b, Some(&truth), &graph, &perfect, Some(&mirror));
        assert_eq!(e.errors.len(), listed);
        assert_eq!(conf.len(), listed);
        let scores = scan_scores(&a, &a.mesh.vertex_neighbors(), &truth, &corr).unwrap();
        assert_eq!(scores.shown, visible);
        assert_eq!(scores.shown_matched, listed);
        assert!(scores.hidden > 0 && scores.hidden + visible <= 200);
        assert!(e.mean_error() < 1e-12, "{}", e.mean_error());
        assert_eq!(e.flip_rate(), Some(0.0));
        let (e, _) = evaluate_pair(&a, &b, Some(&truth), &graph, &mirrored, Some(&mirror));
        assert!(e.mean_error() > 0.05, "{}", e.mean_error());
        assert!(e.flip_rate().unwrap() > 0.5, "{:?}", e.flip_rate());
    }
}
