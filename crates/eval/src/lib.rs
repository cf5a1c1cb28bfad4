//! Evaluation of symcorr's correspondences — measurement, not matching: the paper's metrics
//! (DESIGN.md, Metrics) and the benchmark datasets they are measured on (DESIGN.md, Benchmark
//! datasets). Nothing here feeds a matcher.
//!
//! # Data flow
//! * [`Dataset::open`] reads a dataset folder: mesh and joint files by name, `pairs.txt`, the
//!   optional `mirror.txt` ([`read_mirror`]) and, for single-view scans, `truth/NAME.txt`
//!   ([`read_truth`]). Reading the meshes and joints and running a matcher is the caller's
//!   part (`symcorr bench`); [`Dataset::check_pair`] then checks the pair's vertex counts.
//! * [`evaluate_pair`] turns a pair's matches ([`symcorr_correspond::Pair`], in the ids of the
//!   meshes the matcher worked on, related to the files' ids by [`MeshIds`]) into an
//!   [`Evaluation`]: per match the geodesic error over √area and whether it is a flip
//!   ([`evaluate`] on an [`EvalGraph`]). [`table1_row`] ranks the matches by confidence.
//! * For a single-view scan, [`ShownPoints`] says which template points it shows (from the
//!   truth table) and [`ScanScores`] counts coverage and the `no_counterpart` precision and
//!   recall.
//! * [`Pooled`] pools the pairs of a run: mean error, flip rate, [`within`], the cumulative
//!   curve ([`cumulative_curve`]) and the mean Table 1 row.
//!
//! ```
//! use symcorr_correspond::Pair;
//! use symcorr_eval::{evaluate_pair, table1_row, Dataset, EvalGraph, MeshIds, Pooled};
//! use symcorr_mesh::TriMesh;
//! // A dataset folder: two meshes in the same vertex order, their joint files, one pair.
//! let dir = tempfile::tempdir().unwrap();
//! let root = dir.path();
//! for sub in ["meshes", "joints"] { std::fs::create_dir(root.join(sub)).unwrap(); }
//! let mesh = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
//! for name in ["a", "b"] {
//!     symcorr_mesh::io::write(root.join(format!("meshes/{name}.off")), &mesh, None).unwrap();
//!     std::fs::write(root.join(format!("joints/{name}.json")), "{}").unwrap();
//! }
//! std::fs::write(root.join("pairs.txt"), "a b  # template target\n").unwrap();
//! std::fs::write(root.join("mirror.txt"), "0\n2\n1\n").unwrap();
//! let ds = Dataset::open(root, None).unwrap();
//! assert_eq!(ds.pairs, [("a".to_string(), "b".to_string())]);
//! ds.check_pair(("a", "b"), (3, 3), None).unwrap();
//! // A matcher's output (here: vertex 1 sent onto its mirror image 2), scored.
//! let ids = MeshIds { input_ids: &[0, 1, 2], prepared_ids: &[Some(0), Some(1), Some(2)], area: mesh.total_area() };
//! let matches = [Pair { template: 0, target: 0, confidence: 1.0 }, Pair { template: 1, target: 2, confidence: 0.5 }];
//! let (e, confidence) = evaluate_pair(&ids, &ids, None, &EvalGraph::new(&mesh), &matches, ds.mirror.as_deref());
//! assert_eq!(e.errors[0], 0.0);
//! assert_eq!(e.flips[1], Some(true));
//! let row = table1_row(&e.errors, &confidence);
//! let run = Pooled::new([(&e, &row)]);
//! assert_eq!(run.flip_rate(), Some(1.0)); // vertex 0 is its own mirror image: not counted
//! ```
//!
//! # Conventions
//! * Errors are edge-path (Dijkstra) geodesics over √area of the target, stopped at the ground
//!   truth; a flip is counted only where a point and its mirror image are more than
//!   [`FLIP_MIN_SEPARATION`]·√area apart (details at [`evaluate`]).
//! * A partial target (a `truth/NAME.txt`) is scored on the template's surface, only on the
//!   template points it shows (`docs/decisions/2026-11-23-partial-targets-scored-on-template.md`).
//! * Every file error is an [`EvalError`] naming the file and, for text files, the line.

mod dataset;
mod metrics;
mod scan;

pub use dataset::{
    evaluate_pair, evaluate_surface_pair, read_mirror, read_truth, Dataset, EvalError, MeshIds,
    Pooled,
};
pub use metrics::{
    cumulative_curve, evaluate, surface_errors, table1_row, within, EvalGraph, Evaluation,
    FLIP_MIN_SEPARATION,
};
pub use scan::{ScanScores, ShownPoints, SHOWN_BAND};
