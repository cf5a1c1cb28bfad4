#![no_main]
//! Kinect SDK v1 text parser: never panics; parsed positions are finite.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::sdk_text::{parse_kinect_text, to_kinect_text};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(log) = parse_kinect_text(text, "fuzz") {
            assert!(log.frames.iter().all(|f| f
                .skeleton
                .positions
                .iter()
                .flatten()
                .all(|c| c.is_finite())));
            let _ = parse_kinect_text(&to_kinect_text(&log), "fuzz");
        }
    }
});
