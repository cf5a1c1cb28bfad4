//! `symcorr track` on OpenNI2 `.oni` files (feature `openni2`):
//!
//! * the committed fixture recording (`fixtures/synth/recording/`) written as an `.oni` by
//!   symcorr-kinect's writer (`oni_write`) and played by OpenNI2's own file player: the same
//!   times and intrinsics as the folder, frames matched, and the same correspondences as
//!   tracking the folder;
//! * a recording of OpenNI2's Dummy device made through symcorr-kinect's `Recorder`: Debian's
//!   OpenNI 2.2 plays no frame of it (symcorr_kinect::openni2), and the Dummy's test pattern has
//!   no body anyway, so every frame is skipped; what is checked is that the `.oni` is the
//!   recording: every frame is reported, with the time of the file's timestamp, a status saying
//!   why it was skipped, a row in the arrays, and slices of it work.
#![cfg(feature = "openni2")]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use symcorr_kinect::oni_write::write_recording_oni;
use symcorr_kinect::openni2::{OpenNi, Recorder};
use symcorr_kinect::{DepthSource, Recording};

/// OpenNI2's context is process-global: the tests take turns with it.
static OPENNI: Mutex<()> = Mutex::new(());

fn recording() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/recording")
}

fn joints() -> PathBuf {
    recording().join("joints.json")
}

/// Records `frames` frames of the Dummy device into `path` and returns the number of frames the
/// file holds, as OpenNI2's own player counts them (the recorder may miss the first).
fn record_dummy(path: &Path, frames: usize) -> usize {
    let ni = OpenNi::init().unwrap();
    let dev = ni.open("Dummy").unwrap();
    let mut depth = dev.depth_stream().unwrap();
    depth.start().unwrap();
    let mut rec = Recorder::create(&ni, path).unwrap();
    rec.attach(&depth).unwrap();
    rec.start().unwrap();
    for _ in 0..frames {
        depth.read_frame(2000).unwrap();
    }
    rec.stop();
    drop(rec);
    drop(depth);
    drop(dev);
    let file = ni.open_file(path).unwrap();
    let n = file.depth_stream().unwrap().number_of_frames().unwrap();
    usize::try_from(n).unwrap()
}

fn track(recording: &Path, out: &Path, extra: &[&str]) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_symcorr"))
        .arg("track")
        .arg(recording)
        .arg("--joints")
        .arg(joints())
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&std::fs::read(out.join("track.json")).unwrap()).unwrap()
}

/// The data of a float32 NumPy file.
fn npy_f32(path: &Path) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap();
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    bytes[10 + len..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// The shape in a NumPy file's header and its data, as i32.
fn npy_i32(path: &Path) -> (String, Vec<i32>) {
    let bytes = std::fs::read(path).unwrap();
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = String::from_utf8_lossy(&bytes[10..10 + len]).into_owned();
    let shape = header
        .split("'shape': ")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .map(|s| format!("{s})"))
        .unwrap();
    let data = bytes[10 + len..]
        .chunks_exact(4)
        .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    (shape, data)
}

/// The frames of the fixture tracked from both sources: a slice (the whole recording takes
/// about 16 s in the dev profile) with frames matched and frames the joint log loses.
const SLICE: &str = "50..60";

#[test]
fn track_matches_an_oni_written_from_the_fixture_recording_as_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    let oni = dir.path().join("fixture.oni");
    let folder = Recording::open(recording()).unwrap();
    write_recording_oni(&folder, 0..folder.len(), &oni).unwrap();

    {
        let _openni = OPENNI.lock().unwrap_or_else(|e| e.into_inner());
        // The source: the folder's times exactly (whole µs in the fixture), its intrinsics
        // within the f32 rounding of the field of view OpenNI2 reports.
        let mut source = DepthSource::open(&oni).unwrap();
        assert!(matches!(source, DepthSource::Oni(_)));
        assert_eq!(source.times(), folder.times());
        let (k, want) = (*source.intrinsics(), *folder.intrinsics());
        assert_eq!(
            (k.width, k.height, k.cx, k.cy),
            (want.width, want.height, want.cx, want.cy)
        );
        assert!((k.fx - want.fx).abs() < 1e-4, "{k:?} vs {want:?}");
        assert!((k.fy - want.fy).abs() < 1e-4, "{k:?} vs {want:?}");
        // The pixels, through OpenNI2's player, of a frame in the middle.
        assert!(source.frame(30).unwrap() == folder.frame(30).unwrap());
    }

    let from_oni = track(&oni, &dir.path().join("oni"), &["--frames", SLICE]);
    let from_folder = track(
        &recording(),
        &dir.path().join("folder"),
        &["--frames", SLICE],
    );
    let (a, b) = (
        from_oni["frames"].as_array().unwrap(),
        from_folder["frames"].as_array().unwrap(),
    );
    assert_eq!(a.len(), 10);
    assert_eq!(a.len(), b.len());
    let mut matched = 0;
    for (fa, fb) in a.iter().zip(b) {
        for key in ["frame", "time_s", "status"] {
            assert_eq!(fa[key], fb[key], "{key} of {fa}");
        }
        matched += usize::from(fa["status"] == "ok");
    }
    assert!(matched >= 5, "{matched} of 10 frames matched: {a:?}");
    assert!(matched < a.len(), "the slice also has skipped frames");
    // The same vertex matches, bit for bit.
    let (shape, rows) = npy_i32(&dir.path().join("oni/correspondence.npy"));
    let (folder_shape, folder_rows) = npy_i32(&dir.path().join("folder/correspondence.npy"));
    assert_eq!(shape, folder_shape);
    assert!(rows == folder_rows, "correspondence.npy differs");
    assert!(
        rows.iter().any(|&v| v >= 0),
        "matched frames match vertices"
    );
    // Their confidences and posed templates: equal up to the f32 rounding of the field of view
    // in the file (the focal length reads back 1e-5 px off; a few values differ in their last
    // bit).
    for name in ["confidence.npy", "posed.npy"] {
        let (oni_values, folder_values) = (
            npy_f32(&dir.path().join("oni").join(name)),
            npy_f32(&dir.path().join("folder").join(name)),
        );
        assert_eq!(oni_values.len(), folder_values.len());
        let worst = oni_values
            .iter()
            .zip(&folder_values)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst <= 1e-6, "{name}: differs by {worst}");
    }
}

