//! End-to-end tests of `symcorr track-merge` through the binary, on the first frames of
//! fixtures/synth/recording (slices 0..2 and 2..4), and of the cluster script's slicing
//! (tools/cluster/track_array.sbatch).

mod support;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use support::{bin, read_json, run};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn recording() -> PathBuf {
    root().join("fixtures/synth/recording")
}

/// `symcorr track` of the fixture recording's `frames` into `out`, with scans.
fn track(out: &Path, frames: &str, resume: bool) -> Output {
    let rec = recording();
    let mut c = bin();
    c.arg("track")
        .arg(&rec)
        .arg("--joints")
        .arg(rec.join("joints.json"))
        .args(["--scans", "--frames", frames, "--out"])
        .arg(out);
    if resume {
        c.arg("--resume");
    }
    run(&mut c)
}

fn merge(slices: &[&Path], out: &Path, extra: &[&str]) -> Output {
    run(bin()
        .arg("track-merge")
        .args(slices)
        .arg("--out")
        .arg(out)
        .args(extra))
}

/// The journal's lines, parsed.
fn journal(dir: &Path) -> Vec<Value> {
    std::fs::read_to_string(dir.join("journal.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// A frame line without what differs between two runs of the same frame: its timings.
fn untimed(line: &Value) -> Value {
    let mut l = line.clone();
    if let Some(m) = l.as_object_mut() {
        m.remove("seconds");
        m.remove("timings_s");
    }
    l
}

const ARRAYS: [&str; 3] = ["correspondence.npy", "confidence.npy", "posed.npy"];

/// The data rows of a `.npy` file, `row_bytes` each.
fn npy_rows(path: &Path, row_bytes: usize) -> Vec<Vec<u8>> {
    let bytes = std::fs::read(path).unwrap();
    let header = u16::from_le_bytes([bytes[8], bytes[9]]) as usize + 10;
    bytes[header..]
        .chunks(row_bytes)
        .map(<[u8]>::to_vec)
        .collect()
}

/// Every file under `dir` (relative path → bytes).
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                files.push((p.strip_prefix(dir).unwrap().to_path_buf(), bytes));
            }
        }
    }
    files.sort();
    files
}

/// A refused merge: exit status 1, one line on stderr containing `cause`, and `out` left as it
/// was (absent, or the empty folder it was).
fn assert_refused(o: &Output, cause: &str, out: &Path, out_existed: bool) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains(cause), "expected {cause:?}: {stderr}");
    if out_existed {
        assert_eq!(std::fs::read_dir(out).unwrap().count(), 0, "{stderr}");
    } else {
        assert!(!out.exists(), "{stderr}");
    }
}

