//! Regression tests of attachment on the committed synth bodies (fixtures/synth: MakeHuman CC0 body posed by
//! its game-engine rig, exact Kinect joints, reference labels from the rig's skinning).

mod common;

use common::agreement;
use std::path::{Path, PathBuf};
use symcorr_attach::{attach, AttachOptions, Joint, Segment, Skeleton};
use symcorr_mesh::TriMesh;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth")
}

/// First frame of a `symcorr.joints/1` file (read here: symcorr-attach does not depend on
/// symcorr-kinect, which owns the importers).
fn read_joints(path: &Path) -> Skeleton {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let f = &v["frames"][0];
    let mut sk = Skeleton::from_arrays([[f64::NAN; 3]; 20]);
    for j in Joint::ALL {
        let p = &f["joints"][j.name()];
        if let Some(a) = p.as_array() {
            sk.positions[j.index()] =
                nalgebra::Point3::from(std::array::from_fn(|k| a[k].as_f64().unwrap()));
        } else {
            sk.confidence[j.index()] = 0.0;
        }
        if let Some(c) = f["confidence"][j.name()].as_f64() {
            sk.confidence[j.index()] = c;
        }
    }
    sk
}

fn read_labels(path: &Path) -> Vec<Segment> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| Segment::from_index(l.trim().parse().unwrap()).unwrap())
        .collect()
}

fn bodies(set: &str) -> Vec<(String, TriMesh, Skeleton, Vec<Segment>)> {
    let dir = root().join(set);
    let mut names: Vec<String> = std::fs::read_dir(dir.join("meshes"))
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            p.file_stem().unwrap().to_string_lossy().into_owned()
        })
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|n| {
            let mesh = symcorr_mesh::io::read(dir.join("meshes").join(format!("{n}.ply")))
                .unwrap()
                .mesh;
            let sk = read_joints(&dir.join("joints").join(format!("{n}.json")));
            let labels = read_labels(&dir.join("labels").join(format!("{n}.txt")));
            (n, mesh, sk, labels)
        })
        .collect()
}

/// Runs attachment on every body of `set`; returns the worst agreement and the worst mirror area.
fn run(set: &str) -> (f64, f64) {
    let (mut worst, mut worst_mirror) = (1.0f64, 0.0f64);
    let mut sum = 0.0;
    let all = bodies(set);
    assert!(all.len() >= 12, "{set}: {} bodies", all.len());
    for (name, mesh, sk, reference) in &all {
        let a = attach(mesh, sk, &AttachOptions::default()).unwrap();
        let mask = vec![true; mesh.num_vertices()];
        let (agree, mirror) = agreement(mesh, &a.labels, reference, &mask);
        eprintln!(
            "{set}/{name}: agreement {agree:.4} mirror {mirror:.5} swapped {} moves {}",
            a.diagnostics.mirror.swapped,
            a.diagnostics.joint_moves.len()
        );
        worst = worst.min(agree);
        worst_mirror = worst_mirror.max(mirror);
        sum += agree;
    }
    eprintln!("{set}: mean {:.4} worst {worst:.4}", sum / all.len() as f64);
    (worst, worst_mirror)
}

// The targets are ≥ 95 % (exact joints) and ≥ 90 % (noisy joints) area agreement and zero
// mirrored area. Measured 2026-11-23 (`cargo test --release -p symcorr-attach --test synth --
// --nocapture`) against these reference labels (the MakeHuman rig's skinning conventions: small
// front-only clavicles, a pelvis band above the Kinect spine joint, buttocks in the hips) bone heat
// + joint planes + midline guard (crate docs) reach, on the 12 committed bodies each: exact mean
// 0.861 / worst 0.831, no mirrored area; noisy mean 0.818 / worst 0.786, mirrored ≤ 0.0017
// (before joint planes: 0.818 / 0.796 and 0.801 / 0.768, mirrored ≤ 0.0007 / 0.0083). The
// assertions guard those measured levels; the 40-body acceptance tests live in
// tools/synth/tests/attach_labels.rs.

#[test]
fn exact_joints_regression_level_agreement_and_no_mirror() {
    let (worst, mirror) = run("bodies");
    assert!(worst >= 0.825, "worst agreement {worst}");
    assert_eq!(mirror, 0.0, "mirrored area");
}

#[test]
fn noisy_joints_regression_level_agreement_and_little_mirror() {
    let (worst, mirror) = run("bodies_noisy");
    assert!(worst >= 0.78, "worst agreement {worst}");
    assert!(mirror <= 0.002, "mirrored area {mirror}");
}
