//! `symcorr view` end to end, without a browser: pages are made from hand-written result files
//! on the bundled bodies, and inputs that do not fit their meshes are refused with one line
//! before any page is written. The pages themselves are driven in Chromium by
//! `tests/browser/` (`.ci/run`).

mod support;

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use support::{bin, read_json, run};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/bodies")
}

fn mesh(name: &str) -> PathBuf {
    fixtures().join("meshes").join(format!("{name}.ply"))
}

/// Vertex count of a bundled body (all share one vertex order).
fn body_vertices() -> usize {
    symcorr_mesh::io::read(mesh("s0_rest"))
        .unwrap()
        .mesh
        .num_vertices()
}

/// A `symcorr.correspondence/1` document: `pairs` between s0_rest and s1_t-pose, both
/// of `n` vertices, every vertex on the torso (segment 1).
fn correspondence(n: usize, pairs: &[(u32, u32, f64)]) -> Value {
    json!({
        "format": "symcorr.correspondence/1",
        "template": {"path": mesh("s0_rest"), "vertices": n},
        "target": {"path": mesh("s1_t-pose"), "vertices": n},
        "pairs": pairs.iter().map(|&(p, q, c)| json!([p, q, c])).collect::<Vec<_>>(),
        "segments": {"template": vec![1; n], "target": vec![1; n]},
        "skeleton_filter": {"fallbacks": 0, "kept": 0, "points": 0, "removed": 0, "segment_missing": 0},
        "timings_s": {},
    })
}

fn labels(path: &Path, n: usize) -> Value {
    json!({
        "format": "symcorr.labels/1",
        "mesh": {"path": path, "vertices": n},
        "segments": ["pelvis", "torso"],
        "labels": (0..n).map(|v| v % 17).collect::<Vec<_>>(),
        "joints": {"hip_center": [0.0, 0.9, 0.0], "spine": [0.0, 1.1, 0.0]},
        "diagnostics": {"alignment": {"fit_after": 0.01, "fit_before": 0.02,
            "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "scale": 1.0, "translation": [0, 0, 0]},
            "boundaries": "joint-planes", "components": [], "convention_changes": null,
            "joint_asymmetry": null, "joint_moves": [], "mirrored_fixed": false,
            "nearest_bone_vertices": 0, "repaired_joints": []},
    })
}

fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, doc.to_string()).unwrap();
    p
}

