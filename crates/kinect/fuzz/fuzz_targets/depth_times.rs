#![no_main]
//! `depth_times.txt` reader (`parse_depth_times`, which `Recording::open` calls) with `frames`
//! from the first byte (0..=255) and the rest decoded as lossy UTF-8: never panics; errors are
//! `Parse` naming the file and a line of the input, or `Recording` naming the file; accepted
//! times are exactly `frames` long, finite and strictly increasing.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::{parse_depth_times, KinectError};

fuzz_target!(|data: &[u8]| {
    let Some((&frames, rest)) = data.split_first() else {
        return;
    };
    let frames = usize::from(frames);
    let text = String::from_utf8_lossy(rest);
    match parse_depth_times(&text, frames, "fuzz") {
        Ok(times) => {
            assert_eq!(times.len(), frames);
            assert!(times.iter().all(|t| t.is_finite()), "{times:?}");
            assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
        }
        Err(KinectError::Parse { file, line, .. }) => {
            assert_eq!(file, "fuzz");
            assert!(line >= 1 && line <= text.lines().count(), "line {line}");
        }
        Err(KinectError::Recording { file, .. }) => assert_eq!(file, "fuzz"),
        Err(e) => panic!("unexpected error kind: {e:?}"),
    }
});
