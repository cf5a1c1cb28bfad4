//! The on-disk eigenpair cache through the pipeline ([`PrepareOptions::cache`]): a hit gives
//! the same bits without running the eigensolver, a changed mesh or a broken file is
//! recomputed (the broken one with a warning), never used.

use std::path::Path;
use std::sync::{Arc, Mutex};
use symcorr::cache::{CacheLocation, CacheOutcome, CachePolicy};
use symcorr::{Method, PrepareOptions, PreparedMesh};
use symcorr_attach::testbody::{capsule_body, t_pose};
use symcorr_mesh::TriMesh;

/// What the policy's observer saw: (hit, warning) per preparation.
type Log = Arc<Mutex<Vec<(bool, Option<String>)>>>;

fn options(location: CacheLocation, log: &Log) -> PrepareOptions {
    let log = log.clone();
    PrepareOptions {
        cache: Some(
            CachePolicy::new(location).with_notify(move |o: &CacheOutcome| {
                log.lock().unwrap().push((o.is_hit(), o.warning()))
            }),
        ),
        ..PrepareOptions::default()
    }
}

fn stage_names(p: &PreparedMesh) -> Vec<&str> {
    p.timings.iter().map(|(n, _)| n.as_str()).collect()
}

/// Same eigenvectors, mass and si-HKS descriptors, bit for bit.
fn same_spectral_bits(a: &PreparedMesh, b: &PreparedMesh) -> bool {
    let (ra, rb) = (a.refine.as_ref().unwrap(), b.refine.as_ref().unwrap());
    let (va, vb) = (&ra.basis, &rb.basis);
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    va.nrows() == vb.nrows()
        && va.ncols() == vb.ncols()
        && (0..va.ncols())
            .all(|j| (0..va.nrows()).all(|i| va[(i, j)].to_bits() == vb[(i, j)].to_bits()))
        && bits(&ra.mass) == bits(&rb.mass)
        && ra.descriptors.len() == rb.descriptors.len()
        && (0..ra.descriptors.len())
            .all(|v| bits(ra.descriptors.row(v)) == bits(rb.descriptors.row(v)))
}

fn body() -> (TriMesh, symcorr_attach::Skeleton) {
    let sk = t_pose(1.0);
    let (mesh, _) = capsule_body(&sk, 0.05);
    (mesh, sk)
}

fn flip_byte(path: &Path, from_end: usize) {
    let mut b = std::fs::read(path).unwrap();
    let at = b.len() - from_end;
    b[at] ^= 0x40;
    std::fs::write(path, b).unwrap();
}

#[test]
fn cached_preparation_is_bit_identical_and_skips_the_eigensolver() {
    let (mesh, sk) = body();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("body.off.symcorr-eigs");
    let log: Log = Arc::default();
    let opts = options(CacheLocation::File(file.clone()), &log);

    let cold = PreparedMesh::new(mesh.clone(), &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&cold).contains(&"eigenpairs"));
    assert!(!stage_names(&cold).contains(&"eigenpairs_cached"));
    assert!(file.is_file());
    // Computing through the cache gives what the uncached pipeline gives.
    let plain = PreparedMesh::new(
        mesh.clone(),
        &sk,
        &[Method::Refined],
        &PrepareOptions {
            cache: None,
            ..opts.clone()
        },
    )
    .unwrap();
    assert!(same_spectral_bits(&cold, &plain));

    let warm = PreparedMesh::new(mesh.clone(), &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&warm).contains(&"eigenpairs_cached"));
    assert!(!stage_names(&warm).contains(&"eigenpairs"));
    assert!(same_spectral_bits(&cold, &warm));
    assert_eq!(*log.lock().unwrap(), [(false, None), (true, None)]);
}

#[test]
fn a_changed_mesh_invalidates_the_file() {
    let (mesh, sk) = body();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("body.off.symcorr-eigs");
    let log: Log = Arc::default();
    let opts = options(CacheLocation::File(file.clone()), &log);
    let first = PreparedMesh::new(mesh.clone(), &sk, &[Method::Refined], &opts).unwrap();
    // One vertex moved by 1 µm: another mesh, so the file is stale (no warning: this is the
    // normal life of a cache next to a mesh that was edited).
    let mut moved = mesh.clone();
    moved.positions[10][0] += 1e-6;
    let second = PreparedMesh::new(moved.clone(), &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&second).contains(&"eigenpairs"));
    assert!(!same_spectral_bits(&first, &second));
    // The file now holds the moved mesh's pairs: the moved mesh hits, the original does not.
    let third = PreparedMesh::new(moved, &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&third).contains(&"eigenpairs_cached"));
    assert!(same_spectral_bits(&second, &third));
    let fourth = PreparedMesh::new(mesh, &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&fourth).contains(&"eigenpairs"));
    assert!(same_spectral_bits(&first, &fourth));
    assert_eq!(
        *log.lock().unwrap(),
        [(false, None), (false, None), (true, None), (false, None)]
    );
}

