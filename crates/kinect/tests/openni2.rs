//! Real OpenNI2 behaviour (feature `openni2`): the built-in Dummy device, OpenNI2's own recorder
//! and the OniFile playback driver, and files of the crate's own `.oni` writer played by it.
//! OpenNI2's context is process-global, so everything runs in one test, in order.
#![cfg(feature = "openni2")]

use symcorr_kinect::oni::OniRecording;
use symcorr_kinect::oni_write::write_oni;
use symcorr_kinect::openni2::{FilePlayback, OpenNi, Recorder, STATUS_TIME_OUT};
use symcorr_kinect::{DepthFrame, Intrinsics, KinectError};

#[test]
fn dummy_device_recording_and_oni_playback() {
    let ni = OpenNi::init().unwrap();
    // Initialising again is harmless (one process-wide context).
    let _again = OpenNi::init().unwrap();

    // The Dummy driver is not enumerated, but opens by URI.
    let devices = ni.devices().unwrap();
    assert!(devices.iter().all(|d| d.uri != "Dummy"), "{devices:?}");

    // A device that does not exist: typed error with OpenNI2's text.
    let e = ni.open("no-such-device://x").unwrap_err();
    assert!(matches!(e, KinectError::OpenNi { .. }), "{e}");
    let e = ni.open_file("/nonexistent/rec.oni").unwrap_err();
    assert!(matches!(e, KinectError::Io { .. }), "{e}");

    let dir = tempfile::tempdir().unwrap();
    let oni = dir.path().join("dummy.oni");
    let recorded: Vec<_>;
    {
        let dev = ni.open("Dummy").unwrap();
        assert!(!dev.is_file());
        let mut depth = dev.depth_stream().unwrap();
        let vm = depth.video_mode().unwrap();
        assert_eq!(
            (vm.width, vm.height, vm.fps, vm.pixel_format),
            (320, 240, 30, 100)
        );
        assert_eq!(depth.field_of_view(), None);
        depth.start().unwrap();
        // Live frames: right size, increasing index and timestamp (30 fps → 33 ms apart).
        let a = depth.read_frame(2000).unwrap();
        let b = depth.read_frame(2000).unwrap();
        assert_eq!((a.depth.width, a.depth.height), (320, 240));
        assert_eq!(a.depth.data_mm.len(), 320 * 240);
        assert_eq!(b.frame_index, a.frame_index + 1);
        assert_eq!(b.timestamp_us - a.timestamp_us, 33_000);
        // The Dummy device's test pattern: 2000 mm at the top-left pixel, some zeros.
        assert_eq!(a.depth.at(0, 0), Some(2000));
        assert!(a.depth.data_mm.contains(&0));

        let mut rec = Recorder::create(&ni, &oni).unwrap();
        rec.attach(&depth).unwrap();
        rec.start().unwrap();
        recorded = (0..10).map(|_| depth.read_frame(2000).unwrap()).collect();
        rec.stop();
        drop(rec);
        // Seeking a live device is not supported.
        assert!(dev.seek(&depth, 1).is_err());
    }
    assert!(std::fs::metadata(&oni).unwrap().len() > 0);

    // Playback of OpenNI2's own recording.
    let dev = ni.open_file(&oni).unwrap();
    assert!(dev.is_file());
    dev.set_playback_speed(-1.0).unwrap();
    dev.set_repeat(false).unwrap();
    let mut depth = dev.depth_stream().unwrap();
    let vm = depth.video_mode().unwrap();
    assert_eq!((vm.width, vm.height, vm.pixel_format), (320, 240, 100));
    // The recorder starts with the frame after its start: 9 or 10 of the 10 frames read.
    let n = depth.number_of_frames().unwrap();
    assert!(
        (recorded.len() as i32 - 1..=recorded.len() as i32).contains(&n),
        "{n}"
    );
    depth.start().unwrap();
    // Debian's OpenNI 2.2.0.33: OniFile drops every frame of a Dummy recording (the recording
    // has no cropping property; see the openni2 module docs). Pin that down: if a future
    // OpenNI2 delivers frames, check their content against what was recorded instead.
    match depth.read_frame(1500) {
        Err(KinectError::OpenNi { status, .. }) => {
            assert_eq!(status, STATUS_TIME_OUT);
            // Seeking before any frame is refused instead of hanging.
            assert!(dev.seek(&depth, 1).is_err());
        }
        Ok(first) => {
            assert_eq!((first.depth.width, first.depth.height), (320, 240));
            assert!(recorded.iter().any(|r| r.depth == first.depth));
        }
        Err(e) => panic!("unexpected error {e}"),
    }
    drop(depth);
    drop(dev);

    written_oni_plays_every_frame(&dir.path().join("written.oni"));
}