/// A copy of the slice `from` at `to` whose journal `edit` changes (header first).
fn edited_copy(from: &Path, to: &Path, edit: impl FnOnce(&mut Vec<Value>)) {
    for (rel, bytes) in snapshot(from) {
        let p = to.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    let mut lines = journal(from);
    edit(&mut lines);
    let text: String = lines.iter().map(|l| format!("{l}\n")).collect();
    std::fs::write(to.join("journal.jsonl"), text).unwrap();
}

/// Two slices merged are the run over their frames: the same arrays, animated template and
/// scans byte for byte, the same journal header and frame lines but for timings, as one run
/// over 0..4 interrupted and resumed at frame 2 (each slice, like a resumed run, starts
/// without a previous frame). The merged folder is complete (resuming it tracks nothing) and
/// merges again; the slices are not touched.
#[test]
fn merged_slices_are_the_run_over_their_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (p0, p1, reference) = (d.join("p0"), d.join("p1"), d.join("ref"));
    assert!(track(&p0, "0..2", false).status.success());
    assert!(track(&p1, "2..4", false).status.success());
    assert!(track(&reference, "0..4", false).status.success());
    // The reference interrupted after frame 1: its journal keeps two frame lines.
    let lines = journal(&reference);
    let text: String = lines[..3].iter().map(|l| format!("{l}\n")).collect();
    std::fs::write(reference.join("journal.jsonl"), text).unwrap();
    assert!(track(&reference, "0..4", true).status.success());

    let inputs = (snapshot(&p0), snapshot(&p1));
    let merged = d.join("merged");
    let o = merge(&[&p1, &p0], &merged, &[]);
    assert!(o.status.success());
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("merged 2 slices") && stdout.contains("no gaps"),
        "{stdout}"
    );
    assert_eq!(
        (snapshot(&p0), snapshot(&p1)),
        inputs,
        "the slices are only read"
    );

    let n = journal(&merged)[0]["template_vertices"].as_u64().unwrap() as usize;
    for name in ARRAYS {
        let bytes = std::fs::read(merged.join(name)).unwrap();
        assert_eq!(
            bytes,
            std::fs::read(reference.join(name)).unwrap(),
            "{name}"
        );
        let row = if name == "posed.npy" { 12 * n } else { 4 * n };
        let mut concatenated = npy_rows(&p0.join(name), row);
        concatenated.extend(npy_rows(&p1.join(name), row));
        assert_eq!(npy_rows(&merged.join(name), row), concatenated, "{name}");
    }
    for name in ["template_track.glb", "scans/000000.ply", "scans/000003.ply"] {
        assert_eq!(
            std::fs::read(merged.join(name)).unwrap(),
            std::fs::read(reference.join(name)).unwrap(),
            "{name}"
        );
    }
    let (got, want) = (journal(&merged), journal(&reference));
    assert_eq!(got[0], want[0], "the header of a run over 0..4");
    assert_eq!(got.len(), 5);
    assert_eq!(
        got.iter().map(untimed).collect::<Vec<_>>(),
        want.iter().map(untimed).collect::<Vec<_>>()
    );
    let (doc, ref_doc) = (
        read_json(&merged.join("track.json")),
        read_json(&reference.join("track.json")),
    );
    assert_eq!(doc["run"], ref_doc["run"]);
    let frames = |d: &Value| -> Vec<Value> {
        d["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(untimed)
            .collect()
    };
    assert_eq!(frames(&doc), frames(&ref_doc));
    for key in [
        "frames",
        "frames_in_run",
        "ok",
        "skipped",
        "mean_coverage",
        "mean_confidence",
        "template_track",
    ] {
        assert_eq!(doc["summary"][key], ref_doc["summary"][key], "{key}");
    }
    assert_eq!(doc["summary"]["gaps"], serde_json::json!([]));
    assert_eq!(doc["summary"]["merged_from"][0]["frames"], "0..2");
    assert!(merged.join("track.svg").exists());

    // Complete: resuming the merged folder as the run over 0..4 tracks no frame.
    let before = snapshot(&merged);
    let o = track(&merged, "0..4", true);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("tracked 4 frames"));
    let after = snapshot(&merged);
    for name in ARRAYS.iter().chain(&["journal.jsonl"]) {
        let file = |s: &[(PathBuf, Vec<u8>)]| s.iter().find(|(p, _)| p == Path::new(name)).cloned();
        assert_eq!(file(&after), file(&before), "{name}");
    }

    // A merged folder is a slice like any other: merged alone, or with another slice.
    let (alone, p1_alone, again) = (d.join("alone"), d.join("p1_alone"), d.join("again"));
    assert!(merge(&[&merged], &alone, &[]).status.success());
    assert!(merge(&[&p1], &p1_alone, &[]).status.success());
    assert!(merge(&[&p0, &p1_alone], &again, &[]).status.success());
    for name in ARRAYS
        .iter()
        .chain(&["journal.jsonl", "template_track.glb"])
    {
        let bytes = std::fs::read(merged.join(name)).unwrap();
        assert_eq!(std::fs::read(alone.join(name)).unwrap(), bytes, "{name}");
        assert_eq!(std::fs::read(again.join(name)).unwrap(), bytes, "{name}");
    }

    // Refused, naming the cause, with nothing written: overlapping slices, a slice of another
    // recording, an unfinished slice, an --out that is not empty.
    let out = d.join("refused");
    assert_refused(
        &merge(&[&p0, &reference], &out, &[]),
        "overlap",
        &out,
        false,
    );
    let other = d.join("other");
    edited_copy(&p1, &other, |l| {
        l[0]["recording_digest"] = "0123456789abcdef".into()
    });
    assert_refused(
        &merge(&[&p0, &other], &out, &[]),
        "not slices of one run: their journals' recording_digest differ",
        &out,
        false,
    );
    // The same recording under another path (a job run from another working folder): the
    // content's digest decides, not the spelling.
    let moved = d.join("moved");
    edited_copy(&p1, &moved, |l| l[0]["recording"] = "elsewhere/rec".into());
    let o = merge(&[&p0, &moved], &d.join("merged-moved"), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let offset = d.join("offset");
    edited_copy(&p1, &offset, |l| l[0]["joint_offset_s"] = 0.04.into());
    assert_refused(
        &merge(&[&p0, &offset], &out, &[]),
        "joint_offset_s",
        &out,
        false,
    );
    let unfinished = d.join("unfinished");
    edited_copy(&p1, &unfinished, |l| {
        l.pop();
    });
    std::fs::create_dir(&out).unwrap();
    assert_refused(
        &merge(&[&p0, &unfinished], &out, &[]),
        "unfinished: 1 of its 2 frames are missing",
        &out,
        true,
    );
    std::fs::remove_dir(&out).unwrap();
    let before = snapshot(&p0);
    let o = merge(&[&p1], &p0, &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("must be a new or empty folder"));
    assert_eq!(
        snapshot(&p0),
        before,
        "an --out that is not empty is not touched"
    );

    // A gap between slices is refused unless --allow-gaps, then listed in the summary.
    let p3 = d.join("p3");
    assert!(track(&p3, "3..4", false).status.success());
    assert_refused(
        &merge(&[&p0, &p3], &out, &[]),
        "frames 2..3 are in no slice",
        &out,
        false,
    );
    let o = merge(&[&p0, &p3], &out, &["--allow-gaps"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("gaps: frames 2..3"));
    let doc = read_json(&out.join("track.json"));
    assert_eq!(doc["summary"]["gaps"], serde_json::json!(["2..3"]));
    assert_eq!(doc["run"]["frames"], serde_json::json!([0, 1, 3]));
}

/// tools/cluster/track_array.sbatch run by bash for every task of arrays of several sizes, on
/// recordings of several lengths (its `symcorr` replaced by `echo`): the `--frames` of its
/// tasks cover every frame exactly once, and the --array it declares is the one documented.
#[test]
fn the_cluster_script_slices_every_frame_exactly_once() {
    let script = root().join("tools/cluster/track_array.sbatch");
    let text = std::fs::read_to_string(&script).unwrap();
    assert!(text.contains("#SBATCH --array=0-9"), "{text}");
    if Command::new("bash").arg("-c").arg("true").output().is_err() {
        eprintln!("no bash: the script's arithmetic is not run");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for frames in [1usize, 7, 10, 61, 1000] {
        let rec = dir.path().join(format!("rec{frames}"));
        std::fs::create_dir_all(rec.join("depth")).unwrap();
        for i in 0..frames {
            std::fs::write(rec.join(format!("depth/{i:06}.png")), b"").unwrap();
        }
        for (tasks, min) in [(10usize, 0usize), (3, 1)] {
            let mut covered = vec![0u32; frames];
            for id in min..min + tasks {
                let o = Command::new("bash")
                    .arg(&script)
                    .arg(&rec)
                    .current_dir(dir.path())
                    .env("SYMCORR", "echo")
                    .env("SLURM_ARRAY_TASK_COUNT", tasks.to_string())
                    .env("SLURM_ARRAY_TASK_ID", id.to_string())
                    .env("SLURM_ARRAY_TASK_MIN", min.to_string())
                    .output()
                    .unwrap();
                let stdout = String::from_utf8_lossy(&o.stdout);
                assert!(
                    o.status.success(),
                    "{stdout}{}",
                    String::from_utf8_lossy(&o.stderr)
                );
                let words: Vec<&str> = stdout.split_whitespace().collect();
                let Some(k) = words.iter().position(|w| *w == "--frames") else {
                    assert!(stdout.contains("no frames"), "{stdout}");
                    continue;
                };
                assert!(stdout.contains(&format!("--out parts/{id} ")), "{stdout}");
                let (a, b) = words[k + 1].split_once("..").unwrap();
                let (a, b): (usize, usize) = (a.parse().unwrap(), b.parse().unwrap());
                assert!(a < b && b <= frames, "{stdout}");
                for c in &mut covered[a..b] {
                    *c += 1;
                }
            }
            assert!(
                covered.iter().all(|&c| c == 1),
                "{frames} frames over {tasks} tasks: {covered:?}"
            );
        }
    }
}