#[test]
fn a_corrupted_or_truncated_file_is_recomputed_with_a_warning_never_used() {
    let (mesh, sk) = body();
    let dir = tempfile::tempdir().unwrap();
    let log: Log = Arc::default();
    // A directory location: the file is named by the mesh's hash.
    let opts = options(CacheLocation::Dir(dir.path().join("eigs")), &log);
    let cold = PreparedMesh::new(mesh.clone(), &sk, &[Method::Refined], &opts).unwrap();
    let files: Vec<_> = std::fs::read_dir(dir.path().join("eigs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1);
    let file = &files[0];
    assert_eq!(file.extension().unwrap(), "symcorr-eigs");

    // One flipped bit in the middle of the eigenvectors.
    flip_byte(file, std::fs::metadata(file).unwrap().len() as usize / 2);
    let again = PreparedMesh::new(mesh.clone(), &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&again).contains(&"eigenpairs"));
    assert!(same_spectral_bits(&cold, &again));
    // Truncated (an interrupted copy).
    let b = std::fs::read(file).unwrap();
    std::fs::write(file, &b[..b.len() - 8]).unwrap();
    let again = PreparedMesh::new(mesh.clone(), &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&again).contains(&"eigenpairs"));
    assert!(same_spectral_bits(&cold, &again));
    // The rewritten file is good again.
    let warm = PreparedMesh::new(mesh, &sk, &[Method::Refined], &opts).unwrap();
    assert!(stage_names(&warm).contains(&"eigenpairs_cached"));
    assert!(same_spectral_bits(&cold, &warm));

    let log = log.lock().unwrap();
    let hits: Vec<bool> = log.iter().map(|(h, _)| *h).collect();
    assert_eq!(hits, [false, false, false, true]);
    assert!(log[0].1.is_none() && log[3].1.is_none());
    let w1 = log[1]
        .1
        .as_deref()
        .expect("a warning for the corrupted file");
    let w2 = log[2]
        .1
        .as_deref()
        .expect("a warning for the truncated file");
    assert!(w1.contains("checksum") && w1.contains("recomputed"), "{w1}");
    assert!(w2.contains("bytes"), "{w2}");
}

/// The command line: `match --cache` writes MESH.symcorr-eigs next to each mesh and reads it
/// back (timing `eigenpairs_cached`, same pairs); a corrupted file is a warning on stderr and
/// a recomputation, not a failure; `bench --cache-dir` reports its hits; --cache and
/// --cache-dir together are a usage error.
#[test]
fn command_line_cache_flags() {
    use std::process::Command;
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/bodies");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for name in ["s0_rest", "s0_arms-down"] {
        std::fs::copy(
            fixtures.join("meshes").join(format!("{name}.ply")),
            d.join(format!("{name}.ply")),
        )
        .unwrap();
    }
    let joints = |n: &str| fixtures.join("joints").join(format!("{n}.json"));
    let run_match = |out: &str, extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_symcorr"))
            .arg("match")
            .arg(d.join("s0_rest.ply"))
            .arg(d.join("s0_arms-down.ply"))
            .arg("--template-joints")
            .arg(joints("s0_rest"))
            .arg("--target-joints")
            .arg(joints("s0_arms-down"))
            .arg("--out")
            .arg(d.join(out))
            .args(["--samples", "100", "--method", "refined"])
            .args(extra)
            .output()
            .unwrap();
        let doc: Option<serde_json::Value> = o
            .status
            .success()
            .then(|| serde_json::from_slice(&std::fs::read(d.join(out)).unwrap()).unwrap());
        (o, doc)
    };
    let (o, cold) = run_match("cold.json", &["--cache"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cold = cold.unwrap();
    let eigs = d.join("s0_rest.ply.symcorr-eigs");
    assert!(eigs.is_file() && d.join("s0_arms-down.ply.symcorr-eigs").is_file());
    assert!(cold["timings_s"]["eigenpairs"].as_f64().is_some());
    assert!(cold["timings_s"].get("eigenpairs_cached").is_none());

    let (o, warm) = run_match("warm.json", &["--cache"]);
    let warm = warm.unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("eigenpair cache: 2 of 2 meshes read from it"),
        "{stdout}"
    );
    assert!(warm["timings_s"]["eigenpairs_cached"].as_f64().is_some());
    assert!(warm["timings_s"].get("eigenpairs").is_none());
    assert_eq!(warm["pairs"], cold["pairs"]);

    flip_byte(&eigs, 1000);
    let (o, again) = run_match("again.json", &["--cache"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("warning") && stderr.contains("s0_rest.ply.symcorr-eigs"),
        "{stderr}"
    );
    assert_eq!(again.unwrap()["pairs"], cold["pairs"]);

    let (o, _) = run_match("x.json", &["--cache", "--cache-dir", "x"]);
    assert_eq!(o.status.code(), Some(2));

    // bench with a directory cache, one pair, twice.
    let pairs = d.join("pairs.txt");
    std::fs::write(&pairs, "s0_rest s0_arms-down\n").unwrap();
    let cache = d.join("eigs");
    let bench = || {
        let o = Command::new(env!("CARGO_BIN_EXE_symcorr"))
            .arg("bench")
            .arg(&fixtures)
            .arg("--pairs")
            .arg(&pairs)
            .args(["--samples", "100", "--method", "refined", "--cache-dir"])
            .arg(&cache)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    assert!(bench().contains("eigenpair cache: 0 of 2 meshes read from it"));
    assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 2);
    let second = bench();
    assert!(
        second.contains("eigenpair cache: 2 of 2 meshes read from it"),
        "{second}"
    );
}