/// A file of `oni_write` played by OpenNI2's own file player: every frame, with the pixels and
/// timestamps written, the video mode and the field of view; then through `OniRecording`.
fn written_oni_plays_every_frame(path: &std::path::Path) {
    let (w, h) = (64u32, 48u32);
    let k = Intrinsics::from_field_of_view(w, h, Some((1.02, 0.80)));
    // Irregular times (as a recording's jitter), the first not at 0; pixels that differ per
    // frame and per pixel, with holes (0) and the largest millimetre value.
    let times = [683u64, 32_591, 67_916, 99_999, 133_400, 168_000];
    let frames: Vec<DepthFrame> = (0..times.len())
        .map(|i| {
            let data = (0..w * h)
                .map(|p| match (p as usize + i) % 97 {
                    0 => 0,
                    1 => u16::MAX,
                    r => 500 + (r * 31 + i * 7) as u16,
                })
                .collect();
            DepthFrame::new(w, h, data).unwrap()
        })
        .collect();
    let size = write_oni(path, &k, &times, |i| Ok(frames[i].clone())).unwrap();
    assert_eq!(std::fs::metadata(path).unwrap().len(), size);

    let mut playback = FilePlayback::open(path).unwrap();
    let vm = playback.stream().video_mode().unwrap();
    assert_eq!((vm.width, vm.height, vm.pixel_format), (64, 48, 100));
    assert_eq!((vm.fps), 30, "{vm:?}");
    assert_eq!(
        playback.stream().number_of_frames(),
        Some(times.len() as i32)
    );
    let (hf, vf) = playback.stream().field_of_view().unwrap();
    assert!((f64::from(hf) - 1.02).abs() < 1e-6 && (f64::from(vf) - 0.80).abs() < 1e-6);
    // The recorded mirroring (xnMirror) is the stream's property for OpenNI2's player too.
    assert_eq!(playback.stream().mirroring(), Some(true));
    for (i, (t, f)) in times.iter().zip(&frames).enumerate() {
        let got = playback.read_frame(2000).unwrap();
        assert_eq!(got.timestamp_us, *t, "frame {i}");
        assert_eq!(got.frame_index, i as i32 + 1);
        assert!(got.depth == *f, "frame {i}: other pixels");
    }
    // The end of the file (no repeat): nothing more.
    let e = playback.read_frame(300).unwrap_err();
    assert!(
        matches!(e, KinectError::OpenNi { status, .. } if status == STATUS_TIME_OUT),
        "{e}"
    );
    drop(playback);

    // The same file as a depth source: times in seconds, intrinsics from the field of view,
    // frames in any order (an earlier one reopens the file).
    let mut rec = OniRecording::open(path).unwrap();
    assert_eq!(rec.len(), times.len());
    for (got, t) in rec.times().iter().zip(times) {
        assert_eq!(*got, t as f64 / 1e6);
    }
    let back = rec.intrinsics();
    assert_eq!(
        (back.width, back.height, back.cx, back.cy),
        (w, h, k.cx, k.cy)
    );
    assert!(
        (back.fx - k.fx).abs() < 1e-5 && (back.fy - k.fy).abs() < 1e-5,
        "{back:?} {k:?}"
    );
    for i in [0, 1, 4, 2, 5] {
        assert!(rec.frame(i).unwrap() == frames[i], "frame {i}");
    }
    assert_eq!(
        rec.intrinsics().mirroring,
        symcorr_kinect::Mirroring::Mirrored
    );
    drop(rec);

    // A camera whose image is not mirrored: written so, played so, read so.
    let direct = Intrinsics {
        mirroring: symcorr_kinect::Mirroring::Direct,
        ..k
    };
    write_oni(path, &direct, &times, |i| Ok(frames[i].clone())).unwrap();
    let playback = FilePlayback::open(path).unwrap();
    assert_eq!(playback.stream().mirroring(), Some(false));
    drop(playback);
    let rec = OniRecording::open(path).unwrap();
    assert_eq!(
        rec.intrinsics().mirroring,
        symcorr_kinect::Mirroring::Direct
    );
}
