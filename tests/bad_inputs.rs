//! The bad-input corpus (`tests/bad_inputs/`, written by `tests/bad_inputs/make.py`): runs the
//! `symcorr` binary over every case of `cases.json` and asserts what the case expects.
//!
//! Placeholders in a case's arguments: `{F}` fixtures/synth/bodies, `{K}` fixtures/kinect,
//! `{C}` a fresh copy of the case's folder, `{O}` an empty output folder, `{D}` a copy of
//! fixtures/synth/bodies with the case's `dataset` change applied to one body (its joints
//! replaced, its mesh scaled, or the triangles of its right half turned inside out) and the
//! single pair `s0_rest → body`.
//!
//! Every case: no panic. Exit 1: exactly one line on stderr naming the expected file and cause,
//! nothing in `{O}`, no new file in `{C}`, the `unchanged` inputs byte-identical. Exit 0 on a
//! `dataset` case: the bench summary shows 0 flips against the mirror map.

use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Copies `from` (symlinks as symlinks) into `to`; a case without files has no folder in git.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    let Ok(entries) = std::fs::read_dir(from) else {
        return;
    };
    for e in entries {
        let e = e.unwrap();
        let (src, dst) = (e.path(), to.join(e.file_name()));
        let meta = std::fs::symlink_metadata(&src).unwrap();
        if meta.file_type().is_symlink() {
            #[cfg(unix)]
            std::os::unix::fs::symlink(std::fs::read_link(&src).unwrap(), &dst).unwrap();
        } else if meta.is_dir() {
            copy_dir(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

fn listing(dir: &Path) -> BTreeSet<PathBuf> {
    let mut out = BTreeSet::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            out.insert(e.path());
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                out.extend(listing(&e.path()));
            }
        }
    }
    out
}

/// Applies a case's `dataset` change to a copy of the bodies in `d`.
fn make_dataset(d: &Path, case_dir: &Path, spec: &Value) {
    copy_dir(&root().join("fixtures/synth/bodies"), d);
    let body = spec["body"].as_str().unwrap();
    std::fs::write(d.join("pairs.txt"), format!("s0_rest {body}\n")).unwrap();
    if let Some(j) = spec["joints"].as_str() {
        std::fs::copy(
            case_dir.join(j),
            d.join("joints").join(format!("{body}.json")),
        )
        .unwrap();
    }
    let mesh_path = d.join("meshes").join(format!("{body}.ply"));
    let mut mesh = symcorr_mesh::io::read(&mesh_path).unwrap().mesh;
    if let Some(s) = spec["scale_mesh"].as_f64() {
        for p in mesh.positions.iter_mut() {
            *p = p.map(|x| x * s);
        }
    }
    if spec["flip_faces"].as_str() == Some("right_half") {
        let positions = mesh.positions.clone();
        for t in mesh.triangles.iter_mut() {
            if t.iter().map(|&v| positions[v as usize][0]).sum::<f64>() < 0.0 {
                t.swap(1, 2);
            }
        }
    }
    symcorr_mesh::io::write(&mesh_path, &mesh, None).unwrap();
}

#[test]
fn every_bad_input_is_refused_cleanly_or_handled_correctly() {
    let text = std::fs::read_to_string(root().join("tests/bad_inputs/cases.json")).unwrap();
    let cases: Vec<Value> = serde_json::from_str(&text).unwrap();
    assert!(cases.len() >= 30, "{} cases", cases.len());
    let mut failures = Vec::new();
    for c in &cases {
        let name = c["name"].as_str().unwrap();
        let src = root().join("tests/bad_inputs/cases").join(name);
        let tmp = tempfile::tempdir().unwrap();
        let (cd, od, dd) = (
            tmp.path().join("C"),
            tmp.path().join("O"),
            tmp.path().join("D"),
        );
        copy_dir(&src, &cd);
        std::fs::create_dir_all(&od).unwrap();
        if let Some(spec) = c.get("dataset") {
            make_dataset(&dd, &cd, spec);
        }
        let before = listing(&cd);
        let fill = |a: &str| {
            a.replace(
                "{F}",
                &root().join("fixtures/synth/bodies").display().to_string(),
            )
            .replace("{K}", &root().join("fixtures/kinect").display().to_string())
            .replace("{C}", &cd.display().to_string())
            .replace("{O}", &od.display().to_string())
            .replace("{D}", &dd.display().to_string())
        };
        let args: Vec<String> = c["args"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| fill(a.as_str().unwrap()))
            .collect();
        let out = Command::new(env!("CARGO_BIN_EXE_symcorr"))
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let code = out.status.code();
        let want = c["exit"].as_i64().unwrap() as i32;
        let mut fail = |why: String| failures.push(format!("{name}: {why}\n  stderr: {stderr}"));
        if stderr.contains("panicked") || code.is_none() {
            fail(format!("crashed ({code:?})"));
            continue;
        }
        if code != Some(want) {
            fail(format!("exit {code:?}, expected {want}"));
            continue;
        }
        if want == 1 {
            let lines: Vec<&str> = stderr.trim_end().lines().collect();
            if lines.len() != 1 {
                fail(format!("{} stderr lines, expected one", lines.len()));
            }
            for w in c["stderr"].as_array().unwrap() {
                let w = w.as_str().unwrap();
                if !stderr.contains(w) {
                    fail(format!("stderr lacks {w:?}"));
                }
            }
            let left = listing(&od);
            if !left.is_empty() {
                fail(format!("left output behind: {left:?}"));
            }
            let new: Vec<_> = listing(&cd).difference(&before).cloned().collect();
            if !new.is_empty() {
                fail(format!("left files beside the inputs: {new:?}"));
            }
        } else if c.get("dataset").is_some() {
            let summary: Value =
                serde_json::from_str(&std::fs::read_to_string(od.join("b.json")).unwrap()).unwrap();
            let flips = summary["flip_rate"].as_f64().unwrap_or(f64::NAN);
            if flips != 0.0 {
                fail(format!("flip rate {flips}, expected 0"));
            }
        }
        for u in c["unchanged"].as_array().unwrap() {
            let p = PathBuf::from(fill(u.as_str().unwrap()));
            let rel = p.strip_prefix(&cd).unwrap();
            let (now, was) = (std::fs::read(&p).ok(), std::fs::read(src.join(rel)).ok());
            if now != was {
                fail(format!("{} changed", p.display()));
            }
        }
        for a in c["absent"].as_array().unwrap() {
            let p = PathBuf::from(fill(a.as_str().unwrap()));
            if p.exists() {
                fail(format!("{} exists", p.display()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
