//! `symcorr track` on an OpenNI2 `.oni` file (feature `openni2`): a recording of OpenNI2's
//! Dummy device made through symcorr-kinect's `Recorder` plays through the whole command.
//!
//! Debian's OpenNI 2.2 plays no frame of a Dummy recording (symcorr_kinect::openni2), and the
//! Dummy's test pattern has no body anyway, so every frame is skipped; what is checked is that
//! the `.oni` is the recording: every frame is reported, with the time of the file's
//! timestamp, a status saying why it was skipped, a row in the arrays, and slices of it work.
#![cfg(feature = "openni2")]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use symcorr_kinect::openni2::{OpenNi, Recorder};
use symcorr_kinect::DepthSource;

fn joints() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/recording/joints.json")
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

fn track(oni: &Path, out: &Path, extra: &[&str]) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_symcorr"))
        .arg("track")
        .arg(oni)
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

#[test]
fn track_reads_an_oni_recording_of_the_dummy_device() {
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
            let t = std::time::Instant::now();
            assert!(source.frame(1).is_err());
            assert!(
                t.elapsed().as_secs_f64() < 1.0,
                "a stalled player is not waited for again"
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
