//! Golden files of the output formats (temporary generator, run once with the writer as it was).

use std::path::Path;
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
    let triangles = front.iter().map(|t| t.map(|v| new_id[v as usize])).collect();
    TriMesh::new(positions, triangles).unwrap()
}

#[test]
fn generate_correspondence_golden() {
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
        let doc = correspondence_json("a.ply", &a, "b dir/\"b\".ply", &b, &corr, &timings);
        let text = serde_json::to_string(&doc).unwrap();
        std::fs::write(golden_dir().join(format!("correspondence_{name}.json")), text).unwrap();
    }
}
