//! The committed synthetic Kinect recording (`fixtures/synth/recording/`): its layout, and the
//! corruptions its manifest lists really are in its joint log, and that the generator still
//! writes it bit for bit. Reads only the project's fixtures/.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use symcorr_kinect::joints::{read_joints, JointLog};
use symcorr_kinect::{read_depth_png16, Intrinsics};
use symcorr_skeleton::{Joint, Skeleton};
use symcorr_synth::recording::{
    fixture_recording, write_recording, RecordingSpec, RecordingSummary, DEPTH_TIME_JITTER_S,
    INFERRED_CONFIDENCE, INFERRED_MIN_TURN_DEG, JOINT_CLOCK_OFFSET_S, LEG_PAIRS, RECORDING_FORMAT,
    SWAP_FRAMES, SWAP_MIN_TURN_DEG,
};

/// Vertices of the bundled body model.
const BODY_VERTICES: u32 = 13_380;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/recording")
}

/// The bundled body model (the repository's assets).
fn bundled_model() -> symcorr_synth::Model {
    symcorr_synth::Model::new(
        symcorr_synth::Assets::load(&symcorr_synth::Assets::default_dir()).unwrap(),
    )
    .unwrap()
}

/// The recording `spec` of `model`'s default body, written into a fresh temporary folder.
fn record(
    model: &symcorr_synth::Model,
    spec: &RecordingSpec,
    camera: &symcorr_synth::render::Camera,
    realism: &symcorr_synth::render::Realism,
) -> symcorr_synth::Result<(tempfile::TempDir, RecordingSummary)> {
    let body = model.body(&symcorr_synth::Shape::default())?;
    let out = tempfile::tempdir().unwrap();
    let summary = write_recording(
        out.path(),
        &body,
        model.assets.walk.as_ref(),
        spec,
        camera,
        realism,
    )?;
    Ok((out, summary))
}

