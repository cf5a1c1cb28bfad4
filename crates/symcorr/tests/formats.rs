//! The typed `symcorr.correspondence/1` writer against golden files written by the writer it
//! replaced (a `serde_json::json!` document; `fixtures/formats/`, generated once from the same
//! inputs before the change): byte for byte the same text, and the files parse back. The
//! partial file's confidences were rewritten when the articulated confidence gained its region
//! terms on scans (docs/decisions/2026-12-03-confidence-ranking.md) and again when the head's
//! anchor at the neck's base was weakened (docs/decisions/2026-12-04-head-neck-anchor.md: the
//! confidences moved by at most 0.0005); pairs and every other key unchanged.

use std::path::Path;
use symcorr::formats::CorrespondenceFile;
use symcorr::output::correspondence_json;
use symcorr::{Mode, Pipeline, PipelineOptions};
use symcorr_attach::testbody::{capsule_body, t_pose};
use symcorr_mesh::TriMesh;

fn golden_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/formats")
}

/// The front half of `mesh` (centroid z > 0), vertices in reverse order, plus a stray vertex the
/// repair removes: a partial target whose input ids differ from the prepared ones.
fn front_half(mesh: &TriMesh) -> TriMesh {
    let p = &mesh.positions;
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
    let mut new_id = vec![u32::MAX; mesh.num_vertices()];
    for (i, &v) in used.iter().enumerate() {
        new_id[v as usize] = i as u32 + 1;
    }
    let mut positions = vec![[9.0, 9.0, 9.0]];
    positions.extend(used.iter().map(|&v| p[v as usize]));
    let triangles = front
        .iter()
        .map(|t| t.map(|v| new_id[v as usize]))
        .collect();
    TriMesh::new(positions, triangles).unwrap()
}

#[test]
fn correspondence_files_match_the_golden_files_byte_for_byte() {
    let sk = t_pose(1.0);
    let (mesh, _) = capsule_body(&sk, 0.08);
    let scan = front_half(&mesh);
    let pipeline = Pipeline::new(PipelineOptions {
        mode: Mode::Sparse { samples: 60 },
        ..PipelineOptions::default()
    });
    let a = pipeline.prepare(mesh.clone(), &sk).unwrap();
    let timings = vec![
        ("attachment".to_string(), 0.25),
        ("articulated".to_string(), 1.0 / 3.0),
        ("zz_last".to_string(), 2.0),
    ];
    for (name, target) in [("full", mesh), ("partial", scan)] {
        let b = pipeline.prepare(target, &sk).unwrap();
        let corr = pipeline.run(&a, &b).unwrap();
        let mut doc = correspondence_json("a.ply", &a, "b dir/\"b\".ply", &b, &corr, &timings);
        // The articulated method adds the matches as surface points, one per listed pair, on
        // a triangle around the pair's target vertex; the golden files predate the key, and
        // everything else stays byte for byte (files without it still read).
        let surface = doc
            .surface_points
            .take()
            .expect("articulated surface points");
        assert_eq!(surface.len(), doc.pairs.len(), "{name}");
        for ((corners, w), &(_, q, _)) in surface.iter().zip(&doc.pairs) {
            assert!(corners.contains(&q), "{name}: {corners:?} around {q}");
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 3e-6, "{name}: {w:?}");
        }
        let path = golden_dir().join(format!("correspondence_{name}.json"));
        let golden = std::fs::read_to_string(&path).unwrap();
        assert_eq!(doc.to_json(), golden, "{name}");
        // The same parsed values, and the typed reader reads the golden file back.
        let ours: serde_json::Value = serde_json::to_value(&doc).unwrap();
        let theirs: serde_json::Value = serde_json::from_str(&golden).unwrap();
        assert_eq!(ours, theirs, "{name}");
        let back = CorrespondenceFile::read(&path).unwrap();
        assert_eq!(back, doc, "{name}");
        assert_eq!(back.no_counterpart.is_some(), name == "partial");
        if name == "partial" {
            assert!(back.segments.target.iter().any(Option::is_none));
        }
    }
}

#[test]
fn reading_a_wrong_file_names_it_and_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.json");
    let golden = golden_dir().join("correspondence_full.json");
    let text = std::fs::read_to_string(golden).unwrap();
    std::fs::write(
        &path,
        text.replace("symcorr.correspondence/1", "symcorr.labels/1"),
    )
    .unwrap();
    let e = CorrespondenceFile::read(&path).unwrap_err().to_string();
    assert!(
        e.contains("x.json") && e.contains("expected \"symcorr.correspondence/1\""),
        "{e}"
    );
    std::fs::write(&path, "{\"format\": 1}").unwrap();
    let e = CorrespondenceFile::read(&path).unwrap_err().to_string();
    assert!(
        e.contains("x.json: not a symcorr.correspondence/1 file"),
        "{e}"
    );
    let e = CorrespondenceFile::read(&dir.path().join("none.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("none.json"), "{e}");
}