#[test]
fn track_reads_an_oni_recording_of_the_dummy_device() {
    let _openni = OPENNI.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let oni = dir.path().join("dummy.oni");
    let n = record_dummy(&oni, 8);
    assert!(n >= 5, "{n} frames recorded");

    // The source itself: the file's frame count, times from its timestamps (the recorder
    // writes the first frame at 0 and keeps the Dummy's 33 ms steps), intrinsics from the
    // video mode (the Dummy reports no field of view: the nominal Kinect focal length, scaled).
    let mut source = DepthSource::open(&oni).unwrap();
    assert!(matches!(source, DepthSource::Oni(_)));
    assert_eq!(source.len(), n);
    let expected: Vec<f64> = (0..n).map(|i| i as f64 * 0.033).collect();
    for (t, e) in source.times().iter().zip(&expected) {
        assert!((t - e).abs() < 1e-9, "{:?}", source.times());
    }
    let k = *source.intrinsics();
    assert_eq!((k.width, k.height, k.cx, k.cy), (320, 240, 160.0, 120.0));
    assert!((k.fx - 285.63).abs() < 1e-9, "{k:?}");
    // OpenNI 2.2 plays no frame of a Dummy recording: a typed error that says so, at once for
    // every later frame. (A future OpenNI2 that plays it must give the recorded size.)
    match source.frame(0) {
        Err(e) => {
            let m = e.to_string();
            assert!(m.contains("delivers no frame of this recording"), "{m}");
            // Every later frame names the same cause.
            let later = source.frame(1).unwrap_err().to_string();
            assert!(later.contains("frame 1 not read"), "{later}");
            assert!(
                later.contains("delivers no frame of this recording"),
                "{later}"
            );
        }
        Ok(f) => assert_eq!((f.width, f.height), (320, 240)),
    }
    let e = source.frame(n).unwrap_err().to_string();
    assert!(e.contains(&format!("frame {n} requested")), "{e}");
    drop(source);

    // The whole recording through `symcorr track`.
    let all = track(&oni, &dir.path().join("all"), &[]);
    let frames = all["frames"].as_array().unwrap();
    assert_eq!(frames.len(), n);
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f["frame"], i);
        let t = f["time_s"].as_f64().unwrap();
        assert!((t - expected[i]).abs() < 1e-9, "frame {i} at {t}");
        let status = f["status"].as_str().unwrap();
        assert!(status.starts_with("skipped: "), "{status}");
        assert!(
            status.contains("delivers no frame") || status.contains("skeleton"),
            "the status says why: {status}"
        );
    }
    assert_eq!(all["summary"]["skipped"], n);
    assert_eq!(all["run"]["recording"], oni.display().to_string());
    let vertices = all["run"]["template_vertices"].as_u64().unwrap() as usize;
    let (shape, rows) = npy_i32(&dir.path().join("all/correspondence.npy"));
    assert_eq!(shape, format!("({n}, {vertices})"));
    assert_eq!(rows.len(), n * vertices);
    assert!(
        rows.iter().all(|&v| v == -1),
        "skipped frames match nothing"
    );

    // A slice of it: the same frames, the same times, its own arrays.
    let part = track(&oni, &dir.path().join("part"), &["--frames", "2..5"]);
    let sliced = part["frames"].as_array().unwrap();
    assert_eq!(sliced.len(), 3);
    for (f, i) in sliced.iter().zip(2..) {
        assert_eq!(f["frame"], i);
        assert_eq!(f["time_s"], frames[i]["time_s"]);
    }
    let (shape, _) = npy_i32(&dir.path().join("part/correspondence.npy"));
    assert_eq!(shape, format!("(3, {vertices})"));
}