fn manifest() -> serde_json::Value {
    let text = std::fs::read_to_string(dir().join("recording.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn frames() -> usize {
    manifest()["frames"].as_u64().unwrap() as usize
}

fn depth_times() -> Vec<f64> {
    std::fs::read_to_string(dir().join("depth_times.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect()
}

fn log() -> JointLog {
    read_joints(dir().join("joints.json")).unwrap()
}

fn truth() -> JointLog {
    read_joints(dir().join("truth/joints.json")).unwrap()
}

fn usize_list(v: &serde_json::Value) -> Vec<usize> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect()
}

fn swaps() -> Vec<[usize; 2]> {
    manifest()["swaps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let r = usize_list(r);
            [r[0], r[1]]
        })
        .collect()
}

fn in_swap(f: usize) -> bool {
    swaps().iter().any(|&[a, b]| (a..=b).contains(&f))
}

/// Summed distance of the log's leg joints to the truth's legs, as named and exchanged.
fn leg_distances(log: &Skeleton, truth: &Skeleton) -> (f64, f64) {
    let mut same = 0.0;
    let mut crossed = 0.0;
    for (l, r) in LEG_PAIRS {
        same += (log.position(l) - truth.position(l)).norm()
            + (log.position(r) - truth.position(r)).norm();
        crossed += (log.position(l) - truth.position(r)).norm()
            + (log.position(r) - truth.position(l)).norm();
    }
    (same, crossed)
}

#[test]
fn layout_is_exactly_the_recording_format() {
    let m = manifest();
    assert_eq!(m["format"], RECORDING_FORMAT);
    let n = frames();
    assert!((30..=60).contains(&n), "{n} frames");
    let names = |d: &Path| -> BTreeSet<String> {
        std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect()
    };
    let top: BTreeSet<String> = [
        "intrinsics.json",
        "depth",
        "depth_times.txt",
        "joints.json",
        "joints_k4abt.json",
        "truth",
        "recording.json",
        "camera.json",
    ]
    .map(String::from)
    .into();
    assert_eq!(names(&dir()), top);
    let pngs: BTreeSet<String> = (0..n).map(|f| format!("{f:06}.png")).collect();
    assert_eq!(names(&dir().join("depth")), pngs);
    let mut truth_files = pngs.clone();
    truth_files.insert("joints.json".into());
    assert_eq!(names(&dir().join("truth")), truth_files);

    let k = Intrinsics::read(dir().join("intrinsics.json")).unwrap();
    assert_eq!(
        (k.width as u64, k.height as u64),
        (m["width"].as_u64().unwrap(), m["height"].as_u64().unwrap())
    );
    for f in 0..n {
        let d = read_depth_png16(dir().join(format!("depth/{f:06}.png"))).unwrap();
        assert_eq!((d.width, d.height), (k.width, k.height), "depth frame {f}");
        assert!(d.data_mm.iter().any(|&z| z > 0), "depth frame {f} is empty");
    }

    let times = depth_times();
    assert_eq!(times.len(), n);
    assert!(times.windows(2).all(|w| w[0] < w[1]));
    let fps = m["fps"].as_f64().unwrap();
    let mut jittered = 0;
    for (f, t) in times.iter().enumerate() {
        let dt = t - f as f64 / fps;
        assert!(dt.abs() <= DEPTH_TIME_JITTER_S + 1e-9, "frame {f}: {dt}");
        jittered += usize::from(dt.abs() > 1e-4);
    }
    assert!(jittered > n / 2, "depth times are not jittered");

    let truth = truth();
    assert_eq!(truth.frames.len(), n);
    for (fr, t) in truth.frames.iter().zip(&times) {
        assert_eq!(fr.time_s, *t);
    }
}

#[test]
fn joint_log_runs_at_exactly_the_frame_rate_with_a_40_ms_offset() {
    let m = manifest();
    assert_eq!(m["joint_offset_s"].as_f64().unwrap(), 0.04);
    assert_eq!(JOINT_CLOCK_OFFSET_S, 0.04);
    let fps = m["fps"].as_f64().unwrap();
    let log = log();
    assert_eq!(log.frames.len(), frames());
    let times = depth_times();
    for (k, fr) in log.frames.iter().enumerate() {
        assert!(
            (fr.time_s - (k as f64 / fps + 0.04)).abs() < 1e-9,
            "frame {k}"
        );
        // The depth frame showing the same moment is 40 ms earlier on the log's clock.
        assert!((fr.time_s - 0.04 - times[k]).abs() <= DEPTH_TIME_JITTER_S + 1e-9);
    }
}

#[test]
fn the_listed_corruptions_are_in_the_joint_log() {
    let m = manifest();
    let n = frames();
    let log = log();
    let truth = truth();
    let turn: Vec<f64> = m["turn_deg"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert_eq!(turn.len(), n);
    assert!(
        turn.iter().cloned().fold(0.0, f64::max) > 85.0,
        "no profile"
    );
    assert!(turn[0] < 5.0);

    // Lost body: two consecutive frames without any usable joint, and only those.
    let lost = usize_list(&m["lost_body_frames"]);
    assert_eq!(lost.len(), 2);
    assert_eq!(lost[1], lost[0] + 1);
    for (f, fr) in log.frames.iter().enumerate() {
        let none = fr.skeleton.confidence.iter().all(|&c| c == 0.0);
        assert_eq!(none, lost.contains(&f), "frame {f}");
    }

    // Leg swaps: 3–6 frames, sideways, legs exchanged relative to the truth; elsewhere not.
    let swaps = swaps();
    assert!(!swaps.is_empty());
    for &[a, b] in &swaps {
        assert!((SWAP_FRAMES.0..=SWAP_FRAMES.1).contains(&(b - a + 1)));
        assert!((a..=b).all(|f| turn[f] > SWAP_MIN_TURN_DEG - 1.0));
    }
    for f in (0..n).filter(|f| !lost.contains(f)) {
        let (same, crossed) = leg_distances(&log.frames[f].skeleton, &truth.frames[f].skeleton);
        if in_swap(f) {
            assert!(crossed < same, "frame {f}: legs not swapped");
        } else {
            assert!(same < crossed, "frame {f}: legs swapped");
        }
    }

    // Inferred far-side joints in profile, confidence 0.5; full confidence elsewhere.
    let inferred = usize_list(&m["inferred_frames"]);
    assert!(!inferred.is_empty());
    for (f, fr) in log.frames.iter().enumerate() {
        if lost.contains(&f) {
            continue;
        }
        let half = fr
            .skeleton
            .confidence
            .iter()
            .filter(|&&c| c == INFERRED_CONFIDENCE)
            .count();
        if inferred.contains(&f) {
            assert_eq!(half, 6, "frame {f}");
            assert!(turn[f] > INFERRED_MIN_TURN_DEG - 1.0);
        } else {
            assert!(
                fr.skeleton.confidence.iter().all(|&c| c == 1.0),
                "frame {f}"
            );
        }
    }

    // Jitter: tracked, unswapped joints lie within a few centimetres of the truth.
    let mut sum = 0.0;
    let mut count = 0;
    for f in (0..n).filter(|f| !lost.contains(f) && !in_swap(*f)) {
        for j in Joint::ALL {
            if log.frames[f].skeleton.confidence[j.index()] == 1.0 {
                let d = log.frames[f].skeleton.position(j) - truth.frames[f].skeleton.position(j);
                sum += d.norm_squared();
                count += 1;
            }
        }
    }
    let rms_cm = (sum / count as f64).sqrt() * 100.0;
    assert!((1.0..6.0).contains(&rms_cm), "joint jitter {rms_cm} cm rms");
}

#[test]
fn truth_images_name_body_vertices() {
    let k = Intrinsics::read(dir().join("intrinsics.json")).unwrap();
    for f in 0..frames() {
        let ids = read_depth_png16(dir().join(format!("truth/{f:06}.png"))).unwrap();
        assert_eq!((ids.width, ids.height), (k.width, k.height));
        assert!(ids.data_mm.iter().all(|&v| u32::from(v) <= BODY_VERTICES));
        let depth = read_depth_png16(dir().join(format!("depth/{f:06}.png"))).unwrap();
        let seen = ids.data_mm.iter().filter(|&&v| v > 0).count();
        assert!(seen > 500, "frame {f}: {seen} body pixels");
        // A pixel that names a vertex has a depth reading.
        assert!(ids
            .data_mm
            .iter()
            .zip(&depth.data_mm)
            .all(|(&v, &z)| v == 0 || z > 0));
    }
}

#[test]
fn committed_recording_regenerates_bit_for_bit() {
    let (spec, camera, realism) = fixture_recording().unwrap();
    let (out, summary) = record(&bundled_model(), &spec, &camera, &realism).unwrap();
    assert_eq!(summary.frames, frames());
    let mut files = 0;
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for e in std::fs::read_dir(out.path().join(&rel)).unwrap() {
            let e = e.unwrap();
            let r = rel.join(e.file_name());
            if e.file_type().unwrap().is_dir() {
                stack.push(r);
                continue;
            }
            let new = std::fs::read(e.path()).unwrap();
            let old = std::fs::read(dir().join(&r))
                .unwrap_or_else(|_| panic!("{} not committed", r.display()));
            assert!(
                new == old,
                "{} differs from the committed fixture",
                r.display()
            );
            files += 1;
        }
    }
    assert_eq!(files, 2 * frames() + 7);
}

/// `symcorr-synth oni` writes the recording as an `.oni` file whose depth frames are the
/// folder's, at the folder's times (read back from the file's records, no OpenNI2 needed).
#[test]
fn the_recording_converts_to_an_oni_file_with_its_times() {
    let out = tempfile::tempdir().unwrap();
    let oni = out.path().join("fixture.oni");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_symcorr-synth"))
        .arg("oni")
        .arg(dir())
        .arg("--out")
        .arg(&oni)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(&oni).unwrap();
    let stamps = symcorr_kinect::oni_index::depth_frame_times(&bytes).unwrap();
    let times: Vec<f64> = stamps.iter().map(|&t| t as f64 / 1e6).collect();
    assert_eq!(times, depth_times());
    // Uncompressed: each frame's 16-bit pixels follow its record's 40-byte header and fields.
    let first = read_depth_png16(dir().join("depth/000000.png")).unwrap();
    let pixels: Vec<u8> = first.data_mm.iter().flat_map(|v| v.to_le_bytes()).collect();
    let at = bytes
        .windows(pixels.len())
        .position(|w| w == pixels)
        .expect("frame 0's pixels are in the file");
    assert_eq!(&bytes[at - 40..at - 36], b"NIR\0");

    // A folder that is not a recording: exit 1, one line naming the file, nothing written.
    let bad = out.path().join("bad.oni");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_symcorr-synth"))
        .arg("oni")
        .arg(out.path())
        .arg("--out")
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("intrinsics.json"));
    assert!(!bad.exists());
}

/// `head_turn_deg`: the subject looks left and right — the depth images change where the head
/// is, the exact joints barely (a turn about the head's own axis), the manifest says so; a turn
/// beyond a neck's range is refused.
#[test]
fn a_head_turned_against_the_chest_shows_in_the_depth_not_in_the_joints() {
    let model = bundled_model();
    let (mut spec, mut camera, realism) = fixture_recording().unwrap();
    // 24 frames: the head's largest turn is at 0.75 s, frame 22 or 23.
    spec.frames = 24;
    camera.intrinsics = symcorr_synth::recording::kinect_v1_intrinsics(160, 120).unwrap();
    let write = |spec: &RecordingSpec| record(&model, spec, &camera, &realism).map(|r| r.0);
    let still = write(&spec).unwrap();
    spec.head_turn_deg = 40.0;
    let looking = write(&spec).unwrap();
    let (a, b) = (
        read_joints(still.path().join("truth/joints.json")).unwrap(),
        read_joints(looking.path().join("truth/joints.json")).unwrap(),
    );
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        for j in Joint::ALL {
            let d = (fa.skeleton.position(j) - fb.skeleton.position(j)).norm();
            let limit = if j == Joint::Head { 0.005 } else { 1e-9 };
            assert!(d <= limit, "{j:?}: {d}");
        }
    }
    let depth =
        |dir: &Path, f: usize| std::fs::read(dir.join(format!("depth/{f:06}.png"))).unwrap();
    assert!(depth(still.path(), 22) != depth(looking.path(), 22));
    let text = std::fs::read_to_string(looking.path().join("recording.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(m["head_turn_deg"], 40.0);
    // The Azure Kinect log's face reports the turn (jittered): read back against the truth,
    // 40° · sin(2πt / 3 s) at the log's true time, within the jitter on average; the still
    // subject's log reports about none.
    let reported = |dir: &Path| -> Vec<(f64, f64)> {
        read_joints(dir.join("joints_k4abt.json"))
            .unwrap()
            .frames
            .iter()
            .filter_map(|f| {
                let t = f.time_s - 0.04;
                let truth = symcorr_synth::recording::head_turn_deg(t, 40.0);
                Some((f.skeleton.head_turn?.to_degrees(), truth))
            })
            .collect()
    };
    let (moving, resting) = (reported(looking.path()), reported(still.path()));
    assert_eq!(moving.len(), 22, "the frames with a body report a turn");
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let error: Vec<f64> = moving.iter().map(|(r, t)| (r - t).abs()).collect();
    assert!(mean(&error) < 12.0, "mean error {}°", mean(&error));
    // It follows the look: large where the truth is large.
    let turned: Vec<f64> = moving
        .iter()
        .filter(|(_, t)| t.abs() > 30.0)
        .map(|(r, t)| r * t.signum())
        .collect();
    assert!(!turned.is_empty() && mean(&turned) > 25.0, "{turned:?}");
    let still_turn: Vec<f64> = resting.iter().map(|(r, _)| *r).collect();
    assert!(mean(&still_turn).abs() < 6.0, "{still_turn:?}");
    spec.head_turn_deg = 100.0;
    let e = write(&spec).unwrap_err();
    assert!(e.to_string().contains("±80°"), "{e}");
}

/// `joints_k4abt.json` is `joints.json` as the Azure Kinect's tracker writes it: the same frames
/// at the same times, the same joints where the log has a body, none where it lost it.
#[test]
fn the_azure_kinect_log_holds_the_same_joints() {
    let v1 = log();
    let azure = read_joints(dir().join("joints_k4abt.json")).unwrap();
    assert_eq!(azure.frames.len(), v1.frames.len());
    for (a, b) in azure.frames.iter().zip(&v1.frames) {
        assert!((a.time_s - b.time_s).abs() < 1e-6);
        assert_eq!(a.skeleton.tracks_any(), b.skeleton.tracks_any());
        if b.skeleton.tracks_any() {
            for j in Joint::ALL {
                let d = (a.skeleton.position(j) - b.skeleton.position(j)).norm();
                assert!(d < 1e-9, "{j:?}: {d}");
            }
            assert!(a.skeleton.head_turn.is_some());
        }
    }
}

/// `recording --intrinsics K.json` renders through another camera's intrinsics (here a Kinect
/// v2's depth camera: 512×424, its own focal length and principal point, radial distortion)
/// and writes them as the recording's; it refuses them with the Kinect-v1 options that they
/// replace, and names the option when the file is not valid intrinsics. Nothing is written on
/// refusal.
#[test]
fn a_recording_renders_through_the_intrinsics_it_is_given() {
    let out = tempfile::tempdir().unwrap();
    let k_path = out.path().join("kinect_v2.json");
    std::fs::write(
        &k_path,
        r#"{"format": "symcorr.intrinsics/1", "width": 512, "height": 424, "fx": 365.5,
            "fy": 365.5, "cx": 254.9, "cy": 205.4, "distortion": [0.09, -0.27, 0, 0, 0.09]}"#,
    )
    .unwrap();
    let synth = |args: &[&str], rec: &Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_symcorr-synth"))
            .args(["recording", "--frames", "2", "--realism", "ideal"])
            .args(args)
            .arg("--out")
            .arg(rec)
            .output()
            .unwrap()
    };
    let rec = out.path().join("rec");
    let o = synth(&["--intrinsics", k_path.to_str().unwrap()], &rec);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let given = Intrinsics::read(&k_path).unwrap();
    assert_eq!(
        Intrinsics::read(rec.join("intrinsics.json")).unwrap(),
        given
    );
    let depth = read_depth_png16(rec.join("depth/000000.png")).unwrap();
    assert_eq!((depth.width, depth.height), (512, 424));
    // The body stands 2.6 m away: every reading lies in front of the wall behind it, and the
    // camera's focal length sets the body's size in the image (1.7 m at 2.6 m: about 240 rows).
    let rows: Vec<usize> = (0..424)
        .filter(|&v| (0..512).any(|u| (1..3000).contains(&depth.data_mm[v * 512 + u])))
        .collect();
    let height = rows.last().unwrap() - rows.first().unwrap();
    assert!((200..280).contains(&height), "the body spans {height} rows");
    // Refused: with --width, and a file that is not intrinsics; nothing is written.
    for (args, code, says) in [
        (
            vec!["--intrinsics", k_path.to_str().unwrap(), "--width", "320"],
            2,
            "--width",
        ),
        (vec!["--intrinsics", "Cargo.toml"], 1, "--intrinsics"),
    ] {
        let bad = out.path().join("bad");
        let o = synth(&args, &bad);
        assert_eq!(o.status.code(), Some(code), "{args:?}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(says),
            "{args:?}"
        );
        assert!(!bad.exists(), "{args:?}");
    }
}