/// The embedded data object of a page.
fn page_data(html: &str) -> Value {
    let start = html
        .find(r#"id="symcorr-data" type="application/json">"#)
        .unwrap();
    let rest = &html[start..];
    let open = rest.find('>').unwrap() + 1;
    let close = rest.find("</script>").unwrap();
    serde_json::from_str(&rest[open..close]).unwrap()
}

fn assert_one_line_refusal(o: &std::process::Output, needle: &str, page: &Path) {
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(err.contains(needle), "{err}");
    assert!(!page.exists(), "no page written");
    let leftovers: Vec<_> = std::fs::read_dir(page.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("view"))
        .collect();
    assert!(
        leftovers.is_empty(),
        "no temporary files left: {leftovers:?}"
    );
}

#[test]
fn pair_page_embeds_both_meshes_and_the_matches_with_their_truth() {
    let dir = tempfile::tempdir().unwrap();
    let n = body_vertices();
    // Identity matches on every 10th vertex, and one deliberately wrong match.
    let mut pairs: Vec<(u32, u32, f64)> = (0..n as u32).step_by(10).map(|v| (v, v, 0.9)).collect();
    pairs.push((5, 2000, 0.1));
    let corr = write(dir.path(), "corr.json", &correspondence(n, &pairs));
    let out = dir.path().join("pair.html");
    let o = run(bin()
        .arg("view")
        .arg(&corr)
        .arg("--out")
        .arg(&out)
        .arg("--truth")
        .arg(fixtures()));
    assert!(o.status.success());
    let html = std::fs::read_to_string(&out).unwrap();
    assert!(html.len() < 8 << 20, "{} bytes", html.len());
    assert!(!html.contains("<script src"), "self-contained");
    let data = page_data(&html);
    assert_eq!(data["kind"], "pair");
    assert_eq!(data["pairs"]["count"], pairs.len());
    assert_eq!(data["meshes"]["template"]["vertices"], n);
    assert_eq!(data["segments"].as_array().unwrap().len(), 17);
    // Positions: n × 3 little-endian f32 as base64 (4 characters per 3 bytes).
    let b64 = data["meshes"]["target"]["positions"].as_str().unwrap();
    assert_eq!(b64.len(), (n * 12).div_ceil(3) * 4);
    // The truth: the identity matches have error 0, the wrong one a positive error.
    assert!(data["truth"]["unit"].as_str().unwrap().contains("√area"));
    let errors = decode_f32(data["truth"]["error"].as_str().unwrap());
    assert_eq!(errors.len(), pairs.len());
    assert!(errors[..pairs.len() - 1].iter().all(|&e| e == 0.0));
    assert!(
        errors[pairs.len() - 1] > 0.05,
        "{}",
        errors[pairs.len() - 1]
    );
}

fn decode_f32(b64: &str) -> Vec<f32> {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut bits = 0u32;
    let mut n = 0;
    let mut bytes = Vec::new();
    for c in b64.bytes().filter(|&c| c != b'=') {
        bits = (bits << 6) | A.iter().position(|&a| a == c).unwrap() as u32;
        n += 6;
        if n >= 8 {
            n -= 8;
            bytes.push((bits >> n) as u8);
        }
    }
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

#[test]
fn labels_page_draws_the_joints_and_their_bones() {
    let dir = tempfile::tempdir().unwrap();
    let n = body_vertices();
    let l = write(dir.path(), "labels.json", &labels(&mesh("s0_rest"), n));
    let out = dir.path().join("labels.html");
    let o = run(bin().arg("view").arg(&l).arg("--out").arg(&out));
    assert!(o.status.success());
    let data = page_data(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(data["kind"], "labels");
    assert_eq!(data["bones"], json!([["hip_center", "spine"]]));
}

#[test]
fn a_correspondence_naming_vertices_the_mesh_lacks_is_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let n = body_vertices();
    let out = dir.path().join("view.html");
    let bad_template = write(
        dir.path(),
        "a.json",
        &correspondence(n, &[(0, 0, 1.0), (n as u32 + 7, 3, 1.0)]),
    );
    let o = run(bin().arg("view").arg(&bad_template).arg("--out").arg(&out));
    assert_one_line_refusal(
        &o,
        &format!("pair 1: template vertex {} out of range", n + 7),
        &out,
    );
    let bad_target = write(
        dir.path(),
        "b.json",
        &correspondence(n, &[(0, n as u32, 1.0)]),
    );
    let o = run(bin().arg("view").arg(&bad_target).arg("--out").arg(&out));
    assert_one_line_refusal(&o, &format!("target vertex {n} out of range"), &out);
    // Meshes given on the command line that the file was not made for.
    let small = dir.path().join("tri.off");
    std::fs::write(&small, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    let fine = write(dir.path(), "c.json", &correspondence(n, &[(0, 0, 1.0)]));
    let o = run(bin()
        .arg("view")
        .arg(&fine)
        .arg(&small)
        .arg(mesh("s1_t-pose"))
        .arg("--out")
        .arg(&out));
    assert_one_line_refusal(&o, &format!("made for a template of {n} vertices"), &out);
}

#[test]
fn a_labels_file_for_another_mesh_is_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let n = body_vertices();
    let out = dir.path().join("view.html");
    let l = write(dir.path(), "labels.json", &labels(&mesh("s0_rest"), n + 1));
    let o = run(bin().arg("view").arg(&l).arg("--out").arg(&out));
    assert_one_line_refusal(&o, &format!("made for a mesh of {} vertices", n + 1), &out);
    // Not a result file at all, and a folder without track.json.
    let o = run(bin()
        .arg("view")
        .arg(mesh("s0_rest"))
        .arg("--out")
        .arg(&out));
    assert_one_line_refusal(&o, "not a symcorr.correspondence/1", &out);
    let o = run(bin().arg("view").arg(dir.path()).arg("--out").arg(&out));
    assert_one_line_refusal(&o, "without track.json", &out);
}

#[test]
fn match_view_writes_the_pair_page_beside_the_correspondence() {
    let dir = tempfile::tempdir().unwrap();
    let (corr, page) = (dir.path().join("corr.json"), dir.path().join("pair.html"));
    let joints = |n: &str| fixtures().join("joints").join(format!("{n}.json"));
    let o = run(bin()
        .arg("match")
        .arg(mesh("s0_rest"))
        .arg(mesh("s1_t-pose"))
        .arg("--template-joints")
        .arg(joints("s0_rest"))
        .arg("--target-joints")
        .arg(joints("s1_t-pose"))
        .arg("--out")
        .arg(&corr)
        .arg("--view")
        .arg(&page));
    assert!(o.status.success());
    let doc = read_json(&corr);
    let data = page_data(&std::fs::read_to_string(&page).unwrap());
    assert_eq!(data["kind"], "pair");
    assert_eq!(
        data["pairs"]["count"],
        doc["pairs"].as_array().unwrap().len()
    );
    assert_eq!(
        data["truth"],
        Value::Null,
        "no ground truth without a dataset"
    );
}
